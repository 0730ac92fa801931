# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""``rnea_derivatives(..., out=(dq, dv, M))``: the results written into the caller's arrays.

On every path (one state and a batch; numpy and compiled; float32; ``base=``, ``armature=``,
``friction_threshold=``, ``f_ext``) the arrays hold, bit for bit, what the call without
``out`` returns, and are the ones returned; a loop reusing them gives each state's fresh
call; the arrays that cannot take the results are refused naming ``out[k]``; a call with
``out`` allocates no array the size of a result (tracemalloc: numpy reports its data to
it); a batch's results are three C-contiguous arrays.
"""

import tracemalloc

from conftest import random_state, robot_urdf_path
import numpy as np
import pytest
import spatial_dynamics as sd
from test_core_floating_base import path_of, random_floating_state

ROBOTS = ['ur5', 'solo12']
SHAPES = [(), (7,)]    # one state, and a batch of 7 (the lanes and the scalar tail)


def robot(name):
    """Return the model (Solo12 on a floating base)."""
    if name == 'solo12':
        return sd.Model.from_urdf(path_of('solo_description/robots/solo12.urdf'),
                                  base='floating')
    return sd.Model.from_urdf(robot_urdf_path(name))


def state(model, rng, shape):
    """Return random ``(q, qd, qdd)`` of batch ``shape``."""
    if model.floating:
        return random_floating_state(rng, model, shape)
    return random_state(rng, shape, model.nq)


def empty_out(shape, dtype=np.float64, order='C'):
    """Return three new arrays to write into."""
    return tuple(np.full(shape, np.nan, dtype=dtype, order=order) for _ in range(3))


def variants(model, rng, shape):
    """Return (what, states, keyword arguments): every path of :func:`rnea_derivatives`."""
    q, qd, qdd = state(model, rng, shape)
    link = model.body_names[-1]
    out = [('plain', (q, qd, qdd), {}),
           ('float32', tuple(x.astype(np.float32) for x in (q, qd, qdd)), {}),
           ('gravity', (q, qd, qdd), {'gravity': np.array([0.5, -1.0, -9.0])}),
           ('f_ext', (q, qd, qdd), {'f_ext': {link: rng.normal(size=6)}}),
           ('armature', (q, qd, qdd), {'armature': 0.1}),
           ('friction', (q, qd, qdd), {'friction_threshold': 0.05}),
           ('list', tuple(x.tolist() for x in (q, qd, qdd)), {})]
    if not model.floating:
        out.append(('base', (q, qd, qdd),
                    {'base': sd.BaseMotion(v=rng.normal(size=6), a=rng.normal(size=6))}))
    return out


def same(a, b):
    """Whether ``a`` and ``b`` are equal to the bit (NaN at the same places too)."""
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


@pytest.mark.parametrize('name', ROBOTS)
@pytest.mark.parametrize('shape', SHAPES)
@pytest.mark.parametrize('backend', ['numpy', 'compiled'])
def test_out_holds_what_the_call_returns_bit_for_bit(name, shape, backend, rng):
    """Every path: ``out``'s arrays are returned, holding the results of the call without it.

    C-contiguous arrays (written in place where the kernels can), Fortran-ordered ones (a
    copy) and three views of one stacked array (which share no element).
    """
    from spatial_dynamics.backends import compiled
    if backend == 'compiled' and compiled.ext is None:
        pytest.skip('built without the compiled kernels')
    model = robot(name)
    nv = model.nv
    for what, (q, qd, qdd), options in variants(model, rng, shape):
        fresh = sd.rnea_derivatives(model, q, qd, qdd, backend=backend, **options)
        dtype = fresh[0].dtype
        stacked = np.full(shape + (3, nv, nv), np.nan, dtype=dtype)
        for out in (empty_out(shape + (nv, nv), dtype), empty_out(shape + (nv, nv), dtype, 'F'),
                    tuple(stacked[..., k, :, :] for k in range(3)),
                    list(empty_out(shape + (nv, nv), dtype))):
            got = sd.rnea_derivatives(model, q, qd, qdd, backend=backend, out=out, **options)
            assert type(got) is tuple and len(got) == 3, what
            for k in range(3):
                assert got[k] is out[k], (what, k)
                assert same(out[k], fresh[k]), (what, k, out[k].flags)


@pytest.mark.parametrize('name', ROBOTS)
@pytest.mark.parametrize('shape', SHAPES)
def test_a_loop_reusing_out_gives_each_fresh_call(name, shape, rng):
    """A controller's loop: the same three arrays each period, each period's own results."""
    model = robot(name)
    out = empty_out(shape + (model.nv, model.nv))
    for _ in range(5):
        q, qd, qdd = state(model, rng, shape)
        got = sd.rnea_derivatives(model, q, qd, qdd, out=out)
        fresh = sd.rnea_derivatives(model, q, qd, qdd)
        assert all(same(x, f) for x, f in zip(got, fresh))
        assert all(x is o for x, o in zip(got, out))


def test_out_that_cannot_take_the_results_is_refused_by_name(rng):
    """Not three arrays, wrong shape or dtype, read-only, or sharing memory: named ``out[k]``."""
    model = robot('ur5')
    nv = model.nv
    q, qd, qdd = random_state(rng, (), model.nq)
    qs, qds, qdds = random_state(rng, (7,), model.nq)

    def good():
        return list(empty_out((nv, nv)))

    def changed(k, x):
        out = good()
        out[k] = x
        return tuple(out)

    readonly = np.zeros((nv, nv))
    readonly.setflags(write=False)
    holder = np.zeros((2 * nv + 1, nv))
    cases = [
        (TypeError, 'out must', np.zeros((3, nv, nv)), (q, qd, qdd)),
        (TypeError, 'out must', tuple(good()[:2]), (q, qd, qdd)),
        (TypeError, r'out\[1\]', changed(1, np.zeros((nv, nv)).tolist()), (q, qd, qdd)),
        (ValueError, r'out\[2\]', changed(2, np.zeros((nv + 1, nv))), (q, qd, qdd)),
        (ValueError, r'out\[0\]', changed(0, np.zeros((nv, nv), np.float32)), (q, qd, qdd)),
        (ValueError, r'out\[1\]', changed(1, np.zeros((7, nv, nv))), (q, qd, qdd)),
        (ValueError, r'out\[0\]', changed(0, np.zeros((nv, nv))), (qs, qds, qdds)),
        (ValueError, r'out\[1\].*read-only', changed(1, readonly), (q, qd, qdd)),
        (ValueError, r'out\[2\].*out\[0\]', (holder[:nv], holder[nv:2 * nv], holder[1:nv + 1]),
         (q, qd, qdd)),
        (ValueError, r'out\[0\].*qd\b', changed(0, holder[:nv]),
         (q, holder[nv - 1], qdd)),
    ]
    for error, match, out, (a, b, c) in cases:
        for backend in ('numpy', 'compiled'):
            with pytest.raises(error, match=match):
                sd.rnea_derivatives(model, a, b, c, backend=backend, out=out)
    # an input inside a wrench, or the armature
    out = [np.zeros((nv, nv)) for _ in range(3)]
    with pytest.raises(ValueError, match=r'out\[2\].*f_ext'):
        sd.rnea_derivatives(model, q, qd, qdd, f_ext={model.body_names[-1]: out[2][0]},
                            out=out)
    with pytest.raises(ValueError, match=r'out\[1\].*armature'):
        sd.rnea_derivatives(model, q, qd, qdd, armature=out[1][0], out=out)


def peak(call) -> int:
    """Return the most memory traced while ``call()`` ran (bytes, above what was before)."""
    call()          # the first call's one-time preparations are not the call's
    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        before = tracemalloc.get_traced_memory()[0]
        call()
        return tracemalloc.get_traced_memory()[1] - before
    finally:
        tracemalloc.stop()


@pytest.mark.parametrize('name', ROBOTS)
def test_a_call_with_out_allocates_no_result(name, rng):
    """A call with ``out`` allocates no array the size of a result (numpy traces its data).

    Less than one result's ``nv² 8`` bytes (a state; ``N nv² 8`` a batch) at the peak, where
    the call without ``out`` makes three. One state where a result is larger than the blocks
    numpy keeps in a cache of its own and reuses without allocating (1 KiB): Solo12's.
    """
    model = robot(name)
    nv = model.nv
    N = 2000
    q, qd, qdd = state(model, rng, (N,))
    out = empty_out((N, nv, nv))
    size = N * nv * nv * 8
    assert peak(lambda: sd.rnea_derivatives(model, q, qd, qdd)) >= 3 * size
    assert peak(lambda: sd.rnea_derivatives(model, q, qd, qdd, out=out)) < size
    size = nv * nv * 8
    if size > 1024:
        q, qd, qdd = state(model, rng, ())
        out = empty_out((nv, nv))
        assert peak(lambda: sd.rnea_derivatives(model, q, qd, qdd)) >= 3 * size
        assert peak(lambda: sd.rnea_derivatives(model, q, qd, qdd, out=out)) < size


def test_a_batch_gives_three_contiguous_arrays(rng):
    """A batch's ``(∂τ/∂q, ∂τ/∂q̇, M)``: three C-contiguous arrays, no strided views of one."""
    model = robot('ur5')
    for backend in ('numpy', 'compiled'):
        for N in (7, 300):
            D = sd.rnea_derivatives(model, *random_state(rng, (N,), model.nq), backend=backend)
            for k, x in enumerate(D):
                assert x.shape == (N, model.nv, model.nv), (backend, N, k)
                assert x.flags.c_contiguous, (backend, N, k)
                assert not any(np.shares_memory(x, y) for y in D[k + 1:]), (backend, N, k)


