# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A fixed-base model on a moving base: the base's motion, and what sensors give of it.

A robot arm on a mobile base, a ship or a walking robot's trunk has a base that moves with a
spatial velocity ``v_0`` and a spatial acceleration ``a_0`` (base frame, angular first). RNEA
then starts from them instead of from rest (RBDA table 5.1 with the base's motion)::

    v_0 = v_base;    a_0 = a_base - [0; Rᵀ g]

where ``R`` is the base's orientation in the world and ``g`` gravity in world coordinates.
:class:`BaseMotion` holds ``(v, a, orientation)``; ``rnea``, ``gravity_torque``,
``bias_torque``, ``regressor`` and ``jacobian`` take it as ``base=``.

**Spatial, not classical acceleration.** ``a`` is the derivative of the base's spatial
velocity, ``[ω̇; r̈ - ω × ṙ]`` for the base origin's velocity ``ṙ`` and classical acceleration
``r̈`` (the Plücker-basis paper, eqs. 43-44; :func:`spatial_acceleration`): a base turning at
a constant rate about a fixed axis has ``a = 0`` although each of its points accelerates
towards the axis. It is also the derivative of the body-frame twist's components (what
differentiating ``nav_msgs/Odometry``'s twist gives): ``d/dt (bX0 v) = bX0 v̇ + (v × v) = a``.

**Gravity and an IMU.** An accelerometer measures the specific force ``r̈ - g`` (at rest it
reads +9.81 m/s² upwards): gravity is already in the measurement. :func:`base_from_imu`
therefore returns a motion with ``gravity_included=True``: its ``a`` is the base's
acceleration relative to free fall, ``a_base - [0; Rᵀ g]`` = the ``a_0`` RNEA needs, and
the algorithms add no gravity of their own (their ``gravity`` argument is not used), so the
base's orientation need not be known. A motion with ``gravity_included=False`` (the default;
odometry, a prescribed motion) gets gravity added as ``Rᵀ g``, with ``g`` the algorithm's
``gravity`` in world coordinates; without an ``orientation`` the base's axes are the world's
(``g`` in base coordinates, as for a fixed base).

**The base's linear velocity does not matter to the joints** (Galilean invariance): a motion
``([ω; v], [ω̇; r̈ - ω × v])`` gives the same joint torques for every ``v``. An IMU does not
measure ``v``, so :func:`base_from_imu` takes ``v = 0`` and ``a = [ω̇; r̈ - g]``, which is exact.

How it is computed: a fixed-base model on a moving base is the floating-base model with the
base's rows given. :func:`floating_twin` builds that model once per model (body 1 the base on
a free-flyer, carrying the inertia of the links fixed to the base); the algorithms run on it
with ``q = [0, quaternion, q]``, ``q̇ = [v, q̇]``, ``q̈ = [a, q̈]``, on either backend, and
return its joint rows.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional
import weakref

import numpy as np

from .algorithms.arguments import as_joint_arrays, as_real_array, batch_of
from .joints import (check_quaternion, check_rotation, FIXED, FREE_FLYER,
                     quaternion_matrix)
from .model import Frame, Model
from .spatial import plux_Er
from .text import shown

#: The free-flyer joint of :func:`floating_twin` (Pinocchio's name, as for ``base='floating'``).
ROOT_JOINT = 'root_joint'


