# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Print the flat kernels of :mod:`.codegen` as C: one state at a time, and in SIMD lanes.

:class:`_ToC` prints a flat kernel (the output of ``codegen._ToFlat``) as a C function;
:class:`_ToCLanes` prints the RNEA's kernels a second time on GCC/Clang vectors of 2, 4 or 8
states (:func:`lanes_c`): table values stay scalars, state values become lanes, each lane
the scalar kernel's operations in the same order (bit for bit the same results).
"""

from __future__ import annotations

import ast

from ..joints import joint_motion, joint_torque, joint_transform, joint_velocity, rotation_product
from ..algorithms import components, rnea

# --------------------------------------------------------------------------------------------
# C: the same flat statements, typed

#: C keywords used as names in the source get a trailing underscore.
_C_RESERVED = {'auto', 'case', 'char', 'const', 'default', 'double', 'enum', 'extern', 'float',
               'goto', 'inline', 'int', 'long', 'register', 'restrict', 'short', 'signed',
               'sizeof', 'static', 'struct', 'switch', 'typedef', 'union', 'unsigned', 'void',
               'volatile'}
#: Parameters of the generated kernels that are arrays (the rest are doubles, or int flags).
_C_ARRAYS = {'K', 'q', 'qd', 'qdd', 'dq', 'f_body', 'tau', 'work', 'H', 'mom', 'ctq', 'Y',
             'axes', 'J', 'QR', 'wts', 'res', 'scr', 'lam', 'run',
             'info'}
#: Parameters that are integers: flags, and the joints' code, indices and column.
_C_FLAGS = {'has_fext', 'both', 'code', 'k', 'kv', 'kj', 'col', 'n', 'row', 'nb'}
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
            return [('double *' if p in written else 'const double *') + p] + (
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


#: The kernels printed a second time on lanes, and the arrays holding one value per state.
LANE_SOURCES = (components.cross, components.X_motion, components.XT_force,
                components.XT_force_plus, components.I_motion, rotation_product, joint_transform,
                joint_motion, joint_velocity, joint_torque, rnea.xup_kernel, rnea.rnea_kernel)
_LANE_ARRAYS = {'q', 'qd', 'qdd', 'f_body', 'tau', 'work'}


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
            return [('' if p in written else 'const ') + f'{self.REAL} *{p}']
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
        for (long k = 0; k < nv; k++)
            for (int s = 0; s < {L}; s++)
                TAU[(b + s) * nv + k] = tau[k][s];
    }}
}}
"""

#: How the lane kernels are compiled: two lanes (SSE2, NEON: every 64-bit target), and on
#: x86-64 four for CPUs with AVX and eight with AVX-512F, chosen at run time.
_LANES_HEAD = """\
/* ------------------------------------------------------------------------------------------
 * The same RNEA on several states at once (SIMD across the states of a batch): the kernels
 * printed again by codegen._ToCLanes on GCC and Clang vector extensions. rnea_batch_lanes
 * runs as many states of a batch as fill the lanes and returns how many; a compiler without
 * vector extensions gets SD_LANES undefined, and the batch runs the scalar kernels. */
#if defined(__GNUC__) || defined(__clang__)
#define SD_LANES 8      /* rnea_batch_lanes is defined: up to 8 states at once */
#include <stdint.h>
#include <stdlib.h>
#if defined(__x86_64__)
#define SD_AVX 1
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
#endif  /* vector extensions */
"""


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
                           kernels='\n\n'.join(kernels), **each)


def lanes_c(returns: dict, flat) -> str:
    """Return the C of the lane kernels: 2 lanes, and on x86-64 4 with AVX, 8 with AVX-512F.

    ``flat(fn)`` is the flat syntax tree of a source function (:func:`.codegen._flat`).
    """
    wide = ''.join(
        '#ifdef __clang__\n#pragma clang attribute push (__attribute__((target('
        f'"{isa}"))), apply_to = function)\n#else\n#pragma GCC push_options\n'
        f'#pragma GCC target("{isa}")\n#endif\n' + _lanes_c(returns, lanes, flat)
        + '#ifdef __clang__\n#pragma clang attribute pop\n#else\n#pragma GCC pop_options\n'
        '#endif\n\n' for lanes, isa in ((4, 'avx'), (8, 'avx512f')))
    return (_LANES_HEAD + _lanes_c(returns, 2, flat) + '\n#ifdef SD_AVX\n' + wide
            + '#endif  /* SD_AVX */\n\n' + _LANES_TAIL)
