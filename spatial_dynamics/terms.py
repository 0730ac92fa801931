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

from .algorithms.arguments import as_joint_arrays, as_real_array, batch_of, check_model
from .model import Model, real_numbers
from .text import listed, shown

PerJoint = Union[float, Sequence[float], Mapping[str, float], np.ndarray]


def per_joint(model: Model, what: str, values: PerJoint, default: float = 0.0,
              nonnegative: bool = False) -> np.ndarray:
    """Expand a scalar, a list in joint order, or a {joint name: value} map to an (nv,) array.

    The array is in the order of q̇ and τ, ready for :func:`armature_torque` and the like.
    A fixed-base model: one value per joint of ``model.joint_names``. A floating-base model
    (``base='floating'``): the values are those of its actuated joints
    (``model.joint_names[1:]``, rows 6 on); the free-flyer ``'root_joint'`` has no drive,
    so the six base rows (the wrench on the base) are 0. A list may then also hold all
    ``nv`` numbers with the six base rows 0 (Pinocchio's ``model.armature``).

    ``ValueError`` names the joint of an unknown name (a mimic joint: the joint it follows,
    whose coordinate takes its value) or a non-finite (or, with ``nonnegative``, negative)
    value, and the free-flyer given a value; ``TypeError`` names
    ``what`` given anything but real numbers (a string, a complex number, a boolean:
    ``armature=True`` is no armature of 1).
    """
    check_model(model)
    names = model.joint_names[1:] if model.floating else model.joint_names
    base = model.nv - len(names)        # the free-flyer's rows: 6, or 0 on a fixed base
    n = len(names)
    if isinstance(values, Mapping):
        out = np.full(n, float(default))
        for name, v in values.items():
            if base and name == model.joint_names[0]:
                raise ValueError(f'{what}: {shown(name)} is the floating base\'s free-flyer, '
                                 'which has no drive (its six rows, the wrench on the base, are '
                                 '0)')
            if name not in names:
                raise ValueError(f'{what}: {_not_a_coordinate(model, what, name)}')
            out[names.index(name)] = _number(f'{what} of joint {shown(name)}', v)
    else:
        out = real_numbers(what, values)
        if out.ndim == 0:
            out = np.full(n, float(out))
        if base and out.shape == (model.nv,):
            if np.any(out[:base] != 0.0):
                raise ValueError(f'{what}: {model.nv} values whose first {base} (the '
                                 f'free-flyer {shown(model.joint_names[0])}: the base, which has '
                                 f'no drive) are not 0: {out[:base]}; give the {n} of the '
                                 'actuated joints')
            out = out[base:]
        if out.shape != (n,):
            raise ValueError(f'{what}: expected {n} values for ({listed(names, count=n)})'
                             + (f' (or {model.nv} with the base\'s six 0 first)' if base else '')
                             + f', got {out.shape[0] if out.ndim == 1 else out.shape}')
    for name, v in zip(names, out):
        if not np.isfinite(v) or (nonnegative and v < 0.0):
            raise ValueError(f'{what}: joint {shown(name)} has the value {v}, need a finite '
                             + ('non-negative ' if nonnegative else '') + 'number')
    return np.concatenate([np.zeros(base), out])


def _not_a_coordinate(model: Model, what: str, name) -> str:
    """Say why ``name`` has no value of its own: a mimic joint (and whose), or no joint."""
    if name not in model.mimics:
        return f'unknown joint {shown(name)}'
    follows = model.mimics[name][0]
    source, seen = follows, {name}
    while source in model.mimics and source not in seen:   # a mimic of a mimic
        seen.add(source)
        source = model.mimics[source][0]
    via = '' if source == follows else f', which follows {shown(source)}'
    names = model.joint_names[1:] if model.floating else model.joint_names
    where = (f'; give it to {shown(source)}, whose coordinate it is' if source in names
             else '')
    return (f'joint {shown(name)} is a mimic joint: it follows {shown(follows)}{via} and has '
            f'no coordinate of its own, so no {what} of its own{where}')


def _number(what: str, value) -> float:
    """``value``, one real number, as a float; ``TypeError``/``ValueError`` naming ``what``."""
    a = real_numbers(what, value)
    if a.ndim != 0:
        raise ValueError(f'{what} must be one number, got shape {a.shape}')
    return float(a)


