# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Joint-space inputs from ROS message arrays, mapped to model order by joint name.

Pure Python + numpy (no ROS imports), so it is tested without a ROS graph. The node passes the
fields of a ``sensor_msgs/JointState`` or the first point of a ``trajectory_msgs/JointTrajectory``
and gets ``(q, qd, qdd)``, each of shape ``(n,)`` in the order of ``model.joint_names``:

====================  ===========================  ===========================
message               q (rad | m)                  qd (rad/s | m/s), qdd (rad/s² | m/s²)
====================  ===========================  ===========================
JointState            ``position``                 ``velocity``, ``effort`` (when the node's
                                                   ``acceleration_source`` is ``effort``)
JointTrajectory       ``points[0].positions``      ``points[0].velocities``,
                                                   ``points[0].accelerations``
====================  ===========================  ===========================

Values are matched by joint **name**; the message may list joints in any order and may carry
joints the model doesn't have (ignored). An empty optional array means zeros. Anything else that
is wrong raises :class:`InputError`, whose ``reason`` is one of :data:`REASONS` (a diagnostics
counter key) and whose message names the offending joint or field.
"""

from __future__ import annotations

import sys
import threading
from typing import Dict, Optional, Sequence, Tuple

import numpy as np

from spatial_dynamics.bounds import JOINT_BOUNDS
from spatial_dynamics.ros.text import listed, shown

REASONS = (
    'empty',            # no joint names in the message
    'no_points',        # a trajectory without points
    'length_mismatch',  # an array whose length differs from the list of names
    'duplicate_joint',  # a model joint named twice
    'missing_joint',    # a model joint the message doesn't name
    'non_finite',       # NaN or Inf in a value the model uses
    'out_of_bounds',    # a value beyond what a real robot reaches (spatial_dynamics.bounds)
)
"""Reason codes of :class:`InputError`, in the order the checks run."""


class InputError(ValueError):
    """A message that cannot be turned into ``(q, qd, qdd)``; ``reason`` is in :data:`REASONS`."""

    def __init__(self, reason: str, message: str) -> None:
        super().__init__(message)
        self.reason = reason


def stamp_ns(header) -> int:
    """Return a ``std_msgs/Header``'s stamp in integer nanoseconds."""
    return header.stamp.sec * 1_000_000_000 + header.stamp.nanosec


NAME_CACHE_BYTES = 1024 * 1024
"""Budget of the name-order cache of :func:`name_index`: the names it keeps, in bytes."""

NAME_CACHE_ENTRY_BYTES = NAME_CACHE_BYTES // 8
"""A name list larger than this (~1,500 names of 20 characters) is mapped on every message."""

NAME_CACHE_ENTRIES = 256
"""At most this many name orders are cached (a publisher shuffling its order churns no more)."""

_STR_OVERHEAD = sys.getsizeof('') + 8   # a str object and its slot in the tuple

# (model joint names, message names) -> (index, estimated bytes); insertion order = age.
_cache: Dict[Tuple[Tuple[str, ...], Tuple[str, ...]], Tuple[np.ndarray, int]] = {}
_cache_bytes = 0
_cache_lock = threading.Lock()


def name_index(joint_names: Tuple[str, ...], names: Tuple[str, ...]) -> np.ndarray:
    """Return indices ``idx`` such that ``values[idx]`` is in the order of ``joint_names``.

    ``joint_names`` is the model's order, ``names`` the message's. Cached per pair of tuples, so
    a publisher that keeps its name order costs one dict look-up per message, not a rebuild; the
    returned array is read-only and shared. The cache is bounded by the size of the names it
    holds (:data:`NAME_CACHE_BYTES`) as well as by their count (:data:`NAME_CACHE_ENTRIES`),
    oldest entries dropped first: a message may carry any number of extra names.

    Raises :class:`InputError` (``duplicate_joint``, ``missing_joint``).
    """
    key = (joint_names, names)
    hit = _cache.get(key)
    if hit is not None:
        return hit[0]
    idx = _build_index(joint_names, names)
    size = sum(map(len, names)) + _STR_OVERHEAD * len(names) + idx.nbytes
    if size <= NAME_CACHE_ENTRY_BYTES:
        _remember(key, idx, size)
    return idx


def _remember(key, idx: np.ndarray, size: int) -> None:
    global _cache_bytes
    with _cache_lock:
        if key in _cache:
            return
        while _cache and (_cache_bytes + size > NAME_CACHE_BYTES
                          or len(_cache) >= NAME_CACHE_ENTRIES):
            _cache_bytes -= _cache.pop(next(iter(_cache)))[1]
        _cache[key] = (idx, size)
        _cache_bytes += size


