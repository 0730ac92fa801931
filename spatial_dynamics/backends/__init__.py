# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""How an algorithm runs: :func:`rnea` checks its arguments and picks a backend explicitly.

``rnea(..., backend=...)`` takes one of :data:`BACKENDS`:

* ``'numpy'``: the one source of :mod:`spatial_dynamics.algorithms.rnea` on Python floats
  (one state) or numpy arrays (a batch, any float dtype) — :mod:`.python`;
* ``'compiled'``: the numba kernels generated from the same source, for float64 inputs
  (other dtypes run on numpy) — :mod:`.jit`; :class:`CompiledBackendUnavailable` when
  numba cannot be imported;
* ``'auto'``: compiled when numba is importable, else numpy.

numba is imported on first use, not by ``import spatial_dynamics``, and the attempt is made
once per process. Compiled code is cached on disk by numba; when the package directory is
read-only (an installed tree) and ``NUMBA_CACHE_DIR`` is unset, the cache goes to
``$XDG_CACHE_HOME/spatial_dynamics/numba`` (default ``~/.cache/...``), set in numba's own
configuration (the process environment is never written).
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from types import ModuleType
from typing import Mapping, Optional, Sequence

import numpy as np

from . import layout, python
from .layout import LAYOUTS
from ..algorithms.arguments import as_joint_arrays, as_vector, f_ext_in_bodies
from ..model import Model

BACKENDS = ('auto', 'numpy', 'compiled')
#: Default gravity (m/s², root-link coordinates).
GRAVITY = (0.0, 0.0, -9.81)

_compiled: Optional[ModuleType] = None   # .jit once imported
_crba: Optional[ModuleType] = None       # .jit_crba once imported (by mass_matrix)
_failure: Optional[str] = None           # why numba could not be imported
_tried = False                           # numba import attempted
_F8 = np.dtype(np.float64)
_ndarray = np.ndarray
_NO_GRAVITY = (None, None, None)
_layout_of, _empty = LAYOUTS.get, np.empty      # bound once: the fast path is ~1 µs


class CompiledBackendUnavailable(ImportError):
    """``backend='compiled'`` was asked for, but numba cannot be imported."""


def rnea(model: Model, q, qd, qdd, gravity: Sequence[float] = GRAVITY,
         f_ext: Optional[Mapping[str, np.ndarray]] = None, backend: str = 'auto') -> np.ndarray:
    """Joint torques/forces ``τ = M(q) q̈ + C(q, q̇) q̇ + g(q) - Σ Jᵀ f_ext`` (RBDA table 5.1).

    Args:
        model: the robot.
        q, qd, qdd: joint positions (rad, m), velocities and accelerations in the order of
            ``model.joint_names``; shape (n,) or (..., n), broadcast against each other;
            arrays, lists or tuples of any real type.
        gravity: gravitational acceleration (m/s²) in root-link coordinates, 3 numbers.
        f_ext: link name → spatial force ``[n; f]`` (N m, N), angular first, acting on that
            link and expressed in that link's frame; shape (6,) or broadcastable to (..., 6).
        backend: ``'auto'`` (compiled when numba is importable), ``'numpy'`` or
            ``'compiled'`` (float64 inputs; other dtypes run on numpy).

    Returns:
        τ (N m or N), same shape as the broadcast inputs; float64, or the inputs' floating
        dtype.
    """
    kernels = _compiled if backend == 'auto' and _tried else compiled(backend)
    if not f_ext:
        # The fast path: one float64 state (arrays; lists and tuples are converted once).
        lay = _layout_of(id(model)) or layout.of(model)
        if not (type(q) is type(qd) is type(qdd) is _ndarray):
            q, qd, qdd = _vector(q, lay.n), _vector(qd, lay.n), _vector(qdd, lay.n)
        if (q.dtype is qd.dtype is qdd.dtype is _F8) and q.ndim == qd.ndim == qdd.ndim == 1:
            gx, gy, gz = GRAVITY if gravity is GRAVITY else _gravity(gravity)
            if gx is not None:
                if kernels is not None:
                    tau = _empty(lay.n)
                    if (kernels.single(lay.table, q, qd, qdd, gx, gy, gz, tau)
                            or kernels.single_large(lay.table, q, qd, qdd, gx, gy, gz, tau)):
                        return tau
                elif len(q) == len(qd) == len(qdd) == lay.n:
                    return np.array(python.rnea_rows(lay.rows, q.tolist(), qd.tolist(),
                                                     qdd.tolist(), (gx, gy, gz)))
    return _rnea(model, q, qd, qdd, gravity, f_ext, kernels)


