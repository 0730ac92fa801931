# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The runtime fast paths, each against the full computation.

RNEA skips what cannot change the answer (``algorithms.rnea.rnea_kernel``, which the Python
backends run and the compiled one runs as generated code):

- q̇ = 0: every body velocity and velocity-product term;
- q̇ = q̈ = 0 (gravity only): every angular acceleration too, so ``a_i = (0, E_i l_λ(i))``
  and ``f_i = (h × l_i, m l_i)``: the rotational inertia is never read;
- zero gravity: ``Xup a_0`` for the bodies on the fixed base.

Each is checked on both backends, single states and batches, against the literal 6×6 RNEA
(``rnea_spatial``, which skips nothing) and Pinocchio. That a shortcut is really taken is
shown by poisoning, with NaN, what it must not read: a path that read it would return NaN.
"""

import functools
import os

from conftest import PinOracle, random_state, robot_urdf_path
import numpy as np
import pytest
import spatial_dynamics as sd
from spatial_dynamics.backends import compiled, layout, python as python_backend
from urdf_gen import random_tree_urdf

TOL = 1e-10                   # Nm or N, against Pinocchio (as test_core_pinocchio.py)
REL = 64 * np.finfo(float).eps   # against rnea_spatial, relative to the largest torque
GRAVITIES = {'g': (0.0, 0.0, -9.81), 'g_oblique': (1.3, -2.1, -9.5), 'no_g': (0.0, 0.0, 0.0)}
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CASES = ['panda', 'talos', 'demo_arm', 'tree-mimic-prismatic']


@functools.lru_cache(maxsize=None)
def case(name):
    """Return (Model, PinOracle) of a robot: example-robot-data, the demo arm or a tree."""
    if name == 'demo_arm':     # a tilted axis, a non-unit axis, an axis along -y, a mimic
        source = os.path.join(ROOT, 'config', 'demo_arm.urdf')
    elif name.startswith('tree'):
        source = random_tree_urdf(np.random.default_rng(77), 16, branching=True, mimic=True,
                                  joint_kinds=('revolute', 'prismatic', 'fixed'))
    else:
        source = robot_urdf_path(name)
    return sd.Model.from_urdf(source), PinOracle(source)


@pytest.fixture(params=['numpy', 'compiled'])
def backend(request):
    """Both backends; the compiled one fails when the package was built without it."""
    if request.param == 'compiled':
        assert compiled.ext is not None, compiled.FAILURE
    return request.param


def states(rng, n, shape=()):
    """Named states that take each fast path, and a full one."""
    q, qd, qdd = random_state(rng, shape, n)
    z = np.zeros_like(q)
    return {'static': (q, z, z), 'qd=0': (q, z, qdd), 'q̈=0': (q, qd, z), 'full': (q, qd, qdd)}


def check(model, oracle, args, gravity, backend, f_ext=None):
    """τ of the fast path against rnea_spatial (relative) and Pinocchio (absolute)."""
    tau = sd.rnea(model, *args, gravity=gravity, f_ext=f_ext, backend=backend)
    full = sd.rnea_spatial(model, *args, gravity=gravity, f_ext=f_ext)
    scale = max(1.0, float(np.abs(full).max()))
    assert tau.shape == full.shape and np.all(np.isfinite(tau))
    assert float(np.abs(tau - full).max()) <= REL * scale
    pin = oracle.rnea(model.joint_names, *args, gravity, f_ext)
    assert float(np.abs(tau - pin).max()) <= TOL
    return tau


@pytest.mark.parametrize('gravity', list(GRAVITIES.values()), ids=list(GRAVITIES))
@pytest.mark.parametrize('name', CASES)
def test_each_path_equals_the_full_computation(name, gravity, backend, rng):
    model, oracle = case(name)
    for _ in range(3):
        for what, args in states(rng, model.nq).items():
            check(model, oracle, args, gravity, backend)


@pytest.mark.parametrize('name', CASES)
def test_batches_of_mixed_states(name, backend, rng):
    """A batch whose states take different paths (the compiled kernel decides per state)."""
    model, oracle = case(name)
    q, qd, qdd = random_state(rng, (12,), model.nq)
    qd[::2] = 0.0          # half at rest
    qdd[::4] = 0.0         # a quarter static: gravity only
    check(model, oracle, (q, qd, qdd), GRAVITIES['g_oblique'], backend)
    static = states(rng, model.nq, (5,))['static']        # a batch wholly static
    for gravity in GRAVITIES.values():
        check(model, oracle, static, gravity, backend)


@pytest.mark.parametrize('name', CASES)
def test_static_with_external_wrenches(name, backend, rng):
    model, oracle = case(name)
    links = sorted(model.frames)
    f_ext = {links[i]: rng.normal(0.0, 10.0, 6)
             for i in rng.choice(len(links), size=min(4, len(links)), replace=False)}
    for gravity in GRAVITIES.values():
        check(model, oracle, states(rng, model.nq)['static'], gravity, backend, f_ext)


@pytest.mark.parametrize('name', CASES)
def test_static_and_weightless_is_exactly_zero(name, backend, rng):
    """q̇ = q̈ = 0 without gravity and wrenches: τ = 0, exactly (no rounding to leave)."""
    model, _ = case(name)
    for shape in ((), (4,)):
        tau = sd.rnea(model, *states(rng, model.nq, shape)['static'], gravity=(0.0, 0.0, 0.0),
                      backend=backend)
        np.testing.assert_array_equal(tau, 0.0)


# --------------------------------------------------------------------------------------------
# The shortcuts are taken: what they must not read is poisoned with NaN


def poisoned(model, column, width, bodies):
    """Rows and table of the model's layout with ``column`` (``width`` wide) of ``bodies`` NaN."""
    table = layout.derive(model).table.copy()
    table[bodies, column:column + width] = np.nan
    rows = tuple(tuple(int(x) if j in layout.INTEGER_COLUMNS else x for j, x in enumerate(row))
                 for row in table.tolist())
    return rows, table


