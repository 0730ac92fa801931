# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The contact-consistent split of ``M q̈ + h = Sᵀ τ + J_cᵀ λ`` (Mistry et al. 2010): one source.

With ``J_cᵀ = Q [R; 0]`` (Householder QR, ``Q = [Q1 Q2]``), ``Q2ᵀ`` removes the contact
forces, and the least (``W``-weighted) torques solve ``Q2ᵀ Sᵀ τ = Q2ᵀ b`` (``b = M q̈ + h``,
``Sᵀ = [0; 1]``); then ``R λ = Q1ᵀ (b - Sᵀ τ)``::

    A = Q2ᵀ Sᵀ W^-½,  y = Q2ᵀ b:   τ = W^-½ Aᵀ (A Aᵀ)⁻¹ y,   λ = R⁻¹ (Q1ᵀ b - Q1ᵀ Sᵀ τ)

the equations of :func:`spatial_dynamics.contacts.contact_inverse_dynamics`'s numpy split,
written on scalars (the compiled backend is generated from it; ``m`` provides ``sqrt``).
"""

from __future__ import annotations


def split_kernel(QR, k, n, nb, wts, res, scr, m) -> None:
    """Split into ``res``: ``τ`` (n), ``λ`` (k), then 0 (solved) or 1 (the numpy split's case).

    ``QR`` is ``[J_cᵀ, b, Sᵀ]`` column-major (``nv = nb + n`` rows, ``k + 1 + n`` columns),
    overwritten by the factor; ``wts`` the square roots of the weights (n); ``scr`` scratch
    of ``(nv - k) (nv - k + 1)`` scalars. 1 when the numpy split answers instead: ``J_c`` of
    rank below ``k`` (the same test on ``R``'s diagonal), ``A Aᵀ`` not positive definite, or
    ``A τ`` off ``y`` by more than its 1e-9 check (base rows the contacts cannot carry).
    """
    nv = nb + n
    cols = k + 1 + n
    res[n + k] = 1.0
    # J_cᵀ = Q [R; 0]: reflector j, H = 1 - 2 v vᵀ / vᵀv, v = x - α e_j, applied to the right
    for j in range(k):
        s = 0.0
        for i in range(j, nv):
            s = s + QR[i + j * nv] * QR[i + j * nv]
        x0 = QR[j + j * nv]
        alpha = -m.sqrt(s) if x0 >= 0.0 else m.sqrt(s)
        v0 = x0 - alpha
        vv = s - x0 * x0 + v0 * v0
        QR[j + j * nv] = alpha
        if vv > 0.0:
            for c in range(j + 1, cols):
                t = v0 * QR[j + c * nv]
                for i in range(j + 1, nv):
                    t = t + QR[i + j * nv] * QR[i + c * nv]
                t = 2.0 * t / vv
                QR[j + c * nv] = QR[j + c * nv] - t * v0
                for i in range(j + 1, nv):
                    QR[i + c * nv] = QR[i + c * nv] - t * QR[i + j * nv]
    # rank k: every |R_jj| above 1e-10 max(1, max |R_jj|)
    dmax = 1.0
    for j in range(k):
        d = QR[j + j * nv]
        if d < 0.0:
            d = -d
        if d > dmax:
            dmax = d
    for j in range(k):
        d = QR[j + j * nv]
        if d < 0.0:
            d = -d
        if not d > 1e-10 * dmax:
            return
    # G = A Aᵀ (p × p, p = nv - k, A[i, c] = QR[k + i, k + 1 + c] / wts[c]), its Cholesky L
    p = nv - k
    for i in range(p):
        for j in range(i + 1):
            t = 0.0
            for c in range(n):
                ai = QR[k + i + (k + 1 + c) * nv] / wts[c]
                aj = QR[k + j + (k + 1 + c) * nv] / wts[c]
                t = t + ai * aj
            for a in range(j):
                t = t - scr[i * p + a] * scr[j * p + a]
            if i == j:
                if not t > 0.0:
                    return
                scr[i * p + i] = m.sqrt(t)
            else:
                scr[i * p + j] = t / scr[j * p + j]
    # L Lᵀ x = y (x in scr[p p …])
    for i in range(p):
        t = QR[k + i + k * nv]
        for a in range(i):
            t = t - scr[i * p + a] * scr[p * p + a]
        scr[p * p + i] = t / scr[i * p + i]
    for i in range(p - 1, -1, -1):
        t = scr[p * p + i]
        for a in range(i + 1, p):
            t = t - scr[a * p + i] * scr[p * p + a]
        scr[p * p + i] = t / scr[i * p + i]
    # τ w = Aᵀ x, τ
    for c in range(n):
        t = 0.0
        for i in range(p):
            t = t + (QR[k + i + (k + 1 + c) * nv] / wts[c]) * scr[p * p + i]
        res[c] = t / wts[c]
    # the check: A τ w = y, each row within 1e-9 max(1, max |y|) + 1e-9 |y_i|
    ymax = 1.0
    for i in range(p):
        y = QR[k + i + k * nv]
        if y < 0.0:
            y = -y
        if y > ymax:
            ymax = y
    for i in range(p):
        y = QR[k + i + k * nv]
        t = -y
        for c in range(n):
            t = t + QR[k + i + (k + 1 + c) * nv] * res[c]
        if t < 0.0:
            t = -t
        if y < 0.0:
            y = -y
        if not t <= 1e-9 * ymax + 1e-9 * y:
            return
    # R λ = Q1ᵀ b - Q1ᵀ Sᵀ τ, backwards
    for j in range(k - 1, -1, -1):
        t = QR[j + k * nv]
        for c in range(n):
            t = t - QR[j + (k + 1 + c) * nv] * res[c]
        for a in range(j + 1, k):
            t = t - QR[j + a * nv] * res[n + a]
        res[n + j] = t / QR[j + j * nv]
    res[n + k] = 0.0
