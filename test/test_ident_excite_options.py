# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""``replay excite`` refuses what it cannot plan, before any work, in one line naming it.

Every numeric option is bounded where it is parsed (exit 2); a rate too low for the series'
harmonics and a plan too large to read back are refused before the optimisation; a joint
that cannot move is named; ``--out`` that is an input, a directory, a FIFO or in a missing
folder is refused before the URDF is even read. Nothing is written in any of these cases.
"""

import os
import warnings

from conftest import robot_urdf_path
import pytest
import spatial_dynamics as sd
from spatial_dynamics import URDFWarning
from spatial_dynamics.replay import excite, splines

WRISTS = ['--joints', 'wrist_1_joint', 'wrist_2_joint', 'wrist_3_joint']


def run(argv, capsys):
    """Run ``replay excite``; return (status, stdout, stderr)."""
    try:
        status = excite.main(argv)
    except SystemExit as exit:          # argparse's usage errors
        status = exit.code
    out, err = capsys.readouterr()
    return status, out, err


def assert_refused(status, out, err, want_status, *words):
    """One line on stderr with each of ``words``, no traceback, no planning started."""
    assert status == want_status, (status, out, err)
    assert len(err.strip().splitlines()) == 1, err
    assert 'Traceback' not in err and 'error' in err, err
    for w in words:
        assert w in err, (w, err)
    assert 'excitation of' not in out, out          # refused before the optimisation


@pytest.mark.parametrize('argv, words', [
    (['--iterations', '99999999999999999999'], ['--iterations', '1 .. 10,000']),
    (['--iterations', '0'], ['--iterations']),
    (['--iterations', '1e3'], ['--iterations']),
    (['--seed', '-1'], ['--seed', '0 .. 4294967295']),
    (['--seed', str(2 ** 32)], ['--seed']),
    (['--rate', '1e-300'], ['--rate', 'cannot represent']),
    (['--rate', '1001'], ['--rate', 'at most 1000']),
    (['--period', '0.1'], ['--rate 10 cannot represent', '--harmonics 5', '0.1 s period',
                           '--rate 200 at least']),
    (['--duration', '0.1'], ['cannot represent', '--duration']),
    (['--period', '1e-10'], ['cannot represent', '1e-10 s period']),
    (['--period', '1001'], ['--period', 'at most 1000']),
    (['--duration', '86401'], ['--duration', 'a day']),
    (['--duration', '86400', '--period', '1000', '--rate', '1'],
     ['more than a trajectory may last']),
    (['--controller', 'jtc"; rm -rf ~; "'], ['--controller', 'ROS name']),
    (['--controller', '9jtc'], ['--controller']),
])
def test_options_out_of_bounds_are_usage_errors(argv, words, tmp_path, capsys):
    """Exit 2, one line naming the option and the bound, before the URDF is used."""
    argv = ['--duration', '10'] + argv if '--duration' not in argv else argv
    out = tmp_path / 'plan.yaml'
    status, stdout, err = run(['--urdf', robot_urdf_path('ur5'), '--out', str(out)] + argv,
                              capsys)
    assert_refused(status, stdout, err, 2, *words)
    assert not out.exists()


def test_a_plan_too_large_to_read_back_is_refused_before_the_optimisation(tmp_path, capsys):
    """20,000 s at 10 Hz (the 1 kHz check once raised after writing): exit 1 up front."""
    out = tmp_path / 'plan.yaml'
    status, stdout, err = run(['--urdf', robot_urdf_path('ur5'), '--duration', '20000',
                               '--iterations', '1', '--out', str(out)], capsys)
    assert_refused(status, stdout, err, 1, '200,001 points of 6 joints',
                   'more than a plan may carry', 'lower --duration or --rate')
    assert not out.exists()


def test_the_largest_plan_allowed_is_written_and_checked(tmp_path, capsys):
    """At the bound (3 joints, 999 periods of 20 points): written, read back, checked, exit 0.

    One period more is refused; the 1 kHz check covers one period of 10 s, not 9990 s.
    """
    out = tmp_path / 'plan.yaml'
    count = (excite.MAX_PLAN_VALUES // 9 - 1) // 20
    argv = ['--urdf', robot_urdf_path('ur5'), *WRISTS, '--period', '10', '--rate', '2',
            '--harmonics', '2', '--iterations', '5', '--out', str(out)]
    status, stdout, err = run(argv + ['--duration', str(10 * (count + 1))], capsys)
    assert_refused(status, stdout, err, 1, f'{20 * (count + 1) + 1:,} points of 3 joints')
    status, stdout, err = run(argv + ['--duration', str(10 * count)], capsys)
    assert status == 0, err
    assert f'{20 * count + 1} points (20 a period)' in stdout
    assert f'one period of 10 s (all {count} are the same) sampled at 1000 Hz' in stdout
    assert len(splines.from_yaml(str(out)).time) == 20 * count + 1


def urdf_with_limits(tmp_path, joint, lower, upper):
    """Write the UR5's URDF with ``joint``'s lower and upper limits replaced; return its path."""
    with open(robot_urdf_path('ur5')) as f:
        text = f.read()
    head, sep, tail = text.partition(f'<joint name="{joint}" type="revolute">')
    limit = tail.index('<limit ')
    end = tail.index('/>', limit)
    tail = (tail[:limit] + f'<limit effort="28.0" lower="{lower}" upper="{upper}" '
            'velocity="3.2"' + tail[end:])
    path = tmp_path / 'robot.urdf'
    path.write_text(head + sep + tail)
    return str(path)


@pytest.mark.parametrize('lower, upper, words', [
    (0.5, 0.5, ['are equal (0.5)', 'cannot move']),
    (1.0, -1.0, ['lower limit (1) is above its upper limit (-1)']),
])
def test_a_joint_that_cannot_move_is_named(lower, upper, words, tmp_path, capsys):
    """Equal limits or lower > upper: exit 1 naming the joint; no numpy text, no warnings."""
    urdf = urdf_with_limits(tmp_path, 'wrist_2_joint', lower, upper)
    out = tmp_path / 'plan.yaml'
    with warnings.catch_warnings():
        warnings.simplefilter('error', RuntimeWarning)
        status, stdout, err = run(['--urdf', urdf, *WRISTS, '--duration', '4', '--period', '2',
                                   '--harmonics', '2', '--out', str(out)], capsys)
    assert status == 1 and len(err.strip().splitlines()) == 1, err
    assert "joint 'wrist_2_joint'" in err and 'effort' not in err, err
    for w in words:
        assert w in err, err
    assert not out.exists()


def test_a_locked_joint_with_equal_limits_is_fine(tmp_path, capsys):
    """The joint that cannot move, locked (not moved): the others are planned, exit 0."""
    urdf = urdf_with_limits(tmp_path, 'elbow_joint', 0.5, 0.5)
    out = tmp_path / 'plan.yaml'
    status, stdout, err = run(['--urdf', urdf, *WRISTS, '--locked', 'elbow_joint=0.5',
                               '--duration', '4', '--period', '2', '--harmonics', '2',
                               '--iterations', '5', '--out', str(out)], capsys)
    assert status == 0, err
    assert out.exists()


def test_the_loader_warns_of_a_lower_limit_above_the_upper(tmp_path):
    """Computable (the dynamics never reads the range), odd: a URDFWarning naming the joint."""
    urdf = urdf_with_limits(tmp_path, 'wrist_2_joint', 1.0, -1.0)
    with pytest.warns(URDFWarning, match=r"joint 'wrist_2_joint' <limit>: lower \(1\) is "
                      r'above upper \(-1\)'):
        model = sd.Model.from_urdf(urdf)
    assert model.lower[4] == 1.0 and model.upper[4] == -1.0         # loaded as written
    with pytest.raises(ValueError, match='wrist_2_joint.*strict'):
        sd.Model.from_urdf(urdf, strict=True)
    with warnings.catch_warnings():
        warnings.simplefilter('error', URDFWarning)
        sd.Model.from_urdf(urdf_with_limits(tmp_path, 'wrist_2_joint', 0.5, 0.5))  # equal: fine


@pytest.mark.parametrize('case', ['the urdf', 'a directory', 'a fifo', 'a missing folder'])
def test_out_that_cannot_be_the_plan_is_refused_before_any_work(case, tmp_path, capsys):
    """--out = --urdf, a directory, a FIFO, in a missing folder: exit 1 naming it, untouched."""
    urdf = tmp_path / 'robot.urdf'
    with open(robot_urdf_path('ur5'), 'rb') as f:
        urdf.write_bytes(f.read())
    before = urdf.read_bytes()
    out = {'the urdf': urdf, 'a directory': tmp_path,
           'a fifo': tmp_path / 'fifo', 'a missing folder': tmp_path / 'no' / 'plan.yaml'}[case]
    if case == 'a fifo':
        os.mkfifo(out)
    status, stdout, err = run(['--urdf', str(urdf), '--duration', '10', '--out', str(out)],
                              capsys)
    assert_refused(status, stdout, err, 1, '--out', str(out))
    assert urdf.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ['robot.urdf'] + (['fifo'] if case == 'a fifo' else []))
