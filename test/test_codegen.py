# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The compiled kernels are generated from the one RNEA source, never edited by hand."""

import ast
import inspect

import pytest
from spatial_dynamics.backends import codegen


def test_the_committed_kernels_are_a_fresh_generation():
    with open(codegen.TARGET, encoding='utf-8') as f:
        committed = f.read()
    assert committed == codegen.generate(), (
        'backends/_kernels_generated.py is stale: run python -m spatial_dynamics.backends.codegen')


def test_every_arithmetic_statement_of_the_source_is_in_the_generated_kernels():
    """Statement for statement: what touches no storage is copied unchanged."""
    generated = codegen.generate()
    storage = set(codegen.STORES) | {'rows', 'f_body', 'm', 'nonzero', 'fp', 'cp'}
    checked = 0
    for fn in codegen.SOURCES:
        tree = ast.parse(inspect.getsource(fn))
        for node in ast.walk(tree):
            if not isinstance(node, (ast.Assign, ast.AugAssign, ast.Return)):
                continue
            if {n.id for n in ast.walk(node) if isinstance(n, ast.Name)} & storage:
                continue
            assert ast.unparse(node) in generated, ast.unparse(node)
            checked += 1
    assert checked >= 100    # every arithmetic statement of the seven functions (100 now)


@pytest.mark.parametrize('body,message', [
    ('x = vel', 'outside the rules'),
    ('vel[i] = v', 'store a whole tuple'),
    ('a, b = acc[p]', 'acc holds 6 values'),
    ('a, b = rows[i]', 'unpack the whole row'),
])
def test_code_outside_the_rules_is_refused(body, message):
    tree = ast.parse(f'def rnea_kernel(rows, vel, acc):\n    {body}\n')
    with pytest.raises(SyntaxError, match=message):
        codegen._ToFlat().visit(tree.body[0])
