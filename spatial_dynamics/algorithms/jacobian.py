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

from .arguments import as_joint_arrays, check_model
from ..joints import jcalc, joint_coordinates, NV, quaternion_matrix
from ..model import Model

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
        base: a fixed-base model's :class:`~spatial_dynamics.base.BaseMotion`: with
            ``frame='world'``, the rows are turned by its orientation into the world's axes
            (the columns stay those of the joints: the base's own motion adds
            ``lX0 v_base`` to the link's velocity).

    Returns:
        J, shape (..., 6, nv): rad/s and m/s per unit of q̇ (rows ``[ω; v]``, columns in the
        order of ``model.joint_names``; a mimic joint's column folded onto its source's).
    """
    check_model(model)
    if frame not in FRAMES:
        raise ValueError(f'frame must be one of {list(FRAMES)}, got {frame!r}')
    J, lX0 = local_jacobian(model, q, link)
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
        raise ValueError(f'link {link!r} is not a link of {model.name!r}')
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
