# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The generalized momentum (and M) of a fixed-base model on a moving base (``base=``).

Oracles: Pinocchio's free-flyer model of the same URDF with the base's twist prescribed
(``p_j = (M ν)_j``, ``(Cᵀ ν)_j`` of its Coriolis matrix, ``ν = [v_b; q̇]``), and the momentum
balance of the joint rows: ``rnea(base=) = ṗ_j − (Cᵀ ν)_j + g_j`` along a trajectory of base
and joints, ``ṗ_j`` differentiated numerically.
"""

import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from conftest import robot_urdf_path, to_pin, unit_quaternions  # noqa: E402
import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics.joints import quaternion_matrix  # noqa: E402


@pytest.fixture(scope='module')
def ur5():
    return sd.Model.from_urdf(robot_urdf_path('ur5'))


@pytest.mark.parametrize('backend', ['numpy', 'auto'])
def test_momentum_joint_rows_of_the_free_flyer(ur5, backend):
    # p_j = M_jb v_b + M_jj q̇ and (Cᵀ ν)_j of Pinocchio's free-flyer UR5, base twist given
    # (its acceleration and orientation change neither), one state and a batch.
    pin = pytest.importorskip('pinocchio')
    pm = pin.buildModelFromUrdf(robot_urdf_path('ur5'), pin.JointModelFreeFlyer())
    pd = pm.createData()
    rng = np.random.default_rng(11)
    N = 12
    q, qd = rng.normal(size=(2, N, 6))
    v, a = rng.normal(size=(2, N, 6))
    quat = unit_quaternions(rng, N)
    p_ref, ct_ref = np.zeros((N, 6)), np.zeros((N, 6))
    for k in range(N):
        qk = np.r_[rng.normal(size=3), quat[k], q[k]]
        nu = to_pin(np.r_[v[k], qd[k]])
        M = pin.crba(pm, pd, qk)
        M = np.triu(M) + np.triu(M, 1).T
        C = pin.computeCoriolisMatrix(pm, pd, qk, nu)
        p_ref[k], ct_ref[k] = (M @ nu)[6:], (C.T @ nu)[6:]
    base = sd.BaseMotion(v, a, quat)
    p, ct = sd.generalized_momentum(ur5, q, qd, backend=backend, base=base)
    assert p.shape == ct.shape == (N, 6)
    np.testing.assert_allclose(p, p_ref, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(ct, ct_ref, rtol=1e-12, atol=1e-12)
    for k in (0, N - 1):    # one state; the orientation as a rotation matrix
        one = sd.BaseMotion(v[k], a[k], quaternion_matrix(quat[k]))
        p1, ct1 = sd.generalized_momentum(ur5, q[k], qd[k], backend=backend, base=one)
        np.testing.assert_allclose(p1, p_ref[k], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(ct1, ct_ref[k], rtol=1e-12, atol=1e-12)
    # a base at rest is the fixed base
    p0, ct0 = sd.generalized_momentum(ur5, q, qd, backend=backend,
                                      base=sd.BaseMotion.at_rest(quat))
    pf, ctf = sd.generalized_momentum(ur5, q, qd, backend=backend)
    np.testing.assert_allclose(p0, pf, rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(ct0, ctf, rtol=1e-13, atol=1e-13)


@pytest.mark.parametrize('backend', ['numpy', 'auto'])
def test_mass_matrix_does_not_depend_on_the_base(ur5, backend):
    # M_jj depends on q only: M(base=...) == M, broadcast against the base's batch.
    rng = np.random.default_rng(12)
    q = rng.normal(size=(5, 6))
    base = sd.BaseMotion(rng.normal(size=(5, 6)), rng.normal(size=(5, 6)),
                         unit_quaternions(rng, 5))
    M = sd.mass_matrix(ur5, q, backend=backend)
    assert np.array_equal(sd.mass_matrix(ur5, q, backend=backend, base=base), M)
    one = sd.BaseMotion(np.ones(6), np.ones(6))
    assert np.array_equal(sd.mass_matrix(ur5, q[0], backend=backend, base=one), M[0])
    wide = sd.mass_matrix(ur5, q[0], backend=backend, base=base)     # one q, five bases
    assert wide.shape == (5, 6, 6) and np.array_equal(wide, np.broadcast_to(M[0], (5, 6, 6)))
    with pytest.raises(TypeError, match='BaseMotion'):
        sd.mass_matrix(ur5, q, base=np.zeros(6))


def test_momentum_balance_along_a_trajectory(ur5):
    # The joint rows' momentum balance on a moving base: τ = ṗ_j − (Cᵀ ν)_j + g_j with
    # τ = rnea(q, q̇, q̈, base=(v_b, v̇_b, R)) and g_j the gravity torque at the base's
    # orientation (base at rest). ṗ by the fourth-order central difference with h = 1e-3 s:
    # truncation ~h⁴ p⁽⁵⁾/30 ~ 1e-12 for these O(1..10) motions, rounding ~eps |p| / h ~
    # 1e-12: asserted to 1e-8 of the torques' scale.
    w_b = np.array([0.3, -0.5, 0.8])          # base: turning and translating, body frame

    def state(t):
        s = np.arange(1, 7)
        q = 0.4 * np.sin(1.3 * s * t + s)
        qd = 0.4 * 1.3 * s * np.cos(1.3 * s * t + s)
        qdd = -0.4 * (1.3 * s) ** 2 * np.sin(1.3 * s * t + s)
        v = np.r_[w_b * np.cos(t), 0.5 * np.sin(2 * t), 0.2, -0.3 * t]
        a = np.r_[-w_b * np.sin(t), np.cos(2 * t), 0.0, -0.3]
        angle = 0.7 * t                       # the base's orientation: about a tilted axis
        axis = np.array([1.0, 2.0, 2.0]) / 3.0
        quat = np.r_[axis * np.sin(angle / 2), np.cos(angle / 2)]
        return q, qd, qdd, v, a, quat

    def momentum(t):
        q, qd, _, v, a, quat = state(t)
        return sd.generalized_momentum(ur5, q, qd, base=sd.BaseMotion(v, a, quat))[0]

    h = 1e-3
    for t in (0.2, 0.9, 1.7):
        q, qd, qdd, v, a, quat = state(t)
        base = sd.BaseMotion(v, a, quat)
        p_dot = (momentum(t - 2 * h) - 8 * momentum(t - h) + 8 * momentum(t + h)
                 - momentum(t + 2 * h)) / (12 * h)
        _, ctv = sd.generalized_momentum(ur5, q, qd, base=base)
        g = sd.gravity_torque(ur5, q, base=sd.BaseMotion.at_rest(quat))
        tau = sd.rnea(ur5, q, qd, qdd, base=base)
        np.testing.assert_allclose(p_dot - ctv + g, tau, rtol=0, atol=1e-8 * np.abs(tau).max())
        # without the base's twist the balance fails: the base's motion is in p
        p_fixed_dot = sum(c * sd.generalized_momentum(ur5, *state(t + k * h)[:2])[0]
                          for c, k in ((1, -2), (-8, -1), (8, 1), (-1, 2))) / (12 * h)
        assert np.abs(p_fixed_dot - sd.generalized_momentum(ur5, q, qd)[1] + g
                      - tau).max() > 1e-2