@dataclass(frozen=True, eq=False)
class BaseMotion:
    """The motion of a robot's base: ``base=`` of the algorithms (see the module doc).

    Attributes:
        v: spatial velocity ``[ω; v]`` of the base (rad/s, m/s), base frame, shape (..., 6).
        a: spatial acceleration ``[ω̇; r̈ - ω × v]`` (rad/s², m/s²), base frame, (..., 6);
            with ``gravity_included``, the acceleration relative to free fall
            ``[ω̇; r̈ - ω × v - Rᵀ g]`` (what an IMU's specific force gives).
        orientation: the base's orientation in the world, a unit quaternion ``(x, y, z, w)``
            (..., 4; its norm within 1e-2 of 1, then normalised) or a rotation matrix
            (..., 3, 3; ``RᵀR = 1`` within 1e-6, ``det R = +1``) mapping base to world
            coordinates; ``None``: the world's axes. Used to turn gravity into the base
            frame, and by ``jacobian(..., frame='world')``. Anything else (zero, a scaled or
            reflected matrix) is refused (:func:`~spatial_dynamics.joints.check_quaternion`,
            :func:`~spatial_dynamics.joints.check_rotation`).
        gravity_included: ``a`` already holds gravity (an IMU's specific force): the
            algorithms add none. A bool (Python's or numpy's); anything else (``'yes'``,
            ``'False'``, 1) is refused with ``TypeError``, never read as true.
    """

    v: np.ndarray
    a: np.ndarray
    orientation: Optional[np.ndarray] = None
    gravity_included: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.gravity_included, (bool, np.bool_)):
            raise TypeError('base.gravity_included must be a bool (True: a holds gravity), got '
                            f'{type(self.gravity_included).__name__} '
                            f'{shown(self.gravity_included)}')
        object.__setattr__(self, 'gravity_included', bool(self.gravity_included))
        for what in ('v', 'a'):
            x = as_real_array(f'base.{what}', getattr(self, what)).astype(float)
            if x.ndim == 0 or x.shape[-1] != 6:
                raise ValueError(f'base.{what} must have shape (..., 6) ([angular; linear], '
                                 f'base frame), got shape {x.shape}')
            _finite(f'base.{what}', x)
            object.__setattr__(self, what, x)
        if self.orientation is not None:
            o = as_real_array('base.orientation', self.orientation).astype(float)
            if o.shape[-2:] == (3, 3):
                check_rotation('base.orientation', o)
                o = quaternion_of(o)
            elif o.ndim == 0 or o.shape[-1] != 4:
                raise ValueError('base.orientation must be a quaternion (x, y, z, w) of '
                                 'shape (..., 4) or a rotation matrix of shape (..., 3, 3), '
                                 f'got shape {o.shape}')
            check_quaternion('base.orientation', o)
            object.__setattr__(self, 'orientation', o)

    @classmethod
    def at_rest(cls, orientation=None) -> 'BaseMotion':
        """Return a base at rest (``v = a = 0``), tilted by ``orientation`` if given."""
        return cls(np.zeros(6), np.zeros(6), orientation)


def _finite(what: str, x: np.ndarray) -> None:
    """``ValueError`` naming ``what`` when ``x`` holds a NaN or an infinity."""
    if not np.isfinite(x).all():
        raise ValueError(f'{what} must be finite, got {x}')


def quaternion_of(R) -> np.ndarray:
    """Return the unit quaternion ``(x, y, z, w)`` (..., 4) of rotation matrices (..., 3, 3).

    Shepperd's method: from the largest of ``w², x², y², z²`` (no division by a small number).
    """
    R = np.asarray(R, dtype=float)
    t = np.stack([R[..., 0, 0] + R[..., 1, 1] + R[..., 2, 2],
                  R[..., 0, 0] - R[..., 1, 1] - R[..., 2, 2],
                  -R[..., 0, 0] + R[..., 1, 1] - R[..., 2, 2],
                  -R[..., 0, 0] - R[..., 1, 1] + R[..., 2, 2]], -1)
    k = np.argmax(t, axis=-1)
    s = 2.0 * np.sqrt(1.0 + np.take_along_axis(t, k[..., None], -1)[..., 0])
    r21, r12 = R[..., 2, 1], R[..., 1, 2]
    r02, r20 = R[..., 0, 2], R[..., 2, 0]
    r10, r01 = R[..., 1, 0], R[..., 0, 1]
    cand = np.stack([
        np.stack([(r21 - r12) / s, (r02 - r20) / s, (r10 - r01) / s, s / 4], -1),
        np.stack([s / 4, (r01 + r10) / s, (r02 + r20) / s, (r21 - r12) / s], -1),
        np.stack([(r01 + r10) / s, s / 4, (r12 + r21) / s, (r02 - r20) / s], -1),
        np.stack([(r02 + r20) / s, (r12 + r21) / s, s / 4, (r10 - r01) / s], -1)], -2)
    return np.take_along_axis(cand, k[..., None, None], -2)[..., 0, :]


def spatial_acceleration(omega, velocity, omega_dot, r_ddot) -> np.ndarray:
    """Return the spatial acceleration ``[ω̇; r̈ - ω × ṙ]`` (..., 6) of a classical one.

    The Plücker-basis paper's eq. 44: a body whose origin moves with velocity ``ṙ`` and
    classical acceleration ``r̈`` (m/s, m/s²) while turning at ``ω`` (rad/s) with ``ω̇``
    (rad/s²), all in the same (here the base's) coordinates. A body turning at a constant
    rate about a fixed axis has a spatial acceleration of zero.
    """
    w, v, wd, rdd = (as_real_array(n, x).astype(float) for n, x in
                     (('omega', omega), ('velocity', velocity), ('omega_dot', omega_dot),
                      ('r_ddot', r_ddot)))
    w, v, wd, rdd = np.broadcast_arrays(w, v, wd, rdd)
    return np.concatenate([wd, rdd - np.cross(w, v)], axis=-1)


