# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The node's plans (``desired_trajectory``) off the answering path: their checks, their effort.

A plan's size is decided by whoever publishes it, so nothing a plan costs in proportion to
its size runs where ``joint_states`` are answered (STYLE habit 13):

* the node takes each ``desired_trajectory`` message serialized, in its own callback group,
  refuses one larger than ``trajectory_max_bytes`` before converting it, and converts and
  checks the rest there (:func:`prepare_plan`: every point, every spline's bounds, the mapping onto
  the model, the coefficients); the answering group only schedules what came out
  (:meth:`~spatial_dynamics.ros.answering.Answering.take_plan`, a fixed cost);
* the plan's effort for joint_trajectory_controller is computed by :class:`Annotator`, one
  worker thread (:class:`~spatial_dynamics.ros.worker.Newest`), bounded
  (:func:`~spatial_dynamics.effort.annotate`), the newest plan superseding one not yet done;
  a refusal is counted in ``/diagnostics``.

Pure Python and message types: no rclpy (the node gives the worker its ``publish``).
"""

from __future__ import annotations

from collections import deque
from typing import Callable, NamedTuple, Optional

import numpy as np
from spatial_dynamics import clamp_to_effort_limits
from spatial_dynamics.effort import annotate, AnnotationError
from spatial_dynamics.ros.control import FEEDBACK_MODES
from spatial_dynamics.ros.messages import joint_trajectory
from spatial_dynamics.ros.records import Config
from spatial_dynamics.ros.text import shown
from spatial_dynamics.ros.worker import Newest
from spatial_dynamics.trajectory import prepare, Prepared, TrajectoryError


class PlanItem(NamedTuple):
    """A ``desired_trajectory`` taken off the answering path, ready to be scheduled.

    ``msg``: the message (None when refused before converting it); ``prepared``: the plan
    checked and mapped onto ``joints`` (None: an empty plan, a stop; or feedforward, which
    answers ``msg``'s first point); ``error``: ``(reason, text)`` when refused.
    """

    config: Config
    msg: object
    joints: Optional[tuple]
    prepared: Optional[Prepared]
    error: Optional[tuple]


def prepare_plan(config: Config, msg, size: int = 0) -> PlanItem:
    """Check a ``desired_trajectory`` whole for ``config``'s model (any thread, no state).

    ``size``: its serialized bytes, refused (``too_large``) above ``trajectory_max_bytes``
    (``msg`` is then not needed: None). In the feedback modes, and in feedforward when the
    plan is annotated, the plan is checked whole (:func:`~spatial_dynamics.trajectory.
    prepare`); in feedforward its first point is the desired state.
    """
    robot = config.robot
    limit = config.params.trajectory_max_bytes
    if size > limit:
        return PlanItem(config, None, None, None, (
            'too_large', f'{size:,} bytes serialized, more than trajectory_max_bytes '
            f'{limit:,}: not converted'))
    if robot is None:
        return PlanItem(config, msg, None, None, ('no_model', 'no robot model loaded yet'))
    whole = (config.params.control_mode in FEEDBACK_MODES
             or config.params.trajectory_effort_tolerance > 0.0)
    if not whole:
        return PlanItem(config, msg, robot.joints, None, None)
    try:
        prepared = prepare(msg.joint_names, msg.points, robot.joints)
    except TrajectoryError as err:
        return PlanItem(config, msg, robot.joints, None, (err.reason, str(err)))
    return PlanItem(config, msg, robot.joints, prepared, None)


class Job(NamedTuple):
    """A plan to annotate: the received header, the plan in model order, the config."""

    header: object
    prepared: Prepared
    config: Config


class Annotator:
    """One worker thread that annotates plans with effort for JTC, off the answering path.

    ``submit`` replaces a plan not yet started and cancels the one being annotated (only the
    newest plan matters: JTC follows it); each done plan is turned into its message and
    handed to ``publish`` from the worker thread. The efforts are held to the URDF effort
    limits as the node's answers are: clamped (and said) with ``clamp_to_effort_limits``,
    else published and the joints beyond their limits named in a warning. A plan refused
    (too many points for the tolerance, an effort not finite) is logged and its reason queued
    in :attr:`rejected` for the diagnostics (drained by the answering side).
    """

    def __init__(self, publish: Callable[[object], None], log) -> None:
        self._publish = publish
        self.log = log
        self.rejected: deque = deque()      # reasons, appended here, popped by diagnostics
        self.saturated: deque = deque()     # joint names clamped, for the diagnostics
        self._worker: Newest[Job] = Newest(self._annotate, 'annotated_trajectory')

    def submit(self, job: Job) -> None:
        """Annotate ``job`` next; a plan pending or being annotated is dropped."""
        self._worker.submit(job)

    def stop(self) -> None:
        """Let the worker end (it is a daemon: never waited for)."""
        self._worker.stop()

    def _annotate(self, job: Job, cancelled: Callable[[], bool]) -> None:
        """Worker thread: publish ``job`` annotated, unless a newer plan came meanwhile."""
        try:
            msg = self.build(job, cancelled)
        except AnnotationError as err:
            if err.reason != 'superseded':
                self._refuse(err.reason, str(err))
            return
        except Exception as err:  # never lose the worker: report it as a rejection
            self._refuse('compute_error', repr(err))
            return
        if msg is not None and not cancelled():
            self._publish(msg)

    def build(self, job: Job, cancelled: Callable[[], bool] = lambda: False):
        """Return ``annotated_trajectory`` of ``job`` (None: refused, reason queued)."""
        robot, params = job.config.robot, job.config.params
        done = annotate(robot.model, job.prepared.traj, params.trajectory_effort_tolerance,
                        params.output, params.gravity, cancelled=cancelled,
                        max_values=params.trajectory_annotation_max_values)
        if not np.isfinite(done.effort).all():
            self._refuse('non_finite_output', 'an effort is not finite')
            return None
        limit = robot.model.effort_limit
        over = np.flatnonzero(np.any(np.abs(done.effort) > np.where(limit > 0.0, limit,
                                                                    np.inf), axis=0))
        if len(over):
            peaks = np.abs(done.effort).max(axis=0)
            names = robot.model.joint_names
            text = ', '.join(f'{shown(names[j])} {peaks[j]:.4g} > {limit[j]:g}' for j in over)
            if robot.clamp:
                done.effort[:], _ = clamp_to_effort_limits(robot.model, done.effort)
                self.saturated.extend(names[j] for j in over)
                self.log.warn(f'annotated_trajectory: effort clamped to the URDF effort limit '
                              f'(clamp_to_effort_limits): {text}', throttle_duration_sec=1.0)
            else:
                self.log.warn(f'annotated_trajectory: effort beyond the URDF effort limit: '
                              f'{text} (clamp_to_effort_limits is false)',
                              throttle_duration_sec=1.0)
        if done.jumps:
            self.log.warn(f'annotated_trajectory: the model torque jumps at '
                          f'{len(done.jumps)} point(s) (first at {done.jumps[0][1]:g} s): '
                          'JTC\'s interpolation misses it there by more than the tolerance',
                          throttle_duration_sec=1.0)
        return joint_trajectory(job.header, done)

    def _refuse(self, reason: str, text: str) -> None:
        self.rejected.append(reason)
        self.log.warn(f'annotated_trajectory: message rejected, not annotated ({reason}): '
                      f'{text}', throttle_duration_sec=1.0)
