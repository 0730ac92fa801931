# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The node on a moving or floating base, without ROS: the base's parameters, its inputs held.

Pure Python + numpy + the library (no rclpy import), tested in
``test/test_node_base_inputs.py``. Each message is read by :mod:`.base_messages`, held here
(:class:`BaseInputs`) until an answer takes the base's motion, or a floating base's
:class:`~.floating.FloatingDynamics`, from it; the ``base`` status is
:func:`~.diagnostics.base_status`'. Parameter ``base`` (read-only):

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
             :func:`~.floating.pull_tolerance`) is re-solved by the QP, or refused; one
             that leaves the base unbalanced (:func:`~.floating.residual_tolerance`: the
             contacts in contact cannot carry it) or has no contact in force is refused
             (:class:`~.floating.FloatingDynamics`).
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
  :data:`~.base_messages.QUATERNION_TOLERANCE`.
* ``base/odometry`` (``nav_msgs/Odometry``): its pose and the twist of its
  ``child_frame_id``, held as ``base/pose`` and ``base/twist`` (either input, or both).
* ``base/twist`` (``geometry_msgs/TwistStamped``): the twist of the root link (or, moving, of a
  link fixed to it) in its own axes, ``header.frame_id`` that link or empty: what
  ``nav_msgs/Odometry`` carries in its child frame. A frame that is not a link of the URDF
  (``base_footprint``) must be exactly ``base_input.odometry_frame``, then taken as
  ``base_input.odometry_link`` (:func:`~.base_messages.twist_link`); any other is refused
  (``wrong_frame``).
  Its rate, the base's spatial acceleration, is the difference of successive samples over
  their stamps (``base_input.acceleration: difference``: no closer than
  ``base_input.min_interval``, low-pass filtered and bounded by what a base reaches,
  :func:`~.base_messages.twist_rate`; a refused twist keeps the last good one) or zero
  (``zero``: a base at constant twist).
* ``contact_states`` (``std_msgs/UInt8MultiArray``): one flag per ``contacts.links``, non-zero
  = in contact. While nothing comes on it every link of ``contacts.links`` is in contact (a
  robot without contact detection); once a message comes (taken or refused), only a valid one
  younger than ``base_input.timeout`` says which links touch: none valid yet is
  ``contacts_missing``, an old one ``contacts_stale``, and the answer is refused.
* ``measured_contact_wrenches`` (``geometry_msgs/WrenchStamped``, with ``contacts.measured``):
  a foot sensor's wrench on the robot, ``header.frame_id`` the link of ``contacts.links``,
  ``[n; f]`` in its frame at its origin; the efforts are then ``(M q̈ + h − J_cᵀ λ)`` of the
  joints for the measured ``λ``, and the base rows' residual says how consistent they are.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from typing import Optional, Tuple

import numpy as np
import spatial_dynamics as sd
from spatial_dynamics.ros.base_messages import (imu_arrays, pose_arrays, twist_array, twist_link,
                                                twist_rate, wrench_array)
from spatial_dynamics.ros.control import Dynamics
from spatial_dynamics.ros.floating import FloatingDynamics
from spatial_dynamics.ros.inputs import InputError, stamp_ns
from spatial_dynamics.ros.parameters import ConfigError
from spatial_dynamics.ros.text import shown

#: Values of the ``base`` parameter.
BASES = ('fixed', 'moving', 'floating')
#: Values of ``base_input.source`` (a moving base's motion).
BASE_SOURCES = ('imu', 'twist')
#: Values of ``base_input.acceleration``: the twist's rate differenced, or zero.
BASE_ACCELERATIONS = ('difference', 'zero')
#: Values of ``contacts.kind`` and ``contacts.method`` (the library's).
CONTACT_KINDS = sd.contacts.KINDS
CONTACT_METHODS = sd.contacts.METHODS
#: Why an answer is refused on a moving or floating base (diagnostics counter keys).
BASE_REASONS = ('base_missing', 'base_stale', 'contacts_stale', 'contacts_unsolved',
                'contacts_missing', 'contacts_pull', 'no_contact')
#: The topics whose messages are held as each input an answer needs (their refusals name it).
SOURCES = {'base/imu': ('base/imu',), 'base/pose': ('base/odometry', 'base/pose'),
           'base/twist': ('base/odometry', 'base/twist'), 'contact_states': ('contact_states',),
           'measured_contact_wrenches': ('measured_contact_wrenches',)}
#: Why a base input message is refused.
BASE_INPUT_REASONS = ('non_finite', 'out_of_bounds', 'not_unit', 'wrong_frame', 'unstamped',
                      'stamp_not_increasing', 'interval_too_short', 'length_mismatch',
                      'no_model', 'unknown_link')


