# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Analytical derivatives of inverse dynamics: ``∂τ/∂q``, ``∂τ/∂q̇``, ``∂τ/∂q̈ = M``; one source.

Carpentier and Mansard, "Analytical derivatives of rigid body dynamics algorithms" (RSS
2018): the RNEA is written in world coordinates (every quantity below in one frame fixed
to the ground, ``ᵒ`` dropped; here the frame body 1 has at ``q``, so nothing depends on how
far the robot is from the world's origin), where a joint's motion moves the bodies beyond it
rigidly, so each derivative is a product of quantities every body already has. Forward
pass, body ``i`` with columns ``s = mul_i ᵒX_i⁻¹ S_i[:, c]`` (world)::

    v_i = v_λ + Σ s q̇,   a_i = a_λ + Σ s q̈ + v_i × Σ s q̇   (a_0 = -a_grav)
    h_i = I_i v_i,  f_i = I_i a_i + v_i ×* h_i - f_ext_i,  İ_i = v_i ×* I_i - I_i v_i×

and per column ``s`` of body ``j``, with ``ψ = s × v_λ(j)``::

    ∂/∂q:  α = -(s × a_λ(j) + v_λ(j) × ψ),  β = -ψ
    ∂/∂q̇:  α' = (v_λ(j) + v_j) × s,        β' = s

Backward pass: the subtree sums ``IC``, ``İC``, ``hC`` and ``F`` (world coordinates need no
transform to add). A body ``i`` in the subtree of ``j`` (``i = j`` too) then has, for each
derivative ``(α, β)`` of a column of ``j``::

    ∂F_i = IC_i α + (İC_i - H(hC_i)) β,   H(h) a = -(a ×* h)

(the change of ``S_i`` itself, ``s_j × S_i``, cancels against ``s_j ×* F_i``), so
``∂τ_i = S_iᵀ ∂F_i = A_i·α + B_i·β`` with ``A_i = IC_i S_i``, ``B_i = (İC_i + H(hC_i)) S_i``.
An ancestor ``i`` of ``j`` sees the whole subtree of ``j`` move: ``∂τ_i = S_iᵀ (IC_j α +
(İC_j - H(hC_j)) β + s_j ×* F_j)`` (the last term for ``q`` only). ``M`` is the same walk with
``(α, β) = (s, 0)``. A free-flyer's six columns are its tangent directions ``q ⊕ δ``
(:func:`~spatial_dynamics.algorithms.configuration.integrate`): a twist in its own frame.

A 1-dof column needs no product for ``α'``: ``v_j = v_λ + s q̇``, so ``α' = 2 v_λ × s = 2β``.
Body 1's frame is the world: its inertia needs no transform, nor do its children's ``Xup``.

Body 1's columns, when it has several (a free-flyer's six), are taken at once: in its own
frame ``s = mul S``, and ``v_0 = 0`` (so ``β = 0``); with ``f·(m × s) = -(m ×* f)·s`` its
entries in the row of a column ``k`` of a body below it (or of its own) are each one force
against ``S``, as are those in the column ``k`` (``Q_k·s``, ``V_k·s``: the forces the
ancestors' rows take; :func:`~spatial_dynamics.joints.joint_pair`, ``joint_crba``)::

    ∂τ_k/∂q = -(a_0 ×* A_k)·s,   ∂τ_k/∂q̇ = (B_k - v_1 ×* A_k)·s,   M_k = A_k·s

instead of a product a column (six, above every other body). One column (a fixed base's
first joint) is walked as any ancestor's: one product a column below it, not two.

:func:`derivatives_kernel` is written on scalar components in the subset of
:mod:`~.rnea` (per-body rows unpacked whole, whole-tuple stores, the products of
:mod:`.components`); per column it keeps ``(s, α, β, α')`` in ``dcol[6 i + c]``, and ``s``
(``mul ᵂX_i⁻¹ S``, computed once, where ``v_J`` is summed; of a 1-dof joint from S's
nonzeros, :func:`~spatial_dynamics.joints.joint_world_axis`) in ``scol[6 i + c]``.
"""

from __future__ import annotations

from .components import (crf_force, crm_motion, I_motion, I_rate, Irate_motion, X_compose,
                         X_motion, Xinv_motion, XT_force, XT_I_X)
from ..joints import joint_axis, joint_crba, joint_pair, joint_world_axis


def derivatives_kernel(rows, qd, qdd, gx, gy, gz, f_body, has_fext, dq, dv, H, Xup, oX, vel,
                       acc, frc, IC, dIC, hC, dcol, scol) -> None:
    """``∂τ/∂q`` into ``dq``, ``∂τ/∂q̇`` into ``dv`` and ``M`` into ``H`` (``nv * nv``, row-major).

    ``rows`` are the layout's per-body rows (row 0 the base), ``Xup`` the transforms of
    :func:`~.rnea.xup_kernel` for ``q``; ``oX``, ``vel``, ``acc``, ``frc``, ``IC``, ``dIC``,
    ``hC`` are scratch with a slot per body, ``dcol`` and ``scol`` with six per body (a
    column's ``(s, α, β, α')``, and its ``s`` from the pass that sums ``v_J``). ``f_body`` as
    for :func:`~.rnea.rnea_kernel` (body coordinates). The outputs are zeroed first.
    """
    NB = len(rows) - 1
    zero = 0.0 * gx
    (_, _, _, n, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _,
     _, _, _, _, _, _, _, _, _, _, _, _) = rows[0]
    for k in range(len(H)):
        dq[k] = zero
        dv[k] = zero
        H[k] = zero
    one = zero + 1.0
    # "World" is body 1's frame at this q: a change of frame changes no torque and no
    # derivative; it keeps every r small (no digits lost to where the robot is: the
    # free-flyer's position, a far mount), as rnea's body coordinates do, and makes body 1's
    # columns S itself (ᵂX_1 = 1): the root's columns are then one force against S each
    oX[0] = (one, zero, zero, zero, one, zero, zero, zero, one, zero, zero, zero)
    vel[0] = (zero, zero, zero, zero, zero, zero)
    acc[0] = (zero, zero, zero, -gx, -gy, -gz)      # a_0 = -a_grav
    if NB > 0:
        # ᵂX_0 = ¹X_0⁻¹ = (Eᵀ, -E r) of Xup_1 = (E, r); a_0 in body 1's coordinates
        e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz = Xup[1]
        oX[0] = (e00, e10, e20, e01, e11, e21, e02, e12, e22,
                 -(e00 * rx + e01 * ry + e02 * rz), -(e10 * rx + e11 * ry + e12 * rz),
                 -(e20 * rx + e21 * ry + e22 * rz))
        acc[0] = X_motion(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz,
                          zero, zero, zero, -gx, -gy, -gz)

    # Forward pass, world coordinates
    for i in range(1, NB + 1):
        (p, code, _, kv, dof, ax, ay, az, _, _, _, _, _, _, _, _, _, _, _, _,
         mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz, mul, _) = rows[i]
        if i == 1:
            oX[i] = (one, zero, zero, zero, one, zero, zero, zero, one, zero, zero, zero)
        elif p == 1:                                        # ᵢX_W = Xup_i (ᵂX_1 = 1)
            e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz = Xup[i]
            oX[i] = (e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz)
        else:
            oX[i] = X_compose(*Xup[i], *oX[p])             # ᵢX_W = Xup_i λX_W
        e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz = oX[i]
        pw0, pw1, pw2, pv0, pv1, pv2 = vel[p]
        pa0, pa1, pa2, pl0, pl1, pl2 = acc[p]
        w0, w1, w2, v0, v1, v2 = pw0, pw1, pw2, pv0, pv1, pv2
        j0 = j1 = j2 = j3 = j4 = j5 = zero                  # vJ = Σ s q̇
        a0, a1, a2, l0, l1, l2 = pa0, pa1, pa2, pl0, pl1, pl2
        for c in range(dof):
            # vJ = Σ s q̇ and a_λ + Σ s q̈
            if dof == 1:        # S's nonzeros only
                s0, s1, s2, s3, s4, s5 = joint_world_axis(code, e00, e01, e02, e10, e11, e12,
                                                          e20, e21, e22, rx, ry, rz, ax, ay, az)
            else:               # a unit column of several (the free-flyer's)
                s0, s1, s2, s3, s4, s5 = joint_axis(code, c, ax, ay, az)
                s0, s1, s2, s3, s4, s5 = Xinv_motion(e00, e01, e02, e10, e11, e12, e20, e21,
                                                     e22, rx, ry, rz, s0, s1, s2, s3, s4, s5)
            s0, s1, s2, s3, s4, s5 = mul * s0, mul * s1, mul * s2, mul * s3, mul * s4, mul * s5
            scol[6 * i + c] = (s0, s1, s2, s3, s4, s5)
            qdi, qddi = qd[kv + c], qdd[kv + c]
            j0, j1, j2, j3, j4, j5 = (j0 + s0 * qdi, j1 + s1 * qdi, j2 + s2 * qdi,
                                      j3 + s3 * qdi, j4 + s4 * qdi, j5 + s5 * qdi)
            a0, a1, a2, l0, l1, l2 = (a0 + s0 * qddi, a1 + s1 * qddi, a2 + s2 * qddi,
                                      l0 + s3 * qddi, l1 + s4 * qddi, l2 + s5 * qddi)
        w0, w1, w2, v0, v1, v2 = w0 + j0, w1 + j1, w2 + j2, v0 + j3, v1 + j4, v2 + j5
        c0, c1, c2, c3, c4, c5 = crm_motion(w0, w1, w2, v0, v1, v2, j0, j1, j2, j3, j4, j5)
        a0, a1, a2, l0, l1, l2 = a0 + c0, a1 + c1, a2 + c2, l0 + c3, l1 + c4, l2 + c5
        for c in range(dof):
            # per column: ψ = s × v_λ;  α = -(s × a_λ + v_λ × ψ),  β = -ψ;  α' = (v_λ + v_i) × s
            s0, s1, s2, s3, s4, s5 = scol[6 * i + c]     # the pass above's, taken once
            if i == 1 and dof > 1:
                # (α, β, α') of body 1's columns are not read: they are taken at once
                dcol[6 * i + c] = (s0, s1, s2, s3, s4, s5, zero, zero, zero, zero, zero, zero,
                                   zero, zero, zero, zero, zero, zero, zero, zero, zero, zero,
                                   zero, zero)
            else:
                y0, y1, y2, y3, y4, y5 = crm_motion(s0, s1, s2, s3, s4, s5,
                                                    pw0, pw1, pw2, pv0, pv1, pv2)
                b0, b1, b2, b3, b4, b5 = crm_motion(s0, s1, s2, s3, s4, s5,
                                                    pa0, pa1, pa2, pl0, pl1, pl2)
                d0, d1, d2, d3, d4, d5 = crm_motion(pw0, pw1, pw2, pv0, pv1, pv2,
                                                    y0, y1, y2, y3, y4, y5)
                if dof == 1:
                    # v_i = v_λ + s q̇: α' = 2 v_λ × s = 2β
                    x0, x1, x2, x3, x4, x5 = (-2.0 * y0, -2.0 * y1, -2.0 * y2, -2.0 * y3,
                                              -2.0 * y4, -2.0 * y5)
                else:
                    x0, x1, x2, x3, x4, x5 = crm_motion(pw0 + w0, pw1 + w1, pw2 + w2,
                                                        pv0 + v0, pv1 + v1, pv2 + v2,
                                                        s0, s1, s2, s3, s4, s5)
                dcol[6 * i + c] = (s0, s1, s2, s3, s4, s5, -(b0 + d0), -(b1 + d1), -(b2 + d2),
                                   -(b3 + d3), -(b4 + d4), -(b5 + d5), -y0, -y1, -y2, -y3, -y4,
                                   -y5, x0, x1, x2, x3, x4, x5)
        vel[i] = (w0, w1, w2, v0, v1, v2)
        acc[i] = (a0, a1, a2, l0, l1, l2)
        # I_i in world coordinates, h_i = I_i v_i, f_i = I_i a_i + v_i ×* h_i - f_ext_i
        if i == 1:
            om, ohx, ohy, ohz, oxx, oxy, oxz, oyy, oyz, ozz = (mass, hx, hy, hz, Ixx, Ixy, Ixz,
                                                               Iyy, Iyz, Izz)
        else:
            om, ohx, ohy, ohz, oxx, oxy, oxz, oyy, oyz, ozz = XT_I_X(
                e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz,
                mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz)
        IC[i] = (om, ohx, ohy, ohz, oxx, oxy, oxz, oyy, oyz, ozz)
        m0, m1, m2, k0, k1, k2 = I_motion(om, ohx, ohy, ohz, oxx, oxy, oxz, oyy, oyz, ozz,
                                          w0, w1, w2, v0, v1, v2)
        hC[i] = (m0, m1, m2, k0, k1, k2)
        n0, n1, n2, f0, f1, f2 = I_motion(om, ohx, ohy, ohz, oxx, oxy, oxz, oyy, oyz, ozz,
                                          a0, a1, a2, l0, l1, l2)
        x0, x1, x2, x3, x4, x5 = crf_force(w0, w1, w2, v0, v1, v2, m0, m1, m2, k0, k1, k2)
        n0, n1, n2, f0, f1, f2 = n0 + x0, n1 + x1, n2 + x2, f0 + x3, f1 + x4, f2 + x5
        if has_fext:
            fe0, fe1, fe2, fe3, fe4, fe5 = f_body[i]
            x0, x1, x2, x3, x4, x5 = XT_force(e00, e01, e02, e10, e11, e12, e20, e21, e22,
                                              rx, ry, rz, fe0, fe1, fe2, fe3, fe4, fe5)
            n0, n1, n2, f0, f1, f2 = n0 - x0, n1 - x1, n2 - x2, f0 - x3, f1 - x4, f2 - x5
        frc[i] = (n0, n1, n2, f0, f1, f2)
        dIC[i] = I_rate(om, ohx, ohy, ohz, oxx, oxy, oxz, oyy, oyz, ozz, w0, w1, w2, v0, v1, v2)

    # Backward pass: subtree sums IC, İC, hC, F (all in world coordinates)
    for i in range(NB, 0, -1):
        (p, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _,
         _, _, _, _, _, _, _, _, _, _, _, _) = rows[i]
        if p != 0:
            cm, chx, chy, chz, cxx, cxy, cxz, cyy, cyz, czz = IC[i]
            pm, phx, phy, phz, pxx, pxy, pxz, pyy, pyz, pzz = IC[p]
            IC[p] = (pm + cm, phx + chx, phy + chy, phz + chz, pxx + cxx, pxy + cxy,
                     pxz + cxz, pyy + cyy, pyz + cyz, pzz + czz)
            g0, g1, g2, g3, g4, g5, g6, g7, g8 = dIC[i]
            r0, r1, r2, r3, r4, r5, r6, r7, r8 = dIC[p]
            dIC[p] = (r0 + g0, r1 + g1, r2 + g2, r3 + g3, r4 + g4, r5 + g5, r6 + g6, r7 + g7,
                      r8 + g8)
            x0, x1, x2, x3, x4, x5 = hC[i]
            y0, y1, y2, y3, y4, y5 = hC[p]
            hC[p] = (y0 + x0, y1 + x1, y2 + x2, y3 + x3, y4 + x4, y5 + x5)
            x0, x1, x2, x3, x4, x5 = frc[i]
            y0, y1, y2, y3, y4, y5 = frc[p]
            frc[p] = (y0 + x0, y1 + x1, y2 + x2, y3 + x3, y4 + x4, y5 + x5)

    # Each column of body i against itself and its ancestors j; body 1's columns at once
    # when it has several (a free-flyer's six), else as any ancestor's
    once = False
    last = 0
    if NB > 0:
        (_, _, _, _, dof1, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _,
         _, _, _, _, _, _, _, _, _, _, _, _) = rows[1]
        once = dof1 > 1
        last = 1 if once else 0
    for i in range(1, NB + 1):
        (p, _, _, kv, dof, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _,
         _, _, _, _, _, _, _, _, _, _, _, _) = rows[i]
        cm, chx, chy, chz, cxx, cxy, cxz, cyy, cyz, czz = IC[i]
        g0, g1, g2, g3, g4, g5, g6, g7, g8 = dIC[i]
        hn0, hn1, hn2, hf0, hf1, hf2 = hC[i]
        Fn0, Fn1, Fn2, Ff0, Ff1, Ff2 = frc[i]
        for c in range(dof):
            k = kv + c
            (s0, s1, s2, s3, s4, s5, al0, al1, al2, al3, al4, al5, be0, be1, be2, be3, be4, be5,
             ad0, ad1, ad2, ad3, ad4, ad5) = dcol[6 * i + c]
            # rows of body i: A = IC s, B = İC s - s ×* hC
            A0, A1, A2, A3, A4, A5 = I_motion(cm, chx, chy, chz, cxx, cxy, cxz, cyy, cyz, czz,
                                              s0, s1, s2, s3, s4, s5)
            u0, u1, u2, u3, u4, u5 = Irate_motion(g0, g1, g2, g3, g4, g5, g6, g7, g8,
                                                  s0, s1, s2, s3, s4, s5)       # İC s
            o0, o1, o2, o3, o4, o5 = crf_force(s0, s1, s2, s3, s4, s5,
                                               hn0, hn1, hn2, hf0, hf1, hf2)   # s ×* hC
            B0, B1, B2, B3, B4, B5 = u0 - o0, u1 - o1, u2 - o2, u3 - o3, u4 - o4, u5 - o5
            if p != 0:
                # columns of body i for its ancestors (a root has none):
                # IC α + İC β + β ×* hC + s ×* F, and q̇'s
                Q0, Q1, Q2, Q3, Q4, Q5 = I_motion(cm, chx, chy, chz, cxx, cxy, cxz, cyy, cyz,
                                                  czz, al0, al1, al2, al3, al4, al5)
                x0, x1, x2, x3, x4, x5 = Irate_motion(g0, g1, g2, g3, g4, g5, g6, g7, g8,
                                                      be0, be1, be2, be3, be4, be5)
                y0, y1, y2, y3, y4, y5 = crf_force(be0, be1, be2, be3, be4, be5,
                                                   hn0, hn1, hn2, hf0, hf1, hf2)
                z0, z1, z2, z3, z4, z5 = crf_force(s0, s1, s2, s3, s4, s5,
                                                   Fn0, Fn1, Fn2, Ff0, Ff1, Ff2)
                Q0, Q1, Q2 = Q0 + x0 + y0 + z0, Q1 + x1 + y1 + z1, Q2 + x2 + y2 + z2
                Q3, Q4, Q5 = Q3 + x3 + y3 + z3, Q4 + x4 + y4 + z4, Q5 + x5 + y5 + z5
                V0, V1, V2, V3, V4, V5 = I_motion(cm, chx, chy, chz, cxx, cxy, cxz, cyy, cyz,
                                                  czz, ad0, ad1, ad2, ad3, ad4, ad5)
                V0, V1, V2 = V0 + u0 + o0, V1 + u1 + o1, V2 + u2 + o2   # + İC s + s ×* hC
                V3, V4, V5 = V3 + u3 + o3, V4 + u4 + o4, V5 + u5 + o5
            # body i's own columns: the subtree formula (body 1's several below, at once)
            for d in range(dof if i != 1 or not once else 0):
                r = kv + d
                (t0, t1, t2, t3, t4, t5, bl0, bl1, bl2, bl3, bl4, bl5, bb0, bb1, bb2, bb3, bb4,
                 bb5, bd0, bd1, bd2, bd3, bd4, bd5) = dcol[6 * i + d]
                dq[k * n + r] = dq[k * n + r] + (
                    (A0 * bl0 + A1 * bl1 + A2 * bl2 + A3 * bl3 + A4 * bl4 + A5 * bl5)
                    + (B0 * bb0 + B1 * bb1 + B2 * bb2 + B3 * bb3 + B4 * bb4 + B5 * bb5))
                dv[k * n + r] = dv[k * n + r] + (
                    (A0 * bd0 + A1 * bd1 + A2 * bd2 + A3 * bd3 + A4 * bd4 + A5 * bd5)
                    + (B0 * t0 + B1 * t1 + B2 * t2 + B3 * t3 + B4 * t4 + B5 * t5))
                H[k * n + r] = H[k * n + r] + (
                    A0 * t0 + A1 * t1 + A2 * t2 + A3 * t3 + A4 * t4 + A5 * t5)
            # the ancestors j of body i (but body 1 when its columns are taken at once)
            j = p
            while j > last:
                (pj, _, _, kj, dj, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _,
                 _, _, _, _, _, _, _, _, _, _, _, _) = rows[j]
                for d in range(dj):
                    r = kj + d
                    (t0, t1, t2, t3, t4, t5, bl0, bl1, bl2, bl3, bl4, bl5, bb0, bb1, bb2, bb3,
                     bb4, bb5, bd0, bd1, bd2, bd3, bd4, bd5) = dcol[6 * j + d]
                    # row k (body i, in the subtree of j), column r (joint j)
                    dq[k * n + r] = dq[k * n + r] + (
                        (A0 * bl0 + A1 * bl1 + A2 * bl2 + A3 * bl3 + A4 * bl4 + A5 * bl5)
                        + (B0 * bb0 + B1 * bb1 + B2 * bb2 + B3 * bb3 + B4 * bb4 + B5 * bb5))
                    dv[k * n + r] = dv[k * n + r] + (
                        (A0 * bd0 + A1 * bd1 + A2 * bd2 + A3 * bd3 + A4 * bd4 + A5 * bd5)
                        + (B0 * t0 + B1 * t1 + B2 * t2 + B3 * t3 + B4 * t4 + B5 * t5))
                    Mt = A0 * t0 + A1 * t1 + A2 * t2 + A3 * t3 + A4 * t4 + A5 * t5
                    H[k * n + r] = H[k * n + r] + Mt
                    # row r (ancestor j), column k (body i)
                    dq[r * n + k] = dq[r * n + k] + (
                        t0 * Q0 + t1 * Q1 + t2 * Q2 + t3 * Q3 + t4 * Q4 + t5 * Q5)
                    dv[r * n + k] = dv[r * n + k] + (
                        t0 * V0 + t1 * V1 + t2 * V2 + t3 * V3 + t4 * V4 + t5 * V5)
                    H[r * n + k] = H[r * n + k] + Mt
                j = pj
            if once and (j == 1 or i == 1):
                # body 1 (v_0 = 0, so β = 0; ᵂX_1 = 1, so s = mul S): its columns at once,
                # A·α = -(a_0 ×* A)·s,  A·α' + B·s = (B - v_1 ×* A)·s,  and Q·s, V·s, A·s
                (_, code1, _, kv1, _, bx, by, bz, _, _, _, _, _, _, _, _, _, _, _, _,
                 _, _, _, _, _, _, _, _, _, _, mul1, _) = rows[1]
                x0, x1, x2, x3, x4, x5 = crf_force(*acc[0], A0, A1, A2, A3, A4, A5)
                y0, y1, y2, y3, y4, y5 = crf_force(*vel[1], A0, A1, A2, A3, A4, A5)
                if i == 1:      # its own block: row k
                    joint_crba(code1, dq, n, k, kv1, mul1, False, bx, by, bz,
                               -x0, -x1, -x2, -x3, -x4, -x5)
                    joint_crba(code1, dv, n, k, kv1, mul1, False, bx, by, bz, B0 - y0,
                               B1 - y1, B2 - y2, B3 - y3, B4 - y4, B5 - y5)
                    joint_crba(code1, H, n, k, kv1, mul1, False, bx, by, bz,
                               A0, A1, A2, A3, A4, A5)
                else:           # an ancestor's: row k and column k
                    joint_pair(code1, dq, n, k, kv1, mul1, bx, by, bz,
                               -x0, -x1, -x2, -x3, -x4, -x5, Q0, Q1, Q2, Q3, Q4, Q5)
                    joint_pair(code1, dv, n, k, kv1, mul1, bx, by, bz, B0 - y0, B1 - y1,
                               B2 - y2, B3 - y3, B4 - y4, B5 - y5, V0, V1, V2, V3, V4, V5)
                    joint_pair(code1, H, n, k, kv1, mul1, bx, by, bz, A0, A1, A2, A3, A4, A5,
                               A0, A1, A2, A3, A4, A5)
