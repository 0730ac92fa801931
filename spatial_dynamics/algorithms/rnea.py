# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Recursive Newton-Euler inverse dynamics (RBDA table 5.1, ``ID.m`` of spatial_v2): one source.

Forward pass, for i = 1..NB (body 0 is the fixed base, ``v_0 = 0``, ``a_0 = -a_grav``)::

    XJ, S_i = jcalc(jtype_i, q_i);  Xup_i = XJ Xtree_i;  vJ = S_i q̇_i
    v_i = Xup_i v_λ(i) + vJ
    a_i = Xup_i a_λ(i) + S_i q̈_i + v_i × vJ
    f_i = I_i a_i + v_i ×* I_i v_i - f_ext_i

Backward pass, for i = NB..1::

    τ_i = S_iᵀ f_i;   f_λ(i) += Xup_iᵀ f_i

Two texts of the same equations:

* :func:`rnea_spatial` writes them literally with 6×6 matrices (``crm``, ``crf``, ``jcalc``)
  and einsum over leading batch dimensions: the executable specification.
* :func:`xup_kernel` and :func:`rnea_kernel` (with the products of :mod:`.components`) on 3-vector
  components, with ``Xup = (E, r)`` kept as a rotation and a translation (RBDA §2.12), so no
  6×6 product is formed. **They are the one source every backend runs**: on Python floats
  (one state, no numpy call overhead), on numpy arrays of shape (N,) (a batch, one numpy
  operation per term for all N states), on ``mpmath.mpf`` (the high-precision reference),
  and — translated statement for statement by :mod:`spatial_dynamics.backends.codegen` into
  C when the package is built — compiled. A change to an equation is made here, once; the
  next build compiles it (a test fails while the built kernels are older than the source).

