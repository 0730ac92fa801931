# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Recursive Newton-Euler inverse dynamics (RBDA table 5.1, ``ID.m`` of spatial_v2).

Forward pass, for i = 1..NB (body 0 is the fixed base, ``v_0 = 0``, ``a_0 = -a_grav``)::

    XJ, S_i = jcalc(jtype_i, q_i);  Xup_i = XJ Xtree_i;  vJ = S_i q̇_i
    v_i = Xup_i v_λ(i) + vJ
    a_i = Xup_i a_λ(i) + S_i q̈_i + v_i × vJ
    f_i = I_i a_i + v_i ×* I_i v_i - f_ext_i

Backward pass, for i = NB..1::

    τ_i = S_iᵀ f_i;   f_λ(i) += Xup_iᵀ f_i

Two implementations of the same equations:

* :func:`rnea_spatial` writes them literally with 6×6 matrices (``crm``, ``crf``, ``jcalc``)
  and einsum over leading batch dimensions: the readable reference.
* :func:`rnea_components` writes them on 3-vector components, with ``Xup = (E, r)`` kept as a
  rotation and a translation (RBDA §2.12), so no 6×6 product is ever formed. Its scalars can be
  Python floats (one state: no numpy call overhead), numpy arrays of shape (N,) (a batch, one
  numpy operation per term for all N states) or ``mpmath.mpf`` (a high-precision reference).
  :func:`rnea` dispatches to it.
