# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A fixed-base model on a moving base (``base=BaseMotion(v, a, orientation)``).

Oracles: the Plücker-basis paper's example (a base turning at a constant rate has zero spatial
acceleration), Pinocchio's free-flyer model of the same URDF with the base's rows of ``v``
and ``v̇`` prescribed (its joint rows are the fixed-base robot's on that base), and MuJoCo's
accelerometer and gyro on a site of a free-floating base, whose readings
:func:`~spatial_dynamics.base_from_imu` turns into the base motion that reproduces
``mj_inverse``'s joint torques.
"""

import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from conftest import robot_urdf_path, to_pin, unit_quaternions  # noqa: E402
import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics.algorithms.regressor import parameters  # noqa: E402
from spatial_dynamics.joints import quaternion_matrix  # noqa: E402

G = np.array([0.0, 0.0, -9.81])


@pytest.fixture(scope='module')
def ur5():
    return sd.Model.from_urdf(robot_urdf_path('ur5'))


@pytest.fixture(scope='module')
def pin_ur5():
    pin = pytest.importorskip('pinocchio')
    model = pin.buildModelFromUrdf(robot_urdf_path('ur5'), pin.JointModelFreeFlyer())
    return pin, model, model.createData()


def test_constant_rate_about_a_fixed_axis_has_zero_spatial_acceleration():
    # The seed's example: a body turning at ω about an axis through (0, r, 0) (parallel to z):
    # its origin moves at ṙ = ω × (-r) and accelerates towards the axis (r̈ = ω × ṙ ≠ 0), yet
    # its spatial acceleration [ω̇; r̈ - ω × ṙ] is zero.
    w, r = np.array([0.0, 0.0, 2.0]), np.array([0.0, 0.7, 0.0])
    rd = np.cross(w, -r)
    rdd = np.cross(w, rd)
    assert np.linalg.norm(rdd) == pytest.approx(2.0 ** 2 * 0.7)
    assert np.array_equal(sd.spatial_acceleration(w, rd, np.zeros(3), rdd), np.zeros(6))
    # a batch of such motions about random axes and points
    rng = np.random.default_rng(0)
    w, r = rng.normal(size=(2, 50, 3))
    rd = np.cross(w, -r)
    a = sd.spatial_acceleration(w, rd, np.zeros(3), np.cross(w, rd))
    assert a.shape == (50, 6) and np.abs(a).max() < 1e-14


def test_constant_rate_base_against_pinocchio(ur5, pin_ur5):
    # The turning base of the seed's example under the UR5: odometry reports a constant
    # twist (its rate zero), the joints feel the centripetal motion, as Pinocchio's
    # free-flyer with that twist and v̇ = 0 says; the classical acceleration r̈ given as if it
    # were spatial is wrong.
    pin, pm, pd = pin_ur5
    rng = np.random.default_rng(1)
    w, r = np.array([0.0, 0.0, 1.5]), np.array([0.0, 0.8, 0.0])
    twist = np.r_[w, np.cross(w, -r)]
    q, qd, qdd = rng.normal(size=(3, 6))
    base = sd.base_from_odometry(ur5, twist, np.zeros(6))
    tau = sd.rnea(ur5, q, qd, qdd, base=base)
    ref = pin.rnea(pm, pd, np.r_[0, 0, 0, 0, 0, 0, 1.0, q], to_pin(np.r_[twist, qd]),
                   to_pin(np.r_[np.zeros(6), qdd]))[6:]
    np.testing.assert_allclose(tau, ref, rtol=1e-12, atol=1e-12)
    classical = sd.BaseMotion(twist, np.r_[0, 0, 0, np.cross(w, twist[3:])])
    assert np.abs(sd.rnea(ur5, q, qd, qdd, base=classical) - ref).max() > 0.1


@pytest.mark.parametrize('backend', ['numpy', 'auto'])
def test_joint_rows_of_the_free_flyer(ur5, pin_ur5, backend):
    # A fixed-base UR5 on a moving base = the floating UR5 with the base rows' v, v̇ given:
    # the joint rows match pin.rnea, one state and a batch, the orientation tilting gravity.
    pin, pm, pd = pin_ur5
    rng = np.random.default_rng(2)
    N = 20
    q, qd, qdd = rng.normal(size=(3, N, 6))
    v, a = rng.normal(size=(2, N, 6))
    quat = unit_quaternions(rng, N)
    ref = np.array([pin.rnea(pm, pd, np.r_[rng.normal(size=3), quat[k], q[k]],
                             to_pin(np.r_[v[k], qd[k]]), to_pin(np.r_[a[k], qdd[k]]))[6:]
                    for k in range(N)])
    base = sd.BaseMotion(v, a, quat)
    np.testing.assert_allclose(sd.rnea(ur5, q, qd, qdd, backend=backend, base=base), ref,
                               rtol=1e-12, atol=1e-11)
    for k in (0, N - 1):     # one state; the orientation as a rotation matrix
        one = sd.BaseMotion(v[k], a[k], quaternion_matrix(quat[k]))
        np.testing.assert_allclose(sd.rnea(ur5, q[k], qd[k], qdd[k], backend=backend,
                                           base=one), ref[k], rtol=1e-12, atol=1e-11)
    # gravity_torque and bias_torque: q̈ = 0 (and q̇ = 0) for the joints, the base moving
    zero = np.zeros((N, 6))
    grav = np.array([pin.rnea(pm, pd, np.r_[0, 0, 0, quat[k], q[k]],
                              to_pin(np.r_[v[k], 0 * qd[k]]),
                              to_pin(np.r_[a[k], 0 * qd[k]]))[6:] for k in range(N)])
    np.testing.assert_allclose(sd.gravity_torque(ur5, q, backend=backend, base=base), grav,
                               rtol=1e-12, atol=1e-11)
    np.testing.assert_allclose(sd.bias_torque(ur5, q, qd, backend=backend, base=base),
                               sd.rnea(ur5, q, qd, zero, backend=backend, base=base),
                               rtol=1e-13, atol=1e-12)


def test_mass_matrix_bias_and_regressor_on_a_moving_base(ur5):
    # τ = M(q) q̈ + bias(q, q̇; base): M does not depend on the base's motion; τ = Y π.
    rng = np.random.default_rng(3)
    q, qd, qdd = rng.normal(size=(3, 8, 6))
    base = sd.BaseMotion(rng.normal(size=(8, 6)), rng.normal(size=(8, 6)),
                         unit_quaternions(rng, 8))
    tau = sd.rnea(ur5, q, qd, qdd, base=base)
    M = sd.mass_matrix(ur5, q)
    np.testing.assert_allclose(tau, np.einsum('...ij,...j->...i', M, qdd)
                               + sd.bias_torque(ur5, q, qd, base=base), rtol=1e-12,
                               atol=1e-11)
    Y = sd.regressor(ur5, q, qd, qdd, base=base)
    assert Y.shape == (8, 6, 10 * ur5.NB)
    np.testing.assert_allclose(Y @ parameters(ur5), tau, rtol=1e-11, atol=1e-10)


def test_a_base_at_rest_is_the_fixed_base(ur5):
    rng = np.random.default_rng(4)
    q, qd, qdd = rng.normal(size=(3, 6))
    np.testing.assert_allclose(sd.rnea(ur5, q, qd, qdd, base=sd.BaseMotion.at_rest()),
                               sd.rnea(ur5, q, qd, qdd), rtol=1e-13, atol=1e-12)


def test_the_base_linear_velocity_does_not_matter(ur5):
    # Galilean invariance: ([ω; v], [ω̇; r̈ - ω × v]) gives the same joint torques for any v,
    # which is why an IMU (no velocity) loses nothing.
    rng = np.random.default_rng(5)
    q, qd, qdd = rng.normal(size=(3, 6))
    w, wd, rdd = rng.normal(size=(3, 3))
    taus = []
    for v in (np.zeros(3), *rng.normal(size=(3, 3)) * 5.0):
        base = sd.BaseMotion(np.r_[w, v], sd.spatial_acceleration(w, v, wd, rdd))
        taus.append(sd.rnea(ur5, q, qd, qdd, base=base))
    np.testing.assert_allclose(taus, [taus[0]] * len(taus), rtol=1e-12, atol=1e-11)


def test_an_imu_at_rest_carries_gravity(ur5):
    # An IMU on a still, tilted base reads +g upwards (Rᵀ (-g) in its frame): from it, the
    # torques are the gravity torques of the tilted base, gravity not added twice.
    rng = np.random.default_rng(6)
    q = rng.normal(size=6)
    quat = unit_quaternions(rng, 1)[0]
    R = quaternion_matrix(quat)
    pos, imu = np.array([0.05, 0.02, 0.1]), unit_quaternions(rng, 1)[0]
    R_bs = quaternion_matrix(imu)
    reading = R_bs.T @ R.T @ -G
    base = sd.base_from_imu(ur5, 'base_link', reading, np.zeros(3), position=pos,
                            orientation=imu)
    assert base.gravity_included
    expected = sd.gravity_torque(ur5, q, base=sd.BaseMotion.at_rest(quat))
    np.testing.assert_allclose(sd.gravity_torque(ur5, q, base=base), expected, rtol=1e-12,
                               atol=1e-12)
    # the algorithm's gravity is not used with it
    np.testing.assert_allclose(sd.gravity_torque(ur5, q, gravity=(1.0, 2.0, 3.0), base=base),
                               expected, rtol=1e-12, atol=1e-12)


def test_imu_readings_of_mujoco_reproduce_its_inverse_dynamics(ur5):
    # The UR5 floating freely in MuJoCo with an IMU site (offset and tilted) on its base, at
    # random states: the accelerometer's and gyro's readings (and ω̇, which an IMU does not
    # give) through base_from_imu reproduce mj_inverse's joint torques.
    mujoco = pytest.importorskip('mujoco')
    from spatial_dynamics.sim.robot import mujoco_model, urdf_text
    path = robot_urdf_path('ur5')
    pos, quat = np.array([0.1, -0.05, 0.03]), np.array([0.2, -0.3, 0.1, 0.9])
    quat /= np.linalg.norm(quat)
    m = mujoco_model(urdf_text(path), base='floating', imus={'imu': ('base_link', pos, quat)})
    d = mujoco.MjData(m)
    names = [m.joint(j).name for j in range(1, m.njnt)]
    idx = [ur5.joint_names.index(n) for n in names]
    R_ls = quaternion_matrix(quat)
    rng = np.random.default_rng(7)
    for _ in range(5):
        d.qpos[:3] = rng.normal(size=3)
        d.qpos[3:7] = unit_quaternions(rng, 1)[0]
        d.qpos[7:] = rng.normal(size=6)
        d.qvel[:] = rng.normal(size=12)
        d.qacc[:] = qacc = rng.normal(size=12) * 3.0
        mujoco.mj_inverse(m, d)
        tau_mj = d.qfrc_inverse[6:].copy()
        d.qfrc_applied[:] = d.qfrc_inverse     # the forward dynamics: the sensors' readings
        mujoco.mj_forward(m, d)
        np.testing.assert_allclose(d.qacc, qacc, atol=1e-9)
        base = sd.base_from_imu(ur5, 'base_link', d.sensor('imu_accelerometer').data,
                                d.sensor('imu_gyro').data, R_ls.T @ qacc[3:6], pos, quat)
        q, qd, qdd = np.zeros((3, 6))
        q[idx], qd[idx], qdd[idx] = d.qpos[7:], d.qvel[6:], qacc[6:]
        tau = sd.rnea(ur5, q, qd, qdd, base=base)
        np.testing.assert_allclose(tau[idx], tau_mj, rtol=1e-10, atol=1e-10)


def test_imus_of_a_batch_read_one_motion_and_bad_poses_are_named(ur5):
    """A batch of IMU orientations was a bare "incompatible dimensions for cross product".

    One motion of the base (``ω``, ``ω̇``, the specific force at its origin) read by IMUs
    mounted at four poses (random orientations and positions, one batch): each reads
    ``R_sᵀ (f_0 + ω̇ × r + ω × (ω × r))`` and ``R_sᵀ ω``, and every pose gives the same base
    motion back; a NaN position (it was blamed on ``base.a``) or twist is named.
    """
    rng = np.random.default_rng(9)
    w, wd, f_0 = rng.normal(size=(3, 3))
    quats, r = unit_quaternions(rng, 4), rng.normal(size=(4, 3)) * 0.1
    R_s = quaternion_matrix(quats)
    f_r = f_0 + np.cross(wd, r) + np.cross(w, np.cross(w, r))
    reading = np.einsum('kji,kj->ki', R_s, f_r)             # R_sᵀ f at each IMU
    gyro, gyro_rate = np.einsum('kji,j->ki', R_s, w), np.einsum('kji,j->ki', R_s, wd)
    for orientation in (quats, R_s):
        base = sd.base_from_imu(ur5, 'base_link', reading, gyro, gyro_rate, position=r,
                                orientation=orientation)
        np.testing.assert_allclose(base.v, np.tile(np.r_[w, 0, 0, 0], (4, 1)), atol=1e-12)
        np.testing.assert_allclose(base.a, np.tile(np.r_[wd, f_0], (4, 1)), atol=1e-12)
    with pytest.raises(ValueError, match='base_from_imu: position must be finite'):
        sd.base_from_imu(ur5, 'base_link', G, np.zeros(3), position=[np.nan, 0, 0])
    with pytest.raises(ValueError, match=r'base_from_imu: the batch shapes .* do not broadcast'):
        sd.base_from_imu(ur5, 'base_link', reading, gyro, orientation=quats[:3])
    with pytest.raises(ValueError, match='base_from_odometry: twist_rate must be finite'):
        sd.base_from_odometry(ur5, np.zeros(6), [0, 0, np.inf, 0, 0, 0])


def test_jacobian_in_world_axes_on_a_tilted_base(ur5, pin_ur5):
    pin, pm, pd = pin_ur5
    rng = np.random.default_rng(8)
    q = rng.normal(size=6)
    quat = unit_quaternions(rng, 1)[0]
    qp = np.r_[0, 0, 0, quat, q]
    pin.computeJointJacobians(pm, pd, qp)
    pin.framesForwardKinematics(pm, pd, qp)
    frame = pm.getFrameId('wrist_3_link')
    J = pin.getFrameJacobian(pm, pd, frame, pin.LOCAL_WORLD_ALIGNED)[:, 6:]
    ours = sd.jacobian(ur5, q, 'wrist_3_link', 'world', base=sd.BaseMotion.at_rest(quat))
    np.testing.assert_allclose(ours, np.r_[J[3:], J[:3]], atol=1e-12)


def test_bad_base_motions_are_refused_by_name(ur5):
    with pytest.raises(ValueError, match='base.v must have shape'):
        sd.BaseMotion(np.zeros(3), np.zeros(6))
    with pytest.raises(ValueError, match='base.a must be finite'):
        sd.BaseMotion(np.zeros(6), [0, 0, np.nan, 0, 0, 0])
    with pytest.raises(ValueError, match='base.orientation'):
        sd.BaseMotion(np.zeros(6), np.zeros(6), np.zeros(4))
    with pytest.raises(TypeError, match='base must be a spatial_dynamics.BaseMotion'):
        sd.rnea(ur5, np.zeros(6), np.zeros(6), np.zeros(6), base=np.zeros(6))
    with pytest.raises(ValueError, match="moves with joint 'wrist_3_joint'"):
        sd.base_from_imu(ur5, 'wrist_3_link', G, np.zeros(3))
    with pytest.raises(ValueError, match="'nowhere' is not a link"):
        sd.base_from_imu(ur5, 'nowhere', G, np.zeros(3))
    with pytest.warns(sd.URDFWarning, match="fixed joint 'world_joint'"):
        floating = sd.Model.from_urdf(robot_urdf_path('ur5'), base='floating')
    with pytest.raises(ValueError, match='floating base'):
        sd.base_from_imu(floating, 'base_link', G, np.zeros(3))
    with pytest.raises(ValueError, match='floating base'):
        sd.rnea(floating, np.r_[np.zeros(6), 1, np.zeros(6)], np.zeros(12), np.zeros(12),
                base=sd.BaseMotion.at_rest())


def test_mass_matrix_refuses_a_base_motion_on_a_floating_model_as_rnea_does():
    """``mass_matrix(floating, q, base=...)`` was accepted where rnea refused it."""
    with pytest.warns(sd.URDFWarning, match="fixed joint 'world_joint'"):
        floating = sd.Model.from_urdf(robot_urdf_path('ur5'), base='floating')
    q = np.r_[np.zeros(6), 1, np.zeros(6)]
    for call in (lambda: sd.rnea(floating, q, np.zeros(12), np.zeros(12),
                                 base=sd.BaseMotion.at_rest()),
                 lambda: sd.generalized_momentum(floating, q, np.zeros(12),
                                                 base=sd.BaseMotion.at_rest()),
                 lambda: sd.mass_matrix(floating, q, base=sd.BaseMotion.at_rest())):
        with pytest.raises(ValueError, match="'ur5' has a floating base already"):
            call()


def test_every_function_taking_base_refuses_it_on_a_floating_model():
    """``jacobian(floating, q, link, 'world', base=...)`` turned the rows twice.

    A floating model's world rows are Pinocchio's ``LOCAL_WORLD_ALIGNED`` already (its
    free-flyer's quaternion is the base's orientation); a ``base=`` on top is refused by
    every public function that takes one, as ``rnea`` refuses it.
    """
    import inspect
    from spatial_dynamics import identification
    floating = sd.Model.from_urdf(robot_urdf_path('solo12'), base='floating')
    q = np.r_[np.zeros(6), 1, np.zeros(12)]
    z = np.zeros(18)
    tilted = sd.BaseMotion.at_rest(orientation=[0.0, 0.0, np.sin(0.4), np.cos(0.4)])
    calls = {
        'rnea': lambda b: sd.rnea(floating, q, z, z, base=b),
        'gravity_torque': lambda b: sd.gravity_torque(floating, q, base=b),
        'bias_torque': lambda b: sd.bias_torque(floating, q, z, base=b),
        'mass_matrix': lambda b: sd.mass_matrix(floating, q, base=b),
        'generalized_momentum': lambda b: sd.generalized_momentum(floating, q, z, base=b),
        'regressor': lambda b: sd.regressor(floating, q, z, z, base=b),
        'jacobian': lambda b: sd.jacobian(floating, q, 'FL_FOOT', 'world', base=b),
        'identify_payload': lambda b: identification.identify_payload(
            floating, 'FL_FOOT', q, z, z, z, base=b),
        'identify_inertias': lambda b: identification.identify_inertias(
            floating, q, z, z, z, base=b),
        'predicted_torque': lambda b: identification.predicted_torque(
            floating, q, z, z, G, base=b),
    }
    public = set()
    for module in (sd, identification):
        for name in dir(module):
            function = getattr(module, name)
            if inspect.isfunction(function) and not name.startswith('_'):
                parameters = list(inspect.signature(function).parameters)
                if parameters[:1] == ['model'] and 'base' in parameters:
                    public.add(name)
    assert public <= set(calls), public - set(calls)
    for name, call in calls.items():
        with pytest.raises(ValueError, match="'solo' has a floating base already"):
            call(tilted)
        with pytest.raises(TypeError, match='base must be a spatial_dynamics.BaseMotion'):
            call('world')
    # without base= the world rows are Pinocchio's LOCAL_WORLD_ALIGNED at the base's pose
    pin = pytest.importorskip('pinocchio')
    pm = pin.buildModelFromUrdf(robot_urdf_path('solo12'), pin.JointModelFreeFlyer())
    pdata = pm.createData()
    qt = np.r_[0.1, -0.2, 0.3, tilted.orientation, np.linspace(-0.5, 0.5, 12)]
    pin.computeJointJacobians(pm, pdata, qt)
    pin.updateFramePlacements(pm, pdata)
    Jp = pin.getFrameJacobian(pm, pdata, pm.getFrameId('FL_FOOT'), pin.LOCAL_WORLD_ALIGNED)
    cols = np.r_[3:6, 0:3, 6:18]          # Pinocchio's rows and base columns linear first
    np.testing.assert_allclose(sd.jacobian(floating, qt, 'FL_FOOT', 'world'),
                               np.r_[Jp[3:], Jp[:3]][:, cols], atol=1e-12)
