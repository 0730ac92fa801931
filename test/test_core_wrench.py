# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The virtual F/T sensor: a wrench through τ = Jᵀ w and back, and what it cannot observe.

τ comes from RNEA's answer to ``f_ext`` (not from Jᵀ w), so the round trip also checks that
the sensor's Jacobian and the dynamics agree on frames and signs.
"""

import functools

from conftest import robot_urdf_path
import numpy as np
import pytest
import spatial_dynamics as sd
from spatial_dynamics.wrench import EPSILON, LAMBDA_MAX, wrench_from_torques
from urdf_gen import random_tree_urdf

UR5_GOOD = [0.3, -1.2, 1.5, -1.0, 1.2, 0.4]         # σ_min 0.21 (> ε): no damping
PANDA_GOOD = [0.1, -0.5, 0.2, -2.0, 0.3, 1.8, 0.5, 0.02]


@functools.lru_cache(maxsize=None)
def robot(name):
    return sd.Model.from_urdf(robot_urdf_path(name))


def torque_of(model, q, link, w):
    """τ the joints feel from the wrench w on link (RNEA: τ(f_ext) − τ(0) = −Jᵀ w)."""
    z = np.zeros(model.nq)
    return -(sd.rnea(model, q, z, z, gravity=(0, 0, 0), f_ext={link: w}))


@pytest.mark.parametrize('name,q,link', [('ur5', UR5_GOOD, 'tool0'),
                                         ('panda', PANDA_GOOD, 'panda_hand_tcp')])
def test_a_wrench_is_recovered_where_the_arm_is_well_conditioned(name, q, link, rng):
    model = robot(name)
    J = sd.jacobian(model, q, link)
    for _ in range(5):
        w = rng.normal(0.0, 20.0, 6)
        est = wrench_from_torques(J, torque_of(model, q, link, w))
        assert est.rank == 6 and est.damping == 0.0 and est.sigma_min > EPSILON
        assert not est.weak.any() and est.unobservable().shape == (6, 0)
        assert np.abs(est.wrench - w).max() <= 1e-9 * np.abs(w).max()
    # in base axes at the link origin: the same wrench rotated
    Jw = sd.jacobian(model, q, link, 'world')
    w = rng.normal(0.0, 20.0, 6)
    E = Jw[:3] @ np.linalg.pinv(J[:3])                  # base ← link rotation
    est = wrench_from_torques(Jw, torque_of(model, q, link, w))
    assert np.allclose(est.wrench, np.concatenate([E @ w[:3], E @ w[3:]]), atol=1e-9)


def test_three_joints_observe_the_projection_and_report_rank_three():
    xml = random_tree_urdf(np.random.default_rng(7), 4, branching=False,
                           joint_kinds=('revolute',))
    model = sd.Model.from_urdf(xml)
    assert model.nq == 3
    rng = np.random.default_rng(8)
    q = rng.uniform(-1.0, 1.0, 3)
    link = model.body_names[-1]
    J = sd.jacobian(model, q, link)
    w = rng.normal(0.0, 10.0, 6)
    est = wrench_from_torques(J, torque_of(model, q, link, w), lambda_max=0.0)
    assert est.rank == 3 and est.sigma_min == 0.0
    assert est.weak.sum() >= 3
    U3 = est.U[:, :3]                                   # the observable directions
    assert np.allclose(est.wrench, U3 @ (U3.T @ w), atol=1e-9)
    N = est.unobservable()
    assert N.shape[1] >= 3 and np.allclose(J.T @ N[:, -3:], 0.0, atol=1e-12)
    assert np.allclose(N.T @ est.wrench, 0.0, atol=1e-9)     # nothing along them


def test_near_the_wrist_singularity_the_estimate_stays_bounded_and_says_so(rng):
    model = robot('ur5')
    w = rng.normal(0.0, 20.0, 6)
    for q5 in (0.0, 1e-6, 1e-3):
        q = list(UR5_GOOD)
        q[4] = q5                                        # wrist 1 and 3 axes aligned
        J = sd.jacobian(model, q, 'tool0')
        tau = torque_of(model, q, 'tool0', w)
        noise = 1e-3 * rng.standard_normal(6)            # N m of torque noise
        est = wrench_from_torques(J, tau + noise)
        assert est.sigma_min < 1e-3 < EPSILON and est.damping > 0.9 * LAMBDA_MAX
        assert est.weak.sum() == 1 and est.rank == (5 if q5 == 0.0 else 6)
        # bounded: |ŵ| ≤ |τ| / (2 λ) along the damped direction, not |noise| / σ_min
        assert np.linalg.norm(est.wrench) <= np.linalg.norm(w) + np.linalg.norm(tau) / (
            2 * est.damping)
        # the well observed directions are still right
        good = est.U[:, ~est.weak]
        assert np.allclose(good.T @ est.wrench, good.T @ w, rtol=0.0, atol=0.05)


def test_batched_and_bad_shapes(rng):
    model = robot('ur5')
    Q = rng.uniform(-1.0, 1.0, (4, 6))
    J = sd.jacobian(model, Q, 'tool0')
    tau = rng.normal(0.0, 1.0, (4, 6))
    est = wrench_from_torques(J, tau)
    assert est.wrench.shape == (4, 6) and est.rank.shape == (4,)
    for k in range(4):
        assert np.allclose(est.wrench[k], wrench_from_torques(J[k], tau[k]).wrench)
    with pytest.raises(ValueError, match=r'tau must have shape \(\.\.\., 6\)'):
        wrench_from_torques(J[0], np.zeros(5))
    with pytest.raises(ValueError, match=r'J must have shape'):
        wrench_from_torques(np.zeros((5, 6)), np.zeros(6))
    with pytest.raises(ValueError, match='one state'):
        est.unobservable()
