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

from .. import drives, identification
from ..algorithms.regressor import PARAMETERS
from ..backends import rnea
from ..files import write_atomic
from ..model import Model
from ..text import shown
from . import report, urdf_writer

# matplotlib is imported where a plot is drawn (start-up time, and optional: the plot extra)

#: How many undetermined combinations the warning names (the rest are counted).
NAMED = 8
#: A fitted body lighter than this (kg) is at the fit's floor, not a link: never written.
MASS_FLOOR = 1e-6
#: The robot's length (m) counted at least, for the centre-of-mass check (a gimbal's joints
#: may all sit at one point).
LENGTH_FLOOR = 0.1


def robot_length(model: Model) -> float:
    """Return the robot's length laid out straight (m): every joint's and link's offset summed.

    No point of the robot is farther than that from any of its frames; ``|X[3:, :3]|`` of a
    Plücker transform is √2 times its translation's length (RBDA 2.24).
    """
    offsets = [model.Xtree[i] for i in range(1, model.NB + 1)]
    offsets += [frame.lXb for frame in model.frames.values()]
    return float(sum(np.linalg.norm(X[3:, :3]) for X in offsets) / np.sqrt(2.0))


def unrealistic(model: Model, body: int, inertia: np.ndarray) -> str:
    """Say why a fitted body cannot be the link, or return ''.

    It cannot when its mass is at the fit's floor (:data:`MASS_FLOOR`) or its centre of mass
    lies farther from the link's frame than the robot is long (:func:`robot_length`).
    """
    m, c, _ = identification.mass_com_inertia(identification._ten(inertia))
    length = max(robot_length(model), LENGTH_FLOOR)
    where = ', '.join(f'{x:.3g}' for x in c)
    if m < MASS_FLOOR:
        return (f'its identified mass {m:.3g} kg is at the fit\'s floor (centre of mass '
                f'({where}) m)')
    if np.linalg.norm(c) > length:
        return (f'its identified centre of mass ({where}) m lies {np.linalg.norm(c):.3g} m '
                f'from the link\'s frame, outside the robot ({length:.3g} m laid out straight; '
                f'mass {m:.3g} kg)')
    return ''


