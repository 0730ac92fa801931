# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The nodes' ``-h``/``--help``: their usage from the parameter table, before ROS starts.

rclpy takes an argument it does not know (``--help``) as the program's and starts the node
anyway; ``inverse_dynamics --help`` used to start it. :func:`main` is the
``inverse_dynamics`` command: with ``-h`` or ``--help`` before ``--ros-args`` (after it they
are ROS's) it prints the usage and returns 0 without importing rclpy; otherwise it runs the
node (imported here, inside :func:`main`, so the usage never pays for rclpy's start-up).
"""

from __future__ import annotations

import sys
import textwrap
from typing import Optional, Sequence

from spatial_dynamics.ros.config import PARAMETERS
from spatial_dynamics.ros.parameters import Table

HELP = ('-h', '--help')
WIDTH = 99


def help_requested(argv: Sequence[str]) -> bool:
    """Return whether ``-h``/``--help`` is among the arguments before ``--ros-args``."""
    args = list(argv)
    if '--ros-args' in args:
        args = args[:args.index('--ros-args')]
    return any(arg in HELP for arg in args)


def usage(table: Table, summary: str, page: str) -> str:
    """Return the usage of node ``table.node``: how to set parameters, each one, the docs."""
    lines = [f'usage: {table.node} [--ros-args [-p NAME:=VALUE]... [-r FROM:=TO]... '
             f'[--params-file FILE]]', '', textwrap.fill(summary, WIDTH), '']
    topics = table.header.split('\n\n')[2:]    # after the licence and the file's origin
    lines += [*topics, ''] if topics else []
    lines += ['parameters (type, default, unit):']
    for p in table:
        default = 'unset' if p.default is None else repr(
            list(p.default) if isinstance(p.default, tuple) else p.default)
        unit = f', {p.unit}' if p.unit else ''
        lines.append(f'  {p.name} ({p.type}, default {default}{unit})')
        first = p.description.split('. ')[0].rstrip('.') + '.'
        lines += textwrap.wrap(first, WIDTH, initial_indent=' ' * 6, subsequent_indent=' ' * 6)
    lines += ['', textwrap.fill(
        f'Every parameter in full, the topics and their QoS: {page} in the source tree; the '
        f'parameter file: share/spatial_dynamics/config/{table.node}.yaml of the install.',
        WIDTH)]
    return '\n'.join(lines) + '\n'


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the ``inverse_dynamics`` node, or print its usage for ``-h``/``--help``."""
    if help_requested(sys.argv[1:] if argv is None else argv):
        sys.stdout.write(usage(
            PARAMETERS, 'Inverse dynamics node: desired joint states or whole plans in, '
            'feed-forward joint efforts out (ros2_control), on a fixed, moving or floating '
            'base.', 'doc/node.md'))
        return 0
    from spatial_dynamics.ros.node import main as run
    return run(argv)
