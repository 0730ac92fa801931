# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Compiled RNEA backend: :func:`rnea.rnea_components` as a numba kernel on flat arrays.

The kernel is the component-wise RNEA of ``rnea.py`` statement for statement (RBDA table 5.1,
``Xup = (E, r)`` as in RBDA §2.12), on float64 scalars, in the same order of operations and
without fast-math or fused multiply-adds, so it agrees with the numpy backend to a few ulps
(to the bit against the single-state float path on the same libm).

Importing this module imports numba and compiles the entries, or loads them from numba's
on-disk cache (``cache=True``): the signatures are explicit, so nothing is compiled after
import and a call with other argument types is refused instead of compiling in the hot path.
Use it through ``rnea(..., backend=...)``; :mod:`backends` imports it on first use.

The model enters as one table ``K`` (NB+1, 30) float64, ``model._table`` (built with the
model, see ``model._kernel_table``): row ``i`` = body ``i``, with parent ``λ(i)``, joint code
(``RX RY RZ RA PR``) and index into ``q`` (small integers, exact in float64), axis (3),
``E_tree`` row-major (9), ``r_tree`` (3), mass, ``h = m c`` (3), ``Ibar`` (xx xy xz yy yz zz),
mimic multiplier and offset; row 0 holds ``n = len(q)``. One array is one argument less to
unbox per call.
"""

from __future__ import annotations

import threading

import numba
from numba import prange, types
from numba.extending import intrinsic
import numpy as np

from .model import (Model, PR, RX, RY, RZ, T_AXIS as AX, T_CODE as CODE, T_E as E,
                    T_H as H, T_IBAR as IBAR, T_MASS as MASS, T_MUL as MUL, T_OFF as OFF,
                    T_PARENT as PARENT, T_QIDX as QIDX, T_R as R)
# Columns of the per-body scratch: Xup = (E, r) (12), v (6), a (6), f (6).
XUP, VEL, ACC, FRC, WORK = 0, 12, 18, 24, 30

#: Smallest batch handed to the parallel entry (below it the thread launch costs more).
PARALLEL_MIN = 64
#: Largest model (NB + 1 rows) whose single-state scratch goes on the stack (30 KiB).
STACK_ROWS = 128

# Signatures: inputs are read-only C arrays (writable arrays convert to them), then gravity.
_f8, _in1, _in2, _in3 = (types.float64,) + tuple(
    types.Array(types.float64, nd, 'C', readonly=True) for nd in (1, 2, 3))
_out1, _out2 = (types.Array(types.float64, nd, 'C') for nd in (1, 2))
_SINGLE = types.boolean(_in2, _in1, _in1, _in1, _f8, _f8, _f8, _out1)
_BATCH = types.void(_in2, _in2, _in2, _in2, _f8, _f8, _f8, _in3, _out2)
_PARALLEL = types.void(_in2, _in2, _in2, _in2, _f8, _f8, _f8, _in3, _out2, types.int64)
_JIT = dict(cache=True, fastmath=False, error_model='numpy')
#: f_ext of the single-state entry: none (a compile-time constant).
_NO_FEXT = np.zeros((0, 1, 6))


@intrinsic
def _stack_doubles(typingctx, count):
    """Pointer to ``count`` float64 on the caller's stack frame (freed when it returns)."""
    def codegen(context, builder, signature, args):
        return builder.alloca(context.get_value_type(types.float64), size=args[0])
    return types.CPointer(types.float64)(types.intp), codegen


def kernel_arrays(model: Model) -> tuple[np.ndarray, int]:
    """Return ``(K, n)``: the model's per-body table (read-only) and ``n = model.nq``."""
    return model._table, model.nq


