# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The contact forces inside their friction cones: a QP solved by Clarabel (``method='qp'``).

Minimise ``½ τᵀ W τ + ½ ε |λ|²`` subject to all the rows of ``M q̈ + h = Sᵀ τ + J_cᵀ λ`` and,
per contact, ``n·f ≥ 0`` (unilateral, whatever ``μ``) and ``|f_t| ≤ μ f_n`` (second-order
cones: exact cones, no pyramid), scaled so that every coefficient is at most 1 whatever the
numbers. The caller hands it clarabel and scipy.sparse (:mod:`.contacts` imports them on
first use, only ``'qp'`` needs them, and :func:`~.contacts.warm_qp` ahead of the path that
answers).
"""

from __future__ import annotations

import numpy as np

from .contact_kinematics import Plan


def _tangents(normal: np.ndarray) -> tuple:
    """Two unit vectors orthogonal to ``normal`` and to each other."""
    t1 = np.cross(normal, [1.0, 0.0, 0.0] if abs(normal[0]) < 0.9 else [0.0, 1.0, 0.0])
    t1 /= np.linalg.norm(t1)
    return t1, np.cross(normal, t1)


def qp(plan: Plan, b, Jc, n, W, force_weight, clarabel, sparse) -> tuple:
    """Solve the friction-cone QP with Clarabel: ``(τ, λ, status)``.

    ``clarabel`` and ``scipy.sparse`` the solver's modules, imported by the caller (the
    package imports them once, on first use: :func:`~spatial_dynamics.contacts.warm_qp`).

    ``status`` ``'solved'``, else why not (then ``τ`` and ``λ`` are NaN); see
    :func:`~spatial_dynamics.contacts.contact_inverse_dynamics`.
    """
    contacts = plan.contacts
    k = len(Jc)
    nx = n + k
    if not (np.isfinite(force_weight) and force_weight > 0.0):
        raise ValueError(f'force_weight must be a positive number, got {force_weight}')
    # the argmin is that of the weights over their largest: every weight in (0, 1]
    top = max(W.max(initial=0.0), force_weight)
    P = sparse.diags(np.r_[W / top, np.full(k, force_weight / top)]).tocsc()
    # equality (zero cone): [Sᵀ J_cᵀ] x = b, all nv rows
    A_eq = np.zeros((len(b), nx))
    A_eq[6:, :n] = np.eye(n)
    A_eq[:, n:] = Jc.T
    # unilateral (nonnegative cone): n·f ≥ 0 of each contact, whatever its μ
    N = np.zeros((len(contacts), nx))
    for j, (c, (row, rows)) in enumerate(zip(contacts, plan.slices)):
        N[j, n + row + rows - 3:n + row + rows] = c.normal
    blocks = [A_eq, -N]
    cones, row = [clarabel.ZeroConeT(len(b)), clarabel.NonnegativeConeT(len(contacts))], 0
    for c in contacts:
        t1, t2 = _tangents(c.normal)
        # s = (μ n·f, t1·f, t2·f) in the second-order cone; for μ > 1 the same cone as
        # (n·f, t1·f / μ, t2·f / μ): every coefficient at most 1, whatever μ
        G = np.zeros((3, nx))
        j = n + row + c.rows - 3    # the force's entries of λ
        a, t = (c.mu, 1.0) if c.mu <= 1.0 else (1.0, 1.0 / c.mu)
        G[0, j:j + 3], G[1, j:j + 3], G[2, j:j + 3] = a * c.normal, t * t1, t * t2
        blocks.append(-G)
        cones.append(clarabel.SecondOrderConeT(3))
        row += c.rows
    A = sparse.csc_matrix(np.vstack(blocks))
    rhs = np.r_[b, np.zeros(A.shape[0] - len(b))]
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    solution = clarabel.DefaultSolver(P, np.zeros(nx), A, rhs, cones, settings).solve()
    status = str(solution.status)
    x = np.array(solution.x)
    if 'Solved' not in status or 'Almost' in status:
        kind = ('infeasible: no contact forces inside the friction cones carry the base rows'
                if 'Infeasible' in status else f'not solved ({status})')
        nan = np.full(nx, np.nan)
        return nan[:n], nan[n:], kind
    return x[:n], x[n:], 'solved'
