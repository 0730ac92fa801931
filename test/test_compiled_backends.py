# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The compiled backend (the C extension built with the package) against numpy and Pinocchio.

- compiled vs Pinocchio: max abs difference <= 1e-10 Nm, as the numpy backend;
- compiled vs numpy: a few ulps of the largest torque (the kernel is the same arithmetic in
  the same order; on one libm the results are identical);
- single states, batches (serial and parallel entries, broadcast, shared and per-sample
  wrenches), gravity variations, the Panda with its mimic finger, UR5, Talos, Solo12 and
  seeded random trees (revolute, continuous, prismatic, fixed, mimic);
- float32 inputs run on the kernels in float64 and come back as float32, equal to the float64
  result rounded once; mixed float32/float64 inputs give float64 (numpy's promotion);
  longdouble runs on numpy; without the extension the package imports and
  ``backend='auto'`` runs on numpy, ``backend='compiled'`` says how to build it; nothing is
  compiled or cached at run time.

The compiled tests fail (they do not skip) when the package was built without its kernels.
"""

import functools
import os
import subprocess
import sys
import textwrap

from conftest import PinOracle, random_state, robot_urdf_path
import numpy as np
import pytest
import spatial_dynamics as sd
from spatial_dynamics import backends
from spatial_dynamics.backends import compiled, layout
from urdf_gen import random_tree_urdf

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TOL_PIN = 1e-10      # Nm (N for prismatic joints), as test_core_pinocchio.py
ULPS = 64            # compiled vs numpy: ULPS * eps * max(1, max |tau|)
ROBOTS = ['panda', 'ur5', 'talos', 'talos_reduced', 'solo12']
GRAVITIES = {'g': (0.0, 0.0, -9.81), 'no_g': (0.0, 0.0, 0.0), 'g_oblique': (1.3, -2.1, -9.5)}
# (seed, n_links, branching, mimic), joints drawn from revolute/continuous/prismatic/fixed
TREES = [(1, 2, False, False), (2, 6, True, True), (3, 9, False, True), (4, 14, True, False),
         (5, 20, True, True), (6, 28, True, True)]
TREE_IDS = [f'seed{s}-{n}links-{"tree" if b else "chain"}{"-mimic" if m else ""}'
            for s, n, b, m in TREES]


@pytest.fixture
def kernels():
    """Return the compiled extension; a package built without it fails here."""
    assert compiled.ext is not None, f'built without the compiled kernels: {compiled.FAILURE}'
    return compiled.ext


@functools.lru_cache(maxsize=None)
def robot(name):
    """Return (Model, PinOracle) of an example-robot-data robot, built once per session."""
    path = robot_urdf_path(name)
    return sd.Model.from_urdf(path), PinOracle(path)


@functools.lru_cache(maxsize=None)
def tree(seed, n_links, branching, mimic):
    """Return (Model, PinOracle) of a seeded random tree."""
    xml = random_tree_urdf(np.random.default_rng(2000 + seed), n_links, branching=branching,
                           mimic=mimic)
    return sd.Model.from_urdf(xml), PinOracle(xml)


def model_and_oracle(case):
    return robot(case) if isinstance(case, str) else tree(*case)


CASES = ROBOTS + TREES
CASE_IDS = ROBOTS + TREE_IDS


def assert_ulps_close(compiled, numpy_tau):
    """Compiled and numpy torques agree to ULPS ulps of the largest torque."""
    assert compiled.shape == numpy_tau.shape
    assert compiled.dtype == np.float64
    scale = max(1.0, float(np.abs(numpy_tau).max(initial=0.0)))
    worst = float(np.abs(compiled - numpy_tau).max(initial=0.0))
    assert worst <= ULPS * np.finfo(np.float64).eps * scale, worst


def max_diff(a, b):
    return float(np.abs(np.asarray(a) - np.asarray(b)).max(initial=0.0))


def random_wrenches(rng, model, k, shape=()):
    """Return {link: wrench of shape shape + (6,)} on k links (root and lumped links too)."""
    links = sorted(model.frames)
    pick = rng.choice(len(links), size=min(k, len(links)), replace=False)
    return {links[i]: rng.normal(0.0, 10.0, tuple(shape) + (6,)) for i in pick}


# --------------------------------------------------------------------------------------------
# Compiled vs numpy vs Pinocchio


@pytest.mark.parametrize('gravity', list(GRAVITIES.values()), ids=list(GRAVITIES))
@pytest.mark.parametrize('case', CASES, ids=CASE_IDS)
def test_single_states(kernels, case, gravity, rng):
    model, oracle = model_and_oracle(case)
    n = model.nq
    for _ in range(5):
        q, qd, qdd = random_state(rng, (), n)
        tau = sd.rnea(model, q, qd, qdd, gravity=gravity, backend='compiled')
        assert tau.shape == (n,)
        assert_ulps_close(tau, sd.rnea(model, q, qd, qdd, gravity=gravity, backend='numpy'))
        assert max_diff(tau, oracle.rnea(model.joint_names, q, qd, qdd, gravity)) <= TOL_PIN


@pytest.mark.parametrize('case', CASES, ids=CASE_IDS)
def test_static_and_velocity_only_states(kernels, case, rng):
    """q̇ = 0 (the kernel skips the velocity terms), q̇ = q̈ = 0 and zero gravity."""
    model, oracle = model_and_oracle(case)
    n = model.nq
    q, qd, qdd = random_state(rng, (), n)
    z = np.zeros(n)
    for args, gravity in [((q, z, qdd), GRAVITIES['g']), ((q, z, z), GRAVITIES['g_oblique']),
                          ((q, qd, z), GRAVITIES['no_g']), ((q, z, z), GRAVITIES['no_g'])]:
        tau = sd.rnea(model, *args, gravity=gravity, backend='compiled')
        assert_ulps_close(tau, sd.rnea(model, *args, gravity=gravity, backend='numpy'))
        assert max_diff(tau, oracle.rnea(model.joint_names, *args, gravity)) <= TOL_PIN


@pytest.mark.parametrize('N', [1, 7, 150], ids=['N1', 'N7-serial', 'N150-parallel'])
@pytest.mark.parametrize('case', CASES, ids=CASE_IDS)
def test_batches(kernels, case, N, rng):
    """Batches below and above kernels.PARALLEL_MIN (serial and parallel entries)."""
    model, oracle = model_and_oracle(case)
    n = model.nq
    q, qd, qdd = random_state(rng, (N,), n)
    qd[::3] = 0.0   # some states at rest: the q̇ = 0 shortcut is per state
    gravity = GRAVITIES['g_oblique']
    tau = sd.rnea(model, q, qd, qdd, gravity=gravity, backend='compiled')
    assert tau.shape == (N, n)
    assert_ulps_close(tau, sd.rnea(model, q, qd, qdd, gravity=gravity, backend='numpy'))
    k = slice(None) if N <= 7 else slice(None, None, 17)   # the oracle loops in Python
    assert max_diff(tau[k], oracle.rnea(model.joint_names, q[k], qd[k], qdd[k],
                                        gravity)) <= TOL_PIN
    for j in (0, N - 1):
        single = sd.rnea(model, q[j], qd[j], qdd[j], gravity=gravity, backend='compiled')
        assert_ulps_close(single, tau[j])


@pytest.mark.parametrize('case', CASES, ids=CASE_IDS)
def test_external_wrenches(kernels, case, rng):
    """Wrenches on random links (base, lumped and mimic links included).

    One state; shared by a batch; varying along a batch; a (2, 3) batch with (3, 6) wrenches.
    """
    model, oracle = model_and_oracle(case)
    n, names, g = model.nq, model.joint_names, GRAVITIES['g']
    f_ext = random_wrenches(rng, model, 5)
    q, qd, qdd = random_state(rng, (), n)
    tau = sd.rnea(model, q, qd, qdd, f_ext=f_ext, backend='compiled')
    assert_ulps_close(tau, sd.rnea(model, q, qd, qdd, f_ext=f_ext, backend='numpy'))
    assert max_diff(tau, oracle.rnea(names, q, qd, qdd, g, f_ext)) <= TOL_PIN

    Q, QD, QDD = random_state(rng, (70,), n)
    tau = sd.rnea(model, Q, QD, QDD, f_ext=f_ext, backend='compiled')
    assert_ulps_close(tau, sd.rnea(model, Q, QD, QDD, f_ext=f_ext, backend='numpy'))
    assert max_diff(tau[:3], oracle.rnea(names, Q[:3], QD[:3], QDD[:3], g, f_ext)) <= TOL_PIN

    f_var = random_wrenches(rng, model, 3, shape=(70,))
    tau = sd.rnea(model, Q, QD, QDD, f_ext=f_var, backend='compiled')
    assert_ulps_close(tau, sd.rnea(model, Q, QD, QDD, f_ext=f_var, backend='numpy'))
    for j in (0, 69):
        f_j = {link: f[j] for link, f in f_var.items()}
        assert max_diff(tau[j], oracle.rnea(names, Q[j], QD[j], QDD[j], g, f_j)) <= TOL_PIN

    Q, QD, QDD = random_state(rng, (2, 3), n)
    f_b = random_wrenches(rng, model, 2, shape=(3,))
    tau = sd.rnea(model, Q, QD, QDD, f_ext=f_b, backend='compiled')
    assert tau.shape == (2, 3, n)
    assert_ulps_close(tau, sd.rnea(model, Q, QD, QDD, f_ext=f_b, backend='numpy'))


def test_panda_mimic_finger_and_hand_wrenches(kernels, rng):
    """The mimic finger's torque is folded onto its source; wrenches on lumped hand links."""
    model, oracle = robot('panda')
    n, names = model.nq, model.joint_names
    for link in ['panda_hand_tcp', 'panda_hand', 'panda_leftfinger', 'panda_rightfinger']:
        f_ext = {link: rng.normal(0.0, 10.0, 6)}
        q, qd, qdd = random_state(rng, (), n)
        tau = sd.rnea(model, q, qd, qdd, f_ext=f_ext, backend='compiled')
        assert max_diff(tau, oracle.rnea(names, q, qd, qdd, f_ext=f_ext)) <= TOL_PIN
        assert max_diff(tau, sd.rnea(model, q, qd, qdd, backend='compiled')) > 1e-3, link


def test_broadcast_strided_readonly_and_list_inputs(kernels, rng):
    """Inputs the single-state shortcut declines take the general compiled path."""
    model, oracle = robot('ur5')
    n = model.nq
    Q, QD, QDD = random_state(rng, (4,), n)
    ref = sd.rnea(model, Q, QD, QDD, backend='numpy')
    # q of shape (n,) broadcast against batches of qd, qdd
    tau = sd.rnea(model, Q[0], QD, QDD, backend='compiled')
    assert_ulps_close(tau, sd.rnea(model, Q[0], QD, QDD, backend='numpy'))
    # non-contiguous rows, read-only arrays, lists, integer arrays, gravity as an array
    wide = np.repeat(np.stack([Q, QD, QDD]), 2, axis=-1)[..., ::2]
    assert not wide[0, 0].flags.c_contiguous
    assert_ulps_close(sd.rnea(model, *wide[:, 0], backend='compiled'), ref[0])
    assert_ulps_close(sd.rnea(model, *wide, backend='compiled'), ref)
    frozen = [x[1].copy() for x in (Q, QD, QDD)]
    for x in frozen:
        x.setflags(write=False)
    assert_ulps_close(sd.rnea(model, *frozen, backend='compiled'), ref[1])
    assert_ulps_close(sd.rnea(model, *(x[2].tolist() for x in (Q, QD, QDD)),
                              backend='compiled'), ref[2])
    ints = [np.arange(n) % 3 - 1, np.ones(n, dtype=int), np.zeros(n, dtype=np.int32)]
    assert_ulps_close(sd.rnea(model, *ints, backend='compiled'),
                      sd.rnea(model, *ints, backend='numpy'))
    g = np.array([0.5, 0.0, -9.0])
    assert_ulps_close(sd.rnea(model, Q[3], QD[3], QDD[3], gravity=g, backend='compiled'),
                      sd.rnea(model, Q[3], QD[3], QDD[3], gravity=g, backend='numpy'))
    assert max_diff(sd.rnea(model, Q[3], QD[3], QDD[3], gravity=g, backend='compiled'),
                    oracle.rnea(model.joint_names, Q[3], QD[3], QDD[3], tuple(g))) <= TOL_PIN


def test_validation_errors_are_the_numpy_ones(kernels):
    model, _ = robot('ur5')
    n = model.nq
    z = np.zeros(n)
    with pytest.raises(ValueError, match=r'q must have shape \(\.\.\., 6\)'):
        sd.rnea(model, np.zeros(n + 1), z, z, backend='compiled')
    with pytest.raises(ValueError, match='gravity must be a 3-vector'):
        sd.rnea(model, z, z, z, gravity=(0.0, -9.81), backend='compiled')
    with pytest.raises(ValueError, match='unknown link'):
        sd.rnea(model, z, z, z, f_ext={'nope': np.zeros(6)}, backend='compiled')
    with pytest.raises(ValueError, match='backend must be one of'):
        sd.rnea(model, z, z, z, backend='fortran')


def test_longdouble_runs_on_numpy(kernels, rng):
    """Run longdouble (asked for its precision) on numpy: its dtype, the numpy result."""
    model, _ = robot('panda')
    q, qd, qdd = (x.astype(np.longdouble) for x in random_state(rng, (3,), model.nq))
    for args in [(q, qd, qdd), (q[0], qd[0], qdd[0])]:
        tau = sd.rnea(model, *args, backend='compiled')
        assert tau.dtype == np.longdouble
        np.testing.assert_array_equal(tau, sd.rnea(model, *args, backend='numpy'))


# each public function: how many joint vectors it takes, and whether it takes gravity
FUNCTIONS = {'rnea': (3, True), 'gravity_torque': (1, True), 'bias_torque': (2, True),
             'mass_matrix': (1, False), 'generalized_momentum': (2, False),
             'regressor': (3, True)}


def _call(name, model, vectors, gravity=None, **kwargs):
    """Call the public function ``name`` with its joint vectors (and gravity if it takes it)."""
    k, takes_gravity = FUNCTIONS[name]
    extra = (gravity,) if takes_gravity and gravity is not None else ()
    return getattr(sd, name)(model, *vectors[:k], *extra, **kwargs)


def _arrays(out):
    """Return the result of a public function as a list of arrays (momentum gives two)."""
    return list(out) if isinstance(out, tuple) else [out]


@pytest.mark.parametrize('name', list(FUNCTIONS))
@pytest.mark.parametrize('backend', ['auto', 'compiled'])
def test_float32_runs_on_the_kernels_in_float64(kernels, name, backend, rng):
    """Run float32 on the float64 kernels: their result rounded once, returned as float32.

    For one state and batches; ``backend='numpy'`` keeps float32 arithmetic (the benchmark's
    float32 row).
    """
    model, _ = robot('panda')
    wide = random_state(rng, (5,), model.nq)
    narrow = [x.astype(np.float32) for x in wide]
    same = [x.astype(np.float64) for x in narrow]    # the float32 numbers, in float64
    for pick in (lambda x: x, lambda x: x[2], lambda x: x[1:2], lambda x: x[::2]):
        got = _arrays(_call(name, model, [pick(x) for x in narrow], backend=backend))
        want = _arrays(_call(name, model, [pick(x) for x in same], backend=backend))
        for a, b in zip(got, want, strict=True):
            assert a.dtype == np.float32 and b.dtype == np.float64 and a.shape == b.shape
            np.testing.assert_array_equal(a, b.astype(np.float32))
    # numpy: float32 arithmetic, a float32 result near the float64 one (but not the same)
    slow = _arrays(_call(name, model, narrow, backend='numpy'))
    fast = _arrays(_call(name, model, narrow, backend=backend))
    for a, b in zip(slow, fast, strict=True):
        assert a.dtype == np.float32
        assert np.abs(a - b).max() <= 1e-4 * max(1.0, np.abs(b).max())
    assert any(not np.array_equal(a, b) for a, b in zip(slow, fast))


@pytest.mark.parametrize('name', list(FUNCTIONS))
def test_mixed_dtypes_promote_as_numpy_does(kernels, name, rng):
    """Promote as numpy: float32 with float64, lists or integers gives float64.

    The float64 result of the same numbers; float32 gravity does not change the dtype.
    """
    model, _ = robot('ur5')
    k = FUNCTIONS[name][0]
    narrow = [x.astype(np.float32) for x in random_state(rng, (), model.nq)]
    same = [x.astype(np.float64) for x in narrow]
    g64, g32 = np.array([0.5, -0.25, -9.75]), np.array([0.5, -0.25, -9.75], np.float32)
    want64 = _arrays(_call(name, model, same, g64))
    want32 = _arrays(_call(name, model, narrow, g64))
    for i in range(k if k > 1 else 0):    # one vector float64 (array, list), others float32
        for form in (same[i], same[i].tolist()):
            vectors = narrow[:i] + [form] + narrow[i + 1:]
            for a, b in zip(_arrays(_call(name, model, vectors, g64)), want64, strict=True):
                assert a.dtype == np.float64
                np.testing.assert_array_equal(a, b)
    ints = np.arange(model.nq) % 3 - 1
    mixed = [ints] + narrow[1:]
    for a, b in zip(_arrays(_call(name, model, mixed, g64)),
                    _arrays(_call(name, model, [ints * 1.0] + same[1:], g64)), strict=True):
        assert a.dtype == np.float64
        np.testing.assert_array_equal(a, b)
    for a, b in zip(_arrays(_call(name, model, narrow, g32)), want32, strict=True):
        assert a.dtype == np.float32
        np.testing.assert_array_equal(a, b)


def test_float32_external_wrenches(kernels, rng):
    """Give float32 states with f_ext in float32 or float64 a float32 result.

    The float64 result rounded once (the wrenches convert to float64 exactly), for one state
    and a batch.
    """
    model, _ = robot('ur5')
    link = model.body_names[-1]
    wide = random_state(rng, (4,), model.nq)
    narrow = [x.astype(np.float32) for x in wide]
    same = [x.astype(np.float64) for x in narrow]
    w32 = np.array([0.5, -1.0, 2.0, 10.0, -3.0, 4.5], np.float32)
    for pick in (lambda x: x[0], lambda x: x):
        want = sd.rnea(model, *map(pick, same), f_ext={link: w32.astype(np.float64)})
        for wrench in (w32, w32.astype(np.float64)):
            for backend in ('auto', 'compiled'):
                tau = sd.rnea(model, *map(pick, narrow), f_ext={link: wrench}, backend=backend)
                assert tau.dtype == np.float32
                np.testing.assert_array_equal(tau, want.astype(np.float32))
        tau = sd.rnea(model, *map(pick, narrow), f_ext={link: w32}, backend='numpy')
        assert tau.dtype == np.float32
        assert np.abs(tau - want).max() <= 1e-4 * max(1.0, np.abs(want).max())


def test_the_layout_is_the_backends_not_the_models(kernels):
    """The backend derives its table from the Model, keeps it while the model lives."""
    import gc
    model, _ = robot('panda')
    assert not any(name.startswith('_') for name in vars(model))   # a plain record
    lay = layout.of(model)
    K, C = lay.table, layout.COLUMN
    assert layout.of(model) is lay and lay.n == model.nq
    assert K.shape == (model.NB + 1, layout.WIDTH) and not K.flags.writeable
    assert (lay.kernels.rows, lay.kernels.n) == K.shape[:1] + (model.nq,)   # its copy
    assert K[0, C['qidx']] == model.nq      # the length the single entry checks q against
    np.testing.assert_array_equal(K[1:, C['parent']], model.parent[1:])
    np.testing.assert_array_equal(K[1:, C['qidx']], model.qidx[1:])
    np.testing.assert_array_equal(K[1:, C['mul']], model.qmul[1:])
    np.testing.assert_array_equal(K[1:, C['mass']], model.inertia[1:, 3, 3])
    assert [tuple(row) for row in K.tolist()] == [tuple(map(float, r)) for r in lay.rows]
    # A derived model gets its own layout; the original's is left as it was.
    before = K.copy()
    heavier = sd.with_payload(model, model.body_names[-1], 1.5, [0.0, 0.0, 0.1],
                              [0.01, 0.0, 0.0, 0.01, 0.0, 0.01])
    assert layout.of(heavier).table is not K
    np.testing.assert_array_equal(K, before)
    assert layout.of(heavier).table[-1, C['mass']] == K[-1, C['mass']] + 1.5
    key = id(heavier)
    assert key in layout.LAYOUTS
    del heavier
    gc.collect()
    assert key not in layout.LAYOUTS         # dropped with its model


def test_model_too_large_for_the_stack(kernels, rng):
    """Beyond the C stack scratch (2048 doubles: 50 bodies) the single entry uses the heap."""
    xml = random_tree_urdf(np.random.default_rng(2099), 128 + 20,
                           branching=True, joint_kinds=('revolute', 'prismatic'), mimic=True)
    model, oracle = sd.Model.from_urdf(xml), PinOracle(xml)
    assert (model.NB + 1) * kernels.WORK > 2048
    q, qd, qdd = random_state(rng, (), model.nq)
    tau = kernels.rnea(layout.of(model).kernels, q, qd, qdd, (0.0, 0.0, -9.81))
    assert_ulps_close(tau, sd.rnea(model, q, qd, qdd, backend='numpy'))
    for shape in ((model.nq,), (1, model.nq)):
        args = [x.reshape(shape) for x in (q, qd, qdd)]
        tau = sd.rnea(model, *args, backend='compiled')
        assert tau.shape == shape
        assert_ulps_close(tau, sd.rnea(model, *args, backend='numpy'))
        assert max_diff(tau, oracle.rnea(model.joint_names, *args)) <= TOL_PIN


def test_single_entry_refuses_wrong_lengths(kernels):
    """The C entry declines (None) what is not one state; the general path names it."""
    model, _ = robot('panda')
    n = model.nq
    K = layout.of(model).kernels
    z, g = np.zeros(n), (0.0, 0.0, -9.81)
    for args in ((np.zeros(n - 1), z, z, g), (z, np.zeros(n + 1), z, g), (z, z, z, g[:2]),
                 (np.zeros((1, n)), z, z, g), (z, z, [0.0] * n + [1.0], g),
                 (z, z, z, np.zeros(3, np.float16)), (z.astype(np.float16), z, z, g),
                 (z, z, z, np.zeros(3, np.longdouble)), (z.astype(np.longdouble), z, z, g),
                 (z, z, ['0'] * n, g), (z, z, b'\0' * n, g)):
        assert kernels.rnea(K, *args) is None
    with pytest.raises(ValueError, match=rf'q must have shape \(\.\.\., {n}\)'):
        sd.rnea(model, np.zeros(n - 1), np.zeros(n - 1), np.zeros(n - 1), backend='compiled')


def test_warmup_and_describe(kernels):
    model, _ = robot('talos_reduced')
    assert backends.warmup(model).startswith('compiled (C extension, ')
    assert backends.warmup(model, backend='numpy') == 'numpy'
    assert backends.describe('compiled').startswith('compiled')


def test_concurrent_callers_agree(kernels, rng):
    """Several Python threads calling single and parallel-batch entries at once."""
    from concurrent.futures import ThreadPoolExecutor
    model, _ = robot('talos_reduced')
    Q, QD, QDD = random_state(rng, (200,), model.nq)
    ref = sd.rnea(model, Q, QD, QDD, backend='numpy')

    def job(j):
        if j % 2:
            return sd.rnea(model, Q, QD, QDD)
        return np.stack([sd.rnea(model, Q[k], QD[k], QDD[k]) for k in range(0, 200, 20)])

    with ThreadPoolExecutor(4) as pool:
        results = list(pool.map(job, range(8)))
    for j, tau in enumerate(results):
        assert_ulps_close(tau, ref if j % 2 else ref[::20])


# --------------------------------------------------------------------------------------------
# Without the extension; nothing compiled at run time


def run_python(code, env=None):
    """Run code in a fresh interpreter that imports this checkout's spatial_dynamics."""
    env = dict(os.environ if env is None else env)
    env['PYTHONPATH'] = os.pathsep.join(
        [os.path.dirname(os.path.dirname(os.path.abspath(sd.__file__))), ROOT]
        + [p for p in env.get('PYTHONPATH', '').split(os.pathsep) if p])
    proc = subprocess.run([sys.executable, '-c', textwrap.dedent(code)], capture_output=True,
                          text=True, cwd=ROOT, env=env, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return proc.stdout


URDF = ('<robot name="r"><link name="base"/><link name="arm"><inertial><mass value="1"/>'
        '<origin xyz="0 0 -0.5"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" '
        'izz="0.1"/></inertial></link><joint name="j" type="revolute"><parent link="base"/>'
        '<child link="arm"/><axis xyz="0 1 0"/>'
        '<limit effort="1" velocity="1" lower="-1" upper="1"/></joint></robot>')


def test_without_the_extension_auto_runs_on_numpy():
    """A package built without a C compiler: 'auto' is numpy, 'compiled' says how to build."""
    out = run_python(f'''
        import sys
        sys.modules['spatial_dynamics.backends._compiled'] = None   # its import fails
        import numpy as np
        import spatial_dynamics as sd
        from spatial_dynamics import backends
        m = sd.Model.from_urdf({URDF!r})
        tau = sd.rnea(m, np.array([0.3]), np.zeros(1), np.zeros(1))
        assert abs(tau[0] - 9.81 * 0.5 * np.sin(0.3)) < 1e-12, tau
        assert sd.rnea(m, np.ones((5, 1)), np.ones((5, 1)), np.ones((5, 1))).shape == (5, 1)
        assert sd.mass_matrix(m, [0.3]).shape == (1, 1)
        assert sd.regressor(m, np.ones((5, 1)), [1.0], [1.0]).shape == (5, 1, 10)
        print('describe:', backends.describe())
        print('warmup:', backends.warmup(m))
        try:
            sd.rnea(m, np.zeros(1), np.zeros(1), np.zeros(1), backend='compiled')
        except ImportError as err:
            print('error:', type(err).__name__, err)
        print('kernels:', backends.compiled.ext)
    ''')
    assert 'describe: numpy (compiled kernels not built: ' in out, out
    assert 'warmup: numpy (compiled kernels not built' in out, out
    assert 'error: CompiledBackendUnavailable' in out, out
    assert 'C compiler' in out and 'build-essential python3-dev' in out, out
    assert 'kernels: None' in out, out


def test_a_stale_build_is_not_used():
    """An extension of another interface (left beside newer sources) counts as missing."""
    out = run_python(f'''
        import sys, types
        stale = types.ModuleType('spatial_dynamics.backends._compiled')
        stale.API, stale.__file__ = 0, '/somewhere/_compiled.so'
        sys.modules[stale.__name__] = stale
        import numpy as np
        import spatial_dynamics as sd
        m = sd.Model.from_urdf({URDF!r})
        assert abs(sd.rnea(m, [0.3], [0.0], [0.0])[0] - 9.81 * 0.5 * np.sin(0.3)) < 1e-12
        print(sd.backends.describe())
    ''')
    assert out.startswith('numpy (compiled kernels not built: /somewhere/_compiled.so is a '
                          f'stale build (API 0, not {compiled.API}): build the package '
                          'again)'), out


def test_nothing_is_compiled_or_written_at_run_time(kernels, tmp_path):
    """Every entry runs in a new process with an empty home and cache: nothing is written."""
    home = tmp_path / 'home'
    home.mkdir()
    package = os.path.dirname(os.path.abspath(sd.__file__))

    def listing():
        return sorted(os.path.join(d, f) for d, _, names in os.walk(package) for f in names
                      if '__pycache__' not in d)

    before = listing()
    env = dict(os.environ, HOME=str(home), XDG_CACHE_HOME=str(home / '.cache'),
               PYTHONDONTWRITEBYTECODE='1')
    out = run_python(f'''
        import numpy as np
        import spatial_dynamics as sd
        m = sd.Model.from_urdf({URDF!r})
        z, Z = np.zeros(1), np.zeros((100, 1))
        for q in (z, Z):
            sd.rnea(m, q, q, q, backend='compiled')
            sd.gravity_torque(m, q, backend='compiled')
            sd.bias_torque(m, q, q, backend='compiled')
            sd.mass_matrix(m, q, backend='compiled')
            sd.generalized_momentum(m, q, q, backend='compiled')
            sd.regressor(m, q, q, q, backend='compiled')
        print(sd.backends.describe('compiled'))
    ''', env)
    assert out.startswith('compiled (C extension'), out
    assert list(home.iterdir()) == []
    assert listing() == before


PACKAGE_FILES = ('setup.py', 'setup.cfg', 'pyproject.toml', 'MANIFEST.in', 'package.xml',
                 'README.md', 'LICENSE', 'resource', 'launch', 'config', 'bin', 'spatial_dynamics')


def test_a_build_without_a_compiler_installs_and_runs_with_one_warning(tmp_path):
    """``CC=/bin/false pip install``: installed without the extension, one warning each time."""
    import shutil
    source, target = tmp_path / 'source', tmp_path / 'target'
    for name in PACKAGE_FILES:
        path = os.path.join(ROOT, name)
        if os.path.isdir(path):
            shutil.copytree(path, source / name, ignore=shutil.ignore_patterns(
                '__pycache__', '*.so', '*.pyd'))
        else:
            source.mkdir(exist_ok=True)
            shutil.copy(path, source / name)
    env = dict(os.environ, CC='/bin/false')
    # pip builds in an isolated environment (setuptools and wheel from the index) unless this
    # one can build wheels itself
    import importlib.util
    isolation = [] if importlib.util.find_spec('wheel') is None else ['--no-build-isolation']
    build = subprocess.run([sys.executable, '-m', 'pip', 'install', '-v', '--no-deps',
                            *isolation, '--target', str(target), str(source)],
                           capture_output=True, text=True, env=env, timeout=600)
    log = build.stdout + build.stderr
    assert build.returncode == 0, log[-3000:]
    assert log.count('WARNING: spatial_dynamics: the compiled kernels were not built') == 1, log
    assert 'build-essential python3-dev' in log
    installed = [name for _, _, names in os.walk(target) for name in names]
    assert 'rnea.py' in installed and not any(n.startswith('_compiled') for n in installed)
    code = textwrap.dedent(f'''
        import numpy as np
        import spatial_dynamics as sd
        m = sd.Model.from_urdf({URDF!r})
        tau = sd.rnea(m, [0.3], [0.0], [0.0])
        assert abs(tau[0] - 9.81 * 0.5 * np.sin(0.3)) < 1e-12, tau
        print(sd.backends.describe())
    ''')
    run = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                         cwd=str(tmp_path), timeout=300,
                         env=dict(os.environ, PYTHONPATH=str(target)))
    assert run.returncode == 0, run.stderr
    assert run.stdout.startswith('numpy (compiled kernels not built'), run.stdout
    assert run.stderr.count('RuntimeWarning: spatial_dynamics was built without its compiled '
                            'kernels') == 1, run.stderr