def check_base(params, model: 'sd.Model', source: str) -> None:
    """Check the base parameters against ``model`` (ConfigError naming the parameter)."""
    if params.base == 'fixed':
        return
    links = tuple(params.contacts_links or ())
    for link in links:
        if link not in model.frames:
            raise ConfigError(f'parameter contacts.links: {shown(link)} is not a link of robot '
                              f'{shown(model.name)} ({source})')
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
                          f'it: set the links of robot {shown(model.name)} that touch the ground '
                          '(feet, soles), e.g. contacts.links:=[FL_FOOT, FR_FOOT, HL_FOOT, '
                          f'HR_FOOT] ({source})')
    link, frame = params.base_input_odometry_link, params.base_input_odometry_frame
    if link:
        if link not in model.frames:
            raise ConfigError(f'parameter base_input.odometry_link: {shown(link)} is not a link '
                              f'of robot {shown(model.name)} ({source})')
        try:
            twist_link(model, link, 'base_input.odometry_link')
        except InputError as err:
            raise ConfigError(f'parameter base_input.odometry_link: {err}') from None
    if frame in model.frames:
        raise ConfigError(f'parameter base_input.odometry_frame: {shown(frame)} is a link of '
                          f'robot {shown(model.name)} ({source}), taken as itself: odometry_frame '
                          'names a frame the URDF does not have (e.g. base_footprint)')
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


