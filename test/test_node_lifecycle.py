# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Install layout, start-up, robot_description topic, parameter file, launch file, signals."""

import os
import py_compile
import re
import signal
import subprocess
import sys
import time

from diagnostic_msgs.msg import DiagnosticStatus
import numpy as np
import pytest
import yaml

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from node_harness import (  # noqa: E402
    DEMO_URDF, DOMAIN_ID, Io, joint_state, NodeProcess, PACKAGE, random_states, ROOT, TIMEOUT,
    values)
import spatial_dynamics as sd  # noqa: E402

YAML = os.path.join(ROOT, 'config', 'inverse_dynamics.yaml')
LAUNCH = os.path.join(ROOT, 'launch', 'inverse_dynamics.launch.py')


def declared_parameters():
    """Names the node declares: those of ``ros.config.PARAMETERS`` (a module without ROS)."""
    from spatial_dynamics.ros.config import PARAMETERS
    return {spec.name for spec in PARAMETERS}


def test_ros2_run_layout(install):
    """What `ros2 run spatial_dynamics inverse_dynamics` needs after a colcon build."""
    assert os.path.isfile(install.marker)
    assert os.path.isfile(install.executable) and os.access(install.executable, os.X_OK)
    code = ('from ament_index_python.packages import get_package_prefix; '
            f'print(get_package_prefix({PACKAGE!r}))')
    out = subprocess.run([sys.executable, '-c', code], env=install.env(), check=True,
                         capture_output=True, text=True).stdout.strip()
    assert out == install.prefix
    share = os.path.join(install.prefix, 'share', PACKAGE)
    for name in ('package.xml', 'config/inverse_dynamics.yaml', 'config/demo_arm.urdf',
                 'launch/inverse_dynamics.launch.py'):
        assert os.path.isfile(os.path.join(share, name)), name


def test_yaml_documents_every_parameter():
    with open(YAML) as f:
        text = f.read()
    declared = declared_parameters()
    assert declared == {'robot_description', 'robot_description_file', 'strict_urdf',
                        'joints', 'gravity',
                        'acceleration_source', 'input_timeout', 'locked_joints',
                        'locked_positions', 'payload.link', 'payload.mass', 'payload.com',
                        'payload.inertia', 'armature', 'friction_model',
                        'friction_velocity_threshold', 'clamp_to_effort_limits',
                        'external_wrench_timeout', 'backend', 'output', 'control_mode',
                        'kp', 'kd', 'measured_timeout', 'observer_gain',
                        'external_torque_warn', 'measured_effort', 'wrench_estimate.link',
                        'wrench_estimate.epsilon', 'trajectory_effort_tolerance',
                        'trajectory_max_bytes', 'trajectory_annotation_max_values',
                        'base', 'base_input.source', 'base_input.imu_link',
                        'base_input.imu_frame', 'base_input.odometry_frame',
                        'base_input.odometry_link',
                        'base_input.acceleration', 'base_input.min_interval',
                        'base_input.acceleration_time_constant',
                        'base_input.max_linear_acceleration',
                        'base_input.max_angular_acceleration', 'base_input.timeout',
                        'contacts.links',
                        'contacts.kind', 'contacts.mu', 'contacts.method',
                        'contacts.measured', 'thread_priority', 'cpu_affinity', 'lock_memory'}
    for name in declared:
        # payload.link is written nested: 'payload:' then 'link:'
        *group, leaf = name.split('.')
        for key in group + [leaf]:
            assert re.search(rf'^\s*#?\s*{key}:', text, re.M), f'{name} missing in the yaml'
    params = yaml.safe_load(text)['inverse_dynamics']['ros__parameters']
    assert params['payload'] == {'link': '', 'mass': 0.0, 'com': [0.0] * 3,
                                 'inertia': [0.0] * 6}
    assert params['friction_model'] == 'none' and params['clamp_to_effort_limits'] is False
    assert params['gravity'] == [0.0, 0.0, -9.81]
    assert params['acceleration_source'] == 'effort'
    assert params['strict_urdf'] is False
    assert params['backend'] == 'auto'
    assert params['output'] == 'full' and params['control_mode'] == 'feedforward'
    assert params['kp'] == [0.0] and params['kd'] == [0.0]
    assert params['measured_timeout'] == 0.5
    assert params['observer_gain'] == 20.0 and params['external_torque_warn'] == [5.0]