@dataclass
class Correction:
    """What the replay identified against ``model`` (the URDF as loaded)."""

    model: Model
    bodies: Dict[int, np.ndarray] = field(default_factory=dict)      # body -> 6×6 inertia
    sigma: Dict[int, np.ndarray] = field(default_factory=dict)       # body -> (10,) σ
    undetermined: Dict[int, np.ndarray] = field(default_factory=dict)   # body -> (10,) 0..1
    unexcited: Dict[int, np.ndarray] = field(default_factory=dict)      # body -> (10,) bool
    payload: Optional[identification.Payload] = None
    drives: Optional[Tuple[np.ndarray, np.ndarray, np.ndarray]] = None
    threshold: float = 0.01
    #: (damping, friction, armature): σ per joint (inf: undetermined, nan: not known) and
    #: True where the recording cannot tell the term (``drives`` holds the URDF's value)
    drive_sigma: Optional[Tuple[np.ndarray, np.ndarray, np.ndarray]] = None
    drive_undetermined: Optional[Tuple[np.ndarray, np.ndarray, np.ndarray]] = None

    def shown(self, body: int) -> np.ndarray:
        """Return body's ten parameters as reported: the URDF's where no torque tells them."""
        pi0 = identification.parameters(self.model)[10 * (body - 1):10 * body]
        new = identification._ten(self.bodies[body])
        return np.where(self.unexcited.get(body, np.zeros(10, dtype=bool)), pi0, new)

    def rejected(self) -> Dict[int, str]:
        """Return the fitted bodies that are no link (:func:`unrealistic`), with why."""
        out = {}
        for body, value in sorted(self.bodies.items()):
            why = unrealistic(self.model, body, value)
            if why:
                out[body] = why
        return out

    def undetermined_drives(self) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return ``(damping, friction, armature)`` with nan where the recording cannot tell."""
        undetermined = self.drive_undetermined or tuple(
            np.zeros(len(d), dtype=bool) for d in self.drives)
        return tuple(np.where(u, np.nan, d) for d, u in zip(self.drives, undetermined))

    def corrected_model(self) -> Model:
        """Return the model with the identified inertias and payload."""
        bodies = dict(self.bodies)
        if self.payload is not None:
            body, T = identification.link_to_body(self.model, self.payload.link)
            bodies[body] = bodies.get(body, self.model.inertia[body]) + \
                identification._spatial_inertia(T @ self.payload.pi)
        return identification.with_bodies(self.model, bodies)

    def predict(self, q, qd, qdd, gravity, base=None) -> np.ndarray:
        """Return the corrected robot's torque (rigid body on ``base`` if given, drives)."""
        return identification.predicted_torque(self.corrected_model(), q, qd, qdd, gravity,
                                               self.drives, self.threshold, base)

    def parameter_rows(self) -> List[list]:
        """Return ``[link, parameter, urdf, identified, sigma, undetermined]`` rows."""
        pi0 = identification.parameters(self.model)
        rows = []
        for body in sorted(self.bodies):
            new = self.shown(body)
            for k, name in enumerate(PARAMETERS):
                rows.append([self.model.body_names[body], name, pi0[10 * (body - 1) + k],
                             new[k], self.sigma[body][k], self.undetermined[body][k]])
        if self.payload is not None:
            for k, name in enumerate(PARAMETERS):
                rows.append([f'payload on {self.payload.link}', name, 0.0,
                             self.payload.pi[k], self.payload.sigma[k], 0.0])
        if self.drives is not None:
            prior = (self.model.damping, self.model.friction,
                     np.zeros(len(self.model.joint_names)))
            sigma = self.drive_sigma or tuple(np.full(len(d), np.nan) for d in self.drives)
            shown = self.undetermined_drives()
            for j, joint in enumerate(self.model.joint_names):
                for k, name in enumerate(drives.PARAMETERS):
                    unknown = bool(np.isnan(shown[k][j]))
                    rows.append([joint, name, prior[k][j], prior[k][j] if unknown else
                                 self.drives[k][j], np.inf if unknown else sigma[k][j],
                                 1.0 if unknown else 0.0])
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
            # what the recording cannot tell keeps the URDF's value (its element untouched
            # when it tells neither damping nor friction)
            damping, friction, _ = self.undetermined_drives()
            dynamics = {name: (max(d, 0.0) if d == d else u_d, max(f, 0.0) if f == f else u_f)
                        for name, d, f, u_d, u_f in zip(
                            self.model.joint_names, damping, friction, self.model.damping,
                            self.model.friction)
                        if d == d or f == f}
        rejected = self.rejected()
        bodies = {i: v for i, v in self.bodies.items() if i not in rejected}
        out, notes = urdf_writer.corrected_urdf(text, self.model, bodies, additions, dynamics)
        write_atomic(path, out, 'the corrected URDF')
        return [f'link {shown(self.model.body_names[i])} not written, the URDF\'s <inertial> '
                f'kept: {why}; the fit did not find this link (give the URDF a rough <inertial> '
                'for it, or record motion that loads it more)'
                for i, why in rejected.items()] + notes


def from_inertias(model: Model, found: identification.Inertias, threshold: float
                  ) -> Correction:
    """Return the correction of an :func:`identification.identify_inertias` result."""
    sigma = found.sigma
    bodies = {i: identification._spatial_inertia(found.pi[10 * (i - 1):10 * i])
              for i in found.bodies}
    sig = {i: sigma[10 * k:10 * k + 10] for k, i in enumerate(found.bodies)}
    share = {i: found.undetermined[10 * k:10 * k + 10] for k, i in enumerate(found.bodies)}
    unexcited = {i: found.unexcited[10 * k:10 * k + 10] for k, i in enumerate(found.bodies)}
    return Correction(model, bodies, sig, share, unexcited, drives=found.drives,
                      threshold=threshold, drive_sigma=found.drive_sigma,
                      drive_undetermined=found.drive_unexcited)


