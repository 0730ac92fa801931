# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A parameter change made a Config, without ROS: checked together and against the model.

Pure Python + numpy + the library (no rclpy import), tested in ``test/test_node_config.py``.
The node calls :func:`prepare` to validate a change (its on-set callback) and swaps in the
resulting :class:`~.records.Config` (its post-set callback); everything an answer needs is one
:class:`~.records.Robot` (:func:`build_robot`). Each value on its own is checked by the table
(:data:`~.config.PARAMETERS`); here the rules across parameters and against the model.

Robot descriptions (which source wins, how one is read and parsed) are
:mod:`spatial_dynamics.ros.descriptions`'; this module only asks it for a model.

Backends (parameter ``backend``, :data:`~.config.BACKEND_SETTINGS`): ``numpy`` runs the
plain-float RNEA; ``auto`` and ``compiled`` run the compiled kernels (built with the package)
from the first answer, or numpy, with the reason, in a package built without them
(:func:`resolve_backend`).
"""

from __future__ import annotations

from typing import Any, Callable, Mapping, Optional, Sequence, Tuple

import numpy as np
import spatial_dynamics as sd
from spatial_dynamics import backends
from spatial_dynamics.contacts import warm_qp
from spatial_dynamics.ros.bases import check_base
from spatial_dynamics.ros.config import (BACKEND_SETTINGS, MAX_ARMATURE, MODEL_PARAMETERS,
                                         PARAMETERS)
from spatial_dynamics.ros.control import (
    check_gains, check_gains_without_model, check_mode, continuous_joints, ControlError, Gains)
from spatial_dynamics.ros.descriptions import description_change, parse_description
from spatial_dynamics.ros.floating import pull_tolerance, residual_tolerance
from spatial_dynamics.ros.observer import check_warn, ObserverError
from spatial_dynamics.ros.parameters import ConfigError, number_text, one_of
from spatial_dynamics.ros.records import Config, Payload, Robot
from spatial_dynamics.ros.text import shown


# --------------------------------------------------------------------------------------------
# Validators: each returns the usable value or raises ConfigError naming the parameter

def locked_positions(params) -> dict:
    """``locked_joints`` with ``locked_positions`` (empty = all 0) as {name: value}.

    The one rule across the two parameters (each one's own rules are in the table).
    """
    joints = list(params.locked_joints or ())
    positions = list(params.locked_positions or ())
    if positions and len(positions) != len(joints):
        raise ConfigError(f'parameter locked_positions: {len(positions)} values for '
                          f'{len(joints)} locked_joints {joints} (need the same number, or '
                          'none for all 0)')
    return dict(zip(joints, positions or [0.0] * len(joints)))


def check_armature(model: 'sd.Model', values: Optional[Sequence[float]]
                   ) -> Optional[np.ndarray]:
    """``armature`` (kg m² or kg): empty = none, else one value in [0, MAX_ARMATURE] per joint.

    A floating base's joints are its actuated ones (the free-flyer has no rotor).
    """
    if not values:
        return None
    joints = model.joint_names[1:] if model.floating else model.joint_names
    try:
        if model.floating:
            armature = np.array(values, dtype=float)
            if armature.shape != (len(joints),):
                raise ValueError(f'parameter armature: expected {len(joints)} values for the '
                                 f'actuated joints {list(joints)}, got {len(armature)}')
            for name, value in zip(joints, armature):
                if not value >= 0.0:
                    raise ValueError(f'parameter armature: joint {shown(name)} has the value '
                                     f'{value}, need a finite non-negative number')
        else:
            armature = sd.per_joint(model, 'parameter armature', list(values),
                                    nonnegative=True)
    except ValueError as err:
        raise ConfigError(f'{err} (order of the joints parameter, or the URDF order '
                          'when it is unset)')
    for name, value in zip(joints, armature):
        if value > MAX_ARMATURE:
            raise ConfigError(f'parameter armature: joint {shown(name)} has '
                              f'{number_text(float(value))}, more than {MAX_ARMATURE:g} '
                              'kg m^2 (or kg) cannot be a rotor inertia')
    armature.setflags(write=False)
    return None if not armature.any() else armature


# --------------------------------------------------------------------------------------------
# Backend choice

def resolve_backend(setting: str) -> str:
    """``'numpy'`` or ``'compiled'``: what ``backend`` = ``setting`` runs on in this process.

    ``auto`` and ``compiled`` are the compiled kernels when the package was built with them,
    else numpy (:func:`~.diagnostics.backend_text` says why).
    """
    one_of('backend', setting, BACKEND_SETTINGS)
    if setting == 'numpy' or backends.compiled.ext is None:
        return 'numpy'
    return 'compiled'


# --------------------------------------------------------------------------------------------
# What an answer needs, and how a parameter change produces it

def _base_model(params, current: Optional[Robot], urdf: str, source: str,
                joints: Tuple[str, ...], locked: dict) -> 'sd.Model':
    """Return the (reduced) model of ``urdf``: ``current``'s when nothing it depends on changed."""
    if (current is not None and urdf is current.urdf and joints == current.joints_param
            and tuple(locked.items()) == current.locked):
        return current.base
    if locked and not joints:
        raise ConfigError(f'parameter locked_joints: {list(locked)} lock joints only '
                          'when the joints parameter lists the joints to keep')
    return parse_description(urdf, source, joints, locked, params.strict_urdf, params.base)


def build_robot(params, current: Optional[Robot], urdf: Optional[str] = None,
                source: Optional[str] = None) -> Robot:
    """Build the :class:`~.records.Robot` for ``params``; the URDF is re-parsed only when needed.

    ``urdf`` None keeps the description of ``current``. Reads nothing of the node, so the
    description parser's thread may call it. Raises :class:`ConfigError`.
    """
    if urdf is None:
        urdf, source = current.urdf, current.source
    payload = Payload(params.payload_link, params.payload_mass, params.payload_com,
                      params.payload_inertia)
    locked = locked_positions(params)
    joints = tuple(params.joints or ())
    base = _base_model(params, current, urdf, source, joints, locked)
    if params.strict_urdf and base.warnings:
        raise ConfigError(
            f'parameter strict_urdf: {source} has {len(base.warnings)} URDF warning(s) '
            f'(strict_urdf refuses them), the first: {base.warnings[0]}')
    if payload.link and payload.link not in base.frames:
        raise ConfigError(
            f'parameter payload.link: {shown(payload.link)} is not a link of robot '
            f'{shown(base.name)} ({source}); set payload.link to an existing link or \'\' '
            'first, or together with the new description')
    if params.wrench_estimate_link and params.wrench_estimate_link not in base.frames:
        raise ConfigError(
            f'parameter wrench_estimate.link: {shown(params.wrench_estimate_link)} is not a '
            f'link of robot {shown(base.name)} ({source})')
    check_base(params, base, source)
    qp_missing = _warm_qp(params.contacts_method) if params.base == 'floating' else ''
    setting = params.backend
    actuated = tuple(base.joint_names[1:] if base.floating else base.joint_names)
    model = payload.apply(base)
    return Robot(
        urdf=urdf, source=source, base=base, model=model,
        joints=actuated, joints_param=joints, locked=tuple(locked.items()),
        payload=payload, armature=check_armature(base, params.armature),
        friction_threshold=(params.friction_velocity_threshold
                            if params.friction_model == 'urdf' else None),
        clamp=params.clamp_to_effort_limits, setting=setting,
        backend=resolve_backend(setting), gains=model_gains(base, params, actuated),
        external_torque_warn=_observer_check(check_warn, actuated,
                                             params.external_torque_warn),
        qp_missing=qp_missing,
        pull_tolerance=pull_tolerance(model) if base.floating else 0.0,
        residual_tolerance=residual_tolerance(model) if base.floating else 0.0,
        effort_limit=_effort_limit(model))


def _effort_limit(model: 'sd.Model') -> np.ndarray:
    """Return the URDF's effort limit of each actuated joint (a floating base's rows out).

    ``inf`` where the URDF gives none (``<limit effort>`` absent or not positive), read-only.
    """
    limit = model.effort_limit[6:] if model.floating else model.effort_limit
    limit = np.where(limit > 0.0, limit, np.inf)
    limit.setflags(write=False)
    return limit


def _warm_qp(method: str) -> str:
    """Import and warm the contacts' QP solver here, never on the answering path.

    A floating base needs it whatever ``contacts.method``: a ``torques`` or ``forces``
    split that makes a contact pull is re-solved by it. Return why it cannot run (``''``:
    ready); with ``contacts.method: qp`` that is a ConfigError.
    """
    try:
        warm_qp()
    except ImportError as err:
        if method == 'qp':
            raise ConfigError(f'parameter contacts.method: {err}') from None
        return str(err)
    return ''


def _check_without_model(params) -> None:
    """Check what needs no model of the per-joint values (each named with its joint later)."""
    try:
        for name in ('kp', 'kd'):
            check_gains_without_model(name, getattr(params, name))
    except ControlError as err:
        raise ConfigError(str(err)) from None
    _observer_check(check_warn, None, params.external_torque_warn)


def _observer_check(check: Callable, *args):
    """Run an observer parameter check; its :class:`ObserverError` as a ConfigError."""
    try:
        return check(*args)
    except ObserverError as err:
        raise ConfigError(str(err)) from None


def model_gains(model: 'sd.Model', params, joints: Optional[Tuple[str, ...]] = None) -> Gains:
    """``kp``, ``kd`` of ``params`` for ``joints`` of ``model`` (:func:`~.control.check_gains`)."""
    try:
        return Gains(check_gains(model, 'kp', params.kp, joints),
                     check_gains(model, 'kd', params.kd, joints),
                     continuous_joints(model, joints))
    except ControlError as err:
        raise ConfigError(f'{err} (order of the joints parameter, or the URDF order when it '
                          'is unset)') from None


def check_control(params) -> Tuple[str, str]:
    """``(control_mode, output)`` of ``params`` (:func:`~.control.check_mode`)."""
    try:
        return check_mode(params.control_mode, params.output, params.kp or (),
                          params.kd or ())
    except ControlError as err:
        raise ConfigError(str(err)) from None


def prepare(previous, changes: Mapping[str, Any], current: Optional[Robot]) -> Config:
    """Validate ``changes`` to the parameters ``previous``; the result is swapped in as a whole.

    ``previous`` is the ``Params`` in use (None or empty at start-up, when ``changes`` holds
    the start-up values by name); ``changes`` are raw values by parameter name, checked by
    the table (:data:`PARAMETERS`: type, bounds, choices, length, rules), then together and
    against the model. ``current`` is the robot in use (None: no model yet). Parses a new
    description when the changes make one current (:func:`description_change`) or change the
    model's parameters. Changes nothing; raises :class:`ConfigError` when a value cannot be
    used.
    """
    if not previous:
        params = PARAMETERS.values(changes)
        previous = PARAMETERS.defaults()
    else:
        params = PARAMETERS.changed(previous, changes)
    urdf, source, kept_file = description_change(previous, params, changes)
    robot = current
    if urdf is not None or current is not None:
        robot = build_robot(params, current, urdf, source)
    else:
        locked_positions(params)
        _check_without_model(params)
    check_control(params)
    return Config(params=params, robot=robot, new_description=urdf is not None,
                  kept_file=kept_file)


def reparse_needed(requested, params) -> bool:
    """Whether a description parsed with parameters ``requested`` must be parsed again now."""
    return any(getattr(requested, PARAMETERS.by_name[name].field)
               != getattr(params, PARAMETERS.by_name[name].field)
               for name in MODEL_PARAMETERS + ('strict_urdf', 'base'))
