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
needed. The pass is :func:`~spatial_dynamics.algorithms.rnea.rnea_spatial`'s, batched; bodies
are the model's moving bodies (``model.body_names[1:]``, fixed-joint links lumped into them),
mimic joints fold onto their source as in ``rnea``.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from .arguments import as_joint_arrays, as_vector
from ..joints import jcalc
from ..model import Model
from ..spatial import crm

#: Names of the ten parameters of a body, in the order of :func:`regressor`'s columns.
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


def regressor(model: Model, q, qd, qdd, gravity: Sequence[float] = (0.0, 0.0, -9.81)
              ) -> np.ndarray:
    """Return ``Y`` (..., n, 10·NB) with ``rnea(model, q, qd, qdd, gravity) = Y @ π``.

    ``π`` stacks the :data:`PARAMETERS` of the moving bodies ``model.body_names[1:]`` in
    order (:func:`parameters` gives the model's own). Arguments as :func:`~spatial_dynamics.
    rnea` (no ``f_ext``: external wrenches do not depend on the inertias).
    """
    q, qd, qdd = as_joint_arrays(model, q, qd, qdd)
    a_grav = np.concatenate([np.zeros(3), as_vector('gravity', gravity, 3)])
    batch = q.shape[:-1]
    NB = model.NB
    n = q.shape[-1]
    Y = np.zeros(batch + (n, 10 * NB))
    v = [np.zeros(batch + (6,))] + [None] * NB
    a = [np.broadcast_to(-a_grav, batch + (6,))] + [None] * NB
    # axes[i]: the motion subspaces of body i and its moving ancestors in body i's frame,
    # (..., 6, depth), in the order of chain[i]
    axes, chain = [np.zeros(batch + (6, 0))] + [None] * NB, [[]] + [None] * NB
    for i in range(1, NB + 1):
        k, mul, off = model.qidx[i], model.qmul[i], model.qoff[i]
        XJ, S = jcalc(model.jtype[i], model.axis[i], mul * q[..., k] + off)
        vJ = S * (mul * qd[..., k])[..., None]
        Xup = XJ @ model.Xtree[i]
        p = model.parent[i]
        v[i] = _mv(Xup, v[p]) + vJ
        a[i] = _mv(Xup, a[p]) + S * (mul * qdd[..., k])[..., None] + _mv(crm(v[i]), vJ)
        own = np.broadcast_to(S, batch + (6,))[..., None]
        axes[i] = np.concatenate([Xup @ axes[p], own], axis=-1) if chain[p] else own
        chain[i] = chain[p] + [i]
        # joint j's row, body i's columns: S_jᵀ (ʲX_i)* K_i = (ⁱX_j S_j)ᵀ K_i
        rows = np.swapaxes(axes[i], -1, -2) @ body_wrench_basis(v[i], a[i])
        for r, j in enumerate(chain[i]):
            Y[..., model.qidx[j], 10 * (i - 1):10 * i] += model.qmul[j] * rows[..., r, :]
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
