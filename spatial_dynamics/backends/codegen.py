# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Generate the numba kernels from the one source of each algorithm in :mod:`..algorithms`.

The component kernels there (:mod:`~spatial_dynamics.algorithms.components`,
:mod:`~spatial_dynamics.algorithms.rnea`, :mod:`~spatial_dynamics.algorithms.crba`,
:mod:`~spatial_dynamics.algorithms.momentum`) are plain
Python over tuples and lists. numba compiles such code
only slowly and with allocations, so this module rewrites their syntax tree statement for
statement onto flat float64 arrays and writes ``_kernels_generated.py``; nothing of the
arithmetic changes (same expressions, same order), so every backend computes the same
numbers. The rewriting rules, each a change of storage only:

==============================================  ==============================================
source (Python backends)                        generated (numba)
==============================================  ==============================================
``a, b, … = rows[i]`` (the whole row)           ``a = K[i, 0]; b = K[i, 1]; …`` (``int()`` for
                                                the integer columns; ``_`` skipped)
``x0, …, x5 = vel[p]`` (``Xup acc vel frc IC``) ``x0 = work[p * WORK + VEL + 0]; …``
``vel[i] = (x0, …, x5)``                        ``work[i * WORK + VEL + 0] = x0; …``
``fp = frc[p]`` then ``fp[j] += e``             ``work[p * WORK + FRC + j] += e``
``H[…] = …`` (any other array argument)         unchanged
``fe0, …, fe5 = f_body[i]``                     ``fe0 = f_body[i, 0]; …``
``nonzero(x)``, ``m.sin``, ``len(rows)``        ``x != 0.0``, ``np.sin``, ``K.shape[0]``
==============================================  ==============================================

Run ``python -m spatial_dynamics.backends.codegen`` after changing the source; a test
compares the committed file with a fresh generation.
"""

from __future__ import annotations

import ast
import inspect
import os
import sys
import textwrap

from . import layout
from ..algorithms import components, crba, momentum, rnea

#: Per-body scratch ``work``: Xup = (E, r) (12), v (6), a (6), f (6), composite inertia
#: (m, h, Ibar) (10) per body, flat.
STORES = {'Xup': ('XUP', 0, 12), 'vel': ('VEL', 12, 6), 'acc': ('ACC', 18, 6),
          'frc': ('FRC', 24, 6), 'IC': ('ICS', 30, 10)}
WORK = 40
#: The functions translated, in order (a function is generated after those it calls).
SOURCES = (components.X_motion, components.XT_force, components.I_motion, components.XT_I_X,
           rnea.xup_kernel, rnea.rnea_kernel, crba.crba_kernel, momentum.momentum_kernel)
#: Parameters of the generated functions (the source's, with the stores replaced by work).
SIGNATURES = {'xup_kernel': 'K, q, work',
              'rnea_kernel': 'K, q, qd, qdd, gx, gy, gz, f_body, has_fext, tau, work',
              'crba_kernel': 'K, work, H',
              'momentum_kernel': 'K, q, qd, mom, ctq, work'}
TARGET = os.path.join(os.path.dirname(os.path.abspath(__file__)), '_kernels_generated.py')


class _ToFlat(ast.NodeTransformer):
    """Rewrite one kernel's statements onto flat arrays (rules in the module docstring)."""

    def __init__(self) -> None:
        self.aliases = {}   # name -> (store, index expression)

    # -- helpers -----------------------------------------------------------------------------
    @staticmethod
    def _slot(store: str, index: ast.expr, j: int) -> ast.Subscript:
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
                and node.value.id in STORES):
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
            if len(names) != STORES[store][2]:
                raise SyntaxError(f'line {node.lineno}: {store} holds {STORES[store][2]} values')
            return [self._assign(n, self._slot(store, value.slice, j), node)
                    for j, n in enumerate(names) if n != '_']
        if store and isinstance(target, ast.Name):               # fp = frc[p]
            self.aliases[target.id] = (store, value.slice)
            return None
        if self._store_of(target):                               # vel[i] = (…)
            if not isinstance(value, (ast.Tuple, ast.List)):
                raise SyntaxError(f'line {node.lineno}: store a whole tuple')
            store = target.value.id
            if len(value.elts) != STORES[store][2]:
                raise SyntaxError(f'line {node.lineno}: {store} holds {STORES[store][2]} values')
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
        self.generic_visit(node)
        if isinstance(node.func, ast.Name) and node.func.id == 'nonzero':
            return ast.Compare(node.args[0], [ast.NotEq()], [ast.Constant(0.0)])
        return node

    def visit_Attribute(self, node: ast.Attribute):
        if isinstance(node.value, ast.Name) and node.value.id == 'm':
            return ast.Attribute(ast.Name('np', ast.Load()), node.attr, ast.Load())
        return self.generic_visit(node)

    def visit_Name(self, node: ast.Name):
        if node.id in STORES or node.id in ('rows', 'm') or node.id in self.aliases:
            raise SyntaxError(f'line {node.lineno}: {node.id!r} used outside the rules')
        return node


def _kernel_source(fn) -> str:
    tree = ast.parse(textwrap.dedent(inspect.getsource(fn)))
    func = tree.body[0]
    func.body = [s for s in func.body if not (isinstance(s, ast.Expr)
                                              and isinstance(s.value, ast.Constant))]
    func.returns = None
    if fn.__name__ in SIGNATURES:
        func.args = ast.parse(f'def f({SIGNATURES[fn.__name__]}): pass').body[0].args
    func.decorator_list = [ast.parse('numba.njit(inline="always", **JIT)').body[0].value]
    func = _ToFlat().visit(func)
    ast.fix_missing_locations(func)
    func.body.insert(0, ast.Expr(ast.Constant(
        f'Run {fn.__module__.split(".")[-1]}.{fn.__name__} of the algorithms, generated from it.')))
    return ast.unparse(func)


def generate() -> str:
    """Return the text of ``_kernels_generated.py``."""
    consts = {name: getattr(rnea, name) for name in ('RX', 'RY', 'RZ', 'RA', 'PR')}
    header = f'''\
# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
# flake8: noqa
"""Kernels generated from :mod:`spatial_dynamics.algorithms`: do not edit.

Change the source and run ``python -m spatial_dynamics.backends.codegen``.
"""
import numba
import numpy as np

JIT = dict(cache=True, fastmath=False, error_model='numpy')
{chr(10).join(f'{k} = {v}' for k, v in consts.items())}
WORK = {WORK}
{chr(10).join(f'{const} = {offset}' for const, offset, _ in STORES.values())}
'''
    body = '\n\n\n'.join(_kernel_source(fn) for fn in SOURCES)
    return header + '\n\n' + body + '\n'


def main() -> int:
    """Write ``_kernels_generated.py`` next to this module."""
    text = generate()
    with open(TARGET, 'w', encoding='utf-8') as f:
        f.write(text)
    print(f'wrote {TARGET}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
