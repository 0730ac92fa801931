# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The node on a moving or floating base, without a ROS graph (``base``, ``base_input.*``).

Oracles: the library's ``rnea(..., base=base_from_imu(...))`` and ``base_from_odometry`` for a
moving base, ``contact_inverse_dynamics`` for a floating one (Solo12 standing on its four
feet: the contact wrenches carry its weight, ``m g``); a missing, stale or bad base input is
refused with its reason and no answer, never computed as if the base were fixed.
"""

import os
import sys
import time

from builtin_interfaces.msg import Time
from geometry_msgs.msg import PoseStamped, TwistStamped
from nav_msgs.msg import Odometry
import numpy as np
import pytest
from sensor_msgs.msg import Imu, JointState
from std_msgs.msg import Header, UInt8MultiArray

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from conftest import least_torque_split, robot_urdf_path, to_pin  # noqa: E402
from node_harness import DEMO_URDF, Log  # noqa: E402
import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics.ros import config, configure  # noqa: E402
from spatial_dynamics.ros.answering import Answering  # noqa: E402
from spatial_dynamics.ros.diagnostics import base_status  # noqa: E402
from spatial_dynamics.ros.floating import qp_missing_warning  # noqa: E402
from spatial_dynamics.ros.parameters import ConfigError  # noqa: E402

FEET = ('FL_FOOT', 'FR_FOOT', 'HL_FOOT', 'HR_FOOT')


def configured(**changes):
    params = {spec.name: spec.default for spec in config.PARAMETERS}
    params.update(changes)
    return configure.prepare({}, params, None)


def header(t: float, frame: str = '') -> Header:
    sec = int(t)
    return Header(stamp=Time(sec=sec, nanosec=int(round((t - sec) * 1e9))), frame_id=frame)


def joint_state(joints, t, q, qd, qdd) -> JointState:
    return JointState(header=header(t), name=list(joints), position=list(map(float, q)),
                      velocity=list(map(float, qd)), effort=list(map(float, qdd)))


def imu(t, f, w, frame='base_link') -> Imu:
    msg = Imu(header=header(t, frame))
    a, g = msg.linear_acceleration, msg.angular_velocity
    a.x, a.y, a.z = map(float, f)
    g.x, g.y, g.z = map(float, w)
    return msg


def pose(t, p, quat, frame='odom') -> PoseStamped:
    msg = PoseStamped(header=header(t, frame))
    msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = map(float, p)
    o = msg.pose.orientation
    o.x, o.y, o.z, o.w = map(float, quat)
    return msg


def twist(t, v, frame='') -> TwistStamped:
    msg = TwistStamped(header=header(t, frame))
    w, lin = msg.twist.angular, msg.twist.linear
    w.x, w.y, w.z, lin.x, lin.y, lin.z = map(float, v)
    return msg


@pytest.fixture(scope='module')
def demo_text():
    with open(DEMO_URDF) as f:
        return f.read()


@pytest.fixture(scope='module')
def solo_path():
    return robot_urdf_path('solo12')


def standing(joints):
    """Solo12's joints standing, knees bent (rad), in ``joints`` order."""
    return np.array([{'HAA': 0.05, 'HFE': 0.8 if j[0] == 'F' else -0.8,
                      'KFE': -1.6 if j[0] == 'F' else 1.6}[j[3:]] for j in joints])


# -------------------------------------------------------------------------------------------
# moving base

def test_moving_base_on_an_imu_is_rnea_with_base_from_imu(demo_text):
    cfg = configured(robot_description=demo_text, base='moving',
                     **{'base_input.imu_link': 'base_link'})
    robot = cfg.robot
    n = len(robot.joints)
    answering = Answering(Log())
    f, w = np.array([0.7, -1.2, 9.6]), np.array([0.1, -0.3, 0.5])
    answering.base_input(cfg, 'base/imu', imu(1.0, f, w))
    q, qd, qdd = np.linspace(-1, 1, n), np.linspace(0.4, -0.4, n), np.full(n, 0.2)
    out = answering.joint_state(cfg, joint_state(robot.joints, 1.0, q, qd, qdd))
    expected = sd.rnea(robot.model, q, qd, qdd, base=sd.base_from_imu(
        robot.model, 'base_link', f, w))
    np.testing.assert_allclose(out.answer.tau, expected, rtol=1e-9, atol=1e-9)
    fixed = sd.rnea(robot.model, q, qd, qdd)
    assert np.abs(out.answer.tau - fixed).max() > 0.1       # the base's motion matters
    f2 = np.array([-2.0, 0.5, 11.0])                        # the next sample is used
    answering.base_input(cfg, 'base/imu', imu(1.01, f2, w))
    out = answering.joint_state(cfg, joint_state(robot.joints, 1.01, q, qd, qdd))
    np.testing.assert_allclose(out.answer.tau, sd.rnea(robot.model, q, qd, qdd, base=(
        sd.base_from_imu(robot.model, 'base_link', f2, w))), rtol=1e-9, atol=1e-9)


def test_moving_base_without_or_with_a_stale_imu_publishes_nothing(demo_text):
    cfg = configured(robot_description=demo_text, base='moving',
                     **{'base_input.imu_link': 'base_link', 'base_input.timeout': 0.2})
    robot = cfg.robot
    n = len(robot.joints)
    answering = Answering(Log())
    msg = joint_state(robot.joints, 1.0, np.zeros(n), np.zeros(n), np.zeros(n))
    assert answering.joint_state(cfg, msg).answer is None
    assert answering.totals.rejected['base_missing'] == 1
    answering.base_input(cfg, 'base/imu', imu(1.0, [0, 0, 9.81], [0, 0, 0]))
    assert answering.joint_state(cfg, msg).answer is not None
    answering.base_inputs.imu.receipt_ns -= int(0.3e9)        # 0.3 s later
    assert answering.joint_state(cfg, msg).answer is None
    assert answering.totals.rejected['base_stale'] == 1
    level, text, _ = base_status(cfg.params, robot, answering.base_inputs,
                                 answering.base_inputs.period(),
                                 answering.base_inputs.imu.receipt_ns + int(0.3e9))
    assert level == 'ERROR' and 'base/imu stale' in text and 'not publishing' in text


def test_moving_base_on_pose_and_twist_is_rnea_with_base_from_odometry(demo_text):
    cfg = configured(robot_description=demo_text, base='moving',
                     **{'base_input.source': 'twist'})
    robot = cfg.robot
    n = len(robot.joints)
    answering = Answering(Log())
    quat = np.array([0.1, -0.2, 0.05, 0.97])
    quat /= np.linalg.norm(quat)
    v0, v1 = np.array([0.0, 0.0, 0.5, 1.0, 0.0, 0.0]), np.array([0.0, 0.0, 0.52, 0.98, 0.0, 0.0])
    answering.base_input(cfg, 'base/pose', pose(1.0, [1, 2, 0], quat))
    answering.base_input(cfg, 'base/twist', twist(1.0, v0))
    q, qd, qdd = np.full(n, 0.3), np.full(n, -0.2), np.full(n, 0.1)
    msg = joint_state(robot.joints, 1.0, q, qd, qdd)
    assert answering.joint_state(cfg, msg).answer is None   # one twist: no rate yet
    answering.base_input(cfg, 'base/twist', twist(1.01, v1))
    out = answering.joint_state(cfg, msg)
    rate = (v1 - v0) / 0.01
    expected = sd.rnea(robot.model, q, qd, qdd, base=sd.base_from_odometry(
        robot.model, v1, rate, quat))
    np.testing.assert_allclose(out.answer.tau, expected, rtol=1e-9, atol=1e-9)


def odometry(t, p, quat, v, child='') -> Odometry:
    msg = Odometry(header=header(t, 'odom'), child_frame_id=child)
    msg.pose.pose = pose(t, p, quat).pose
    msg.twist.twist = twist(t, v).twist
    return msg


def test_moving_base_on_odometry_is_its_pose_and_twist(demo_text):
    """``base/odometry`` (nav_msgs/Odometry) gives the answer its pose and twist would."""
    cfg = configured(robot_description=demo_text, base='moving',
                     **{'base_input.source': 'twist'})
    robot = cfg.robot
    n = len(robot.joints)
    quat = np.array([0.1, -0.2, 0.05, 0.97]) / np.linalg.norm([0.1, -0.2, 0.05, 0.97])
    v0, v1 = np.array([0.0, 0.1, 0.5, 1.0, 0.0, 0.2]), np.array([0.0, 0.1, 0.52, 0.98, 0.0, 0.2])
    q, qd, qdd = np.full(n, 0.3), np.full(n, -0.2), np.full(n, 0.1)
    msg = joint_state(robot.joints, 1.0, q, qd, qdd)
    answers = []
    for feed in ('odometry', 'pose and twist'):
        answering = Answering(Log())
        for t, v in ((1.0, v0), (1.01, v1)):
            if feed == 'odometry':
                answering.base_input(cfg, 'base/odometry',
                                     odometry(t, [1, 2, 0], quat, v, 'base_link'))
            else:
                answering.base_input(cfg, 'base/pose', pose(t, [1, 2, 0], quat))
                answering.base_input(cfg, 'base/twist', twist(t, v, 'base_link'))
        answers.append(answering.joint_state(cfg, msg).answer.tau)
    expected = sd.rnea(robot.model, q, qd, qdd, base=sd.base_from_odometry(
        robot.model, v1, (v1 - v0) / 0.01, quat))
    np.testing.assert_allclose(answers[0], expected, rtol=1e-9, atol=1e-9)
    np.testing.assert_array_equal(answers[0], answers[1])
    # a bad orientation refuses the whole message: the twist is not held without its pose
    answering = Answering(Log())
    answering.base_input(cfg, 'base/odometry', odometry(1.0, [0, 0, 0], [0, 0, 0, 0.5], v0))
    answering.base_input(cfg, 'base/odometry', odometry(1.0, [0, 0, 0], quat, v0, 'link3'))
    inputs = answering.base_inputs
    assert inputs.pose is None and inputs.twist is None
    assert dict(inputs.rejected) == {'base/odometry not_unit': 1,
                                     'base/odometry wrong_frame': 1}


