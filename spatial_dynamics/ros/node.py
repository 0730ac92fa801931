# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""ROS 2 node ``inverse_dynamics``: desired (and measured) joint states in, efforts out.

A thin shell, like robot_state_publisher: it declares the parameters of the table in
:mod:`spatial_dynamics.ros.config` (documented in ``config/inverse_dynamics.yaml`` and the
README, generated from it), validates a change into a whole new
:class:`~spatial_dynamics.ros.records.Config` in the on-set callback
(:func:`~spatial_dynamics.ros.configure.prepare`) and swaps it in (one
reference) in the post-set callback, and hands each input message with the current ``Config``
to :class:`~spatial_dynamics.ros.answering.Answering`, which computes the answer
(:mod:`spatial_dynamics.ros.control`) and returns what to publish; the node only publishes
it. With the defaults (``control_mode: feedforward``, ``output: full``) that is
``tau = ID(model, q, qd, qdd, f_ext) + armature·qdd + friction(qd)`` (RBDA §5.3) of each
desired state; the feedback modes answer each measured ``joint_states`` message instead.

Topics (relative, so they can be remapped), their types and QoS, and the parameters: the
README's tables (the parameters' is generated from the table, checked by a test).

The robot description comes from, in this order of precedence: the ``robot_description``
parameter (URDF XML), the ``robot_description_file`` parameter (a path, read by
:mod:`spatial_dynamics.files`), the ``robot_description`` topic. A new one is parsed completely
(:mod:`spatial_dynamics.ros.descriptions`) and swapped in between two messages only if it
loads. Four callback groups run in four threads: the inputs in ``inputs``; the plans
(``desired_trajectory``, sized, converted and checked: :mod:`.plans`) in ``plans``; the
diagnostics timer in ``diagnosing``; the parameter services, the description topic and the
parser's notifications in rclpy's default group, which alone writes ``config``. A
description set by parameter is parsed in its callback (the answer says whether it was
accepted) while the answers and the diagnostics go on in theirs.

