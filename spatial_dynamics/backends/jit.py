# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Compiled backend: numba entries around the kernels generated from the one RNEA source.

The arithmetic is :mod:`spatial_dynamics.algorithms.rnea`'s, translated to flat arrays by
:mod:`.codegen` (``_kernels_generated.py``): same statements, same order, no fast-math or
fused multiply-adds, so it agrees with the Python backends to a few ulps (to the bit against
the single-state float path on the same libm). This module only moves data: scratch space,
the loop over a batch, threads.

Importing it imports numba and compiles the entries, or loads them from numba's on-disk cache
(``cache=True``): the signatures are explicit, so nothing is compiled after import, and an
argument of another type is refused instead of compiled in the hot path. The model enters as
the table of :mod:`.layout` (one array is one argument less to unbox per call).
"""

from __future__ import annotations

import threading

import numba
from numba import prange, types
from numba.extending import intrinsic
import numpy as np

from . import layout
from ._kernels_generated import momentum_kernel, rnea_kernel, WORK, xup_kernel

QIDX = layout.COLUMN['qidx']
#: Smallest batch handed to the parallel entry (below it the thread launch costs more).
PARALLEL_MIN = 64
#: Largest model (NB + 1 rows) whose single-state scratch goes on the stack (40 KiB).
STACK_ROWS = 128

# Signatures: inputs are read-only arrays of any layout (writable, strided arrays convert to
# them; the batch entry gets C arrays), then gravity.
_f8, _in1, _in2, _in3 = (types.float64, types.Array(types.float64, 1, 'A', readonly=True)) \
    + tuple(types.Array(types.float64, nd, 'C', readonly=True) for nd in (2, 3))
_out1, _out2 = (types.Array(types.float64, nd, 'C') for nd in (1, 2))
_SINGLE = types.boolean(_in2, _in1, _in1, _in1, _f8, _f8, _f8, _out1)
_BATCH = types.void(_in2, _in2, _in2, _in2, _f8, _f8, _f8, _in3, types.boolean, _out2)
_PARALLEL = types.void(_in2, _in2, _in2, _in2, _f8, _f8, _f8, _in3, types.boolean, _out2,
                       types.int64)
_MOMENTUM_SINGLE = types.boolean(_in2, _in1, _in1, _out1, _out1)
_MOMENTUM_BATCH = types.void(_in2, _in2, _in2, _out2, _out2)
_JIT = dict(cache=True, fastmath=False, error_model='numpy')
#: f_ext of the single-state entries: none (a compile-time constant, never read).
_NO_FEXT = np.zeros((1, 6))


@intrinsic
def _stack_doubles(typingctx, count):
    """Pointer to ``count`` float64 on the caller's stack frame (freed when it returns)."""
    def codegen(context, builder, signature, args):
        return builder.alloca(context.get_value_type(types.float64), size=args[0])
    return types.CPointer(types.float64)(types.intp), codegen


def _without_nrt(signature):
    """``numba.njit(signature)`` with numba's reference-counted runtime (NRT) off, if it can be.

    Without NRT, unboxing an array argument allocates no meminfo: five arrays cost ~0.1 µs
    less per call, a tenth of a single call. The function then cannot allocate arrays. The
    option is private (``_nrt``); a numba without it gets the function with NRT on.
    """
    def decorate(fn):
        try:
            return numba.njit(signature, _nrt=False, **_JIT)(fn)
        except Exception:   # pragma: no cover - depends on the numba version
            return numba.njit(signature, **_JIT)(fn)
    return decorate


@_without_nrt(_SINGLE)
def rnea_single(K, q, qd, qdd, gx, gy, gz, tau):
    """One state without f_ext: q, qd, qdd (n,) → tau (n,); False (nothing done) if not (n,).

    The scratch is on the stack, so a model of more than ``STACK_ROWS - 1`` bodies returns
    False too (:func:`rnea_single_large` takes it). Holds the GIL: a call is too short to
    gain from releasing it.
    """
    n = int(K[0, QIDX])
    rows = K.shape[0]
    if (tau.shape[0] != n or q.shape[0] != n or qd.shape[0] != n or qdd.shape[0] != n
            or rows > STACK_ROWS):
        return False
    work = _stack_doubles(rows * WORK)     # a raw pointer: no array (needs no NRT)
    xup_kernel(K, q, work)
    rnea_kernel(K, q, qd, qdd, gx, gy, gz, _NO_FEXT, False, tau, work)
    return True


@numba.njit(_SINGLE, **_JIT)
def rnea_single_large(K, q, qd, qdd, gx, gy, gz, tau):
    """As :func:`rnea_single`, for models of any size: the scratch is allocated (with NRT)."""
    n = int(K[0, QIDX])
    if tau.shape[0] != n or q.shape[0] != n or qd.shape[0] != n or qdd.shape[0] != n:
        return False
    work = np.empty(K.shape[0] * WORK)
    xup_kernel(K, q, work)
    rnea_kernel(K, q, qd, qdd, gx, gy, gz, _NO_FEXT, False, tau, work)
    return True


@numba.njit(_BATCH, nogil=True, **_JIT)
def _rnea_batch(K, q, qd, qdd, gx, gy, gz, fext, has_fext, tau):
    """N states, one thread: q, qd, qdd (N, n), fext (1 or N, NB+1, 6) → tau (N, n)."""
    work = np.empty(K.shape[0] * WORK)
    per_state = fext.shape[0] > 1
    for s in range(q.shape[0]):
        xup_kernel(K, q[s], work)
        rnea_kernel(K, q[s], qd[s], qdd[s], gx, gy, gz, fext[s if per_state else 0], has_fext,
                    tau[s], work)


