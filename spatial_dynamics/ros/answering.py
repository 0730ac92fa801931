# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""What the ``inverse_dynamics`` node does with each input message, without ROS.

:class:`Answering` holds what lives between messages (the held desired state, the followed
trajectory, the external wrenches, the observer, the counters of diagnostics), checks each
message against the current :class:`~spatial_dynamics.ros.records.Config` (read once per
message: a parameter change swaps the whole of it) and returns what to publish (an
:class:`Out`): the node only publishes it. It reads the fields of the message types
(``sensor_msgs/JointState``, ``trajectory_msgs/JointTrajectory``,
``geometry_msgs/WrenchStamped``) and never imports rclpy; the node
(:mod:`spatial_dynamics.ros.node`) does the ROS part. All of it runs in the node's ``inputs``
callback group, one message at a time; what a plan costs in proportion to its size (its
conversion and checks, its effort for JTC) runs elsewhere (:mod:`.plans`).

Every message is answered or rejected on its own: a rejected message (reason counted in
diagnostics) produces no output, and nothing is published without fresh input, so a stale
input means no output (never zeros). In ``feedforward`` each desired message is answered; in
the feedback modes each measured ``joint_states`` message is, with the last desired state held
(zero-order hold) while it is younger than ``input_timeout``, or the followed
``desired_trajectory`` sampled at the measurement's stamp (:class:`~spatial_dynamics.trajectory.
Follower`, joint_trajectory_controller's rules). A measured state with the (non-zero) stamp of
the one answered last is not answered again (a lockstep simulator republishing the state it
waits on must not get two commands for it).

External torques (any ``control_mode``): each measured state whose ``effort`` holds the
measured torque of every model joint updates a generalized-momentum observer
(:mod:`spatial_dynamics.ros.observer`, gain ``observer_gain``, the node's model with payload,
armature, friction and gravity), integrated over the header stamps (a message stamped 0 or with
the stamp of the previous one, or closer to it than any sensor publishes, is skipped; a stamp
going back, a gap above ``measured_timeout`` or a change of the model or of a parameter it
uses restarts it at zero); its estimate of
τ_ext = Jᵀw is published on ``external_torque_estimate``.
"""

from __future__ import annotations

import time
from typing import NamedTuple, Optional, Tuple

import numpy as np
import spatial_dynamics as sd
from spatial_dynamics.bounds import check_bounded, MAX_WRENCH
from spatial_dynamics.effort import with_gravity
from spatial_dynamics.ros.bases import BaseInputs, observer_off
from spatial_dynamics.ros.control import answer, Dynamics, FEEDBACK_MODES, measured_arrays
from spatial_dynamics.ros.diagnostics import Totals, Window
from spatial_dynamics.ros.floating import ContactWrenches
from spatial_dynamics.ros.inputs import (InputError, joint_state_arrays, stamp_ns,
                                         trajectory_arrays)
from spatial_dynamics.ros.observer import (
    EstimateWindow, make_observer, measured_effort, observer_key, sample_time)
from spatial_dynamics.ros.plans import Job, prepare_plan, PlanItem
from spatial_dynamics.ros.records import Config, Robot
from spatial_dynamics.ros.text import shown
from spatial_dynamics.trajectory import check_start, Follower, TrajectoryError
from spatial_dynamics.wrench import wrench_from_torques

_WRENCH_FIELDS = ('torque.x', 'torque.y', 'torque.z', 'force.x', 'force.y', 'force.z')


class Held(NamedTuple):
    """A good state kept between messages: model joints, arrays, receipt (monotonic ns)."""

    joints: Tuple[str, ...]
    state: tuple
    receipt_ns: int


class Answer(NamedTuple):
    """One answer to publish: the input's header, the model joints, q_d, q̇_d, τ, the terms.

    ``contacts``: on a floating base, ``(link, [n; f] in the link's frame)`` pairs of the
    contact solution (a :class:`~.floating.ContactWrenches`, computed when first iterated),
    published on ``contact_wrenches`` while somebody subscribes; None otherwise.
    """

    header: object
    joints: Tuple[str, ...]
    q: np.ndarray
    qd: np.ndarray
    tau: np.ndarray
    terms: Optional[dict]
    contacts: Optional[tuple] = None


class Out(NamedTuple):
    """What one message gives to publish (each None when nothing): see :class:`Answering`.

    ``answer``: the command; ``estimate``: ``(header, joints, τ_ext)``; ``wrench``:
    ``(header, link, [n; f])``; ``annotate``: a plan to annotate (off the answering thread).
    """

    answer: Optional[Answer] = None
    estimate: Optional[tuple] = None
    wrench: Optional[tuple] = None
    annotate: Optional[Job] = None


#: The result of a message that gives nothing to publish (rejected, or held for later).
NOTHING = Out()


class Answering:
    """The answers to the input messages, and the state they keep (see the module docstring).

    Each public method takes the current ``Config`` and a message and returns an :class:`Out`:
    what the node publishes (an answer; an observer estimate and a virtual F/T reading; a plan
    to annotate for JTC). The helpers return their part of it to the method, which puts it
    in the ``Out``; nothing to publish is kept in between. It never calls into the node;
    ``log`` is the node's logger (``info``/``warn`` with ``throttle_duration_sec``).
    """

    def __init__(self, log) -> None:
        self.log = log
        self._observing: Optional[tuple] = None   # (msg, (q, qd)) accepted by measured()
        self.desired: Optional[Held] = None    # the last good desired state (zero-order hold)
        self.follower = Follower()   # desired_trajectory in the feedback modes (JTC's rules)
        self._following: Optional[tuple] = None   # the joints the follower's plans are in
        self._measured_q: Optional[np.ndarray] = None   # the last measured position
        self._measured_stamp = 0     # its stamp (ns): the clock trajectories are sampled on
        self._measured_seen = False  # whether that clock has ticked (a simulator starts at 0)
        self._pending_plan: Optional[PlanItem] = None   # came before that clock: waits
        self._answered_stamp = 0               # stamp (ns) of the measured state answered last
        self.observer = None              # MomentumObserver of the current model, when on
        self._observed: Optional[Config] = None   # the config the observer was checked for
        self._observer_key: Optional[tuple] = None
        self.estimates = EstimateWindow()   # external_torque_estimate of the period
        self.totals = Totals()
        self.window = Window()
        self.wrenches: dict = {}  # link -> (wrench [n; f] in the link frame, expiry ns)
        self.base_inputs = BaseInputs()   # base: moving or floating (the base's inputs held)

    def period(self) -> Tuple[Window, EstimateWindow]:
        """Return the counters of the period that ended; start new ones."""
        window, self.window = self.window, Window()
        estimates, self.estimates = self.estimates, EstimateWindow()
        return window, estimates

    def joint_state(self, config: Config, msg, with_terms: bool = False) -> Out:
        """Take a ``desired_joint_states`` message (``with_terms``: compute the terms too)."""
        answer = self._on_desired(
            config, msg, 'desired_joint_states', joint_state_arrays,
            (msg.name, msg.position, msg.velocity,
             msg.effort if config.params.acceleration_source == 'effort' else None), with_terms)
        return Out(answer)

    def take_plan(self, config: Config, item: PlanItem, clock_ns: int,
                  with_terms: bool = False) -> Out:
        """Take a ``desired_trajectory`` checked off the answering path (:mod:`.plans`).

        Feedback modes: a plan to follow, scheduled at its stamp on the measured clock; one
        that comes before the first measured state waits for it (its stamp is judged on that
        clock, a simulator's too). Feedforward: its first point is the desired state,
        answered at once. ``clock_ns``: the node's clock, the start of a plan stamped 0 in
        feedforward. A plan scheduled (feedback) or checked whole (feedforward) is handed on
        to be annotated when ``trajectory_effort_tolerance`` > 0: what is refused is not.
        """
        feedback = config.params.control_mode in FEEDBACK_MODES
        msg = item.msg
        item = self._current(config, item)
        if not feedback and msg is not None and config.robot is not None:
            answer = self._on_desired(config, msg, 'desired_trajectory', trajectory_arrays,
                                      (msg.joint_names, msg.points), with_terms)
            return Out(answer, annotate=self._annotation(config, item, clock_ns))
        if not feedback:
            self.window.received += 1
        if item.error is not None:
            reason, text = item.error
            self._reject('desired_trajectory', reason, 'refused whole' + (
                ', the trajectory followed before goes on' if feedback else '') + f': {text}')
            return NOTHING
        if not self._measured_seen:   # judged on the measured clock, once it ticks
            if self._pending_plan is None:
                self.log.info('desired_trajectory: waiting for the first joint_states: its '
                              'stamp is the clock the plan starts on')
            self._pending_plan = item
            return NOTHING
        return Out(annotate=self._schedule(config, item, self._measured_stamp))

    def _annotation(self, config: Config, item: PlanItem, clock_ns: int) -> Optional[Job]:
        """Feedforward: the plan whose first point was answered, to annotate (None: not)."""
        if not self._annotating(config):
            return None
        if item.error is not None:   # the first point may do; the plan is not annotated
            self._reject_annotation(item.error[0], item.error[1])
            return None
        msg = item.msg
        stamp = stamp_ns(msg.header)
        try:
            check_start(stamp or clock_ns, clock_ns)
        except TrajectoryError as err:
            self._reject_annotation(err.reason, str(err))
            return None
        if item.prepared is None:
            return None
        return Job(msg.header, item.prepared, config)

    def _current(self, config: Config, item: PlanItem) -> PlanItem:
        """``item``, checked again when the model or the mode changed since (rare)."""
        if item.error is not None or item.config is config:
            return item
        robot = config.robot
        if (robot is None or item.joints != robot.joints
                or (item.prepared is None and item.msg is not None
                    and len(item.msg.points) and (
                        config.params.control_mode in FEEDBACK_MODES
                        or config.params.trajectory_effort_tolerance > 0.0))):
            return prepare_plan(config, item.msg)
        return item

    def _annotating(self, config: Config) -> bool:
        """Whether plans are annotated; an ``output: none`` is said (no model torque)."""
        if not config.params.trajectory_effort_tolerance > 0.0 or config.robot is None:
            return False
        if config.params.base != 'fixed':
            self.totals.rejected['base_not_fixed'] += 1
            self.log.warn(f'annotated_trajectory: not annotated: base {config.params.base} '
                          '(annotation needs a fixed base)', throttle_duration_sec=1.0)
            return False
        if config.params.output == 'none':
            self.totals.rejected['no_model_part'] += 1
            self.log.warn('annotated_trajectory: message rejected: output none has no model '
                          'torque to annotate the plan with', throttle_duration_sec=1.0)
            return False
        return True

    def _schedule(self, config: Config, item: PlanItem, now_ns: int) -> Optional[Job]:
        """Feedback modes: follow a whole trajectory, sampled at each measured stamp (JTC).

        Returns the plan to annotate, when it is followed and plans are annotated.
        """
        robot, msg = config.robot, item.msg
        start_ns = stamp_ns(msg.header)
        q = self._measured_q
        if q is not None and len(q) != len(robot.joints):   # measured on another model
            q = None
        try:
            traj = self.follower.schedule(item.prepared, start_ns, now_ns, robot.joints, q)
        except TrajectoryError as err:
            self._reject('desired_trajectory', err.reason, f'refused whole, the trajectory '
                         f'followed before goes on: {err}')
            return None
        self._following = robot.joints
        self.totals.last_desired_ns = time.monotonic_ns()
        self.log.info(
            'desired_trajectory: stopped, holding the measured position' if traj is None else
            f'desired_trajectory: following {len(msg.points)} points ({traj.kind}, '
            f'{traj.time[-1]:g} s) from {(start_ns or now_ns) * 1e-9:.9f} s')
        if traj is not None and self._annotating(config):
            return Job(msg.header, item.prepared, config)
        return None

    def drain(self, annotator) -> None:
        """Count what the annotation worker refused or clamped since (diagnostics thread)."""
        while annotator.rejected:
            self.totals.rejected[annotator.rejected.popleft()] += 1
        names = []
        while annotator.saturated:
            names.append(annotator.saturated.popleft())
        if names:
            self.totals.saturated += 1
            self.totals.saturated_joints.update(names)

    def _on_desired(self, config: Config, msg, topic: str, to_arrays, fields: tuple,
                    with_terms: bool) -> Optional[Answer]:
        """Hold a good desired state; in feedforward mode, return its answer (None: none)."""
        t0 = time.monotonic_ns()
        answers = config.params.control_mode not in FEEDBACK_MODES
        if answers:
            self.window.received += 1
        robot = config.robot
        if robot is None:
            self._reject(topic, 'no_model', 'no robot model loaded yet')
            return None
        try:
            desired = to_arrays(robot.joints, *fields)
        except InputError as err:
            self._reject(topic, err.reason, str(err))
            return None
        self.desired = Held(robot.joints, desired, t0)
        self.totals.last_desired_ns = t0
        if not answers:
            return None
        return self._respond(config, msg.header, topic, desired, None, t0, with_terms)

    def measured(self, config: Config, msg, with_terms: bool = False) -> Out:
        """Check a measured state; in a feedback mode, answer it with the held desired one.

        The observer's update waits for :meth:`observe`, called once the answer is out: it
        never delays a command.
        """
        self._observing = None
        t0 = time.monotonic_ns()
        feedback = config.params.control_mode in FEEDBACK_MODES
        totals = self.totals
        totals.measured_received += 1
        if feedback:
            self.window.received += 1
        robot = config.robot
        if robot is None:
            self._reject_measured('no_model', 'no robot model loaded yet')
            return NOTHING
        try:
            measured = measured_arrays(robot.joints, msg.name, msg.position, msg.velocity,
                                       feedback)
        except InputError as err:
            self._reject_measured(err.reason, str(err))
            return NOTHING
        totals.last_measured_ns = t0
        self.window.measured += 1
        stamp = stamp_ns(msg.header)
        self._measured_q = measured[0]     # in robot.joints order: held by an empty trajectory
        self._measured_stamp = stamp or self._measured_stamp
        self._measured_seen = True
        annotate = None
        if self._pending_plan is not None:   # a plan that came first starts on this clock
            annotate = self._start_pending(config)
        answer = None
        if feedback:
            answer = self._answer_measured(config, msg, measured, t0, with_terms)
        self._observing = (msg, measured)
        return Out(answer, annotate=annotate)

    def _start_pending(self, config: Config) -> Optional[Job]:
        """Schedule the plan that waited for the measured clock; return it to annotate."""
        item, self._pending_plan = self._current(config, self._pending_plan), None
        if item.error is not None:
            self._reject('desired_trajectory', item.error[0], f'refused whole: '
                         f'{item.error[1]}')
            return None
        if config.params.control_mode in FEEDBACK_MODES:
            return self._schedule(config, item, self._measured_stamp)
        return None

    def observe(self, config: Config, msg) -> Out:
        """Update the observer with the measured state :meth:`measured` just accepted.

        Returns its estimate and, with ``wrench_estimate.link``, the virtual F/T reading.
        """
        observing, self._observing = self._observing, None
        if config.params.observer_gain <= 0.0 or observer_off(config.params):
            self.observer = None
            return NOTHING
        if observing is None or observing[0] is not msg:
            return NOTHING
        q, qd = observing[1]
        r = self._observe(config, msg, q, qd)
        if r is None:
            return NOTHING
        header, link = msg.header, config.params.wrench_estimate_link
        return Out(estimate=(header, config.robot.joints, r), wrench=(
            (header, link, self._sense_wrench(config, q, r)) if link else None))

    def _answer_measured(self, config: Config, msg, measured: tuple, t0: int,
                         with_terms: bool) -> Optional[Answer]:
        """Answer a good measured state with the held desired state (a feedback mode)."""
        robot, mode = config.robot, config.params.control_mode
        stamp = stamp_ns(msg.header)
        desired = None
        if self._following == robot.joints:   # a trajectory, sampled at this measurement
            desired = self.follower.sample(stamp or self._measured_stamp)
            if desired is not None:   # a followed plan is a live desired input (its end held)
                self.totals.last_desired_ns = t0
        if desired is None:
            held = self.desired
            if held is None or held.joints != robot.joints:
                self._reject('joint_states', 'no_desired', f'{mode}: no desired '
                             'state for the model\'s joints yet')
                return None
            age = (t0 - held.receipt_ns) * 1e-9
            if age > config.params.input_timeout:
                self._reject('joint_states', 'desired_stale',
                             f'{mode}: the held desired state is {age:.3f} s old '
                             f'(input_timeout {config.params.input_timeout} s); not publishing')
                return None
            desired = held.state
        if stamp != 0 and stamp == self._answered_stamp:
            self._reject('joint_states', 'repeated',
                         f'{mode}: the measured state stamped {stamp * 1e-9:.9f} '
                         's was answered already (one answer per measurement)')
            return None
        answer = self._respond(config, msg.header, 'joint_states', desired, measured, t0,
                               with_terms)
        if answer is not None:   # a refused state is not answered: sent again, it may be
            self._answered_stamp = stamp
        return answer

    def _observe(self, config: Config, msg, q: np.ndarray, qd: Optional[np.ndarray]
                 ) -> Optional[np.ndarray]:
        """Update the external-torque observer with a measured state; return its estimate.

        A message without effort (or velocity) for every model joint only skips the update
        (counted in diagnostics, None returned): not an error. The observer restarts when the
        model or a parameter it depends on changes (:func:`~.observer.observer_key`).
        """
        skipped = self.estimates.skipped
        robot = config.robot
        if qd is None:
            skipped['no_velocity'] += 1
            return None
        try:
            tau = measured_effort(robot.joints, msg.name, msg.effort)
        except InputError as err:
            skipped[err.reason if err.reason in skipped else 'no_effort'] += 1
            return None
        measured_kind = config.params.measured_effort
        if measured_kind != 'full':   # e.g. UR: the drive reports the torque beyond gravity
            tau = with_gravity(robot.model, q, tau, measured_kind, config.params.gravity)
        observer = self._observer_for(config)
        t = sample_time(msg.header.stamp.sec, msg.header.stamp.nanosec)
        if t is None:
            skipped['unstamped'] += 1
            return None
        base = None
        if config.params.base == 'moving':     # its twist and orientation (source twist)
            try:
                base = self.base_inputs.velocity(config, time.monotonic_ns())
            except InputError as err:
                skipped[err.reason] = skipped.get(err.reason, 0) + 1
                return None
        try:
            r = observer.update(t, q, qd, tau, base)
        except InputError as err:   # a sample refused (interval_too_short): the state kept
            skipped[err.reason] += 1
            return None
        except Exception as err:  # never die on one message
            self.log.warn(f'external torque observer failed: {err!r}', throttle_duration_sec=1.0)
            observer.reset('compute error')
            return None
        if r is None:
            skipped['repeated'] += 1
            return None
        self.estimates.add(r)
        return r

    def _observer_for(self, config: Config):
        """Return the observer of ``config``: kept unless what it depends on changed."""
        observer, robot = self.observer, config.robot
        if config is not self._observed:   # a new config: does the observer still hold?
            key = observer_key(robot, config.params)
            if observer is None or key != self._observer_key:
                observer = self.observer = make_observer(robot, config.params)
                self._observer_key = key
            observer.backend = robot.backend
            self._observed = config
        return observer

    def _sense_wrench(self, config: Config, q: np.ndarray, r: np.ndarray) -> np.ndarray:
        """Return the wrench [n; f] at ``wrench_estimate.link`` that explains ``r`` (F/T)."""
        link, robot = config.params.wrench_estimate_link, config.robot
        J = sd.jacobian(robot.model, q, link, frame='local')
        estimate = wrench_from_torques(J, r, config.params.wrench_estimate_epsilon)
        self.estimates.add_wrench(link, estimate,
                                  bool(np.any(np.abs(r) > robot.external_torque_warn)))
        return estimate.wrench

    def _respond(self, config: Config, header, topic: str, desired: tuple,
                 measured: Optional[tuple], t0: int, with_terms: bool) -> Optional[Answer]:
        """Compute one answer (and its terms while subscribed); None when it is rejected."""
        robot, params = config.robot, config.params
        dynamics = None
        try:
            f_ext = self._active_wrenches(robot, t0) if self.wrenches else None
            if params.base == 'fixed':
                dynamics = Dynamics(robot.model, params.gravity, robot.backend, robot.armature,
                                    robot.friction_threshold, f_ext)
            else:   # the base's inputs held: InputError when missing or stale
                dynamics = self.base_inputs.dynamics(config, f_ext, t0)
                with_terms = with_terms and not robot.base.floating
            tau, terms = answer(dynamics, params.control_mode, params.output, desired, measured,
                                robot.gains, with_terms)
        except InputError as err:   # the base's state is not known: nothing is published
            if getattr(dynamics, 'pulls', None):   # a contact would pull, no QP answer
                self.base_inputs.pulled(dynamics.pulls, err)
            if getattr(dynamics, 'unsolved', None):   # the contacts cannot carry the base
                self.base_inputs.unsolved(dynamics.unsolved[-1], err)
            self._reject(topic, err.reason, str(err))
            return None
        except Exception as err:  # never die on one message
            self._reject(topic, 'compute_error', f'rnea failed: {err!r}')
            return None
        if not np.isfinite(tau).all():
            self._reject(topic, 'non_finite_output', 'torque is not finite (extreme input?)')
            return None
        if robot.clamp:
            tau, saturated = self._clamp(robot, tau)
            if saturated.any():
                self._count_saturated(robot, tau, saturated)
        else:
            self._count_above_limit(robot, tau)
        contacts = None
        if robot.base.floating and dynamics.pulls:   # re-solved by qp: a contact would pull
            self.base_inputs.pulled(dynamics.pulls)
        if robot.base.floating and dynamics.results:   # the solution at the model part's state
            result = dynamics.results[-1]
            self.base_inputs.solved(result, robot.pull_tolerance)
            q = measured[0] if params.control_mode == 'computed_torque' else desired[0]
            contacts = ContactWrenches(robot.model, dynamics.base_q, q, result)
        t1 = time.monotonic_ns()
        self._count_answer(self.window, header.stamp, t0, t1)
        return Answer(header, robot.joints, desired[0], desired[1], tau, terms, contacts)

    @staticmethod
    def _clamp(robot: Robot, tau: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
        """Clamp ``tau`` to the URDF limits (a floating model's base rows have none)."""
        if not robot.base.floating:
            return sd.clamp_to_effort_limits(robot.model, tau)
        tau, saturated = sd.clamp_to_effort_limits(robot.model, np.r_[np.zeros(6), tau])
        return tau[6:], saturated[6:]

    def base_input(self, config: Config, topic: str, msg) -> None:
        """Hold a base input (``base/imu``, ``base/pose``, ``base/twist``, ``contact_states``).

        Nothing to publish: it enters the answers that follow; a refused one is counted and
        logged, and the one held before stays (it goes stale on its own).
        """
        refused = self.base_inputs.take(topic, config, msg, time.monotonic_ns())
        if refused:
            self.log.warn(refused, throttle_duration_sec=1.0)

    def _count_answer(self, window: Window, stamp, t0: int, t1: int) -> None:
        totals = self.totals
        totals.answered += 1
        totals.last_input_ns = t0
        window.answered += 1
        compute = t1 - t0
        window.compute_ns += compute
        if compute > window.compute_max_ns:
            window.compute_max_ns = compute
        if stamp.sec or stamp.nanosec:
            delay = time.time_ns() - (stamp.sec * 1_000_000_000 + stamp.nanosec)
            window.delay_ns += delay
            window.delay_count += 1
            if delay > window.delay_max_ns:
                window.delay_max_ns = delay

    def _count_saturated(self, robot: Robot, tau: np.ndarray, saturated: np.ndarray) -> None:
        names = [robot.joints[i] for i in np.flatnonzero(saturated)]
        self.totals.saturated += 1
        self.totals.saturated_joints.update(names)
        self.log.warn(
            'clamped to the URDF effort limit: '
            + ', '.join(f'{shown(name)} at {tau[robot.joints.index(name)]:+g}' for name in names),
            throttle_duration_sec=1.0)

    def _count_above_limit(self, robot: Robot, tau: np.ndarray) -> None:
        """Count (and WARN, throttled) an answer above a joint's URDF effort limit.

        Published as it is: the URDF's limits are often wrong; clamping is
        ``clamp_to_effort_limits``'s, opt-in.
        """
        ratio = np.abs(tau) / robot.effort_limit
        i = int(np.argmax(ratio))
        if not ratio[i] > 1.0:
            return
        window, joint, limit = self.window, robot.joints[i], float(robot.effort_limit[i])
        window.above_limit += 1
        if window.above_worst is None or ratio[i] > window.above_worst[0]:
            window.above_worst = (float(ratio[i]), joint, float(tau[i]), limit)
        self.log.warn(f'effort above the URDF limit, published (clamp_to_effort_limits is '
                      f'off): {shown(joint)} {tau[i]:+.4g}, limit {limit:g} ({ratio[i]:.3g}x)',
                      throttle_duration_sec=1.0)

    def _active_wrenches(self, robot: Robot, now_ns: int) -> Optional[dict]:
        """Link -> wrench of the unexpired external wrenches on links of the model."""
        wrenches = self.wrenches
        for link in [link for link, (_, expiry) in wrenches.items() if expiry < now_ns]:
            del wrenches[link]
        frames = robot.model.frames
        return {link: f for link, (f, _) in wrenches.items() if link in frames} or None

    def wrench(self, config: Config, msg) -> None:
        """Store (or, when zero, remove) the wrench on link ``header.frame_id``.

        Nothing to publish: the wrench enters the answers that follow.
        """
        self.totals.wrenches_received += 1
        link = msg.header.frame_id
        robot = config.robot
        if robot is None:
            self._reject_wrench('no_model', f'{shown(link)}: no robot model loaded yet')
            return
        if robot.base.floating:
            self._reject_wrench('floating_base', f'on {shown(link)}: not applied on a floating '
                                'base (its contacts carry what acts on it: contacts.links, '
                                'measured_contact_wrenches)')
            return
        if link not in robot.model.frames:
            self._reject_wrench('unknown_link', f'header.frame_id {shown(link)} is not a link of '
                                f'robot {shown(robot.model.name)}')
            return
        t, f = msg.wrench.torque, msg.wrench.force
        wrench = np.array([t.x, t.y, t.z, f.x, f.y, f.z])   # [n; f], angular first
        if not np.isfinite(wrench).all():
            bad = [name for name, ok in zip(_WRENCH_FIELDS, np.isfinite(wrench)) if not ok]
            self._reject_wrench('non_finite', f'on {shown(link)}: wrench.{", wrench.".join(bad)} '
                                'not finite')
            return
        reason = check_bounded('wrench', wrench, MAX_WRENCH, 'N m or N', _WRENCH_FIELDS)
        if reason:
            self._reject_wrench('out_of_bounds', f'on {shown(link)}: {reason}')
            return
        if not wrench.any():
            self.wrenches.pop(link, None)
            return
        expiry = time.monotonic_ns() + int(config.params.external_wrench_timeout * 1e9)
        self.wrenches[link] = (wrench, expiry)

    def _reject_annotation(self, reason: str, text: str) -> None:
        self.totals.rejected[reason] += 1   # logged here: its own throttle
        self.log.warn(f'annotated_trajectory: message rejected, not annotated ({reason}): '
                      f'{text}', throttle_duration_sec=1.0)

    def _reject_wrench(self, reason: str, text: str) -> None:
        self.totals.wrenches_rejected[reason] += 1
        self.log.warn(f'external_wrenches: message rejected ({reason}): {text}',
                      throttle_duration_sec=1.0)

    def _reject_measured(self, reason: str, text: str) -> None:
        totals = self.totals
        totals.measured_rejected[reason] += 1
        totals.last_measured_rejected = (reason, text, time.monotonic_ns())
        self.log.warn(f'joint_states: measured state rejected ({reason}): {text}',
                      throttle_duration_sec=1.0)

    def _reject(self, topic: str, reason: str, text: str) -> None:
        totals = self.totals
        totals.rejected[reason] += 1
        totals.last_rejected = (reason, f'{topic}: {text}', time.monotonic_ns())
        self.log.warn(f'{topic}: message rejected ({reason}): {text}',
                      throttle_duration_sec=1.0)
