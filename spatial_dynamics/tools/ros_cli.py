# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
r"""``ros2 param set`` and ``ros2 topic pub`` for the route without a ROS installation.

    python -m spatial_dynamics.tools.ros_cli param set /inverse_dynamics payload.mass 1.5
    python -m spatial_dynamics.tools.ros_cli topic pub /external_wrenches \
        geometry_msgs/msg/WrenchStamped "{header: {frame_id: hand}, wrench: {force: {z: -9.81}}}"

The quick start's venv has rclpy and the message packages as wheels, but not ros2cli (it is
not on PyPI), so the docs' ``ros2 param set`` and ``ros2 topic pub`` had no equivalent there.
These two take the same arguments as theirs (a subset of the options): a value is read as
ros2 reads it (YAML: ``1.5`` a double, ``"[0.0, 0.0, 9.81]"`` a double array, ``true`` a bool,
anything else a string), a message from its YAML form, each field converted to the field's
own type (an integer given for a float field is a float). Where ros2cli is installed, the
``ros2`` commands do the same.

Exit status: 0 done, 1 refused (no such node or service within ``--timeout``, a value the
node refused, a message type or field that does not exist), 2 bad usage.
"""

from __future__ import annotations

import argparse
import importlib
import sys
import time
from typing import Any, Optional, Sequence

from rcl_interfaces.msg import Parameter
from rcl_interfaces.srv import SetParameters
import rclpy
from rclpy.parameter import get_parameter_value
import yaml


def parse_args(argv: Optional[Sequence[str]]) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog='python -m spatial_dynamics.tools.ros_cli',
                                description=__doc__.split('\n\n')[0])
    sub = p.add_subparsers(dest='verb', required=True)
    param = sub.add_parser('param', help='parameters of a running node')
    param_sub = param.add_subparsers(dest='action', required=True)
    put = param_sub.add_parser('set', help='set one parameter, as ros2 param set does')
    put.add_argument('node', help='the node, e.g. /inverse_dynamics')
    put.add_argument('name', help='the parameter, e.g. payload.mass')
    put.add_argument('value', help='the value, read as YAML (1.5, "[0.0, 0.0, 9.81]", true, '
                     'a string)')
    put.add_argument('--timeout', type=float, default=10.0,
                     help='seconds to wait for the node (default %(default)s)')
    topic = sub.add_parser('topic', help='publish on a topic')
    topic_sub = topic.add_subparsers(dest='action', required=True)
    pub = topic_sub.add_parser('pub', help='publish a message, as ros2 topic pub does')
    pub.add_argument('topic', help='the topic, e.g. /external_wrenches')
    pub.add_argument('type', help='the message type, e.g. geometry_msgs/msg/WrenchStamped')
    pub.add_argument('values', nargs='?', default='{}',
                     help='the message in YAML, fields left out are zero (default {})')
    pub.add_argument('--once', '-1', action='store_true',
                     help='publish once (after a subscriber matched, or --timeout) and exit')
    pub.add_argument('--rate', '-r', type=float, default=1.0,
                     help='publish at this rate, Hz, until Ctrl-C (default %(default)s)')
    pub.add_argument('--times', '-t', type=int, default=0,
                     help='publish this many times and exit (default: until Ctrl-C)')
    pub.add_argument('--timeout', type=float, default=5.0,
                     help='seconds to wait for a subscriber before the first message '
                     '(default %(default)s)')
    args = p.parse_args(argv)
    if args.action == 'pub' and not (args.rate > 0.0 and args.rate <= 1e4):
        p.error(f'--rate: a rate in Hz above 0 and at most 10000, got {args.rate}')
    return args


