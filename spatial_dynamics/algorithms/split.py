# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The contact-consistent split of ``M q̈ + h = Sᵀ τ + J_cᵀ λ`` (Mistry et al. 2010): one source.

With ``J_cᵀ P = Q [R; 0]`` (Householder QR with column pivoting, ``Q = [Q1 Q2]``, ``Q1`` the
``r`` columns of the rank found), ``Q2ᵀ`` removes the contact forces, and the least
(``W``-weighted) torques solve ``Q2ᵀ Sᵀ τ = Q2ᵀ b`` (``b = M q̈ + h``, ``Sᵀ = [0; 1]``); then
the least ``λ`` of ``[R11 R12] Pᵀ λ = Q1ᵀ (b - Sᵀ τ)``::

    A = Q2ᵀ Sᵀ W^-½,  y = Q2ᵀ b:   τ = W^-½ Aᵀ (A Aᵀ)⁻¹ y,   λ = P [R11 R12]⁺ (Q1ᵀ b - Q1ᵀ Sᵀ τ)

**The rank.** Step ``j`` of the QR takes the row of ``J_c`` farthest from the span of the rows
taken before (its distance is ``|R_jj|``); the rank ``r`` is the number of steps whose distance
exceeds :data:`RANK_TOLERANCE` times the largest row norm of ``J_c`` (the scale of ``J_c``). A
row closer than that to the others (two points of one body a few µm apart, the fourth corner
of a sole, a foot and its shin's ``x`` rows) adds no direction: the contacts' wrenches are the
same with or without it. Rows dependent to rounding (every entry of ``R22`` within
:data:`DEPENDENT` of the scale: the corners of a sole, a foot and its shin) share the load, the
least ``λ``; rows only nearly dependent (two points of one body less than a few µm apart, not
one) carry none (``λ`` of those rows 0), which keeps ``J_cᵀ λ`` exact. Unpivoted, a
dependent row in the middle of ``J_c`` leaves a zero inside ``R``'s diagonal and the first
``r`` columns of ``Q`` are not the range of ``J_cᵀ``.

:func:`split_numpy` is the split in numpy (``'torques'`` with ``backend='numpy'``, and the
cases the kernel leaves to it); :func:`split_kernel` its equations on scalars (the compiled
backend is generated from it; ``m`` provides ``sqrt``).
"""

from __future__ import annotations

import numpy as np

#: Rank tolerance of ``J_c``, relative to its largest row norm (see the module doc). On a
#: robot of metre scale (rows of norm ~1 to 3) two points of one body closer than a few µm
#: count as one point: the couple they could make would need forces of ``τ / d``.
RANK_TOLERANCE = 1e-6
#: ``R22`` (the rows left out, reduced) within this of ``J_c``'s scale: dependent to rounding.
DEPENDENT = 1e-12


def split_kernel(QR, k, n, nb, wts, res, scr, tol, m) -> None:
    """Split into ``res``: ``τ`` (n), ``λ`` (k), 0 (solved) or 1 (the numpy split's case), r.

    ``QR`` is ``[J_cᵀ, b, Sᵀ]`` column-major (``nv = nb + n`` rows, ``k + 1 + n`` columns),
    overwritten by the factor; ``wts`` the square roots of the weights (n); ``tol`` the rank
    tolerance (:data:`RANK_TOLERANCE`); ``scr`` scratch of ``k + (nv + k + 2) nv`` scalars: the
    pivots (k), then ``A Aᵀ``'s Cholesky factor, then the QR of ``[R11 R12]ᵀ``. 1 when the
    numpy split answers instead: fewer than six base rows carried (``nv - r > n``), ``A Aᵀ``
    not positive definite, or ``A τ`` off ``y`` by more than its 1e-9 check (base rows the
    contacts cannot carry). ``res[n + k + 1]`` is the rank ``r`` found.
    """
    nv = nb + n
    cols = k + 1 + n
    res[n + k] = 1.0
    # the scale of J_c: its largest row norm (a column of J_cᵀ)
    big = 0.0
    for c in range(k):
        s = 0.0
        for i in range(nv):
            s = s + QR[i + c * nv] * QR[i + c * nv]
        if s > big:
            big = s
    floor = tol * m.sqrt(big)
    # J_cᵀ P = Q [R; 0]: step j swaps in the column of the largest norm below row j (pivot
    # scr[j]), then reflector j, H = 1 - 2 v vᵀ / vᵀv, v = x - α e_j, applied to the right.
    # Each column's sum runs down its rows in order, the columns side by side (scr[k + c],
    # free until the Cholesky factor): independent sums, not one chain after another
    r = 0
    for j in range(k):
        for c in range(j, k):
            scr[k + c] = 0.0
        for i in range(j, nv):
            for c in range(j, k):
                scr[k + c] = scr[k + c] + QR[i + c * nv] * QR[i + c * nv]
        best = -1.0
        piv = j
        for c in range(j, k):
            if scr[k + c] > best:
                best = scr[k + c]
                piv = c
        if not m.sqrt(best) > floor:
            break
        scr[j] = piv
        if piv != j:
            for i in range(nv):
                t = QR[i + j * nv]
                QR[i + j * nv] = QR[i + piv * nv]
                QR[i + piv * nv] = t
        x0 = QR[j + j * nv]
        alpha = -m.sqrt(best) if x0 >= 0.0 else m.sqrt(best)
        v0 = x0 - alpha
        vv = best - x0 * x0 + v0 * v0
        QR[j + j * nv] = alpha
        if vv > 0.0:
            for c in range(j + 1, cols):
                scr[k + c] = v0 * QR[j + c * nv]
            for i in range(j + 1, nv):
                vi = QR[i + j * nv]
                for c in range(j + 1, cols):
                    scr[k + c] = scr[k + c] + vi * QR[i + c * nv]
            for c in range(j + 1, cols):
                t = 2.0 * scr[k + c] / vv
                QR[j + c * nv] = QR[j + c * nv] - t * v0
                for i in range(j + 1, nv):
                    QR[i + c * nv] = QR[i + c * nv] - t * QR[i + j * nv]
        r = j + 1
    res[n + k + 1] = r
    # G = A Aᵀ (p × p, p = nv - r, A[i, c] = QR[r + i, k + 1 + c] / wts[c]), its Cholesky L
    p = nv - r
    if p > n:
        return
    for i in range(p):
        for j in range(i + 1):
            t = 0.0
            for c in range(n):
                ai = QR[r + i + (k + 1 + c) * nv] / wts[c]
                aj = QR[r + j + (k + 1 + c) * nv] / wts[c]
                t = t + ai * aj
            for a in range(j):
                t = t - scr[k + i * p + a] * scr[k + j * p + a]
            if i == j:
                if not t > 0.0:
                    return
                scr[k + i * p + i] = m.sqrt(t)
            else:
                scr[k + i * p + j] = t / scr[k + j * p + j]
    # L Lᵀ x = y (x in scr[k + p p …])
    for i in range(p):
        t = QR[r + i + k * nv]
        for a in range(i):
            t = t - scr[k + i * p + a] * scr[k + p * p + a]
        scr[k + p * p + i] = t / scr[k + i * p + i]
    for i in range(p - 1, -1, -1):
        t = scr[k + p * p + i]
        for a in range(i + 1, p):
            t = t - scr[k + a * p + i] * scr[k + p * p + a]
        scr[k + p * p + i] = t / scr[k + i * p + i]
    # τ w = Aᵀ x, τ
    for c in range(n):
        t = 0.0
        for i in range(p):
            t = t + (QR[r + i + (k + 1 + c) * nv] / wts[c]) * scr[k + p * p + i]
        res[c] = t / wts[c]
    # the check: A τ w = y, each row within 1e-9 max(1, max |y|) + 1e-9 |y_i|
    ymax = 1.0
    for i in range(p):
        y = QR[r + i + k * nv]
        if y < 0.0:
            y = -y
        if y > ymax:
            ymax = y
    for i in range(p):
        y = QR[r + i + k * nv]
        t = -y
        for c in range(n):
            t = t + QR[r + i + (k + 1 + c) * nv] * res[c]
        if t < 0.0:
            t = -t
        if y < 0.0:
            y = -y
        if not t <= 1e-9 * ymax + 1e-9 * y:
            return
    # the rows left out: dependent to rounding (every |R22| within 1e-12 of the scale) share
    # the load (the least z), those only nearly dependent carry none (z2 = 0: exact)
    dep = 0.0
    for j in range(r, k):
        for i in range(r, nv):
            d = QR[i + j * nv]
            if d < 0.0:
                d = -d
            if d > dep:
                dep = d
    if r < k and dep <= 1e-12 * m.sqrt(big):
        # the least z of [R11 R12] z = Q1ᵀ b - Q1ᵀ Sᵀ τ: [R11 R12]ᵀ = Z [L; 0] (X, k × r at
        # scr[k …], reflectors' v0 and vᵀv after it), Lᵀ u = …, z = Z [u; 0]
        for i in range(r):
            for a in range(k):
                scr[k + a + i * k] = QR[i + a * nv] if a >= i else 0.0
        for i in range(r):
            s = 0.0
            for a in range(i, k):
                s = s + scr[k + a + i * k] * scr[k + a + i * k]
            x0 = scr[k + i + i * k]
            alpha = -m.sqrt(s) if x0 >= 0.0 else m.sqrt(s)
            v0 = x0 - alpha
            vv = s - x0 * x0 + v0 * v0
            scr[k + i + i * k] = alpha
            scr[k + k * r + i] = v0
            scr[k + k * r + r + i] = vv
            if vv > 0.0:
                for c in range(i + 1, r):
                    t = v0 * scr[k + i + c * k]
                    for a in range(i + 1, k):
                        t = t + scr[k + a + i * k] * scr[k + a + c * k]
                    t = 2.0 * t / vv
                    scr[k + i + c * k] = scr[k + i + c * k] - t * v0
                    for a in range(i + 1, k):
                        scr[k + a + c * k] = scr[k + a + c * k] - t * scr[k + a + i * k]
        for i in range(r):
            t = QR[i + k * nv]
            for c in range(n):
                t = t - QR[i + (k + 1 + c) * nv] * res[c]
            for a in range(i):
                t = t - scr[k + a + i * k] * res[n + a]
            res[n + i] = t / scr[k + i + i * k]
        for i in range(r, k):
            res[n + i] = 0.0
        for i in range(r - 1, -1, -1):
            v0 = scr[k + k * r + i]
            vv = scr[k + k * r + r + i]
            if vv > 0.0:
                t = v0 * res[n + i]
                for a in range(i + 1, k):
                    t = t + scr[k + a + i * k] * res[n + a]
                t = 2.0 * t / vv
                res[n + i] = res[n + i] - t * v0
                for a in range(i + 1, k):
                    res[n + a] = res[n + a] - t * scr[k + a + i * k]
    else:
        # R11 z1 = Q1ᵀ b - Q1ᵀ Sᵀ τ, backwards; z2 = 0
        for i in range(r, k):
            res[n + i] = 0.0
        for j in range(r - 1, -1, -1):
            t = QR[j + k * nv]
            for c in range(n):
                t = t - QR[j + (k + 1 + c) * nv] * res[c]
            for a in range(j + 1, r):
                t = t - QR[j + a * nv] * res[n + a]
            res[n + j] = t / QR[j + j * nv]
    # λ = P z: the pivots' swaps undone, last first
    for j in range(r - 1, -1, -1):
        piv = int(scr[j])
        t = res[n + j]
        res[n + j] = res[n + piv]
        res[n + piv] = t
    res[n + k] = 0.0


def split_numpy(Jc: np.ndarray, b: np.ndarray, n: int, w: np.ndarray) -> tuple:
    """Return the contact-consistent ``(τ, λ, r)`` of ``J_c`` (k, nv) and ``b`` (nv,), in numpy.

    The module's equations: the pivoted QR is :func:`pivoted_qr` (:func:`split_kernel`'s
    steps, the same rank); ``τ`` the least solution by ``A Aᵀ`` when the contacts carry the
    base rows, else numpy's least squares (``A τ ≈ y``: the base residual says what is left);
    ``λ`` the least solution of ``[R11 R12] Pᵀ λ = Q1ᵀ (b - Sᵀ τ)`` when the rows left out
    are dependent to rounding (:data:`DEPENDENT`), else ``R11 z1 = …`` with those rows' ``λ``
    zero. ``w`` the square roots of the joints' weights (n,).
    """
    k, nv = Jc.shape
    M = np.zeros((nv, k + 1 + n))                   # [J_cᵀ, b, Sᵀ], Sᵀ = [0; 1]
    M[:, :k], M[:, k] = Jc.T, b
    M[nv - n:, k + 1:] = np.eye(n)
    r, perm, scale = pivoted_qr(M, k)
    A, y = M[r:, k + 1:] / w, M[r:, k]               # Q2ᵀ Sᵀ (τ / w) ... = Q2ᵀ b
    try:        # the least-norm solution Aᵀ (A Aᵀ)⁻¹ y, A of full row rank (feasible base rows)
        tau = A.T @ np.linalg.solve(A @ A.T, y) / w
        if not np.allclose(A @ (tau * w), y, rtol=1e-9, atol=1e-9 * max(1.0, np.abs(y).max(
                initial=0.0))):
            raise np.linalg.LinAlgError
    except np.linalg.LinAlgError:   # too few contacts to carry the base rows: least squares
        tau = np.linalg.lstsq(A, y, rcond=None)[0] / w
    c = M[:r, k] - M[:r, k + 1:] @ tau              # Q1ᵀ (b - Sᵀ τ)
    z = np.zeros(k)
    if r < k and np.abs(M[r:, r:k]).max(initial=0.0) <= DEPENDENT * scale:
        z = np.linalg.lstsq(M[:r, :k], c, rcond=None)[0]    # the least z of [R11 R12] z = c
    elif r:                                                 # R11 z1 = c, z2 = 0
        z[:r] = np.linalg.solve(M[:r, :r], c)
    lam = np.empty(k)
    lam[perm] = z
    return tau, lam, r


def pivoted_qr(M: np.ndarray, k: int) -> tuple:
    """Reduce ``M = [J_cᵀ, …]`` (nv, ≥ k) to ``Qᵀ M P`` in place; return ``(r, P, scale)``.

    ``P`` is the columns' order, ``scale`` the largest norm of the first ``k`` columns.

    The steps of :func:`split_kernel`: step ``j`` swaps in the column of
    the first ``k`` whose norm below row ``j`` is largest and stops when that norm is not
    above :data:`RANK_TOLERANCE` times ``J_c``'s largest row norm (``r``
    steps made); a Householder reflector then zeroes it below row ``j`` in every column.
    """
    nv = len(M)
    perm = np.arange(k)
    scale = np.sqrt(np.einsum('ij,ij->j', M[:, :k], M[:, :k]).max(initial=0.0))
    floor = RANK_TOLERANCE * scale
    r = 0
    for j in range(min(k, nv)):
        below = np.einsum('ij,ij->j', M[j:, j:k], M[j:, j:k])
        p = j + int(np.argmax(below))
        if not np.sqrt(below[p - j]) > floor:
            break
        M[:, [j, p]], perm[[j, p]] = M[:, [p, j]], perm[[p, j]]
        x = M[j:, j]
        alpha = -np.sqrt(below[p - j]) if x[0] >= 0.0 else np.sqrt(below[p - j])
        v = x.copy()
        v[0] -= alpha
        vv = v @ v
        if vv > 0.0:
            M[j:, j + 1:] -= np.outer(v, (2.0 / vv) * (v @ M[j:, j + 1:]))
        M[j, j], M[j + 1:, j] = alpha, 0.0
        r = j + 1
    return r, perm, scale


def contact_rank(Jc: np.ndarray) -> int:
    """Return the rank of ``J_c`` (k, nv) that the split finds (:func:`pivoted_qr`)."""
    return pivoted_qr(Jc.T.copy(), len(Jc))[0]
