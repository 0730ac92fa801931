# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The records a parameter change produces: :class:`Payload`, :class:`Robot`, :class:`Config`.

A leaf of the ros layer: the modules that build these records (:mod:`.config`), read them
(:mod:`.answering`, :mod:`.plans`, :mod:`.observer`, :mod:`.diagnostics`) or hand them
around (:mod:`.descriptions`) all import it, and it imports none of them
(``test/test_lint_layers.py`` refuses an import cycle). Pure: numpy and the library.

``Robot`` is the robot the answers are computed for (its model with the payload, its joints,
the per-joint terms and gains, the backend), ``Config`` the table's checked ``Params`` with
that robot, swapped into the node as one reference. ``output`` is only ever the parameter
(``'full'``, ``'without_gravity'``...): ``config.params.output``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Tuple

import numpy as np
import spatial_dynamics as sd
from spatial_dynamics.ros.control import Gains
from spatial_dynamics.ros.parameters import ConfigError
from spatial_dynamics.ros.text import shown


@dataclass(frozen=True)
class Payload:
    """A rigid payload on ``link`` (``''`` = none): kg, m (link frame), kg m² about the com."""

    link: str = ''
    mass: float = 0.0
    com: Tuple[float, ...] = (0.0, 0.0, 0.0)
    inertia: Tuple[float, ...] = (0.0,) * 6

    def __str__(self) -> str:
        if not self.link:
            return 'none'
        return (f'{self.mass:g} kg on {shown(self.link)}, com {list(self.com)} m, inertia '
                f'{list(self.inertia)} kg m^2')

    def apply(self, model: 'sd.Model') -> 'sd.Model':
        """Return ``model`` with the payload (:func:`~spatial_dynamics.with_payload`)."""
        if not self.link:
            return model
        try:
            return sd.with_payload(model, self.link, self.mass, self.com, self.inertia)
        except ValueError as err:
            raise ConfigError(f'parameter payload.*: {err}')


@dataclass(frozen=True)
class Robot:
    """The robot the answers are computed for, swapped as one object between two messages.

    ``base`` is the (reduced) model of the URDF, ``model`` the same with the payload; ``tau``
    is in the order of ``joints`` (= ``model.joint_names``). ``armature`` is ``None`` or (n,),
    ``friction_threshold`` is ``None`` (friction_model none) or the smooth-sign velocity.
    ``backend`` is what the answers run on (``'numpy'`` or ``'compiled'``, see
    :func:`~.configure.resolve_backend`), ``setting`` the ``backend`` parameter. On a floating
    base, ``qp_missing`` says why the contacts' QP cannot run (``''``: imported and warmed)
    ``pull_tolerance`` is the N by which a contact may pull
    (:func:`~.floating.pull_tolerance`) and ``residual_tolerance`` the base residual (N m, N) a
    split may leave (:func:`~.floating.residual_tolerance`). ``effort_limit`` (n,) is the URDF's
    ``<limit effort>`` of each of ``joints`` (the model's, in their order; ``inf`` where the
    URDF gives none): an answer above it is reported (clamped only with ``clamp``).
    """

    urdf: str
    source: str
    base: 'sd.Model'
    model: 'sd.Model'
    joints: Tuple[str, ...]
    joints_param: Tuple[str, ...]
    locked: Tuple[Tuple[str, float], ...]
    payload: Payload
    armature: Optional[np.ndarray] = None
    friction_threshold: Optional[float] = None
    clamp: bool = False
    backend: str = 'numpy'
    setting: str = 'auto'
    gains: Optional[Gains] = None
    external_torque_warn: Optional[np.ndarray] = None
    qp_missing: str = ''
    pull_tolerance: float = 0.0
    residual_tolerance: float = 0.0
    effort_limit: Optional[np.ndarray] = None


@dataclass(frozen=True)
class Config:
    """The checked parameters and the robot, swapped in as one (see :func:`~.configure.prepare`).

    ``params`` is the table's frozen ``Params`` (one field per parameter, under the
    parameter's name with ``.`` as ``_``): what the answers read. ``robot`` is None until a
    description loads.
    """

    params: object
    robot: Optional[Robot]
    new_description: bool = False
    kept_file: str = ''
