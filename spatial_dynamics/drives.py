# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Per-joint drive terms from the torque residual, by linear least squares.

What a joint's drive adds to the rigid-body torque is modelled as the node does it
(:func:`spatial_dynamics.terms.friction_torque`, :func:`~spatial_dynamics.terms.armature_torque`)::

    r_j = τ_measured,j - RNEA_j(q, q̇, q̈) = damping_j q̇_j + friction_j tanh(q̇_j / ε)
                                           + armature_j q̈_j + noise

which is linear in ``(damping_j, friction_j, armature_j)``: one least-squares fit per joint
on the regressor ``[q̇_j, tanh(q̇_j/ε), q̈_j]``. A joint whose column is (nearly) zero or
collinear with another (it never moved, never reversed, or never accelerated) leaves that
parameter unidentified (``nan``) and the rest are fitted without it.

Not identifiable this way: link masses, centres of mass and inertias. Each enters the torque
of every joint between the link and the base through ``q`` and ``q̇`` of all of them, so one
joint's residual alone cannot separate them; they need the full inertial-parameter regressor
(Atkeson, An and Hollerbach 1986; ten parameters per link, reduced to a base set) and
trajectories that excite all of them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import List, Optional

import numpy as np

PARAMETERS = ('damping', 'friction', 'armature')
#: A regressor column counts as absent when its RMS is below this fraction of the largest
#: one's (after scaling the columns to unit RMS: collinearity via the singular values).
RCOND = 1e-3


@dataclass
class Identified:
    """Fitted ``damping``, ``friction``, ``armature`` (n,) and residual RMS before/after.

    ``notes`` says per joint what could not be identified and why; a term not identified is
    ``nan`` (its σ too).
    """

    damping: np.ndarray
    friction: np.ndarray
    armature: np.ndarray
    rms_before: np.ndarray
    rms_after: np.ndarray
    notes: List[str]
    sigma: Optional[np.ndarray] = None      # (n, 3) one σ of each fitted term (nan: none)


def regressor(qd: np.ndarray, qdd: np.ndarray, threshold: float) -> np.ndarray:
    """Columns ``[q̇, tanh(q̇/ε), q̈]`` of one joint, (N, 3)."""
    return np.column_stack((qd, np.tanh(qd / threshold), qdd))


def missing_note(joint: str, use: np.ndarray) -> List[str]:
    """Return the note (a list of one, or none) naming the drive terms ``use`` leaves out."""
    missing = [PARAMETERS[k] for k in range(3) if not use[k]]
    if not missing:
        return []
    why = ('velocity never left zero' if not use[0] and not use[1] else
           'motion does not separate it from the other terms')
    return [f'{joint}: {", ".join(missing)} not identified (the joint\'s {why})']


def identify(residual: np.ndarray, qd: np.ndarray, qdd: np.ndarray, threshold: float,
             names) -> Identified:
    """Fit each joint's damping, Coulomb friction and armature to its residual (N, n)."""
    n = residual.shape[1]
    theta = np.full((n, 3), np.nan)
    sigma = np.full((n, 3), np.nan)
    after = np.sqrt(np.mean(residual ** 2, axis=0))
    before = after.copy()
    notes = []
    for j in range(n):
        A = regressor(qd[:, j], qdd[:, j], threshold)
        r = residual[:, j]
        scale = np.sqrt(np.mean(A ** 2, axis=0))
        use = scale > 0.0
        if use.any():
            use &= scale > RCOND * scale.max()
        # Drop the columns that are collinear with the others, the weakest first.
        while use.sum() > 1:
            s = np.linalg.svd(A[:, use] / scale[use], compute_uv=False)
            if s[-1] > RCOND * s[0]:
                break
            weakest = np.flatnonzero(use)[np.argmin(scale[use])]
            use[weakest] = False
        notes += missing_note(names[j], use)
        if not use.any():
            continue
        x, *_ = np.linalg.lstsq(A[:, use], r, rcond=None)
        theta[j, use] = x
        fit = r - A[:, use] @ x
        after[j] = np.sqrt(np.mean(fit ** 2))
        s2 = fit @ fit / max(len(r) - int(use.sum()), 1)
        sigma[j, use] = np.sqrt(s2 * np.diag(np.linalg.pinv(A[:, use].T @ A[:, use])))
    return Identified(theta[:, 0], theta[:, 1], theta[:, 2], before, after, notes, sigma)
