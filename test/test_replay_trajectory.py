# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Trajectory check: the splines analytically, τ against Pinocchio, the effort-limit verdict."""

import os
import sys

import numpy as np
import pytest
import yaml

sys.path.insert(0, os.path.dirname(__file__))
from conftest import robot_urdf_path  # noqa: E402

from spatial_dynamics.replay import splines  # noqa: E402
from spatial_dynamics.replay.__main__ import main  # noqa: E402
from spatial_dynamics.replay.report import write_csv  # noqa: E402

RNG = np.random.default_rng(11)


def random_trajectory(n=3, m=5, fields=('positions', 'velocities', 'accelerations')):
    """Points at uneven times with random values of the given fields."""
    t = np.cumsum(RNG.uniform(0.3, 1.0, m))
    points = [{f: RNG.uniform(-1, 1, n).tolist() for f in fields} for _ in range(m)]
    for p, tk in zip(points, t):
        p['time_from_start'] = {'sec': int(tk), 'nanosec': int(round((tk % 1) * 1e9))}
    return splines.trajectory([f'j{k}' for k in range(n)], points)


@pytest.mark.parametrize('fields', [('positions',), ('positions', 'velocities'),
                                    ('positions', 'velocities', 'accelerations')])
def test_splines_meet_the_points_and_are_continuous(fields):
    traj = random_trajectory(fields=fields)
    assert traj.kind == {1: 'linear', 2: 'cubic', 3: 'quintic'}[len(fields)]
    c = splines.coefficients(traj)
    T = np.diff(traj.time)[:, None]
    p = np.arange(6)
    # value and derivatives of every segment at its two ends
    at = [np.einsum('kpj,kp->kj', c, s ** p) for s in (np.zeros_like(T), T)]
    d1 = [np.einsum('kpj,kp->kj', c[:, 1:], (p[1:] * s ** (p[1:] - 1))) for s in
          (np.zeros_like(T), T)]
    d2 = [np.einsum('kpj,kp->kj', c[:, 2:], (p[2:] * (p[2:] - 1) * s ** (p[2:] - 2)))
          for s in (np.zeros_like(T), T)]
    assert np.allclose(at[0], traj.positions[:-1]) and np.allclose(at[1], traj.positions[1:])
    if traj.velocities is not None:
        assert np.allclose(d1[0], traj.velocities[:-1])
        assert np.allclose(d1[1], traj.velocities[1:])
    if traj.accelerations is not None:
        assert np.allclose(d2[0], traj.accelerations[:-1])
        assert np.allclose(d2[1], traj.accelerations[1:])
    if traj.kind == 'linear':
        assert np.allclose(d1[0], np.diff(traj.positions, axis=0) / T)
    # the samples: q̇ is the derivative of q (central differences), and the ends are exact
    t, q, qd, qdd = splines.sample(traj, 20000.0)
    assert t[0] == traj.time[0] and t[-1] == traj.time[-1]
    assert np.allclose(q[0], traj.positions[0]) and np.allclose(q[-1], traj.positions[-1])
    h = np.diff(t)
    inner = np.abs(np.diff(np.searchsorted(traj.time, t, side='right'))) == 0
    fd = (q[2:] - q[:-2]) / (h[1:] + h[:-1])[:, None]
    ok = inner[1:] & inner[:-1]
    assert np.allclose(fd[ok], qd[1:-1][ok], atol=1e-5)
    if traj.kind != 'linear':   # q̇ continuous across knots: no jump between samples
        assert np.max(np.abs(np.diff(qd, axis=0))) < 0.005


def test_quintic_with_zero_velocities_and_accelerations_is_the_minimum_jerk_profile():
    traj = splines.trajectory(['a'], [
        {'positions': [0.0], 'velocities': [0.0], 'accelerations': [0.0],
         'time_from_start': {'sec': 0, 'nanosec': 0}},
        {'positions': [1.0], 'velocities': [0.0], 'accelerations': [0.0],
         'time_from_start': {'sec': 2, 'nanosec': 0}}])
    t, q, _, _ = splines.sample(traj, 100.0)
    s = t / 2.0
    assert np.allclose(q[:, 0], 10 * s ** 3 - 15 * s ** 4 + 6 * s ** 5)


def trajectory_yaml(path, names, q_points, times):
    """Write a JointTrajectory (positions, velocities, accelerations) in its YAML form."""
    points = [{'positions': list(map(float, q)), 'velocities': [0.0] * len(q),
               'accelerations': [0.0] * len(q),
               'time_from_start': {'sec': int(tk), 'nanosec': int(round((tk % 1) * 1e9))}}
              for q, tk in zip(q_points, times)]
    doc = {'header': {'stamp': {'sec': 0, 'nanosec': 0}, 'frame_id': ''},
           'joint_names': list(names), 'points': points}
    with open(path, 'w') as f:
        yaml.safe_dump(doc, f)
    return str(path)


