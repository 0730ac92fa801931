# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""What a plan's splines ask between its points is bounded like a desired state.

Points within the bounds of :mod:`spatial_dynamics.bounds` can still ask, between them,
velocities and accelerations no state may have (two points 1 µs apart and 1 rad away: 1e6
rad/s). The largest |q|, |q̇|, |q̈| of every segment's linear, cubic or quintic spline is found
exactly (against dense sampling) and held to the bounds: beyond them the plan is refused
whole, naming the segment, the joint and the value; at the bound it is accepted. The
follower refuses the segment it adds from the current state to a later first point alike.
"""

import numpy as np
import pytest

from spatial_dynamics.bounds import MAX_ACCELERATION, MAX_POSITION, MAX_VELOCITY
from spatial_dynamics.trajectory import evaluate, Follower, trajectory, TrajectoryError


def point(t_ns, q, v=None, a=None):
    p = {'positions': list(q), 'time_from_start': {'sec': t_ns // 10**9,
                                                   'nanosec': t_ns % 10**9}}
    if v is not None:
        p['velocities'] = list(v)
    if a is not None:
        p['accelerations'] = list(a)
    return p


def refused(points, *words, names=('j1',)):
    with pytest.raises(TrajectoryError) as err:
        trajectory(list(names), points)
    assert err.value.reason == 'out_of_bounds', err.value
    for word in words:
        assert word in str(err.value), (word, str(err.value))
    return err.value


def test_the_microsecond_step_of_the_issue_is_refused():
    """UR5-like: (0 ns, 0 rad), (1000 ns, 1 rad), (1 s, 1 rad), linear: 1e6 rad/s."""
    refused([point(0, [0.0]), point(1000, [1.0]), point(10**9, [1.0])],
            'point 0', 'point 1', "'j1'", 'velocity of 1e+06')
    refused([point(0, [0.0], [0.0]), point(1, [1.0], [0.0]), point(10**9, [1.0], [0.0])],
            'velocity of 1.5e+09')                      # 1 ns, cubic: 1.5 Δq/T
    refused([point(0, [0.0], [0.0], [0.0]), point(1000, [1.0], [0.0], [0.0])],
            'velocity of 1.88e+06')                     # quintic: 15/8 Δq/T


def test_extrema_between_the_points_are_found_not_only_at_them():
    """A cubic whose point velocities are in bounds but whose middle is not (q̇ peak inside)."""
    # q(0) = q(T) = 0, q̇(0) = v, q̇(T) = -v: q̇ is v at both ends, and the peak |q̈| = 2v/T...
    T = 1e-3
    v = 0.99 * MAX_VELOCITY
    # ... while the position bulges to v T / 4 and q̈ = ∓2v/T = 2e7: beyond 1e6 rad/s²
    refused([point(0, [0.0], [v]), point(int(T * 1e9), [0.0], [-v])], 'acceleration')
    # velocity peak strictly inside: q0 = 0, q1 = 1.4 v T with zero end velocities, cubic
    # q̇ peaks at 1.5 q1 / T = 2.1 v in the middle while both ends are at rest
    T = 1.0
    q1 = 1.4 * v * T
    refused([point(0, [0.0], [0.0]), point(10**9, [q1], [0.0])], 'velocity of 2.08e+04')


@pytest.mark.parametrize('degree', [2, 3, 4, 5])
def test_the_exact_maximum_matches_dense_sampling(degree):
    from spatial_dynamics.trajectory import _exact_max
    rng = np.random.default_rng(degree)
    b = rng.normal(size=(500, degree + 1)) * rng.uniform(0.1, 10, size=(500, 1))
    u = np.linspace(0.0, 1.0, 100_001)
    dense = np.abs(np.polynomial.polynomial.polyval(u, b.T)).max(axis=1)
    exact = _exact_max(b)
    assert np.all(exact >= dense - 1e-12 * dense)          # never below a sampled value
    assert np.all(exact <= dense * (1 + 1e-7))             # and the sampled grid nears it


def test_a_plan_at_the_bounds_is_accepted():
    """Exactly at the bounds (a linear 1e4 rad/s ramp; a cubic with q̈ peak = 1e6) is fine."""
    trajectory(['j1'], [point(0, [0.0]), point(10**9, [MAX_VELOCITY])])
    T = 1e-2          # cubic from rest to rest: |q̈| peaks at 6 Δq/T² at the ends
    dq = MAX_ACCELERATION * T * T / 6
    traj = trajectory(['j1'], [point(0, [0.0], [0.0]), point(int(T * 1e9), [dq], [0.0])])
    _, qd, qdd = evaluate(traj, np.linspace(0.0, T, 1001))
    assert np.abs(qdd).max() <= MAX_ACCELERATION * (1 + 1e-9)
    # real plans: UR5-sized moves over seconds, quintic and cubic, many points
    rng = np.random.default_rng(3)
    t = np.cumsum(rng.uniform(0.05, 0.5, 200)).astype(float)
    t = np.concatenate([[0.0], t])
    q = np.cumsum(rng.uniform(-0.2, 0.2, (201, 6)), axis=0)
    pts = [point(int(round(tk * 1e9)), q[k], rng.uniform(-1, 1, 6), rng.uniform(-3, 3, 6))
           for k, tk in enumerate(t)]
    trajectory([f'j{i}' for i in range(6)], pts)
    # the position is bounded too: a quintic overshooting 1e5 between points within it
    with pytest.raises(TrajectoryError, match='position'):
        trajectory(['j1'], [point(0, [0.99 * MAX_POSITION], [MAX_VELOCITY * 0.9]),
                            point(10 * 10**9, [0.99 * MAX_POSITION], [-MAX_VELOCITY * 0.9])])


def test_the_follower_refuses_a_first_point_it_could_only_reach_too_fast():
    """The segment from where the robot is to a later first point is bounded alike."""
    follower = Follower()
    with pytest.raises(TrajectoryError) as err:
        follower.accept(['j1'], [point(1000, [1.0])], 0, 10**9, ['j1'], [0.0])
    assert err.value.reason == 'out_of_bounds' and 'velocity' in str(err.value)
    assert not follower.following
    follower.accept(['j1'], [point(10**9, [1.0])], 0, 10**9, ['j1'], [0.0])
    assert follower.following


@pytest.mark.slow
def test_a_plan_of_the_documented_maximum_is_no_alias_bomb(tmp_path):
    """1,000,000 points (each an alias of one point: a small file) reach the plan's checks.

    The YAML node budget of a trajectory file is derived from the point limit, so what is
    refused is the plan's own fault (here: time not increasing), not an "alias bomb"; one
    point more than the limit is refused as too many points; a billion laughs still is a bomb.
    """
    from spatial_dynamics.bounds import MAX_TRAJECTORY_POINTS
    from spatial_dynamics.replay import splines
    head = ('joint_names: [j1]\npoints:\n- &p {positions: [0.0], velocities: [0.0], '
            'accelerations: [0.0], effort: [0.0], time_from_start: {sec: 0, nanosec: 0}}\n')
    for count, message in ((MAX_TRAJECTORY_POINTS, 'time_from_start must increase'),
                           (MAX_TRAJECTORY_POINTS + 1, 'more than 1,000,000')):
        path = tmp_path / f'plan{count}.yaml'
        path.write_text(head + '- *p\n' * (count - 1))
        with pytest.raises(ValueError, match=message):
            splines.from_yaml(str(path))
    assert splines.MAX_YAML_NODES >= splines.yaml_nodes(MAX_TRAJECTORY_POINTS, 32)
    bomb = tmp_path / 'bomb.yaml'
    lines = ['a0: &a0 [x, x, x, x, x, x, x, x, x, x]']
    lines += [f'a{i}: &a{i} [' + ', '.join([f'*a{i - 1}'] * 10) + ']' for i in range(1, 10)]
    bomb.write_text('\n'.join(lines) + '\n')
    with pytest.raises(ValueError, match='alias bomb'):
        splines.from_yaml(str(bomb))


def test_an_integer_beyond_float_is_refused_with_its_field():
    """YAML reads 10**400 written in digits as an int: refused naming the field, no traceback."""
    for field in ('positions', 'time_from_start'):
        p = point(10**9, [0.0])
        if field == 'positions':
            p['positions'] = [10**400]
        else:
            p['time_from_start'] = {'sec': 10**400, 'nanosec': 0}
        with pytest.raises(TrajectoryError, match=f'point 0 {field}') as err:
            trajectory(['j1'], [p])
        assert err.value.reason == 'out_of_bounds'
