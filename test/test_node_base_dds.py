# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The installed node on a moving base (an IMU) and on a floating base (Solo12), over DDS.

Oracles: ``rnea(..., base=base_from_imu(...))`` for the demo arm on a moving base,
``contact_inverse_dynamics`` for Solo12 standing on its four feet (its contact wrenches,
published per foot, carry its weight ``m g``); a stale base input gets no answer and
``/diagnostics`` says which input.
"""

import os
import sys
import time

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from conftest import robot_urdf_path  # noqa: E402
from node_harness import (  # noqa: E402
    DEMO_URDF, Io, joint_state, NodeProcess, stamp, stamp_key, TIMEOUT, values)
import spatial_dynamics as sd  # noqa: E402

pytestmark = pytest.mark.ros

FEET = ('FL_FOOT', 'FR_FOOT', 'HL_FOOT', 'HR_FOOT')


def imu_msg(k, f, w):
    from sensor_msgs.msg import Imu
    msg = Imu()
    msg.header.stamp, msg.header.frame_id = stamp(k), 'base_link'
    a, g = msg.linear_acceleration, msg.angular_velocity
    a.x, a.y, a.z = map(float, f)
    g.x, g.y, g.z = map(float, w)
    return msg


def odometry_msg(k, position, quat):
    """Return a state estimator's ``nav_msgs/Odometry`` of a base at rest at ``position``."""
    from nav_msgs.msg import Odometry
    msg = Odometry(child_frame_id='base_link')
    msg.header.stamp, msg.header.frame_id = stamp(k), 'odom'
    p, o = msg.pose.pose.position, msg.pose.pose.orientation
    p.x, p.y, p.z = map(float, position)
    o.x, o.y, o.z, o.w = map(float, quat)
    return msg


def answered(driver, io, publish, timeout=TIMEOUT):
    """Publish ``publish(k)`` every 20 ms until an answer comes; return the answers' stamps."""
    count = len(io.efforts)
    deadline = time.monotonic() + timeout
    k = 0
    while len(io.efforts) == count:
        assert time.monotonic() < deadline, 'the node never answered'
        publish(k)
        driver.spin_for(0.02)
        k += 1
    return k


def base_status(io):
    """Return the next ``base`` status of the node."""
    return io.fresh_status('base')


def test_moving_base_imu_over_dds_and_stale_imu(install, driver, demo_model, tmp_path):
    proc = NodeProcess(install, ['-p', f'robot_description_file:={DEMO_URDF}',
                                 '-p', 'base:=moving', '-p', 'base_input.imu_link:=base_link',
                                 '-p', 'base_input.timeout:=0.3'], str(tmp_path))
    io = Io(driver)
    from sensor_msgs.msg import Imu
    imu_pub = driver.node.create_publisher(Imu, 'base/imu', 10)
    try:
        io.wait_connected()
        driver.spin_until(lambda: imu_pub.get_subscription_count() >= 1, what='base/imu')
        n = len(demo_model.joint_names)
        q, qd, qdd = np.linspace(-1, 1, n), np.linspace(0.4, -0.4, n), np.full(n, 0.2)
        f, w = np.array([0.7, -1.2, 9.6]), np.array([0.1, -0.3, 0.5])

        def publish(k):
            imu_pub.publish(imu_msg(k, f, w))
            driver.spin_for(0.005)
            io.joint_states.publish(joint_state(demo_model.joint_names, q, qd, qdd, k))
        answered(driver, io, publish)
        expected = sd.rnea(demo_model, q, qd, qdd,
                           base=sd.base_from_imu(demo_model, 'base_link', f, w))
        for msg in io.efforts:
            np.testing.assert_allclose(msg.effort, expected, rtol=1e-9, atol=1e-9)
        assert np.abs(expected - sd.rnea(demo_model, q, qd, qdd)).max() > 0.1

        # the IMU stops: joint states go on, nothing is answered, diagnostics say why
        driver.spin_for(0.5)
        count = len(io.efforts)
        for k in range(1000, 1025):
            io.joint_states.publish(joint_state(demo_model.joint_names, q, qd, qdd, k))
            driver.spin_for(0.02)
        driver.spin_for(0.3)
        assert len(io.efforts) == count
        status = base_status(io)
        assert status.level == status.ERROR and 'base/imu stale' in status.message, status
        feedforward = values(io.status('feedforward'))
        assert int(feedforward['rejected base_stale']) >= 1
    finally:
        driver.node.destroy_publisher(imu_pub)
        io.close()
        assert proc.stop() == 0, proc.log()


def test_floating_solo12_standing_over_dds(install, driver, tmp_path):
    path = robot_urdf_path('solo12')
    proc = NodeProcess(install, ['-p', f'robot_description_file:={path}',
                                 '-p', 'base:=floating',
                                 '-p', f'contacts.links:=[{",".join(FEET)}]',
                                 '-p', 'base_input.acceleration:=zero'], str(tmp_path))
    io = Io(driver, )
    from geometry_msgs.msg import WrenchStamped
    from nav_msgs.msg import Odometry
    odometry_pub = driver.node.create_publisher(Odometry, 'base/odometry', 10)
    wrenches = []
    wrench_sub = driver.node.create_subscription(WrenchStamped, 'contact_wrenches',
                                                 wrenches.append, 100)
    model = sd.Model.from_urdf(path, base='floating')
    joints = model.joint_names[1:]
    q = np.array([{'HAA': 0.05, 'HFE': 0.8 if j[0] == 'F' else -0.8,
                   'KFE': -1.6 if j[0] == 'F' else 1.6}[j[3:]] for j in joints])
    quat = np.array([0.02, -0.03, 0.01, 1.0]) / np.sqrt(1.0014)
    position = (0.1, 0.2, 0.25)
    zero = np.zeros(12)
    try:
        io.wait_connected()
        driver.spin_until(lambda: (odometry_pub.get_subscription_count() >= 1
                                   and wrench_sub.get_publisher_count() >= 1),
                          what='the base topics')

        def publish(k):
            odometry_pub.publish(odometry_msg(k, position, quat))
            driver.spin_for(0.005)
            io.joint_states.publish(joint_state(joints, q, zero, zero, k))
        answered(driver, io, publish)
        driver.spin_for(0.3)
        q_full = np.r_[position, quat, q]
        expected = sd.contact_inverse_dynamics(model, q_full, np.zeros(18), np.zeros(18),
                                               [sd.Contact(f) for f in FEET])
        assert list(io.efforts[0].name) == list(joints)
        for msg in io.efforts:
            np.testing.assert_allclose(msg.effort, expected.tau, rtol=1e-9, atol=1e-9)
        k = stamp_key(io.efforts[0].header.stamp)
        mine = [w for w in wrenches if stamp_key(w.header.stamp) == k]
        assert sorted(w.header.frame_id for w in mine) == sorted(FEET)
        rotations = sd.contacts.link_orientations(model, q_full, FEET)
        total = np.zeros(3)
        for w in mine:
            f = w.wrench.force
            total += rotations[w.header.frame_id] @ np.array([f.x, f.y, f.z])
        weight = model.inertia[:, 3, 3].sum() * 9.81
        np.testing.assert_allclose(total, [0.0, 0.0, weight], atol=1e-9)
        status = base_status(io)
        assert 'contact solutions' in values(status)
    finally:
        driver.node.destroy_publisher(odometry_pub)
        driver.node.destroy_subscription(wrench_sub)
        io.close()
        assert proc.stop() == 0, proc.log()
