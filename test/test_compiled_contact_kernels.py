# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The kernels of the contact path, ``bodies_kernel`` and ``split_kernel``: source, flat, C.

Each is one source in ``spatial_dynamics/algorithms`` (``jacobian.py``, ``split.py``) run on
Python floats, its flat listing (the rewrite the C is printed from), and the compiled entry
(``bodies``, ``bodies_batch``, ``split``): the same numbers. Oracles: ``sd.jacobian(...,
frame='world')`` for every body of a random tree with mimic joints, the numpy split (numpy's
QR) and, for redundant contact rows, the split by an SVD (conftest's ``least_torque_split``).
"""

import math
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from conftest import least_torque_split  # noqa: E402
from urdf_gen import random_tree_urdf  # noqa: E402
import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics.algorithms.jacobian import bodies_kernel, PLACEMENT  # noqa: E402
from spatial_dynamics.algorithms.rnea import xup_kernel  # noqa: E402
from spatial_dynamics.algorithms.split import RANK_TOLERANCE, split_kernel  # noqa: E402
from spatial_dynamics.backends import codegen, compiled, layout  # noqa: E402

needs_ext = pytest.mark.skipif(compiled.ext is None, reason='built without the kernels')


@pytest.fixture(scope='module')
def tree():
    """Return a fixed-base random tree of 9 bodies, branching, with mimic joints."""
    return sd.Model.from_urdf(random_tree_urdf(np.random.default_rng(5), 9, branching=True,
                                               mimic=True))


def source_bodies(model, q):
    """Return ``bodies_kernel`` of the source on Python floats: (NB + 1, 16 + 6 nv)."""
    rows = layout.of(model).rows
    Xup = [None] * len(rows)
    xup_kernel(rows, q.tolist(), math, Xup)
    J = [0.0] * (len(rows) * (PLACEMENT + 6 * model.nv))
    bodies_kernel(rows, Xup, J)
    return np.array(J).reshape(len(rows), -1)


def test_bodies_source_is_every_body_world_jacobian(tree):
    rng = np.random.default_rng(1)
    q = rng.normal(size=tree.nq)
    rows = source_bodies(tree, q)
    for link, frame in tree.frames.items():
        if frame.body > 0 and np.array_equal(frame.lXb, np.eye(6)):
            np.testing.assert_allclose(rows[frame.body, PLACEMENT:].reshape(6, tree.nv),
                                       sd.jacobian(tree, q, link, frame='world'), rtol=0,
                                       atol=1e-12)
    np.testing.assert_array_equal(rows[:, 12:16], np.tile([0.0, 0.0, 0.0, 1.0], (len(rows), 1)))


@needs_ext
def test_bodies_flat_and_compiled_compute_what_the_source_computes(tree):
    rng = np.random.default_rng(2)
    q = rng.normal(size=tree.nq)
    lay = layout.of(tree)
    flat = codegen.flat_module()
    work = np.zeros(lay.table.shape[0] * flat.WORK)
    J = np.zeros(lay.table.shape[0] * (PLACEMENT + 6 * tree.nv))
    flat.xup_kernel(lay.table, q, work)
    flat.bodies_kernel(lay.table, work, J)
    expected = source_bodies(tree, q)
    assert J.reshape(expected.shape).tolist() == expected.tolist()
    np.testing.assert_allclose(compiled.ext.bodies(lay.kernels, q), expected, rtol=0, atol=1e-14)
    out = np.empty((3,) + expected.shape)
    compiled.ext.bodies_batch(lay.kernels, 3, np.tile(q, (3, 1)), out, 2)
    np.testing.assert_array_equal(out, np.broadcast_to(compiled.ext.bodies(lay.kernels, q),
                                                       out.shape))


def split_problem(rng, k=12, n=12, nb=6):
    """Return a random ``[J_cᵀ, b, Sᵀ]`` by columns ((k + 1 + n, nv)), weights' roots."""
    nv = nb + n
    QR = np.zeros((k + 1 + n, nv))
    QR[:k] = rng.normal(size=(k, nv))
    QR[:k, :nb] += 3.0 * np.eye(k, nb)                  # the contacts carry the base, well
    QR[k] = rng.normal(size=nv) * 10.0
    QR[k + 1:, nb:] = np.eye(n)
    return QR, np.sqrt(rng.uniform(0.5, 2.0, n))


def numpy_split(QR, k, w):
    """Return the numpy split of ``contact_inverse_dynamics`` (its equations, numpy's QR)."""
    Jc, b = QR[:k], QR[k]
    Q, R = np.linalg.qr(Jc.T, mode='complete')
    Q1, Q2 = Q[:, :k], Q[:, k:]
    A, y = Q2[-len(w):].T / w, Q2.T @ b
    tau = A.T @ np.linalg.solve(A @ A.T, y) / w
    rest = b.copy()
    rest[-len(w):] -= tau
    return tau, np.linalg.solve(R[:k], Q1.T @ rest)


def scratch(k, nv):
    """Return the split's scratch: the pivots, then A Aᵀ's factor or the second QR."""
    return np.zeros(k + (nv + k + 2) * nv)


def run_split(QR, k, w):
    """Run the source, the flat listing and the compiled entry; assert them alike.

    Returns the source's ``res``: ``τ`` (n), ``λ`` (k), the status, the rank.
    """
    n, nv = len(w), QR.shape[1]
    flat = codegen.flat_module()
    res = [0.0] * (n + k + 2)
    split_kernel(QR.ravel().tolist(), k, n, nv - n, w.tolist(), res, scratch(k, nv).tolist(),
                 RANK_TOLERANCE, math)
    flat_res = np.zeros(n + k + 2)
    flat.split_kernel(QR.ravel().copy(), k, n, nv - n, w, flat_res, scratch(k, nv),
                      RANK_TOLERANCE)
    assert flat_res.tolist() == res
    c_res = np.zeros(n + k + 2)
    compiled.ext.split(QR.copy(), k, w, c_res, scratch(k, nv), RANK_TOLERANCE)
    scale = max(1.0, np.abs(res[:-2]).max())
    np.testing.assert_allclose(c_res, res, rtol=0, atol=1e-14 * scale)
    return np.array(res)


@needs_ext
@pytest.mark.parametrize('k', [6, 9, 12, 15])
def test_split_source_flat_and_compiled_against_numpy(k):
    rng = np.random.default_rng(k)
    for _ in range(5):
        QR, w = split_problem(rng, k)
        n = len(w)
        tau, lam = numpy_split(QR, k, w)
        res = run_split(QR, k, w)
        assert res[n + k] == 0.0 and res[n + k + 1] == k
        scale = max(1.0, np.abs(np.r_[tau, lam]).max())
        np.testing.assert_allclose(res[:n], tau, rtol=0, atol=1e-12 * scale)
        np.testing.assert_allclose(res[n:n + k], lam, rtol=0, atol=1e-12 * scale)


@needs_ext
@pytest.mark.parametrize('k, copies', [(12, ((11, 10),)), (12, ((3, 0), (4, 1))),
                                       (15, ((0, 9), (5, 14), (7, 2))), (18, ((17, 2),)),
                                       (24, ((20, 1), (21, 5)))])
def test_split_of_redundant_rows_is_the_least_torque(k, copies):
    """Rows that copy others, anywhere in J_c, up to k ≥ nv: the SVD split's τ and least λ."""
    rng = np.random.default_rng(k + len(copies))
    for _ in range(3):
        QR, w = split_problem(rng, k)
        w = np.ones_like(w)
        for row, of in copies:                     # a row equal to another times a factor
            QR[row] = QR[of] * rng.uniform(0.5, 2.0)
        n = len(w)
        tau, lam, rank = least_torque_split(QR[:k], QR[k], RANK_TOLERANCE)
        res = run_split(QR, k, w)
        assert res[n + k] == 0.0 and res[n + k + 1] == rank < k
        scale = max(1.0, np.abs(np.r_[tau, lam]).max())
        np.testing.assert_allclose(res[:n], tau, rtol=0, atol=1e-11 * scale)
        np.testing.assert_allclose(res[n:n + k], lam, rtol=0, atol=1e-11 * scale)


@needs_ext
def test_split_leaves_uncarried_bases_to_numpy():
    rng = np.random.default_rng(9)
    QR, w = split_problem(rng, 6)
    QR[:6, :6] = 0.0                                    # no contact row reaches the base
    assert run_split(QR, 6, w)[-2] == 1.0
    QR, w = split_problem(rng, 12)
    QR[:12] = QR[0]                                     # twelve rows, one direction: rank 1
    assert run_split(QR, 12, w)[-2:].tolist() == [1.0, 1.0]


@needs_ext
def test_split_refuses_arrays_of_the_wrong_size():
    QR, w = split_problem(np.random.default_rng(0), 12)
    with pytest.raises(ValueError, match='QR must hold'):
        compiled.ext.split(QR, 12, w, np.zeros(3), scratch(12, 18), RANK_TOLERANCE)
    with pytest.raises(ValueError, match='QR must hold'):
        compiled.ext.split(QR, 12, w, np.zeros(26), np.zeros(18 * 18), RANK_TOLERANCE)
    with pytest.raises(ValueError, match='QR must hold'):
        compiled.ext.split(QR[:-1], 12, w, np.zeros(26), scratch(12, 18), RANK_TOLERANCE)
    with pytest.raises(ValueError, match='tol >= 0'):
        compiled.ext.split(QR, 12, w, np.zeros(26), scratch(12, 18), float('nan'))
    with pytest.raises(TypeError, match='C-contiguous float64'):
        compiled.ext.split(QR.astype(np.float32), 12, w, np.zeros(26), scratch(12, 18),
                           RANK_TOLERANCE)
