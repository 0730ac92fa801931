# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The compiled contact path against the numpy one: the same answers to 1e-12.

``contact_jacobian`` and ``contact_inverse_dynamics`` with ``backend='compiled'`` take every
body's world-aligned Jacobian from one compiled pass (``bodies_kernel``) and split the
``'torques'`` with the compiled ``split_kernel``; ``backend='numpy'`` is the reference
(numpy columns, numpy QR). Oracles: that reference (Solo12, Talos' soles, the full Talos'
mimic grippers) and ``sd.jacobian(..., frame='world')`` for the bodies' rows.
"""

import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from conftest import robot_urdf_path  # noqa: E402
import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics.backends import compiled, kernels  # noqa: E402

pytestmark = pytest.mark.skipif(compiled.ext is None, reason='built without the kernels')
FEET = ('FL_FOOT', 'FR_FOOT', 'HL_FOOT', 'HR_FOOT')
SOLES = ('left_sole_link', 'right_sole_link')


@pytest.fixture(scope='module')
def solo():
    return sd.Model.from_urdf(robot_urdf_path('solo12'), base='floating')


@pytest.fixture(scope='module')
def talos():
    return sd.Model.from_urdf(robot_urdf_path('talos_reduced'), base='floating')


def state(model, rng, scale=1.0):
    """Return a random state: base anywhere, tilted; joints, rates of size ``scale``."""
    q = rng.normal(size=model.nq) * scale
    q[:3] = rng.uniform(-2.0, 2.0, 3)
    q[3:7] /= np.linalg.norm(q[3:7])
    return q, rng.normal(size=model.nv) * scale, rng.normal(size=model.nv) * scale


def close(fast, ref):
    """Assert ``fast`` equals ``ref`` to 1e-12 of the reference's scale (max(1, |ref|))."""
    fast, ref = np.asarray(fast), np.asarray(ref)
    assert fast.shape == ref.shape
    assert np.abs(fast - ref).max(initial=0.0) <= 1e-12 * max(1.0, np.abs(ref).max(initial=0.0))


def same(fast, ref):
    """Assert two ContactResults alike: torques, forces, base residual, rank, violations."""
    close(fast.tau, ref.tau)
    assert list(fast.forces) == list(ref.forces)
    for name in ref.forces:
        close(fast.forces[name], ref.forces[name])
    close(fast.base_residual, ref.base_residual)
    assert (fast.method, fast.status, fast.rank) == (ref.method, ref.status, ref.rank)
    assert [(v.contact, v.kind) for v in fast.violations] == [
        (v.contact, v.kind) for v in ref.violations]
    for a, b in zip(fast.violations, ref.violations):
        close(a.amount, b.amount)


def test_bodies_rows_are_the_world_jacobians_of_every_body(solo, talos):
    """Each body's row: R, p and the Jacobian that sd.jacobian(frame='world') gives."""
    rng = np.random.default_rng(3)
    full = sd.Model.from_urdf(robot_urdf_path('talos'), base='floating')    # 12 mimic joints
    for model in (solo, talos, full):
        kern = kernels(model)
        q = state(model, rng)[0]
        rows = compiled.ext.bodies(kern, q)
        assert rows.shape == (model.NB + 1, 16 + 6 * model.nv)
        for link, frame in model.frames.items():
            if frame.body == 0 or not np.array_equal(frame.lXb, np.eye(6)):
                continue            # the body's own link
            row = rows[frame.body]
            J = sd.jacobian(model, q, link, frame='world')
            np.testing.assert_allclose(row[16:].reshape(6, model.nv), J, rtol=0, atol=1e-12)
            lX0 = sd.algorithms.jacobian.local_jacobian(model, q, link)[1]
            px = -lX0[:3, :3].T @ lX0[3:, :3]       # lX0 = [[E, 0], [-E p×, E]]: p× = -Eᵀ B
            H = np.eye(4)
            H[:3, :3], H[:3, 3] = lX0[:3, :3].T, (px[2, 1], px[0, 2], px[1, 0])
            np.testing.assert_allclose(row[:16].reshape(4, 4), H, rtol=0, atol=1e-12)


def test_bodies_batch_is_the_single_state_entry(solo):
    rng = np.random.default_rng(4)
    kern = kernels(solo)
    Q = np.array([state(solo, rng)[0] for _ in range(7)])
    out = np.empty((7, solo.NB + 1, 16 + 6 * solo.nv))
    compiled.ext.bodies_batch(kern, 7, Q, out, 2)
    for q, rows in zip(Q, out):
        np.testing.assert_array_equal(rows, compiled.ext.bodies(kern, q))


def test_contact_jacobian_compiled_equals_numpy(solo, talos):
    """Points, surfaces and both mixed, contact points off the link origins; mimic joints."""
    rng = np.random.default_rng(5)
    full = sd.Model.from_urdf(robot_urdf_path('talos'), base='floating')
    grippers = ('gripper_left_inner_single_link', 'gripper_right_fingertip_1_link')
    for model, links in ((solo, FEET), (talos, SOLES), (full, SOLES + grippers)):
        for kinds in (('point',), ('surface',), ('point', 'surface')):
            contacts = [sd.Contact(link, offset=rng.normal(size=3) * 0.05,
                                   kind=kinds[j % len(kinds)]) for j, link in enumerate(links)]
            for _ in range(5):
                q = state(model, rng)[0]
                fast = sd.contact_jacobian(model, q, contacts, backend='compiled')
                close(fast, sd.contact_jacobian(model, q, contacts, backend='numpy'))
                close(sd.contact_jacobian(model, q.tolist(), contacts), fast)