def from_drives(model: Model, fit: drives.Identified, threshold: float) -> Correction:
    """Return the correction of a drives-only fit: what it cannot tell keeps the URDF's."""
    values = (fit.damping, fit.friction, fit.armature)
    unknown = tuple(np.isnan(x) for x in values)
    prior = (model.damping, model.friction, np.zeros(len(model.joint_names)))
    sigma = tuple(np.where(u, np.inf, fit.sigma[:, k]) for k, u in enumerate(unknown))
    return Correction(model, drives=tuple(np.where(u, p, x) for x, u, p in
                                          zip(values, unknown, prior)),
                      threshold=threshold, drive_sigma=sigma, drive_undetermined=unknown)


def rms(x: np.ndarray) -> np.ndarray:
    """Return the RMS per column."""
    return np.sqrt(np.mean(np.asarray(x) ** 2, axis=0))


def residuals(correction: Correction, data: Dict, gravity) -> Tuple[np.ndarray, np.ndarray]:
    """Return the RMS residual per joint of the URDF's model and of the corrected one.

    ``data['base']`` (if there and not None) is the base's motion at each sample.
    """
    q, qd, qdd, effort = (data[k] for k in ('q', 'qd', 'qdd', 'effort'))
    base = data.get('base')
    before = rms(effort - rnea(correction.model, q, qd, qdd, gravity, base=base))
    after = rms(effort - correction.predict(q, qd, qdd, gravity, base))
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
    rejected = correction.rejected()
    rows = []
    for body in sorted(correction.bodies):
        old, new = pi0[10 * (body - 1):10 * body], correction.shown(body)
        s = correction.sigma[body]
        unexcited = correction.unexcited.get(body, np.zeros(10, dtype=bool))

        def com(p):
            c = p[1:4] / p[0] if p[0] > 0 else np.zeros(3)
            return np.where(np.abs(c) < 1e-9, 0.0, c)        # rounding noise as 0
        if unexcited[0]:
            mass = f'{new[0]:.4g} undetermined'
        else:
            mass = f'{new[0]:.4g} ± {s[0]:.2g}' + (
                '' if correction.undetermined[body][0] < 0.5 else ' *')
        if body in rejected:
            mass += ' NOT WRITTEN'
        rows.append([shown(correction.model.body_names[body], quote=False), f'{old[0]:.4g}', mass,
                     ' '.join(f'{x:.4g}' for x in com(old)),
                     ' '.join(f'{x:.4g}' for x in com(new))])
    print('\nidentified inertias (bodies with the links fixed to them; centre of mass in the '
          'body frame, m; parameters.csv has all ten with one σ). * the recording does not '
          'determine this mass by itself, only in combinations with other parameters (the '
          'base parameters): the value is one consistent choice near the URDF\'s; judge the '
          'fit by the residual below. undetermined: no torque of the recording depends on '
          'it (σ infinite); the URDF\'s value is shown, and the body written is the nearest '
          'consistent one.')
    print(report.table(['link', 'mass URDF', 'mass identified (kg)', 'com URDF',
                        'com identified'], rows))
    for body, why in rejected.items():
        print(f'  {shown(correction.model.body_names[body])}: NOT WRITTEN: {why}')


def write_parameters(correction: Correction, out: str) -> None:
    """Write ``parameters.csv``: link, parameter, URDF value, identified value, one σ.

    ``undetermined`` is 0 when the data determines the parameter by itself and 1 when it
    does not (it enters only combinations with others, or none: the value is the one nearest
    the URDF's that fits). A parameter no torque of the recording depends on has σ ``inf``
    and the URDF's value. The drives' terms follow, one row each (link: the joint).
    Inertias are about the body frame's origin (the link frame of the
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
    rows = [[shown(n, quote=False)] + [f'{c[j]:.4g}' for c in columns]
            for j, n in enumerate(names)]
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