UR5 = ['shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint', 'wrist_1_joint',
       'wrist_2_joint', 'wrist_3_joint']


def test_torque_along_the_trajectory_equals_pinocchio(tmp_path, capsys):
    pin = pytest.importorskip('pinocchio')
    urdf = robot_urdf_path('ur5')
    names = UR5[::-1]                  # another order than the URDF's
    path = trajectory_yaml(tmp_path / 't.yaml', names,
                           [np.zeros(6), RNG.uniform(-1, 1, 6), RNG.uniform(-1, 1, 6)],
                           [0.0, 1.5, 3.0])
    out = str(tmp_path / 'out')
    assert main(['trajectory', path, '--urdf', urdf, '--out', out, '--rate', '200',
                 '--no-plots']) == 0
    text = capsys.readouterr().out
    assert 'quintic interpolation' in text and 'peak |tau|' in text
    data = np.loadtxt(os.path.join(out, 'trajectory.csv'), delimiter=',', skiprows=1)
    # independent: Pinocchio's RNEA at the spline samples (its joint order is the URDF's)
    traj = splines.from_yaml(path)
    t, q, qd, qdd = splines.sample(traj, 200.0)
    model = pin.buildModelFromUrdf(urdf)
    data_pin = model.createData()
    order = [traj.joint_names.index(j) for j in UR5]
    tau = np.array([pin.rnea(model, data_pin, q[k, order], qd[k, order], qdd[k, order])
                    for k in range(len(t))])
    assert np.allclose(data[:, 0], t, atol=1e-6)
    # columns in the trajectory's joint order; the CSV keeps 4 decimals
    assert np.allclose(data[:, 1:], tau[:, [UR5.index(j) for j in names]], atol=1e-4)


def test_exceeded_limit_exits_1_and_names_the_joint(tmp_path, capsys):
    urdf = robot_urdf_path('ur5')
    fast = trajectory_yaml(tmp_path / 'fast.yaml', UR5,
                           [np.zeros(6), np.full(6, 3.0), np.zeros(6)], [0.0, 0.15, 0.3])
    assert main(['trajectory', fast, '--urdf', urdf, '--out', str(tmp_path / 'o'),
                 '--no-plots']) == 1
    captured = capsys.readouterr()
    assert 'EXCEEDED' in captured.out and 'effort limit is exceeded' in captured.err
    slow = trajectory_yaml(tmp_path / 'slow.yaml', UR5,
                           [np.zeros(6), np.full(6, 0.2)], [0.0, 5.0])
    assert main(['trajectory', slow, '--urdf', urdf, '--out', str(tmp_path / 'o')]) == 0
    assert os.path.exists(tmp_path / 'o' / 'trajectory.png')


def test_trajectory_topic_of_a_bag(tmp_path, capsys):
    pytest.importorskip('rosbags')
    from test_replay_subcommands import trajectory_bag
    bag = trajectory_bag(tmp_path / 'bag')
    assert main(['trajectory', bag, '--topic', '/traj', '--urdf', robot_urdf_path('ur5'),
                 '--out', str(tmp_path / 'o'), '--no-plots']) == 1
    text = capsys.readouterr().out
    first, second = text.split("'/traj' #1")
    assert 'cubic interpolation' in first and 'EXCEEDED' not in first
    assert 'EXCEEDED' in second


def test_bad_trajectory_files_exit_1(tmp_path, capsys):
    urdf = robot_urdf_path('ur5')
    bad = tmp_path / 'bad.yaml'
    bad.write_text('joint_names: [shoulder_pan_joint]\npoints:\n'
                   '- positions: [0.0]\n  time_from_start: {sec: 1, nanosec: 0}\n'
                   '- positions: [1.0]\n  time_from_start: {sec: 0, nanosec: 0}\n')
    assert main(['trajectory', str(bad), '--urdf', urdf, '--out', str(tmp_path)]) == 1
    assert 'time_from_start must increase' in capsys.readouterr().err
    unknown = trajectory_yaml(tmp_path / 'u.yaml', ['nope'], [[0.0], [1.0]], [0.0, 1.0])
    assert main(['trajectory', unknown, '--urdf', urdf, '--out', str(tmp_path)]) == 1
    assert 'nope' in capsys.readouterr().err


def test_csv_writer_round_trips(tmp_path):
    x = np.concatenate([RNG.normal(0, 100, 1000), [0.0, -0.0, 1e-9, -5e-5, 123456.78, np.nan,
                                                   -np.inf]])
    path = str(tmp_path / 'x.csv')
    write_csv(path, ['a', 'b'], [x, -x], [4, 2])
    back = np.genfromtxt(path, delimiter=',', skip_header=1)
    assert np.allclose(back[:, 0], np.round(x, 4), atol=1e-12, equal_nan=True)
    assert np.allclose(back[:, 1], np.round(-x, 2), atol=1e-12, equal_nan=True)
