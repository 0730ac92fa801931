# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""ROS 2 node ``inverse_dynamics``: desired (and measured) joint states in, efforts out.

The only module that imports rclpy: a thin shell that declares the parameters of
:mod:`spatial_dynamics.ros.config`, validates a change there (the on-set callback) and swaps
the result in (the post-set callback), maps messages to ``(q, qd, qdd)`` by joint name
(:mod:`spatial_dynamics.ros.inputs`), has :func:`spatial_dynamics.ros.control.answer` compute
the answer and publishes it. With the defaults (``control_mode: feedforward``,
``output: full``) that is

    tau = ID(model, q, qd, qdd, f_ext) + armature·qdd + friction(qd)   (RBDA §5.3)

of each desired state, clamped to the URDF effort limits when asked (N or N·m per joint).
Every extra term is off by default (:mod:`spatial_dynamics.terms`). ``output`` selects the
model part (``full``, ``without_gravity`` = tau − g(q), ``gravity_only`` = g(q), ``none``);
``control_mode`` ``pd_feedforward`` adds kp (q_d − q) + kd (qd_d − qd) to the model part at
the desired state, ``computed_torque`` evaluates the model part at the measured state with
qdd_d + kp e + kd ė (:mod:`spatial_dynamics.ros.control`). In ``feedforward`` each desired
message is answered; in the feedback modes each measured ``joint_states`` message is
answered, with the last desired state held (zero-order hold), so a controller updates at its
sensor rate and a simulator in lockstep gets one command per measured state. A measured state
with the (non-zero) stamp of the one answered last is not answered again (a lockstep
simulator republishing the state it waits on must not get two commands for it).

Topics (relative, so they can be remapped):

============================  ====================================  ============================
``desired_joint_states``      sensor_msgs/JointState, in            best effort, keep last 1
``desired_trajectory``        trajectory_msgs/JointTrajectory, in   best effort, keep last 1
``external_wrenches``         geometry_msgs/WrenchStamped, in       best effort, keep last 10
``joint_states``              sensor_msgs/JointState, in: the       best effort, keep last 1
                              MEASURED state (position; velocity
                              in the feedback modes; effort:
                              measured torque, for the observer)
``robot_description``         std_msgs/String, in (subscribed only  reliable, transient local, 1
                              while no description parameter is
                              set; parsed off the answering path)
``feedforward_efforts``       sensor_msgs/JointState, out           reliable
``effort_commands``           std_msgs/Float64MultiArray, out       reliable
``feedforward_terms``         sensor_msgs/JointState, out: name     reliable; published only
                              ``<joint>/<term>``, effort = value    while subscribed
``external_torque_estimate``  sensor_msgs/JointState, out: the      reliable; one per measured
                              observer's τ_ext per model joint in   message with velocity and
                              effort (N m, N), the measurement's    effort for every model
                              header                                joint (observer_gain > 0)
``/diagnostics``              diagnostic_msgs/DiagnosticArray, out  ~1 Hz
============================  ====================================  ============================

Parameters are listed in ``config/inverse_dynamics.yaml``. Every message is answered or
rejected on its own: a rejected message (reason counted in diagnostics) produces no output, and
nothing is published without fresh input, so a stale input means no output (never zeros). In
the feedback modes a measured state is answered only while the held desired state is younger
than ``input_timeout``; with no measured state for ``measured_timeout`` nothing is published
(diagnostics ERROR naming the measured state). ``feedforward_efforts`` carries the desired
``q_d``, ``qd_d`` in position/velocity (what an MIT-mode drive takes with the torque).

External torques (any ``control_mode``): each measured state whose ``effort`` holds the
measured torque of every model joint updates a generalized-momentum observer
(:mod:`spatial_dynamics.ros.observer`, gain ``observer_gain``, the node's model with payload,
armature, friction and gravity), integrated over the header stamps (a message stamped 0 or with
the stamp of the previous one is skipped; a stamp going back, a gap above ``measured_timeout``
or a change of the model or of a parameter it uses restarts it at zero), and its estimate of
τ_ext = Jᵀw is published on ``external_torque_estimate``. Diagnostics (status ``external
torque``) give its RMS per joint over the period and WARN, naming the joints, above
``external_torque_warn``.

