# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""g(q), C(q, q̇) q̇ + g(q) and M(q) (CRBA) against Pinocchio and the identities that tie them.

Pinocchio's oracle models a mimic joint as an independent joint; with ``v_pin = P q̇`` (``P``
the Jacobian of the mimic expansion) our inertia is ``Pᵀ M_pin P`` and our torques fold the
followers' onto their sources (``Pᵀ τ_pin``).
"""

from conftest import PinOracle, random_state, robot_urdf_path
import numpy as np
import pytest
import spatial_dynamics as sd
from spatial_dynamics.backends import compiled
from urdf_gen import random_tree_urdf

ROBOTS = ('ur5', 'panda', 'talos', 'solo12')
EPS = np.finfo(float).eps


@pytest.fixture(params=['numpy', 'compiled'])
def backend(request):
    if request.param == 'compiled':     # built with the package: its absence is a failure
        assert compiled.ext is not None, compiled.FAILURE
    return request.param


@pytest.fixture(scope='module', params=ROBOTS)
def robot(request):
    path = robot_urdf_path(request.param)
    return sd.Model.from_urdf(path), PinOracle(path)


def pin_terms(model, oracle, q, qd):
    """Pinocchio's g, C q̇ + g and M at one state, in our coordinates."""
    pin = oracle.pin
    q_pin, P = oracle.velocity_map(model.joint_names, q)
    v_pin = P @ qd
    g = pin.computeGeneralizedGravity(oracle.model, oracle.data, q_pin).copy()
    b = pin.nonLinearEffects(oracle.model, oracle.data, q_pin, v_pin).copy()
    M = pin.crba(oracle.model, oracle.data, q_pin).copy()
    M = np.triu(M) + np.triu(M, 1).T
    return P.T @ g, P.T @ b, P.T @ M @ P


def close(a, b, scale):
    """Agreement to 1e-12 relative to ``max(1, scale)``, normwise."""
    return np.abs(a - b).max() <= 1e-12 * max(1.0, scale)


def test_each_term_equals_pinocchio(robot, backend, rng):
    model, oracle = robot
    Q, QD, _ = random_state(rng, (4,), model.nq)
    ours_g = sd.gravity_torque(model, Q, backend=backend)
    ours_b = sd.bias_torque(model, Q, QD, backend=backend)
    ours_M = sd.mass_matrix(model, Q, backend=backend)
    assert ours_M.shape == (4, model.nq, model.nq)
    for s in range(4):
        g, b, M = pin_terms(model, oracle, Q[s], QD[s])
        assert close(ours_g[s], g, np.abs(g).max())
        assert close(ours_b[s], b, np.abs(b).max())
        assert close(ours_M[s], M, np.abs(M).max())
        # one state, the single-state entries
        assert close(sd.gravity_torque(model, Q[s], backend=backend), g, np.abs(g).max())
        assert close(sd.bias_torque(model, Q[s], QD[s], backend=backend), b, np.abs(b).max())
        assert close(sd.mass_matrix(model, Q[s], backend=backend), M, np.abs(M).max())


def test_inertial_plus_bias_is_rnea(robot, backend, rng):
    """M(q) q̈ + C(q, q̇) q̇ + g(q) = RNEA(q, q̇, q̈): the CRBA and the RNEA agree."""
    model, _ = robot
    Q, QD, QDD = random_state(rng, (16,), model.nq)
    tau = sd.rnea(model, Q, QD, QDD, backend=backend)
    M = sd.mass_matrix(model, Q, backend=backend)
    lhs = np.einsum('sij,sj->si', M, QDD) + sd.bias_torque(model, Q, QD, backend=backend)
    assert np.abs(lhs - tau).max() <= 1e-12 * max(1.0, np.abs(tau).max())


def test_mass_matrix_is_symmetric_positive_definite(robot, backend, rng):
    model, _ = robot
    Q, _, _ = random_state(rng, (16,), model.nq)
    M = sd.mass_matrix(model, Q, backend=backend)
    assert np.array_equal(M, np.swapaxes(M, -1, -2))      # built symmetric, exactly
    assert np.linalg.eigvalsh(M).min() > 0.0
    np.linalg.cholesky(M)


def test_power_balance_mdot_equals_twice_c(robot, rng):
    """q̇ᵀ Ṁ q̇ = 2 q̇ᵀ C q̇ (Ṁ - 2C is skew): M's derivative along q̇ against RNEA's C q̇."""
    model, _ = robot
    Q, QD, _ = random_state(rng, (8,), model.nq)
    h = 1e-5
    Mdot = (sd.mass_matrix(model, Q + h * QD) - sd.mass_matrix(model, Q - h * QD)) / (2 * h)
    Cqd = sd.bias_torque(model, Q, QD) - sd.gravity_torque(model, Q)
    lhs = np.einsum('si,sij,sj->s', QD, Mdot, QD)
    rhs = 2.0 * np.einsum('si,si->s', QD, Cqd)
    assert np.abs(lhs - rhs).max() <= 1e-6 * max(1.0, np.abs(rhs).max())


def test_gravity_and_bias_are_rnea_with_zero_rates(robot, backend, rng):
    model, _ = robot
    q, qd, _ = random_state(rng, (), model.nq)
    z = np.zeros(model.nq)
    g = (0.3, -1.0, -9.0)
    assert np.array_equal(sd.gravity_torque(model, q, g, backend=backend),
                          sd.rnea(model, q, z, z, g, backend=backend))
    assert np.array_equal(sd.bias_torque(model, q, qd, g, backend=backend),
                          sd.rnea(model, q, qd, z, g, backend=backend))