def test_bad_base_inputs_are_refused_with_their_reason(demo_text):
    cfg = configured(robot_description=demo_text, base='moving',
                     **{'base_input.imu_link': 'base_link', 'base_input.source': 'twist'})
    answering = Answering(Log())
    inputs = answering.base_inputs
    answering.base_input(cfg, 'base/pose', pose(1.0, [0, 0, 0], [0, 0, 0, 0.5]))
    answering.base_input(cfg, 'base/pose', pose(1.0, [np.nan, 0, 0], [0, 0, 0, 1]))
    answering.base_input(cfg, 'base/pose', pose(1.0, [2e5, 0, 0], [0, 0, 0, 1]))
    answering.base_input(cfg, 'base/twist', twist(1.0, [0, 0, 0, 0, 0, 0], 'link3'))
    answering.base_input(cfg, 'base/twist', twist(0.0, [0, 0, 0, 0, 0, 0]))
    answering.base_input(cfg, 'base/imu', imu(1.0, [0, 0, 9.8], [0, 0, 0], 'link2'))
    answering.base_input(cfg, 'base/imu', imu(1.0, [0, 0, np.inf], [0, 0, 0]))
    assert inputs.pose is None and inputs.twist is None and inputs.imu is None
    assert dict(inputs.rejected) == {
        'base/pose not_unit': 1, 'base/pose non_finite': 1, 'base/pose out_of_bounds': 1,
        'base/twist wrong_frame': 1, 'base/twist unstamped': 1, 'base/imu wrong_frame': 1,
        'base/imu non_finite': 1}
    said = ' '.join(text for _, text in answering.log.said)
    assert "'x'" in said and 'not a unit quaternion' in said and "'link3'" in said
    answering.base_input(cfg, 'base/twist', twist(2.0, [0, 0, 0, 0, 0, 0]))
    answering.base_input(cfg, 'base/twist', twist(1.5, [0, 0, 0, 0, 0, 0]))
    assert inputs.rejected['base/twist stamp_not_increasing'] == 1


def test_base_parameters_are_checked_against_the_model(demo_text, solo_path):
    with pytest.raises(ConfigError, match='base_input.imu_link.*link2.*moves with joint'):
        configured(robot_description=demo_text, base='moving',
                   **{'base_input.imu_link': 'link2'})
    with pytest.raises(ConfigError, match='base_input.imu_link.*needs the link'):
        configured(robot_description=demo_text, base='moving')
    with pytest.raises(ConfigError, match="contacts.links: 'LF_FOOT' is not a link"):
        configured(robot_description_file=solo_path, base='floating',
                   **{'contacts.links': ['LF_FOOT']})
    with pytest.raises(ConfigError, match="wrench_estimate.link: not supported with base"):
        configured(robot_description_file=solo_path, base='floating',
                   **{'wrench_estimate.link': 'FL_FOOT', 'contacts.links': list(FEET)})
    with pytest.raises(ConfigError, match='armature: expected 12 values for the actuated'):
        configured(robot_description_file=solo_path, base='floating', armature=[0.1] * 13,
                   **{'contacts.links': list(FEET)})
    with pytest.raises(ConfigError, match='base'):
        configured(robot_description=demo_text, base='sideways')
    assert configured(robot_description=demo_text).params.base == 'fixed'


# -------------------------------------------------------------------------------------------
# floating base

def floating(solo_path, **changes):
    return configured(robot_description_file=solo_path, base='floating',
                      **{'contacts.links': list(FEET), 'base_input.acceleration': 'zero',
                         **changes})


def feed_base(cfg, answering, quat=(0.02, -0.03, 0.01, 1.0)):
    quat = np.array(quat) / np.linalg.norm(quat)
    answering.base_input(cfg, 'base/pose', pose(1.0, [0.1, 0.2, 0.25], quat))
    answering.base_input(cfg, 'base/twist', twist(1.0, np.zeros(6), 'base_link'))
    answering.base_input(cfg, 'base/twist', twist(1.0, np.zeros(6), 'FL_FOOT'))   # refused
    assert answering.base_inputs.rejected['base/twist wrong_frame'] == 1
    return np.r_[0.1, 0.2, 0.25, quat]


def world_forces(model, q_full, contacts):
    rotations = sd.contacts.link_orientations(model, q_full, [link for link, _ in contacts])
    return {link: rotations[link] @ w[3:] for link, w in contacts}


def test_floating_solo12_standing_is_contact_inverse_dynamics(solo_path):
    cfg = floating(solo_path)
    robot = cfg.robot
    assert robot.joints == robot.model.joint_names[1:] and 'root_joint' not in robot.joints
    answering = Answering(Log())
    base_q = feed_base(cfg, answering)
    q = standing(robot.joints)
    zero = np.zeros(12)
    out = answering.joint_state(cfg, joint_state(robot.joints, 1.0, q, zero, zero))
    expected = sd.contact_inverse_dynamics(
        robot.model, np.r_[base_q, q], np.zeros(18), np.zeros(18),
        [sd.Contact(f) for f in FEET])
    assert len(out.answer.tau) == 12
    np.testing.assert_allclose(out.answer.tau, expected.tau, rtol=1e-9, atol=1e-9)
    forces = world_forces(robot.model, np.r_[base_q, q], out.answer.contacts)
    assert set(forces) == set(FEET)
    for link in FEET:
        np.testing.assert_allclose(forces[link], expected.forces[link], atol=1e-9)
    weight = robot.model.inertia[:, 3, 3].sum() * 9.81
    np.testing.assert_allclose(sum(forces.values()), [0.0, 0.0, weight], atol=1e-9)
    level, _, values = base_status(cfg.params, robot, answering.base_inputs,
                                   answering.base_inputs.period(), answering.base_inputs
                                   .pose.receipt_ns)
    assert level == 'OK' and dict(values)['contact solutions'] == '1'


def test_contact_wrenches_are_computed_when_read_not_on_every_answer(solo_path, monkeypatch):
    """An answer carries its contact wrenches unread: the node reads them for a subscriber."""
    from spatial_dynamics.ros import floating as floating_module
    computed = []
    compute = floating_module.contact_wrenches
    monkeypatch.setattr(floating_module, 'contact_wrenches',
                        lambda *args: computed.append(args) or compute(*args))
    cfg = floating(solo_path)
    robot = cfg.robot
    answering = Answering(Log())
    base_q = feed_base(cfg, answering)
    q = standing(robot.joints)
    zero = np.zeros(12)
    out = answering.joint_state(cfg, joint_state(robot.joints, 1.0, q, zero, zero))
    assert out.answer is not None and computed == []
    first = list(out.answer.contacts)
    assert len(computed) == 1 and [link for link, _ in first] == list(FEET)
    again = list(out.answer.contacts)          # computed once, read as often as wanted
    assert len(computed) == 1 and all(a[1] is b[1] for a, b in zip(first, again))
    forces = world_forces(robot.model, np.r_[base_q, q], first)
    weight = robot.model.inertia[:, 3, 3].sum() * 9.81
    np.testing.assert_allclose(sum(forces.values()), [0.0, 0.0, weight], atol=1e-9)


def test_floating_contacts_follow_contact_states_and_violations_are_reported(solo_path):
    cfg = floating(solo_path, **{'contacts.mu': 0.01})
    robot = cfg.robot
    answering = Answering(Log())
    base_q = feed_base(cfg, answering, quat=(0.2, 0.0, 0.0, 1.0))    # tilted: it would slip
    q = standing(robot.joints)
    zero = np.zeros(12)
    answering.base_input(cfg, 'contact_states', UInt8MultiArray(data=[1, 1, 0, 1]))
    out = answering.joint_state(cfg, joint_state(robot.joints, 1.0, q, zero, zero))
    expected = sd.contact_inverse_dynamics(
        robot.model, np.r_[base_q, q], np.zeros(18), np.zeros(18),
        [sd.Contact(f, mu=0.01) for f in ('FL_FOOT', 'FR_FOOT', 'HR_FOOT')])
    np.testing.assert_allclose(out.answer.tau, expected.tau, rtol=1e-9, atol=1e-9)
    assert [link for link, _ in out.answer.contacts] == ['FL_FOOT', 'FR_FOOT', 'HR_FOOT']
    assert expected.violations
    level, text, _ = base_status(cfg.params, robot, answering.base_inputs,
                                 answering.base_inputs.period(),
                                 answering.base_inputs.pose.receipt_ns)
    assert level == 'WARN' and 'friction' in text
    answering.base_input(cfg, 'contact_states', UInt8MultiArray(data=[1, 1]))
    assert answering.base_inputs.rejected['contact_states length_mismatch'] == 1


def test_floating_feedback_modes(solo_path):
    kp, kd = 30.0, 2.0
    cfg = floating(solo_path, control_mode='computed_torque', kp=[kp], kd=[kd])
    robot = cfg.robot
    answering = Answering(Log())
    base_q = feed_base(cfg, answering)
    q_d = standing(robot.joints)
    q, qd = q_d + 0.05, np.full(12, 0.1)
    zero = np.zeros(12)
    answering.joint_state(cfg, joint_state(robot.joints, 1.0, q_d, zero, zero))
    out = answering.measured(cfg, joint_state(robot.joints, 1.01, q, qd, ()))
    u = kp * (q_d - q) + kd * (zero - qd)
    feet = [sd.Contact(f) for f in FEET]
    expected = sd.contact_inverse_dynamics(robot.model, np.r_[base_q, q], np.r_[np.zeros(6), qd],
                                           np.r_[np.zeros(6), u], feet)
    np.testing.assert_allclose(out.answer.tau, expected.tau, rtol=1e-9, atol=1e-9)

    cfg = floating(solo_path, control_mode='pd_feedforward', kp=[kp], kd=[kd])
    answering = Answering(Log())
    feed_base(cfg, answering)
    answering.joint_state(cfg, joint_state(robot.joints, 1.0, q_d, zero, zero))
    out = answering.measured(cfg, joint_state(robot.joints, 1.01, q, qd, ()))
    at_desired = sd.contact_inverse_dynamics(robot.model, np.r_[base_q, q_d], np.zeros(18),
                                             np.zeros(18), feet)
    np.testing.assert_allclose(out.answer.tau, at_desired.tau + u, rtol=1e-9, atol=1e-9)


