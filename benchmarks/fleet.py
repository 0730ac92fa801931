# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The fleet's throughput: bag-hours per minute per core, serial against 1 and 2 workers.

``python -m benchmarks.fleet`` (from the checkout) writes (or reuses, in ``--dir``) a fleet of
``--robots`` × ``--bags`` synthetic bags of ``--seconds`` each at ``--rate`` Hz: a 3-joint arm's
torque from our own RNEA plus a drive (damping, Coulomb friction, armature) and noise, the
stamps an hour apart. It runs the fleet's tasks as the command does (``run_tasks``, no
cache): in this process, on a local cluster of 1 worker, of 2 workers (the cluster's
start-up timed apart), and prints per way the wall time, the bag-hours processed per minute
per core and the overhead per core against serial. Then one long bag (``--long`` s) as one
task and cut into ``--chunk`` s chunks, each in a fresh process: the messages a task holds
and the process's peak RSS, which the chunks bound whatever the bag's length.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from typing import List, Optional, Sequence

import numpy as np

#: The drive every synthetic bag carries: damping N m s, Coulomb friction N m, armature.
DRIVE = (0.4, 0.8, 0.03)
#: Noise of the measured velocity (rad/s) and torque (N m).
NOISE_QD, NOISE_TAU = 0.002, 0.05
T0 = 1_790_000_000 * 10 ** 9        # the first bag's first bag time, ns
HOUR = 3600 * 10 ** 9


def arm_urdf() -> str:
    """Return the 3-joint arm every synthetic robot is (benchmarks.generate's chain)."""
    from benchmarks.generate import chain_urdf
    return chain_urdf(3, seed=7)


def synthetic_bag(path: str, urdf: str, seconds: float, rate: float, t0_ns: int, seed: int,
                  storage: str = 'sqlite3', latency_ns: int = 2_500_000) -> None:
    """Write a bag of ``/joint_states``: sinusoids, RNEA torque + the drive + noise.

    Bag times are ``t0_ns + k / rate``; ``header.stamp`` is ``latency_ns`` earlier (the
    time of the measurement, the bag's the time it was recorded).
    """
    import spatial_dynamics as sd
    from spatial_dynamics.replay import bags
    model = sd.Model.from_urdf(urdf)
    rng = np.random.default_rng(seed)
    n = model.nq
    N = int(round(seconds * rate))
    t = np.arange(N) / rate
    w = rng.uniform(0.5, 3.0, (3, n))
    amp, phase = rng.uniform(0.2, 0.8, (3, n)), rng.uniform(0, 2 * np.pi, (3, n))
    arg = t[:, None, None] * w + phase                         # (N, 3, n)
    q = np.sum(amp * np.sin(arg), axis=1)
    qd = np.sum(amp * w * np.cos(arg), axis=1)
    qdd = -np.sum(amp * w ** 2 * np.sin(arg), axis=1)
    damping, friction, armature = DRIVE
    effort = (sd.rnea(model, q, qd, qdd) + damping * qd + friction * np.tanh(qd / 0.01)
              + armature * qdd + rng.normal(0.0, NOISE_TAU, (N, n)))
    times = t0_ns + np.round(t * 1e9).astype(np.int64)
    block = bags.encode_joint_states(model.joint_names, times - latency_ns, q,
                                     qd + rng.normal(0.0, NOISE_QD, (N, n)), effort)
    bags.write_bag(path, storage, [('/joint_states', bags.JOINT_STATE, times,
                                    [x.tobytes() for x in block])])
