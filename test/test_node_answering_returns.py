# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The node's answers flow one way: ``Answering`` returns what to publish, the node publishes.

:class:`~spatial_dynamics.ros.answering.Answering` keeps nothing to publish between two calls
(STYLE habit 10). Pure: the answering module driven with message objects, no ROS graph; the
torques are checked against the library's RNEA, the observer's estimate against its own first
sample (zero).
"""

import os
import sys

from builtin_interfaces.msg import Duration, Time
import numpy as np
import pytest
from sensor_msgs.msg import JointState
from std_msgs.msg import Header
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from node_harness import DEMO_URDF, Log  # noqa: E402
import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics.ros import config, configure  # noqa: E402
from spatial_dynamics.ros.answering import Answer, Answering, NOTHING, Out  # noqa: E402
from spatial_dynamics.ros.plans import Job, prepare_plan  # noqa: E402


@pytest.fixture(scope='module')
def demo_text():
    with open(DEMO_URDF) as f:
        return f.read()


def configured(demo_text, **changes):
    params = {spec.name: spec.default for spec in config.PARAMETERS}
    params.update(robot_description=demo_text, **changes)
    return configure.prepare({}, params, None)


def header(t: float) -> Header:
    sec = int(t)
    return Header(stamp=Time(sec=sec, nanosec=int(round((t - sec) * 1e9))), frame_id='')


def joint_state(joints, t, q, qd=(), effort=()) -> JointState:
    return JointState(header=header(t), name=list(joints), position=list(map(float, q)),
                      velocity=list(map(float, qd)), effort=list(map(float, effort)))


def test_an_answer_is_returned_and_nothing_is_kept_to_publish(demo_text):
    cfg = configured(demo_text)
    robot = cfg.robot
    n = len(robot.joints)
    q, qd, qdd = np.linspace(-1.0, 1.0, n), np.linspace(0.5, -0.5, n), np.full(n, 0.3)
    answering = Answering(Log())
    msg = joint_state(robot.joints, 1.0, q, qd, qdd)
    out = answering.joint_state(cfg, msg)
    assert isinstance(out, Out) and out.estimate is None and out.wrench is None
    assert out.annotate is None
    answer = out.answer
    assert isinstance(answer, Answer) and answer.header is msg.header
    assert answer.joints == robot.joints and answer.terms is None
    np.testing.assert_allclose(answer.tau, sd.rnea(robot.model, q, qd, qdd, backend='numpy'),
                               rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(answer.q, q)
    # No side channel: what one message gave is not kept on the answering object
    assert not [name for name, value in vars(answering).items() if isinstance(value, Out)]
    with pytest.raises(AttributeError):
        out.answer = None                   # what was returned is not written afterwards
    # a rejected message gives nothing, and the answer returned before is untouched
    bad = joint_state(robot.joints, 2.0, [float('nan')] * n)
    assert answering.joint_state(cfg, bad) == NOTHING
    assert out.answer is answer


def test_feedback_answer_estimate_and_wrench_are_returned(demo_text):
    cfg = configured(demo_text, control_mode='pd_feedforward', kp=[10.0], kd=[1.0],
                     acceleration_source='none', observer_gain=20.0)
    robot = cfg.robot
    link = robot.model.body_names[-1]
    cfg = configure.prepare(cfg.params, {'wrench_estimate.link': link}, robot)
    robot = cfg.robot
    n = len(robot.joints)
    answering = Answering(Log())
    q_d = np.linspace(-0.5, 0.5, n)
    assert answering.joint_state(cfg, joint_state(robot.joints, 1.0, q_d)) == NOTHING  # held
    q, qd = np.zeros(n), np.full(n, 0.1)
    tau_m = sd.rnea(robot.model, q, qd, np.zeros(n), backend='numpy')
    for k, t in enumerate((1.0, 1.001)):
        msg = joint_state(robot.joints, t, q, qd, tau_m)
        out = answering.measured(cfg, msg)
        expected = (sd.rnea(robot.model, q_d, np.zeros(n), np.zeros(n), backend='numpy')
                    + 10.0 * (q_d - q) + 1.0 * (0.0 - qd))
        np.testing.assert_allclose(out.answer.tau, expected, rtol=1e-9, atol=1e-9)
        assert out.estimate is None and out.wrench is None      # the observer comes after
        seen = answering.observe(cfg, msg)
        assert seen.answer is None and seen.annotate is None
        header_, joints, r = seen.estimate
        assert header_ is msg.header and joints == robot.joints and r.shape == (n,)
        if k == 0:
            np.testing.assert_array_equal(r, np.zeros(n))   # the observer's first sample
        wrench_header, wrench_link, wrench = seen.wrench
        assert wrench_header is msg.header and wrench_link == link and wrench.shape == (6,)
        assert out.answer is not None and out.estimate is None   # each result is its own
    # observe() of a message measured() did not accept gives nothing
    assert answering.observe(cfg, joint_state(robot.joints, 1.002, q, qd, tau_m)) == NOTHING


def test_a_plan_gives_its_first_answer_and_its_job(demo_text):
    cfg = configured(demo_text, trajectory_effort_tolerance=0.5)
    robot = cfg.robot
    n = len(robot.joints)
    points = [JointTrajectoryPoint(positions=[0.1 * k] * n, velocities=[0.0] * n,
                                   time_from_start=Duration(sec=k)) for k in range(3)]
    msg = JointTrajectory(header=header(0.0), joint_names=list(robot.joints), points=points)
    out = Answering(Log()).take_plan(cfg, prepare_plan(cfg, msg), clock_ns=5_000_000_000)
    np.testing.assert_allclose(
        out.answer.tau, sd.rnea(robot.model, np.zeros(n), np.zeros(n), np.zeros(n),
                                backend='numpy'), rtol=1e-12, atol=1e-12)
    assert isinstance(out.annotate, Job) and out.annotate.config is cfg
    assert out.annotate.header is msg.header


def test_a_measured_state_stamped_closer_than_any_sensor_is_not_integrated(demo_text):
    # two joint_states 1 µs apart: Δp/Δt would be 1e6 times the change; the sample is skipped
    # with its reason in /diagnostics and the estimate is that of the states around it
    from spatial_dynamics.ros.diagnostics import observer_status
    cfg = configured(demo_text, observer_gain=20.0)
    robot = cfg.robot
    n = len(robot.joints)
    answering = Answering(Log())
    q, rest = np.linspace(-0.5, 0.5, n), np.zeros(n)
    g = sd.gravity_torque(robot.model, q, backend='numpy')
    estimates = []
    for t, qd, tau_m in ((1.0, rest, g), (1.001, rest, g), (1.001 + 1e-6, rest + 0.5, g + 50.0),
                         (1.002, rest, g)):
        msg = joint_state(robot.joints, t, q, qd, tau_m)
        answering.measured(cfg, msg)
        estimates.append(answering.observe(cfg, msg).estimate)
    assert estimates[2] is None and None not in (estimates[0], estimates[1], estimates[3])
    # held at rest by gravity's torque: nothing external, before and after the refused sample
    np.testing.assert_allclose(estimates[3][2], np.zeros(n), atol=1e-9)
    assert answering.estimates.skipped['interval_too_short'] == 1
    _, _, values = observer_status(robot, 20.0, answering.observer, answering.estimates)
    said = dict(values)
    assert said['skipped interval_too_short'] == '1'
    assert 'less than 1e-05 s' in said['last refused sample']
