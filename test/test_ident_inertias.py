# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Base parameters (``spatial_dynamics.identification``): what a recording can determine.

Analytic cases (a pendulum: its mass on the axis and the inertias across it never load the
joint; a UR5's first link turns about gravity's direction, so its mass and first moments are
carried by the base), the count for a UR-type 6R arm, the identity ``τ = Y_base β`` on states
the decomposition never saw, and a recording that moves one joint only.
"""

import os

import numpy as np
import pytest

from conftest import robot_urdf_path
from node_harness import DEMO_URDF
import spatial_dynamics as sd
from spatial_dynamics.algorithms.regressor import parameters
from spatial_dynamics.identification import base_parameters, random_states

PENDULUM = os.path.join(os.path.dirname(DEMO_URDF), 'pendulum.urdf')


def test_a_pendulum_has_three_base_parameters():
    """A body turning about y under gravity along z: τ = I_yy q̈ + g (m c_x cos q ...).

    Only the first moments across the axis and the inertia about it enter; the mass itself
    (carried by the axis), the first moment along it and the other inertias do not.
    """
    model = sd.Model.from_urdf(PENDULUM)
    axis = model.axis[1]
    assert np.allclose(np.abs(axis), [0.0, 1.0, 0.0])     # the case the names below assume
    base = base_parameters(model)
    body = model.body_names[1]
    assert base.rank == 3
    assert {base.names[i] for i in base.independent} == {
        f'mc_x of {body}', f'mc_z of {body}', f'I_yy of {body}'}
    assert set(base.unexcited_names()) == {f'{p} of {body}' for p in (
        'm', 'mc_y', 'I_xx', 'I_xy', 'I_xz', 'I_yz', 'I_zz')}


def test_ur5_has_36_base_parameters_and_its_shoulder_mass_is_unexcited():
    model = sd.Model.from_urdf(robot_urdf_path('ur5'))
    base = base_parameters(model)
    assert base.rank == 36          # the known count for a 6R arm of this geometry
    unexcited = set(base.unexcited_names())
    for p in ('m', 'mc_x', 'mc_y', 'mc_z', 'I_xx', 'I_xy', 'I_xz', 'I_yz'):
        assert f'{p} of shoulder_link' in unexcited, p
    assert 'I_zz of shoulder_link' not in unexcited        # it turns about z: it is felt


def test_base_regressor_reproduces_the_torques_on_unseen_states():
    for path in (DEMO_URDF, robot_urdf_path('ur5'), robot_urdf_path('panda')):
        model = sd.Model.from_urdf(path)
        base = base_parameters(model, seed=1)
        q, qd, qdd = random_states(model, 25, seed=99)
        Y = sd.regressor(model, q, qd, qdd)
        pi = parameters(model)
        tau = sd.rnea(model, q, qd, qdd)
        np.testing.assert_allclose(base.columns(Y) @ base.beta(pi), tau, rtol=0,
                                   atol=1e-10 * np.abs(tau).max())
        # and the names describe every base parameter from its combination
        assert all(base.describe(k).startswith(base.names[base.independent[k]])
                   for k in range(base.rank))


def test_a_recording_moving_one_joint_determines_little():
    """Joint 2 of the UR5 alone, the others held: far fewer base parameters, named."""
    model = sd.Model.from_urdf(robot_urdf_path('ur5'))
    q, qd, qdd = random_states(model, 400, seed=3)
    held = [0, 2, 3, 4, 5]
    q[:, held] = q[0, held]          # the other joints held where they are
    qd[:, held] = qdd[:, held] = 0.0
    poor = base_parameters(model, (q, qd, qdd))
    full = base_parameters(model)
    # measured: 18 of 36, with 22 parameters felt by no torque instead of 9
    assert poor.rank <= full.rank // 2, (poor.rank, full.rank)
    assert len(poor.unexcited) > 2 * len(full.unexcited)


def test_a_payload_is_recovered_from_noisy_torques():
    """UR5 with 1.5 kg on tool0, torques with 0.05 N m of noise: mass, centre, inertia back."""
    from spatial_dynamics.identification import identify_payload
    model = sd.Model.from_urdf(robot_urdf_path('ur5'))
    true = dict(mass=1.5, com=(0.01, -0.02, 0.08),
                inertia=(0.004, 0.0002, -0.0001, 0.005, 0.0003, 0.003))
    heavy = sd.with_payload(model, 'tool0', **true)
    q, qd, qdd = random_states(model, 2000, seed=4)
    noise = 0.05
    tau = sd.rnea(heavy, q, qd, qdd) + np.random.default_rng(0).normal(0.0, noise, q.shape)
    payload = identify_payload(model, 'tool0', q, qd, qdd, tau)
    assert abs(payload.mass - 1.5) < 0.01 * 1.5
    assert abs(payload.mass - 1.5) < 5 * payload.sigma[0]     # the uncertainty is honest
    np.testing.assert_allclose(payload.com, true['com'], rtol=0, atol=1e-3)
    np.testing.assert_allclose(payload.inertia, true['inertia'], rtol=0, atol=1e-3)
    np.testing.assert_allclose(payload.rms, noise, rtol=0.1)   # what is left is the noise
    # what the node and a URDF take
    assert 'payload.link: tool0' in payload.node_parameters()
    assert f'<mass value="{payload.mass:.6g}"/>' in payload.urdf_inertial()
    # the identified payload makes the model predict the torques to the noise level
    fitted = sd.with_payload(model, 'tool0', payload.mass, payload.com, payload.inertia)
    residual = tau - sd.rnea(fitted, q, qd, qdd)
    assert np.sqrt(np.mean(residual ** 2)) < 1.1 * noise


def test_a_payload_the_recording_cannot_tell_is_refused_with_why():
    """Only the last joint turning: the wrist cannot tell the payload's mass from the arm's."""
    from spatial_dynamics.identification import identify_payload
    model = sd.Model.from_urdf(robot_urdf_path('ur5'))
    q, qd, qdd = random_states(model, 200, seed=5)
    held = [0, 1, 2, 3, 4]
    q[:, held] = q[0, held]
    qd[:, held] = qdd[:, held] = 0.0
    tau = sd.rnea(sd.with_payload(model, 'tool0', 1.0), q, qd, qdd)
    with pytest.raises(ValueError, match='determines only .* of the 10 payload parameters'):
        identify_payload(model, 'tool0', q, qd, qdd, tau)
    with pytest.raises(ValueError, match="link 'gripper' is not a link"):
        identify_payload(model, 'gripper', q, qd, qdd, tau)


def perturbed_ur5(seed=1):
    """Return the UR5 and a 'true' one: every body 25 % heavier (all ten parameters).

    The centres of mass are moved too.
    """
    from dataclasses import replace
    from spatial_dynamics.identification import _spatial_inertia
    model = sd.Model.from_urdf(robot_urdf_path('ur5'))
    rng = np.random.default_rng(seed)
    inertia = np.array(model.inertia)
    pi = parameters(model)
    for i in range(model.NB):
        p = 1.25 * pi[10 * i:10 * i + 10]
        p[1:4] += p[0] * rng.normal(0.0, 0.01, 3)          # ~1 cm shifts
        inertia[i + 1] = _spatial_inertia(p)
    return model, replace(model, inertia=inertia)


def test_inertias_fitted_stay_physical_and_predict_held_out_motion():
    """Fit all bodies of a UR5 whose URDF is 25 % off, on noisy torques; check on new motion."""
    from spatial_dynamics.identification import identify_inertias, pseudo_inertia
    model, true = perturbed_ur5()
    q, qd, qdd = random_states(model, 1500, seed=2)
    noise = 0.05
    tau = sd.rnea(true, q, qd, qdd) + np.random.default_rng(3).normal(0.0, noise, q.shape)
    fit = identify_inertias(model, q, qd, qdd, tau)
    np.testing.assert_allclose(fit.after, noise, rtol=0.1)          # down to the noise
    assert (fit.before > 5 * noise).sum() >= 4                      # the URDF was far off
    for i in range(model.NB):   # every body realisable: its pseudo-inertia is U Uᵀ, so
        # positive semi-definite; eigvalsh rounds a zero eigenvalue to ±1e-15 of the largest
        w = np.linalg.eigvalsh(pseudo_inertia(fit.pi[10 * i:10 * i + 10]))
        assert w.min() >= -1e-12 * w.max(), w
    # held-out motion the fit never saw: within 2x the noise, the URDF's error far above
    qv, qdv, qddv = random_states(model, 300, seed=9)
    truth = sd.rnea(true, qv, qdv, qddv)
    Y = sd.regressor(model, qv, qdv, qddv)
    fitted = np.sqrt(np.mean((Y @ fit.pi - truth) ** 2, axis=0))
    urdf = np.sqrt(np.mean((Y @ parameters(model) - truth) ** 2, axis=0))
    assert (fitted < 2 * noise).all(), fitted
    assert (urdf > 10 * fitted).sum() >= 4, (urdf, fitted)


def test_what_the_recording_cannot_tell_stays_at_the_urdf_values():
    """Only joint 2 moves: the shoulder link's mass (felt by no torque) keeps its URDF value."""
    from spatial_dynamics.identification import identify_inertias
    model, true = perturbed_ur5()
    q, qd, qdd = random_states(model, 400, seed=3)
    held = [0, 2, 3, 4, 5]
    q[:, held] = q[0, held]
    qd[:, held] = qdd[:, held] = 0.0
    fit = identify_inertias(model, q, qd, qdd, sd.rnea(true, q, qd, qdd))
    urdf = parameters(model)
    assert fit.pi[0] == pytest.approx(urdf[0], rel=1e-6)   # m of shoulder_link
    assert fit.after.max() < 1e-3 * max(1.0, fit.before.max())   # what is felt, is fitted