def test_floating_without_base_pose_publishes_nothing(solo_path):
    cfg = floating(solo_path)
    robot = cfg.robot
    answering = Answering(Log())
    zero = np.zeros(12)
    out = answering.joint_state(cfg, joint_state(robot.joints, 1.0, standing(robot.joints),
                                                 zero, zero))
    assert out.answer is None and answering.totals.rejected['base_missing'] == 1
    assert any('no good base/pose yet' in text for _, text in answering.log.said)


@pytest.mark.parametrize('method', ['torques', 'forces', 'qp'])
@pytest.mark.parametrize('flags', [(1, 0, 0, 0), (1, 1, 0, 0), (1, 0, 0, 1)])
def test_floating_contacts_that_cannot_carry_the_base_are_refused(solo_path, method, flags):
    """Solo12 standing on one or two feet: no contact forces carry its base, nothing published.

    The split's base residual is the least any contact forces leave (the QP, bound by the same
    rows, is infeasible): the answer is refused (``contacts_unsolved``), the WARN names the
    residual and the contacts in contact, the ``base`` status counts it; on four feet again
    the node answers again.
    """
    cfg = floating(solo_path, **{'contacts.method': method})
    robot = cfg.robot
    answering = Answering(Log())
    base_q = feed_base(cfg, answering)
    q, zero = standing(robot.joints), np.zeros(12)
    msg = joint_state(robot.joints, 1.0, q, zero, zero)
    good = answering.joint_state(cfg, msg).answer
    assert good is not None
    touching = [link for link, flag in zip(FEET, flags) if flag]
    state = (robot.model, np.r_[base_q, q], np.zeros(18), np.zeros(18),
             [sd.Contact(link) for link in touching])
    split = sd.contact_inverse_dynamics(*state)
    residual = np.abs(split.base_residual).max()
    weight = robot.model.inertia[:, 3, 3].sum() * 9.81   # m g
    assert residual > 1e3 * robot.residual_tolerance   # the least: no λ carries the base
    assert robot.residual_tolerance == pytest.approx(1e-6 * weight)
    assert sd.contact_inverse_dynamics(*state, method='qp').status.startswith('infeasible')
    answering.base_input(cfg, 'contact_states', UInt8MultiArray(data=list(flags)))
    out = answering.joint_state(cfg, msg)
    assert out.answer is None
    assert answering.totals.rejected['contacts_unsolved'] == 1
    said = answering.log.said[-1]
    assert said[0] == 'warn' and 'cannot carry the base' in said[1], said
    assert str(touching) in said[1], said
    if method != 'qp':     # the QP's infeasible answer has no λ: its residual is all of b
        assert f'base residual {residual:.3g}' in said[1], said
    level, text, values = base_status(cfg.params, robot, answering.base_inputs,
                                      answering.base_inputs.period(),
                                      answering.base_inputs.pose.receipt_ns)
    values = dict(values)
    assert level == 'WARN' and 'cannot carry the base' in text, text
    assert values['refused: the contacts cannot carry the base (contacts_unsolved, '
                  'no_contact)'] == '1'
    answering.base_input(cfg, 'contact_states', UInt8MultiArray(data=[1, 1, 1, 1]))
    again = answering.joint_state(cfg, msg).answer
    np.testing.assert_array_equal(again.tau, good.tau)


@pytest.mark.parametrize('changes', [{'contacts.method': 'torques'},
                                     {'contacts.method': 'forces'},
                                     {'contacts.method': 'qp'},
                                     {'contacts.measured': True}])
def test_floating_in_flight_every_answer_is_refused(solo_path, changes):
    """Every contact_states flag 0: no contact carries the base, no answer, whatever the method."""
    cfg = floating(solo_path, **changes)
    robot = cfg.robot
    answering = Answering(Log())
    feed_base(cfg, answering)
    q, zero = standing(robot.joints), np.zeros(12)
    answering.base_input(cfg, 'contact_states', UInt8MultiArray(data=[0, 0, 0, 0]))
    for t in (1.0, 1.01):
        out = answering.joint_state(cfg, joint_state(robot.joints, t, q, zero, zero))
        assert out.answer is None
    assert answering.totals.rejected['no_contact'] == 2
    said = answering.log.said[-1]
    assert said[0] == 'warn' and 'no contact carries the base' in said[1], said
    level, text, _ = base_status(cfg.params, robot, answering.base_inputs,
                                 answering.base_inputs.period(),
                                 answering.base_inputs.pose.receipt_ns)
    assert level == 'WARN' and 'no contact carries the base' in text, text


def test_a_floating_base_without_contacts_is_refused_at_configuration(solo_path):
    """Nothing would carry the base: contacts.links unset or empty is a ConfigError."""
    for links in (None, []):
        with pytest.raises(ConfigError, match='contacts.links: a floating base needs contacts '
                           'to carry it'):
            configured(robot_description_file=solo_path, base='floating',
                       **{'contacts.links': links})


def test_the_observer_is_off_on_a_moving_base_and_says_so(demo_text):
    from spatial_dynamics.ros.bases import observer_off
    from spatial_dynamics.ros.diagnostics import observer_status
    from spatial_dynamics.ros.observer import EstimateWindow
    cfg = configured(robot_description=demo_text, base='moving',
                     **{'base_input.imu_link': 'base_link'})
    robot = cfg.robot
    n = len(robot.joints)
    answering = Answering(Log())
    msg = joint_state(robot.joints, 1.0, np.zeros(n), np.zeros(n), np.ones(n))
    answering.measured(cfg, msg)
    out = answering.observe(cfg, msg)        # efforts of every joint: fixed, it would estimate
    assert out.estimate is None and answering.observer is None
    level, text, _ = observer_status(robot, cfg.params.observer_gain, None, EstimateWindow(),
                                     observer_off(cfg.params))
    assert level == 'OK' and text.startswith('observer off (base moving with '
                                             'base_input.source imu:')


def test_armature_on_a_floating_base_and_terms_on_a_moving_one(solo_path, demo_text):
    armature = np.linspace(0.01, 0.12, 12)
    cfg = floating(solo_path, armature=list(armature))
    robot = cfg.robot
    answering = Answering(Log())
    base_q = feed_base(cfg, answering)
    q, qdd = standing(robot.joints), np.linspace(-1.0, 1.0, 12)
    out = answering.joint_state(cfg, joint_state(robot.joints, 1.0, q, np.zeros(12), qdd))
    expected = sd.contact_inverse_dynamics(robot.model, np.r_[base_q, q], np.zeros(18),
                                           np.r_[np.zeros(6), qdd],
                                           [sd.Contact(f) for f in FEET])
    np.testing.assert_allclose(out.answer.tau, expected.tau + armature * qdd, rtol=1e-9,
                               atol=1e-9)
    assert out.answer.terms is None           # no term split on a floating base

    cfg = configured(robot_description=demo_text, base='moving',
                     **{'base_input.imu_link': 'base_link'})
    robot = cfg.robot
    n = len(robot.joints)
    answering = Answering(Log())
    answering.base_input(cfg, 'base/imu', imu(1.0, [1.0, 0.0, 9.0], [0.0, 0.4, 0.0]))
    q, qd, qdd = np.full(n, 0.2), np.full(n, 0.3), np.full(n, -0.4)
    out = answering.joint_state(cfg, joint_state(robot.joints, 1.0, q, qd, qdd), True)
    base = sd.base_from_imu(robot.model, 'base_link', [1.0, 0.0, 9.0], [0.0, 0.4, 0.0])
    terms = out.answer.terms
    np.testing.assert_allclose(terms['gravity'], sd.gravity_torque(robot.model, q, base=base),
                               atol=1e-9)
    np.testing.assert_allclose(sum(terms.values()), sd.rnea(robot.model, q, qd, qdd, base=base),
                               rtol=1e-9, atol=1e-9)


def test_contact_states_for_other_contacts_links_are_not_applied(solo_path):
    cfg = floating(solo_path)
    robot = cfg.robot
    answering = Answering(Log())
    feed_base(cfg, answering)
    answering.base_input(cfg, 'contact_states', UInt8MultiArray(data=[1, 0, 1, 1]))
    three = floating(solo_path, **{'contacts.links': list(FEET[:3])})   # changed live
    zero = np.zeros(12)
    out = answering.joint_state(three, joint_state(robot.joints, 1.0, standing(robot.joints),
                                                   zero, zero))
    assert out.answer is None and answering.totals.rejected['contacts_stale'] == 1


def test_contact_states_are_a_links_flags_not_a_places(solo_path):
    """The same feet in another order, changed live: the held flags are not read anew.

    ``[1, 0, 1, 1]`` was sent for FL, FR, HL, HR (FR in the air); read against FR, FL, HL, HR
    it would put FR on the ground and lift FL. No answer until a message for the new list,
    which is then applied (the oracle: the library's contact split on those feet).
    """
    cfg = floating(solo_path)
    robot = cfg.robot
    answering = Answering(Log())
    base_q = feed_base(cfg, answering)
    answering.base_input(cfg, 'contact_states', UInt8MultiArray(data=[1, 0, 1, 1]))
    order = [FEET[1], FEET[0], FEET[2], FEET[3]]
    swapped = floating(solo_path, **{'contacts.links': order})     # changed live
    q, zero = standing(robot.joints), np.zeros(12)
    out = answering.joint_state(swapped, joint_state(robot.joints, 1.0, q, zero, zero))
    assert out.answer is None and answering.totals.rejected['contacts_stale'] == 1
    answering.base_input(swapped, 'contact_states', UInt8MultiArray(data=[1, 1, 1, 1]))
    out = answering.joint_state(swapped, joint_state(robot.joints, 1.001, q, zero, zero))
    solved = sd.contact_inverse_dynamics(robot.model, np.r_[base_q, q], np.zeros(18),
                                         np.zeros(18), [sd.Contact(f) for f in order])
    assert out.answer is not None, answering.totals.rejected
    np.testing.assert_allclose(out.answer.tau, solved.tau, rtol=1e-9, atol=1e-9)


def wrench_msg(link, wrench):
    from geometry_msgs.msg import WrenchStamped
    msg = WrenchStamped(header=header(1.0, link))
    t, f = msg.wrench.torque, msg.wrench.force
    t.x, t.y, t.z, f.x, f.y, f.z = map(float, wrench)
    return msg


