# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Python backend: the one RNEA source run on Python floats, numpy arrays or mpmath numbers.

One float64 state runs on plain floats (no per-term numpy call overhead); a batch runs on
numpy arrays of shape (N,), one numpy operation per term for all N states (any float
dtype); ``mpmath.mpf`` scalars give the high-precision reference of the benchmark.

What cannot be computed comes out as the compiled kernels give it, without a word: NaN or an
infinity in, NaN (or an infinity) out, and a product beyond float's range infinite. Python's
``math.sin(inf)`` raises instead of returning NaN as C's does (:func:`transforms`), and numpy
warns where C is silent (:data:`QUIET`, around each batch).
"""

from __future__ import annotations

import math
from types import SimpleNamespace
from typing import Sequence

import numpy as np

from ..algorithms.aba import aba_kernel
from ..algorithms.crba import crba_kernel
from ..algorithms.derivatives import derivatives_kernel
from ..algorithms.forward import forward_kernel, PIVOT_TOL
from ..algorithms.momentum import momentum_kernel
from ..algorithms.regressor import regressor_kernel
from ..algorithms.rnea import rnea_kernel, xup_kernel

#: numpy's error state around a batch's kernels: NaN, infinities and overflow pass silently,
#: as on Python floats and in C.
QUIET = {'over': 'ignore', 'invalid': 'ignore', 'divide': 'ignore'}


def _sin(x: float) -> float:
    """``math.sin``, NaN at ±inf as C's ``sin`` (``math.sin`` raises ``ValueError``)."""
    return math.sin(x) if math.isfinite(x) else math.nan


def _cos(x: float) -> float:
    """``math.cos``, NaN at ±inf as C's ``cos`` (``math.cos`` raises ``ValueError``)."""
    return math.cos(x) if math.isfinite(x) else math.nan


#: ``math`` as C's libm answers ±inf (NaN), for a state :func:`transforms` found one in.
_LIBM = SimpleNamespace(sin=_sin, cos=_cos, sqrt=math.sqrt)


def transforms(rows, q, m, Xup) -> None:
    """:func:`~spatial_dynamics.algorithms.rnea.xup_kernel` into ``Xup``, ±inf in ``q`` as NaN.

    On Python floats (``m`` is ``math``) ``math.sin(±inf)`` raises ``ValueError``; that state
    runs again with a ``sin`` and ``cos`` that give NaN there, as C and numpy do, so a
    joint at ±inf gives the NaN it gives on the compiled backend (a NaN joint already does).
    """
    try:
        xup_kernel(rows, q, m, Xup)
    except ValueError:
        if m is not math:
            raise
        xup_kernel(rows, q, _LIBM, Xup)


def _body_forces(f_body, slots: int, zero):
    """Return the kernels' ``f_body`` table (a 6-tuple a body slot, ``zero`` elsewhere), or None.

    ``f_body`` maps a body index to its ``[n; f]``; None or empty: no table (``has_fext``
    false).
    """
    if not f_body:
        return None
    fb = [(zero,) * 6] * slots
    for b, f in f_body.items():
        fb[b] = f
    return fb


def rnea_rows(rows, q, qd, qdd, gravity, f_body=None, m=math) -> list:
    """τ as a list of ``nv`` scalars from the per-body ``rows`` of :mod:`.layout`.

    ``q`` (``nq``), ``qd`` and ``qdd`` (``nv``) are sequences of scalars of one kind (floats,
    (N,) arrays or ``mpmath.mpf``), ``gravity`` three of them; ``m`` provides their ``sin``
    and ``cos`` (``math``, ``numpy`` or ``mpmath``). ``f_body`` maps a body index to its
    external force ``[n; f]`` in body coordinates as 6 scalars.
    """
    gx, gy, gz = gravity
    slots = len(rows)
    Xup, vel, acc, frc = [None] * slots, [None] * slots, [None] * slots, [None] * slots
    transforms(rows, q, m, Xup)
    zero = 0.0 * gx
    tau = [zero] * rows[0][3]
    fb = _body_forces(f_body, slots, zero)
    rnea_kernel(rows, q, qd, qdd, gx, gy, gz, fb, fb is not None, tau, Xup, vel, acc, frc)
    return tau