def check_threshold(threshold, what: str = 'threshold') -> float:
    """Return the friction velocity ``threshold`` (rad/s or m/s) as a float, checked.

    One real number, finite and > 0; ``TypeError`` (a string, a complex number) or
    ``ValueError`` (a vector, 0, negative, not finite) naming ``what``, the caller's name
    for it (``friction_threshold`` in :func:`~spatial_dynamics.rnea_derivatives`).
    """
    t = _number(what, threshold)
    if not t > 0.0 or not np.isfinite(t):
        raise ValueError(f'{what}: friction velocity threshold must be > 0, got {t}')
    return t


def armature_torque(armature: np.ndarray, qdd) -> np.ndarray:
    """Rotor inertia reflected through the gear: ``τ = armature · q̈``.

    ``armature`` as :func:`per_joint` returns it (real numbers: ``TypeError`` otherwise).
    """
    a, qdd = real_numbers('armature', armature), as_real_array('qdd', qdd).astype(float)
    if a.ndim and qdd.ndim and a.shape[-1] != qdd.shape[-1]:
        raise ValueError(f'armature has {a.shape[-1]} values a state and qdd {qdd.shape[-1]}')
    batch_of((f'armature of shape {a.shape}', a.shape[:-1]), (f'qdd of shape {qdd.shape}',
                                                              qdd.shape[:-1]))
    return a * qdd


def friction_torque(model: Model, qd, threshold: float) -> np.ndarray:
    """URDF ``<dynamics>`` friction: ``τ = damping·q̇ + friction·tanh(q̇ / threshold)``.

    ``threshold`` (rad/s or m/s, > 0) is the velocity at which the Coulomb term reaches
    tanh(1) ≈ 76 % of its full value. A mimic joint's own friction, at its rate
    ``mult·q̇_src``, is folded back onto its source like its torque: ``τ_src += mult·τ_mimic``.
    """
    threshold = check_threshold(threshold)
    (qd,) = as_joint_arrays(model, qd, names=('qd',))
    qd = qd.astype(float)
    vidx, qmul = model.vidx[1:], model.qmul[1:]
    qd_body = qmul * qd[..., vidx]
    tau_body = model.body_damping[1:] * qd_body + model.body_friction[1:] * np.tanh(
        qd_body / threshold)
    fold = np.zeros((model.NB, model.nv))
    fold[np.arange(model.NB), vidx] = qmul
    return tau_body @ fold


def friction_derivative(model: Model, qd, threshold: float) -> np.ndarray:
    """Return ``∂/∂q̇`` of :func:`friction_torque`: (..., nv, nv), diagonal but for mimics.

    Each body's ``mult² (damping + friction (1 − tanh²(mult q̇ / threshold)) / threshold)``
    at its source joint's row and column (the torque folded as :func:`friction_torque`).
    """
    threshold = check_threshold(threshold)
    (qd,) = as_joint_arrays(model, qd, names=('qd',))
    qd = qd.astype(float)
    vidx, qmul = model.vidx[1:], model.qmul[1:]
    t = np.tanh(qmul * qd[..., vidx] / threshold)
    slope = qmul * qmul * (model.body_damping[1:]
                           + model.body_friction[1:] * (1.0 - t * t) / threshold)
    fold = np.zeros((model.NB, model.nv))
    fold[np.arange(model.NB), vidx] = 1.0
    return np.einsum('bi,...b,bj->...ij', fold, slope, fold)


def clamp_to_effort_limits(model: Model, tau) -> tuple[np.ndarray, np.ndarray]:
    """Clamp τ to the URDF ``<limit effort>``; returns ``(clamped, saturated)``.

    Joints without a positive effort limit are left alone; ``saturated`` is a boolean array
    of τ's shape marking the clamped entries.
    """
    (tau,) = as_joint_arrays(model, tau, names=('tau',))
    tau = tau.astype(float)
    limit = np.where(model.effort_limit > 0.0, model.effort_limit, np.inf)
    return np.clip(tau, -limit, limit), np.abs(tau) > limit
