# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""One state's ``'torques'`` answer in one compiled call: the extension's ``contact`` entry.

``contact_inverse_dynamics(..., method='torques')`` of one float64 state takes ``M q̈ + h``,
``J_c``, the split and the base residual from one call of the entry, not from the separate
entries (``rnea``, ``bodies``) and numpy steps between them. Oracles: Pinocchio's ``rnea``
and frame Jacobians at the contact points, split by an SVD (conftest's
``least_torque_split``), on every contact layout of ``test_core_contacts.py``, the redundant
ones too; what the entry declines goes to the general path, which names what is wrong.
"""

import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from conftest import least_torque_split, robot_urdf_path, to_pin  # noqa: E402
import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics.algorithms.split import RANK_TOLERANCE  # noqa: E402
from spatial_dynamics.backends import compiled, kernels  # noqa: E402
from test_core_contacts import (FEET, pin_contact_jacobian, REDUNDANT, SOLES,  # noqa: E402
                                standing_solo, standing_talos)

pin = pytest.importorskip('pinocchio')
pytestmark = pytest.mark.skipif(compiled.ext is None, reason='built without the kernels')
LAYOUTS = dict(REDUNDANT, **{
    'solo12, four feet': ('solo', lambda: [sd.Contact(f) for f in FEET]),
    'talos, two soles': ('talos', lambda: [sd.Contact(s, kind='surface') for s in SOLES]),
    'talos, a sole and a point': ('talos', lambda: [
        sd.Contact(SOLES[0], kind='surface'), sd.Contact(SOLES[1], offset=(0.1, 0.05, 0.0))]),
})


@pytest.fixture(scope='module')
def robots():
    out = {}
    for robot, name in (('solo', 'solo12'), ('talos', 'talos_reduced')):
        path = robot_urdf_path(name)
        out[robot] = (sd.Model.from_urdf(path, base='floating'),
                      pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer()))
    return out


def only_the_entry(monkeypatch):
    """Make every other step of the path fail: the separate entries and the numpy split."""
    def other(*args, **kwargs):
        raise AssertionError('a step outside the contact entry was taken')
    for name in ('_c_rnea', '_c_bodies', '_split_numpy', 'rnea', 'contact_jacobian'):
        monkeypatch.setattr(sd.contacts, name, other)


@pytest.mark.parametrize('layout', list(LAYOUTS))
def test_one_state_s_torques_are_one_compiled_call_and_pinocchios_split(robots, layout,
                                                                        monkeypatch):
    """The contact entry alone answers, and its answer is Pinocchio's dynamics split least."""
    robot, make = LAYOUTS[layout]
    model, pm = robots[robot]
    contacts = make()
    only_the_entry(monkeypatch)
    rng = np.random.default_rng(3)
    q0 = standing_solo(model) if robot == 'solo' else standing_talos(model)
    for k in range(3):
        q, qd, qdd = q0.copy(), np.zeros(model.nv), np.zeros(model.nv)
        if k:
            q[7:] += rng.normal(size=model.nq - 7) * 0.05
            qd, qdd = rng.normal(size=(2, model.nv)) * 0.5
        w = rng.uniform(0.5, 2.0, model.nv - 6) if k == 2 else None
        r = sd.contact_inverse_dynamics(model, q, qd, qdd, contacts, weights=w)
        b = to_pin(pin.rnea(pm, pm.createData(), q, to_pin(qd), to_pin(qdd)))
        Jc = pin_contact_jacobian(pm, q, contacts)
        got = np.concatenate([r.forces[c.name] for c in contacts])
        assert r.status == 'solved' and r.method == 'torques'
        np.testing.assert_allclose(np.r_[np.zeros(6), r.tau] + Jc.T @ got, b, atol=1e-9)
        np.testing.assert_allclose(r.base_residual, b[:6] - Jc[:, :6].T @ got, atol=1e-9)
        assert np.abs(r.base_residual).max() < 1e-9, (layout, r.summary())
        if w is None:
            tau, _, rank = least_torque_split(Jc, b, RANK_TOLERANCE)
            assert r.rank == rank, (layout, r.rank, rank)
            np.testing.assert_allclose(r.tau, tau, rtol=0,
                                       atol=1e-9 * max(1.0, np.abs(tau).max()))
        else:       # the weighted least torques: τ = W^-½ (A W^-½)⁺ y on the null space of J_cᵀ
            U, s, _ = np.linalg.svd(Jc.T)
            U2 = U[:, r.rank:]
            A = U2[6:].T / np.sqrt(w)
            tau = np.linalg.lstsq(A, U2.T @ b, rcond=None)[0] / np.sqrt(w)
            np.testing.assert_allclose(r.tau, tau, rtol=0,
                                       atol=1e-9 * max(1.0, np.abs(tau).max()))


def test_the_contact_entry_declines_what_it_cannot_answer(robots):
    """float32, a zero quaternion, NaN, too few rows: None (the general path's to answer)."""
    model, _ = robots['solo']
    kern = kernels(model)
    plan = sd.contacts.plan_contacts(model, [sd.Contact(f) for f in FEET])
    q, zero, g = standing_solo(model), np.zeros(model.nv), (0.0, 0.0, -9.81)
    w, res = np.ones(model.nv - 6), np.zeros(6)
    entry = compiled.ext.contact
    tau, lam, r = entry(kern, q, zero, zero, g, plan.points, w, RANK_TOLERANCE, res)
    assert (tau.shape, lam.shape, r) == ((12,), (12,), 12)
    np.testing.assert_allclose(lam.reshape(4, 3).sum(0)[2], model.inertia[:, 3, 3].sum() * 9.81)
    bad_q = q.copy()
    bad_q[3:7] = 0.0
    nan = zero.copy()
    nan[3] = np.nan
    for args in ((q.astype(np.float32), zero, zero), (bad_q, zero, zero), (q, nan, zero),
                 (q, zero, np.full(model.nv, 1e200))):
        assert entry(kern, *args, g, plan.points, w, RANK_TOLERANCE, res) is None
    one = sd.contacts.plan_contacts(model, [sd.Contact(FEET[0])])       # 3 rows: the numpy split's
    assert entry(kern, q, zero, zero, g, one.points, w, RANK_TOLERANCE, res) is None
    for points, weights, residual in ((plan.points[:, :4].copy(), w, res),
                                      (plan.points, w[1:], res),
                                      (plan.points + [[99, 0, 0, 0, 0]] * 4, w, res),
                                      (plan.points + [[0, 1, 0, 0, 0]] * 4, w, res),
                                      (plan.points, w, np.zeros(5))):
        with pytest.raises(ValueError, match='contact: '):
            entry(kern, q, zero, zero, g, points, weights, RANK_TOLERANCE, residual)
    with pytest.raises(ValueError, match=r'qd must be finite: qd\[3\] is nan'):
        sd.contact_inverse_dynamics(model, q, nan, zero, [sd.Contact(f) for f in FEET])
