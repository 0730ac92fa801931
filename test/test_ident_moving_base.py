# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The inertial fits on a moving base: ``base=`` of identify_payload and identify_inertias.

A UR5 whose base sways, yaws and rolls (the closed forms of ``test_replay_moving_base``)
carries a payload on its last link; its torques are ``rnea(..., base=...)`` of the robot with
the payload. Given the base's motion the fits recover the payload exactly; ignoring it, the
base's acceleration passes for payload.
"""

import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(__file__))
from conftest import robot_urdf_path  # noqa: E402
from test_replay_moving_base import GRAVITY, joints, motion  # noqa: E402

import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics import identification  # noqa: E402
from spatial_dynamics.algorithms.regressor import parameters  # noqa: E402

MASS, COM = 1.7, np.array([0.02, -0.01, 0.05])       # kg, m in the link frame


@pytest.fixture(scope='module')
def moving():
    """``(model without payload, q, q̇, q̈, τ with the payload, base motion, body)``."""
    model = sd.Model.from_urdf(robot_urdf_path('ur5'))
    t = np.arange(0.0, 10.0, 0.01)
    q, qd, qdd = joints(t)
    body, T = identification.link_to_body(model, 'wrist_3_link')
    pi = np.zeros(10)
    pi[0], pi[1:4] = MASS, MASS * COM
    # about the link origin, in PARAMETERS' order: xx, xy, yy, xz, yz, zz
    x, y, z = COM
    pi[4:] = MASS * np.array([y * y + z * z, -x * y, x * x + z * z, -x * z, -y * z,
                              x * x + y * y]) + 1e-3 * np.array([1, 0, 1, 0, 0, 1])
    loaded = parameters(model).copy()
    loaded[10 * (body - 1):10 * body] += T @ pi
    base = motion(t)
    tau = sd.regressor(model, q, qd, qdd, GRAVITY, base=base) @ loaded
    return model, q, qd, qdd, tau, base


def test_a_payload_on_a_moving_base_is_identified_given_the_base(moving):
    model, q, qd, qdd, tau, base = moving
    found = identification.identify_payload(model, 'wrist_3_link', q, qd, qdd, tau, GRAVITY,
                                            base=base)
    assert found.mass == pytest.approx(MASS, rel=1e-9)
    np.testing.assert_allclose(found.com, COM, atol=1e-9)
    assert found.rms.max() < 1e-9
    fixed = identification.identify_payload(model, 'wrist_3_link', q, qd, qdd, tau, GRAVITY)
    assert fixed.rms.max() > 1.0        # the base's motion is no payload


def test_the_inertial_fit_on_a_moving_base_explains_the_torque(moving):
    model, q, qd, qdd, tau, base = moving
    found = identification.identify_inertias(model, q, qd, qdd, tau, ['wrist_3_link'],
                                             GRAVITY, base=base)
    # what is left is the regularisation's pull toward the URDF (1e-3 of the column norms)
    assert found.after.max() < 1e-5 * found.before.max()
    body = identification.link_to_body(model, 'wrist_3_link')[0]
    mass = found.model(model).inertia[body][3, 3]
    assert mass == pytest.approx(model.inertia[body][3, 3] + MASS, rel=1e-5)
