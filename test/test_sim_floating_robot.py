# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A floating-base robot on a floor in MuJoCo (``FloatingRobot``), in our coordinates.

Oracles: ``sd.rnea`` of the floating model (MuJoCo's ``mj_inverse`` converted), MuJoCo's own
body velocity (``mj_objectVelocity``) for the meaning of our base twist, and the robot's weight
for the contact forces of a robot standing still.
"""

import os
import sys

import numpy as np
import pytest

pytest.importorskip('mujoco')
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from conftest import robot_urdf_path  # noqa: E402
import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics.sim.robot import FloatingRobot, Foot, without_mimic  # noqa: E402
from spatial_dynamics.tools.legged import gains  # noqa: E402

SOLO_FEET = ('FL_FOOT', 'FR_FOOT', 'HL_FOOT', 'HR_FOOT')


def solo():
    feet = [Foot(sd.Contact(link), (0.002,)) for link in SOLO_FEET]
    return FloatingRobot(robot_urdf_path('solo12'), feet)


def talos():
    with open(robot_urdf_path('talos_reduced'), encoding='utf-8') as f:
        xml = without_mimic(f.read())
    feet = [Foot(sd.Contact(f'{side}_sole_link', kind='surface'), (0.1, 0.05))
            for side in ('left', 'right')]
    return FloatingRobot(xml, feet)


def random_state(model, rng):
    q = rng.uniform(-1.0, 1.0, model.nq)
    q[3:7] /= np.linalg.norm(q[3:7])
    return q, rng.uniform(-2.0, 2.0, model.nv), rng.uniform(-5.0, 5.0, model.nv)


@pytest.mark.parametrize('make', [solo, talos], ids=['solo12', 'talos'])
def test_mj_inverse_in_our_coordinates_equals_rnea_of_the_floating_model(make):
    robot = make()
    model = robot.model
    assert model.floating and robot.m.nv == model.nv
    rng = np.random.default_rng(7)
    for _ in range(10):
        q, v, a = random_state(model, rng)
        tau = sd.rnea(model, q, v, a)
        assert np.allclose(robot.inverse(q, v, a), tau, rtol=0.0,
                           atol=1e-9 * max(1.0, np.abs(tau).max()))


def test_state_conversion_is_exact_both_ways_and_means_what_mujoco_means():
    import mujoco
    robot = solo()
    model = robot.model
    rng = np.random.default_rng(3)
    for _ in range(5):
        q, v, _ = random_state(model, rng)
        robot.set_state(q, v)
        assert np.allclose(robot.q, q, rtol=0.0, atol=1e-15)
        assert np.allclose(robot.v, v, rtol=0.0, atol=1e-14)
        # MuJoCo's own reading of the base's motion: [ω; v] of the root body, world axes
        vel = np.zeros(6)
        mujoco.mj_objectVelocity(robot.m, robot.d, mujoco.mjtObj.mjOBJ_BODY,
                                 robot.m.body('base_link').id, vel, 0)
        R = robot.d.xmat[robot.m.body('base_link').id].reshape(3, 3)
        assert np.allclose(R.T @ vel[:3], v[:3], atol=1e-12)      # ω, base frame
        assert np.allclose(R.T @ vel[3:], v[3:6], atol=1e-12)     # v of the origin, base frame
        quat = robot.d.qpos[3:7]                                  # MuJoCo's w x y z
        assert np.allclose(np.r_[quat[1:], quat[0]], q[3:7], atol=1e-15)
        assert np.allclose(robot.d.qpos[robot.m.joint('FL_KFE').qposadr[0]],
                           q[7 + model.joint_names[1:].index('FL_KFE')])


def test_standing_still_the_floor_carries_the_weight_at_the_feet():
    robot = solo()
    model = robot.model
    q = np.zeros(model.nq)
    q[6] = 1.0
    for leg, sign in (('FL', 1), ('FR', 1), ('HL', -1), ('HR', -1)):
        q[7 + robot.joint_names.index(f'{leg}_HFE')] = 0.8 * sign
        q[7 + robot.joint_names.index(f'{leg}_KFE')] = -1.6 * sign
    low = min(robot.frame_pose(q, link)[1][2] for link in SOLO_FEET)
    q[2] = 0.002 - low                                 # the spheres touch the floor
    robot.set_state(q)
    contacts = [f.contact for f in robot.feet]
    zero = np.zeros(model.nv)
    hold = sd.contact_inverse_dynamics(model, q, zero, zero, contacts, method='qp')
    kp, kd = gains(model, q, 10.0)
    for _ in range(1500):
        robot.step(hold.tau + kp * (q[7:] - robot.q[7:]) - kd * robot.v[6:])
    forces = robot.contact_forces()
    weight = float(model.inertia[:, 3, 3].sum()) * 9.81
    total = sum(forces.values())
    assert np.abs(robot.v).max() < 1e-4                             # it stands still
    assert total[2] == pytest.approx(weight, rel=1e-3)
    assert np.abs(total[:2]).max() < 1e-3 * weight
    for c in contacts:          # each foot as the QP split it (the legs are square: unique)
        assert forces[c.name][2] == pytest.approx(hold.forces[c.name][2], rel=0.01)


def test_a_sole_box_lies_on_its_sole_plane():
    robot = talos()
    q = np.zeros(robot.model.nq)
    q[6] = 1.0
    q[2] = -robot.frame_pose(q, 'left_sole_link')[1][2]        # the soles on the floor
    robot.set_state(q)
    for _ in range(20):         # falling from rest: it touches the floor, nothing pushes yet
        robot.step(np.zeros(robot.model.nv - 6))
    assert sum(robot.contact_forces().values())[5] > 0.0
    assert robot.q[2] < q[2]                    # and did not pop up out of the floor


def test_mimic_joints_are_refused_by_name():
    with pytest.raises(ValueError, match=r'mimic joints are not simulated \(gripper_left'):
        FloatingRobot(robot_urdf_path('talos_reduced'))


def test_a_foot_of_the_wrong_size_or_link_is_refused_by_name():
    with pytest.raises(ValueError, match=r"foot 'left_sole_link': size must be 2"):
        Foot(sd.Contact('left_sole_link', kind='surface'), (0.1,))
    with pytest.raises(ValueError, match=r"foot 'FL_FOOT': size must be 1 positive"):
        Foot(sd.Contact('FL_FOOT'), (-0.01,))
    with pytest.raises(ValueError, match=r"foot 'hand': no link 'hand'"):
        FloatingRobot(robot_urdf_path('solo12'), [Foot(sd.Contact('hand'))])


def test_a_foot_on_the_world_is_refused_by_name():
    """Refuse ``world``: MuJoCo's ``spec.body('world')`` is its world (was accepted)."""
    with pytest.raises(ValueError, match=r"foot 'world': no link 'world' in robot 'solo'"):
        FloatingRobot(robot_urdf_path('solo12'), [Foot(sd.Contact('world'))])


def test_a_diverging_floating_robot_restarts_at_home_within_the_bounds():
    """Solo12 under 1e6 N m: joint velocities reached 3.4e6 rad/s; the fixed-base rule holds.

    A velocity beyond ±1e4 rad/s (a position beyond ±1e5) restarts at :attr:`home` at rest,
    counted with the reason, as :class:`SimulatedRobot` does; then it runs as a fresh robot.
    """
    robot = solo()
    home = robot.on_floor()
    robot.set_state(home)
    n = robot.model.nv - 6
    top = 0.0
    for _ in range(200):
        robot.step(np.full(n, 1e6))
        assert np.isfinite(robot.q).all() and np.isfinite(robot.v).all()
        top = max(top, float(np.abs(robot.v).max()))
    assert top <= 1e4
    assert robot.resets >= 1 and 'beyond ±10000 rad/s' in robot.reset_reason, (
        robot.resets, robot.reset_reason)
    robot.set_state(home)
    fresh = solo()
    fresh.set_state(home)
    resets = robot.resets
    robot.step(np.zeros(n), 50)
    fresh.step(np.zeros(n), 50)
    assert robot.resets == resets
    np.testing.assert_array_equal(robot.q, fresh.q)
    np.testing.assert_array_equal(robot.v, fresh.v)