def test_launch_file_compiles():
    py_compile.compile(LAUNCH, doraise=True)
    with open(LAUNCH) as f:
        text = f.read()
    assert "executable='inverse_dynamics'" in text and 'inverse_dynamics.yaml' in text


@pytest.mark.ros
@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM], ids=['SIGINT', 'SIGTERM'])
def test_clean_exit_on_signal_while_busy(install, driver, tmp_path, sig):
    """Exit status 0 on SIGINT/SIGTERM, also while answering 500 messages a second."""
    node = NodeProcess(install, ['-p', f'robot_description_file:={DEMO_URDF}'], str(tmp_path))
    io = Io(driver)
    try:
        io.wait_connected()
        model = sd.Model.from_urdf(DEMO_URDF)
        names = model.joint_names
        states = random_states(20, 200, len(names))
        io.publish_until_answered(lambda k: joint_state(names, *states[0], k))
        for j in range(200):
            io.joint_states.publish(joint_state(names, *states[j], j))
            driver.spin_for(0.002)
        start = time.monotonic()
        status = node.stop(sig)
        print(f'{sig!r}: exit status {status} after {time.monotonic() - start:.2f} s')
        assert status == 0, node.log()
        assert 'Traceback' not in node.log()
    finally:
        io.close()
        node.stop(signal.SIGKILL)


def flood(stop, names, states):
    """Publish JointStates as fast as possible (5-20 kHz here) from a context of its own."""
    import rclpy
    from rclpy.signals import SignalHandlerOptions
    from sensor_msgs.msg import JointState
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=DOMAIN_ID,
               signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node(f'flood_{os.getpid()}', context=context)
    try:
        publisher = node.create_publisher(JointState, 'desired_joint_states', 10)
        k = 0
        while not stop.is_set():
            publisher.publish(joint_state(names, *states[k % len(states)], k))
            k += 1
        return k
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=context)


@pytest.mark.ros
def test_exit_0_on_every_signal_under_flood(install, tmp_path):
    """SIGINT/SIGTERM while input arrives at kHz rates: always exit 0, never a traceback.

    Before, 6 of 14 such stops exited 1 with ``RCLError: failed to initialize wait set: the
    given context is not valid`` out of spin(): the signal handler shut the context down
    between two waits of the executor.
    """
    import threading
    model = sd.Model.from_urdf(DEMO_URDF)
    names = model.joint_names
    states = random_states(23, 100, len(names))
    stop = threading.Event()
    sent = []
    publisher = threading.Thread(target=lambda: sent.append(flood(stop, names, states)))
    publisher.start()
    failures = []
    try:
        for run in range(12):
            sig = (signal.SIGINT, signal.SIGTERM)[run % 2]
            node = NodeProcess(install, ['-p', f'robot_description_file:={DEMO_URDF}'],
                               str(tmp_path))
            try:
                node.wait_for_log("robot 'demo_arm' from file")
                time.sleep(0.5 + 0.1 * run)   # answering the flood by now
                status = node.stop(sig)
                log = node.log()
                if status != 0 or 'Traceback' in log:
                    failures.append((sig, status, log[-2000:]))
            finally:
                node.stop(signal.SIGKILL)
    finally:
        stop.set()
        publisher.join()
    print(f'{sent[0]} messages published; {len(failures)} of 12 stops failed')
    for sig, status, log in failures:
        print(f'--- {sig!r}: exit status {status}; the end of the log:\n{log}')
    assert not failures, [(sig, status) for sig, status, _ in failures]


def test_ctrl_c_while_the_node_imports_stops_it_without_a_traceback(install, tmp_path):
    """SIGINT in the first second, while Python still imports rclpy, numpy and the package.

    Before ``spin`` takes over SIGINT, Python's own handler turned it into a
    ``KeyboardInterrupt`` traceback from whatever import was running; then the default
    action ended the process on the signal (status 130 in a shell, where the docs promise
    0). The launcher's handler now ends it with status 0 until ``rclpy.init`` has returned.
    The signal is sent once rclpy's extension is loaded: the imports after it take the
    better part of a second, and a node already spinning exits 0 on SIGINT, also silently.
    """
    node = NodeProcess(install, ['-p', f'robot_description_file:={DEMO_URDF}'], str(tmp_path))
    deadline = time.monotonic() + TIMEOUT
    try:
        while node.proc.poll() is None and time.monotonic() < deadline:
            try:
                with open(f'/proc/{node.proc.pid}/maps') as maps:
                    if '_rclpy_pybind11' in maps.read():
                        break
            except OSError:
                pass
            time.sleep(0.002)
        status = node.stop(signal.SIGINT)
    finally:
        node.stop(signal.SIGKILL)
    log = node.log()
    assert 'Traceback' not in log and 'KeyboardInterrupt' not in log, log[-2000:]
    assert status == 0, (status, log[-2000:])