The ``inputs`` group is the answering group: :func:`~spatial_dynamics.ros.common.spin` runs it
in a thread of its own with an executor that waits on it alone, and the rest (plans,
parameters, descriptions, the diagnostics timer) in a MultiThreadedExecutor that never waits
on it. That thread applies the real-time knobs (``thread_priority``, ``cpu_affinity``,
``lock_memory``: :mod:`spatial_dynamics.ros.realtime`) when it starts.
"""

from __future__ import annotations

from array import array
from collections import deque
from dataclasses import replace
import sys
import threading
import time
from typing import Optional, Sequence, Tuple
import warnings

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped, TwistStamped, WrenchStamped
from nav_msgs.msg import Odometry
import numpy as np
from rcl_interfaces.msg import SetParametersResult
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.event_handler import PublisherEventCallbacks
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import Imu, JointState
import spatial_dynamics as sd
from spatial_dynamics.ros import messages
from spatial_dynamics.ros.answering import Answering, Out
from spatial_dynamics.ros.bases import observer_off
from spatial_dynamics.ros.common import advertise, DESCRIPTION_QOS, plan_qos, spin, subscribe
from spatial_dynamics.ros.config import (
    ConfigError, NODE_NAME, PARAMETER_NAMES, PARAMETERS, PAYLOAD_PARAMETERS)
from spatial_dynamics.ros.configure import build_robot, prepare, reparse_needed
from spatial_dynamics.ros.control import terms_names
from spatial_dynamics.ros.descriptions import description_source, DescriptionParser, ParseRequest
from spatial_dynamics.ros.diagnostics import (
    backend_text, base_status, dof_text, feedforward_status, model_status, observer_status)
from spatial_dynamics.ros.floating import qp_missing_warning
from spatial_dynamics.ros.plans import Annotator, prepare_plan
from spatial_dynamics.ros import realtime
from spatial_dynamics.ros.records import Config, Robot
from spatial_dynamics.ros.text import listed, shown
from spatial_dynamics.ros.worker import Abandoned, abandonable
from std_msgs.msg import Float64MultiArray, String, UInt8MultiArray
from trajectory_msgs.msg import JointTrajectory

WRENCH_DEPTH = 10                   # several links may publish in one burst
#: Parameters that can change while the node runs (all but the read-only ones).
LIVE_PARAMETERS = frozenset(spec.name for spec in PARAMETERS if not spec.read_only)
_UNSET = {'string[]': Parameter.Type.STRING_ARRAY, 'double[]': Parameter.Type.DOUBLE_ARRAY,
          'int[]': Parameter.Type.INTEGER_ARRAY}


class InverseDynamicsNode(Node):
    """Publishes tau = ID(q, qd, qdd) for every good desired state it receives."""

    def __init__(self, **kwargs) -> None:
        super().__init__(NODE_NAME, **kwargs)
        for param in PARAMETERS:   # the values are checked by _prepare, below
            self.declare_parameter(param.name, _UNSET[param.type] if param.default is None
                                   else param.default, PARAMETERS.descriptor(param))
        # Callback groups, each its thread: the answering one (inputs; spin gives it a thread
        # and a loop of its own), the plans' one (below), the diagnostics' one (below) and
        # rclpy's default one (parameter services, the description topic, the parser's
        # notifications), which alone writes ``config``. A parameter change that parses a
        # description waits in its callback for the parse while the answers go on in theirs;
        # the new ``Config`` is swapped in as one reference, and each answer reads
        # ``self.config`` once.
        self.inputs = MutuallyExclusiveCallbackGroup()
        # Plans (desired_trajectory) are taken serialized, sized, converted and checked in a
        # third group (a third thread), handed to the answering group through a queue and a
        # guard condition, and annotated for JTC by a worker thread: what a plan costs in
        # proportion to its size never runs where joint_states are answered.
        self.plans = MutuallyExclusiveCallbackGroup()
        # The diagnostics timer in a group of its own: a description set by parameter is
        # parsed in the parameter service's callback (default group), seconds for a big one,
        # and /diagnostics went silent that long (21 s for 8000 links under load). It only
        # reads ``config`` (one reference) and swaps the period's counters under the lock.
        self.diagnosing = MutuallyExclusiveCallbackGroup()
        self._plan_queue: deque = deque()
        self.config: Optional[Config] = None
        self.answering = Answering(self.get_logger())
        # Held while one message is counted and answered, and while diagnostics swap the
        # period's counters (another thread): a swap between a message's 'received' and its
        # 'answered' would report it rejected.
        self._counting = threading.Lock()
        self.realtime: Optional[realtime.InEffect] = None   # set by the answering thread
        self._collections = 0      # diagnostics periods, each with a young-generation collection
        self._collection_ns = 0    # the pause of the last one
        # Topic descriptions: parsed by a worker; the result is applied only if its
        # generation is still the newest (a parameter or a newer message supersedes).
        self._description_generation = 0
        self._topic_descriptions = 0   # received on the topic: each one's number in the log
        self._description_sub = None
        self._pending = None      # (parameters, Config, changes) validated, not yet applied
        self._parsed = self.create_guard_condition(self._on_parsed)
        self._parser = DescriptionParser(self._build_from_topic, self._parsed.trigger)
        try:   # a big description parses for seconds: a signal meanwhile ends the wait
            self._configure({name: self._value(name) for name in PARAMETER_NAMES})
        except Abandoned:
            raise ExternalShutdownException() from None
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self.add_post_set_parameters_callback(self._on_parameters_set)
        self._make_endpoints()
        if self.robot is None:
            self._warn_waiting()

    @property
    def answering_group(self) -> MutuallyExclusiveCallbackGroup:
        """The callback group spun in the answering thread (see the module docstring)."""
        return self.inputs

    def on_answering_thread(self) -> None:
        """Answering thread, before its first wait: apply the real-time knobs; GC off.

        What the system refuses is one WARN (how to grant it) and normal scheduling; what is
        in effect is in /diagnostics (``real-time``).
        """
        params = self.config.params
        in_effect = realtime.apply(params.thread_priority, params.cpu_affinity,
                                   params.lock_memory)
        warning = realtime.warning(in_effect)
        if warning:
            self.get_logger().warn(warning)
        else:
            self.get_logger().info(f'real-time: {in_effect.priority}; {in_effect.affinity}; '
                                   f'memory {in_effect.memory}')
        self.realtime = in_effect
        realtime.keep_collector_off_answers()

    @property
    def robot(self) -> Optional[Robot]:
        """The robot the answers are computed for now (None: no model yet)."""
        return self.config.robot

    def _make_endpoints(self) -> None:
        self.commands_pub = advertise(self, Float64MultiArray, 'effort_commands')
        self.efforts_pub = advertise(self, JointState, 'feedforward_efforts')
        self.diagnostics_pub = self.create_publisher(
            DiagnosticArray, '/diagnostics', 10,
            event_callbacks=PublisherEventCallbacks(use_default_callbacks=False))
        self.terms_pub = advertise(self, JointState, 'feedforward_terms')
        self.estimate_pub = advertise(self, JointState, 'external_torque_estimate')
        self.wrench_pub = advertise(self, WrenchStamped, 'external_wrench_estimate')
        self.annotated_pub = advertise(self, JointTrajectory, 'annotated_trajectory')
        self.annotator = Annotator(self.annotated_pub.publish, self.get_logger())
        self._plan_ready = self.create_guard_condition(self._on_plans_ready,
                                                       callback_group=self.inputs)
        self._estimate = JointState()
        self._commands = Float64MultiArray()
        self._efforts = JointState()
        self._efforts_joints = None
        self._terms = JointState()
        group = self.inputs
        subscribe(self, JointState, 'desired_joint_states', self._on_joint_state, group=group)
        subscribe(self, JointTrajectory, 'desired_trajectory', self._on_plan, group=self.plans,
                  qos=plan_qos(), raw=True)
        subscribe(self, JointState, 'joint_states', self._on_measured, group=group)
        subscribe(self, WrenchStamped, 'external_wrenches', self._on_wrench, WRENCH_DEPTH,
                  group=group)
        if self.config.params.base != 'fixed':   # read-only: decided once, at start
            self.contacts_pub = advertise(self, WrenchStamped, 'contact_wrenches')
            for msg_type, topic in ((Imu, 'base/imu'), (Odometry, 'base/odometry'),
                                    (PoseStamped, 'base/pose'), (TwistStamped, 'base/twist'),
                                    (UInt8MultiArray, 'contact_states')):
                subscribe(self, msg_type, topic, self._base_callback(topic), group=group)
            subscribe(self, WrenchStamped, 'measured_contact_wrenches',
                      self._base_callback('measured_contact_wrenches'), WRENCH_DEPTH,
                      group=group)
        self.create_timer(1.0, self._publish_diagnostics, callback_group=self.diagnosing)

    def _base_callback(self, topic: str):
        def take(msg) -> None:
            with self._counting:
                self.answering.base_input(self.config, topic, msg)
        return take

    def destroy_node(self) -> None:
        """Stop the description parser and the annotation worker, then destroy the node."""
        self._parser.stop()
        self.annotator.stop()
        super().destroy_node()

    # -- parameters: validated on set, applied after ------------------------------------------

    def _value(self, name: str):
        parameter = self.get_parameter_or(name, None)
        return None if parameter is None else parameter.value

    def _on_set_parameters(self, parameters: Sequence[Parameter]) -> SetParametersResult:
        """Validate a change; the answer says whether it is accepted. Changes nothing else."""
        self._pending = None
        changes = {p.name: p.value for p in parameters if p.name in LIVE_PARAMETERS}
        if not changes:
            return SetParametersResult(successful=True)
        try:   # may parse a description: the answers go on in their own thread meanwhile
            config = self._prepare(changes)
        except Abandoned:   # the node is shutting down: nothing to apply, nothing to count
            return SetParametersResult(successful=False, reason='the node is shutting down')
        except Exception as err:  # ConfigError; anything else must not take the node down
            if not isinstance(err, ConfigError):
                err = ConfigError(f'{", ".join(changes)}: {err!r}')
            self.get_logger().warn(f'parameter change rejected: {err}')
            if {'robot_description', 'robot_description_file'} & changes.keys():
                self.answering.totals.description_rejected(str(err))
            return SetParametersResult(successful=False, reason=str(err))
        self._pending = (parameters, config, changes)
        return SetParametersResult(successful=True)

    def _on_parameters_set(self, parameters: Sequence[Parameter]) -> None:
        """Apply the change that :meth:`_on_set_parameters` validated (post-set callback)."""
        pending = self._pending
        if pending is not None and pending[0] is parameters:   # the list on-set validated
            self._pending = None
            self._apply(pending[1], pending[2])

    def _prepare(self, changes: dict) -> Config:
        """Validate ``changes`` against the current state (:func:`~.configure.prepare`).

        On a thread of its own, waited for while the context is valid: a signal ends the wait
        (:class:`~.worker.Abandoned`) instead of waiting out a long parse.
        """
        config = self.config
        if config is None:
            previous, robot = {}, None
        else:
            previous, robot = config.params, config.robot
        return abandonable(lambda: prepare(previous, changes, robot), self.context.ok,
                           'parameter change')

    def _configure(self, changes: dict) -> None:
        """Validate ``changes`` against the current state, then apply all of them at once."""
        self._apply(self._prepare(changes), changes)

    def _apply(self, config: Config, changes: dict) -> None:
        """Swap in a validated configuration (between two messages), log what changed."""
        before = ('feedforward', 'full') if self.config is None else (
            self.config.params.control_mode, self.config.params.output)
        if (config.params.control_mode, config.params.output) != before:
            self.get_logger().info(f'control_mode {config.params.control_mode}, output '
                                   f'{config.params.output}')
        if config.new_description:
            self._description_generation += 1   # a topic description still parsing is stale
        self._swap_in(config, bool(set(PAYLOAD_PARAMETERS) & changes.keys()))
        if config.kept_file:
            self.get_logger().info(
                f'robot_description_file {config.kept_file!r} checked and kept: '
                'robot_description is set and takes precedence; the file is used once '
                'robot_description is cleared')
        self._follow_topic()

    def _swap_in(self, config: Config, payload_changed: bool = False) -> None:
        """Swap ``config`` in (one reference); log a new model or payload."""
        previous = self.config
        before = None if previous is None else previous.robot
        robot = config.robot
        self.config = config
        if robot is not None and (before is None or robot.base is not before.base):
            self._log_model(robot, before)
        elif robot is not None and payload_changed:
            self.get_logger().info(f'payload: {robot.payload}')

    # -- the robot_description topic --------------------------------------------------------

    def _follow_topic(self) -> None:
        """Subscribe to the description topic while no description parameter is set, only."""
        wanted = description_source(self.config.params) == 'topic'
        if wanted and self._description_sub is None:
            # rclpy's default QoS event handlers stay here: a volatile publisher of the
            # description never reaches this transient-local subscription, worth a warning.
            self._description_sub = self.create_subscription(
                String, 'robot_description', self._on_description_topic, DESCRIPTION_QOS)
        elif not wanted and self._description_sub is not None:
            self.destroy_subscription(self._description_sub)
            self._description_sub = None
            self._description_generation += 1   # drop a topic description still parsing
            self.get_logger().info(
                'robot_description topic: unsubscribed, a description parameter is set and '
                'takes precedence')

    def _on_description_topic(self, msg: String) -> None:
        if description_source(self.config.params) != 'topic':   # taken just before unsubscribing
            self.get_logger().info(
                'robot_description topic: message ignored, a description parameter is set '
                'and takes precedence', throttle_duration_sec=5.0)
            return
        self._topic_descriptions += 1
        request = self._submit_topic(msg.data, self._topic_descriptions)
        self.get_logger().info(f'robot_description topic: {request} received, parsing')

    def _submit_topic(self, urdf: str, number: int) -> ParseRequest:
        """Hand a topic description to the parser; say which one waiting it drops."""
        self._description_generation += 1
        config = self.config
        request = ParseRequest(self._description_generation, urdf, config.params, config.robot,
                               number)
        dropped = self._parser.submit(request)
        if dropped is not None and dropped.number != number:
            self._superseded(dropped, f'{request} came before its parse started')
        return request

    def _superseded(self, request: ParseRequest, why: str) -> None:
        """Log and count a topic description dropped for something newer."""
        self.get_logger().info(f'robot_description topic: {request} dropped, not applied: '
                               f'{why}')
        self.answering.totals.descriptions_superseded += 1

    def _build_from_topic(self, request: ParseRequest) -> Robot:
        """Worker thread: the :class:`~.records.Robot` of a topic description (ConfigError)."""
        return build_robot(request.params, request.current, request.urdf,
                           'topic robot_description')

    def _on_parsed(self) -> None:
        """Executor: swap in a parsed topic description, unless something newer came since."""
        for request, result in self._parser.finished():
            if description_source(self.config.params) != 'topic':
                self._superseded(request, 'a description parameter is set and takes '
                                 'precedence')
                continue
            if request.generation != self._description_generation:
                self._superseded(request, 'a newer description came while it parsed')
                continue
            if request.params is not self.config.params:   # changed while it parsed
                result = self._rebuilt(request, result)
                if result is None:
                    continue
            if isinstance(result, ConfigError):
                self.get_logger().error(
                    f'robot description rejected, keeping the current model: {result}')
                self.answering.totals.description_rejected(str(result))
                continue
            self._swap_in(replace(self.config, robot=result))

    def _rebuilt(self, request: ParseRequest, result):
        """Rebuild ``result`` for the current parameters; None when it is parsed again."""
        params = self.config.params
        if isinstance(result, ConfigError) or reparse_needed(request.params, params):
            self._submit_topic(request.urdf, request.number)   # again, with the current params
            return None
        try:   # the same model: only the cheap parts again
            return build_robot(params, result)
        except ConfigError as err:
            return err

    def _log_model(self, robot: Robot, previous: Optional[Robot]) -> None:
        """Log what was loaded; each URDF warning once per new description text."""
        model = robot.model
        self.get_logger().info(
            f'robot {shown(model.name)} from {robot.source}: {dof_text(model)}; '
            f'output joints [{listed(robot.joints, count=30)}]')
        self.get_logger().info(f'model: {robot.base.summary()}; backend: '
                               f'{backend_text(robot)}; payload: {robot.payload}')
        if robot.backend != 'compiled' and robot.setting != 'numpy' and previous is None:
            self.get_logger().warn(f'backend {robot.setting}: compiled kernels unavailable, '
                                   f'answering on numpy: {sd.backends.compiled.FAILURE}')
        if previous is None and qp_missing_warning(robot):   # base is read-only: once
            self.get_logger().warn(qp_missing_warning(robot))
        if previous is None or robot.urdf != previous.urdf:
            for warning in robot.base.warnings:
                self.get_logger().warn(f'URDF warning ({robot.source}): {warning}')

    def _warn_waiting(self) -> None:
        self.get_logger().warn(
            'no robot model: set parameter robot_description or robot_description_file, or '
            f'publish on {shown(self.resolve_topic_name("robot_description"), quote=False)} '
            '(reliable, transient local); inputs are rejected until then',
            throttle_duration_sec=5.0)

    # -- inputs, answered by ``answering`` ----------------------------------------------------

    def _on_joint_state(self, msg: JointState) -> None:
        with self._counting:
            out = self.answering.joint_state(self.config, msg, self._wants_terms())
        self._send(out)

    def _on_plan(self, raw: bytes) -> None:
        """Size, convert and check a serialized plan; hand it to the answers (plans group)."""
        config = self.config
        size = len(raw)
        msg = None
        if size <= config.params.trajectory_max_bytes:
            try:
                msg = deserialize_message(raw, JointTrajectory)
            except Exception as err:  # a sample the type support cannot read
                self._plan_queue.append(prepare_plan(config, None, 0)._replace(
                    error=('malformed', f'cannot deserialize: {err!r}')))
                self._plan_ready.trigger()
                return
        self._plan_queue.append(prepare_plan(config, msg, size))
        self._plan_ready.trigger()

    def _on_plans_ready(self) -> None:
        """Schedule (or answer) the plans checked since, oldest first (inputs group)."""
        while self._plan_queue:
            item = self._plan_queue.popleft()
            with self._counting:
                out = self.answering.take_plan(self.config, item,
                                               self.get_clock().now().nanoseconds,
                                               self._wants_terms())
            self._send(out)

    def _on_measured(self, msg: JointState) -> None:
        config = self.config
        with self._counting:
            out = self.answering.measured(config, msg, self._wants_terms())
        self._send(out)
        with self._counting:
            out = self.answering.observe(config, msg)
        self._send(out)   # after the command is out

    def _on_wrench(self, msg: WrenchStamped) -> None:
        self.answering.wrench(self.config, msg)

    def _wants_terms(self) -> bool:
        return self.terms_pub.get_subscription_count() > 0

    def _send(self, out: Out) -> None:
        """Publish what one message gave: an answer, an estimate, a wrench, an annotated plan."""
        if out.answer is not None:
            self._publish(*out.answer[:6])
            if (out.answer.contacts is not None
                    and self.contacts_pub.get_subscription_count() > 0):
                for link, wrench in out.answer.contacts:
                    self.contacts_pub.publish(messages.wrench_stamped(out.answer.header, link,
                                                                      wrench))
        if out.estimate is not None:
            self._publish_estimate(*out.estimate)
        if out.wrench is not None:
            self.wrench_pub.publish(messages.wrench_stamped(*out.wrench))
        if out.annotate is not None:
            self.annotator.submit(out.annotate)

    def _publish(self, header, joints: Tuple[str, ...], q: np.ndarray, qd: np.ndarray,
                 tau: np.ndarray, terms: Optional[dict]) -> None:
        """Publish ``effort_commands``, ``feedforward_efforts`` (the input's header), terms.

        ``feedforward_terms``: name ``<joint>/<term>``, effort = the term's value; the terms
        sum to the answer before clamping.
        """
        # The output messages are reused: publish() serialises them before it returns.
        commands = self._commands
        commands.data = array('d', tau.tobytes())
        self.commands_pub.publish(commands)
        efforts = self._efforts
        efforts.header = header
        if self._efforts_joints is not joints:   # once per model, not per answer
            efforts.name = joints
            self._efforts_joints = joints
        efforts.position = array('d', q.tobytes())
        efforts.velocity = array('d', qd.tobytes())
        efforts.effort = commands.data
        self.efforts_pub.publish(efforts)
        if terms is not None:
            msg = self._terms
            msg.header = header
            msg.name = terms_names(joints, tuple(terms))
            values = np.concatenate(list(terms.values())) if terms else np.zeros(0)
            msg.effort = array('d', values.tobytes())
            self.terms_pub.publish(msg)

    def _publish_estimate(self, header, joints: Tuple[str, ...], r: np.ndarray) -> None:
        """Publish ``external_torque_estimate``: the observer's τ_ext in ``effort``."""
        estimate = self._estimate
        estimate.header = header
        estimate.name = joints
        estimate.effort = array('d', r.tobytes())
        self.estimate_pub.publish(estimate)

    # -- diagnostics ------------------------------------------------------------------------

    def _publish_diagnostics(self) -> None:
        """Publish the ``robot model`` and ``feedforward`` statuses of the period that ended."""
        self._collection_ns = realtime.collect(self._collections)   # off the answering thread
        self._collections += 1
        now_ns = time.monotonic_ns()
        answering = self.answering
        with self._counting:   # between two messages: a period never splits one's counts
            answering.drain(self.annotator)
            window, estimates = answering.period()
            base_period = (answering.base_inputs.period()
                           if self.config.params.base != 'fixed' else None)
        config = self.config
        robot = config.robot
        if robot is None:
            self._warn_waiting()
        backend = '' if robot is None else backend_text(robot)
        statuses = [
            ('robot model', model_status(robot, answering.totals, config.params.strict_urdf,
                                         backend)),
            ('feedforward', feedforward_status(robot, window, answering.totals, config.params,
                                               answering.wrenches, now_ns)),
            ('external torque', observer_status(robot, config.params.observer_gain,
                                                answering.observer, estimates,
                                                observer_off(config.params)))]
        level, message, values = realtime.status(self.realtime)
        values.append(('gc collection', f'{self._collection_ns / 1000:.0f} µs (diagnostics '
                       'timer; automatic collections off)'))
        statuses.append(('real-time', (level, message, values)))
        if config.params.base != 'fixed':
            statuses.append(('base', base_status(config.params, robot, answering.base_inputs,
                                                 base_period, now_ns)))
        name = self.get_fully_qualified_name().lstrip('/')  # 'inverse_dynamics' in the root ns
        diagnostics = messages.diagnostic_array(
            name, '' if robot is None else robot.model.name, statuses,
            self.get_clock().now().to_msg())
        self.diagnostics_pub.publish(diagnostics)


def main(args: Optional[Sequence[str]] = None) -> int:
    """Run the node until SIGINT/SIGTERM; 0 on a clean exit, 1 if the start-up config is bad."""
    # The node logs each URDF warning itself (once per description) and lists them in
    # /diagnostics: Python's own printing of them would repeat each one on stderr.
    warnings.filterwarnings('ignore', category=sd.URDFWarning)
    return spin(InverseDynamicsNode, args, threads=4)


if __name__ == '__main__':
    sys.exit(main())
