# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The base's messages read into arrays, each field checked, without ROS.

Pure Python + numpy + the library (no rclpy import), tested in
``test/test_node_base_inputs.py``: the readers of ``sensor_msgs/Imu``,
``geometry_msgs/PoseStamped`` (and ``nav_msgs/Odometry``'s pose), ``geometry_msgs/Twist`` and
``geometry_msgs/Wrench``, the twist's rate (:func:`twist_rate`) and the link a twist is of
(:func:`twist_link`). Each raises :class:`~.inputs.InputError` naming the field; what the
node holds of them is :class:`~.bases.BaseInputs`'.
"""

from __future__ import annotations

from typing import Optional, Tuple

import numpy as np
import spatial_dynamics as sd
from spatial_dynamics.bounds import (check_bounded, MAX_IMU_RATE, MAX_IMU_SPECIFIC_FORCE,
                                     MAX_POSITION, MAX_VELOCITY, MAX_WRENCH)
from spatial_dynamics.ros.inputs import InputError
from spatial_dynamics.ros.text import shown

#: ``|‖quaternion‖ − 1|`` accepted (then normalised): the library's, for every quaternion read.
QUATERNION_TOLERANCE = sd.joints.QUATERNION_TOLERANCE

_XYZ = ('x', 'y', 'z')


def _vector(what: str, values, bound: float, unit: str, names) -> np.ndarray:
    """``values`` as an array, or InputError (non_finite, out_of_bounds) naming the field."""
    x = np.array(values, dtype=float)
    reason = check_bounded(what, x, bound, unit, names)
    if reason:
        raise InputError('non_finite' if 'not finite' in reason else 'out_of_bounds', reason)
    return x


def unit_quaternion(what: str, o) -> np.ndarray:
    """``(x, y, z, w)`` of a ``geometry_msgs/Quaternion``, normalised; InputError if not unit."""
    quat = _vector(what, (o.x, o.y, o.z, o.w), 2.0, '', ('x', 'y', 'z', 'w'))
    norm = float(np.linalg.norm(quat))
    if abs(norm - 1.0) > QUATERNION_TOLERANCE:
        raise InputError('not_unit', f'{what} has norm {norm:g}, not a unit quaternion '
                         f'(tolerance {QUATERNION_TOLERANCE:g})')
    return quat / norm


def twist_array(twist) -> np.ndarray:
    """``[ω; v]`` (6,) of a ``geometry_msgs/Twist`` (rad/s, m/s), bounded."""
    w, v = twist.angular, twist.linear
    return _vector('twist', (w.x, w.y, w.z, v.x, v.y, v.z), MAX_VELOCITY, 'rad/s or m/s',
                   [f'angular.{a}' for a in _XYZ] + [f'linear.{a}' for a in _XYZ])


def pose_arrays(msg) -> Tuple[np.ndarray, np.ndarray]:
    """``(position (3,), quaternion (4,) x y z w)`` of what has a ``pose``.

    A ``geometry_msgs/PoseStamped``, or ``nav_msgs/Odometry``'s ``PoseWithCovariance``.
    """
    p = msg.pose.position
    position = _vector('pose.position', (p.x, p.y, p.z), MAX_POSITION, 'm', _XYZ)
    return position, unit_quaternion('pose.orientation', msg.pose.orientation)


def imu_arrays(msg) -> Tuple[np.ndarray, np.ndarray]:
    """``(specific force (3,) m/s², ω (3,) rad/s)`` of a ``sensor_msgs/Imu``.

    Each axis bounded by what an IMU reports (:data:`~spatial_dynamics.bounds.MAX_IMU_RATE`,
    :data:`~spatial_dynamics.bounds.MAX_IMU_SPECIFIC_FORCE`).
    """
    a, w = msg.linear_acceleration, msg.angular_velocity
    return (_vector('linear_acceleration', (a.x, a.y, a.z), MAX_IMU_SPECIFIC_FORCE, 'm/s²',
                    _XYZ),
            _vector('angular_velocity', (w.x, w.y, w.z), MAX_IMU_RATE, 'rad/s', _XYZ))


def wrench_array(what: str, wrench) -> np.ndarray:
    """``[n; f]`` (6,) of a ``geometry_msgs/Wrench`` (N m, N), bounded."""
    t, f = wrench.torque, wrench.force
    return _vector(what, (t.x, t.y, t.z, f.x, f.y, f.z), MAX_WRENCH, 'N m or N',
                   [f'torque.{a}' for a in _XYZ] + [f'force.{a}' for a in _XYZ])


def twist_rate(before: Optional[np.ndarray], v_before: np.ndarray, v: np.ndarray, dt: float,
               time_constant: float, max_linear: float, max_angular: float) -> np.ndarray:
    """Return the base's acceleration ``[ω̇; v̇]`` (6,) from two twists ``dt`` s apart.

    The difference ``(v − v_before) / dt`` low-pass filtered over the stamps,
    ``a = before + (1 − exp(−dt / T)) (Δv / dt − before)`` (``before`` None: a first
    difference, taken as it is; ``T`` 0: unfiltered), so a jump ``Δv`` moves ``a`` by at
    most ``Δv / T``. InputError (out_of_bounds) when ``|ω̇|`` or ``|v̇|`` exceeds what a
    real base reaches (``max_angular`` rad/s², ``max_linear`` m/s²): naming the norm.
    """
    raw = (v - v_before) / dt
    if before is None or time_constant <= 0.0:
        a = raw
    else:
        a = before + (-np.expm1(-dt / time_constant)) * (raw - before)
    for part, bound, unit, param in ((a[:3], max_angular, 'rad/s²', 'angular'),
                                     (a[3:], max_linear, 'm/s²', 'linear')):
        norm = float(np.linalg.norm(part))
        if not norm <= bound:
            raise InputError('out_of_bounds', f'the twist differenced over {dt:.3g} s gives a '
                             f'base {param} acceleration of {norm:.3g} {unit}, beyond '
                             f'base_input.max_{param}_acceleration {bound:g} {unit}; the last '
                             'good acceleration kept')
    return a


def twist_link(model: 'sd.Model', frame: str, field: str, odometry_link: str = '',
               odometry_frame: str = '') -> str:
    """Return the link of ``model`` a base twist in ``frame`` is of ('' = the root link).

    ``frame`` is the message's ``field`` (``child_frame_id`` of ``nav_msgs/Odometry``,
    ``header.frame_id`` of ``geometry_msgs/TwistStamped``): a link of the model, or exactly
    ``odometry_frame`` (the frame a source writes that the URDF does not have, the
    ``base_footprint`` of a typical /odom), which is ``odometry_link`` ('' = the root link);
    empty is ``odometry_link`` too. Any other frame (a typo, another robot's odometry) is
    InputError (wrong_frame) naming ``field``, as is a link other than the root link or (fixed
    base) a link fixed to it.
    """
    aliased = not frame or (odometry_frame and frame == odometry_frame)
    link = odometry_link if aliased else frame
    root = model.body_names[1 if model.floating else 0]
    if link and link not in model.frames:
        known = (f', nor base_input.odometry_frame {shown(odometry_frame)}' if odometry_frame
                 else '')
        raise InputError('wrong_frame', f'{field} {shown(frame)} is not a link of the model'
                         f"{known}: the twist must be the base's, in its frame {shown(root)}" + (
                             '' if model.floating else ' or a link fixed to it') + (
                             f'; if {shown(frame)} is the frame your odometry writes, set '
                             f'base_input.odometry_frame to {shown(frame)} and '
                             'base_input.odometry_link to the link of the URDF it is'))
    if link and link != root and (model.floating or model.frames[link].body != 0):
        where = 'a link that moves with a joint' if not model.floating else 'not the root link'
        raise InputError('wrong_frame', f'{field} {shown(frame)} is {where}: the twist must be '
                         f"the base's, in its frame {shown(root)}" + (
                             '' if model.floating else ' or a link fixed to it'))
    return link
