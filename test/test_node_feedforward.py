# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Feed-forward terms and model reduction in the installed node, over real DDS.

Each answer is compared with the library on the same URDF: a payload set while running equals
``rnea(with_payload(...))`` from the next message on; armature and URDF friction add
``armature·q̈ + friction_torque``; clamping equals ``clamp_to_effort_limits`` and is counted;
an external wrench equals ``rnea(..., f_ext=...)`` until its timeout; the ``joints`` parameter
equals the full model with the other joints locked. Bad values are rejected with the reason and
change nothing.
"""

import math
import os
import sys
import time

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from node_harness import (  # noqa: E402
    DEMO_URDF, Driver, Io, joint_state, NodeProcess, PENDULUM_URDF, random_states, stamp_key,
    TIMEOUT, values)
import spatial_dynamics as sd  # noqa: E402

pytestmark = pytest.mark.ros

TOL = 1e-9  # N m; the node computes with the same library
PAYLOAD = dict(link='hand', mass=1.5, com=[0.01, -0.02, 0.08],
               inertia=[0.004, 0.0002, -0.0001, 0.005, 0.0003, 0.003])


@pytest.fixture
def node(install, tmp_path):
    proc = NodeProcess(install, ['-p', f'robot_description_file:={DEMO_URDF}'], str(tmp_path))
    yield proc
    assert proc.stop() == 0, proc.log()


@pytest.fixture
def io(driver, node, demo_model):
    channels = Io(driver)
    channels.wait_connected()
    channels.prime(demo_model.joint_names)
    yield channels
    channels.close()


class Asker:
    """Publish one state under a fresh stamp until the answer to that stamp arrives."""

    def __init__(self, driver: Driver, io: Io) -> None:
        self.driver, self.io, self.k = driver, io, 0

    def __call__(self, names, state) -> np.ndarray:
        self.k += 1
        k, io = self.k, self.io
        msg = joint_state(names, *state, k)
        deadline = time.monotonic() + TIMEOUT
        while True:
            answers = [m for m in io.efforts if stamp_key(m.header.stamp) == k]
            if answers:
                assert tuple(answers[0].name) == tuple(names)
                return np.array(answers[0].effort)
            assert time.monotonic() < deadline, f'no answer to message {k}'
            io.joint_states.publish(msg)
            self.driver.spin_for(0.05)


def ok(results):
    """Assert every SetParametersResult succeeded."""
    for result in results:
        assert result.successful, result.reason


def test_payload_set_live_and_bad_payloads_rejected(driver, io, demo_model, node):
    ask = Asker(driver, io)
    names = demo_model.joint_names
    state = random_states(31, 1, len(names))[0]
    plain = ask(names, state)
    np.testing.assert_allclose(plain, sd.rnea(demo_model, *state), rtol=0, atol=TOL)

    ok(io.set_parameters(**{f'payload.{key}': value for key, value in PAYLOAD.items()}))
    loaded = sd.with_payload(demo_model, **PAYLOAD)
    tau = sd.rnea(loaded, *state)
    assert np.abs(tau - plain).max() > 0.1, 'the payload should change the torques'
    np.testing.assert_allclose(ask(names, state), tau, rtol=0, atol=TOL)

    # bad values: rejected, naming the field and the problem; the payload stays
    for name, value, words in [
            ('payload.link', 'no_such_link', ["payload.link", "'no_such_link'"]),
            ('payload.mass', -1.0, ['payload.mass', '-1.0']),
            ('payload.mass', math.nan, ['payload.mass']),
            ('payload.inertia', [0.001, 0.0, 0.0, -0.002, 0.0, 0.001],
             ['payload', 'positive semi-definite']),
            ('payload.inertia', [0.001, 0.0, 0.0, 0.001, 0.0, 0.005],
             ['payload', 'triangle inequality']),
            ('payload.inertia', [0.001] * 5, ['payload.inertia', '6']),
            ('payload.com', [0.0, 0.0], ['payload.com', '3'])]:
        result = io.set_parameters(**{name: value})[0]
        assert not result.successful, (name, value)
        for word in words:
            assert word in result.reason, (word, result.reason)
    np.testing.assert_allclose(ask(names, state), tau, rtol=0, atol=TOL)
    kv = values(io.fresh_status('feedforward'))
    assert kv['payload'].startswith("1.5 kg on 'hand'")

    # a description without the payload's link is refused while the payload is set
    result = io.set_parameters(robot_description_file=PENDULUM_URDF)[0]
    assert not result.successful and 'payload.link' in result.reason
    # payload off: back to the plain model, exactly
    ok(io.set_parameters(**{'payload.link': ''}))
    np.testing.assert_allclose(ask(names, state), plain, rtol=0, atol=0)


def test_armature_and_urdf_friction(driver, io, demo_model, node):
    ask = Asker(driver, io)
    names = demo_model.joint_names
    states = random_states(32, 3, len(names))
    armature = [0.3, 0.3, 0.2, 0.2, 0.05, 0.05, 0.02, 0.5]
    assert len(armature) == len(names)
    ok(io.set_parameters(armature=armature))
    for state in states:
        q, qd, qdd = state
        np.testing.assert_allclose(
            ask(names, state), sd.rnea(demo_model, q, qd, qdd) + sd.armature_torque(
                np.array(armature), qdd), rtol=0, atol=TOL)
    ok(io.set_parameters(friction_model='urdf', friction_velocity_threshold=0.05))
    slow = states[0].copy()
    slow[1] *= 0.01   # velocities near the threshold: the smooth sign matters
    for state in list(states) + [slow]:
        q, qd, qdd = state
        want = (sd.rnea(demo_model, q, qd, qdd) + sd.armature_torque(np.array(armature), qdd)
                + sd.friction_torque(demo_model, qd, 0.05))
        np.testing.assert_allclose(ask(names, state), want, rtol=0, atol=TOL)

    for name, value, word in [('armature', [0.1] * 3, 'armature'),
                              ('armature', [-0.1] + armature[1:], 'joint1'),
                              ('friction_model', 'coulomb', 'friction_model')]:
        result = io.set_parameters(**{name: value})[0]
        assert not result.successful and word in result.reason, (name, result.reason)
    kv = values(io.fresh_status('feedforward'))
    assert kv['friction model'] == 'urdf (threshold 0.05)'
    # off again: the plain rigid-body torques
    from rclpy.parameter import Parameter
    ok(io.set_parameters(friction_model='none',
                         armature=Parameter('armature', Parameter.Type.DOUBLE_ARRAY, [])))
    np.testing.assert_allclose(ask(names, states[0]), sd.rnea(demo_model, *states[0]),
                               rtol=0, atol=TOL)


def test_clamp_to_effort_limits_counts_saturation(driver, io, demo_model, node):
    ask = Asker(driver, io)
    names = demo_model.joint_names
    state = random_states(33, 1, len(names))[0]
    state[2] = 200.0   # accelerations far beyond what joint5..7 (12 N m) can give
    tau = sd.rnea(demo_model, *state)
    clamped, saturated = sd.clamp_to_effort_limits(demo_model, tau)
    assert saturated.any() and not saturated.all()
    np.testing.assert_allclose(ask(names, state), tau, rtol=0, atol=TOL)   # default: off
    ok(io.set_parameters(clamp_to_effort_limits=True))
    np.testing.assert_allclose(ask(names, state), clamped, rtol=0, atol=TOL)
    kv = values(io.fresh_status('feedforward'))
    assert int(kv['saturated']) >= 1
    for i in np.flatnonzero(saturated):
        assert f'{names[i]}: ' in kv['saturated joints'], kv['saturated joints']
    assert 'clamped to the URDF effort limit' in node.wait_for_log('clamped to the URDF')
    assert repr(names[int(np.flatnonzero(saturated)[0])]) in node.log()


def wrench_msg(link, torque, force):
    """Return a WrenchStamped on ``link`` (its frame)."""
    from geometry_msgs.msg import WrenchStamped
    msg = WrenchStamped()
    msg.header.frame_id = link
    (msg.wrench.torque.x, msg.wrench.torque.y, msg.wrench.torque.z) = map(float, torque)
    (msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z) = map(float, force)
    return msg


def test_external_wrenches_applied_until_timeout(driver, io, demo_model, node):
    from geometry_msgs.msg import WrenchStamped
    ask = Asker(driver, io)
    names = demo_model.joint_names
    state = random_states(34, 1, len(names))[0]
    plain = sd.rnea(demo_model, *state)
    wrenches = driver.node.create_publisher(WrenchStamped, 'external_wrenches', 10)
    driver.spin_until(lambda: wrenches.get_subscription_count() >= 1, what='wrench subscriber')
    ok(io.set_parameters(external_wrench_timeout=30.0))
    hand = ([0.2, -0.1, 0.3], [5.0, -3.0, 20.0])
    link4 = ([0.0, 0.5, 0.0], [0.0, 0.0, -8.0])
    f_ext = {'hand': np.r_[hand[0], hand[1]], 'link4': np.r_[link4[0], link4[1]]}
    want_both = sd.rnea(demo_model, *state, f_ext=f_ext)
    want_hand = sd.rnea(demo_model, *state, f_ext={'hand': f_ext['hand']})

    def until(want, publish=()):
        deadline = time.monotonic() + TIMEOUT
        while True:
            for msg in publish:
                wrenches.publish(msg)
            driver.spin_for(0.05)
            got = ask(names, state)
            if np.allclose(got, want, rtol=0, atol=TOL):
                return
            assert time.monotonic() < deadline, f'never answered {want}, last {got}'

    try:
        until(want_both, [wrench_msg('hand', *hand), wrench_msg('link4', *link4)])
        # stays while unexpired, without republishing
        driver.spin_for(0.5)
        np.testing.assert_allclose(ask(names, state), want_both, rtol=0, atol=TOL)
        # a zero wrench removes that link's wrench
        until(want_hand, [wrench_msg('link4', [0, 0, 0], [0, 0, 0])])
        # bad wrenches: rejected and counted, the active one stays
        for _ in range(3):
            wrenches.publish(wrench_msg('no_such_link', [0, 0, 0], [1, 0, 0]))
            wrenches.publish(wrench_msg('hand', [0, 0, 0], [math.nan, 0, 0]))
            wrenches.publish(wrench_msg('hand', [0, 0, 0], [0, 1.7e308, 0]))
            driver.spin_for(0.05)
        node.wait_for_log("header.frame_id 'no_such_link' is not a link")
        kv = values(io.fresh_status('feedforward'))
        assert int(kv['external wrenches rejected unknown_link']) >= 1
        assert int(kv['external wrenches rejected non_finite']) >= 1
        assert int(kv['external wrenches rejected out_of_bounds']) >= 1
        assert kv['external wrenches active'] == 'hand'
        np.testing.assert_allclose(ask(names, state), want_hand, rtol=0, atol=TOL)
        # timeout: a short one, and the wrench goes away by itself
        ok(io.set_parameters(external_wrench_timeout=0.3))
        until(want_hand, [wrench_msg('hand', *hand)])
        driver.spin_for(1.0)
        np.testing.assert_allclose(ask(names, state), plain, rtol=0, atol=TOL)
    finally:
        driver.node.destroy_publisher(wrenches)


def test_joints_reduce_the_model_with_locked_positions(driver, io, demo_model, node):
    """Outputs on the kept joints equal the full model's with the others locked, at rest."""
    ask = Asker(driver, io)
    names = demo_model.joint_names
    kept = ['joint4', 'joint1', 'joint2', 'joint3']
    idx = [names.index(j) for j in kept]
    state = random_states(35, 1, len(names))[0]
    ok(io.set_parameters(joints=kept))
    for locked in ({}, {'joint6': 0.7, 'finger_joint1': 0.02}):
        if locked:
            ok(io.set_parameters(locked_joints=list(locked),
                                 locked_positions=list(locked.values())))
        full = np.zeros_like(state)
        full[:, idx] = state[:, idx]
        for name, value in locked.items():
            full[0, names.index(name)] = value
        want = sd.rnea(demo_model, *full)[idx]
        # the message carries the kept joints only
        got = ask(kept, state[:, idx])
        np.testing.assert_allclose(got, want, rtol=0, atol=TOL)
        # and equals the library's reduced model
        reduced = sd.Model.from_urdf(DEMO_URDF, joints=kept, locked=locked)
        np.testing.assert_allclose(got, sd.rnea(reduced, *state[:, idx]), rtol=0, atol=TOL)
    kv = values(io.fresh_status('robot model'))
    assert kv['model joints'] == ', '.join(kept)
    assert 'locked: ' in kv['summary'] and 'joint6=0.7' in kv['summary']
    for name, value, word in [('locked_positions', [0.1], 'locked_positions'),
                              ('locked_joints', ['joint1', 'joint6'], 'joint1')]:
        result = io.set_parameters(**{name: value})[0]
        assert not result.successful and word in result.reason, result.reason


def test_backend_warmed_up_and_summary_logged(driver, io, demo_model, node):
    log = node.wait_for_log('backend: ')
    assert f'model: {demo_model.summary()}' in log
    kv = values(io.fresh_status('robot model'))
    assert kv['backend'] and kv['backend'].split()[0] in ('compiled', 'numpy')
    assert kv['summary'] == demo_model.summary()