def name_cache_info() -> Tuple[int, int]:
    """Return ``(entries, estimated bytes)`` of the cache of :func:`name_index`."""
    with _cache_lock:
        return len(_cache), _cache_bytes


def name_cache_clear() -> None:
    """Empty the cache of :func:`name_index`."""
    global _cache_bytes
    with _cache_lock:
        _cache.clear()
        _cache_bytes = 0


def _build_index(joint_names: Tuple[str, ...], names: Tuple[str, ...]) -> np.ndarray:
    position = {}
    repeated = set()
    for i, name in enumerate(names):
        if name in position:
            repeated.add(name)
        position[name] = i
    duplicated = [name for name in joint_names if name in repeated]
    if duplicated:
        raise InputError('duplicate_joint',
                         f'joint(s) named more than once: {listed(duplicated)}')
    missing = [name for name in joint_names if name not in position]
    if missing:
        raise InputError('missing_joint', f'missing joint(s) {listed(missing)}')
    idx = np.fromiter((position[name] for name in joint_names), dtype=np.intp,
                      count=len(joint_names))
    idx.setflags(write=False)
    return idx


def _arrays(
    joint_names: Tuple[str, ...],
    names: Sequence[str],
    fields: Sequence[Tuple[str, Optional[Sequence[float]], str]],
) -> Tuple[np.ndarray, ...]:
    """Map each ``(field, values, kind)`` to model order; the first is required, ``None`` = 0.

    ``kind`` (``position``, ``velocity``, ``acceleration``, ``effort``) names the bound of
    :data:`spatial_dynamics.bounds.JOINT_BOUNDS` every value is held to. Checks run in the
    order of :data:`REASONS`; one check failing stops the conversion, so the caller never sees
    a partial result.
    """
    count = len(names)
    if count == 0:
        raise InputError('empty', "field 'name' is empty: no joints in the message")
    for k, (field, values, _) in enumerate(fields):
        if values is None:
            continue
        length = len(values)
        if length != count and (k == 0 or length != 0):
            allowed = f'{count}' if k == 0 else f'0 or {count}'
            raise InputError(
                'length_mismatch',
                f"field '{field}' has {length} values for {count} names (expected {allowed})")
    idx = name_index(joint_names, tuple(names))
    n = len(joint_names)
    result = []
    for field, values, kind in fields:
        if values is None or len(values) == 0:
            result.append(np.zeros(n))
            continue
        mapped = np.asarray(values, dtype=np.float64)[idx]
        bound, unit = JOINT_BOUNDS[kind]
        if not np.abs(mapped).max(initial=0.0) <= bound:    # NaN fails too: one pass if good
            if not np.isfinite(mapped).all():
                bad = [joint_names[i] for i in np.flatnonzero(~np.isfinite(mapped))]
                raise InputError('non_finite',
                                 f"field '{field}' is not finite for joint(s) {listed(bad)}")
            huge = np.flatnonzero(np.abs(mapped) > bound)
            raise InputError('out_of_bounds', f"field '{field}' of joint "
                             f'{shown(joint_names[huge[0]])} is {mapped[huge[0]]:g}, beyond '
                             f'±{bound:g} {unit}')
        result.append(mapped)
    return tuple(result)


def joint_state_arrays(
    joint_names: Tuple[str, ...],
    name: Sequence[str],
    position: Sequence[float],
    velocity: Sequence[float],
    effort: Optional[Sequence[float]],
) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(q, qd, qdd)`` in ``joint_names`` order from the arrays of a ``sensor_msgs/JointState``.

    ``effort`` carries the desired accelerations qdd (rad/s² or m/s²); pass ``None`` when they
    come from elsewhere (``acceleration_source: none``), and qdd is zeros. ``position`` is
    required (same length as ``name``); ``velocity`` and ``effort`` may be empty (zeros).
    """
    return _arrays(joint_names, name,
                   (('position', position, 'position'), ('velocity', velocity, 'velocity'),
                    ('effort', effort, 'acceleration')))


def trajectory_arrays(
    joint_names: Tuple[str, ...],
    names: Sequence[str],
    points: Sequence,
) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(q, qd, qdd)`` in ``joint_names`` order from a ``trajectory_msgs/JointTrajectory``.

    ``names`` is its ``joint_names``; ``points[0]`` gives ``positions`` (required),
    ``velocities`` and ``accelerations`` (empty = zeros). Later points are ignored.
    """
    if len(points) == 0:
        raise InputError('no_points', "field 'points' is empty: no trajectory point")
    point = points[0]
    return _arrays(joint_names, names,
                   (('points[0].positions', point.positions, 'position'),
                    ('points[0].velocities', point.velocities, 'velocity'),
                    ('points[0].accelerations', point.accelerations, 'acceleration')))