def test_the_recording_is_summed_in_chunks_without_changing_the_least_squares(monkeypatch):
    """|F x − f|² = |A x − b|² for any x: the chunked square root is the stacked system.

    ``A`` is the stacked regressor of chosen bodies' columns with the drive columns, ``b``
    the torque less the other bodies' share, built here directly from ``sd.regressor``.
    """
    from spatial_dynamics import identification
    model, true = perturbed_ur5()
    q, qd, qdd = random_states(model, 700, seed=4)
    tau = sd.rnea(true, q, qd, qdd) + 0.3 * np.tanh(qd / 0.01)
    pi0 = parameters(model)
    cols = np.arange(20, 60)                                # bodies 3..6
    monkeypatch.setattr(identification, 'CHUNK', 128)       # several chunks, a short last one
    F = identification._square_root(model, (q, qd, qdd), tau, (0.0, 0.0, -9.81), cols, pi0,
                                    0.01)
    Y = sd.regressor(model, q, qd, qdd)
    fixed = np.setdiff1d(np.arange(10 * model.NB), cols)
    b = (tau - Y[..., fixed] @ pi0[fixed]).reshape(-1)
    n = model.nq
    drive = np.zeros((len(q), n, 3 * n))
    for j in range(n):
        drive[:, j, 3 * j:3 * j + 3] = np.column_stack(
            [qd[:, j], np.tanh(qd[:, j] / 0.01), qdd[:, j]])
    A = np.hstack([Y[..., cols].reshape(len(b), -1), drive.reshape(len(b), -1)])
    rng = np.random.default_rng(0)
    for x in [np.zeros(A.shape[1])] + [rng.normal(size=A.shape[1]) for _ in range(3)]:
        direct = np.sum((A @ x - b) ** 2)
        assert np.sum((F[:, :-1] @ x - F[:, -1]) ** 2) == pytest.approx(direct, rel=1e-9)
