# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The compiled kernels are generated from the one RNEA source, never edited by hand."""

import ast
import inspect

import pytest
from spatial_dynamics.backends import codegen


def test_the_built_extension_is_compiled_from_the_current_source():
    """The extension records the SHA-256 of the header it was built from: a fresh generation.

    The generated kernels are build products (written into the build directory by setup.py);
    a build older than a change to the algorithms fails here until the package is built again.
    """
    import hashlib
    from spatial_dynamics.backends import compiled
    if compiled.ext is None:
        pytest.fail(f'the compiled kernels are not built: {compiled.FAILURE}')
    fresh = hashlib.sha256(codegen.generate_c().encode('utf-8')).hexdigest()
    assert compiled.ext.KERNELS_SHA256 == fresh, (
        'the compiled kernels are older than spatial_dynamics/algorithms or backends/codegen.py:'
        ' build the package again (colcon build / scripts/dev)')


def test_the_generation_is_a_function_of_the_source_alone(tmp_path):
    """Two generations are the same text, and the command writes exactly them."""
    assert codegen.generate_c() == codegen.generate_c()
    assert codegen.main([str(tmp_path)]) == 0
    assert (tmp_path / codegen.HEADER).read_text(encoding='utf-8') == codegen.generate_c()
    assert (tmp_path / codegen.LISTING).read_text(encoding='utf-8') == codegen.generate()
    assert not (tmp_path / 'x' / 'y').exists() and codegen.main(['a', 'b']) == 2


def test_every_arithmetic_statement_of_the_source_is_in_the_generated_kernels():
    """Statement for statement: what touches no storage is copied unchanged."""
    generated = codegen.generate()
    storage = set(codegen.WIDTHS) | {'rows', 'f_body', 'm', 'nonzero', 'fp', 'cp'}
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
    ('x = f(*q)', r'\* only on a store read whole'),
])
def test_code_outside_the_rules_is_refused(body, message):
    tree = ast.parse(f'def rnea_kernel(rows, vel, acc):\n    {body}\n')
    with pytest.raises(SyntaxError, match=message):
        codegen._ToFlat().visit(tree.body[0])


def test_a_store_read_whole_into_a_call_and_a_product_stored_whole():
    """``f(*vel[p])`` passes the six slots of vel[p]; ``frc[p] = f(…)`` stores each result."""
    tree = ast.parse('def rnea_kernel(rows, vel, frc):\n'
                     '    frc[p] = f(a, *vel[p + 1], b)\n')
    flat = ast.unparse(codegen._ToFlat().visit(tree.body[0]))
    slots = ', '.join(f'work[(p + 1) * WORK + VEL + {j}]' for j in range(6))
    names = [f'stored1_{j}' for j in range(6)]
    assert f"{', '.join(names)} = f(a, {slots}, b)" in flat, flat
    for j, name in enumerate(names):
        assert f'work[p * WORK + FRC + {j}] = {name}' in flat, flat


def test_every_arithmetic_assignment_is_a_c_statement_as_written():
    """``x = expression`` of the source is ``x = expression;`` in C, character for character."""
    generated = codegen.generate_c()
    storage = set(codegen.WIDTHS) | {'rows', 'f_body', 'm', 'nonzero', 'fp', 'cp'}
    checked = 0
    for fn in codegen.SOURCES:
        tree = ast.parse(inspect.getsource(fn))
        for node in ast.walk(tree):
            if not (isinstance(node, ast.Assign) and len(node.targets) == 1
                    and isinstance(node.targets[0], ast.Name)
                    and isinstance(node.value, ast.BinOp)):
                continue
            if {n.id for n in ast.walk(node) if isinstance(n, ast.Name)} & storage:
                continue
            assert f'{ast.unparse(node)};' in generated, ast.unparse(node)
            checked += 1
    assert checked >= 40


def test_tuple_assignments_evaluate_every_value_before_storing():
    """``a, b = b, a`` swaps in C as in Python (temporaries, then the stores)."""
    func = ast.parse('def xup_kernel(K, q, work):\n    a, b = b + 1.0, a\n').body[0]
    text = codegen._ToC(func, {}).function()
    body = [line.strip() for line in text.splitlines()]
    first, second = body.index('a = tmp1_;'), body.index('b = tmp2_;')
    assert body.index('const double tmp1_ = b + 1.0;') < first
    assert body.index('const double tmp2_ = a;') < first < second


