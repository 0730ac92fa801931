# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""``inverse_dynamics --help`` and ``sim --help``: the usage, exit 0, no node started.

rclpy ignores an argument it does not know, so ``--help`` used to start the node (which then
ran until killed). The launchers of bin/ run here as installed, from the source tree.
"""

import os
import subprocess
import sys

import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from node_harness import ROOT  # noqa: E402
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


def test_help_after_ros_args_is_ros_s():
    assert help_requested(['--help'])
    assert help_requested(['-h', '--ros-args', '-p', 'a:=1'])
    assert not help_requested(['--ros-args', '--help'])
    assert not help_requested(['--ros-args', '-p', 'robot_description_file:=x.urdf'])
