# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The joint-torque regressor ``Y`` (``sd.regressor``): ``τ = Y π``, RNEA's linearity.

Against Pinocchio's ``computeJointTorqueRegressor`` element by element where the body frames
and the parameter order coincide (UR5, Solo12: the same bodies, the same joint frames, the
order of ``Inertia.toDynamicParameters``), for the kernel on each backend and for the 6×6
specification; ``Y π = rnea`` with the model's own parameters on robots with mimic joints,
lumped links and many bodies; linearity in π checked on perturbed inertias. The compiled
kernel against the numpy backend (the same source on Python floats and numpy arrays) and the
specification, for every argument form ``rnea`` takes, one state and batches over threads.
"""

import functools

import numpy as np
import pytest

from conftest import robot_urdf_path
from node_harness import DEMO_URDF
import spatial_dynamics as sd
from spatial_dynamics.algorithms.regressor import parameters, PARAMETERS, regressor_spatial
from spatial_dynamics.backends import compiled, layout

TOL = 1e-12
#: The implementations of Y: the kernel on each backend, and the 6×6 specification.
IMPLEMENTATIONS = {
    'auto': sd.regressor,
    'numpy': functools.partial(sd.regressor, backend='numpy'),
    'spatial': regressor_spatial,
}


def random_states(model, count, seed):
    rng = np.random.default_rng(seed)
    return rng.uniform(-1.5, 1.5, size=(3, count, len(model.joint_names)))


@pytest.mark.parametrize('implementation', sorted(IMPLEMENTATIONS))
@pytest.mark.parametrize('robot', ['ur5', 'solo12'])
def test_equals_pinocchio_joint_torque_regressor(robot, implementation):
    pin = pytest.importorskip('pinocchio')
    path = robot_urdf_path(robot)
    model = sd.Model.from_urdf(path)
    pm = pin.buildModelFromUrdf(path)
    data = pm.createData()
    assert pm.nq == len(model.joint_names) and pm.njoints - 1 == model.NB
    q, qd, qdd = random_states(model, 5, 3)
    Y = IMPLEMENTATIONS[implementation](model, q, qd, qdd)
    assert Y.shape == (5, model.nq, 10 * model.NB)
    for k in range(5):
        ref = pin.computeJointTorqueRegressor(pm, data, q[k], qd[k], qdd[k])
        np.testing.assert_allclose(Y[k], ref, rtol=0, atol=1e-12 * max(1.0, np.abs(ref).max()))
    # and the parameters are Pinocchio's, body for body
    ours = parameters(model)
    for i in range(1, model.NB + 1):
        np.testing.assert_allclose(ours[10 * (i - 1):10 * i],
                                   pm.inertias[i].toDynamicParameters(), rtol=0, atol=1e-12)


@pytest.mark.parametrize('robot', ['demo_arm', 'panda', 'talos'])
def test_y_pi_is_rnea(robot):
    """Mimic fingers (demo arm, Panda), lumped links, 32 joints (Talos); any gravity."""
    path = DEMO_URDF if robot == 'demo_arm' else robot_urdf_path(robot)
    model = sd.Model.from_urdf(path)
    q, qd, qdd = random_states(model, 4, 5)
    pi = parameters(model)
    for gravity in ((0.0, 0.0, -9.81), (1.0, -2.0, 3.0)):
        tau = sd.rnea(model, q, qd, qdd, gravity=gravity)
        Y = sd.regressor(model, q, qd, qdd, gravity=gravity)
        np.testing.assert_allclose(Y @ pi, tau, rtol=0, atol=1e-10 * max(1.0, np.abs(tau).max()))
        # one state, unbatched: the same rows
        np.testing.assert_allclose(sd.regressor(model, q[0], qd[0], qdd[0], gravity=gravity),
                                   Y[0], rtol=0, atol=1e-13 * max(1.0, np.abs(Y).max()))


def test_linear_in_the_parameters_of_other_inertias():
    """Y does not depend on π: a model with a payload has the same Y, and Y π' is its τ."""
    model = sd.Model.from_urdf(DEMO_URDF)
    heavy = sd.with_payload(model, model.body_names[-1], 2.5, (0.01, -0.02, 0.05),
                            (0.01, 0.0, 0.0, 0.02, 0.0, 0.03))
    q, qd, qdd = random_states(model, 3, 9)
    Y = sd.regressor(model, q, qd, qdd)
    np.testing.assert_array_equal(Y, sd.regressor(heavy, q, qd, qdd))
    np.testing.assert_allclose(Y @ parameters(heavy), sd.rnea(heavy, q, qd, qdd),
                               rtol=0, atol=1e-10)
    assert len(PARAMETERS) == 10 and PARAMETERS[0] == 'm'