def _say(problems: list, err: InputError) -> None:
    """Add an answer's refusal to ``problems`` as a status says it.

    Without its '; not publishing', and without the refused message a problem before it
    named already (base/pose and base/twist are both missing when odometry is refused).
    """
    text = str(err).removesuffix('; not publishing')
    head, said, refused = text.partition('; last refused ')
    if said and any(problem.endswith(said + refused) for problem in problems):
        text = head
    problems.append(text)


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
    last: object = None         # the last solution (its summary() when diagnostics are sent)
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
        self.refused: dict = {}    # topic -> (reason, text, receipt ns) of its last refusal
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
            self.refused[topic] = (err.reason, str(err), now_ns)
            return f'{topic}: message rejected ({err.reason}): {err}'
        return None

    def last_refused(self, topic: str, since_ns: Optional[int] = None) -> str:
        """Say the last refused message of the topics held as ``topic`` (after ``since_ns``).

        ``'; last refused <topic> (<reason>): <why>'``, '' when none: what an answer refused
        for a missing or stale ``topic`` adds, and the ``base`` status (formatted only then).
        """
        last = None
        for source in SOURCES[topic]:
            refused = self.refused.get(source)
            if (refused is not None and (since_ns is None or refused[2] > since_ns)
                    and (last is None or refused[2] > last[1][2])):
                last = (source, refused)
        if last is None:
            return ''
        source, (reason, text, _) = last
        return f'; last refused {source} ({reason}): {text}'

    def _take_base_imu(self, config, msg, now_ns: int) -> None:
        params = config.params
        link, alias = params.base_input_imu_link, params.base_input_imu_frame
        if msg.header.frame_id not in ('', link, alias or link):
            raise InputError('wrong_frame', f'header.frame_id {shown(msg.header.frame_id)} is not '
                             f'base_input.imu_link {shown(link)}, the IMU frame of the model' + (
                                 f', nor base_input.imu_frame {shown(alias)}' if alias else
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
        ``base_input.odometry_frame``, taken as ``base_input.odometry_link``
        (:func:`~.base_messages.twist_link`).
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
        # the flags with the contacts.links they were sent for: a flag is a link's, not a place's
        self.flags = Held((links, tuple(bool(x) for x in msg.data)), 0, now_ns)

    def _take_measured_contact_wrenches(self, config, msg, now_ns: int) -> None:
        link = msg.header.frame_id
        links = tuple(config.params.contacts_links or ())
        if link not in links:
            raise InputError('unknown_link', f'header.frame_id {shown(link)} is not one of '
                             f'contacts.links {list(links)}')
        wrench = wrench_array(f'wrench on {shown(link)}', msg.wrench)
        self.measured[link] = Held(wrench, stamp_ns(msg.header), now_ns)

    def _measured(self, params, contacts, now_ns: int) -> Optional[dict]:
        """Link -> measured ``[n; f]`` (link frame) of each contact in force, or None (off)."""
        if not params.contacts_measured:
            return None
        measured = self.measured
        result = {}
        for contact in contacts:
            link = contact.link
            result[link] = self._fresh(params, measured.get(link), 'measured_contact_wrenches',
                                       now_ns, 'contacts', link)
        return result

    # -- what an answer needs -------------------------------------------------------------------
    def _fresh(self, params, held: Optional[Held], topic: str, now_ns: int,
               kind: str = 'base', link: str = '') -> tuple:
        """Return ``held``'s value; InputError ``<kind>_missing`` or ``<kind>_stale`` if none.

        ``topic`` (a key of :data:`SOURCES`, of ``link`` for a contact's wrench) is named in
        the error, with its last refused message (:meth:`last_refused`).
        """
        if held is not None:
            age = (now_ns - held.receipt_ns) * 1e-9
            if age <= params.base_input_timeout:
                return held.value
        what = f'{topic} of {shown(link)}' if link else topic
        if held is None:
            raise InputError(f'{kind}_missing', f'no good {what} yet (base {params.base})'
                             f'{self.last_refused(topic)}; not publishing')
        since = self.last_refused(topic, held.receipt_ns)
        raise InputError(f'{kind}_stale', f'{what} stale: {age:.3f} s old (base_input.timeout '
                         f'{params.base_input_timeout} s){since}; not publishing')

    def _rate(self, params, topic: str) -> np.ndarray:
        if params.base_input_acceleration == 'zero':
            return np.zeros(6)
        if self.rate is None:
            raise InputError('base_missing', f'{topic}: base_input.acceleration difference needs '
                             'two successive twists (one so far, or a gap)'
                             f'{self.last_refused(topic, self.twist.receipt_ns)}; not publishing')
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
        flags = self._flags(params, links, now_ns)
        key = (links, params.contacts_kind, params.contacts_mu, flags)
        if self._contacts[0] != key:     # the same Contacts each answer: the library's plan
            self._contacts = key, tuple(   # for them is cached, their checks made once
                sd.Contact(link, kind=params.contacts_kind, mu=params.contacts_mu)
                for link, touching in zip(links, flags) if touching)
        return self._contacts[1]

    def _flags(self, params, links: tuple, now_ns: int) -> tuple:
        """Return whether each of ``links`` is in contact now (InputError: not known).

        All of them while nothing came on ``contact_states`` (``contacts.links``' default);
        once something came, the valid one held: ``contacts_missing`` before the first,
        ``contacts_stale`` when it is older than ``base_input.timeout`` or was sent for
        other ``contacts.links`` than today's (the same links in another order too).
        """
        held = self.flags
        if held is None:
            received = self.received.get('contact_states')
            if not received:
                return (True,) * len(links)
            raise InputError('contacts_missing', f'no valid contact_states yet ({received} '
                             'received: contacts.links are all in contact only while nothing '
                             f'comes on it){self.last_refused("contact_states")}; '
                             'not publishing')
        sent_for, flags = self._fresh(params, held, 'contact_states', now_ns, 'contacts')
        if sent_for != links:   # contacts.links changed since: a flag would go to another link
            raise InputError('contacts_stale', f'contact_states was sent for contacts.links '
                             f'{list(sent_for)}, not for today\'s {list(links)}'
                             f'{self.last_refused("contact_states", held.receipt_ns)}; '
                             'not publishing')
        return flags

    def blocked(self, params, now_ns: int) -> list:
        """Say each input an answer needs now that is missing or stale ([]: none).

        The texts of the refusals an answer would get (:meth:`dynamics`'s checks, without
        computing it), for the ``base`` status.
        """
        if params.base == 'moving' and params.base_input_source == 'imu':
            needed = [(self.imu, 'base/imu')]
        else:
            needed = [(self.pose, 'base/pose'), (self.twist, 'base/twist')]
        problems = []
        for held, topic in needed:
            try:
                self._fresh(params, held, topic, now_ns)
            except InputError as err:
                _say(problems, err)
        if not problems and needed[-1][1] == 'base/twist':
            try:
                self._rate(params, 'base/twist')
            except InputError as err:
                _say(problems, err)
        if params.base != 'floating':
            return problems
        links = tuple(params.contacts_links or ())
        try:
            flags = self._flags(params, links, now_ns)
        except InputError as err:
            _say(problems, err)
            flags = (True,) * len(links)
        if params.contacts_measured:
            for link, touching in zip(links, flags):
                if touching:
                    try:
                        self._fresh(params, self.measured.get(link), 'measured_contact_wrenches',
                                    now_ns, 'contacts', link)
                    except InputError as err:
                        _say(problems, err)
        return problems

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

        A normal force below zero by no more than ``tolerance``
        (:func:`~.floating.pull_tolerance`) is rounding, not a pull.
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
        window.last = result   # summarized when diagnostics are sent, not on every answer

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