def test_measured_contact_wrenches_give_the_efforts_and_their_residual(solo_path):
    cfg = floating(solo_path, **{'contacts.measured': True})
    robot = cfg.robot
    answering = Answering(Log())
    base_q = feed_base(cfg, answering)
    q, zero = standing(robot.joints), np.zeros(12)
    msg = joint_state(robot.joints, 1.0, q, zero, zero)
    solved = sd.contact_inverse_dynamics(robot.model, np.r_[base_q, q], np.zeros(18),
                                         np.zeros(18), [sd.Contact(f) for f in FEET])
    R = sd.contacts.link_orientations(robot.model, np.r_[base_q, q], FEET)
    for link in FEET[:3]:
        answering.base_input(cfg, 'measured_contact_wrenches',
                             wrench_msg(link, np.r_[np.zeros(3), R[link].T @ solved.forces[link]]))
    assert answering.joint_state(cfg, msg).answer is None       # HR_FOOT not measured yet
    assert answering.totals.rejected['contacts_missing'] == 1
    answering.base_input(cfg, 'measured_contact_wrenches', wrench_msg('base_link', np.zeros(6)))
    assert answering.base_inputs.rejected['measured_contact_wrenches unknown_link'] == 1
    half = 0.5 * solved.forces['HR_FOOT']     # the sensor reads half: the base rows miss it
    answering.base_input(cfg, 'measured_contact_wrenches',
                         wrench_msg('HR_FOOT', np.r_[np.zeros(3), R['HR_FOOT'].T @ half]))
    out = answering.joint_state(cfg, msg)
    measured = dict(solved.forces, HR_FOOT=half)
    expected = sd.contact_inverse_dynamics(robot.model, np.r_[base_q, q], np.zeros(18),
                                           np.zeros(18), [sd.Contact(f) for f in FEET],
                                           measured=measured)
    np.testing.assert_allclose(out.answer.tau, expected.tau, rtol=1e-9, atol=1e-9)
    assert np.abs(expected.base_residual).max() > 1.0
    level, text, _ = base_status(cfg.params, robot, answering.base_inputs,
                                 answering.base_inputs.period(),
                                 answering.base_inputs.pose.receipt_ns)
    assert level == 'WARN' and 'base residual' in text


def test_external_wrenches_are_refused_on_a_floating_base(solo_path):
    cfg = floating(solo_path)
    answering = Answering(Log())
    answering.wrench(cfg, wrench_msg('base_link', [0, 0, 0, 10.0, 0, 0]))
    assert answering.wrenches == {}
    assert answering.totals.wrenches_rejected['floating_base'] == 1
    assert any('not applied on a floating base' in text for _, text in answering.log.said)


# -------------------------------------------------------------------------------------------
# contacts that share a body; unilateral contact in the QP; the QP solver made ready

def solo_with_toe(solo_path, ahead):
    """Return Solo12's URDF with a link FL_TOE fixed ``ahead`` m in front of FL_FOOT."""
    with open(solo_path) as f:
        text = f.read()
    toe = ('<joint name="FL_TOE_JOINT" type="fixed"><parent link="FL_FOOT"/>'
           f'<child link="FL_TOE"/><origin xyz="{ahead} 0 0" rpy="0 0 0"/></joint>'
           '<link name="FL_TOE"/>')
    return text.replace('</robot>', toe + '</robot>')


def test_floating_a_toe_beside_a_foot_publishes_the_qp_not_a_pull(solo_path):
    """FL_TOE 1 cm ahead of FL_FOOT, both contacts: the least-torque split pulls; not published.

    Oracle: Pinocchio's frame Jacobians and rnea of the same URDF, split by an SVD
    (conftest's ``least_torque_split``): the library's ``'torques'`` split is its τ and λ,
    and there the toe pulls some 49 N (a couple with the foot that cancels the knee torque) on
    a 24.5 N robot. The node re-solves such a state by the QP (``contacts.mu``'s cones,
    ``n·f ≥ 0``): it publishes the QP's efforts and wrenches, no wrench pulls, they sum to
    the weight, the efforts are no smaller than the least-torque ones, and /diagnostics
    counts the re-solve with the worst pull seen, never that the contacts cannot carry the base.
    """
    pin = pytest.importorskip('pinocchio')
    text = solo_with_toe(solo_path, 0.01)
    links = ['FL_FOOT', 'FL_TOE', 'FR_FOOT', 'HL_FOOT', 'HR_FOOT']
    cfg = configured(robot_description=text, base='floating',
                     **{'contacts.links': links, 'base_input.acceleration': 'zero'})
    robot = cfg.robot
    answering = Answering(Log())
    base_q = feed_base(cfg, answering)
    q = standing(robot.joints)
    zero = np.zeros(12)
    out = answering.joint_state(cfg, joint_state(robot.joints, 1.0, q, zero, zero))
    pm = pin.buildModelFromXML(text, pin.JointModelFreeFlyer())
    pd = pm.createData()
    q_full = np.r_[base_q, q]
    b = to_pin(pin.rnea(pm, pd, q_full, np.zeros(18), np.zeros(18)))
    pin.computeJointJacobians(pm, pd, q_full)
    pin.framesForwardKinematics(pm, pd, q_full)
    Jc = np.vstack([to_pin(pin.getFrameJacobian(pm, pd, pm.getFrameId(link),
                                                pin.LOCAL_WORLD_ALIGNED))[:3]
                    for link in links])               # the point's velocity, world axes
    tau, lam, rank = least_torque_split(Jc, b, 1e-6)
    assert rank == 14
    contacts = [sd.Contact(link) for link in links]
    split = sd.contact_inverse_dynamics(robot.model, q_full, np.zeros(18), np.zeros(18),
                                        contacts)
    np.testing.assert_allclose(split.tau, tau, rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.concatenate([split.forces[link] for link in links]), lam,
                               rtol=0, atol=1e-9)
    pull = -lam[5]                                     # FL_TOE's n·f, the floor's normal z
    assert pull > 40.0
    qp = sd.contact_inverse_dynamics(robot.model, q_full, np.zeros(18), np.zeros(18),
                                     contacts, method='qp')
    np.testing.assert_allclose(out.answer.tau, qp.tau, rtol=0, atol=1e-9)
    forces = world_forces(robot.model, q_full, out.answer.contacts)
    np.testing.assert_allclose(np.concatenate([forces[link] for link in links]),
                               np.concatenate([qp.forces[link] for link in links]), rtol=0,
                               atol=1e-9)
    weight = robot.model.inertia[:, 3, 3].sum() * 9.81
    tolerance = 1e-6 * weight
    mu = cfg.params.contacts_mu
    for link, f in forces.items():
        assert f[2] >= -tolerance, (link, f)                      # never pulls
        assert np.hypot(f[0], f[1]) <= mu * f[2] + 1e-6, (link, f)   # inside its cone
    np.testing.assert_allclose(sum(forces.values()), [0.0, 0.0, weight], atol=1e-6)
    assert np.linalg.norm(out.answer.tau) >= np.linalg.norm(tau) - 1e-9
    level, status, values = base_status(cfg.params, robot, answering.base_inputs,
                                        answering.base_inputs.period(),
                                        answering.base_inputs.pose.receipt_ns)
    values = dict(values)
    assert float(values['base residual max']) < 1e-6
    assert 'cannot carry' not in status and level == 'OK', status
    assert values['re-solved by qp (a contact would pull)'] == '1'
    worst, contact = values['worst pull [N]'].split()
    assert contact == '(FL_TOE)' and float(worst) == pytest.approx(pull, rel=1e-3)
    assert values['qp fallback'] == 'ready'
    assert answering.totals.rejected['contacts_pull'] == 0
    # output gravity_only holds the robot still on the same contacts: the QP's efforts too
    cfg = configured(robot_description=text, base='floating', output='gravity_only',
                     **{'contacts.links': links, 'base_input.acceleration': 'zero'})
    answering = Answering(Log())
    feed_base(cfg, answering)
    out = answering.joint_state(cfg, joint_state(robot.joints, 1.0, q, zero, zero))
    np.testing.assert_allclose(out.answer.tau, qp.tau, rtol=0, atol=1e-9)


def accelerate_base(cfg, answering, a_world, t=1.0, quat=(0.02, -0.03, 0.01, 1.0)):
    """Feed a base at rest at ``t`` − 0.02 s, at ``a_world`` m/s² × 0.02 s at ``t``: (q, rate)."""
    quat = np.array(quat) / np.linalg.norm(quat)
    R = sd.joints.quaternion_matrix(quat)
    answering.base_input(cfg, 'base/pose', pose(t, [0.1, 0.2, 0.25], quat))
    answering.base_input(cfg, 'base/twist', twist(t - 0.02, np.zeros(6), 'base_link'))
    answering.base_input(cfg, 'base/twist',
                         twist(t, np.r_[np.zeros(3), R.T @ (0.02 * np.asarray(a_world))],
                               'base_link'))
    rate = answering.base_inputs.rate           # the twist differenced over its stamps
    np.testing.assert_allclose(rate, np.r_[np.zeros(3), R.T @ a_world], atol=1e-9)
    return np.r_[0.1, 0.2, 0.25, quat], rate    # the same floats as the node's answer


@pytest.mark.parametrize('method, control_mode', [
    ('torques', 'feedforward'), ('forces', 'feedforward'), ('torques', 'computed_torque'),
    ('forces', 'pd_feedforward')])
