# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The installed ``inverse_dynamics`` node, driven over real DDS from this process.

Every answer is checked against ``spatial_dynamics.rnea`` on the same URDF and against Pinocchio
(mimic finger stripped and folded back, see conftest.PinOracle). Inputs are best effort, so a
message may be dropped under load: the tests require that *every answer* is right, that
*bad messages get none* and that the node answers the good ones it gets (its counters), never
how many of them the transport delivers.
"""

import math
import os
import random
import sys
import time

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from node_harness import (  # noqa: E402
    DEMO_URDF, drive, Io, joint_state, NodeProcess, PENDULUM_URDF, PRIME, random_states, settle,
    stamp, stamp_key, TIMEOUT, values)
import spatial_dynamics as sd  # noqa: E402
from diagnostic_msgs.msg import DiagnosticStatus  # noqa: E402

pytestmark = pytest.mark.ros

UNKNOWN = 'conveyor_joint'   # a joint the model doesn't have: ignored
RATE = 500.0                 # Hz
GRAVITY = (0.0, 0.0, -9.81)
WALL = (0.0, -9.81, 0.0)     # wall mount: gravity along the base's -y


@pytest.fixture
def node(install, tmp_path):
    proc = NodeProcess(install, ['-p', f'robot_description_file:={DEMO_URDF}',
                                 '-p', 'input_timeout:=0.3'], str(tmp_path))
    yield proc
    assert proc.stop() == 0, proc.log()


@pytest.fixture
def unprimed_io(driver, node):
    channels = Io(driver)
    channels.wait_connected()
    yield channels
    channels.close()


@pytest.fixture
def io(unprimed_io, demo_model):
    unprimed_io.prime(demo_model.joint_names)
    return unprimed_io


def shuffled_message(names, row, k, rng, extra=(UNKNOWN,)):
    """Return a JointState for state ``row`` (3, n), names shuffled, plus unknown joints."""
    all_names = list(names) + list(extra)
    data = np.concatenate([row, np.full((3, len(extra)), 7.0)], axis=1)
    order = list(range(len(all_names)))
    rng.shuffle(order)
    return joint_state([all_names[i] for i in order], data[0, order], data[1, order],
                       data[2, order], k)


def spoil(msg, kind, names, rng):
    """Make ``msg`` bad in the way ``kind`` (an InputError reason) says."""
    from sensor_msgs.msg import JointState
    victim = msg.name.index(rng.choice(names))
    if kind == 'non_finite':
        field = rng.choice(['position', 'velocity', 'effort'])
        values = list(getattr(msg, field))
        values[victim] = rng.choice([math.nan, math.inf, -math.inf])
        setattr(msg, field, values)
    elif kind == 'missing_joint':
        for field in ('name', 'position', 'velocity', 'effort'):
            values = list(getattr(msg, field))
            del values[victim]
            setattr(msg, field, values)
    elif kind == 'length_mismatch':
        field = rng.choice(['position', 'velocity', 'effort'])
        setattr(msg, field, list(getattr(msg, field))[:-1])
    elif kind == 'duplicate_joint':
        msg.name = list(msg.name) + [msg.name[victim]]
        for field in ('position', 'velocity', 'effort'):
            setattr(msg, field, list(getattr(msg, field)) + [0.0])
    elif kind == 'empty':
        empty = JointState()
        empty.header = msg.header
        return empty
    return msg


BAD_KINDS = ('non_finite', 'missing_joint', 'length_mismatch', 'duplicate_joint', 'empty')


def answers_by_stamp(io):
    """{k: JointState answer} for all feed-forward answers received."""
    return {stamp_key(msg.header.stamp): msg for msg in io.efforts}


def expected(demo_model, states, gravity=GRAVITY):
    """Library torques for states of shape (count, 3, n)."""
    return sd.rnea(demo_model, states[:, 0], states[:, 1], states[:, 2], gravity=gravity)


def test_joint_states_answered_like_library_and_pinocchio_bad_ones_not(driver, io, demo_model,
                                                                       node):
    """~500 Hz of shuffled JointStates, every 10th spoilt: good ones answered right, bad never."""
    from node_harness import pin_oracle
    names = demo_model.joint_names
    count = 2500
    states = random_states(1, count, len(names))
    rng = random.Random(2)
    bad = {}

    def publish(k):
        msg = shuffled_message(names, states[k], k, rng)
        if k % 10 == 5:
            bad[k] = BAD_KINDS[(k // 10) % len(BAD_KINDS)]
            msg = spoil(msg, bad[k], names, rng)
        io.joint_states.publish(msg)

    drive(driver, publish, count, RATE)
    settle(driver, io)

    answers = {k: msg for k, msg in answers_by_stamp(io).items() if k != PRIME}  # late primes
    assert not set(answers) & set(bad), 'a bad message was answered'
    good = count - len(bad)
    print(f'answered {len(answers)} of {good} good messages')
    # how many best-effort inputs reach the node is the transport's (a busy machine drops
    # most); that it answers every good one it gets is the node's, checked on its counters
    assert answers and set(answers) <= set(range(count))

    ks = np.array(sorted(answers))
    tau = expected(demo_model, states[ks])
    oracle = pin_oracle(DEMO_URDF)
    tau_pin = oracle.rnea(list(names), states[ks, 0], states[ks, 1], states[ks, 2])
    for row, k in enumerate(ks):
        msg = answers[k]
        assert tuple(msg.name) == names
        np.testing.assert_array_equal(msg.position, states[k, 0])
        np.testing.assert_array_equal(msg.velocity, states[k, 1])
        np.testing.assert_allclose(msg.effort, tau[row], rtol=0, atol=1e-9)
        np.testing.assert_allclose(msg.effort, tau_pin[row], rtol=0, atol=1e-8)

    # effort_commands: the same torques, full length, finite, never anything else
    efforts = {tuple(msg.effort) for msg in io.efforts}
    assert io.commands, 'no effort_commands received'
    for msg in io.commands:
        assert len(msg.data) == len(names) and all(math.isfinite(x) for x in msg.data)
        assert tuple(msg.data) in efforts

    # counters: the node rejected only bad messages, each kind at most as often as it was
    # sent (the slow test below sees every kind counted exactly), and counted every answer
    status = io.fresh_status('feedforward')
    kv = values(status)
    rejected = 0
    for kind in BAD_KINDS:
        sent = sum(1 for v in bad.values() if v == kind)
        assert 0 <= int(kv[f'rejected {kind}']) <= sent, (kind, kv)
        rejected += int(kv[f'rejected {kind}'])
    assert int(kv['rejected']) == rejected, kv
    assert len(answers) <= int(kv['answered']) - io.primed
    # throttled warnings name the offending field or joint
    log = node.log()
    assert 'desired_joint_states: message rejected' in log
    assert log.count('message rejected') < count / 10 / 2, 'warnings are not throttled'


def test_bad_messages_counted_by_reason_and_named_in_warnings(driver, io, demo_model, node):
    """Slow, one at a time: each bad message is counted under its reason, no answer."""
    names = demo_model.joint_names
    # The node's own count after priming: a priming answer may be lost to discovery (the
    # node's publisher not yet matched to our subscription), so what we received is not it.
    before = int(values(io.fresh_status('feedforward'))['answered'])
    rng = random.Random(3)
    states = random_states(4, 10, len(names))
    sent = {}
    for j, kind in enumerate(BAD_KINDS * 2):
        msg = spoil(shuffled_message(names, states[j], j, rng), kind, names, rng)
        io.joint_states.publish(msg)
        sent[kind] = sent.get(kind, 0) + 1
        driver.spin_for(0.05)
    good = shuffled_message(names, states[-1], 99, rng)
    io.joint_states.publish(good)
    driver.spin_until(lambda: len(io.efforts) >= 1, what='the good message answered')
    settle(driver, io)
    assert [stamp_key(m.header.stamp) for m in io.efforts] == [99]
    assert io.commands and len(io.commands) == 1

    kv = values(io.fresh_status('feedforward'))
    for kind in BAD_KINDS:
        assert int(kv[f'rejected {kind}']) == sent[kind], (kind, kv)
    assert int(kv['answered']) == before + 1   # the good one
    log = node.log()
    assert 'message rejected (non_finite)' in log  # the first one; later ones are throttled


def test_warning_names_the_missing_joint(driver, io, demo_model, node):
    names = demo_model.joint_names
    msg = shuffled_message(names, random_states(5, 1, len(names))[0], 0, random.Random(5))
    spoil_joint = 'joint4'
    i = list(msg.name).index(spoil_joint)
    for field in ('name', 'position', 'velocity', 'effort'):
        vals = list(getattr(msg, field))
        del vals[i]
        setattr(msg, field, vals)
    io.joint_states.publish(msg)
    node.wait_for_log("missing joint(s) 'joint4'")
    nan = shuffled_message(names, random_states(5, 1, len(names))[0], 1, random.Random(6))
    nan.velocity[list(nan.name).index('joint6')] = math.nan
    driver.spin_for(1.2)  # past the warning throttle
    io.joint_states.publish(nan)
    node.wait_for_log("field 'velocity' is not finite for joint(s) 'joint6'")
    assert not io.efforts


def test_gravity_changed_while_running(driver, io, demo_model):
    """Answers switch from floor to wall gravity once, in order; bad gravity is rejected."""
    names = demo_model.joint_names
    count = 1000
    states = random_states(6, count, len(names))
    rng = random.Random(7)
    switch = {}

    def publish(k):
        io.joint_states.publish(shuffled_message(names, states[k], k, rng))
        if k == count // 2:
            switch['future'] = io.parameters.call_async(_request(gravity=list(WALL)))

    drive(driver, publish, count, RATE)
    driver.spin_until(switch['future'].done, what='set gravity')
    assert switch['future'].result().results[0].successful
    settle(driver, io)

    answers = answers_by_stamp(io)
    ks = np.array(sorted(answers))
    floor = expected(demo_model, states[ks], GRAVITY)
    wall = expected(demo_model, states[ks], WALL)
    which = []
    for row, k in enumerate(ks):
        effort = np.array(answers[k].effort)
        on_floor = np.allclose(effort, floor[row], rtol=0, atol=1e-9)
        on_wall = np.allclose(effort, wall[row], rtol=0, atol=1e-9)
        assert on_floor != on_wall, f'answer {k} matches neither gravity'
        which.append(on_wall)
    assert which[0] is False and which[-1] is True
    assert which == sorted(which), 'gravity switched back and forth'

    # then a steady state with the new gravity, and an invalid gravity is rejected
    result = io.set_parameters(gravity=[0.0, 0.0])
    assert not result[0].successful and 'gravity' in result[0].reason
    kv = values(io.fresh_status('feedforward'))
    assert kv['gravity [m/s^2]'] == str(list(WALL))


def _request(**params):
    from rcl_interfaces.srv import SetParameters
    from rclpy.parameter import Parameter
    return SetParameters.Request(parameters=[
        Parameter(name, value=value).to_parameter_msg() for name, value in params.items()])


def heavier_hand(urdf_path, mass):
    """Return the demo arm's URDF text with the hand's mass changed (a payload change)."""
    with open(urdf_path) as f:
        text = f.read()
    start = text.index('<link name="hand">')
    old = '<mass value="0.6"/>'
    at = text.index(old, start)
    return text[:at] + f'<mass value="{mass}"/>' + text[at + len(old):]


def test_robot_description_swapped_while_running(driver, io, demo_model, node):
    """A valid description is swapped in between two messages; an invalid one changes nothing."""
    names = demo_model.joint_names
    heavy_urdf = heavier_hand(DEMO_URDF, 3.6)
    heavy = sd.Model.from_urdf(heavy_urdf)
    count = 1000
    states = random_states(8, count, len(names))
    rng = random.Random(9)
    swap = {}

    def publish(k):
        io.joint_states.publish(shuffled_message(names, states[k], k, rng))
        if k == count // 2:
            swap['future'] = io.parameters.call_async(_request(robot_description=heavy_urdf))

    drive(driver, publish, count, RATE)
    driver.spin_until(swap['future'].done, what='robot_description set')
    assert swap['future'].result().results[0].successful
    settle(driver, io)

    answers = answers_by_stamp(io)
    ks = np.array(sorted(answers))
    light_tau = expected(demo_model, states[ks])
    heavy_tau = expected(heavy, states[ks])
    which = []
    for row, k in enumerate(ks):
        effort = np.array(answers[k].effort)
        is_light = np.allclose(effort, light_tau[row], rtol=0, atol=1e-9)
        is_heavy = np.allclose(effort, heavy_tau[row], rtol=0, atol=1e-9)
        assert is_light != is_heavy, f'answer {k} matches neither model'
        which.append(is_heavy)
    assert which[0] is False and which[-1] is True and which == sorted(which)

    # invalid descriptions are rejected with a reason; the heavy model keeps answering
    for bad_urdf in ['<robot name="broken"><link name="a">',
                     heavy_urdf.replace('<child link="link3"/>', '<child link="no_such_link"/>')]:
        result = io.set_parameters(robot_description=bad_urdf)
        assert not result[0].successful and result[0].reason, result[0]
        assert 'robot_description' in result[0].reason
    result = io.set_parameters(robot_description_file='/nonexistent/robot.urdf')
    assert not result[0].successful and '/nonexistent/robot.urdf' in result[0].reason

    before = len(io.efforts)
    state = random_states(10, 1, len(names))[0]
    io.joint_states.publish(shuffled_message(names, state, 5000, rng))
    driver.spin_until(lambda: len(io.efforts) > before, what='an answer after the rejects')
    np.testing.assert_allclose(io.efforts[-1].effort, expected(heavy, state[None])[0],
                               rtol=0, atol=1e-9)
    kv = values(io.fresh_status('robot model'))
    assert kv['descriptions rejected'] == '3'
    assert kv['source'] == 'parameter robot_description'

    # an empty string is not an error: robot_description_file (the demo arm) applies again
    result = io.set_parameters(robot_description='')
    assert result[0].successful, result[0].reason
    before = len(io.efforts)
    io.joint_states.publish(shuffled_message(names, state, 5001, rng))
    driver.spin_until(lambda: len(io.efforts) > before, what='an answer after the fallback')
    np.testing.assert_allclose(io.efforts[-1].effort, expected(demo_model, state[None])[0],
                               rtol=0, atol=1e-9)
    kv = values(io.fresh_status('robot model'))
    assert kv['descriptions rejected'] == '3' and kv['source'] == f'file {DEMO_URDF}'


def test_description_with_other_joints_and_output_joints(driver, io, demo_model, node):
    """``joints`` keeps and orders joints (model reduction: the others locked at 0)."""
    names = demo_model.joint_names
    rng = random.Random(11)
    result = io.set_parameters(joints=['joint3', 'joint1', 'finger_joint1'])
    assert result[0].successful, result[0].reason
    result = io.set_parameters(joints=['joint3', 'not_a_joint'])
    assert not result[0].successful and 'not_a_joint' in result[0].reason
    state = random_states(12, 1, len(names))[0]
    io.joint_states.publish(shuffled_message(names, state, 1, rng))
    driver.spin_until(lambda: io.efforts and io.commands, what='an answer')
    # the full model's tau with every other joint locked at 0 (and at rest)
    kept = [names.index(j) for j in ('joint3', 'joint1', 'finger_joint1')]
    locked = np.zeros_like(state)
    locked[:, kept] = state[:, kept]
    tau = dict(zip(names, expected(demo_model, locked[None])[0]))
    assert tuple(io.efforts[-1].name) == ('joint3', 'joint1', 'finger_joint1')
    np.testing.assert_allclose(io.commands[-1].data,
                               [tau['joint3'], tau['joint1'], tau['finger_joint1']],
                               rtol=0, atol=1e-9)
    np.testing.assert_array_equal(
        io.efforts[-1].position, [state[0][names.index(j)] for j in io.efforts[-1].name])

    # the pendulum has none of these joints: refused while `joints` names them
    result = io.set_parameters(robot_description_file=PENDULUM_URDF)
    assert not result[0].successful and 'joint3' in result[0].reason
    # with the default order again (empty list), it loads and answers for 'pivot' alone
    from rclpy.parameter import Parameter
    result = io.set_parameters(joints=Parameter('joints', Parameter.Type.STRING_ARRAY, []))
    assert result[0].successful, result[0].reason
    result = io.set_parameters(robot_description_file=PENDULUM_URDF)
    assert result[0].successful, result[0].reason
    before = len(io.efforts)
    q, qd, qdd = 0.7, 1.3, -2.0
    # arm joints are unknown to the pendulum now: ignored
    msg = joint_state(list(names) + ['pivot'], list(state[0]) + [q], list(state[1]) + [qd],
                      list(state[2]) + [qdd], 2)
    io.joint_states.publish(msg)
    driver.spin_until(lambda: len(io.efforts) > before, what='a pendulum answer')
    answer = io.efforts[-1]
    assert list(answer.name) == ['pivot']
    # config/pendulum.urdf: tau = (m L^2 + I_c) qdd + m g L sin(q) = 1.001 qdd + g sin(q)
    assert answer.effort[0] == pytest.approx(1.001 * qdd + 9.81 * math.sin(q), abs=1e-9)


def test_acceleration_source_none_ignores_effort(driver, io, demo_model, node):
    names = demo_model.joint_names
    rng = random.Random(13)
    state = random_states(14, 1, len(names))[0]
    assert io.set_parameters(acceleration_source='none')[0].successful
    result = io.set_parameters(acceleration_source='torque')
    assert not result[0].successful and 'acceleration_source' in result[0].reason
    msg = shuffled_message(names, state, 1, rng)
    msg.effort = [123.0] * 3   # measured torques of any length: unused
    io.joint_states.publish(msg)
    driver.spin_until(lambda: io.efforts, what='an answer')
    zero_qdd = np.stack([state[0], state[1], np.zeros(len(names))])
    np.testing.assert_allclose(io.efforts[-1].effort, expected(demo_model, zero_qdd[None])[0],
                               rtol=0, atol=1e-9)
    # velocity empty = zeros too
    msg = shuffled_message(names, state, 2, rng)
    msg.velocity = []
    io.joint_states.publish(msg)
    driver.spin_until(lambda: len(io.efforts) >= 2, what='a second answer')
    static = np.stack([state[0], np.zeros(len(names)), np.zeros(len(names))])
    np.testing.assert_allclose(io.efforts[-1].effort, expected(demo_model, static[None])[0],
                               rtol=0, atol=1e-9)


def test_joint_trajectory_input(driver, io, demo_model, node):
    """points[0] of a JointTrajectory, by name, with its stamp; no points = rejected."""
    from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
    names = demo_model.joint_names
    states = random_states(15, 20, len(names))
    rng = random.Random(16)
    for k in range(20):
        order = list(range(len(names)))
        rng.shuffle(order)
        msg = JointTrajectory(joint_names=[names[i] for i in order] + [UNKNOWN])
        msg.header.stamp = stamp(k)
        msg.points = [JointTrajectoryPoint(positions=list(states[k, 0, order]) + [0.0],
                                           velocities=list(states[k, 1, order]) + [0.0],
                                           accelerations=list(states[k, 2, order]) + [0.0]),
                      JointTrajectoryPoint(positions=[0.0] * (len(names) + 1))]
        if k % 5 == 4:
            msg.points = []
        io.trajectory.publish(msg)
        driver.spin_for(0.02)
    settle(driver, io)
    answers = answers_by_stamp(io)
    assert set(answers) == {k for k in range(20) if k % 5 != 4}
    ks = np.array(sorted(answers))
    tau = expected(demo_model, states[ks])
    for row, k in enumerate(ks):
        np.testing.assert_allclose(answers[k].effort, tau[row], rtol=0, atol=1e-9)
        np.testing.assert_array_equal(answers[k].position, states[k, 0])
    kv = values(io.fresh_status('feedforward'))
    assert kv['rejected no_points'] == '4'


def test_diagnostics_model_rate_and_staleness(driver, unprimed_io, demo_model, node):
    """Model loaded, rate and compute time while fed; ERROR and no output once stale."""
    io = unprimed_io
    status = io.fresh_status('robot model')
    kv = values(status)
    assert status.level == DiagnosticStatus.OK
    assert kv['robot name'] == 'demo_arm' and kv['dof'] == str(len(demo_model.joint_names))
    assert kv['source'] == f'file {DEMO_URDF}'
    status = io.fresh_status('feedforward')
    # before any input: WARN, not ERROR
    assert status.level == DiagnosticStatus.WARN and 'no input' in status.message

    names = demo_model.joint_names
    states = random_states(17, 1500, len(names))
    rng = random.Random(18)
    first = len(io.diagnostics)

    def ok_while_fed():
        return [s for msg in io.diagnostics[first:] for s in msg.status
                if s.name == 'inverse_dynamics: feedforward' and s.level == DiagnosticStatus.OK]
    # fed in bursts until a diagnostics period has seen them (1 Hz): on a loaded machine a
    # burst may end before the node's next period, so the test feeds on rather than guessing
    deadline = time.monotonic() + TIMEOUT
    k = 0
    while not ok_while_fed():
        assert time.monotonic() < deadline, 'no OK status while fed'
        drive(driver, lambda i: io.joint_states.publish(
            shuffled_message(names, states[(k + i) % 1500], k + i, rng)), 300, RATE)
        k += 300
    during = ok_while_fed()
    status = during[-1]
    kv = values(status)
    assert float(kv['input rate [Hz]']) > 0 and float(kv['output rate [Hz]']) > 0
    assert float(kv['compute time mean [us]']) > 0
    assert kv['stale'] == 'False'

    # input stops: within a period past input_timeout (0.3 s) the status is ERROR, stale
    settle(driver, io)
    answered = len(io.efforts)
    status = io.fresh_status('feedforward')
    status = io.fresh_status('feedforward')
    assert status.level == DiagnosticStatus.ERROR and 'stale' in status.message, status
    assert values(status)['stale'] == 'True'
    driver.spin_for(1.0)
    assert len(io.efforts) == answered and len(io.commands) <= answered, 'published while stale'
