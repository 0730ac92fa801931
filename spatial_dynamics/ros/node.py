# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""ROS 2 node ``inverse_dynamics``: desired joint states in, feed-forward efforts out.

The only module that imports rclpy: a thin shell that declares and validates parameters, builds
the :class:`~spatial_dynamics.Model`, maps messages to ``(q, qd, qdd)`` by joint name
(:mod:`spatial_dynamics.ros.inputs`), calls :func:`~spatial_dynamics.rnea` and publishes

    tau = ID(model, q, qd, qdd, f_ext) + armature·qdd + friction(qd)   (RBDA §5.3)

clamped to the URDF effort limits when asked (N or N·m per joint). Every extra term is off by
default (:mod:`spatial_dynamics.terms`).

Topics (relative, so they can be remapped):

==========================  ====================================  ============================
``desired_joint_states``    sensor_msgs/JointState, in            best effort, keep last 1
``desired_trajectory``      trajectory_msgs/JointTrajectory, in   best effort, keep last 1
``external_wrenches``       geometry_msgs/WrenchStamped, in       best effort, keep last 10
``robot_description``       std_msgs/String, in (subscribed only  reliable, transient local, 1
                            while no description parameter is
                            set; parsed off the answering path)
``feedforward_efforts``     sensor_msgs/JointState, out           reliable
``effort_commands``         std_msgs/Float64MultiArray, out       reliable
``/diagnostics``            diagnostic_msgs/DiagnosticArray, out  ~1 Hz
==========================  ====================================  ============================

Parameters are listed in ``config/inverse_dynamics.yaml``. Every message is answered or
rejected on its own: a rejected message (reason counted in diagnostics) produces no output, and
nothing is published without fresh input, so a stale input means no output (never zeros).