def numpy_tau(model, rows, args, gravity):
    """τ of the component kernel (the numpy backend's) on the given rows, one state."""
    return np.array(python_backend.rnea_rows(rows, *(list(x) for x in args), list(gravity)))


def compiled_tau(model, table, args, gravity):
    """τ of the compiled single-state entry on the given table."""
    tau = compiled.ext.rnea(compiled.ext.Kernels(table), *args, gravity)
    assert tau is not None
    return tau


def nan_inertia(model):
    """Rows and table with every rotational inertia (Ibar) NaN."""
    return poisoned(model, layout.COLUMN['Ibar'], 6, slice(1, None))


def nan_root_offsets(model):
    """Rows and table with the tree offset r of every body on the fixed base NaN."""
    return poisoned(model, layout.COLUMN['r'], 3, np.flatnonzero(model.parent == 0))


@pytest.mark.parametrize('name', CASES)
def test_gravity_only_never_reads_the_rotational_inertia(name, backend, rng):
    model, _ = case(name)
    rows, table = nan_inertia(model)
    s = states(rng, model.nq)
    for gravity in (GRAVITIES['g'], GRAVITIES['g_oblique']):
        expected = sd.rnea(model, *s['static'], gravity=gravity, backend=backend)
        if backend == 'numpy':
            static = numpy_tau(model, rows, s['static'], gravity)
            full = numpy_tau(model, rows, s['qd=0'], gravity)
        else:
            static = compiled_tau(model, table, s['static'], gravity)
            full = compiled_tau(model, table, s['qd=0'], gravity)
        np.testing.assert_array_equal(static, expected)    # the same path, bit for bit
        assert np.isnan(full).any()                        # q̈ ≠ 0 does read it


@pytest.mark.parametrize('name', CASES)
def test_zero_gravity_skips_the_base_acceleration(name, backend, rng):
    """With q̇ = 0 and no gravity, a body on the base never transforms ``a_0``."""
    model, _ = case(name)
    rows, table = nan_root_offsets(model)
    args = states(rng, model.nq)['qd=0']
    run = ((lambda g: numpy_tau(model, rows, args, g)) if backend == 'numpy' else
           (lambda g: compiled_tau(model, table, args, g)))
    np.testing.assert_array_equal(run(GRAVITIES['no_g']),
                                  sd.rnea(model, *args, gravity=GRAVITIES['no_g'],
                                          backend=backend))
    assert np.isnan(run(GRAVITIES['g'])).any()
