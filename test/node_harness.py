# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Harness for the node tests: a colcon build, the node as a process, a driver node.

Real rclpy and real DDS: the package is colcon-built once per test session into a temporary
directory, the installed executable ``lib/spatial_dynamics/inverse_dynamics`` runs as a separate
process (as ``ros2 run`` would start it), and the tests talk to it from a node in this process.
All of it runs on one random ROS domain per session (1..200) restricted to localhost, so
parallel runs do not cross-talk.
"""

import atexit
import functools
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from typing import Callable, Dict, List, Optional, Sequence

import numpy as np
import pytest
from spatial_dynamics.tools.driving import die_with_parent

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PACKAGE = 'spatial_dynamics'
DEMO_URDF = os.path.join(ROOT, 'config', 'demo_arm.urdf')
PENDULUM_URDF = os.path.join(ROOT, 'config', 'pendulum.urdf')
DOMAIN_ID = random.SystemRandom().randint(1, 200)
TIMEOUT = 60.0  # generous: bounds a broken run; a fresh install JIT-compiles at first start
PRIME = -1      # stamp key of priming messages


class Install:
    """Where the colcon build put the package."""

    def __init__(self, base: str) -> None:
        self.base = base
        self.prefix = os.path.join(base, 'install', PACKAGE)
        self.executable = os.path.join(self.prefix, 'lib', PACKAGE, 'inverse_dynamics')
        self.marker = os.path.join(self.prefix, 'share', 'ament_index', 'resource_index',
                                   'packages', PACKAGE)
        site = f'python{sys.version_info[0]}.{sys.version_info[1]}'
        self.site_packages = os.path.join(self.prefix, 'lib', site, 'site-packages')

    def env(self) -> Dict[str, str]:
        """Environment of a sourced install, on this session's domain."""
        env = dict(os.environ)
        env['AMENT_PREFIX_PATH'] = os.pathsep.join(
            [self.prefix] + [p for p in env.get('AMENT_PREFIX_PATH', '').split(os.pathsep) if p])
        env['PYTHONPATH'] = os.pathsep.join(
            [self.site_packages] + [p for p in env.get('PYTHONPATH', '').split(os.pathsep) if p])
        env['ROS_DOMAIN_ID'] = str(DOMAIN_ID)
        env['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
        env['PYTHONUNBUFFERED'] = '1'
        env['RCUTILS_LOGGING_BUFFERED_STREAM'] = '0'
        return env


@functools.lru_cache(maxsize=None)
def colcon_install() -> Install:
    """Colcon-build the package once per session into a temporary directory."""
    if shutil.which('colcon') is None:
        pytest.skip('colcon is not installed')
    base = tempfile.mkdtemp(prefix='spatial_dynamics_colcon_')
    atexit.register(shutil.rmtree, base, True)
    cmd = ['colcon', '--log-base', os.path.join(base, 'log'), 'build',
           '--base-paths', ROOT, '--build-base', os.path.join(base, 'build'),
           '--install-base', os.path.join(base, 'install'),
           '--packages-select', PACKAGE]
    proc = subprocess.run(cmd, cwd=base, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, f'colcon build failed:\n{proc.stdout}\n{proc.stderr}'
    return Install(base)


class NodeProcess:
    """An installed executable (``inverse_dynamics`` unless told) running as a child process."""

    def __init__(self, install: Install, args: Sequence[str] = (), log_dir: str = '',
                 env: Optional[Dict[str, str]] = None,
                 executable: str = 'inverse_dynamics') -> None:
        """Start it with ``--ros-args *args``; ``env`` adds to :meth:`Install.env`."""
        self.log_path = os.path.join(log_dir or install.base,
                                     f'{executable}_{time.monotonic_ns()}.log')
        self._log = open(self.log_path, 'w')
        path = os.path.join(install.prefix, 'lib', PACKAGE, executable)
        self.proc = subprocess.Popen([path, '--ros-args', *args],
                                     env={**install.env(), **(env or {})}, stdout=self._log,
                                     stderr=subprocess.STDOUT, preexec_fn=die_with_parent)

    def log(self) -> str:
        """Return what the node printed so far."""
        with open(self.log_path) as f:
            return f.read()

    def wait_for_log(self, text: str, timeout: float = TIMEOUT) -> str:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            log = self.log()
            if text in log:
                return log
            time.sleep(0.05)
        raise AssertionError(f'{text!r} not in the node log:\n{self.log()}')

    def refused_at_start(self, words: Sequence[str]) -> None:
        """Assert the process exits 1, saying it cannot start and naming each of ``words``.

        No traceback: a refusal is a message for the user, not a crash.
        """
        assert self.proc.wait(TIMEOUT) == 1
        log = self.log()
        assert 'cannot start' in log and 'Traceback' not in log, log
        for word in words:
            assert word in log, (word, log)
        self.stop()

    def stop(self, sig: int = signal.SIGINT, timeout: float = TIMEOUT) -> int:
        """Send ``sig`` and wait for the exit status (killed after ``timeout``)."""
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
                raise AssertionError(f'node did not exit on {sig!r}:\n{self.log()}')
        self._log.close()
        return self.proc.returncode


class Driver:
    """A test node in this process, on the session's domain, with its own context."""

    def __init__(self) -> None:
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.signals import SignalHandlerOptions
        self.rclpy = rclpy
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=DOMAIN_ID,
                   signal_handler_options=SignalHandlerOptions.NO)
        self.node = rclpy.create_node(f'test_driver_{os.getpid()}', context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def close(self) -> None:
        self.executor.shutdown()
        self.node.destroy_node()
        self.rclpy.try_shutdown(context=self.context)

    def spin_for(self, seconds: float) -> None:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=min(0.01, max(deadline - time.monotonic(), 0)))

    def spin_until(self, predicate: Callable[[], bool], timeout: float = TIMEOUT,
                   what: str = 'condition') -> None:
        deadline = time.monotonic() + timeout
        while not predicate():
            if time.monotonic() > deadline:
                raise AssertionError(f'timed out waiting for {what}')
            self.executor.spin_once(timeout_sec=0.01)

    def call(self, client, request, timeout: float = TIMEOUT):
        """Call a service and spin until the answer arrives."""
        self.spin_until(lambda: client.service_is_ready(), timeout, f'service {client.srv_name}')
        future = client.call_async(request)
        self.spin_until(future.done, timeout, f'answer of {client.srv_name}')
        return future.result()


class Io:
    """Publishers to and recorders of one ``inverse_dynamics`` node, for a driver."""

    def __init__(self, driver: Driver, node_name: str = 'inverse_dynamics') -> None:
        from diagnostic_msgs.msg import DiagnosticArray
        from rcl_interfaces.srv import SetParameters
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from sensor_msgs.msg import JointState
        from std_msgs.msg import Float64MultiArray, String
        from trajectory_msgs.msg import JointTrajectory
        self.driver = driver
        node = driver.node
        self.efforts: List = []
        self.arrivals: List[float] = []   # time.monotonic() at which each effort arrived
        self.commands: List = []
        self.diagnostics: List = []
        self.diagnostic_arrivals: List[float] = []   # time.monotonic() of each of ours
        self.subscriptions = [
            node.create_subscription(JointState, 'feedforward_efforts', self._on_efforts,
                                     1000),
            node.create_subscription(Float64MultiArray, 'effort_commands',
                                     self.commands.append, 1000),
            node.create_subscription(DiagnosticArray, '/diagnostics', self._on_diagnostics,
                                     100),
        ]
        self.joint_states = node.create_publisher(JointState, 'desired_joint_states', 10)
        self.trajectory = node.create_publisher(JointTrajectory, 'desired_trajectory', 10)
        self.description = node.create_publisher(
            String, 'robot_description',
            QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.TRANSIENT_LOCAL))
        self.parameters = node.create_client(SetParameters, f'/{node_name}/set_parameters')
        self.atomic = None
        self.node_name = node_name

    def _on_efforts(self, msg) -> None:
        self.arrivals.append(time.monotonic())
        self.efforts.append(msg)

    def _on_diagnostics(self, msg) -> None:
        if any(s.name.startswith(self.node_name + ':') for s in msg.status):
            self.diagnostics.append(msg)
            self.diagnostic_arrivals.append(time.monotonic())

    def close(self) -> None:
        node = self.driver.node
        for sub in self.subscriptions:
            node.destroy_subscription(sub)
        for pub in (self.joint_states, self.trajectory, self.description):
            node.destroy_publisher(pub)
        node.destroy_client(self.parameters)
        if self.atomic is not None:
            node.destroy_client(self.atomic)

    def wait_connected(self) -> None:
        """Wait until the node's subscriptions and publishers are matched with ours."""
        self.driver.spin_until(
            lambda: (self.joint_states.get_subscription_count() >= 1
                     and self.trajectory.get_subscription_count() >= 1
                     and all(s.get_publisher_count() >= 1 for s in self.subscriptions)),
            what='the node to connect')

    def prime(self, names: Sequence[str]) -> None:
        """Publish on both inputs until each is answered, then forget the answers.

        Discovery is asymmetric: our publisher may see the node's subscription before the node
        sees our publisher, and what is published in between is lost. Two answers (stamp -1)
        prove both directions work; they count in the node's ``answered``, and so does every
        priming message answered after the next was sent (a busy node answers slower than
        one publish period): ``self.primed`` is how many answers arrived, a lower bound of
        the node's count (an answer sent before the node's publisher matched our subscription
        is counted there and lost here).
        """
        from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
        zeros = [0.0] * len(names)
        trajectory = JointTrajectory(joint_names=list(names),
                                     points=[JointTrajectoryPoint(positions=zeros)])
        trajectory.header.stamp = stamp(PRIME)
        for publisher, msg in ((self.joint_states, joint_state(names, zeros, zeros, zeros, PRIME)),
                               (self.trajectory, trajectory)):
            count = len(self.efforts)
            deadline = time.monotonic() + TIMEOUT
            while len(self.efforts) == count:
                assert time.monotonic() < deadline, 'the node never answered the priming input'
                publisher.publish(msg)
                self.driver.spin_for(0.05)
        self.driver.spin_for(0.2)
        self.primed = len(self.efforts)
        self.efforts.clear()
        self.commands.clear()

    def publish_until_answered(self, make: Callable[[int], object], period: float = 0.02,
                               timeout: float = TIMEOUT) -> int:
        """Publish ``make(k)``, k = 0, 1, ..., every ``period`` s until an answer; return k.

        The answer is to message k or an earlier one (the tests use the same state for all).
        """
        count = len(self.efforts)
        deadline = time.monotonic() + timeout
        k = 0
        while len(self.efforts) == count:
            assert time.monotonic() < deadline, 'the node never answered'
            self.joint_states.publish(make(k))
            self.driver.spin_for(period)
            k += 1
        return k

    def set_parameters(self, **values) -> List:
        """Set parameters of the node; returns the SetParametersResult list."""
        from rcl_interfaces.srv import SetParameters
        from rclpy.parameter import Parameter
        request = SetParameters.Request()
        for name, value in values.items():
            if isinstance(value, Parameter):
                request.parameters.append(value.to_parameter_msg())
            else:
                request.parameters.append(Parameter(name, value=value).to_parameter_msg())
        return self.driver.call(self.parameters, request).results

    def set_parameters_atomically(self, **values) -> List:
        """Set parameters all or none (SetParametersAtomically); a one-result list."""
        from rcl_interfaces.srv import SetParametersAtomically
        from rclpy.parameter import Parameter
        if self.atomic is None:
            self.atomic = self.driver.node.create_client(
                SetParametersAtomically, f'/{self.node_name}/set_parameters_atomically')
        request = SetParametersAtomically.Request()
        request.parameters = [Parameter(name, value=value).to_parameter_msg()
                              for name, value in values.items()]
        return [self.driver.call(self.atomic, request).result]

    def status(self, suffix: str, after: int = 0):
        """Latest diagnostics status ``'<node>: <suffix>'`` from message index ``after`` on."""
        name = f'{self.node_name}: {suffix}'
        self.driver.spin_until(lambda: len(self.diagnostics) > after, what='diagnostics')
        for status in self.diagnostics[-1].status:
            if status.name == name:
                return status
        raise AssertionError(f'no status {name!r} in {self.diagnostics[-1]}')

    def fresh_status(self, suffix: str):
        """Return a diagnostics status published after now (waits for the next period)."""
        return self.status(suffix, after=len(self.diagnostics) + 1)