The kernels' text keeps to what the translation understands: per-body rows unpacked whole
from ``rows[i]`` (the layout of :mod:`spatial_dynamics.backends.layout`), spatial vectors
stored whole as tuples in ``Xup``, ``vel``, ``acc``, ``frc`` and read whole (or an element of
``frc[p]`` updated in place), ``nonzero(x)`` for "not identically zero", ``m.sin``/``m.cos``
for the sine and cosine of the number type.
"""

from __future__ import annotations

from typing import Mapping, Optional, Sequence

import numpy as np

from .arguments import as_joint_arrays, as_vector, f_ext_in_bodies
from .components import I_motion, X_motion, XT_force_plus
from ..joints import (jcalc, joint_coordinates, joint_motion, joint_torque, joint_transform,
                      joint_velocity, NV)
from ..model import Model
from ..spatial import crf, crm


def nonzero(x) -> bool:
    """Tell whether a scalar or array component is not identically zero."""
    return bool(x != 0) if not isinstance(x, np.ndarray) else bool(x.any())


def xup_kernel(rows, q, m, Xup) -> None:
    """Body transforms ``Xup_i = XJ(q_i) Xtree_i`` as ``(E (9 scalars), r (3))`` into ``Xup``.

    Each joint's :func:`~spatial_dynamics.joints.joint_transform` (RBDA table 4.1 and eq.
    2.27). ``m`` provides ``sin`` and ``cos`` for the scalars of ``q``.
    """
    for i in range(1, len(rows)):
        (_, code, k, _, _, ax, ay, az, t00, t01, t02, t10, t11, t12, t20, t21, t22, rx, ry, rz,
         _, _, _, _, _, _, _, _, _, _, mul, off) = rows[i]
        Xup[i] = joint_transform(code, q, k, mul, off, ax, ay, az, t00, t01, t02, t10, t11, t12,
                                 t20, t21, t22, rx, ry, rz, m)


def rnea_kernel(rows, q, qd, qdd, gx, gy, gz, f_body, has_fext, tau, Xup, vel, acc,
                frc) -> None:
    """RNEA on scalar components into ``tau`` (``model.nv`` scalars, any kind: see above).

    ``rows`` are the per-body rows of :mod:`~spatial_dynamics.backends.layout` (row 0 the
    base), ``Xup`` the transforms of :func:`xup_kernel` for the same ``q``; ``vel``, ``acc``
    and ``frc`` are scratch with a slot per body. With ``has_fext``, ``f_body[i]`` is the
    external force ``[n; f]`` on body ``i`` in body coordinates (6 scalars, zeros if none).
    What depends on the joint's kind (``S q̈``, ``S q̇`` and ``v_i × S q̇``, ``Sᵀ f``) the
    joint computes (:mod:`spatial_dynamics.joints`).

    Terms that cannot change the answer are skipped: with q̇ = 0 every body velocity and
    velocity-product term is zero; with q̇ = q̈ = 0 (gravity only) every angular acceleration
    is zero too, so ``a_i = (0, E_i l_λ(i))`` and ``f_i = (h × l_i, m l_i)``; with zero
    gravity a body on the fixed base skips ``Xup a_0``. Each result is the full computation's
    (the skipped products are exact zeros).
    """
    NB = len(rows) - 1
    zero = 0.0 * gx
    moving = False
    for x in qd:
        if nonzero(x):
            moving = True
            break
    static = not moving
    if static:
        for x in qdd:
            if nonzero(x):
                static = False
                break
    weightless = not (nonzero(gx) or nonzero(gy) or nonzero(gz))
    vel[0] = (zero, zero, zero, zero, zero, zero)
    acc[0] = (zero, zero, zero, -gx, -gy, -gz)      # a_0 = -a_grav
    for k in range(len(tau)):
        tau[k] = zero

    for i in range(1, NB + 1):
        (p, code, _, kv, _, ax, ay, az, _, _, _, _, _, _, _, _, _, _, _, _,
         mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz, mul, _) = rows[i]
        e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz = Xup[i]
        if static:
            # Gravity only: a_i = (0, E_i l_λ(i)), f_i = I_i a_i = (h × l_i, m l_i).
            _, _, _, pl0, pl1, pl2 = acc[p]
            l0 = e00 * pl0 + e01 * pl1 + e02 * pl2
            l1 = e10 * pl0 + e11 * pl1 + e12 * pl2
            l2 = e20 * pl0 + e21 * pl1 + e22 * pl2
            acc[i] = (zero, zero, zero, l0, l1, l2)
            n0, n1, n2 = hy * l2 - hz * l1, hz * l0 - hx * l2, hx * l1 - hy * l0
            f0, f1, f2 = mass * l0, mass * l1, mass * l2
        else:
            # a_i = Xup_i a_λ(i) + S_i q̈_i + v_i × vJ
            if p == 0 and weightless:
                a0 = a1 = a2 = l0 = l1 = l2 = zero      # a_0 = 0
            else:
                pa0, pa1, pa2, pl0, pl1, pl2 = acc[p]
                a0, a1, a2, l0, l1, l2 = X_motion(e00, e01, e02, e10, e11, e12, e20, e21, e22,
                                                  rx, ry, rz, pa0, pa1, pa2, pl0, pl1, pl2)
            a0, a1, a2, l0, l1, l2 = joint_motion(code, qdd, kv, mul, ax, ay, az,
                                                  a0, a1, a2, l0, l1, l2)

            # f_i = I_i a_i + v_i ×* I_i v_i - f_ext_i, with I = [[Ibar, h×], [h×ᵀ, m 1]]
            w0 = w1 = w2 = v0 = v1 = v2 = zero
            if moving:
                # v_i = Xup_i v_λ(i) + vJ,  vJ = S_i q̇_i
                pw0, pw1, pw2, pv0, pv1, pv2 = vel[p]
                w0, w1, w2, v0, v1, v2 = X_motion(e00, e01, e02, e10, e11, e12, e20, e21, e22,
                                                  rx, ry, rz, pw0, pw1, pw2, pv0, pv1, pv2)
                (w0, w1, w2, v0, v1, v2, a0, a1, a2, l0, l1, l2) = joint_velocity(
                    code, qd, kv, mul, ax, ay, az, w0, w1, w2, v0, v1, v2, a0, a1, a2, l0, l1,
                    l2)
                vel[i] = (w0, w1, w2, v0, v1, v2)
            acc[i] = (a0, a1, a2, l0, l1, l2)

            n0, n1, n2, f0, f1, f2 = I_motion(mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz,
                                              a0, a1, a2, l0, l1, l2)      # I_i a_i
            if moving:
                # momentum I_i v_i, then v_i ×* (I_i v_i) = [w × hn + v × hf; w × hf]
                m0, m1, m2, k0, k1, k2 = I_motion(mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz,
                                                  Izz, w0, w1, w2, v0, v1, v2)
                n0 += (w1 * m2 - w2 * m1) + (v1 * k2 - v2 * k1)
                n1 += (w2 * m0 - w0 * m2) + (v2 * k0 - v0 * k2)
                n2 += (w0 * m1 - w1 * m0) + (v0 * k1 - v1 * k0)
                f0 += w1 * k2 - w2 * k1
                f1 += w2 * k0 - w0 * k2
                f2 += w0 * k1 - w1 * k0
        if has_fext:
            fe0, fe1, fe2, fe3, fe4, fe5 = f_body[i]
            n0, n1, n2 = n0 - fe0, n1 - fe1, n2 - fe2
            f0, f1, f2 = f0 - fe3, f1 - fe4, f2 - fe5
        frc[i] = [n0, n1, n2, f0, f1, f2]

    # Backward pass: τ_i = S_iᵀ f_i, f_λ(i) += Xup_iᵀ f_i
    for i in range(NB, 0, -1):
        (p, code, _, kv, _, ax, ay, az, _, _, _, _, _, _, _, _, _, _, _, _,
         _, _, _, _, _, _, _, _, _, _, mul, _) = rows[i]
        n0, n1, n2, f0, f1, f2 = frc[i]
        joint_torque(code, tau, kv, mul, ax, ay, az, n0, n1, n2, f0, f1, f2)
        if p != 0:
            frc[p] = XT_force_plus(*Xup[i], n0, n1, n2, f0, f1, f2, *frc[p])


# --------------------------------------------------------------------------------------------
# The executable specification: the same equations on 6×6 matrices

def rnea_spatial(model: Model, q, qd, qdd, gravity: Sequence[float] = (0.0, 0.0, -9.81),
                 f_ext: Optional[Mapping[str, np.ndarray]] = None) -> np.ndarray:
    """RNEA written literally on 6×6 spatial matrices (reference; same contract as rnea)."""
    q, qd, qdd = as_joint_arrays(model, q, qd, qdd)
    a_grav = np.concatenate([np.zeros(3), as_vector('gravity', gravity, 3)])
    fb = f_ext_in_bodies(model, f_ext)
    batch = q.shape[:-1]
    NB = model.NB
    Xup, v, a, f = [None] * (NB + 1), [None] * (NB + 1), [None] * (NB + 1), [None] * (NB + 1)
    v[0] = np.zeros(batch + (6,))
    a[0] = np.broadcast_to(-a_grav, batch + (6,))
    S = [None] * (NB + 1)
    for i in range(1, NB + 1):
        k, kv, mul, jt = model.qidx[i], model.vidx[i], model.qmul[i], model.jtype[i]
        XJ, S[i] = jcalc(jt, model.axis[i], joint_coordinates(jt, q, k, mul, model.qoff[i]))
        dofs = slice(kv, kv + NV[jt])
        vJ = mul * (qd[..., dofs] @ S[i].T)
        Xup[i] = XJ @ model.Xtree[i]
        p = model.parent[i]
        v[i] = _mv(Xup[i], v[p]) + vJ
        a[i] = _mv(Xup[i], a[p]) + mul * (qdd[..., dofs] @ S[i].T) + _mv(crm(v[i]), vJ)
        Iv = _mv(model.inertia[i], v[i])
        f[i] = _mv(model.inertia[i], a[i]) + _mv(crf(v[i]), Iv) - fb.get(i, 0.0)
    tau = np.zeros(qd.shape)
    for i in range(NB, 0, -1):
        kv = model.vidx[i]
        tau[..., kv:kv + NV[model.jtype[i]]] += model.qmul[i] * (f[i] @ S[i])
        p = model.parent[i]
        if p > 0:
            f[p] = f[p] + _mv(np.swapaxes(Xup[i], -1, -2), f[i])
    return tau


def _mv(A: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Batched matrix-vector product ``A x`` over leading dimensions."""
    return np.einsum('...ij,...j->...i', A, x)
