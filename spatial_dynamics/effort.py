# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Effort along a trajectory for joint_trajectory_controller, and what a measured effort means.

**Feed-forward for JTC.** joint_trajectory_controller (ros2_controllers ≥ 4.22, PR #1200)
reads a point's ``effort`` when it claims an ``effort`` command interface and interpolates it
*linearly* between points (``trajectory.cpp``, ``interpolate_between_points``), whatever
spline it uses for the positions. :func:`annotate` resamples a trajectory so that this linear
interpolation stays within ``tol`` of the model torque: it bisects every interval whose
interpolated effort misses the model torque by more than ``tol`` at any of ``checks`` interior
points. The inserted points lie on the same splines (a cubic or quintic Hermite through
points of a cubic or quintic reproduces it), so the motion JTC follows is unchanged.

Where the model torque jumps (q̇ jumps at the points of a linear trajectory, q̈ at those of a
cubic one) no linear interpolation follows it: the interval before such a point is bisected
down to between ``min_step`` and twice that, and reported in :attr:`Annotated.jumps`.

**Measured effort.** Drives report different torques in ``JointState.effort``: link-side
torque including gravity (``'full'``: Franka ``tau_J``, KUKA LBR ``measured torque``, most
ros2_control hardware) or torque with the model's gravity already removed
(``'gravity_compensated'``: UR's ``joint_torques`` / ``effort``). :func:`with_gravity` turns
either into the full link-side torque the dynamics predicts: ``τ_full = τ_meas + g(q)`` for
gravity-compensated drives.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, List, Optional, Sequence, Tuple

import numpy as np

from .backends import GRAVITY, gravity_torque, rnea
from .bounds import MAX_TRAJECTORY_POINTS
from .model import Model
from .text import listed, shown
from .trajectory import coefficients, evaluate, Trajectory

#: What the effort of a point carries: τ, τ − g(q) (drives compensating gravity), g(q).
OUTPUTS = ('full', 'without_gravity', 'gravity_only')
#: What a drive's measured effort is: link-side torque with gravity, or without it (UR).
MEASURED_EFFORT = ('full', 'gravity_compensated')
#: Interior points per interval where :func:`annotate` checks the interpolation.
CHECKS = 15
#: Shortest interval :func:`annotate` makes, s (a 1 kHz controller's period).
MIN_STEP = 1e-3
#: Values (points x joints x (fields + effort)) an annotated plan may hold: 32 MB of float64,
#: ~100 MB of YAML (below what ``--trajectory`` reads back); e.g. 222,222 points of a cubic
#: plan of 6 joints.
MAX_ANNOTATED_VALUES = 4_000_000
#: Intervals :func:`annotate` checks at once (memory: CHUNK x (CHECKS + 2) x n floats).
CHUNK = 4096
_NS = 1_000_000_000


def model_effort(model: Model, q, qd, qdd, output: str = 'full',
                 gravity: Sequence[float] = GRAVITY) -> np.ndarray:
    """Return the ``output`` part of the rigid-body torque (N m, N), shape of ``q``.

    ``'full'``: ``τ = M q̈ + C q̇ + g``; ``'without_gravity'``: ``τ − g(q)``;
    ``'gravity_only'``: ``g(q)``. Arguments as :func:`spatial_dynamics.rnea`.
    """
    if output not in OUTPUTS:
        raise ValueError(f'output must be one of {list(OUTPUTS)}, got {shown(output)}')
    if output == 'gravity_only':
        return gravity_torque(model, q, gravity)
    tau = rnea(model, q, qd, qdd, gravity)
    return tau - gravity_torque(model, q, gravity) if output == 'without_gravity' else tau


def with_gravity(model: Model, q, effort, measured: str = 'full',
                 gravity: Sequence[float] = GRAVITY) -> np.ndarray:
    """Return the link-side torque with gravity from a drive's measured ``effort`` (..., n).

    ``measured='full'``: the effort as is; ``'gravity_compensated'``: ``effort + g(q)``.
    """
    if measured not in MEASURED_EFFORT:
        raise ValueError(f'measured effort must be one of {list(MEASURED_EFFORT)}, got '
                         f'{shown(measured)}')
    effort = np.asarray(effort, dtype=float)
    if measured == 'full':
        return effort
    return effort + gravity_torque(model, q, gravity)


@dataclass
class Annotated:
    """A trajectory resampled for JTC, with the effort of every point.

    Attributes:
        trajectory: the points (model joint order, times on a 1 ns grid), the fields the
            input had.
        effort: (m, n) the model torque (``output`` part) at each point, N m or N.
        tol: the tolerance asked, N m or N.
        max_error: the largest |linear interpolation − model torque| seen at the check
            points, outside the intervals ending at a jump.
        jumps: ``(start, point)`` s of the intervals that end at a point where the model
            torque jumps: inside them the interpolation misses by more than ``tol``.
    """

    trajectory: Trajectory
    effort: np.ndarray
    tol: float
    max_error: float
    jumps: List[Tuple[float, float]]


class AnnotationError(ValueError):
    """A plan :func:`annotate` does not annotate; ``reason`` is a diagnostics counter key."""

    def __init__(self, reason: str, message: str) -> None:
        super().__init__(message)
        self.reason = reason


def max_points(n: int, fields: int, max_values: Optional[int] = None) -> int:
    """Points an annotated plan of ``n`` joints and ``fields`` arrays a point may hold."""
    max_values = MAX_ANNOTATED_VALUES if max_values is None else max_values
    return min(MAX_TRAJECTORY_POINTS, max_values // max(1, n * (fields + 1)))


def annotate(model: Model, traj: Trajectory, tol: float, output: str = 'full',
             gravity: Sequence[float] = GRAVITY, min_step: float = MIN_STEP,
             checks: int = CHECKS, max_values: Optional[int] = None,
             cancelled: Optional[Callable[[], bool]] = None) -> Annotated:
    """Resample ``traj`` until JTC's linear interpolation of effort is within ``tol``.

    ``traj`` names every joint of ``model`` (any order; extra joints refused). Intervals are
    bisected while the interpolated effort misses the model torque by more than ``tol``
    (N m or N) at one of ``checks`` evenly spaced interior points, down to ``min_step`` s.

    The last point carries the torque of the state held after it (q̇ = q̈ = 0: what JTC goes
    on applying once the plan ended); where that differs from the end of the last segment
    the end is a torque jump like an interior point where q̇ or q̈ jumps.

    Bounded: the plan may grow to :func:`max_points` points (``max_values`` values in all,
    effort included; each point costs ``checks + 2`` model evaluations at most twice; None:
    :data:`MAX_ANNOTATED_VALUES`, the node's and ``replay --annotate``'s), the intervals are
    checked :data:`CHUNK` at a time, and ``cancelled()`` (when given) is asked between two
    chunks. :class:`AnnotationError` ``too_many_points`` (the tolerance asks for
    more) or ``superseded`` (cancelled).
    """
    if not tol > 0.0:
        raise ValueError(f'tolerance must be > 0 N m, got {tol}')
    if set(traj.joint_names) != set(model.joint_names):
        ours, theirs = model.joint_names, traj.joint_names
        raise ValueError(f'the trajectory joints [{listed(theirs, count=len(theirs))}] are not '
                         f'the model joints [{listed(ours, count=len(ours))}]')
    traj = traj.reordered(model.joint_names)
    max_values = MAX_ANNOTATED_VALUES if max_values is None else max_values
    fields = {'linear': 1, 'cubic': 2, 'quintic': 3}[traj.kind]
    limit = max_points(len(model.joint_names), fields, max_values)

    def too_many(count: int) -> AnnotationError:
        return AnnotationError('too_many_points', f'{count:,} points with effort for '
                               f'{len(model.joint_names)} joints, more than {limit:,} '
                               f'({max_values:,} values): tolerance {tol:g} N m is too small '
                               'for this plan')

    if len(traj.time) > limit:
        raise too_many(len(traj.time))
    c = coefficients(traj) if len(traj.time) > 1 else None
    end = traj.time[-1]

    def effort_at(t, side='right'):
        q, qd, qdd = evaluate(traj, t, c, side)
        held = (np.asarray(t) >= end)[..., None]      # the end and after: the held state
        qd, qdd = np.where(held, 0.0, qd), np.where(held, 0.0, qdd)
        return model_effort(model, q, qd, qdd, output, gravity)

    times = list(traj.time)
    todo = list(zip(times[:-1], times[1:]))
    s = np.arange(1, checks + 1) / (checks + 1)
    max_error = 0.0
    short = []                                      # intervals at min_step still missing
    while todo:
        split = []
        for first in range(0, len(todo), CHUNK):
            if cancelled is not None and cancelled():
                raise AnnotationError('superseded', 'a newer plan came before this one was '
                                      'annotated')
            chunk = todo[first:first + CHUNK]
            a = np.array([i[0] for i in chunk])
            b = np.array([i[1] for i in chunk])
            ends = effort_at(np.stack([a, b], -1))      # (k, 2, n)
            inner = a[:, None] + (b - a)[:, None] * s    # (k, checks)
            line = ends[:, :1] + s[None, :, None] * (ends[:, 1:] - ends[:, :1])
            error = np.abs(effort_at(inner) - line).max(axis=(1, 2))
            for (ai, bi), e in zip(chunk, error):
                if e <= tol:
                    max_error = max(max_error, float(e))
                elif bi - ai > 2 * min_step:
                    m = 0.5 * (ai + bi)
                    times.append(m)
                    split += [(ai, m), (m, bi)]
                else:
                    short.append((ai, bi, float(e)))
            if len(times) > limit:
                raise too_many(len(times))
        todo = split
    knots = set(traj.time[1:].tolist())
    jumps = sorted((ai, bi) for ai, bi, e in short if bi in knots)
    for ai, bi, e in short:
        if bi not in knots:                     # not at a jump: counts as a miss
            max_error = max(max_error, e)
    ns = np.unique(np.round(np.array(times) * _NS)).astype(np.int64)   # the message's grid
    t = ns // _NS + (ns % _NS) * 1e-9                # as a reader computes sec + nanosec
    q, qd, qdd = evaluate(traj, t, c)
    out = Trajectory(traj.joint_names, t, q, None if traj.velocities is None else qd,
                     None if traj.accelerations is None else qdd)
    return Annotated(out, effort_at(t), float(tol), max_error,
                     [(float(a), float(b)) for a, b in jumps])


def message_dict(traj: Trajectory, effort: np.ndarray) -> dict:
    """Return the JointTrajectory's YAML form (``ros2 topic echo``) with ``effort`` filled."""
    points = []
    for k, tk in enumerate(traj.time):
        ns = int(round(tk * _NS))
        p = {'positions': traj.positions[k].tolist()}
        p['velocities'] = [] if traj.velocities is None else traj.velocities[k].tolist()
        p['accelerations'] = ([] if traj.accelerations is None
                              else traj.accelerations[k].tolist())
        p['effort'] = effort[k].tolist()
        p['time_from_start'] = {'sec': ns // _NS, 'nanosec': ns % _NS}
        points.append(p)
    return {'header': {'stamp': {'sec': 0, 'nanosec': 0}, 'frame_id': ''},
            'joint_names': list(traj.joint_names), 'points': points}
