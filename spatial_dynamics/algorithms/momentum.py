# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Generalized momentum ``p = M(q) q̇`` and ``Cᵀ(q, q̇) q̇``, in one O(n) pass: one source.

What a momentum observer needs (``ṗ = τ + Cᵀ q̇ - g + τ_ext``, De Luca and Mattone 2003).
With the body velocities ``v_i`` and momenta ``h_i = I_i v_i`` of the RNEA forward pass, and
``H_i`` the momentum of the subtree of body i (the RNEA backward pass with ``h_i`` for ``f_i``):

    p_i = S_iᵀ H_i
    (Cᵀ q̇)_i = ∂T/∂q_i = (v_i × S_i)ᵀ H_i

The second line: turning joint i by dq moves the subtree's velocities and inertias with it,
so the kinetic energy T = ½ Σ v_jᵀ I_j v_j changes by ``-h_jᵀ (S_i × v_i) dq`` for each body j
of the subtree; and ``Cᵀ q̇ = ∂T/∂q`` follows from Lagrange's equations
(``d/dt ∂T/∂q̇ = ṗ``) and ``Ṁ = C + Cᵀ``. A mimic body adds ``mul`` times its part to its
source joint, as in the RNEA.

Written on scalar components under the rules of :mod:`.rnea` (the compiled backend is
generated from it).
"""

from __future__ import annotations

from .components import I_motion, X_motion, XT_force_plus
from ..joints import joint_ctq, joint_motion, joint_torque


def momentum_kernel(rows, q, qd, mom, ctq, Xup, vel, frc) -> None:
    """``M(q) q̇`` into ``mom`` and ``Cᵀ(q, q̇) q̇`` into ``ctq`` (``nv`` scalars each).

    ``Xup`` are the transforms of :func:`~.rnea.xup_kernel` for ``q``; ``vel`` and ``frc``
    scratch with a slot per body.
    """
    NB = len(rows) - 1
    vel[0] = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    for k in range(len(mom)):
        mom[k] = 0.0
        ctq[k] = 0.0
    for i in range(1, NB + 1):
        (p, code, _, kv, _, ax, ay, az, _, _, _, _, _, _, _, _, _, _, _, _,
         mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz, mul, _) = rows[i]
        e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz = Xup[i]
        # v_i = Xup_i v_λ(i) + S_i q̇_i
        w0, w1, w2, v0, v1, v2 = X_motion(e00, e01, e02, e10, e11, e12, e20, e21, e22,
                                          rx, ry, rz, *vel[p])
        w0, w1, w2, v0, v1, v2 = joint_motion(code, qd, kv, mul, ax, ay, az,
                                              w0, w1, w2, v0, v1, v2)
        vel[i] = (w0, w1, w2, v0, v1, v2)
        # h_i = I_i v_i
        m0, m1, m2, k0, k1, k2 = I_motion(mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz,
                                          w0, w1, w2, v0, v1, v2)
        frc[i] = [m0, m1, m2, k0, k1, k2]

    # Backward pass: H_λ(i) += Xup_iᵀ H_i; p_i = S_iᵀ H_i, (Cᵀ q̇)_i = (v_i × S_i)ᵀ H_i
    for i in range(NB, 0, -1):
        (p, code, _, kv, _, ax, ay, az, _, _, _, _, _, _, _, _, _, _, _, _,
         _, _, _, _, _, _, _, _, _, _, mul, _) = rows[i]
        n0, n1, n2, f0, f1, f2 = frc[i]
        w0, w1, w2, v0, v1, v2 = vel[i]
        joint_torque(code, mom, kv, mul, ax, ay, az, n0, n1, n2, f0, f1, f2)
        joint_ctq(code, ctq, kv, mul, ax, ay, az, w0, w1, w2, v0, v1, v2, n0, n1, n2, f0, f1,
                  f2)
        if p != 0:
            frc[p] = XT_force_plus(*Xup[i], n0, n1, n2, f0, f1, f2, *frc[p])
