# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The nodes' command lines: ``-h``/``--help`` and unknown options, before ROS starts.

rclpy takes an argument it does not know (``--help``, ``--bogus``) before ``--ros-args`` as
the program's and starts the node anyway, and refuses one after it with a traceback
(``UnknownROSArgsError``). :func:`launch` answers both before rclpy is imported: ``-h`` or
``--help`` anywhere prints the usage and returns 0; any other argument outside the
``--ros-args`` blocks is one ``cannot start: unknown option`` line and status 2. :func:`main`
is the ``inverse_dynamics`` command (the node is imported inside it, so the usage never pays
for rclpy's start-up).
"""

from __future__ import annotations

import sys
import textwrap
from typing import Callable, Optional, Sequence

from spatial_dynamics.ros.arguments import split_args
from spatial_dynamics.ros.config import PARAMETERS
from spatial_dynamics.ros.parameters import number_text, Table

HELP = ('-h', '--help')
WIDTH = 99


def help_requested(argv: Sequence[str]) -> bool:
    """Return whether ``-h``/``--help`` is among the arguments, before or after ``--ros-args``."""
    program, ros = split_args(argv)
    return any(arg in HELP for arg in program + [option for option, _ in ros])


def usage(table: Table, summary: str, page: str) -> str:
    """Return the usage of node ``table.node``: how to set parameters, each one, the docs."""
    lines = [f'usage: {table.node} [--ros-args [-p NAME:=VALUE]... [-r FROM:=TO]... '
             f'[--params-file FILE]]', '', textwrap.fill(summary, WIDTH), '']
    topics = table.header.split('\n\n')[2:]    # after the licence and the file's origin
    lines += [*topics, ''] if topics else []
    lines += ['parameters (type; default, unit; range or values; read-only):']
    for p in table:
        default = 'unset' if p.default is None else repr(
            list(p.default) if isinstance(p.default, tuple) else p.default)
        unit = f', {p.unit}' if p.unit else ''
        notes = [p.type, f'default {default}{unit}']
        if p.bounds is not None:
            each = ' each' if '[]' in p.type else ''
            notes.append(f'{number_text(p.bounds[0])} .. {number_text(p.bounds[1])}{each}')
        if p.choices:
            notes.append('one of ' + ', '.join(map(str, p.choices)))
        if p.read_only:
            notes.append('read-only')
        lines += textwrap.wrap(f'{p.name} ({"; ".join(notes)})', WIDTH, initial_indent='  ',
                               subsequent_indent=' ' * 6)
        lines += textwrap.wrap(p.description, WIDTH, initial_indent=' ' * 6,
                               subsequent_indent=' ' * 6, break_on_hyphens=False)
    lines += ['', textwrap.fill(
        f'Every parameter in full, the topics and their QoS: {page} in the source tree; the '
        f'parameter file: share/spatial_dynamics/config/{table.node}.yaml of the install.',
        WIDTH)]
    return '\n'.join(lines) + '\n'


def launch(argv: Optional[Sequence[str]], table: Table, summary: str, page: str,
           run: Callable[[], int]) -> int:
    """Print the usage for ``-h``/``--help``, refuse an unknown option, or return ``run()``.

    ``argv``: the command line without the program (None: ``sys.argv[1:]``). An argument
    outside the ``--ros-args`` blocks is none of the node's: one ``cannot start: unknown
    option`` line on stderr and status 2, nothing started.
    """
    args = sys.argv[1:] if argv is None else list(argv)
    if help_requested(args):
        sys.stdout.write(usage(table, summary, page))
        return 0
    program = split_args(args)[0]
    if program:
        print(f'{table.node}: cannot start: unknown option {program[0]!r} (the parameters '
              'go after --ros-args; see --help)', file=sys.stderr)
        return 2
    return run()


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the ``inverse_dynamics`` node, or print its usage for ``-h``/``--help``."""
    def run() -> int:
        from spatial_dynamics.ros.node import main as node
        return node(argv)

    return launch(argv, PARAMETERS, 'Inverse dynamics node: desired joint states or whole '
                  'plans in, feed-forward joint efforts out (ros2_control), on a fixed, moving '
                  'or floating base.', 'doc/node.md', run)