def _columns(x: np.ndarray) -> list:
    """Split a batch (..., n) into ``n`` contiguous (N,) columns, the kernels' joint scalars.

    ``N`` is the product of the batch dimensions, so that n = 0 (a model without joints) has
    N states too (``reshape(-1, 0)`` could not tell).
    """
    N = math.prod(x.shape[:-1])
    return list(np.ascontiguousarray(x.reshape(N, x.shape[-1]).T))


def _stacked(values: Sequence, N: int, dtype, shape: tuple) -> np.ndarray:
    """Gather the kernels' outputs (each a scalar or an (N,) array) into one array."""
    out = np.empty((N, len(values)), dtype=dtype)
    for k, v in enumerate(values):
        out[:, k] = v
    return out.reshape(shape)


def rnea(rows, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, gravity: np.ndarray,
         f_body: dict) -> np.ndarray:
    """τ (..., nv) from validated arrays of one float dtype: q (..., nq), qd, qdd (..., nv)."""
    if q.dtype == np.float64 and q.size == q.shape[-1] > 0:
        # One state (maybe with batch dimensions of 1): plain floats beat the batch path's
        # fixed cost of one numpy call per term.
        fl = {b: np.reshape(f, -1)[-6:].tolist() for b, f in f_body.items()}
        tau = rnea_rows(rows, *(x.reshape(-1).tolist() for x in (q, qd, qdd)),
                        [float(x) for x in gravity], fl)
        return np.array(tau).reshape(qd.shape)
    batch = q.shape[:-1]
    N = int(np.prod(batch, dtype=np.intp))
    fl = {b: list(np.broadcast_to(f, batch + (6,)).reshape(N, 6).T.astype(q.dtype))
          for b, f in f_body.items()}
    with np.errstate(**QUIET):
        tau = rnea_rows(rows, *(_columns(x) for x in (q, qd, qdd)),
                        [q.dtype.type(x) for x in gravity], fl, np)
    return _stacked(tau, N, q.dtype, qd.shape)


def mass_matrix_rows(rows, q, m=math) -> list:
    """M(q) as a list of ``nv * nv`` scalars (row-major) from the per-body ``rows``.

    ``q`` is a sequence of ``nq`` scalars of one kind (floats or (N,) arrays); ``m`` provides
    their ``sin`` and ``cos``.
    """
    slots = len(rows)
    Xup, IC = [None] * slots, [None] * slots
    transforms(rows, q, m, Xup)
    H = [0.0] * (rows[0][3] ** 2)
    crba_kernel(rows, Xup, IC, H)
    return H


def mass_matrix(rows, q: np.ndarray) -> np.ndarray:
    """M(q) of shape (..., nv, nv) from a validated float array ``q`` of shape (..., nq)."""
    n = rows[0][3]
    if q.dtype == np.float64 and q.size == q.shape[-1]:
        return np.array(mass_matrix_rows(rows, q.reshape(-1).tolist())).reshape(
            q.shape[:-1] + (n, n))
    batch = q.shape[:-1]
    with np.errstate(**QUIET):
        H = mass_matrix_rows(rows, _columns(q), np)
    return _stacked(H, int(np.prod(batch, dtype=np.intp)), q.dtype, batch + (n, n))


def momentum_rows(rows, q, qd, m=math) -> tuple:
    """``(M(q) q̇, Cᵀ(q, q̇) q̇)`` as two lists of ``nv`` scalars from the per-body ``rows``."""
    slots = len(rows)
    Xup, vel, frc = [None] * slots, [None] * slots, [None] * slots
    transforms(rows, q, m, Xup)
    n = rows[0][3]
    mom, ctq = [0.0] * n, [0.0] * n
    momentum_kernel(rows, q, qd, mom, ctq, Xup, vel, frc)
    return mom, ctq


