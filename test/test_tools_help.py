# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Every command's ``--help`` says what each option is, and its default.

Each tool's own parser is taken as its ``main`` builds it (``parse_args`` stops it there, so
nothing runs); every option has a help text, and an option with a default (other than
off, empty or none) shows it in that text as ``--help`` prints it. ``fleet_demo --days``
printed no text at all.
"""

import argparse
import importlib
import os
import sys

import pytest

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

#: The commands with an argparse parser (the nodes take ROS arguments: test_node_usage.py).
TOOLS = ['spatial_dynamics.tools.' + name for name in (
    'closed_loop', 'demo', 'fleet_demo', 'identify_demo', 'latency', 'legged', 'moving_base',
    'soak', 'startup', 'ros_cli')] + [
    'spatial_dynamics.check', 'spatial_dynamics.replay.__main__', 'benchmarks.bench',
    'benchmarks.fleet', 'benchmarks.replay']


class Built(Exception):
    """Raised by ``parse_args`` with the parser the command built."""


def parsers(module: str, monkeypatch):
    """Return ``[(name, parser)]``: the command's parser and each of its subcommands'."""
    def parse_args(self, args=None, namespace=None):
        raise Built(self)
    monkeypatch.setattr(argparse.ArgumentParser, 'parse_args', parse_args)
    main = importlib.import_module(module).main
    with pytest.raises(Built) as built:
        main(['--help'])
    parser = built.value.args[0]
    found = [(module, parser)]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            found += [(f'{module} {name}', sub) for name, sub in action.choices.items()]
    return found


def shown(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    """Return the help of ``action`` as ``--help`` prints it (``%(default)s`` expanded)."""
    formatter = parser._get_formatter()
    return formatter._expand_help(action) if action.help else ''


@pytest.mark.parametrize('module', TOOLS)
def test_every_option_has_a_help_text_with_its_default(module, monkeypatch):
    missing, no_default = [], []
    for name, parser in parsers(module, monkeypatch):
        for action in parser._actions:
            if isinstance(action, (argparse._HelpAction, argparse._SubParsersAction)):
                continue
            text = shown(parser, action)
            what = f'{name}: {"/".join(action.option_strings) or action.dest}'
            if not text.strip():
                missing.append(what)
            elif (action.option_strings and action.default not in (None, False, '', [], ())
                  and action.default is not argparse.SUPPRESS
                  and 'default' not in text.lower()):
                no_default.append(f'{what} (default {action.default!r}): {text}')
    assert not missing, f'options without a help text: {missing}'
    assert not no_default, f'options whose help hides the default: {no_default}'