def test_floating_a_split_that_pulls_is_re_solved_by_the_qp(solo_path, method, control_mode):
    """The base swerving at (3, 5, 0) m/s² on four feet: both splits make FL_FOOT pull.

    The feet can carry it (5.8 m/s² sideways is inside μ g = 6.9 m/s²): the node publishes
    the QP's answer (the library's ``method='qp'``), every foot pushing; the contact forces
    sum to ``m (a − g)`` (the joints still, the base not turning: Newton on the whole robot).
    The same in the feedback modes (computed_torque's model part goes through the same
    contact answer).
    """
    cfg = floating(solo_path, **{'contacts.method': method, 'control_mode': control_mode,
                                 'base_input.acceleration': 'difference',
                                 # the twist's difference as it is (no low-pass)
                                 'base_input.acceleration_time_constant': 0.0})
    robot = cfg.robot
    answering = Answering(Log())
    a_world = np.array([3.0, 5.0, 0.0])
    base_q, base_a = accelerate_base(cfg, answering, a_world)
    q, zero = standing(robot.joints), np.zeros(12)
    state = (robot.model, np.r_[base_q, q], np.zeros(18), np.r_[base_a, zero],
             [sd.Contact(f) for f in FEET])
    split = sd.contact_inverse_dynamics(*state, method=method)
    assert any(v.contact == 'FL_FOOT' and v.kind == 'unilateral' and v.amount > 0.5
               for v in split.violations), split.summary()
    qp = sd.contact_inverse_dynamics(*state, method='qp')
    out = answering.joint_state(cfg, joint_state(robot.joints, 1.0, q, zero, zero))
    if control_mode != 'feedforward':     # the measured state at the desired one: u = 0
        out = answering.measured(cfg, joint_state(robot.joints, 1.0, q, zero, ()))
    np.testing.assert_allclose(out.answer.tau, qp.tau, rtol=0, atol=1e-9)
    forces = world_forces(robot.model, state[1], out.answer.contacts)
    mass = robot.model.inertia[:, 3, 3].sum()
    for link in FEET:
        np.testing.assert_allclose(forces[link], qp.forces[link], rtol=0, atol=1e-9)
        assert forces[link][2] >= -1e-6 * mass * 9.81, forces
    np.testing.assert_allclose(sum(forces.values()), mass * (a_world + [0.0, 0.0, 9.81]),
                               atol=1e-6)
    level, _, values = base_status(cfg.params, robot, answering.base_inputs,
                                   answering.base_inputs.period(),
                                   answering.base_inputs.pose.receipt_ns)
    assert dict(values)['re-solved by qp (a contact would pull)'] == '1'
    assert answering.totals.rejected['contacts_pull'] == 0


@pytest.mark.parametrize('method', ['torques', 'forces'])
def test_floating_a_base_falling_faster_than_gravity_is_refused(solo_path, method):
    """The base accelerating down at 30 m/s² on four feet: every split pulls, the QP has none.

    Nothing is published for it (the controller keeps the last good command): the reason
    ``contacts_unsolved`` is counted, the WARN names the contact that would pull most and by
    how much, and /diagnostics explains it; standing again, the node answers again. The
    twist is differenced unfiltered: each step of the base is its own acceleration.
    """
    cfg = floating(solo_path, **{'contacts.method': method,
                                 'base_input.acceleration': 'difference',
                                 # the twist's difference as it is (no low-pass)
                                 'base_input.acceleration_time_constant': 0.0})
    robot = cfg.robot
    answering = Answering(Log())
    q, zero = standing(robot.joints), np.zeros(12)
    msg = joint_state(robot.joints, 1.0, q, zero, zero)
    accelerate_base(cfg, answering, np.zeros(3))
    good = answering.joint_state(cfg, msg).answer
    assert good is not None
    base_q, base_a = accelerate_base(cfg, answering, np.array([0.0, 0.0, -30.0]), 2.0)
    state = (robot.model, np.r_[base_q, q], np.zeros(18), np.r_[base_a, zero],
             [sd.Contact(f) for f in FEET])
    worst = max((v for v in sd.contact_inverse_dynamics(*state, method=method).violations
                 if v.kind == 'unilateral'), key=lambda v: v.amount)
    assert worst.amount > 10.0
    assert sd.contact_inverse_dynamics(*state, method='qp').status.startswith('infeasible')
    out = answering.joint_state(cfg, msg)
    assert out.answer is None and out.estimate is None
    assert answering.totals.rejected['contacts_unsolved'] == 1
    said = answering.log.said[-1]
    assert said[0] == 'warn' and f'{worst.contact!r} would pull' in said[1], said
    assert f'{worst.amount:.3g} N' in said[1] and 'infeasible' in said[1], said
    level, text, values = base_status(cfg.params, robot, answering.base_inputs,
                                      answering.base_inputs.period(),
                                      answering.base_inputs.pose.receipt_ns)
    values = dict(values)
    assert level == 'WARN' and 'refused, a contact would pull' in text, text
    assert values['refused contacts_unsolved (a contact would pull)'] == '1'
    assert values['re-solved by qp (a contact would pull)'] == '0'
    assert values['worst pull [N]'] == f'{worst.amount:.3g} ({worst.contact})'
    accelerate_base(cfg, answering, np.zeros(3), 3.0)
    again = answering.joint_state(cfg, msg).answer
    np.testing.assert_array_equal(again.tau, good.tau)


def test_floating_without_the_qp_a_pulling_split_is_refused(solo_path, monkeypatch):
    """Without clarabel a floating base still loads, with a WARN naming the qp extra.

    ``contacts.method: qp`` is refused at configuration; with ``torques`` the toe's pulling
    split is refused (``contacts_pull``, the contact and its pull named), and a state whose
    split pulls nowhere is answered as before.
    """
    monkeypatch.setitem(sys.modules, 'clarabel', None)      # import clarabel fails
    monkeypatch.setattr(sd.contacts, '_solver', {})          # as in a fresh process
    text = solo_with_toe(solo_path, 0.01)
    links = ['FL_FOOT', 'FL_TOE', 'FR_FOOT', 'HL_FOOT', 'HR_FOOT']
    with pytest.raises(ConfigError, match="contacts.method: .*'qp' extra"):
        configured(robot_description=text, base='floating',
                   **{'contacts.links': links, 'contacts.method': 'qp'})
    cfg = configured(robot_description=text, base='floating',
                     **{'contacts.links': links, 'base_input.acceleration': 'zero'})
    robot = cfg.robot
    assert "'qp' extra" in robot.qp_missing
    warning = qp_missing_warning(robot)
    assert "'qp' extra" in warning and 'refusing' in warning
    assert qp_missing_warning(floating(solo_path, **{'contacts.links': ['FL_FOOT']}).robot) != ''
    answering = Answering(Log())
    base_q = feed_base(cfg, answering)
    q, zero = standing(robot.joints), np.zeros(12)
    msg = joint_state(robot.joints, 1.0, q, zero, zero)
    split = sd.contact_inverse_dynamics(robot.model, np.r_[base_q, q], np.zeros(18),
                                        np.zeros(18), [sd.Contact(link) for link in links])
    pull = next(v for v in split.violations if v.kind == 'unilateral')
    assert pull.contact == 'FL_TOE' and pull.amount > 40.0
    assert answering.joint_state(cfg, msg).answer is None
    assert answering.totals.rejected['contacts_pull'] == 1
    said = answering.log.said[-1][1]
    assert f"'FL_TOE' would pull {pull.amount:.3g} N" in said and "'qp' extra" in said, said
    level, _, values = base_status(cfg.params, robot, answering.base_inputs,
                                   answering.base_inputs.period(),
                                   answering.base_inputs.pose.receipt_ns)
    assert level == 'WARN' and dict(values)['refused contacts_pull (a contact would pull)'] == '1'
    assert "'qp' extra" in dict(values)['qp fallback']

    cfg = floating(solo_path)                  # four feet: the split pulls nowhere
    answering = Answering(Log())
    base_q = feed_base(cfg, answering)
    out = answering.joint_state(cfg, msg)
    expected = sd.contact_inverse_dynamics(robot.model, np.r_[base_q, q], np.zeros(18),
                                           np.zeros(18), [sd.Contact(f) for f in FEET])
    assert not expected.violations
    np.testing.assert_allclose(out.answer.tau, expected.tau, rtol=1e-9, atol=1e-9)
    assert 'clarabel' not in sd.contacts._solver


def test_floating_qp_without_friction_never_publishes_pulling_feet(solo_path):
    """contacts.mu 0, method qp, the base accelerating down at 30 m/s²: no answer, the reason.

    Feet cannot pull; on ice they cannot push sideways either. Standing still on the same
    ice is answered, every foot pushing straight up.
    """
    cfg = floating(solo_path, **{'contacts.method': 'qp', 'contacts.mu': 0.0,
                                 'base_input.acceleration': 'difference',
                                 # the twist's difference as it is (no low-pass)
                                 'base_input.acceleration_time_constant': 0.0})
    robot = cfg.robot
    answering = Answering(Log())
    quat = np.array([0.02, -0.03, 0.01, 1.0]) / np.linalg.norm([0.02, -0.03, 0.01, 1.0])
    R = sd.joints.quaternion_matrix(quat)
    answering.base_input(cfg, 'base/pose', pose(1.0, [0.1, 0.2, 0.25], quat))
    answering.base_input(cfg, 'base/twist', twist(0.98, np.zeros(6), 'base_link'))
    down = np.r_[np.zeros(3), R.T @ [0.0, 0.0, -0.6]]          # 0.02 s later: -30 m/s²
    answering.base_input(cfg, 'base/twist', twist(1.0, down, 'base_link'))
    q, zero = standing(robot.joints), np.zeros(12)
    out = answering.joint_state(cfg, joint_state(robot.joints, 1.0, q, zero, zero))
    if out.answer is not None:
        forces = world_forces(robot.model, np.r_[0.1, 0.2, 0.25, quat, q], out.answer.contacts)
        assert all(f[2] >= 0.0 for f in forces.values()), forces
    else:
        assert answering.totals.rejected['contacts_unsolved'] == 1
    answering = Answering(Log())
    answering.base_input(cfg, 'base/pose', pose(1.0, [0.1, 0.2, 0.25], quat))
    answering.base_input(cfg, 'base/twist', twist(0.98, np.zeros(6), 'base_link'))
    answering.base_input(cfg, 'base/twist', twist(1.0, np.zeros(6), 'base_link'))
    out = answering.joint_state(cfg, joint_state(robot.joints, 1.0, q, zero, zero))
    forces = world_forces(robot.model, np.r_[0.1, 0.2, 0.25, quat, q], out.answer.contacts)
    for f in forces.values():
        assert f[2] > 0.0 and np.hypot(f[0], f[1]) < 1e-6 * f[2], forces


