# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Every quaternion and rotation read is an orientation, or refused by name.

A free-flyer's quaternion in ``q`` and a base's orientation are normalised when their norm is
within 1e-2 of 1 (rounding, float32, integration drift: the answer is the unit quaternion's,
checked against Pinocchio), and refused otherwise (zero, NaN, 2, 1e155 whose square
overflows) with a ``ValueError`` naming the argument, by every public function and both
backends, one state or a batch (naming the first bad state). A rotation matrix must be
orthonormal within 1e-6 and proper.
"""

from conftest import robot_urdf_path, to_pin, unit_quaternions
import numpy as np
import pytest
import spatial_dynamics as sd
from spatial_dynamics import joints
from spatial_dynamics.backends import compiled

pin = pytest.importorskip('pinocchio')

BACKENDS = ('numpy', 'compiled') if compiled.ext is not None else ('numpy',)
#: Quaternions that are no orientation: zero, NaN, twice unit, 0.5, and a norm whose square
#: overflows (it became "upright" when normalised by the overflowed square).
BAD = {'zero': (0.0, 0.0, 0.0, 0.0), 'nan': (np.nan, 0.0, 0.0, 1.0),
       'two': (0.0, 0.0, 0.6 * 2, 0.8 * 2), 'half': (0.3, 0.0, 0.0, 0.4),
       'huge': (0.0, 0.0, 0.6e155, 0.8e155)}


@pytest.fixture(scope='module')
def solo():
    """Return Solo12 on a free-flyer and its Pinocchio twin."""
    path = robot_urdf_path('solo12')
    return (sd.Model.from_urdf(path, base='floating'),
            pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer()))


def state(model, rng, quat):
    """Return a random ``(q, qd, qdd)`` of ``model`` whose base quaternion is ``quat``."""
    q = rng.uniform(-1.0, 1.0, model.nq)
    q[3:7] = quat
    return q, rng.normal(size=model.nv), rng.normal(size=model.nv)


CALLS = {
    'rnea': lambda m, q, qd, qdd, b: sd.rnea(m, q, qd, qdd, backend=b),
    'rnea_list': lambda m, q, qd, qdd, b: sd.rnea(m, list(q), list(qd), list(qdd), backend=b),
    'rnea_float32': lambda m, q, qd, qdd, b: sd.rnea(
        m, q.astype(np.float32), qd.astype(np.float32), qdd.astype(np.float32), backend=b),
    'gravity_torque': lambda m, q, qd, qdd, b: sd.gravity_torque(m, q, backend=b),
    'bias_torque': lambda m, q, qd, qdd, b: sd.bias_torque(m, q, qd, backend=b),
    'mass_matrix': lambda m, q, qd, qdd, b: sd.mass_matrix(m, q, backend=b),
    'generalized_momentum': lambda m, q, qd, qdd, b: sd.generalized_momentum(m, q, qd,
                                                                             backend=b),
    'regressor': lambda m, q, qd, qdd, b: sd.regressor(m, q, qd, qdd, backend=b),
    'rnea_f_ext': lambda m, q, qd, qdd, b: sd.rnea(
        m, q, qd, qdd, f_ext={'FL_FOOT': np.ones(6)}, backend=b),
    'jacobian': lambda m, q, qd, qdd, b: sd.jacobian(m, q, 'FL_FOOT'),
    'integrate': lambda m, q, qd, qdd, b: sd.integrate(m, q, qd, 0.01),
    'contact_jacobian': lambda m, q, qd, qdd, b: sd.contact_jacobian(
        m, q, [sd.Contact('FL_FOOT')], backend=b),
    'contact_inverse_dynamics': lambda m, q, qd, qdd, b: sd.contact_inverse_dynamics(
        m, q, qd, qdd, [sd.Contact(f) for f in ('FL_FOOT', 'FR_FOOT', 'HL_FOOT', 'HR_FOOT')],
        backend=b),
}


@pytest.mark.filterwarnings('ignore:overflow encountered in cast')    # 1e155 as float32
@pytest.mark.parametrize('backend', BACKENDS)
@pytest.mark.parametrize('call', sorted(CALLS))
@pytest.mark.parametrize('bad', sorted(BAD))
def test_a_quaternion_that_is_no_orientation_is_refused_by_name(solo, rng, backend, call, bad):
    model, _ = solo
    q, qd, qdd = state(model, rng, BAD[bad])
    with pytest.raises(ValueError, match=r"q: the free-flyer quaternion of joint "
                       r"'root_joint' at q\[3:7\] has norm .*a unit quaternion"):
        CALLS[call](model, q, qd, qdd, backend)


@pytest.mark.parametrize('backend', BACKENDS)
@pytest.mark.parametrize('call', ('rnea', 'gravity_torque', 'mass_matrix', 'integrate',
                                  'regressor', 'contact_jacobian'))
def test_a_batch_names_its_first_bad_state(solo, rng, backend, call):
    model, _ = solo
    q = rng.uniform(-1.0, 1.0, (6, model.nq))
    q[:, 3:7] = unit_quaternions(rng, 6)
    q[4, 3:7], q[5, 3:7] = 0.0, np.nan
    qd, qdd = rng.normal(size=(6, model.nv)), rng.normal(size=(6, model.nv))
    with pytest.raises(ValueError, match=r'at q\[3:7\] \(state 4\) has norm 0'):
        CALLS[call](model, q, qd, qdd, backend)


@pytest.mark.parametrize('backend', BACKENDS)
@pytest.mark.parametrize('scale', (1.0 - 9e-3, 1.0 + 9e-3, 1.0 + 1e-12))
def test_a_quaternion_within_the_tolerance_is_normalised(solo, rng, backend, scale):
    # drift, float32 rounding: the unit quaternion's answer, as Pinocchio gives it
    model, pmodel = solo
    data = pmodel.createData()
    q, qd, qdd = state(model, rng, unit_quaternions(rng, 1)[0])
    drifted = q.copy()
    drifted[3:7] *= scale
    tau = sd.rnea(model, drifted, qd, qdd, backend=backend)
    assert np.allclose(tau, to_pin(pin.rnea(pmodel, data, q, to_pin(qd), to_pin(qdd))),
                       rtol=1e-12, atol=1e-10)
    batch = sd.gravity_torque(model, np.stack([drifted, q]), backend=backend)
    assert np.allclose(batch[0], batch[1], rtol=1e-12, atol=1e-10)
    moved = sd.integrate(model, drifted, qd, 0.01)
    assert np.allclose(moved, pin.integrate(pmodel, q, to_pin(qd) * 0.01), atol=1e-12)


def test_the_compiled_entry_takes_the_same_norms_as_the_check():
    if compiled.ext is None:
        pytest.skip('built without the compiled kernels')
    low, high = compiled.ext.UNIT_SQUARED
    assert (low, high) == ((1 - joints.QUATERNION_TOLERANCE) ** 2,
                           (1 + joints.QUATERNION_TOLERANCE) ** 2)


# --------------------------------------------------------------------------------------------
# A base's orientation: a quaternion or a rotation matrix

ARM = '''<robot name="arm"><link name="base"/><link name="l1">
  <inertial><mass value="2"/><origin xyz="0.1 0 0.3"/>
    <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <axis xyz="0 1 0"/><limit effort="10" velocity="1" lower="-3" upper="3"/></joint>
</robot>'''

NOT_ROTATIONS = {'zeros': np.zeros((3, 3)), 'twice': 2.0 * np.eye(3),
                 'reflection': np.diag([1.0, 1.0, -1.0]),
                 'sheared': np.eye(3) + 1e-4 * np.triu(np.ones((3, 3)), 1),
                 'nan': np.full((3, 3), np.nan)}


@pytest.mark.parametrize('what', sorted(NOT_ROTATIONS))
def test_a_matrix_that_is_no_rotation_is_refused(what):
    with pytest.raises(ValueError, match='base.orientation .*a rotation matrix'):
        sd.BaseMotion.at_rest(NOT_ROTATIONS[what])


def test_a_reflection_is_named_as_one():
    with pytest.raises(ValueError, match=r'reflection \(det -1\)'):
        sd.BaseMotion.at_rest(np.diag([-1.0, 1.0, 1.0]))


@pytest.mark.parametrize('bad', sorted(BAD))
def test_a_base_quaternion_that_is_no_orientation_is_refused(bad):
    with pytest.raises(ValueError, match='base.orientation has norm'):
        sd.BaseMotion.at_rest(BAD[bad])
    model = sd.Model.from_urdf(ARM)
    with pytest.raises(ValueError, match='base_from_odometry: orientation has norm'):
        sd.base_from_odometry(model, np.zeros(6), np.zeros(6), BAD[bad])
    with pytest.raises(ValueError, match='base_from_imu: orientation has norm'):
        sd.base_from_imu(model, 'base', (0, 0, 9.81), (0, 0, 0), orientation=BAD[bad])


def test_a_batch_of_orientations_names_its_first_bad_state(rng):
    R = np.stack([joints.quaternion_matrix(x) for x in unit_quaternions(rng, 5)])
    R[3] = np.diag([1.0, -1.0, 1.0])
    with pytest.raises(ValueError, match=r'base.orientation \(state 3\) is a reflection'):
        sd.BaseMotion(np.zeros(6), np.zeros(6), R)


def test_a_rotation_rounded_to_float32_is_a_rotation(rng):
    # an IMU driver's or a TF's float32 matrix: RᵀR − 1 ~1e-7; the answer is gravity's
    model = sd.Model.from_urdf(ARM)
    quat = unit_quaternions(rng, 1)[0]
    R = joints.quaternion_matrix(quat)
    R32 = R.astype(np.float32)
    assert np.abs(R32.T.astype(float) @ R32 - np.eye(3)).max() > 1e-9   # really rounded
    tau = sd.gravity_torque(model, [0.4], base=sd.BaseMotion.at_rest(R32))
    g_base = R.T @ np.array(sd.GRAVITY)
    assert np.allclose(tau, sd.gravity_torque(model, [0.4], gravity=g_base), atol=1e-6)
    odometry = sd.base_from_odometry(model, np.zeros(6), np.zeros(6), R32)
    assert np.allclose(sd.gravity_torque(model, [0.4], base=odometry), tau, atol=1e-12)


def test_a_base_quaternion_within_the_tolerance_is_normalised(rng):
    model = sd.Model.from_urdf(ARM)
    quat = unit_quaternions(rng, 1)[0]
    g_base = joints.quaternion_matrix(quat).T @ np.array(sd.GRAVITY)
    expected = sd.gravity_torque(model, [0.4], gravity=g_base)
    for scale in (0.995, 1.005):
        tau = sd.gravity_torque(model, [0.4], base=sd.BaseMotion.at_rest(scale * quat))
        assert np.allclose(tau, expected, rtol=1e-12, atol=1e-12)