def values(status) -> Dict[str, str]:
    """Key-value pairs of a DiagnosticStatus as a dict."""
    return {kv.key: kv.value for kv in status.values}


def stamp(k: int):
    """Return a unique, recognisable header stamp for message ``k`` (not wall time)."""
    from builtin_interfaces.msg import Time
    return Time(sec=1_000_000 + k // 1000, nanosec=(k % 1000) * 1000)


def stamp_key(t) -> int:
    """Return the ``k`` of :func:`stamp`."""
    return (t.sec - 1_000_000) * 1000 + t.nanosec // 1000


def joint_state(names: Sequence[str], q, qd, qdd, k: int):
    """Return a JointState with the arrays (already in ``names`` order) and stamp ``k``."""
    from sensor_msgs.msg import JointState
    msg = JointState()
    msg.header.stamp = stamp(k)
    msg.name = list(names)
    msg.position = [float(x) for x in q]
    msg.velocity = [float(x) for x in qd]
    msg.effort = [float(x) for x in qdd]
    return msg


def random_states(seed: int, count: int, n: int) -> np.ndarray:
    """``count`` random (q, qd, qdd) rows, shape (count, 3, n), within joint-ish ranges."""
    rng = np.random.default_rng(seed)
    return rng.uniform(-1.0, 1.0, size=(count, 3, n)) * np.array([2.5, 2.0, 5.0])[:, None]


def drive(driver: Driver, publish: Callable[[int], None], count: int, rate: float) -> None:
    """Call ``publish(k)`` for k in range(count) at ``rate`` Hz, spinning in between."""
    from spatial_dynamics.tools.latency_pacer import pace   # the latency and soak tools' pacing
    assert pace(driver.executor, rate, count / rate, publish) == count


def settle(driver: Driver, io: Io, seconds: float = 0.5) -> None:
    """Spin until no new answer arrived for ``seconds``."""
    last = -1
    while last != len(io.efforts):
        last = len(io.efforts)
        driver.spin_for(seconds)


def pin_oracle(urdf: str):
    """Pinocchio on the same URDF (mimic stripped and folded back), or skip."""
    pytest.importorskip('pinocchio')
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from conftest import PinOracle
    return PinOracle(urdf)


# Fixtures of the node tests; test/conftest.py imports them (it must import without ROS, and
# so can this module: rclpy is imported only when a driver is made).


@pytest.fixture(scope='module')
def install() -> Install:
    """Build and install the package with colcon (once per session)."""
    return colcon_install()


@pytest.fixture(scope='module')
def driver():
    """Yield a node in this process that talks to the node under test."""
    d = Driver()
    yield d
    d.close()


@pytest.fixture(scope='module')
def demo_model():
    """Return the library's model of the demo arm the node tests start the node with."""
    import spatial_dynamics as sd
    return sd.Model.from_urdf(DEMO_URDF)


class Log:
    """The node's logger, as ``Answering`` uses it: what it said, by level."""

    def __init__(self) -> None:
        self.said = []

    def info(self, text, **_):
        self.said.append(('info', text))

    def warn(self, text, **_):
        self.said.append(('warn', text))