@pytest.mark.parametrize('method', ['qp', 'torques'])
def test_the_qp_solver_is_ready_before_the_first_answer(solo_path, method):
    """Preparing a floating base imports and warms the QP solver, whatever contacts.method.

    In a fresh interpreter: nothing imported clarabel before; after ``prepare`` it is
    imported and has solved once, so the first answer never waits 0.3 to 0.7 s for it
    (``torques``: the QP re-solves a split that makes a contact pull).
    """
    code = (
        'import sys\n'
        'from spatial_dynamics.ros import config, configure\n'
        "assert 'clarabel' not in sys.modules\n"
        'params = {spec.name: spec.default for spec in config.PARAMETERS}\n'
        f'params.update(robot_description_file={solo_path!r}, base="floating")\n'
        f"params.update({{'contacts.links': ['FL_FOOT'], 'contacts.method': {method!r}}})\n"
        'configure.prepare({}, params, None)\n'
        'from spatial_dynamics import contacts\n'
        "assert 'clarabel' in sys.modules and contacts._solver.get('warm'), contacts._solver\n")
    import subprocess
    proc = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr


# -------------------------------------------------------------------------------------------
# a differenced twist is bounded by what a base can do (issue 34)

@pytest.fixture(scope='module')
def ur5_text():
    with open(robot_urdf_path('ur5')) as f:
        return f.read()


def moving_on_twist(text, **changes):
    return configured(robot_description=text, base='moving',
                      **{'base_input.source': 'twist', **changes})


@pytest.mark.parametrize('dt, dv', [(1e-6, 0.1), (1e-6, 1.0), (1e-9, 1e-3)])
def test_twists_stamped_closer_than_a_source_period_are_refused(ur5_text, dt, dv):
    """The issue's UR5: two twists within bounds 1 µs (1 ns) apart gave 2.6e6-3.2e6 N m."""
    cfg = moving_on_twist(ur5_text)
    robot = cfg.robot
    n = len(robot.joints)
    answering = Answering(Log())
    quat = np.array([0.0, 0.0, 0.0, 1.0])
    v0 = np.zeros(6)
    v1 = np.array([0.0, 0.0, 0.0, dv, 0.0, 0.0])
    answering.base_input(cfg, 'base/pose', pose(1.0, [0, 0, 0], quat))
    answering.base_input(cfg, 'base/twist', twist(1.0, v0))
    msg = joint_state(robot.joints, 1.0, np.full(n, 0.3), np.zeros(n), np.zeros(n))
    answering.base_input(cfg, 'base/twist', twist(1.0 + dt, v1))
    assert answering.base_inputs.rejected['base/twist interval_too_short'] == 1
    assert answering.joint_state(cfg, msg).answer is None       # no acceleration: no output
    said = ' '.join(text for _, text in answering.log.said)
    assert 'base_input.min_interval' in said
    level, text, values = base_status(cfg.params, robot, answering.base_inputs,
                                      answering.base_inputs.period(),
                                      answering.base_inputs.twist.receipt_ns)
    assert dict(values)['rejected base/twist interval_too_short'] == '1'
    # a twist a source period later is differenced; the last good one kept after a refusal
    v2 = np.array([0.0, 0.0, 0.0, 0.2, 0.0, 0.0])                # 20 m/s² over 10 ms
    answering.base_input(cfg, 'base/twist', twist(1.01, v2))
    rate = (v2 - v0) / 0.01
    out = answering.joint_state(cfg, msg)
    q = np.full(n, 0.3)
    expected = sd.rnea(robot.model, q, np.zeros(n), np.zeros(n),
                       base=sd.base_from_odometry(robot.model, v2, rate, quat))
    np.testing.assert_allclose(out.answer.tau, expected, rtol=1e-9, atol=1e-9)
    answering.base_input(cfg, 'base/twist', twist(1.01 + dt, v0))        # refused again
    np.testing.assert_allclose(answering.joint_state(cfg, msg).answer.tau, expected,
                               rtol=1e-9, atol=1e-9)


def test_a_differenced_twist_is_filtered_and_bounded(ur5_text):
    """``a += (1 − e^{−dt/T}) (Δv/dt − a)``; beyond the base's bound refused, last kept."""
    T = 0.01
    cfg = moving_on_twist(ur5_text, **{'base_input.acceleration_time_constant': T,
                                       'base_input.max_linear_acceleration': 20.0,
                                       'base_input.max_angular_acceleration': 30.0})
    robot = cfg.robot
    n = len(robot.joints)
    answering = Answering(Log())
    quat = np.array([0.0, 0.0, 0.0, 1.0])
    answering.base_input(cfg, 'base/pose', pose(1.0, [0, 0, 0], quat))
    q = np.linspace(-0.5, 0.5, n)
    msg = joint_state(robot.joints, 1.0, q, np.zeros(n), np.zeros(n))

    def answer():
        return answering.joint_state(cfg, msg).answer

    def oracle(v, a):
        return sd.rnea(robot.model, q, np.zeros(n), np.zeros(n),
                       base=sd.base_from_odometry(robot.model, v, a, quat))

    v0, v1 = np.zeros(6), np.array([0.1, 0.0, 0.0, 0.1, 0.0, 0.0])
    answering.base_input(cfg, 'base/twist', twist(1.0, v0))
    answering.base_input(cfg, 'base/twist', twist(1.01, v1))     # first difference: as is
    a = (v1 - v0) / 0.01
    np.testing.assert_allclose(answer().tau, oracle(v1, a), rtol=1e-9, atol=1e-9)
    v2, dt = v1 + np.array([0.0, 0.0, 0.0, 0.05, 0.0, 0.0]), 1e-4    # a jump 0.1 ms later
    answering.base_input(cfg, 'base/twist', twist(1.01 + dt, v2))
    a2 = a + (1 - np.exp(-dt / T)) * ((v2 - v1) / dt - a)
    assert np.linalg.norm(a2 - a) <= 0.05 / T                    # moved by at most Δv / T
    np.testing.assert_allclose(answer().tau, oracle(v2, a2), rtol=1e-9, atol=1e-9)
    for jump, reason in ((np.array([0, 0, 0, 0.5, 0, 0]), 'linear'),
                         (np.array([0.5, 0, 0, 0, 0, 0]), 'angular')):
        answering.base_input(cfg, 'base/twist', twist(1.0102, v2 + jump))   # beyond: refused
        said = answering.log.said[-1][1]
        assert f'base_input.max_{reason}_acceleration' in said, said
        np.testing.assert_allclose(answer().tau, oracle(v2, a2), rtol=1e-9, atol=1e-9)
    assert answering.base_inputs.rejected['base/twist out_of_bounds'] == 2


# -------------------------------------------------------------------------------------------
# a typical /odom and IMU driver (issue 35)

def test_odometry_of_base_footprint_is_taken_as_base_input_odometry_link(demo_text):
    """``child_frame_id: base_footprint`` (no such link): named by the right field, then mapped.

    Exactly ``base_input.odometry_frame`` is taken as ``base_input.odometry_link``.
    """
    quat = np.array([0.0, 0.0, 0.0, 1.0])
    v0, v1 = np.array([0, 0, 0.1, 0.5, 0, 0.0]), np.array([0, 0, 0.12, 0.52, 0, 0.0])
    cfg = moving_on_twist(demo_text)
    answering = Answering(Log())
    answering.base_input(cfg, 'base/odometry', odometry(1.0, [0, 0, 0], quat, v0,
                                                        'base_footprint'))
    assert answering.base_inputs.rejected['base/odometry wrong_frame'] == 1
    said = answering.log.said[-1][1]
    assert "child_frame_id 'base_footprint'" in said and 'header.frame_id' not in said
    assert "base_input.odometry_frame to 'base_footprint'" in said, said
    assert 'base_input.odometry_link' in said
    cfg = moving_on_twist(demo_text, **{'base_input.odometry_frame': 'base_footprint',
                                        'base_input.odometry_link': 'base_link'})
    robot = cfg.robot
    n = len(robot.joints)
    answering = Answering(Log())
    for t, v in ((1.0, v0), (1.01, v1)):
        answering.base_input(cfg, 'base/odometry', odometry(t, [0, 0, 0], quat, v,
                                                            'base_footprint'))
    q = np.full(n, 0.2)
    out = answering.joint_state(cfg, joint_state(robot.joints, 1.0, q, q, q))
    expected = sd.rnea(robot.model, q, q, q, base=sd.base_from_odometry(
        robot.model, v1, (v1 - v0) / 0.01, quat, link='base_link'))
    np.testing.assert_allclose(out.answer.tau, expected, rtol=1e-9, atol=1e-9)
    # a link of the URDF that moves is still refused; the parameters are checked
    answering.base_input(cfg, 'base/odometry', odometry(1.02, [0, 0, 0], quat, v1, 'link3'))
    assert answering.base_inputs.rejected['base/odometry wrong_frame'] == 1
    with pytest.raises(ConfigError, match="base_input.odometry_link: 'base_footprint' is not"):
        moving_on_twist(demo_text, **{'base_input.odometry_link': 'base_footprint'})
    with pytest.raises(ConfigError, match='base_input.odometry_link.*moves with a joint'):
        moving_on_twist(demo_text, **{'base_input.odometry_link': 'link3'})
    with pytest.raises(ConfigError, match="base_input.odometry_frame: 'link3' is a link"):
        moving_on_twist(demo_text, **{'base_input.odometry_frame': 'link3'})


@pytest.mark.parametrize('child', ['odom_combined', 'base_footprint_2', 'robot2/base_footprint'])
def test_odometry_of_another_frame_than_base_input_odometry_frame_is_refused(demo_text, child):
    """A typo or another robot's odometry is never taken as the base's: ``wrong_frame``.

    Only the frame named in ``base_input.odometry_frame`` stands for
    ``base_input.odometry_link``; the twist held before stays and the answers keep using it.
    """
    quat = np.array([0.0, 0.0, 0.0, 1.0])
    v = np.array([0, 0, 0.1, 0.5, 0, 0.0])
    cfg = moving_on_twist(demo_text, **{'base_input.odometry_frame': 'base_footprint',
                                        'base_input.odometry_link': 'base_link',
                                        'base_input.acceleration': 'zero'})
    robot = cfg.robot
    n = len(robot.joints)
    answering = Answering(Log())
    answering.base_input(cfg, 'base/odometry', odometry(1.0, [0, 0, 0], quat, v,
                                                        'base_footprint'))
    answering.base_input(cfg, 'base/odometry', odometry(1.01, [0, 0, 0], quat, 10 * v, child))
    assert answering.base_inputs.rejected['base/odometry wrong_frame'] == 1
    said = answering.log.said[-1][1]
    assert f"child_frame_id {child!r}" in said and "'base_footprint'" in said, said
    assert 'base_input.odometry_frame' in said and 'base_input.odometry_link' in said, said
    q = np.full(n, 0.2)
    out = answering.joint_state(cfg, joint_state(robot.joints, 1.0, q, q, q))
    expected = sd.rnea(robot.model, q, q, q, base=sd.base_from_odometry(
        robot.model, v, np.zeros(6), quat, link='base_link'))
    np.testing.assert_allclose(out.answer.tau, expected, rtol=1e-9, atol=1e-9)