def momentum(rows, q: np.ndarray, qd: np.ndarray) -> tuple:
    """``(M q̇, Cᵀ q̇)``, each of shape (..., nv), from validated q (..., nq), qd (..., nv)."""
    if q.dtype == np.float64 and q.size == q.shape[-1]:
        mom, ctq = momentum_rows(rows, q.reshape(-1).tolist(), qd.reshape(-1).tolist())
        return np.array(mom).reshape(qd.shape), np.array(ctq).reshape(qd.shape)
    N = int(np.prod(q.shape[:-1], dtype=np.intp))
    with np.errstate(**QUIET):
        parts = momentum_rows(rows, _columns(q), _columns(qd), np)
    return tuple(_stacked(part, N, q.dtype, qd.shape) for part in parts)


def regressor_rows(rows, q, qd, qdd, gravity, m=math) -> list:
    """Return the regressor ``Y`` as a list of ``nv * 10 NB`` scalars (row-major) from ``rows``.

    Arguments as for :func:`rnea_rows` (no external forces: they do not depend on π).
    """
    gx, gy, gz = gravity
    slots = len(rows)
    Xup, vel, acc = [None] * slots, [None] * slots, [None] * slots
    transforms(rows, q, m, Xup)
    Y = [None] * (rows[0][3] * 10 * (slots - 1))
    regressor_kernel(rows, qd, qdd, gx, gy, gz, Y, [None] * (6 * slots * (slots + 5)), Xup, vel,
                     acc)
    return Y


def regressor(rows, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
              gravity: Sequence[float]) -> np.ndarray:
    """``Y`` (..., nv, 10 NB) from validated arrays of one float dtype (q (..., nq), qd, qdd)."""
    shape = q.shape[:-1] + (rows[0][3], 10 * (len(rows) - 1))
    if q.dtype == np.float64 and q.size == q.shape[-1] > 0:
        Y = regressor_rows(rows, *(x.reshape(-1).tolist() for x in (q, qd, qdd)),
                           [float(x) for x in gravity])
        return np.array(Y).reshape(shape)
    N = int(np.prod(q.shape[:-1], dtype=np.intp))
    with np.errstate(**QUIET):
        Y = regressor_rows(rows, *(_columns(x) for x in (q, qd, qdd)),
                           [q.dtype.type(x) for x in gravity], np)
    return _stacked(Y, N, q.dtype, shape)


def forward_solve(rows, H: np.ndarray, b: np.ndarray) -> tuple:
    """Solve ``H q̈ = b`` per state: ``(q̈, None)``, or ``(None, (state, k))`` if a pivot fails.

    ``H`` (..., nv, nv) and ``b`` (..., nv) broadcast; ``(state, k)`` is the first state (flat
    index) whose ``H`` has a pivot ``d_k <= PIVOT_TOL H_kk``
    (:data:`~spatial_dynamics.algorithms.forward.PIVOT_TOL`).

    :func:`~spatial_dynamics.algorithms.forward.forward_kernel` on the floats of each state (a
    float64 state on Python floats, other dtypes on numpy scalars); a batch of float32 or
    float64 states on numpy's Cholesky (LAPACK) of ``H`` with its coordinates reversed (the
    kernel's pivots), which gives the same ``q̈`` to rounding.
    """
    with np.errstate(**QUIET):
        return _solve(rows, H, b)


def _solve(rows, H: np.ndarray, b: np.ndarray) -> tuple:
    """Run :func:`forward_solve`: its answer, from its arguments as they came."""
    n = b.shape[-1]
    batch = np.broadcast_shapes(H.shape[:-2], b.shape[:-1])
    N = math.prod(batch)
    H = np.broadcast_to(H, batch + (n, n)).reshape(N, n, n)
    b = np.broadcast_to(b, batch + (n,)).reshape(N, n)
    if N > 1 and b.dtype in (np.float32, np.float64):
        # H = Lᵀ L from the last coordinate back, as the kernel: the Cholesky factor of H with
        # its rows and columns reversed, whose pivots are the kernel's d_k
        R = H[:, ::-1, ::-1]
        try:
            L = np.linalg.cholesky(R)
        except np.linalg.LinAlgError:
            L = None    # the loop below finds the state and the coordinate
        if L is not None and not np.any(np.diagonal(L, axis1=1, axis2=2) ** 2
                                        <= PIVOT_TOL * np.diagonal(R, axis1=1, axis2=2)):
            y = np.linalg.solve(L, b[:, ::-1, None])
            x = np.linalg.solve(np.swapaxes(L, -1, -2), y)[:, ::-1, 0]
            return x.reshape(batch + (n,)), None
    out = np.empty((N, n), dtype=b.dtype)
    m = math if b.dtype == np.float64 else np
    for s in range(N):
        Hs, x = ((H[s].ravel().tolist(), b[s].tolist()) if m is math
                 else (list(H[s].ravel()), list(b[s])))
        info = [0]
        forward_kernel(rows, Hs, x, [0] * n, [0] * n, [0] * (2 * n), [0] * n, info, m)
        if info[0] >= 0:
            return None, (s, int(info[0]))
        out[s] = x
    return out.reshape(batch + (n,)), None


