# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The joint-torque regressor: ``τ = Y(q, q̇, q̈) π``, RNEA's linearity in the inertias.

Every body's wrench in the RNEA, ``f_i = I_i a_i + v_i ×* I_i v_i`` (RBDA eq. 5.9), is linear
in its inertial parameters (Atkeson, An and Hollerbach 1986; RBDA §9.4)::

    π_i = [m, m c_x, m c_y, m c_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz]

(``c`` the centre of mass, ``I`` the rotational inertia about the body frame's origin, both
in the body frame: Pinocchio's ``Inertia.toDynamicParameters`` order). With ``h = m c`` and
``Ī`` that inertia, the spatial inertia is ``[[Ī, h×], [-h×, m 1]]`` and

    n = Ī ω̇ + h × a + ω × Ī ω + ω × (h × v) + v × (ω × h)
    f = m a + ω̇ × h + ω × (ω × h) + m ω × v

(``[ω; v]`` the body's velocity, ``[ω̇; a]`` its acceleration with gravity as a base
acceleration, RBDA §5.3), so ``f_i = K(v_i, a_i) π_i`` with ``K`` 6×10. The backward pass
then carries ``K`` instead of ``f``: the column block of body ``i`` in the row of joint ``j``
is ``S_jᵀ (ʲX_i)* K_i = (ⁱX_j S_j)ᵀ K_i`` for every ``i`` in the subtree of ``j``, so one
forward pass carries each body's ancestors' joint axes into its frame and no backward pass is
needed. Bodies are the model's moving bodies (``model.body_names[1:]``, fixed-joint links
lumped into them); mimic joints fold onto their source as in ``rnea`` (``mul_j S_j``).

Two texts of the same equations, as for the RNEA (:mod:`.rnea`):

* :func:`regressor_spatial` writes them with 6×6 matrices (``jcalc``, ``crm``) and numpy
  batches, and :func:`body_wrench_basis` forms ``K`` column by column from the cross
  products above: the executable specification.