``joint_states`` is subscribed best effort, keep last 1, like the desired inputs: that
matches drivers' reliable publishers and sensor-data best-effort ones alike (a reliable
subscription never connects to a best-effort publisher), and keep last 1 answers the newest
state. A simulator in lockstep may override it to reliable
(``qos_overrides./joint_states.subscription.reliability``).

The robot description comes from, in this order of precedence: the ``robot_description``
parameter (URDF XML), the ``robot_description_file`` parameter (a path: a regular UTF-8 file of
at most 32 MiB), the ``robot_description`` topic (URDF XML). A description is XML text and
never opened as a path. A new one is parsed completely and swapped in between two messages
(one reference assignment) only if it loads; otherwise the old model stays. Descriptions from
the topic are parsed in a worker thread; a description set by parameter is parsed in a thread
while the parameter callback keeps answering the inputs (its answer says whether the change
was accepted), so answers keep coming while a large one parses.

The answers run on the backend of the read-only ``backend`` parameter (``auto``, ``numpy``,
``compiled``): on numpy from the first message, switched to the compiled kernels (one
reference swap) once they are prepared off the answering path
(:class:`~spatial_dynamics.ros.config.CompiledKernels`).
"""

from __future__ import annotations

from array import array
import sys
import threading
import time
from typing import Callable, NamedTuple, Optional, Sequence, Tuple
import warnings

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import WrenchStamped
import numpy as np
from rcl_interfaces.msg import SetParametersResult
from rclpy.event_handler import PublisherEventCallbacks
from rclpy.node import Node
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
import spatial_dynamics as sd
from spatial_dynamics.bounds import check_bounded, MAX_WRENCH
from spatial_dynamics.ros.common import advertise, DESCRIPTION_QOS, spin, subscribe
from spatial_dynamics.ros.config import (
    build_output, CompiledKernels, Config, ConfigError, DEFAULT_GRAVITY,
    DEFAULT_INPUT_TIMEOUT, DEFAULT_MEASURED_TIMEOUT, DEFAULT_OBSERVER_GAIN,
    DEFAULT_WRENCH_TIMEOUT, make_observer, NODE_NAME, observer_key, Output,
    PARAMETER_NAMES, PARAMETERS, PAYLOAD_PARAMETERS, prepare, reparse_needed,
    SLOW_PARAMETERS)
from spatial_dynamics.ros.descriptions import description_source, DescriptionParser, ParseRequest
from spatial_dynamics.ros.diagnostics import (
    backend_text, feedforward_status, model_status, observer_status, Settings, Totals, Window)
from spatial_dynamics.ros.control import (answer, Dynamics, FEEDBACK_MODES, measured_arrays,
                                          terms_names)
from spatial_dynamics.ros.inputs import InputError, joint_state_arrays, trajectory_arrays
from spatial_dynamics.ros.observer import EstimateWindow, measured_effort, sample_time
from spatial_dynamics.trajectory import Follower, TrajectoryError
from std_msgs.msg import Float64MultiArray, String
from trajectory_msgs.msg import JointTrajectory

WRENCH_DEPTH = 10                   # several links may publish in one burst
#: Parameters that can change while the node runs (all but the read-only ones).
LIVE_PARAMETERS = frozenset(spec.name for spec in PARAMETERS if not spec.read_only)
_UNSET = {'string[]': Parameter.Type.STRING_ARRAY, 'double[]': Parameter.Type.DOUBLE_ARRAY}
_LEVELS = {'OK': DiagnosticStatus.OK, 'WARN': DiagnosticStatus.WARN,
           'ERROR': DiagnosticStatus.ERROR}
_WRENCH_FIELDS = ('torque.x', 'torque.y', 'torque.z', 'force.x', 'force.y', 'force.z')


class Held(NamedTuple):
    """A good state kept between messages: model joints, arrays, receipt (monotonic ns)."""

    joints: Tuple[str, ...]
    state: tuple
    receipt_ns: int


class InverseDynamicsNode(Node):
    """Publishes tau = ID(q, qd, qdd) for every good desired state it receives."""

    def __init__(self, **kwargs) -> None:
        super().__init__(NODE_NAME, **kwargs)
        for param in PARAMETERS:   # the values are checked by _configure, below
            self.declare_parameter(param.name, _UNSET[param.type] if param.default is None
                                   else param.default, PARAMETERS.descriptor(param))
        self.output: Optional[Output] = None
        self.gravity = DEFAULT_GRAVITY
        self.acceleration_source = 'effort'
        self.input_timeout = DEFAULT_INPUT_TIMEOUT
        self.control_mode = 'feedforward'
        self.output_choice = 'full'
        self.measured_timeout = DEFAULT_MEASURED_TIMEOUT
        self.observer_gain = DEFAULT_OBSERVER_GAIN
        self.observer = None              # MomentumObserver of the current model, when on
        self._observed: Optional[Output] = None   # the output the observer was made for
        self._observer_key: Optional[tuple] = None
        self.estimates = EstimateWindow()   # external_torque_estimate of the period
        self.desired: Optional[Held] = None    # the last good desired state (zero-order hold)
        self.follower = Follower()   # desired_trajectory in the feedback modes (JTC's rules)
        self._following: Optional[tuple] = None   # the joints the follower's plans are in
        self._measured_q: Optional[np.ndarray] = None   # the last measured position
        self._measured_stamp = 0     # its stamp (ns): the clock trajectories are sampled on
        self._answered_stamp = 0               # stamp (ns) of the measured state answered last
        self.wrench_timeout_ns = int(DEFAULT_WRENCH_TIMEOUT * 1e9)
        self.params: dict = {}   # the last accepted value of every parameter of PARAMETERS
        self.totals = Totals()
        self.window = Window()
        self.wrenches: dict = {}  # link -> (wrench [n; f] in the link frame, expiry ns)
        # Topic descriptions: parsed by a worker; the result is applied in the executor only
        # if its generation is still the newest (a parameter or a newer message supersedes).
        self._description_generation = 0
        self._description_sub = None
        self._inputs: list = []   # input subscriptions, served while a parameter change parses
        self._pending = None      # (parameters, Config, changes) validated, not yet applied
        self._parsed = self.create_guard_condition(self._on_parsed)
        self._parser = DescriptionParser(self._build_from_topic, self._parsed.trigger)
        self._compiled = self.create_guard_condition(self._on_compiled)
        self.kernels = CompiledKernels(self._compiled.trigger)
        self._configure({name: self._value(name) for name in PARAMETER_NAMES})
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self.add_post_set_parameters_callback(self._on_parameters_set)
        self._make_endpoints()
        if self.output is None:
            self._warn_waiting()

    def _make_endpoints(self) -> None:
        self.commands_pub = advertise(self, Float64MultiArray, 'effort_commands')
        self.efforts_pub = advertise(self, JointState, 'feedforward_efforts')
        self.diagnostics_pub = self.create_publisher(
            DiagnosticArray, '/diagnostics', 10,
            event_callbacks=PublisherEventCallbacks(use_default_callbacks=False))
        self.terms_pub = advertise(self, JointState, 'feedforward_terms')
        self.estimate_pub = advertise(self, JointState, 'external_torque_estimate')
        self._estimate = JointState()
        self._commands = Float64MultiArray()
        self._efforts = JointState()
        self._terms = JointState()
        self._inputs = [
            subscribe(self, JointState, 'desired_joint_states', self._on_joint_state),
            subscribe(self, JointTrajectory, 'desired_trajectory', self._on_trajectory),
            subscribe(self, JointState, 'joint_states', self._on_measured),
            subscribe(self, WrenchStamped, 'external_wrenches', self._on_wrench, WRENCH_DEPTH)]
        self.create_timer(1.0, self._publish_diagnostics)

    def destroy_node(self) -> None:
        """Stop the description parser, then destroy the node."""
        self._parser.stop()
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
        try:
            if SLOW_PARAMETERS & changes.keys():   # may parse a description
                config = self._while_answering(lambda: self._prepare(changes))
            else:
                config = self._prepare(changes)
        except Exception as err:  # ConfigError; anything else must not take the node down
            if not isinstance(err, ConfigError):
                err = ConfigError(f'{", ".join(changes)}: {err!r}')
            self.get_logger().warn(f'parameter change rejected: {err}')
            if {'robot_description', 'robot_description_file'} & changes.keys():
                self.totals.description_rejected(str(err))
            return SetParametersResult(successful=False, reason=str(err))
        self._pending = (parameters, config, changes)
        return SetParametersResult(successful=True)

    def _on_parameters_set(self, parameters: Sequence[Parameter]) -> None:
        """Apply the change that :meth:`_on_set_parameters` validated (post-set callback)."""
        pending = self._pending
        if pending is not None and pending[0] is parameters:   # the list on-set validated
            self._pending = None
            self._apply(pending[1], pending[2])

    def _while_answering(self, prepare_config: Callable[[], Config]) -> Config:
        """Run ``prepare_config`` in a thread; meanwhile, answer the inputs from this one.

        The parameter service's callback runs in the executor that answers the inputs, and its
        reply must say whether the change was accepted, so it has to wait for the parse; the
        inputs are taken and answered here in the meantime (as the executor would), so a large
        description set by parameter does not silence the node either. ``prepare_config``
        changes nothing of the node; its exception is raised here.
        """
        done = threading.Event()
        box: dict = {}

        def run() -> None:
            try:
                box['config'] = prepare_config()
            except BaseException as err:  # handed to the caller
                box['error'] = err
            finally:
                done.set()

        threading.Thread(target=run, daemon=True, name='parameter change').start()
        serve = True
        while not done.wait(0.001 if serve else 0.1):
            serve = serve and self._serve_inputs()
        if 'error' in box:
            raise box['error']
        return box['config']

    def _serve_inputs(self) -> bool:
        """Take and handle the waiting input messages; False if they cannot be taken here.

        Uses the take of rclpy's executor (``handle.take_message``); should it be unavailable,
        parameter changes simply wait for the parse, as the executor would.
        """
        for sub in self._inputs:
            try:
                with sub.handle:
                    taken = sub.handle.take_message(sub.msg_type, sub.raw)
            except Exception:
                return False
            if taken is not None:
                sub.callback(taken[0])
        return True

    def _prepare(self, changes: dict) -> Config:
        """Validate ``changes`` against the current state (:func:`~.config.prepare`)."""
        return prepare(self.params, changes, self.output, self.kernels)

    def _configure(self, changes: dict) -> None:
        """Validate ``changes`` against the current state, then apply all of them at once."""
        self._apply(self._prepare(changes), changes)

    def _apply(self, config: Config, changes: dict) -> None:
        """Swap in a validated configuration (between two messages), log what changed."""
        self.params = config.params
        self.gravity = config.gravity
        self.acceleration_source = config.acceleration_source
        self.input_timeout = config.input_timeout
        self.wrench_timeout_ns = int(config.wrench_timeout * 1e9)
        if config.control_mode != self.control_mode or config.output_choice != self.output_choice:
            self.get_logger().info(f'control_mode {config.control_mode}, output '
                                   f'{config.output_choice}')
        self.control_mode = config.control_mode
        self.output_choice = config.output_choice
        self.measured_timeout = config.measured_timeout
        self.observer_gain = config.observer_gain
        self._observed = None   # the observer's settings are checked again at the next sample
        if config.observer_gain <= 0.0:
            self.observer = None
        if config.new_description:
            self._description_generation += 1   # a topic description still parsing is stale
        self._set_output(config.output, bool(set(PAYLOAD_PARAMETERS) & changes.keys()))
        if config.kept_file:
            self.get_logger().info(
                f'robot_description_file {config.kept_file!r} checked and kept: '
                'robot_description is set and takes precedence; the file is used once '
                'robot_description is cleared')
        self._follow_topic()

    def _set_output(self, output: Optional[Output], payload_changed: bool = False) -> None:
        """Swap ``output`` in (one reference); start preparing compiled kernels if it wants."""
        previous = self.output
        if output is not None and output.waits_for_compiled:
            if self.kernels.ready:   # got ready while this output was built
                output = output.upgraded()
            else:
                self.kernels.request(output.model)
        self.output = output
        if output is not None and (previous is None or output.base is not previous.base):
            self._log_model(output, previous)
        elif output is not None and payload_changed:
            self.get_logger().info(f'payload: {output.payload}')

    def _on_compiled(self) -> None:
        """Executor: the compiled kernels are ready (switch to them) or cannot be had."""
        kernels = self.kernels
        if not kernels.ready:
            self.get_logger().warn(f'compiled kernels unavailable, answering on numpy: '
                                   f'{kernels.error}')
            return
        self.get_logger().info(f'compiled kernels ready after {kernels.seconds:.1f} s: '
                               f'{kernels.description}')
        output = self.output
        if output is not None and output.waits_for_compiled:
            self.output = output = output.upgraded()
            self.get_logger().info(f'backend: {backend_text(output, kernels)}')

    # -- the robot_description topic --------------------------------------------------------

    def _follow_topic(self) -> None:
        """Subscribe to the description topic while no description parameter is set, only."""
        wanted = description_source(self.params) == 'topic'
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
        if description_source(self.params) != 'topic':   # taken just before unsubscribing
            self.get_logger().info(
                'robot_description topic: message ignored, a description parameter is set '
                'and takes precedence', throttle_duration_sec=5.0)
            return
        self._submit_topic(msg.data)

    def _submit_topic(self, urdf: str) -> None:
        self._description_generation += 1
        self._parser.submit(ParseRequest(self._description_generation, urdf, self.params,
                                         self.output))

    def _build_from_topic(self, request: ParseRequest) -> Output:
        """Worker thread: the :class:`Output` of a topic description (ConfigError if bad)."""
        return build_output(request.params, request.current, request.urdf,
                            'topic robot_description', self.kernels)

    def _on_parsed(self) -> None:
        """Executor: swap in a parsed topic description, unless something newer came since."""
        for request, result in self._parser.finished():
            if (request.generation != self._description_generation
                    or description_source(self.params) != 'topic'):
                continue   # superseded by a newer message or by a description parameter
            if request.params is not self.params:   # parameters changed while it parsed
                result = self._rebuilt(request, result)
                if result is None:
                    continue
            if isinstance(result, ConfigError):
                self.get_logger().error(
                    f'robot description rejected, keeping the current model: {result}')
                self.totals.description_rejected(str(result))
                continue
            self._set_output(result)

    def _rebuilt(self, request: ParseRequest, result):
        """Rebuild ``result`` for the current parameters; None when it is parsed again."""
        if isinstance(result, ConfigError) or reparse_needed(request.params, self.params):
            self._submit_topic(request.urdf)   # again, with the current parameters
            return None
        try:   # the same model: only the cheap parts again
            return build_output(self.params, result, kernels=self.kernels)
        except ConfigError as err:
            return err

    def _log_model(self, out: Output, previous: Optional[Output]) -> None:
        """Log what was loaded; each URDF warning once per new description text."""
        self.get_logger().info(
            f'robot {out.model.name!r} from {out.source}: {len(out.model.joint_names)} DOF; '
            f'output joints {list(out.joints)}')
        self.get_logger().info(f'model: {out.base.summary()}; backend: '
                               f'{backend_text(out, self.kernels)}; payload: {out.payload}')
        if previous is None or out.urdf != previous.urdf:
            for warning in out.base.warnings:
                self.get_logger().warn(f'URDF warning ({out.source}): {warning}')

    def _warn_waiting(self) -> None:
        self.get_logger().warn(
            'no robot model: set parameter robot_description or robot_description_file, or '
            f'publish on {self.resolve_topic_name("robot_description")} '
            '(reliable, transient local); inputs are rejected until then',
            throttle_duration_sec=5.0)

    # -- hot path ---------------------------------------------------------------------------

    def _on_joint_state(self, msg: JointState) -> None:
        self._on_desired(msg, 'desired_joint_states', joint_state_arrays,
                         (msg.name, msg.position, msg.velocity,
                          msg.effort if self.acceleration_source == 'effort' else None))

    def _on_trajectory(self, msg: JointTrajectory) -> None:
        if self.control_mode in FEEDBACK_MODES:
            self._follow(msg)
        else:   # feedforward: the first point is the desired state, answered at once
            self._on_desired(msg, 'desired_trajectory', trajectory_arrays,
                             (msg.joint_names, msg.points))

    def _follow(self, msg: JointTrajectory) -> None:
        """Feedback modes: follow a whole trajectory, sampled at each measured stamp (JTC)."""
        output = self.output
        if output is None:
            self._reject('desired_trajectory', 'no_model', 'no robot model loaded yet')
            return
        start_ns = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        now_ns = self._measured_stamp or self.get_clock().now().nanoseconds
        q = self._measured_q
        if q is not None and len(q) != len(output.joints):   # measured on another model
            q = None
        try:
            traj = self.follower.accept(msg.joint_names, msg.points, start_ns, now_ns,
                                        output.joints, q)
        except TrajectoryError as err:
            self._reject('desired_trajectory', err.reason, f'refused whole, the trajectory '
                         f'followed before goes on: {err}')
            return
        self._following = output.joints
        self.totals.last_desired_ns = time.monotonic_ns()
        self.get_logger().info(
            'desired_trajectory: stopped, holding the measured position' if traj is None else
            f'desired_trajectory: following {len(msg.points)} points ({traj.kind}, '
            f'{traj.time[-1] - traj.time[0]:g} s) from {(start_ns or now_ns) * 1e-9:.9f} s')

    def _on_desired(self, msg, topic: str, to_arrays, fields: tuple) -> None:
        """Hold a good desired state; in feedforward mode, answer it (or reject it whole)."""
        t0 = time.monotonic_ns()
        answers = self.control_mode not in FEEDBACK_MODES
        if answers:
            self.window.received += 1
        output = self.output
        if output is None:
            self._reject(topic, 'no_model', 'no robot model loaded yet')
            return
        try:
            desired = to_arrays(output.model.joint_names, *fields)
        except InputError as err:
            self._reject(topic, err.reason, str(err))
            return
        self.desired = Held(output.joints, desired, t0)
        self.totals.last_desired_ns = t0
        if answers:
            self._respond(msg.header, output, topic, desired, None, t0)

    def _on_measured(self, msg: JointState) -> None:
        """Check a measured state; in a feedback mode, answer it with the held desired one."""
        t0 = time.monotonic_ns()
        feedback = self.control_mode in FEEDBACK_MODES
        totals = self.totals
        totals.measured_received += 1
        if feedback:
            self.window.received += 1
        output = self.output
        if output is None:
            self._reject_measured('no_model', 'no robot model loaded yet')
            return
        try:
            measured = measured_arrays(output.joints, msg.name, msg.position, msg.velocity,
                                       feedback)
        except InputError as err:
            self._reject_measured(err.reason, str(err))
            return
        totals.last_measured_ns = t0
        self.window.measured += 1
        stamp = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        self._measured_q = measured[0]     # in output.joints order: held by an empty trajectory
        self._measured_stamp = stamp or self._measured_stamp
        if feedback:
            self._answer_measured(msg, output, measured, t0)
        if self.observer_gain > 0.0:   # after the answer: it never delays a command
            self._observe(msg, output, measured)

    def _answer_measured(self, msg: JointState, output: Output, measured: tuple,
                         t0: int) -> None:
        """Answer a good measured state with the held desired state (a feedback mode)."""
        stamp = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        desired = None
        if self._following == output.joints:   # a trajectory, sampled at this measurement
            desired = self.follower.sample(stamp or self._measured_stamp)
        if desired is None:
            held = self.desired
            if held is None or held.joints != output.joints:
                self._reject('joint_states', 'no_desired', f'{self.control_mode}: no desired '
                             'state for the model\'s joints yet')
                return
            age = (t0 - held.receipt_ns) * 1e-9
            if age > self.input_timeout:
                self._reject('joint_states', 'desired_stale',
                             f'{self.control_mode}: the held desired state is {age:.3f} s old '
                             f'(input_timeout {self.input_timeout} s); not publishing')
                return
            desired = held.state
        if stamp != 0 and stamp == self._answered_stamp:
            self._reject('joint_states', 'repeated',
                         f'{self.control_mode}: the measured state stamped {stamp * 1e-9:.9f} '
                         's was answered already (one answer per measurement)')
            return
        self._answered_stamp = stamp
        self._respond(msg.header, output, 'joint_states', desired, measured, t0)

    def _observe(self, msg: JointState, output: Output, measured: tuple) -> None:
        """Update the external-torque observer with a measured state; publish its estimate.

        A message without effort (or velocity) for every model joint only skips the update
        (counted in diagnostics): not an error. The observer restarts when the model or a
        parameter it depends on changes (:func:`~.config.observer_key`).
        """
        skipped = self.estimates.skipped
        q, qd = measured
        if qd is None:
            skipped['no_velocity'] += 1
            return
        try:
            tau = measured_effort(output.joints, msg.name, msg.effort)
        except InputError as err:
            skipped[err.reason if err.reason in skipped else 'no_effort'] += 1
            return
        observer = self.observer
        if output is not self._observed:
            key = observer_key(output, self.gravity, self.observer_gain, self.measured_timeout)
            if observer is None or key != self._observer_key:
                observer = self.observer = make_observer(output, self.gravity,
                                                         self.observer_gain,
                                                         self.measured_timeout)
                self._observer_key = key
            observer.backend = output.backend
            self._observed = output
        t = sample_time(msg.header.stamp.sec, msg.header.stamp.nanosec)
        if t is None:
            skipped['unstamped'] += 1
            return
        try:
            r = observer.update(t, q, qd, tau)
        except Exception as err:  # never die on one message
            self.get_logger().warn(f'external torque observer failed: {err!r}',
                                   throttle_duration_sec=1.0)
            observer.reset('compute error')
            return
        if r is None:
            skipped['repeated'] += 1
            return
        estimate = self._estimate
        estimate.header = msg.header
        estimate.name = output.joints
        estimate.effort = array('d', r.tobytes())
        self.estimate_pub.publish(estimate)
        self.estimates.add(r)

    def _respond(self, header, output: Output, topic: str, desired: tuple,
                 measured: Optional[tuple], t0: int) -> None:
        """Compute and publish one answer (and its terms while subscribed), or reject it."""
        with_terms = self.terms_pub.get_subscription_count() > 0
        try:
            f_ext = self._active_wrenches(output, t0) if self.wrenches else None
            dynamics = Dynamics(output.model, self.gravity, output.backend, output.armature,
                                output.friction_threshold, f_ext)
            tau, terms = answer(dynamics, self.control_mode, self.output_choice, desired,
                                measured, output.gains, with_terms)
        except Exception as err:  # never die on one message
            self._reject(topic, 'compute_error', f'rnea failed: {err!r}')
            return
        if not np.isfinite(tau).all():
            self._reject(topic, 'non_finite_output', 'torque is not finite (extreme input?)')
            return
        if output.clamp:
            tau, saturated = sd.clamp_to_effort_limits(output.model, tau)
            if saturated.any():
                self._count_saturated(output, tau, saturated)
        t1 = time.monotonic_ns()
        self._publish(header, output, desired[0], desired[1], tau)
        if terms is not None:
            self._publish_terms(header, output, terms)
        self._count_answer(self.window, header.stamp, t0, t1)

    def _publish(self, header, output: Output, q: np.ndarray, qd: np.ndarray,
                 tau: np.ndarray) -> None:
        """Publish ``effort_commands`` then ``feedforward_efforts`` (the input's header)."""
        # The two output messages are reused: publish() serialises them before it returns.
        commands = self._commands
        commands.data = array('d', tau.tobytes())
        self.commands_pub.publish(commands)
        efforts = self._efforts
        efforts.header = header
        efforts.name = output.joints
        efforts.position = array('d', q.tobytes())
        efforts.velocity = array('d', qd.tobytes())
        efforts.effort = commands.data
        self.efforts_pub.publish(efforts)

    def _publish_terms(self, header, output: Output, terms: dict) -> None:
        """Publish ``feedforward_terms``: ``<joint>/<term>``, effort = the term's value.

        The terms sum to the answer before clamping.
        """
        msg = self._terms
        msg.header = header
        msg.name = terms_names(output.joints, tuple(terms))
        values = np.concatenate(list(terms.values())) if terms else np.zeros(0)
        msg.effort = array('d', values.tobytes())
        self.terms_pub.publish(msg)

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

    def _count_saturated(self, output: Output, tau: np.ndarray, saturated: np.ndarray) -> None:
        names = [output.joints[i] for i in np.flatnonzero(saturated)]
        self.totals.saturated += 1
        self.totals.saturated_joints.update(names)
        self.get_logger().warn(
            'clamped to the URDF effort limit: '
            + ', '.join(f'{name!r} at {tau[output.joints.index(name)]:+g}' for name in names),
            throttle_duration_sec=1.0)

    def _active_wrenches(self, output: Output, now_ns: int) -> Optional[dict]:
        """Link -> wrench of the unexpired external wrenches on links of the model."""
        wrenches = self.wrenches
        for link in [link for link, (_, expiry) in wrenches.items() if expiry < now_ns]:
            del wrenches[link]
        frames = output.model.frames
        return {link: f for link, (f, _) in wrenches.items() if link in frames} or None

    def _on_wrench(self, msg: WrenchStamped) -> None:
        """Store (or, when zero, remove) the wrench on link ``header.frame_id``."""
        self.totals.wrenches_received += 1
        link = msg.header.frame_id
        output = self.output
        if output is None:
            self._reject_wrench('no_model', f'{link!r}: no robot model loaded yet')
            return
        if link not in output.model.frames:
            self._reject_wrench('unknown_link', f'header.frame_id {link!r} is not a link of '
                                f'robot {output.model.name!r}')
            return
        t, f = msg.wrench.torque, msg.wrench.force
        wrench = np.array([t.x, t.y, t.z, f.x, f.y, f.z])   # [n; f], angular first
        if not np.isfinite(wrench).all():
            bad = [name for name, ok in zip(_WRENCH_FIELDS, np.isfinite(wrench)) if not ok]
            self._reject_wrench('non_finite', f'on {link!r}: wrench.{", wrench.".join(bad)} '
                                'not finite')
            return
        reason = check_bounded('wrench', wrench, MAX_WRENCH, 'N m or N', _WRENCH_FIELDS)
        if reason:
            self._reject_wrench('out_of_bounds', f'on {link!r}: {reason}')
            return
        if not wrench.any():
            self.wrenches.pop(link, None)
            return
        self.wrenches[link] = (wrench, time.monotonic_ns() + self.wrench_timeout_ns)

    def _reject_wrench(self, reason: str, text: str) -> None:
        self.totals.wrenches_rejected[reason] += 1
        self.get_logger().warn(f'external_wrenches: message rejected ({reason}): {text}',
                               throttle_duration_sec=1.0)

    def _reject_measured(self, reason: str, text: str) -> None:
        self.totals.measured_rejected[reason] += 1
        self.get_logger().warn(f'joint_states: measured state rejected ({reason}): {text}',
                               throttle_duration_sec=1.0)

    def _reject(self, topic: str, reason: str, text: str) -> None:
        self.totals.rejected[reason] += 1
        self.get_logger().warn(f'{topic}: message rejected ({reason}): {text}',
                               throttle_duration_sec=1.0)

    # -- diagnostics ------------------------------------------------------------------------

    def _publish_diagnostics(self) -> None:
        """Publish the ``robot model`` and ``feedforward`` statuses of the period that ended."""
        now_ns = time.monotonic_ns()
        window, self.window = self.window, Window()
        output = self.output
        if output is None:
            self._warn_waiting()
        backend = '' if output is None else backend_text(output, self.kernels)
        settings = Settings(self.gravity, self.acceleration_source, self.input_timeout,
                            self.control_mode, self.output_choice, self.measured_timeout)
        estimates, self.estimates = self.estimates, EstimateWindow()
        statuses = [
            ('robot model', model_status(output, self.totals, self.params['strict_urdf'],
                                         backend)),
            ('feedforward', feedforward_status(output, window, self.totals, settings,
                                               self.wrenches, now_ns)),
            ('external torque', observer_status(output, self.observer_gain, self.observer,
                                                estimates))]
        name = self.get_fully_qualified_name().lstrip('/')  # 'inverse_dynamics' in the root ns
        hardware_id = '' if output is None else output.model.name
        diagnostics = DiagnosticArray(status=[
            DiagnosticStatus(level=_LEVELS[level], name=f'{name}: {suffix}', message=message,
                             hardware_id=hardware_id,
                             values=[KeyValue(key=k, value=v) for k, v in values])
            for suffix, (level, message, values) in statuses])
        diagnostics.header.stamp = self.get_clock().now().to_msg()
        self.diagnostics_pub.publish(diagnostics)


def main(args: Optional[Sequence[str]] = None) -> int:
    """Run the node until SIGINT/SIGTERM; 0 on a clean exit, 1 if the start-up config is bad."""
    # The node logs each URDF warning itself (once per description) and lists them in
    # /diagnostics: Python's own printing of them would repeat each one on stderr.
    warnings.filterwarnings('ignore', category=sd.URDFWarning)
    return spin(InverseDynamicsNode, args)


if __name__ == '__main__':
    sys.exit(main())