def aba_rows(rows, q, qd, tau, gravity, f_body=None, arm=None, m=math) -> tuple:
    """``(q̈, info)``: the articulated-body algorithm on scalars, ``q̈`` a list of ``nv``.

    Arguments as for :func:`rnea_rows`, ``tau`` in place of ``qdd``; ``arm`` ``nv`` armatures
    or None. ``info`` -1 when solved, else what
    :func:`~spatial_dynamics.algorithms.aba.aba_kernel` leaves (-2: two bodies share a
    coordinate; ``k``: the pivot of coordinate ``k`` is at most ``PIVOT_TOL M_kk``), ``q̈``
    then unfinished.
    """
    gx, gy, gz = gravity
    slots = len(rows)
    Xup = [None] * slots
    transforms(rows, q, m, Xup)
    zero = 0.0 * gx
    qdd = [zero] * rows[0][3]
    fb = _body_forces(f_body, slots, zero)
    info = [-1]
    aba_kernel(rows, qd, tau, gx, gy, gz, fb, fb is not None, arm, arm is not None, qdd,
               [zero] * 42, info, Xup, *([None] * slots for _ in range(7)))
    return qdd, int(info[0])


def derivatives_rows(rows, q, qd, qdd, gravity, f_body=None, m=math) -> tuple:
    """``(∂τ/∂q, ∂τ/∂q̇, M)`` as three lists of ``nv * nv`` scalars (row-major) from ``rows``.

    Arguments as for :func:`rnea_rows`; see :mod:`spatial_dynamics.algorithms.derivatives`.
    """
    gx, gy, gz = gravity
    slots = len(rows)
    Xup = [None] * slots
    transforms(rows, q, m, Xup)
    zero = 0.0 * gx
    n = rows[0][3]
    dq, dv, H = [zero] * (n * n), [zero] * (n * n), [zero] * (n * n)
    fb = _body_forces(f_body, slots, zero)
    derivatives_kernel(rows, qd, qdd, gx, gy, gz, fb, fb is not None, dq, dv, H, Xup,
                       *([None] * slots for _ in range(7)), [None] * (6 * slots),
                       [None] * (6 * slots))
    return dq, dv, H


def derivatives(rows, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, gravity: Sequence[float],
                f_body: dict) -> tuple:
    """``(∂τ/∂q, ∂τ/∂q̇, M)``, each (..., nv, nv), from validated arrays of one float dtype."""
    n = rows[0][3]
    shape = qd.shape + (n,)
    if q.dtype == np.float64 and q.size == q.shape[-1] > 0:
        fl = {b: np.reshape(f, -1)[-6:].tolist() for b, f in f_body.items()}
        out = derivatives_rows(rows, *(x.reshape(-1).tolist() for x in (q, qd, qdd)),
                               [float(x) for x in gravity], fl)
        return tuple(np.array(x).reshape(shape) for x in out)
    batch = q.shape[:-1]
    N = int(np.prod(batch, dtype=np.intp))
    fl = {b: list(np.broadcast_to(f, batch + (6,)).reshape(N, 6).T.astype(q.dtype))
          for b, f in f_body.items()}
    with np.errstate(**QUIET):
        out = derivatives_rows(rows, *(_columns(x) for x in (q, qd, qdd)),
                               [q.dtype.type(x) for x in gravity], fl, np)
    return tuple(_stacked(x, N, q.dtype, shape) for x in out)
