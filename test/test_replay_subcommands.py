# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""``replay`` as subcommands: residual, identify, trajectory, annotate, excite.

Each has its own ``--help``, ``replay --help`` lists them one line each, the options of one
job are refused by another (usage, exit 2), and every old spelling still runs for one release:
the same files and exit status as its new spelling, with one deprecation line on stderr
naming the new one.
"""

import os
import shlex
import sys

import numpy as np
import pytest
import yaml

sys.path.insert(0, os.path.dirname(__file__))
from conftest import robot_urdf_path  # noqa: E402
from test_replay_outputs import motion_bag  # noqa: E402

import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics.replay import bags  # noqa: E402
from spatial_dynamics.replay.__main__ import main, parser  # noqa: E402

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
# The old spellings: the same run as the new one, plus a deprecation line

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


#: (old spelling, new spelling, exit status); OUT is the output (directory or file).
SPELLINGS = [
    ('BAG --urdf URDF --out OUT --no-plots', 'residual BAG --urdf URDF --out OUT --no-plots', 0),
    ('BAG --urdf URDF --out OUT --identify --no-plots --threshold 0.02',
     'identify BAG --urdf URDF --out OUT --no-plots --threshold 0.02', 0),
    ('BAG --urdf URDF --out OUT --payload tool0 --no-plots',
     'identify BAG --payload tool0 --urdf URDF --out OUT --no-plots', 0),
    ('BAG --urdf URDF --out OUT --payload tool0 --identify --no-plots --residual npy',
     'identify BAG --urdf URDF --payload tool0 --drives --out OUT --no-plots --residual npy', 0),
    ('BAG --urdf URDF --out OUT --inertias wrist_3_link --no-plots --residual none',
     'identify BAG --urdf URDF --inertias wrist_3_link --out OUT --no-plots --residual none',
     0),
    ('--urdf URDF --trajectory PLAN --out OUT --no-plots --rate 200',
     'trajectory PLAN --urdf URDF --out OUT --no-plots --rate 200', 0),
    ('--urdf URDF --trajectory FAST --out OUT --no-plots',
     'trajectory FAST --urdf URDF --out OUT --no-plots', 1),
    ('--urdf URDF --trajectory PLAN --annotate OUT --tolerance 0.5',
     'annotate PLAN --urdf URDF --out OUT --tolerance 0.5', 0),
    ('TRAJ_BAG --urdf URDF --trajectory-topic /traj --out OUT --no-plots',
     'trajectory TRAJ_BAG --topic /traj --urdf URDF --out OUT --no-plots', 1),
    ('--urdf URDF --trajectory FAST --annotate OUT', 'annotate FAST --urdf URDF --out OUT', 1),
]


def spelled(line, inputs, out):
    """Return the argv of a spelling with its placeholders filled."""
    return [inputs.get(w, out if w == 'OUT' else w) for w in line.split()]


def outputs(path):
    """Return {name: bytes} of the output file, or of every file in the output directory."""
    if os.path.isfile(path):
        return {'': open(path, 'rb').read()}
    return {n: open(os.path.join(path, n), 'rb').read() for n in sorted(os.listdir(path))}


def comparable(argv):
    """Return the parsed arguments of ``argv``, without the callables of the subcommand."""
    return {k: v for k, v in vars(parser().parse_args(argv)).items() if not callable(v)}


@pytest.mark.parametrize('old, new, status', SPELLINGS)
def test_the_old_spelling_runs_the_new_one_and_says_so(old, new, status, inputs, tmp_path,
                                                       capsys):
    is_file = '--annotate' in old
    out_old, out_new = (str(tmp_path / n) + ('.yaml' if is_file else '') for n in ('a', 'b'))
    assert main(spelled(new, inputs, out_new)) == status
    new_out, new_err = capsys.readouterr()
    assert main(spelled(old, inputs, out_old)) == status
    old_out, old_err = capsys.readouterr()
    assert outputs(out_old) == outputs(out_new) and outputs(out_new)
    assert old_out.replace(out_old, out_new) == new_out
    assert 'deprecated' not in new_err
    said = [line for line in old_err.splitlines() if 'deprecated' in line]
    assert len(said) == 1 and old_err.replace(said[0] + '\n', '', 1) == new_err
    # the line names the new spelling, whole: it parses as the new one
    assert said[0].startswith('replay: deprecated spelling'), said
    suggested = shlex.split(said[0].split('; use: replay ', 1)[1])
    assert suggested[0] == new.split()[0]
    assert comparable(suggested) == comparable(spelled(new, inputs, out_old))


def test_an_old_spelling_refused_as_before(inputs, capsys):
    """The old checks and their texts stay on the old spelling (exit 2, no deprecation)."""
    argv = [inputs['BAG'], '--urdf', UR5, '--inertias', '--payload', 'tool0']
    status, _, err = usage(argv, capsys)
    assert status == 2 and 'exclude each other' in err


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
