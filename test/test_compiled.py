# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The compiled extension's one door: every argument form, the terms, batches over threads.

- compiled == numpy backend (plain Python floats for one state) to 1e-12 of the largest value
  on the example-robot-data robots, for q, qd, qdd given as float64 arrays (contiguous and
  strided), lists, tuples, Python ints and integer arrays, gravity as the default, a tuple,
  a list of ints, a float64 or integer array, f_ext on one link or several, and the terms
  gravity_torque, bias_torque, mass_matrix and generalized_momentum;
- each of those forms reaches the extension's single-state entry (it returns an answer, not
  None) — no form falls back to a slower path;
- a batch split over threads (the batch entries release the GIL) equals the single calls
  state by state, bit for bit (to 1e-12 with external wrenches), also for batch sizes that
  do not divide evenly and for several Python threads calling at once; so does a batch run
  in SIMD lanes, on the robots and a random tree with general axes, prismatic and mimic
  joints.
"""

import array
import functools
import gc
import threading

from conftest import random_state, robot_urdf_path
import numpy as np
import pytest
import spatial_dynamics as sd
from spatial_dynamics.backends import codegen, compiled, layout

ROBOTS = ['ur5', 'panda', 'talos', 'solo12']
TOL = 1e-12


@pytest.fixture(autouse=True)
def ext():
    """Return the extension (built with the package: its absence is a failure)."""
    assert compiled.ext is not None, compiled.FAILURE
    return compiled.ext


@functools.lru_cache(maxsize=None)
def robot(name):
    return sd.Model.from_urdf(robot_urdf_path(name))


def close(a, b):
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape and a.dtype == b.dtype == np.float64
    return float(np.abs(a - b).max(initial=0.0)) <= TOL * max(1.0, np.abs(b).max(initial=0.0))


def forms(x):
    """Return the forms users pass one joint vector in: name -> value."""
    wide = np.repeat(x, 2)[::2]
    assert not wide.flags.c_contiguous
    unaligned = np.frombuffer(b'\0' + x.tobytes(), offset=1)
    assert not unaligned.flags.aligned
    return {'ndarray': x, 'strided': wide, 'list': x.tolist(), 'tuple': tuple(x.tolist()),
            'readonly': np.frombuffer(x.tobytes()), 'unaligned': unaligned,
            'reversed': x[::-1].copy()[::-1], 'array.array': array.array('d', x.tolist()),
            'memoryview': memoryview(x)}


def integer_forms(n):
    """Return integer joint vectors: Python ints in a list and a tuple, integer arrays."""
    k = np.arange(n) % 3 - 1
    return {'int list': k.tolist(), 'int tuple': tuple(k.tolist()), 'int64': k,
            'int32': k.astype(np.int32), 'bool': k > 0, 'int8': k.astype(np.int8),
            'uint16': (k + 1).astype(np.uint16), 'longlong': k.astype(np.longlong),
            'ulonglong': (k + 1).astype(np.ulonglong), 'strided int': np.repeat(k, 3)[::3],
            'int array.array': array.array('l', k.tolist())}


GRAVITY_FORMS = {'default': None, 'tuple': (0.3, -0.2, -9.81), 'list of ints': [0, 0, -10],
                 'ndarray': np.array([0.3, -0.2, -9.81]), 'int array': np.array([0, 1, -9]),
                 'list of numpy floats': [np.float64(0.0), np.float64(0.5), np.float64(-9.8)]}


def gravity_kw(g):
    return {} if g is None else {'gravity': g}


@pytest.mark.parametrize('name', ROBOTS)
def test_every_argument_form_gives_the_python_backends_answer(name, rng):
    model = robot(name)
    n = model.nq
    q, qd, qdd = random_state(rng, (), n)
    kernels = layout.of(model).kernels
    cases = list(zip(forms(q).values(), forms(qd).values(), forms(qdd).values()))
    cases += [(x, x, x) for x in integer_forms(n).values()]
    cases += [(q.tolist(), qd, tuple(qdd.tolist())), (q, [0] * n, (0,) * n)]
    for args in cases:
        for g in GRAVITY_FORMS.values():
            expected = sd.rnea(model, *args, backend='numpy', **gravity_kw(g))
            assert close(sd.rnea(model, *args, **gravity_kw(g)), expected)
            assert close(sd.rnea(model, *args, backend='compiled', **gravity_kw(g)), expected)
            # the extension's own entry answers every one of these forms (no fallback)
            g3 = sd.GRAVITY if g is None else g
            assert close(compiled.ext.rnea(kernels, *args, g3), expected)


@pytest.mark.parametrize('name', ROBOTS)
def test_external_wrenches_on_one_state(name, rng):
    model = robot(name)
    n = model.nq
    links = sorted(model.frames)
    q, qd, qdd = random_state(rng, (), n)
    for k in (1, 3):
        f_ext = {links[j]: rng.normal(0.0, 10.0, 6)
                 for j in rng.choice(len(links), size=k, replace=False)}
        for args in ((q, qd, qdd), (q.tolist(), tuple(qd.tolist()), qdd.tolist())):
            as_lists = {link: f.tolist() for link, f in f_ext.items()}
            for wrenches in (f_ext, as_lists):
                expected = sd.rnea(model, *args, f_ext=wrenches, backend='numpy')
                assert close(sd.rnea(model, *args, f_ext=wrenches), expected)
                assert close(sd.rnea(model, *args, f_ext=wrenches, backend='compiled'),
                             expected)
        assert not close(sd.rnea(model, q, qd, qdd, f_ext=f_ext), sd.rnea(model, q, qd, qdd))


@pytest.mark.parametrize('name', ROBOTS)
def test_the_terms_take_every_form_too(name, rng):
    model = robot(name)
    n = model.nq
    q, qd, _ = random_state(rng, (), n)
    kernels = layout.of(model).kernels
    for fq, fd in list(zip(forms(q).values(), forms(qd).values())) + [
            (x, x) for x in integer_forms(n).values()]:
        for g in GRAVITY_FORMS.values():
            assert close(sd.gravity_torque(model, fq, **gravity_kw(g)),
                         sd.gravity_torque(model, fq, backend='numpy', **gravity_kw(g)))
            assert close(sd.bias_torque(model, fq, fd, **gravity_kw(g)),
                         sd.bias_torque(model, fq, fd, backend='numpy', **gravity_kw(g)))
        g3 = (0.0, 0.0, -9.81)
        assert compiled.ext.gravity_torque(kernels, fq, g3) is not None
        assert compiled.ext.bias_torque(kernels, fq, fd, g3) is not None
        M = sd.mass_matrix(model, fq)
        assert M.shape == (n, n) and close(M, sd.mass_matrix(model, fq, backend='numpy'))
        assert compiled.ext.mass_matrix(kernels, fq) is not None
        p, ctq = sd.generalized_momentum(model, fq, fd)
        p_ref, ctq_ref = sd.generalized_momentum(model, fq, fd, backend='numpy')
        assert close(p, p_ref) and close(ctq, ctq_ref)
        assert compiled.ext.generalized_momentum(kernels, fq, fd) is not None


@pytest.mark.parametrize('N', [1, 15, 16, 33, 1001, 2400])
@pytest.mark.parametrize('name', ['ur5', 'talos'])
def test_a_batch_over_threads_equals_the_single_calls(name, N, rng):
    """Batches split into slices over threads (4096 body-states at least each), bit for bit."""
    model = robot(name)
    n = model.nq
    Q, QD, QDD = random_state(rng, (N,), n)
    QD[::4] = 0.0
    g = (0.4, -0.3, -9.7)
    f_var = {sorted(model.frames)[-1]: rng.normal(0.0, 5.0, (N, 6))}
    tau = sd.rnea(model, Q, QD, QDD, gravity=g)
    tau_f = sd.rnea(model, Q, QD, QDD, gravity=g, f_ext=f_var)
    H = sd.mass_matrix(model, Q)
    P, CTQ = sd.generalized_momentum(model, Q, QD)
    picks = range(N) if N <= 33 else range(0, N, 37)
    for s in picks:
        np.testing.assert_array_equal(tau[s], sd.rnea(model, Q[s], QD[s], QDD[s], gravity=g))
        one = {link: f[s] for link, f in f_var.items()}
        # (the link-to-body transform of a batch of wrenches is one numpy matmul: its sums
        # may round differently from the single wrench's)
        assert close(tau_f[s], sd.rnea(model, Q[s], QD[s], QDD[s], gravity=g, f_ext=one))
        np.testing.assert_array_equal(H[s], sd.mass_matrix(model, Q[s]))
        p, ctq = sd.generalized_momentum(model, Q[s], QD[s])
        np.testing.assert_array_equal(P[s], p)
        np.testing.assert_array_equal(CTQ[s], ctq)


@functools.lru_cache(maxsize=None)
def lane_tree():
    """Return a random tree with general axes, prismatic and mimic joints (mult, offset)."""
    from urdf_gen import random_tree_urdf
    return sd.Model.from_urdf(random_tree_urdf(np.random.default_rng(5), 12, branching=True,
                                               mimic=True))


@pytest.mark.parametrize('name', ['ur5', 'panda', 'talos', 'tree'])
def test_the_batch_in_simd_lanes_gives_each_state_its_own_bits(ext, name, rng):
    """A batch runs its states in SIMD lanes (2; 4 with AVX, 8 with AVX-512F), bit for bit.

    The lane kernels are the scalar ones printed on vectors (backends/codegen.py): the same
    operations in the same order per lane, so a moving state's torques are its single call's
    bit for bit. A state at rest in a group with a moving one takes the general path, whose
    extra products are exact zeros: equal values (a zero's sign aside). The batch size leaves
    a remainder that runs state by state; zero gravity takes the weightless path; external
    forces are the same for every state or one table per state.
    """
    model = lane_tree() if name == 'tree' else robot(name)
    n, lay = model.nq, layout.of(model)
    if name == 'tree':
        codes = lay.table[1:, layout.COLUMN['code']]
        mul = lay.table[1:, layout.COLUMN['mul']]
        assert {3, 4} <= set(codes.tolist()) and (mul != 1.0).any()   # RA, PR, mimic
    N = 8 * 5 + 7
    Q, QD, QDD = random_state(rng, (N,), n)
    QD[5] = 0.0                             # at rest, accelerating, beside moving states
    QD[8:16] = QDD[8:16] = 0.0              # a whole group of lanes: gravity only
    QD[17] = QDD[17] = 0.0                  # gravity only, beside moving states
    moving = (QD != 0.0).any(axis=1)
    rows = lay.table.shape[0]
    each = rng.normal(0.0, 5.0, (N, rows, 6))
    for g, fext in (((0.4, -0.3, -9.7), None), ((0.0, 0.0, 0.0), None),
                    ((0.4, -0.3, -9.7), each[0]), ((0.0, 0.0, -9.8), each)):
        for threads in (1, 2):
            tau = np.empty((N, n))
            ext.rnea_batch(lay.kernels, N, Q, QD, QDD, g, fext, tau, threads)
            one = np.array([ext.rnea(lay.kernels, Q[s], QD[s], QDD[s], g,
                                     *(() if fext is None else (fext[s] if fext.ndim == 3
                                                                else fext,)))
                            for s in range(N)])
            np.testing.assert_array_equal(tau, one)
            np.testing.assert_array_equal(tau[moving].view(np.int64),
                                          one[moving].view(np.int64))
            assert np.isfinite(tau).all() and np.abs(tau).max() > 0.0


#: Runs the scalar kernels and each lane width of the generated header on the states of a
#: file (the widths this CPU has), without and with external forces (a table per state),
#: and writes their torques.
LANES_PROGRAM = r"""
#include <stdio.h>
#include <stdlib.h>
#include "_kernels_generated.h"
int main(int argc, char **argv)
{
    long rows, N, n;
    FILE *f = fopen(argv[1], "rb");
    if (fread(&rows, sizeof rows, 1, f) != 1 || fread(&N, sizeof N, 1, f) != 1)
        return 1;
    double *K = malloc(sizeof(double) * rows * WIDTH);
    if (fread(K, sizeof(double), rows * WIDTH, f) != (size_t)(rows * WIDTH))
        return 1;
    n = (long)K[QIDX];
    const long size = 3 * N * n + N * rows * 6;
    double *S = malloc(sizeof(double) * size), *tau = malloc(sizeof(double) * N * n);
    if (fread(S, sizeof(double), size, f) != (size_t)size)
        return 1;
    fclose(f);
    const double *Q = S, *QD = S + N * n, *QDD = S + 2 * N * n, *FE = S + 3 * N * n;
    double *work = malloc(sizeof(double) * rows * WORK);
    sd_vd8 *lanes = aligned_alloc(64, sizeof(sd_vd8) * (rows * WORK + 4 * n + 6 * rows));
    f = fopen(argv[2], "wb");
    for (int with_f = 0; with_f < 2; with_f++) {
        const double *F = with_f ? FE : NULL;
        for (long k = 0; k < N; k++) {
            xup_kernel(K, rows, Q + k * n, work);
            rnea_kernel(K, rows, Q + k * n, QD + k * n, QDD + k * n, 0.4, -0.3, -9.7,
                        F ? F + k * rows * 6 : NULL, with_f, tau + k * n, work);
        }
        fwrite(tau, sizeof(double), N * n, f);
        for (int width = 2; width <= 8; width *= 2) {
            if (width == 2)
                rnea_batch_lanes2(K, rows, N, Q, QD, QDD, 0.4, -0.3, -9.7, F, 1, tau,
                                  (void *)lanes);
#ifdef SD_AVX
            else if (width == 4 && __builtin_cpu_supports("avx"))
                rnea_batch_lanes4(K, rows, N, Q, QD, QDD, 0.4, -0.3, -9.7, F, 1, tau,
                                  (void *)lanes);
            else if (width == 8 && __builtin_cpu_supports("avx512f"))
                rnea_batch_lanes8(K, rows, N, Q, QD, QDD, 0.4, -0.3, -9.7, F, 1, tau,
                                  (void *)lanes);
#endif
            else
                continue;
            if (!with_f)
                fprintf(stderr, "%d\n", width);
            fwrite(tau, sizeof(double), N * n, f);
        }
    }
    fclose(f);
    return 0;
}
"""


@pytest.mark.parametrize('name', ['talos', 'tree'])
def test_every_lane_width_gives_the_scalar_kernels_bits(name, rng, tmp_path):
    """Each lane width this CPU runs (2; 4 with AVX; 8 with AVX-512F), not only the widest.

    The extension runs the widest; this compiles the generated header into a small program
    with the compiler that built the extension (-ffp-contract=off, as setup.py) and runs
    the scalar kernels and every width on the same states, without and with external forces.
    """
    import shlex
    import subprocess
    import sysconfig
    model = lane_tree() if name == 'tree' else robot(name)
    n, lay = model.nq, layout.of(model)
    N = 8 * 6
    Q, QD, QDD = random_state(rng, (N,), n)
    QD[3] = 0.0
    QD[16:24] = QDD[16:24] = 0.0
    rows = lay.table.shape[0]
    with open(tmp_path / 'in', 'wb') as f:
        f.write(np.array([rows, N], dtype=np.int64).tobytes())
        f.write(np.ascontiguousarray(lay.table).tobytes())
        f.write(np.concatenate([Q, QD, QDD]).tobytes())
        f.write(rng.normal(0.0, 5.0, (N, rows, 6)).tobytes())
    (tmp_path / 'lanes.c').write_text(LANES_PROGRAM)
    (tmp_path / codegen.HEADER).write_text(codegen.generate_c())
    cc = shlex.split(sysconfig.get_config_var('CC') or 'cc')
    subprocess.run(cc + ['-O2', '-ffp-contract=off', '-I', str(tmp_path),
                         str(tmp_path / 'lanes.c'), '-o', str(tmp_path / 'lanes'), '-lm'],
                   check=True)
    run = subprocess.run([str(tmp_path / 'lanes'), str(tmp_path / 'in'), str(tmp_path / 'out')],
                         check=True, capture_output=True, text=True)
    widths = [int(w) for w in run.stderr.split()]
    assert widths[0] == 2
    out = np.fromfile(tmp_path / 'out').reshape(2, 1 + len(widths), N, n)
    np.testing.assert_array_equal(out[0, 0],
                                  sd.rnea(model, Q, QD, QDD, gravity=(0.4, -0.3, -9.7)))
    assert not np.array_equal(out[0, 0], out[1, 0])          # the forces count
    moving = (QD != 0.0).any(axis=1)
    for scalar, *lanes in out:
        for width, tau in zip(widths, lanes):
            np.testing.assert_array_equal(tau, scalar, err_msg=f'{width} lanes')
            np.testing.assert_array_equal(tau[moving].view(np.int64),
                                          scalar[moving].view(np.int64), err_msg=f'{width} lanes')


def test_the_thread_count_does_not_change_a_bit(ext, rng):
    """The same batch on 1, 2, 3 and 64 threads (slices of other sizes), and under load."""
    model = robot('talos')
    n, lay = model.nq, layout.of(model)
    N = 777
    Q, QD, QDD = random_state(rng, (N,), n)
    results = []
    for threads in (1, 2, 3, 64):
        tau = np.empty((N, n))
        ext.rnea_batch(lay.kernels, N, Q, QD, QDD, (0.0, 0.0, -9.81), None, tau, threads)
        results.append(tau)
    for tau in results[1:]:
        np.testing.assert_array_equal(tau, results[0])
    np.testing.assert_array_equal(results[0], sd.rnea(model, Q, QD, QDD, backend='numpy'))

    def call(out, k):
        out[k] = sd.rnea(model, Q, QD, QDD)
    out = [None] * 4
    workers = [threading.Thread(target=call, args=(out, k)) for k in range(4)]
    for w in workers:
        w.start()
    for w in workers:
        w.join()
    for tau in out:
        np.testing.assert_array_equal(tau, results[0])


def test_batch_entries_check_their_buffers(ext):
    model = robot('ur5')
    n, lay = model.nq, layout.of(model)
    Q = np.zeros((4, n))
    with pytest.raises(ValueError, match='q must hold 24 numbers'):
        ext.rnea_batch(lay.kernels, 4, Q[:3], Q, Q, (0, 0, -9.81), None, np.empty((4, n)), 2)
    with pytest.raises(TypeError, match='tau must be C-contiguous float64'):
        ext.rnea_batch(lay.kernels, 4, Q, Q, Q, (0, 0, -9.81), None, np.empty((4, n), 'f4'), 2)
    with pytest.raises(ValueError, match='fext must hold'):
        ext.rnea_batch(lay.kernels, 4, Q, Q, Q, (0, 0, -9.81), np.zeros(5), np.empty((4, n)), 2)
    with pytest.raises(ValueError, match='read-only'):
        frozen = np.empty((4, n))
        frozen.flags.writeable = False
        ext.rnea_batch(lay.kernels, 4, Q, Q, Q, (0, 0, -9.81), None, frozen, 2)
    with pytest.raises(TypeError, match='expected Kernels'):
        ext.rnea(lay.table, Q[0], Q[0], Q[0], (0, 0, -9.81))


def test_a_table_that_is_not_a_tree_is_refused(ext):
    """The table's integer columns index the arrays: a broken one never reaches the kernels."""
    table = layout.of(robot('ur5')).table.copy()
    ext.Kernels(table)
    for column, value in ((layout.COLUMN['parent'], 5.0), (layout.COLUMN['qidx'], 6.0),
                          (layout.COLUMN['code'], 7.0), (layout.COLUMN['qidx'], 0.5)):
        bad = table.copy()
        bad[3, column] = value
        with pytest.raises(ValueError, match='not a tree'):
            ext.Kernels(bad)
    with pytest.raises(ValueError, match='shape'):
        ext.Kernels(table[:, :5].copy())


def test_the_doors_are_the_functions_entered_in_c(ext, rng):
    """sd.rnea and the terms are entered in C; every other call reaches the Python function."""
    import inspect
    from spatial_dynamics import backends
    model = robot('ur5')
    n = model.nq
    q, qd, qdd = random_state(rng, (), n)
    for name in ('rnea', 'gravity_torque', 'bias_torque', 'mass_matrix',
                 'generalized_momentum'):
        door = getattr(sd, name)
        assert isinstance(door, ext.Door) and door is getattr(backends, name)
        assert door.__name__ == name and door.__doc__ == door.__wrapped__.__doc__
        assert inspect.signature(door) == inspect.signature(door.__wrapped__)
    expected = sd.rnea.__wrapped__(model, q, qd, qdd, (0.0, 0.1, -9.8), None, 'auto')
    calls = [lambda: sd.rnea(model, q, qd, qdd, (0.0, 0.1, -9.8)),
             lambda: sd.rnea(model, q, qd, qdd, gravity=[0.0, 0.1, -9.8]),
             lambda: sd.rnea(model, q, qd, qdd, (0.0, 0.1, -9.8), None, 'compiled'),
             lambda: sd.rnea(model, q, qd, qdd, (0.0, 0.1, -9.8), {}, backend='auto'),
             lambda: sd.rnea(model, q, qd, qdd=qdd, gravity=(0.0, 0.1, -9.8)),    # Python
             lambda: sd.rnea(model, q, qd, qdd, (0.0, 0.1, -9.8), backend='numpy')]
    for call in calls[:5]:
        np.testing.assert_array_equal(call(), expected)
    assert close(calls[5](), expected)
    with pytest.raises(TypeError, match='unexpected keyword'):
        sd.rnea(model, q, qd, qdd, gravty=(0.0, 0.0, -9.81))
    with pytest.raises(TypeError, match='positional'):
        sd.rnea(model, q, qd, qdd, (0.0, 0.0, -9.81), None, 'auto', 1)
    with pytest.raises(TypeError, match='missing'):
        sd.rnea(model, q, qd)
    with pytest.raises(ValueError, match='backend must be one of'):
        sd.gravity_torque(model, q, backend='fortran')
    with pytest.raises(ValueError, match='gravity must be a 3-vector'):
        sd.bias_torque(model, q, qd, gravity=(0.0, -9.81))
    M = sd.mass_matrix(model, q.tolist(), backend='compiled')
    np.testing.assert_array_equal(M, sd.mass_matrix.__wrapped__(model, q))
    assert close(sd.mass_matrix(model, q, 'numpy'), M)


def test_arrays_the_entries_decline_take_the_general_path(ext, rng):
    """Swapped bytes, float16, longdouble, batches of one state: None, and the same answer."""
    model = robot('ur5')
    n = model.nq
    kernels = layout.of(model).kernels
    q, qd, qdd = random_state(rng, (), n)
    swapped = q.astype(q.dtype.newbyteorder())
    assert ext.rnea(kernels, swapped, qd, qdd, sd.GRAVITY) is None
    assert ext.mass_matrix(kernels, swapped) is None
    np.testing.assert_array_equal(sd.rnea(model, swapped, qd, qdd), sd.rnea(model, q, qd, qdd))
    np.testing.assert_array_equal(sd.mass_matrix(model, swapped), sd.mass_matrix(model, q))
    for declined in (q.astype(np.float16), q.astype(np.longdouble), q[None], q[:-1],
                     np.append(q, 0.0), q.astype(np.complex128), q.astype(object),
                     q.astype(np.float32).astype(np.dtype('>f4'))):
        assert ext.rnea(kernels, declined, qd, qdd, sd.GRAVITY) is None
        assert ext.gravity_torque(kernels, declined, sd.GRAVITY) is None
        assert ext.mass_matrix(kernels, declined) is None
    assert ext.rnea(kernels, q, qd, qdd, np.zeros(4)) is None
    assert ext.rnea(kernels, q, qd, qdd, np.zeros(3, dtype=np.float16)) is None


def test_the_entries_take_float32_and_answer_in_float32(ext, rng):
    """Read float32 arrays (any strides) and buffers in C, answer float32 when all are.

    With every joint vector float32 the result is the float64 one rounded once to float32; a
    float32 vector among float64 ones gives the float64 result of the same numbers, and
    float32 gravity does not change the dtype.
    """
    model = robot('panda')
    n = model.nq
    kernels = layout.of(model).kernels
    narrow = [x.astype(np.float32) for x in random_state(rng, (), n)]
    same = [x.astype(np.float64) for x in narrow]
    g = (0.1, -0.2, -9.8)
    g32 = np.array(g, np.float32)
    wide_g32 = g32.astype(np.float64)
    strided = [np.repeat(x, 2)[::2] for x in narrow]
    buffers = [array.array('f', x.tolist()) for x in narrow]
    for vectors in (narrow, strided, buffers):
        entries = [(ext.rnea(kernels, *vectors, g), ext.rnea(kernels, *same, g)),
                   (ext.regressor(kernels, *vectors, g), ext.regressor(kernels, *same, g)),
                   (ext.gravity_torque(kernels, vectors[0], g),
                    ext.gravity_torque(kernels, same[0], g)),
                   (ext.bias_torque(kernels, *vectors[:2], g),
                    ext.bias_torque(kernels, *same[:2], g)),
                   (ext.mass_matrix(kernels, vectors[0]), ext.mass_matrix(kernels, same[0]))]
        entries += zip(ext.generalized_momentum(kernels, *vectors[:2]),
                       ext.generalized_momentum(kernels, *same[:2]))
        for got, want in entries:
            assert got.dtype == np.float32 and want.dtype == np.float64
            np.testing.assert_array_equal(got, want.astype(np.float32))
    # float32 gravity: read as float64 numbers, no say in the dtype
    for vectors, dtype in ((narrow, np.float32), (same, np.float64)):
        tau = ext.rnea(kernels, *vectors, g32)
        assert tau.dtype == dtype
        np.testing.assert_array_equal(tau, ext.rnea(kernels, *same, wide_g32).astype(dtype))
    # one float64 (or list, or integer) vector among float32 ones: float64
    want = ext.rnea(kernels, *same, g)
    for i in range(3):
        for form in (same[i], same[i].tolist(), tuple(same[i].tolist())):
            tau = ext.rnea(kernels, *narrow[:i], form, *narrow[i + 1:], g)
            assert tau.dtype == np.float64
            np.testing.assert_array_equal(tau, want)
    # with an external force table
    fb = np.zeros((model.NB + 1, 6))
    fb[-1] = [0.5, -1.0, 2.0, 10.0, -3.0, 4.5]
    tau = ext.rnea(kernels, *narrow, g, fb)
    assert tau.dtype == np.float32
    np.testing.assert_array_equal(tau, ext.rnea(kernels, *same, g, fb).astype(np.float32))


def test_the_doors_answer_each_model_with_its_own_kernels(ext, rng):
    """Calls alternating between models, and a model made after one was collected."""
    names = ['ur5', 'panda']
    models = [sd.Model.from_urdf(robot_urdf_path(name)) for name in names]
    states = [random_state(rng, (), m.nq) for m in models]
    expected = [sd.rnea.__wrapped__(m, *x) for m, x in zip(models, states)]
    masses = [sd.mass_matrix.__wrapped__(m, x[0]) for m, x in zip(models, states)]
    for _ in range(3):
        for m, x, tau, M in zip(models, states, expected, masses):
            np.testing.assert_array_equal(sd.rnea(m, *x), tau)
            np.testing.assert_array_equal(sd.mass_matrix(m, x[0]), M)
    for k in range(20):         # a new model may take the address of a collected one
        models = [None, None]
        gc.collect()
        j = k % 2
        model = sd.Model.from_urdf(robot_urdf_path(names[j]))
        np.testing.assert_array_equal(sd.rnea(model, *states[j]), expected[j])
        np.testing.assert_array_equal(sd.mass_matrix(model, states[j][0]), masses[j])
        del model
