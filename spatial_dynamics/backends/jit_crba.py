# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Compiled M(q): numba entries around the CRBA kernel generated from ``algorithms/crba.py``.

A module of its own, imported on the first compiled :func:`~spatial_dynamics.mass_matrix`
call: the node never needs M(q), and compiling these entries with :mod:`.jit` doubled the
node's cold preparation of the compiled kernels (16 → 33 s on the UR5). The scratch, the
entry points and the checks follow :mod:`.jit`; a batch runs on one thread.
"""

from __future__ import annotations

import numba
from numba import types
import numpy as np

from . import layout
from ._kernels_generated import crba_kernel, WORK, xup_kernel
from .jit import _entry, _in1, _in2, _JIT, _out1, _out2, _stack_doubles, _without_nrt, \
    QIDX, STACK_ROWS

_CRBA_SINGLE = types.boolean(_in2, _in1, _out1)
_CRBA_BATCH = types.void(_in2, _in2, _out2)


@_without_nrt(_CRBA_SINGLE)
def crba_single(K, q, H):
    """One state: q (n,) → M(q) into H (n * n, row-major); False if the sizes do not fit.

    Scratch on the stack as in :func:`.jit.rnea_single` (False for more than
    ``STACK_ROWS - 1`` bodies: :func:`crba_single_large` takes it).
    """
    n = int(K[0, QIDX])
    rows = K.shape[0]
    if q.shape[0] != n or H.shape[0] != n * n or rows > STACK_ROWS:
        return False
    work = _stack_doubles(rows * WORK)
    xup_kernel(K, q, work)
    crba_kernel(K, work, H)
    return True


@numba.njit(_CRBA_SINGLE, **_JIT)
def crba_single_large(K, q, H):
    """As :func:`crba_single`, for models of any size (the scratch is allocated)."""
    n = int(K[0, QIDX])
    if q.shape[0] != n or H.shape[0] != n * n:
        return False
    work = np.empty(K.shape[0] * WORK)
    xup_kernel(K, q, work)
    crba_kernel(K, work, H)
    return True


@numba.njit(_CRBA_BATCH, nogil=True, **_JIT)
def crba_batch(K, q, H):
    """N states: q (N, n) → H (N, n * n)."""
    work = np.empty(K.shape[0] * WORK)
    for s in range(q.shape[0]):
        xup_kernel(K, q[s], work)
        crba_kernel(K, work, H[s])


#: The single-state entries for arguments checked by the caller (see :func:`.jit._entry`).
single = _entry(crba_single)
single_large = _entry(crba_single_large)


def mass_matrix(lay: layout.Layout, q: np.ndarray) -> np.ndarray:
    """M(q) of shape (..., n, n) from a validated float64 array ``q`` of shape (..., n)."""
    n = lay.n
    batch = q.shape[:-1]
    N = int(np.prod(batch, dtype=np.intp))
    H = np.empty((N, n * n))
    crba_batch(lay.table, np.ascontiguousarray(q.reshape(N, n), dtype=np.float64), H)
    return H.reshape(batch + (n, n))
