# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Articulated-body algorithm: forward dynamics ``q̈`` in O(NB) (RBDA table 7.1), one source.

Forward pass, for i = 1..NB (``v_0 = 0``)::

    v_i = Xup_i v_λ(i) + S_i q̇_i;   c_i = v_i × S_i q̇_i
    IA_i = I_i;   pA_i = v_i ×* I_i v_i - f_ext_i

Backward pass, for i = NB..1::

    U_i = IA_i S_i;   D_i = S_iᵀ U_i + armature_i;   u_i = τ_i - S_iᵀ pA_i
    if λ(i) ≠ 0:   Ia = IA_i - U_i D_i⁻¹ U_iᵀ;   pa = pA_i + Ia c_i + U_i D_i⁻¹ u_i
                   IA_λ(i) += Xup_iᵀ Ia Xup_i;   pA_λ(i) += Xup_iᵀ pa

Forward pass, for i = 1..NB (``a_0 = -a_grav``)::

    a' = Xup_i a_λ(i) + c_i;   q̈_i = D_i⁻¹ (u_i - U_iᵀ a');   a_i = a' + S_i q̈_i

A free-flyer root has ``S = 1`` (its six coordinates are the body's ``[ω; v]``): ``D = IA``,
so ``IA a_1 = τ_1 - pA_1`` is solved directly (``IA = L diag(d) Lᵀ``, 6x6) and
``q̈_1 = a_1 - a'``. Armature (kg m² or kg per coordinate) adds to ``D`` (to ``IA``'s diagonal
on the free-flyer): it is ``M + diag(armature)`` the algorithm inverts.

``D_i`` are the pivots of the factorization of ``M`` from its last coordinate back (RBDA
§6.5 and §7.3, :mod:`.forward`), and ``M_kk = S_iᵀ IC_i S_i`` (+ armature) its diagonal, with
``IC_i`` the composite inertia of ``i``'s subtree (RBDA table 6.2), accumulated alongside::

    IC_i = I_i;   M_kk = S_iᵀ IC_i S_i;   IC_λ(i) += Xup_iᵀ IC_i Xup_i

