# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Configurations: moving ``q`` by a velocity ``q̇`` (``nv`` numbers) for a time step.

For a fixed-base model ``q`` and ``q̇`` have one coordinate per joint and this is
``q + q̇ dt``. A floating base's ``q`` holds a position and a unit quaternion (7 numbers) and
its ``q̇`` the base twist ``[ω; v]`` in the base frame (6): the pose moves along the screw of
the twist, ``M exp(q̇ dt)`` (RBDA §4.5; Pinocchio's ``integrate``), see
:func:`spatial_dynamics.joints.integrate_free_flyer`.
"""

from __future__ import annotations

import numpy as np

from .arguments import as_joint_arrays, as_real_array
from ..bounds import MAX_POSITION
from ..joints import joint_integrate, NQ, NV
from ..model import Model


def integrate(model: Model, q, qd, dt=1.0) -> np.ndarray:
    """Return the configuration reached from ``q`` moving with ``qd`` for ``dt`` seconds.

    ``q`` (..., nq) and ``qd`` (..., nv), batch dimensions broadcast; ``dt`` (s) a number or
    an array of batch dimensions broadcast with theirs (one step per state); returns
    (..., nq). The joints' coordinates move by ``qd dt``; a free-flyer's pose by its twist
    (see the module docstring), its quaternion renormalised. ``ValueError`` naming ``q``,
    ``qd`` or ``dt`` when one is not finite, ``dt``'s shape does not broadcast, or a
    coordinate's step ``qd dt`` exceeds ±:data:`~spatial_dynamics.bounds.MAX_POSITION`
    (rad or m; far beyond any real step, well before the pose's arithmetic overflows).
    """
    q, qd = as_joint_arrays(model, q, qd)
    dt = as_real_array('dt', dt).astype(float)
    batch = q.shape[:-1]
    try:
        batch = np.broadcast_shapes(batch, dt.shape)
    except ValueError:
        raise ValueError(f'dt must be a number (s) or an array whose shape broadcasts with '
                         f'the batch {batch} of q and qd, got shape {dt.shape}') from None
    for what, x in (('q', q), ('qd', qd), ('dt', dt)):
        bad = np.argwhere(~np.isfinite(x))
        if len(bad):
            where = f'[{", ".join(map(str, bad[0]))}]' if x.ndim else ''
            raise ValueError(f'{what} must be finite: {what}{where} is {x[tuple(bad[0])]}')
    q, qd = (np.broadcast_to(x, batch + x.shape[-1:]) for x in (q, qd))
    dt = np.broadcast_to(dt, batch)[..., None]
    with np.errstate(over='ignore'):            # the guard's own product may overflow
        step = np.abs(qd * dt)
    bad = np.argwhere(~(step <= MAX_POSITION))
    if len(bad):
        k = tuple(bad[0])
        raise ValueError(f'qd · dt must stay within ±{MAX_POSITION:g} rad or m a step '
                         f'(bounds.MAX_POSITION): qd[{", ".join(map(str, k))}] is {qd[k]:g}, '
                         f'dt {dt[k[:-1] + (0,)]:g} s')
    out = np.array(q, dtype=np.result_type(q, np.float64))
    for i in range(1, model.NB + 1):
        if model.body_joints[i] not in model.joint_names:
            continue                                # a mimic joint: its source moves
        k, kv, jt = model.qidx[i], model.vidx[i], model.jtype[i]
        out[..., k:k + NQ[jt]] = joint_integrate(jt, q[..., k:k + NQ[jt]],
                                                 qd[..., kv:kv + NV[jt]], dt)
    return out