@pytest.mark.ros
def test_bad_start_up_configuration_exits_1_with_reason(install, tmp_path):
    bad = tmp_path / 'bad.urdf'
    bad.write_text('<robot name="r"><link name="a"/><joint name="j" type="revolute">'
                   '<parent link="a"/><child link="missing"/></joint></robot>')
    good = f'robot_description_file:={DEMO_URDF}'
    sub = 'qos_overrides./desired_joint_states.subscription'
    for args, expect in [([f'robot_description_file:={tmp_path}/none.urdf'], 'no such file'),
                         ([f'robot_description_file:={bad}'], 'bad.urdf'),
                         ([good, 'gravity:=[0,0,-10]'], 'gravity'),
                         ([good, 'input_timeout:=0.0'], 'input_timeout'),
                         ([good, 'acceleration_source:=torque'], 'acceleration_source'),
                         ([good, 'joints:=[joint1,gripper]'], "'gripper'"),
                         ([good, 'payload.link:=gripper'], "payload.link: 'gripper'"),
                         ([good, 'friction_model:=coulomb'], 'friction_model'),
                         ([good, 'armature:=[0.1]'], 'armature'),
                         ([good, 'gravity:=[0.0,0.0,-1.0e308]'], 'parameter gravity'),
                         ([good, 'payload.link:=hand', 'payload.mass:=1.0e300'],
                          'payload.mass'),
                         ([good, 'thread_priority:=1000000000'],
                          'thread_priority: need a value from 0 to 99, got 1000000000'),
                         # checked before rcl sees them: rcl printed 13-25
                         # rcutils_set_error_state() dumps for a negative depth first
                         *[([good, f'{sub}.depth:={given}'],
                            (f"cannot start: {sub}.depth: need an integer from 0 to "
                             f"2147483647 (messages queued), got {said}",))
                           for given, said in [('-1', '-1'), ('2147483648', '2147483648'),
                                               ('1e300', '1e+300 (a double)'),
                                               ('1.5', '1.5 (a double)'),
                                               ('abc', "'abc'"), ('true', 'true (a bool)'),
                                               ('99999999999999999999', '1e+20 (a double)')]],
                         ([good, f'{sub}.reliability:=1'],
                          f'cannot start: {sub}.reliability: need one of reliable, '
                          'best_effort, best_available, system_default, got 1'),
                         ([good, f'{sub}.history:=5'],
                          f'cannot start: {sub}.history: need one of keep_last, keep_all, '
                          'system_default, got 5'),
                         ([good, 'qos_overrides./joint_states.subscription.reliability:=foo'],
                          'subscription.reliability: need one of reliable, best_effort, '
                          "best_available, system_default, got 'foo'"),
                         ([good, f'{sub}.reliability:=sometimes'], "got 'sometimes'"),
                         ([good, f'{sub}.reliability:='],
                          f'cannot start: {sub}.reliability: need one of reliable, '
                          'best_effort, best_available, system_default, got nothing'),
                         ([good, 'robot_description:='],
                          'cannot start: robot_description: no value after :='),
                         # other policies were ignored without a word
                         ([good, f'{sub}.durability:=forever'],
                          f"cannot start: {sub}.durability: the subscription of "
                          "'/desired_joint_states' takes overrides of history, depth, "
                          "reliability only, got 'forever'"),
                         ([good, f'{sub}.deadline:=-1'],
                          f'cannot start: {sub}.deadline: the subscription'),
                         ([good, 'qos_overrides./effort_commands.publisher.depth:=-3'],
                          'cannot start: qos_overrides./effort_commands.publisher.depth: '
                          'need an integer from 0 to 2147483647 (messages queued), got -3'),
                         ([good, 'qos_overrides./feedforward_efforts.publisher.lifespan:=5'],
                          'publisher.lifespan: the publisher of')]:
        command = [install.executable, '--ros-args']
        for arg in args:
            command += ['-p', arg]
        proc = subprocess.run(command, env=install.env(), capture_output=True, text=True,
                              timeout=TIMEOUT)
        assert proc.returncode == 1, proc
        said = proc.stderr + proc.stdout
        assert 'cannot start' in said, proc
        parts = expect if isinstance(expect, tuple) else (expect,)
        assert all(part in said for part in parts), proc
        assert 'Traceback' not in proc.stderr
        if any(arg.startswith('qos_overrides.') or arg.endswith(':=') for arg in args):
            for noise in ('rcutils', 'error not set', 'Trying to set parameter', '.c:',
                          'warnings.warn', 'middleware'):
                assert noise not in said, (noise, proc)
        assert said.count('cannot start') == 1, proc


