# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Inputs at the edge of what the dynamics functions take, the same on every path.

``sd.rnea``, ``sd.rnea_derivatives``, ``sd.forward_dynamics``, ``sd.gravity_torque``,
``sd.bias_torque``, ``sd.mass_matrix``: one state and batches, ``backend='numpy'`` and the
compiled kernels. A batch row is the same state alone, to the bit, with per-state wrenches on
links offset from their body (Talos' soles and wrist sensors); infinite numbers give NaN as NaN
does; numbers as text are refused on every path; the dtype rule holds for float16; per-joint
terms refuse booleans.
"""

import functools

from conftest import PinOracle, random_state, robot_urdf_path
import numpy as np
import pytest
import spatial_dynamics as sd

BACKENDS = ('numpy', 'compiled')


@functools.lru_cache(maxsize=None)
def robot(name):
    """Return the Model of an example-robot-data robot, built once per session."""
    return sd.Model.from_urdf(robot_urdf_path(name))


def offset_links(model):
    """Links of a moving body whose frame is not the body's (fixed joints merged into it)."""
    return [name for name, frame in model.frames.items()
            if frame.body != 0 and not np.allclose(frame.lXb, np.eye(6))]


# A per-state wrench on a link offset from its body: a batch row is the state alone

@pytest.mark.parametrize('backend', BACKENDS)
@pytest.mark.parametrize('name', ['talos', 'panda'])
def test_a_batch_row_with_wrenches_on_offset_links_is_the_state_alone(name, backend, rng):
    model = robot(name)
    links = offset_links(model)
    assert len(links) >= 3, links        # soles, wrist sensors, the hand's TCP
    N = 40
    q, qd, qdd = random_state(rng, (N,), model.nv)
    for link in links[:4]:
        f = rng.normal(0.0, 10.0, (N, 6))
        tau = sd.rnea(model, q, qd, qdd, f_ext={link: f}, backend=backend)
        D = sd.rnea_derivatives(model, q, qd, qdd, f_ext={link: f}, backend=backend)
        for s in range(N):
            one = {link: f[s]}
            assert np.array_equal(tau[s], sd.rnea(model, q[s], qd[s], qdd[s], f_ext=one,
                                                  backend=backend)), (link, s)
            alone = sd.rnea_derivatives(model, q[s], qd[s], qdd[s], f_ext=one, backend=backend)
            for d, a in zip(D, alone):
                assert np.array_equal(d[s], a), (link, s)
        if backend == 'compiled':
            # (the numpy backend solves a batch with LAPACK's Cholesky: equal to rounding)
            qdd_fd = sd.forward_dynamics(model, q, qd, tau, f_ext={link: f}, backend=backend)
            for s in range(N):
                assert np.array_equal(qdd_fd[s], sd.forward_dynamics(
                    model, q[s], qd[s], tau[s], f_ext={link: f[s]}, backend=backend))


@pytest.mark.parametrize('backend', BACKENDS)
def test_per_state_wrenches_on_offset_links_agree_with_pinocchio(backend, rng):
    """Talos (full: grippers with mimic fingers, sole and wrist sensor frames) and its fext."""
    pytest.importorskip('pinocchio')
    model = robot('talos')
    oracle = PinOracle(robot_urdf_path('talos'))
    links = offset_links(model)
    N = 4
    q, qd, qdd = random_state(rng, (N,), model.nv)
    f = {link: rng.normal(0.0, 10.0, (N, 6)) for link in links[:4]}
    tau = sd.rnea(model, q, qd, qdd, f_ext=f, backend=backend)
    for s in range(N):
        expected = oracle.rnea(model.joint_names, q[s], qd[s], qdd[s],
                               f_ext={link: w[s] for link, w in f.items()})
        assert np.abs(tau[s] - expected).max() <= 1e-10, s
