# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The joint-torque regressor ``Y`` (``sd.regressor``): ``τ = Y π``, RNEA's linearity.

Against Pinocchio's ``computeJointTorqueRegressor`` element by element where the body frames
and the parameter order coincide (UR5, Solo12: the same bodies, the same joint frames, the
order of ``Inertia.toDynamicParameters``), and ``Y π = rnea`` with the model's own parameters
on robots with mimic joints, lumped links and many bodies; linearity in π checked on
perturbed inertias.
"""

import numpy as np
import pytest

from conftest import robot_urdf_path
from node_harness import DEMO_URDF
import spatial_dynamics as sd
from spatial_dynamics.algorithms.regressor import parameters, PARAMETERS


def random_states(model, count, seed):
    rng = np.random.default_rng(seed)
    return rng.uniform(-1.5, 1.5, size=(3, count, len(model.joint_names)))


@pytest.mark.parametrize('robot', ['ur5', 'solo12'])
def test_equals_pinocchio_joint_torque_regressor(robot):
    pin = pytest.importorskip('pinocchio')
    path = robot_urdf_path(robot)
    model = sd.Model.from_urdf(path)
    pm = pin.buildModelFromUrdf(path)
    data = pm.createData()
    assert pm.nq == len(model.joint_names) and pm.njoints - 1 == model.NB
    q, qd, qdd = random_states(model, 5, 3)
    Y = sd.regressor(model, q, qd, qdd)
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
