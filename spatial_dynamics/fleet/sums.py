# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The drive fit as sums: normal equations that add over chunks, bags and days.

Each joint's drive fit (:mod:`spatial_dynamics.replay.identify`) is the least-squares
solution of ``A θ ≈ r`` with ``A = [q̇, tanh(q̇/ε), q̈]`` (N, 3) and ``r`` the torque residual
(N,). Everything the solution, its σ and the residual RMS need is in four sums::

    G = AᵀA (3, 3),   h = Aᵀr (3,),   rr = rᵀr,   N

and the sums of two recordings are the sums of their concatenation, so a robot's fit over a
week of bags, or over one long bag cut into chunks on several workers, is one addition and
one 3×3 solve: equal to the fit of the concatenated samples to rounding.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Dict, Iterable, Sequence

import numpy as np

from ..replay.identify import Identified, missing_note, RCOND, regressor


@dataclass
class Sums:
    """Normal equations of ``n`` joints: ``G`` (n, 3, 3), ``h`` (n, 3), ``rr`` (n,), ``N``."""

    G: np.ndarray
    h: np.ndarray
    rr: np.ndarray
    N: int

    def __add__(self, other: 'Sums') -> 'Sums':
        """Return the sums of both recordings (their samples concatenated)."""
        return Sums(self.G + other.G, self.h + other.h, self.rr + other.rr,
                    self.N + other.N)

    def to_dict(self) -> Dict:
        """Return plain lists (JSON: floats written by repr come back bit for bit)."""
        return {'G': self.G.tolist(), 'h': self.h.tolist(), 'rr': self.rr.tolist(),
                'N': int(self.N)}

    @classmethod
    def from_dict(cls, d: Dict) -> 'Sums':
        """Inverse of :meth:`to_dict`."""
        return cls(np.array(d['G'], float), np.array(d['h'], float),
                   np.array(d['rr'], float), int(d['N']))


def normal_sums(residual: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
                threshold: float) -> Sums:
    """Return the sums of a recording's residual (N, n) with its regressors."""
    n = residual.shape[1]
    G, h = np.empty((n, 3, 3)), np.empty((n, 3))
    for j in range(n):
        A = regressor(qd[:, j], qdd[:, j], threshold)
        G[j], h[j] = A.T @ A, A.T @ residual[:, j]
    return Sums(G, h, np.einsum('ij,ij->j', residual, residual), residual.shape[0])


def total(parts: Iterable[Sums]) -> Sums:
    """Return the sum of ``parts`` (in the order given: the same order, the same bits)."""
    parts = list(parts)
    out = parts[0]
    for p in parts[1:]:
        out = out + p
    return out


def solve(s: Sums, names: Sequence[str]) -> Identified:
    """Fit each joint's damping, friction and armature from the sums; as ``identify`` does.

    The same columns are dropped as :func:`spatial_dynamics.replay.identify.identify` drops
    them (column RMS ``sqrt(G_kk/N)``; collinearity from the singular values of the scaled
    columns, the square roots of the eigenvalues of the scaled ``G``). The solution is found
    on the scaled normal equations; the residual sum of squares is ``rr - θᵀh``.
    """
    n = s.G.shape[0]
    theta = np.full((n, 3), np.nan)
    sigma = np.full((n, 3), np.nan)
    N = max(s.N, 1)
    before = np.sqrt(s.rr / N)
    after = before.copy()
    notes = []
    for j in range(n):
        G, h = s.G[j], s.h[j]
        scale = np.sqrt(np.maximum(np.diag(G), 0.0) / N)
        use = scale > 0.0
        if use.any():
            use &= scale > RCOND * scale.max()
        while use.sum() > 1:
            k = np.flatnonzero(use)
            Gs = G[np.ix_(k, k)] / np.outer(scale[k], scale[k]) / N
            lam = np.linalg.eigvalsh(Gs)
            if np.sqrt(max(lam[0], 0.0)) > RCOND * np.sqrt(lam[-1]):
                break
            use[k[np.argmin(scale[k])]] = False
        notes += missing_note(names[j], use)
        if not use.any():
            continue
        k = np.flatnonzero(use)
        D = scale[k] * np.sqrt(N)
        Gs = G[np.ix_(k, k)] / np.outer(D, D)
        x = np.linalg.solve(Gs, h[k] / D) / D
        theta[j, k] = x
        ss = max(s.rr[j] - x @ h[k], 0.0)
        after[j] = np.sqrt(ss / N)
        s2 = ss / max(s.N - len(k), 1)
        sigma[j, k] = np.sqrt(s2 * np.diag(np.linalg.inv(Gs)) / D ** 2)
    return Identified(theta[:, 0], theta[:, 1], theta[:, 2], before, after, notes, sigma)
