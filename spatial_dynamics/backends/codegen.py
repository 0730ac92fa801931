# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Generate the C kernels from the one source of each algorithm in :mod:`..algorithms`.

The component kernels there (:mod:`~spatial_dynamics.algorithms.components`,
:mod:`~spatial_dynamics.algorithms.rnea`, :mod:`~spatial_dynamics.algorithms.crba`,
:mod:`~spatial_dynamics.algorithms.momentum`, :mod:`~spatial_dynamics.algorithms.regressor`,
:mod:`~spatial_dynamics.algorithms.jacobian`'s bodies, :mod:`~spatial_dynamics.algorithms.split`,
:mod:`~spatial_dynamics.algorithms.derivatives`, :mod:`~spatial_dynamics.algorithms.forward`,
:mod:`~spatial_dynamics.algorithms.aba`)
are plain Python over tuples and lists. This module rewrites their syntax tree statement for
statement onto flat float64 arrays (``_kernels_generated.py``, a readable listing the tests
run, :func:`flat_module`) and prints the result as C (``_kernels_generated.h``, written into
the build directory and compiled into the extension ``_compiled`` when the package is built:
see ``setup.py``); nothing of the arithmetic changes
(same expressions, same order, no fused multiply-adds), so every backend computes the same
numbers. The rewriting rules, each a change of storage only:

==============================================  ==============================================
source (Python backends)                        generated (flat arrays)
==============================================  ==============================================
``a, b, … = rows[i]`` (the whole row)           ``a = K[i, 0]; b = K[i, 1]; …`` (``int()`` for
                                                the integer columns; ``_`` skipped)
``x0, …, x5 = vel[p]`` (``Xup acc vel frc IC``) ``x0 = work[p * WORK + VEL + 0]; …``
``vel[i] = (x0, …, x5)``                        ``work[i * WORK + VEL + 0] = x0; …``
``f(…, *vel[p], …)`` (a store read whole)       ``f(…, work[p * WORK + VEL + 0], …, … + 5], …)``
``frc[p] = f(…)`` (a product stored whole)      ``s0, …, s5 = f(…)``, then stored as above
``fp = frc[p]`` then ``fp[j] += e``             ``work[p * WORK + FRC + j] += e``
``H[…] = …`` (any other array argument)         unchanged
``fe0, …, fe5 = f_body[i]``                     ``fe0 = f_body[i, 0]; …``
``nonzero(x)``, ``m.sin``, ``len(rows)``        ``x != 0.0``, ``np.sin``, ``K.shape[0]``
``f(…, m)``, ``def f(…, m)`` (the sin/cos kind)  ``f(…)``, ``def f(…)``
==============================================  ==============================================

The C is the flat text typed (:class:`.c_printer._ToC`): integer names ``long``, the rest
``double``; ``K[i, j]`` is ``K[i * WIDTH + j]``, a tuple assignment evaluates every value
before it stores one, a component product returns its values through an output array.

The RNEA kernels (with the components they call) are printed again on vectors of 2, 4 and
8 states (:class:`.c_lanes._ToCLanes`: SIMD across the states of a batch, GCC and Clang
vector extensions), each lane doing the scalar kernel's operations in its order.

