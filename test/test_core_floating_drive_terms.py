# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""``per_joint`` and the drive terms on a floating-base model (Solo12 on a free-flyer).

The values are the actuated joints'; the free-flyer's six rows (the wrench on the base) get
none. Checked against Pinocchio's free-flyer model with the same ``model.armature`` (its
``rnea`` adds ``armature · a``), the map to Pinocchio as in ``test_core_floating_base``.
"""

import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(__file__))
from test_core_floating_base import (FloatingOracle, path_of, pinocchio_text,  # noqa: E402
                                     random_floating_state)

import spatial_dynamics as sd  # noqa: E402

pin = pytest.importorskip('pinocchio')
SOLO12 = 'solo_description/robots/solo12.urdf'


@pytest.fixture(scope='module')
def solo12():
    """Solo12 on a free-flyer: our model and Pinocchio's."""
    path = path_of(SOLO12)
    return sd.Model.from_urdf(path, base='floating'), FloatingOracle(pinocchio_text(path))


def test_armature_of_a_floating_model_against_pinocchio_free_flyer(solo12, rng):
    model, oracle = solo12
    names = model.joint_names[1:]
    values = {name: float(v) for name, v in zip(names, rng.uniform(0.05, 1.5, len(names)))}
    armature = sd.per_joint(model, 'armature', values)
    assert armature.shape == (model.nv,) and not armature[:6].any()
    for name, value in values.items():
        oracle.model.armature[oracle.joints[name][1]] = value
    try:
        for shape in ((), (4,)):
            q, v, a = random_floating_state(rng, model, shape)
            tau = sd.rnea(model, q, v, a) + sd.armature_torque(armature, a)
            assert tau.shape == shape + (model.nv,)
            for k in np.ndindex(shape):
                expected = oracle.terms(model.joint_names, q[k], v[k], a[k])[0]
                assert np.linalg.norm(tau[k] - expected) <= 1e-10 * np.linalg.norm(expected)
                assert np.linalg.norm(tau[k] - sd.rnea(model, q[k], v[k], a[k])) > 1e-2
    finally:
        oracle.model.armature[:] = 0.0


def test_per_joint_forms_on_a_floating_model(solo12):
    model, oracle = solo12
    names, n = model.joint_names[1:], model.nv - 6
    expected = np.r_[np.zeros(6), np.full(n, 0.25)]
    np.testing.assert_array_equal(sd.per_joint(model, 'armature', 0.25), expected)
    values = [0.1 * (k + 1) for k in range(n)]
    np.testing.assert_array_equal(sd.per_joint(model, 'damping', values), np.r_[np.zeros(6),
                                                                                values])
    # all nv numbers, the base's six 0 (Pinocchio's model.armature)
    np.testing.assert_array_equal(sd.per_joint(model, 'damping', np.r_[np.zeros(6), values]),
                                  np.r_[np.zeros(6), values])
    out = sd.per_joint(model, 'friction', {'FL_KFE': 0.7}, default=0.1)
    assert out[6 + names.index('FL_KFE')] == 0.7 and not out[:6].any()
    assert np.all(np.delete(out[6:], names.index('FL_KFE')) == 0.1)
    # the order is Pinocchio's velocity order
    for name in names:
        one = sd.per_joint(model, 'armature', {name: 1.0})
        assert np.flatnonzero(one).tolist() == [oracle.joints[name][1]], name


def test_per_joint_refuses_drive_terms_for_the_free_flyer(solo12):
    model, _ = solo12
    n = model.nv - 6
    with pytest.raises(ValueError, match="armature: 'root_joint' is the floating base's "
                                         'free-flyer, which has no drive'):
        sd.per_joint(model, 'armature', {'root_joint': 0.1})
    with pytest.raises(ValueError, match=r'armature: 18 values whose first 6 \(the '
                                         r"free-flyer 'root_joint'"):
        sd.per_joint(model, 'armature', np.ones(model.nv))
    for bad in ([0.1] * (n - 1), [0.1] * (model.nq)):
        with pytest.raises(ValueError, match=rf"armature: expected {n} values for \('FL_HAA'"
                                             r'.* \(or 18 with the base'):
            sd.per_joint(model, 'armature', bad)


def test_friction_torque_of_a_floating_model_leaves_the_base_rows_zero(solo12, rng):
    """The URDF's <dynamics> on the actuated joints; the base rows get no friction."""
    model, _ = solo12
    _, v, _ = random_floating_state(rng, model, (3,))
    tau = sd.friction_torque(model, v, 0.01)
    assert tau.shape == (3, model.nv) and not tau[:, :6].any()
    expected = model.damping[6:] * v[:, 6:] + model.friction[6:] * np.tanh(v[:, 6:] / 0.01)
    np.testing.assert_allclose(tau[:, 6:], expected, rtol=1e-15, atol=0.0)
