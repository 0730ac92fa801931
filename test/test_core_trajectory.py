# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The core trajectory module: JTC's splines, and the Follower's rules (pure, no ROS).

Splines: the points are met with what they give, q (and q̇, q̈) continuous at the knots,
analytic profiles. Follower: every refusal reason (the old trajectory kept), names in any
order, stamp zero = now, a start in the future, replacement mid-way, hold after the end,
an empty trajectory stops, a later first point is reached from the current state.
"""

from types import SimpleNamespace

import numpy as np
import pytest

from spatial_dynamics import bounds
from spatial_dynamics.trajectory import (coefficients, evaluate, Follower, REASONS,
                                         trajectory, TrajectoryError)

NS = 1_000_000_000
MODEL = ('a', 'b', 'c')


def point(t, q, qd=None, qdd=None):
    p = {'positions': list(q), 'time_from_start': {'sec': int(t), 'nanosec':
                                                   int(round((t % 1) * 1e9))}}
    if qd is not None:
        p['velocities'] = list(qd)
    if qdd is not None:
        p['accelerations'] = list(qdd)
    return p


def test_linear_cubic_quintic_meet_the_points_and_join_continuously():
    rng = np.random.default_rng(3)
    t = np.array([0.0, 0.4, 1.1, 1.5])
    Q, V, A = (rng.uniform(-1, 1, (4, 2)) for _ in range(3))
    for kind, pts in (('linear', [point(ti, q) for ti, q in zip(t, Q)]),
                      ('cubic', [point(ti, q, v) for ti, q, v in zip(t, Q, V)]),
                      ('quintic', [point(ti, q, v, a) for ti, q, v, a in zip(t, Q, V, A)])):
        traj = trajectory(['x', 'y'], pts)
        assert traj.kind == kind
        c = coefficients(traj)
        right = evaluate(traj, t, c)                    # segments starting at each point
        left = evaluate(traj, t, c, side='left')        # segments ending at each point
        for q in (right[0], left[0]):
            assert np.allclose(q, Q, atol=1e-12)
        if kind != 'linear':
            assert np.allclose(right[1][:-1], V[:-1]) and np.allclose(left[1][1:], V[1:])
        if kind == 'quintic':
            assert np.allclose(right[2][:-1], A[:-1]) and np.allclose(left[2][1:], A[1:])
        if kind == 'linear':   # constant velocity (q1 - q0)/T inside a segment
            mid = evaluate(traj, (t[:-1] + t[1:]) / 2, c)
            assert np.allclose(mid[1], np.diff(Q, axis=0) / np.diff(t)[:, None])
            assert np.allclose(mid[2], 0.0)


def test_cubic_from_rest_to_rest_is_the_smoothstep():
    traj = trajectory(['x'], [point(0, [0.0], [0.0]), point(2, [1.0], [0.0])])
    s = np.linspace(0.0, 1.0, 11)
    q, qd, qdd = evaluate(traj, 2 * s)
    assert np.allclose(q[:, 0], 3 * s ** 2 - 2 * s ** 3)
    assert np.allclose(qd[:, 0], (6 * s - 6 * s ** 2) / 2)
    assert np.allclose(qdd[:, 0], (6 - 12 * s) / 4)


def test_held_before_the_first_and_after_the_last_point():
    traj = trajectory(['x'], [point(1, [0.5], [1.0]), point(2, [1.5], [2.0])])
    q, qd, qdd = evaluate(traj, [0.0, 3.0])
    assert q[:, 0].tolist() == [0.5, 1.5] and not qd.any() and not qdd.any()


# --------------------------------------------------------------------------------------------
# Refusals

def refused(follower, names, points, reason, match, **kw):
    with pytest.raises(TrajectoryError, match=match) as err:
        follower.accept(names, points, kw.get('start', 0), kw.get('now', NS), MODEL)
    assert err.value.reason == reason and reason in REASONS
    assert '\n' not in str(err.value)


def test_every_refusal_names_the_field_and_keeps_the_old_trajectory():
    f = Follower()
    good = [point(0, [0, 0, 0]), point(1, [1, 1, 1])]
    f.accept(MODEL, good, 0, NS, MODEL)
    before = f.sample(int(1.5 * NS))
    p = point(1, [1, 1, 1])
    cases = [
        (MODEL, [point(0, [0, 0, 0]), point(0, [1, 1, 1])], 'time_not_increasing',
         r'time_from_start must increase; point 1 at 0 s follows 0 s'),
        (MODEL, [point(0, [0, np.nan, 0])], 'non_finite',
         r"point 0 positions is not finite for index 1"),
        (MODEL, [point(0, [0, 0, np.inf], [0, 0, 0])], 'non_finite', r'positions'),
        (MODEL, [point(0, [0, 0, 0], [0, 0, np.nan])], 'non_finite', r'point 0 velocities'),
        (MODEL, [point(0, [0, 2e5, 0])], 'out_of_bounds',
         r'point 0 positions of index 1 is 200000, beyond ±100000'),
        (('a', 'b', 'x'), good, 'unknown_joint', r"\['x'\] are not joints of the model"),
        (('a', 'b'), [point(0, [0, 0])], 'missing_joint', r"\['c'\] of the model are missing"),
        (('a', 'a', 'b'), good, 'duplicate_joint', r"\['a'\] more than once"),
        ((), good, 'empty_names', 'joint_names is empty'),
        (MODEL, [point(0, [0, 0])], 'length_mismatch', r'point 0 has 2 positions for 3'),
        (MODEL, [point(0, [0, 0, 0], [0, 0])], 'length_mismatch', r'2 velocities for 3'),
        (MODEL, [point(0, [0, 0, 0], [0, 0, 0]), p], 'length_mismatch',
         r'velocities given for some points but not all \(point 1'),
        (MODEL, [{'velocities': [0, 0, 0]}], 'length_mismatch', 'every point needs positions'),
        (MODEL, [point(bounds.MAX_TRAJECTORY_TIME + 1, [0, 0, 0])], 'time_out_of_bounds',
         r'time_from_start is 86401 s, outside 0 .. 86400 s'),
        (MODEL, [{'positions': ['x', 0, 0]}], 'malformed', r'point 0 positions: need a number'),
        (MODEL, 'points', 'malformed', 'points must be a list'),
    ]
    for names, points, reason, match in cases:
        refused(f, names, points, reason, match)
    refused(f, MODEL, good, 'start_out_of_bounds', r'header.stamp is 86401 s from now',
            start=NS + (86400 + 1) * NS)
    many = [point(0, [0, 0, 0])] * (bounds.MAX_TRAJECTORY_POINTS + 1)
    refused(f, MODEL, many, 'too_many_points', r'1000001 points, more than 1,000,000')
    after = f.sample(int(1.5 * NS))
    assert all(np.array_equal(x, y) for x, y in zip(before, after))


def test_message_objects_are_read_like_the_yaml_form():
    msg_points = [SimpleNamespace(positions=np.array([0.0, 1.0, 2.0]),
                                  velocities=np.array([]), accelerations=np.array([]),
                                  time_from_start=SimpleNamespace(sec=0, nanosec=500_000_000))]
    f = Follower()
    traj = f.accept(('c', 'a', 'b'), msg_points, 0, NS, MODEL)
    assert traj.kind == 'linear'
    q, _, _ = f.sample(2 * NS)
    assert q.tolist() == [1.0, 2.0, 0.0]


# --------------------------------------------------------------------------------------------
# The rules

def test_names_in_any_order_are_mapped_onto_the_model_order():
    f = Follower()
    f.accept(('c', 'a', 'b'), [point(0, [3, 1, 2]), point(2, [6, 2, 4])], 0, 10 * NS, MODEL)
    q, qd, qdd = f.sample(11 * NS)
    assert np.allclose(q, [1.5, 3.0, 4.5]) and np.allclose(qd, [0.5, 1.0, 1.5])
    assert not qdd.any()


def test_stamp_zero_starts_at_receipt_and_a_stamp_in_the_future_waits():
    f = Follower()
    assert f.sample(NS) is None                           # nothing followed yet
    f.accept(MODEL, [point(0, [0, 0, 0]), point(1, [1, 1, 1])], 0, 5 * NS, MODEL)
    assert f.sample(4 * NS) is None                       # before its start (receipt)
    assert np.allclose(f.sample(int(5.5 * NS))[0], 0.5)
    # a second one stamped 2 s ahead: the first goes on (and holds its end) until then
    f.accept(MODEL, [point(0, [5, 5, 5]), point(1, [7, 7, 7])], 8 * NS, 6 * NS, MODEL)
    assert np.allclose(f.sample(int(5.5 * NS))[0], 0.5)
    q, qd, qdd = f.sample(int(7.9 * NS))
    assert np.allclose(q, 1.0) and not qd.any() and not qdd.any()   # held after its end
    assert np.allclose(f.sample(int(8.5 * NS))[0], 6.0)
    assert np.allclose(f.sample(20 * NS)[0], 7.0)


def test_a_new_trajectory_replaces_the_old_one_mid_way_from_its_start():
    f = Follower()
    f.accept(MODEL, [point(0, [0, 0, 0], [0, 0, 0]), point(4, [4, 4, 4], [0, 0, 0])],
             0, 0, MODEL)
    q_mid, qd_mid, _ = f.sample(2 * NS)
    # received at 2 s, first point 1 s later: reached from the old trajectory's state at 2 s
    f.accept(MODEL, [point(1, [-1, -1, -1], [0, 0, 0]), point(2, [-2, -2, -2], [0, 0, 0])],
             0, 2 * NS, MODEL)
    q, qd, _ = f.sample(2 * NS)
    assert np.allclose(q, q_mid) and np.allclose(qd, qd_mid)    # continuous at the switch
    assert np.allclose(f.sample(3 * NS)[0], -1.0)
    assert np.allclose(f.sample(4 * NS)[0], -2.0)               # not the old 4.0
    assert np.allclose(f.sample(100 * NS)[0], -2.0)
    # a stamp in the past: the new one is followed as if started then (JTC)
    f.accept(MODEL, [point(0, [0, 0, 0]), point(10, [10, 10, 10])], 90 * NS, 100 * NS, MODEL)
    assert np.allclose(f.sample(100 * NS)[0], 10.0)
    assert np.allclose(f.sample(95 * NS)[0], 5.0)


def test_a_later_first_point_is_reached_from_the_measured_position():
    f = Follower()
    f.accept(MODEL, [point(2, [2, 2, 2])], 0, 0, MODEL, q_measured=[0.0, 1.0, 2.0])
    assert np.allclose(f.sample(NS)[0], [1.0, 1.5, 2.0])
    assert np.allclose(f.sample(3 * NS)[0], 2.0)


def test_an_empty_trajectory_stops_and_holds_the_measured_position():
    f = Follower()
    f.accept(MODEL, [point(0, [0, 0, 0]), point(10, [10, 10, 10])], 0, 0, MODEL)
    assert f.accept(MODEL, [], 0, 3 * NS, MODEL, q_measured=[2.9, 3.1, 3.0]) is None
    q, qd, qdd = f.sample(5 * NS)
    assert q.tolist() == [2.9, 3.1, 3.0] and not qd.any() and not qdd.any()
    # without a measured position the desired one at the stop is held
    f.accept(MODEL, [point(0, [0, 0, 0]), point(10, [10, 10, 10])], 0, 0, MODEL)
    f.accept(MODEL, [], 0, 4 * NS, MODEL)
    assert np.allclose(f.sample(9 * NS)[0], 4.0)


def test_queued_trajectories_are_bounded():
    f = Follower()
    for k in range(16):
        f.accept(MODEL, [point(0, [k, k, k])], (10 + k) * NS, NS, MODEL)
    refused(f, MODEL, [point(0, [0, 0, 0])], 'start_out_of_bounds', 'wait for a later start',
            start=100 * NS)
    assert np.allclose(f.sample(12 * NS)[0], 2.0)
