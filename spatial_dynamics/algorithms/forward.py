# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Forward dynamics ``q̈ = M(q)⁻¹ (τ - C(q, q̇) q̇ - g(q))``: the sparse ``LᵀL`` solve, one source.

Forward dynamics runs the articulated-body algorithm (:mod:`.aba`) where it exists; this
solve is the path of a model where two bodies share a coordinate (a mimic joint), of a moving
base and of batches with armature, and it names the joint of a pivot that is not positive.
With ``M`` from :mod:`.crba` and the bias ``h = C q̇ + g`` from :mod:`.rnea` at ``q̈ = 0``,
``M q̈ = τ - h`` is solved by the factorization of RBDA §6.5 (tables 6.3 and 6.4), which keeps
the sparsity that branches give ``M``: ``M_ij ≠ 0`` only when coordinate ``i`` is an ancestor
of ``j`` or ``j`` of ``i``. ``λ(k)`` is the parent of velocity coordinate ``k`` (the previous
coordinate of its joint, or the parent body's last, or -1 at the root)::

    for k = n-1..0:   L_kk = √M_kk;   M_ki /= L_kk  (i = λ(k), λ(λ(k)), …)
                      M_ij -= M_ki M_kj  (i = λ(k), …;  j = i, λ(i), …)       M = Lᵀ L
    Lᵀ y = b:  for k = n-1..0:  y_k = b_k / L_kk;  b_i -= L_ki y_k  (i = λ(k), …)
    L x = y:   for k = 0..n-1:  x_k = (y_k - Σ L_kj x_j) / L_kk  (j = λ(k), …)

It costs the sum over coordinates of their depth squared instead of ``n³ / 6``. Two changes
of order leave every subtraction as it is (each ``M_ij`` still takes its updates ``k = n-1..0``
in turn): a coordinate's ancestors are walked once, into chains of consecutive coordinates
(``seg``), and the updates of the root block (the coordinates ``0..r-1`` that are ancestors of
every other one: a free-flyer's six) are made in one pass once the rows below it are done,
``M_rr -= Wᵀ W`` with ``W`` those rows' first ``r`` columns; a free-flyer's 6x6 holds its
lower triangle in 21 scalars meanwhile. A model where
two bodies share a coordinate (a mimic joint and its source) may break the pattern: there
``λ(k) = k - 1``, which is the dense factorization.

The pivot of coordinate ``k``, ``d_k = L_kk²``, is what of ``M_kk`` (its diagonal before the
factorization) the coordinates after it cannot take: ``M_kk`` less the Schur complement of
``M[k+1:, k+1:]``, with ``0 <= d_k <= M_kk``. In exact arithmetic ``d_k = 0`` for a joint whose
motion the rest of its subtree can make without it (a joint that moves no mass and has no
armature, two joints repeating each other's motion through massless links, a floating base's
massless root link); rounding then leaves ``d_k / M_kk`` of 1e-16 to 1e-13, either sign. A pivot
``d_k <= PIVOT_TOL M_kk`` leaves ``info`` at ``k`` (``M`` is singular to within
:data:`PIVOT_TOL` of the joint's own inertia); otherwise ``-1``. ``d_k / M_kk >= 1 / cond(M)``,
so an ``M`` whose condition number is below ``1 / PIVOT_TOL`` is never refused.

:func:`forward_kernel` is written on scalars under the rules of :mod:`.crba` (``m`` provides
``sqrt``), so the Python backend runs it on floats and the compiled one is generated from it.
"""

from __future__ import annotations

#: The least pivot ``d_k`` of ``M``'s factorization, relative to the joint's inertia ``M_kk``
#: (both with the armature), that forward dynamics takes: below it the joint's motion is made
#: by the rest of its subtree to within ``PIVOT_TOL`` of its inertia, and ``q̈`` is refused.
#: Measured (``python -m benchmarks.pivots``): the real robots of example-robot-data at random
#: states have ``d_k / M_kk`` of 2e-6 and more (iCub), down to 1e-9 only within 1e-4 rad of a
#: gimbal lock of three revolute joints through massless links (a ball joint, human and iCub:
#: singular at the lock); rounding leaves an exactly singular ``M`` at 1e-13 and less.
PIVOT_TOL = 1e-12


def forward_kernel(rows, H, qdd, lam, run, seg, Hkk, info, m) -> None:
    """Solve ``H q̈ = τ - h`` in place: ``H`` (nv * nv, row-major) becomes ``L``.

    ``qdd`` holds ``τ - h`` on entry and ``q̈`` on return. ``rows`` are the layout's per-body
    rows (row 0 holds ``nv``); ``lam`` and ``run`` scratch of ``nv`` scalars each: ``λ(k)``,
    and the first coordinate of the chain of consecutive coordinates that ends at ``k``
    (``λ(j) = j - 1`` from it to ``k``; a chain never crosses into the root block), so that
    the walks up the tree run over whole chains, as contiguous loops; ``seg`` scratch of
    ``2 nv``: the first and last coordinate of each chain of one coordinate's ancestors;
    ``Hkk`` scratch of ``nv``: ``H``'s diagonal as it came. ``info[0]`` -1 when solved, else
    the coordinate whose pivot ``d_k`` is at most ``PIVOT_TOL H_kk`` (``qdd`` is then not the
    solution).
    """
    NB = len(rows) - 1
    (_, _, _, n, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _,
     _, _, _, _, _, _, _, _, _, _, _, _) = rows[0]
    # λ(k): the parent of each velocity coordinate, -2 until a body claims it
    dense = 0
    for k in range(n):
        lam[k] = -2.0
    for i in range(1, NB + 1):
        (p, _, _, kv, dof, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _,
         _, _, _, _, _, _, _, _, _, _, _, _) = rows[i]
        if lam[kv] != -2.0:
            dense = 1       # a mimic joint: its source's coordinate
        pk = -1
        if p != 0:
            (_, _, _, kp, dp, _, _, _, _, _, _, _, _, _, _, _, _, _, _, _,
             _, _, _, _, _, _, _, _, _, _, _, _) = rows[p]
            pk = kp + dp - 1
        if pk >= kv:
            dense = 1
        lam[kv] = pk
        for c in range(1, dof):
            lam[kv + c] = kv + c - 1
    if dense == 1:
        for k in range(n):
            lam[k] = k - 1
    # r: the root block, coordinates 0..r-1 that are ancestors of every other one (a
    # free-flyer's six; all of a chain, n): a chain starting at s hangs from λ(s)
    r = n
    for k in range(1, n):
        lk = int(lam[k])
        if lk != k - 1 and lk + 1 < r:
            r = lk + 1
    for k in range(n):
        run[k] = k
        if k > 0 and k != r and int(lam[k]) == k - 1:
            run[k] = run[k - 1]
    for k in range(n):
        Hkk[k] = H[k * n + k]
    # M = Lᵀ L (RBDA table 6.3)
    for k in range(n - 1, -1, -1):
        d = H[k * n + k]
        if d <= PIVOT_TOL * Hkk[k]:     # (a NaN state goes through: NaN in, NaN out)
            info[0] = k
            return
        Lkk = m.sqrt(d)
        H[k * n + k] = Lkk
        inv = 1.0 / Lkk         # (a product each, not a division)
        ns = 0
        top = int(lam[k])
        while top != -1:        # M_ki /= L_kk  (i = λ(k), λ(λ(k)), …), chain by chain
            low = int(run[top])
            seg[2 * ns] = low
            seg[2 * ns + 1] = top
            ns += 1
            for i in range(low, top + 1):
                H[k * n + i] = H[k * n + i] * inv
            top = int(lam[low])
        stop = 0
        if k >= r:
            stop = r        # the root block's own updates wait: M_rr -= Wᵀ W below
        for t in range(ns):     # M_ij -= M_ki M_kj  (i = λ(k), …;  j = i, λ(i), …)
            low = int(seg[2 * t])
            top = int(seg[2 * t + 1])
            if low >= stop:
                for i in range(low, top + 1):
                    Lki = H[k * n + i]
                    for j in range(low, i + 1):
                        H[i * n + j] = H[i * n + j] - Lki * H[k * n + j]
                    for u in range(t + 1, ns):
                        for j in range(int(seg[2 * u]), int(seg[2 * u + 1]) + 1):
                            H[i * n + j] = H[i * n + j] - Lki * H[k * n + j]
        if k == r and r == 6:   # a free-flyer's root block, its lower triangle in registers:
            # M_ij -= M_ci M_cj (i, j < 6) for c = n-1..6, the same subtractions as below
            (M00,
             M10, M11,
             M20, M21, M22,
             M30, M31, M32, M33,
             M40, M41, M42, M43, M44,
             M50, M51, M52, M53, M54, M55) = (
                H[0],
                H[n], H[n + 1],
                H[2 * n], H[2 * n + 1], H[2 * n + 2],
                H[3 * n], H[3 * n + 1], H[3 * n + 2], H[3 * n + 3],
                H[4 * n], H[4 * n + 1], H[4 * n + 2], H[4 * n + 3], H[4 * n + 4],
                H[5 * n], H[5 * n + 1], H[5 * n + 2], H[5 * n + 3], H[5 * n + 4], H[5 * n + 5])
            for c in range(n - 1, 5, -1):
                L0, L1, L2, L3, L4, L5 = (H[c * n], H[c * n + 1], H[c * n + 2], H[c * n + 3],
                                          H[c * n + 4], H[c * n + 5])
                (M00,
                 M10, M11,
                 M20, M21, M22,
                 M30, M31, M32, M33,
                 M40, M41, M42, M43, M44,
                 M50, M51, M52, M53, M54, M55) = (
                    M00 - L0 * L0,
                    M10 - L1 * L0, M11 - L1 * L1,
                    M20 - L2 * L0, M21 - L2 * L1, M22 - L2 * L2,
                    M30 - L3 * L0, M31 - L3 * L1, M32 - L3 * L2, M33 - L3 * L3,
                    M40 - L4 * L0, M41 - L4 * L1, M42 - L4 * L2, M43 - L4 * L3, M44 - L4 * L4,
                    M50 - L5 * L0, M51 - L5 * L1, M52 - L5 * L2, M53 - L5 * L3, M54 - L5 * L4,
                    M55 - L5 * L5)
            H[0] = M00
            H[n] = M10
            H[n + 1] = M11
            H[2 * n] = M20
            H[2 * n + 1] = M21
            H[2 * n + 2] = M22
            H[3 * n] = M30
            H[3 * n + 1] = M31
            H[3 * n + 2] = M32
            H[3 * n + 3] = M33
            H[4 * n] = M40
            H[4 * n + 1] = M41
            H[4 * n + 2] = M42
            H[4 * n + 3] = M43
            H[4 * n + 4] = M44
            H[5 * n] = M50
            H[5 * n + 1] = M51
            H[5 * n + 2] = M52
            H[5 * n + 3] = M53
            H[5 * n + 4] = M54
            H[5 * n + 5] = M55
        elif k == r:    # every row below the root block is done: M_ij -= M_ci M_cj (i, j < r)
            for c in range(n - 1, r - 1, -1):
                for i in range(r):
                    Lci = H[c * n + i]
                    for j in range(i + 1):
                        H[i * n + j] = H[i * n + j] - Lci * H[c * n + j]
    # Lᵀ y = τ - h (RBDA table 6.4): y_k = b_k / L_kk;  b_i -= L_ki y_k  (i = λ(k), …)
    for k in range(n - 1, -1, -1):
        yk = qdd[k] / H[k * n + k]
        qdd[k] = yk
        top = int(lam[k])
        while top != -1:
            low = int(run[top])
            for i in range(low, top + 1):
                qdd[i] = qdd[i] - H[k * n + i] * yk
            top = int(lam[low])
    # L q̈ = y:  q̈_k = (y_k - Σ L_kj q̈_j) / L_kk  (j = λ(k), …)
    for k in range(n):
        s = qdd[k]
        top = int(lam[k])
        while top != -1:
            low = int(run[top])
            for j in range(low, top + 1):
                s = s - H[k * n + j] * qdd[j]
            top = int(lam[low])
        qdd[k] = s / H[k * n + k]
    info[0] = -1.0
