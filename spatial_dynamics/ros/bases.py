# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The node on a moving or floating base, without ROS: the base's inputs held, their answers.

Pure Python + numpy + the library (no rclpy import), tested in
``test/test_node_base_inputs.py``. Parameter ``base`` (read-only):

===========  ===================================================================================
``fixed``    today's node: the URDF's root link is fixed to the world (default).
``moving``   the fixed-base model on a moving base (a mobile manipulator, a ship): each answer
             is ``rnea(..., base=motion)`` with the base's motion from an IMU on the base
             (``base_input.source: imu``: :func:`~spatial_dynamics.base_from_imu`, its link the
             ``base_input.imu_link``) or from its pose and twist (``base_input.source: twist``:
             :func:`~spatial_dynamics.base_from_odometry`).
``floating`` the model loaded with ``base='floating'`` (a legged robot): the base's pose and
             twist come from ``base/pose`` and ``base/twist``, the joints' from the desired
             (or measured) joint state, and :func:`~spatial_dynamics.contact_inverse_dynamics`
             splits ``M q̈ + h`` between the joints' efforts and the contact wrenches of
             ``contacts.links``; a split that makes a contact pull (beyond
             :func:`pull_tolerance`) is re-solved by the QP, or refused; one that leaves
             the base unbalanced (:func:`residual_tolerance`: the contacts in contact cannot
             carry it) or has no contact in force is refused (:class:`FloatingDynamics`).
             ``contacts.links`` is required.
===========  ===================================================================================

Inputs (each sampled, checked and held; an answer whose base input is missing or older than
``base_input.timeout`` is refused, reason named in /diagnostics, never computed on a fixed base):

* ``base/imu`` (``sensor_msgs/Imu``): ``linear_acceleration`` is the specific force
  ``r̈ − g`` and ``angular_velocity`` ``ω`` in the IMU's frame, which is
  ``base_input.imu_link`` (its placement from the URDF; ``header.frame_id`` that link,
  ``base_input.imu_frame`` or empty). ``ω̇`` is taken as zero. Each axis within what an IMU
  reports (:data:`~spatial_dynamics.bounds.MAX_IMU_RATE`,
  :data:`~spatial_dynamics.bounds.MAX_IMU_SPECIFIC_FORCE`).
* ``base/pose`` (``geometry_msgs/PoseStamped``): the pose in the world (``header.frame_id``,
  any) of the frame of ``base/twist`` (the root link; moving: or a link fixed to it), as
  ``nav_msgs/Odometry``'s pose of its ``child_frame_id``; a unit quaternion (x y z w) within
  :data:`QUATERNION_TOLERANCE`.
* ``base/odometry`` (``nav_msgs/Odometry``): its pose and the twist of its
  ``child_frame_id``, held as ``base/pose`` and ``base/twist`` (either input, or both).
* ``base/twist`` (``geometry_msgs/TwistStamped``): the twist of the root link (or, moving, of a
  link fixed to it) in its own axes, ``header.frame_id`` that link or empty: what
  ``nav_msgs/Odometry`` carries in its child frame. A frame that is not a link of the URDF
  (``base_footprint``) must be exactly ``base_input.odometry_frame``, then taken as
  ``base_input.odometry_link`` (:func:`twist_link`); any other is refused (``wrong_frame``).
  Its rate, the base's spatial acceleration, is the difference of successive samples over
  their stamps (``base_input.acceleration: difference``: no closer than
  ``base_input.min_interval``, low-pass filtered and bounded by what a base reaches,
  :func:`twist_rate`; a refused twist keeps the last good one) or zero (``zero``: a base at
  constant twist).
* ``contact_states`` (``std_msgs/UInt8MultiArray``): one flag per ``contacts.links``, non-zero
  = in contact; until the first message every link of ``contacts.links`` is in contact.
* ``measured_contact_wrenches`` (``geometry_msgs/WrenchStamped``, with ``contacts.measured``):
  a foot sensor's wrench on the robot, ``header.frame_id`` the link of ``contacts.links``,
  ``[n; f]`` in its frame at its origin; the efforts are then ``(M q̈ + h − J_cᵀ λ)`` of the
  joints for the measured ``λ``, and the base rows' residual says how consistent they are.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from typing import List, Optional, Tuple

import numpy as np
import spatial_dynamics as sd
from spatial_dynamics.bounds import (check_bounded, MAX_IMU_RATE, MAX_IMU_SPECIFIC_FORCE,
                                     MAX_POSITION, MAX_VELOCITY, MAX_WRENCH)
from spatial_dynamics.contacts import link_orientations
from spatial_dynamics.ros.control import Dynamics
from spatial_dynamics.ros.inputs import InputError, stamp_ns
from spatial_dynamics.ros.parameters import ConfigError

