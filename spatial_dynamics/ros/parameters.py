# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Parameter tables: each parameter of a node written once, everything else derived from it.

In the spirit of ros2_controllers' ``generate_parameter_library`` (a YAML file from which the
declarations, the validation, a typed ``params_`` struct and the documentation are generated),
without its C++ code generation: a node's parameters are a :class:`Table` of :class:`Param`
entries, each with its name, type, default, unit, bounds or choices, shape (fixed length, or
one value per model joint), whether it is read-only, its description and any named rules.
From the table come

* the declarations with their ``ParameterDescriptor`` (:meth:`Table.declare`),
* the validation, one function per rule (:func:`check`; shape and bounds from the entry, the
  entry's ``rules`` after them), reused by every entry that has the rule,
* a typed, frozen ``Params`` the code reads (:meth:`Table.values`, :meth:`Table.changed`):
  ``params.payload_mass`` for ``payload.mass``, arrays as tuples,
* the documentation: the node's ``config/<node>.yaml`` (:meth:`Table.yaml`) and the README's
  parameter table (:meth:`Table.markdown`), which a test compares with the files.

Pure Python: ROS is imported only inside :meth:`Table.descriptor` and :meth:`Table.declare`,
so a table, its documents and a node's ``--help`` load without rclpy's start-up.
"""

from __future__ import annotations

from dataclasses import dataclass, field, make_dataclass, replace
import math
import textwrap
from typing import Any, Callable, Dict, Iterable, Mapping, Optional, Sequence, Tuple

#: The parameter types a table may use (ROS 2 names).
TYPES = ('bool', 'int', 'double', 'string', 'double[]', 'int[]', 'string[]')


class ConfigError(ValueError):
    """A parameter value or robot description that cannot be used; the message says why."""


class ParameterError(ConfigError):
    """A parameter value that cannot be used; the message names the parameter and says why."""


@dataclass(frozen=True)
class Param:
    """One parameter of a node, as written once in its table.

    ``default`` None means unset (arrays only: rclpy cannot infer the type of an empty list).
    ``bounds`` is a closed interval for a number, or for each element of an array of numbers;
    ``length`` an exact number of elements; ``per_joint`` says a ``double[]`` holds one value
    for every joint or one per model joint (checked against the model by
    :func:`per_joint_values`, the rest of the shape here). ``rules`` are further checks,
    ``rule(name, value)`` raising :class:`ParameterError`, run after the entry's own.
    """

    name: str
    type: str
    default: Any
    description: str
    unit: str = ''
    bounds: Optional[Tuple[float, float]] = None
    choices: Tuple[str, ...] = ()
    length: Optional[int] = None
    per_joint: bool = False
    read_only: bool = False
    rules: Tuple[Callable[[str, Any], None], ...] = ()

    def __post_init__(self) -> None:
        if self.type not in TYPES:
            raise ValueError(f'parameter {self.name}: type {self.type!r} is not one of {TYPES}')
        if self.default is None and not self.type.endswith('[]'):
            raise ValueError(f'parameter {self.name}: only an array may be unset')

    @property
    def field(self) -> str:
        """The attribute of ``Params`` holding this parameter (dots become underscores)."""
        return self.name.replace('.', '_')

    @property
    def live(self) -> bool:
        """Whether the parameter may change while the node runs."""
        return not self.read_only


# --------------------------------------------------------------------------------------------
# Validation: one function per rule

def _number(name: str, value: Any, kind: type) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(f'parameter {name}: need a number, got {value!r}')
    if kind is int and not isinstance(value, int):
        raise ParameterError(f'parameter {name}: need an integer, got {value!r}')
    if kind is float and not math.isfinite(value):
        raise ParameterError(f'parameter {name}: need a finite number, got {value}')
    return kind(value)


def number_text(value: float) -> str:
    """Write a number as it was given: an integer in full, a float in its shortest form.

    ``1000000000`` stays ``1000000000`` (``:g`` wrote ``1e+09``, as if a float had been given,
    and ``2147483648`` as ``2.14748e+09``, another number); a float is written by ``:g`` when
    that is the same number (``0.001``, ``3600``), else by ``repr`` (``12345678.9``).
    """
    if isinstance(value, int) and not isinstance(value, bool):
        return str(value)
    text = f'{value:g}'
    return text if float(text) == value else repr(float(value))


def within(name: str, value: float, bounds: Tuple[float, float], unit: str = '') -> float:
    """Return ``value`` if it lies in the closed interval ``bounds``."""
    lo, hi = bounds
    if not lo <= value <= hi:
        raise ParameterError(f'parameter {name}: need a value from {number_text(lo)} to '
                             f'{number_text(hi)}{" " + unit if unit else ""}, got '
                             f'{number_text(value)}')
    return value


def one_of(name: str, value: str, choices: Sequence[str]) -> str:
    """Return ``value`` if it is one of ``choices``."""
    if value not in choices:
        raise ParameterError(f'parameter {name}: {value!r} is not one of {list(choices)}')
    return value


def of_length(name: str, values: Sequence, length: int, unit: str = '') -> Sequence:
    """Return ``values`` if it has exactly ``length`` elements."""
    if len(values) != length:
        raise ParameterError(f'parameter {name}: need {length} values'
                             f'{" (" + unit + ")" if unit else ""}, got {list(values)}')
    return values


def distinct(name: str, values: Sequence[str]) -> Sequence[str]:
    """No name repeated.

    (The first line of a rule's docstring is its constraint in the generated documentation.)
    """
    if len(set(values)) != len(values):
        raise ParameterError(f'parameter {name}: names repeated in {list(values)}')
    return values


def check(param: Param, value: Any) -> Any:
    """Return ``value`` as ``Params`` holds it (tuples for arrays), or raise ParameterError.

    The entry's type, choices, length and bounds, then its ``rules``; ``None`` (unset) is
    kept for an array whose default is unset.
    """
    name = param.name
    if value is None:
        if param.default is not None:
            raise ParameterError(f'parameter {name}: needs a value')
        return None
    if param.type == 'bool':
        if not isinstance(value, bool):
            raise ParameterError(f'parameter {name}: need true or false, got {value!r}')
    elif param.type in ('int', 'double'):
        value = _number(name, value, int if param.type == 'int' else float)
        if param.bounds is not None:
            within(name, value, param.bounds, param.unit)
    elif param.type == 'string':
        if not isinstance(value, str):
            raise ParameterError(f'parameter {name}: need a string, got {value!r}')
        if param.choices:
            one_of(name, value, param.choices)
    elif param.type == 'string[]':
        if isinstance(value, str) or not all(isinstance(x, str) for x in value):
            raise ParameterError(f'parameter {name}: need a list of strings, got {value!r}')
        value = tuple(value)
    else:   # double[], int[]
        if isinstance(value, str):
            raise ParameterError(f'parameter {name}: need a list of numbers, got {value!r}')
        value = tuple(_number(name, x, int if param.type == 'int[]' else float)
                      for x in value)
        if param.length is not None:
            of_length(name, value, param.length, param.unit)
        if param.per_joint and not value:
            raise ParameterError(f'parameter {name}: need one value for all joints or one per '
                                 'joint, got none')
        if param.bounds is not None:
            for x in value:
                within(name, x, param.bounds, param.unit)
    for rule in param.rules:
        rule(name, value)
    return value


def per_joint_values(param: Param, value: Sequence[float], joint_names: Sequence[str]
                     ) -> Tuple[float, ...]:
    """Return one value per joint of ``joint_names`` from a ``per_joint`` parameter's value.

    One value applies to every joint; otherwise there must be one per joint, in that order.
    """
    if len(value) == 1:
        return tuple(value) * len(joint_names)
    if len(value) != len(joint_names):
        raise ParameterError(
            f'parameter {param.name}: {len(value)} values for {len(joint_names)} joints '
            f'{list(joint_names)} (need one for all, or one per joint in the order of the '
            'joints parameter, or the URDF order when it is unset)')
    return tuple(value)


# --------------------------------------------------------------------------------------------
# A node's table

class Table:
    """The parameters of one node, each written once; see the module docstring."""

    def __init__(self, node: str, params: Iterable[Param], header: str = '') -> None:
        self.node = node
        self.header = header         # the comment at the top of the node's parameter file
        self.params: Tuple[Param, ...] = tuple(params)
        self.by_name: Dict[str, Param] = {p.name: p for p in self.params}
        if len(self.by_name) != len(self.params):
            raise ValueError(f'{node}: a parameter name is repeated')
        self.Params = make_dataclass(
            ''.join(part.title() for part in node.split('_')) + 'Params',
            [(p.field, Any, field(default=None)) for p in self.params], frozen=True)
        self.Params.__doc__ = f'The checked parameters of node {node!r}, one field each.'

    def __iter__(self):
        """Iterate over the :class:`Param` entries, in table order."""
        return iter(self.params)

    @property
    def names(self) -> Tuple[str, ...]:
        """Every parameter name, in table order."""
        return tuple(p.name for p in self.params)

    @property
    def live(self) -> frozenset:
        """The names of the parameters that may change while the node runs."""
        return frozenset(p.name for p in self.params if p.live)

    def defaults(self) -> Any:
        """Return ``Params`` with every default."""
        return self.values({})

    def values(self, raw: Mapping[str, Any]) -> Any:
        """Check raw values by name (missing ones take their default); return ``Params``."""
        unknown = set(raw) - set(self.by_name)
        if unknown:
            raise ParameterError(f'unknown parameter(s) {sorted(unknown)} of {self.node}')
        return self.Params(**{p.field: check(p, raw.get(p.name, p.default))
                              for p in self.params})

    def changed(self, params: Any, changes: Mapping[str, Any]) -> Any:
        """``params`` with ``changes`` (raw values by name) checked and applied."""
        checked = {}
        for name, value in changes.items():
            if name not in self.by_name:
                raise ParameterError(f'unknown parameter {name} of {self.node}')
            checked[self.by_name[name].field] = check(self.by_name[name], value)
        return replace(params, **checked)

    # -- declaration (rclpy) --------------------------------------------------------------------
    def descriptor(self, param: Param):
        """Return the ``rcl_interfaces/ParameterDescriptor`` of ``param``."""
        from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor
        result = ParameterDescriptor(description=_sentence(param), read_only=param.read_only)
        if param.type == 'double' and param.bounds is not None:
            result.floating_point_range = [FloatingPointRange(
                from_value=float(param.bounds[0]), to_value=float(param.bounds[1]), step=0.0)]
        constraints = _constraints(param)
        if constraints:
            result.additional_constraints = constraints
        return result

    def declare(self, node) -> Any:
        """Declare every parameter on ``node`` (an rclpy Node); return the checked ``Params``.

        Raises :class:`ParameterError` naming the first unusable start-up value.
        """
        from rclpy.parameter import Parameter
        unset = {'double[]': Parameter.Type.DOUBLE_ARRAY,
                 'int[]': Parameter.Type.INTEGER_ARRAY,
                 'string[]': Parameter.Type.STRING_ARRAY}
        raw = {}
        for p in self.params:
            default = unset[p.type] if p.default is None else _ros_value(p.default)
            raw[p.name] = node.declare_parameter(p.name, default, self.descriptor(p)).value
        return self.values(raw)

    # -- documentation --------------------------------------------------------------------------
    def yaml(self) -> str:
        """Return the node's parameter file: each parameter, its default, described above it."""
        lines = [f'# {line}' if line else '#' for line in self.header.splitlines()]
        lines += [f'{self.node}:', '  ros__parameters:']
        group = ''
        for p in self.params:
            *prefix, key = p.name.split('.')      # payload.mass is written nested
            if '.'.join(prefix) != group:
                group = '.'.join(prefix)
                if group:
                    lines.append(f'    {group}:')
            indent = '    ' + '  ' * len(prefix)
            text = f'{p.name} ({_type_text(p)}): {_sentence(p)}'
            constraints = _constraints(p)
            if constraints:
                text += f' Constraints: {constraints}.'
            lines += textwrap.wrap(text, 99 - len(indent) - 2, initial_indent=indent + '# ',
                                   subsequent_indent=indent + '# ')
            if p.default is None:
                lines.append(f'{indent}# {key}: []   (unset by default)')
            else:
                lines.append(f'{indent}{key}: {_yaml_value(p.default)}')
        return '\n'.join(lines) + '\n'

    def markdown(self) -> str:
        """Return the README's table of the parameters: name, type, default, unit, rules, text."""
        rows = ['| parameter | type | default | unit | constraints | description |',
                '|---|---|---|---|---|---|']
        for p in self.params:
            default = 'unset' if p.default is None else f'`{_yaml_value(p.default)}`'
            rows.append(f'| `{p.name}` | {_type_text(p)} | {default} | {p.unit or "-"} | '
                        f'{_constraints(p) or "-"} | {p.description} |')
        return '\n'.join(rows) + '\n'


def _ros_value(value: Any) -> Any:
    return list(value) if isinstance(value, tuple) else value


def _yaml_value(value: Any) -> str:
    if isinstance(value, bool):
        return 'true' if value else 'false'
    if isinstance(value, str):
        return "''" if not value else (repr(value) if ':' in value or '#' in value else value)
    if isinstance(value, (list, tuple)):
        return '[' + ', '.join(_yaml_value(x) for x in value) + ']'
    if isinstance(value, float):
        return repr(value)
    return str(value)


def _type_text(p: Param) -> str:
    return p.type + (', read-only' if p.read_only else '')


def _sentence(p: Param) -> str:
    return p.description + (f' Unit: {p.unit}.' if p.unit else '')


def _constraints(p: Param) -> str:
    parts = []
    if p.choices:
        parts.append('one of ' + ', '.join(p.choices))
    if p.bounds is not None:
        parts.append(f'{number_text(p.bounds[0])} .. {number_text(p.bounds[1])}'
                     + (' each' if p.type.endswith('[]') else ''))
    if p.length is not None:
        parts.append(f'{p.length} values')
    if p.per_joint:
        parts.append('one value for all joints or one per joint')
    parts += [rule.__doc__.strip().splitlines()[0].rstrip('.') for rule in p.rules
              if rule.__doc__]
    return '; '.join(parts)
