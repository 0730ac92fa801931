# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Output choice, feed-forward terms and feedback on the measured state, over real DDS.

The installed node runs as a process; its answers are compared with Pinocchio
(computeGeneralizedGravity, nonLinearEffects, crba, rnea) on the same URDF: the terms on
``feedforward_terms`` sum to the published torque and each equals its part of the dynamics
(UR5); ``without_gravity`` and ``gravity_only`` equal τ − g(q) and g(q); ``pd_feedforward``
and ``computed_torque`` equal their formulas for a desired + measured pair, with the position
error of a continuous joint wrapped (the demo arm's joint7). Each measured message is answered
once, desired messages only update the held setpoint; a stale measured state stops the
output with diagnostics ERROR; bad gains and bad measured messages are refused with the
reason and change nothing. Waits are generous bounds, never timing assertions.
"""

import contextlib
import math
import os
import sys
import time

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from conftest import robot_urdf_path  # noqa: E402
from node_harness import (  # noqa: E402
    DEMO_URDF, Driver, Io, joint_state, NodeProcess, pin_oracle, stamp, stamp_key, TIMEOUT,
    values)

pytestmark = pytest.mark.ros

TOL = 1e-9   # N m: against Pinocchio (RNEA vs RNEA/CRBA, double precision)
ERROR = b'\x02'   # diagnostic_msgs/DiagnosticStatus.ERROR as rclpy gives a byte field


def ok(results):
    """Assert every SetParametersResult succeeded."""
    for result in results:
        assert result.successful, result.reason


def refused(results, *words):
    """Assert the one result failed and its reason names every word."""
    (result,) = results
    assert not result.successful
    for word in words:
        assert word in result.reason, (word, result.reason)
    return result.reason


class Loop:
    """Desired and measured states to the node; its answers (efforts, terms) by stamp."""

    def __init__(self, driver: Driver, io: Io, names) -> None:
        from sensor_msgs.msg import JointState
        self.driver, self.io, self.names = driver, io, tuple(names)
        self.k = 1000    # stamps of this test's messages
        self.terms = []
        self.measured = driver.node.create_publisher(JointState, 'joint_states', 10)
        self.terms_sub = None
        driver.spin_until(lambda: self.measured.get_subscription_count() >= 1,
                          what='the node to subscribe joint_states')

    def subscribe_terms(self) -> None:
        from sensor_msgs.msg import JointState
        self.terms_sub = self.driver.node.create_subscription(
            JointState, 'feedforward_terms', self.terms.append, 100)
        self.driver.spin_until(lambda: self.terms_sub.get_publisher_count() >= 1,
                               what='feedforward_terms')

    def close(self) -> None:
        self.driver.node.destroy_publisher(self.measured)
        if self.terms_sub is not None:
            self.driver.node.destroy_subscription(self.terms_sub)

    def answers(self, k):
        return [m for m in self.io.efforts if stamp_key(m.header.stamp) == k]

    def _ask(self, publisher, message, with_terms=False):
        """Publish ``message(k)`` until answered; the effort (and the terms) of stamp ``k``.

        The node publishes the terms only once it has seen our subscription, which on a
        loaded machine may come after its answer to the first stamp: an answer without
        terms is asked again with the next stamp (the node answers a stamp once).
        """
        self.k += 1
        msg = message(self.k)
        deadline = time.monotonic() + TIMEOUT
        while True:
            k = self.k
            answers = self.answers(k)
            terms = [m for m in self.terms if stamp_key(m.header.stamp) == k]
            if answers and (terms or not with_terms):
                assert tuple(answers[0].name) == self.names
                effort = np.array(answers[0].effort)
                return (effort, terms[0]) if with_terms else effort
            assert time.monotonic() < deadline, (
                f'no answer to message {k} ({len(answers)} answers of it, '
                f'{len(self.io.efforts)} efforts and {len(self.terms)} terms received, '
                f'the last of stamps {[stamp_key(m.header.stamp) for m in self.io.efforts[-3:]]}'
                f', terms wanted: {with_terms})')
            if answers:             # answered before the node saw our terms subscription
                self.driver.spin_for(0.05)      # terms of k may still be on their way
                if not [m for m in self.terms if stamp_key(m.header.stamp) == k]:
                    self.k += 1
                    msg = message(self.k)
                continue
            publisher.publish(msg)
            self.driver.spin_for(0.05)

    def desired(self, state, with_terms=False):
        """Publish a desired state (q, qd, qdd) until answered (feedforward mode)."""
        return self._ask(self.io.joint_states, lambda k: joint_state(self.names, *state, k),
                         with_terms)

    def measured_msg(self, q, qd, k):
        msg = joint_state(self.names, q, qd, [], k)
        msg.effort = [123.0] * len(self.names)    # a measured torque: never read
        return msg

    def measure(self, q, qd, with_terms=False):
        """Publish a measured (q, qd) until answered (feedback modes)."""
        return self._ask(self.measured, lambda k: self.measured_msg(q, qd, k), with_terms)


@pytest.fixture
def demo(install, tmp_path):
    proc = NodeProcess(install, ['-p', f'robot_description_file:={DEMO_URDF}',
                                 '-p', 'input_timeout:=60.0'], str(tmp_path))
    yield proc
    assert proc.stop() == 0, proc.log()


@contextlib.contextmanager
def connected(driver, names):
    """Yield ``(io, loop)`` talking to the node, primed; close both afterwards."""
    io = Io(driver)
    loop = None
    try:
        io.wait_connected()
        io.prime(names)
        loop = Loop(driver, io, names)
        yield io, loop
    finally:
        if loop is not None:
            loop.close()
        io.close()


def pin_parts(oracle, names, q, qd, qdd):
    """Pinocchio's g(q), C q̇, M q̈ and RNEA in our joint order (mimic torques folded)."""
    pin = oracle.pin
    q_pin, v_pin, a_pin = oracle.expand(names, q, qd, qdd)
    g = pin.computeGeneralizedGravity(oracle.model, oracle.data, q_pin).copy()
    nle = pin.nonLinearEffects(oracle.model, oracle.data, q_pin, v_pin).copy()
    M = pin.crba(oracle.model, oracle.data, q_pin).copy()
    M = np.triu(M) + np.triu(M, 1).T
    tau = pin.rnea(oracle.model, oracle.data, q_pin, v_pin, a_pin).copy()
    fold = oracle.fold
    return dict(gravity=fold(names, g), velocity_product=fold(names, nle - g),
                inertial=fold(names, M @ a_pin), rnea=fold(names, tau))


def split(msg, names):
    """Term -> (n,) of a feedforward_terms message; checks its ``<joint>/<term>`` names."""
    terms = {}
    for name, value in zip(msg.name, msg.effort):
        joint, term = name.rsplit('/', 1)
        terms.setdefault(term, {})[joint] = value
    for term, by_joint in terms.items():
        assert set(by_joint) == set(names), term
    assert len(msg.effort) == len(msg.name) == len(terms) * len(names)
    return {term: np.array([by_joint[j] for j in names]) for term, by_joint in terms.items()}


def test_terms_and_outputs_against_pinocchio_ur5(install, driver, tmp_path):
    urdf = robot_urdf_path('ur5')
    oracle = pin_oracle(urdf)
    import spatial_dynamics as sd
    names = sd.Model.from_urdf(urdf).joint_names
    node = NodeProcess(install, ['-p', f'robot_description_file:={urdf}'], str(tmp_path))
    with connected(driver, names) as (io, loop):
        rng = np.random.default_rng(61)
        state = tuple(rng.uniform(-1.0, 1.0, len(names)) * s for s in (2.0, 1.5, 4.0))
        pin = pin_parts(oracle, names, *state)
        # nobody subscribed: no terms computed; then subscribed: the terms of each answer
        tau = loop.desired(state)
        np.testing.assert_allclose(tau, pin['rnea'], rtol=0, atol=TOL)
        loop.subscribe_terms()
        tau, msg = loop.desired(state, with_terms=True)
        terms = split(msg, names)
        assert list(terms) == ['gravity', 'velocity_product', 'inertial', 'armature',
                               'friction', 'external']
        np.testing.assert_allclose(sum(terms.values()), tau, rtol=0, atol=1e-12)
        for term in ('gravity', 'velocity_product', 'inertial'):
            np.testing.assert_allclose(terms[term], pin[term], rtol=0, atol=TOL, err_msg=term)
        for term in ('armature', 'friction', 'external'):   # all off by default
            np.testing.assert_array_equal(terms[term], 0.0)
        assert stamp_key(msg.header.stamp) == loop.k   # the answer's header

        ok(io.set_parameters(output='without_gravity'))
        tau, msg = loop.desired(state, with_terms=True)
        np.testing.assert_allclose(tau, pin['rnea'] - pin['gravity'], rtol=0, atol=TOL)
        terms = split(msg, names)
        assert 'gravity' not in terms
        np.testing.assert_allclose(sum(terms.values()), tau, rtol=0, atol=1e-12)

        ok(io.set_parameters(output='gravity_only'))
        tau, msg = loop.desired(state, with_terms=True)
        np.testing.assert_allclose(tau, pin['gravity'], rtol=0, atol=TOL)
        assert list(split(msg, names)) == ['gravity']

        # output none has nothing to publish in feedforward mode: refused, output unchanged
        refused(io.set_parameters(output='none'), 'none', 'feedforward', 'zeros')
        refused(io.set_parameters(output='all'), 'output', "'all'")
        np.testing.assert_allclose(loop.desired(state), pin['gravity'], rtol=0, atol=TOL)
        kv = values(io.fresh_status('feedforward'))
        assert kv['output'] == 'gravity_only' and kv['control mode'] == 'feedforward'
        assert node.stop() == 0, node.log()


def wrapped_pair(names, seed):
    """Return a desired state, a measured one and e; joint7 (continuous) a turn away."""
    rng = np.random.default_rng(seed)
    n = len(names)
    desired = tuple(rng.uniform(-1.0, 1.0, n) * s for s in (1.5, 1.0, 3.0))
    q = desired[0] + rng.uniform(-0.2, 0.2, n)
    qd = desired[1] + rng.uniform(-0.5, 0.5, n)
    j7 = names.index('joint7')
    q[j7] = desired[0][j7] - 0.3 + 2.0 * math.pi     # naive error 0.3 - 2 pi, wrapped 0.3
    e = desired[0] - q
    e[j7] = 0.3
    return desired, (q, qd), e


def test_pd_feedforward_and_computed_torque_against_pinocchio(driver, demo, demo_model):
    names = demo_model.joint_names
    oracle = pin_oracle(DEMO_URDF)
    with connected(driver, names) as (io, loop):
        n = len(names)
        kp, kd = np.linspace(20.0, 90.0, n), np.linspace(2.0, 9.0, n)
        ok(io.set_parameters(kp=kp.tolist(), kd=kd.tolist()))
        desired, (q, qd), e = wrapped_pair(names, 62)
        u = kp * e + kd * (desired[1] - qd)
        # the desired state is answered in feedforward mode (so it is known to be held) ...
        np.testing.assert_allclose(loop.desired(desired), oracle.rnea(names, *desired),
                                   rtol=0, atol=TOL)
        # ... and held when the measured state triggers the answers
        ok(io.set_parameters(control_mode='pd_feedforward'))
        loop.subscribe_terms()
        tau, msg = loop.measure(q, qd, with_terms=True)
        np.testing.assert_allclose(tau, oracle.rnea(names, *desired) + u, rtol=0, atol=TOL)
        terms = split(msg, names)
        np.testing.assert_allclose(terms['feedback'], u, rtol=0, atol=1e-12)
        np.testing.assert_allclose(sum(terms.values()), tau, rtol=0, atol=1e-12)
        answered = io.efforts[-1]
        np.testing.assert_array_equal(answered.position, desired[0])   # the setpoint
        np.testing.assert_array_equal(answered.velocity, desired[1])

        ok(io.set_parameters(control_mode='computed_torque'))
        pin = pin_parts(oracle, names, q, qd, desired[2])
        tau, msg = loop.measure(q, qd, with_terms=True)
        M_u = pin_parts(oracle, names, q, np.zeros(n), u)['inertial']
        np.testing.assert_allclose(tau, oracle.rnea(names, q, qd, desired[2] + u), rtol=0,
                                   atol=TOL)
        terms = split(msg, names)
        for term in ('gravity', 'velocity_product', 'inertial'):   # at the MEASURED state
            np.testing.assert_allclose(terms[term], pin[term], rtol=0, atol=TOL, err_msg=term)
        np.testing.assert_allclose(terms['feedback'], M_u, rtol=0, atol=TOL)
        np.testing.assert_allclose(sum(terms.values()), tau, rtol=0, atol=1e-12)

        ok(io.set_parameters(output='without_gravity'))
        np.testing.assert_allclose(loop.measure(q, qd), oracle.rnea(
            names, q, qd, desired[2] + u) - pin['gravity'], rtol=0, atol=TOL)
        ok(io.set_parameters(output='none'))
        np.testing.assert_allclose(loop.measure(q, qd), M_u, rtol=0, atol=TOL)
        # PD alone: output none in pd_feedforward is the feedback term only
        ok(io.set_parameters(control_mode='pd_feedforward'))
        np.testing.assert_allclose(loop.measure(q, qd), u, rtol=0, atol=1e-12)
        refused(io.set_parameters(control_mode='feedforward'), 'none', 'feedforward')
        kv = values(io.fresh_status('feedforward'))
        assert kv['control mode'] == 'pd_feedforward' and kv['output'] == 'none'
        assert kv['continuous joints'] == 'joint7'


def test_each_measured_state_answered_once_desired_only_held(driver, demo, demo_model):
    names = demo_model.joint_names
    n = len(names)
    with connected(driver, names) as (io, loop):
        ok(io.set_parameters(kp=[10.0], kd=[1.0], control_mode='pd_feedforward'))
        ok(io.set_parameters(output='none'))
        zeros = np.zeros(n)
        q = np.linspace(-0.1, 0.1, n)
        # held from the priming message (zeros): PD towards it
        np.testing.assert_allclose(loop.measure(q, zeros), -10.0 * q, rtol=0, atol=1e-12)
        # lockstep: each measured message published once, answered once
        for step in range(5):
            k = 4000 + step
            loop.measured.publish(loop.measured_msg(q * step, zeros, k))
            driver.spin_until(lambda: loop.answers(k), what=f'the answer to {k}')
        driver.spin_for(0.5)
        for step in range(5):
            (answer,) = loop.answers(4000 + step)
            np.testing.assert_allclose(answer.effort, -10.0 * q * step, rtol=0, atol=1e-12)
        # desired messages are not answered in a feedback mode, they move the setpoint
        q_d = np.full(n, 0.2)
        before = len(io.efforts)
        for k in range(5):
            io.joint_states.publish(joint_state(names, q_d, zeros, zeros, 5000 + k))
            driver.spin_for(0.05)
        driver.spin_for(0.5)
        assert len(io.efforts) == before, 'a desired message was answered in pd_feedforward'
        deadline = time.monotonic() + TIMEOUT
        while not np.allclose(loop.measure(q, zeros), 10.0 * (q_d - q), rtol=0, atol=1e-12):
            assert time.monotonic() < deadline, 'the new desired state was never held'
            io.joint_states.publish(joint_state(names, q_d, zeros, zeros, 5000))
        keys = [stamp_key(m.header.stamp) for m in io.efforts]
        assert not any(5000 <= k < 5005 for k in keys)


def test_stale_measured_or_desired_state_stops_the_output(driver, demo, demo_model):
    names = demo_model.joint_names
    n = len(names)
    zeros = np.zeros(n)
    with connected(driver, names) as (io, loop):
        ok(io.set_parameters(control_mode='pd_feedforward', kp=[5.0], measured_timeout=0.2))
        ok(io.set_parameters(output='none'))    # the PD alone: -5 * 0.1 below
        loop.measure(zeros + 0.1, zeros)
        # no measured state any more, desired still coming: nothing is published
        driver.spin_until(lambda: 'measured state stale' in io.fresh_status('feedforward')
                          .message, what='diagnostics to report the stale measured state')
        status = io.fresh_status('feedforward')
        assert status.level == ERROR and 'joint_states' in status.message, status.message
        before = len(io.efforts)
        for k in range(10):
            io.joint_states.publish(joint_state(names, zeros, zeros, zeros, 6000 + k))
            driver.spin_for(0.05)
        driver.spin_for(0.3)
        assert len(io.efforts) == before, 'published without a fresh measured state'
        assert values(status)['measured state stale'] == 'True'

        # a desired state older than input_timeout: measured states are not answered
        ok(io.set_parameters(input_timeout=0.2, measured_timeout=60.0))
        driver.spin_for(0.5)
        before = len(io.efforts)
        for k in range(10):
            loop.measured.publish(loop.measured_msg(zeros, zeros, 7000 + k))
            driver.spin_for(0.05)
        driver.spin_until(lambda: int(values(io.fresh_status('feedforward'))
                                      ['rejected desired_stale']) >= 1,
                          what='stale desired states to be counted')
        assert len(io.efforts) == before, 'answered with a stale desired state'
        status = io.fresh_status('feedforward')
        assert status.level == ERROR and 'desired state stale' in status.message, status.message
        # fresh again: answers resume
        ok(io.set_parameters(input_timeout=60.0))
        io.joint_states.publish(joint_state(names, zeros, zeros, zeros, 8000))
        driver.spin_for(0.2)
        np.testing.assert_allclose(loop.measure(zeros + 0.1, zeros), -0.5, rtol=0, atol=1e-9)


def test_bad_gains_and_bad_measured_states_change_nothing(driver, demo, demo_model):
    names = demo_model.joint_names
    n = len(names)
    with connected(driver, names) as (io, loop):
        ok(io.set_parameters(kp=np.linspace(1.0, 8.0, n).tolist(), kd=[2.0]))
        desired, (q, qd), _ = wrapped_pair(names, 63)
        loop.desired(desired)    # answered in feedforward mode, so held from now on
        ok(io.set_parameters(control_mode='computed_torque'))
        first = loop.measure(q, qd)

        # output none with zero gains would publish zeros: refused, also atomically
        ok(io.set_parameters(control_mode='pd_feedforward'))
        refused(io.set_parameters_atomically(output='none', kp=[0.0], kd=[0.0]), 'output',
                'kp = kd = 0', 'zeros')
        ok(io.set_parameters(control_mode='computed_torque'))
        np.testing.assert_array_equal(loop.measure(q, qd), first)
        for change, words in [
                (dict(kp=[-1.0]), ['kp', 'joint1', '-1.0']),
                (dict(kp=[1.0, 2.0]), ['kp', '2 values', '8 joints']),
                (dict(kd=[math.nan]), ['kd', 'nan']),
                (dict(kp=[1e7]), ['kp', '1e+06', '1/s²']),
                (dict(kd=[1e5] * n), ['kd', '10000', '1/s']),
                (dict(control_mode='pid'), ['control_mode', "'pid'"])]:
            refused(io.set_parameters(**change), *words)

        bad = []
        for field, value in [('position', [math.nan] + list(q[1:])),
                             ('position', list(q[:-1])),
                             ('velocity', []),
                             ('velocity', [1e6] * n),
                             ('name', list(names[:-1]) + ['no_such_joint'])]:
            msg = loop.measured_msg(q, qd, 0)
            setattr(msg, field, value)
            bad.append(msg)
        for k, msg in enumerate(bad):
            msg.header.stamp = stamp(9100 + k)
            for _ in range(3):
                loop.measured.publish(msg)
                driver.spin_for(0.05)
        reasons = ('non_finite', 'length_mismatch', 'no_velocity', 'out_of_bounds',
                   'missing_joint')

        def counted():
            kv = values(io.fresh_status('feedforward'))
            return all(int(kv[f'measured states rejected {r}']) >= 1 for r in reasons)

        driver.spin_until(counted, what='every bad measured state counted with its reason')
        keys = [stamp_key(m.header.stamp) for m in io.efforts]
        assert not any(9100 <= k < 9100 + len(bad) for k in keys), 'a bad state was answered'
        demo.wait_for_log('joint_states: measured state rejected')
        np.testing.assert_array_equal(loop.measure(q, qd), first)   # identical to before

        # a desired state that cannot be real is refused where it enters: the held one stays
        huge = [list(desired[0]), list(desired[1]), list(desired[2])]
        huge[0][0] = 1e300
        for _ in range(3):
            io.joint_states.publish(joint_state(names, *huge, 9200))
            driver.spin_for(0.05)
        driver.spin_until(lambda: int(values(io.fresh_status('feedforward'))
                                      ['rejected out_of_bounds']) >= 1,
                          what='the absurd desired state to be counted')
        np.testing.assert_array_equal(loop.measure(q, qd), first)   # identical to before


def test_a_measured_state_is_answered_once_even_if_sent_again(driver, demo, demo_model):
    """A lockstep simulator republishes the state it waits on: one command per measurement."""
    names = demo_model.joint_names
    n = len(names)
    with connected(driver, names) as (io, loop):
        ok(io.set_parameters(kp=[10.0], kd=[1.0], control_mode='pd_feedforward'))
        zeros = np.zeros(n)
        q = np.linspace(-0.1, 0.1, n)
        loop.measure(q, zeros)                        # the loop is up
        before = int(values(io.fresh_status('feedforward'))['rejected repeated'])
        msg = loop.measured_msg(q, zeros, 6000)
        for _ in range(4):
            loop.measured.publish(msg)
            driver.spin_for(0.1)
        driver.spin_until(lambda: int(values(io.fresh_status('feedforward'))
                                      ['rejected repeated']) >= before + 3,
                          what='three repeats counted')
        assert len(loop.answers(6000)) == 1
        # the next measurement is answered again
        loop.measured.publish(loop.measured_msg(q, zeros, 6001))
        driver.spin_until(lambda: loop.answers(6001), what='the answer to 6001')


THREE_JOINTS = ('<robot name="three"><link name="base"/>' + ''.join(
    f'<link name="l{i}"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" '
    f'iyy="0.01" iyz="0" izz="0.01"/></inertial></link>'
    f'<joint name="j{i}" type="revolute"><parent link="{"base" if i == 1 else f"l{i - 1}"}"/>'
    f'<child link="l{i}"/><origin xyz="0 0 0.2"/><axis xyz="0 1 0"/>'
    '<limit lower="-3" upper="3" effort="50" velocity="3"/></joint>' for i in (1, 2, 3))
    + '</robot>')


def test_related_changes_are_all_or_nothing_with_set_parameters_atomically(
        driver, demo, demo_model, tmp_path):
    """A new 3-joint description with its 3 gains: atomically all applied; one by one, not.

    rclpy's plain SetParameters validates and applies each parameter alone (the README says
    so): the description is refused against the 8 gains in use, the 3 gains against the
    8-joint model, and only kd is applied. SetParametersAtomically validates them together.
    """
    path = tmp_path / 'three.urdf'
    path.write_text(THREE_JOINTS)
    n = len(demo_model.joint_names)
    with connected(driver, demo_model.joint_names) as (io, _):
        ok(io.set_parameters(kp=np.linspace(1.0, 8.0, n).tolist(), kd=[0.0]))
        change = dict(robot_description_file=str(path), kp=[1.0, 2.0, 3.0], kd=[0.5])
        results = io.set_parameters(**change)
        assert [r.successful for r in results] == [False, False, True], results
        assert values(io.fresh_status('robot model'))['dof'] == str(n)
        ok(io.set_parameters_atomically(**change))
        driver.spin_until(lambda: values(io.fresh_status('robot model'))['dof'] == '3',
                          what='the 3-joint model')


def test_a_whole_trajectory_is_followed_at_the_measured_stamps(driver, demo, demo_model):
    """pd_feedforward samples the held trajectory at each measured state's stamp (JTC rules).

    The answers equal the control law at the trajectory's cubic spline evaluated at the
    stamp (the same splines as replay --trajectory); after the last point the last position
    is held; a bad trajectory is refused whole and the one followed goes on; a new one
    replaces it from its start.
    """
    from builtin_interfaces.msg import Duration, Time
    from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
    import spatial_dynamics as sd
    from spatial_dynamics import trajectory as plan
    names = demo_model.joint_names
    n = len(names)
    kp, kd = 10.0, 1.0
    t0 = 2_000_000                  # s: the trajectories' start, on the measured clock
    rng = np.random.default_rng(71)
    points = [(0.0, rng.uniform(-0.5, 0.5, n), np.zeros(n)),
              (0.6, rng.uniform(-0.5, 0.5, n), rng.uniform(-0.5, 0.5, n)),
              (1.0, rng.uniform(-0.5, 0.5, n), np.zeros(n))]

    def message(pts, start, order=None):
        order = list(range(n)) if order is None else order
        msg = JointTrajectory(joint_names=[names[i] for i in order])
        msg.header.stamp = Time(sec=ns(start) // 1_000_000_000,
                                nanosec=ns(start) % 1_000_000_000)
        for t, q, qd in pts:
            msg.points.append(JointTrajectoryPoint(
                positions=[float(q[i]) for i in order], velocities=[float(qd[i]) for i in order],
                time_from_start=Duration(sec=int(t), nanosec=int(round((t % 1) * 1e9)))))
        return msg

    def ns(t):
        """Seconds after t0 as integer ns on the measured clock (what the node samples at)."""
        return t0 * 1_000_000_000 + int(round(t * 1e9))

    def expected(pts, start, t, q, qd):
        traj = plan.trajectory(names, [{'positions': list(p[1]), 'velocities': list(p[2]),
                                        'time_from_start': {'sec': int(p[0]),
                                                            'nanosec': int(round(
                                                                (p[0] % 1) * 1e9))}}
                                       for p in pts])
        qd_, vd, ad = (x[0] for x in plan.evaluate(traj, np.array([(ns(t) - ns(start)) * 1e-9])))
        return sd.rnea(demo_model, qd_, vd, ad) + kp * (qd_ - q) + kd * (vd - qd)

    with connected(driver, names) as (io, loop):
        ok(io.set_parameters(control_mode='pd_feedforward', kp=[kp], kd=[kd]))
        # the measured clock (a driver's, or sim time) is the one trajectories are sampled on
        first = loop.measured_msg(np.zeros(n), np.zeros(n), 0)
        first.header.stamp = Time(sec=t0 - 1, nanosec=0)
        for _ in range(3):
            loop.measured.publish(first)
            driver.spin_for(0.05)
        # names in another order: mapped by name
        io.trajectory.publish(message(points, 0.0, order=list(reversed(range(n)))))
        demo.wait_for_log('desired_trajectory: following 3 points (cubic')

        def answer(t, q, qd):
            msg = loop.measured_msg(q, qd, 0)
            msg.header.stamp = Time(sec=ns(t) // 1_000_000_000, nanosec=ns(t) % 1_000_000_000)
            key = (msg.header.stamp.sec, msg.header.stamp.nanosec)
            deadline = time.monotonic() + TIMEOUT
            while True:
                got = [m for m in io.efforts
                       if (m.header.stamp.sec, m.header.stamp.nanosec) == key]
                if got:
                    return np.array(got[0].effort)
                assert time.monotonic() < deadline, f'no answer at {t}'
                loop.measured.publish(msg)
                driver.spin_for(0.05)

        q, qd = rng.uniform(-0.5, 0.5, n), rng.uniform(-0.5, 0.5, n)
        for dt in (0.0, 0.25, 0.61, 0.85, 1.01, 1.7):    # not at knots; 1.01, 1.7: held
            np.testing.assert_allclose(answer(dt, q, qd),
                                       expected(points, 0.0, dt, q, qd), rtol=0, atol=1e-9,
                                       err_msg=f'{dt} s into the trajectory')
        # refused whole (time_from_start not increasing): the old trajectory goes on
        bad = [points[0], points[2], points[1]]
        io.trajectory.publish(message(bad, 1.8))
        driver.spin_until(lambda: int(values(io.fresh_status('feedforward'))
                                      ['rejected time_not_increasing']) >= 1,
                          what='the bad trajectory to be refused')
        np.testing.assert_allclose(answer(1.9, q, qd), expected(points, 0.0, 1.9, q, qd),
                                   rtol=0, atol=1e-9)
        # a new one replaces it from its start; before that start, the old one goes on
        new = [(0.0, points[2][1], np.zeros(n)), (0.5, points[0][1], np.zeros(n))]
        io.trajectory.publish(message(new, 2.0))
        demo.wait_for_log('desired_trajectory: following 2 points')
        np.testing.assert_allclose(answer(1.95, q, qd), expected(points, 0.0, 1.95, q, qd),
                                   rtol=0, atol=1e-9)
        for dt in (2.1, 2.4, 3.0):
            np.testing.assert_allclose(answer(dt, q, qd), expected(new, 2.0, dt, q, qd),
                                       rtol=0, atol=1e-9)


def test_a_plan_is_annotated_with_model_effort_for_jtc(driver, demo, demo_model):
    """trajectory_effort_tolerance > 0: each desired_trajectory comes back with effort.

    On ``annotated_trajectory``: the same joints (model order), the plan's own points among
    the resampled ones with positions unchanged, effort = the model torque (``output`` part)
    of the spline at each point, and JTC's linear interpolation of that effort between two
    points within the tolerance of the model torque along the spline (checked at 7 interior
    instants of every interval; a quintic plan: no torque jumps at its points).
    ``output: without_gravity`` annotates τ − g(q); a plan
    naming only some joints is refused with a reason and nothing is published.
    """
    from builtin_interfaces.msg import Duration
    from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
    import spatial_dynamics as sd
    from spatial_dynamics import trajectory as plan
    names = demo_model.joint_names
    n = len(names)
    tol = 0.05                       # N m
    rng = np.random.default_rng(5)
    points = [(0.0, rng.uniform(-0.5, 0.5, n)), (0.8, rng.uniform(-0.5, 0.5, n)),
              (2.0, rng.uniform(-0.5, 0.5, n))]
    msg = JointTrajectory(joint_names=list(reversed(names)))
    for t, q in points:
        msg.points.append(JointTrajectoryPoint(
            positions=[float(x) for x in reversed(q)], velocities=[0.0] * n,
            accelerations=[0.0] * n,
            time_from_start=Duration(sec=int(t), nanosec=int(round((t % 1) * 1e9)))))
    traj = plan.trajectory(names, [
        {'positions': list(q), 'velocities': [0.0] * n, 'accelerations': [0.0] * n,
         'time_from_start': {'sec': int(t), 'nanosec': int(round((t % 1) * 1e9))}}
        for t, q in points])
    got = []
    sub = driver.node.create_subscription(JointTrajectory, 'annotated_trajectory', got.append,
                                          10)
    try:
        with connected(driver, names) as (io, loop):
            for output, part in (('full', lambda q, v, a: sd.rnea(demo_model, q, v, a)),
                                 ('without_gravity', lambda q, v, a: sd.rnea(demo_model, q, v, a)
                                  - sd.gravity_torque(demo_model, q))):
                ok(io.set_parameters(trajectory_effort_tolerance=tol, output=output))
                before = len(got)
                io.trajectory.publish(msg)
                driver.spin_until(lambda: len(got) > before, what='annotated_trajectory')
                out = got[-1]
                assert list(out.joint_names) == list(names)
                times = np.array([p.time_from_start.sec + p.time_from_start.nanosec * 1e-9
                                  for p in out.points])
                assert np.all(np.diff(times) > 0) and len(times) > len(points)
                effort = np.array([p.effort for p in out.points])
                for t, q in points:          # the plan's own points are kept as they were
                    k = int(np.argmin(np.abs(times - t)))
                    assert abs(times[k] - t) < 1e-9
                    np.testing.assert_allclose(out.points[k].positions, q, rtol=0, atol=1e-12)
                for k, t in enumerate(times):    # effort = the model part on the spline
                    q, v, a = (x[0] for x in plan.evaluate(traj, np.array([t])))
                    np.testing.assert_allclose(effort[k], part(q, v, a), rtol=0, atol=1e-9)
                worst = 0.0                  # what JTC interpolates, against the model
                for k in range(len(times) - 1):
                    for s in np.linspace(0.0, 1.0, 9)[1:-1]:
                        t = times[k] + s * (times[k + 1] - times[k])
                        q, v, a = (x[0] for x in plan.evaluate(traj, np.array([t])))
                        linear = (1 - s) * effort[k] + s * effort[k + 1]
                        worst = max(worst, float(np.abs(linear - part(q, v, a)).max()))
                assert worst <= tol, worst
            # a plan that names only some of the joints: refused, nothing published
            partial = JointTrajectory(joint_names=list(names[:3]))
            partial.points = [JointTrajectoryPoint(positions=[0.0] * 3,
                                                   time_from_start=Duration(sec=1))]
            count = len(got)
            io.trajectory.publish(partial)
            demo.wait_for_log('annotated_trajectory: message rejected')
            driver.spin_for(0.3)
            assert len(got) == count
    finally:
        driver.node.destroy_subscription(sub)