#: Values of the ``base`` parameter.
BASES = ('fixed', 'moving', 'floating')
#: Values of ``base_input.source`` (a moving base's motion).
BASE_SOURCES = ('imu', 'twist')
#: Values of ``base_input.acceleration``: the twist's rate differenced, or zero.
BASE_ACCELERATIONS = ('difference', 'zero')
#: Values of ``contacts.kind`` and ``contacts.method`` (the library's).
CONTACT_KINDS = sd.contacts.KINDS
CONTACT_METHODS = sd.contacts.METHODS
#: ``|‖quaternion‖ − 1|`` accepted (then normalised): the library's, for every quaternion read.
QUATERNION_TOLERANCE = sd.joints.QUATERNION_TOLERANCE
#: Why an answer is refused on a moving or floating base (diagnostics counter keys).
BASE_REASONS = ('base_missing', 'base_stale', 'contacts_stale', 'contacts_unsolved',
                'contacts_missing', 'contacts_pull', 'no_contact')
#: Why a base input message is refused.
BASE_INPUT_REASONS = ('non_finite', 'out_of_bounds', 'not_unit', 'wrong_frame', 'unstamped',
                      'stamp_not_increasing', 'interval_too_short', 'length_mismatch',
                      'no_model', 'unknown_link')
#: A contact pulls when its normal force ``n·f`` is below ``−PULL_TOLERANCE · m · 9.81`` N, ``m``
#: the model's mass (:func:`pull_tolerance`): relative to the weight, because the split's
#: rounding and the QP's convergence tolerance (relative, ~1e-8) scale with the forces, which
#: scale with the weight; an absolute 1e-6 N would refuse a 100 kg robot's QP answers for
#: their solver noise, and let a 0.1 kg one pull a tenth of a mN unseen.
PULL_TOLERANCE = 1e-6
#: A split leaves the base rows unbalanced when a component of its base residual
#: ``(M q̈ + h)_base − J_c,baseᵀ λ`` (N m, N) exceeds ``RESIDUAL_TOLERANCE · m · 9.81``
#: (:func:`residual_tolerance`), relative to the weight as :data:`PULL_TOLERANCE` and for the
#: same reasons: the contacts in force cannot carry the base (one foot, none), the answer is
#: refused (``contacts_unsolved``). A split that carries it leaves rounding (~1e-15 of the
#: weight); the QP its convergence tolerance (~1e-8).
RESIDUAL_TOLERANCE = 1e-6

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
        known = (f', nor base_input.odometry_frame {odometry_frame!r}' if odometry_frame
                 else '')
        raise InputError('wrong_frame', f'{field} {frame!r} is not a link of the model{known}: '
                         f"the twist must be the base's, in its frame {root!r}" + (
                             '' if model.floating else ' or a link fixed to it') + (
                             f'; if {frame!r} is the frame your odometry writes, set '
                             f'base_input.odometry_frame to {frame!r} and '
                             'base_input.odometry_link to the link of the URDF it is'))
    if link and link != root and (model.floating or model.frames[link].body != 0):
        where = 'a link that moves with a joint' if not model.floating else 'not the root link'
        raise InputError('wrong_frame', f'{field} {frame!r} is {where}: the twist must be the '
                         f"base's, in its frame {root!r}" + (
                             '' if model.floating else ' or a link fixed to it'))
    return link


def check_base(params, model: 'sd.Model', source: str) -> None:
    """Check the base parameters against ``model`` (ConfigError naming the parameter)."""
    if params.base == 'fixed':
        return
    links = tuple(params.contacts_links or ())
    for link in links:
        if link not in model.frames:
            raise ConfigError(f'parameter contacts.links: {link!r} is not a link of robot '
                              f'{model.name!r} ({source})')
    if params.base == 'moving':
        if params.base_input_source == 'imu':
            link = params.base_input_imu_link
            if not link:
                raise ConfigError("parameter base_input.imu_link: base_input.source 'imu' "
                                  'needs the link the IMU is mounted on (or set '
                                  "base_input.source 'twist' to take the base's motion from "
                                  'base/odometry, or base/pose and base/twist)')
            try:
                sd.base_from_imu(model, link, np.zeros(3), np.zeros(3))
            except ValueError as err:
                raise ConfigError(f'parameter base_input.imu_link: {err}') from None
        if links:
            raise ConfigError("parameter contacts.links: contacts need base 'floating' (a "
                              "moving base's motion is given, nothing carries it)")
    elif not links:
        raise ConfigError('parameter contacts.links: a floating base needs contacts to carry '
                          f'it: set the links of robot {model.name!r} that touch the ground '
                          '(feet, soles), e.g. contacts.links:=[FL_FOOT, FR_FOOT, HL_FOOT, '
                          f'HR_FOOT] ({source})')
    link, frame = params.base_input_odometry_link, params.base_input_odometry_frame
    if link:
        if link not in model.frames:
            raise ConfigError(f'parameter base_input.odometry_link: {link!r} is not a link of '
                              f'robot {model.name!r} ({source})')
        try:
            twist_link(model, link, 'base_input.odometry_link')
        except InputError as err:
            raise ConfigError(f'parameter base_input.odometry_link: {err}') from None
    if frame in model.frames:
        raise ConfigError(f'parameter base_input.odometry_frame: {frame!r} is a link of robot '
                          f'{model.name!r} ({source}), taken as itself: odometry_frame names '
                          'a frame the URDF does not have (e.g. base_footprint)')
    off = observer_off(params)
    if params.wrench_estimate_link and off:
        raise ConfigError(f'parameter wrench_estimate.link: not supported with {off}')