def gravity_torque(model: Model, q, gravity: Sequence[float] = GRAVITY,
                   backend: str = 'auto') -> np.ndarray:
    """Generalized gravity ``g(q)``: the torque that holds the robot still at ``q``.

    ``rnea(model, q, 0, 0, gravity)``; the kernels then skip every velocity and acceleration
    product (see :func:`~spatial_dynamics.algorithms.rnea.rnea_kernel`). ``q`` of shape (n,)
    or (..., n); returns τ of the same shape. Arguments as for :func:`rnea`.
    """
    lay = _layout_of(id(model)) or layout.of(model)
    if type(q) is _ndarray and q.dtype is _F8 and q.shape == lay.zeros.shape:
        return rnea(model, q, lay.zeros, lay.zeros, gravity, backend=backend)
    q = _vector(q, lay.n)
    zero = np.zeros(np.shape(q), dtype=q.dtype if q.dtype.kind == 'f' else np.float64)
    return rnea(model, q, zero, zero, gravity, backend=backend)


def bias_torque(model: Model, q, qd, gravity: Sequence[float] = GRAVITY,
                backend: str = 'auto') -> np.ndarray:
    """Bias forces ``C(q, q̇) q̇ + g(q)`` (Pinocchio's ``nonLinearEffects``): RNEA at q̈ = 0.

    ``q``, ``qd`` of shape (n,) or (..., n), broadcast; returns τ of the broadcast shape.
    Arguments as for :func:`rnea`.
    """
    lay = _layout_of(id(model)) or layout.of(model)
    if (type(q) is type(qd) is _ndarray and q.dtype is qd.dtype is _F8
            and q.shape == qd.shape == lay.zeros.shape):
        return rnea(model, q, qd, lay.zeros, gravity, backend=backend)
    q, qd = _vector(q, lay.n), _vector(qd, lay.n)
    dtype = np.result_type(q, qd)
    zero = np.zeros(np.broadcast_shapes(np.shape(q), np.shape(qd)),
                    dtype=dtype if dtype.kind == 'f' else np.float64)
    return rnea(model, q, qd, zero, gravity, backend=backend)


def mass_matrix(model: Model, q, backend: str = 'auto') -> np.ndarray:
    """Joint-space inertia ``M(q)`` by the composite rigid body algorithm (RBDA table 6.2).

    ``M`` is symmetric positive definite (for a model whose every joint moves some mass);
    ``τ = M(q) q̈ + bias_torque(q, q̇)``. ``q`` of shape (n,) or (..., n), arrays, lists or
    tuples; returns an array of shape (..., n, n), float64 or ``q``'s floating dtype.
    """
    kernels = _compiled if backend == 'auto' and _tried else compiled(backend)
    if kernels is not None:
        global _crba
        if _crba is None:
            from . import jit_crba       # compiled on first use (the node never needs it)
            _crba = jit_crba
        kernels = _crba
    lay = _layout_of(id(model)) or layout.of(model)
    q = _vector(q, lay.n)
    n = lay.n
    if kernels is not None and type(q) is _ndarray and q.dtype is _F8 and q.shape == (n,):
        H = _empty(n * n)
        if kernels.single(lay.table, q, H) or kernels.single_large(lay.table, q, H):
            return H.reshape(n, n)
    (q,) = as_joint_arrays(model, q)
    if kernels is not None and q.dtype == np.float64:
        return kernels.mass_matrix(lay, q)
    return python.mass_matrix(lay.rows, q)


def generalized_momentum(model: Model, q, qd, backend: str = 'auto') -> tuple:
    """``(p, Cᵀ q̇)``: the generalized momentum ``p = M(q) q̇`` and ``Cᵀ(q, q̇) q̇``, in O(n).

    What a momentum observer of external torques integrates (``ṗ = τ + Cᵀ q̇ - g + τ_ext``);
    ``Cᵀ q̇ = ∂T/∂q`` for the kinetic energy ``T = ½ q̇ᵀ M q̇``, and ``Ṁ q̇ = C q̇ + Cᵀ q̇``
    (see :mod:`spatial_dynamics.algorithms.momentum`). ``q``, ``qd`` of shape (n,) or
    (..., n), broadcast; returns two arrays of the broadcast shape.
    """
    kernels = _compiled if backend == 'auto' and _tried else compiled(backend)
    lay = _layout_of(id(model)) or layout.of(model)
    q, qd = as_joint_arrays(model, q, qd)
    if kernels is not None and q.dtype == np.float64:
        batch, n = q.shape[:-1], lay.n
        if q.ndim == 1:
            mom, ctq = np.empty(n), np.empty(n)
            kernels.momentum_single(lay.table, q, qd, mom, ctq)
            return mom, ctq
        N = int(np.prod(batch, dtype=np.intp))
        mom, ctq = np.empty((N, n)), np.empty((N, n))
        kernels.momentum_batch(lay.table, *(np.ascontiguousarray(x.reshape(N, n))
                                            for x in (q, qd)), mom, ctq)
        return mom.reshape(q.shape), ctq.reshape(q.shape)
    return python.momentum(lay.rows, q, qd)