def _base_link(model: Model, link: str, what: str) -> Frame:
    """Return the frame of ``link``, which must be fixed to the base of a fixed-base model."""
    if not isinstance(model, Model):
        raise TypeError(f'model must be a spatial_dynamics.Model, got {type(model).__name__}')
    if model.floating:
        raise ValueError(f'{what}: {shown(model.name)} has a floating base, whose motion is its '
                         "free-flyer's q̇ and q̈: load it with base='fixed' to give a base "
                         'motion')
    frame = model.frames.get(link)
    if frame is None:
        raise ValueError(f'{what}: {shown(link)} is not a link of {shown(model.name)}')
    if frame.body != 0:
        raise ValueError(f'{what}: link {shown(link)} moves with joint '
                         f'{shown(model.body_joints[frame.body])}; the sensor must be on the base '
                         f'({shown(model.body_names[0])} or a link fixed to it)')
    return frame


def _rotation(orientation, what: str) -> np.ndarray:
    """Rotation matrix of a quaternion ``(x, y, z, w)`` or of a rotation matrix, checked.

    The quaternion's norm within 1e-2 of 1, the matrix orthonormal within 1e-6 and proper
    (:func:`~spatial_dynamics.joints.check_quaternion`, ``check_rotation``).
    """
    o = as_real_array(what, orientation).astype(float)
    if o.shape[-2:] == (3, 3):
        check_rotation(what, o)
        return o
    if o.shape[-1:] != (4,):
        raise ValueError(f'{what} must be a quaternion (x, y, z, w) or a rotation matrix, '
                         f'got shape {o.shape}')
    check_quaternion(what, o)
    return quaternion_matrix(o)


def base_from_imu(model: Model, link: str, specific_force, angular_velocity,
                  angular_acceleration=(0.0, 0.0, 0.0), position=(0.0, 0.0, 0.0),
                  orientation=(0.0, 0.0, 0.0, 1.0)) -> BaseMotion:
    """Return the base motion an IMU on the base measures (``sensor_msgs/Imu``).

    Args:
        model: a fixed-base model.
        link: the link the IMU is mounted on (the base or a link fixed to it).
        specific_force: ``Imu.linear_acceleration`` (m/s²), IMU frame, (..., 3): the
            acceleration minus gravity ``r̈_s - g`` at the IMU (+9.81 upwards at rest).
        angular_velocity: ``Imu.angular_velocity`` (rad/s), IMU frame, (..., 3).
        angular_acceleration: ``ω̇`` (rad/s², IMU frame), e.g. the gyro's rate differentiated
            and filtered; an IMU does not give it, zero by default.
        position, orientation: the IMU's pose in ``link``'s frame (m; quaternion x y z w
            or rotation matrix mapping IMU to link coordinates, held to
            :class:`BaseMotion`'s tolerances), as in the URDF joint or TF of the sensor;
            (..., 3) and (..., 4) or (..., 3, 3), batched like the readings.

    Returns:
        ``BaseMotion(v=[ω; 0], a=[ω̇; r̈_0 - g], gravity_included=True)`` in base
        coordinates, ``r̈_0 = r̈_s - ω̇ × r - ω × (ω × r)`` the classical acceleration of the base
        origin for the IMU at ``r`` (base frame). The linear velocity is taken as zero: the
        joints' torques do not depend on it (see the module doc), so this is exact.
    """
    frame = _base_link(model, link, 'base_from_imu')
    E_lb, r_l = plux_Er(frame.lXb)          # lXb: E rotates base -> link, r the link origin
    R_ls = _rotation(orientation, 'base_from_imu: orientation')
    p_l = as_real_array('base_from_imu: position', position).astype(float)
    if p_l.ndim == 0 or p_l.shape[-1] != 3:
        raise ValueError('base_from_imu: position must have shape (..., 3) (m), got shape '
                         f'{p_l.shape}')
    _finite('base_from_imu: position', p_l)
    R_bs = E_lb.T @ R_ls                    # IMU -> base coordinates, (..., 3, 3)
    r = r_l + p_l @ E_lb                    # the IMU's position in base coordinates: E_lbᵀ p
    vectors = []
    for what, x in (('specific_force', specific_force),
                    ('angular_velocity', angular_velocity),
                    ('angular_acceleration', angular_acceleration)):
        x = as_real_array(f'base_from_imu: {what}', x).astype(float)
        if x.ndim == 0 or x.shape[-1] != 3:
            raise ValueError(f'base_from_imu: {what} must have shape (..., 3), got {x.shape}')
        _finite(f'base_from_imu: {what}', x)
        vectors.append(x)
    try:
        np.broadcast_shapes(*(x.shape[:-1] for x in vectors), R_bs.shape[:-2], r.shape[:-1])
    except ValueError:
        raise ValueError('base_from_imu: the batch shapes of specific_force '
                         f'{vectors[0].shape}, angular_velocity {vectors[1].shape}, '
                         f'angular_acceleration {vectors[2].shape}, orientation '
                         f'{R_ls.shape[:-2]} and position {p_l.shape} do not broadcast') from None
    f_s, w, wd = np.broadcast_arrays(*(np.einsum('...ij,...j->...i', R_bs, x) for x in vectors))
    f_s, w, wd, r = np.broadcast_arrays(f_s, w, wd, r)
    f_0 = f_s - np.cross(wd, r) - np.cross(w, np.cross(w, r))    # r̈_0 - g, base frame
    return BaseMotion(np.concatenate([w, np.zeros_like(w)], -1),
                      np.concatenate([wd, f_0], -1), gravity_included=True)


