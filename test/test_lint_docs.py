# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Every code block of the README and of doc/ runs here, so a snippet cannot rot.

* ``python`` blocks run, in the order of their page, in one namespace per page (a later block
  may use what an earlier one made, as a reader would), in a fresh interpreter whose working
  directory is the checkout (the snippets name ``config/demo_arm.urdf``).
* ``bash`` blocks: every command of this package (``python -m spatial_dynamics.…``, ``ros2 run
  spatial_dynamics …``, the installed ``lib/spatial_dynamics/…`` launchers,
  ``spatial_dynamics_check``, ``scripts/dev …``, ``python -m benchmarks.…``) has its arguments
  parsed by the command's own parser — an option that does not exist or a value it refuses fails
  the test — and every ``-p name:=value`` of the nodes is a parameter of the node's table. Commands
  of other tools (git, colcon, ros2 bag, …) are the reader's to run.
* ``text`` blocks are what a command printed; each page names the command beside it.

Also: every local link of a page points at a file that exists, and the doc tree builds with
Sphinx, warnings as errors (rosdoc2's build of the same pages: test_lint_rosdoc2.py).
"""

import argparse
import importlib
import os
import re
import shlex
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PAGES = ['README.md'] + sorted(os.path.join('doc', f)
                               for f in os.listdir(os.path.join(ROOT, 'doc')) if f.endswith('.md'))
FENCE = re.compile(r'^```(\w*)[^\n]*\n(.*?)^```\s*$', re.S | re.M)


def blocks(page: str, language: str):
    with open(os.path.join(ROOT, page), encoding='utf-8') as f:
        text = f.read()
    return [m.group(2) for m in FENCE.finditer(text) if m.group(1) == language]


def commands(block: str):
    """Return the commands of a shell block: continuation lines joined, comments dropped."""
    joined = re.sub(r'\\\n\s*', ' ', block)
    for line in joined.splitlines():
        line = line.split(' #')[0].strip()
        if line.startswith('#') or not line:
            continue
        for part in re.split(r'\s*(?:&&|;)\s*', line):
            if part:
                yield shlex.split(part)


class Parsed(Exception):
    """Raised instead of running a command once its arguments parsed."""


def parse_only(module: str, argv):
    """Run ``module``'s main on ``argv`` up to its argument parser; raise on a usage error."""
    original = argparse.ArgumentParser.parse_args

    def parse_args(self, args=None, namespace=None):
        original(self, args, namespace)
        raise Parsed

    mod = importlib.import_module(module)
    argparse.ArgumentParser.parse_args = parse_args
    try:
        mod.main(list(argv))
    except Parsed:
        return
    except SystemExit as exit:
        raise AssertionError(f'{module} {shlex.join(argv)}: usage error (exit {exit.code})')
    finally:
        argparse.ArgumentParser.parse_args = original
    raise AssertionError(f'{module} {shlex.join(argv)}: ran without parsing its arguments')


def node_table(node: str):
    pytest.importorskip('rclpy')
    if node == 'sim':
        from spatial_dynamics.sim.node import PARAMETERS
    else:
        from spatial_dynamics.ros.config import PARAMETERS
    return {p.name for p in PARAMETERS.params}


def check_ros_args(node: str, argv):
    names = node_table(node)
    assert argv[:1] == ['--ros-args'], f'{node}: arguments must follow --ros-args'
    args = iter(argv[1:])
    for flag in args:
        value = next(args)
        if flag == '-p':
            name = value.split(':=')[0]
            assert name in names, f'{node}: no parameter {name!r}'
        else:
            assert flag == '-r', f'{node}: unknown ROS argument {flag}'


MODULES = {'replay': 'spatial_dynamics.replay.__main__',
           'spatial_dynamics_check': 'spatial_dynamics.check',
           'demo': 'spatial_dynamics.tools.demo'}


def check_command(argv) -> bool:
    """Check one command of this package; return False for another tool's command."""
    if argv[:2] == ['python', '-m']:
        module, rest = argv[2], argv[3:]
        if module == 'spatial_dynamics.replay':
            module = 'spatial_dynamics.replay.__main__'
        if not module.startswith(('spatial_dynamics', 'benchmarks')):
            return False
        parse_only(module, rest)
        return True
    if argv[:3] in (['ros2', 'run', 'spatial_dynamics'],):
        argv = ['install/lib/spatial_dynamics/' + argv[3]] + argv[4:]
    if argv[0].startswith('install/lib/spatial_dynamics/') or argv[0] == 'spatial_dynamics_check':
        name = os.path.basename(argv[0])
        assert os.path.exists(os.path.join(ROOT, 'bin', name)), f'no command {name}'
        if name in ('inverse_dynamics', 'sim'):
            check_ros_args(name, argv[1:])
        else:
            parse_only(MODULES[name], argv[1:])
        return True
    if argv[0] == 'scripts/dev':
        with open(os.path.join(ROOT, 'scripts', 'dev'), encoding='utf-8') as f:
            verbs = re.findall(r'^    ([a-z0-9-]+)\)$', f.read(), re.M)
        assert argv[1] in verbs, f'scripts/dev has no {argv[1]!r} ({verbs})'
        if argv[1] == 'demo' and argv[2:3] == ['--closed-loop']:
            parse_only('spatial_dynamics.tools.closed_loop', argv[3:])
        elif argv[1] == 'demo':
            parse_only('spatial_dynamics.tools.demo', argv[2:])
        elif argv[1] == 'bench':
            parse_only('benchmarks.bench', argv[2:])
        return True
    if argv[:3] == ['ros2', 'launch', 'spatial_dynamics']:
        assert os.path.exists(os.path.join(ROOT, 'launch', argv[3])), f'no launch file {argv[3]}'
        return True
    return False


@pytest.mark.parametrize('page', PAGES)
def test_python_blocks_run(page):
    code = blocks(page, 'python')
    if not code:
        return
    program = '\n'.join(f'# --- block {i}\n{c}' for i, c in enumerate(code))
    run = subprocess.run([sys.executable, '-c', program], cwd=ROOT, capture_output=True,
                         text=True, env=dict(os.environ, MPLBACKEND='Agg'))
    assert run.returncode == 0, f'{page}: a python block failed:\n{run.stderr[-3000:]}'


@pytest.mark.parametrize('page', PAGES)
def test_shell_commands_parse(page, monkeypatch):
    monkeypatch.chdir(ROOT)
    ours = 0
    for block in blocks(page, 'bash'):
        for argv in commands(block):
            ours += check_command(argv)
    if page == 'README.md':
        assert ours >= 8, 'the README shows the package\'s commands'


def test_shell_checker_catches_a_wrong_option(monkeypatch):
    """The checker itself fails on what a stale snippet would say."""
    monkeypatch.chdir(ROOT)
    with pytest.raises(AssertionError):
        check_command(shlex.split('python -m spatial_dynamics.check ROBOT.urdf --no-such-flag'))
    with pytest.raises(AssertionError):
        check_command(shlex.split('scripts/dev no-such-verb'))
    with pytest.raises(AssertionError):
        check_command(['install/lib/spatial_dynamics/inverse_dynamics', '--ros-args', '-p',
                       'no_such_parameter:=1'])


@pytest.mark.parametrize('page', PAGES)
def test_local_links_exist(page):
    with open(os.path.join(ROOT, page), encoding='utf-8') as f:
        text = f.read()
    folder = os.path.dirname(os.path.join(ROOT, page))
    for target in re.findall(r'\]\(([^)#\s]+)(?:#[^)]*)?\)', text):
        if '://' in target:
            continue
        assert os.path.exists(os.path.join(folder, target)), f'{page}: link to {target}'


def test_sphinx_builds_without_warnings(tmp_path):
    pytest.importorskip('sphinx')
    pytest.importorskip('myst_parser')
    run = subprocess.run([sys.executable, '-m', 'sphinx', '-W', '--keep-going', '-q', '-b',
                          'html', 'doc', str(tmp_path / 'html')], cwd=ROOT,
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr[-5000:]