@numba.njit(_PARALLEL, nogil=True, parallel=True, **_JIT)
def _rnea_batch_parallel(K, q, qd, qdd, gx, gy, gz, fext, has_fext, tau, chunks):
    """As :func:`_rnea_batch`, on ``chunks`` contiguous slices of the batch in numba's threads.

    Each slice is one call of the compiled :func:`_rnea_batch` (not re-lowered here).
    """
    N = q.shape[0]
    per_state = fext.shape[0] > 1
    for c in prange(chunks):
        lo, hi = c * N // chunks, (c + 1) * N // chunks
        _rnea_batch(K, q[lo:hi], qd[lo:hi], qdd[lo:hi], gx, gy, gz,
                    fext[lo:hi] if per_state else fext, has_fext, tau[lo:hi])


@numba.njit(_MOMENTUM_SINGLE, **_JIT)
def momentum_single(K, q, qd, mom, ctq):
    """One state: q, qd (n,) → M q̇ into ``mom``, Cᵀ q̇ into ``ctq``; False if not (n,)."""
    n = int(K[0, QIDX])
    if q.shape[0] != n or qd.shape[0] != n or mom.shape[0] != n or ctq.shape[0] != n:
        return False
    work = np.empty(K.shape[0] * WORK)
    xup_kernel(K, q, work)
    momentum_kernel(K, q, qd, mom, ctq, work)
    return True


@numba.njit(_MOMENTUM_BATCH, nogil=True, **_JIT)
def momentum_batch(K, q, qd, mom, ctq):
    """N states, one thread: q, qd (N, n) → mom, ctq (N, n)."""
    work = np.empty(K.shape[0] * WORK)
    for s in range(q.shape[0]):
        xup_kernel(K, q[s], work)
        momentum_kernel(K, q[s], qd[s], mom[s], ctq[s], work)


def _entry(dispatcher):
    """Return the compiled function of a one-signature ``dispatcher`` (no numba dispatch).

    numba's dispatcher works out each argument's numba type to pick an overload (~0.2 µs of a
    ~1 µs single call); with one signature and arguments :func:`rnea` has already checked to
    be exactly its types (float64 arrays of the right number of dimensions, Python floats),
    the compiled entry can be called directly. It still refuses an array of another dtype;
    the dimensions are the caller's to check. A numba without ``overloads`` gets the
    dispatcher.
    """
    try:
        (compiled_result,) = dispatcher.overloads.values()
        return compiled_result.entry_point
    except (AttributeError, ValueError):   # pragma: no cover - depends on the numba version
        return dispatcher


#: The single-state entries for arguments checked by the caller (see :func:`_entry`).
single = _entry(rnea_single)
single_large = _entry(rnea_single_large)


# The workqueue threading layer (used when neither TBB nor OpenMP is available) must not be
# entered by two threads at once; a lock is cheap next to a parallel batch.
_parallel_lock = threading.Lock()


def rnea(lay: layout.Layout, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, gravity: tuple,
         f_body: dict) -> np.ndarray:
    """τ from validated float64 arrays of one broadcast shape (..., n) (any strides).

    ``gravity`` (gx, gy, gz) floats, m/s² in root coordinates; ``f_body`` maps a body index to
    its external force ``[n; f]`` in body coordinates, shape (6,) or broadcastable to
    (..., 6). Returns τ of shape (..., n), float64.
    """
    K, n = lay.table, lay.n
    NB = K.shape[0] - 1
    batch = q.shape[:-1]
    N = int(np.prod(batch, dtype=np.intp))
    # f_ext per body as (M, NB+1, 6): M = 1 (one for all states, or none) or N.
    shared = all(np.ndim(f) <= 1 for f in f_body.values())
    fext = np.zeros(((1,) if shared else batch) + (NB + 1, 6))
    for b, f in f_body.items():
        fext[..., b, :] = f
    fext = fext.reshape(-1, NB + 1, 6)
    args = [np.ascontiguousarray(x.reshape(N, n), dtype=np.float64) for x in (q, qd, qdd)]
    tau = np.empty((N, n))
    threads = numba.get_num_threads()
    if N >= PARALLEL_MIN and threads > 1:
        with _parallel_lock:
            _rnea_batch_parallel(K, *args, *gravity, fext, bool(f_body), tau,
                                 min(N, 4 * threads))
    else:
        _rnea_batch(K, *args, *gravity, fext, bool(f_body), tau)
    return tau.reshape(batch + (n,))


def warmup(lay: layout.Layout) -> None:
    """Run every entry once on a zero state (loads the code, starts the threads)."""
    n = lay.n
    z1, z2 = np.zeros(n), np.zeros((PARALLEL_MIN, n))
    g = (0.0, 0.0, -9.81)
    rnea_single(lay.table, z1, z1, z1, *g, np.empty(n))
    rnea_single_large(lay.table, z1, z1, z1, *g, np.empty(n))
    rnea(lay, z1, z1, z1, g, {})
    rnea(lay, z2, z2, z2, g, {})
    momentum_single(lay.table, z1, z1, np.empty(n), np.empty(n))
