# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Compiled backend: the C extension ``_compiled`` built with the package, and its batches.

``setup.py`` compiles ``_compiled.c`` and its units; ``kernels.c`` includes
``_kernels_generated.h``, the kernels that :mod:`.codegen` prints from
:mod:`spatial_dynamics.algorithms` into the build directory: the same statements in the same
order, without fused multiply-adds, so the results agree with the Python backends to a few
ulps (to the bit on the same libm). Nothing is compiled at run time. A build without a C
compiler installs without the extension: then :data:`ext` is ``None``, :data:`FAILURE` says
why, importing warns once, and ``backend='auto'`` runs on numpy.

The single-state entries are called by :mod:`spatial_dynamics.backends` directly; this module
prepares the batches: one float64 C-contiguous copy of each input, the external forces as one
(1 or N, NB + 1, 6) table, and the number of threads; float32 states (:data:`DTYPES`) are
computed in float64 and their results rounded back to float32 once.
"""

from __future__ import annotations

from contextlib import contextmanager
import importlib
import math
import os
from typing import Iterator, Optional
import warnings

import numpy as np

#: The interface of ``_compiled.c`` this module speaks (its ``API``).
API = 19

try:
    ext = importlib.import_module(__package__ + '._compiled')
    FAILURE: Optional[str] = None
    if getattr(ext, 'API', None) != API:      # an old build beside newer sources
        ext, FAILURE = None, (f'{ext.__file__} is a stale build (API {getattr(ext, "API", 0)}'
                              f', not {API}): build the package again')
except ImportError as err:                 # built without a C compiler
    ext = None
    FAILURE = (f'no module {err.name}: the package was built without them'
               if isinstance(err, ModuleNotFoundError) else f'{type(err).__name__}: {err}')
    if 'numpy' in str(err) and not isinstance(err, ModuleNotFoundError):
        # built against numpy 1.x headers, imported on numpy 2.x
        FAILURE += (f'; they were built against another numpy than this {np.__version__}: '
                    'build the package again')
if ext is None:
    warnings.warn('spatial_dynamics was built without its compiled kernels; it runs on plain '
                  'Python (10-100x slower per call). Install a C compiler and the Python headers '
                  '(Debian/Ubuntu: build-essential python3-dev) and build it again. '
                  f'({FAILURE})', RuntimeWarning, stacklevel=2)

#: Threads a batch may use: the CPUs this process may run on (:func:`threads_at_most` lowers
#: it for a block). The package's other thread pools (the derivatives' filter, the inertia
#: fit's sums, the CSV writer) read it too, when they run.
THREADS = len(os.sched_getaffinity(0)) if hasattr(os, 'sched_getaffinity') else (
    os.cpu_count() or 1)


@contextmanager
def threads_at_most(n: int) -> Iterator[None]:
    """Run the block with at most ``n`` of this package's threads at a time, process-wide.

    For a process that is one of several sharing the cores (a fleet worker: one core each):
    threads of its own on top would oversubscribe them. BLAS's threads are limited apart
    (``threadpoolctl``). Not for a process whose other threads run batches meanwhile.
    """
    global THREADS
    before = THREADS
    THREADS = max(1, min(before, int(n)))
    try:
        yield
    finally:
        THREADS = before


def kernels(table: np.ndarray):
    """Return the extension's copy of a model's table (:mod:`.layout`), or ``None``."""
    return None if ext is None else ext.Kernels(table)


#: The dtypes the kernels take: float64, and float32 computed in float64 and rounded back.
DTYPES = (np.dtype(np.float64), np.dtype(np.float32))


def _batch(entry, lay, vectors: tuple, middle: tuple, shape: tuple, results: int = 1,
           into: Optional[tuple] = None) -> list:
    """Run the batch ``entry`` on validated arrays ``vectors`` of one batch shape (...).

    Each is made one C-contiguous float64 (N, nq) or (N, nv) copy (none when it is one already);
    ``middle`` are the entry's arguments between the vectors and the results (gravity,
    external forces). Returns ``results`` arrays of shape (...,) + ``shape`` in the vectors'
    dtype (float32 rounded once from the float64 results): new ones, or ``into`` (C-contiguous
    float64 arrays of that shape, written in place; float64 vectors only).
    """
    batch = vectors[0].shape[:-1]
    N = math.prod(batch)        # (np.prod takes ~2 µs: a batch of a few states feels it)
    rows = [np.ascontiguousarray(x.reshape(N, x.shape[-1]), dtype=np.float64) for x in vectors]
    outs = ([np.empty((N,) + shape) for _ in range(results)] if into is None else
            [x.reshape((N,) + shape) for x in into])    # (C-contiguous: views)
    entry(lay.kernels, N, *rows, *middle, *outs, THREADS)
    if into is not None:
        return list(into)
    dtype = vectors[0].dtype
    return [out.reshape(batch + shape).astype(dtype, copy=False) for out in outs]


def rnea(lay, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, gravity: tuple,
         f_body: dict) -> np.ndarray:
    """τ (..., nv) from validated q (..., nq), qd, qdd (..., nv) (any strides, :data:`DTYPES`).

    ``gravity`` (gx, gy, gz) floats, m/s² in root coordinates; ``f_body`` maps a body index to
    its external force ``[n; f]`` in body coordinates, shape (6,) or broadcastable to
    (..., 6). Returns τ of shape (..., n) in ``q``'s dtype.
    """
    return _batch(ext.rnea_batch, lay, (q, qd, qdd), (gravity, _fext(lay, q, f_body)),
                  (lay.nv,))[0]


def forward_dynamics(lay, q: np.ndarray, qd: np.ndarray, tau: np.ndarray, gravity: tuple,
                     f_body: dict) -> np.ndarray:
    """q̈ (..., nv) from validated q (..., nq), qd, tau (..., nv); arguments as :func:`rnea`.

    A state whose ``M`` has a pivot that is not positive comes back as NaN.
    """
    return _batch(ext.forward_dynamics_batch, lay, (q, qd, tau),
                  (gravity, _fext(lay, q, f_body)), (lay.nv,))[0]


def _fext(lay, q: np.ndarray, f_body: dict):
    """Return the batch entries' external forces: None, (1, rows, 6) shared or (..., rows, 6)."""
    if not f_body:
        return None
    shared = all(np.ndim(f) <= 1 for f in f_body.values())
    fext = np.zeros(((1,) if shared else q.shape[:-1]) + (lay.table.shape[0], 6))
    for b, f in f_body.items():
        fext[..., b, :] = f
    return fext