A pivot ``D_i <= PIVOT_TOL M_kk`` (:data:`~.forward.PIVOT_TOL`: the rest of ``i``'s subtree
makes its motion to within that of its inertia; a joint that moves no mass and carries no
armature, two joints repeating each other's motion through massless links) leaves ``info``
at its coordinate, ``q̈`` unfinished; on the free-flyer the pivots of ``IA_1``'s factor
against ``IC_1``'s diagonal (a massless root link whose motion a joint repeats). A model where two
bodies share a coordinate (a mimic joint and its source) has no articulated-body recursion (the
coordinate's ``D`` is no single body's): ``info`` is then ``-2`` before any work, and the
caller takes the composite-rigid-body path (:mod:`.crba`, :mod:`.forward`). ``-1``: solved.

:func:`aba_kernel` is written on scalars under the rules of :mod:`.rnea` (per-body rows, the
stores ``Xup vel acc IC`` and ``IA pA cJ UD`` read and written whole, the products of
:mod:`.components`), so the Python backend runs it on floats and the compiled backend is
generated from it.
"""

from __future__ import annotations

from .components import (I_articulated, I_motion, IA_motion, X_motion, XT_force_plus,
                         XT_I_X_plus, XT_IA_X_plus)
from .forward import PIVOT_TOL
from .rnea import nonzero
from ..joints import joint_axis, joint_motion, joint_velocity


def aba_kernel(rows, qd, tau, gx, gy, gz, f_body, has_fext, arm, has_arm, qdd, T, info, Xup,
               vel, acc, IC, IA, pA, cJ, UD) -> None:
    """``q̈`` into ``qdd`` (``nv`` scalars) from ``τ`` and the ``Xup`` of ``q`` (see above).

    ``rows`` are the layout's per-body rows (row 0 the base), ``Xup`` the transforms of
    :func:`~.rnea.xup_kernel`; ``f_body`` and ``has_fext`` as :func:`~.rnea.rnea_kernel` takes
    them; with ``has_arm``, ``arm`` holds ``nv`` armatures. ``vel acc IC IA pA cJ UD`` are
    scratch with a slot per body (``IC`` a composite inertia ``(m, h, Ibar)``; ``IA`` the upper
    triangle of a symmetric 6x6, 21 scalars; ``UD`` a joint's ``U`` (6), ``D⁻¹`` and ``u``),
    ``T`` scratch of 42 scalars (the free-flyer's factor, 36, and ``IC_1``'s diagonal).
    ``info[0]``: -1 when solved, else as the module docstring says.
    """
    NB = len(rows) - 1
    (_, _, _, n, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _,
     _, _, _, _, _, _, _, _, _, _, _, _) = rows[0]
    claimed = 0
    for i in range(1, NB + 1):
        (_, _, _, _, dof, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _,
         _, _, _, _, _, _, _, _, _, _, _, _) = rows[i]
        claimed += dof
    if claimed != n:        # a coordinate of two bodies (a mimic joint): no ABA
        info[0] = -2.0
        return
    zero = 0.0 * gx
    moving = False
    for x in qd:
        if nonzero(x):
            moving = True
            break
    vel[0] = (zero, zero, zero, zero, zero, zero)
    acc[0] = (zero, zero, zero, -gx, -gy, -gz)      # a_0 = -a_grav

    # v_i, c_i; IA_i = I_i, pA_i = v_i ×* I_i v_i - f_ext_i
    for i in range(1, NB + 1):
        (p, code, _, kv, _, ax, ay, az, _, _, _, _, _, _, _, _, _, _, _, _,
         mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz, mul, _) = rows[i]
        n0 = n1 = n2 = f0 = f1 = f2 = zero
        if moving:
            pw0, pw1, pw2, pv0, pv1, pv2 = vel[p]
            e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz = Xup[i]
            w0, w1, w2, v0, v1, v2 = X_motion(e00, e01, e02, e10, e11, e12, e20, e21, e22,
                                              rx, ry, rz, pw0, pw1, pw2, pv0, pv1, pv2)
            (w0, w1, w2, v0, v1, v2, c0, c1, c2, c3, c4, c5) = joint_velocity(
                code, qd, kv, mul, ax, ay, az, w0, w1, w2, v0, v1, v2, zero, zero, zero, zero,
                zero, zero)
            vel[i] = (w0, w1, w2, v0, v1, v2)
            cJ[i] = (c0, c1, c2, c3, c4, c5)
            # v_i ×* (I_i v_i) = [w × hn + v × hf; w × hf]
            m0, m1, m2, k0, k1, k2 = I_motion(mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz,
                                              w0, w1, w2, v0, v1, v2)
            n0 = (w1 * m2 - w2 * m1) + (v1 * k2 - v2 * k1)
            n1 = (w2 * m0 - w0 * m2) + (v2 * k0 - v0 * k2)
            n2 = (w0 * m1 - w1 * m0) + (v0 * k1 - v1 * k0)
            f0 = w1 * k2 - w2 * k1
            f1 = w2 * k0 - w0 * k2
            f2 = w0 * k1 - w1 * k0
        else:
            cJ[i] = (zero, zero, zero, zero, zero, zero)
        if has_fext:
            fe0, fe1, fe2, fe3, fe4, fe5 = f_body[i]
            n0, n1, n2 = n0 - fe0, n1 - fe1, n2 - fe2
            f0, f1, f2 = f0 - fe3, f1 - fe4, f2 - fe5
        pA[i] = (n0, n1, n2, f0, f1, f2)
        IA[i] = I_articulated(mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz)
        IC[i] = (mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz)

    # U_i, D_i, u_i; the articulated inertia and bias force handed to the parent; M_kk
    for i in range(NB, 0, -1):
        (p, code, _, kv, dof, ax, ay, az, _, _, _, _, _, _, _, _, _, _, _, _,
         _, _, _, _, _, _, _, _, _, _, mul, _) = rows[i]
        if dof == 1:
            (i00, i01, i02, i03, i04, i05, i11, i12, i13, i14, i15, i22, i23, i24, i25,
             i33, i34, i35, i44, i45, i55) = IA[i]
            p0, p1, p2, p3, p4, p5 = pA[i]
            s0, s1, s2, s3, s4, s5 = joint_axis(code, 0, ax, ay, az)
            if mul != 1.0:
                s0, s1, s2, s3, s4, s5 = (mul * s0, mul * s1, mul * s2, mul * s3, mul * s4,
                                          mul * s5)
            U0, U1, U2, U3, U4, U5 = IA_motion(i00, i01, i02, i03, i04, i05, i11, i12, i13,
                                               i14, i15, i22, i23, i24, i25, i33, i34, i35,
                                               i44, i45, i55, s0, s1, s2, s3, s4, s5)
            D = s0 * U0 + s1 * U1 + s2 * U2 + s3 * U3 + s4 * U4 + s5 * U5
            # M_kk = S_iᵀ IC_i S_i
            cm, chx, chy, chz, cxx, cxy, cxz, cyy, cyz, czz = IC[i]
            F0, F1, F2, F3, F4, F5 = I_motion(cm, chx, chy, chz, cxx, cxy, cxz, cyy, cyz, czz,
                                              s0, s1, s2, s3, s4, s5)
            Mkk = s0 * F0 + s1 * F1 + s2 * F2 + s3 * F3 + s4 * F4 + s5 * F5
            if has_arm:
                D = D + arm[kv]
                Mkk = Mkk + arm[kv]
            if D <= PIVOT_TOL * Mkk:    # (a NaN state goes through: NaN in, NaN out)
                info[0] = kv
                return
            Dinv = 1.0 / D
            u = tau[kv] - (s0 * p0 + s1 * p1 + s2 * p2 + s3 * p3 + s4 * p4 + s5 * p5)
            UD[i] = (U0, U1, U2, U3, U4, U5, Dinv, u)
            if p != 0:
                # Ia = IA - U D⁻¹ Uᵀ;  pa = pA + Ia c + U D⁻¹ u
                W0, W1, W2, W3, W4, W5 = (U0 * Dinv, U1 * Dinv, U2 * Dinv, U3 * Dinv,
                                          U4 * Dinv, U5 * Dinv)
                (i00, i01, i02, i03, i04, i05, i11, i12, i13, i14, i15, i22, i23, i24, i25,
                 i33, i34, i35, i44, i45, i55) = (
                    i00 - W0 * U0, i01 - W0 * U1, i02 - W0 * U2, i03 - W0 * U3, i04 - W0 * U4,
                    i05 - W0 * U5, i11 - W1 * U1, i12 - W1 * U2, i13 - W1 * U3, i14 - W1 * U4,
                    i15 - W1 * U5, i22 - W2 * U2, i23 - W2 * U3, i24 - W2 * U4, i25 - W2 * U5,
                    i33 - W3 * U3, i34 - W3 * U4, i35 - W3 * U5, i44 - W4 * U4, i45 - W4 * U5,
                    i55 - W5 * U5)
                if moving:
                    c0, c1, c2, c3, c4, c5 = cJ[i]
                    b0, b1, b2, b3, b4, b5 = IA_motion(i00, i01, i02, i03, i04, i05, i11, i12,
                                                       i13, i14, i15, i22, i23, i24, i25, i33,
                                                       i34, i35, i44, i45, i55,
                                                       c0, c1, c2, c3, c4, c5)
                    p0, p1, p2, p3, p4, p5 = (p0 + b0, p1 + b1, p2 + b2, p3 + b3, p4 + b4,
                                              p5 + b5)
                p0, p1, p2, p3, p4, p5 = (p0 + W0 * u, p1 + W1 * u, p2 + W2 * u,
                                          p3 + W3 * u, p4 + W4 * u, p5 + W5 * u)
                IA[p] = XT_IA_X_plus(*Xup[i], i00, i01, i02, i03, i04, i05, i11, i12, i13,
                                     i14, i15, i22, i23, i24, i25, i33, i34, i35, i44, i45,
                                     i55, *IA[p])
                pA[p] = XT_force_plus(*Xup[i], p0, p1, p2, p3, p4, p5, *pA[p])
                IC[p] = XT_I_X_plus(*Xup[i], cm, chx, chy, chz, cxx, cxy, cxz, cyy, cyz, czz,
                                    *IC[p])

    # a' = Xup_i a_λ(i) + c_i;  q̈_i = D_i⁻¹ (u_i - U_iᵀ a');  a_i = a' + S_i q̈_i
    for i in range(1, NB + 1):
        (p, code, _, kv, dof, ax, ay, az, _, _, _, _, _, _, _, _, _, _, _, _,
         _, _, _, _, _, _, _, _, _, _, mul, _) = rows[i]
        e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz = Xup[i]
        pa0, pa1, pa2, pl0, pl1, pl2 = acc[p]
        a0, a1, a2, a3, a4, a5 = X_motion(e00, e01, e02, e10, e11, e12, e20, e21, e22,
                                          rx, ry, rz, pa0, pa1, pa2, pl0, pl1, pl2)
        if moving:
            c0, c1, c2, c3, c4, c5 = cJ[i]
            a0, a1, a2, a3, a4, a5 = a0 + c0, a1 + c1, a2 + c2, a3 + c3, a4 + c4, a5 + c5
        if dof == 1:
            U0, U1, U2, U3, U4, U5, Dinv, u = UD[i]
            qdd[kv] = Dinv * (u - (U0 * a0 + U1 * a1 + U2 * a2 + U3 * a3 + U4 * a4
                                   + U5 * a5))
            a0, a1, a2, a3, a4, a5 = joint_motion(code, qdd, kv, mul, ax, ay, az,
                                                  a0, a1, a2, a3, a4, a5)
        else:
            # a free-flyer root (S = 1): IA a_1 = τ_1 - pA_1 by IA = L diag(d) Lᵀ, in T
            (i00, i01, i02, i03, i04, i05, i11, i12, i13, i14, i15, i22, i23, i24, i25,
             i33, i34, i35, i44, i45, i55) = IA[i]
            p0, p1, p2, p3, p4, p5 = pA[i]
            T[0] = i00
            T[1] = i01
            T[2] = i02
            T[3] = i03
            T[4] = i04
            T[5] = i05
            T[7] = i11
            T[8] = i12
            T[9] = i13
            T[10] = i14
            T[11] = i15
            T[14] = i22
            T[15] = i23
            T[16] = i24
            T[17] = i25
            T[21] = i33
            T[22] = i34
            T[23] = i35
            T[28] = i44
            T[29] = i45
            T[35] = i55
            # IC_1's diagonal: the pivots' M_kk
            cm, _, _, _, cxx, _, _, cyy, _, czz = IC[i]
            T[36] = cxx
            T[37] = cyy
            T[38] = czz
            T[39] = cm
            T[40] = cm
            T[41] = cm
            if has_arm:
                for c in range(6):
                    T[7 * c] = T[7 * c] + arm[kv + c]
                    T[36 + c] = T[36 + c] + arm[kv + c]
            qdd[kv] = tau[kv] - p0
            qdd[kv + 1] = tau[kv + 1] - p1
            qdd[kv + 2] = tau[kv + 2] - p2
            qdd[kv + 3] = tau[kv + 3] - p3
            qdd[kv + 4] = tau[kv + 4] - p4
            qdd[kv + 5] = tau[kv + 5] - p5
            # T (upper triangle, row j) = L diag(d) Lᵀ: T[6 j + k] = L_kj (k > j), T[7 j] = d_j
            for j in range(6):
                for k in range(j):
                    d = T[6 * k + j]
                    for t in range(k):
                        d = d - T[6 * t + k] * T[6 * t + j] * T[7 * t]
                    T[6 * k + j] = d / T[7 * k]
                d = T[7 * j]
                for t in range(j):
                    d = d - T[6 * t + j] * T[6 * t + j] * T[7 * t]
                if d <= PIVOT_TOL * T[36 + j]:
                    info[0] = kv + j
                    return
                T[7 * j] = d
            for j in range(6):          # L y = b
                for t in range(j):
                    qdd[kv + j] = qdd[kv + j] - T[6 * t + j] * qdd[kv + t]
            for j in range(6):
                qdd[kv + j] = qdd[kv + j] / T[7 * j]
            for j in range(5, -1, -1):  # Lᵀ a_1 = y / d
                for t in range(j + 1, 6):
                    qdd[kv + j] = qdd[kv + j] - T[6 * j + t] * qdd[kv + t]
            # q̈_1 = a_1 - a'
            b0, b1, b2, b3, b4, b5 = (qdd[kv], qdd[kv + 1], qdd[kv + 2], qdd[kv + 3],
                                      qdd[kv + 4], qdd[kv + 5])
            qdd[kv] = b0 - a0
            qdd[kv + 1] = b1 - a1
            qdd[kv + 2] = b2 - a2
            qdd[kv + 3] = b3 - a3
            qdd[kv + 4] = b4 - a4
            qdd[kv + 5] = b5 - a5
            a0, a1, a2, a3, a4, a5 = b0, b1, b2, b3, b4, b5
        acc[i] = (a0, a1, a2, a3, a4, a5)
    info[0] = -1.0
