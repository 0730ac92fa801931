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
node refused, a message type or field that does not exist, a bad node or topic name), 2 bad
usage, 130 on Ctrl-C and 143 on SIGTERM (one line, no traceback).
"""

from __future__ import annotations

import argparse
import importlib
import math
import signal
import sys
import time
from typing import Any, Optional, Sequence

from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
from rcl_interfaces.srv import GetParameterTypes, SetParameters
import rclpy
from rclpy.exceptions import NameValidationException
from rclpy.parameter import get_parameter_value
from rclpy.signals import SignalHandlerOptions
from rclpy.validate_topic_name import validate_topic_name
import yaml

#: The rates ``topic pub`` accepts, Hz.
RATES = (1e-3, 1e4)
#: The empty value of each array parameter type: ``[]`` takes the type the node declared.
EMPTY = {ParameterType.PARAMETER_BYTE_ARRAY: 'byte_array_value',
         ParameterType.PARAMETER_BOOL_ARRAY: 'bool_array_value',
         ParameterType.PARAMETER_INTEGER_ARRAY: 'integer_array_value',
         ParameterType.PARAMETER_DOUBLE_ARRAY: 'double_array_value',
         ParameterType.PARAMETER_STRING_ARRAY: 'string_array_value'}


class Interrupted(Exception):
    """SIGINT or SIGTERM arrived: the command stops with 128 + the signal's number."""

    def __init__(self, signum: int):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def _interrupted(signum: int, frame) -> None:
    raise Interrupted(signum)


def seconds(text: str) -> float:
    """Return a timeout in seconds: a finite number above 0 (argparse type)."""
    value = float(text)
    if not (math.isfinite(value) and value > 0.0):
        raise argparse.ArgumentTypeError(f'a finite number of seconds above 0, got {text}')
    return value


def count(text: str) -> int:
    """Return a number of messages: an integer of at least 1 (argparse type)."""
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f'at least 1 message, got {text}')
    return value


def rate(text: str) -> float:
    """Return a rate in Hz within :data:`RATES` (argparse type)."""
    value = float(text)
    if not RATES[0] <= value <= RATES[1]:
        raise argparse.ArgumentTypeError(
            f'a rate in Hz from {RATES[0]:g} to {RATES[1]:g}, got {text}')
    return value


