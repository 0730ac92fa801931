# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Read a JointTrajectory for ``replay``: from a bag's message or its YAML form.

The interpolation (joint_trajectory_controller's linear / cubic / quintic splines) and the
validation live in the core, :mod:`spatial_dynamics.trajectory`, shared with the node; they
are re-exported here for the replay's callers.
"""

from __future__ import annotations

from ..bounds import MAX_TRAJECTORY_POINTS
from ..files import load_yaml, read_regular
from ..trajectory import (coefficients, evaluate, hermite, sample, Samples,  # noqa: F401
                          Trajectory, trajectory)

#: Largest trajectory YAML file read, bytes.
MAX_YAML_BYTES = 256 * 1024 * 1024
#: Joints of the widest plan whose every point the YAML node budget makes room for.
PLAN_JOINTS = 32


def yaml_nodes(points: int, joints: int) -> int:
    """YAML nodes of a JointTrajectory of ``points`` points of ``joints`` joints, at most.

    The document: header (stamp, frame_id), joint_names and the points list, 12 + ``joints``
    nodes; each point: its mapping, five keys, four lists (positions, velocities,
    accelerations, effort) of ``joints`` numbers and time_from_start {sec, nanosec}.
    """
    return 12 + joints + points * (1 + 5 + 4 * (1 + joints) + 5)


#: Nodes a trajectory file may stand for with its aliases expanded: a plan of the most points
#: the reader takes (:data:`~spatial_dynamics.bounds.MAX_TRAJECTORY_POINTS`) with every field
#: filled for :data:`PLAN_JOINTS` joints; beyond it, an alias bomb.
MAX_YAML_NODES = yaml_nodes(MAX_TRAJECTORY_POINTS, PLAN_JOINTS)


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
    budget :data:`MAX_YAML_NODES`, what the point limit allows); ``ValueError`` names the
    file and the reason.
    """
    doc = load_yaml(read_regular(path, f'trajectory file {path!r}', MAX_YAML_BYTES),
                    f'trajectory file {path!r}', MAX_YAML_NODES)
    if not isinstance(doc, dict):
        raise ValueError(f'{path!r}: no JointTrajectory mapping in the file')
    if 'joint_names' not in doc or 'points' not in doc:
        raise ValueError(f'{path!r}: a JointTrajectory needs joint_names and points')
    return trajectory(doc['joint_names'], doc['points'], what=repr(path))
