# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""ROS 2 node ``inverse_dynamics``: desired joint states in, feed-forward efforts out.

The only module that imports rclpy: a thin shell that declares and validates parameters, builds
the :class:`~spatial_dynamics.Model`, maps messages to ``(q, qd, qdd)`` by joint name
(:mod:`spatial_dynamics.inputs`), calls :func:`~spatial_dynamics.rnea` and publishes

    tau = ID(model, q, qd, qdd, f_ext) + armature·qdd + friction(qd)   (RBDA §5.3)

clamped to the URDF effort limits when asked (N or N·m per joint). Every extra term is off by
default (:mod:`spatial_dynamics.terms`).

Topics (relative, so they can be remapped):

==========================  ====================================  ============================
``desired_joint_states``    sensor_msgs/JointState, in            best effort, keep last 1
``desired_trajectory``      trajectory_msgs/JointTrajectory, in   best effort, keep last 1
``external_wrenches``       geometry_msgs/WrenchStamped, in       best effort, keep last 10
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
from typing import Callable, Optional, Sequence, Tuple

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import WrenchStamped
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
from spatial_dynamics import backends
from spatial_dynamics.inputs import InputError, joint_state_arrays, REASONS, trajectory_arrays
from std_msgs.msg import Float64MultiArray, String
from trajectory_msgs.msg import JointTrajectory

NODE_NAME = 'inverse_dynamics'
ACCELERATION_SOURCES = ('effort', 'none')
DEFAULT_GRAVITY = (0.0, 0.0, -9.81)
DEFAULT_INPUT_TIMEOUT = 0.5
FRICTION_MODELS = ('none', 'urdf')
DEFAULT_FRICTION_THRESHOLD = 0.01   # rad/s or m/s
DEFAULT_WRENCH_TIMEOUT = 0.5        # s
WRENCH_DEPTH = 10                   # several links may publish in one burst

# Rejection reasons the node adds to those of the input mapping.
NODE_REASONS = ('no_model', 'compute_error', 'non_finite_output')
# Rejection reasons of external_wrenches messages.
WRENCH_REASONS = ('no_model', 'unknown_link', 'non_finite')


def input_qos(depth: int = 1) -> QoSProfile:
    """Input QoS: best effort, keep last ``depth`` (connects to reliable and best-effort pubs).

    A new object per call: QoS overrides (``qos_overrides.<topic>.subscription.*``) are
    written into the profile passed to ``create_subscription``, so it must not be shared.
    """
    return QoSProfile(reliability=QoSReliabilityPolicy.BEST_EFFORT,
                      history=HistoryPolicy.KEEP_LAST, depth=depth)


def output_qos() -> QoSProfile:
    """Output QoS: reliable (what ros2_control's controllers subscribe with), keep last 10."""
    return QoSProfile(reliability=QoSReliabilityPolicy.RELIABLE,
                      history=HistoryPolicy.KEEP_LAST, depth=10)


DESCRIPTION_QOS = QoSProfile(reliability=QoSReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL,
                             history=HistoryPolicy.KEEP_LAST, depth=1)


