# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Joint-space terms a real drive adds to the rigid-body torque (all off by default).

    τ = RNEA(q, q̇, q̈) + armature·q̈ + damping·q̇ + friction·s(q̇)

``armature`` is the reflected rotor inertia (kg m² or kg), ``damping`` viscous friction
(N m s/rad or N s/m) and ``friction`` Coulomb friction (N m or N) from the URDF
``<dynamics>``; ``s(q̇) = tanh(q̇ / threshold)`` is a smooth sign, so the output never jumps at
q̇ = 0. Arrays are (n,) in the order of ``model.joint_names`` or broadcast against (..., n).
"""

from __future__ import annotations

from typing import Mapping, Sequence, Union

import numpy as np

from .algorithms.arguments import as_joint_arrays, as_real_array, check_model
from .model import Model

PerJoint = Union[float, Sequence[float], Mapping[str, float], np.ndarray]


def per_joint(model: Model, what: str, values: PerJoint, default: float = 0.0,
              nonnegative: bool = False) -> np.ndarray:
    """Expand a scalar, a list in joint order, or a {joint name: value} map to an (n,) array.

    ``ValueError`` names the joint of an unknown name or a non-finite (or, with
    ``nonnegative``, negative) value.
    """
    check_model(model)
    n = model.nq
    if isinstance(values, Mapping):
        out = np.full(n, float(default))
        for name, v in values.items():
            if name not in model.joint_names:
                raise ValueError(f'{what}: unknown joint {name!r}')
            out[model.joint_names.index(name)] = float(v)
    else:
        out = np.asarray(values, dtype=float)
        if out.ndim == 0:
            out = np.full(n, float(out))
        if out.shape != (n,):
            raise ValueError(f'{what}: expected {n} values for {model.joint_names}, '
                             f'got {out.shape[0] if out.ndim == 1 else out.shape}')
    for name, v in zip(model.joint_names, out):
        if not np.isfinite(v) or (nonnegative and v < 0.0):
            raise ValueError(f'{what}: joint {name!r} has the value {v}, need a finite '
                             + ('non-negative ' if nonnegative else '') + 'number')
    return out


def armature_torque(armature: np.ndarray, qdd) -> np.ndarray:
    """Rotor inertia reflected through the gear: ``τ = armature · q̈``."""
    return armature * as_real_array('qdd', qdd).astype(float)


def friction_torque(model: Model, qd, threshold: float) -> np.ndarray:
    """URDF ``<dynamics>`` friction: ``τ = damping·q̇ + friction·tanh(q̇ / threshold)``.

    ``threshold`` (rad/s or m/s, > 0) is the velocity at which the Coulomb term reaches
    tanh(1) ≈ 76 % of its full value. A mimic joint's own friction, at its rate
    ``mult·q̇_src``, is folded back onto its source like its torque: ``τ_src += mult·τ_mimic``.
    """
    if not threshold > 0.0 or not np.isfinite(threshold):
        raise ValueError(f'friction velocity threshold must be > 0, got {threshold}')
    (qd,) = as_joint_arrays(model, qd, names=('qd',))
    qd = qd.astype(float)
    vidx, qmul = model.vidx[1:], model.qmul[1:]
    qd_body = qmul * qd[..., vidx]
    tau_body = model.body_damping[1:] * qd_body + model.body_friction[1:] * np.tanh(
        qd_body / threshold)
    fold = np.zeros((model.NB, model.nv))
    fold[np.arange(model.NB), vidx] = qmul
    return tau_body @ fold


def clamp_to_effort_limits(model: Model, tau) -> tuple[np.ndarray, np.ndarray]:
    """Clamp τ to the URDF ``<limit effort>``; returns ``(clamped, saturated)``.

    Joints without a positive effort limit are left alone; ``saturated`` is a boolean array
    of τ's shape marking the clamped entries.
    """
    (tau,) = as_joint_arrays(model, tau, names=('tau',))
    tau = tau.astype(float)
    limit = np.where(model.effort_limit > 0.0, model.effort_limit, np.inf)
    return np.clip(tau, -limit, limit), np.abs(tau) > limit