def test_imu_frame_of_the_driver_is_taken_as_the_imu_link(demo_text):
    cfg = configured(robot_description=demo_text, base='moving',
                     **{'base_input.imu_link': 'base_link'})
    answering = Answering(Log())
    answering.base_input(cfg, 'base/imu', imu(1.0, [0, 0, 9.81], [0, 0, 0], 'imu'))
    assert answering.base_inputs.rejected['base/imu wrong_frame'] == 1
    assert 'base_input.imu_frame' in answering.log.said[-1][1]
    cfg = configured(robot_description=demo_text, base='moving',
                     **{'base_input.imu_link': 'base_link', 'base_input.imu_frame': 'imu'})
    robot = cfg.robot
    n = len(robot.joints)
    f, w = np.array([0.3, 0.1, 9.7]), np.array([0.2, 0.0, -0.1])
    answering.base_input(cfg, 'base/imu', imu(1.0, f, w, 'imu'))
    q = np.full(n, 0.2)
    out = answering.joint_state(cfg, joint_state(robot.joints, 1.0, q, q, q))
    np.testing.assert_allclose(out.answer.tau, sd.rnea(robot.model, q, q, q, base=(
        sd.base_from_imu(robot.model, 'base_link', f, w))), rtol=1e-9, atol=1e-9)


def test_an_imu_rate_no_imu_reports_is_refused(demo_text):
    """An IMU rate of 1e4 rad/s gave 1.1e8 N m: beyond any gyro's full scale, refused."""
    cfg = configured(robot_description=demo_text, base='moving',
                     **{'base_input.imu_link': 'base_link'})
    answering = Answering(Log())
    answering.base_input(cfg, 'base/imu', imu(1.0, [0, 0, 9.81], [1e4, 0, 0]))
    answering.base_input(cfg, 'base/imu', imu(1.0, [0, 0, 1e5], [0, 0, 0]))
    assert answering.base_inputs.rejected['base/imu out_of_bounds'] == 2
    answering.base_input(cfg, 'base/imu', imu(1.0, [0, 0, 9.81], [34.9, 0, 0]))   # 2000 deg/s
    assert answering.base_inputs.imu is not None


def test_odometry_on_source_imu_suggests_source_twist(demo_text):
    cfg = configured(robot_description=demo_text, base='moving',
                     **{'base_input.imu_link': 'base_link'})
    robot = cfg.robot
    n = len(robot.joints)
    answering = Answering(Log())
    quat = np.array([0.0, 0.0, 0.0, 1.0])
    answering.base_input(cfg, 'base/odometry', odometry(1.0, [0, 0, 0], quat, np.zeros(6)))
    msg = joint_state(robot.joints, 1.0, np.zeros(n), np.zeros(n), np.zeros(n))
    assert answering.joint_state(cfg, msg).answer is None
    said = answering.log.said[-1][1]
    assert "base_input.source 'twist'" in said, said
    level, text, _ = base_status(cfg.params, robot, answering.base_inputs,
                                 answering.base_inputs.period(), 0)
    assert level == 'ERROR' and "base_input.source 'twist'" in text
    with pytest.raises(ConfigError, match="base_input.source 'twist'"):
        configured(robot_description=demo_text, base='moving')


# -------------------------------------------------------------------------------------------
# efforts above the URDF's limits are published, counted and said (issue 34)

def urdf_effort_limits(text):
    """Joint name -> ``<limit effort>`` of each joint of a URDF that gives one (the oracle)."""
    import xml.etree.ElementTree as ET
    return {joint.get('name'): float(joint.find('limit').get('effort'))
            for joint in ET.fromstring(text).iter('joint')
            if joint.find('limit') is not None and joint.find('limit').get('effort')}


def test_an_answer_above_the_urdf_effort_limit_is_published_counted_and_said(demo_text):
    """An IMU reading within its bounds gives 1e4 N m on an 87 N m joint: published, WARNed.

    The limits are the URDF's, read here with an XML parser; the worst joint is the one of
    the largest ``|τ| / limit``. Clamping stays opt-in (``clamp_to_effort_limits``); a
    reading of gravity alone is within every limit and says nothing.
    """
    from spatial_dynamics.ros.diagnostics import feedforward_status
    cfg = configured(robot_description=demo_text, base='moving',
                     **{'base_input.imu_link': 'base_link'})
    robot = cfg.robot
    n = len(robot.joints)
    limits = urdf_effort_limits(demo_text)
    limit = np.array([limits.get(joint, np.inf) for joint in robot.joints])
    answering = Answering(Log())
    q = np.full(n, 0.3)
    msg = joint_state(robot.joints, 1.0, q, np.zeros(n), np.zeros(n))
    answering.base_input(cfg, 'base/imu', imu(1.0, [0, 0, 9.81], [0, 0, 0]))
    quiet = answering.joint_state(cfg, msg).answer
    assert np.all(np.abs(quiet.tau) <= limit)
    f, w = np.array([3999.0, 0.0, 3999.0]), np.array([99.0, 0.0, 99.0])
    answering.base_input(cfg, 'base/imu', imu(1.0, f, w))
    out = answering.joint_state(cfg, msg)
    expected = sd.rnea(robot.model, q, np.zeros(n), np.zeros(n),
                       base=sd.base_from_imu(robot.model, 'base_link', f, w))
    np.testing.assert_allclose(out.answer.tau, expected, rtol=1e-9, atol=1e-9)   # published
    ratio = np.abs(expected) / limit
    worst = int(np.argmax(ratio))
    assert ratio[worst] > 10.0
    window = answering.window
    assert window.above_limit == 1
    assert window.above_worst[1] == robot.joints[worst]
    assert window.above_worst[3] == limit[worst]
    said = [text for level, text in answering.log.said if level == 'warn']
    assert len(said) == 1 and 'URDF limit' in said[0], said
    assert f'{robot.joints[worst]!r} {expected[worst]:+.4g}' in said[0], said
    assert f'limit {limit[worst]:g}' in said[0], said
    window, _ = answering.period()
    level, text, values = feedforward_status(robot, window, answering.totals, cfg.params, {},
                                             answering.totals.last_input_ns)
    values = dict(values)
    assert 'above the URDF effort limit' in text and robot.joints[worst] in text, text
    assert values['above effort limit'] == '1'
    assert values['above effort limit worst'].startswith(f'{robot.joints[worst]}: ')
    clamped = configured(robot_description=demo_text, base='moving', clamp_to_effort_limits=True,
                         **{'base_input.imu_link': 'base_link'})
    answering.base_input(clamped, 'base/imu', imu(1.0, f, w))
    out = answering.joint_state(clamped, msg)
    np.testing.assert_allclose(out.answer.tau, np.clip(expected, -limit, limit))
    assert answering.window.above_limit == 0 and answering.totals.saturated == 1


def test_a_measured_state_refused_for_its_base_is_answered_when_sent_again(demo_text):
    """A lockstep simulator republishes the state it waits on: refused once, answered later.

    'One answer per measurement' marked the stamp answered before the answer was computed,
    so a state refused for a missing base input was refused again as 'repeated' once the base
    input came: the simulator waited for good.
    """
    cfg = configured(robot_description=demo_text, base='moving', control_mode='pd_feedforward',
                     kp=[10.0], kd=[1.0], **{'base_input.imu_link': 'base_link'})
    robot = cfg.robot
    n = len(robot.joints)
    answering = Answering(Log())
    q = np.linspace(-0.5, 0.5, n)
    answering.joint_state(cfg, joint_state(robot.joints, 1.0, q, np.zeros(n), np.zeros(n)))
    state = joint_state(robot.joints, 1.0, q, np.zeros(n), np.zeros(n))
    assert answering.measured(cfg, state).answer is None
    assert answering.totals.rejected['base_missing'] == 1
    answering.base_input(cfg, 'base/imu', imu(1.0, [0, 0, 9.81], [0, 0, 0]))
    answer = answering.measured(cfg, state).answer      # the same state, sent again
    assert answer is not None and answering.totals.rejected['repeated'] == 0
    expected = sd.rnea(robot.model, q, np.zeros(n), np.zeros(n), base=sd.base_from_imu(
        robot.model, 'base_link', [0, 0, 9.81], [0, 0, 0]))
    np.testing.assert_allclose(answer.tau, expected, rtol=1e-9, atol=1e-9)
    assert answering.measured(cfg, state).answer is None    # answered once: not again
    assert answering.totals.rejected['repeated'] == 1


# -------------------------------------------------------------------------------------------
# contact inputs: what an answer takes of them, and what /diagnostics says when they block it

def solo_answer(cfg, answering, t=1.0):
    """Answer Solo12 standing (``standing``), at rest; return the answer (None: refused)."""
    joints = cfg.robot.joints
    zero = np.zeros(12)
    return answering.joint_state(cfg, joint_state(joints, t, standing(joints), zero,
                                                  zero)).answer


def on_feet(cfg, base_q, feet):
    """Return the oracle: Solo12 standing, at rest, on ``feet`` (``contact_inverse_dynamics``)."""
    model = cfg.robot.model
    return sd.contact_inverse_dynamics(model, np.r_[base_q, standing(cfg.robot.joints)],
                                       np.zeros(18), np.zeros(18), [sd.Contact(f) for f in feet])


def statuses(cfg, answering, now_ns):
    """Return the ``feedforward`` and ``base`` statuses at ``now_ns`` of the period ended."""
    from spatial_dynamics.ros.diagnostics import feedforward_status
    window, _ = answering.period()
    inputs = answering.base_inputs
    return (feedforward_status(cfg.robot, window, answering.totals, cfg.params, {}, now_ns),
            base_status(cfg.params, cfg.robot, inputs, inputs.period(), now_ns))