Both are build products, not sources: a change to an algorithm is a change to its source
here, and the next build compiles it (``setup.py`` lists the sources the extension depends
on). ``python -m spatial_dynamics.backends.codegen [DIR]`` writes both files for reading;
the extension records the SHA-256 of the header it was built from, which a test compares
with a fresh generation (a build older than its sources fails it).
"""

from __future__ import annotations

import ast
import inspect
import os
import sys
import textwrap
import types
from typing import Optional, Sequence

from . import layout
from .c_lanes import lanes_c, target_region
from .c_printer import _ToC
from ..joints import (CODES, joint_axis, joint_crba, joint_ctq, joint_motion, joint_pair,
                      joint_torque, joint_transform, joint_velocity, joint_world_axis,
                      rotation_product)
from ..algorithms import (aba, components, crba, derivatives, forward, jacobian, momentum,
                          regressor, rnea, split)

#: Per-body scratch ``work``: Xup = (E, r) (12), v (6), a (6), f (6), composite inertia
#: (m, h, Ibar) (10) per body, flat.
STORES = {'Xup': ('XUP', 0, 12), 'vel': ('VEL', 12, 6), 'acc': ('ACC', 18, 6),
          'frc': ('FRC', 24, 6), 'IC': ('ICS', 30, 10)}
WORK = 40
#: The derivatives' scratch after the per-body rows (``rows * WORK`` doubles in): per body
#: its world transform ``oX`` (12), ``İC`` (9) and ``hC`` (6) in ``DWORK`` doubles, then six
#: columns a body of ``(s, α, β, α')`` (24 each) and ``s`` alone (6: the forward pass's, read
#: again by the pass of α, β, α'); name -> (constant, offset, values, start, stride), a slot
#: ``work[start + index * stride + offset + j]``.
DWORK, CWORK = 27, 30
#: The articulated-body algorithm's scratch after the per-body rows, ``AWORK`` doubles a body:
#: its articulated inertia ``IA`` (21, an upper triangle), bias force ``pA`` (6), velocity
#: product ``c`` (6), and its joint's ``U``, ``D⁻¹``, ``u`` (8).
AWORK = 41
MORE_STORES = {'oX': ('OXS', 0, 12, 'K.shape[0] * WORK', 'DWORK'),
               'dIC': ('DIC', 12, 9, 'K.shape[0] * WORK', 'DWORK'),
               'hC': ('HCS', 21, 6, 'K.shape[0] * WORK', 'DWORK'),
               'dcol': ('DCOL', 0, 24, 'K.shape[0] * (WORK + DWORK)', 'CWORK'),
               'scol': ('SCOL', 24, 6, 'K.shape[0] * (WORK + DWORK)', 'CWORK'),
               'IA': ('IAS', 0, 21, 'K.shape[0] * WORK', 'AWORK'),
               'pA': ('PAS', 21, 6, 'K.shape[0] * WORK', 'AWORK'),
               'cJ': ('CJS', 27, 6, 'K.shape[0] * WORK', 'AWORK'),
               'UD': ('UDS', 33, 8, 'K.shape[0] * WORK', 'AWORK')}
#: Every store's number of values.
WIDTHS = {**{k: v[2] for k, v in STORES.items()}, **{k: v[2] for k, v in MORE_STORES.items()}}
#: The functions translated, in order (a function is generated after those it calls).
#: The joints' operations (:mod:`spatial_dynamics.joints`) come first: the kernels call them,
#: and the C compiler inlines them (``static inline``), as it does the components.
SOURCES = (components.cross, components.X_motion, components.XT_force, components.XT_force_plus,
           components.I_motion, components.XT_I_X, components.XT_I_X_plus, rotation_product,
           joint_transform, joint_motion, joint_velocity, joint_torque, joint_ctq, joint_axis,
           joint_world_axis, joint_crba, joint_pair, components.X_compose,
           components.Xinv_motion, components.crm_motion, components.crf_force,
           components.I_rate, components.Irate_motion,
           rnea.xup_kernel, rnea.rnea_kernel, crba.crba_kernel, momentum.momentum_kernel,
           regressor.regressor_kernel, jacobian.bodies_kernel, split.split_kernel,
           derivatives.derivatives_kernel, forward.forward_kernel, components.I_articulated,
           components.IA_motion, components.XT_IA_X_plus, aba.aba_kernel)
#: Parameters of the generated functions (the source's, with the stores replaced by work).
SIGNATURES = {'xup_kernel': 'K, q, work',
              'rnea_kernel': 'K, q, qd, qdd, gx, gy, gz, f_body, has_fext, tau, work',
              'crba_kernel': 'K, work, H',
              'momentum_kernel': 'K, q, qd, mom, ctq, work',
              'regressor_kernel': 'K, qd, qdd, gx, gy, gz, Y, axes, work',
              'bodies_kernel': 'K, work, J',
              'split_kernel': 'QR, k, n, nb, wts, res, scr, tol',
              'derivatives_kernel': 'K, qd, qdd, gx, gy, gz, f_body, has_fext, dq, dv, H, work',
              'forward_kernel': 'K, H, qdd, lam, run, seg, Hkk, info',
              'aba_kernel': 'K, qd, tau, gx, gy, gz, f_body, has_fext, arm, has_arm, qdd, T, '
                            'info, work'}
#: The kernels printed a second time for CPUs with AVX (``name_avx``, chosen at run time by
#: ``run_state``): the same operations in VEX encodings, the same bits (see :func:`_vex`).
VEX = ('derivatives_kernel',)
#: The generated files' names. Build products, not sources: ``setup.py`` writes the header
#: into its build directory when it compiles the extension; ``python -m
#: spatial_dynamics.backends.codegen DIR`` writes both for reading.
LISTING, HEADER = '_kernels_generated.py', '_kernels_generated.h'


class _ToFlat(ast.NodeTransformer):
    """Rewrite one kernel's statements onto flat arrays (rules in the module docstring)."""

    def __init__(self) -> None:
        self.aliases = {}   # name -> (store, index expression)
        self.fresh = 0      # names made for a component's results stored whole

    # -- helpers -----------------------------------------------------------------------------
    @staticmethod
    def _slot(store: str, index: ast.expr, j: int) -> ast.Subscript:
        if store in MORE_STORES:
            const, _, _, start, stride = MORE_STORES[store]
            where = ast.parse(f'{start} + ({ast.unparse(index)}) * {stride} + {const} + {j}',
                              mode='eval').body
            return ast.Subscript(value=ast.Name('work', ast.Load()), slice=where,
                                 ctx=ast.Load())
        const, _, _ = STORES[store]
        return ast.Subscript(
            value=ast.Name('work', ast.Load()),
            slice=ast.BinOp(ast.BinOp(ast.BinOp(index, ast.Mult(), ast.Name('WORK', ast.Load())),
                                      ast.Add(), ast.Name(const, ast.Load())),
                            ast.Add(), ast.Constant(j)),
            ctx=ast.Load())

    @staticmethod
    def _store_of(node) -> str:
        if (isinstance(node, ast.Subscript) and isinstance(node.value, ast.Name)
                and node.value.id in WIDTHS):
            return node.value.id
        return ''

    @staticmethod
    def _names(target) -> list:
        if not isinstance(target, ast.Tuple) or not all(
                isinstance(e, ast.Name) for e in target.elts):
            raise SyntaxError(f'line {target.lineno}: unpack into plain names only')
        return [e.id for e in target.elts]

    def _assign(self, name: str, value: ast.expr, like: ast.AST) -> ast.Assign:
        return ast.copy_location(ast.Assign([ast.Name(name, ast.Store())], value), like)

    # -- statements -----------------------------------------------------------------------------
    def visit_Assign(self, node: ast.Assign):
        if len(node.targets) != 1:
            return self.generic_visit(node)
        target, value = node.targets[0], node.value
        # sub-expressions first (indices, stored values); the store names stay for the rules
        for sub in (value, target):
            if self._store_of(sub) or (isinstance(sub, ast.Subscript)
                                       and isinstance(sub.value, ast.Name)
                                       and sub.value.id in ('rows', 'f_body')):
                sub.slice = self.visit(sub.slice)
            else:
                setattr(node, 'value' if sub is value else 'targets',
                        self.visit(sub) if sub is value else [self.visit(sub)])
        target, value = node.targets[0], node.value
        store = self._store_of(value)
        if store and isinstance(target, ast.Tuple):              # x0, … = vel[p]
            names = self._names(target)
            if len(names) != WIDTHS[store]:
                raise SyntaxError(f'line {node.lineno}: {store} holds {WIDTHS[store]} values')
            return [self._assign(n, self._slot(store, value.slice, j), node)
                    for j, n in enumerate(names) if n != '_']
        if store and isinstance(target, ast.Name):               # fp = frc[p]
            self.aliases[target.id] = (store, value.slice)
            return None
        if self._store_of(target) and isinstance(value, ast.Call):   # frc[p] = XT_…(…)
            store = target.value.id
            self.fresh += 1
            names = [f'stored{self.fresh}_{j}' for j in range(WIDTHS[store])]
            call = ast.copy_location(ast.Assign(
                [ast.Tuple([ast.Name(n, ast.Store()) for n in names], ast.Store())], value),
                node)
            return [call] + [ast.copy_location(ast.Assign(
                [self._slot(store, target.slice, j)], ast.Name(n, ast.Load())), node)
                for j, n in enumerate(names)]
        if self._store_of(target):                               # vel[i] = (…)
            if not isinstance(value, (ast.Tuple, ast.List)):
                raise SyntaxError(f'line {node.lineno}: store a whole tuple')
            store = target.value.id
            if len(value.elts) != WIDTHS[store]:
                raise SyntaxError(f'line {node.lineno}: {store} holds {WIDTHS[store]} values')
            return [ast.copy_location(ast.Assign(
                [self._slot(store, target.slice, j)], elt), node)
                for j, elt in enumerate(value.elts)]
        if isinstance(value, ast.Subscript) and isinstance(value.value, ast.Name):
            if value.value.id == 'rows':                         # a, b, … = rows[i]
                names = self._names(target)
                if len(names) != layout.WIDTH:
                    raise SyntaxError(f'line {node.lineno}: unpack the whole row '
                                      f'({layout.WIDTH} columns)')
                out = []
                for j, n in enumerate(names):
                    if n == '_':
                        continue
                    read = ast.Subscript(ast.Name('K', ast.Load()), ast.Tuple(
                        [value.slice, ast.Constant(j)], ast.Load()), ast.Load())
                    if j in layout.INTEGER_COLUMNS:
                        read = ast.Call(ast.Name('int', ast.Load()), [read], [])
                    out.append(self._assign(n, read, node))
                return out
            if value.value.id == 'f_body':                       # fe0, … = f_body[i]
                names = self._names(target)
                return [self._assign(n, ast.Subscript(ast.Name('f_body', ast.Load()), ast.Tuple(
                    [value.slice, ast.Constant(j)], ast.Load()), ast.Load()), node)
                    for j, n in enumerate(names) if n != '_']
        return node

    def visit_AugAssign(self, node: ast.AugAssign):
        node.value = self.visit(node.value)
        target = node.target
        if not (isinstance(target, ast.Subscript) and isinstance(target.value, ast.Name)
                and target.value.id in self.aliases):
            node.target = self.visit(target)
            return node
        if (isinstance(target, ast.Subscript) and isinstance(target.value, ast.Name)
                and target.value.id in self.aliases and isinstance(target.slice, ast.Constant)):
            store, index = self.aliases[target.value.id]
            slot = self._slot(store, index, target.slice.value)
            slot.ctx = ast.Store()
            node.target = slot
        return node

    # -- expressions ----------------------------------------------------------------------------
    def visit_Call(self, node: ast.Call):
        if (isinstance(node.func, ast.Name) and node.func.id == 'len'
                and isinstance(node.args[0], ast.Name) and node.args[0].id == 'rows'):
            return ast.Subscript(ast.Attribute(ast.Name('K', ast.Load()), 'shape', ast.Load()),
                                 ast.Constant(0), ast.Load())
        args = []
        for arg in node.args:                                    # f(…, *vel[p], …)
            if isinstance(arg, ast.Name) and arg.id == 'm':
                continue                                         # f(…, m): sin, cos are np's
            if isinstance(arg, ast.Starred):
                store = self._store_of(arg.value)
                if not store:
                    raise SyntaxError(f'line {node.lineno}: * only on a store read whole')
                index = self.visit(arg.value.slice)
                args += [self._slot(store, index, j) for j in range(WIDTHS[store])]
            else:
                args.append(self.visit(arg))
        node.func, node.args = self.visit(node.func), args
        node.keywords = [self.visit(k) for k in node.keywords]
        if isinstance(node.func, ast.Name) and node.func.id == 'nonzero':
            return ast.Compare(node.args[0], [ast.NotEq()], [ast.Constant(0.0)])
        return node

    def visit_Attribute(self, node: ast.Attribute):
        if isinstance(node.value, ast.Name) and node.value.id == 'm':
            return ast.Attribute(ast.Name('np', ast.Load()), node.attr, ast.Load())
        return self.generic_visit(node)

    def visit_Name(self, node: ast.Name):
        if node.id in WIDTHS or node.id in ('rows', 'm') or node.id in self.aliases:
            raise SyntaxError(f'line {node.lineno}: {node.id!r} used outside the rules')
        return node