def subscribe(node: Node, msg_type, topic: str, callback, depth: int = 1):
    """Subscribe with :func:`input_qos`, QoS overrides enabled, no QoS event handlers.

    rclpy adds default event handlers (incompatible QoS / type warnings) per endpoint to the
    wait set, which costs every spin of the executor 5-12 µs per endpoint (measured with
    rclpy 7.1.6: an idle spin_once with 3 subscriptions + 3 publishers took 219 µs with them,
    148 µs without). The inputs' best effort + volatile accepts every publisher anyway, and
    the other end of an incompatible pair still reports it with its own default handlers.
    """
    return node.create_subscription(
        msg_type, topic, callback, input_qos(depth),
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


def parse_description(urdf: str, source: str, joints: Optional[Sequence[str]] = None,
                      locked: Optional[dict] = None) -> 'sd.Model':
    """Build the (reduced) model from URDF text; ``source`` names where it came from.

    With ``joints``, model reduction (:meth:`~spatial_dynamics.Model.from_urdf`): the other
    joints are locked at ``locked[name]`` (default 0), lumped, and branches that cannot move
    a kept joint's torque are pruned; ``model.joint_names == joints``.

    One inverse-dynamics call at q = qd = qdd = 0 follows, before the model is used: it proves
    the model computes, and any one-time cost of the first call (imports, compilation, caches)
    is paid here, at load time, not by the first live message.
    """
    if not urdf.strip():
        raise ConfigError(f'{source}: empty robot description')
    where = source
    if joints:
        where = f'{source} reduced to joints {list(joints)}'
        if locked:
            where += f' (locked {locked})'
    try:
        model = sd.Model.from_urdf(urdf, joints=list(joints) if joints else None,
                                   locked=locked or None)
        zeros = np.zeros(len(model.joint_names))
        tau = sd.rnea(model, zeros, zeros, zeros)
    except Exception as err:  # a bad description must never take the node down
        raise ConfigError(f'{where}: {err}')
    if not np.isfinite(tau).all():
        raise ConfigError(f'{source}: the model gives non-finite torques at rest')
    return model


@dataclass(frozen=True)
class Payload:
    """A rigid payload on ``link`` (``''`` = none): kg, m (link frame), kg m² about the com."""

    link: str = ''
    mass: float = 0.0
    com: Tuple[float, ...] = (0.0, 0.0, 0.0)
    inertia: Tuple[float, ...] = (0.0,) * 6

    def __str__(self) -> str:
        if not self.link:
            return 'none'
        return (f'{self.mass:g} kg on {self.link!r}, com {list(self.com)} m, inertia '
                f'{list(self.inertia)} kg m^2')

    def apply(self, model: 'sd.Model') -> 'sd.Model':
        """Return ``model`` with the payload (:func:`~spatial_dynamics.with_payload`)."""
        if not self.link:
            return model
        try:
            return sd.with_payload(model, self.link, self.mass, self.com, self.inertia)
        except ValueError as err:
            raise ConfigError(f'parameter payload.*: {err}')


def check_payload(link, mass, com, inertia) -> Payload:
    """Shape and finiteness of the ``payload.*`` parameters (the physics: :meth:`apply`)."""
    mass = float(mass)
    if not math.isfinite(mass) or mass < 0.0:
        raise ConfigError(f'parameter payload.mass: need a finite mass >= 0 kg, got {mass}')
    com = tuple(float(x) for x in com)
    if len(com) != 3 or not all(math.isfinite(x) for x in com):
        raise ConfigError(f'parameter payload.com: need 3 finite values (m, link frame), '
                          f'got {list(com)}')
    inertia = tuple(float(x) for x in inertia)
    if len(inertia) != 6 or not all(math.isfinite(x) for x in inertia):
        raise ConfigError('parameter payload.inertia: need 6 finite values (ixx ixy ixz iyy '
                          f'iyz izz, kg m^2 about the com), got {list(inertia)}')
    return Payload(str(link), mass, com, inertia)


def check_locked(joints: Optional[Sequence[str]], positions: Optional[Sequence[float]]
                 ) -> dict:
    """``locked_joints`` + ``locked_positions`` (empty = all 0) as {name: value}."""
    joints = list(joints or [])
    positions = list(positions or [])
    if positions and len(positions) != len(joints):
        raise ConfigError(f'parameter locked_positions: {len(positions)} values for '
                          f'{len(joints)} locked_joints {joints} (need the same number, or '
                          'none for all 0)')
    if len(set(joints)) != len(joints):
        raise ConfigError(f'parameter locked_joints: names repeated in {joints}')
    values = positions or [0.0] * len(joints)
    if not all(math.isfinite(v) for v in values):
        raise ConfigError(f'parameter locked_positions: not finite: {values}')
    return dict(zip(joints, (float(v) for v in values)))


@dataclass(frozen=True)
class Output:
    """Everything an answer needs, swapped as one object between two messages.

    ``base`` is the (reduced) model of the URDF, ``model`` the same with the payload; ``tau``
    is in the order of ``joints`` (= ``model.joint_names``). ``armature`` is ``None`` or (n,),
    ``friction_threshold`` is ``None`` (friction_model none) or the smooth-sign velocity.
    """

    urdf: str
    source: str
    base: 'sd.Model'
    model: 'sd.Model'
    joints: Tuple[str, ...]
    joints_param: Tuple[str, ...]
    locked: Tuple[Tuple[str, float], ...]
    payload: Payload
    armature: Optional[np.ndarray] = None
    friction_threshold: Optional[float] = None
    clamp: bool = False


def check_armature(model: 'sd.Model', values: Optional[Sequence[float]]
                   ) -> Optional[np.ndarray]:
    """``armature`` (kg m² or kg): empty = none, else one value >= 0 per model joint."""
    if not values:
        return None
    try:
        armature = sd.per_joint(model, 'parameter armature', list(values), nonnegative=True)
    except ValueError as err:
        raise ConfigError(f'{err} (order of the joints parameter, or the URDF order '
                          'when it is unset)')
    armature.setflags(write=False)
    return None if not armature.any() else armature


def check_gravity(value: Sequence[float]) -> Tuple[float, float, float]:
    """Gravity ``[gx, gy, gz]`` in m/s², base frame."""
    g = tuple(float(x) for x in value)
    if len(g) != 3 or not all(math.isfinite(x) for x in g):
        raise ConfigError(f'parameter gravity: need 3 finite values in m/s², got {list(value)}')
    return g


def check_choice(name: str, value: str, choices: Sequence[str]) -> str:
    """Return ``value`` if it is one of ``choices``."""
    if value not in choices:
        raise ConfigError(f'parameter {name}: {value!r} is not one of {list(choices)}')
    return value


def check_acceleration_source(value: str) -> str:
    """Return a valid ``acceleration_source``."""
    return check_choice('acceleration_source', value, ACCELERATION_SOURCES)


def check_positive(name: str, value: float, unit: str = 'seconds') -> float:
    """Return ``value`` if it is a finite number > 0."""
    if not (math.isfinite(value) and value > 0.0):
        raise ConfigError(f'parameter {name}: need a positive number of {unit}, got {value}')
    return float(value)


def check_input_timeout(value: float) -> float:
    """Return a valid ``input_timeout``."""
    return check_positive('input_timeout', value)


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
        self.wrench_timeout_ns = int(DEFAULT_WRENCH_TIMEOUT * 1e9)
        self.params: dict = {}   # the last accepted value of every parameter in _PARAMETERS
        self.backend = ''
        self.rejected: Counter = Counter({reason: 0 for reason in REASONS + NODE_REASONS})
        self.wrenches: dict = {}  # link -> (wrench [n; f] in the link frame, expiry ns)
        self.wrenches_received = 0
        self.wrenches_rejected: Counter = Counter({reason: 0 for reason in WRENCH_REASONS})
        self.saturated = 0                  # answers with at least one clamped joint
        self.saturated_joints: Counter = Counter()
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
        subscribe(self, WrenchStamped, 'external_wrenches', self._on_wrench, WRENCH_DEPTH)
        self.create_timer(1.0, self._publish_diagnostics)
        if self.output is None:
            # rclpy's default QoS event handlers stay here: a volatile publisher of the
            # description never reaches this transient-local subscription, worth a warning.
            self.create_subscription(String, 'robot_description', self._on_description_topic,
                                     DESCRIPTION_QOS)
            self._warn_waiting()

    # -- parameters ------------------------------------------------------------------------

    _PARAMETERS = ('robot_description', 'robot_description_file', 'joints', 'locked_joints',
                   'locked_positions', 'gravity', 'acceleration_source', 'input_timeout',
                   'payload.link', 'payload.mass', 'payload.com', 'payload.inertia',
                   'armature', 'friction_model', 'friction_velocity_threshold',
                   'clamp_to_effort_limits', 'external_wrench_timeout')
    _MODEL_PARAMETERS = ('joints', 'locked_joints', 'locked_positions')
    _PAYLOAD_PARAMETERS = ('payload.link', 'payload.mass', 'payload.com', 'payload.inertia')

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
            'Joints the model keeps, in the output order of effort_commands and '
            "feedforward_efforts: a subset of the URDF's movable, non-mimic joints. The "
            'others are locked (locked_joints/locked_positions, default 0) and lumped, and '
            'branches that cannot affect the kept joints are pruned (model reduction); inputs '
            'need only the kept joints. Unset or empty: all joints, in URDF order.'))
        self.declare_parameter('locked_joints', Parameter.Type.STRING_ARRAY, describe(
            'Joints locked at a non-zero position when joints is set (others lock at 0); '
            'values in locked_positions, same order.'))
        self.declare_parameter('locked_positions', Parameter.Type.DOUBLE_ARRAY, describe(
            'Positions (rad or m) of locked_joints, same length; unset or empty = all 0.'))
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
        self.declare_parameter('payload.link', '', describe(
            "Link carrying a rigid payload (tool, grasped object); '' = no payload. Live: "
            'applied from the next message. A new robot_description lacking this link is '
            'rejected.'))
        self.declare_parameter('payload.mass', 0.0, describe(
            'Payload mass, kg (>= 0).'))
        self.declare_parameter('payload.com', [0.0, 0.0, 0.0], describe(
            "Payload centre of mass [x, y, z] in payload.link's frame, m."))
        self.declare_parameter('payload.inertia', [0.0] * 6, describe(
            'Payload inertia [ixx, ixy, ixz, iyy, iyz, izz] about its centre of mass, axes of '
            "payload.link's frame, kg m^2 (positive semi-definite, triangle inequality)."))
        self.declare_parameter('armature', Parameter.Type.DOUBLE_ARRAY, describe(
            'Rotor inertia reflected through the gear (kg m^2 or kg), one value >= 0 per '
            'model joint in the order of the joints parameter (URDF order when unset): '
            'tau += armature * qdd. Unset or empty: none.'))
        self.declare_parameter('friction_model', 'none', describe(
            '"none", or "urdf": tau += damping * qd + friction * tanh(qd / '
            "friction_velocity_threshold) from each joint's URDF <dynamics>.",
            additional_constraints='one of: none, urdf'))
        self.declare_parameter('friction_velocity_threshold', DEFAULT_FRICTION_THRESHOLD,
                               describe('Velocity (rad/s or m/s) at which the smooth Coulomb '
                                        'sign reaches tanh(1) = 76 %.',
                                        floating_point_range=[FloatingPointRange(
                                            from_value=1e-9, to_value=1e3, step=0.0)]))
        self.declare_parameter('clamp_to_effort_limits', False, describe(
            'Clamp tau to the URDF <limit effort> (joints without a positive limit are left '
            'alone); a throttled warning names the saturated joints.'))
        self.declare_parameter('external_wrench_timeout', DEFAULT_WRENCH_TIMEOUT, describe(
            'Seconds after its receipt that an external_wrenches message stops applying.',
            floating_point_range=[FloatingPointRange(from_value=1e-3, to_value=3600.0,
                                                     step=0.0)]))

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
        params = {**self.params, **changes}
        urdf = source = None
        if changes.get('robot_description'):
            urdf, source = changes['robot_description'], 'parameter robot_description'
        elif changes.get('robot_description_file'):
            path = changes['robot_description_file']
            urdf, source = read_description(path), f'file {path}'
        output = self.output
        if urdf is not None or output is not None:
            output = self._build_output(params, urdf, source)
        else:  # no model yet: check what needs none; the rest is checked when one arrives
            check_payload(params['payload.link'], params['payload.mass'],
                          params['payload.com'], params['payload.inertia'])
            check_locked(params['locked_joints'], params['locked_positions'])
            check_choice('friction_model', params['friction_model'], FRICTION_MODELS)
            check_positive('friction_velocity_threshold',
                           params['friction_velocity_threshold'], 'rad/s or m/s')
        gravity = check_gravity(params['gravity'])
        acceleration_source = check_acceleration_source(params['acceleration_source'])
        input_timeout = check_input_timeout(params['input_timeout'])
        wrench_timeout = check_positive('external_wrench_timeout',
                                        params['external_wrench_timeout'])
        # Everything parsed: swap in.
        model_changed = output is not None and (
            self.output is None or output.base is not self.output.base)
        self.output = output
        self.params = params
        self.gravity = gravity
        self.acceleration_source = acceleration_source
        self.input_timeout = input_timeout
        self.wrench_timeout_ns = int(wrench_timeout * 1e9)
        if model_changed:
            self._log_model()
        elif output is not None and set(self._PAYLOAD_PARAMETERS) & changes.keys():
            self.get_logger().info(f'payload: {output.payload}')

    def _build_output(self, params: dict, urdf: Optional[str] = None,
                      source: Optional[str] = None) -> Output:
        """Build the :class:`Output` for ``params``; the URDF is re-parsed only when needed.

        ``urdf`` None keeps the current description. Raises :class:`ConfigError`.
        """
        current = self.output
        if urdf is None:
            urdf, source = current.urdf, current.source
        # the four payload parameters are checked first: they need no model
        payload = check_payload(params['payload.link'], params['payload.mass'],
                                params['payload.com'], params['payload.inertia'])
        locked = check_locked(params['locked_joints'], params['locked_positions'])
        joints = tuple(params['joints'] or ())
        if (current is not None and urdf is current.urdf and joints == current.joints_param
                and tuple(locked.items()) == current.locked):
            base = current.base
        else:
            if locked and not joints:
                raise ConfigError(f'parameter locked_joints: {list(locked)} lock joints only '
                                  'when the joints parameter lists the joints to keep')
            base = parse_description(urdf, source, joints, locked)
        if payload.link and payload.link not in base.frames:
            raise ConfigError(
                f'parameter payload.link: {payload.link!r} is not a link of robot '
                f'{base.name!r} ({source}); set payload.link to an existing link or \'\' '
                'first, or together with the new description')
        model = payload.apply(base)
        friction_model = check_choice('friction_model', params['friction_model'],
                                      FRICTION_MODELS)
        threshold = check_positive('friction_velocity_threshold',
                                   params['friction_velocity_threshold'], 'rad/s or m/s')
        return Output(
            urdf=urdf, source=source, base=base, model=model, joints=tuple(base.joint_names),
            joints_param=joints, locked=tuple(locked.items()), payload=payload,
            armature=check_armature(base, params['armature']),
            friction_threshold=threshold if friction_model == 'urdf' else None,
            clamp=bool(params['clamp_to_effort_limits']))

    def _on_description_topic(self, msg: String) -> None:
        try:
            output = self._build_output(self.params, msg.data, 'topic robot_description')
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
        """Warm the backend up for the new model and log what was loaded."""
        out = self.output
        self.backend = backends.warmup(out.model)
        self.get_logger().info(
            f'robot {out.model.name!r} from {out.source}: {len(out.model.joint_names)} DOF; '
            f'output joints {list(out.joints)}')
        self.get_logger().info(f'model: {out.base.summary()}; backend: {self.backend}; '
                               f'payload: {out.payload}')

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
            f_ext = self._active_wrenches(output, t0) if self.wrenches else None
            tau = sd.rnea(output.model, q, qd, qdd, gravity=self.gravity, f_ext=f_ext)
            if output.armature is not None:
                tau += output.armature * qdd
            if output.friction_threshold is not None:
                tau += sd.friction_torque(output.model, qd, output.friction_threshold)
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

        # The two output messages are reused: publish() serialises them before it returns.
        commands = self._commands
        commands.data = array('d', tau.tobytes())
        self.commands_pub.publish(commands)
        efforts = self._efforts
        efforts.header = msg.header
        efforts.name = output.joints
        efforts.position = array('d', q.tobytes())
        efforts.velocity = array('d', qd.tobytes())
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

    def _count_saturated(self, output: Output, tau: np.ndarray, saturated: np.ndarray) -> None:
        names = [output.joints[i] for i in np.flatnonzero(saturated)]
        self.saturated += 1
        self.saturated_joints.update(names)
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
        self.wrenches_received += 1
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
            bad = [name for name, ok in zip(('torque.x', 'torque.y', 'torque.z', 'force.x',
                                             'force.y', 'force.z'), np.isfinite(wrench))
                   if not ok]
            self._reject_wrench('non_finite', f'on {link!r}: wrench.{", wrench.".join(bad)} '
                                'not finite')
            return
        if not wrench.any():
            self.wrenches.pop(link, None)
            return
        self.wrenches[link] = (wrench, time.monotonic_ns() + self.wrench_timeout_ns)

    def _reject_wrench(self, reason: str, text: str) -> None:
        self.wrenches_rejected[reason] += 1
        self.get_logger().warn(f'external_wrenches: message rejected ({reason}): {text}',
                               throttle_duration_sec=1.0)

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
                KeyValue(key='summary', value=output.base.summary()),
                KeyValue(key='backend', value=self.backend),
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
        if output is not None:
            values += [
                ('payload', str(output.payload)),
                ('armature', 'none' if output.armature is None
                 else str(output.armature.tolist())),
                ('friction model', 'none' if output.friction_threshold is None
                 else f'urdf (threshold {output.friction_threshold:g})'),
                ('clamp to effort limits', str(output.clamp)),
            ]
        values += [
            ('saturated', str(self.saturated)),
            ('saturated joints', ', '.join(f'{name}: {count}' for name, count
                                           in sorted(self.saturated_joints.items()))),
            ('external wrenches active', ', '.join(sorted(
                link for link, (_, expiry) in self.wrenches.items() if expiry >= now_ns))),
            ('external wrenches received', str(self.wrenches_received)),
            ('external wrenches rejected', str(sum(self.wrenches_rejected.values()))),
        ]
        values += [(f'external wrenches rejected {reason}', str(count))
                   for reason, count in self.wrenches_rejected.items()]
        status.values = [KeyValue(key=k, value=v) for k, v in values]

        diagnostics = DiagnosticArray(status=[model, status])
        diagnostics.header.stamp = self.get_clock().now().to_msg()
        self.diagnostics_pub.publish(diagnostics)


def spin(make_node: Callable[[], Node], args: Optional[Sequence[str]] = None,
         name: str = NODE_NAME) -> int:
    """Make a node and spin it until SIGINT/SIGTERM; 0 on a clean exit, 1 on a bad start-up.

    The node's and the latency baseline's (``relay.py``) process around them, one routine.
    """
    rclpy.init(args=args)
    node = None
    status = 0
    try:
        node = make_node()
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except (ConfigError, InvalidParameterTypeException, InvalidParameterValueException) as err:
        # e.g. -p gravity:=[0,0,-10] (integers) or -p input_timeout:=0.0 (out of range)
        rclpy.logging.get_logger(name).fatal(f'cannot start: {err}')
        status = 1
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return status


def main(args: Optional[Sequence[str]] = None) -> int:
    """Run the node until SIGINT/SIGTERM; 0 on a clean exit, 1 if the start-up config is bad."""
    return spin(InverseDynamicsNode, args)


if __name__ == '__main__':
    sys.exit(main())