def check_name(name: str, what: str) -> None:
    """Raise ``ValueError`` naming ``what`` if ``name`` is no valid ROS topic/service name."""
    try:
        validate_topic_name(name)
    except NameValidationException as err:
        raise ValueError(f'{what} {name!r}: {" ".join(str(err).split()[:-1])}') from None


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
    put.add_argument('--timeout', type=seconds, default=10.0,
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
    pub.add_argument('--rate', '-r', type=rate, default=1.0,
                     help=f'publish at this rate, Hz ({RATES[0]:g} to {RATES[1]:g}), until '
                     'Ctrl-C (default %(default)s)')
    pub.add_argument('--times', '-t', type=count, default=0,
                     help='publish this many times (at least 1) and exit (default: until '
                     'Ctrl-C)')
    pub.add_argument('--timeout', type=seconds, default=5.0,
                     help='seconds to wait for a subscriber before the first message '
                     '(default %(default)s)')
    return p.parse_args(argv)


def message_type(name: str):
    """Return the message class of ``pkg/msg/Type`` (or ``pkg/Type``)."""
    parts = name.split('/')
    if len(parts) == 2:
        parts = [parts[0], 'msg', parts[1]]
    if len(parts) != 3 or not all(part.isidentifier() for part in parts):
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
            continue
        try:
            if isinstance(current, bool):
                setattr(message, key, bool(value))
            elif isinstance(current, (int, float, str)):
                setattr(message, key, type(current)(value))
            elif isinstance(value, (list, tuple, bytes)):   # sequences and arrays: a list
                setattr(message, key, value)
            else:
                raise TypeError(key)
        except (AssertionError, TypeError, ValueError, OverflowError):
            raise ValueError(f'{name}: {value!r} is not a {fields[key]}') from None
    return message


def parameter_value(node, node_name: str, name: str, text: str,
                    timeout: float) -> ParameterValue:
    """Return ``text`` read as ros2 param set reads it; ``[]`` as the declared array type.

    A value YAML reads as no parameter type (a mapping, binary, a date) is sent as the text.
    """
    try:
        value = get_parameter_value(text)
    except yaml.YAMLError:
        value = ParameterValue(type=ParameterType.PARAMETER_STRING, string_value=text)
    if value.type == ParameterType.PARAMETER_STRING and not isinstance(value.string_value, str):
        # rclpy puts what YAML read there (a dict, bytes, a date): send the text instead
        value = ParameterValue(type=ParameterType.PARAMETER_STRING, string_value=text)
    if value.type in EMPTY and not len(getattr(value, EMPTY[value.type])):
        client = node.create_client(GetParameterTypes, node_name.rstrip('/')
                                    + '/get_parameter_types')
        if client.wait_for_service(timeout_sec=timeout):
            future = client.call_async(GetParameterTypes.Request(names=[name]))
            rclpy.spin_until_future_complete(node, future, timeout_sec=timeout)
            declared = future.result().types[0] if future.result() is not None else None
            if declared in EMPTY:
                value = ParameterValue(type=declared)
    return value


def set_parameter(node_name: str, name: str, text: str, timeout: float) -> int:
    """Send one SetParameters request; print the node's answer; return the exit status."""
    if node_name.strip('/') == '':
        raise ValueError(f'node name {node_name!r}: empty')
    service = node_name.rstrip('/') + '/set_parameters'
    check_name(service, 'node name')
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    try:
        node = rclpy.create_node('ros_cli_param')
        client = node.create_client(SetParameters, service)
        if not client.wait_for_service(timeout_sec=timeout):
            print(f'error: no node {node_name} ({service} not found within {timeout:g} s)',
                  file=sys.stderr)
            return 1
        request = SetParameters.Request(parameters=[Parameter(
            name=name, value=parameter_value(node, node_name, name, text, timeout))])
        future = client.call_async(request)
        rclpy.spin_until_future_complete(node, future, timeout_sec=timeout)
        if future.result() is None:
            print(f'error: {node_name} did not answer within {timeout:g} s', file=sys.stderr)
            return 1
        result = future.result().results[0]
        if not result.successful:
            print(f'Setting parameter {name} failed: {result.reason}', file=sys.stderr)
            return 1
        print('Set parameter successful')
        return 0
    finally:
        rclpy.try_shutdown()


def publish(topic: str, kind: str, text: str, once: bool, rate: float, times: int,
            timeout: float) -> int:
    """Publish the message ``text`` (YAML) of type ``kind`` on ``topic``; return 0."""
    check_name(topic, 'topic')
    cls = message_type(kind)
    message = fill(cls(), yaml.safe_load(text))
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
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
    finally:
        rclpy.try_shutdown()


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run ``param set`` or ``topic pub``; return the exit status."""
    args = parse_args(argv)
    handlers = {signum: signal.signal(signum, _interrupted)
                for signum in (signal.SIGINT, signal.SIGTERM)}
    try:
        if args.verb == 'param':
            return set_parameter(args.node, args.name, args.value, args.timeout)
        return publish(args.topic, args.type, args.values, args.once, args.rate, args.times,
                       args.timeout)
    except (ValueError, yaml.YAMLError, NameValidationException) as err:
        print(f'error: {" ".join(str(err).split())}', file=sys.stderr)
        return 1
    except Interrupted as err:
        print(f'interrupted ({err})', file=sys.stderr)
        return 128 + err.signum
    finally:
        for signum, handler in handlers.items():
            signal.signal(signum, handler)


if __name__ == '__main__':
    sys.exit(main())
