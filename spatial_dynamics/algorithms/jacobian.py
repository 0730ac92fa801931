# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The Jacobian of a link's frame (RBDA §4.4 and eq. 4.10): ``v_l = J(q) q̇``.

The velocity of body ``b`` is the sum of the joint velocities on its path to the base, each
carried into ``b``'s coordinates (RBDA eq. 4.10, ``v_i = Xup_i v_λ(i) + S_i q̇_i``)::

    v_b = Σ_{j ∈ κ(b)} bXj S_j q̇_j,     bXj = Xup_b Xup_λ(b) ⋯ Xup_μ(j)   (bXb = 1)

so the column of joint ``j`` is ``bXj S_j`` (zero for joints not on the path). A link ``l``
lumped into ``b`` by fixed joints sees ``lXb`` more: ``J_l = lXb J_b``. A mimic joint moves by
``qmul · q̇`` of its source, so its column ``qmul · lXj S_j`` adds to the source's column, as
``rnea`` folds its torque. Columns are motion vectors ``[ω; v]`` (angular first).
"""

from __future__ import annotations

import numpy as np

from .arguments import as_joint_arrays, batch_of, check_model
from ..base import base_batches, check_base_motion
from ..joints import jcalc, joint_axis, joint_coordinates, NV, quaternion_matrix
from ..model import Model
from ..text import shown

#: Coordinates of :func:`jacobian`: the link's own frame, or the base (root link) axes with
#: the origin at the link's origin.
FRAMES = ('local', 'world')


def jacobian(model: Model, q, link: str, frame: str = 'local', *, base=None) -> np.ndarray:
    """Return the 6×nv Jacobian of ``link``'s frame: ``[ω; v] = J(q) q̇``, angular first.

    Args:
        model: the robot.
        q: joint positions (rad, m) in the order of ``model.joint_names``, shape (nq,) or
            (..., nq).
        link: any URDF link of the model, including links lumped into a body by fixed joints
            (``model.frames``) and the base (whose Jacobian is zero for a fixed base; the
            free-flyer's columns are the identity in its own frame for a floating base).
        frame: the coordinates of ``ω`` and ``v``; ``v`` is always the velocity of the point
            at the link's origin.

            * ``'local'``: the link's frame (Pinocchio's ``LOCAL``; the body Jacobian).
              ``τ = Jᵀ w`` for a wrench ``w = [n; f]`` expressed in the link frame, as
              ``rnea``'s ``f_ext`` takes it.
            * ``'world'``: the axes of the base (root link) frame, or of the world for a
              floating base, origin at the link's origin
              (Pinocchio's ``LOCAL_WORLD_ALIGNED``; what KDL's ``ChainJntToJacSolver`` and
              MoveIt's ``getJacobian`` return, angular and linear rows swapped). Not
              Pinocchio's ``WORLD``, whose ``v`` is that of the point at the base origin.
        base: a fixed-base model's :class:`~spatial_dynamics.base.BaseMotion` (a floating
            model's is refused: its rows are the world's already): with
            ``frame='world'``, the rows are turned by its orientation into the world's axes
            (the columns stay those of the joints: the base's own motion adds
            ``lX0 v_base`` to the link's velocity).

    Returns:
        J, shape (..., 6, nv): rad/s and m/s per unit of q̇ (rows ``[ω; v]``, columns in the
        order of ``model.joint_names``; a mimic joint's column folded onto its source's).
    """
    check_model(model)
    if frame not in FRAMES:
        raise ValueError(f'frame must be one of {list(FRAMES)}, got {shown(frame)}')
    if base is not None:
        check_base_motion(base, model)      # a floating model's rows are the world's already
    J, lX0 = local_jacobian(model, q, link)
    if base is not None:    # a base of another batch is refused in either frame
        batch_of((f'q of shape {np.shape(q)}', J.shape[:-2]), *base_batches(base))
    if frame == 'world':
        E = np.swapaxes(lX0[..., :3, :3], -1, -2)      # lX0 = [[E, 0], [-E r×, E]]: 0 ← l is Eᵀ
        if base is not None and base.orientation is not None:
            E = quaternion_matrix(base.orientation)[..., :, :] @ E     # world <- base <- link
        J = np.concatenate([E @ J[..., :3, :], E @ J[..., 3:, :]], axis=-2)
    return J


def local_jacobian(model: Model, q, link: str) -> tuple[np.ndarray, np.ndarray]:
    """Return ``(J, lX0)``: ``link``'s Jacobian in its own frame and its transform ``lX0``.

    ``J`` (..., 6, nv) as :func:`jacobian` with ``frame='local'``; ``lX0`` (..., 6, 6) maps
    motion vectors from base (body 0: the world of a floating base) to link coordinates, so
    the link's orientation is ``lX0[:3, :3]ᵀ`` and its origin ``-E ᵀ`` of the lower block.
    """
    at = model.frames.get(link)
    if at is None:
        raise ValueError(f'link {shown(link)} is not a link of {shown(model.name)}')
    (q,) = as_joint_arrays(model, q)
    batch = q.shape[:-1]
    J = np.zeros(batch + (6, model.nv), dtype=np.result_type(q, np.float64))
    lXi = np.broadcast_to(at.lXb, batch + (6, 6))      # lXb, then lXj as i climbs to the base
    i = at.body
    while i > 0:
        k, kv, mul, jt = model.qidx[i], model.vidx[i], model.qmul[i], model.jtype[i]
        XJ, S_i = jcalc(jt, model.axis[i], joint_coordinates(jt, q, k, mul, model.qoff[i]))
        J[..., :, kv:kv + NV[jt]] += mul * (lXi @ S_i)  # columns of joint i: lXi S_i
        lXi = lXi @ (XJ @ model.Xtree[i])               # lXλ(i) = lXi Xup_i
        i = model.parent[i]
    return J, lXi


#: Scalars of one body's row in :func:`bodies_kernel`'s output before its Jacobian: the
#: homogeneous placement ``[R p; 0 0 0 1]`` (4 × 4, row-major).
PLACEMENT = 16


def bodies_kernel(rows, Xup, J) -> None:
    """Every body's placement and world-aligned Jacobian into ``J``, from the ``Xup`` of ``q``.

    ``J`` holds ``len(rows) * (16 + 6 nv)`` scalars, a row per body (row 0 the base): its
    placement ``[R_i p_i; 0 0 0 1]`` (4 × 4 row-major: orientation world <- body, origin in
    the world), then its Jacobian ``J_i`` (6 × nv, row-major, angular rows first) at its
    origin in world axes (Pinocchio's ``LOCAL_WORLD_ALIGNED``, :func:`jacobian` with
    ``frame='world'``). From ``Xup_i = (E_i, r_i)`` (:func:`~.rnea.xup_kernel`), for each
    body after its parent::

        d_i = R_λ(i) r_i;   R_i = R_λ(i) E_iᵀ;   p_i = p_λ(i) + d_i
        J_i = [1 0; -d_i× 1] J_λ(i)  +  mul_i [R_i 0; 0 R_i] S_i   (at columns kv_i …)

    the parent's columns carried to the body's origin (``v + ω × d``), and the joint's own
    columns ``S_i[:, c]`` (:func:`~spatial_dynamics.joints.joint_axis`) turned into world
    axes; a mimic joint's add ``mul`` times theirs to its source's columns. Written on scalar
    components under the rules of :mod:`.rnea` (the compiled backend is generated from it).
    """
    (_, _, _, nv, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _,
     _, _, _, _, _, _, _, _, _, _, _, _) = rows[0]
    width = 16 + 6 * nv
    for a in range(width):
        J[a] = 0.0
    J[0] = 1.0
    J[5] = 1.0
    J[10] = 1.0
    J[15] = 1.0
    for i in range(1, len(rows)):
        (p, code, _, kv, dof, ax, ay, az, _, _, _, _, _, _, _, _, _, _, _, _,
         _, _, _, _, _, _, _, _, _, _, mul, _) = rows[i]
        e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz = Xup[i]
        o = p * width
        w = i * width
        a00 = J[o]
        a01 = J[o + 1]
        a02 = J[o + 2]
        a10 = J[o + 4]
        a11 = J[o + 5]
        a12 = J[o + 6]
        a20 = J[o + 8]
        a21 = J[o + 9]
        a22 = J[o + 10]
        # d_i = R_λ r_i;  R_i = R_λ E_iᵀ;  p_i = p_λ + d_i
        d0 = a00 * rx + a01 * ry + a02 * rz
        d1 = a10 * rx + a11 * ry + a12 * rz
        d2 = a20 * rx + a21 * ry + a22 * rz
        b00 = a00 * e00 + a01 * e01 + a02 * e02
        b01 = a00 * e10 + a01 * e11 + a02 * e12
        b02 = a00 * e20 + a01 * e21 + a02 * e22
        b10 = a10 * e00 + a11 * e01 + a12 * e02
        b11 = a10 * e10 + a11 * e11 + a12 * e12
        b12 = a10 * e20 + a11 * e21 + a12 * e22
        b20 = a20 * e00 + a21 * e01 + a22 * e02
        b21 = a20 * e10 + a21 * e11 + a22 * e12
        b22 = a20 * e20 + a21 * e21 + a22 * e22
        J[w] = b00
        J[w + 1] = b01
        J[w + 2] = b02
        J[w + 3] = J[o + 3] + d0
        J[w + 4] = b10
        J[w + 5] = b11
        J[w + 6] = b12
        J[w + 7] = J[o + 7] + d1
        J[w + 8] = b20
        J[w + 9] = b21
        J[w + 10] = b22
        J[w + 11] = J[o + 11] + d2
        J[w + 12] = 0.0
        J[w + 13] = 0.0
        J[w + 14] = 0.0
        J[w + 15] = 1.0
        # the parent's columns at the body's origin: ω, v + ω × d_i
        for j in range(nv):
            c = 16 + j
            w0 = J[o + c]
            w1 = J[o + c + nv]
            w2 = J[o + c + 2 * nv]
            J[w + c] = w0
            J[w + c + nv] = w1
            J[w + c + 2 * nv] = w2
            J[w + c + 3 * nv] = J[o + c + 3 * nv] + (w1 * d2 - w2 * d1)
            J[w + c + 4 * nv] = J[o + c + 4 * nv] + (w2 * d0 - w0 * d2)
            J[w + c + 5 * nv] = J[o + c + 5 * nv] + (w0 * d1 - w1 * d0)
        # the joint's own columns, world axes: mul [R_i s_ω; R_i s_v]
        for col in range(dof):
            s0, s1, s2, s3, s4, s5 = joint_axis(code, col, ax, ay, az)
            c = w + 16 + kv + col
            J[c] = J[c] + mul * (b00 * s0 + b01 * s1 + b02 * s2)
            J[c + nv] = J[c + nv] + mul * (b10 * s0 + b11 * s1 + b12 * s2)
            J[c + 2 * nv] = J[c + 2 * nv] + mul * (b20 * s0 + b21 * s1 + b22 * s2)
            J[c + 3 * nv] = J[c + 3 * nv] + mul * (b00 * s3 + b01 * s4 + b02 * s5)
            J[c + 4 * nv] = J[c + 4 * nv] + mul * (b10 * s3 + b11 * s4 + b12 * s5)
            J[c + 5 * nv] = J[c + 5 * nv] + mul * (b20 * s3 + b21 * s4 + b22 * s5)