@pytest.mark.parametrize('backend', ['compiled', 'numpy'])
@pytest.mark.parametrize('batch', [(), (3,)])
def test_a_refused_drive_term_leaves_out_as_it_was(backend, batch, rng):
    """A bad armature or threshold: refused before anything is written (it wrote M first)."""
    model = sd.Model.from_urdf(robot_urdf_path('ur5'))
    n = model.nv
    q, qd, qdd = (rng.uniform(-1, 1, batch + (n,)) for _ in range(3))
    out = tuple(np.full(batch + (n, n), -1.0) for _ in range(3))
    for bad in ({'armature': True}, {'armature': np.full(n, -1.0)}, {'armature': '0.1'},
                {'friction_threshold': 0.0}, {'friction_threshold': np.nan},
                {'friction_threshold': True}):
        with pytest.raises((TypeError, ValueError)):
            sd.rnea_derivatives(model, q, qd, qdd, backend=backend, out=out, **bad)
        assert all(np.all(o == -1.0) for o in out), bad


def test_a_masked_or_self_overlapping_out_is_refused(rng):
    """A masked out kept its mask (results hidden); a stride-0 out kept the last state only."""
    from numpy.lib.stride_tricks import as_strided
    model = sd.Model.from_urdf(robot_urdf_path('ur5'))
    n = model.nv
    q, qd, qdd = (rng.uniform(-1, 1, (4, n)) for _ in range(3))
    masked = tuple(np.ma.masked_array(np.zeros((4, n, n))) for _ in range(3))
    with pytest.raises(TypeError, match=r'out\[0\] must be a numpy array \(not masked\)'):
        sd.rnea_derivatives(model, q, qd, qdd, out=masked)
    stacked = tuple(as_strided(np.zeros((n, n)), (4, n, n), (0, 8 * n, 8)) for _ in range(3))
    with pytest.raises(ValueError, match=r'out\[0\] overlaps itself \(strides \(0, '):
        sd.rnea_derivatives(model, q, qd, qdd, out=stacked)
    # transposed, negative strides and views of one stacked array do not overlap themselves
    D = np.zeros((3, 4, n, n))
    fine = (D[0][:, ::-1, :], np.swapaxes(D[1], -1, -2), D[2])
    got = sd.rnea_derivatives(model, q, qd, qdd, out=fine)
    for a, b in zip(got, sd.rnea_derivatives(model, q, qd, qdd)):
        assert np.array_equal(a, b)


def test_an_out_of_another_kind_is_said_by_its_kind_and_shapes_not_its_numbers():
    """Two arrays, or one stacked array: the message says so, not 600 characters of data."""
    model = sd.Model.from_urdf(robot_urdf_path('ur5'))
    z = np.zeros(model.nv)
    with pytest.raises(TypeError, match=r'got a tuple of 2$'):
        sd.rnea_derivatives(model, z, z, z, out=(np.empty((6, 6)), np.empty((6, 6))))
    with pytest.raises(TypeError, match=r'got ndarray of shape \(3, 6, 6\): tuple\(a\) gives'):
        sd.rnea_derivatives(model, z, z, z, out=np.empty((3, 6, 6)))
    with pytest.raises(ValueError, match=r"dtype float64 \('<f8'\), got shape \(6, 6\) and "
                                         r"dtype >f8 \('>f8'\)"):
        sd.rnea_derivatives(model, z, z, z, out=tuple(np.empty((6, 6), '>f8') for _ in 'abc'))
