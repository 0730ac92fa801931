# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Robot descriptions for the node: read, expand xacro, parse, and the parser's worker thread.

By precedence (:func:`description_source`): the ``robot_description`` parameter (URDF XML
text, never a path), the ``robot_description_file`` parameter (a regular UTF-8 file of at
most :data:`MAX_DESCRIPTION_BYTES`, read by :func:`spatial_dynamics.urdf.read_description`),
the ``robot_description`` topic (parsed by :class:`DescriptionParser`'s worker thread, off the
answering path). Pure: no rclpy.
"""

from __future__ import annotations

from dataclasses import dataclass
import threading
from typing import Callable, List, Optional, Sequence, Tuple

import numpy as np
import spatial_dynamics as sd
from spatial_dynamics.ros.parameters import ConfigError
from spatial_dynamics.ros.records import Robot
from spatial_dynamics.ros.text import listed, shown
from spatial_dynamics.ros.worker import Newest
from spatial_dynamics.urdf import MAX_DESCRIPTION_BYTES
from spatial_dynamics.urdf import read_description as read_urdf_description


# --------------------------------------------------------------------------------------------
# Robot descriptions

def read_description(path: str) -> str:
    """URDF text of the file ``path`` (:func:`spatial_dynamics.urdf.read_description`).

    A regular file (symbolic links followed) of at most :data:`MAX_DESCRIPTION_BYTES`, UTF-8;
    a ``.xacro`` file is expanded when ``xacro`` is importable. A named pipe, a device or a
    directory is refused without blocking; :class:`ConfigError` names the file.
    """
    try:
        return read_urdf_description(path, MAX_DESCRIPTION_BYTES,
                                     f'robot_description_file {path!r}')
    except ValueError as err:
        raise ConfigError(f'{err} (a robot description)') from None


def parse_description(urdf: str, source: str, joints: Optional[Sequence[str]] = None,
                      locked: Optional[dict] = None, strict: bool = False,
                      base: str = 'fixed') -> 'sd.Model':
    """Build the (reduced) model from URDF text; ``source`` names where it came from.

    ``urdf`` is XML text, never a path (a path goes in ``robot_description_file``): it is
    handed to the parser as bytes, which :meth:`~spatial_dynamics.Model.from_urdf` never
    opens. With ``joints``, model reduction (:meth:`~spatial_dynamics.Model.from_urdf`): the
    other joints are locked at ``locked[name]`` (default 0), lumped, and branches that cannot
    move a kept joint's torque are pruned; ``model.joint_names == joints``. ``strict``: a
    physically inconsistent but computable description (a :class:`~spatial_dynamics.URDFWarning`)
    is refused; otherwise it loads and its warnings are in ``model.warnings``. ``base``:
    ``'floating'`` hangs the root link on a free-flyer (the node's ``base: floating``).

    One plain-float inverse-dynamics call at q = qd = qdd = 0 follows, before the model is
    used: it proves the model computes (finite torques), and derives the backend's layout at
    load time, not at the first live message.
    """
    text = urdf.lstrip('\ufeff \t\r\n')
    if not text:
        raise ConfigError(f'{source}: empty robot description')
    if not text.startswith('<'):
        raise ConfigError(f'{source}: not URDF XML (it starts with {shown(text, limit=200)}): '
                          'a robot description is XML text, never a path; give a file in '
                          'the robot_description_file parameter')
    where = source
    if joints:
        where = f'{source} reduced to joints [{listed(list(joints), count=30)}]'
        if locked:
            where += f' (locked [{listed(list(locked))}])'
    try:
        model = sd.Model.from_urdf(text.encode('utf-8'), joints=list(joints) if joints else None,
                                   locked=locked or None, strict=strict,
                                   base='floating' if base == 'floating' else 'fixed')
        q = np.zeros(model.nq)
        if model.floating:
            q[6] = 1.0     # the free-flyer's identity quaternion
        zeros = np.zeros(model.nv)
        tau = sd.rnea(model, q, zeros, zeros, backend='numpy')
    except Exception as err:  # a bad description must never take the node down
        raise ConfigError(f'{where}: {err}')
    if not np.isfinite(tau).all():
        raise ConfigError(f'{source}: the model gives non-finite torques at rest')
    return model


def description_source(params: dict) -> str:
    """Where the description comes from: ``'parameter'``, ``'file'`` or ``'topic'`` (precedence).

    The ``robot_description`` parameter when it is set (non-empty), else
    ``robot_description_file`` when it is set, else the topic.
    """
    if params.robot_description:
        return 'parameter'
    if params.robot_description_file:
        return 'file'
    return 'topic'


def description_change(previous: dict, params: dict, changes: dict
                       ) -> Tuple[Optional[str], Optional[str], str]:
    """Return ``(urdf, source, kept)``: the description ``changes`` make current.

    ``previous`` are the parameters before the change, ``params`` after it. By precedence
    (:func:`description_source`); ``urdf`` is None when the model's description does not
    change. ``kept`` is the path of a ``robot_description_file`` that was set (and read, so
    it is known to be readable) while ``robot_description`` is set: kept for later, not used.
    """
    text, path = params.robot_description, params.robot_description_file
    if text:
        kept = ''
        if path and 'robot_description_file' in changes:
            read_description(path)
            kept = path
        if 'robot_description' in changes:
            return text, 'parameter robot_description', kept
        return None, None, kept
    if path and ('robot_description_file' in changes
                 or previous.robot_description):  # set, or the string cleared
        return read_description(path), f'file {path}', ''
    return None, None, ''


# --------------------------------------------------------------------------------------------
# Descriptions from the topic: parsed by a worker thread

@dataclass(frozen=True)
class ParseRequest:
    """A description from the topic to build a :class:`~.records.Robot` from, with its context.

    ``generation`` identifies the request: the node applies the result only if no other
    description came (or a parameter took precedence) since; ``params`` and ``current`` are
    the node's parameters and robot when the message arrived; ``number`` counts the
    descriptions received on the topic (a request parsed again keeps its number).
    """

    generation: int
    urdf: str
    params: dict
    current: Optional[Robot]
    number: int = 0     # the how-manieth description received on the topic (for the log)

    def __str__(self) -> str:
        """Name the description for a log line: its number on the topic and its size."""
        return f'description #{self.number} ({len(self.urdf):,} characters)'


class DescriptionParser:
    """One worker thread that builds robots from topic descriptions, off the answering path.

    ``submit`` replaces any request not yet started (only the newest description matters);
    each finished request is queued with its result (a :class:`~.records.Robot` or a
    :class:`ConfigError`) and ``notify()`` is called, from the worker thread, so the node can
    pick it up in its executor (a guard condition). The thread
    (:class:`~spatial_dynamics.ros.worker.Newest`) starts with the first request.
    """

    def __init__(self, build: Callable[[ParseRequest], Robot], notify: Callable[[], None]
                 ) -> None:
        self._build = build
        self._notify = notify
        self._lock = threading.Lock()
        self._done: List[Tuple[ParseRequest, object]] = []
        self._worker: Newest[ParseRequest] = Newest(self._parse, 'robot_description parser')

    def submit(self, request: ParseRequest) -> Optional[ParseRequest]:
        """Parse ``request`` next; return the request it drops (one not started yet), if any."""
        return self._worker.submit(request)

    def finished(self) -> List[Tuple[ParseRequest, object]]:
        """Return (and forget) the finished requests with their results, oldest first."""
        with self._lock:
            done, self._done = self._done, []
        return done

    def stop(self) -> None:
        """Let the worker end after the request it is on (it is a daemon: never waited for)."""
        self._worker.stop()

    def _parse(self, request: ParseRequest, cancelled: Callable[[], bool]) -> None:
        """Worker thread: queue ``request`` with its result and notify the node.

        A result is queued even when a newer request came meanwhile: the node drops it by its
        ``generation``; after :meth:`stop` nothing is.
        """
        try:
            result = self._build(request)
        except ConfigError as err:
            result = err
        except Exception as err:  # never lose the worker: report it as a rejection
            result = ConfigError(f'topic robot_description: {err!r}')
        with self._lock:
            if self._worker.stopped:
                return
            self._done.append((request, result))
        try:
            self._notify()
        except Exception:  # the context is gone: the node is shutting down
            self._worker.stop()
