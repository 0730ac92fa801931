# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""ROS 2 node ``inverse_dynamics``: desired joint states in, feed-forward efforts out.

The only module that imports rclpy: a thin shell that declares and validates parameters, builds
the :class:`~spatial_dynamics.Model`, maps messages to ``(q, qd, qdd)`` by joint name
(:mod:`spatial_dynamics.inputs`), calls :func:`~spatial_dynamics.rnea` and publishes

    tau = ID(model, q, qd, qdd)        (RBDA §5.3; N or N·m per joint)

Topics (relative, so they can be remapped):

==========================  ====================================  ============================
``desired_joint_states``    sensor_msgs/JointState, in            best effort, keep last 1
``desired_trajectory``      trajectory_msgs/JointTrajectory, in   best effort, keep last 1
``robot_description``       std_msgs/String, in (only when no     reliable, transient local, 1
                            description parameter is set)
``feedforward_efforts``     sensor_msgs/JointState, out           reliable
``effort_commands``         std_msgs/Float64MultiArray, out       reliable
``/diagnostics``            diagnostic_msgs/DiagnosticArray, out  ~1 Hz
==========================  ====================================  ============================

Parameters are listed in ``config/inverse_dynamics.yaml``. Every message is answered or
rejected on its own: a rejected message (reason counted in diagnostics) produces no output, and
nothing is published without fresh input, so a stale input means no output (never zeros).
"""

from __future__ import annotations

from array import array
from collections import Counter
from dataclasses import dataclass
import math
import os
import sys
import time
from typing import Optional, Sequence, Tuple

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
import numpy as np
from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor, SetParametersResult
import rclpy
from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks
from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
import rclpy.logging
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import (DurabilityPolicy, HistoryPolicy, QoSProfile, QoSReliabilityPolicy)
from rclpy.qos_overriding_options import QoSOverridingOptions
from sensor_msgs.msg import JointState
import spatial_dynamics as sd
from spatial_dynamics.inputs import InputError, joint_state_arrays, REASONS, trajectory_arrays
from std_msgs.msg import Float64MultiArray, String
from trajectory_msgs.msg import JointTrajectory

NODE_NAME = 'inverse_dynamics'
ACCELERATION_SOURCES = ('effort', 'none')
DEFAULT_GRAVITY = (0.0, 0.0, -9.81)
DEFAULT_INPUT_TIMEOUT = 0.5

# Rejection reasons the node adds to those of the input mapping.
NODE_REASONS = ('no_model', 'compute_error', 'non_finite_output')


def input_qos() -> QoSProfile:
    """Input QoS: best effort, keep last 1 (connects to reliable and best-effort publishers).

    A new object per call: QoS overrides (``qos_overrides.<topic>.subscription.*``) are
    written into the profile passed to ``create_subscription``, so it must not be shared.
    """
    return QoSProfile(reliability=QoSReliabilityPolicy.BEST_EFFORT,
                      history=HistoryPolicy.KEEP_LAST, depth=1)


def output_qos() -> QoSProfile:
    """Output QoS: reliable (what ros2_control's controllers subscribe with), keep last 10."""
    return QoSProfile(reliability=QoSReliabilityPolicy.RELIABLE,
                      history=HistoryPolicy.KEEP_LAST, depth=10)


DESCRIPTION_QOS = QoSProfile(reliability=QoSReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL,
                             history=HistoryPolicy.KEEP_LAST, depth=1)


def subscribe(node: Node, msg_type, topic: str, callback):
    """Subscribe with :func:`input_qos`, QoS overrides enabled, no QoS event handlers.

    rclpy adds default event handlers (incompatible QoS / type warnings) per endpoint to the
    wait set, which costs every spin of the executor 5-12 µs per endpoint (measured with
    rclpy 7.1.6: an idle spin_once with 3 subscriptions + 3 publishers took 219 µs with them,
    148 µs without). The inputs' best effort + volatile accepts every publisher anyway, and
    the other end of an incompatible pair still reports it with its own default handlers.
    """
    return node.create_subscription(
        msg_type, topic, callback, input_qos(),
        qos_overriding_options=QoSOverridingOptions.with_default_policies(),
        event_callbacks=SubscriptionEventCallbacks(use_default_callbacks=False))


def advertise(node: Node, msg_type, topic: str):
    """Create a publisher with :func:`output_qos`, QoS overrides, no QoS event handlers."""
    return node.create_publisher(
        msg_type, topic, output_qos(),
        qos_overriding_options=QoSOverridingOptions.with_default_policies(),
        event_callbacks=PublisherEventCallbacks(use_default_callbacks=False))


class ConfigError(ValueError):
    """A parameter value or robot description that cannot be used; the message says why."""


def read_description(path: str) -> str:
    """URDF text from ``path``; a ``.xacro`` file is expanded when ``xacro`` is importable."""
    if not os.path.isfile(path):
        raise ConfigError(f'robot_description_file {path!r}: no such file')
    if path.endswith('.xacro'):
        try:
            import xacro
        except ImportError:
            raise ConfigError(f'robot_description_file {path!r}: a .xacro file needs the '
                              'xacro module (pip install xacro, or apt ros-jazzy-xacro)')
        try:
            return xacro.process_file(path).toxml()
        except Exception as err:  # xacro raises many types; all mean "cannot expand"
            raise ConfigError(f'robot_description_file {path!r}: xacro failed: {err}')
    try:
        with open(path, encoding='utf-8') as f:
            return f.read()
    except OSError as err:
        raise ConfigError(f'robot_description_file {path!r}: {err.strerror}')


def parse_description(urdf: str, source: str) -> 'sd.Model':
    """Build the model from URDF text; ``source`` names where it came from in the error.

    One inverse-dynamics call at q = qd = qdd = 0 follows, before the model is used: it proves
    the model computes, and any one-time cost of the first call (imports, compilation, caches)
    is paid here, at load time, not by the first live message.
    """
    if not urdf.strip():
        raise ConfigError(f'{source}: empty robot description')
    try:
        model = sd.Model.from_urdf(urdf)
        zeros = np.zeros(len(model.joint_names))
        tau = sd.rnea(model, zeros, zeros, zeros)
    except Exception as err:  # a bad description must never take the node down
        raise ConfigError(f'{source}: {err}')
    if not np.isfinite(tau).all():
        raise ConfigError(f'{source}: the model gives non-finite torques at rest')
    return model


@dataclass(frozen=True)
class Output:
    """The loaded model with the output order: ``tau[index]`` is in the order of ``joints``."""

    model: 'sd.Model'
    source: str
    joints: Tuple[str, ...]
    index: np.ndarray

    @classmethod
    def build(cls, model: 'sd.Model', source: str,
              joints: Optional[Sequence[str]]) -> 'Output':
        """Check ``joints`` (empty or None = the model's order) against the model's joints."""
        model_joints = tuple(model.joint_names)
        joints = tuple(joints) if joints else model_joints
        unknown = [name for name in joints if name not in model_joints]
        if unknown:
            raise ConfigError(f'parameter joints: {unknown} not among the joints of robot '
                              f'{model.name!r} {list(model_joints)}')
        if len(set(joints)) != len(joints):
            raise ConfigError(f'parameter joints: names repeated in {list(joints)}')
        index = np.array([model_joints.index(name) for name in joints], dtype=np.intp)
        index.setflags(write=False)
        return cls(model, source, joints, index)


def check_gravity(value: Sequence[float]) -> Tuple[float, float, float]:
    """Gravity ``[gx, gy, gz]`` in m/s², base frame."""
    g = tuple(float(x) for x in value)
    if len(g) != 3 or not all(math.isfinite(x) for x in g):
        raise ConfigError(f'parameter gravity: need 3 finite values in m/s², got {list(value)}')
    return g


def check_acceleration_source(value: str) -> str:
    if value not in ACCELERATION_SOURCES:
        raise ConfigError(f'parameter acceleration_source: {value!r} is not one of '
                          f'{list(ACCELERATION_SOURCES)}')
    return value


def check_input_timeout(value: float) -> float:
    if not (math.isfinite(value) and value > 0.0):
        raise ConfigError(
            f'parameter input_timeout: need a positive number of seconds, got {value}')
    return float(value)


class Window:
    """Counts and compute times over one diagnostics period."""

    def __init__(self) -> None:
        self.start_ns = time.monotonic_ns()
        self.received = 0
        self.answered = 0
        self.compute_ns = 0
        self.compute_max_ns = 0
        self.delay_ns = 0
        self.delay_count = 0
        self.delay_max_ns = 0


class InverseDynamicsNode(Node):
    """Publishes tau = ID(q, qd, qdd) for every good desired state it receives."""

    def __init__(self, **kwargs) -> None:
        super().__init__(NODE_NAME, **kwargs)
        self._declare_parameters()
        self.output: Optional[Output] = None
        self.gravity = DEFAULT_GRAVITY
        self.acceleration_source = 'effort'
        self.input_timeout = DEFAULT_INPUT_TIMEOUT
        self.rejected: Counter = Counter({reason: 0 for reason in REASONS + NODE_REASONS})
        self.descriptions_rejected = 0
        self.last_description_error = ''
        self.answered = 0
        self.last_input_ns: Optional[int] = None
        self.window = Window()
        self._configure({name: self._value(name) for name in self._PARAMETERS})
        self.add_on_set_parameters_callback(self._on_set_parameters)

        self.commands_pub = advertise(self, Float64MultiArray, 'effort_commands')
        self.efforts_pub = advertise(self, JointState, 'feedforward_efforts')
        self.diagnostics_pub = self.create_publisher(
            DiagnosticArray, '/diagnostics', 10,
            event_callbacks=PublisherEventCallbacks(use_default_callbacks=False))
        self._commands = Float64MultiArray()
        self._efforts = JointState()
        subscribe(self, JointState, 'desired_joint_states', self._on_joint_state)
        subscribe(self, JointTrajectory, 'desired_trajectory', self._on_trajectory)
        self.create_timer(1.0, self._publish_diagnostics)
        if self.output is None:
            # rclpy's default QoS event handlers stay here: a volatile publisher of the
            # description never reaches this transient-local subscription, worth a warning.
            self.create_subscription(String, 'robot_description', self._on_description_topic,
                                     DESCRIPTION_QOS)
            self._warn_waiting()

    # -- parameters ------------------------------------------------------------------------

    _PARAMETERS = ('robot_description', 'robot_description_file', 'joints', 'gravity',
                   'acceleration_source', 'input_timeout')

    def _declare_parameters(self) -> None:
        def describe(text, **kwargs):
            return ParameterDescriptor(description=text, **kwargs)

        self.declare_parameter('robot_description', '', describe(
            'URDF XML of the robot. Takes precedence over robot_description_file and the '
            'robot_description topic. A new value is parsed completely and swapped in only if '
            'it parses; otherwise it is rejected with the reason and the old model stays.'))
        self.declare_parameter('robot_description_file', '', describe(
            'Path of a URDF (or .xacro, expanded when the xacro module is importable), used '
            'when robot_description is empty.'))
        self.declare_parameter('joints', Parameter.Type.STRING_ARRAY, describe(
            'Output joint order of effort_commands and feedforward_efforts: a subset of the '
            "model's movable, non-mimic joints. Unset or empty: all of them, in URDF order."))
        self.declare_parameter('gravity', list(DEFAULT_GRAVITY), describe(
            'Gravity [gx, gy, gz] in the base frame, m/s² (tilted or wall mounts). Live.'))
        self.declare_parameter('acceleration_source', 'effort', describe(
            'Where desired_joint_states carries qdd: "effort" (the effort array holds desired '
            'accelerations, rad/s² or m/s²; empty = zeros) or "none" (qdd = 0: gravity and '
            'Coriolis compensation, safe with measured /joint_states).',
            additional_constraints='one of: effort, none'))
        self.declare_parameter('input_timeout', DEFAULT_INPUT_TIMEOUT, describe(
            'Seconds without a good input after which diagnostics report ERROR (stale). The '
            'node publishes only in answer to input, so stale input means no output, never '
            'zeros.', floating_point_range=[FloatingPointRange(
                from_value=1e-3, to_value=3600.0, step=0.0)]))

    def _value(self, name: str):
        parameter = self.get_parameter_or(name, None)
        return None if parameter is None else parameter.value

    def _on_set_parameters(self, parameters: Sequence[Parameter]) -> SetParametersResult:
        changes = {p.name: p.value for p in parameters if p.name in self._PARAMETERS}
        if changes:
            try:
                self._configure(changes)
            except ConfigError as err:
                self.get_logger().warn(f'parameter change rejected: {err}')
                if {'robot_description', 'robot_description_file'} & changes.keys():
                    self._count_description_rejected(str(err))
                return SetParametersResult(successful=False, reason=str(err))
        return SetParametersResult(successful=True)

    def _configure(self, changes: dict) -> None:
        """Validate ``changes`` against the current state, then apply all of them at once."""
        output = self.output
        model = source = None
        if changes.get('robot_description'):
            model = parse_description(changes['robot_description'],
                                      'parameter robot_description')
            source = 'parameter robot_description'
        elif changes.get('robot_description_file'):
            path = changes['robot_description_file']
            model = parse_description(read_description(path), f'robot_description_file {path!r}')
            source = f'file {path}'
        elif output is not None and 'joints' in changes:
            model, source = output.model, output.source
        if model is not None:
            joints = changes['joints'] if 'joints' in changes else self._value('joints')
            output = Output.build(model, source, joints)
        gravity = check_gravity(changes.get('gravity', self.gravity))
        acceleration_source = check_acceleration_source(
            changes.get('acceleration_source', self.acceleration_source))
        input_timeout = check_input_timeout(changes.get('input_timeout', self.input_timeout))
        # Everything parsed: swap in.
        changed = output is not self.output
        self.output = output
        self.gravity = gravity
        self.acceleration_source = acceleration_source
        self.input_timeout = input_timeout
        if changed:
            self._log_model()

    def _on_description_topic(self, msg: String) -> None:
        try:
            model = parse_description(msg.data, 'topic robot_description')
            output = Output.build(model, 'topic robot_description', self._value('joints'))
        except ConfigError as err:
            self.get_logger().error(
                f'robot description rejected, keeping the current model: {err}')
            self._count_description_rejected(str(err))
            return
        self.output = output
        self._log_model()

    def _count_description_rejected(self, reason: str) -> None:
        self.descriptions_rejected += 1
        self.last_description_error = reason

    def _log_model(self) -> None:
        out = self.output
        self.get_logger().info(
            f'robot {out.model.name!r} from {out.source}: {len(out.model.joint_names)} DOF; '
            f'output joints {list(out.joints)}')

    def _warn_waiting(self) -> None:
        self.get_logger().warn(
            'no robot model: set parameter robot_description or robot_description_file, or '
            f'publish on {self.resolve_topic_name("robot_description")} '
            '(reliable, transient local); inputs are rejected until then',
            throttle_duration_sec=5.0)

    # -- hot path ---------------------------------------------------------------------------

    def _on_joint_state(self, msg: JointState) -> None:
        self._answer(msg, 'desired_joint_states', joint_state_arrays,
                     (msg.name, msg.position, msg.velocity,
                      msg.effort if self.acceleration_source == 'effort' else None))

    def _on_trajectory(self, msg: JointTrajectory) -> None:
        self._answer(msg, 'desired_trajectory', trajectory_arrays,
                     (msg.joint_names, msg.points))

    def _answer(self, msg, topic: str, to_arrays, fields: tuple) -> None:
        """Validate, compute and publish both outputs for one message, or reject it whole."""
        t0 = time.monotonic_ns()
        window = self.window
        window.received += 1
        output = self.output
        if output is None:
            self._reject(topic, 'no_model', 'no robot model loaded yet')
            return
        try:
            q, qd, qdd = to_arrays(output.model.joint_names, *fields)
        except InputError as err:
            self._reject(topic, err.reason, str(err))
            return
        try:
            tau = sd.rnea(output.model, q, qd, qdd, gravity=self.gravity)
        except Exception as err:  # never die on one message
            self._reject(topic, 'compute_error', f'rnea failed: {err!r}')
            return
        if not np.isfinite(tau).all():
            self._reject(topic, 'non_finite_output', 'torque is not finite (extreme input?)')
            return
        index = output.index
        tau_out = tau[index]
        t1 = time.monotonic_ns()

        # The two output messages are reused: publish() serialises them before it returns.
        commands = self._commands
        commands.data = array('d', tau_out.tobytes())
        self.commands_pub.publish(commands)
        efforts = self._efforts
        efforts.header = msg.header
        efforts.name = output.joints
        efforts.position = array('d', q[index].tobytes())
        efforts.velocity = array('d', qd[index].tobytes())
        efforts.effort = commands.data
        self.efforts_pub.publish(efforts)

        self.answered += 1
        self.last_input_ns = t0
        window.answered += 1
        compute = t1 - t0
        window.compute_ns += compute
        if compute > window.compute_max_ns:
            window.compute_max_ns = compute
        stamp = msg.header.stamp
        if stamp.sec or stamp.nanosec:
            delay = time.time_ns() - (stamp.sec * 1_000_000_000 + stamp.nanosec)
            window.delay_ns += delay
            window.delay_count += 1
            if delay > window.delay_max_ns:
                window.delay_max_ns = delay

    def _reject(self, topic: str, reason: str, text: str) -> None:
        self.rejected[reason] += 1
        self.get_logger().warn(f'{topic}: message rejected ({reason}): {text}',
                               throttle_duration_sec=1.0)

    # -- diagnostics ------------------------------------------------------------------------

    def _publish_diagnostics(self) -> None:
        now_ns = time.monotonic_ns()
        window, self.window = self.window, Window()
        period = max((now_ns - window.start_ns) * 1e-9, 1e-9)
        name = self.get_fully_qualified_name().lstrip('/')  # 'inverse_dynamics' in the root ns
        output = self.output

        model = DiagnosticStatus(name=f'{name}: robot model')
        if output is None:
            self._warn_waiting()
            model.level = DiagnosticStatus.ERROR
            model.message = 'waiting for robot_description'
            model.values = [KeyValue(key='descriptions rejected',
                                     value=str(self.descriptions_rejected)),
                            KeyValue(key='last rejection', value=self.last_description_error)]
        else:
            model.level = DiagnosticStatus.OK
            model.hardware_id = output.model.name
            model.message = (f'robot {output.model.name!r} loaded, '
                             f'{len(output.model.joint_names)} DOF')
            model.values = [
                KeyValue(key='robot name', value=output.model.name),
                KeyValue(key='dof', value=str(len(output.model.joint_names))),
                KeyValue(key='model joints', value=', '.join(output.model.joint_names)),
                KeyValue(key='output joints', value=', '.join(output.joints)),
                KeyValue(key='source', value=output.source),
                KeyValue(key='descriptions rejected', value=str(self.descriptions_rejected)),
                KeyValue(key='last rejection', value=self.last_description_error),
            ]

        age = None if self.last_input_ns is None else (now_ns - self.last_input_ns) * 1e-9
        stale = age is None or age > self.input_timeout
        rejected_now = window.received - window.answered
        status = DiagnosticStatus(name=f'{name}: feedforward', hardware_id=model.hardware_id)
        if output is None:
            status.level, status.message = DiagnosticStatus.ERROR, 'no robot model'
        elif age is None:
            status.level, status.message = DiagnosticStatus.WARN, 'no input received yet'
        elif stale:
            status.level = DiagnosticStatus.ERROR
            status.message = (f'input stale: no good input for {age:.2f} s '
                              f'(input_timeout {self.input_timeout} s); not publishing')
        elif rejected_now:
            status.level = DiagnosticStatus.WARN
            status.message = f'{window.answered / period:.1f} Hz, {rejected_now} rejected'
        else:
            status.level = DiagnosticStatus.OK
            status.message = f'{window.answered / period:.1f} Hz'

        def us(ns):
            return f'{ns * 1e-3:.1f}'

        values = [
            ('input rate [Hz]', f'{window.received / period:.1f}'),
            ('output rate [Hz]', f'{window.answered / period:.1f}'),
            ('compute time mean [us]', us(window.compute_ns / window.answered)
             if window.answered else ''),
            ('compute time max [us]', us(window.compute_max_ns) if window.answered else ''),
            ('input delay mean [ms]', f'{window.delay_ns / window.delay_count * 1e-6:.3f}'
             if window.delay_count else ''),
            ('input delay max [ms]', f'{window.delay_max_ns * 1e-6:.3f}'
             if window.delay_count else ''),
            ('last input age [s]', '' if age is None else f'{age:.3f}'),
            ('input timeout [s]', str(self.input_timeout)),
            ('stale', str(stale)),
            ('answered', str(self.answered)),
            ('rejected', str(sum(self.rejected.values()))),
        ]
        values += [(f'rejected {reason}', str(count)) for reason, count in self.rejected.items()]
        values += [('gravity [m/s^2]', str(list(self.gravity))),
                   ('acceleration source', self.acceleration_source)]
        status.values = [KeyValue(key=k, value=v) for k, v in values]

        diagnostics = DiagnosticArray(status=[model, status])
        diagnostics.header.stamp = self.get_clock().now().to_msg()
        self.diagnostics_pub.publish(diagnostics)


def main(args: Optional[Sequence[str]] = None) -> int:
    """Run the node until SIGINT/SIGTERM; 0 on a clean exit, 1 if the start-up config is bad."""
    rclpy.init(args=args)
    node = None
    status = 0
    try:
        node = InverseDynamicsNode()
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except (ConfigError, InvalidParameterTypeException, InvalidParameterValueException) as err:
        # e.g. -p gravity:=[0,0,-10] (integers) or -p input_timeout:=0.0 (out of range)
        rclpy.logging.get_logger(NODE_NAME).fatal(f'cannot start: {err}')
        status = 1
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return status


if __name__ == '__main__':
    sys.exit(main())
