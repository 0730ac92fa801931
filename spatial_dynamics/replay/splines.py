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


def trajectory(joint_names: Sequence[str], points: Sequence[dict], what: str = 'trajectory'
               ) -> Trajectory:
    """Build a :class:`Trajectory` from points in the message's dictionary form.

    Each point: ``{positions, velocities, accelerations, time_from_start: {sec, nanosec}}``;
    ``ValueError`` names the point that is wrong.
    """
    names = tuple(joint_names)
    n = len(names)
    if not n or len(set(names)) != n:
        raise ValueError(f'{what}: joint_names must be non-empty and distinct, got {names}')
    if not points:
        raise ValueError(f'{what}: no points')
    time, fields = [], {'positions': [], 'velocities': [], 'accelerations': []}
    for k, p in enumerate(points):
        tfs = p.get('time_from_start') or {}
        time.append(float(tfs.get('sec', 0)) + float(tfs.get('nanosec', 0)) * 1e-9)
        for f, values in fields.items():
            v = np.asarray(p.get(f, []) if p.get(f) is not None else [], dtype=float)
            if v.size not in (0, n):
                raise ValueError(f'{what}: point {k} has {v.size} {f} for {n} joints')
            if not np.all(np.isfinite(v)):
                raise ValueError(f'{what}: point {k} has a non-finite value in {f}')
            values.append(v if v.size else None)
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
    points = [{'positions': p.positions, 'velocities': p.velocities,
               'accelerations': p.accelerations,
               'time_from_start': {'sec': p.time_from_start.sec,
                                   'nanosec': p.time_from_start.nanosec}}
              for p in msg.points]
    return trajectory(msg.joint_names, points)


def from_yaml(path: str) -> Trajectory:
    """Read a JointTrajectory in its YAML form (``ros2 topic echo --once ... > FILE``)."""
    import yaml
    with open(path, encoding='utf-8') as f:
        docs = [d for d in yaml.safe_load_all(f) if d]
    if not docs or not isinstance(docs[0], dict):
        raise ValueError(f'{path}: no JointTrajectory mapping in the file')
    doc = docs[0]
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