def _vector(x, n: int):
    """Return a list or tuple of ``n`` numbers as a float64 array, anything else as an array."""
    if type(x) is _ndarray:
        return x
    if (type(x) is list or type(x) is tuple) and len(x) == n:
        try:
            return np.array(x, dtype=_F8)
        except (TypeError, ValueError):
            pass        # not numbers: the general path names the argument
    return np.asarray(x)


def _gravity(gravity):
    """``gravity`` as three Python floats, or three Nones (the general path validates it)."""
    if (type(gravity) is tuple or type(gravity) is list) and len(gravity) == 3:
        gx, gy, gz = gravity
        if type(gx) is float and type(gy) is float and type(gz) is float:
            return gravity
        try:
            return float(gx), float(gy), float(gz)
        except (TypeError, ValueError):
            return _NO_GRAVITY
    if type(gravity) is _ndarray and gravity.shape == (3,) and gravity.dtype.kind in 'fiu':
        return (gravity if gravity.dtype is _F8 else gravity.astype(_F8)).tolist()
    return _NO_GRAVITY


def _rnea(model: Model, q, qd, qdd, gravity, f_ext, kernels) -> np.ndarray:
    """Run :func:`rnea` for all its fast path leaves: validation, wrenches, batches."""
    q, qd, qdd = as_joint_arrays(model, q, qd, qdd)
    g = tuple(as_vector('gravity', gravity, 3).tolist())
    fb = f_ext_in_bodies(model, f_ext)
    if fb:  # batched wrenches broadcast against the batch of states
        batch = np.broadcast_shapes(q.shape[:-1], *(np.shape(f)[:-1] for f in fb.values()))
        q, qd, qdd = (np.broadcast_to(x, batch + q.shape[-1:]) for x in (q, qd, qdd))
    lay = layout.of(model)
    if kernels is not None and q.dtype == np.float64:
        if not fb and q.size == q.shape[-1] > 0:
            # One state with batch dimensions of 1: a single-state entry, not the batch's.
            tau = np.empty(lay.n)
            kernels.rnea_single_large(lay.table, *(np.array(x.reshape(lay.n))
                                                   for x in (q, qd, qdd)), *g, tau)
            return tau.reshape(q.shape)
        return kernels.rnea(lay, q, qd, qdd, g, fb)
    return python.rnea(lay.rows, q, qd, qdd, g, fb)


# --------------------------------------------------------------------------------------------
# The compiled backend: loaded on first use

def compiled(backend: str = 'auto') -> Optional[ModuleType]:
    """Return the compiled backend (:mod:`.jit`) if ``backend`` selects it, else ``None``.

    Raises ``ValueError`` for an unknown backend and :class:`CompiledBackendUnavailable` for
    ``'compiled'`` without numba.
    """
    if backend == 'numpy':
        return None
    if backend not in BACKENDS:
        raise ValueError(f'backend must be one of {BACKENDS}, got {backend!r}')
    if not _tried:
        _load()
    if _compiled is None and backend == 'compiled':
        raise CompiledBackendUnavailable(
            f"backend='compiled' needs numba, which cannot be imported ({_failure}); "
            "install it with `pip install numba` (or the extra: "
            "`pip install spatial_dynamics[fast]`), or use backend='auto' or 'numpy'")
    return _compiled


def describe(backend: str = 'auto') -> str:
    """Name the backend that ``backend`` selects, for logs: e.g. ``'compiled (numba 0.61)'``."""
    if compiled(backend) is None:
        return 'numpy' if backend == 'numpy' else f'numpy (numba unavailable: {_failure})'
    import numba
    return f'compiled (numba {numba.__version__}, {numba.get_num_threads()} threads)'