The robot description comes from, in this order of precedence: the ``robot_description``
parameter (URDF XML), the ``robot_description_file`` parameter (a path: a regular UTF-8 file of
at most :data:`MAX_DESCRIPTION_BYTES`), the ``robot_description`` topic (URDF XML). A
description is XML text and never opened as a path. A new one is parsed completely and swapped
in between two messages (one reference assignment) only if it loads; otherwise the old model
stays. Descriptions from the topic are parsed in a worker thread, so answers keep coming while a
large one parses; parameter changes are validated in the parameter service's callback (its
answer says whether the change was accepted), so a description set by parameter is parsed
there, synchronously.
"""

from __future__ import annotations

from array import array
from collections import Counter
from dataclasses import dataclass
import math
import os
import signal
import stat
import sys
import threading
import time
from typing import Callable, List, Optional, Sequence, Tuple
import warnings

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
from spatial_dynamics.ros.inputs import InputError, joint_state_arrays, REASONS, trajectory_arrays
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

# Bounds beyond which a value cannot be physical: refused with the bound named, instead of
# being accepted and then making every answer non-finite.
MAX_DESCRIPTION_BYTES = 32 * 1024 * 1024   # robot_description_file (the largest URDF of
#                                            example-robot-data is < 1 MiB)
MAX_GRAVITY = 1e3                   # m/s², norm of `gravity` (100 g)
MAX_ARMATURE = 1e6                  # kg m² (or kg), per joint
MAX_PAYLOAD_MASS = 1e6              # kg
MAX_PAYLOAD_COM = 1e3               # m, per component
MAX_PAYLOAD_INERTIA = 1e6           # kg m², per component
MAX_LOCKED_POSITION = 1e4           # rad or m
URDF_WARNINGS_LISTED = 5            # URDF warnings listed one by one in /diagnostics

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


_FILE_KINDS = ((stat.S_ISDIR, 'directory'), (stat.S_ISFIFO, 'named pipe'),
               (stat.S_ISCHR, 'character device'), (stat.S_ISBLK, 'block device'),
               (stat.S_ISSOCK, 'socket'))


def _check_regular_file(where: str, info: os.stat_result) -> None:
    """Refuse anything but a regular file of at most :data:`MAX_DESCRIPTION_BYTES`."""
    if not stat.S_ISREG(info.st_mode):
        kind = next((name for test, name in _FILE_KINDS if test(info.st_mode)), 'special file')
        raise ConfigError(f'{where}: not a regular file (a {kind})')
    if info.st_size > MAX_DESCRIPTION_BYTES:
        raise ConfigError(f'{where}: {info.st_size} bytes, more than the limit of '
                          f'{MAX_DESCRIPTION_BYTES >> 20} MiB for a robot description')


def read_description(path: str) -> str:
    """URDF text of the file ``path``; a ``.xacro`` file is expanded when ``xacro`` is importable.

    Only a regular file (symbolic links followed) of at most :data:`MAX_DESCRIPTION_BYTES`,
    UTF-8 (a byte order mark is dropped). Nothing else is opened: a named pipe, a device or a
    directory is refused after ``stat``, and the file is opened non-blocking and checked again
    (the path may have changed in between), so reading never blocks or runs away.
    """
    where = f'robot_description_file {path!r}'
    try:
        _check_regular_file(where, os.stat(path))
        if path.endswith('.xacro'):
            return _expand_xacro(where, path)
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
        with open(fd, 'rb') as f:
            _check_regular_file(where, os.fstat(f.fileno()))
            data = f.read(MAX_DESCRIPTION_BYTES + 1)
    except FileNotFoundError:
        raise ConfigError(f'{where}: no such file') from None
    except OSError as err:
        raise ConfigError(f'{where}: {err.strerror or err}') from None
    if len(data) > MAX_DESCRIPTION_BYTES:   # it grew after the check
        raise ConfigError(f'{where}: more than the limit of {MAX_DESCRIPTION_BYTES >> 20} MiB '
                          'for a robot description')
    try:
        return data.decode('utf-8-sig')
    except UnicodeDecodeError as err:
        raise ConfigError(f'{where}: not UTF-8 text (byte 0x{data[err.start]:02x} at offset '
                          f'{err.start}); a URDF file must be UTF-8') from None


def _expand_xacro(where: str, path: str) -> str:
    try:
        import xacro
    except ImportError:
        raise ConfigError(f'{where}: a .xacro file needs the xacro module (pip install xacro, '
                          'or apt ros-jazzy-xacro)') from None
    try:
        text = xacro.process_file(path).toxml()
    except Exception as err:  # xacro raises many types; all mean "cannot expand"
        raise ConfigError(f'{where}: xacro failed: {err}') from None
    if len(text) > MAX_DESCRIPTION_BYTES:
        raise ConfigError(f'{where}: expands to more than the limit of '
                          f'{MAX_DESCRIPTION_BYTES >> 20} MiB for a robot description')
    return text


def parse_description(urdf: str, source: str, joints: Optional[Sequence[str]] = None,
                      locked: Optional[dict] = None, strict: bool = False) -> 'sd.Model':
    """Build the (reduced) model from URDF text; ``source`` names where it came from.

    ``urdf`` is XML text, never a path (a path goes in ``robot_description_file``): it is
    handed to the parser as bytes, which :meth:`~spatial_dynamics.Model.from_urdf` never
    opens. With ``joints``, model reduction (:meth:`~spatial_dynamics.Model.from_urdf`): the
    other joints are locked at ``locked[name]`` (default 0), lumped, and branches that cannot
    move a kept joint's torque are pruned; ``model.joint_names == joints``. ``strict``: a
    physically inconsistent but computable description (a :class:`~spatial_dynamics.URDFWarning`)
    is refused; otherwise it loads and its warnings are in ``model.warnings``.

    One inverse-dynamics call at q = qd = qdd = 0 follows, before the model is used: it proves
    the model computes, and any one-time cost of the first call (imports, compilation, caches)
    is paid here, at load time, not by the first live message.
    """
    text = urdf.lstrip('\ufeff \t\r\n')
    if not text:
        raise ConfigError(f'{source}: empty robot description')
    if not text.startswith('<'):
        raise ConfigError(f'{source}: not URDF XML (it starts with {text[:200]!r}): a robot '
                          'description is XML text, never a path; give a file in the '
                          'robot_description_file parameter')
    where = source
    if joints:
        where = f'{source} reduced to joints {list(joints)}'
        if locked:
            where += f' (locked {locked})'
    try:
        model = sd.Model.from_urdf(text.encode('utf-8'), joints=list(joints) if joints else None,
                                   locked=locked or None, strict=strict)
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


def _within(values: Sequence[float], bound: float) -> bool:
    return all(math.isfinite(x) and abs(x) <= bound for x in values)


def check_payload(link, mass, com, inertia) -> Payload:
    """Shape, finiteness and bounds of the ``payload.*`` parameters (the physics: :meth:`apply`).

    Bounds (what no payload can exceed): :data:`MAX_PAYLOAD_MASS`, :data:`MAX_PAYLOAD_COM` per
    com component, :data:`MAX_PAYLOAD_INERTIA` per inertia component.
    """
    mass = float(mass)
    if not (math.isfinite(mass) and 0.0 <= mass <= MAX_PAYLOAD_MASS):
        raise ConfigError(f'parameter payload.mass: need a mass from 0 to '
                          f'{MAX_PAYLOAD_MASS:g} kg, got {mass}')
    com = tuple(float(x) for x in com)
    if len(com) != 3 or not _within(com, MAX_PAYLOAD_COM):
        raise ConfigError(f'parameter payload.com: need 3 finite values within '
                          f'±{MAX_PAYLOAD_COM:g} m (link frame), got {list(com)}')
    inertia = tuple(float(x) for x in inertia)
    if len(inertia) != 6 or not _within(inertia, MAX_PAYLOAD_INERTIA):
        raise ConfigError('parameter payload.inertia: need 6 finite values (ixx ixy ixz iyy '
                          f'iyz izz, kg m^2 about the com) within ±{MAX_PAYLOAD_INERTIA:g} '
                          f'kg m^2, got {list(inertia)}')
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
    if not _within(values, MAX_LOCKED_POSITION):
        raise ConfigError(f'parameter locked_positions: need finite values within '
                          f'±{MAX_LOCKED_POSITION:g} rad or m, got {values}')
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
    backend: str = ''


def check_armature(model: 'sd.Model', values: Optional[Sequence[float]]
                   ) -> Optional[np.ndarray]:
    """``armature`` (kg m² or kg): empty = none, else one value in [0, MAX_ARMATURE] per joint."""
    if not values:
        return None
    try:
        armature = sd.per_joint(model, 'parameter armature', list(values), nonnegative=True)
    except ValueError as err:
        raise ConfigError(f'{err} (order of the joints parameter, or the URDF order '
                          'when it is unset)')
    for name, value in zip(model.joint_names, armature):
        if value > MAX_ARMATURE:
            raise ConfigError(f'parameter armature: joint {name!r} has {value:g}, more than '
                              f'{MAX_ARMATURE:g} kg m^2 (or kg) cannot be a rotor inertia')
    armature.setflags(write=False)
    return None if not armature.any() else armature


def check_gravity(value: Sequence[float]) -> Tuple[float, float, float]:
    """Gravity ``[gx, gy, gz]`` in m/s², base frame, of norm at most :data:`MAX_GRAVITY`."""
    g = tuple(float(x) for x in value)
    if len(g) != 3 or not all(math.isfinite(x) for x in g):
        raise ConfigError(f'parameter gravity: need 3 finite values in m/s², got {list(value)}')
    norm = math.hypot(*g)
    if norm > MAX_GRAVITY:
        raise ConfigError(f'parameter gravity: |g| = {norm:g} m/s² in {list(g)}, more than '
                          f'{MAX_GRAVITY:g} m/s² (100 g) cannot be a mounting')
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


@dataclass(frozen=True)
class Config:
    """A validated parameter change, ready to be swapped in (see ``InverseDynamicsNode``)."""

    params: dict
    output: Optional[Output]
    new_description: bool
    kept_file: str
    gravity: Tuple[float, float, float]
    acceleration_source: str
    input_timeout: float
    wrench_timeout: float


def description_source(params: dict) -> str:
    """Where the description comes from: ``'parameter'``, ``'file'`` or ``'topic'`` (precedence).

    The ``robot_description`` parameter when it is set (non-empty), else
    ``robot_description_file`` when it is set, else the topic.
    """
    if params.get('robot_description'):
        return 'parameter'
    if params.get('robot_description_file'):
        return 'file'
    return 'topic'


@dataclass(frozen=True)
class ParseRequest:
    """A description from the topic to build an :class:`Output` from, with its context.

    ``generation`` identifies the request: the node applies the result only if no other
    description came (or a parameter took precedence) since; ``params`` and ``current`` are
    the node's parameters and output when the message arrived.
    """

    generation: int
    urdf: str
    params: dict
    current: Optional[Output]


class DescriptionParser:
    """One worker thread that builds outputs from topic descriptions, off the answering path.

    ``submit`` replaces any request not yet started (only the newest description matters);
    each finished request is queued with its result (an :class:`Output` or a
    :class:`ConfigError`) and ``notify()`` is called, from the worker thread, so the node can
    pick it up in its executor (a guard condition). The thread starts with the first request.
    """

    def __init__(self, build: Callable[[ParseRequest], Output], notify: Callable[[], None]
                 ) -> None:
        self._build = build
        self._notify = notify
        self._wake = threading.Condition()
        self._request: Optional[ParseRequest] = None
        self._done: List[Tuple[ParseRequest, object]] = []
        self._stopped = False
        self._thread: Optional[threading.Thread] = None

    def submit(self, request: ParseRequest) -> None:
        """Parse ``request`` next (dropping a request that has not started yet)."""
        with self._wake:
            if self._stopped:
                return
            self._request = request
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, daemon=True,
                                                name='robot_description parser')
                self._thread.start()
            self._wake.notify()

    def finished(self) -> List[Tuple[ParseRequest, object]]:
        """Return (and forget) the finished requests with their results, oldest first."""
        with self._wake:
            done, self._done = self._done, []
        return done

    def stop(self) -> None:
        """Let the worker end after the request it is on (it is a daemon: never waited for)."""
        with self._wake:
            self._stopped = True
            self._request = None
            self._wake.notify()

    def _run(self) -> None:
        while True:
            with self._wake:
                while self._request is None and not self._stopped:
                    self._wake.wait()
                if self._stopped:
                    return
                request, self._request = self._request, None
            try:
                result = self._build(request)
            except ConfigError as err:
                result = err
            except Exception as err:  # never lose the worker: report it as a rejection
                result = ConfigError(f'topic robot_description: {err!r}')
            with self._wake:
                if self._stopped:
                    return
                self._done.append((request, result))
            try:
                self._notify()
            except Exception:  # the context is gone: the node is shutting down
                return


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
        # Topic descriptions: parsed by a worker; the result is applied in the executor only
        # if its generation is still the newest (a parameter or a newer message supersedes).
        self._description_generation = 0
        self._description_sub = None
        self._inputs: list = []   # input subscriptions, served while a parameter change parses
        self._parsed = self.create_guard_condition(self._on_parsed)
        self._parser = DescriptionParser(self._build_from_topic, self._parsed.trigger)
        self._configure({name: self._value(name) for name in self._PARAMETERS})
        self.add_on_set_parameters_callback(self._on_set_parameters)

        self.commands_pub = advertise(self, Float64MultiArray, 'effort_commands')
        self.efforts_pub = advertise(self, JointState, 'feedforward_efforts')
        self.diagnostics_pub = self.create_publisher(
            DiagnosticArray, '/diagnostics', 10,
            event_callbacks=PublisherEventCallbacks(use_default_callbacks=False))
        self._commands = Float64MultiArray()
        self._efforts = JointState()
        self._inputs = [
            subscribe(self, JointState, 'desired_joint_states', self._on_joint_state),
            subscribe(self, JointTrajectory, 'desired_trajectory', self._on_trajectory),
            subscribe(self, WrenchStamped, 'external_wrenches', self._on_wrench, WRENCH_DEPTH)]
        self.create_timer(1.0, self._publish_diagnostics)
        if self.output is None:
            self._warn_waiting()

    def destroy_node(self) -> None:
        """Stop the description parser, then destroy the node."""
        self._parser.stop()
        super().destroy_node()

    # -- parameters ------------------------------------------------------------------------

    _PARAMETERS = ('robot_description', 'robot_description_file', 'strict_urdf', 'joints',
                   'locked_joints', 'locked_positions', 'gravity', 'acceleration_source',
                   'input_timeout', 'payload.link', 'payload.mass', 'payload.com',
                   'payload.inertia', 'armature', 'friction_model', 'friction_velocity_threshold',
                   'clamp_to_effort_limits', 'external_wrench_timeout')
    _MODEL_PARAMETERS = ('joints', 'locked_joints', 'locked_positions')
    # Changes that may parse a description (slow for a large one).
    _SLOW_PARAMETERS = {'robot_description', 'robot_description_file', *_MODEL_PARAMETERS}
    _PAYLOAD_PARAMETERS = ('payload.link', 'payload.mass', 'payload.com', 'payload.inertia')

    def _declare_parameters(self) -> None:
        def describe(text, **kwargs):
            return ParameterDescriptor(description=text, **kwargs)

        self.declare_parameter('robot_description', '', describe(
            'URDF XML of the robot (XML text, never a path). Takes precedence over '
            'robot_description_file and the robot_description topic. A new value is parsed '
            'completely and swapped in only if it parses; otherwise it is rejected with the '
            "reason and the old model stays. Set to '' to fall back to robot_description_file "
            '(or, when that is empty too, to the topic).'))
        self.declare_parameter('robot_description_file', '', describe(
            'Path of a URDF (or .xacro, expanded when the xacro module is importable): a '
            f'regular UTF-8 file of at most {MAX_DESCRIPTION_BYTES >> 20} MiB. Used when '
            'robot_description is empty; set while robot_description is set, it is checked '
            'and kept for later, and the model stays that of robot_description.'))
        self.declare_parameter('strict_urdf', False, describe(
            'Refuse a description with URDF warnings (physically inconsistent but computable: '
            'an inertia that is not positive semi-definite or breaks the triangle inequality, '
            'inertia on a massless link...) like any bad description. Off: it loads as written '
            'and each warning is logged and listed in /diagnostics. Cannot be switched on '
            'while the loaded description has warnings.'))
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
                if self._SLOW_PARAMETERS & changes.keys():   # may parse a description
                    config = self._while_answering(lambda: self._prepare(changes))
                else:
                    config = self._prepare(changes)
                self._apply(config, changes)
            except Exception as err:  # ConfigError; anything else must not take the node down
                if not isinstance(err, ConfigError):
                    err = ConfigError(f'{", ".join(changes)}: {err!r}')
                self.get_logger().warn(f'parameter change rejected: {err}')
                if {'robot_description', 'robot_description_file'} & changes.keys():
                    self._count_description_rejected(str(err))
                return SetParametersResult(successful=False, reason=str(err))
        return SetParametersResult(successful=True)

    def _while_answering(self, prepare: Callable[[], 'Config']) -> 'Config':
        """Run ``prepare`` in a thread; meanwhile, answer the inputs from this one.

        The parameter service's callback runs in the executor that answers the inputs, and its
        reply must say whether the change was accepted, so it has to wait for the parse; the
        inputs are taken and answered here in the meantime (as the executor would), so a large
        description set by parameter does not silence the node either. ``prepare`` changes
        nothing of the node; its exception is raised here.
        """
        done = threading.Event()
        box: dict = {}

        def run() -> None:
            try:
                box['config'] = prepare()
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

    def _configure(self, changes: dict) -> None:
        """Validate ``changes`` against the current state, then apply all of them at once."""
        self._apply(self._prepare(changes), changes)

    def _prepare(self, changes: dict) -> 'Config':
        """Validate ``changes`` against the current state; changes nothing of the node.

        Raises :class:`ConfigError` when a value cannot be used.
        """
        params = {**self.params, **changes}
        urdf, source, kept_file = self._description_change(params, changes)
        current = self.output
        output = current
        if urdf is not None or current is not None:
            output = self._build_output(params, current, urdf, source)
        else:  # no model yet: check what needs none; the rest is checked when one arrives
            check_payload(params['payload.link'], params['payload.mass'],
                          params['payload.com'], params['payload.inertia'])
            check_locked(params['locked_joints'], params['locked_positions'])
            check_choice('friction_model', params['friction_model'], FRICTION_MODELS)
            check_positive('friction_velocity_threshold',
                           params['friction_velocity_threshold'], 'rad/s or m/s')
        return Config(
            params=params, output=output, new_description=urdf is not None,
            kept_file=kept_file, gravity=check_gravity(params['gravity']),
            acceleration_source=check_acceleration_source(params['acceleration_source']),
            input_timeout=check_input_timeout(params['input_timeout']),
            wrench_timeout=check_positive('external_wrench_timeout',
                                          params['external_wrench_timeout']))

    def _apply(self, config: 'Config', changes: dict) -> None:
        """Swap in a prepared configuration (between two messages), log what changed."""
        current, output = self.output, config.output
        self.output = output
        self.params = config.params
        self.gravity = config.gravity
        self.acceleration_source = config.acceleration_source
        self.input_timeout = config.input_timeout
        self.wrench_timeout_ns = int(config.wrench_timeout * 1e9)
        if config.new_description:
            self._description_generation += 1   # a topic description still parsing is stale
        if output is not None and (current is None or output.base is not current.base):
            self._log_model(output, current)
        elif output is not None and set(self._PAYLOAD_PARAMETERS) & changes.keys():
            self.get_logger().info(f'payload: {output.payload}')
        if config.kept_file:
            self.get_logger().info(
                f'robot_description_file {config.kept_file!r} checked and kept: '
                'robot_description is set and takes precedence; the file is used once '
                'robot_description is cleared')
        self._follow_topic()

    def _description_change(self, params: dict, changes: dict
                            ) -> Tuple[Optional[str], Optional[str], str]:
        """Return ``(urdf, source, kept)``: the description ``changes`` make current.

        By precedence (:func:`description_source`); ``urdf`` is None when the model's
        description does not change. ``kept`` is the path of a ``robot_description_file`` that
        was set (and read, so it is known to be readable) while ``robot_description`` is set:
        kept for later, not used.
        """
        text, path = params['robot_description'], params['robot_description_file']
        if text:
            kept = ''
            if path and 'robot_description_file' in changes:
                read_description(path)
                kept = path
            if 'robot_description' in changes:
                return text, 'parameter robot_description', kept
            return None, None, kept
        if path and ('robot_description_file' in changes
                     or self.params.get('robot_description')):  # set, or string cleared
            return read_description(path), f'file {path}', ''
        return None, None, ''

    def _build_output(self, params: dict, current: Optional[Output], urdf: Optional[str] = None,
                      source: Optional[str] = None) -> Output:
        """Build the :class:`Output` for ``params``; the URDF is re-parsed only when needed.

        ``urdf`` None keeps the description of ``current``. Reads nothing else of the node, so
        the description parser's thread may call it. Raises :class:`ConfigError`.
        """
        if urdf is None:
            urdf, source = current.urdf, current.source
        # the four payload parameters are checked first: they need no model
        payload = check_payload(params['payload.link'], params['payload.mass'],
                                params['payload.com'], params['payload.inertia'])
        locked = check_locked(params['locked_joints'], params['locked_positions'])
        joints = tuple(params['joints'] or ())
        strict = bool(params['strict_urdf'])
        if (current is not None and urdf is current.urdf and joints == current.joints_param
                and tuple(locked.items()) == current.locked):
            base = current.base
        else:
            if locked and not joints:
                raise ConfigError(f'parameter locked_joints: {list(locked)} lock joints only '
                                  'when the joints parameter lists the joints to keep')
            base = parse_description(urdf, source, joints, locked, strict)
        if strict and base.warnings:
            raise ConfigError(
                f'parameter strict_urdf: {source} has {len(base.warnings)} URDF warning(s) '
                f'(strict_urdf refuses them), the first: {base.warnings[0]}')
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
        armature = check_armature(base, params['armature'])
        if current is not None and base is current.base:
            backend = current.backend
        else:   # a new model: load (or compile) the backend for it now, not at a message
            backend = backends.warmup(model)
        return Output(
            urdf=urdf, source=source, base=base, model=model, joints=tuple(base.joint_names),
            joints_param=joints, locked=tuple(locked.items()), payload=payload,
            armature=armature, friction_threshold=threshold if friction_model == 'urdf' else None,
            clamp=bool(params['clamp_to_effort_limits']), backend=backend)

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
        return self._build_output(request.params, request.current, request.urdf,
                                  'topic robot_description')

    def _on_parsed(self) -> None:
        """Executor: swap in a parsed topic description, unless something newer came since."""
        for request, result in self._parser.finished():
            if (request.generation != self._description_generation
                    or description_source(self.params) != 'topic'):
                continue   # superseded by a newer message or by a description parameter
            if request.params is not self.params:   # parameters changed while it parsed
                model_params = self._MODEL_PARAMETERS + ('strict_urdf',)
                if isinstance(result, ConfigError) or any(
                        request.params[k] != self.params[k] for k in model_params):
                    self._submit_topic(request.urdf)   # again, with the current parameters
                    continue
                try:   # the same model: only the cheap parts again
                    result = self._build_output(self.params, result)
                except ConfigError as err:
                    result = err
            if isinstance(result, ConfigError):
                self.get_logger().error(
                    f'robot description rejected, keeping the current model: {result}')
                self._count_description_rejected(str(result))
                continue
            current, self.output = self.output, result
            self._log_model(result, current)

    def _count_description_rejected(self, reason: str) -> None:
        self.descriptions_rejected += 1
        self.last_description_error = reason

    def _log_model(self, out: Output, previous: Optional[Output]) -> None:
        """Log what was loaded; each URDF warning once per new description text."""
        self.backend = out.backend
        self.get_logger().info(
            f'robot {out.model.name!r} from {out.source}: {len(out.model.joint_names)} DOF; '
            f'output joints {list(out.joints)}')
        self.get_logger().info(f'model: {out.base.summary()}; backend: {self.backend}; '
                               f'payload: {out.payload}')
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
            # WARN while the loaded description has URDF warnings: the torques are those of the
            # file as written, but the file is physically inconsistent somewhere.
            urdf_warnings = output.base.warnings
            model.level = DiagnosticStatus.WARN if urdf_warnings else DiagnosticStatus.OK
            model.hardware_id = output.model.name
            model.message = (f'robot {output.model.name!r} loaded, '
                             f'{len(output.model.joint_names)} DOF')
            if urdf_warnings:
                model.message += f', {len(urdf_warnings)} URDF warning(s)'
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
                KeyValue(key='strict urdf', value=str(bool(self.params['strict_urdf']))),
                KeyValue(key='urdf warnings', value=str(len(urdf_warnings))),
            ] + [KeyValue(key=f'urdf warning {i}', value=text) for i, text
                 in enumerate(urdf_warnings[:URDF_WARNINGS_LISTED], 1)]

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


def _context_shut_down(grace: float = 1.0) -> bool:
    """Whether the default context is shut down, or is within ``grace`` s (signal thread)."""
    deadline = time.monotonic() + grace
    while rclpy.ok():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.01)
    return True


def spin(make_node: Callable[[], Node], args: Optional[Sequence[str]] = None,
         name: str = NODE_NAME) -> int:
    """Make a node and spin it until SIGINT/SIGTERM; 0 on a clean exit, 1 on a bad start-up.

    The node's and the latency baseline's (``relay.py``) process around them, one routine.

    SIGINT is handled as SIGTERM is: rclpy's handler shuts the context down and wakes the
    executor, which returns between two callbacks. Python's own SIGINT handler is not chained
    to it: its KeyboardInterrupt would fire at any bytecode, inside rclpy's bookkeeping too
    (half-built tasks, a taken message lost in pybind11's conversion).
    """
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_DFL)
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
    except Exception:
        # SIGINT/SIGTERM shut the context down from rclpy's signal thread, wherever the
        # executor is: between two waits it raises RCLError ("failed to initialize wait set:
        # the given context is not valid"); in a take, the KeyboardInterrupt of SIGINT inside
        # pybind11's message conversion surfaces as RuntimeError ("Unable to convert call
        # argument"). Those are the requested shutdown; with the context still valid, an
        # exception is a real error and is raised.
        if not _context_shut_down():
            raise
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return status


def main(args: Optional[Sequence[str]] = None) -> int:
    """Run the node until SIGINT/SIGTERM; 0 on a clean exit, 1 if the start-up config is bad."""
    # The node logs each URDF warning itself (once per description) and lists them in
    # /diagnostics: Python's own printing of them would repeat each one on stderr.
    warnings.filterwarnings('ignore', category=sd.URDFWarning)
    return spin(InverseDynamicsNode, args)


if __name__ == '__main__':
    sys.exit(main())