def observer_off(params) -> str:
    """Why the external-torque observer cannot run on this base ('' when it can).

    It needs the base's twist and orientation (see :mod:`~spatial_dynamics.ros.observer`):
    a fixed base, or a moving one with ``base_input.source: twist``. An IMU gives the twist
    only integrated (its drift would enter the momentum), and a floating base's twist is the
    robot's own state, not a given motion.
    """
    if params.base == 'fixed' or (params.base == 'moving'
                                  and params.base_input_source == 'twist'):
        return ''
    if params.base == 'moving':
        return ("base moving with base_input.source imu: the observer needs the base's "
                'twist, which an IMU gives only integrated (base_input.source twist gives it)')
    return (f'base {params.base}: the observer needs a base whose motion is given (fixed, or '
            'moving with base_input.source twist)')


def source_hint(params, inputs: 'BaseInputs') -> str:
    """Return what to set when the inputs that arrive are not those ``base_input.source`` reads.

    '' when they are (or nothing arrived): a moving base on ``imu`` receiving only
    odometry, pose or twist messages, or on ``twist`` receiving only IMU messages.
    """
    if params.base != 'moving':
        return ''
    received = inputs.received
    odometry = [t for t in ('base/odometry', 'base/pose', 'base/twist') if received[t]]
    if params.base_input_source == 'imu' and odometry and not received['base/imu']:
        return (f"{' and '.join(odometry)} arrive but base_input.source is 'imu': set "
                "base_input.source 'twist' to use them")
    if params.base_input_source == 'twist' and received['base/imu'] and not odometry:
        return ("base/imu arrives but base_input.source is 'twist': set base_input.source "
                "'imu' (and base_input.imu_link) to use it")
    return ''


def pull_tolerance(model: 'sd.Model') -> float:
    """Return the N by which a contact may pull: :data:`PULL_TOLERANCE` of ``m · 9.81``."""
    return PULL_TOLERANCE * float(model.inertia[:, 3, 3].sum()) * 9.81


def residual_tolerance(model: 'sd.Model') -> float:
    """Return the base residual (N m, N) a split may leave: :data:`RESIDUAL_TOLERANCE` · m g."""
    return RESIDUAL_TOLERANCE * float(model.inertia[:, 3, 3].sum()) * 9.81


def qp_missing_warning(robot) -> str:
    """Return the WARN, once at configuration, of a floating base without its QP ('': none)."""
    if robot is None or not robot.qp_missing:
        return ''
    return ('contacts: the QP that re-solves a split making a contact pull cannot run '
            f'({robot.qp_missing}); answering with contacts.method alone, and refusing '
            'each answer whose split makes a contact pull (contacts_pull in /diagnostics)')


def _same(a: Optional[tuple], b: tuple) -> bool:
    """Whether two keys hold the same objects (identity: a model is not compared by value)."""
    return a is not None and len(a) == len(b) and all(x is y for x, y in zip(a, b))


class Held:
    """A checked base input: its arrays, its stamp (ns) and its receipt (monotonic ns)."""

    def __init__(self, value: tuple, stamp_ns: int, receipt_ns: int) -> None:
        self.value, self.stamp_ns, self.receipt_ns = value, stamp_ns, receipt_ns


@dataclass
class BaseWindow:
    """What the contact solutions of one diagnostics period said."""

    solved: int = 0
    residual_max: float = 0.0
    violations: Counter = field(default_factory=Counter)   # 'contact kind' -> count
    worst: dict = field(default_factory=dict)               # 'contact kind' -> largest N
    last: str = ''
    resolved: int = 0           # answers re-solved by qp: the split made a contact pull
    refused: Counter = field(default_factory=Counter)      # pulling answers refused, by reason
    pull_max: float = 0.0       # the worst pull seen (N) of those, and its contact
    pull_contact: str = ''
    refused_last: str = ''      # why the last of them was refused
    unsolved: int = 0           # answers refused: the contacts could not carry the base
    unsolved_residual: float = 0.0   # the largest base residual of those (N m, N)
    unsolved_last: str = ''     # why the last of them was refused


