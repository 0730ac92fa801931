# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Composite rigid body algorithm: the joint-space inertia ``M(q)`` (RBDA table 6.2), one source.

::

    IC_i = I_i                                      for i = 1..NB
    IC_λ(i) += Xup_iᵀ IC_i Xup_i                    for i = NB..1 (λ(i) ≠ 0)
    F = IC_i S_i;  H_ii = S_iᵀ F                    for i = 1..NB
    j = i;  while λ(j) ≠ 0:  F = Xup_jᵀ F;  j = λ(j);  H_ij = H_ji = S_jᵀ F

(``S_i`` has one column per velocity coordinate of joint ``i``: six for a free-flyer.)

Each body's joint moves with ``mul_i q̇_k(i)`` (a mimic joint follows its source), so
``H_ij`` adds ``mul_i mul_j H_ij`` to ``M[k(i), k(j)]`` (and to ``M[k(j), k(i)]``): ``M`` is the
sum over pairs of bodies.

:func:`crba_kernel` is written on scalar components like :func:`~.rnea.rnea_kernel` and under
the same rules (the per-body rows of :mod:`spatial_dynamics.backends.layout`, whole-tuple
stores ``Xup`` and ``IC``, the products of :mod:`.components`), so the Python backends run it
on floats or (N,) arrays and the compiled backend is generated from it.
"""

from __future__ import annotations

from .components import I_motion, XT_force, XT_I_X_plus
from ..joints import joint_axis, joint_crba


def crba_kernel(rows, Xup, IC, H) -> None:
    """``M(q)`` into ``H``, ``nv * nv`` scalars row-major, from the ``Xup`` of ``q``.

    ``rows`` are the layout's per-body rows (row 0 the base), ``Xup`` the transforms of
    :func:`~.rnea.xup_kernel`, ``IC`` scratch with a slot per body for the composite inertias
    ``(m, h, Ibar)``. A joint of ``dof`` velocity coordinates (6 for a free-flyer) has as many
    columns ``S[:, c]`` of its motion subspace (:func:`~spatial_dynamics.joints.joint_axis`),
    each a row and a column of ``M``.
    """
    NB = len(rows) - 1
    for a in range(len(H)):
        H[a] = 0.0
    for i in range(1, NB + 1):
        (_, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _,
         mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz, _, _) = rows[i]
        IC[i] = [mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz]
    # Composite inertias: IC_λ(i) += Xup_iᵀ IC_i Xup_i
    for i in range(NB, 0, -1):
        (p, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _,
         _, _, _, _, _, _, _, _, _, _, _, _) = rows[i]
        if p != 0:
            IC[p] = XT_I_X_plus(*Xup[i], *IC[i], *IC[p])
    (_, _, _, n, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _,
     _, _, _, _, _, _, _, _, _, _, _, _) = rows[0]
    for i in range(1, NB + 1):
        (p, code, _, kv, dof, ax, ay, az, _, _, _, _, _, _, _, _, _, _, _, _,
         _, _, _, _, _, _, _, _, _, _, mul, _) = rows[i]
        cm, chx, chy, chz, cxx, cxy, cxz, cyy, cyz, czz = IC[i]
        for c in range(dof):
            # F = IC_i S_i[:, c];  H_ii = S_iᵀ F
            s0, s1, s2, s3, s4, s5 = joint_axis(code, c, ax, ay, az)
            F0, F1, F2, F3, F4, F5 = I_motion(cm, chx, chy, chz, cxx, cxy, cxz, cyy, cyz, czz,
                                              s0, s1, s2, s3, s4, s5)
            k = kv + c
            joint_crba(code, H, n, k, kv, mul * mul, False, ax, ay, az, F0, F1, F2, F3, F4, F5)
            # j = i;  while λ(j) ≠ 0:  F = Xup_jᵀ F;  j = λ(j);  H_ij = H_ji = S_jᵀ F
            j = i
            pj = p
            while pj != 0:
                e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz = Xup[j]
                F0, F1, F2, F3, F4, F5 = XT_force(e00, e01, e02, e10, e11, e12, e20, e21, e22,
                                                  rx, ry, rz, F0, F1, F2, F3, F4, F5)
                j = pj
                (pj, cj, _, kj, _, bx, by, bz, _, _, _, _, _, _, _, _, _, _, _, _,
                 _, _, _, _, _, _, _, _, _, _, mj, _) = rows[j]
                joint_crba(cj, H, n, k, kj, mul * mj, True, bx, by, bz, F0, F1, F2, F3, F4, F5)