def warmup(model: Model, backend: str = 'auto') -> str:
    """Load (or compile) the compiled kernels and run each entry once on ``model``.

    Call it before the first time-critical ``rnea`` call: afterwards no call pays for
    importing numba, compiling, loading the cache or starting the worker threads. Returns
    :func:`describe` of the backend.
    """
    kernels = compiled(backend)
    if kernels is not None:
        kernels.warmup(layout.of(model))
    return describe(backend)


#: What the child of :func:`prepare_compiled` runs: the import that compiles (or loads) the
#: kernels of the package in ``sys.argv[1]`` (first on the path, before the working
#: directory), at a lower CPU priority (nice +10: the caller's own work comes first); it
#: prints the file it compiled. On Linux it asks for SIGTERM when its parent goes (prctl
#: PR_SET_PDEATHSIG), so a node stopped while the kernels compile leaves no compiler running.
_PREPARE = '\n'.join([
    'import ctypes, os, signal, sys',
    'sys.path.insert(0, sys.argv[1])',
    'try:',
    '    os.nice(10)',
    '    ctypes.CDLL(None).prctl(1, signal.SIGTERM)',
    'except (OSError, AttributeError):',
    '    pass',
    'from spatial_dynamics import backends',
    'backends.compiled("compiled")',
    'print(backends.jit.__file__)'])


def prepare_compiled(timeout: Optional[float] = None) -> None:
    """Fill numba's on-disk cache with the compiled kernels, in a child process.

    Importing :mod:`.jit` compiles every kernel (about 13 s) unless numba's cache holds them
    (then it loads them, < 1 s). This runs that import in a child Python (this interpreter,
    this environment, this very package first on its path, whatever the working directory),
    so the cache it fills is the one this process reads (``NUMBA_CACHE_DIR`` or
    :func:`cache_dir_fallback`, entries keyed by the kernels' source file), and returns when
    the child is done: a :func:`warmup` here afterwards only loads. Nothing of this process
    changes, and the compilation never holds its interpreter. Returns at once when the
    kernels are loaded here already. Raises :class:`CompiledBackendUnavailable` when numba is
    not installed, the child fails (with the child's last error line) or compiled another
    file than this process would load, and ``subprocess.TimeoutExpired`` after ``timeout`` s.
    """
    if _compiled is not None:
        return
    if importlib.util.find_spec('numba') is None:
        raise CompiledBackendUnavailable('numba is not installed (pip install numba)')
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.dirname(os.path.dirname(here))
    proc = subprocess.run([sys.executable, '-c', _PREPARE, root], stdin=subprocess.DEVNULL,
                          capture_output=True, text=True, timeout=timeout)
    if proc.returncode != 0:
        lines = proc.stderr.strip().splitlines()
        raise CompiledBackendUnavailable(
            f'compiling the kernels failed (exit status {proc.returncode}): '
            + (lines[-1] if lines else 'no error output'))
    compiled_file = (proc.stdout.strip().splitlines() or [''])[-1]
    expected = os.path.join(here, 'jit.py')
    if not (compiled_file and os.path.samefile(compiled_file, expected)):
        raise CompiledBackendUnavailable(
            f'the compiling process compiled {compiled_file!r}, not {expected!r}')


def cache_dir_fallback() -> Optional[str]:
    """Return the numba cache directory to use, or ``None`` to keep numba's choice.

    ``None`` when ``NUMBA_CACHE_DIR`` is set or numba can write next to this package
    (``__pycache__``); else ``$XDG_CACHE_HOME/spatial_dynamics/numba`` (``~/.cache/...``).
    """
    if os.environ.get('NUMBA_CACHE_DIR'):
        return None
    here = os.path.dirname(os.path.abspath(__file__))
    pycache = os.path.join(here, '__pycache__')
    if os.access(pycache if os.path.isdir(pycache) else here, os.W_OK):
        return None
    base = os.environ.get('XDG_CACHE_HOME') or os.path.join(os.path.expanduser('~'), '.cache')
    return os.path.join(base, 'spatial_dynamics', 'numba')


def _load() -> None:
    """Import numba (once) and then :mod:`.jit`; remember why numba failed, if it did."""
    global _compiled, _failure, _tried
    _tried = True
    try:
        import numba
    except Exception as err:  # ImportError, or numba refusing this numpy version
        _failure = f'{type(err).__name__}: {err}'
        return
    fallback = cache_dir_fallback()
    if fallback is not None:
        numba.config.CACHE_DIR = fallback     # read when the kernels' caches are opened
    from . import jit   # an error in the kernels themselves is a bug: let it raise
    _compiled = jit
