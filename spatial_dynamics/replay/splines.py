# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Interpolate a JointTrajectory as ros2_control's joint_trajectory_controller does.

Between two points ``T`` seconds apart, each joint follows the polynomial fixed by what the
points give (joint_trajectory_controller's ``interpolation_method: splines``):

* positions only: linear, ``q(s) = q0 + (q1 - q0) s/T`` (q̇ constant, q̈ = 0 inside);
* positions and velocities: cubic Hermite, position and velocity matched at both ends;
* positions, velocities and accelerations: quintic, all three matched at both ends.

So q is continuous everywhere, q̇ too for cubic and quintic, q̈ for quintic. The trajectory
starts at its first point (the robot is assumed to be there); before it nothing is sampled.
Also reads the message's YAML form (``ros2 topic echo`` output).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Sequence, Tuple

import numpy as np

from ..bounds import (check_bounded, JOINT_BOUNDS, MAX_SAMPLES, MAX_TRAJECTORY_POINTS,
                      MAX_TRAJECTORY_TIME)
from ..files import load_yaml, read_regular

#: Largest trajectory YAML file read, bytes.
MAX_YAML_BYTES = 256 * 1024 * 1024


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


def _number(value, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f'{what}: need a number, got {value!r}'[:300])
    return float(value)


def _time_from_start(p: dict, k: int, what: str) -> float:
    tfs = p.get('time_from_start')
    if tfs is None:
        tfs = {}
    if not isinstance(tfs, dict):
        raise ValueError(f'{what}: point {k} time_from_start must be a mapping of sec and '
                         f'nanosec, got {tfs!r}'[:300])
    t = (_number(tfs.get('sec', 0), f'{what}: point {k} time_from_start.sec')
         + _number(tfs.get('nanosec', 0), f'{what}: point {k} time_from_start.nanosec') * 1e-9)
    if not 0.0 <= t <= MAX_TRAJECTORY_TIME:
        raise ValueError(f'{what}: point {k} time_from_start is {t:g} s, outside 0 .. '
                         f'{MAX_TRAJECTORY_TIME:g} s')
    return t


def _values(p: dict, f: str, n: int, k: int, what: str) -> Optional[np.ndarray]:
    raw = p.get(f)
    if raw is None:
        return None
    if isinstance(raw, (str, bytes, dict)) or not hasattr(raw, '__len__'):
        raise ValueError(f'{what}: point {k} {f} must be a list of numbers, got {raw!r}'[:300])
    v = np.array([_number(x, f'{what}: point {k} {f}') for x in raw], dtype=float)
    if v.size not in (0, n):
        raise ValueError(f'{what}: point {k} has {v.size} {f} for {n} joints')
    bound, unit = JOINT_BOUNDS[f]
    reason = check_bounded(f'{what}: point {k} {f}', v, bound, unit)
    if reason:
        raise ValueError(reason)
    return v if v.size else None


def trajectory(joint_names: Sequence[str], points: Sequence[dict], what: str = 'trajectory'
               ) -> Trajectory:
    """Build a :class:`Trajectory` from points in the message's dictionary form.

    Each point: ``{positions, velocities, accelerations, time_from_start: {sec, nanosec}}``.
    Refused whole, with a ``ValueError`` naming the point and field: anything not of the
    message's shape, a non-finite value or one beyond the bounds of
    :mod:`spatial_dynamics.bounds`, a time_from_start beyond a day, more than
    :data:`~spatial_dynamics.bounds.MAX_TRAJECTORY_POINTS` points.
    """
    if (isinstance(joint_names, (str, bytes, dict)) or not hasattr(joint_names, '__len__')
            or not all(isinstance(x, str) for x in joint_names)):
        raise ValueError(f'{what}: joint_names must be a list of names, got '
                         f'{joint_names!r}'[:300])
    names = tuple(joint_names)
    n = len(names)
    if not n or len(set(names)) != n:
        raise ValueError(f'{what}: joint_names must be non-empty and distinct, got {names}'
                         [:300])
    if isinstance(points, (str, bytes, dict)) or not hasattr(points, '__len__'):
        raise ValueError(f'{what}: points must be a list of points, got {points!r}'[:300])
    if not points:
        raise ValueError(f'{what}: no points')
    if len(points) > MAX_TRAJECTORY_POINTS:
        raise ValueError(f'{what}: {len(points)} points, more than '
                         f'{MAX_TRAJECTORY_POINTS:,}')
    time, fields = [], {'positions': [], 'velocities': [], 'accelerations': []}
    for k, p in enumerate(points):
        if not isinstance(p, dict):
            raise ValueError(f'{what}: point {k} must be a mapping (positions, velocities, '
                             f'accelerations, time_from_start), got {p!r}'[:300])
        time.append(_time_from_start(p, k, what))
        for f, values in fields.items():
            values.append(_values(p, f, n, k, what))
    if any(v is None for v in fields['positions']):
        raise ValueError(f'{what}: every point needs positions')
    t = np.array(time)
    if np.any(np.diff(t) <= 0.0):
        k = int(np.flatnonzero(np.diff(t) <= 0.0)[0]) + 1
        raise ValueError(f'{what}: time_from_start must increase; point {k} at {t[k]:g} s '
                         f'follows {t[k - 1]:g} s')

    def stacked(f: str) -> Optional[np.ndarray]:
        values = fields[f]
        if all(v is None for v in values):
            return None
        if any(v is None for v in values):
            raise ValueError(f'{what}: {f} given for some points but not all')
        return np.array(values)

    vel, acc = stacked('velocities'), stacked('accelerations')
    if acc is not None and vel is None:
        acc = None      # the controller needs velocities to use accelerations
    return Trajectory(names, t, np.array(fields['positions']), vel, acc)


def from_message(msg) -> Trajectory:
    """Build a :class:`Trajectory` from a ``rosbags`` JointTrajectory message."""
    points = [{'positions': list(p.positions), 'velocities': list(p.velocities),
               'accelerations': list(p.accelerations),
               'time_from_start': {'sec': int(p.time_from_start.sec),
                                   'nanosec': int(p.time_from_start.nanosec)}}
              for p in msg.points]
    return trajectory(list(msg.joint_names), points)


def from_yaml(path: str) -> Trajectory:
    """Read a JointTrajectory in its YAML form (``ros2 topic echo --once ... > FILE``).

    The file goes through :func:`spatial_dynamics.files.read_regular` (a regular file of at
    most :data:`MAX_YAML_BYTES`) and :func:`spatial_dynamics.files.load_yaml` (safe, alias
    budget); ``ValueError`` names the file and the reason.
    """
    doc = load_yaml(read_regular(path, f'trajectory file {path!r}', MAX_YAML_BYTES),
                    f'trajectory file {path!r}')
    if not isinstance(doc, dict):
        raise ValueError(f'{path}: no JointTrajectory mapping in the file')
    if 'joint_names' not in doc or 'points' not in doc:
        raise ValueError(f'{path}: a JointTrajectory needs joint_names and points')
    return trajectory(doc['joint_names'], doc['points'], what=path)


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
    if len(traj.time) == 1:
        q = np.repeat(traj.positions, len(t), axis=0)
        return t, q, np.zeros_like(q), np.zeros_like(q)
    c = coefficients(traj)
    seg = np.clip(np.searchsorted(traj.time, t, side='right') - 1, 0, len(c) - 1)
    s = (t - traj.time[seg])[:, None]
    cs = c[seg]                                            # (N, 6, n)
    c0, c1, c2, c3, c4, c5 = (cs[:, p] for p in range(6))
    q = c0 + s * (c1 + s * (c2 + s * (c3 + s * (c4 + s * c5))))
    qd = c1 + s * (2 * c2 + s * (3 * c3 + s * (4 * c4 + s * 5 * c5)))
    qdd = 2 * c2 + s * (6 * c3 + s * (12 * c4 + s * 20 * c5))
    return t, q, qd, qdd