* :func:`regressor_kernel` on scalar components (with :func:`~.rnea.xup_kernel` and the
  products of :mod:`.components`), under the rules of :mod:`.rnea` plus two flat arrays, the
  result ``Y`` and the carried axes ``axes``, indexed explicitly: the one source that
  ``sd.regressor`` runs, on floats or (N,) arrays (``backend='numpy'``) or compiled from its
  translation (:mod:`spatial_dynamics.backends.codegen`). It writes ``K_i``'s nonzero
  entries in closed form: with ``α = a + ω × v`` and ``B = ω̇× + ω× ω×``, the column of
  ``m`` is ``[0; α]``, of ``h_k`` ``[e_k × α; B e_k]`` (``ω × (h × v) + v × (ω × h) =
  h × (ω × v)`` by Jacobi's identity), of ``Ī_rc`` ``[E_rc ω̇ + ω × E_rc ω; 0]``, so that a
  joint's row costs 36 products per body.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from .arguments import as_joint_arrays, as_vector
from .components import X_motion
from ..joints import jcalc, joint_axis, joint_coordinates, joint_motion, joint_velocity, NV
from ..model import Model
from ..spatial import crm

#: Names of the ten parameters of a body, in the order of the regressor's columns.
PARAMETERS = ('m', 'mc_x', 'mc_y', 'mc_z', 'I_xx', 'I_xy', 'I_yy', 'I_xz', 'I_yz', 'I_zz')
_SYM = ((0, 0), (0, 1), (1, 1), (0, 2), (1, 2), (2, 2))   # (row, col) of I_xx, I_xy, ...


def body_wrench_basis(v: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Return ``K`` (..., 6, 10): the body wrench ``I a + v ×* I v`` is ``K π``.

    ``v``, ``a``: (..., 6) the body's spatial velocity and acceleration ``[ω; v]``.
    """
    w, u = v[..., :3], v[..., 3:]
    dw, du = a[..., :3], a[..., 3:]
    K = np.zeros(v.shape[:-1] + (6, 10))
    K[..., 3:, 0] = du + np.cross(w, u)                       # m (a + ω × v)
    eye = np.eye(3)
    for k in range(3):                                        # h = e_k
        e = np.broadcast_to(eye[k], w.shape)
        K[..., :3, 1 + k] = (np.cross(e, du) + np.cross(w, np.cross(e, u))
                             + np.cross(u, np.cross(w, e)))
        K[..., 3:, 1 + k] = np.cross(dw, e) + np.cross(w, np.cross(w, e))
    for col, (r, c) in enumerate(_SYM):                       # Ī = E_rc + E_cr (or E_rr)
        E = np.zeros((3, 3))
        E[r, c] = E[c, r] = 1.0
        Ew = w @ E.T
        K[..., :3, 4 + col] = dw @ E.T + np.cross(w, Ew)
    return K


def regressor_kernel(rows, qd, qdd, gx, gy, gz, Y, axes, Xup, vel, acc) -> None:
    """``Y`` (``nv * 10 NB`` scalars, row-major) on scalar components, from the ``Xup`` of ``q``.

    The rules of :mod:`.rnea`: ``rows`` the layout's per-body rows, ``Xup`` the transforms of
    :func:`~.rnea.xup_kernel`, ``vel`` and ``acc`` scratch with a slot per body; ``axes``
    scratch of ``6 (NB + 1) (NB + 6)`` scalars, where ``axes[6 (i (NB + 6) + j) + c]`` holds
    ``mul_j ⁱX_j S_j`` (the axis of joint ``j``, an ancestor of body ``i`` or ``i`` itself, in
    body ``i``'s coordinates, times its mimic multiplier), and slots ``NB + 1 .. NB + 5`` the
    other five columns of a free-flyer's ``S``.
    """
    NB = len(rows) - 1
    R = len(rows) + 5
    W = 10 * NB
    zero = 0.0 * gx
    for c in range(len(Y)):
        Y[c] = zero
    vel[0] = (zero, zero, zero, zero, zero, zero)
    acc[0] = (zero, zero, zero, -gx, -gy, -gz)      # a_0 = -a_grav
    for i in range(1, NB + 1):
        (p, code, _, kv, _, ax, ay, az, _, _, _, _, _, _, _, _, _, _, _, _,
         _, _, _, _, _, _, _, _, _, _, mul, _) = rows[i]
        e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz = Xup[i]

        # v_i = Xup_i v_λ(i) + vJ,  a_i = Xup_i a_λ(i) + S_i q̈_i + v_i × vJ,  vJ = S_i q̇_i
        w0, w1, w2, v0, v1, v2 = X_motion(e00, e01, e02, e10, e11, e12, e20, e21, e22,
                                          rx, ry, rz, *vel[p])
        a0, a1, a2, l0, l1, l2 = X_motion(e00, e01, e02, e10, e11, e12, e20, e21, e22,
                                          rx, ry, rz, *acc[p])
        a0, a1, a2, l0, l1, l2 = joint_motion(code, qdd, kv, mul, ax, ay, az,
                                              a0, a1, a2, l0, l1, l2)
        (w0, w1, w2, v0, v1, v2, a0, a1, a2, l0, l1, l2) = joint_velocity(
            code, qd, kv, mul, ax, ay, az, w0, w1, w2, v0, v1, v2, a0, a1, a2, l0, l1, l2)
        vel[i] = (w0, w1, w2, v0, v1, v2)
        acc[i] = (a0, a1, a2, l0, l1, l2)

        # K_i, the body wrench I_i a_i + v_i ×* I_i v_i = K_i π_i, column by column (with
        # α = a + ω × v, B = ω̇× + ω× ω×, E_rc the unit symmetric matrix of Ibar_rc):
        #   m: [0; α],   h_k = e_k: [e_k × α; B e_k],   Ibar_rc: [E_rc ω̇ + ω × E_rc ω; 0]
        al0 = l0 + (w1 * v2 - w2 * v1)
        al1 = l1 + (w2 * v0 - w0 * v2)
        al2 = l2 + (w0 * v1 - w1 * v0)
        p01, p02, p12 = w0 * w1, w0 * w2, w1 * w2
        q00, q11, q22 = w0 * w0, w1 * w1, w2 * w2
        b00, b11, b22 = -(q11 + q22), -(q00 + q22), -(q00 + q11)     # B = ω̇× + ω ωᵀ - |ω|² 1
        b01, b10 = p01 - a2, p01 + a2
        b02, b20 = p02 + a1, p02 - a1
        b12, b21 = p12 - a0, p12 + a0
        xx0, xx1, xx2 = a0, p02, -p01                              # the angular parts
        xy0, xy1, xy2 = a1 - p02, a0 + p12, q00 - q11
        yy0, yy1, yy2 = -p12, a1, p01
        xz0, xz1, xz2 = a2 + p01, q22 - q00, a0 - p12
        yz0, yz1, yz2 = q11 - q22, a2 - p01, a1 + p02
        zz0, zz1, zz2 = p12, -p02, a2

        # Row of each joint j that moves body i (i and its ancestors), block i, for each
        # column c of S_j: (ⁱX_j S_j[:, c])ᵀ K_i, with ⁱX_j S_j = Xup_i (ᵖX_j S_j) carried from
        # the parent's slots (slot j for a joint's first column, NB + c for a free-flyer's
        # column c > 0: the root's, the one free-flyer of a model)
        j = i
        while j != 0:
            (pj, cj, _, kj, dj, bx, by, bz, _, _, _, _, _, _, _, _, _, _, _, _,
             _, _, _, _, _, _, _, _, _, _, mj, _) = rows[j]
            for col in range(dj):
                sl = j if col == 0 else NB + col
                if j == i:
                    s0, s1, s2, s3, s4, s5 = joint_axis(cj, col, bx, by, bz)
                    t0, t1, t2, u0, u1, u2 = mj * s0, mj * s1, mj * s2, mj * s3, mj * s4, mj * s5
                else:
                    c = 6 * (p * R + sl)
                    t0, t1, t2, u0, u1, u2 = X_motion(
                        e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz,
                        axes[c], axes[c + 1], axes[c + 2], axes[c + 3], axes[c + 4], axes[c + 5])
                c = 6 * (i * R + sl)
                axes[c] = t0
                axes[c + 1] = t1
                axes[c + 2] = t2
                axes[c + 3] = u0
                axes[c + 4] = u1
                axes[c + 5] = u2
                y = (kj + col) * W + 10 * (i - 1)
                Y[y] = Y[y] + (u0 * al0 + u1 * al1 + u2 * al2)
                Y[y + 1] = Y[y + 1] + ((al1 * t2 - al2 * t1) + (b00 * u0 + b10 * u1 + b20 * u2))
                Y[y + 2] = Y[y + 2] + ((al2 * t0 - al0 * t2) + (b01 * u0 + b11 * u1 + b21 * u2))
                Y[y + 3] = Y[y + 3] + ((al0 * t1 - al1 * t0) + (b02 * u0 + b12 * u1 + b22 * u2))
                Y[y + 4] = Y[y + 4] + (t0 * xx0 + t1 * xx1 + t2 * xx2)
                Y[y + 5] = Y[y + 5] + (t0 * xy0 + t1 * xy1 + t2 * xy2)
                Y[y + 6] = Y[y + 6] + (t0 * yy0 + t1 * yy1 + t2 * yy2)
                Y[y + 7] = Y[y + 7] + (t0 * xz0 + t1 * xz1 + t2 * xz2)
                Y[y + 8] = Y[y + 8] + (t0 * yz0 + t1 * yz1 + t2 * yz2)
                Y[y + 9] = Y[y + 9] + (t0 * zz0 + t1 * zz1 + t2 * zz2)
            j = pj


def regressor_spatial(model: Model, q, qd, qdd,
                      gravity: Sequence[float] = (0.0, 0.0, -9.81)) -> np.ndarray:
    """Return ``Y`` (..., n, 10·NB) with ``rnea(model, q, qd, qdd, gravity) = Y @ π``.

    Written on 6×6 matrices, batched with numpy: the executable specification of
    :func:`regressor_kernel` (``sd.regressor`` runs the kernel on the chosen backend).

    ``π`` stacks the :data:`PARAMETERS` of the moving bodies ``model.body_names[1:]`` in
    order (:func:`parameters` gives the model's own). Arguments as :func:`~spatial_dynamics.
    rnea` (no ``f_ext``: external wrenches do not depend on the inertias).
    """
    q, qd, qdd = as_joint_arrays(model, q, qd, qdd)
    a_grav = np.concatenate([np.zeros(3), as_vector('gravity', gravity, 3)])
    batch = q.shape[:-1]
    NB = model.NB
    Y = np.zeros(batch + (model.nv, 10 * NB))
    v = [np.zeros(batch + (6,))] + [None] * NB
    a = [np.broadcast_to(-a_grav, batch + (6,))] + [None] * NB
    # axes[i]: the motion subspaces of body i and its moving ancestors in body i's frame,
    # (..., 6, depth), in the order of chain[i]
    axes, chain = [np.zeros(batch + (6, 0))] + [None] * NB, [[]] + [None] * NB
    for i in range(1, NB + 1):
        k, kv, mul, jt = model.qidx[i], model.vidx[i], model.qmul[i], model.jtype[i]
        XJ, S = jcalc(jt, model.axis[i], joint_coordinates(jt, q, k, mul, model.qoff[i]))
        dofs = slice(kv, kv + NV[jt])
        vJ = mul * (qd[..., dofs] @ S.T)
        Xup = XJ @ model.Xtree[i]
        p = model.parent[i]
        v[i] = _mv(Xup, v[p]) + vJ
        a[i] = _mv(Xup, a[p]) + mul * (qdd[..., dofs] @ S.T) + _mv(crm(v[i]), vJ)
        own = np.broadcast_to(S, batch + S.shape)
        axes[i] = np.concatenate([Xup @ axes[p], own], axis=-1) if chain[p] else own
        chain[i] = chain[p] + [(i, col) for col in range(S.shape[1])]
        # the row of joint j's column c, body i's columns: (ⁱX_j S_j[:, c])ᵀ K_i
        rows = np.swapaxes(axes[i], -1, -2) @ body_wrench_basis(v[i], a[i])
        for r, (j, col) in enumerate(chain[i]):
            Y[..., model.vidx[j] + col, 10 * (i - 1):10 * i] += model.qmul[j] * rows[..., r, :]
    return Y


def parameters(model: Model) -> np.ndarray:
    """Return ``π`` (10·NB,): the :data:`PARAMETERS` of each moving body of ``model``.

    Read from the bodies' spatial inertias ``[[Ī, h×], [-h×, m 1]]`` (body frame, lumped
    links included), so ``regressor(model, ...) @ parameters(model)`` is ``rnea``.
    """
    out = np.zeros(10 * model.NB)
    for i in range(1, model.NB + 1):
        inertia = model.inertia[i]
        hx = inertia[:3, 3:]
        out[10 * (i - 1):10 * i] = [inertia[3, 3], hx[2, 1], hx[0, 2], hx[1, 0],
                                    *(inertia[r, c] for r, c in _SYM)]
    return out


def _mv(A: np.ndarray, x: np.ndarray) -> np.ndarray:
    return np.einsum('...ij,...j->...i', A, x)