@pytest.mark.parametrize('body', ['x = y ** 2', 'x = y // 2', 'x = [y]',
                                  'for i in range(0, 9, 2):\n        pass'])
def test_code_without_a_c_translation_is_refused(body):
    func = ast.parse(f'def xup_kernel(K, q, work):\n    {body}\n').body[0]
    with pytest.raises(SyntaxError, match='no C for|steps by 1'):
        codegen._ToC(func, {}).function()


def test_the_flat_python_kernels_compute_what_the_source_computes(rng):
    """The flat-array listing (the rewrite the C is printed from) run on Python floats."""
    import numpy as np
    import spatial_dynamics as sd
    from spatial_dynamics.backends import layout, python
    flat = codegen.flat_module()
    from urdf_gen import random_tree_urdf
    model = sd.Model.from_urdf(random_tree_urdf(np.random.default_rng(5), 9, branching=True,
                                                mimic=True))
    lay, n = layout.of(model), model.nq
    q, qd, qdd = rng.normal(size=(3, n))
    work = np.zeros(lay.table.shape[0] * flat.WORK)
    tau = np.zeros(n)
    flat.xup_kernel(lay.table, q, work)
    flat.rnea_kernel(lay.table, q, qd, qdd, 0.5, 0.0, -9.8, np.zeros((1, 6)), False, tau, work)
    expected = python.rnea_rows(lay.rows, q.tolist(), qd.tolist(), qdd.tolist(), (0.5, 0.0, -9.8))
    assert tau.tolist() == expected
    H = np.zeros(n * n)
    flat.crba_kernel(lay.table, work, H)
    assert H.tolist() == python.mass_matrix_rows(lay.rows, q.tolist())
    rows = lay.table.shape[0]
    Y = np.zeros(n * 10 * (rows - 1))
    flat.regressor_kernel(lay.table, qd, qdd, 0.5, 0.0, -9.8, Y, np.zeros(6 * rows * (rows + 5)),
                          work)
    assert Y.tolist() == python.regressor_rows(lay.rows, q.tolist(), qd.tolist(), qdd.tolist(),
                                               (0.5, 0.0, -9.8))


def _c_function(text: str, name: str) -> str:
    """Return the C function ``name`` of the header ``text``, from its comment to its end."""
    start = text.rindex('/* Run ', 0, text.index(f'static inline void {name}('))
    return text[start:text.index('\n}\n', start) + 3]


def test_the_derivatives_kernel_has_an_avx_copy_of_the_same_statements():
    """One state's derivatives run on an AVX copy of the kernel where the CPU has AVX.

    The copy is the scalar kernel's text but for its name, compiled in a ``target("avx")``
    region: the same operations in the same order, without fused multiply-adds, so the
    same bits (the lane kernels, bit for bit the single call, are checked against it in
    test_derivatives.py); the header defines it only for GCC and Clang on x86-64.
    """
    text = codegen.generate_c()
    scalar = _c_function(text, 'derivatives_kernel')
    copy = _c_function(text, 'derivatives_kernel_avx')
    assert copy == scalar.replace(' derivatives_kernel(', ' derivatives_kernel_avx(').replace(
        'generated from it.', 'generated from it (AVX encodings).')
    before, after = text.split(copy)
    assert before.endswith('#pragma GCC target("avx")\n#endif\n')
    assert after.lstrip().startswith('#ifdef __clang__\n#pragma clang attribute pop')
    assert before.rfind('#ifdef SD_VEX') > before.rfind('#endif  /* SD_VEX */')
    assert '#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))\n' \
        '#define SD_VEX 1' in text


def test_each_column_of_the_derivatives_is_computed_once():
    """The derivatives' forward pass takes a column ``s = mul ᵂX⁻¹ S`` once, not once a loop."""
    from spatial_dynamics.algorithms import derivatives
    source = inspect.getsource(derivatives.derivatives_kernel)
    assert source.count('joint_axis(') == 1 and source.count('Xinv_motion(') == 1
