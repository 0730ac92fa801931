# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""One bag, one task: read, clean, differentiate, the residual, the drive fit's sums.

:func:`process` is what a worker runs; it returns a plain dict (JSON-ready: the cache keeps
it as it is) and never raises for a bad bag: ``{'ok': False, 'reason': ...}`` names what is
wrong, and the rest of the fleet finishes. :func:`content_key` is the cache's key: a hash of
the bag's bytes, the URDF's bytes and the options, so a changed bag, URDF or option is done
again and nothing else is.
"""

from __future__ import annotations

from dataclasses import dataclass, field
import hashlib
import json
import os
from typing import Dict

import numpy as np

#: Changes when what a task computes changes (the cache's results are then stale).
VERSION = 'fleet-1'

#: Per-robot options and their defaults (the replay command's).
DEFAULTS = {'topic': '/joint_states', 'joints': None, 'threshold': 0.01, 'window': 0.05,
            'order': 3, 'measured_effort': 'full', 'gravity': (0.0, 0.0, -9.81)}


@dataclass(frozen=True)
class Task:
    """A bag of a robot, with the URDF and the options it is read with."""

    robot: str
    urdf: str
    bag: str
    options: Dict = field(default_factory=dict, hash=False)

    def option(self, name: str):
        """Return an option's value (the default when the manifest leaves it out)."""
        return self.options.get(name, DEFAULTS[name])


def _hash_file(h, path: str) -> None:
    with open(path, 'rb') as f:
        while True:
            block = f.read(1 << 20)
            if not block:
                return
            h.update(block)


def content_key(task: Task) -> str:
    """Return the hex SHA-256 of the bag's files, the URDF and the options (and VERSION)."""
    h = hashlib.sha256(VERSION.encode())
    files = ([os.path.join(task.bag, f) for f in sorted(os.listdir(task.bag))
              if os.path.isfile(os.path.join(task.bag, f))]
             if os.path.isdir(task.bag) else [task.bag])
    for path in files:
        h.update(os.path.basename(path).encode() + b'\0')
        _hash_file(h, path)
    h.update(b'\0urdf\0')
    _hash_file(h, task.urdf)
    options = {k: task.option(k) for k in sorted(DEFAULTS)}
    h.update(json.dumps(options, sort_keys=True, default=list).encode())
    return h.hexdigest()


def prepare(task: Task, model) -> Dict:
    """Read and clean the bag, derive q̇ and q̈: ``{t, q, qd, qdd, effort, skipped}``."""
    from .. import effort as effort_model
    from ..replay import bags, differentiate
    from ..replay.recording import clean
    window, order = float(task.option('window')), int(task.option('order'))
    js = bags.read_joint_states(task.bag, task.option('topic'), model.joint_names)
    s = clean(js, window)
    t, q, spans = s['t'], s['q'], s['spans']
    if s['qd'] is not None:
        (qd, qdd), _ = differentiate.derivatives(t, s['qd'], window, order, (0, 1), spans)
    else:
        (qd, qdd), _ = differentiate.derivatives(t, q, window, order, (1, 2), spans)
    effort = effort_model.with_gravity(model, q, s['effort'], task.option('measured_effort'),
                                       task.option('gravity'))
    return {'t': t, 'q': q, 'qd': qd, 'qdd': qdd, 'effort': effort, 'skipped': s['skipped']}


def process(task: Task) -> Dict:
    """Run one bag: the fit's sums and the residual statistics, or why the bag is refused.

    Returns ``{ok, robot, bag, start (s since the epoch), seconds, samples, joints, sums,
    rms_residual (rigid body), skipped}`` or ``{ok: False, robot, bag, reason}``. BLAS runs
    on one thread (the engine gives each worker one core).
    """
    from threadpoolctl import threadpool_limits
    from .. import rnea
    from ..replay import bags
    from ..replay.arguments import load_model, one_line, Refused
    from .sums import normal_sums
    head = {'robot': task.robot, 'bag': task.bag}
    try:
        with threadpool_limits(limits=1, user_api='blas'):
            model = load_model(_ModelArgs(task.urdf), task.option('joints'))
            d = prepare(task, model)
            residual = d['effort'] - rnea(model, d['q'], d['qd'], d['qdd'],
                                          task.option('gravity'))
            sums = normal_sums(residual, d['qd'], d['qdd'], float(task.option('threshold')))
    except (Refused, bags.BagError, bags.MissingDependency, ValueError, OSError,
            MemoryError) as err:
        return dict(head, ok=False, reason=one_line(err))
    t = d['t']
    return dict(head, ok=True, start=float(t[0]), seconds=float(t[-1] - t[0]),
                samples=int(len(t)), joints=list(model.joint_names), sums=sums.to_dict(),
                rms_residual=np.sqrt(np.mean(residual ** 2, axis=0)).tolist(),
                skipped={k: int(v) for k, v in d['skipped'].items()})


class _ModelArgs:
    """What :func:`spatial_dynamics.replay.arguments.load_model` reads of the arguments."""

    def __init__(self, urdf: str) -> None:
        self.urdf, self.joints, self.locked = urdf, None, []