@pytest.mark.ros
def test_good_qos_overrides_start_and_depth_0_is_said_once(install, tmp_path):
    """Depth 0 (keep last: the middleware's default) is one INFO line, not rclpy's warning.

    An override for a topic the node does not have stays ignored; best_available (Jazzy's)
    is a reliability the middleware takes.
    """
    node = NodeProcess(install, [
        '-p', f'robot_description_file:={DEMO_URDF}',
        '-p', 'qos_overrides./effort_commands.publisher.depth:=0',
        '-p', 'qos_overrides./desired_joint_states.subscription.reliability:=best_available',
        '-p', 'qos_overrides./not_ours.subscription.durability:=forever'], str(tmp_path))
    try:
        log = node.wait_for_log('real-time:')
        assert node.proc.poll() is None, log
    finally:
        assert node.stop() == 0
    log = node.log()
    assert log.count("qos_overrides./effort_commands.publisher.depth: 0 with keep_last is "
                     "the middleware's default depth") == 1, log
    assert 'UserWarning' not in log and 'warnings.warn' not in log, log


START_UP_SIGNALLED = """
import sys, time
import rclpy
from rclpy.node import Node
from sensor_msgs.msg import JointState
from spatial_dynamics.ros.common import advertise, spin

def make_node():
    node = Node('starting')
    node.get_logger().info('making the endpoints')
    deadline = time.monotonic() + 60.0
    while rclpy.ok() and time.monotonic() < deadline:   # until the signal shuts it down
        time.sleep(0.01)
    advertise(node, JointState, 'joint_states')
    return node

sys.exit(spin(make_node, name='starting'))
"""


@pytest.mark.ros
@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM], ids=['SIGINT', 'SIGTERM'])
def test_a_signal_while_the_node_is_made_is_a_clean_exit(install, tmp_path, sig):
    """A signal while making the endpoints: exit 0, one INFO line, never a QoS refusal.

    Before, rcl refusing a publisher on the context the signal had shut down was turned into
    ``cannot start: the middleware refused the QoS of publisher ...`` and exit 1 (seen with
    the simulator's /joint_states and the node's /feedforward_efforts at ~1 s).
    """
    script = tmp_path / 'starting.py'
    script.write_text(START_UP_SIGNALLED)
    log_path = tmp_path / 'starting.log'
    with open(log_path, 'w') as log:
        proc = subprocess.Popen([sys.executable, str(script)], env=install.env(),
                                stdout=log, stderr=subprocess.STDOUT)
    try:
        deadline = time.monotonic() + TIMEOUT
        while 'making the endpoints' not in log_path.read_text():
            assert proc.poll() is None and time.monotonic() < deadline, log_path.read_text()
            time.sleep(0.05)
        proc.send_signal(sig)
        status = proc.wait(TIMEOUT)
    finally:
        proc.kill()
        proc.wait()
    said = log_path.read_text()
    assert status == 0, (status, said)
    assert said.count('interrupted while starting') == 1, said
    assert 'cannot start' not in said and 'Traceback' not in said, said


