# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The simulated robot (MuJoCo) is the URDF's rigid-body robot: its physics against ours.

Oracles: ``sd.rnea`` (inverse dynamics), and the forward dynamics ``M(q) q̈ = τ - c(q, q̇)``
from ``sd.mass_matrix`` and ``sd.bias_torque`` integrated by the scheme the simulator uses.
"""

import os
import subprocess
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from conftest import robot_urdf_path  # noqa: E402
import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics.sim.robot import (  # noqa: E402
    MUJOCO_MISSING, SimulatedRobot)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEMO = os.path.join(ROOT, 'config', 'demo_arm.urdf')
PANDA_ARM = [f'panda_joint{i}' for i in range(1, 8)]


def urdf(name):
    return DEMO if name == 'demo' else robot_urdf_path(name)


# Robots as simulated: (URDF, model reduction). The Panda and the demo arm have a mimic finger;
# 'panda_arm' locks both fingers (one a mimic) at 2 cm.
CASES = {
    'ur5': ('ur5', {}),
    'panda': ('panda', {}),
    'panda_arm': ('panda', {'joints': PANDA_ARM, 'locked': {'panda_finger_joint1': 0.02}}),
    'demo': ('demo', {}),
    'ur5_reordered': ('ur5', {'joints': ['wrist_3_joint', 'elbow_joint', 'shoulder_pan_joint',
                                         'wrist_1_joint', 'shoulder_lift_joint',
                                         'wrist_2_joint']}),
}


@pytest.fixture(scope='module', params=sorted(CASES))
def case(request):
    name, reduction = CASES[request.param]
    return request.param, urdf(name), reduction


def states(rng, n, count=20):
    return rng.uniform(-1.0, 1.0, (count, 3, n)) * np.array([2.5, 2.0, 5.0])[:, None]


def forward(model, q, qd, tau, f_ext=None, damping=0.0, armature=0.0):
    """q̈ from our library: (M + armature) q̈ = τ - c(q, q̇) - damping·q̇ (+ Jᵀ f_ext)."""
    M = sd.mass_matrix(model, q) + np.diag(np.broadcast_to(armature, len(q)))
    c = sd.rnea(model, q, qd, np.zeros(len(q)), f_ext=f_ext) + damping * qd
    return np.linalg.solve(M, tau - c)


def test_import_spatial_dynamics_imports_no_mujoco_and_sim_robot_no_rclpy():
    code = ('import sys; import spatial_dynamics; assert "mujoco" not in sys.modules; '
            'import spatial_dynamics.sim.robot; assert "mujoco" not in sys.modules; '
            'assert "rclpy" not in sys.modules')
    subprocess.run([sys.executable, '-c', code], cwd=ROOT, check=True)


def test_missing_mujoco_is_one_clear_error():
    code = ('import sys; sys.modules["mujoco"] = None\n'
            'from spatial_dynamics.sim.robot import SimulatedRobot, MujocoMissing\n'
            'try:\n    SimulatedRobot(sys.argv[1])\n'
            'except MujocoMissing as err:\n    print(err); sys.exit(3)\n')
    proc = subprocess.run([sys.executable, '-c', code, DEMO], cwd=ROOT, capture_output=True,
                          text=True)
    assert proc.returncode == 3, proc.stderr
    assert proc.stdout.strip() == MUJOCO_MISSING


def test_mj_inverse_equals_rnea(case, rng):
    name, path, reduction = case
    robot = SimulatedRobot(path, **reduction)
    model = robot.model
    if 'joints' in reduction:
        assert model.joint_names == tuple(reduction['joints'])
    worst = 0.0
    for q, qd, qdd in states(rng, model.nq):
        tau = sd.rnea(model, q, qd, qdd)
        worst = max(worst, np.abs(robot.inverse(q, qd, qdd) - tau).max() / np.abs(tau).max())
    assert worst < 1e-9, (name, worst)


def test_mj_inverse_with_external_wrench_equals_rnea(case, rng):
    _, path, reduction = case
    robot = SimulatedRobot(path, **reduction)
    model = robot.model
    link = model.body_names[-1]
    q, qd, qdd = states(rng, model.nq, 1)[0]
    f_ext = {link: rng.normal(size=6) * 10.0, model.body_names[1]: rng.normal(size=6)}
    tau = sd.rnea(model, q, qd, qdd, f_ext=f_ext)
    assert np.allclose(robot.inverse(q, qd, qdd, f_ext), tau, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize('integrator', ['euler', 'rk4'])
def test_one_step_is_our_forward_dynamics_integrated(case, rng, integrator):
    """Euler: q̇⁺ = q̇ + h q̈, q⁺ = q + h q̇⁺; RK4: the classical tableau on (q, q̇)."""
    _, path, reduction = case
    h = 1e-3
    robot = SimulatedRobot(path, timestep=h, integrator=integrator, **reduction)
    model = robot.model
    for q, qd, tau in states(rng, model.nq, 3):
        robot.set_state(q, qd)
        t0 = robot.time
        robot.step(tau)
        if integrator == 'euler':
            qd1 = qd + h * forward(model, q, qd, tau)
            q1 = q + h * qd1
        else:
            k1 = qd, forward(model, q, qd, tau)
            k2 = qd + h / 2 * k1[1], forward(model, q + h / 2 * k1[0], qd + h / 2 * k1[1], tau)
            k3 = qd + h / 2 * k2[1], forward(model, q + h / 2 * k2[0], qd + h / 2 * k2[1], tau)
            k4 = qd + h * k3[1], forward(model, q + h * k3[0], qd + h * k3[1], tau)
            q1 = q + h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
            qd1 = qd + h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
        assert np.allclose(robot.qd, qd1, rtol=1e-9, atol=1e-9)
        assert np.allclose(robot.q, q1, rtol=1e-12, atol=1e-12)
        assert robot.time == pytest.approx(t0 + h, abs=1e-15)


def test_zero_torque_free_fall_moves_as_our_forward_dynamics(rng):
    """From rest, zero torque: the first step is q̇ = h q̈ with M q̈ = -g(q)."""
    robot = SimulatedRobot(urdf('ur5'), integrator='euler')
    q = rng.uniform(-1.0, 1.0, 6)
    robot.set_state(q)
    robot.step(np.zeros(6))
    qdd = np.linalg.solve(sd.mass_matrix(robot.model, q), -sd.gravity_torque(robot.model, q))
    assert np.linalg.norm(qdd) > 1.0                 # it does fall
    assert np.allclose(robot.qd, 1e-3 * qdd, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize('name', ['ur5', 'panda', 'panda_arm'])
def test_gravity_torque_holds_the_arm_still(name, rng):
    path, reduction = urdf(CASES[name][0]), CASES[name][1]
    robot = SimulatedRobot(path, **reduction)
    q0 = rng.uniform(-1.0, 1.0, robot.model.nq)
    robot.set_state(q0)
    for _ in range(1000):                                            # 1 s at 1 ms
        robot.step(sd.gravity_torque(robot.model, robot.q))
    assert robot.time == pytest.approx(1.0)
    assert np.abs(robot.q - q0).max() < 1e-9
    # and without it, it falls
    robot.set_state(q0)
    robot.step(np.zeros(robot.model.nq), 1000)
    assert np.abs(robot.q - q0).max() > 0.1


def test_mimic_joint_follows_its_source_exactly():
    robot = SimulatedRobot(urdf('panda'))
    mj = robot.m
    k = robot.joint_names.index('panda_finger_joint1')
    q0 = np.zeros(robot.model.nq)
    q0[k] = 0.02
    robot.set_state(q0)
    tau = np.zeros(robot.model.nq)
    tau[k] = 1.0
    robot.step(tau, 500)
    adr = [mj.joint(f'panda_finger_joint{i}').qposadr[0] for i in (1, 2)]
    assert robot.q[k] != 0.02
    assert robot.d.qpos[adr[1]] == robot.d.qpos[adr[0]]              # multiplier 1, offset 0


def test_damping_and_armature_are_the_terms_of_terms_py(rng):
    """mj_inverse adds damping·q̇ + armature·q̈; a step integrates (M + armature) q̈ = τ - c."""
    path = urdf('ur5')
    n = 6
    damping, armature = rng.uniform(0.1, 2.0, n), rng.uniform(0.01, 0.5, n)
    robot = SimulatedRobot(path, damping=damping, armature=armature, integrator='euler')
    model = robot.model
    for q, qd, qdd in states(rng, n, 5):
        expected = sd.rnea(model, q, qd, qdd) + damping * qd + sd.armature_torque(armature, qdd)
        assert np.allclose(robot.inverse(q, qd, qdd), expected, rtol=1e-9, atol=1e-9)
        robot.set_state(q, qd)
        robot.step(qdd)                                       # any torque
        qd1 = qd + 1e-3 * forward(model, q, qd, qdd, damping=damping, armature=armature)
        assert np.allclose(robot.qd, qd1, rtol=1e-9, atol=1e-9)
    # by joint name, in any order; the URDF's <dynamics> is not used unless asked for
    named = SimulatedRobot(path, damping={'elbow_joint': 3.0})
    assert named.damping.tolist() == [3.0 if j == 'elbow_joint' else 0.0
                                      for j in named.joint_names]
    demo = SimulatedRobot(DEMO)
    assert (demo.m.dof_damping == 0).all() and (demo.m.dof_frictionloss == 0).all()
    assert np.isfinite(demo.model.damping).all() and (demo.model.damping > 0).all()


def test_friction_loss_is_a_bounded_constraint_not_tanh(rng):
    """Check friction loss: in MuJoCo a dry-friction constraint force of at most ``friction``.

    In mj_inverse, once the joint slides (|q̇| well above the constraint's softness) it is
    exactly friction·sign(q̇); at rest with q̈ = 0 it is 0; it never exceeds friction (terms.py's
    friction·tanh(q̇/threshold) is the smooth counterpart). Forward, a torque below it
    barely moves a joint that is at rest.
    """
    path = urdf('ur5')
    n = 6
    friction = rng.uniform(0.5, 2.0, n)
    robot = SimulatedRobot(path, friction=friction)
    model = robot.model
    for q, qd, qdd in states(rng, n, 10):
        qd = np.sign(qd) * np.maximum(np.abs(qd), 0.5)
        extra = robot.inverse(q, qd, qdd) - sd.rnea(model, q, qd, qdd)
        assert np.allclose(extra, friction * np.sign(qd), rtol=1e-9, atol=1e-9)
        slow = 1e-3 * qd
        extra = robot.inverse(q, slow, qdd) - sd.rnea(model, q, slow, qdd)
        assert (np.abs(extra) <= friction * (1 + 1e-9)).all()
        zero = np.zeros(n)
        assert np.allclose(robot.inverse(q, zero, zero), sd.gravity_torque(model, q),
                           rtol=1e-9, atol=1e-9)
    q0 = rng.uniform(-1.0, 1.0, n)
    free = SimulatedRobot(path)
    for sim in (robot, free):
        sim.set_state(q0)
        for _ in range(200):
            sim.step(sd.gravity_torque(model, sim.q) + 0.5 * friction)
    moved, moved_free = np.abs(robot.q - q0), np.abs(free.q - q0)
    assert (moved < 0.1 * moved_free).all(), (moved, moved_free)


def test_apply_wrench_is_rneas_f_ext(rng):
    """A wrench [n; f] in the link's frame moves the robot as f_ext does in sd.rnea."""
    robot = SimulatedRobot(urdf('panda'), integrator='euler')
    model = robot.model
    wrench = np.array([0.5, -0.3, 0.2, 5.0, -3.0, 8.0])
    q, qd, tau = states(rng, model.nq, 1)[0]
    for link in ('panda_hand_tcp', 'panda_link5'):       # a lumped link, a body's own link
        robot.set_state(q, qd)
        robot.apply_wrench(link, wrench)
        robot.step(tau)
        robot.apply_wrench(link, None)
        qdd = forward(model, q, qd, tau, f_ext={link: wrench})
        assert np.allclose(robot.qd, qd + 1e-3 * qdd, rtol=1e-9, atol=1e-9)
    with pytest.raises(ValueError, match='unknown link'):
        robot.apply_wrench('nowhere', wrench)


def test_refusals_name_what_is_wrong():
    with pytest.raises(ValueError, match='panda_finger_joint2'):
        SimulatedRobot(urdf('panda'), friction=0.1)      # a constraint: not exact with mimic
    robot = SimulatedRobot(urdf('ur5'))
    with pytest.raises(ValueError, match='expected 6 values'):
        robot.step(np.zeros(5))
    with pytest.raises(ValueError, match='elbow_joint'):
        robot.step([0, 0, np.nan, 0, 0, 0])
    with pytest.raises(ValueError, match='negative|non-negative'):
        SimulatedRobot(urdf('ur5'), damping=-1.0)
    with pytest.raises(ValueError, match='timestep'):
        SimulatedRobot(urdf('ur5'), timestep=0.0)


def test_a_diverging_state_restarts_at_home_and_stays_finite():
    """The demo arm (mimic finger, our RK4): 1e6 N m once, then zeros; then 1e3 N m held.

    The state leaves what a robot reaches; the simulation restarts at its initial positions at
    rest (counted, with the reason) and then runs exactly as a fresh robot from there.
    """
    robot = SimulatedRobot(DEMO, timestep=1e-3)
    n = robot.model.nq
    home = np.linspace(-0.3, 0.3, n)
    home[-1] = 0.01       # the finger
    robot.set_state(home)
    robot.step(np.full(n, 1e6))
    for _ in range(10):
        robot.step(np.zeros(n))
        assert np.isfinite(robot.q).all() and np.isfinite(robot.qd).all()
    assert robot.resets >= 1 and 'beyond' in robot.reset_reason
    robot.step(np.full(n, 1e3), 200)
    assert np.isfinite(robot.q).all() and np.abs(robot.qd).max() <= 1e4
    # after a restart the physics is a fresh robot's
    robot.set_state(home)
    fresh = SimulatedRobot(DEMO, timestep=1e-3)
    fresh.set_state(home)
    resets = robot.resets
    robot.step(np.zeros(n), 50)
    fresh.step(np.zeros(n), 50)
    assert robot.resets == resets
    np.testing.assert_array_equal(robot.q, fresh.q)
    np.testing.assert_array_equal(robot.qd, fresh.qd)


def test_set_state_beyond_the_bounds_is_refused():
    robot = SimulatedRobot(DEMO, timestep=1e-3)
    n = robot.model.nq
    with pytest.raises(ValueError, match='beyond'):
        robot.set_state(np.full(n, 1e300))
