# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""What a user passes to an algorithm, checked: joint arrays, vectors, external wrenches."""

from __future__ import annotations

from typing import Mapping

import numpy as np

from ..joints import check_quaternion, is_unit
from ..model import Model, refuse_masked
from ..text import listed, shown


def check_model(model) -> None:
    """``TypeError`` naming the argument ``model`` when it is no :class:`Model`."""
    if not isinstance(model, Model):
        raise TypeError(f'model must be a spatial_dynamics.Model, got {type(model).__name__}')


def as_real_array(what: str, x) -> np.ndarray:
    """``x`` (an array, a list or tuple, a buffer) as a numpy array of real numbers.

    Booleans and integers are kept as they are (the caller promotes them). ``TypeError``
    names ``what`` when ``x`` is no array of real numbers: strings, complex numbers, objects,
    ``None``, ragged lists, a buffer numpy cannot read (suboffsets, an unknown format);
    ``ValueError`` when it is a masked array with masked entries (numpy would drop the mask
    and read what lies under it).
    """
    refuse_masked(what, x)
    try:
        a = np.asarray(x)
    except (TypeError, ValueError, BufferError) as err:
        raise TypeError(f'{what} must be an array of real numbers, got '
                        f'{type(x).__name__}: {err}') from None
    if a.dtype.kind not in 'biuf':
        raise TypeError(f'{what} must be an array of real numbers, got {type(x).__name__} '
                        f'of dtype {a.dtype}')
    return a


def batch_of(*named) -> tuple:
    """Return the broadcast of batch shapes ``(label, batch)``; ``ValueError`` saying the labels.

    A label names the argument and its shape (``'qd of shape (2, 6)'``): numpy's own message
    names positions (``arg 0 with shape (3,)``), not the user's arguments.
    """
    try:
        return np.broadcast_shapes(*(batch for _, batch in named))
    except ValueError:
        raise ValueError('the batch dimensions (all but the last) do not broadcast: '
                         + ', '.join(label for label, _ in named)) from None


def as_joint_arrays(model: Model, *arrays, names: tuple = ('q', 'qd', 'qdd')) -> list:
    """``q, qd, qdd`` as arrays of one float dtype, shapes (..., nq), (..., nv), (..., nv).

    The leading (batch) dimensions broadcast. ``TypeError`` names the argument (``names``, in
    order) that is no array of real numbers, ``ValueError`` the one whose last dimension is
    not ``model.nq`` (``q``) or ``model.nv`` (``qd``, ``qdd``).
    """
    check_model(model)
    if all(type(a) is np.ndarray and a.ndim == 1 and a.dtype == np.float64 for a in arrays):
        # one float64 state (the common call): only the lengths to check, nothing to convert
        sizes = [model.nq if what == 'q' else model.nv for what in names[:len(arrays)]]
        if all(len(a) == n for a, n in zip(arrays, sizes)):
            if model.free_flyers and names[0] == 'q':
                check_configuration(model, arrays[0])
            return list(arrays)
    out = []
    for what, x in zip(names, arrays):
        a = as_real_array(what, x)
        n = model.nq if what == 'q' else model.nv
        if a.ndim == 0 or a.shape[-1] != n:
            names = model.joint_names
            raise ValueError(f'{what} must have shape (..., {n}) for the joints '
                             f'({listed(names, count=len(names))}), got shape {a.shape}')
        out.append(a)
    dtype = np.result_type(*out, np.float64) if not all(
        np.issubdtype(a.dtype, np.floating) for a in out) else np.result_type(*out)
    batch = batch_of(*((f'{what} of shape {a.shape}', a.shape[:-1])
                       for what, a in zip(names, out)))
    if model.free_flyers and names[0] == 'q':
        check_configuration(model, out[0])
    return [np.broadcast_to(a.astype(dtype, copy=False), batch + a.shape[-1:]) for a in out]


def check_configuration(model: Model, q: np.ndarray) -> None:
    """Refuse a ``q`` (..., nq) whose free-flyer quaternion is no orientation.

    :func:`~spatial_dynamics.joints.check_quaternion` on each free-flyer's ``q[k + 3:k + 7]``:
    ``ValueError`` naming the joint, its rows and, in a batch, the first bad state.
    """
    for name, k in model.free_flyers:
        if q.ndim == 1 and is_unit(*q[k + 3:k + 7].tolist()):
            continue        # one state: four Python floats
        check_quaternion(f'q: the free-flyer quaternion of joint {shown(name)} '
                         f'at q[{k + 3}:{k + 7}]', q[..., k + 3:k + 7])


def as_vector(what: str, x, size: int) -> np.ndarray:
    """``x`` as a float array of shape (size,); ``ValueError`` naming ``what`` otherwise.

    ``TypeError`` (:func:`as_real_array`) when ``x`` is no array of real numbers.
    """
    a = as_real_array(what, x)
    if a.shape != (size,):
        raise ValueError(f'{what} must be a {size}-vector, got shape {a.shape}')
    return a.astype(float)


def f_ext_in_bodies(model: Model, f_ext) -> dict:
    """Map link-frame wrenches to body-frame wrenches: ``f_b = lXbᵀ f_l`` (RBDA eq. 2.25).

    ``f_ext`` maps a link name to ``[n; f]`` (N m, N) in that link's frame, shape (6,) or
    (..., 6); wrenches on links of one body add up; those on the fixed base are dropped.
    """
    if f_ext is not None and not isinstance(f_ext, Mapping):
        raise TypeError('f_ext must map link names to wrenches [n; f], got '
                        f'{type(f_ext).__name__}')
    fb = {}
    for link, f in (f_ext or {}).items():
        frame = model.frames.get(link)
        if frame is None:
            raise ValueError(f'f_ext: unknown link {shown(link)}')
        f = as_real_array(f'f_ext[{shown(link)}]', f).astype(float)
        if f.shape[-1:] != (6,):
            raise ValueError(f'f_ext[{shown(link)}] must have shape (..., 6), got {f.shape}')
        if frame.body == 0:
            continue  # acts on the fixed base: no joint feels it
        fb[frame.body] = fb.get(frame.body, 0.0) + _transposed_times(frame.lXb, f)
    return fb


def with_wrenches(f_ext, arrays: list, names: tuple) -> list:
    """Return ``arrays`` (checked joint arrays) broadcast against ``f_ext``'s batched wrenches.

    ``ValueError`` naming the arguments when their batch dimensions do not broadcast.
    """
    batch = batch_of(*((f'{what} of shape {a.shape}', a.shape[:-1])
                       for what, a in zip(names, arrays)),
                     *((f'f_ext[{shown(link)}] of shape {np.shape(f)}', np.shape(f)[:-1])
                       for link, f in f_ext.items()))
    return [np.broadcast_to(a, batch + a.shape[-1:]) for a in arrays]


def _transposed_times(X: np.ndarray, f: np.ndarray) -> np.ndarray:
    """``Xᵀ f`` for ``f`` of shape (..., 6): ``Σ_k f_k X[k]``, the six terms added in order.

    One element-wise product and sum per term, so a batch's row rounds as the same state
    alone (a matrix product would sum in an order that depends on the batch's shape). An
    infinite ``f`` gives NaN (``inf · 0``) without a warning, as the kernels take it.
    """
    with np.errstate(invalid='ignore', over='ignore'):
        out = f[..., 0:1] * X[0]
        for k in range(1, 6):
            out = out + f[..., k:k + 1] * X[k]
    return out
