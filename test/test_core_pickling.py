# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The public functions and the Model pickle, deep-copy and cross into worker processes.

``functools.partial(sd.gravity_torque, model)`` handed to a ``ProcessPoolExecutor`` pickles
the function (the compiled door: pickled by name, the function of the same name on loading)
and the model (its fields; a loaded model computes the same torques, bit for bit, in this
process and in a fresh one).
"""

import concurrent.futures
import copy
import functools
import multiprocessing
import pickle
import subprocess
import sys

from conftest import robot_urdf_path
import numpy as np
import pytest
import spatial_dynamics as sd

PUBLIC = [name for name in sd.__all__ if callable(getattr(sd, name))
          and not isinstance(getattr(sd, name), type)]


def ur5():
    return sd.Model.from_urdf(robot_urdf_path('ur5'))


def states(n, count=16):
    rng = np.random.default_rng(5)
    return [rng.uniform(-3.0, 3.0, n) for _ in range(count)]


@pytest.mark.parametrize('name', PUBLIC)
def test_every_public_function_pickles_and_copies_as_itself(name):
    function = getattr(sd, name)
    for protocol in range(pickle.HIGHEST_PROTOCOL + 1):
        assert pickle.loads(pickle.dumps(function, protocol)) is function
    assert copy.deepcopy(function) is function
    assert copy.copy(function) is function


def same_model(a, b):
    """Whether two models hold the same fields (arrays equal and read-only, maps equal)."""
    from dataclasses import fields
    for f in fields(sd.Model):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray):
            assert np.array_equal(x, y) and x.dtype == y.dtype, f.name
            assert not y.flags.writeable, f.name
        elif f.name == 'frames':
            assert x.keys() == y.keys()
            for link in x:
                assert x[link].body == y[link].body
                assert np.array_equal(x[link].lXb, y[link].lXb)
        else:
            assert dict(x) == dict(y) if hasattr(x, 'keys') else x == y, f.name
    return True


def test_a_model_pickles_and_computes_the_same_torques():
    model = ur5()
    qs = states(model.nq)
    for loaded in (pickle.loads(pickle.dumps(model)), copy.deepcopy(model)):
        assert type(loaded) is sd.Model and same_model(model, loaded)
        with pytest.raises(TypeError):
            loaded.frames['x'] = None           # still a read-only view
        for q in qs:
            np.testing.assert_array_equal(sd.gravity_torque(loaded, q),
                                          sd.gravity_torque(model, q))
            np.testing.assert_array_equal(sd.mass_matrix(loaded, q), sd.mass_matrix(model, q))


def test_a_pickled_partial_computes_the_same_torques_in_a_fresh_process():
    model = ur5()
    qs = np.array(states(model.nq))
    task = pickle.dumps((functools.partial(sd.gravity_torque, model), qs))
    code = ('import pickle, sys; import numpy as np; '
            'f, qs = pickle.loads(sys.stdin.buffer.read()); '
            'sys.stdout.buffer.write(pickle.dumps(np.array([f(q) for q in qs])))')
    done = subprocess.run([sys.executable, '-c', code], input=task, capture_output=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr.decode()[-3000:]
    there = pickle.loads(done.stdout)
    here = np.array([sd.gravity_torque(model, q) for q in qs])
    np.testing.assert_array_equal(there, here)
    assert here.dtype == there.dtype == np.float64


@pytest.mark.parametrize('start', ['fork', 'spawn'])
def test_a_process_pool_computes_gravity_torque_bit_for_bit(start):
    """The report: ProcessPoolExecutor with functools.partial(sd.gravity_torque, model)."""
    model = ur5()
    qs = states(model.nq, 64)
    here = [sd.gravity_torque(model, q) for q in qs]
    context = multiprocessing.get_context(start)
    with concurrent.futures.ProcessPoolExecutor(2, mp_context=context) as pool:
        there = list(pool.map(functools.partial(sd.gravity_torque, model), qs, chunksize=4))
    for a, b in zip(there, here):
        assert a.dtype == b.dtype == np.float64
        np.testing.assert_array_equal(a, b)