def _flat(fn) -> ast.FunctionDef:
    """Return the syntax tree of ``fn`` rewritten onto flat arrays (no docstring)."""
    tree = ast.parse(textwrap.dedent(inspect.getsource(fn)))
    func = tree.body[0]
    func.body = [s for s in func.body if not (isinstance(s, ast.Expr)
                                              and isinstance(s.value, ast.Constant))]
    func.returns = None
    func.args.args = [a for a in func.args.args if a.arg != 'm']      # sin, cos are np's
    if fn.__name__ in SIGNATURES:
        func.args = ast.parse(f'def f({SIGNATURES[fn.__name__]}): pass').body[0].args
    func = _ToFlat().visit(func)
    ast.fix_missing_locations(func)
    return func


def _summary(fn) -> str:
    module = fn.__module__.split('.')[-1]
    return f'Run {module}.{fn.__name__} of the algorithms, generated from it.'


def _kernel_source(fn) -> str:
    func = _flat(fn)
    func.body.insert(0, ast.Expr(ast.Constant(_summary(fn))))
    return ast.unparse(func)


#: The real constants the kernels name (printed ``static const double`` in C).
REALS = {'PIVOT_TOL': forward.PIVOT_TOL}


def _constants() -> dict:
    """Return the constants the kernels name: joint codes and the scratch layout."""
    consts = dict(CODES)
    consts['WORK'] = WORK
    consts.update((const, offset) for const, offset, _ in STORES.values())
    consts.update(DWORK=DWORK, CWORK=CWORK, AWORK=AWORK)
    consts.update((v[0], v[1]) for v in MORE_STORES.values())
    return consts


