# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The node's output messages built from what :mod:`.answering` and :mod:`.diagnostics` give.

Message types only (no rclpy): each function returns a new message.
"""

from __future__ import annotations

from typing import Sequence, Tuple

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import WrenchStamped
import numpy as np
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

_LEVELS = {'OK': DiagnosticStatus.OK, 'WARN': DiagnosticStatus.WARN,
           'ERROR': DiagnosticStatus.ERROR}
_NS = 1_000_000_000


def wrench_stamped(header, link: str, wrench: np.ndarray) -> WrenchStamped:
    """Return ``external_wrench_estimate``: ``[n; f]`` in ``link``'s frame, at its origin."""
    msg = WrenchStamped()
    msg.header.stamp = header.stamp
    msg.header.frame_id = link
    n, f = msg.wrench.torque, msg.wrench.force
    n.x, n.y, n.z, f.x, f.y, f.z = np.asarray(wrench, dtype=float).tolist()
    return msg


def joint_trajectory(header, annotated) -> JointTrajectory:
    """Return ``annotated_trajectory``: the resampled plan with ``effort`` at every point.

    ``annotated`` is an :class:`~spatial_dynamics.effort.Annotated`; ``header`` is the
    received one (its stamp is the plan's start).
    """
    traj, msg = annotated.trajectory, JointTrajectory()
    msg.header = header
    msg.joint_names = list(traj.joint_names)
    for k, t in enumerate(traj.time):
        point = JointTrajectoryPoint(positions=traj.positions[k].tolist(),
                                     effort=annotated.effort[k].tolist())
        if traj.velocities is not None:
            point.velocities = traj.velocities[k].tolist()
        if traj.accelerations is not None:
            point.accelerations = traj.accelerations[k].tolist()
        ns = int(round(t * _NS))
        point.time_from_start.sec, point.time_from_start.nanosec = divmod(ns, _NS)
        msg.points.append(point)
    return msg


def diagnostic_array(name: str, hardware_id: str,
                     statuses: Sequence[Tuple[str, Tuple[str, str, list]]],
                     stamp) -> DiagnosticArray:
    """Return ``/diagnostics``: a status ``'<name>: <suffix>'`` per ``(suffix, status)``."""
    msg = DiagnosticArray(status=[
        DiagnosticStatus(level=_LEVELS[level], name=f'{name}: {suffix}', message=message,
                         hardware_id=hardware_id,
                         values=[KeyValue(key=k, value=v) for k, v in values])
        for suffix, (level, message, values) in statuses])
    msg.header.stamp = stamp
    return msg
