# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A plan annotated with effort for JTC: the last point, the bounds, the limits, the files.

The last point of a plan carries the torque of the state JTC holds after it (compared with
Pinocchio's computeGeneralizedGravity on the example-robot-data UR5); the annotation is
bounded in points (a tolerance asking for more is refused with a reason, never a
MemoryError) and can be cancelled; ``replay --annotate`` checks the efforts against the URDF
limits as ``--trajectory`` does, says when the tolerance is not met, refuses an output that
is an input before any work, writes atomically and creates no output directory.
"""

import functools
import os
import sys

import numpy as np
import pytest
import yaml

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from conftest import robot_urdf_path  # noqa: E402
import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics import effort  # noqa: E402
from spatial_dynamics.replay.__main__ import main  # noqa: E402
from spatial_dynamics.trajectory import trajectory  # noqa: E402


@functools.lru_cache(maxsize=None)
def ur5():
    path = robot_urdf_path('ur5')
    return path, sd.Model.from_urdf(path)


def point(t, q, v=None, a=None):
    p = {'positions': [float(x) for x in q],
         'time_from_start': {'sec': int(t), 'nanosec': int(round(t % 1 * 1e9))}}
    if v is not None:
        p['velocities'] = [float(x) for x in v]
    if a is not None:
        p['accelerations'] = [float(x) for x in a]
    return p


Q0 = np.array([0.0, -1.0, 0.8, -0.5, 0.3, 0.1])
Q1 = np.array([0.4, -1.6, 1.2, 0.2, -0.4, 0.5])


def pin_gravity(q):
    """g(q) of the UR5 by Pinocchio (joint order by name: ours)."""
    pin = pytest.importorskip('pinocchio')
    path, model = ur5()
    pm = pin.buildModelFromUrdf(path)
    data = pm.createData()
    q_pin = pin.neutral(pm)
    for name, x in zip(model.joint_names, q):
        q_pin[pm.joints[pm.getJointId(name)].idx_q] = x
    g = pin.computeGeneralizedGravity(pm, data, q_pin)
    return np.array([g[pm.joints[pm.getJointId(name)].idx_v] for name in model.joint_names])


@pytest.mark.parametrize('kind', ['linear', 'cubic', 'quintic'])
def test_the_last_point_carries_the_torque_of_the_held_state(kind):
    """After the end JTC holds the last point: its effort is g(q_N), the torque of rest."""
    _, model = ur5()
    z = np.zeros(6)
    v = None if kind == 'linear' else z
    a = z if kind == 'quintic' else None
    traj = trajectory(model.joint_names, [point(0.0, Q0, v, a), point(1.0, Q1, v, a)])
    done = effort.annotate(model, traj, 0.1)
    np.testing.assert_allclose(done.effort[-1], pin_gravity(Q1), rtol=0, atol=1e-9)
    if kind != 'quintic':    # the end of the last segment is not at rest: a torque jump there
        assert done.jumps and done.jumps[-1][1] == 1.0
        a_, b_ = done.jumps[-1]
        assert effort.MIN_STEP <= b_ - a_ <= 2 * effort.MIN_STEP
    for output, expected in (('without_gravity', np.zeros(6)),
                             ('gravity_only', pin_gravity(Q1))):
        np.testing.assert_allclose(effort.annotate(model, traj, 0.1, output).effort[-1],
                                   expected, rtol=0, atol=1e-9)


def test_a_tolerance_asking_for_too_many_points_is_refused_not_exhausted():
    """1e-11 N m on a 2000 s plan would bisect to 2 million points: refused with its reason."""
    _, model = ur5()
    traj = trajectory(model.joint_names, [point(0.0, Q0, np.zeros(6)),
                                          point(2000.0, Q1, np.zeros(6))])
    with pytest.raises(effort.AnnotationError, match='more than 1,666 ') as err:
        effort.annotate(model, traj, 1e-11, max_values=30_000)
    assert err.value.reason == 'too_many_points'
    assert effort.max_points(6, 2) * 6 * 3 <= effort.MAX_ANNOTATED_VALUES
    calls = []
    with pytest.raises(effort.AnnotationError) as err:
        effort.annotate(model, traj, 1e-11, cancelled=lambda: calls.append(1) or len(calls) > 2)
    assert err.value.reason == 'superseded' and len(calls) == 3


def write_plan(path, names, points):
    path.write_text(yaml.safe_dump({'joint_names': list(names), 'points': points}))
    return str(path)


def test_replay_annotate_checks_the_effort_limits(tmp_path, capsys):
    """A 0.2 s UR5 move asks far beyond the URDF limits: EXCEEDED, exit 1 (as --trajectory)."""
    urdf, model = ur5()
    src = write_plan(tmp_path / 'fast.yaml', model.joint_names,
                     [point(0.0, Q0, np.zeros(6)), point(0.2, Q1, np.zeros(6))])
    out = tmp_path / 'out.yaml'
    assert main(['annotate', src, '--urdf', urdf, '--out', str(out)]) == 1
    text = capsys.readouterr()
    assert 'EXCEEDED' in text.out and 'effort limit' in text.err
    written = yaml.safe_load(out.read_text())     # written, for a look, but the exit says no
    peak = np.abs([p['effort'] for p in written['points']]).max(axis=0)
    assert np.any(peak > model.effort_limit)


def test_replay_annotate_is_bounded_and_says_when_the_tolerance_is_not_met(
        tmp_path, capsys, monkeypatch):
    urdf, model = ur5()
    src = write_plan(tmp_path / 'plan.yaml', model.joint_names,
                     [point(0.0, Q0, np.zeros(6)), point(4.0, Q1, np.zeros(6))])
    out = tmp_path / 'out.yaml'
    # 1e-300 N m cannot be met at the 1 ms steps: said, exit 1
    assert main(['annotate', src, '--urdf', urdf, '--out', str(out),
                 '--tolerance', '1e-300']) == 1
    text = capsys.readouterr()
    assert 'tolerance 1e-300 N m NOT met' in text.err
    # a 2000 s plan at 1e-9 N m is too many points: refused, nothing written (the bound of
    # the node and of the command, made small here to keep the test short)
    monkeypatch.setattr(effort, 'MAX_ANNOTATED_VALUES', 30_000)
    long = write_plan(tmp_path / 'long.yaml', model.joint_names,
                      [point(0.0, Q0, np.zeros(6)), point(2000.0, Q1, np.zeros(6))])
    out2 = tmp_path / 'out2.yaml'
    assert main(['annotate', long, '--urdf', urdf, '--out', str(out2),
                 '--tolerance', '1e-9']) == 1
    assert 'too small for this plan' in capsys.readouterr().err
    assert not out2.exists()


def test_replay_annotate_output_is_checked_first_and_written_alone(tmp_path, capsys,
                                                                   monkeypatch):
    urdf, model = ur5()
    src = write_plan(tmp_path / 'plan.yaml', model.joint_names,
                     [point(0.0, Q0, np.zeros(6)), point(4.0, Q1, np.zeros(6))])
    before = open(src).read()
    for target in (src, urdf):           # an output that is an input: refused, untouched
        text = open(target).read()
        assert main(['annotate', src, '--urdf', urdf, '--out', target]) == 1
        assert 'also an input' in capsys.readouterr().err
        assert open(target).read() == text
    assert open(src).read() == before
    monkeypatch.chdir(tmp_path)          # the default --out (replay_out) is not created
    written = []
    real = sd.files.write_atomic

    def spy(path, data, what):
        written.append(path)
        return real(path, data, what)

    monkeypatch.setattr(sd.files, 'write_atomic', spy)
    assert main(['annotate', src, '--urdf', urdf, '--out', 'out.yaml']) == 0
    assert written == ['out.yaml'] and os.path.exists('out.yaml')
    assert not os.path.exists('replay_out')
    assert sorted(os.listdir(tmp_path)) == ['out.yaml', 'plan.yaml']