def test_a_body_without_inertia_has_zero_parameters_but_its_columns():
    """Columns exist for every moving body; the static part is the gravity regressor."""
    model = sd.Model.from_urdf(DEMO_URDF)
    n = len(model.joint_names)
    q = np.linspace(-0.5, 0.5, n)
    z = np.zeros(n)
    Y = sd.regressor(model, q, z, z)
    np.testing.assert_allclose(Y @ parameters(model), sd.gravity_torque(model, q), atol=1e-10)
    # at rest only the mass and first moments matter (gravity is linear in m and m c)
    assert not Y.reshape(n, model.NB, 10)[:, :, 4:].any()


@functools.lru_cache(maxsize=None)
def robot(name):
    return sd.Model.from_urdf(DEMO_URDF if name == 'demo_arm' else robot_urdf_path(name))


def close(a, b, tol=TOL):
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape, (a.shape, b.shape)
    scale = max(1.0, float(np.abs(b).max(initial=0.0)))
    return float(np.abs(a - b).max(initial=0.0)) <= tol * scale


@pytest.mark.parametrize('name', ['ur5', 'panda', 'solo12', 'talos', 'demo_arm'])
def test_compiled_equals_the_numpy_backend_and_the_specification(name):
    """Mimic fingers (Panda, demo arm, Talos's grippers with multiplier -1), a tree (Solo12)."""
    assert compiled.ext is not None, compiled.FAILURE
    model = robot(name)
    q, qd, qdd = random_states(model, 7, 11)
    qd[2] = 0.0                                    # at rest, and a state without gravity
    qdd[2] = 0.0
    for gravity in ((0.0, 0.0, -9.81), (0.4, -0.3, 9.7), (0.0, 0.0, 0.0)):
        Y = sd.regressor(model, q, qd, qdd, gravity, backend='compiled')
        assert Y.shape == (7, model.nq, 10 * model.NB) and Y.dtype == np.float64
        assert close(Y, sd.regressor(model, q, qd, qdd, gravity, backend='numpy'))
        assert close(Y, regressor_spatial(model, q, qd, qdd, gravity))
        tau = sd.rnea(model, q, qd, qdd, gravity)
        assert close(Y @ parameters(model), tau, 1e-10)
        for k in range(7):      # the single-state entry and plain Python floats
            one = sd.regressor(model, q[k], qd[k], qdd[k], gravity)
            np.testing.assert_array_equal(one, Y[k])
            assert close(one, sd.regressor(model, q[k], qd[k], qdd[k], gravity,
                                           backend='numpy'))