@pytest.mark.ros
def test_description_from_topic_then_rejected_update(install, driver, tmp_path):
    """No parameter: waits (warning, ERROR diagnostics, inputs rejected), then the topic."""
    node = NodeProcess(install, [], str(tmp_path))
    io = Io(driver)
    try:
        io.wait_connected()
        node.wait_for_log('no robot model')
        status = io.fresh_status('robot model')
        assert status.level == DiagnosticStatus.ERROR and 'waiting' in status.message
        model = sd.Model.from_urdf(DEMO_URDF)
        names = model.joint_names
        states = random_states(21, 50, len(names))
        for k in range(5):
            io.joint_states.publish(joint_state(names, *states[k], k))
            driver.spin_for(0.05)
        kv = values(io.fresh_status('feedforward'))
        assert int(kv['rejected no_model']) >= 1 and not io.efforts

        from std_msgs.msg import String
        with open(DEMO_URDF) as f:
            io.description.publish(String(data=f.read()))
        node.wait_for_log("robot 'demo_arm' from topic robot_description")
        io.publish_until_answered(lambda k: joint_state(names, *states[10], k), 0.05)
        np.testing.assert_allclose(io.efforts[-1].effort, sd.rnea(model, *states[10]),
                                   rtol=0, atol=1e-9)

        io.description.publish(String(data='<robot name="half">'))
        node.wait_for_log('robot description rejected, keeping the current model')
        before = len(io.efforts)
        io.joint_states.publish(joint_state(names, *states[49], 49))
        driver.spin_until(lambda: len(io.efforts) > before, what='answer after a bad update')
        np.testing.assert_allclose(io.efforts[-1].effort, sd.rnea(model, *states[49]),
                                   rtol=0, atol=1e-9)
        status = io.fresh_status('robot model')
        kv = values(status)
        assert status.level == DiagnosticStatus.OK and kv['source'] == 'topic robot_description'
        assert kv['descriptions rejected'] == '1' and 'topic robot_description' in \
            kv['last rejection']
    finally:
        io.close()
        assert node.stop() == 0


@pytest.mark.ros
def test_parameter_file_and_xacro(install, driver, tmp_path):
    """The shipped yaml loads; a .xacro file is expanded (xacro is a test requirement)."""
    import xacro  # noqa: F401
    description = tmp_path / 'arm.urdf.xacro'
    with open(DEMO_URDF) as f:
        text = f.read()
    assert '<robot name="demo_arm">' in text and '<mass value="0.6"/>' in text
    text = text.replace('<robot name="demo_arm">',
                        '<robot name="demo_arm" xmlns:xacro="http://www.ros.org/wiki/xacro">'
                        '<xacro:property name="hand_mass" value="0.6"/>')
    text = text.replace('<mass value="0.6"/>', '<mass value="${hand_mass}"/>')
    description.write_text(text)
    node = NodeProcess(install, ['--params-file', YAML,
                                 '-p', f'robot_description_file:={description}',
                                 '-p', 'gravity:=[0.0, -9.81, 0.0]'], str(tmp_path))
    io = Io(driver)
    try:
        io.wait_connected()
        model = sd.Model.from_urdf(DEMO_URDF)
        names = model.joint_names
        state = random_states(22, 1, len(names))[0]
        io.publish_until_answered(lambda k: joint_state(names, *state, k), 0.05)
        np.testing.assert_allclose(io.efforts[-1].effort,
                                   sd.rnea(model, *state, gravity=(0.0, -9.81, 0.0)),
                                   rtol=0, atol=1e-9)
        kv = values(io.fresh_status('feedforward'))
        assert kv['acceleration source'] == 'effort' and kv['input timeout [s]'] == '0.5'
    finally:
        io.close()
        assert node.stop() == 0


@pytest.mark.ros
def test_qos_override_changes_its_own_topic_only():
    """qos_overrides.<topic>... reach that subscription, and only that one."""
    import rclpy
    from rclpy.qos import ReliabilityPolicy
    from spatial_dynamics.ros.node import InverseDynamicsNode
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=DOMAIN_ID, args=[
        '--ros-args', '-r', '__ns:=/qos_test', '-p', f'robot_description_file:={DEMO_URDF}',
        '-p', 'qos_overrides./qos_test/desired_joint_states.subscription.depth:=5',
        '-p', 'qos_overrides./qos_test/effort_commands.publisher.depth:=3'])
    node = InverseDynamicsNode(context=context)
    try:
        subscriptions = {s.topic_name: s.qos_profile for s in node.subscriptions}
        publishers = {p.topic_name: p.qos_profile for p in node.publishers}
        assert subscriptions['/qos_test/desired_joint_states'].depth == 5
        assert subscriptions['/qos_test/desired_joint_states'].reliability == \
            ReliabilityPolicy.BEST_EFFORT
        plans = subscriptions['/qos_test/desired_trajectory']   # plan_qos(), untouched
        assert (plans.depth, plans.reliability) == (10, ReliabilityPolicy.RELIABLE)
        assert publishers['/qos_test/effort_commands'].depth == 3
        assert publishers['/qos_test/feedforward_efforts'].depth == 10
        for topic in ('/qos_test/effort_commands', '/qos_test/feedforward_efforts'):
            assert publishers[topic].reliability == ReliabilityPolicy.RELIABLE
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=context)
