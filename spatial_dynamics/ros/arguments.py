# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A node's command line split into the program's and ROS's arguments (no rclpy import).

Used by :mod:`.usage` (``--help``, unknown options) and :func:`.common.spin` (the
``--params-file`` files and the ``-p`` rules checked before ``rclpy.init``); a module of its
own so that neither imports the other.
"""

from __future__ import annotations

from typing import List, Optional, Sequence, Tuple

#: The options of rcl's ``--ros-args`` that take the next argument as their value.
ROS_VALUE_OPTIONS = ('-p', '--param', '-r', '--remap', '-e', '--enclave', '--params-file',
                     '--log-level', '--log-config-file', '--log-file-name')


def split_args(argv: Sequence[str]) -> Tuple[List[str], List[Tuple[str, Optional[str]]]]:
    """Split a command line (without the program) into the program's and ROS's arguments.

    ROS's are those of each ``--ros-args`` block, up to ``--`` or the end, as (option, value)
    pairs (value None for an option without one, such as ``--help``).
    """
    program: List[str] = []
    ros: List[Tuple[str, Optional[str]]] = []
    args = iter(argv)
    inside = False
    for arg in args:
        if arg == '--ros-args':
            inside = True
        elif inside and arg == '--':
            inside = False
        elif inside:
            ros.append((arg, next(args, None) if arg in ROS_VALUE_OPTIONS else None))
        else:
            program.append(arg)
    return program, ros


def params_files(argv: Sequence[str]) -> List[str]:
    """Return the files of the ``--params-file`` options in ``argv``'s ``--ros-args``."""
    return [value for option, value in split_args(argv)[1]
            if option == '--params-file' and value is not None]


def empty_param_rules(argv: Sequence[str]) -> List[Tuple[str, str]]:
    """Return each ``-p``/``--param`` rule of ``argv``'s ``--ros-args`` without a value.

    As (parameter name, rule) pairs: ``-p name:=`` and ``-p node:name:=`` (also with only
    blanks after ``:=``). rcl refuses them at ``rclpy.init`` with ``Error: error not set``.
    """
    empty = []
    for option, rule in split_args(argv)[1]:
        if option in ('-p', '--param') and rule is not None and ':=' in rule:
            head, _, value = rule.partition(':=')
            if not value.strip():
                empty.append((head.split(':')[-1], rule))
    return empty
