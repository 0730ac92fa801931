# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Which RNEA backend runs: numpy always; the compiled kernels when numba is importable.

``rnea(..., backend=...)`` takes one of :data:`BACKENDS`:

* ``'numpy'``: the component-wise RNEA in ``rnea.py`` (any float dtype);
* ``'compiled'``: the numba kernels of :mod:`kernels` for float64 inputs (other dtypes use
  numpy); :class:`CompiledBackendUnavailable` when numba cannot be imported;
* ``'auto'``: compiled when numba is importable, else numpy.

numba is imported on first use, not by ``import spatial_dynamics``, and the attempt is made
once per process. Compiled code is cached on disk by numba; when the package directory is
read-only (an installed tree) and ``NUMBA_CACHE_DIR`` is unset, the cache goes to
``$XDG_CACHE_HOME/spatial_dynamics/numba`` (default ``~/.cache/...``).
"""

from __future__ import annotations

import os
import sys
from types import ModuleType
from typing import Optional

BACKENDS = ('auto', 'numpy', 'compiled')

_kernels: Optional[ModuleType] = None   # spatial_dynamics.kernels once imported
_failure: Optional[str] = None          # why numba could not be imported


class CompiledBackendUnavailable(ImportError):
    """``backend='compiled'`` was asked for, but numba cannot be imported."""


def compiled(backend: str = 'auto') -> Optional[ModuleType]:
    """Return the :mod:`kernels` module if ``backend`` selects it, else ``None``.

    Raises ``ValueError`` for an unknown backend and :class:`CompiledBackendUnavailable` for
    ``'compiled'`` without numba.
    """
    if backend == 'numpy':
        return None
    if _kernels is not None and (backend == 'auto' or backend == 'compiled'):
        return _kernels
    if backend not in BACKENDS:
        raise ValueError(f'backend must be one of {BACKENDS}, got {backend!r}')
    if _failure is None:
        _load()
    if _kernels is None and backend == 'compiled':
        raise CompiledBackendUnavailable(
            f"backend='compiled' needs numba, which cannot be imported ({_failure}); "
            "install it with `pip install numba` (or the extra: "
            "`pip install spatial_dynamics[fast]`), or use backend='auto' or 'numpy'")
    return _kernels


def describe(backend: str = 'auto') -> str:
    """Name the backend that ``backend`` selects, for logs: e.g. ``'compiled (numba 0.61)'``."""
    if compiled(backend) is None:
        return 'numpy' if backend == 'numpy' else f'numpy (numba unavailable: {_failure})'
    import numba
    return f'compiled (numba {numba.__version__}, {numba.get_num_threads()} threads)'


def warmup(model, backend: str = 'auto') -> str:
    """Load (or compile) the compiled kernels and run each entry once on ``model``.

    Call it before the first time-critical ``rnea`` call (the node does, before it
    subscribes): afterwards no call pays for importing numba, compiling, loading the cache or
    starting the worker threads. Returns :func:`describe` of the backend.
    """
    kernels = compiled(backend)
    if kernels is not None:
        kernels.warmup(model)
    return describe(backend)


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
    """Import numba (once) and then :mod:`kernels`; remember why numba failed, if it did."""
    global _kernels, _failure
    fallback = cache_dir_fallback()
    if fallback is not None:
        os.environ['NUMBA_CACHE_DIR'] = fallback
    imported_before = 'numba' in sys.modules
    try:
        import numba
    except Exception as err:  # ImportError, or numba refusing this numpy version
        _failure = f'{type(err).__name__}: {err}'
        return
    if fallback is not None and imported_before:
        numba.core.config.reload_config()   # numba read the environment already: again
    from . import kernels   # an error in the kernels themselves is a bug: let it raise
    _kernels = kernels
