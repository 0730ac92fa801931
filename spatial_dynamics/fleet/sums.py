# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The drive fit as sums: normal equations that add over chunks, bags and days.

Each joint's drive fit (:mod:`spatial_dynamics.drives`) is the least-squares
solution of ``A θ ≈ r`` with ``A = [q̇, tanh(q̇/ε), q̈]`` (N, 3) and ``r`` the torque residual
(N,). The normal equations of ``[A r]``, ``[A r]ᵀ[A r]`` (4, 4), hold everything the
solution, its σ and the residual RMS need, and those of two recordings are the sum of
theirs: a robot's fit over a week of bags, or over one long bag cut into chunks on several
workers, is one addition and one small solve, equal to the fit of the concatenated samples
to rounding.

They are kept square-rooted: ``R`` (4, 4), the triangular factor of ``[A r]`` (``RᵀR =
[A r]ᵀ[A r]``, from a QR factorisation); two recordings' factors add by the QR factorisation
of the two stacked (8, 4) (the sequential least squares of Lawson and Hanson, *Solving Least
Squares Problems*, ch. 27). The sums themselves lose the residual: ``|r - Aθ|² = rᵀr - θᵀAᵀr``
at the solution, a difference of two nearly equal numbers when the drives explain the
residual almost wholly (residuals of 1e-5 N m on torques of 1 N m: off by ~eps·10¹⁰; a
noiseless bag's merged chunks gave σ 3e-8 off the whole bag's), while ``|R [θ; -1]|²``
cancels no digit, and ``R[:, :3] θ ≈ R[:, 3]`` is solved to the digits of a QR, not the
squared condition of the normal equations. ``G = AᵀA`` and ``rr = rᵀr`` are kept as sums too:
the column scales and the collinearity test read ``G``, the RMS before the fit ``rr``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Dict, Iterable, Sequence

import numpy as np

from ..drives import Identified, missing_note, RCOND, regressor


@dataclass
class Sums:
    """The fit's sums of ``n`` joints: ``G`` (n, 3, 3), ``rr`` (n,), ``N``, ``R`` (n, 4, 4).

    ``R``: the triangular factor of each joint's ``[A r]`` (the module's docstring).
    """

    G: np.ndarray
    rr: np.ndarray
    N: int
    R: np.ndarray

    def rss(self, theta: np.ndarray) -> np.ndarray:
        """Return ``|r - Aθ|²`` per joint for ``theta`` (n, 3), without cancelling digits."""
        x = np.concatenate([theta, -np.ones((len(theta), 1))], axis=1)
        e = np.einsum('jkl,jl->jk', self.R, x)
        return np.einsum('jk,jk->j', e, e)

    def __add__(self, other: 'Sums') -> 'Sums':
        """Return the sums of both recordings (their samples concatenated)."""
        return Sums(self.G + other.G, self.rr + other.rr, self.N + other.N,
                    _triangular(np.concatenate([self.R, other.R], axis=1)))

    def to_dict(self) -> Dict:
        """Return plain lists (JSON: floats written by repr come back bit for bit)."""
        return {'G': self.G.tolist(), 'rr': self.rr.tolist(), 'N': int(self.N),
                'R': self.R.tolist()}

    @classmethod
    def from_dict(cls, d: Dict) -> 'Sums':
        """Inverse of :meth:`to_dict`."""
        return cls(np.array(d['G'], float), np.array(d['rr'], float), int(d['N']),
                   np.array(d['R'], float))


def _triangular(M: np.ndarray) -> np.ndarray:
    """Return the (n, 4, 4) triangular factors of stacked rows ``M`` (n, m, 4) (zeros below m)."""
    R = np.zeros((len(M), 4, 4))
    for j, rows in enumerate(M):
        if len(rows):
            r = np.linalg.qr(rows, mode='r')
            R[j, :len(r)] = r
    return R


def normal_sums(residual: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
                threshold: float) -> Sums:
    """Return the sums of a recording's residual (N, n) with its regressors."""
    n = residual.shape[1]
    G, R = np.empty((n, 3, 3)), np.zeros((n, 4, 4))
    for j in range(n):
        A = regressor(qd[:, j], qdd[:, j], threshold)
        G[j] = A.T @ A
        R[j] = _triangular(np.column_stack((A, residual[:, j]))[None])[0]
    return Sums(G, np.einsum('ij,ij->j', residual, residual), residual.shape[0], R)


def total(parts: Iterable[Sums]) -> Sums:
    """Return the sum of ``parts`` (in the order given: the same order, the same bits)."""
    parts = list(parts)
    out = parts[0]
    for p in parts[1:]:
        out = out + p
    return out


def solve(s: Sums, names: Sequence[str]) -> Identified:
    """Fit each joint's damping, friction and armature from the sums; as ``identify`` does.

    The same columns are dropped as :func:`spatial_dynamics.drives.identify` drops
    them (column RMS ``sqrt(G_kk/N)``; collinearity from the singular values of the scaled
    columns, the square roots of the eigenvalues of the scaled ``G``). The solution is the
    least squares of the triangular factor (``R[:, k] θ ≈ R[:, 3]`` over the columns ``k``
    kept: the same problem as ``A[:, k] θ ≈ r``, to the digits of a QR factorisation, not
    the squared condition of the normal equations), and the residual sum of squares is
    :meth:`Sums.rss` at it.
    """
    n = s.G.shape[0]
    theta = np.full((n, 3), np.nan)
    sigma = np.full((n, 3), np.nan)
    N = max(s.N, 1)
    before = np.sqrt(s.rr / N)
    after = before.copy()
    notes = []
    fitted = []         # (joint, the columns fitted, the diagonal of their G⁻¹)
    for j in range(n):
        G = s.G[j]
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
        x = np.linalg.lstsq(s.R[j][:, k] / D, s.R[j][:, 3], rcond=None)[0] / D
        theta[j, k] = x
        fitted.append((j, k, np.diag(np.linalg.inv(Gs)) / D ** 2))
    ss = np.maximum(s.rss(np.nan_to_num(theta)), 0.0)      # a term left out counts as 0
    for j, k, unscaled in fitted:
        after[j] = np.sqrt(ss[j] / N)
        sigma[j, k] = np.sqrt(ss[j] / max(s.N - len(k), 1) * unscaled)
    return Identified(theta[:, 0], theta[:, 1], theta[:, 2], before, after, notes, sigma)
