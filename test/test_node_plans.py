# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The node's plans (desired_trajectory) over real DDS: bounded, off the answering path.

* a plan whose splines ask beyond the bounds between in-bound points is refused whole
  (no 3.6e12 N m answers), and nothing of it is forwarded on annotated_trajectory;
* a plan stamped 10 days ahead is refused and not forwarded;
* following a plan is a live desired input: no "desired state stale" while it is followed;
* a 9,000-point plan from a default (reliable) publisher arrives and is followed;
* a plan too large for the node is refused unconverted, counted, while joint_states are
  answered; a plan too large to annotate is refused (counted) while joint_states are answered;
* a plan stamped on a simulator's clock before the first joint_states waits for that clock.

Waits are generous bounds; assertions count messages, never time them.
"""

import os
import sys
import time

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from node_harness import DEMO_URDF, NodeProcess, TIMEOUT, values  # noqa: E402
from test_node_control import connected, ok  # noqa: E402

pytestmark = pytest.mark.ros

ERROR = b'\x02'


def plan_msg(names, points, start_ns=0):
    """Return a JointTrajectory of ``points`` = [(t s, q, qd or None)], stamped ``start_ns``."""
    from builtin_interfaces.msg import Duration, Time
    from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
    msg = JointTrajectory(joint_names=list(names))
    msg.header.stamp = Time(sec=start_ns // 10**9, nanosec=start_ns % 10**9)
    for t, q, qd in points:
        ns = int(round(t * 1e9))
        p = JointTrajectoryPoint(positions=[float(x) for x in q],
                                 time_from_start=Duration(sec=ns // 10**9, nanosec=ns % 10**9))
        if qd is not None:
            p.velocities = [float(x) for x in qd]
        msg.points.append(p)
    return msg


def measured(loop, q, stamp_ns, qd=None):
    from builtin_interfaces.msg import Time
    msg = loop.measured_msg(q, np.zeros(len(q)) if qd is None else qd, 0)
    msg.header.stamp = Time(sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9)
    return msg


def answer_at(driver, io, loop, q, stamp_ns):
    """Publish a measured state stamped ``stamp_ns`` until it is answered; its answer."""
    msg = measured(loop, q, stamp_ns)
    key = (msg.header.stamp.sec, msg.header.stamp.nanosec)
    deadline = time.monotonic() + TIMEOUT
    while True:
        got = [m for m in io.efforts if (m.header.stamp.sec, m.header.stamp.nanosec) == key]
        if got:
            return got[0]
        assert time.monotonic() < deadline, f'no answer at {stamp_ns}'
        loop.measured.publish(msg)
        driver.spin_for(0.05)


def rejected(io, reason):
    return int(values(io.fresh_status('feedforward')).get(f'rejected {reason}', '0'))


@pytest.fixture
def node(install, tmp_path):
    proc = NodeProcess(install, ['-p', f'robot_description_file:={DEMO_URDF}',
                                 '-p', 'input_timeout:=0.5'], str(tmp_path))
    yield proc
    assert proc.stop() == 0, proc.log()


def annotated_sub(driver, got):
    from trajectory_msgs.msg import JointTrajectory
    return driver.node.create_subscription(JointTrajectory, 'annotated_trajectory',
                                           got.append, 10)


T0 = 3_000_000 * 10**9      # ns: the measured clock of these tests


def test_out_of_bound_plans_are_refused_and_not_forwarded(driver, node, demo_model):
    """(0 ns, 0), (1000 ns, 1 rad), (1 s, 1 rad): refused, no answer beyond the bounds.

    A plan stamped 10 days ahead is refused too; neither reaches annotated_trajectory.
    """
    names = demo_model.joint_names
    n = len(names)
    got = []
    sub = annotated_sub(driver, got)
    try:
        with connected(driver, names) as (io, loop):
            ok(io.set_parameters(control_mode='pd_feedforward', kp=[10.0], kd=[1.0],
                                 input_timeout=60.0, trajectory_effort_tolerance=0.5))
            answer_at(driver, io, loop, np.zeros(n), T0)      # the measured clock ticks
            fine = plan_msg(names, [(0.0, np.zeros(n), None), (1.0, np.full(n, 0.1), None)])
            io.trajectory.publish(fine)                        # a good plan: forwarded
            driver.spin_until(lambda: len(got) >= 1, what='the good plan annotated')
            e = np.ones(n)
            bad = plan_msg(names, [(0.0, 0 * e, None), (1e-6, e, None), (1.0, e, None)])
            io.trajectory.publish(bad)
            driver.spin_until(lambda: rejected(io, 'out_of_bounds') >= 1,
                              what='the microsecond step to be refused')
            late = plan_msg(names, [(0.0, np.zeros(n), None), (1.0, np.full(n, 0.2), None)],
                            T0 + 10 * 86400 * 10**9)
            io.trajectory.publish(late)
            driver.spin_until(lambda: rejected(io, 'start_out_of_bounds') >= 1,
                              what='the plan 10 days ahead to be refused')
            for k in range(1, 6):       # inside the refused plan's microsecond: bounded
                a = answer_at(driver, io, loop, np.zeros(n), T0 + 200 * k)
                assert np.abs(a.effort).max() < 1e3, a.effort
            driver.spin_for(0.5)
            assert len(got) == 1, 'a refused plan was forwarded to annotated_trajectory'
    finally:
        driver.node.destroy_subscription(sub)


def test_a_followed_plan_is_a_live_desired_input(driver, node, demo_model):
    """Following a 60 s plan at input_timeout 0.5 s: no "desired state stale" on the way."""
    names = demo_model.joint_names
    n = len(names)
    with connected(driver, names) as (io, loop):
        ok(io.set_parameters(control_mode='pd_feedforward', kp=[10.0], kd=[1.0]))
        io.trajectory.publish(plan_msg(names, [(0.0, np.zeros(n), None),
                                               (60.0, np.full(n, 0.3), None)], T0))
        node.wait_for_log('waiting for the first joint_states')
        answer_at(driver, io, loop, np.zeros(n), T0)
        node.wait_for_log('desired_trajectory: following 2 points')
        seen = len(io.diagnostics)
        answered = 0
        k = 0
        while len(io.diagnostics) < seen + 4:       # four periods of answering (> 0.5 s)
            k += 1
            answer_at(driver, io, loop, np.zeros(n), T0 + k * 20_000_000)
            answered += 1
        statuses = [s for msg in io.diagnostics[seen + 1:] for s in msg.status
                    if s.name.endswith(': feedforward')]
        assert answered > 4 and statuses
        for s in statuses:
            assert 'desired state stale' not in s.message, s.message
        # after the end, the last point is held on purpose: still not stale
        answer_at(driver, io, loop, np.zeros(n), T0 + 61 * 10**9)
        seen = len(io.diagnostics)
        k = 0
        while len(io.diagnostics) < seen + 3:
            k += 1
            a = answer_at(driver, io, loop, np.zeros(n), T0 + 61 * 10**9 + k * 20_000_000)
            np.testing.assert_allclose(a.position, np.full(n, 0.3), rtol=0, atol=1e-12)
        for msg in io.diagnostics[seen + 1:]:
            for s in msg.status:
                assert 'desired state stale' not in s.message, s.message


def test_a_large_plan_arrives_and_is_followed(driver, node, demo_model):
    """9,000 points (~650 KB) from a default publisher: followed (best effort lost it)."""
    names = demo_model.joint_names
    n = len(names)
    with connected(driver, names) as (io, loop):
        ok(io.set_parameters(control_mode='pd_feedforward', kp=[10.0], kd=[1.0],
                             input_timeout=60.0))
        answer_at(driver, io, loop, np.zeros(n), T0)
        t = np.arange(9000) * 0.01
        q = 0.2 * np.sin(t)[:, None] * np.ones(n)
        qd = 0.2 * np.cos(t)[:, None] * np.ones(n)
        msg = plan_msg(names, list(zip(t, q, qd)), T0)
        io.trajectory.publish(msg)
        node.wait_for_log('desired_trajectory: following 9000 points (cubic')
        a = answer_at(driver, io, loop, np.zeros(n), T0 + 45_000_000_000)
        np.testing.assert_allclose(a.position, 0.2 * np.sin(45.0) * np.ones(n), rtol=0,
                                   atol=1e-12)


def round_trips_until(driver, io, loop, n, done, start_ns):
    """Answer measured states one after the other until ``done()``; how many were answered."""
    count = 0
    while not done():
        count += 1
        answer_at(driver, io, loop, np.zeros(n), start_ns + count * 1_000_000)
    return count


@pytest.fixture
def small_bounds_node(install, tmp_path):
    """Start the node with small plan bounds, so a plan beyond them is cheap to send here."""
    proc = NodeProcess(install, ['-p', f'robot_description_file:={DEMO_URDF}',
                                 '-p', 'input_timeout:=0.5',
                                 '-p', f'trajectory_max_bytes:={MAX_BYTES}',
                                 '-p', f'trajectory_annotation_max_values:={MAX_VALUES}'],
                       str(tmp_path))
    yield proc
    assert proc.stop() == 0, proc.log()


MAX_BYTES = 1_000_000    # the node's defaults (128 MB, 4 M values) work the same way, slower
MAX_VALUES = 21_000      # 1,000 points of a cubic plan of the demo arm's 7 joints


def test_oversized_plans_are_refused_while_joint_states_are_answered(
        driver, small_bounds_node, demo_model):
    """Plans too large are refused, counted, while each measured state is answered.

    One above ``trajectory_max_bytes`` is refused unconverted; one too large to annotate
    (``trajectory_annotation_max_values``) is followed and refused by the annotation worker.
    """
    from spatial_dynamics import effort
    node = small_bounds_node
    names = demo_model.joint_names
    n = len(names)
    with connected(driver, names) as (io, loop):
        ok(io.set_parameters(control_mode='pd_feedforward', kp=[10.0], kd=[1.0],
                             input_timeout=60.0, trajectory_effort_tolerance=0.1))
        # a short plan followed first: its held end is the desired state however long this is
        io.trajectory.publish(plan_msg(names, [(0.0, np.zeros(n), None),
                                               (0.5, np.zeros(n), None)], T0))
        node.wait_for_log('waiting for the first joint_states')
        answer_at(driver, io, loop, np.zeros(n), T0)
        huge = plan_msg(names[:1], [(0.0, np.zeros(1), None)])
        huge.points[0].positions = np.zeros(MAX_BYTES // 8 + 1)
        io.trajectory.publish(huge)
        round_trips_until(driver, io, loop, n,
                          lambda: 'message rejected (too_large)' in node.log(), T0)
        assert rejected(io, 'too_large') == 1
        # 5,000 points: followed, but more than the annotation bound for 7 joints (cubic)
        t = np.arange(5_000) * 0.01
        q = 0.1 * np.sin(t)[:, None] * np.ones(n)
        qd = 0.1 * np.cos(t)[:, None] * np.ones(n)
        assert 5_000 > effort.max_points(n, 2, MAX_VALUES)
        io.trajectory.publish(plan_msg(names, list(zip(t, q, qd)), T0 + 10**9))
        count = round_trips_until(
            driver, io, loop, n,
            lambda: 'not annotated (too_many_points)' in node.log(), T0 + 10**9)
        node.wait_for_log('desired_trajectory: following 5000 points')
        assert rejected(io, 'too_many_points') == 1
        answer_at(driver, io, loop, np.zeros(n), T0 + (count + 2) * 10**9)   # still answering


def test_a_sim_time_plan_before_the_first_measured_state_waits_for_its_clock(
        driver, node, demo_model):
    """Stamped 100 s (a simulator's clock), sent before any joint_states: followed from 100 s."""
    names = demo_model.joint_names
    n = len(names)
    with connected(driver, names) as (io, loop):
        ok(io.set_parameters(control_mode='pd_feedforward', kp=[10.0], kd=[1.0],
                             input_timeout=60.0))
        start = 100 * 10**9
        io.trajectory.publish(plan_msg(names, [(0.0, np.zeros(n), None),
                                               (1.0, np.full(n, 0.4), None)], start))
        node.wait_for_log('waiting for the first joint_states')
        a = answer_at(driver, io, loop, np.zeros(n), start + 500_000_000)
        np.testing.assert_allclose(a.position, np.full(n, 0.2), rtol=0, atol=1e-12)
        assert rejected(io, 'start_out_of_bounds') == 0
