# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The corrected model of a replay: what was identified, checked on held-out data, written.

One :class:`Correction` gathers what ``--inertias``, ``--payload`` and ``--identify`` found
(the bodies' inertias, a payload on a link, each joint's damping, Coulomb friction and
armature); it predicts the torque of the corrected robot, reports the residual before and
after on the training bag and on a held-out one (``--validate``), lists the parameter changes
with their uncertainty (``parameters.csv``) and writes the user's URDF with only those
elements replaced (``--write-urdf``, :mod:`.urdf_writer`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
import os
from typing import Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from .. import identification
from ..algorithms.regressor import PARAMETERS
from ..backends import rnea
from ..files import write_atomic
from ..model import Model
from . import report, urdf_writer

#: How many undetermined combinations the warning names (the rest are counted).
NAMED = 8


@dataclass
class Correction:
    """What the replay identified against ``model`` (the URDF as loaded)."""

    model: Model
    bodies: Dict[int, np.ndarray] = field(default_factory=dict)      # body -> 6×6 inertia
    sigma: Dict[int, np.ndarray] = field(default_factory=dict)       # body -> (10,) σ
    undetermined: Dict[int, np.ndarray] = field(default_factory=dict)   # body -> (10,) 0..1
    payload: Optional[identification.Payload] = None
    drives: Optional[Tuple[np.ndarray, np.ndarray, np.ndarray]] = None
    threshold: float = 0.01

    def corrected_model(self) -> Model:
        """Return the model with the identified inertias and payload."""
        bodies = dict(self.bodies)
        if self.payload is not None:
            body, T = identification.link_to_body(self.model, self.payload.link)
            bodies[body] = bodies.get(body, self.model.inertia[body]) + \
                identification._spatial_inertia(T @ self.payload.pi)
        return identification.with_bodies(self.model, bodies)

    def predict(self, q, qd, qdd, gravity) -> np.ndarray:
        """Return the corrected robot's torque (rigid body and drives)."""
        return identification.predicted_torque(self.corrected_model(), q, qd, qdd, gravity,
                                               self.drives, self.threshold)

    def parameter_rows(self) -> List[list]:
        """Return ``[link, parameter, urdf, identified, sigma, undetermined]`` rows."""
        pi0 = identification.parameters(self.model)
        rows = []
        for body, value in sorted(self.bodies.items()):
            new = identification._ten(value)
            for k, name in enumerate(PARAMETERS):
                rows.append([self.model.body_names[body], name, pi0[10 * (body - 1) + k],
                             new[k], self.sigma[body][k], self.undetermined[body][k]])
        if self.payload is not None:
            for k, name in enumerate(PARAMETERS):
                rows.append([f'payload on {self.payload.link}', name, 0.0,
                             self.payload.pi[k], self.payload.sigma[k], 0.0])
        return rows

    def write_urdf(self, text: Union[bytes, urdf_writer.Source], path: str) -> List[str]:
        """Write ``text`` (the URDF as read) with the identified elements replaced.

        Written whole or not at all (:func:`~spatial_dynamics.files.write_atomic`).
        """
        additions = None
        if self.payload is not None:
            additions = {self.payload.link: identification._spatial_inertia(self.payload.pi)}
        dynamics = None
        if self.drives is not None:
            damping, friction, _ = self.drives
            dynamics = {name: (max(d, 0.0), max(f, 0.0))
                        for name, d, f in zip(self.model.joint_names, damping, friction)}
        out, notes = urdf_writer.corrected_urdf(text, self.model, self.bodies, additions,
                                                dynamics)
        write_atomic(path, out, 'the corrected URDF')
        return notes


def from_inertias(model: Model, found: identification.Inertias, threshold: float
                  ) -> Correction:
    """Return the correction of an :func:`identification.identify_inertias` result."""
    sigma = found.sigma
    bodies = {i: identification._spatial_inertia(found.pi[10 * (i - 1):10 * i])
              for i in found.bodies}
    sig = {i: sigma[10 * k:10 * k + 10] for k, i in enumerate(found.bodies)}
    share = {i: found.undetermined[10 * k:10 * k + 10] for k, i in enumerate(found.bodies)}
    return Correction(model, bodies, sig, share, drives=found.drives, threshold=threshold)


def rms(x: np.ndarray) -> np.ndarray:
    """Return the RMS per column."""
    return np.sqrt(np.mean(np.asarray(x) ** 2, axis=0))


def residuals(correction: Correction, data: Dict, gravity) -> Tuple[np.ndarray, np.ndarray]:
    """Return the RMS residual per joint of the URDF's model and of the corrected one."""
    q, qd, qdd, effort = (data[k] for k in ('q', 'qd', 'qdd', 'effort'))
    before = rms(effort - rnea(correction.model, q, qd, qdd, gravity))
    after = rms(effort - correction.predict(q, qd, qdd, gravity))
    return before, after


def undetermined_warning(model: Model, data: Dict, bodies: Sequence[int], gravity) -> str:
    """Return a warning naming what the recording does not determine ('' when all is)."""
    weak = identification.poorly_excited(model, (data['q'], data['qd'], data['qdd']),
                                         bodies, gravity)
    if not weak:
        return ''
    named = '; '.join(weak[:NAMED]) + (f'; and {len(weak) - NAMED} more'
                                       if len(weak) > NAMED else '')
    return (f'warning: the recording does not determine {len(weak)} combination(s) of the '
            f'inertial parameters fitted (excited less than {identification.WEAK:g} times as '
            f'well as motion over the joint limits); they stay near the URDF\'s values: '
            f'{named}. Record motion that moves every joint, fast and slow, over its range '
            '(replay excite writes such a plan)')


def print_inertias(correction: Correction) -> None:
    """Print each fitted link's mass and centre of mass, before and after, with σ."""
    pi0 = identification.parameters(correction.model)
    rows = []
    for body, value in sorted(correction.bodies.items()):
        old, new = pi0[10 * (body - 1):10 * body], identification._ten(value)
        s = correction.sigma[body]

        def com(p):
            c = p[1:4] / p[0] if p[0] > 0 else np.zeros(3)
            return np.where(np.abs(c) < 1e-9, 0.0, c)        # rounding noise as 0
        alone = correction.undetermined[body][0] < 0.5
        rows.append([correction.model.body_names[body], f'{old[0]:.4g}',
                     f'{new[0]:.4g} ± {s[0]:.2g}' + ('' if alone else ' *'),
                     ' '.join(f'{x:.4g}' for x in com(old)),
                     ' '.join(f'{x:.4g}' for x in com(new))])
    print('\nidentified inertias (bodies with the links fixed to them; centre of mass in the '
          'body frame, m; parameters.csv has all ten with one σ). * the recording does not '
          'determine this mass by itself, only in combinations with other parameters (the '
          'base parameters): the value is one consistent choice near the URDF\'s; judge the '
          'fit by the residual below.')
    print(report.table(['link', 'mass URDF', 'mass identified (kg)', 'com URDF',
                        'com identified'], rows))


def write_parameters(correction: Correction, out: str) -> None:
    """Write ``parameters.csv``: link, parameter, URDF value, identified value, one σ.

    ``undetermined`` is 0 when the data determines the parameter by itself and 1 when it
    does not (it enters only combinations with others, or none: the value is the one nearest
    the URDF's that fits). Inertias are about the body frame's origin (the link frame of the
    link that starts the body).
    """
    report.write_summary(os.path.join(out, 'parameters.csv'), correction.parameter_rows(),
                         ['link', 'parameter', 'urdf', 'identified', 'sigma', 'undetermined'])


def print_validation(names: Sequence[str], train: Tuple[np.ndarray, np.ndarray],
                     held: Optional[Tuple[np.ndarray, np.ndarray]], out: str,
                     plots: bool) -> None:
    """Print and write (``validation.csv``, ``identification.png``) the residual RMS."""
    head = ['joint', 'train URDF', 'train corrected']
    columns = [train[0], train[1]]
    if held is not None:
        head += ['held-out URDF', 'held-out corrected']
        columns += [held[0], held[1]]
    rows = [[n] + [f'{c[j]:.4g}' for c in columns] for j, n in enumerate(names)]
    print('\nresidual RMS per joint, measured - model (N m or N), with the URDF and with the '
          'correction' + (' (held-out: --validate)' if held is not None else ''))
    print(report.table(head, rows))
    report.write_summary(os.path.join(out, 'validation.csv'),
                         [[n] + [c[j] for c in columns] for j, n in enumerate(names)],
                         [h.replace(' ', '_').replace('-', '_').lower() for h in head])
    if plots:
        import matplotlib
        matplotlib.use('Agg')
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(max(6, 1.3 * len(names)), 4))
        x = np.arange(len(names))
        width = 0.8 / len(columns)
        for k, (label, c) in enumerate(zip(head[1:], columns)):
            ax.bar(x + (k - (len(columns) - 1) / 2) * width, c, width, label=label)
        ax.set_xticks(x, names, rotation=30, ha='right', fontsize=8)
        ax.set_ylabel('residual RMS (N m or N)')
        ax.set_title('measured - model: the URDF against the corrected model')
        ax.legend(fontsize=8)
        ax.grid(True, axis='y', alpha=0.3)
        fig.tight_layout()
        try:
            report.save_figure(fig, os.path.join(out, 'identification.png'))
        finally:
            plt.close(fig)