def f_body_table(lay, f_body: dict) -> np.ndarray:
    """One state's external forces ``{body: (6,)}`` as the (NB + 1, 6) table of the kernels."""
    fext = np.zeros((lay.table.shape[0], 6))
    for b, f in f_body.items():
        fext[b] = f
    return fext


def mass_matrix(lay, q: np.ndarray) -> np.ndarray:
    """M(q) of shape (..., nv, nv) from a validated array ``q`` of shape (..., nq)."""
    return _batch(ext.mass_matrix_batch, lay, (q,), (), (lay.nv, lay.nv))[0]


def momentum(lay, q: np.ndarray, qd: np.ndarray) -> tuple:
    """``(M q̇, Cᵀ q̇)``, each (..., nv), from validated q (..., nq) and qd (..., nv)."""
    return tuple(_batch(ext.momentum_batch, lay, (q, qd), (), (lay.nv,), results=2))


def regressor(lay, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, gravity: tuple) -> np.ndarray:
    """``Y`` of shape (..., nv, 10 NB) from validated q (..., nq), qd, qdd (..., nv)."""
    shape = (lay.nv, 10 * (lay.table.shape[0] - 1))
    return _batch(ext.regressor_batch, lay, (q, qd, qdd), (gravity,), shape)[0]


def derivatives(lay, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, gravity: tuple,
                f_body: dict, out: Optional[tuple] = None) -> tuple:
    """``(∂τ/∂q, ∂τ/∂q̇, M)``, each (..., nv, nv), from validated arrays (as :func:`rnea`).

    Three C-contiguous arrays; or ``out``, three checked arrays of the results' shape and
    dtype: written in place when they are C-contiguous float64 (and so are the results),
    else the results are copied into them.
    """
    nv = lay.nv
    direct = out is not None and q.dtype == np.float64 and all(
        x.dtype == np.float64 and x.flags.c_contiguous for x in out)
    results = _batch(ext.derivatives_batch, lay, (q, qd, qdd),
                     (gravity, _fext(lay, q, f_body)), (nv, nv), 3, out if direct else None)
    if out is not None and not direct:
        for x, r in zip(out, results):
            np.copyto(x, r)
        return tuple(out)
    return tuple(results)


def describe() -> str:
    """``'compiled (C extension, 2 threads)'``, or why there is no extension."""
    if ext is None:
        return f'numpy (compiled kernels not built: {FAILURE})'
    return f'compiled (C extension, {THREADS} threads)'