"""

from __future__ import annotations

import math
import weakref
from typing import Mapping, Optional, Sequence

import numpy as np

from . import backends
from .joints import jcalc
from .model import PR, RX, RY, RZ, Model
from .spatial import crf, crm

GRAVITY = (0.0, 0.0, -9.81)

#: Per model, the last single-call ``q`` and its transforms (values only; never stale: a hit
#: needs the identical ``q``).
_LAST_XUP: 'weakref.WeakKeyDictionary[Model, tuple]' = weakref.WeakKeyDictionary()


def rnea(model: Model, q, qd, qdd, gravity: Sequence[float] = GRAVITY,
         f_ext: Optional[Mapping[str, np.ndarray]] = None, backend: str = 'auto') -> np.ndarray:
    """Joint torques/forces ``τ = M(q) q̈ + C(q, q̇) q̇ + g(q) - Σ Jᵀ f_ext``.

    Args:
        model: the robot.
        q, qd, qdd: joint positions (rad, m), velocities and accelerations in the order of
            ``model.joint_names``; shape (n,) or (..., n), broadcast against each other.
        gravity: gravitational acceleration (m/s²) in root-link coordinates.
        f_ext: link name → spatial force ``[n; f]`` (N m, N), angular first, acting on that
            link and expressed in that link's frame; shape (6,) or broadcastable to (..., 6).
        backend: ``'auto'`` (compiled when numba is importable), ``'numpy'`` or
            ``'compiled'`` (float64 inputs; other dtypes run on numpy); see ``backends``.

    Returns:
        τ (N m or N), same shape and floating dtype as the broadcast inputs.
    """
    kernels = backends._kernels      # loaded already: skip the call in the common case
    if kernels is None or backend != 'auto' and backend != 'compiled':
        kernels = backends.compiled(backend)
    if kernels is not None and not f_ext:
        # One C-contiguous float64 state of shape (n,) goes straight into the kernel; other
        # dtypes, layouts or argument types match no overload (TypeError), other lengths
        # return False: the general path then validates and runs them. Lists (no ndim) and
        # batches never try: numba takes ~70 µs to explain a type mismatch.
        try:
            if q.ndim == 1:
                tau = np.empty(len(q))
                gx, gy, gz = gravity
                K = model._table
                if (kernels.rnea_single(K, q, qd, qdd, gx, gy, gz, tau)
                        or kernels.rnea_single_large(K, q, qd, qdd, gx, gy, gz, tau)):
                    return tau
        except (AttributeError, TypeError, ValueError):
            pass
    return _rnea(model, q, qd, qdd, gravity, f_ext, kernels)


def _rnea(model: Model, q, qd, qdd, gravity, f_ext, kernels) -> np.ndarray:
    """Run :func:`rnea` for all that its fast path leaves.

    Kept apart from it: the comprehensions here would turn ``rnea``'s arguments into cell
    variables, which costs ~0.1 µs per call.
    """
    single = _single_state(model, q, qd, qdd) if kernels is None else None
    if single is not None and not f_ext:
        # One float64 state: plain Python floats, no per-term numpy call overhead.
        g = [float(x) for x in gravity]
        if len(g) != 3:
            raise ValueError(f'gravity must be a 3-vector, got {gravity!r}')
        q_list = single[0]
        last = _LAST_XUP.get(model)
        if last is not None and last[0] == q_list:
            Xup = last[1]          # q unchanged since the last call: reuse the transforms
        else:
            Xup = xup_components(model, q_list)
            _LAST_XUP[model] = (q_list, Xup)
        return np.array(rnea_components(model, *single, g, Xup=Xup))
    q, qd, qdd = _as_joint_arrays(model, q, qd, qdd)
    g = _as_vector('gravity', gravity, 3)
    fb = _f_ext_in_bodies(model, f_ext)
    if fb:  # batched wrenches broadcast against the batch of states
        batch = np.broadcast_shapes(q.shape[:-1], *(np.shape(f)[:-1] for f in fb.values()))
        q, qd, qdd = (np.broadcast_to(x, batch + q.shape[-1:]) for x in (q, qd, qdd))
    if kernels is not None and q.dtype == np.float64:
        if not fb and q.size == q.shape[-1] > 0:
            # One state with batch dimensions of 1: a single-state entry, not the batch's.
            n = model.nq
            tau = np.empty(n)
            kernels.rnea_single_large(model._table,
                                      *(np.array(x.reshape(n)) for x in (q, qd, qdd)),
                                      *(float(x) for x in g), tau)
            return tau.reshape(q.shape)
        return kernels.rnea(model, q, qd, qdd, g, fb)
    if q.dtype == np.float64 and q.size == q.shape[-1] > 0:
        # One state (maybe with batch dimensions of 1): plain floats beat the batch path's
        # fixed cost of one numpy call per term.
        fl = {b: np.reshape(f, -1)[-6:].tolist() for b, f in fb.items()}
        tau = rnea_components(model, *(x.reshape(-1).tolist() for x in (q, qd, qdd)),
                              [float(x) for x in g], fl)
        return np.array(tau).reshape(q.shape)
    batch = q.shape[:-1]
    N = int(np.prod(batch, dtype=np.intp))
    cols = [np.ascontiguousarray(x.reshape(N, model.nq).T) for x in (q, qd, qdd)]
    fl = {b: list(np.broadcast_to(f, batch + (6,)).reshape(N, 6).T.astype(q.dtype))
          for b, f in fb.items()}
    tau = rnea_components(model, *cols, [q.dtype.type(x) for x in g], fl, np)
    out = np.empty((N, model.nq), dtype=q.dtype)
    for k, t in enumerate(tau):
        out[:, k] = t
    return out.reshape(q.shape)


def _single_state(model: Model, *arrays) -> Optional[list]:
    """``[q, qd, qdd]`` as lists of floats when all three are float64 arrays of shape (n,)."""
    n = model.nq
    for x in arrays:
        if type(x) is not np.ndarray or x.shape != (n,) or x.dtype != np.float64:
            return None
    return [x.tolist() for x in arrays]


def _as_joint_arrays(model: Model, *arrays) -> list:
    n = model.nq
    out = []
    for what, x in zip(('q', 'qd', 'qdd'), arrays):
        a = np.asarray(x)
        if a.ndim == 0 or a.shape[-1] != n:
            raise ValueError(f'{what} must have shape (..., {n}) for the joints '
                             f'{model.joint_names}, got shape {a.shape}')
        out.append(a)
    dtype = np.result_type(*out, np.float64) if not all(
        np.issubdtype(a.dtype, np.floating) for a in out) else np.result_type(*out)
    shape = np.broadcast_shapes(*(a.shape for a in out))
    return [np.broadcast_to(a.astype(dtype, copy=False), shape) for a in out]


def _as_vector(what: str, x, size: int) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.shape != (size,):
        raise ValueError(f'{what} must be a {size}-vector, got shape {a.shape}')
    return a


def _f_ext_in_bodies(model: Model, f_ext) -> dict:
    """Map link-frame wrenches to body-frame wrenches: ``f_b = lXbᵀ f_l`` (RBDA eq. 2.25)."""
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


def rnea_components(model: Model, q, qd, qdd, gravity, f_body=None, m=math,
                    Xup: Optional[list] = None) -> list:
    """RNEA on scalar components; returns ``τ`` as a list of ``model.nq`` scalars.

    ``q, qd, qdd`` are sequences (indexed like ``joint_names``) of scalars of one kind:
    floats, (N,) arrays, or mpmath numbers; ``m`` provides ``sin`` and ``cos`` for them
    (``math``, ``numpy`` or ``mpmath``). ``f_body`` maps a body index to its external force
    ``[n; f]`` in body coordinates as 6 scalars. ``Xup`` may pass the transforms
    :func:`xup_components` returned for the same ``q``.

    Terms that cannot change the answer are skipped: with q̇ = 0 every body velocity and
    velocity-product term is zero; with q̇ = q̈ = 0 (gravity only) every angular acceleration
    is zero too, so ``a_i = (0, E_i l_λ(i))`` and ``f_i = (h × l_i, m l_i)``; with zero
    gravity a body on the fixed base skips ``Xup a_0``. Each result is the full computation's
    (the skipped products are exact zeros).
    """
    gx, gy, gz = gravity
    zero = 0.0 * gx
    if Xup is None:
        Xup = xup_components(model, q, m)
    moving = any(_nonzero(x) for x in qd)
    static = not moving and not any(_nonzero(x) for x in qdd)
    weightless = not (_nonzero(gx) or _nonzero(gy) or _nonzero(gz))
    NB = len(model._kernel)
    vel = [None] * (NB + 1)
    acc = [None] * (NB + 1)
    frc = [None] * (NB + 1)
    vel[0] = (zero,) * 6
    acc[0] = (zero, zero, zero, -gx, -gy, -gz)      # a_0 = -a_grav
    tau = [zero] * len(q)
    f_body = f_body or {}

    for i, row in enumerate(model._kernel, start=1):
        p, code, (ax, ay, az), _, _, mass, (hx, hy, hz), Ib, k, mul, _ = row
        e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz = Xup[i]
        if static:
            # Gravity only: a_i = (0, E_i l_λ(i)), f_i = I_i a_i = (h × l_i, m l_i).
            _, _, _, pl0, pl1, pl2 = acc[p]
            l0 = e00 * pl0 + e01 * pl1 + e02 * pl2
            l1 = e10 * pl0 + e11 * pl1 + e12 * pl2
            l2 = e20 * pl0 + e21 * pl1 + e22 * pl2
            acc[i] = (zero, zero, zero, l0, l1, l2)
            n0, n1, n2 = hy * l2 - hz * l1, hz * l0 - hx * l2, hx * l1 - hy * l0
            f0, f1, f2 = mass * l0, mass * l1, mass * l2
        else:
            qddi = qdd[k] if mul == 1.0 else mul * qdd[k]

            # a_i = Xup_i a_λ(i) + S_i q̈_i + v_i × vJ
            if p == 0 and weightless:
                a0 = a1 = a2 = l0 = l1 = l2 = zero      # a_0 = 0
            else:
                pa0, pa1, pa2, pl0, pl1, pl2 = acc[p]
                u0 = pl0 - (ry * pa2 - rz * pa1)
                u1 = pl1 - (rz * pa0 - rx * pa2)
                u2 = pl2 - (rx * pa1 - ry * pa0)
                a0 = e00 * pa0 + e01 * pa1 + e02 * pa2
                a1 = e10 * pa0 + e11 * pa1 + e12 * pa2
                a2 = e20 * pa0 + e21 * pa1 + e22 * pa2
                l0 = e00 * u0 + e01 * u1 + e02 * u2
                l1 = e10 * u0 + e11 * u1 + e12 * u2
                l2 = e20 * u0 + e21 * u1 + e22 * u2
            if code == PR:
                l0, l1, l2 = l0 + ax * qddi, l1 + ay * qddi, l2 + az * qddi
            else:
                a0, a1, a2 = a0 + ax * qddi, a1 + ay * qddi, a2 + az * qddi

            # f_i = I_i a_i + v_i ×* I_i v_i - f_ext_i, with I = [[Ibar, h×], [h×ᵀ, m 1]]
            Ixx, Ixy, Ixz, Iyy, Iyz, Izz = Ib
            if moving:
                # v_i = Xup_i v_λ(i) + vJ,  vJ = S_i q̇_i
                qdi = qd[k] if mul == 1.0 else mul * qd[k]
                pw0, pw1, pw2, pv0, pv1, pv2 = vel[p]
                u0 = pv0 - (ry * pw2 - rz * pw1)
                u1 = pv1 - (rz * pw0 - rx * pw2)
                u2 = pv2 - (rx * pw1 - ry * pw0)
                w0 = e00 * pw0 + e01 * pw1 + e02 * pw2
                w1 = e10 * pw0 + e11 * pw1 + e12 * pw2
                w2 = e20 * pw0 + e21 * pw1 + e22 * pw2
                v0 = e00 * u0 + e01 * u1 + e02 * u2
                v1 = e10 * u0 + e11 * u1 + e12 * u2
                v2 = e20 * u0 + e21 * u1 + e22 * u2
                j0, j1, j2 = ax * qdi, ay * qdi, az * qdi
                if code == PR:
                    v0, v1, v2 = v0 + j0, v1 + j1, v2 + j2
                    l0 += w1 * j2 - w2 * j1
                    l1 += w2 * j0 - w0 * j2
                    l2 += w0 * j1 - w1 * j0
                else:
                    w0, w1, w2 = w0 + j0, w1 + j1, w2 + j2
                    a0 += w1 * j2 - w2 * j1
                    a1 += w2 * j0 - w0 * j2
                    a2 += w0 * j1 - w1 * j0
                    l0 += v1 * j2 - v2 * j1
                    l1 += v2 * j0 - v0 * j2
                    l2 += v0 * j1 - v1 * j0
                vel[i] = (w0, w1, w2, v0, v1, v2)
            acc[i] = (a0, a1, a2, l0, l1, l2)

            # I_i a_i
            n0 = Ixx * a0 + Ixy * a1 + Ixz * a2 + (hy * l2 - hz * l1)
            n1 = Ixy * a0 + Iyy * a1 + Iyz * a2 + (hz * l0 - hx * l2)
            n2 = Ixz * a0 + Iyz * a1 + Izz * a2 + (hx * l1 - hy * l0)
            f0 = mass * l0 - (hy * a2 - hz * a1)
            f1 = mass * l1 - (hz * a0 - hx * a2)
            f2 = mass * l2 - (hx * a1 - hy * a0)
            if moving:
                # momentum I_i v_i, then v_i ×* (I_i v_i) = [w × hn + v × hf; w × hf]
                m0 = Ixx * w0 + Ixy * w1 + Ixz * w2 + (hy * v2 - hz * v1)
                m1 = Ixy * w0 + Iyy * w1 + Iyz * w2 + (hz * v0 - hx * v2)
                m2 = Ixz * w0 + Iyz * w1 + Izz * w2 + (hx * v1 - hy * v0)
                k0 = mass * v0 - (hy * w2 - hz * w1)
                k1 = mass * v1 - (hz * w0 - hx * w2)
                k2 = mass * v2 - (hx * w1 - hy * w0)
                n0 += (w1 * m2 - w2 * m1) + (v1 * k2 - v2 * k1)
                n1 += (w2 * m0 - w0 * m2) + (v2 * k0 - v0 * k2)
                n2 += (w0 * m1 - w1 * m0) + (v0 * k1 - v1 * k0)
                f0 += w1 * k2 - w2 * k1
                f1 += w2 * k0 - w0 * k2
                f2 += w0 * k1 - w1 * k0
        fe = f_body.get(i)
        if fe is not None:
            n0, n1, n2 = n0 - fe[0], n1 - fe[1], n2 - fe[2]
            f0, f1, f2 = f0 - fe[3], f1 - fe[4], f2 - fe[5]
        frc[i] = [n0, n1, n2, f0, f1, f2]

    # Backward pass: τ_i = S_iᵀ f_i, f_λ(i) += Xup_iᵀ f_i
    for i in range(NB, 0, -1):
        p, code, (ax, ay, az), _, _, _, _, _, k, mul, _ = model._kernel[i - 1]
        n0, n1, n2, f0, f1, f2 = frc[i]
        if code == PR:
            t = ax * f0 + ay * f1 + az * f2
        else:
            t = ax * n0 + ay * n1 + az * n2
        tau[k] = tau[k] + (t if mul == 1.0 else mul * t)
        if p == 0:
            continue
        e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz = Xup[i]
        F0 = e00 * f0 + e10 * f1 + e20 * f2
        F1 = e01 * f0 + e11 * f1 + e21 * f2
        F2 = e02 * f0 + e12 * f1 + e22 * f2
        fp = frc[p]
        fp[0] += e00 * n0 + e10 * n1 + e20 * n2 + (ry * F2 - rz * F1)
        fp[1] += e01 * n0 + e11 * n1 + e21 * n2 + (rz * F0 - rx * F2)
        fp[2] += e02 * n0 + e12 * n1 + e22 * n2 + (rx * F1 - ry * F0)
        fp[3] += F0
        fp[4] += F1
        fp[5] += F2
    return tau


def xup_components(model: Model, q, m=math) -> list:
    """Body transforms ``Xup_i = XJ(q_i) Xtree_i`` as ``(E (9 scalars), r (3))`` per body.

    RBDA table 4.1 for ``XJ`` and eq. 2.27 for the product ``(E_J, 0)(E_t, r_t)`` (revolute:
    ``E = E_J E_t``, ``r = r_t``) or ``(1, axis q)(E_t, r_t)`` (prismatic: ``E = E_t``,
    ``r = r_t + E_tᵀ axis q``). Index 0 (the base) is ``None``.
    """
    sin, cos = m.sin, m.cos
    Xup = [None]
    for p, code, (ax, ay, az), Et, (rx, ry, rz), _, _, _, k, mul, off in model._kernel:
        qi = q[k] if mul == 1.0 and off == 0.0 else mul * q[k] + off
        t00, t01, t02, t10, t11, t12, t20, t21, t22 = Et
        if code == PR:
            Xup.append(Et + (rx + (t00 * ax + t10 * ay + t20 * az) * qi,
                             ry + (t01 * ax + t11 * ay + t21 * az) * qi,
                             rz + (t02 * ax + t12 * ay + t22 * az) * qi))
            continue
        c, s = cos(qi), sin(qi)
        if code == RZ:
            s = az * s     # about ±Z
            E = (c * t00 + s * t10, c * t01 + s * t11, c * t02 + s * t12,
                 c * t10 - s * t00, c * t11 - s * t01, c * t12 - s * t02,
                 t20, t21, t22)
        elif code == RX:
            s = ax * s     # about ±X
            E = (t00, t01, t02,
                 c * t10 + s * t20, c * t11 + s * t21, c * t12 + s * t22,
                 c * t20 - s * t10, c * t21 - s * t11, c * t22 - s * t12)
        elif code == RY:
            s = ay * s     # about ±Y
            E = (c * t00 - s * t20, c * t01 - s * t21, c * t02 - s * t22,
                 t10, t11, t12,
                 s * t00 + c * t20, s * t01 + c * t21, s * t02 + c * t22)
        else:  # general axis: E_J = R(axis, q)ᵀ = c 1 - s axis× + (1 - c) axis axisᵀ
            C = 1.0 - c
            j00, j11, j22 = c + C * ax * ax, c + C * ay * ay, c + C * az * az
            cxy, cxz, cyz = C * ax * ay, C * ax * az, C * ay * az
            sx, sy, sz = s * ax, s * ay, s * az
            j01, j02, j10 = cxy + sz, cxz - sy, cxy - sz
            j12, j20, j21 = cyz + sx, cxz + sy, cyz - sx
            E = (j00 * t00 + j01 * t10 + j02 * t20,
                 j00 * t01 + j01 * t11 + j02 * t21,
                 j00 * t02 + j01 * t12 + j02 * t22,
                 j10 * t00 + j11 * t10 + j12 * t20,
                 j10 * t01 + j11 * t11 + j12 * t21,
                 j10 * t02 + j11 * t12 + j12 * t22,
                 j20 * t00 + j21 * t10 + j22 * t20,
                 j20 * t01 + j21 * t11 + j22 * t21,
                 j20 * t02 + j21 * t12 + j22 * t22)
        Xup.append(E + (rx, ry, rz))
    return Xup


def _nonzero(x) -> bool:
    """Tell whether a scalar or array component is not identically zero."""
    return bool(x != 0) if not isinstance(x, np.ndarray) else bool(x.any())


def rnea_spatial(model: Model, q, qd, qdd, gravity: Sequence[float] = GRAVITY,
                 f_ext: Optional[Mapping[str, np.ndarray]] = None) -> np.ndarray:
    """RNEA written literally on 6×6 spatial matrices (reference; same contract as rnea)."""
    q, qd, qdd = _as_joint_arrays(model, q, qd, qdd)
    a_grav = np.concatenate([np.zeros(3), _as_vector('gravity', gravity, 3)])
    fb = _f_ext_in_bodies(model, f_ext)
    batch = q.shape[:-1]
    NB = model.NB
    Xup, v, a, f = [None] * (NB + 1), [None] * (NB + 1), [None] * (NB + 1), [None] * (NB + 1)
    v[0] = np.zeros(batch + (6,))
    a[0] = np.broadcast_to(-a_grav, batch + (6,))
    S = [None] * (NB + 1)
    for i in range(1, NB + 1):
        k, mul, off = model.qidx[i], model.qmul[i], model.qoff[i]
        XJ, S[i] = jcalc(model.jtype[i], model.axis[i], mul * q[..., k] + off)
        vJ = S[i] * (mul * qd[..., k])[..., None]
        Xup[i] = XJ @ model.Xtree[i]
        p = model.parent[i]
        v[i] = _mv(Xup[i], v[p]) + vJ
        a[i] = _mv(Xup[i], a[p]) + S[i] * (mul * qdd[..., k])[..., None] + _mv(crm(v[i]), vJ)
        Iv = _mv(model.inertia[i], v[i])
        f[i] = _mv(model.inertia[i], a[i]) + _mv(crf(v[i]), Iv) - fb.get(i, 0.0)
    tau = np.zeros(q.shape)
    for i in range(NB, 0, -1):
        k = model.qidx[i]
        tau[..., k] += model.qmul[i] * (f[i] @ S[i])
        p = model.parent[i]
        if p > 0:
            f[p] = f[p] + _mv(np.swapaxes(Xup[i], -1, -2), f[i])
    return tau


def _mv(A: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Batched matrix-vector product ``A x`` over leading dimensions."""
    return np.einsum('...ij,...j->...i', A, x)
