# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Joint vectors and gravity given as buffer-protocol objects, in every public function.

A ctypes array exports its buffer without strides (a C-contiguous exporter may), a
``_testbuffer`` array with suboffsets, a ``memoryview`` of bytes as unsigned bytes: each such
argument gives the answer of the same numbers as a list (or as ``np.array`` of it, which keeps
float32 and the integer types), or a ``TypeError`` that names the argument; it never crashes
the interpreter. Each check runs in a child process, so that a crash fails the test instead of
ending pytest.
"""

import array
import ctypes
import functools
import inspect
import os
import subprocess
import sys

from conftest import TWO_JOINTS
import numpy as np
import pytest
import spatial_dynamics as sd

HERE = os.path.dirname(os.path.abspath(__file__))

#: A single link: no joint, q of length 0.
NO_JOINTS = '<robot name="one"><link name="base"/></robot>'


def buffers(values):
    """Return the buffer exporters users may pass for one vector: name -> (object, numbers).

    ``numbers`` is the list of the same numbers (what the buffer should be read as); None for
    a buffer that cannot be one vector of numbers.
    """
    from _testbuffer import ND_PIL, ndarray
    x = [float(v) for v in values]
    n = len(x)
    small = [float(k % 7) for k in range(n)]            # exact in every item type below
    raw = array.array('d', x).tobytes()
    out = {
        'ctypes double': ((ctypes.c_double * n)(*x), x),
        'ctypes from numpy': (np.ctypeslib.as_ctypes(np.array(x)), x),
        'ctypes float': ((ctypes.c_float * n)(*small), small),
        'ctypes int': ((ctypes.c_int * n)(*map(int, small)), small),
        'ctypes long': ((ctypes.c_long * n)(*map(int, small)), small),
        'ctypes bool': ((ctypes.c_bool * n)(*map(bool, small)), [float(bool(v)) for v in small]),
        'ctypes 2-D': (((ctypes.c_double * n) * 1)((ctypes.c_double * n)(*x)), [x]),
        'ctypes char': ((ctypes.c_char * n)(), None),
        'ctypes longdouble': ((ctypes.c_longdouble * n)(*x), None),
        'memoryview bytes B': (memoryview(bytes(map(int, small))), small),
        'memoryview double': (memoryview(array.array('d', x)), x),
        'read-only double': (memoryview(raw).cast('d'), x),
        'strided double': (memoryview(array.array('d', [v for v in x for _ in (0, 1)]))[::2],
                           x),
        'array d': (array.array('d', x), x),
        'array f': (array.array('f', small), small),
        'array q': (array.array('q', map(int, small)), small),
        'suboffsets': (ndarray(x or [0.0], shape=[max(n, 1)], format='d', flags=ND_PIL),
                       None),
        'empty': ((ctypes.c_double * 0)(), []),
    }
    return out


def calls(model, q, qd, qdd):
    """Return the public functions that take arrays: name -> (function, arguments)."""
    n = model.nq
    link = model.body_names[-1]
    out = {
        'rnea': (sd.rnea, [model, q, qd, qdd, sd.GRAVITY]),
        'gravity_torque': (sd.gravity_torque, [model, q, sd.GRAVITY]),
        'bias_torque': (sd.bias_torque, [model, q, qd, sd.GRAVITY]),
        'mass_matrix': (sd.mass_matrix, [model, q]),
        'generalized_momentum': (sd.generalized_momentum, [model, q, qd]),
        'regressor': (sd.regressor, [model, q, qd, qdd, sd.GRAVITY]),
        'rnea_spatial': (sd.rnea_spatial, [model, q, qd, qdd, sd.GRAVITY]),
        'jacobian': (sd.jacobian, [model, q, link]),
        'friction_torque': (sd.friction_torque, [model, qd, 0.01]),
        'clamp_to_effort_limits': (sd.clamp_to_effort_limits, [model, q]),
        'armature_torque': (sd.armature_torque, [np.full(n, 0.5), qdd]),
    }
    for backend in ('numpy', 'compiled'):
        for name in ('rnea', 'gravity_torque', 'bias_torque', 'mass_matrix',
                     'generalized_momentum', 'regressor'):
            function, args = out[name]
            out[f'{name} {backend}'] = (functools.partial(function, backend=backend), args)
    return out


def answer(function, args):
    """``function(*args)`` as ('ok', result) or ('error', exception type)."""
    try:
        return 'ok', function(*args)
    except (TypeError, ValueError) as err:
        return 'error', err


def parameter(function, position):
    """Return the name of ``function``'s parameter at ``position`` (its errors' name)."""
    return list(inspect.signature(function).parameters)[position]


def same(got, want):
    """Whether two answers are the same arrays (dtype and bits) or errors of one type."""
    if got[0] != want[0]:
        return False
    if got[0] == 'error':
        return type(got[1]) is type(want[1])
    a, b = got[1], want[1]
    if isinstance(b, tuple):
        return len(a) == len(b) and all(same(('ok', x), ('ok', y)) for x, y in zip(a, b))
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b, equal_nan=True)


def check_every_buffer(urdf):
    """Give every public function every buffer in every array argument (the child's work).

    A buffer of numbers must answer as ``np.array`` of it does (for float64 buffers that is
    the list's answer too); a buffer that is not one vector of numbers raises a TypeError or
    ValueError that names the argument, never another exception or a crash.
    """
    model = sd.Model.from_urdf(urdf)
    n = model.nq
    rng = np.random.default_rng(7)
    state = [rng.uniform(-1, 1, n).tolist() for _ in range(3)]
    checked, problems = 0, []

    def expect(condition, *what):
        if not condition:
            problems.append(what)
    for slot in range(3):
        for name, (obj, numbers) in buffers(state[slot]).items():
            vectors = list(state)
            vectors[slot] = obj
            listed = list(state)
            listed[slot] = numbers
            for call, (function, args) in calls(model, *state).items():
                positions = [i for i, a in enumerate(args) if a is state[slot]]
                if not positions:
                    continue
                given = [obj if i in positions else a for i, a in enumerate(args)]
                got = answer(function, given)
                if numbers is None:
                    expect(got[0] == 'error', call, name, got)
                    expect(isinstance(got[1], TypeError), call, name, got)
                    what = parameter(function, positions[0])
                    expect(str(got[1]).startswith(what + ' '), call, name, what, got)
                else:
                    want = answer(function, [np.array(obj) if i in positions else a
                                             for i, a in enumerate(args)])
                    expect(same(got, want), call, name, slot, got, want)
                    if name in ('ctypes double', 'ctypes from numpy', 'read-only double',
                                'memoryview double', 'strided double', 'array d'):
                        lst = answer(function, [numbers if i in positions else a
                                                for i, a in enumerate(args)])
                        expect(same(got, lst), call, name, got, lst)
                checked += 1
    # gravity as a buffer
    for name, (obj, numbers) in buffers([0.1, -0.2, -9.8]).items():
        for call, (function, args) in calls(model, *state).items():
            if not any(a is sd.GRAVITY for a in args):
                continue
            given = [obj if a is sd.GRAVITY else a for a in args]
            got = answer(function, given)
            if numbers is None or name in ('ctypes 2-D', 'empty'):
                expect(got[0] == 'error', call, name, got)
                expect(str(got[1]).startswith('gravity '), call, name, got)
            else:
                want = answer(function, [numbers if a is sd.GRAVITY else a for a in args])
                expect(same(got, want), call, name, got, want)
            checked += 1
    assert not problems, '\n'.join(map(repr, problems))
    assert checked > 100
    print('checked', checked)


def run_child(what):
    """Run ``what`` in a child process; fail with its output when it fails or crashes."""
    code = ('import sys; sys.path.insert(0, %r); import faulthandler; faulthandler.enable(); '
            'import test_compiled_buffer_arguments as t; %s' % (HERE, what))
    done = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, (done.returncode, done.stdout[-3000:], done.stderr[-6000:])
    assert 'checked' in done.stdout


def test_a_ctypes_array_gives_the_lists_answer_in_a_child_process():
    """The report's three calls: ctypes q into rnea, ctypes gravity, as_ctypes into M(q)."""
    run_child('t.check_the_reported_calls()')


def check_the_reported_calls():
    model = sd.Model.from_urdf(TWO_JOINTS)
    q = [0.3, -0.2]
    z = [0.0, 0.0]
    g = [0.0, 0.0, -9.81]
    np.testing.assert_array_equal(sd.rnea(model, (ctypes.c_double * 2)(*q), z, z),
                                  sd.rnea(model, q, z, z))
    np.testing.assert_array_equal(sd.rnea(model, q, z, z, (ctypes.c_double * 3)(*g)),
                                  sd.rnea(model, q, z, z, g))
    np.testing.assert_array_equal(sd.mass_matrix(model, np.ctypeslib.as_ctypes(np.array(q))),
                                  sd.mass_matrix(model, q))
    print('checked')


@pytest.mark.parametrize('urdf', [TWO_JOINTS, NO_JOINTS], ids=['two joints', 'no joints'])
def test_every_buffer_in_every_public_function(urdf):
    """Every exporter, every argument slot, every public function, both backends."""
    run_child(f't.check_every_buffer({urdf!r})')