@numba.njit(inline='always', **_JIT)
def _xup(K, q, work):
    """Body transforms ``Xup_i = XJ(q_i) Xtree_i`` as ``(E, r)`` into ``work[30 i + XUP:]``.

    RBDA table 4.1 for ``XJ`` and eq. 2.27 for the product, as ``rnea.xup_components``.
    """
    for i in range(1, K.shape[0]):
        b = i * WORK
        code, k = int(K[i, CODE]), int(K[i, QIDX])
        ax, ay, az = K[i, AX], K[i, AX + 1], K[i, AX + 2]
        mul, off = K[i, MUL], K[i, OFF]
        qi = q[k] if mul == 1.0 and off == 0.0 else mul * q[k] + off
        t00, t01, t02 = K[i, E], K[i, E + 1], K[i, E + 2]
        t10, t11, t12 = K[i, E + 3], K[i, E + 4], K[i, E + 5]
        t20, t21, t22 = K[i, E + 6], K[i, E + 7], K[i, E + 8]
        rx, ry, rz = K[i, R], K[i, R + 1], K[i, R + 2]
        if code == PR:
            e00, e01, e02, e10, e11, e12, e20, e21, e22 = \
                t00, t01, t02, t10, t11, t12, t20, t21, t22
            rx = rx + (t00 * ax + t10 * ay + t20 * az) * qi
            ry = ry + (t01 * ax + t11 * ay + t21 * az) * qi
            rz = rz + (t02 * ax + t12 * ay + t22 * az) * qi
        else:
            c, s = np.cos(qi), np.sin(qi)
            if code == RZ:
                s = az * s     # about ±Z
                e00, e01, e02 = c * t00 + s * t10, c * t01 + s * t11, c * t02 + s * t12
                e10, e11, e12 = c * t10 - s * t00, c * t11 - s * t01, c * t12 - s * t02
                e20, e21, e22 = t20, t21, t22
            elif code == RX:
                s = ax * s     # about ±X
                e00, e01, e02 = t00, t01, t02
                e10, e11, e12 = c * t10 + s * t20, c * t11 + s * t21, c * t12 + s * t22
                e20, e21, e22 = c * t20 - s * t10, c * t21 - s * t11, c * t22 - s * t12
            elif code == RY:
                s = ay * s     # about ±Y
                e00, e01, e02 = c * t00 - s * t20, c * t01 - s * t21, c * t02 - s * t22
                e10, e11, e12 = t10, t11, t12
                e20, e21, e22 = s * t00 + c * t20, s * t01 + c * t21, s * t02 + c * t22
            else:  # general axis: E_J = R(axis, q)ᵀ = c 1 - s axis× + (1 - c) axis axisᵀ
                C = 1.0 - c
                j00, j11, j22 = c + C * ax * ax, c + C * ay * ay, c + C * az * az
                cxy, cxz, cyz = C * ax * ay, C * ax * az, C * ay * az
                sx, sy, sz = s * ax, s * ay, s * az
                j01, j02, j10 = cxy + sz, cxz - sy, cxy - sz
                j12, j20, j21 = cyz + sx, cxz + sy, cyz - sx
                e00 = j00 * t00 + j01 * t10 + j02 * t20
                e01 = j00 * t01 + j01 * t11 + j02 * t21
                e02 = j00 * t02 + j01 * t12 + j02 * t22
                e10 = j10 * t00 + j11 * t10 + j12 * t20
                e11 = j10 * t01 + j11 * t11 + j12 * t21
                e12 = j10 * t02 + j11 * t12 + j12 * t22
                e20 = j20 * t00 + j21 * t10 + j22 * t20
                e21 = j20 * t01 + j21 * t11 + j22 * t21
                e22 = j20 * t02 + j21 * t12 + j22 * t22
        work[b + XUP], work[b + XUP + 1], work[b + XUP + 2] = e00, e01, e02
        work[b + XUP + 3], work[b + XUP + 4], work[b + XUP + 5] = e10, e11, e12
        work[b + XUP + 6], work[b + XUP + 7], work[b + XUP + 8] = e20, e21, e22
        work[b + XUP + 9], work[b + XUP + 10], work[b + XUP + 11] = rx, ry, rz