def base_from_odometry(model: Model, twist, twist_rate, orientation=None,
                       link: Optional[str] = None) -> BaseMotion:
    """Return the base motion of odometry (``nav_msgs/Odometry``) and its derivative.

    Args:
        model: a fixed-base model.
        twist: ``Odometry.twist.twist`` as ``[angular; linear]`` (rad/s, m/s), (..., 6), in
            the child frame (``child_frame_id``), the velocity of its origin.
        twist_rate: the time derivative of those six numbers (the twist differentiated
            component by component, rad/s², m/s²). This is the spatial acceleration (see the
            module doc); from a classical ``ω̇, r̈`` use :func:`spatial_acceleration`.
        orientation: ``Odometry.pose.pose.orientation`` (x, y, z, w; or a rotation matrix),
            the child frame's in the world, for gravity, held to :class:`BaseMotion`'s
            tolerances; ``None``: the child frame's axes are the world's.
        link: the child frame: the base (default) or a link fixed to it.
    """
    frame = _base_link(model, model.body_names[0] if link is None else link,
                       'base_from_odometry')
    bXl = np.linalg.inv(frame.lXb)
    v, a = (as_real_array(f'base_from_odometry: {n}', x).astype(float)
            for n, x in (('twist', twist), ('twist_rate', twist_rate)))
    for what, x in (('twist', v), ('twist_rate', a)):
        if x.ndim == 0 or x.shape[-1] != 6:
            raise ValueError(f'base_from_odometry: {what} must have shape (..., 6) '
                             f'([angular; linear]), got {x.shape}')
        _finite(f'base_from_odometry: {what}', x)
    if orientation is not None:
        E_lb, _ = plux_Er(frame.lXb)
        R_wb = _rotation(orientation, 'base_from_odometry: orientation') @ E_lb
        orientation = R_wb
    return BaseMotion(v @ bXl.T, a @ bXl.T, orientation)


# --------------------------------------------------------------------------------------------
# The floating-base model whose base rows a base motion gives

_twins: 'weakref.WeakKeyDictionary[Model, Model]' = weakref.WeakKeyDictionary()


