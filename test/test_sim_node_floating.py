# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The installed ``sim`` node with ``floating``: Solo12 standing on the floor, over real DDS.

Its joint states, base pose and base twist are checked against a
:class:`~spatial_dynamics.sim.robot.FloatingRobot` in this process stepped with the same
commands (the same physics, so the same numbers), while the commands hold the robot up with
the contact feed-forward of ``contact_inverse_dynamics``.
"""

import math
import os
import signal
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from conftest import robot_urdf_path  # noqa: E402
import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics.sim.robot import FloatingRobot, Foot  # noqa: E402
from test_sim_node import Channels, SimProcess, sim_time  # noqa: E402

pytestmark = pytest.mark.ros

H = 0.001
FEET = ['FL_FOOT', 'FR_FOOT', 'HL_FOOT', 'HR_FOOT']
STANDING = [0.0, 0.8, -1.6, 0.0, 0.8, -1.6, 0.0, -0.8, 1.6, 0.0, -0.8, 1.6]


def floating_args(path):
    return ['-p', f'robot_description_file:={path}', '-p', 'floating:=true',
            '-p', f'feet:=[{", ".join(FEET)}]', '-p', 'foot_size:=[0.002]',
            '-p', 'friction:=0.8', '-p', f'timestep:={H}']


def test_lockstep_floating_robot_stands_with_the_same_physics(install, driver, tmp_path):
    from geometry_msgs.msg import PoseStamped, TwistStamped
    path = robot_urdf_path('solo12')
    proc = SimProcess(install, floating_args(path) + [
        '-p', 'mode:=lockstep', '-p', f'initial_positions:={STANDING}'], str(tmp_path))
    io = Channels(driver)
    poses, twists = [], []
    subs = [driver.node.create_subscription(PoseStamped, 'base_pose', poses.append, 1000),
            driver.node.create_subscription(TwistStamped, 'base_twist', twists.append, 1000)]
    try:
        io.wait_connected()
        oracle = FloatingRobot(path, [Foot(sd.Contact(f, mu=0.8), (0.002,)) for f in FEET],
                               timestep=H)
        q0 = oracle.on_floor(STANDING)
        oracle.set_state(q0)
        model, contacts = oracle.model, [f.contact for f in oracle.feet]
        assert list(io.states[0].name) == list(oracle.joint_names)
        assert np.allclose(io.states[0].position, STANDING, rtol=0, atol=0)
        zero = np.zeros(model.nv)
        hold = sd.contact_inverse_dynamics(model, q0, zero, zero, contacts, method='qp').tau
        for k in range(1, 31):
            tau = hold + 5.0 * (q0[7:] - oracle.q[7:]) - 0.05 * oracle.qd
            count = len(io.states)
            io.command(tau)

            def at_k(msgs):
                return [m for m in msgs if math.isclose(sim_time(m), k * H, abs_tol=1e-9)]

            io.driver.spin_until(lambda: at_k(io.states[count:]) and at_k(poses)
                                 and at_k(twists), what=f'step {k}')
            oracle.step(tau)
            state, pose, twist = (at_k(io.states[count:])[0], at_k(poses)[0],
                                  at_k(twists)[0])
            assert np.allclose(state.position, oracle.q[7:], rtol=0, atol=1e-12)
            assert np.allclose(state.velocity, oracle.qd, rtol=0, atol=1e-12)
            p, o = pose.pose.position, pose.pose.orientation
            assert np.allclose([p.x, p.y, p.z, o.x, o.y, o.z, o.w], oracle.q[:7],
                               rtol=0, atol=1e-12)
            w, u = twist.twist.angular, twist.twist.linear
            assert np.allclose([w.x, w.y, w.z, u.x, u.y, u.z], oracle.v[:6], rtol=0,
                               atol=1e-12)
            assert pose.header.frame_id == 'world' and twist.header.frame_id == 'base_link'
        # it stands: the floor carries it, the base is where it started to a millimetre
        assert abs(oracle.q[2] - q0[2]) < 1e-3
        weight = float(model.inertia[:, 3, 3].sum()) * 9.81
        assert sum(oracle.contact_forces().values())[2] == pytest.approx(weight, rel=0.05)
    finally:
        for sub in subs:
            driver.node.destroy_subscription(sub)
        io.close()
        assert proc.stop(signal.SIGINT) == 0, proc.log()


@pytest.mark.parametrize('params, words', [
    (['floating:=true'], ['floating: set feet']),
    (['floating:=true', 'feet:=[hand]'], ["foot 'hand': no link 'hand'"]),
    (['floating:=true', 'feet:=[FL_FOOT]', 'foot_size:=[0.1, 0.1, 0.1]'], ['foot_size']),
    (['floating:=true', 'feet:=[FL_FOOT]', 'integrator:=rk4'], ['integrator']),
    (['floating:=true', 'feet:=[FL_FOOT]', 'initial_positions:=[0.0]'],
     ['joint positions', '12']),
])
def test_bad_floating_start_up_exits_1_naming_the_problem(install, tmp_path, params, words):
    args = ['-p', f'robot_description_file:={robot_urdf_path("solo12")}']
    for param in params:
        args += ['-p', param]
    proc = SimProcess(install, args, str(tmp_path))
    proc.refused_at_start(words)