def test_without_contact_states_every_link_is_in_contact(solo_path):
    """The documented default: nothing on contact_states, contacts.links all in contact."""
    cfg = floating(solo_path)
    answering = Answering(Log())
    base_q = feed_base(cfg, answering)
    out = solo_answer(cfg, answering)
    np.testing.assert_allclose(out.tau, on_feet(cfg, base_q, FEET).tau, rtol=1e-9, atol=1e-9)
    assert [link for link, _ in out.contacts] == list(FEET)


@pytest.mark.parametrize('flags', [[1, 0, 0, 0, 0], [1, 0, 0]])
def test_contact_states_all_refused_give_no_answer_never_all_feet(solo_path, flags):
    """contact_states arrive, each of the wrong length: no answer, never four feet assumed.

    Once messages come on contact_states, only a valid one says which feet touch: before the
    first, every answer is refused (``contacts_missing``) and /diagnostics names contact_states
    and what was wrong with the last one refused; a valid one held then goes stale whatever
    refused messages follow (``contacts_stale``), as every base input does.
    """
    cfg = floating(solo_path)
    answering = Answering(Log())
    base_q = feed_base(cfg, answering)
    for t in (1.0, 1.005, 1.01):
        answering.base_input(cfg, 'contact_states', UInt8MultiArray(data=flags))
        assert solo_answer(cfg, answering, t) is None
    assert answering.base_inputs.rejected['contact_states length_mismatch'] == 3
    assert answering.totals.rejected['contacts_missing'] == 3
    said = answering.log.said[-1][1]
    assert 'contact_states' in said and 'length_mismatch' in said, said
    (level, text, _), (base_level, base_text, values) = statuses(cfg, answering,
                                                                 time.monotonic_ns())
    assert level == 'ERROR' and 'contacts_missing' in text and 'contact_states' in text, text
    assert base_level == 'ERROR', base_text
    assert 'contact_states' in base_text and 'length_mismatch' in base_text, base_text
    assert f'{len(flags)} flags for the 4 contacts.links' in base_text, base_text
    assert dict(values)['rejected contact_states length_mismatch'] == '3'

    answering.base_input(cfg, 'contact_states', UInt8MultiArray(data=[1, 1, 0, 1]))
    out = solo_answer(cfg, answering, 1.02)
    three = ('FL_FOOT', 'FR_FOOT', 'HR_FOOT')
    np.testing.assert_allclose(out.tau, on_feet(cfg, base_q, three).tau, rtol=1e-9, atol=1e-9)
    assert [link for link, _ in out.contacts] == list(three)
    answering.base_input(cfg, 'contact_states', UInt8MultiArray(data=flags))   # refused
    inputs = answering.base_inputs
    inputs.flags.receipt_ns -= int(1e9)          # the valid one is 1 s old: stale
    inputs.pose.receipt_ns = inputs.twist.receipt_ns = time.monotonic_ns()
    assert solo_answer(cfg, answering, 1.03) is None
    assert answering.totals.rejected['contacts_stale'] == 1
    (level, text, _), (base_level, base_text, _) = statuses(cfg, answering, time.monotonic_ns())
    assert base_level == 'ERROR' and 'contact_states stale' in base_text, base_text
    assert 'length_mismatch' in base_text, base_text
    assert 'contacts_stale' in text, text


def test_stale_contact_states_make_the_base_status_an_error(solo_path):
    cfg = floating(solo_path)
    answering = Answering(Log())
    feed_base(cfg, answering)
    answering.base_input(cfg, 'contact_states', UInt8MultiArray(data=[1, 1, 1, 1]))
    assert solo_answer(cfg, answering) is not None
    inputs = answering.base_inputs
    now = inputs.flags.receipt_ns + int(0.6e9)      # base_input.timeout 0.5 s
    inputs.pose.receipt_ns = inputs.twist.receipt_ns = now
    _, (level, text, values) = statuses(cfg, answering, now)
    assert level == 'ERROR' and 'contact_states stale' in text and 'not publishing' in text, text
    assert dict(values)['contact_states age [s]'] == '0.600'


def measured_feet(cfg, answering, base_q, skip=()):
    """Send each foot's sensor reading of Solo12 standing (the oracle's forces, link frames)."""
    solved = on_feet(cfg, base_q, FEET)
    R = sd.contacts.link_orientations(cfg.robot.model, np.r_[base_q, standing(cfg.robot.joints)],
                                      FEET)
    for link in FEET:
        if link not in skip:
            answering.base_input(cfg, 'measured_contact_wrenches', wrench_msg(
                link, np.r_[np.zeros(3), R[link].T @ solved.forces[link]]))
    return solved


@pytest.mark.parametrize('bad', ['none', 'nan', '../HR_FOOT', 'HR_LOWER_LEG'])
def test_a_foot_without_a_good_measured_wrench_is_named_not_the_base(solo_path, bad):
    """contacts.measured, HR_FOOT's sensor silent or refused: contacts_stale, not base_stale.

    The base's inputs are fresh: the ``base`` status is ERROR naming the foot's
    measured_contact_wrenches (and the last refusal), the refusals are counted under
    contacts_stale, the ``feedforward`` status names them.
    """
    cfg = floating(solo_path, **{'contacts.measured': True})
    answering = Answering(Log())
    base_q = feed_base(cfg, answering)
    solved = measured_feet(cfg, answering, base_q)
    out = solo_answer(cfg, answering)
    np.testing.assert_allclose(out.tau, solved.tau, rtol=1e-9, atol=1e-9)
    inputs = answering.base_inputs
    for link in FEET:                 # 0.6 s later: the three others come again, HR does not
        inputs.measured[link].receipt_ns -= int(0.6e9)
    inputs.pose.receipt_ns = inputs.twist.receipt_ns = time.monotonic_ns()
    measured_feet(cfg, answering, base_q, skip=('HR_FOOT',))
    if bad == 'nan':
        answering.base_input(cfg, 'measured_contact_wrenches',
                             wrench_msg('HR_FOOT', [0, 0, 0, float('nan'), 0, 10.0]))
    elif bad != 'none':
        answering.base_input(cfg, 'measured_contact_wrenches',
                             wrench_msg(bad, [0, 0, 0, 0, 0, 10.0]))
    for t in (1.01, 1.02):
        assert solo_answer(cfg, answering, t) is None
    rejected = answering.totals.rejected
    assert rejected['contacts_stale'] == 2 and rejected['base_stale'] == 0, rejected
    said = answering.log.said[-1][1]
    assert "measured_contact_wrenches of 'HR_FOOT' stale" in said, said
    (level, text, _), (base_level, base_text, _) = statuses(cfg, answering, time.monotonic_ns())
    assert base_level == 'ERROR', base_text
    assert "measured_contact_wrenches of 'HR_FOOT' stale" in base_text, base_text
    refusal = {'none': None, 'nan': 'non_finite'}.get(bad, 'unknown_link')
    if refusal:
        assert refusal in base_text, base_text
    assert 'contacts_stale' in text, text


def test_the_feedforward_status_names_why_inputs_are_not_answered(solo_path):
    """Desired states arrive and are refused: the status says the refusal, not 'no input'.

    Before any measured wrench (contacts.measured) every input is refused contacts_missing;
    later, the base's pose going stale while desired states still come, base_stale.
    """
    cfg = floating(solo_path, **{'contacts.measured': True})
    answering = Answering(Log())
    base_q = feed_base(cfg, answering)
    for k in range(50):
        assert solo_answer(cfg, answering, 1.0 + 0.02 * k) is None
    assert answering.totals.rejected['contacts_missing'] == 50
    (level, text, values), _ = statuses(cfg, answering, time.monotonic_ns())
    assert level == 'ERROR' and 'no answer yet' in text, text
    assert 'contacts_missing' in text and 'measured_contact_wrenches' in text, text
    assert 'contacts_missing' in dict(values)['last rejection']
    measured_feet(cfg, answering, base_q)
    assert solo_answer(cfg, answering, 2.0) is not None
    answering.totals.last_input_ns -= int(3e9)     # answered 3 s ago
    inputs = answering.base_inputs
    inputs.pose.receipt_ns -= int(3e9)
    for link in FEET:
        inputs.measured[link].receipt_ns = time.monotonic_ns()
    for k in range(5):                              # desired states still come
        assert solo_answer(cfg, answering, 2.1 + 0.02 * k) is None
    assert answering.totals.rejected['base_stale'] == 5
    (level, text, _), (base_level, base_text, _) = statuses(cfg, answering, time.monotonic_ns())
    assert level == 'ERROR' and 'no answer for' in text, text
    assert 'base_stale' in text and 'base/pose stale' in text, text
    assert 'input stale' not in text, text
    assert base_level == 'ERROR' and 'base/pose stale' in base_text, base_text


def test_unstamped_odometry_is_named_in_the_base_status(solo_path):
    """Odometry stamped 0 with base_input.acceleration difference: refused, and said so.

    Then one good twist: the acceleration needs a second one, and the status says that
    (every answer is refused base_missing meanwhile).
    """
    cfg = floating(solo_path, **{'base_input.acceleration': 'difference'})
    answering = Answering(Log())
    msg = odometry(0.0, [0.1, 0.2, 0.25], [0.0, 0.0, 0.0, 1.0], np.zeros(6), 'base_link')
    for _ in range(3):
        answering.base_input(cfg, 'base/odometry', msg)
    assert answering.base_inputs.rejected['base/odometry unstamped'] == 3
    assert solo_answer(cfg, answering) is None
    assert answering.totals.rejected['base_missing'] == 1
    said = answering.log.said[-1][1]
    assert 'no good base/pose yet' in said and 'unstamped' in said, said
    (level, text, _), (base_level, base_text, _) = statuses(cfg, answering, time.monotonic_ns())
    assert base_level == 'ERROR' and 'no good base/pose yet' in base_text, base_text
    assert 'base/odometry (unstamped)' in base_text, base_text
    assert 'base_missing' in text and 'unstamped' in text, text
    answering.base_input(cfg, 'base/odometry', odometry(
        1.0, [0.1, 0.2, 0.25], [0.0, 0.0, 0.0, 1.0], np.zeros(6), 'base_link'))
    assert solo_answer(cfg, answering) is None
    assert answering.totals.rejected['base_missing'] == 2
    _, (base_level, base_text, _) = statuses(cfg, answering, time.monotonic_ns())
    assert base_level == 'ERROR' and 'two successive twists' in base_text, base_text
