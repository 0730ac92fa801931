# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Print the RNEA's flat kernels a second time in SIMD lanes: several states at once.

:class:`_ToCLanes` prints the RNEA's kernels and its derivatives' on GCC/Clang vectors of 2,
4 or 8 states (:func:`lanes_c`): table values stay scalars, state values become lanes, each
lane the scalar kernel's operations in the same order (bit for bit the results of
:class:`.c_printer._ToC`'s kernels).
"""

from __future__ import annotations

import ast

from ..algorithms import components, derivatives, rnea
from ..joints import (joint_axis, joint_crba, joint_motion, joint_pair, joint_torque,
                      joint_transform, joint_velocity, joint_world_axis, rotation_product)
from .c_printer import _C_ARRAYS, _C_RESTRICT, _c_name, _ToC


#: The kernels printed a second time on lanes, and the arrays holding one value per state.
LANE_SOURCES = (components.cross, components.X_motion, components.XT_force,
                components.XT_force_plus, components.I_motion, rotation_product, joint_transform,
                joint_motion, joint_velocity, joint_torque, joint_axis, joint_world_axis,
                joint_crba, joint_pair, components.X_compose, components.Xinv_motion,
                components.crm_motion, components.crf_force, components.I_rate,
                components.Irate_motion, components.XT_I_X, rnea.xup_kernel,
                rnea.rnea_kernel, derivatives.derivatives_kernel)
_LANE_ARRAYS = {'q', 'qd', 'qdd', 'f_body', 'tau', 'work', 'dq', 'dv', 'H', 'D'}


class _ToCLanes(_ToC):
    """Print one flat kernel again for ``lanes`` states at once (SIMD across states).

    A value derived from the state (``q``, ``qd``, ``qdd``, ``f_body``, ``work``, ``tau``) is an
    ``sd_vd2`` (``sd_vd4``, ``sd_vd8``), a GCC/Clang vector of one double per state; one read
    from the table (joint code, parent, axis, ``Xtree``, inertia, mimic multiplier), gravity
    and the flags stay scalars, uniform across the lanes, as do the branches on them. Each
    lane gets the scalar kernel's operations in the scalar kernel's order (a scalar operand
    is broadcast, ``sin`` and ``cos`` are the C library's, lane by lane), so each lane's
    result is the scalar kernel's to the bit. A test over the state (``nonzero(x)``) is true
    when it holds in some lane: the lanes then take the general path, whose skipped products
    are exact zeros where the test fails.
    """

    def __init__(self, func: ast.FunctionDef, returns: dict, lanes: int, lane_params: set,
                 calls: dict) -> None:
        super().__init__(func, returns)
        self.REAL, self.SUFFIX, self.n_lanes = f'sd_vd{lanes}', f'_lanes{lanes}', lanes
        self.lanes = set(lane_params)   # names holding one value per state
        self.calls = calls              # component -> positions of its lane parameters

    def _lane(self, node) -> bool:
        """Whether an expression holds one value per state."""
        if isinstance(node, ast.Name):
            return node.id in self.lanes
        if isinstance(node, ast.Subscript):
            return isinstance(node.value, ast.Name) and node.value.id in self.lanes
        if isinstance(node, ast.Call):
            if isinstance(node.func, ast.Name):
                return node.func.id in self.returns
            return any(self._lane(a) for a in node.args)          # np.sin, np.cos
        if isinstance(node, (ast.Compare, ast.BoolOp)):
            return False                                           # a truth value: uniform
        return any(self._lane(c) for c in ast.iter_child_nodes(node))

    def _infer(self) -> None:
        super()._infer()
        changed = True
        while changed:          # a name holds lanes once one of its values does
            changed = False
            for node in ast.walk(self.func):
                pairs = []
                if isinstance(node, ast.Assign):
                    for t in node.targets:
                        if isinstance(t, ast.Tuple) and isinstance(node.value, ast.Tuple):
                            pairs += zip(t.elts, node.value.elts)
                        else:
                            pairs += [(e, node.value) for e in (
                                t.elts if isinstance(t, ast.Tuple) else [t])]
                elif isinstance(node, ast.For) and isinstance(node.iter, ast.Name):
                    pairs = [(node.target, node.iter)]
                for t, v in pairs:
                    if (isinstance(t, ast.Name) and t.id not in self.lanes
                            and t.id not in self.ints and self._lane(v)):
                        self.lanes.add(t.id)
                        changed = True
            for node in ast.walk(self.func):      # the lane arguments of each component
                if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                        and node.func.id in self.returns):
                    self.calls.setdefault(node.func.id, set()).update(
                        k for k, a in enumerate(node.args) if self._lane(a))

    def expr(self, node, prec: int = 0) -> str:
        if isinstance(node, ast.Compare) and any(
                self._lane(x) for x in [node.left] + node.comparators):
            if not (isinstance(node.ops[0], ast.NotEq) and isinstance(node.comparators[0],
                                                                      ast.Constant)
                    and node.comparators[0].value == 0.0):
                raise SyntaxError(f'line {node.lineno}: lanes test only nonzero(x)')
            return f'sd_nonzero{self.n_lanes}({self.expr(node.left)})'
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                and self._lane(node)):
            return f'sd_{node.func.attr}{self.n_lanes}({self.expr(node.args[0])})'
        if isinstance(node, ast.IfExp) and self._lane(node):
            body, orelse = (self.expr(x, 1) if self._lane(x) else self._splat(x)
                            for x in (node.body, node.orelse))
            return f'({self.expr(node.test, 1)} ? {body} : {orelse})'
        return super().expr(node, prec)

    def _kind(self, name: str) -> str:
        return self.REAL if name in self.lanes else super()._kind(name)

    def _splat(self, node) -> str:
        return f'sd_splat{self.n_lanes}({self.expr(node)})'

    def _stored(self, targets: list, value: ast.expr) -> str:
        lane = any(t is None or self._lane(t) for t in targets)
        return self._splat(value) if lane and not self._lane(value) else self.expr(value)

    def _arguments(self, callee: str, args: list) -> list:
        lanes = self.calls.get(callee, set())
        return [self._splat(a) if k in lanes and not self._lane(a) else self.expr(a)
                for k, a in enumerate(args)]

    def _parameter(self, p: str, written: set) -> list:
        if p in self.lanes and p in _C_ARRAYS:
            restrict = 'restrict ' if self.func.name in _C_RESTRICT else ''
            return [('' if p in written else 'const ') + f'{self.REAL} *{restrict}{p}']
        if p in self.lanes:
            return [f'{self.REAL} {_c_name(p)}']
        return super()._parameter(p, written)


#: Helpers of the lane kernels, and the entry that runs a batch on them (``{L}`` the lanes).
_LANES_C = """\
typedef double sd_vd{L} __attribute__((vector_size({size})));

/* x in every lane. */
static inline sd_vd{L} sd_splat{L}(double x)
{{
    return (sd_vd{L}){{{splat}}};
}}

/* Whether x is nonzero in some lane. */
static inline long sd_nonzero{L}(sd_vd{L} x)
{{
    return {nonzero};
}}

/* The C library's sin and cos, lane by lane: each lane's value is the scalar kernel's (the
 * compiler computes the sine and cosine of one lane with one call to sincos). */
static inline sd_vd{L} sd_sin{L}(sd_vd{L} x)
{{
    return (sd_vd{L}){{{sin}}};
}}

static inline sd_vd{L} sd_cos{L}(sd_vd{L} x)
{{
    return (sd_vd{L}){{{cos}}};
}}

{out}

{kernels}

/* RNEA of the states [0, N - N % {L}) of a batch, {L} at a time: rows of Q (nq numbers each),
 * QD, QDD (nv each) into the same rows of TAU (nv each), with the external forces F (rows x 6
 * numbers for every state, or for each state with F_each) or none (NULL); `work` holds
 * rows * WORK + nq + 3 nv + 6 rows vectors. Each state's torques are, bit for bit, those of
 * xup_kernel and rnea_kernel on that state alone. */
static void rnea_batch_lanes{L}(const double *K, long rows, long N, const double *Q,
    const double *QD, const double *QDD, double gx, double gy, double gz, const double *F,
    long F_each, double *TAU, sd_vd{L} *work)
{{
    const long nq = (long)K[QIDX], nv = (long)K[VIDX];
    sd_vd{L} *q = work + rows * WORK, *qd = q + nq, *qdd = qd + nv, *tau = qdd + nv;
    sd_vd{L} *f_body = tau + nv;
    for (long b = 0; b + {L} <= N; b += {L}) {{
        for (long k = 0; k < nq; k++)
            for (int s = 0; s < {L}; s++)
                q[k][s] = Q[(b + s) * nq + k];
        for (long k = 0; k < nv; k++)
            for (int s = 0; s < {L}; s++) {{
                qd[k][s] = QD[(b + s) * nv + k];
                qdd[k][s] = QDD[(b + s) * nv + k];
            }}
        for (long k = 0; F != NULL && k < rows * 6; k++)
            for (int s = 0; s < {L}; s++)
                f_body[k][s] = F[(F_each ? b + s : 0) * rows * 6 + k];
        xup_kernel_lanes{L}(K, rows, q, work);
        rnea_kernel_lanes{L}(K, rows, q, qd, qdd, gx, gy, gz, f_body, F != NULL, tau, work);
        sd_out{L}(tau, nv, TAU + b * nv, nv);
    }}
}}

/* The derivatives (dtau/dq, dtau/dqd, M: nv x nv numbers a state each, into the rows of
 * DQ, DV and DM) of the states [0, N - N % {L}) of a batch, {L} at a time; arguments as for
 * rnea_batch_lanes{L}, `work` holding rows * (WORK + DWORK + 6 CWORK) + nq + 2 nv
 * + 6 rows + 3 nv nv vectors. Each state's, bit for bit, those of derivatives_kernel on it
 * alone. */
static void derivatives_batch_lanes{L}(const double *K, long rows, long N, const double *Q,
    const double *QD, const double *QDD, double gx, double gy, double gz, const double *F,
    long F_each, double *DQ, double *DV, double *DM, sd_vd{L} *work)
{{
    const long nq = (long)K[QIDX], nv = (long)K[VIDX], nv2 = nv * nv;
    sd_vd{L} *q = work + rows * (WORK + DWORK + 6 * CWORK), *qd = q + nq, *qdd = qd + nv;
    sd_vd{L} *f_body = qdd + nv, *dq = f_body + 6 * rows, *dv = dq + nv2, *H = dv + nv2;
    for (long b = 0; b + {L} <= N; b += {L}) {{
        for (long k = 0; k < nq; k++)
            for (int s = 0; s < {L}; s++)
                q[k][s] = Q[(b + s) * nq + k];
        for (long k = 0; k < nv; k++)
            for (int s = 0; s < {L}; s++) {{
                qd[k][s] = QD[(b + s) * nv + k];
                qdd[k][s] = QDD[(b + s) * nv + k];
            }}
        for (long k = 0; F != NULL && k < rows * 6; k++)
            for (int s = 0; s < {L}; s++)
                f_body[k][s] = F[(F_each ? b + s : 0) * rows * 6 + k];
        xup_kernel_lanes{L}(K, rows, q, work);
        derivatives_kernel_lanes{L}(K, rows, qd, qdd, gx, gy, gz, f_body, F != NULL, dq, dv, H,
                                    work);
        sd_out{L}(dq, nv2, DQ + b * nv2, nv2);
        sd_out{L}(dv, nv2, DV + b * nv2, nv2);
        sd_out{L}(H, nv2, DM + b * nv2, nv2);
    }}
}}
"""

#: How the lane kernels are compiled: two lanes (SSE2, NEON: every 64-bit target), and on
#: x86-64 four for CPUs with AVX and eight with AVX-512F, chosen at run time.
_LANES_HEAD = """\
/* ------------------------------------------------------------------------------------------
 * The same RNEA on several states at once (SIMD across the states of a batch): the kernels
 * printed again by c_lanes._ToCLanes on GCC and Clang vector extensions. rnea_batch_lanes
 * runs as many states of a batch as fill the lanes and returns how many; a compiler without
 * vector extensions gets SD_LANES undefined, and the batch runs the scalar kernels. */
#if defined(__GNUC__) || defined(__clang__)
#define SD_LANES 8      /* rnea_batch_lanes is defined: up to 8 states at once */
#include <stdint.h>
#include <stdlib.h>
#if defined(__x86_64__)
#define SD_AVX 1
#include <immintrin.h>
#endif

"""

_LANES_TAIL = """\
/* RNEA of the first states of a batch of N (see above) in lanes: the number of states done
 * (N rounded down to the lanes), or -1 without memory. */
static long rnea_batch_lanes(const double *K, long rows, long N, const double *Q,
    const double *QD, const double *QDD, double gx, double gy, double gz, const double *F,
    long F_each, double *TAU)
{
    const long nq = (long)K[QIDX], nv = (long)K[VIDX];
    const long size = 8 * (rows * WORK + nq + 3 * nv + 6 * rows);   /* doubles */
    long lanes = 2;
#ifdef SD_AVX
    lanes = __builtin_cpu_supports("avx512f") ? 8 : __builtin_cpu_supports("avx") ? 4 : 2;
#endif
    if (N < lanes)
        return 0;
    double *raw = malloc(sizeof(double) * size + 64);
    if (raw == NULL)
        return -1;
    void *work = (void *)(((uintptr_t)raw + 63) & ~(uintptr_t)63);
#ifdef SD_AVX
    if (lanes == 8)
        rnea_batch_lanes8(K, rows, N, Q, QD, QDD, gx, gy, gz, F, F_each, TAU, work);
    else if (lanes == 4)
        rnea_batch_lanes4(K, rows, N, Q, QD, QDD, gx, gy, gz, F, F_each, TAU, work);
    else
#endif
        rnea_batch_lanes2(K, rows, N, Q, QD, QDD, gx, gy, gz, F, F_each, TAU, work);
    free(raw);
    return N - N % lanes;
}

/* The derivatives of the first states of a batch of N (see above) in lanes: the number of
 * states done (N rounded down to the lanes), or -1 without memory. */
static long derivatives_batch_lanes(const double *K, long rows, long N, const double *Q,
    const double *QD, const double *QDD, double gx, double gy, double gz, const double *F,
    long F_each, double *DQ, double *DV, double *DM)
{
    const long nq = (long)K[QIDX], nv = (long)K[VIDX];
    const long size = 8 * (rows * (WORK + DWORK + 6 * CWORK) + nq + 2 * nv + 6 * rows
                           + 3 * nv * nv);      /* doubles */
    long lanes = 2;
#ifdef SD_AVX
    lanes = __builtin_cpu_supports("avx512f") ? 8 : __builtin_cpu_supports("avx") ? 4 : 2;
#endif
    if (N < lanes)
        return 0;
    double *raw = malloc(sizeof(double) * size + 64);
    if (raw == NULL)
        return -1;
    void *work = (void *)(((uintptr_t)raw + 63) & ~(uintptr_t)63);
#ifdef SD_AVX
    if (lanes == 8)
        derivatives_batch_lanes8(K, rows, N, Q, QD, QDD, gx, gy, gz, F, F_each, DQ, DV,
            DM, work);
    else if (lanes == 4)
        derivatives_batch_lanes4(K, rows, N, Q, QD, QDD, gx, gy, gz, F, F_each, DQ, DV,
            DM, work);
    else
#endif
        derivatives_batch_lanes2(K, rows, N, Q, QD, QDD, gx, gy, gz, F, F_each, DQ, DV,
            DM, work);
    free(raw);
    return N - N % lanes;
}
#endif  /* vector extensions */
"""


#: Each lane's results to its state's row: a vector read once, its lanes to their rows.
_OUT = """\
/* Lane s of x[0..count) to out[s * stride + 0..count), for s < {L}: the states' results to
 * their rows, each vector read once. */
static inline void sd_out{L}(const sd_vd{L} *x, long count, double *out, long stride)
{{
    for (long k = 0; k < count; k++)
        for (int s = 0; s < {L}; s++)
            out[s * stride + k] = x[k][s];
}}"""

#: The same for four lanes (AVX), four vectors at a time: a 4 x 4 transposition in registers.
_OUT4 = """\
/* Lane s of x[0..count) to out[s * stride + 0..count), for s < 4: the states' results to
 * their rows, four vectors transposed at once in registers, a row of four stored whole. */
static inline void sd_out4(const sd_vd4 *x, long count, double *out, long stride)
{
    double *o0 = out, *o1 = o0 + stride, *o2 = o1 + stride, *o3 = o2 + stride;
    long k = 0;
    for (; k + 4 <= count; k += 4) {
        const __m256d a = x[k], b = x[k + 1], c = x[k + 2], d = x[k + 3];
        const __m256d ab0 = _mm256_unpacklo_pd(a, b), ab1 = _mm256_unpackhi_pd(a, b);
        const __m256d cd0 = _mm256_unpacklo_pd(c, d), cd1 = _mm256_unpackhi_pd(c, d);
        _mm256_storeu_pd(o0 + k, _mm256_permute2f128_pd(ab0, cd0, 0x20));
        _mm256_storeu_pd(o1 + k, _mm256_permute2f128_pd(ab1, cd1, 0x20));
        _mm256_storeu_pd(o2 + k, _mm256_permute2f128_pd(ab0, cd0, 0x31));
        _mm256_storeu_pd(o3 + k, _mm256_permute2f128_pd(ab1, cd1, 0x31));
    }
    for (; k < count; k++) {
        o0[k] = x[k][0];
        o1[k] = x[k][1];
        o2[k] = x[k][2];
        o3[k] = x[k][3];
    }
}"""


def _lanes_c(returns: dict, lanes: int, flat) -> str:
    """Return the C of the lane kernels on ``lanes`` states (the callers type the components)."""
    calls, kernels, printers = {}, [], {}
    for fn in reversed(LANE_SOURCES):          # callers first: they type the components
        func = flat(fn)
        func.body.insert(0, ast.Expr(ast.Constant(
            f'Run {fn.__module__.split(".")[-1]}.{fn.__name__} on {lanes} states, '
            'generated from it.')))
        if fn.__name__ in returns:
            params = {a.arg for k, a in enumerate(func.args.args)
                      if k in calls.get(fn.__name__, set())}
        else:
            params = {a.arg for a in func.args.args if a.arg in _LANE_ARRAYS}
        printers[fn.__name__] = printer = _ToCLanes(func, returns, lanes, params, calls)
        printer._infer()
        printer.typed = True
    for fn in LANE_SOURCES:
        kernels.append(printers[fn.__name__].function())
    each = {f: ', '.join(f'{f}(x[{j}])' for j in range(lanes)) for f in ('sin', 'cos')}
    return _LANES_C.format(L=lanes, size=8 * lanes, splat=', '.join(['x'] * lanes),
                           nonzero=' || '.join(f'x[{j}] != 0.0' for j in range(lanes)),
                           out=_OUT4 if lanes == 4 else _OUT.format(L=lanes),
                           kernels='\n\n'.join(kernels), **each)


def target_region(isa: str, text: str) -> str:
    """Return the C ``text`` compiled for the instruction set ``isa`` (GCC's and Clang's pragmas).

    The caller checks at run time that the CPU has ``isa`` before it calls a function of it.
    """
    return ('#ifdef __clang__\n#pragma clang attribute push (__attribute__((target('
            f'"{isa}"))), apply_to = function)\n#else\n#pragma GCC push_options\n'
            f'#pragma GCC target("{isa}")\n#endif\n' + text
            + '#ifdef __clang__\n#pragma clang attribute pop\n#else\n#pragma GCC pop_options\n'
            '#endif\n')


def lanes_c(returns: dict, flat) -> str:
    """Return the C of the lane kernels: 2 lanes, and on x86-64 4 with AVX, 8 with AVX-512F.

    ``flat(fn)`` is the flat syntax tree of a source function (:func:`.codegen._flat`).
    """
    wide = ''.join(target_region(isa, _lanes_c(returns, lanes, flat)) + '\n'
                   for lanes, isa in ((4, 'avx'), (8, 'avx512f')))
    return (_LANES_HEAD + _lanes_c(returns, 2, flat) + '\n#ifdef SD_AVX\n' + wide
            + '#endif  /* SD_AVX */\n\n' + _LANES_TAIL)
