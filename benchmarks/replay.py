# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Time the replay command on a generated bag: one hour of a 7-joint arm at 1 kHz by default.

    python -m benchmarks.replay [--seconds 3600] [--rate 1000]
                                            [--storage mcap|sqlite3|both] [--dir DIR]
                                            [--residual csv|npy|none] [--identify]
                                            [--inertias] [--repeat 1]

Writes ``/joint_states`` of the demo arm (joint1..7, fingers locked) moving on sinusoids, with
efforts from the model plus damping and friction, into DIR (a temporary directory by
default, removed afterwards), then runs ``python -m spatial_dynamics.replay`` on it in a
child process and prints the command's wall and CPU time and its stages (``--timings``: wall
and CPU time of each), ``--repeat`` times. Writing the bag is not part of the measurement.
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from typing import Optional, Sequence

import numpy as np

from spatial_dynamics import Model, rnea
from spatial_dynamics.recordings import bags

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
URDF = os.path.join(ROOT, 'config', 'demo_arm.urdf')
JOINTS = [f'joint{k}' for k in range(1, 8)]


def generate(path: str, storage: str, seconds: float, rate: float) -> int:
    """Write the benchmark bag; return its number of messages."""
    model = Model.from_urdf(URDF, joints=JOINTS)
    N = int(seconds * rate)
    k = np.arange(7)
    w, amp = 2 * np.pi * (0.1 + 0.05 * k), 0.5 / (1 + 0.1 * k)
    stamp = (1_700_000_000 * 10 ** 9 + np.arange(N) * int(round(1e9 / rate))).astype(np.int64)
    names = list(model.joint_names)
    chunk = 1 << 18
    blocks = []
    for a in range(0, N, chunk):
        t = (stamp[a:a + chunk] - stamp[0])[:, None] * 1e-9
        q, qd, qdd = amp * np.sin(w * t), amp * w * np.cos(w * t), -amp * w * w * np.sin(w * t)
        tau = rnea(model, q, qd, qdd) + 0.5 * qd + 0.3 * np.tanh(qd / 0.01)
        blocks.append(bags.encode_joint_states(names, stamp[a:a + chunk], q, qd, tau))
    bags.write_bag(path, storage, [('/joint_states', bags.JOINT_STATE, stamp,
                                    (row.tobytes() for b in blocks for row in b))])
    return N


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Generate the bag(s), time the command on each; return 0 (1 if the command fails)."""
    p = argparse.ArgumentParser(prog='python -m benchmarks.replay',
                                description=__doc__.split('\n\n')[0])
    p.add_argument('--seconds', type=float, default=3600.0,
                   help='length of the generated bag, s (default %(default)s)')
    p.add_argument('--rate', type=float, default=1000.0,
                   help='its joint-state rate, Hz (default %(default)s)')
    p.add_argument('--storage', choices=('mcap', 'sqlite3', 'both'), default='both',
                   help='bag storage to time (default %(default)s)')
    p.add_argument('--dir', help='where to write the bags (kept); default a temporary one')
    p.add_argument('--residual', choices=('csv', 'npy', 'none'), default='csv',
                   help="the command's --residual (default %(default)s)")
    p.add_argument('--identify', action='store_true',
                   help='time replay identify (the drives\' fit) instead of residual')
    p.add_argument('--inertias', action='store_true',
                   help='time the fit of every link\'s inertial parameters too')
    p.add_argument('--repeat', type=int, default=1,
                   help='run the command this many times (on a shared machine: take the '
                   'fastest; default %(default)s)')
    args = p.parse_args(argv)
    work = args.dir or tempfile.mkdtemp(prefix='replay_bench_')
    storages = ('mcap', 'sqlite3') if args.storage == 'both' else (args.storage,)
    status = 0
    try:
        for storage in storages:
            bag = os.path.join(work, f'bag_{storage}')
            if not os.path.exists(bag):
                start = time.perf_counter()
                n = generate(bag, storage, args.seconds, args.rate)
                print(f'{storage}: wrote {n} messages in {time.perf_counter() - start:.1f} s '
                      f'({_size(bag) / 2 ** 20:.0f} MiB)', flush=True)
            fits = args.identify or args.inertias
            cmd = [sys.executable, '-m', 'spatial_dynamics.replay',
                   'identify' if fits else 'residual', bag, '--urdf', URDF,
                   '--joints', *JOINTS, '--out', os.path.join(work, f'out_{storage}'),
                   '--timings', '--residual', args.residual] + (
                       ['--inertias'] if args.inertias else []) + (
                       ['--drives'] if args.identify and args.inertias else [])
            env = dict(os.environ, PYTHONPATH=os.pathsep.join(
                [ROOT] + ([os.environ['PYTHONPATH']] if 'PYTHONPATH' in os.environ else [])))
            print(f'{storage}: timing {" ".join(cmd[1:])}', flush=True)
            walls = []
            for _ in range(args.repeat):
                before = resource.getrusage(resource.RUSAGE_CHILDREN)
                start = time.perf_counter()
                r = subprocess.run(cmd, capture_output=True, text=True, env=env)
                walls.append(time.perf_counter() - start)
                after = resource.getrusage(resource.RUSAGE_CHILDREN)
                cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
                print(f'{storage}: command {walls[-1]:.2f} s wall, {cpu:.2f} s CPU (user + '
                      f'system, its children included; exit {r.returncode}, '
                      f'{os.cpu_count()} CPUs, load {os.getloadavg()[0]:.1f})')
                print(r.stderr.rstrip(), flush=True)
                status |= r.returncode != 0
            if args.repeat > 1:
                print(f'{storage}: fastest of {args.repeat}: {min(walls):.2f} s wall')
    finally:
        if not args.dir:
            shutil.rmtree(work, ignore_errors=True)
    return int(status)


def _size(path: str) -> int:
    """Bytes of the files under ``path``."""
    return sum(os.path.getsize(os.path.join(d, f)) for d, _, fs in os.walk(path) for f in fs)


if __name__ == '__main__':
    sys.exit(main())
