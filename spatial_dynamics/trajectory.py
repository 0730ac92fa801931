# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Joint trajectories as ros2_control's joint_trajectory_controller (JTC) interpolates them.

Between two points ``T`` seconds apart, each joint follows the polynomial fixed by what the
points give (JTC's ``interpolation_method: splines``, ``trajectory.cpp``
``interpolate_between_points``):

* positions only: linear, ``q(s) = q0 + (q1 - q0) s/T`` (q̇ constant, q̈ = 0 inside);
* positions and velocities: cubic Hermite, position and velocity matched at both ends;
* positions, velocities and accelerations: quintic, all three matched at both ends.

So q is continuous everywhere, q̇ too for cubic and quintic, q̈ for quintic. Before the first
point the first position is held, after the last point the last one (q̇ = q̈ = 0).

:class:`Follower` holds the trajectories a node receives and answers "where should the robot
be at this stamp": JTC's rules for ``header.stamp`` (zero = start on receipt), replacement
(a new trajectory takes over from its start time), an empty trajectory (stop: hold the
measured position) and the end (hold the last point). Pure numpy: the ROS node passes the
message's fields and its clock in nanoseconds.
"""

from __future__ import annotations

from dataclasses import dataclass
from math import comb, factorial
from typing import List, Optional, Sequence, Tuple

import numpy as np

from .bounds import (check_bounded, JOINT_BOUNDS, MAX_SAMPLES, MAX_TRAJECTORY_POINTS,
                     MAX_TRAJECTORY_TIME)
from .text import shown

#: Why a trajectory is refused (:attr:`TrajectoryError.reason`, a diagnostics counter key).
REASONS = ('malformed', 'empty_names', 'duplicate_joint', 'unknown_joint', 'missing_joint',
           'no_points', 'too_many_points', 'length_mismatch', 'non_finite', 'out_of_bounds',
           'time_not_increasing', 'time_out_of_bounds', 'start_out_of_bounds')
#: Trajectories a :class:`Follower` keeps waiting for their start time (beyond: refused).
MAX_QUEUED = 16
_NS = 1_000_000_000


class TrajectoryError(ValueError):
    """A trajectory refused whole; ``reason`` is one of :data:`REASONS`, the message names it."""

    def __init__(self, reason: str, message: str) -> None:
        super().__init__(message[:300])
        self.reason = reason


@dataclass
class Trajectory:
    """``joint_names``, ``time`` (m,) s, ``positions`` (m, n) and optional derivatives."""

    joint_names: Tuple[str, ...]
    time: np.ndarray
    positions: np.ndarray
    velocities: Optional[np.ndarray] = None
    accelerations: Optional[np.ndarray] = None

    @property
    def kind(self) -> str:
        """``'linear'``, ``'cubic'`` or ``'quintic'``: what the points give."""
        if self.velocities is None:
            return 'linear'
        return 'cubic' if self.accelerations is None else 'quintic'

    def reordered(self, joint_names: Sequence[str]) -> 'Trajectory':
        """Return the same trajectory with its columns in the order of ``joint_names``."""
        cols = [self.joint_names.index(j) for j in joint_names]
        pick = (lambda a: None if a is None else a[:, cols])
        return Trajectory(tuple(joint_names), self.time, self.positions[:, cols],
                          pick(self.velocities), pick(self.accelerations))


# --------------------------------------------------------------------------------------------
# Reading the points (dictionaries of the YAML form, or message objects), refused whole

def _get(p, name: str):
    return p.get(name) if isinstance(p, dict) else getattr(p, name, None)


def _number(value, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating,
                                                         np.integer)):
        raise TrajectoryError('malformed', f'{what}: need a number, got {shown(value)}')
    try:
        return float(value)
    except OverflowError:     # an integer beyond float64 (YAML reads 1e400 digits as one)
        raise TrajectoryError('out_of_bounds', f'{what}: {str(value)[:20]}... is beyond any '
                              'float') from None


def _time_from_start(p, k: int, what: str) -> float:
    tfs = _get(p, 'time_from_start')
    if tfs is None:
        tfs = {}
    if not isinstance(tfs, dict) and not hasattr(tfs, 'sec'):
        raise TrajectoryError('malformed', f'{what}: point {k} time_from_start must be a '
                              f'mapping of sec and nanosec, got {shown(tfs)}')
    sec, nanosec = _get(tfs, 'sec'), _get(tfs, 'nanosec')
    t = (_number(0 if sec is None else sec, f'{what}: point {k} time_from_start.sec')
         + _number(0 if nanosec is None else nanosec,
                   f'{what}: point {k} time_from_start.nanosec') * 1e-9)
    if not 0.0 <= t <= MAX_TRAJECTORY_TIME:
        raise TrajectoryError('time_out_of_bounds',
                              f'{what}: point {k} time_from_start is {t:g} s, outside 0 .. '
                              f'{MAX_TRAJECTORY_TIME:g} s')
    return t


def _values(p, f: str, n: int, k: int, what: str) -> Optional[np.ndarray]:
    raw = _get(p, f)
    if raw is None:
        return None
    if isinstance(raw, (str, bytes, dict)) or not hasattr(raw, '__len__'):
        raise TrajectoryError('malformed', f'{what}: point {k} {f} must be a list of numbers, '
                              f'got {shown(raw)}')
    if isinstance(raw, np.ndarray) and raw.dtype.kind == 'f' or type(raw).__name__ == 'array':
        v = np.asarray(raw, dtype=float).ravel()      # a message's float64 array: no check
    else:
        v = np.array([_number(x, f'{what}: point {k} {f}') for x in raw], dtype=float)
    if v.size not in (0, n):
        raise TrajectoryError('length_mismatch', f'{what}: point {k} has {v.size} {f} for '
                              f'{n} joints')
    bound, unit = JOINT_BOUNDS[f]
    reason = check_bounded(f'{what}: point {k} {f}', v, bound, unit)
    if reason:
        raise TrajectoryError('non_finite' if 'not finite' in reason else 'out_of_bounds',
                              reason)
    return v if v.size else None


def trajectory(joint_names: Sequence[str], points: Sequence, what: str = 'trajectory'
               ) -> Trajectory:
    """Build a :class:`Trajectory` from a JointTrajectory's ``joint_names`` and ``points``.

    Each point is a mapping (the message's YAML form) or a ``JointTrajectoryPoint``:
    ``positions``, ``velocities``, ``accelerations``, ``time_from_start: {sec, nanosec}``.
    Refused whole with a :class:`TrajectoryError` (a ``ValueError``) naming the point and
    field: anything not of the message's shape, names empty or repeated, a non-finite value or
    one beyond the bounds of :mod:`spatial_dynamics.bounds`, time_from_start not increasing
    or beyond a day, more than :data:`~spatial_dynamics.bounds.MAX_TRAJECTORY_POINTS` points,
    velocities or accelerations given for some points but not all. Accelerations without
    velocities are dropped (JTC needs velocities to use them).
    """
    if (isinstance(joint_names, (str, bytes, dict)) or not hasattr(joint_names, '__len__')
            or not all(isinstance(x, str) for x in joint_names)):
        raise TrajectoryError('malformed', f'{what}: joint_names must be a list of names, got '
                              f'{shown(joint_names)}')
    names = tuple(joint_names)
    n = len(names)
    if not n:
        raise TrajectoryError('empty_names', f'{what}: joint_names is empty')
    if len(set(names)) != n:
        twice = sorted({j for j in names if names.count(j) > 1})
        raise TrajectoryError('duplicate_joint', f'{what}: joint_names lists {twice} more '
                              'than once')
    if isinstance(points, (str, bytes, dict)) or not hasattr(points, '__len__'):
        raise TrajectoryError('malformed', f'{what}: points must be a list of points, got '
                              f'{shown(points)}')
    if not len(points):
        raise TrajectoryError('no_points', f'{what}: no points')
    if len(points) > MAX_TRAJECTORY_POINTS:
        raise TrajectoryError('too_many_points', f'{what}: {len(points)} points, more than '
                              f'{MAX_TRAJECTORY_POINTS:,}')
    time, fields = [], {'positions': [], 'velocities': [], 'accelerations': []}
    for k, p in enumerate(points):
        if not isinstance(p, dict) and not hasattr(p, 'positions'):
            raise TrajectoryError('malformed', f'{what}: point {k} must be a mapping '
                                  '(positions, velocities, accelerations, time_from_start), '
                                  f'got {shown(p)}')
        time.append(_time_from_start(p, k, what))
        for f, values in fields.items():
            values.append(_values(p, f, n, k, what))
    missing = [k for k, v in enumerate(fields['positions']) if v is None]
    if missing:
        raise TrajectoryError('length_mismatch', f'{what}: every point needs positions; point '
                              f'{missing[0]} has none')
    t = np.array(time)
    if np.any(np.diff(t) <= 0.0):
        k = int(np.flatnonzero(np.diff(t) <= 0.0)[0]) + 1
        raise TrajectoryError('time_not_increasing',
                              f'{what}: time_from_start must increase; point {k} at '
                              f'{t[k]:g} s follows {t[k - 1]:g} s')

    def stacked(f: str) -> Optional[np.ndarray]:
        values = fields[f]
        if all(v is None for v in values):
            return None
        if any(v is None for v in values):
            k = next(k for k, v in enumerate(values) if v is None)
            raise TrajectoryError('length_mismatch', f'{what}: {f} given for some points but '
                                  f'not all (point {k} has none)')
        return np.array(values)

    vel, acc = stacked('velocities'), stacked('accelerations')
    if acc is not None and vel is None:
        acc = None      # the controller needs velocities to use accelerations
    traj = Trajectory(names, t, np.array(fields['positions']), vel, acc)
    check_splines(traj, what)
    return traj


# --------------------------------------------------------------------------------------------
# The splines

def hermite(T, q0, v0, a0, q1, v1, a1) -> np.ndarray:
    """Coefficients ``c[0..5]`` of the quintic with q, q̇, q̈ given at s = 0 and s = T."""
    T2, T3 = T * T, T * T * T
    dq = q1 - q0
    c3 = (20 * dq - (8 * v1 + 12 * v0) * T - (3 * a0 - a1) * T2) / (2 * T3)
    c4 = (-30 * dq + (14 * v1 + 16 * v0) * T + (3 * a0 - 2 * a1) * T2) / (2 * T3 * T)
    c5 = (12 * dq - 6 * (v1 + v0) * T + (a1 - a0) * T2) / (2 * T3 * T2)
    return np.array([q0, v0, a0 / 2, c3, c4, c5])


def coefficients(traj: Trajectory) -> np.ndarray:
    """Return every segment's polynomial coefficients, (m-1, 6, n): ``q = Σ c_p s^p``."""
    T = np.diff(traj.time)[:, None]
    q0, q1 = traj.positions[:-1], traj.positions[1:]
    c = np.zeros((len(T), 6, traj.positions.shape[1]))
    if traj.kind == 'linear':
        c[:, 0], c[:, 1] = q0, (q1 - q0) / T
    elif traj.kind == 'cubic':
        v0, v1 = traj.velocities[:-1], traj.velocities[1:]
        c[:, 0], c[:, 1] = q0, v0
        c[:, 2] = (3 * (q1 - q0) - (2 * v0 + v1) * T) / T ** 2
        c[:, 3] = (-2 * (q1 - q0) + (v0 + v1) * T) / T ** 3
    else:
        c[:] = np.moveaxis(hermite(T, q0, traj.velocities[:-1], traj.accelerations[:-1],
                                   q1, traj.velocities[1:], traj.accelerations[1:]), 0, 1)
    return c


def evaluate(traj: Trajectory, t, c: Optional[np.ndarray] = None, side: str = 'right'
             ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return ``q``, ``q̇``, ``q̈`` (..., n) at times ``t`` (...) s from the trajectory's start.

    Inside ``[time[0], time[-1]]`` the spline of the segment that starts at or before ``t``
    (``side='left'``: the segment that ends at a point, for the limit from the left);
    before, the first position is held, after, the last one (q̇ = q̈ = 0). ``c``: the
    :func:`coefficients`, when already computed.
    """
    t = np.asarray(t, dtype=float)
    n = traj.positions.shape[1]
    if len(traj.time) == 1:
        q = np.broadcast_to(traj.positions[0], t.shape + (n,)).copy()
        return q, np.zeros_like(q), np.zeros_like(q)
    c = coefficients(traj) if c is None else c
    seg = np.clip(np.searchsorted(traj.time, t, side=side) - 1, 0, len(c) - 1)
    s = np.clip(t - traj.time[seg], 0.0, traj.time[seg + 1] - traj.time[seg])[..., None]
    c0, c1, c2, c3, c4, c5 = (c[seg, p] for p in range(6))
    q = c0 + s * (c1 + s * (c2 + s * (c3 + s * (c4 + s * c5))))
    qd = c1 + s * (2 * c2 + s * (3 * c3 + s * (4 * c4 + s * 5 * c5)))
    qdd = 2 * c2 + s * (6 * c3 + s * (12 * c4 + s * 20 * c5))
    outside = ((t < traj.time[0]) | (t > traj.time[-1]))[..., None]
    if outside.any():
        held = np.where((t < traj.time[0])[..., None], traj.positions[0], traj.positions[-1])
        q = np.where(outside, held, q)
        qd, qdd = np.where(outside, 0.0, qd), np.where(outside, 0.0, qdd)
    return q, qd, qdd


#: Segments whose splines :func:`check_splines` bounds at once (memory: 6 x n floats each).
_CHUNK = 1 << 15
#: What each derivative of the spline is, with its bound (:data:`JOINT_BOUNDS`).
_DERIVATIVES = ((0, 'position', 'positions'), (1, 'velocity', 'velocities'),
                (2, 'acceleration', 'accelerations'))


def _hull(b: np.ndarray) -> np.ndarray:
    """Return max |Bernstein coefficient| on [0, 1] of power coefficients ``b`` (D+1, k).

    A polynomial on [0, 1] lies within the hull of its Bernstein coefficients (and equals the
    first and the last at u = 0 and 1): this bounds max |p| from above.
    """
    D = len(b) - 1
    hull = np.zeros(b.shape[1:])
    for k in range(D + 1):
        bk = sum(comb(k, j) / comb(D, j) * b[j] for j in range(k + 1))
        hull = np.maximum(hull, np.abs(bk))
    return hull


def _polyval(b: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Evaluate power coefficients ``b`` (k, D+1) at ``u`` (k, r): (k, r) (Horner)."""
    p = np.zeros(u.shape, dtype=float) + b[:, -1:]
    for j in range(b.shape[1] - 2, -1, -1):
        p = p * u + b[:, j:j + 1]
    return p


def _exact_max(b: np.ndarray) -> np.ndarray:
    """Return max |p(u)| over u in [0, 1] of each row of power coefficients ``b`` (k, D+1).

    At u = 0, u = 1 or where p' = 0: the roots of p' (eigenvalues of its companion matrix,
    all rows of one degree at once) are candidates with their real parts clipped to [0, 1];
    a candidate that is no critical point is still a point of [0, 1], so the largest |p| over
    the candidates is the maximum.
    """
    D = b.shape[1] - 1
    ends = np.abs(np.stack([b[:, 0], b.sum(axis=1)], axis=1)).max(axis=1)
    if D < 2:
        return ends
    d = b[:, 1:] * np.arange(1, D + 1)                 # p' (k, D), degree D - 1
    scale = np.abs(d).max(axis=1)
    best = ends.copy()
    finite = np.isfinite(d).all(axis=1)
    best[~finite] = np.inf
    # the degree of p' in each row: its highest coefficient that is not rounding noise
    degree = np.zeros(len(b), dtype=int)
    for j in range(1, D):
        degree[np.abs(d[:, j]) > 1e-13 * scale] = j
    for g in range(1, D):
        rows = np.flatnonzero((degree == g) & finite)
        if not len(rows):
            continue
        lead = d[rows, g]
        companion = np.zeros((len(rows), g, g))
        companion[:, 0, :] = -d[rows, g - 1::-1][:, :g] / lead[:, None]
        companion[:, np.arange(1, g), np.arange(g - 1)] = 1.0
        u = np.clip(np.linalg.eigvals(companion).real, 0.0, 1.0)
        best[rows] = np.maximum(best[rows], np.abs(_polyval(b[rows], u)).max(axis=1))
    return best


def check_splines(traj: Trajectory, what: str = 'trajectory') -> None:
    """Refuse a trajectory whose splines ask, between its points, what no state may be.

    For every segment and joint, the largest |q|, |q̇| and |q̈| of the spline over the segment
    (:func:`coefficients`), found exactly (the polynomial's value at the ends and where its
    derivative is zero: linear, cubic and quintic alike), is held to the bounds of a desired
    state (:data:`~spatial_dynamics.bounds.JOINT_BOUNDS`): two points 1 µs apart 1 rad away
    from each other ask 1e6 rad/s. The hull of the Bernstein coefficients bounds each
    polynomial first; the roots are computed only where that hull reaches beyond the bound.
    :class:`TrajectoryError` ``out_of_bounds`` names the segment, the joint and the value.
    """
    if len(traj.time) < 2:
        return
    for first in range(0, len(traj.time) - 1, _CHUNK):
        last = min(first + _CHUNK, len(traj.time) - 1) + 1
        part = Trajectory(traj.joint_names, traj.time[first:last], traj.positions[first:last],
                          None if traj.velocities is None else traj.velocities[first:last],
                          None if traj.accelerations is None
                          else traj.accelerations[first:last])
        _check_chunk(part, first, what)


def _check_chunk(traj: Trajectory, first: int, what: str) -> None:
    n = traj.positions.shape[1]
    T = np.diff(traj.time)[None, :, None]
    c = np.moveaxis(coefficients(traj), 1, 0)                # (6, k, n) in s
    with np.errstate(over='ignore', invalid='ignore'):
        for order, name, field in _DERIVATIVES:
            # the order-th derivative in u = s / T: coefficient p is p!/(p-order)! c_p T^(p-order)
            b = np.stack([comb(p, order) * factorial(order) * c[p] * T[0] ** (p - order)
                          for p in range(order, 6)]).reshape(6 - order, -1)   # (D+1, k n)
            bound, unit = JOINT_BOUNDS[field]
            suspect = np.flatnonzero(~(_hull(b) <= bound))
            if not len(suspect):
                continue
            peak = _exact_max(b[:, suspect].T)
            bad = np.flatnonzero(~(peak <= bound))
            if not len(bad):
                continue
            k, j = divmod(int(suspect[bad[0]]), n)
            raise TrajectoryError(
                'non_finite' if not np.isfinite(peak[bad[0]]) else 'out_of_bounds',
                f'{what}: between point {first + k} ({traj.time[k]:.9g} s) and point '
                f'{first + k + 1} ({traj.time[k + 1]:.9g} s) the {traj.kind} spline of '
                f'{shown(traj.joint_names[j])} reaches a {name} of {peak[bad[0]]:.3g} {unit}, '
                f'beyond ±{bound:g} (points too close in time for their motion?)')


Samples = Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def sample(traj: Trajectory, rate: float) -> Samples:
    """Return ``t`` (N,), ``q``, ``q̇``, ``q̈`` (N, n) at ``rate`` Hz from the first point on.

    The last point is always included. Inside a linear segment q̈ = 0.
    """
    t0, t1 = traj.time[0], traj.time[-1]
    count = (t1 - t0) * rate + 1
    if not count <= MAX_SAMPLES:
        raise ValueError(f'{t1 - t0:g} s at {rate:g} Hz is {count:.4g} samples, more than '
                         f'{MAX_SAMPLES:,}: lower the rate')
    t = t0 + np.arange(int(np.floor((t1 - t0) * rate)) + 1) / rate
    if t[-1] < t1 - 1e-12:
        t = np.append(t, t1)
    t = np.minimum(t, t1)
    return (t,) + evaluate(traj, t)


# --------------------------------------------------------------------------------------------
# Following received trajectories

@dataclass
class _Plan:
    start_ns: int
    traj: Trajectory
    c: Optional[np.ndarray]
    lead: Optional[Tuple[Trajectory, np.ndarray]] = None   # to a first point after 0


class Follower:
    """The trajectories a node follows, sampled at the stamps of measured states (JTC rules).

    * :meth:`accept` validates a whole ``JointTrajectory`` (refused whole with a
      :class:`TrajectoryError`; what was followed stays), maps it by joint name onto the
      model's order and schedules it at its start: ``header.stamp``, or the receipt time when
      the stamp is zero. From that start on it replaces whatever was followed (trajectories
      waiting for a later start are dropped); before it, the old one goes on. It is
      :func:`prepare` (the work a plan's size decides: done anywhere, on any thread) followed
      by :meth:`schedule` (cheap: a fixed number of operations whatever the plan's size).
    * A first point with ``time_from_start > 0`` is reached from where the robot is meant to
      be at the start (the old trajectory sampled there, else the measured position), as JTC
      interpolates from its current state; that segment is bounded as the plan's own are.
    * An empty trajectory stops following now: the measured position is held.
    * :meth:`sample` returns ``(q_d, q̇_d, q̈_d)`` at a stamp; after the last point the last
      position is held (q̇ = q̈ = 0); before anything started, ``None``.
    """

    def __init__(self) -> None:
        """Follow nothing."""
        self._plans: List[_Plan] = []

    @property
    def following(self) -> bool:
        """Whether a trajectory (or a hold) is scheduled."""
        return bool(self._plans)

    def ends_ns(self) -> Optional[int]:
        """When the last scheduled trajectory ends (ns, the start's clock); None: nothing."""
        if not self._plans:
            return None
        p = self._plans[-1]
        return p.start_ns + int(round(p.traj.time[-1] * _NS))

    def clear(self) -> None:
        """Follow nothing (the model changed, the node deactivated)."""
        self._plans = []

    def accept(self, joint_names: Sequence[str], points: Sequence, start_ns: int, now_ns: int,
               model_joint_names: Sequence[str], q_measured=None) -> Optional[Trajectory]:
        """Validate and schedule a trajectory; return it in model order (``None``: stopped).

        ``start_ns``: ``header.stamp`` in ns (0 = now); ``now_ns``: the receipt time on the
        same clock; ``q_measured``: the last measured position in model order (or ``None``),
        held after an empty trajectory and the start of one whose first point is later.
        """
        return self.schedule(prepare(joint_names, points, model_joint_names), start_ns,
                             now_ns, model_joint_names, q_measured)

    def schedule(self, prepared: Optional['Prepared'], start_ns: int, now_ns: int,
                 model_joint_names: Sequence[str], q_measured=None) -> Optional[Trajectory]:
        """Schedule what :func:`prepare` gave (``None``: stop); arguments as :meth:`accept`."""
        model_joint_names = tuple(model_joint_names)
        start = int(now_ns) if int(start_ns) == 0 else int(start_ns)
        check_start(start, now_ns)
        held = None if q_measured is None else np.array(q_measured, dtype=float)
        if held is not None and held.shape != (len(model_joint_names),):
            raise ValueError(f'q_measured must have {len(model_joint_names)} values, got '
                             f'{held.shape}')
        if prepared is None:
            if held is None:
                state = self.sample(now_ns)
                held = None if state is None else state[0]
            self._plans = [] if held is None else [
                _Plan(int(now_ns), _hold(model_joint_names, held), None)]
            return None
        traj = prepared.traj
        kept = [p for p in self._plans if p.start_ns < start]
        if len(kept) >= MAX_QUEUED and all(p.start_ns > now_ns for p in kept[-MAX_QUEUED:]):
            raise TrajectoryError('start_out_of_bounds', f'{MAX_QUEUED} trajectories already '
                                  'wait for a later start')
        lead = None
        if traj.time[0] > 0.0:
            before = _sample_plans(kept, start)
            if before is None:
                q0 = held if held is not None else traj.positions[0]
                before = (q0, np.zeros_like(q0), np.zeros_like(q0))
            first = Trajectory(traj.joint_names, traj.time[:1], traj.positions[:1],
                               None if traj.velocities is None else traj.velocities[:1],
                               None if traj.accelerations is None
                               else traj.accelerations[:1])
            path = _prepend(first, *before)
            check_splines(path, 'trajectory: from the state at its start to its first point')
            lead = (path, coefficients(path))
        self._plans = _prune(kept, now_ns) + [_Plan(start, traj, prepared.c, lead)]
        return traj

    def sample(self, t_ns: int) -> Optional[Tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """Return ``(q_d, q̇_d, q̈_d)`` (n,) each at ``t_ns``, or ``None`` before any start."""
        return _sample_plans(self._plans, int(t_ns))


@dataclass
class Prepared:
    """A trajectory checked whole and mapped onto the model, with its splines' coefficients."""

    traj: Trajectory
    c: Optional[np.ndarray]


def prepare(joint_names: Sequence[str], points: Sequence, model_joint_names: Sequence[str]
            ) -> Optional[Prepared]:
    """Validate a ``JointTrajectory``'s fields for the model (``None``: empty, a stop).

    All the work a plan's size decides (:func:`trajectory`: every point and every spline;
    the coefficients): a :class:`TrajectoryError` names what is refused.
    """
    if not len(points):
        return None
    model_joint_names = tuple(model_joint_names)
    traj = trajectory(joint_names, points)
    unknown = [j for j in traj.joint_names if j not in model_joint_names]
    if unknown:
        raise TrajectoryError('unknown_joint', f'trajectory: joint(s) {unknown} are not '
                              'joints of the model')
    missing = [j for j in model_joint_names if j not in traj.joint_names]
    if missing:
        raise TrajectoryError('missing_joint', f'trajectory: joint(s) {missing} of the '
                              'model are missing')
    traj = traj.reordered(model_joint_names)
    return Prepared(traj, coefficients(traj) if len(traj.time) > 1 else None)


def check_start(start_ns: int, now_ns: int) -> None:
    """Refuse a start (``header.stamp``, ns) beyond a day from ``now_ns`` (another clock?)."""
    if abs(int(start_ns) - int(now_ns)) > MAX_TRAJECTORY_TIME * _NS:
        raise TrajectoryError('start_out_of_bounds', f'header.stamp is '
                              f'{(int(start_ns) - int(now_ns)) / _NS:g} s from now, beyond '
                              f'±{MAX_TRAJECTORY_TIME:g} s (another clock?)')


def _hold(joint_names: Tuple[str, ...], q: np.ndarray) -> Trajectory:
    return Trajectory(joint_names, np.zeros(1), q[None, :].copy())


def _prepend(traj: Trajectory, q, qd, qdd) -> Trajectory:
    """Add a point at time 0 (the state the first point is reached from)."""
    def add(a, x):
        return None if a is None else np.vstack([x[None, :], a])
    return Trajectory(traj.joint_names, np.concatenate([[0.0], traj.time]),
                      add(traj.positions, q), add(traj.velocities, qd),
                      add(traj.accelerations, qdd))


def _sample_plans(plans: List[_Plan], t_ns: int):
    for p in reversed(plans):
        if p.start_ns <= t_ns:
            t = (t_ns - p.start_ns) / _NS
            if p.lead is not None and t < p.traj.time[0]:
                return evaluate(p.lead[0], t, p.lead[1])
            return evaluate(p.traj, t, p.c)
    return None


def _prune(plans: List[_Plan], now_ns: int) -> List[_Plan]:
    """Drop the plans a later one has replaced by now (the one active now is kept)."""
    active = [k for k, p in enumerate(plans) if p.start_ns <= now_ns]
    return plans[active[-1]:] if active else plans
