# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Forward dynamics takes the articulated-body algorithm, and CRBA + ``LᵀL`` where it cannot.

The two paths give ``q̈`` to rounding but not to the bit: on a model where no two bodies share
a coordinate ``sd.forward_dynamics`` (both backends, with external wrenches and armature) has
the bits of :func:`~spatial_dynamics.algorithms.aba.aba_kernel` run on Python floats and not
those of ``M⁻¹ (τ - h)``; on a model with a mimic joint the kernel declines (``info`` -2)
and the answer has the bits of the factorization. The articulated inertia's change of
frame, ``Xᵀ I X`` of any symmetric 6x6, is checked against the 6x6 product.
"""

import math

from conftest import robot_urdf_path
import numpy as np
import pytest
import spatial_dynamics as sd
from spatial_dynamics.algorithms.arguments import f_ext_in_bodies
from spatial_dynamics.algorithms.components import I_articulated, XT_IA_X_plus
from spatial_dynamics.backends import codegen, layout, python
from spatial_dynamics.spatial import mcI, plux_Er, rotx, roty, rotz, xlt

BACKENDS = ('numpy', 'compiled')


def _upper(A: np.ndarray) -> tuple:
    """Return the upper triangle of a 6x6, row by row (21 numbers)."""
    return tuple(A[j, k] for j in range(6) for k in range(j, 6))


def _full(t) -> np.ndarray:
    """Return the symmetric 6x6 of an upper triangle (21 numbers)."""
    A = np.zeros((6, 6))
    A[np.triu_indices(6)] = t
    return A + np.triu(A, 1).T


def _state(rng, model):
    q = rng.uniform(-1.5, 1.5, model.nq)
    if model.floating:
        quat = rng.normal(size=4)
        q[3:7] = quat / np.linalg.norm(quat)
    return q, rng.uniform(-2.0, 2.0, model.nv), rng.uniform(-3.0, 3.0, model.nv)


def _terms(model, rng) -> dict:
    """Return an external wrench on the last body and armature on every joint."""
    joints = model.joint_names[1:] if model.floating else model.joint_names
    return {'f_ext': {model.body_names[-1]: rng.normal(size=6)},
            'armature': {name: 0.01 * (k + 1) for k, name in enumerate(joints)}}


def _crba_path(model, q, qd, tau, f_ext, armature):
    """``q̈`` by CRBA, RNEA at ``q̈ = 0`` and the ``LᵀL`` factorization, on Python floats."""
    lay = layout.of(model)
    h = sd.rnea(model, q, qd, np.zeros(model.nv), f_ext=f_ext, backend='numpy')
    H = sd.mass_matrix(model, q, backend='numpy') + np.diag(
        sd.per_joint(model, 'armature', armature))
    qdd, failed = python.forward_solve(lay.rows, H, tau - h)
    assert failed is None
    return qdd


def _aba(model, q, qd, tau, f_ext, armature):
    """``(q̈, info)`` of the articulated-body kernel on Python floats."""
    lay = layout.of(model)
    bodies = {b: np.asarray(f, dtype=float).tolist()
              for b, f in f_ext_in_bodies(model, f_ext).items()}
    arm = None if armature is None else sd.per_joint(model, 'armature', armature).tolist()
    return python.aba_rows(lay.rows, q.tolist(), qd.tolist(), tau.tolist(), sd.GRAVITY,
                           bodies, arm)


@pytest.mark.parametrize('robot,base', [('ur5', 'fixed'), ('talos_reduced', 'fixed'),
                                        ('solo12', 'floating'), ('talos_reduced', 'floating')])
def test_forward_dynamics_takes_the_articulated_body_algorithm(robot, base, rng):
    model = sd.Model.from_urdf(robot_urdf_path(robot), base=base)
    terms = _terms(model, rng)
    q, qd, qdd = _state(rng, model)
    A = sd.per_joint(model, 'armature', terms['armature'])
    tau = sd.rnea(model, q, qd, qdd, f_ext=terms['f_ext']) + sd.armature_torque(A, qdd)
    aba, info = _aba(model, q, qd, tau, **terms)
    assert info == -1
    crba = _crba_path(model, q, qd, tau, **terms)
    assert np.abs(np.array(aba) - qdd).max() <= 1e-10 * max(1.0, np.abs(qdd).max())
    assert aba != crba.tolist()     # the paths differ in their last bits: the check tells them
    for backend in BACKENDS:
        assert sd.forward_dynamics(model, q, qd, tau, backend=backend,
                                   **terms).tolist() == aba, backend
    tau0 = tau - sd.armature_torque(A, qdd)
    plain, info = python.aba_rows(layout.of(model).rows, q.tolist(), qd.tolist(),
                                  tau0.tolist(), sd.GRAVITY)
    assert info == -1
    assert sd.forward_dynamics(model, q, qd, tau0).tolist() == plain       # the fast entry
    assert sd.forward_dynamics(model, q[None], qd[None], tau0[None])[0].tolist() == plain


def test_a_mimic_joint_keeps_the_composite_rigid_body_path(rng):
    model = sd.Model.from_urdf(robot_urdf_path('panda'))        # its finger mimics the other
    assert model.mimics
    terms = _terms(model, rng)
    q, qd, qdd = _state(rng, model)
    A = sd.per_joint(model, 'armature', terms['armature'])
    tau = sd.rnea(model, q, qd, qdd, f_ext=terms['f_ext']) + sd.armature_torque(A, qdd)
    assert _aba(model, q, qd, tau, **terms)[1] == -2
    crba = _crba_path(model, q, qd, tau, **terms)
    assert np.abs(crba - qdd).max() <= 1e-10 * max(1.0, np.abs(qdd).max())
    for backend in BACKENDS:
        assert sd.forward_dynamics(model, q, qd, tau, backend=backend,
                                   **terms).tolist() == crba.tolist(), backend
    tau0 = tau - sd.armature_torque(A, qdd)
    zero = {'f_ext': {}, 'armature': None}
    crba0 = _crba_path(model, q, qd, tau0, {}, {})
    assert _aba(model, q, qd, tau0, **zero)[1] == -2
    assert sd.forward_dynamics(model, q, qd, tau0).tolist() == crba0.tolist()


def test_the_aba_kernel_is_generated_and_compiled():
    assert 'aba_kernel' in [fn.__name__ for fn in codegen.SOURCES]
    assert 'aba_kernel(const double *K' in codegen.generate_c()


def test_an_articulated_inertia_changes_frame_as_the_6x6_product(rng):
    """``c + Xᵀ I X`` of any symmetric 6x6 ``I`` equals the product of 6x6 matrices."""
    for _ in range(5):
        X = rotx(rng.normal()) @ roty(rng.normal()) @ rotz(rng.normal()) @ xlt(rng.normal(size=3))
        E, r = plux_Er(X)
        B = rng.normal(size=(6, 6))
        Ii, C = B @ B.T, rng.normal(size=(6, 6))
        C = C + C.T
        got = XT_IA_X_plus(*E.ravel(), *r, *_upper(Ii), *_upper(C))
        assert np.allclose(_full(got), C + X.T @ Ii @ X, rtol=0, atol=1e-12)
    rigid = mcI(2.0, np.array([0.1, -0.2, 0.3]), np.diag([0.1, 0.2, 0.3]))
    h, Ibar = rigid[:3, 3:], rigid[:3, :3]
    got = I_articulated(2.0, h[2, 1], h[0, 2], h[1, 0], Ibar[0, 0], Ibar[0, 1], Ibar[0, 2],
                        Ibar[1, 1], Ibar[1, 2], Ibar[2, 2])
    assert np.array_equal(_full(got), rigid)
    assert math.isfinite(sum(got))
