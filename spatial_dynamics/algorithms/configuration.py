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

from .arguments import as_joint_arrays
from ..joints import joint_integrate, NQ, NV
from ..model import Model


def integrate(model: Model, q, qd, dt: float = 1.0) -> np.ndarray:
    """Return the configuration reached from ``q`` moving with ``qd`` for ``dt`` seconds.

    ``q`` (..., nq) and ``qd`` (..., nv), batch dimensions broadcast; returns (..., nq). The
    joints' coordinates move by ``qd dt``; a free-flyer's pose by its twist (see the module
    docstring), its quaternion renormalised.
    """
    q, qd = as_joint_arrays(model, q, qd)
    out = np.array(q, dtype=np.result_type(q, np.float64))
    for i in range(1, model.NB + 1):
        if model.body_joints[i] not in model.joint_names:
            continue                                # a mimic joint: its source moves
        k, kv, jt = model.qidx[i], model.vidx[i], model.jtype[i]
        out[..., k:k + NQ[jt]] = joint_integrate(jt, q[..., k:k + NQ[jt]],
                                                 qd[..., kv:kv + NV[jt]], dt)
    return out
