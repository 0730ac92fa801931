# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""``replay`` as subcommands: residual, identify, trajectory, annotate, excite.

Each has its own ``--help``, ``replay --help`` lists them one line each, the options of one
job are refused by another (usage, exit 2), and a command line without a subcommand is a usage
error.
"""

import os
import sys

import numpy as np
import pytest
import yaml

sys.path.insert(0, os.path.dirname(__file__))
from conftest import robot_urdf_path  # noqa: E402
from test_replay_outputs import motion_bag  # noqa: E402

import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics.recordings import bags  # noqa: E402
from spatial_dynamics.replay.__main__ import main  # noqa: E402

pytest.importorskip('rosbags')
COMMANDS = ['residual', 'identify', 'trajectory', 'annotate', 'excite']
UR5 = robot_urdf_path('ur5')


def usage(argv, capsys):
    """Run ``main(argv)`` expecting argparse to exit; return (status, stdout, stderr)."""
    with pytest.raises(SystemExit) as exit:
        main(argv)
    out, err = capsys.readouterr()
    return exit.value.code, out, err


def test_help_lists_every_subcommand_in_one_line(capsys):
    status, out, _ = usage(['--help'], capsys)
    assert status == 0
    for name in COMMANDS:
        lines = [line for line in out.splitlines() if line.split()[:1] == [name]]
        assert len(lines) == 1 and len(lines[0].split()) > 2, (name, out)


@pytest.mark.parametrize('name', COMMANDS)
def test_each_subcommand_has_its_own_help(name, capsys):
    status, out, _ = usage([name, '--help'], capsys)
    assert status == 0 and out.startswith(f'usage: replay {name} ')
    assert '--urdf' in out and '--gravity' in out        # the shared model options
    assert ('--payload' in out) == (name == 'identify')
    assert ('--tolerance' in out) == (name == 'annotate')


@pytest.mark.parametrize('argv, words', [
    (['residual', 'b', '--urdf', UR5, '--payload', 'tool0'], ['unrecognized', '--payload']),
    (['trajectory', 'p.yaml', '--urdf', UR5, '--validate', 'b'], ['unrecognized']),
    (['identify', 'b', '--urdf', UR5, '--payload', 'tool0', '--inertias'],
     ['--inertias', 'not allowed with', '--payload']),
    (['annotate', 'p.yaml', '--urdf', UR5], ['--out']),
    (['identify', 'b', '--urdf', UR5, '--locked', 'a=1'], ['--locked needs --joints']),
])
def test_usage_errors_of_the_subcommands(argv, words, capsys):
    status, _, err = usage(argv, capsys)
    assert status == 2 and err.startswith('usage: replay ')
    for w in words:
        assert w in err.splitlines()[-1], (w, err)


# --------------------------------------------------------------------------------------------
# The inputs of the subcommands

def trajectory_bag(path):
    """Write a bag of two JointTrajectory messages on /traj, the second beyond the limits."""
    store = bags.typestore()
    JT = store.types[bags.JOINT_TRAJECTORY]
    P = store.types['trajectory_msgs/msg/JointTrajectoryPoint']
    Header, Time = store.types['std_msgs/msg/Header'], store.types['builtin_interfaces/msg/Time']
    D = store.types['builtin_interfaces/msg/Duration']
    names = sd.Model.from_urdf(UR5).joint_names

    def msg(target, seconds):
        points = [P(positions=np.asarray(q, float), velocities=np.zeros(6),
                    accelerations=np.array([], float), effort=np.array([], float),
                    time_from_start=D(sec=int(s), nanosec=int((s % 1) * 1e9)))
                  for q, s in ((np.zeros(6), 0.0), (target, seconds))]
        return bags.serialize(JT(header=Header(stamp=Time(sec=0, nanosec=0), frame_id=''),
                                 joint_names=names, points=points), bags.JOINT_TRAJECTORY)

    raw = [msg(np.full(6, 0.3), 4.0), msg(np.full(6, 3.0), 0.2)]
    bags.write_bag(str(path), 'mcap', [('/traj', bags.JOINT_TRAJECTORY, np.array([1, 2]), raw)])
    return str(path)


def plan(path, seconds):
    """Write a UR5 plan from rest to rest in ``seconds`` (quintic)."""
    names = sd.Model.from_urdf(UR5).joint_names
    q0, q1 = [0.0, -1.0, 0.8, -0.5, 0.3, 0.1], [0.5, -0.5, 0.3, 0.2, -0.4, 0.6]
    points = [{'positions': q, 'velocities': [0.0] * 6, 'accelerations': [0.0] * 6,
               'time_from_start': {'sec': int(s), 'nanosec': int(round(s % 1 * 1e9))}}
              for q, s in ((q0, 0.0), (q1, seconds))]
    path.write_text(yaml.safe_dump({'joint_names': list(names), 'points': points}))
    return str(path)


@pytest.fixture(scope='module')
def inputs(tmp_path_factory):
    d = tmp_path_factory.mktemp('inputs')
    return {'BAG': motion_bag(d / 'run'), 'TRAJ_BAG': trajectory_bag(d / 'traj'),
            'PLAN': plan(d / 'plan.yaml', 4.0), 'FAST': plan(d / 'fast.yaml', 0.2),
            'URDF': UR5}


@pytest.mark.parametrize('argv', [
    'BAG --urdf URDF --out OUT --identify --no-plots',
    '--urdf URDF --trajectory PLAN --out OUT --no-plots',
    'BAG --urdf URDF --out OUT --no-plots'])
def test_a_command_line_without_a_subcommand_is_a_usage_error(argv, inputs, tmp_path, capsys):
    """The one-command spellings of before the subcommands were never released: none runs."""
    out = tmp_path / 'out'
    status, stdout, err = usage([inputs.get(w, str(out) if w == 'OUT' else w)
                                 for w in argv.split()], capsys)
    assert status == 2 and err.startswith('usage: replay ') and not stdout
    assert 'invalid choice' in err.splitlines()[-1] or 'required' in err.splitlines()[-1], err
    assert not out.exists()


def test_each_job_writes_only_its_files(inputs, tmp_path, monkeypatch):
    out = tmp_path / 'r'
    assert main(['residual', inputs['BAG'], '--urdf', UR5, '--out', str(out),
                 '--no-plots']) == 0
    assert sorted(os.listdir(out)) == ['residual.csv', 'summary.csv']
    out = tmp_path / 't'
    assert main(['trajectory', inputs['PLAN'], '--urdf', UR5, '--out', str(out),
                 '--no-plots']) == 0
    assert sorted(os.listdir(out)) == ['trajectory.csv']
    monkeypatch.chdir(tmp_path)
    assert main(['annotate', inputs['PLAN'], '--urdf', UR5, '--out', 'x.yaml']) == 0
    assert sorted(os.listdir(tmp_path)) == ['r', 't', 'x.yaml']
