# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Physics and algebra identities on seeded random trees and random spatial quantities.

- mass matrix from unit accelerations, M[:, j] = rnea(q, 0, e_j, gravity=0): symmetric,
  positive definite, tau(q, qd, qdd) - tau(q, qd, 0) = M qdd, 1/2 qd^T M qd = Pinocchio's
  kinetic energy;
- gravity torque = dV/dq (finite differences of Pinocchio's potential energy);
- power balance qd . tau = dE/dt along a smooth trajectory;
- invariance when the URDF is re-expressed (fixed frames inserted and compensated, inertials
  moved onto fixed children);
- spatial algebra: crf = -crm^T, transform/inverse round trips, plux_force = inv(X)^T, scalar
  product invariance, v x v = 0, mcI against its definition, batch shapes.
"""

from conftest import PinOracle, random_state
import numpy as np
import pytest
import spatial_dynamics as sd
from spatial_dynamics import spatial as sp
from urdf_gen import insert_fixed_frame, move_inertial_to_fixed_child, random_rotation
from urdf_gen import random_tree_urdf

G = (0.0, 0.0, -9.81)
ZERO_G = (0.0, 0.0, 0.0)

# (seed, n_links, branching, mimic)
TREES = [(1, 2, False, False), (2, 5, True, False), (3, 7, False, True), (4, 9, True, True),
         (5, 12, True, True), (6, 16, True, False), (7, 16, False, True), (8, 24, True, True)]
TREE_IDS = [f'seed{s}-{n}links-{"tree" if b else "chain"}{"-mimic" if m else ""}'
            for s, n, b, m in TREES]


def tree(seed, n_links, branching, mimic, p_inertial=0.8):
    """Return (URDF XML, Model, PinOracle, rng) of a seeded random tree."""
    rng = np.random.default_rng(seed)
    xml = random_tree_urdf(rng, n_links, branching=branching, mimic=mimic,
                           p_inertial=p_inertial)
    return xml, sd.Model.from_urdf(xml), PinOracle(xml), rng


def mass_matrix(model, q):
    """Return M(q) from n unit accelerations in one batched call (column j = rnea(e_j))."""
    n = len(model.joint_names)
    Q = np.broadcast_to(q, (n, n)).copy()
    tau = sd.rnea(model, Q, np.zeros((n, n)), np.eye(n), gravity=ZERO_G)
    return tau.T


def five_point(fun, x, h):
    """Return the 5-point central difference derivative of fun at x (error O(h^4))."""
    return (fun(x - 2 * h) - 8 * fun(x - h) + 8 * fun(x + h) - fun(x + 2 * h)) / (12 * h)


# --------------------------------------------------------------------------------------------
# Mass matrix


@pytest.mark.parametrize('seed,n_links,branching,mimic', TREES, ids=TREE_IDS)
def test_mass_matrix_symmetric_positive_definite(seed, n_links, branching, mimic):
    xml, model, oracle, rng = tree(seed, n_links, branching, mimic, p_inertial=1.0)
    n = len(model.joint_names)
    for _ in range(5):
        q = rng.uniform(-2.0, 2.0, n)
        M = mass_matrix(model, q)
        scale = np.abs(M).max()
        assert np.abs(M - M.T).max() <= 1e-12 * scale
        eig = np.linalg.eigvalsh(0.5 * (M + M.T))
        assert eig.min() > 1e-9 * eig.max(), eig


@pytest.mark.parametrize('seed,n_links,branching,mimic', TREES, ids=TREE_IDS)
def test_mass_matrix_psd_with_massless_links(seed, n_links, branching, mimic):
    xml, model, oracle, rng = tree(seed, n_links, branching, mimic, p_inertial=0.5)
    n = len(model.joint_names)
    q = rng.uniform(-2.0, 2.0, n)
    M = mass_matrix(model, q)
    scale = max(np.abs(M).max(), 1.0)
    assert np.abs(M - M.T).max() <= 1e-12 * scale
    assert np.linalg.eigvalsh(0.5 * (M + M.T)).min() >= -1e-12 * scale


@pytest.mark.parametrize('seed,n_links,branching,mimic', TREES, ids=TREE_IDS)
def test_tau_affine_in_qdd_and_kinetic_energy(seed, n_links, branching, mimic):
    """tau(q, qd, qdd) - tau(q, qd, 0) = M(q) qdd; 1/2 qd^T M qd = Pinocchio's kinetic energy."""
    xml, model, oracle, rng = tree(seed, n_links, branching, mimic)
    n = len(model.joint_names)
    for _ in range(4):
        q, qd, qdd = random_state(rng, (), n)
        M = mass_matrix(model, q)
        tau = sd.rnea(model, q, qd, qdd, gravity=G)
        tau0 = sd.rnea(model, q, qd, np.zeros(n), gravity=G)
        assert np.abs((tau - tau0) - M @ qdd).max() <= 1e-10
        T = 0.5 * qd @ M @ qd
        T_pin = oracle.kinetic_energy(model.joint_names, q, qd)
        assert abs(T - T_pin) <= 1e-11 * max(1.0, abs(T_pin))


# --------------------------------------------------------------------------------------------
# Gravity and energy


def test_pinocchio_potential_energy_sign():
    """V = m g h for a point raised by h against gravity (Pinocchio's convention, checked)."""
    urdf = ('<robot name="lift"><link name="base"/><link name="box"><inertial>'
            '<mass value="2.0"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" '
            'izz="0.1"/></inertial></link><joint name="z" type="prismatic"><parent link="base"/>'
            '<child link="box"/><axis xyz="0 0 1"/><limit effort="1" velocity="1" lower="-1" '
            'upper="1"/></joint></robot>')
    oracle = PinOracle(urdf)
    V0 = oracle.potential_energy(['z'], np.array([0.0]), G)
    V1 = oracle.potential_energy(['z'], np.array([0.5]), G)
    assert V1 - V0 == pytest.approx(2.0 * 9.81 * 0.5, rel=1e-14)


@pytest.mark.parametrize('seed,n_links,branching,mimic', TREES, ids=TREE_IDS)
@pytest.mark.parametrize('gravity', [G, (3.0, -4.0, 1.5)], ids=['g_z', 'g_oblique'])
def test_gravity_torque_is_gradient_of_potential(seed, n_links, branching, mimic, gravity):
    xml, model, oracle, rng = tree(seed, n_links, branching, mimic)
    names = model.joint_names
    n = len(names)
    h = 1e-3
    for _ in range(3):
        q = rng.uniform(-2.0, 2.0, n)
        z = np.zeros(n)
        tau_g = sd.rnea(model, q, z, z, gravity=gravity)
        dV = np.array([five_point(lambda s: oracle.potential_energy(names, q + s * e, gravity),
                                  0.0, h) for e in np.eye(n)])
        scale = max(1.0, np.abs(tau_g).max())
        assert np.abs(tau_g - dV).max() <= 1e-8 * scale, (tau_g, dV)


@pytest.mark.parametrize('seed,n_links,branching,mimic', TREES, ids=TREE_IDS)
def test_power_balance_along_trajectory(seed, n_links, branching, mimic):
    """Power balance q̇·τ = dE/dt, E = ½ q̇ᵀ M q̇ + V, along q(t) = q0 + A sin(w t + phi)."""
    xml, model, oracle, rng = tree(seed, n_links, branching, mimic)
    names = model.joint_names
    n = len(names)
    q0 = rng.uniform(-1.0, 1.0, n)
    A = rng.uniform(0.2, 1.0, n)
    w = rng.uniform(0.5, 3.0, n)
    phi = rng.uniform(-np.pi, np.pi, n)

    def state(t):
        s, c = np.sin(w * t + phi), np.cos(w * t + phi)
        return q0 + A * s, A * w * c, -A * w * w * s

    def energy(t):
        q, qd, _ = state(t)
        return 0.5 * qd @ mass_matrix(model, q) @ qd + oracle.potential_energy(names, q, G)

    for t in np.linspace(0.0, 2.0, 5):
        q, qd, qdd = state(t)
        tau = sd.rnea(model, q, qd, qdd, gravity=G)
        power = qd @ tau
        dE = five_point(energy, t, 1e-3)
        scale = max(1.0, np.abs(qd * tau).sum())
        assert abs(power - dE) <= 1e-7 * scale, (power, dE)


# --------------------------------------------------------------------------------------------
# Re-expressing the URDF does not change the dynamics


def permutation(names, names2):
    """Return p with names2 == names[p] (the joint order follows the URDF's declarations)."""
    assert sorted(names2) == sorted(names)
    return np.array([names.index(name) for name in names2])


@pytest.mark.parametrize('seed,n_links,branching,mimic', TREES, ids=TREE_IDS)
def test_invariant_under_inserted_fixed_frames(seed, n_links, branching, mimic):
    xml, model, oracle, rng = tree(seed, n_links, branching, mimic)
    names = model.joint_names
    q, qd, qdd = random_state(rng, (4,), len(names))
    tau = sd.rnea(model, q, qd, qdd, gravity=G)
    for i in range(1, n_links):
        xml2 = insert_fixed_frame(xml, f'joint_{i}', rng=rng)
        model2 = sd.Model.from_urdf(xml2)
        p = permutation(names, model2.joint_names)
        tau2 = sd.rnea(model2, q[..., p], qd[..., p], qdd[..., p], gravity=G)
        assert np.abs(tau2 - tau[..., p]).max() <= 1e-10, f'joint_{i}'


@pytest.mark.parametrize('seed,n_links,branching,mimic', TREES, ids=TREE_IDS)
def test_invariant_under_inertial_moved_to_fixed_child(seed, n_links, branching, mimic):
    xml, model, oracle, rng = tree(seed, n_links, branching, mimic)
    names = model.joint_names
    q, qd, qdd = random_state(rng, (4,), len(names))
    f_ext = {f'link_{n_links - 1}': rng.normal(0.0, 5.0, 6)}
    tau = sd.rnea(model, q, qd, qdd, gravity=G, f_ext=f_ext)
    xml2 = xml
    for i in range(n_links):
        xml2 = move_inertial_to_fixed_child(xml2, f'link_{i}', rng)
    model2 = sd.Model.from_urdf(xml2)
    p = permutation(names, model2.joint_names)
    tau2 = sd.rnea(model2, q[..., p], qd[..., p], qdd[..., p], gravity=G, f_ext=f_ext)
    assert np.abs(tau2 - tau[..., p]).max() <= 1e-10


def test_rnea_batch_shapes_match_single_calls():
    xml, model, oracle, rng = tree(4, 9, True, True)
    n = len(model.joint_names)
    for shape in [(), (1,), (5,), (2, 3)]:
        q, qd, qdd = random_state(rng, shape, n)
        tau = sd.rnea(model, q, qd, qdd, gravity=G)
        assert tau.shape == shape + (n,)
        rows = zip(q.reshape(-1, n), qd.reshape(-1, n), qdd.reshape(-1, n))
        flat = [sd.rnea(model, *x, gravity=G) for x in rows]
        assert np.abs(tau.reshape(-1, n) - np.array(flat)).max() <= 1e-12


# --------------------------------------------------------------------------------------------
# Spatial algebra

BATCH = (4, 5)


@pytest.fixture
def srng():
    return np.random.default_rng(7)


def random_X(rng, batch=BATCH):
    """Return (X, E, r): random Plücker motion transforms with their E and r."""
    E = np.array([random_rotation(rng) for _ in range(int(np.prod(batch)))]).reshape(
        batch + (3, 3))
    r = rng.normal(0.0, 1.0, batch + (3,))
    return sp.plux(E, r), E, r


def test_skew_is_cross_product(srng):
    w, u = srng.normal(size=BATCH + (3,)), srng.normal(size=BATCH + (3,))
    S = sp.skew(w)
    assert S.shape == BATCH + (3, 3)
    assert np.allclose(S @ u[..., None], np.cross(w, u)[..., None], rtol=0, atol=1e-14)
    assert np.array_equal(S, -np.swapaxes(S, -1, -2))


def test_crm_crf_duality_and_definition(srng):
    v, m = srng.normal(size=BATCH + (6,)), srng.normal(size=BATCH + (6,))
    C, Cf = sp.crm(v), sp.crf(v)
    assert C.shape == Cf.shape == BATCH + (6, 6)
    assert np.allclose(Cf, -np.swapaxes(C, -1, -2), rtol=0, atol=1e-15)
    w, vo, mw, mv = v[..., :3], v[..., 3:], m[..., :3], m[..., 3:]
    expected = np.concatenate([np.cross(w, mw), np.cross(w, mv) + np.cross(vo, mw)], -1)
    assert np.allclose((C @ m[..., None])[..., 0], expected, rtol=0, atol=1e-14)
    # v x v = 0
    assert np.abs((C @ v[..., None])[..., 0]).max() <= 1e-14


def test_crm_transforms_like_a_tensor(srng):
    """crm(X m) = X crm(m) X^-1."""
    X, _, _ = random_X(srng)
    m = srng.normal(size=BATCH + (6,))
    lhs = sp.crm((X @ m[..., None])[..., 0])
    rhs = X @ sp.crm(m) @ np.linalg.inv(X)
    assert np.allclose(lhs, rhs, rtol=0, atol=1e-12)


def test_plux_structure(srng):
    X, E, r = random_X(srng)
    assert X.shape == BATCH + (6, 6)
    assert np.allclose(X[..., :3, :3], E, rtol=0, atol=0)
    assert np.allclose(X[..., 3:, 3:], E, rtol=0, atol=0)
    assert np.array_equal(X[..., :3, 3:], np.zeros(BATCH + (3, 3)))
    assert np.allclose(X[..., 3:, :3], -E @ sp.skew(r), rtol=0, atol=1e-15)


@pytest.mark.parametrize('name,E', [
    ('rotx', lambda c, s: [[1, 0, 0], [0, c, s], [0, -s, c]]),
    ('roty', lambda c, s: [[c, 0, -s], [0, 1, 0], [s, 0, c]]),
    ('rotz', lambda c, s: [[c, s, 0], [-s, c, 0], [0, 0, 1]]),
])
def test_rot_xyz_match_featherstone(name, E):
    theta = np.linspace(-3.0, 3.0, 7)
    X = getattr(sp, name)(theta)
    assert X.shape == (7, 6, 6)
    for t, Xt in zip(theta, X):
        Et = np.array(E(np.cos(t), np.sin(t)), dtype=float)
        assert np.allclose(Xt, sp.plux(Et, np.zeros(3)), rtol=0, atol=1e-15)
        assert np.allclose(getattr(sp, name)(t), Xt, rtol=0, atol=0)
    assert getattr(sp, name)(0.3).shape == (6, 6)
    assert getattr(sp, name)(np.zeros((2, 3))).shape == (2, 3, 6, 6)


def test_xlt(srng):
    r = srng.normal(size=BATCH + (3,))
    X = sp.xlt(r)
    assert X.shape == BATCH + (6, 6)
    expected = np.zeros(BATCH + (6, 6))
    expected[..., :3, :3] = np.eye(3)
    expected[..., 3:, 3:] = np.eye(3)
    expected[..., 3:, :3] = -sp.skew(r)
    assert np.allclose(X, expected, rtol=0, atol=0)
    assert np.allclose(X, sp.plux(np.broadcast_to(np.eye(3), BATCH + (3, 3)), r), atol=0)


def test_plux_inverse_round_trip(srng):
    X, E, r = random_X(srng)
    Xi = sp.plux_inv(X)
    eye = np.broadcast_to(np.eye(6), BATCH + (6, 6))
    assert np.allclose(Xi @ X, eye, rtol=0, atol=1e-13)
    assert np.allclose(X @ Xi, eye, rtol=0, atol=1e-13)
    assert np.allclose(Xi, np.linalg.inv(X), rtol=0, atol=1e-13)
    # the inverse of plux(E, r) is plux(E^T, -E r)
    assert np.allclose(Xi, sp.plux(np.swapaxes(E, -1, -2), -(E @ r[..., None])[..., 0]),
                       rtol=0, atol=1e-13)


def test_plux_force_and_scalar_product_invariance(srng):
    X, _, _ = random_X(srng)
    Xf = sp.plux_force(X)
    assert Xf.shape == BATCH + (6, 6)
    assert np.allclose(Xf, np.swapaxes(np.linalg.inv(X), -1, -2), rtol=0, atol=1e-13)
    m, f = srng.normal(size=BATCH + (6,)), srng.normal(size=BATCH + (6,))
    Xm, Xf_f = (X @ m[..., None])[..., 0], (Xf @ f[..., None])[..., 0]
    assert np.allclose((Xm * Xf_f).sum(-1), (m * f).sum(-1), rtol=1e-13, atol=1e-13)
    # composition: cXa = cXb bXa, and likewise for forces
    Y, _, _ = random_X(srng)
    assert np.allclose(sp.plux_force(Y @ X), sp.plux_force(Y) @ Xf, rtol=0, atol=1e-12)


def test_force_cross_product_dual(srng):
    """(v x m) . f = -m . (v x* f)."""
    v, m, f = (srng.normal(size=BATCH + (6,)) for _ in range(3))
    lhs = ((sp.crm(v) @ m[..., None])[..., 0] * f).sum(-1)
    rhs = -(m * (sp.crf(v) @ f[..., None])[..., 0]).sum(-1)
    assert np.allclose(lhs, rhs, rtol=1e-13, atol=1e-13)


def test_mcI_against_definition(srng):
    m = srng.uniform(0.1, 5.0, BATCH)
    c = srng.normal(size=BATCH + (3,))
    R = np.array([random_rotation(srng) for _ in range(int(np.prod(BATCH)))]).reshape(
        BATCH + (3, 3))
    Ic = R @ (np.diag([0.3, 0.4, 0.5]) * m[..., None, None]) @ np.swapaxes(R, -1, -2)
    Ii = sp.mcI(m, c, Ic)
    assert Ii.shape == BATCH + (6, 6)
    C = sp.skew(c)
    mm = m[..., None, None]
    expected = np.zeros(BATCH + (6, 6))
    expected[..., :3, :3] = Ic - mm * C @ C
    expected[..., :3, 3:] = mm * C
    expected[..., 3:, :3] = -mm * C
    expected[..., 3:, 3:] = mm * np.eye(3)
    assert np.allclose(Ii, expected, rtol=0, atol=1e-13)
    # momentum from first principles: h = [Ic w + c x m vc; m vc], vc = vo + w x c
    v = srng.normal(size=BATCH + (6,))
    w, vo = v[..., :3], v[..., 3:]
    vc = vo + np.cross(w, c)
    h = np.concatenate([(Ic @ w[..., None])[..., 0] + np.cross(c, m[..., None] * vc),
                        m[..., None] * vc], -1)
    assert np.allclose((Ii @ v[..., None])[..., 0], h, rtol=0, atol=1e-12)
    # single (unbatched) call
    assert np.allclose(sp.mcI(m[0, 0], c[0, 0], Ic[0, 0]), expected[0, 0], rtol=0, atol=1e-13)


def test_inertia_transforms_as_force_from_motion(srng):
    """The same body's inertia in two frames: I_b = bXa_f I_a aXb, and kinetic energy agrees."""
    X, _, _ = random_X(srng)  # bXa
    m = srng.uniform(0.1, 5.0, BATCH)
    c = srng.normal(size=BATCH + (3,))
    Ia = sp.mcI(m, c, np.broadcast_to(np.diag([0.2, 0.3, 0.4]), BATCH + (3, 3)))
    Ib = sp.plux_force(X) @ Ia @ sp.plux_inv(X)
    va = srng.normal(size=BATCH + (6,))
    vb = (X @ va[..., None])[..., 0]
    Ta = (va * (Ia @ va[..., None])[..., 0]).sum(-1)
    Tb = (vb * (Ib @ vb[..., None])[..., 0]).sum(-1)
    assert np.allclose(Ta, Tb, rtol=1e-12, atol=1e-12)
    assert np.allclose(Ib, np.swapaxes(Ib, -1, -2), rtol=0, atol=1e-12)