@pytest.mark.parametrize('method', ['torques', 'forces'])
def test_solo_four_feet_compiled_equals_numpy(solo, method):
    """Solo12 on four point feet, 50 random states (knees near straight too), both splits."""
    rng = np.random.default_rng(6)
    feet = [sd.Contact(f, mu=0.6) for f in FEET]
    for k in range(50):
        q, qd, qdd = state(solo, rng, scale=0.5 if k % 2 else 2.0)
        ref = sd.contact_inverse_dynamics(solo, q, qd, qdd, feet, method=method,
                                          backend='numpy')
        same(sd.contact_inverse_dynamics(solo, q, qd, qdd, feet, method=method), ref)
        same(sd.contact_inverse_dynamics(solo, q, qd, qdd, feet, method=method,
                                         backend='compiled'), ref)


def test_weights_surfaces_measured_and_redundant_rows(solo, talos):
    rng = np.random.default_rng(7)
    soles = [sd.Contact(s, kind='surface') for s in SOLES]
    feet = [sd.Contact(f) for f in FEET]
    twice = feet + [sd.Contact('FL_FOOT', name='FL again')]         # rank 12 of 15 rows
    three = feet[:3]                                                 # 9 rows
    one = feet[:1]                                                   # 3 rows: base not carried
    w = rng.uniform(0.5, 2.0, 12)
    for _ in range(10):
        q, qd, qdd = state(talos, rng)
        for kw in ({}, {'weights': rng.uniform(0.5, 2.0, talos.nv - 6)}):
            same(sd.contact_inverse_dynamics(talos, q, qd, qdd, soles, **kw),
                 sd.contact_inverse_dynamics(talos, q, qd, qdd, soles, backend='numpy', **kw))
        q, qd, qdd = state(solo, rng)
        for contacts, kw in ((feet, {'weights': w}), (twice, {}), (three, {}), (one, {}),
                             (feet, {'measured': {f: rng.normal(size=3) for f in FEET}})):
            same(sd.contact_inverse_dynamics(solo, q, qd, qdd, contacts, **kw),
                 sd.contact_inverse_dynamics(solo, q, qd, qdd, contacts, backend='numpy', **kw))


def test_a_wrong_fast_split_is_seen(solo, monkeypatch):
    """The comparison above catches a fast path that is off: a perturbed λ fails it."""
    from spatial_dynamics import contacts as module
    split = module._split_compiled

    def off(*args):
        tau, lam, rank = split(*args)
        return tau, lam * (1.0 + 1e-10), rank

    monkeypatch.setattr(module, '_split_compiled', off)
    rng = np.random.default_rng(8)
    q, qd, qdd = state(solo, rng)
    feet = [sd.Contact(f) for f in FEET]
    with pytest.raises(AssertionError):
        same(sd.contact_inverse_dynamics(solo, q, qd, qdd, feet),
             sd.contact_inverse_dynamics(solo, q, qd, qdd, feet, backend='numpy'))


def test_inputs_the_entries_decline_take_the_checked_path(solo):
    """float32, a (1, nq) q, a bad backend: the general path's answer or its error."""
    q = np.zeros(solo.nq)
    q[2], q[6] = 0.25, 1.0
    q[7:] = [0.0, 0.8, -1.6] * 2 + [0.0, -0.8, 1.6] * 2
    zero = np.zeros(solo.nv)
    feet = [sd.Contact(f) for f in FEET]
    ref = sd.contact_inverse_dynamics(solo, q, zero, zero, feet, backend='numpy')
    same(sd.contact_inverse_dynamics(solo, list(q), list(zero), tuple(zero), feet), ref)
    with pytest.raises(ValueError, match='one state'):
        sd.contact_inverse_dynamics(solo, q[None], zero, zero, feet)
    with pytest.raises(ValueError, match=r'q must have shape \(\.\.\., 19\)'):
        sd.contact_inverse_dynamics(solo, q[:-1], zero, zero, feet)
    with pytest.raises(ValueError, match='backend must be one of'):
        sd.contact_inverse_dynamics(solo, q, zero, zero, feet, backend='fast')
    with pytest.raises(ValueError, match='backend must be one of'):
        sd.contact_jacobian(solo, q, feet, backend='fast')
    r32 = sd.contact_inverse_dynamics(solo, q.astype(np.float32), zero.astype(np.float32),
                                      zero.astype(np.float32), feet)
    assert r32.feasible
    np.testing.assert_allclose(r32.tau, ref.tau, atol=1e-3)


def test_contact_jacobian_of_a_batch_is_each_state_s(solo, talos):
    """Take a batch q (2, 3, nq): the compiled batch entry and numpy, state by state alike."""
    rng = np.random.default_rng(9)
    for model, contacts in ((solo, [sd.Contact(f, offset=(0.01, 0.0, -0.02)) for f in FEET]),
                            (talos, [sd.Contact(SOLES[0], kind='surface'),
                                     sd.Contact(SOLES[1], offset=(0.1, 0.05, 0.0))])):
        Q = np.array([state(model, rng)[0] for _ in range(6)]).reshape(2, 3, model.nq)
        each = np.array([sd.contact_jacobian(model, q, contacts, backend='numpy')
                         for q in Q.reshape(6, -1)]).reshape(2, 3, -1, model.nv)
        for backend in ('compiled', 'numpy'):
            J = sd.contact_jacobian(model, Q, contacts, backend=backend)
            assert J.shape == each.shape
            close(J, each)
        assert sd.contact_jacobian(model, Q[:0], contacts).shape == (0, 3) + each.shape[2:]
