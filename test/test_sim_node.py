# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The installed ``sim`` node over real DDS: states out, effort commands in.

The node runs as ``ros2 run spatial_dynamics sim`` would start it (the colcon-installed
executable, see node_harness). Its states are checked against a
:class:`~spatial_dynamics.sim.robot.SimulatedRobot` in this process stepped with the same
commands: the same physics, so the same numbers.
"""

import math
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from node_harness import DEMO_URDF, NodeProcess, TIMEOUT  # noqa: E402
from spatial_dynamics.sim.robot import MUJOCO_MISSING, SimulatedRobot  # noqa: E402

pytestmark = pytest.mark.ros

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
H = 0.002                      # s, the node's timestep in these tests


class SimProcess(NodeProcess):
    """The installed ``sim`` executable as a child process, its output in a log file."""

    def __init__(self, install, args, log_dir):
        super().__init__(install, args, log_dir, executable='sim')


class Channels:
    """A command publisher and a joint_states recorder on the driver node."""

    def __init__(self, driver):
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from sensor_msgs.msg import JointState
        from std_msgs.msg import Float64MultiArray
        self.driver = driver
        self.states = []
        self.sub = driver.node.create_subscription(JointState, 'joint_states',
                                                   self.states.append, 1000)
        self.pub = driver.node.create_publisher(
            Float64MultiArray, 'effort_commands',
            QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE))
        self.Float64MultiArray = Float64MultiArray

    def close(self):
        self.driver.node.destroy_subscription(self.sub)
        self.driver.node.destroy_publisher(self.pub)

    def wait_connected(self):
        self.driver.spin_until(lambda: self.pub.get_subscription_count() >= 1 and self.states,
                               what='the sim to connect')

    def command(self, values):
        self.pub.publish(self.Float64MultiArray(data=[float(v) for v in values]))

    def wait_states(self, count):
        self.driver.spin_until(lambda: len(self.states) >= count, what=f'{count} states')


def sim_time(msg):
    return msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9


@pytest.fixture
def lockstep(install, driver, tmp_path):
    proc = SimProcess(install, ['-p', f'robot_description_file:={DEMO_URDF}',
                                '-p', 'mode:=lockstep', '-p', f'timestep:={H}'], str(tmp_path))
    channels = Channels(driver)
    channels.wait_connected()
    yield proc, channels
    channels.close()
    assert proc.stop(signal.SIGINT) == 0, proc.log()


def test_lockstep_one_step_per_command_same_physics(lockstep, rng):
    proc, io = lockstep
    oracle = SimulatedRobot(DEMO_URDF, timestep=H)
    n = oracle.model.nq
    first = io.states[0]
    assert list(first.name) == list(oracle.joint_names)
    assert sim_time(first) == 0.0 and list(first.position) == [0.0] * n
    for k in range(1, 21):
        tau = rng.uniform(-5.0, 5.0, n)
        count = len(io.states)
        io.command(tau)
        io.driver.spin_until(lambda: any(math.isclose(sim_time(s), k * H, abs_tol=1e-9)
                                         for s in io.states[count:]), what=f'step {k}')
        oracle.step(tau)
        state = next(s for s in io.states[count:]
                     if math.isclose(sim_time(s), k * H, abs_tol=1e-9))
        assert np.allclose(state.position, oracle.q, rtol=0, atol=1e-12)
        assert np.allclose(state.velocity, oracle.qd, rtol=0, atol=1e-12)
        assert np.allclose(state.effort, tau, rtol=0, atol=0)
    # every state published is of a step 0..20, in order (republished states repeat one)
    steps = [round(sim_time(s) / H) for s in io.states]
    assert steps == sorted(steps) and steps[-1] == 20
    assert all(math.isclose(sim_time(s), round(sim_time(s) / H) * H, abs_tol=1e-9)
               for s in io.states)


def test_lockstep_refuses_bad_commands_and_republishes_while_waiting(lockstep):
    proc, io = lockstep
    n = 8
    for bad in ([0.0] * (n - 1), [math.nan] + [0.0] * (n - 1), [0.0] * (n - 1) + [math.inf],
                [2e6] + [0.0] * (n - 1)):
        io.command(bad)
    # the state is republished while the node waits: wait for a few more, all still step 0
    count = len(io.states)
    io.wait_states(count + 3)
    assert all(sim_time(s) == 0.0 and list(s.position) == [0.0] * n for s in io.states)
    log = proc.log()
    assert 'command refused' in log and f'{n - 1} values for {n} joints' in log, log
    # one good command: exactly one step
    io.command([1.0] * n)
    io.driver.spin_until(lambda: sim_time(io.states[-1]) > 0.0, what='the step')
    count = len(io.states)
    io.wait_states(count + 2)
    assert {round(sim_time(s) / H) for s in io.states} == {0, 1}


def test_realtime_publishes_and_zero_torque_falls(install, driver, tmp_path):
    proc = SimProcess(install, ['-p', f'robot_description_file:={DEMO_URDF}',
                                '-p', 'initial_positions:=[0.0, 0.8, 0.0, -1.0, 0.0, 0.5, '
                                '0.0, 0.0]', '-p', 'publish_clock:=true'], str(tmp_path))
    io = Channels(driver)
    from rosgraph_msgs.msg import Clock
    clocks = []
    sub = driver.node.create_subscription(Clock, '/clock', clocks.append, 100)
    try:
        io.wait_connected()
        io.wait_states(200)
        oracle = SimulatedRobot(DEMO_URDF)
        names = list(oracle.joint_names)
        last = io.states[-1]
        assert list(last.name) == names and list(last.effort) == [0.0] * 8
        assert abs(last.position[1] - 0.8) > 1e-3          # no command: the arm falls
        assert clocks and clocks[-1].clock.sec + clocks[-1].clock.nanosec > 0
    finally:
        driver.node.destroy_subscription(sub)
        io.close()
        assert proc.stop(signal.SIGTERM) == 0, proc.log()


def test_missing_mujoco_clear_message_exit_1(tmp_path):
    (tmp_path / 'mujoco.py').write_text('raise ImportError("no mujoco here")\n')
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path), ROOT]))
    proc = subprocess.run([sys.executable, '-m', 'spatial_dynamics.sim'], env=env,
                          capture_output=True, text=True, timeout=TIMEOUT)
    assert proc.returncode == 1
    assert proc.stderr.strip() == f'sim: {MUJOCO_MISSING}'


@pytest.mark.parametrize('param, words', [
    ('mode:=fast', ["mode: 'fast'"]),
    ('timestep:=1e300', ['timestep', '1e+300']),
    ('timestep:=1e-12', ['timestep', '1e-06']),
    ('command_timeout:=1e300', ['command_timeout']),
    ('initial_positions:=[1e300,0.0,0.0,0.0,0.0,0.0,0.0,0.0]', ['initial_positions', '1e+300'])])
def test_bad_start_up_exits_1_naming_the_problem(install, tmp_path, param, words):
    proc = SimProcess(install, ['-p', f'robot_description_file:={DEMO_URDF}',
                                '-p', param], str(tmp_path))
    proc.refused_at_start(words)


def test_lockstep_republishes_every_period_while_waiting(lockstep):
    """With no controller, the state comes again every REPUBLISH_PERIOD (0.1 s), not 0.2."""
    from spatial_dynamics.sim.node import REPUBLISH_PERIOD
    proc, io = lockstep
    io.states.clear()
    arrivals = []
    deadline = time.monotonic() + TIMEOUT
    while len(arrivals) < 12 and time.monotonic() < deadline:
        count = len(io.states)
        io.driver.spin_until(lambda: len(io.states) > count, what='a republished state')
        arrivals.append(time.monotonic())
    gaps = np.diff(arrivals)
    # The old timer gave every gap 0.2 s. On a loaded machine a wake-up comes late (a long
    # gap, then a short one when two states arrive together): so a quarter of the gaps may be
    # late and a quarter early, and the middle half must still be one period.
    early, late = np.percentile(gaps, [25, 75])
    assert early < 1.5 * REPUBLISH_PERIOD and late > 0.75 * REPUBLISH_PERIOD, gaps


def test_commands_beyond_the_robot_never_publish_nan(lockstep):
    """Send 1e6 N m once, zeros, then 1e3 N m held: every published state stays finite.

    The demo arm's finger diverges; the sim restarts at its initial positions (logged).
    """
    proc, io = lockstep
    n = 8
    sequences = [[1e6] * n] + [[0.0] * n] * 20 + [[1e3] * n] * 120
    for k, tau in enumerate(sequences):
        count = len(io.states)
        io.command(tau)
        io.driver.spin_until(lambda: any(round(sim_time(s) / H) == k + 1
                                         for s in io.states[count:]), what=f'step {k + 1}')
    for s in io.states:
        assert np.isfinite(s.position).all() and np.isfinite(s.velocity).all()
        assert np.abs(s.position).max() <= 1e5 and np.abs(s.velocity).max() <= 1e4
    proc.wait_for_log('the simulation diverged and restarted')


def test_applied_wrench_pushes_the_robot_as_apply_wrench_does(lockstep):
    from geometry_msgs.msg import WrenchStamped
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    proc, io = lockstep
    oracle = SimulatedRobot(DEMO_URDF, timestep=H)
    n = oracle.model.nq
    pub = io.driver.node.create_publisher(
        WrenchStamped, 'applied_wrench', QoSProfile(depth=10,
                                                    reliability=ReliabilityPolicy.RELIABLE))

    def wrench(link, values):
        msg = WrenchStamped()
        msg.header.frame_id = link
        t, f = msg.wrench.torque, msg.wrench.force
        t.x, t.y, t.z, f.x, f.y, f.z = (float(v) for v in values)
        return msg

    def wait_log(text):
        io.driver.spin_until(lambda: text in proc.log(), what=f'{text!r} in the sim log')

    try:
        io.driver.spin_until(lambda: pub.get_subscription_count() >= 1, what='applied_wrench')
        for bad, why in ((wrench('no_such_link', [1.0] * 6), "'no_such_link' is not a link"),
                         (wrench('tcp', [0.0, math.nan, 0, 0, 0, 0]), 'torque.y')):
            pub.publish(bad)
            wait_log(why)
        w = [0.5, -0.3, 0.2, 10.0, -5.0, 8.0]
        pub.publish(wrench('tcp', w))
        wait_log("applied_wrench on 'tcp'")
        oracle.apply_wrench('tcp', w)
        tau = np.zeros(n)
        for k in range(1, 11):
            count = len(io.states)
            io.command(tau)
            io.driver.spin_until(lambda: any(math.isclose(sim_time(s), k * H, abs_tol=1e-9)
                                             for s in io.states[count:]), what=f'step {k}')
            oracle.step(tau)
        state = io.states[-1]
        assert np.allclose(state.position, oracle.q, rtol=0, atol=1e-12)
        assert np.allclose(state.velocity, oracle.qd, rtol=0, atol=1e-12)
        free = SimulatedRobot(DEMO_URDF, timestep=H)     # without the push: elsewhere
        free.step(tau, 10)
        assert np.abs(free.qd - oracle.qd).max() > 1e-3
        assert list(state.effort) == [0.0] * n   # the effort is the command, not the push
    finally:
        io.driver.node.destroy_publisher(pub)


def test_check_wrench_names_the_link_or_the_component():
    from spatial_dynamics.sim.node import check_wrench
    links = ['base', 'tcp']
    assert check_wrench('tcp', [0.0] * 6, links) is None
    assert "'hand' is not a link" in check_wrench('hand', [0.0] * 6, links)
    assert 'force.z' in check_wrench('tcp', [0, 0, 0, 0, 0, math.inf], links)
    assert 'torque.x' in check_wrench('tcp', [math.nan, 0, 0, 0, 0, 0], links)
    assert 'force.x above' in check_wrench('tcp', [0, 0, 0, 2e6, 0, 0], links)


def test_check_command_names_the_length_or_the_value():
    from spatial_dynamics.sim.node import check_command
    assert check_command([0.0, 1.0], 2) is None
    assert check_command([0.0], 2) == '1 values for 2 joints'
    assert check_command([0.0, math.nan], 2) == 'non-finite value at index 1'
    assert check_command([-2e6, 0.0], 2) == 'value at index 0 above 1e+06'