class BaseInputs:
    """The base's inputs held between messages (see the module docstring); counters."""

    def __init__(self) -> None:
        self.imu: Optional[Held] = None
        self.pose: Optional[Held] = None
        self.twist: Optional[Held] = None
        self.rate: Optional[np.ndarray] = None    # the differenced twist, (6,)
        self.flags: Optional[Held] = None
        self.measured: dict = {}                   # link -> Held([n; f] in the link's frame)
        self.received: Counter = Counter()
        self._contacts: tuple = (None, ())    # (key, the Contacts of contacts.links in force)
        self.rejected: Counter = Counter()
        self.window = BaseWindow()
        self._motion: tuple = (None, None)         # (what it was made from, BaseMotion)
        self._velocity: tuple = (None, None)       # the same, the observer's (twist only)

    def period(self) -> BaseWindow:
        """Return the contact figures of the period that ended; start new ones."""
        window, self.window = self.window, BaseWindow()
        return window

    # -- inputs ---------------------------------------------------------------------------------
    def take(self, topic: str, config, msg, now_ns: int) -> Optional[str]:
        """Check and hold one base input; return why it was refused (None: taken)."""
        self.received[topic] += 1
        try:
            if config.robot is None:
                raise InputError('no_model', 'no robot model loaded yet')
            getattr(self, '_take_' + topic.replace('/', '_'))(config, msg, now_ns)
        except InputError as err:
            self.rejected[f'{topic} {err.reason}'] += 1
            return f'{topic}: message rejected ({err.reason}): {err}'
        return None

    def _take_base_imu(self, config, msg, now_ns: int) -> None:
        params = config.params
        link, alias = params.base_input_imu_link, params.base_input_imu_frame
        if msg.header.frame_id not in ('', link, alias or link):
            raise InputError('wrong_frame', f'header.frame_id {msg.header.frame_id!r} is not '
                             f'base_input.imu_link {link!r}, the IMU frame of the model' + (
                                 f', nor base_input.imu_frame {alias!r}' if alias else
                                 ' (set base_input.imu_frame to the frame the IMU driver '
                                 'writes)'))
        self.imu = Held(imu_arrays(msg), stamp_ns(msg.header), now_ns)

    def _take_base_pose(self, config, msg, now_ns: int) -> None:
        self.pose = Held(pose_arrays(msg), stamp_ns(msg.header), now_ns)

    def _take_base_odometry(self, config, msg, now_ns: int) -> None:
        """``nav_msgs/Odometry``: its pose and its ``child_frame_id``'s twist, both or neither."""
        pose = pose_arrays(msg.pose)
        self._hold_twist(config, msg.twist.twist, msg.child_frame_id, 'child_frame_id',
                         stamp_ns(msg.header), now_ns)
        self.pose = Held(pose, stamp_ns(msg.header), now_ns)

    def _take_base_twist(self, config, msg, now_ns: int) -> None:
        self._hold_twist(config, msg.twist, msg.header.frame_id, 'header.frame_id',
                         stamp_ns(msg.header), now_ns)

    def _hold_twist(self, config, twist, frame: str, field: str, stamp: int,
                    now_ns: int) -> None:
        """Check and hold the base's ``twist`` (a ``geometry_msgs/Twist``) in ``frame``.

        ``field`` names where the message carries ``frame``: a link of the model, or
        ``base_input.odometry_frame``, taken as ``base_input.odometry_link`` (:func:`twist_link`).
        """
        robot, params = config.robot, config.params
        frame = twist_link(robot.base, frame, field, params.base_input_odometry_link,
                           params.base_input_odometry_frame)
        v = twist_array(twist)
        before = self.twist
        rate = None
        if params.base_input_acceleration == 'difference':
            if stamp == 0:
                raise InputError('unstamped', 'header.stamp is 0: base_input.acceleration '
                                 "'difference' differences the twist over its stamps")
            fresh = (before is not None and before.value[1] == frame
                     and (now_ns - before.receipt_ns) * 1e-9 <= params.base_input_timeout)
            if fresh:
                dt = (stamp - before.stamp_ns) * 1e-9
                if dt <= 0.0:
                    raise InputError('stamp_not_increasing', f'header.stamp {stamp * 1e-9:.9f} '
                                     f's is not after the last twist\'s '
                                     f'{before.stamp_ns * 1e-9:.9f} s')
                if dt < params.base_input_min_interval:
                    raise InputError('interval_too_short', f'header.stamp {dt:.3g} s after the '
                                     'last twist\'s, less than base_input.min_interval '
                                     f'{params.base_input_min_interval:g} s (the source\'s '
                                     'period): not differenced; the last good acceleration '
                                     'kept')
                rate = twist_rate(self.rate, before.value[0], v, dt,
                                  params.base_input_acceleration_time_constant,
                                  params.base_input_max_linear_acceleration,
                                  params.base_input_max_angular_acceleration)
        self.twist = Held((v, frame), stamp, now_ns)
        self.rate = rate

    def _take_contact_states(self, config, msg, now_ns: int) -> None:
        links = tuple(config.params.contacts_links or ())
        if len(msg.data) != len(links):
            raise InputError('length_mismatch', f'{len(msg.data)} flags for the '
                             f'{len(links)} contacts.links {list(links)}')
        self.flags = Held(tuple(bool(x) for x in msg.data), 0, now_ns)

    def _take_measured_contact_wrenches(self, config, msg, now_ns: int) -> None:
        link = msg.header.frame_id
        links = tuple(config.params.contacts_links or ())
        if link not in links:
            raise InputError('unknown_link', f'header.frame_id {link!r} is not one of '
                             f'contacts.links {list(links)}')
        t, f = msg.wrench.torque, msg.wrench.force
        wrench = _vector(f'wrench on {link!r}', (t.x, t.y, t.z, f.x, f.y, f.z), MAX_WRENCH,
                         'N m or N', [f'torque.{a}' for a in _XYZ] + [f'force.{a}' for a in _XYZ])
        self.measured[link] = Held(wrench, stamp_ns(msg.header), now_ns)

    def _measured(self, params, contacts, now_ns: int) -> Optional[dict]:
        """Link -> measured ``[n; f]`` (link frame) of each contact in force, or None (off)."""
        if not params.contacts_measured:
            return None
        result = {}
        for contact in contacts:
            held = self.measured.get(contact.link)
            if held is None:
                raise InputError('contacts_missing', f'contacts.measured: no measured wrench '
                                 f'of {contact.link!r} yet; not publishing')
            result[contact.link] = self._fresh(params, held, 'measured_contact_wrenches of '
                                               f'{contact.link!r}', now_ns)
        return result

    # -- what an answer needs -------------------------------------------------------------------
    def _fresh(self, params, held: Optional[Held], topic: str, now_ns: int) -> tuple:
        if held is None:
            raise InputError('base_missing', f'no good {topic} yet (base {params.base}); '
                             'not publishing')
        age = (now_ns - held.receipt_ns) * 1e-9
        if age > params.base_input_timeout:
            raise InputError('base_stale', f'{topic} is {age:.3f} s old (base_input.timeout '
                             f'{params.base_input_timeout} s); not publishing')
        return held.value

    def _rate(self, params, topic: str) -> np.ndarray:
        if params.base_input_acceleration == 'zero':
            return np.zeros(6)
        if self.rate is None:
            raise InputError('base_missing', f'{topic}: base_input.acceleration difference needs '
                             'two successive twists (one so far, or a gap); not publishing')
        return self.rate

    def motion(self, config, now_ns: int) -> 'sd.BaseMotion':
        """Return a moving base's motion now; InputError (base_missing, base_stale): unknown."""
        params, model = config.params, config.robot.model
        if params.base_input_source == 'imu':
            hint = source_hint(params, self)
            if hint and self.imu is None:
                raise InputError('base_missing', f'no good base/imu yet (base moving); {hint}; '
                                 'not publishing')
            f, w = self._fresh(params, self.imu, 'base/imu', now_ns)
            key = (model, params.base_input_imu_link, self.imu)
            if not _same(self._motion[0], key):   # once per sample, not per answer
                self._motion = key, sd.base_from_imu(model, key[1], f, w)
            return self._motion[1]
        hint = source_hint(params, self)
        if hint and (self.pose is None or self.twist is None):
            raise InputError('base_missing', f'no good base/odometry (or base/pose and '
                             f'base/twist) yet (base moving); {hint}; not publishing')
        _, quat = self._fresh(params, self.pose, 'base/pose', now_ns)
        v, frame = self._fresh(params, self.twist, 'base/twist', now_ns)
        rate = self._rate(params, 'base/twist')
        key = (model, self.pose, self.twist, params.base_input_acceleration)
        if not _same(self._motion[0], key):
            self._motion = key, sd.base_from_odometry(model, v, rate, quat, link=frame or None)
        return self._motion[1]

    def velocity(self, config, now_ns: int) -> 'sd.BaseMotion':
        """Return a moving base's twist and orientation now, its acceleration zero.

        What the observer needs (``base_input.source: twist``): the last ``base/twist`` and
        ``base/pose`` (or ``base/odometry``), whatever ``base_input.acceleration`` says.
        InputError (base_missing, base_stale) when either is missing or stale.
        """
        params, model = config.params, config.robot.model
        _, quat = self._fresh(params, self.pose, 'base/pose', now_ns)
        v, frame = self._fresh(params, self.twist, 'base/twist', now_ns)
        key = (model, self.pose, self.twist)
        if not _same(self._velocity[0], key):
            self._velocity = key, sd.base_from_odometry(model, v, np.zeros(6), quat,
                                                        link=frame or None)
        return self._velocity[1]

    def contacts(self, config, now_ns: int) -> Tuple['sd.Contact', ...]:
        """Return the contacts in force now (``contacts.links`` filtered by ``contact_states``)."""
        params = config.params
        links = tuple(params.contacts_links or ())
        flags = (True,) * len(links)
        if self.flags is not None:
            age = (now_ns - self.flags.receipt_ns) * 1e-9
            if age > params.base_input_timeout:
                raise InputError('contacts_stale', f'contact_states is {age:.3f} s old '
                                 f'(base_input.timeout {params.base_input_timeout} s); '
                                 'not publishing')
            if len(self.flags.value) != len(links):   # contacts.links changed since
                raise InputError('contacts_stale', f'contact_states has '
                                 f'{len(self.flags.value)} flags for the {len(links)} '
                                 f'contacts.links {list(links)}; not publishing')
            flags = self.flags.value
        key = (links, params.contacts_kind, params.contacts_mu, flags)
        if self._contacts[0] != key:     # the same Contacts each answer: the library's plan
            self._contacts = key, tuple(   # for them is cached, their checks made once
                sd.Contact(link, kind=params.contacts_kind, mu=params.contacts_mu)
                for link, touching in zip(links, flags) if touching)
        return self._contacts[1]

    def dynamics(self, config, f_ext, now_ns: int) -> Dynamics:
        """Return the :class:`~.control.Dynamics` of an answer on this base (InputError: none)."""
        robot, params = config.robot, config.params
        if params.base == 'moving':
            return Dynamics(robot.model, params.gravity, robot.backend, robot.armature,
                            robot.friction_threshold, f_ext, self.motion(config, now_ns))
        position, quat = self._fresh(params, self.pose, 'base/pose', now_ns)
        v, _ = self._fresh(params, self.twist, 'base/twist', now_ns)
        contacts = self.contacts(config, now_ns)
        return FloatingDynamics(
            robot.model, params.gravity, robot.backend, robot.armature,
            robot.friction_threshold, f_ext,
            None, np.concatenate((position, quat)), v, self._rate(params, 'base/twist'),
            contacts, params.contacts_method, [], self._measured(params, contacts, now_ns),
            robot.qp_missing, robot.pull_tolerance, [], robot.residual_tolerance, [])

    def solved(self, result: 'sd.ContactResult', tolerance: float) -> None:
        """Count a contact solution's residual and violations for the period.

        A normal force below zero by no more than ``tolerance`` (:func:`pull_tolerance`) is
        rounding, not a pull.
        """
        window = self.window
        window.solved += 1
        window.residual_max = max(window.residual_max,
                                  float(np.abs(result.base_residual).max()))
        for violation in result.violations:
            if violation.kind == 'unilateral' and violation.amount <= tolerance:
                continue
            key = f'{violation.contact} {violation.kind}'
            window.violations[key] += 1
            window.worst[key] = max(window.worst.get(key, 0.0), violation.amount)
        window.last = result.summary()

    def pulled(self, pulls: list, refused: Optional[InputError] = None) -> None:
        """Count an answer whose split made a contact pull: re-solved by qp, or ``refused``.

        ``pulls``: the :class:`~spatial_dynamics.contacts.Violation` s (``unilateral``) of the
        answer's splits (:attr:`FloatingDynamics.pulls`).
        """
        window = self.window
        if refused is None:
            window.resolved += 1
        else:
            window.refused[refused.reason] += 1
            window.refused_last = str(refused)
        for pull in pulls:
            if pull.amount > window.pull_max:
                window.pull_max, window.pull_contact = pull.amount, pull.contact

    def unsolved(self, residual: float, refused: InputError) -> None:
        """Count an answer refused because its contacts could not carry the base.

        ``residual``: the largest component of its base residual (N m, N; the whole
        ``(M q̈ + h)_base`` when no contact is in force).
        """
        window = self.window
        window.unsolved += 1
        window.unsolved_residual = max(window.unsolved_residual, residual)
        window.unsolved_last = str(refused)