def message_type(name: str):
    """Return the message class of ``pkg/msg/Type`` (or ``pkg/Type``)."""
    parts = name.split('/')
    if len(parts) == 2:
        parts = [parts[0], 'msg', parts[1]]
    if len(parts) != 3 or not all(parts):
        raise ValueError(f'message type {name!r}: expected package/msg/Type')
    try:
        return getattr(importlib.import_module(f'{parts[0]}.{parts[1]}'), parts[2])
    except (ImportError, AttributeError):
        raise ValueError(f'message type {name!r} is not installed') from None


def fill(message: Any, values: Any, where: str = '') -> Any:
    """Set the fields of ``message`` from a mapping, each to its field's type; return it."""
    if values is None:
        return message
    if not isinstance(values, dict):
        raise ValueError(f'{where or "the message"}: a mapping of fields, got {values!r}')
    fields = message.get_fields_and_field_types()
    for key, value in values.items():
        name = f'{where}.{key}' if where else key
        if key not in fields:
            raise ValueError(f'{name}: no such field of {type(message).__name__} '
                             f'(fields: {", ".join(fields)})')
        current = getattr(message, key)
        if hasattr(current, 'get_fields_and_field_types'):
            fill(current, value, name)
        elif isinstance(current, bool):
            setattr(message, key, bool(value))
        elif isinstance(current, (int, float, str)):
            setattr(message, key, type(current)(value))
        else:                          # sequences and arrays take a list as it is
            setattr(message, key, value)
    return message


def set_parameter(node_name: str, name: str, text: str, timeout: float) -> int:
    """Send one SetParameters request; print the node's answer; return the exit status."""
    rclpy.init()
    try:
        node = rclpy.create_node('ros_cli_param')
        service = node_name.rstrip('/') + '/set_parameters'
        client = node.create_client(SetParameters, service)
        if not client.wait_for_service(timeout_sec=timeout):
            print(f'error: no node {node_name} ({service} not found within {timeout:g} s)',
                  file=sys.stderr)
            return 1
        request = SetParameters.Request(
            parameters=[Parameter(name=name, value=get_parameter_value(text))])
        future = client.call_async(request)
        rclpy.spin_until_future_complete(node, future, timeout_sec=timeout)
        if future.result() is None:
            print(f'error: {node_name} did not answer within {timeout:g} s', file=sys.stderr)
            return 1
        result = future.result().results[0]
        if not result.successful:
            print(f'Setting parameter failed: {result.reason}', file=sys.stderr)
            return 1
        print('Set parameter successful')
        return 0
    finally:
        rclpy.try_shutdown()


def publish(topic: str, kind: str, text: str, once: bool, rate: float, times: int,
            timeout: float) -> int:
    """Publish the message ``text`` (YAML) of type ``kind`` on ``topic``; return 0."""
    cls = message_type(kind)
    message = fill(cls(), yaml.safe_load(text))
    rclpy.init()
    try:
        node = rclpy.create_node('ros_cli_pub')
        publisher = node.create_publisher(cls, topic, 10)
        deadline = time.monotonic() + timeout
        while publisher.get_subscription_count() == 0 and time.monotonic() < deadline:
            time.sleep(0.05)
        count = 1 if once else times
        sent = 0
        while rclpy.ok() and (count == 0 or sent < count):
            publisher.publish(message)
            sent += 1
            print(f'publishing #{sent}: {message}')
            if count and sent >= count:
                break
            time.sleep(1.0 / rate)
        time.sleep(0.2)                    # let the last message leave before the node goes
        return 0
    except KeyboardInterrupt:
        return 0
    finally:
        rclpy.try_shutdown()


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run ``param set`` or ``topic pub``; return the exit status."""
    args = parse_args(argv)
    try:
        if args.verb == 'param':
            return set_parameter(args.node, args.name, args.value, args.timeout)
        return publish(args.topic, args.type, args.values, args.once, args.rate, args.times,
                       args.timeout)
    except (ValueError, yaml.YAMLError) as err:
        print(f'error: {" ".join(str(err).split())}', file=sys.stderr)
        return 1


if __name__ == '__main__':
    sys.exit(main())