def test_every_argument_form_rnea_takes():
    """Lists, tuples, ints, strided and integer arrays, batch dimensions, broadcasting, float32."""
    model = robot('panda')
    n, kernels = model.nq, layout.of(model).kernels
    q, qd, qdd = random_states(model, 4, 13)
    g = (0.1, 0.2, -9.8)
    ref = sd.regressor(model, q, qd, qdd, g, backend='numpy')
    wide = np.repeat(q[0], 2)[::2]
    for args in ((q[0].tolist(), tuple(qd[0].tolist()), qdd[0]),
                 (wide, qd[0], qdd[0].tolist())):
        for gravity in (g, list(g), np.array(g)):
            assert close(sd.regressor(model, *args, gravity), ref[0])
            assert compiled.ext.regressor(kernels, *args, gravity) is not None
    ints = np.arange(n) % 3 - 1
    for x in (ints, ints.tolist(), tuple(ints.tolist()), ints.astype(np.int32)):
        assert close(sd.regressor(model, x, x, x, [0, 0, -10]),
                     sd.regressor(model, ints * 1.0, ints * 1.0, ints * 1.0, (0.0, 0.0, -10.0),
                                  backend='numpy'))
    # batch dimensions of 1, a batch of two dimensions, broadcasting
    assert close(sd.regressor(model, q[:1], qd[:1], qdd[:1], g), ref[:1])
    Y = sd.regressor(model, q.reshape(2, 2, n), qd.reshape(2, 2, n), qdd.reshape(2, 2, n), g)
    assert Y.shape == (2, 2, n, 10 * model.NB) and close(Y.reshape(ref.shape), ref)
    assert close(sd.regressor(model, q, qd[0], qdd[0].tolist(), g),
                 sd.regressor(model, q, np.tile(qd[0], (4, 1)), np.tile(qdd[0], (4, 1)), g,
                              backend='numpy'))
    # float32 runs on the kernels in float64 and comes back as float32, as rnea does
    narrow = [x.astype(np.float32) for x in (q, qd, qdd)]
    Y32 = sd.regressor(model, *narrow, g)
    assert Y32.dtype == np.float32 and close(Y32, ref, 1e-4)
    np.testing.assert_array_equal(
        Y32, sd.regressor(model, *(x.astype(np.float64) for x in narrow), g).astype(np.float32))
    one = compiled.ext.regressor(kernels, *(x[0] for x in narrow), g)
    assert one.dtype == np.float32
    np.testing.assert_array_equal(one, Y32[0])
    Y32_numpy = sd.regressor(model, *narrow, g, backend='numpy')     # float32 arithmetic
    assert Y32_numpy.dtype == np.float32 and close(Y32_numpy, ref, 1e-4)
    with pytest.raises(ValueError, match='qd must have shape'):
        sd.regressor(model, q, qd[:, :3], qdd)
    with pytest.raises(ValueError, match='gravity must be a 3-vector'):
        sd.regressor(model, q, qd, qdd, (0.0, 9.81))


@pytest.mark.parametrize('N', [1, 33, 300])
def test_a_batch_over_threads_equals_the_single_calls(N):
    """Batches split over threads (the GIL released), bit for bit, any number of threads."""
    model = robot('talos')
    n, lay = model.nq, layout.of(model)
    q, qd, qdd = random_states(model, N, 17)
    Y = sd.regressor(model, q, qd, qdd)
    for k in range(0, N, 97):
        np.testing.assert_array_equal(Y[k], sd.regressor(model, q[k], qd[k], qdd[k]))
    for threads in (1, 3):
        out = np.empty((N, n, 10 * model.NB))
        compiled.ext.regressor_batch(lay.kernels, N, q, qd, qdd, sd.GRAVITY, out, threads)
        np.testing.assert_array_equal(out, Y)


def test_the_batch_entry_checks_its_buffers():
    model = robot('ur5')
    n, lay = model.nq, layout.of(model)
    Q = np.zeros((4, n))
    with pytest.raises(ValueError, match='Y must hold 1440 numbers'):
        compiled.ext.regressor_batch(lay.kernels, 4, Q, Q, Q, sd.GRAVITY, np.empty((4, n)), 2)
    with pytest.raises(TypeError, match='Y must be C-contiguous float64'):
        compiled.ext.regressor_batch(lay.kernels, 4, Q, Q, Q, sd.GRAVITY,
                                     np.empty((4, n, 60), 'f4'), 2)