def floating_twin(model: Model) -> Model:
    """Return the floating-base model of a fixed-base ``model`` (built once per model).

    Body 1 is the base on a free-flyer (``'root_joint'``, ``Xtree = 1``) with the inertia of
    the links fixed to the base (``model.inertia[0]``); body ``i + 1`` is ``model``'s body
    ``i``; ``q = [p, quaternion, q]``, ``q̇ = [v, q̇]``. Its joint rows are ``model``'s on a
    moving base; its base rows are the wrench on the base (base frame) that moves it so.
    """
    twin = _twins.get(model)
    if twin is not None:
        return twin
    if model.floating:
        raise ValueError(f'{shown(model.name)} has a floating base already')
    NB = model.NB + 1
    shift = np.r_[-1, 0, model.parent[1:] + 1].astype(np.intp)
    six_nan, six_zero = np.full(6, np.nan), np.zeros(6)
    twin = Model(
        name=model.name, joint_names=(ROOT_JOINT,) + tuple(model.joint_names),
        body_names=('universe',) + tuple(model.body_names),
        body_joints=('', ROOT_JOINT) + tuple(model.body_joints[1:]), NB=NB, parent=shift,
        jtype=np.r_[FIXED, FREE_FLYER, model.jtype[1:]].astype(np.intp),
        axis=np.r_[np.zeros((2, 3)), model.axis[1:]],
        Xtree=np.r_[np.eye(6)[None], np.eye(6)[None], model.Xtree[1:]],
        inertia=np.r_[np.zeros((1, 6, 6)), model.inertia],
        qidx=np.r_[-1, 0, model.qidx[1:] + 7].astype(np.intp),
        vidx=np.r_[-1, 0, model.vidx[1:] + 6].astype(np.intp),
        qmul=np.r_[0.0, 1.0, model.qmul[1:]], qoff=np.r_[0.0, 0.0, model.qoff[1:]],
        frames={name: Frame(f.body + 1, f.lXb) for name, f in model.frames.items()},
        effort_limit=np.r_[six_nan, model.effort_limit],
        velocity_limit=np.r_[six_nan, model.velocity_limit],
        lower=np.r_[six_nan, model.lower], upper=np.r_[six_nan, model.upper],
        damping=np.r_[six_zero, model.damping], friction=np.r_[six_zero, model.friction],
        body_damping=np.r_[0.0, model.body_damping],
        body_friction=np.r_[0.0, model.body_friction],
        lumped=model.lumped, locked=dict(model.locked), warnings=model.warnings,
        joint_types=dict(model.joint_types), mimics=dict(model.mimics))
    _twins[model] = twin
    return twin


_ORIGIN = np.zeros(3)


def check_base_motion(base, model: Optional[Model] = None) -> None:
    """Refuse a ``base=`` that no function taking it can use.

    ``TypeError`` naming what ``base`` is, unless it is a :class:`BaseMotion`; with
    ``model``, ``ValueError`` when ``model`` has a floating base already (its base's motion
    is its free-flyer's ``q``, ``q̇``, ``q̈``): every public function taking ``base=`` calls
    this, so none answers a floating model's base twice.
    """
    if not isinstance(base, BaseMotion):
        raise TypeError("base must be a spatial_dynamics.BaseMotion (the base's v, a and "
                        f'orientation), got {type(base).__name__}')
    if model is not None and model.floating:
        raise ValueError(f'base=: {shown(model.name)} has a floating base already, whose motion '
                         "is its free-flyer's q, q̇ and q̈: load it with base='fixed' to "
                         'give a base motion')


def base_batches(base: BaseMotion) -> list:
    """Return the batch shapes of ``base``'s arrays, labelled for :func:`.arguments.batch_of`."""
    arrays = [('base.v', base.v), ('base.a', base.a)] + (
        [] if base.orientation is None else [('base.orientation', base.orientation)])
    return [(f'{name} of shape {x.shape}', x.shape[:-1]) for name, x in arrays]


def twin_state(model: Model, base: BaseMotion, q, qd=None, qdd=None, gravity=None):
    """Return the twin's ``(q, q̇, q̈, gravity)`` for ``model``'s ``q, q̇, q̈`` on ``base``.

    ``q̇``/``q̈`` ``None`` are zero; arrays broadcast against the base's batch. ``gravity``
    becomes zero when the base's ``a`` includes it.
    """
    check_base_motion(base, model)
    zero = np.zeros(model.nv)
    q, qd, qdd = as_joint_arrays(model, q, zero if qd is None else qd,
                                 zero if qdd is None else qdd)
    quat = base.orientation if base.orientation is not None else np.array([0.0, 0, 0, 1])
    batch = batch_of((f'the joints\' states of shape {q.shape}', q.shape[:-1]),
                     *base_batches(base))

    def joined(head, x):
        head = np.broadcast_to(head, batch + head.shape[-1:])
        return np.concatenate([head, np.broadcast_to(x, batch + x.shape[-1:])],
                              -1).astype(q.dtype, copy=False)

    if base.gravity_included:
        gravity = (0.0, 0.0, 0.0)
    if not batch:       # one state (a node's answer): nothing to broadcast
        cat, dtype = np.concatenate, q.dtype
        return (cat((_ORIGIN, quat, q)).astype(dtype, copy=False),
                cat((base.v, qd)).astype(dtype, copy=False),
                cat((base.a, qdd)).astype(dtype, copy=False), gravity)
    pose = np.concatenate([np.zeros(quat.shape[:-1] + (3,)), quat], -1)
    return joined(pose, q), joined(base.v, qd), joined(base.a, qdd), gravity
