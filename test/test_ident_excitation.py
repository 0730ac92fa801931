# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Excitation trajectories: the written plan keeps the limits, rests at its ends, identifies.

The plan is read back as a JointTrajectory and sampled like joint_trajectory_controller's
splines (what the robot would follow), and every claim is checked on that: the URDF's limits,
rest at the ends, the condition number of its base regressor computed here from scratch, and
a least-squares fit on its simulated torques predicting a different motion.
"""

import contextlib
import io
import re

from conftest import robot_urdf_path
import numpy as np
import pytest
import spatial_dynamics as sd
from spatial_dynamics.algorithms.regressor import parameters
from spatial_dynamics.identification import base_parameters, identify_inertias, random_states
from spatial_dynamics.replay import excite, splines
from spatial_dynamics.trajectory import sample
from test_ident_inertias import perturbed_ur5

VELOCITY, EFFORT = 0.8, 0.6           # the fractions asked for below


@pytest.fixture(scope='module')
def ur5_plan(tmp_path_factory):
    """Plan 2 periods of 8 s for a UR5; return (model, stdout, the plan read back)."""
    path = str(tmp_path_factory.mktemp('excite') / 'plan.yaml')
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        status = excite.main(['--urdf', robot_urdf_path('ur5'), '--duration', '16',
                              '--period', '8', '--harmonics', '4', '--iterations', '60',
                              '--velocity-fraction', str(VELOCITY),
                              '--effort-fraction', str(EFFORT), '--out', path])
    assert status == 0, out.getvalue()
    return sd.Model.from_urdf(robot_urdf_path('ur5')), out.getvalue(), splines.from_yaml(path)


def scaled_condition(model, q, qd, qdd):
    """Return cond of the base regressor stacked over the states, columns at unit norm."""
    base = base_parameters(model)
    W = sd.regressor(model, q, qd, qdd)[..., base.independent].reshape(-1, base.rank)
    s = np.linalg.svd(W / np.linalg.norm(W, axis=0), compute_uv=False)
    return s[0] / s[-1]


def test_plan_keeps_the_limits_and_rests_at_both_ends_of_each_period(ur5_plan):
    """Sampled at 1 kHz as the controller interpolates it: ranges, velocities, torques, rest."""
    model, _, traj = ur5_plan
    assert traj.kind == 'quintic' and traj.joint_names == model.joint_names
    assert traj.time[-1] == pytest.approx(16.0)
    t, q, qd, qdd = sample(traj, 1000.0)
    assert (q >= model.lower).all() and (q <= model.upper).all()
    assert (np.abs(qd) <= VELOCITY * model.velocity_limit * 1.001).all()
    tau = sd.rnea(model, q, qd, qdd)
    assert (np.abs(tau) <= EFFORT * model.effort_limit * 1.001).all()
    # it moves: each joint uses a good part of its velocity limit
    assert (np.abs(qd).max(axis=0) > 0.5 * VELOCITY * model.velocity_limit).all()
    for k in (0, 8000, len(t) - 1):       # start, between the periods, end
        assert t[k] == pytest.approx(k / 1000.0)
        np.testing.assert_allclose(qd[k], 0.0, atol=1e-6)
        np.testing.assert_allclose(qdd[k], 0.0, atol=1e-5)
    np.testing.assert_allclose(q[0], q[-1], atol=1e-6)             # periodic: back at the start


def test_optimised_condition_number_is_lower_than_the_start(ur5_plan):
    """The plan's condition number, computed here from its samples, is far below the start's."""
    model, text, traj = ur5_plan
    before = float(re.search(r'([0-9.e+]+) at the start', text).group(1))
    t, q, qd, qdd = sample(traj, 50.0)
    after = scaled_condition(model, q, qd, qdd)
    assert after < before / 2, (before, after)
    assert after < 10.0
    assert 'the plan determines 36 of the 36' in text


def test_plan_identifies_every_base_parameter(ur5_plan):
    """Torques simulated on the plan for a UR5 25 % off its URDF fit, and predict new motion."""
    model, true = perturbed_ur5()
    _, _, traj = ur5_plan
    t, q, qd, qdd = sample(traj, 100.0)
    assert base_parameters(model, (q, qd, qdd)).rank == base_parameters(model).rank
    noise = 0.05
    tau = sd.rnea(true, q, qd, qdd) + np.random.default_rng(3).normal(0.0, noise, q.shape)
    fit = identify_inertias(model, q, qd, qdd, tau)
    np.testing.assert_allclose(fit.after, noise, rtol=0.15)         # down to the noise
    # a different motion, the fit never saw it: random states over the whole ranges
    qv, qdv, qddv = random_states(model, 300, seed=9)
    truth = sd.rnea(true, qv, qdv, qddv)
    Y = sd.regressor(model, qv, qdv, qddv)
    fitted = np.sqrt(np.mean((Y @ fit.pi - truth) ** 2, axis=0))
    urdf = np.sqrt(np.mean((Y @ parameters(model) - truth) ** 2, axis=0))
    assert (fitted < noise).all(), fitted          # 0.002 .. 0.008 N m measured
    assert (urdf > 10 * fitted).sum() >= 4, (urdf, fitted)


@pytest.mark.parametrize('argv, status', [
    (['--duration', '-3'], 2),
    (['--duration', 'nan'], 2),
    (['--duration', '10', '--period', 'inf'], 2),
    (['--duration', '10', '--harmonics', '0'], 2),
    (['--duration', '10', '--effort-fraction', '1.5'], 2),
    (['--duration', '10', '--gravity', '0', '0', 'nan'], 2),
    (['--duration', '10', '--locked', 'elbow_joint=0'], 2),
    (['--duration', '10', '--joints', 'no_such_joint'], 1),
    (['--duration', '10', '--urdf-missing'], 1),
    (['--duration', '10', '--urdf-directory'], 1),
])
def test_usage_errors_are_one_line(argv, status, tmp_path, capsys):
    """Bad arguments exit 2, unusable inputs 1: one line on stderr, never a traceback."""
    urdf = robot_urdf_path('ur5')
    if '--urdf-missing' in argv:
        argv, urdf = argv[:-1], str(tmp_path / 'missing.urdf')
    elif '--urdf-directory' in argv:
        argv, urdf = argv[:-1], str(tmp_path)
    try:
        got = excite.main(['--urdf', urdf, '--out', str(tmp_path / 'p.yaml')] + argv)
    except SystemExit as exit:          # argparse's usage errors
        got = exit.code
    assert got == status
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1, err
    assert 'Traceback' not in err and 'error' in err
    assert not (tmp_path / 'p.yaml').exists()


def test_out_unwritable_is_refused(tmp_path, capsys):
    """An --out in a directory that does not exist: exit 1, one line, before the plan."""
    status = excite.main(['--urdf', robot_urdf_path('ur5'), '--duration', '4',
                          '--harmonics', '2', '--iterations', '3',
                          '--out', str(tmp_path / 'no' / 'plan.yaml')])
    out, err = capsys.readouterr()
    assert status == 1 and len(err.strip().splitlines()) == 1 and 'does not exist' in err
    assert 'excitation of' not in out


def test_effort_limit_binds_and_holds():
    """The UR5 wrist with 2 % of its effort limits: the torques reach the bound, not beyond."""
    from spatial_dynamics.excitation import excitation
    model = sd.Model.from_urdf(robot_urdf_path('ur5'),
                               joints=['wrist_1_joint', 'wrist_2_joint', 'wrist_3_joint'])
    bound = 0.02 * model.effort_limit
    plan = excitation(model, period=6.0, harmonics=3, effort_fraction=0.02, maxiter=40)
    t, q, qd, qdd = plan.sample(1000.0)
    peak = np.abs(sd.rnea(model, q, qd, qdd)).max(axis=0)
    assert (peak <= bound * 1.001).all(), (peak, bound)
    assert peak.max() > 0.95 * bound.max()            # the constraint is what stopped it
    assert plan.cond_after < plan.cond_before
    again = excitation(model, period=6.0, harmonics=3, effort_fraction=0.02, maxiter=40)
    np.testing.assert_array_equal(plan.a, again.a)     # seeded: the same plan twice
    np.testing.assert_array_equal(plan.b, again.b)


def test_effort_limits_no_pose_can_hold_are_refused(tmp_path, capsys):
    """1 % of the UR5's effort limits cannot hold its arm still: exit 1, one line."""
    status = excite.main(['--urdf', robot_urdf_path('ur5'), '--duration', '10',
                          '--effort-fraction', '0.01', '--out', str(tmp_path / 'p.yaml')])
    err = capsys.readouterr().err
    assert status == 1 and len(err.strip().splitlines()) == 1 and 'no motion' in err, err
    assert not (tmp_path / 'p.yaml').exists()
