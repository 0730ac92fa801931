# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""``inverse_dynamics --help`` and ``sim --help``: the usage, exit 0, no node started.

rclpy ignores an argument it does not know, so ``--help`` used to start the node (which then
ran until killed). The launchers of bin/ run here as installed, from the source tree.
"""

import os
import re
import subprocess
import sys

import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from node_harness import ROOT  # noqa: E402
from spatial_dynamics.ros.arguments import params_files, split_args  # noqa: E402
from spatial_dynamics.ros.usage import help_requested  # noqa: E402

#: What the launcher's process reports after the usage: its exit status, and whether rclpy
#: was imported and initialised.
PROBE = '''
import runpy, sys
sys.argv = [sys.argv[1]] + sys.argv[2:]
try:
    runpy.run_path(sys.argv[0], run_name='__main__')
except SystemExit as exit:
    status = exit.code
rclpy = sys.modules.get('rclpy')
print('STATUS', status, 'rclpy', rclpy is not None, rclpy is not None and rclpy.ok())
'''


def run_launcher(name, *args):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([ROOT, os.environ.get('PYTHONPATH', '')]))
    return subprocess.run([sys.executable, '-c', PROBE, os.path.join(ROOT, 'bin', name), *args],
                          capture_output=True, text=True, timeout=120, env=env, cwd=ROOT)


def table(name):
    if name == 'sim':
        from spatial_dynamics.sim.node import PARAMETERS
    else:
        from spatial_dynamics.ros.config import PARAMETERS
    return PARAMETERS


@pytest.mark.parametrize('name, page', [('inverse_dynamics', 'doc/node.md'),
                                        ('sim', 'doc/simulator.md')])
@pytest.mark.parametrize('flag', ['--help', '-h'])
def test_help_prints_the_usage_and_starts_nothing(name, page, flag):
    pytest.importorskip('rclpy')
    proc = run_launcher(name, flag)
    *usage, status = proc.stdout.rstrip('\n').split('\n')
    assert proc.returncode == 0, proc.stderr
    assert status.startswith('STATUS 0 rclpy'), (status, proc.stderr)
    # the node never initialised rclpy; inverse_dynamics does not even import it
    assert status.endswith('False'), status
    if name == 'inverse_dynamics':
        assert status == 'STATUS 0 rclpy False False'
    assert usage[0].startswith(f'usage: {name} [--ros-args')
    listed = {line.split()[0] for line in usage if line.startswith('  ') and '(' in line
              and line.split()[0] in table(name).names}
    assert listed == set(table(name).names)
    assert page in ' '.join(usage)


def test_help_anywhere_and_the_ros_arguments_read_as_rcl_does():
    assert help_requested(['--help'])
    assert help_requested(['-h', '--ros-args', '-p', 'a:=1'])
    assert help_requested(['--ros-args', '--help'])
    assert help_requested(['--ros-args', '-p', 'a:=1', '-h'])
    assert not help_requested(['--ros-args', '-p', 'robot_description_file:=x.urdf'])
    assert not help_requested(['--ros-args', '-r', '__node:=x'])
    # the value of an option is not an option, and -- ends the ROS arguments
    assert split_args(['a', '--ros-args', '--params-file', '-h', '--', 'b']) == (
        ['a', 'b'], [('--params-file', '-h')])
    assert params_files(['x', '--ros-args', '-p', 'a:=1', '--params-file', 'f.yaml',
                         '--', '--ros-args', '--params-file', 'g.yaml']) == ['f.yaml', 'g.yaml']


@pytest.mark.parametrize('name', ['inverse_dynamics', 'sim'])
@pytest.mark.parametrize('flag', ['--help', '-h'])
def test_help_after_ros_args_prints_the_usage(name, flag):
    pytest.importorskip('rclpy')
    proc = run_launcher(name, '--ros-args', '-p', 'a:=1', flag)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith(f'usage: {name} [--ros-args'), proc.stdout
    assert 'Traceback' not in proc.stderr, proc.stderr
    assert proc.stdout.rstrip('\n').split('\n')[-1].startswith('STATUS 0 rclpy')


def cannot_start(proc, status, *words):
    """Assert one ``cannot start:`` line naming ``words`` and exit ``status``, no traceback."""
    assert 'Traceback' not in proc.stderr, proc.stderr
    lines = [line for line in proc.stderr.splitlines() if 'cannot start:' in line]
    assert len(lines) == 1, proc.stderr
    assert all(word in lines[0] for word in words), lines
    assert f'STATUS {status} ' in proc.stdout, (proc.stdout, proc.stderr)


@pytest.mark.parametrize('name', ['inverse_dynamics', 'sim'])
def test_an_unknown_option_is_refused_before_anything_starts(name):
    pytest.importorskip('rclpy')
    proc = run_launcher(name, '--bogus', '--ros-args', '-p', 'a:=1')
    cannot_start(proc, 2, 'unknown option', '--bogus')
    assert proc.stdout.rstrip('\n').split('\n')[-1].endswith('False')   # rclpy never started


def test_an_unknown_ros_argument_is_one_line():
    pytest.importorskip('rclpy')
    cannot_start(run_launcher('inverse_dynamics', '--ros-args', '--bogus'), 1, '--bogus')


@pytest.mark.parametrize('kind', ['missing', 'fifo', 'directory', 'unparsable'])
def test_a_bad_params_file_is_one_line(kind, tmp_path):
    pytest.importorskip('rclpy')
    path = tmp_path / 'params.yaml'
    if kind == 'fifo':
        os.mkfifo(path)   # rcl would block opening it, the node never started
    elif kind == 'directory':
        path.mkdir()
    elif kind == 'unparsable':
        path.write_text('a: [\n')
    proc = run_launcher('inverse_dynamics', '--ros-args', '--params-file', str(path))
    cannot_start(proc, 1, str(path))


def test_usage_gives_each_description_whole_with_its_range_values_and_read_only():
    from spatial_dynamics.ros.config import PARAMETERS
    from spatial_dynamics.ros.usage import usage
    text = usage(PARAMETERS, 'summary', 'doc/node.md')
    flat = ' '.join(text.split())
    for p in PARAMETERS:
        assert ' '.join(p.description.split()) in flat, p.name   # whole, not to its first '. '
        head = next(line for line in text.splitlines() if line.startswith(f'  {p.name} ('))
        entry = ' '.join(text[text.index(head):].split('\n      ')[0].split())
        if p.bounds is not None:   # the range as written reads back as the bounds exactly
            found = re.search(r'(\S+) \.\. ([^;)\s]+)', entry)
            assert found and (float(found[1]), float(found[2])) == tuple(p.bounds), entry
        assert all(str(c) in entry for c in p.choices), entry
        assert ('read-only' in entry) == p.read_only, entry


def test_usage_lists_every_topic_the_node_has():
    import re
    from spatial_dynamics.ros.config import PARAMETERS
    from spatial_dynamics.ros.usage import usage
    with open(os.path.join(ROOT, 'spatial_dynamics', 'ros', 'node.py')) as f:
        source = f.read()
    topics = set(re.findall(r"(?:advertise|subscribe)\(self, \w+, '([\w/]+)'", source))
    assert {'external_wrench_estimate', 'annotated_trajectory',
            'measured_contact_wrenches'} <= topics
    text = usage(PARAMETERS, 'summary', 'doc/node.md')
    listed = set(re.findall(r'^  (?:in|out)\s+([\w/]+)', text, re.M))
    assert topics <= listed, topics - listed