def generate() -> str:
    """Return the text of ``_kernels_generated.py``."""
    header = f'''\
# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Kernels generated from :mod:`spatial_dynamics.algorithms`: do not edit.

The flat-array form of the one source (the rules of :mod:`.codegen`), from which the C of
``_kernels_generated.h`` is printed; plain Python, run by the tests to check the rewriting.
Change the source, not this listing: codegen prints it from the source.
"""
import numpy as np

{chr(10).join(f'{k} = {v!r}' for k, v in {**_constants(), **REALS}.items())}
'''
    body = '\n\n\n'.join(_kernel_source(fn) for fn in SOURCES)
    return header + '\n\n' + body + '\n'


def _vex(text: str, name: str) -> str:
    """Return the C function ``text`` (of ``name``) again as ``name_avx``, compiled for AVX.

    The same statements in the same order, without fused multiply-adds: only the encoding
    changes (VEX, three operands), so each result has the bits of the scalar function's.
    The inline components it calls are inlined into it (their ISA is a subset of AVX).
    """
    return ('#ifdef SD_VEX\n' + target_region('avx', text.replace(
        f' {name}(', f' {name}_avx(', 1).replace(
            'generated from it.', 'generated from it (AVX encodings).', 1) + '\n')
        + '#endif  /* SD_VEX */')