@dataclass(frozen=True)
class FloatingDynamics(Dynamics):
    """A floating base's model part: contact-consistent joint efforts (one answer).

    ``q, q̇, q̈`` of the methods are the joints'; the base's are ``base_q`` (position, x y z w),
    ``base_v`` and ``base_a`` (``[ω; v]``, base frame). Each :meth:`full` solves
    :func:`~spatial_dynamics.contact_inverse_dynamics` with ``contacts`` by ``method`` and
    keeps its result in ``results`` (the contact wrenches to publish); with ``measured``
    (link -> ``[n; f]`` in the link's frame) :meth:`full` takes those instead of solving
    for them (their base residual is the check); the efforts never
    include the base's rows. Armature and friction (``friction_threshold``) add to the
    joints' (the rotors' torque; the drives' friction).

    A split (``torques``, ``forces``) that makes a contact pull by more than
    ``pull_tolerance`` N (:func:`pull_tolerance`) in :meth:`full` or :meth:`gravity_torque`
    is re-solved by ``'qp'`` (friction cones of the contacts' ``μ``, ``n·f ≥ 0``), whose
    answer is used; each such pull is kept in ``pulls``. InputError ``contacts_unsolved``
    when the QP finds none, ``contacts_pull`` when ``qp_missing`` says why the QP cannot run
    (or it pulls itself). :meth:`inertia_times` is not checked for pulls: its forces are the
    increments of a linear split (no gravity), which have no sign of their own.

    Every split (each method, :meth:`inertia_times` too) must carry the base: a base
    residual above ``residual_tolerance`` (N m, N; :func:`residual_tolerance`) is
    InputError ``contacts_unsolved``, its residual kept in ``unsolved``, and no contact in
    force at all (in flight) InputError ``no_contact``, whatever the residual. The split's
    residual is the least any ``λ`` leaves (``J_cᵀ``'s range), so the QP, bound by the same
    rows, cannot carry what it could not: it is refused, not re-solved. Measured wrenches
    are the sensors': their residual is reported, not refused.
    """

    base_q: np.ndarray = None
    base_v: np.ndarray = None
    base_a: np.ndarray = None
    contacts: Tuple['sd.Contact', ...] = ()
    method: str = 'torques'
    results: List = None
    measured: Optional[dict] = None
    qp_missing: str = ''
    pull_tolerance: float = 0.0
    pulls: List = None
    residual_tolerance: float = 0.0
    unsolved: List = None

    def _solve(self, q, qd, qdd, base_v, base_a, gravity, measured=None,
               unilateral: bool = True) -> np.ndarray:
        q_full = np.concatenate((self.base_q, q))
        if measured is not None:   # world axes, as contact_inverse_dynamics takes them
            rotations = link_orientations(self.model, q_full, list(measured))
            measured = {c.name: _world(rotations[c.link], measured[c.link], c.rows)
                        for c in self.contacts}
        state = (self.model, q_full, np.concatenate((base_v, qd)),
                 np.concatenate((base_a, qdd)), self.contacts)
        result = sd.contact_inverse_dynamics(*state, measured=measured, method=self.method,
                                             gravity=gravity)
        if result.status != 'solved' and self.contacts:   # the QP: no forces in the cones
            self.unsolved.append(float(np.abs(result.base_residual).max()))
            raise InputError('contacts_unsolved', f'contacts {self.method}: the contacts in '
                             f'contact {[c.link for c in self.contacts]} cannot carry the '
                             f'base: {result.summary()}; not publishing')
        if measured is None or not self.contacts:
            self._carries(result)
        if measured is not None or not unilateral:
            return result
        pull = _worst_pull(result, self.pull_tolerance)
        if pull is None:      # the fast path: the violations _result found, usually none
            return result
        self.pulls.append(pull)
        what = (f'contacts {self.method}: contact {pull.contact!r} would pull {pull.amount:.3g} '
                f'N (n·f < 0; tolerance {self.pull_tolerance:.3g} N)')
        if self.method == 'qp' or self.qp_missing:
            raise InputError('contacts_pull', what + (
                '; not publishing' if self.method == 'qp' else
                f'; the QP that re-solves it cannot run ({self.qp_missing}); not publishing'))
        result = sd.contact_inverse_dynamics(*state, method='qp', gravity=gravity)
        if result.status != 'solved':
            raise InputError('contacts_unsolved', f'{what}; re-solved by qp: '
                             f'{result.summary()}; not publishing')
        self._carries(result)
        again = _worst_pull(result, self.pull_tolerance)
        if again is not None:
            raise InputError('contacts_pull', f'{what}; re-solved by qp, contact '
                             f'{again.contact!r} still pulls {again.amount:.3g} N; '
                             'not publishing')
        return result

    def _carries(self, result: 'sd.ContactResult') -> None:
        """Refuse ``result`` unless it carries the base rows (InputError ``contacts_unsolved``).

        ``no_contact`` whatever its residual when no contact is in force (in flight).
        """
        residual = float(np.abs(result.base_residual).max())
        if not self.contacts:
            self.unsolved.append(residual)
            raise InputError('no_contact', 'no contact carries the base: no link of '
                             'contacts.links is in contact (contact_states all 0: in flight), '
                             f'base residual {residual:.3g} (N m, N); not publishing')
        if residual > self.residual_tolerance:
            self.unsolved.append(residual)
            raise InputError('contacts_unsolved', f'contacts {result.method}: the contacts in '
                             f'contact {[c.link for c in self.contacts]} cannot carry the '
                             f'base: base residual {residual:.3g} (N m, N; tolerance '
                             f'{self.residual_tolerance:.3g}, 1e-6 m g); not publishing')

    def full(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        """Return the joints' efforts of ``M q̈ + h = Sᵀ τ + J_cᵀ λ``, + armature, friction."""
        result = self._solve(q, qd, qdd, self.base_v, self.base_a, self.gravity, self.measured)
        self.results.append(result)
        tau = np.array(result.tau)
        if self.armature is not None:
            tau += self.armature * qdd
        if self.friction_threshold is not None:
            tau += sd.friction_torque(self.model, np.concatenate((self.base_v, qd)),
                                      self.friction_threshold)[6:]
        return tau

    def gravity_torque(self, q: np.ndarray) -> np.ndarray:
        """Return the joints' efforts that hold the robot still on its contacts (q̇ = q̈ = 0)."""
        zero, six = np.zeros(len(q)), np.zeros(6)
        return np.array(self._solve(q, zero, zero, six, six, self.gravity).tau)

    def inertia_times(self, q: np.ndarray, u: np.ndarray) -> np.ndarray:
        """Return the contact-consistent efforts of joint accelerations ``u`` (no gravity)."""
        zero, six = np.zeros(len(q)), np.zeros(6)
        tau = np.array(self._solve(q, zero, u, six, six, (0.0, 0.0, 0.0),
                                   unilateral=False).tau)
        if self.armature is not None:
            tau += self.armature * u
        return tau


def _worst_pull(result: 'sd.ContactResult', tolerance: float
                ) -> Optional['sd.contacts.Violation']:
    """Return the contact of ``result`` that pulls most beyond ``tolerance`` N (None: none)."""
    worst = None
    for violation in result.violations:
        if (violation.kind == 'unilateral' and violation.amount > tolerance
                and (worst is None or violation.amount > worst.amount)):
            worst = violation
    return worst


def _world(R: np.ndarray, wrench: np.ndarray, rows: int) -> np.ndarray:
    """Return a link-frame ``[n; f]`` in world axes: a point contact's force (3), else both."""
    if rows == 3:
        return R @ wrench[3:]
    return np.r_[R @ wrench[:3], R @ wrench[3:]]


def contact_wrenches(model: 'sd.Model', base_q: np.ndarray, q: np.ndarray,
                     result: 'sd.ContactResult') -> Tuple[Tuple[str, np.ndarray], ...]:
    """Each contact's wrench ``[n; f]`` (6,) on the robot, in its link's frame, at its origin.

    ``result.forces`` are in world axes at the contact point (the link's origin: contacts of
    the node have no offset); a point contact's moment is zero.
    """
    links = tuple(result.forces)
    rotations = link_orientations(model, np.concatenate((base_q, q)), links)
    out = []
    for link in links:
        R = rotations[link]
        force = np.asarray(result.forces[link], dtype=float)
        wrench = np.zeros(6)
        if len(force) == 3:
            wrench[3:] = R.T @ force
        else:
            wrench[:3], wrench[3:] = R.T @ force[:3], R.T @ force[3:]
        out.append((link, wrench))
    return tuple(out)


def base_status(params, robot, inputs: BaseInputs, window: BaseWindow, now_ns: int):
    """Return the ``base`` status: what the base's inputs are, the contacts' figures.

    ERROR while a needed input is missing or stale (nothing is published), WARN when a
    contact solution of the period violated a friction cone or pulled on the ground, left
    a base residual above :func:`residual_tolerance` (measured wrenches), when an answer
    was refused because its split made a contact pull and the QP could not re-solve it, or
    because its contacts could not carry the base. Answers re-solved by the QP
    (a contact would have pulled) are counted, with the worst pull seen: that is the node
    working as documented, not a warning.
    """
    values = [('base', params.base)]
    needed = []
    if params.base == 'moving':
        values.append(('source', params.base_input_source))
        needed = ([('base/imu', inputs.imu)] if params.base_input_source == 'imu'
                  else [('base/pose', inputs.pose), ('base/twist', inputs.twist)])
    elif params.base == 'floating':
        needed = [('base/pose', inputs.pose), ('base/twist', inputs.twist)]
    values += [('base acceleration', params.base_input_acceleration),
               ('base timeout [s]', str(params.base_input_timeout))]
    problems = []
    for topic, held in needed:
        age = None if held is None else (now_ns - held.receipt_ns) * 1e-9
        values.append((f'{topic} age [s]', '' if age is None else f'{age:.3f}'))
        if age is None:
            problems.append(f'no {topic} yet')
        elif age > params.base_input_timeout:
            problems.append(f'{topic} stale ({age:.2f} s, base_input.timeout '
                            f'{params.base_input_timeout} s)')
    values += [(f'{topic} received', str(count)) for topic, count in inputs.received.items()]
    values += [(f'rejected {key}', str(count)) for key, count in inputs.rejected.items()]
    if params.base == 'floating':
        values += [('contacts', ', '.join(params.contacts_links or ())),
                   ('contacts method', params.contacts_method),
                   ('contact solutions', str(window.solved)),
                   ('base residual max', f'{window.residual_max:.3g}'),
                   ('last solution', window.last)]
        values += [(f'violation {key}', f'{count} (worst {window.worst[key]:.3g} N)')
                   for key, count in window.violations.items()]
        values += [('contact pull tolerance [N]', f'{robot.pull_tolerance:.3g}' if robot
                    else ''),
                   ('qp fallback', (robot.qp_missing or 'ready') if robot else ''),
                   ('re-solved by qp (a contact would pull)', str(window.resolved)),
                   ('worst pull [N]', f'{window.pull_max:.3g}' + (
                       f' ({window.pull_contact})' if window.pull_contact else ''))]
        values += [(f'refused {reason} (a contact would pull)', str(count))
                   for reason, count in window.refused.items()]
        values += [('refused: the contacts cannot carry the base (contacts_unsolved, '
                    'no_contact)', str(window.unsolved)),
                   ('worst refused base residual', f'{window.unsolved_residual:.3g}')]
    if robot is None:
        return 'ERROR', 'no robot model', values
    hint = source_hint(params, inputs)
    if problems and hint:
        problems.append(hint)
    if problems:
        return 'ERROR', '; '.join(problems) + '; not publishing', values
    warnings = []
    if window.refused:
        warnings.append(f'{sum(window.refused.values())} answer(s) refused, a contact would '
                        f'pull: {window.refused_last}')
    if window.violations:
        warnings.append('contact violations: ' + ', '.join(
            f'{key} ({count}x, worst {window.worst[key]:.3g} N)'
            for key, count in window.violations.items()))
    if window.unsolved:
        warnings.append(f'{window.unsolved} answer(s) refused, the contacts cannot carry the '
                        f'base (worst base residual {window.unsolved_residual:.3g}): '
                        f'{window.unsolved_last}')
    if window.residual_max > robot.residual_tolerance:
        warnings.append(f'base residual {window.residual_max:.3g} (the measured contact '
                        'wrenches do not carry the base rows)')
    if warnings:
        return 'WARN', '; '.join(warnings), values
    return 'OK', f'base {params.base}: inputs fresh', values