def test_backends_agree_on_trees_with_mimic_and_prismatic_joints(rng):
    for seed in range(6):
        xml = random_tree_urdf(np.random.default_rng(seed), 14, mimic=True)
        model = sd.Model.from_urdf(xml)
        Q, _, _ = random_state(rng, (5,), model.nq)
        a = sd.mass_matrix(model, Q, backend='numpy')
        b = sd.mass_matrix(model, Q, backend='compiled')
        # the columns of RNEA at q̇ = 0, q̈ = e_j, no gravity: an independent construction
        cols = np.stack([sd.rnea(model, Q, np.zeros_like(Q), np.broadcast_to(e, Q.shape),
                                 (0.0, 0.0, 0.0), backend='numpy')
                         for e in np.eye(model.nq)], axis=-1)
        scale = max(1.0, np.abs(cols).max())
        assert np.abs(a - cols).max() <= 1e-13 * scale
        assert np.abs(b - a).max() <= 1e-13 * scale


def test_a_model_too_large_for_the_stack_scratch(rng):
    """More bodies than the single-state entry keeps on the stack (2048 doubles): the heap."""
    xml = random_tree_urdf(np.random.default_rng(3), 128 + 20,
                           joint_kinds=('revolute', 'prismatic'))
    model = sd.Model.from_urdf(xml)
    assert model.nq + (model.NB + 1) * compiled.ext.WORK > 2048
    q, _, _ = random_state(rng, (), model.nq)
    a = sd.mass_matrix(model, q, backend='compiled')
    b = sd.mass_matrix(model, q, backend='numpy')
    assert np.abs(a - b).max() <= 1e-12 * max(1.0, np.abs(b).max())


def test_arguments(rng):
    model = sd.Model.from_urdf(robot_urdf_path('ur5'))
    q, _, _ = random_state(rng, (), model.nq)
    M = sd.mass_matrix(model, q)
    assert np.array_equal(sd.mass_matrix(model, q.tolist()), M)
    assert np.array_equal(sd.mass_matrix(model, tuple(q)), M)
    q32 = q.astype(np.float32)
    M32 = sd.mass_matrix(model, q32[None])
    assert M32.dtype == np.float32 and M32.shape == (1, 6, 6)
    assert np.abs(M32[0] - M).max() < 1e-4 * np.abs(M).max()
    # float32 states run on the kernels: the float64 M of the same numbers, rounded once
    # (numpy's backend computes in float32)
    assert compiled.ext is not None, compiled.FAILURE
    M_wide = sd.mass_matrix(model, q32.astype(np.float64))
    np.testing.assert_array_equal(M32[0], M_wide.astype(np.float32))
    np.testing.assert_array_equal(sd.mass_matrix(model, q32), M32[0])
    M32_numpy = sd.mass_matrix(model, q32[None], backend='numpy')
    assert M32_numpy.dtype == np.float32
    assert np.abs(M32_numpy[0] - M).max() < 1e-4 * np.abs(M).max()
    assert sd.mass_matrix(model, np.zeros((2, 3, 6))).shape == (2, 3, 6, 6)
    with pytest.raises(ValueError, match=r'q must have shape \(\.\.\., 6\)'):
        sd.mass_matrix(model, np.zeros(5))
    with pytest.raises(ValueError, match='q must have shape'):
        sd.gravity_torque(model, [0.0] * 7)


def test_generalized_momentum_is_m_qdot(robot, backend, rng):
    model, oracle = robot
    Q, QD, _ = random_state(rng, (6,), model.nq)
    p, _ = sd.generalized_momentum(model, Q, QD, backend=backend)
    M = sd.mass_matrix(model, Q, backend=backend)
    expected = np.einsum('sij,sj->si', M, QD)
    assert np.abs(p - expected).max() <= 1e-13 * max(1.0, np.abs(expected).max())
    p1, _ = sd.generalized_momentum(model, Q[2], QD[2], backend=backend)
    assert np.abs(p1 - expected[2]).max() <= 1e-13 * max(1.0, np.abs(expected).max())


def test_coriolis_transpose_against_pinocchio(robot, backend, rng):
    """Cᵀ q̇ against Pinocchio's Coriolis matrix (computeCoriolisMatrix, Ṁ = C + Cᵀ)."""
    model, oracle = robot
    pin = oracle.pin
    Q, QD, _ = random_state(rng, (4,), model.nq)
    _, ctq = sd.generalized_momentum(model, Q, QD, backend=backend)
    for s in range(4):
        q_pin, P = oracle.velocity_map(model.joint_names, Q[s])
        C = pin.computeCoriolisMatrix(oracle.model, oracle.data, q_pin, P @ QD[s])
        expected = P.T @ (C.T @ (P @ QD[s]))
        assert np.abs(ctq[s] - expected).max() <= 1e-12 * max(1.0, np.abs(expected).max())
        _, one = sd.generalized_momentum(model, Q[s], QD[s], backend=backend)
        assert np.abs(one - expected).max() <= 1e-12 * max(1.0, np.abs(expected).max())


def test_coriolis_transpose_is_the_gradient_of_kinetic_energy(robot, rng):
    """Cᵀ q̇ = ∂T/∂q with T = ½ q̇ᵀ M(q) q̇, by central differences of the CRBA."""
    model, _ = robot
    q, qd, _ = random_state(rng, (), model.nq)
    _, ctq = sd.generalized_momentum(model, q, qd)
    h = 1e-6
    grad = np.array([(qd @ sd.mass_matrix(model, q + h * e) @ qd
                      - qd @ sd.mass_matrix(model, q - h * e) @ qd) / (4 * h)
                     for e in np.eye(model.nq)])
    assert np.abs(ctq - grad).max() <= 1e-7 * max(1.0, np.abs(grad).max())
