# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Effort for joint_trajectory_controller, and the meaning of a measured effort.

* annotate: the efforts written are RNEA at the written points; JTC's linear interpolation of
  them (np.interp, as ``interpolate_between_points``) stays within the tolerance of the model
  torque on a dense grid; the motion is unchanged (the inserted points lie on the splines);
  the output modes; ``replay --trajectory --annotate`` round-trips through the YAML reader.
* measured effort: a bag recorded gravity-compensated (UR) gives the residual of the same
  bag recorded with gravity, with ``--measured-effort gravity_compensated``.
"""

import csv
import functools
import os

from conftest import robot_urdf_path
import numpy as np
import pytest
import spatial_dynamics as sd
from spatial_dynamics import effort
from spatial_dynamics.replay import splines
from spatial_dynamics.replay.__main__ import main
from spatial_dynamics.trajectory import evaluate, trajectory
import yaml


@functools.lru_cache(maxsize=None)
def ur5():
    path = robot_urdf_path('ur5')
    return path, sd.Model.from_urdf(path)


def plan(model, kind='quintic', m=5, seed=1):
    """Return a 4 s plan in reversed joint order with the fields of ``kind``."""
    rng = np.random.default_rng(seed)
    names = list(model.joint_names)[::-1]
    t = np.linspace(0.0, 4.0, m)
    Q = rng.uniform(-1.5, 1.5, (m, model.nq))
    V = rng.uniform(-0.5, 0.5, (m, model.nq))
    V[0] = V[-1] = 0.0
    A = rng.uniform(-1.0, 1.0, (m, model.nq))
    A[0] = A[-1] = 0.0
    points = []
    for k in range(m):
        p = {'positions': Q[k].tolist(),
             'time_from_start': {'sec': int(t[k]), 'nanosec': int(round(t[k] % 1 * 1e9))}}
        if kind != 'linear':
            p['velocities'] = V[k].tolist()
        if kind == 'quintic':
            p['accelerations'] = A[k].tolist()
        points.append(p)
    return trajectory(names, points)


def jtc_effort(times, efforts, t):
    """Linear interpolation of the points' effort (JTC's, held after the last point)."""
    return np.stack([np.interp(t, times, efforts[:, j]) for j in range(efforts.shape[1])], -1)


@pytest.mark.parametrize('output', effort.OUTPUTS)
def test_quintic_interpolated_effort_is_within_the_tolerance_everywhere(output):
    _, model = ur5()
    traj = plan(model)
    tol = 0.05
    result = effort.annotate(model, traj, tol, output)
    out = result.trajectory
    assert out.joint_names == model.joint_names and out.kind == 'quintic'
    assert not result.jumps and result.max_error <= tol
    assert len(out.time) > len(traj.time)
    # the efforts are the model's at the written points
    expected = {'full': sd.rnea(model, out.positions, out.velocities, out.accelerations),
                'gravity_only': sd.gravity_torque(model, out.positions)}
    expected['without_gravity'] = expected['full'] - expected['gravity_only']
    assert np.allclose(result.effort, expected[output], rtol=0, atol=1e-9)
    # the motion is the plan's: the written points re-interpolated give the same q, q̇, q̈
    dense = np.linspace(0.0, 4.0, 40001)
    mine = traj.reordered(model.joint_names)
    for a, b in zip(evaluate(out, dense), evaluate(mine, dense)):
        assert np.abs(a - b).max() <= 1e-6
    q, qd, qdd = evaluate(mine, dense)
    model_tau = effort.model_effort(model, q, qd, qdd, output)
    miss = np.abs(jtc_effort(out.time, result.effort, dense) - model_tau).max()
    assert miss <= tol
    if output == 'full':     # and an interpolation of the plan's own points would not be
        coarse = effort.model_effort(model, *evaluate(mine, mine.time), output)
        assert np.abs(jtc_effort(mine.time, coarse, dense) - model_tau).max() > 10 * tol


def test_cubic_plan_reports_the_jumps_and_is_within_the_tolerance_elsewhere():
    _, model = ur5()
    traj = plan(model, 'cubic')
    tol = 0.05
    result = effort.annotate(model, traj, tol)
    out = result.trajectory
    assert out.kind == 'cubic' and result.max_error <= tol
    knots = traj.time[1:]     # q̈ jumps; at the end, from the last segment's to rest (held)
    assert result.jumps and {b for a, b in result.jumps} <= set(knots.tolist())
    assert result.jumps[-1][1] == traj.time[-1]
    dense = np.linspace(0.0, 4.0, 40001)
    near = np.zeros(dense.shape, dtype=bool)
    for a, b in result.jumps:
        assert effort.MIN_STEP <= b - a <= 2 * effort.MIN_STEP
        near |= (dense > a) & ((dense < b) | (dense == traj.time[-1]))
    model_tau = effort.model_effort(model, *evaluate(traj.reordered(model.joint_names),
                                                     dense))
    miss = np.abs(jtc_effort(out.time, result.effort, dense) - model_tau).max(axis=-1)
    assert miss[~near].max() <= tol
    assert near.sum() < 0.01 * len(dense)


def test_measured_effort_with_gravity():
    _, model = ur5()
    q = np.random.default_rng(2).uniform(-1, 1, (3, model.nq))
    g = sd.gravity_torque(model, q)
    assert np.array_equal(effort.with_gravity(model, q, np.ones_like(q)), np.ones_like(q))
    assert np.allclose(effort.with_gravity(model, q, 1 - g, 'gravity_compensated'), 1.0)
    with pytest.raises(ValueError, match="measured effort must be one of"):
        effort.with_gravity(model, q, g, 'compensated')
    with pytest.raises(ValueError, match="output must be one of"):
        effort.model_effort(model, q, q, q, 'none')


# --------------------------------------------------------------------------------------------
# The command line

def test_replay_annotate_round_trips_through_the_reader(tmp_path, capsys):
    urdf, _ = ur5()
    traj = plan(ur5()[1])
    model = sd.Model.from_urdf(urdf, joints=list(traj.joint_names))   # the command's model
    src = tmp_path / 'plan.yaml'
    doc = {'joint_names': list(traj.joint_names), 'points': []}
    for k, t in enumerate(traj.time):
        doc['points'].append({'positions': traj.positions[k].tolist(),
                              'velocities': traj.velocities[k].tolist(),
                              'accelerations': traj.accelerations[k].tolist(),
                              'time_from_start': {'sec': int(t),
                                                  'nanosec': int(round(t % 1 * 1e9))}})
    src.write_text(yaml.safe_dump(doc))
    out = tmp_path / 'out.yaml'
    assert main(['annotate', str(src), '--urdf', urdf, '--out', str(out),
                 '--tolerance', '0.05']) == 0
    text = capsys.readouterr().out
    assert 'points with effort (full)' in text
    back = splines.from_yaml(str(out))                 # the same reader reads it back
    written = yaml.safe_load(out.read_text())
    E = np.array([p['effort'] for p in written['points']])
    assert back.joint_names == model.joint_names and len(back.time) == len(E)
    direct = effort.annotate(model, traj, 0.05)
    assert np.array_equal(back.time, direct.trajectory.time)
    assert np.array_equal(E, direct.effort)
    assert np.allclose(E, sd.rnea(model, back.positions, back.velocities, back.accelerations),
                       rtol=0, atol=1e-9)
    # the annotated file is a valid plan: checking it again passes
    assert main(['trajectory', str(out), '--urdf', urdf, '--no-plots',
                 '--out', str(tmp_path / 'o')]) == 0
    # annotate without its plan is a usage error
    with pytest.raises(SystemExit) as exit_:
        main(['annotate', '--urdf', urdf, '--out', str(out)])
    assert exit_.value.code == 2


def test_a_gravity_compensated_bag_gives_the_residual_of_the_full_one(tmp_path):
    pytest.importorskip('rosbags')
    from spatial_dynamics.recordings import bags
    urdf, model = ur5()
    rate, n = 500.0, 2000
    t = np.arange(n) / rate
    w = 2 * np.pi * (0.2 + 0.1 * np.arange(model.nq))
    q = 0.5 * np.sin(np.outer(t, w))
    qd = 0.5 * w * np.cos(np.outer(t, w))
    qdd = -0.5 * w ** 2 * np.sin(np.outer(t, w))
    tau = sd.rnea(model, q, qd, qdd) + np.random.default_rng(4).normal(0, 0.05, q.shape)
    t_ns = (1_700_000_000 * 10 ** 9 + np.arange(n) * int(1e9 / rate)).astype(np.int64)
    residuals = {}
    for label, measured in (('full', tau), ('gravity_compensated',
                                            tau - sd.gravity_torque(model, q))):
        bag = str(tmp_path / label)
        block = bags.encode_joint_states(model.joint_names, t_ns, q, qd, measured)
        bags.write_bag(bag, 'sqlite3', [('/joint_states', bags.JOINT_STATE, t_ns,
                                         [r.tobytes() for r in block])])
        out = str(tmp_path / f'out_{label}')
        assert main(['residual', bag, '--urdf', urdf, '--out', out, '--no-plots',
                     '--measured-effort', label]) == 0
        with open(os.path.join(out, 'residual.csv')) as f:
            residuals[label] = np.array([[float(x) for x in row[1:]]
                                         for row in list(csv.reader(f))[1:]])
    full, comp = residuals['full'], residuals['gravity_compensated']
    assert full.shape == comp.shape and np.sqrt(np.mean(full ** 2)) < 0.2
    assert np.abs(full - comp).max() <= 2e-4          # equal to the 4 decimals written
    # read as full, the gravity-compensated bag misses g(q) (the old behaviour)
    out = str(tmp_path / 'wrong')
    assert main(['residual', str(tmp_path / 'gravity_compensated'), '--urdf', urdf, '--out', out,
                 '--no-plots']) == 0
    with open(os.path.join(out, 'residual.csv')) as f:
        wrong = np.array([[float(x) for x in row[1:]] for row in list(csv.reader(f))[1:]])
    assert np.sqrt(np.mean(wrong ** 2)) > 10 * np.sqrt(np.mean(full ** 2))
