# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Print the flat kernels of :mod:`.codegen` as C, one state at a time.

:class:`_ToC` prints a flat kernel (the output of ``codegen._ToFlat``) as a C function: integer
names ``long``, the rest ``double``, C's precedence. :mod:`.c_lanes` prints the RNEA's kernels
a second time on SIMD lanes, as a subclass of it.
"""

from __future__ import annotations

import ast

# --------------------------------------------------------------------------------------------
# C: the same flat statements, typed

#: C keywords used as names in the source get a trailing underscore.
_C_RESERVED = {'auto', 'case', 'char', 'const', 'default', 'double', 'enum', 'extern', 'float',
               'goto', 'inline', 'int', 'long', 'register', 'restrict', 'short', 'signed',
               'sizeof', 'static', 'struct', 'switch', 'typedef', 'union', 'unsigned', 'void',
               'volatile'}
#: Parameters of the generated kernels that are arrays (the rest are doubles, or int flags).
_C_ARRAYS = {'K', 'q', 'qd', 'qdd', 'dq', 'dv', 'f_body', 'tau', 'work', 'H', 'D', 'mom',
             'ctq', 'Y', 'axes', 'J', 'QR', 'wts', 'res', 'scr', 'lam', 'run', 'seg', 'info',
             'arm', 'T', 'Hkk'}
#: Parameters that are integers: flags, and the joints' code, indices and column.
_C_FLAGS = {'has_fext', 'has_arm', 'both', 'code', 'k', 'kv', 'kj', 'col', 'n', 'row', 'nb'}
#: Kernels whose written arrays never overlap (every caller passes distinct results and
#: scratch): printed ``restrict``, so the compiler keeps values read from one in registers
#: across stores to the others (~4 % fewer instructions for the derivatives).
_C_RESTRICT = {'derivatives_kernel', 'forward_kernel', 'aba_kernel'}
#: ``len(x)`` of an array parameter: the number of velocity coordinates ``nv`` (``q̇``, ``τ``),
#: ``nv * nv`` for M(q), ``nv * 10 NB`` for the regressor.
_C_LENGTH = {'H': 'nv * nv', 'Y': 'nv * 10 * (rows - 1)'}
_C_OPS = {ast.Add: ('+', 10), ast.Sub: ('-', 10), ast.Mult: ('*', 11), ast.Div: ('/', 11)}
_C_COMPARE = {ast.Eq: '==', ast.NotEq: '!=', ast.Lt: '<', ast.LtE: '<=', ast.Gt: '>',
              ast.GtE: '>='}


def _c_name(name: str) -> str:
    return name + '_' if name in _C_RESERVED else name


class _ToC:
    """Print one flat kernel (the output of :class:`_ToFlat`) as a C function.

    Every name is a ``double``, except those that only ever hold integers or truth values
    (``int()`` of a table entry, loop counters, flags: ``long``). Tuple assignments evaluate
    every value before storing any (Python's order); a component product returns its tuple
    through an output array. Expressions keep Python's tree, printed with the parentheses
    Python's own printer uses (C has the same precedence for ``+ - * /`` and unary minus),
    and nothing is contracted into fused multiply-adds (the build passes
    ``-ffp-contract=off``), so each operation rounds as it does in Python.
    """

    def __init__(self, func: ast.FunctionDef, returns: dict) -> None:
        self.func = func
        self.returns = returns          # component name -> number of values it returns
        self.params = [a.arg for a in func.args.args]
        self.ints: set = set()
        self.doubles: set = set()
        self.uses_nv = False
        self.temp = 0
        self.typed = False              # _infer has run

    # -- types -----------------------------------------------------------------------------
    def _is_int(self, node) -> bool:
        if isinstance(node, ast.Constant):
            return isinstance(node.value, (bool, int))
        if isinstance(node, ast.Name):
            return node.id in self.ints or (node.id in self.params and node.id in _C_FLAGS)
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
            return node.func.id in ('int', 'len')
        if isinstance(node, ast.Subscript) and isinstance(node.value, ast.Attribute):
            return True                                       # K.shape[0]
        if isinstance(node, ast.BinOp):
            return (not isinstance(node.op, ast.Div) and self._is_int(node.left)
                    and self._is_int(node.right))
        if isinstance(node, ast.UnaryOp):
            return isinstance(node.op, ast.Not) or self._is_int(node.operand)
        if isinstance(node, ast.IfExp):
            return self._is_int(node.body) and self._is_int(node.orelse)
        return isinstance(node, (ast.Compare, ast.BoolOp))

    def _infer(self) -> None:
        """Type every local: ``long`` if each value it is given is an integer, else double."""
        assigned = {}
        for node in ast.walk(self.func):
            if isinstance(node, ast.Assign):
                for target in node.targets:
                    values = (node.value.elts if isinstance(target, ast.Tuple)
                              and isinstance(node.value, ast.Tuple) else None)
                    names = target.elts if isinstance(target, ast.Tuple) else [target]
                    for j, t in enumerate(names):
                        if isinstance(t, ast.Name):
                            value = values[j] if values else (
                                node.value if not isinstance(target, ast.Tuple) else None)
                            assigned.setdefault(t.id, []).append(value)
            elif isinstance(node, ast.For) and isinstance(node.target, ast.Name):
                ranged = (isinstance(node.iter, ast.Call) and isinstance(node.iter.func, ast.Name)
                          and node.iter.func.id == 'range')
                assigned.setdefault(node.target.id, []).append(
                    ast.Constant(0) if ranged else None)
        locals_ = set(assigned) - set(self.params)
        changed = True
        while changed:      # a name is an integer once all its values are
            changed = False
            for name in locals_ - self.ints:
                values = assigned[name]
                if all(v is not None and self._is_int(v) for v in values):
                    self.ints.add(name)
                    changed = True
        self.doubles = locals_ - self.ints

    # -- expressions -----------------------------------------------------------------------
    def expr(self, node, prec: int = 0) -> str:
        """C text of an expression; parenthesized when its precedence is below ``prec``."""
        if isinstance(node, ast.Constant):
            if isinstance(node.value, bool):
                return '1' if node.value else '0'
            if isinstance(node.value, (int, float)):
                return repr(node.value)
        elif isinstance(node, ast.Name):
            return _c_name(node.id)
        elif isinstance(node, ast.BinOp) and type(node.op) in _C_OPS:
            op, p = _C_OPS[type(node.op)]
            text = f'{self.expr(node.left, p)} {op} {self.expr(node.right, p + 1)}'
            return f'({text})' if p < prec else text
        elif isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
            operand = self.expr(node.operand, 12)
            text = '-' + (f'({operand})' if operand.startswith('-') else operand)
            return f'({text})' if 12 < prec else text
        elif isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.Not):
            return f'!{self.expr(node.operand, 13)}'
        elif isinstance(node, ast.BoolOp):
            op, p = ('&&', 4) if isinstance(node.op, ast.And) else ('||', 3)
            text = f' {op} '.join(self.expr(v, p + 1) for v in node.values)
            return f'({text})' if p < prec else text
        elif (isinstance(node, ast.Compare) and len(node.ops) == 1
              and type(node.ops[0]) in _C_COMPARE):
            text = (f'{self.expr(node.left, 9)} {_C_COMPARE[type(node.ops[0])]} '
                    f'{self.expr(node.comparators[0], 9)}')
            return f'({text})' if 8 < prec else text
        elif isinstance(node, ast.IfExp):
            return (f'({self.expr(node.test, 1)} ? {self.expr(node.body, 1)} : '
                    f'{self.expr(node.orelse, 1)})')
        elif isinstance(node, ast.Subscript):
            return self._subscript(node)
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
            name = node.func.id
            if name == 'int':
                return f'(long){self.expr(node.args[0], 13)}'
            if name == 'len' and isinstance(node.args[0], ast.Name):
                self.uses_nv = True
                return _C_LENGTH.get(node.args[0].id, 'nv')
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
              and isinstance(node.func.value, ast.Name) and node.func.value.id == 'np'
              and node.func.attr in ('sin', 'cos', 'sqrt')):
            return f'{node.func.attr}({self.expr(node.args[0])})'
        raise SyntaxError(f'line {getattr(node, "lineno", "?")}: no C for '
                          f'{ast.unparse(node)!r}')

    def _subscript(self, node: ast.Subscript) -> str:
        base = node.value
        if isinstance(base, ast.Attribute) and base.attr == 'shape':     # K.shape[0]
            return 'rows'
        if not isinstance(base, ast.Name) or base.id not in _C_ARRAYS:
            raise SyntaxError(f'line {node.lineno}: no C for {ast.unparse(node)!r}')
        index = node.slice
        if isinstance(index, ast.Tuple):       # K[i, j], f_body[i, j]: rows of a 2-D table
            row, col = index.elts
            width = 'WIDTH' if base.id == 'K' else '6'
            return f'{base.id}[{self.expr(row, 11)} * {width} + {self.expr(col, 11)}]'
        return f'{base.id}[{self.expr(index)}]'

    # -- statements ------------------------------------------------------------------------
    def block(self, body, depth: int) -> list:
        out = []
        for stmt in body:
            out.extend(self.stmt(stmt, depth))
        return out

    def stmt(self, node, depth: int) -> list:
        pad = '    ' * depth
        if isinstance(node, ast.Assign):
            return self._assign(node, pad)
        if isinstance(node, ast.AugAssign) and type(node.op) in _C_OPS:
            op = _C_OPS[type(node.op)][0]
            return [f'{pad}{self.expr(node.target)} {op}= '
                    f'{self._stored([node.target], node.value)};']
        if isinstance(node, ast.If):
            out = [f'{pad}if ({self.expr(node.test)}) {{'] + self.block(node.body, depth + 1)
            orelse = node.orelse
            while len(orelse) == 1 and isinstance(orelse[0], ast.If):
                out += [f'{pad}}} else if ({self.expr(orelse[0].test)}) {{']
                out += self.block(orelse[0].body, depth + 1)
                orelse = orelse[0].orelse
            if orelse:
                out += [f'{pad}}} else {{'] + self.block(orelse, depth + 1)
            return out + [f'{pad}}}']
        if isinstance(node, ast.For) and isinstance(node.target, ast.Name) and not node.orelse:
            return self._for(node, depth)
        if isinstance(node, ast.While) and not node.orelse:
            return ([f'{pad}while ({self.expr(node.test)}) {{']
                    + self.block(node.body, depth + 1) + [f'{pad}}}'])
        if isinstance(node, ast.Break):
            return [f'{pad}break;']
        if isinstance(node, ast.Continue):
            return [f'{pad}continue;']
        if isinstance(node, ast.Return) and isinstance(node.value, ast.Tuple):
            return [f'{pad}out[{j}] = {self._stored([None], v)};'
                    for j, v in enumerate(node.value.elts)] + [f'{pad}return;']
        if isinstance(node, ast.Return) and node.value is None:
            return [f'{pad}return;']
        if (isinstance(node, ast.Expr) and isinstance(node.value, ast.Call)
                and isinstance(node.value.func, ast.Name) and node.value.func.id in self.returns
                and self.returns[node.value.func.id] == 0):          # f(…) writing an array
            args = ', '.join(self._arguments(node.value.func.id, node.value.args))
            return [f'{pad}{node.value.func.id}{self.SUFFIX}({args});']
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant):
            return []                                                    # the docstring
        raise SyntaxError(f'line {getattr(node, "lineno", "?")}: no C for {ast.unparse(node)!r}')

    def _assign(self, node: ast.Assign, pad: str) -> list:
        target, value = node.targets[-1], node.value
        if len(node.targets) > 1 or isinstance(target, (ast.Name, ast.Subscript)):
            if not all(isinstance(t, (ast.Name, ast.Subscript)) for t in node.targets):
                raise SyntaxError(f'line {node.lineno}: no C for {ast.unparse(node)!r}')
            left = ' = '.join(self.expr(t) for t in node.targets)
            return [f'{pad}{left} = {self._stored(node.targets, value)};']
        names = [self.expr(t) for t in target.elts]
        if (isinstance(value, ast.Call) and isinstance(value.func, ast.Name)
                and value.func.id in self.returns):          # x0, … = component(…)
            if self.returns[value.func.id] != len(names):
                raise SyntaxError(f'line {node.lineno}: {value.func.id} returns '
                                  f'{self.returns[value.func.id]} values')
            r = f'ret{self._next()}_'
            args = ', '.join(self._arguments(value.func.id, value.args))
            return ([f'{pad}{{', f'{pad}    {self.REAL} {r}[{len(names)}];',
                     f'{pad}    {value.func.id}{self.SUFFIX}({args}, {r});']
                    + [f'{pad}    {n} = {r}[{j}];' for j, n in enumerate(names) if n != '_']
                    + [f'{pad}}}'])
        if isinstance(value, ast.Tuple) and len(value.elts) == len(names):
            if len(names) == 1:
                return [f'{pad}{names[0]} = {self.expr(value.elts[0])};']
            temps = [f'tmp{self._next()}_' for _ in names]        # every value, then every store
            kinds = [self._kind(t.id) for t in target.elts]
            values = [f'{pad}    const {k} {t} = {self._stored([e], v)};'
                      for k, t, e, v in zip(kinds, temps, target.elts, value.elts)]
            stores = [f'{pad}    {n} = {t};' for n, t in zip(names, temps)]
            return [f'{pad}{{'] + values + stores + [f'{pad}}}']
        raise SyntaxError(f'line {node.lineno}: no C for {ast.unparse(node)!r}')

    def _for(self, node: ast.For, depth: int) -> list:
        pad, it, i = '    ' * depth, node.iter, _c_name(node.target.id)
        if isinstance(it, ast.Call) and isinstance(it.func, ast.Name) and it.func.id == 'range':
            args = list(it.args)
            step = 1
            if len(args) == 3:
                if not (isinstance(args[2], ast.UnaryOp) and isinstance(args[2].op, ast.USub)
                        and isinstance(args[2].operand, ast.Constant)
                        and args[2].operand.value == 1):
                    raise SyntaxError(f'line {node.lineno}: range steps by 1 or -1 only')
                step, args = -1, args[:2]
            lo, hi = (ast.Constant(0), args[0]) if len(args) == 1 else args
            if step == 1:
                head = f'for ({i} = {self.expr(lo)}; {i} < {self.expr(hi)}; {i}++) {{'
            else:
                head = f'for ({i} = {self.expr(lo)}; {i} > {self.expr(hi)}; {i}--) {{'
            return [pad + head] + self.block(node.body, depth + 1) + [f'{pad}}}']
        if isinstance(it, ast.Name) and it.id in _C_ARRAYS:    # for x in qd: the joint values
            self.uses_nv = True
            j = f'j{self._next()}_'
            return ([f'{pad}for (long {j} = 0; {j} < {_C_LENGTH.get(it.id, "nv")}; {j}++) {{',
                     f'{pad}    {i} = {it.id}[{j}];']
                    + self.block(node.body, depth + 1) + [f'{pad}}}'])
        raise SyntaxError(f'line {node.lineno}: no C for {ast.unparse(node.iter)!r}')

    def _next(self) -> int:
        self.temp += 1
        return self.temp

    # -- types of values (overridden by the lanes) -------------------------------------------
    #: The C type of a real number, and the suffix of the generated functions' names.
    REAL = 'double'
    SUFFIX = ''

    def _kind(self, name: str) -> str:
        return 'long' if name in self.ints else 'double'

    def _stored(self, targets: list, value: ast.expr) -> str:
        """C text of ``value`` as stored into ``targets`` (``None``: the output array)."""
        return self.expr(value)

    def _arguments(self, callee: str, args: list) -> list:
        return [self.expr(a) for a in args]

    def _parameter(self, p: str, written: set) -> list:
        if p in _C_ARRAYS:
            restrict = 'restrict ' if self.func.name in _C_RESTRICT else ''
            return [(f'double *{restrict}' if p in written else 'const double *') + p] + (
                ['long rows'] if p == 'K' else [])
        return [('long ' if p in _C_FLAGS else 'double ') + _c_name(p)]

    # -- the function ----------------------------------------------------------------------
    def function(self) -> str:
        if not self.typed:
            self._infer()
            self.typed = True
        name = self.func.name
        targets = [t for n in ast.walk(self.func) if isinstance(n, ast.Assign)
                   for t in n.targets]
        targets += [n.target for n in ast.walk(self.func) if isinstance(n, ast.AugAssign)]
        written = {t.value.id for t in targets
                   if isinstance(t, ast.Subscript) and isinstance(t.value, ast.Name)}
        params = []
        for p in self.params:
            params += self._parameter(p, written)
        body = self.block(self.func.body, 1)
        if self.returns.get(name):
            params.append(f'{self.REAL} *out')
        used = {n.id for n in ast.walk(self.func) if isinstance(n, ast.Name)}
        head = [f'    (void){_c_name(p)};' for p in self.params if p not in used]
        if self.uses_nv:
            head.append('    const long nv = (long)K[VIDX];')
        kinds = {}
        for n in sorted(self.ints) + sorted(self.doubles):
            if n != '_':
                kinds.setdefault(self._kind(n), []).append(_c_name(n))
        for kind, names in kinds.items():
            for k in range(0, len(names), 12):
                head.append(f'    {kind} {", ".join(names[k:k + 12])};')
        doc = ast.get_docstring(self.func) or ''
        lines, line = [], f'static inline void {name}{self.SUFFIX}('
        for k, p in enumerate(params):
            text = p + (', ' if k + 1 < len(params) else ')')
            if len(line) + len(text.rstrip()) > 99:
                lines.append(line.rstrip())
                line = '    '
            line += text
        return '\n'.join([f'/* {doc} */'] + lines + [line, '{'] + head + body + ['}'])
