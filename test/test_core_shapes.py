# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The shape contract of ``sd.rnea``: (n,) or (..., n) in, the broadcast shape out."""

import os

import numpy as np
import pytest

import spatial_dynamics as sd

DEMO = os.path.join(os.path.dirname(os.path.dirname(__file__)), 'config', 'demo_arm.urdf')


@pytest.fixture(scope='module')
def model():
    return sd.Model.from_urdf(DEMO)


@pytest.mark.parametrize('backend', ['numpy', 'auto'])
def test_empty_batch_gives_empty_result(model, backend):
    n = model.nq
    for shape in ((0, n), (2, 0, n)):
        tau = sd.rnea(model, np.zeros(shape), np.zeros(n), np.zeros(n), backend=backend)
        assert tau.shape == shape


@pytest.mark.parametrize('backend', ['numpy', 'auto'])
def test_broadcast_rows_equal_single_calls(model, backend):
    rng = np.random.default_rng(7)
    n = model.nq
    q = rng.uniform(-2, 2, (4, 1, n))
    qd = rng.uniform(-2, 2, (3, n))
    qdd = rng.uniform(-2, 2, n)
    tau = sd.rnea(model, q, qd, qdd, backend=backend)
    assert tau.shape == (4, 3, n)
    for i in range(4):
        for j in range(3):
            np.testing.assert_allclose(tau[i, j], sd.rnea(model, q[i, 0], qd[j], qdd),
                                       rtol=0, atol=1e-12)


def test_wrong_joint_count_names_the_joints(model):
    with pytest.raises(ValueError, match='joint1'):
        sd.rnea(model, np.zeros(model.nq + 1), np.zeros(model.nq + 1), np.zeros(model.nq + 1))
    with pytest.raises(ValueError, match='gravity'):
        sd.rnea(model, np.zeros(model.nq), np.zeros(model.nq), np.zeros(model.nq),
                gravity=(0.0, -9.81), backend='numpy')
