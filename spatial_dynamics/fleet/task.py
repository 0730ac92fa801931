# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""One bag (or one chunk of a long bag), one task: read, clean, differentiate, the sums.

:func:`process` is what a worker runs; it returns a plain dict (JSON-ready: the cache keeps
it as it is) and never raises for a bad bag: ``{'ok': False, 'reason': ...}`` names what is
wrong, and the rest of the fleet finishes. :func:`content_key` is the cache's key: a hash of
the bag's bytes, the URDF's bytes, the options and the chunk's time range, so a changed bag,
URDF or option is done again and nothing else is.

A chunk owns the samples of the messages recorded in its bag-time range ``[start, stop)``
and reads a margin on each side, so that each sample it owns is cleaned and differentiated
with the neighbours it has in the whole bag: the chunks' sums add up to the whole bag's
(:mod:`spatial_dynamics.fleet.chunks`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
import hashlib
import json
import os
import resource
from typing import Dict, Optional

import numpy as np

import spatial_dynamics as sd

from .. import effort as effort_model
from ..backends.compiled import threads_at_most
from ..files import read_blocks
from ..recordings import bags
from ..recordings.bags import JointStates, MAX_STORAGE_BYTES
from ..recordings.base_topics import base_motion, BaseTopic
from ..recordings.differentiate import window_samples
from ..recordings.errors import one_line, Refused
from ..recordings.loading import load_model
from ..recordings.recording import clean, rates
from .sums import normal_sums
from ..urdf import MAX_FILE_BYTES

#: Changes when what a task computes changes (the cache's results are then stale).
VERSION = 'fleet-3'

#: Bag time read on each side of a chunk, s, at least: four differentiation windows or this.
MARGIN = 1.0
#: Bag time (ns) of a base topic read beyond a chunk's joint states, each side.
BASE_MARGIN = 10 ** 9
#: How often a chunk's margin is widened (×4) before it reads the whole bag.
WIDENINGS = 4

#: Per-robot options and their defaults (the replay command's). ``base_odometry`` or
#: ``base_imu``: a mobile manipulator's base motion from that topic of each bag (with
#: ``odometry_link``/``imu_link``), as ``replay --base-odometry/--base-imu``.
DEFAULTS = {'topic': '/joint_states', 'joints': None, 'threshold': 0.01, 'window': 0.05,
            'order': 3, 'measured_effort': 'full', 'gravity': (0.0, 0.0, -9.81),
            'base_odometry': None, 'base_imu': None, 'odometry_link': None, 'imu_link': None}
#: The options that name a base topic, and the link option that goes with each.
BASE_TOPICS = {'base_odometry': 'odometry_link', 'base_imu': 'imu_link'}


@dataclass(frozen=True)
class Task:
    """A bag of a robot, with the URDF and the options it is read with.

    ``start``, ``stop``: the chunk's bag-time range (ns; ``None`` is the bag's beginning,
    end); both ``None``: the whole bag. ``where``: the manifest row or folder it comes from
    (what a ``failed:`` line names).
    """

    robot: str
    urdf: str
    bag: str
    options: Dict = field(default_factory=dict, hash=False)
    start: Optional[int] = None
    stop: Optional[int] = None
    where: str = field(default='', compare=False)

    @property
    def chunked(self) -> bool:
        """Whether the task is a chunk of its bag (not the whole bag)."""
        return self.start is not None or self.stop is not None

    def option(self, name: str):
        """Return an option's value (the default when the manifest leaves it out)."""
        return self.options.get(name, DEFAULTS[name])


def _hash_file(h, path: str, what: str, limit: int) -> None:
    """Add the bytes of ``path`` to ``h``, through the one reader of user files.

    A FIFO, a device or a directory is refused before a byte is read (``ValueError`` naming
    the file as ``what``): it would block or never end.
    """
    for block in read_blocks(path, what, limit):
        h.update(block)


def bag_digest(path: str) -> bytes:
    """Return the SHA-256 of a bag's files (a directory's regular files by name, or the file).

    ``ValueError`` for a bag file that is not a regular file (a FIFO, a device).
    """
    h = hashlib.sha256()
    files = ([os.path.join(path, f) for f in sorted(os.listdir(path))
              if os.path.isfile(os.path.join(path, f))]
             if os.path.isdir(path) else [path])
    for name in files:
        h.update(os.path.basename(name).encode() + b'\0')
        _hash_file(h, name, f'bag file {name!r}', MAX_STORAGE_BYTES)
    return h.digest()


def content_key(task: Task, digests: Optional[Dict[str, bytes]] = None) -> str:
    """Return the hex SHA-256 of the bag's files, the URDF, the options and the chunk.

    ``digests``: bag path -> :func:`bag_digest`, filled as bags are hashed (the chunks of
    a long bag then hash its bytes once).
    """
    digests = {} if digests is None else digests
    if task.bag not in digests:
        digests[task.bag] = bag_digest(task.bag)
    h = hashlib.sha256(VERSION.encode())
    h.update(digests[task.bag])
    h.update(b'\0urdf\0')
    _hash_file(h, task.urdf, f'URDF file {task.urdf!r}', MAX_FILE_BYTES)
    options = {k: task.option(k) for k in sorted(DEFAULTS)}
    h.update(json.dumps(options, sort_keys=True, default=list).encode())
    if task.chunked:
        h.update(f'\0chunk\0{task.start}\0{task.stop}'.encode())
    return h.hexdigest()


def prepare(task: Task, model) -> Dict:
    """Read and clean the bag, derive q̇ and q̈: ``{t, q, qd, qdd, effort, skipped, ...}``.

    ``owned`` (bool (N,), or None for a whole bag) marks the samples that are the chunk's;
    ``messages``: how many messages were read (held in memory at once); ``recorded``: the
    bag time (s since the epoch) of the first message of the bag or chunk, its date.
    """
    if not task.chunked:
        js = bags.read_joint_states(task.bag, task.option('topic'), model.joint_names)
        return dict(_derive(task, model, js, (None, None)), owned=None,
                    messages=len(js.stamp), recorded=_first(js))
    margin = int(max(MARGIN, 4.0 * float(task.option('window'))) * 1e9)
    for _ in range(WIDENINGS):
        d = _prepare_chunk(task, model, margin)
        if d is not None:
            return d
        margin *= 4
    return _prepare_chunk(task, model, None)


def _derive(task: Task, model, js, between) -> Dict:
    """Clean the messages ``js`` and differentiate them as ``replay`` does.

    ``base``: the base's motion at each sample (a base topic option), read from the bag
    in the bag-time range ``between`` (ns; ``(None, None)``: all of it), or None.
    """
    window, order = float(task.option('window')), int(task.option('order'))
    s = clean(js, window)
    t, q, spans = s['t'], s['q'], s['spans']
    qd, qdd, _ = rates(s, window, order)
    topic = BaseTopic(task.option('base_odometry'), task.option('base_imu'),
                      task.option('odometry_link'), task.option('imu_link'))
    base = base_motion(topic, task.bag, model, t, spans, window, order, between)
    effort = effort_model.with_gravity(model, q, s['effort'], task.option('measured_effort'),
                                       task.option('gravity'))
    return {'t': t, 'q': q, 'qd': qd, 'qdd': qdd, 'effort': effort, 'skipped': s['skipped'],
            'period': s['period'], 'base': base}


def _prepare_chunk(task: Task, model, margin: Optional[int]) -> Optional[Dict]:
    """:func:`prepare` of a chunk read with ``margin`` ns each side (None: the whole bag).

    The chunk owns the samples of the messages recorded in ``[start, stop)``; a stamp that
    is also a message's before ``start`` is the earlier chunk's (the cleaning keeps the first
    of a repeated stamp, in bag order). Returns None when an owned sample has fewer than two
    differentiation windows of samples read on a side the margin cut: a wider margin is
    needed for it to see the whole bag's neighbours (stamps far from the bag times).
    """
    def read(start, stop):
        return bags.read_joint_states_between(task.bag, task.option('topic'),
                                              model.joint_names, start, stop)

    lo = None if task.start is None or margin is None else task.start - margin
    hi = None if task.stop is None or margin is None else task.stop + margin
    pre = read(lo, task.start) if task.start is not None else None
    own = read(task.start, task.stop)
    post = read(task.stop, hi) if task.stop is not None else None
    js = _joined([p for p in (pre, own, post) if p is not None])
    messages = len(js.stamp)
    # the base topic over the joint states read and a margin more: its samples must reach
    # past the first and last joint stamps (by header stamp, which may lag the bag time)
    between = ((None if lo is None else lo - BASE_MARGIN),
               (None if hi is None else hi + BASE_MARGIN))
    try:
        d = _derive(task, model, js, between)
    except Refused as err:      # nothing usable here: the whole bag drops these samples too
        return {'owned': np.zeros(0, dtype=bool), 'messages': messages, 'empty': str(err)}
    owned = np.isin(d['t'], own.stamp)
    if pre is not None:
        owned &= ~np.isin(d['t'], pre.stamp)
    k = np.flatnonzero(owned)
    need = 2 * window_samples(float(task.option('window')), d['period'])
    if k.size and ((lo is not None and k[0] < need)
                   or (hi is not None and len(d['t']) - 1 - k[-1] < need)):
        return None
    return dict(d, owned=owned, messages=messages, recorded=_first(own))


def _first(js: JointStates) -> float:
    """Return the bag time (s since the epoch) of the first message of ``js`` (NaN: none)."""
    return float(np.min(js.received)) if len(js.received) else float('nan')


def _joined(parts) -> JointStates:
    """Return the JointStates of ``parts`` one after the other (bag order)."""
    if len(parts) == 1:
        return parts[0]
    skipped: Dict[str, int] = {}
    for p in parts:
        for k, v in p.skipped.items():
            skipped[k] = skipped.get(k, 0) + v
    return JointStates(parts[0].names, *(np.concatenate([getattr(p, f) for p in parts])
                                         for f in ('stamp', 'position', 'velocity', 'effort')),
                       skipped=skipped, fast=sum(p.fast for p in parts),
                       generic=sum(p.generic for p in parts),
                       received=np.concatenate([p.received for p in parts]))


def process(task: Task) -> Dict:
    """Run one bag or chunk: the fit's sums and the residual statistics, or why it is refused.

    Returns ``{ok, robot, bag, start, end (the first and last sample's header.stamp, s),
    seconds, recorded (s since the epoch: when its first message was recorded, the bag's
    date whatever clock the stamps are on), samples, joints, sums, rms_residual (rigid
    body), skipped, messages (read at once), peak_rss_mb (of the process so far)}`` or
    ``{ok: False, robot, bag, reason}``.
    A chunk with no usable sample has ``samples`` 0 and ``empty``: why. BLAS and the
    package's own threads (the kernels' batches, the derivatives' filter) run on one thread:
    the engine gives each worker one core.
    """
    # optional (the replay and fleet extras): imported where it is used, so the command starts
    # and says what to install without it
    from threadpoolctl import threadpool_limits
    head = {'robot': task.robot, 'bag': task.bag}
    if task.chunked:
        head['chunk'] = [task.start, task.stop]
    try:
        with threadpool_limits(limits=1, user_api='blas'), threads_at_most(1):
            model = load_model(task.urdf, task.option('joints'))
            d = prepare(task, model)
            owned = d['owned']
            if owned is not None and not owned.any():
                n = len(model.joint_names)
                return dict(head, ok=True, samples=0, joints=list(model.joint_names),
                            sums=normal_sums(np.zeros((0, n)), np.zeros((0, n)),
                                             np.zeros((0, n)), 1.0).to_dict(),
                            messages=d['messages'], peak_rss_mb=peak_rss_mb(),
                            empty=one_line(d.get('empty') or 'no message in the range'))
            residual = d['effort'] - sd.rnea(model, d['q'], d['qd'], d['qdd'],
                                             task.option('gravity'), base=d['base'])
            t, qd, qdd = d['t'], d['qd'], d['qdd']
            if owned is not None:
                t, residual, qd, qdd = t[owned], residual[owned], qd[owned], qdd[owned]
            sums = normal_sums(residual, qd, qdd, float(task.option('threshold')))
    except (Refused, bags.BagError, bags.MissingDependency, ValueError, OSError,
            MemoryError) as err:
        return dict(head, ok=False, reason=one_line(err))
    return dict(head, ok=True, start=float(t[0]), end=float(t[-1]),
                seconds=float(t[-1] - t[0]), recorded=d['recorded'], samples=int(len(t)),
                joints=list(model.joint_names), sums=sums.to_dict(),
                rms_residual=np.sqrt(np.mean(residual ** 2, axis=0)).tolist(),
                skipped={k: int(v) for k, v in d['skipped'].items()},
                messages=d['messages'], peak_rss_mb=peak_rss_mb())


def peak_rss_mb() -> float:
    """Return this process's peak resident memory so far, MB.

    Linux's ``VmHWM`` (``/proc/self/status``): the high-water mark of this process's own
    memory. ``getrusage``'s ``ru_maxrss`` is not: a process started by fork and exec keeps
    its parent's RSS at the fork as its floor (a worker of a large command would report the
    command's). Elsewhere ``ru_maxrss`` (kB on Linux and BSD).
    """
    try:
        with open('/proc/self/status', encoding='ascii') as f:
            for line in f:
                if line.startswith('VmHWM:'):
                    return int(line.split()[1]) / 1024.0
    except (OSError, ValueError, IndexError):
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
