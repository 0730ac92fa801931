# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Joint models: ``jcalc`` returns the joint transform ``XJ`` and motion subspace ``S``.

RBDA table 4.1, for a 1-DOF joint about or along a unit ``axis`` given in the child
(successor) frame, which coincides with the joint frame at ``q = 0``.
"""

from __future__ import annotations

import numpy as np

from .spatial import Eaxis, Erotx, Eroty, Erotz, _rot, xlt

#: Joint kinds stored in ``Model.jtype``. Body 0 (the fixed base) has kind ``FIXED``.
FIXED, REVOLUTE, PRISMATIC = 0, 1, 2
KIND_NAMES = {FIXED: 'fixed', REVOLUTE: 'revolute', PRISMATIC: 'prismatic'}

#: URDF joint types and the kind that models them.
URDF_KINDS = {'revolute': REVOLUTE, 'continuous': REVOLUTE, 'prismatic': PRISMATIC,
              'fixed': FIXED}

_AXIS_E = (Erotx, Eroty, Erotz)


def motion_subspace(jtype: int, axis: np.ndarray) -> np.ndarray:
    """Return ``S`` (6,): ``[axis; 0]`` for revolute, ``[0; axis]`` for prismatic joints."""
    S = np.zeros(6)
    if jtype == REVOLUTE:
        S[:3] = axis
    elif jtype == PRISMATIC:
        S[3:] = axis
    return S


def jcalc(jtype: int, axis: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joint transform and motion subspace (RBDA table 4.1), batch-aware.

    ``q`` (...) in rad or m; returns ``XJ`` (..., 6, 6) mapping parent-side joint-frame
    coordinates to child coordinates, and ``S`` (6,) in child coordinates.
    Revolute: ``XJ = rot(E(axis, q))``, prismatic: ``XJ = xlt(axis q)``. An axis equal to a
    frame axis uses the cheaper ``rx``/``ry``/``rz`` form.
    """
    q = np.asarray(q, dtype=float)
    S = motion_subspace(jtype, axis)
    if jtype == REVOLUTE:
        k = _frame_axis(axis)
        XJ = _rot(_AXIS_E[k](q) if k >= 0 else Eaxis(axis, q))
    elif jtype == PRISMATIC:
        XJ = xlt(q[..., None] * axis)
    else:
        XJ = np.broadcast_to(np.eye(6), q.shape + (6, 6))
    return XJ, S


def _frame_axis(axis: np.ndarray) -> int:
    """Index 0/1/2 when ``axis`` is exactly +x/+y/+z, else -1."""
    for k in range(3):
        if axis[k] == 1.0 and axis[(k + 1) % 3] == 0.0 and axis[(k + 2) % 3] == 0.0:
            return k
    return -1