@numba.njit(inline='always', **_JIT)
def _rnea_one(K, q, qd, qdd, gx, gy, gz, fext, row, tau, work):
    """RNEA on one state into ``tau`` (n,); ``fext[row]`` is f_ext (none if ``row < 0``).

    ``work`` (flat, 30 per body: a 1-D array or a pointer) holds, per body ``i`` from
    ``30 i``, ``Xup = (E, r)``, ``v``, ``a`` and ``f``. As in
    ``rnea.rnea_components``, what cannot change the answer is skipped: the velocity terms
    when q̇ = 0, everything but gravity when q̇ = q̈ = 0, and ``Xup a_0`` when gravity is zero.
    """
    NB = K.shape[0] - 1
    zero = 0.0 * gx
    _xup(K, q, work)
    moving = False
    for k in range(qd.shape[0]):
        if qd[k] != 0.0:
            moving = True
            break
    static = not moving
    if static:
        for k in range(qdd.shape[0]):
            if qdd[k] != 0.0:
                static = False
                break
    weightless = gx == 0.0 and gy == 0.0 and gz == 0.0
    for c in range(VEL, VEL + 6):
        work[c] = zero
    work[ACC], work[ACC + 1], work[ACC + 2] = zero, zero, zero
    work[ACC + 3], work[ACC + 4], work[ACC + 5] = -gx, -gy, -gz   # a_0 = -a_grav
    tau[:] = zero

    for i in range(1, NB + 1):
        p, code, k = int(K[i, PARENT]), int(K[i, CODE]), int(K[i, QIDX])
        b, bp = i * WORK, p * WORK      # this body's and its parent's scratch
        e00, e01, e02 = work[b + XUP], work[b + XUP + 1], work[b + XUP + 2]
        e10, e11, e12 = work[b + XUP + 3], work[b + XUP + 4], work[b + XUP + 5]
        e20, e21, e22 = work[b + XUP + 6], work[b + XUP + 7], work[b + XUP + 8]
        mass = K[i, MASS]
        hx, hy, hz = K[i, H], K[i, H + 1], K[i, H + 2]
        if static:
            # Gravity only (q̇ = q̈ = 0): every angular acceleration is zero, so
            # a_i = (0, E_i l_λ(i)) and f_i = I_i a_i = (h × l_i, m l_i).
            pl0, pl1, pl2 = work[bp + ACC + 3], work[bp + ACC + 4], work[bp + ACC + 5]
            l0 = e00 * pl0 + e01 * pl1 + e02 * pl2
            l1 = e10 * pl0 + e11 * pl1 + e12 * pl2
            l2 = e20 * pl0 + e21 * pl1 + e22 * pl2
            work[b + ACC + 3], work[b + ACC + 4], work[b + ACC + 5] = l0, l1, l2
            n0, n1, n2 = hy * l2 - hz * l1, hz * l0 - hx * l2, hx * l1 - hy * l0
            f0, f1, f2 = mass * l0, mass * l1, mass * l2
        else:
            ax, ay, az = K[i, AX], K[i, AX + 1], K[i, AX + 2]
            rx, ry, rz = work[b + XUP + 9], work[b + XUP + 10], work[b + XUP + 11]
            mul = K[i, MUL]
            qddi = qdd[k] if mul == 1.0 else mul * qdd[k]

            # a_i = Xup_i a_λ(i) + S_i q̈_i + v_i × vJ
            if p == 0 and weightless:
                a0 = a1 = a2 = l0 = l1 = l2 = zero     # a_0 = 0
            else:
                pa0, pa1, pa2 = work[bp + ACC], work[bp + ACC + 1], work[bp + ACC + 2]
                pl0, pl1, pl2 = work[bp + ACC + 3], work[bp + ACC + 4], work[bp + ACC + 5]
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
            Ixx, Ixy, Ixz = K[i, IBAR], K[i, IBAR + 1], K[i, IBAR + 2]
            Iyy, Iyz, Izz = K[i, IBAR + 3], K[i, IBAR + 4], K[i, IBAR + 5]
            w0 = w1 = w2 = v0 = v1 = v2 = zero
            if moving:
                # v_i = Xup_i v_λ(i) + vJ,  vJ = S_i q̇_i
                qdi = qd[k] if mul == 1.0 else mul * qd[k]
                pw0, pw1, pw2 = work[bp + VEL], work[bp + VEL + 1], work[bp + VEL + 2]
                pv0, pv1, pv2 = work[bp + VEL + 3], work[bp + VEL + 4], work[bp + VEL + 5]
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
                work[b + VEL], work[b + VEL + 1], work[b + VEL + 2] = w0, w1, w2
                work[b + VEL + 3], work[b + VEL + 4], work[b + VEL + 5] = v0, v1, v2
            work[b + ACC], work[b + ACC + 1], work[b + ACC + 2] = a0, a1, a2
            work[b + ACC + 3], work[b + ACC + 4], work[b + ACC + 5] = l0, l1, l2

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
        if row >= 0:
            fe = fext[row]
            n0, n1, n2 = n0 - fe[i, 0], n1 - fe[i, 1], n2 - fe[i, 2]
            f0, f1, f2 = f0 - fe[i, 3], f1 - fe[i, 4], f2 - fe[i, 5]
        work[b + FRC], work[b + FRC + 1], work[b + FRC + 2] = n0, n1, n2
        work[b + FRC + 3], work[b + FRC + 4], work[b + FRC + 5] = f0, f1, f2

    # Backward pass: τ_i = S_iᵀ f_i, f_λ(i) += Xup_iᵀ f_i
    for i in range(NB, 0, -1):
        p, code, k = int(K[i, PARENT]), int(K[i, CODE]), int(K[i, QIDX])
        b, bp = i * WORK, p * WORK      # this body's and its parent's scratch
        ax, ay, az = K[i, AX], K[i, AX + 1], K[i, AX + 2]
        mul = K[i, MUL]
        n0, n1, n2 = work[b + FRC], work[b + FRC + 1], work[b + FRC + 2]
        f0, f1, f2 = work[b + FRC + 3], work[b + FRC + 4], work[b + FRC + 5]
        if code == PR:
            t = ax * f0 + ay * f1 + az * f2
        else:
            t = ax * n0 + ay * n1 + az * n2
        tau[k] = tau[k] + (t if mul == 1.0 else mul * t)
        if p == 0:
            continue
        e00, e01, e02 = work[b + XUP], work[b + XUP + 1], work[b + XUP + 2]
        e10, e11, e12 = work[b + XUP + 3], work[b + XUP + 4], work[b + XUP + 5]
        e20, e21, e22 = work[b + XUP + 6], work[b + XUP + 7], work[b + XUP + 8]
        rx, ry, rz = work[b + XUP + 9], work[b + XUP + 10], work[b + XUP + 11]
        F0 = e00 * f0 + e10 * f1 + e20 * f2
        F1 = e01 * f0 + e11 * f1 + e21 * f2
        F2 = e02 * f0 + e12 * f1 + e22 * f2
        work[bp + FRC] += e00 * n0 + e10 * n1 + e20 * n2 + (ry * F2 - rz * F1)
        work[bp + FRC + 1] += e01 * n0 + e11 * n1 + e21 * n2 + (rz * F0 - rx * F2)
        work[bp + FRC + 2] += e02 * n0 + e12 * n1 + e22 * n2 + (rx * F1 - ry * F0)
        work[bp + FRC + 3] += F0
        work[bp + FRC + 4] += F1
        work[bp + FRC + 5] += F2


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

    ``rnea.rnea`` calls it directly on its arguments (the fast path from Python: no
    validation copies, one dispatch); an argument of another type (not a C-contiguous
    float64 array, gravity not three numbers) raises ``TypeError`` as no overload matches,
    and the caller falls back to the general path. Holds the GIL: a call is too short to
    gain from releasing it. The scratch is on the stack, so a model of more than
    ``STACK_ROWS - 1`` bodies returns False too (:func:`rnea_single_large` takes it).
    """
    n = int(K[0, QIDX])
    rows = K.shape[0]
    if (tau.shape[0] != n or q.shape[0] != n or qd.shape[0] != n or qdd.shape[0] != n
            or rows > STACK_ROWS):
        return False
    work = _stack_doubles(rows * WORK)     # a raw pointer: no array (needs no NRT)
    _rnea_one(K, q, qd, qdd, gx, gy, gz, _NO_FEXT, -1, tau, work)
    return True


@numba.njit(_SINGLE, **_JIT)
def rnea_single_large(K, q, qd, qdd, gx, gy, gz, tau):
    """As :func:`rnea_single`, for models of any size: the scratch is allocated (with NRT).

    ``rnea.rnea`` calls it when :func:`rnea_single` returned False, which for a model of
    ``STACK_ROWS`` bodies or more means too large for the stack; False if not (n,).
    """
    n = int(K[0, QIDX])
    if tau.shape[0] != n or q.shape[0] != n or qd.shape[0] != n or qdd.shape[0] != n:
        return False
    _rnea_one(K, q, qd, qdd, gx, gy, gz, _NO_FEXT, -1, tau, np.empty(K.shape[0] * WORK))
    return True


@numba.njit(_BATCH, nogil=True, **_JIT)
def _rnea_batch(K, q, qd, qdd, gx, gy, gz, fext, tau):
    """N states, one thread: q, qd, qdd (N, n), fext (N, 1 or 0 rows, NB+1, 6) → tau (N, n)."""
    work = np.empty(K.shape[0] * WORK)
    M = fext.shape[0]
    for n in range(q.shape[0]):
        row = n if M > 1 else M - 1
        _rnea_one(K, q[n], qd[n], qdd[n], gx, gy, gz, fext, row, tau[n], work)


@numba.njit(_PARALLEL, nogil=True, parallel=True, **_JIT)
def _rnea_batch_parallel(K, q, qd, qdd, gx, gy, gz, fext, tau, chunks):
    """As :func:`_rnea_batch`, on ``chunks`` contiguous slices of the batch in numba's threads.

    Each slice is one call of the compiled :func:`_rnea_batch` (not re-lowered here).
    """
    N = q.shape[0]
    per_state = fext.shape[0] > 1
    for c in prange(chunks):
        lo, hi = c * N // chunks, (c + 1) * N // chunks
        _rnea_batch(K, q[lo:hi], qd[lo:hi], qdd[lo:hi], gx, gy, gz,
                    fext[lo:hi] if per_state else fext, tau[lo:hi])


# The workqueue threading layer (used when neither TBB nor OpenMP is available) must not be
# entered by two threads at once; a lock is cheap next to a parallel batch.
_parallel_lock = threading.Lock()


def rnea(model: Model, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, gravity: np.ndarray,
         f_body: dict) -> np.ndarray:
    """τ from validated float64 arrays of one broadcast shape (..., n) (any strides).

    ``gravity`` (3,) m/s² in root coordinates; ``f_body`` maps a body index to its external
    force ``[n; f]`` in body coordinates, shape (6,) or broadcastable to (..., 6), as made by
    ``rnea._f_ext_in_bodies``. Returns τ of shape (..., n), float64.
    """
    K, n = kernel_arrays(model)
    NB = K.shape[0] - 1
    batch = q.shape[:-1]
    N = int(np.prod(batch, dtype=np.intp))
    gx, gy, gz = (float(x) for x in gravity)
    # f_ext per body as (M, NB+1, 6): M = 0 (none), 1 (one for all states) or N.
    shared = all(np.ndim(f) <= 1 for f in f_body.values())
    fext = np.zeros(((1 if f_body else 0,) if shared else batch) + (NB + 1, 6))
    for b, f in f_body.items():
        fext[..., b, :] = f
    fext = fext.reshape(-1, NB + 1, 6)
    args = [np.ascontiguousarray(x.reshape(N, n), dtype=np.float64) for x in (q, qd, qdd)]
    tau = np.empty((N, n))
    threads = numba.get_num_threads()
    if N >= PARALLEL_MIN and threads > 1:
        with _parallel_lock:
            _rnea_batch_parallel(K, *args, gx, gy, gz, fext, tau, min(N, 4 * threads))
    else:
        _rnea_batch(K, *args, gx, gy, gz, fext, tau)
    return tau.reshape(batch + (n,))


def warmup(model: Model) -> None:
    """Run every entry once on a zero state of ``model`` (loads code, starts the threads)."""
    n = model.nq
    z1, z2 = np.zeros(n), np.zeros((PARALLEL_MIN, n))
    g = np.array([0.0, 0.0, -9.81])
    rnea_single(model._table, z1, z1, z1, *g, np.empty(n))
    rnea_single_large(model._table, z1, z1, z1, *g, np.empty(n))
    rnea(model, z1, z1, z1, g, {})
    rnea(model, z2, z2, z2, g, {})