def generate_c() -> str:
    """Return the text of ``_kernels_generated.h``: the same kernels as C functions."""
    consts = dict(_constants(), WIDTH=layout.WIDTH, QIDX=layout.COLUMN['qidx'],
                  VIDX=layout.COLUMN['vidx'], DOF=layout.COLUMN['dof'])
    funcs, returns = [], {}
    for fn in SOURCES:
        func = _flat(fn)
        func.body.insert(0, ast.Expr(ast.Constant(_summary(fn))))
        ret = [n for n in ast.walk(func) if isinstance(n, ast.Return)]
        if ret:     # how many values it returns (0: it writes into an array it is given)
            returns[fn.__name__] = len(ret[0].value.elts) if ret[0].value is not None else 0
        funcs.append(_ToC(func, returns).function())
        if fn.__name__ in VEX:
            funcs.append(_vex(funcs[-1], fn.__name__))
    header = '''\
/* Copyright 2026 spatial_dynamics contributors
 * SPDX-License-Identifier: Apache-2.0
 *
 * Kernels generated from spatial_dynamics.algorithms: do not edit.
 * Change the source, not this header: setup.py generates it into the build directory.
 * Included by kernels.c; compile without fused multiply-adds (-ffp-contract=off).
 */
#ifndef SPATIAL_DYNAMICS_KERNELS_GENERATED_H
#define SPATIAL_DYNAMICS_KERNELS_GENERATED_H

#include <math.h>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define SD_VEX 1        /* the kernels of codegen.VEX have an AVX copy, name_avx */
#endif

'''
    enum = 'enum {\n' + ',\n'.join(f'    {k} = {v}' for k, v in consts.items()) + '\n};\n'
    enum += ''.join(f'static const double {k} = {v!r};\n' for k, v in REALS.items())
    return (header + enum + '\n' + '\n\n'.join(funcs) + '\n\n' + lanes_c(returns, _flat)
            + '\n#endif  /* SPATIAL_DYNAMICS_KERNELS_GENERATED_H */\n')


def flat_module():
    """Return the flat-array listing (:func:`generate`) as a module, to run it on floats."""
    module = types.ModuleType('spatial_dynamics.backends.' + LISTING[:-3])
    exec(compile(generate(), LISTING, 'exec'), module.__dict__)
    return module


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Write the listing and the C header into a directory (default ``build/generated``)."""
    args = list(sys.argv[1:] if argv is None else argv)
    if len(args) > 1 or args[:1] in (['-h'], ['--help']):
        print('usage: python -m spatial_dynamics.backends.codegen [DIR]', file=sys.stderr)
        return 2
    directory = args[0] if args else os.path.join('build', 'generated')
    os.makedirs(directory, exist_ok=True)
    for name, text in ((LISTING, generate()), (HEADER, generate_c())):
        path = os.path.join(directory, name)
        with open(path, 'w', encoding='utf-8') as f:
            f.write(text)
        print(f'wrote {path}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
