# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Every code block of the README and of doc/ runs here, or says why not, so a snippet cannot rot.

A block is a fence anywhere in a line's indentation (a block inside a list item is a block);
its info string is the language, then optionally a marker::

    ```bash not-run: needs a ROS installation (ros2 launch)

``not-run: REASON`` says the block is not run here and why (the reason is required and shown
to the reader as the fence's info). What each language gets:

* ``python`` blocks run, in the order of their page, in one namespace per page (a later block
  may use what an earlier one made, as a reader would), in a fresh interpreter whose working
  directory is the checkout (the snippets name ``config/demo_arm.urdf``).
* ``bash`` blocks: every command of this package (``python -m spatial_dynamics.…``, ``ros2 run
  spatial_dynamics …``, the installed ``lib/spatial_dynamics/…`` launchers,
  ``spatial_dynamics_check``, ``scripts/dev …``, ``python -m benchmarks.…``) has its arguments
  parsed by the command's own parser — an option that does not exist or a value it refuses fails
  the test — and every ``-p name:=value`` of the nodes is a parameter of the node's table, in
  marked blocks too. An unmarked block runs after the quick start, without a ROS installation:
  a command that needs one (``ros2``, ``rosdep``) makes it fail unless the block is marked.
  Commands of other tools (git, colcon, …) are the reader's to run.
* ``text`` blocks are what a command printed; each page names the command beside it.
* ``{toctree}`` is Sphinx's table of contents.

Also: every local link of a page points at a file that exists, no link is a placeholder, and
the doc tree builds with Sphinx, warnings as errors (rosdoc2's build of the same pages:
test_lint_rosdoc2.py).
"""

import argparse
import importlib
import os
import re
import shlex
import subprocess
import sys
import textwrap
from typing import List, NamedTuple

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PAGES = ['README.md'] + sorted(os.path.join('doc', f)
                               for f in os.listdir(os.path.join(ROOT, 'doc')) if f.endswith('.md'))
#: A fenced block at any indentation: its indentation, info string and body.
FENCE = re.compile(r'^(?P<indent>[ \t]*)```(?P<info>[^\n`]*)\n(?P<body>.*?)^(?P=indent)```[ \t]*$',
                   re.S | re.M)
LANGUAGES = ('python', 'bash', 'text', '{toctree}')
NOT_RUN = re.compile(r'not-run: (?P<reason>\S.*)')
#: Commands that need a ROS installation (ros2cli, rosdep): not in the quick start's venv.
NEEDS_ROS = ('ros2', 'rosdep')
CODE_HOSTS = ('github.com', 'gitlab.com', 'bitbucket.org')


class Block(NamedTuple):
    language: str
    marker: str        # '' or the whole marker, 'not-run: REASON'
    body: str          # dedented
    line: int          # of the opening fence, 1-based


def all_blocks(page: str) -> List[Block]:
    """Return every fenced block of ``page``, in order."""
    with open(os.path.join(ROOT, page), encoding='utf-8') as f:
        text = f.read()
    found = []
    for m in FENCE.finditer(text):
        language, _, marker = m.group('info').strip().partition(' ')
        body = textwrap.dedent(m.group('body')) if m.group('indent') else m.group('body')
        found.append(Block(language, marker.strip(), body, text.count('\n', 0, m.start()) + 1))
    return found


def blocks(page: str, language: str, run_only: bool = False) -> List[str]:
    """Return the bodies of ``page``'s blocks in ``language`` (unmarked ones: ``run_only``)."""
    return [b.body for b in all_blocks(page)
            if b.language == language and not (run_only and b.marker)]


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
        elif flag == '--params-file':   # the installed copy of config/: check the source's
            path = re.sub(r'^install/share/spatial_dynamics/', '', value)
            assert os.path.isfile(os.path.join(ROOT, path)), f'{node}: no file {value}'
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
def test_every_fence_is_a_block_that_runs_or_says_why_not(page):
    """Each fence of the page is found (indented ones too) and known; a marker has a reason."""
    with open(os.path.join(ROOT, page), encoding='utf-8') as f:
        fences = [line for line in f if line.lstrip().startswith('```')]
    found = all_blocks(page)
    assert 2 * len(found) == len(fences), f'{page}: a fence that is not a block'
    for block in found:
        where = f'{page}:{block.line}'
        assert block.language in LANGUAGES, f'{where}: language {block.language!r}'
        assert not block.marker or NOT_RUN.fullmatch(block.marker), \
            f'{where}: the marker is `not-run: REASON`, got {block.marker!r}'


@pytest.mark.parametrize('page', PAGES)
def test_unmarked_shell_blocks_need_no_ros_installation(page):
    """What the quick start installs runs them: no ros2cli, no rosdep (or a marker saying so)."""
    for block in all_blocks(page):
        if block.language != 'bash' or block.marker:
            continue
        for argv in commands(block.body):
            assert argv[0] not in NEEDS_ROS, (
                f'{page}:{block.line}: {shlex.join(argv)} needs a ROS installation: give the '
                'command that works after the quick start (install/lib/spatial_dynamics/…, '
                'python -m spatial_dynamics.tools.ros_cli …) or mark the block '
                '`not-run: needs a ROS installation`')


@pytest.mark.parametrize('page', PAGES)
def test_no_link_is_a_placeholder(page):
    """A link goes somewhere (not ``https://github.com/``); no ``<this repository>``."""
    with open(os.path.join(ROOT, page), encoding='utf-8') as f:
        text = f.read()
    for target in re.findall(r'\]\((\w+://[^)\s]*)\)', text):
        host, _, path = target.split('://', 1)[1].partition('/')
        if host in CODE_HOSTS:      # a project there is owner/name
            assert len([p for p in path.split('/') if p]) >= 2, f'{page}: placeholder {target}'
    assert '<this repository>' not in text, f'{page}: a placeholder for the repository'


@pytest.mark.parametrize('page', PAGES)
def test_python_blocks_run(page):
    code = blocks(page, 'python', run_only=True)
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
