# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""What a user passes to an algorithm, checked: joint arrays, vectors, external wrenches."""

from __future__ import annotations

import numpy as np

from ..model import Model


def as_joint_arrays(model: Model, *arrays) -> list:
    """``q, qd, qdd`` as arrays of one float dtype, shapes (..., nq), (..., nv), (..., nv).

    The leading (batch) dimensions broadcast. ``ValueError`` names the argument whose last
    dimension is not ``model.nq`` (``q``) or ``model.nv`` (``qd``, ``qdd``).
    """
    out = []
    for what, x in zip(('q', 'qd', 'qdd'), arrays):
        a = np.asarray(x)
        n = model.nq if what == 'q' else model.nv
        if a.ndim == 0 or a.shape[-1] != n:
            raise ValueError(f'{what} must have shape (..., {n}) for the joints '
                             f'{model.joint_names}, got shape {a.shape}')
        out.append(a)
    dtype = np.result_type(*out, np.float64) if not all(
        np.issubdtype(a.dtype, np.floating) for a in out) else np.result_type(*out)
    batch = np.broadcast_shapes(*(a.shape[:-1] for a in out))
    return [np.broadcast_to(a.astype(dtype, copy=False), batch + a.shape[-1:]) for a in out]


def as_vector(what: str, x, size: int) -> np.ndarray:
    """``x`` as a float array of shape (size,); ``ValueError`` naming ``what`` otherwise."""
    a = np.asarray(x, dtype=float)
    if a.shape != (size,):
        raise ValueError(f'{what} must be a {size}-vector, got shape {a.shape}')
    return a


def f_ext_in_bodies(model: Model, f_ext) -> dict:
    """Map link-frame wrenches to body-frame wrenches: ``f_b = lXbᵀ f_l`` (RBDA eq. 2.25).

    ``f_ext`` maps a link name to ``[n; f]`` (N m, N) in that link's frame, shape (6,) or
    (..., 6); wrenches on links of one body add up; those on the fixed base are dropped.
    """
    fb = {}
    for link, f in (f_ext or {}).items():
        frame = model.frames.get(link)
        if frame is None:
            raise ValueError(f'f_ext: unknown link {link!r}')
        f = np.asarray(f, dtype=float)
        if f.shape[-1:] != (6,):
            raise ValueError(f'f_ext[{link!r}] must have shape (..., 6), got {f.shape}')
        if frame.body == 0:
            continue  # acts on the fixed base: no joint feels it
        fb[frame.body] = fb.get(frame.body, 0.0) + f @ frame.lXb
    return fb
