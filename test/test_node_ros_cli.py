# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""``python -m spatial_dynamics.tools.ros_cli``: ros2's param set and topic pub without ros2cli.

Where ros2cli is not installed (the quick start's venv), against a node in this process.
"""

import os
import signal
import subprocess
import sys

import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from node_harness import DOMAIN_ID, ROOT  # noqa: E402
from spatial_dynamics.tools.ros_cli import fill, message_type  # noqa: E402

pytestmark = pytest.mark.ros


def ros_cli(driver, *args):
    """Run the command while ``driver`` spins; return the finished process."""
    env = dict(os.environ, ROS_DOMAIN_ID=str(DOMAIN_ID),
               PYTHONPATH=os.pathsep.join([ROOT, os.environ.get('PYTHONPATH', '')]))
    proc = subprocess.Popen([sys.executable, '-m', 'spatial_dynamics.tools.ros_cli', *args],
                            cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    driver.spin_until(lambda: proc.poll() is not None, what='ros_cli to finish')
    out, err = proc.communicate()
    return proc.returncode, out, err


@pytest.fixture(scope='module')
def target(driver):
    """Yield a node with two parameters and a WrenchStamped subscription, spun by ``driver``."""
    from geometry_msgs.msg import WrenchStamped
    node = driver.rclpy.create_node(f'ros_cli_target_{os.getpid()}', context=driver.context)
    node.declare_parameter('gravity', [0.0, 0.0, -9.81])
    node.declare_parameter('payload.link', 'hand')
    node.received = []
    node.create_subscription(WrenchStamped, 'ros_cli_wrenches', node.received.append, 10)

    driver.executor.add_node(node)
    yield node
    driver.executor.remove_node(node)
    node.destroy_node()


def test_param_set_sets_the_value_as_ros2_reads_it(driver, target):
    name = target.get_fully_qualified_name()
    status, out, err = ros_cli(driver, 'param', 'set', name, 'gravity', '[0.0, 0.0, 9.81]')
    assert status == 0 and 'successful' in out, err
    assert list(target.get_parameter('gravity').value) == [0.0, 0.0, 9.81]
    status, out, err = ros_cli(driver, 'param', 'set', name, 'payload.link', '')
    assert status == 0, err
    assert target.get_parameter('payload.link').value == ''
    status, out, err = ros_cli(driver, 'param', 'set', name, 'gravity', '3')
    assert status == 1 and 'Setting parameter gravity failed' in err and 'INTEGER' in err


def test_param_set_of_empty_lists_mappings_and_unknown_names(driver, target):
    name = target.get_fully_qualified_name()
    # [] takes the declared type (a double array), as the node's armature: [] needs
    status, out, err = ros_cli(driver, 'param', 'set', name, 'gravity', '[]')
    assert status == 0 and 'successful' in out, err
    assert list(target.get_parameter('gravity').value) == []
    # what YAML reads as no parameter type is sent as the string, as ros2 param set does
    for text in ('{a: 1}', '!!binary aGk='):
        status, out, err = ros_cli(driver, 'param', 'set', name, 'payload.link', text)
        assert status == 0 and 'Traceback' not in err, err
        assert target.get_parameter('payload.link').value == text
    status, out, err = ros_cli(driver, 'param', 'set', name, 'no_such_parameter', '1')
    assert status == 1 and 'no_such_parameter' in err and 'Traceback' not in err, err


@pytest.mark.parametrize('signum', [signal.SIGINT, signal.SIGTERM])
def test_topic_pub_stops_on_a_signal_without_a_traceback(driver, target, signum):
    env = dict(os.environ, ROS_DOMAIN_ID=str(DOMAIN_ID),
               PYTHONPATH=os.pathsep.join([ROOT, os.environ.get('PYTHONPATH', '')]))
    from geometry_msgs.msg import WrenchStamped
    received = []
    topic = f'ros_cli_signal_{signum}'
    subscription = target.create_subscription(WrenchStamped, topic, received.append, 10)
    proc = subprocess.Popen([sys.executable, '-m', 'spatial_dynamics.tools.ros_cli', 'topic',
                             'pub', '-r', '20', '/' + topic,
                             'geometry_msgs/msg/WrenchStamped'], cwd=ROOT, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        driver.spin_until(lambda: received, what='a published wrench')
        proc.send_signal(signum)
        driver.spin_until(lambda: proc.poll() is not None, what='ros_cli to stop')
    finally:
        target.destroy_subscription(subscription)
        proc.kill()
    _, err = proc.communicate()
    assert proc.returncode == 128 + signum, err
    assert 'Traceback' not in err, err


def test_param_set_of_a_missing_node_is_refused_in_time(driver):
    status, _, err = ros_cli(driver, 'param', 'set', '/no_such_node', 'x', '1', '--timeout', '1')
    assert status == 1 and 'no node /no_such_node' in err


def test_topic_pub_once_delivers_the_message(driver, target):
    status, _, err = ros_cli(driver, 'topic', 'pub', '--once', '/ros_cli_wrenches',
                             'geometry_msgs/msg/WrenchStamped',
                             '{header: {frame_id: hand}, wrench: {force: {z: -19}}}')
    assert status == 0, err
    driver.spin_until(lambda: target.received, what='the published wrench')
    message = target.received[0]
    assert message.header.frame_id == 'hand'
    assert (message.wrench.force.z, message.wrench.force.x) == (-19.0, 0.0)


def test_a_field_or_type_that_does_not_exist_is_named():
    from geometry_msgs.msg import WrenchStamped
    with pytest.raises(ValueError, match='wrench.forse: no such field'):
        fill(WrenchStamped(), {'wrench': {'forse': {'z': 1.0}}})
    with pytest.raises(ValueError, match='not installed'):
        message_type('geometry_msgs/msg/NoSuchType')
