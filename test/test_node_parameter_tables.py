# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Parameter tables: one rule per check, typed frozen values, and documents that cannot drift.

The mechanism (:mod:`spatial_dynamics.ros.parameters`) is checked without ROS; the nodes'
tables are checked against the files users read: ``config/<node>.yaml`` and the user guide's
parameter table of each node are exactly what the table generates (set ``UPDATE_DOCS=1`` to
rewrite them after changing a table).
"""

import dataclasses
import math
import os
import re

import pytest
import yaml

from spatial_dynamics.ros.parameters import (
    check, Param, ParameterError, per_joint_values, Table)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def rule_even(name, value):
    """Even numbers only."""
    if value % 2:
        raise ParameterError(f'parameter {name}: {value} is odd')


TABLE = Table('toy', [
    Param('flag', 'bool', False, 'A switch.'),
    Param('count', 'int', 2, 'A count.', bounds=(0, 10), rules=(rule_even,)),
    Param('rate', 'double', 1.5, 'A rate.', unit='Hz', bounds=(0.1, 100.0)),
    Param('mode', 'string', 'a', 'A choice.', choices=('a', 'b')),
    Param('payload.com', 'double[]', [0.0, 0.0, 0.0], 'A point.', unit='m', length=3,
          bounds=(-1e3, 1e3)),
    Param('gains', 'double[]', [0.0], 'Per joint.', per_joint=True, bounds=(0.0, 1e6)),
    Param('names', 'string[]', None, 'Unset by default.', read_only=True),
], header='A toy node.')


@pytest.mark.parametrize('name, value, words', [
    ('flag', 1, ['flag', 'true or false']),
    ('count', 12, ['count', '0 to 10']),
    ('count', 3, ['count', 'odd']),
    ('count', 2.5, ['count']),
    ('rate', math.nan, ['rate', 'finite']),
    ('rate', 1e9, ['rate', '0.1 to 100 Hz']),
    ('mode', 'c', ['mode', "'c'", "['a', 'b']"]),
    ('payload.com', [0.0, 0.0], ['payload.com', '3 values']),
    ('payload.com', [0.0, 0.0, 1e9], ['payload.com', '-1000 to 1000']),
    ('gains', [], ['gains', 'one value for all joints']),
    ('gains', [-1.0], ['gains']),
    ('names', 'abc', ['names', 'list of strings']),
])
def test_each_rule_refuses_naming_the_parameter(name, value, words):
    with pytest.raises(ParameterError) as err:
        check(TABLE.by_name[name], value)
    for word in words:
        assert word in str(err.value), (word, str(err.value))


def test_refusals_write_numbers_as_given():
    """An integer is written in full (not 1e+09), a float as the number it is."""
    from spatial_dynamics.ros.config import PARAMETERS
    from spatial_dynamics.ros.usage import usage
    cases = [(PARAMETERS.by_name['thread_priority'], 1_000_000_000,
              'need a value from 0 to 99, got 1000000000'),
             (PARAMETERS.by_name['trajectory_max_bytes'], 100,
              'need a value from 1024 to 2147483648 bytes, got 100'),
             (TABLE.by_name['rate'], 12345678.9,
              'need a value from 0.1 to 100 Hz, got 12345678.9'),
             (TABLE.by_name['rate'], 1e9, 'got 1e+09')]   # a float given as 1e9 is 1e9
    for param, value, words in cases:
        with pytest.raises(ParameterError) as err:
            check(param, value)
        assert words in str(err.value), str(err.value)
    # the documents and --help say the same bounds
    assert '1024 .. 2147483648' in PARAMETERS.markdown()
    assert '1024 .. 2147483648' in usage(PARAMETERS, 'summary', 'page')


def test_values_are_typed_frozen_and_checked():
    params = TABLE.defaults()
    assert params.payload_com == (0.0, 0.0, 0.0) and params.names is None
    assert params.count == 2 and isinstance(params.rate, float)
    with pytest.raises(dataclasses.FrozenInstanceError):
        params.count = 4
    changed = TABLE.changed(params, {'count': 4, 'gains': [1, 2]})
    assert (changed.count, changed.gains, params.count) == (4, (1.0, 2.0), 2)
    with pytest.raises(ParameterError, match='unknown parameter'):
        TABLE.changed(params, {'nope': 1})
    assert TABLE.live == frozenset(TABLE.names) - {'names'}
    assert per_joint_values(TABLE.by_name['gains'], (2.0,), ('a', 'b', 'c')) == (2.0,) * 3
    with pytest.raises(ParameterError, match='2 values for 3 joints'):
        per_joint_values(TABLE.by_name['gains'], (1.0, 2.0), ('a', 'b', 'c'))


def test_generated_yaml_loads_to_the_defaults():
    doc = yaml.safe_load(TABLE.yaml())
    assert doc == {'toy': {'ros__parameters': {
        'flag': False, 'count': 2, 'rate': 1.5, 'mode': 'a', 'payload': {'com': [0.0, 0.0, 0.0]},
        'gains': [0.0]}}}
    table = TABLE.markdown().splitlines()
    assert len(table) == 2 + len(TABLE.params)
    assert '| `rate` | double | `1.5` | Hz | 0.1 .. 100 | A rate. |' in table
    assert 'Even numbers only' in TABLE.markdown()


def tables():
    """Return every node's table (imported here: the sim's module needs the ROS messages)."""
    pytest.importorskip('rclpy')
    from spatial_dynamics.ros.config import PARAMETERS as INVERSE_DYNAMICS
    from spatial_dynamics.sim.node import PARAMETERS as SIM
    return {'sim': SIM, 'inverse_dynamics': INVERSE_DYNAMICS}


#: The user-guide page that carries each node's table.
DOC_PAGE = {'sim': 'simulator.md', 'inverse_dynamics': 'node.md'}


def readme_block(text: str, node: str) -> str:
    match = re.search(rf'<!-- parameters of {node}: [^\n]*-->\n(.*?)<!-- end of parameters of '
                      rf'{node} -->', text, re.S)
    assert match, f'no parameter block of {node} in doc/{DOC_PAGE[node]}'
    return match.group(1)


@pytest.mark.parametrize('node', ['sim', 'inverse_dynamics'])
def test_config_file_and_readme_are_the_table(node):
    table = tables()[node]
    config = os.path.join(ROOT, 'config', f'{node}.yaml')
    readme = os.path.join(ROOT, 'doc', DOC_PAGE[node])
    with open(readme, encoding='utf-8') as f:
        text = f.read()
    if os.environ.get('UPDATE_DOCS'):
        with open(config, 'w', encoding='utf-8') as f:
            f.write(table.yaml())
        old = readme_block(text, node)
        start = text.index(f'<!-- parameters of {node}: ')
        start = text.index('\n', start) + 1
        text = text[:start] + table.markdown() + text[start + len(old):]
        with open(readme, 'w', encoding='utf-8') as f:
            f.write(text)
    with open(config, encoding='utf-8') as f:
        assert f.read() == table.yaml(), f'config/{node}.yaml differs from its table'
    assert readme_block(text, node) == table.markdown(), \
        f'the table of {node} in doc/{DOC_PAGE[node]} differs'
    # and every default in the file is what the node declares
    declared = yaml.safe_load(table.yaml())[node]['ros__parameters']
    for param in table.params:
        if param.default is not None:
            value = declared
            for key in param.name.split('.'):     # payload.mass is written nested
                value = value[key]
            assert value == param.default, param.name
