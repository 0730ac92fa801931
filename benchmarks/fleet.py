# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The fleet's throughput: bag-hours per minute per core, serial against 1 and 2 workers.

``python -m benchmarks.fleet`` (from the checkout) writes (or reuses, in ``--dir``) a fleet of
``--robots`` × ``--bags`` synthetic bags of ``--seconds`` each at ``--rate`` Hz: an arm of
``--joints`` joints, its torque from our own RNEA plus a drive (damping, Coulomb friction,
armature) and noise, the bags an hour apart. It runs the fleet's tasks as the command does
(``run_tasks``, no cache): in this process, on a local cluster of 1 worker, of 2 workers (the
cluster's start-up timed apart), and prints per way the wall time, the bag-hours processed
per minute per core (and per CPU-minute: user + system time of this process and the
workers, which a busy machine does not inflate as it does the wall time), the overhead per
core, and whether the sums are the serial ones bit for bit. A cluster of N workers is
measured against N plain processes that each run an equal share with no engine at all (what
N cores give this work here: they share caches and memory bandwidth), 1 worker against
serial. Then long bags
(``--long`` s) as one task and cut into ``--chunk`` s chunks, each in a fresh process: the
most messages a task holds and the process's peak RSS, which the chunks bound whatever the
bag's length.

The command's own rows run ``python -m spatial_dynamics.fleet`` on a manifest of the fleet,
each in a fresh process as a user would (its imports included): ``--serial``, then the
default (below 1 GB of bags to process it runs without a cluster), then the same command
again with the cache in its ``--out``: the re-run's wall time as a fraction of the first
run's, the default's against ``--serial``. ``--parts`` chooses what runs (default: all).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from typing import List, Optional, Sequence

import numpy as np

#: What ``--parts`` may choose.
PARTS = ('command', 'engine', 'memory')
#: The drive every synthetic bag carries: damping N m s, Coulomb friction N m, armature.
DRIVE = (0.4, 0.8, 0.03)
#: Noise of the measured velocity (rad/s) and torque (N m).
NOISE_QD, NOISE_TAU = 0.002, 0.05
T0 = 1_790_000_000 * 10 ** 9        # the first bag's first bag time, ns
HOUR = 3600 * 10 ** 9


def arm_urdf(joints: int = 3) -> str:
    """Return the arm every synthetic robot is (benchmarks.generate's chain of ``joints``)."""
    from benchmarks.generate import chain_urdf
    return chain_urdf(joints, seed=7)


def synthetic_bag(path: str, urdf: str, seconds: float, rate: float, t0_ns: int, seed: int,
                  storage: str = 'sqlite3', latency_ns: int = 2_500_000) -> None:
    """Write a bag of ``/joint_states``: sinusoids, RNEA torque + the drive + noise.

    Bag times are ``t0_ns + k / rate``; ``header.stamp`` is ``latency_ns`` earlier (the
    time of the measurement, the bag's the time it was recorded).
    """
    import spatial_dynamics as sd
    from spatial_dynamics.recordings import bags
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


def make_fleet(folder: str, robots: int, per_robot: int, seconds: float, rate: float,
               joints: int = 3) -> List:
    """Write (or reuse) ``robots`` × ``per_robot`` bags under ``folder``; return the tasks."""
    from spatial_dynamics.fleet.task import Task
    folder = os.path.join(folder, f'{joints}joints')
    urdf = os.path.join(folder, 'robot.urdf')
    os.makedirs(folder, exist_ok=True)
    with open(urdf, 'w', encoding='utf-8') as f:
        f.write(arm_urdf(joints))
    tasks = []
    for r in range(robots):
        for b in range(per_robot):
            path = os.path.join(folder, f'r{r + 1:02d}', f'bag{b + 1:03d}_{seconds:g}s_{rate:g}hz')
            if not os.path.exists(os.path.join(path, 'metadata.yaml')):
                shutil_rm(path)
                synthetic_bag(path, arm_urdf(joints), seconds, rate, T0 + b * HOUR,
                              1000 * r + b)
            tasks.append(Task(f'r{r + 1:02d}', urdf, path))
    return tasks


def shutil_rm(path: str) -> None:
    """Remove a half-written bag (a run stopped while writing it)."""
    import shutil
    shutil.rmtree(path, ignore_errors=True)


def cpu_of(pids: Sequence[int]) -> float:
    """CPU seconds (user + system) the processes ``pids`` have used so far."""
    import psutil
    return sum(sum(psutil.Process(p).cpu_times()[:2]) for p in pids)


def read_once(tasks: List) -> None:
    """Read every bag once: every way then reads them from the page cache, the first too."""
    for task in tasks:
        walk = os.walk(task.bag) if os.path.isdir(task.bag) else [('', (), [task.bag])]
        for root, _, files in walk:
            for name in files:
                with open(os.path.join(root, name), 'rb') as f:
                    while f.read(1 << 24):
                        pass


def timed_runs(tasks: List, workers: Sequence[int]) -> List[dict]:
    """Run ``tasks`` serially and on local clusters of ``workers`` processes; the figures."""
    from distributed import Client
    from spatial_dynamics.fleet.engine import Cache, load_modules, local_cluster, run_tasks, warm
    rows = []
    me = [os.getpid()]
    load_modules()      # as warm() does on each worker
    read_once(tasks)
    c0, t0 = cpu_of(me), time.perf_counter()
    results = run_tasks(tasks, Cache(None))
    rows.append({'way': 'serial', 'cores': 1, 'wall': time.perf_counter() - t0,
                 'cpu': cpu_of(me) - c0, 'startup': 0.0, 'results': results})
    for n in workers:
        if n > 1:       # the machine's own limit: n processes, no engine, n equal shares
            rows.append(plain_processes(tasks, n))
        t0 = time.perf_counter()
        with local_cluster(n) as cluster, Client(cluster) as client:
            warm(client)
            pids = list(client.run(os.getpid).values())
            startup = time.perf_counter() - t0
            c0, w0, t0 = cpu_of(me), cpu_of(pids), time.perf_counter()
            results = run_tasks(tasks, Cache(None), client)
            wall = time.perf_counter() - t0
            here, there = cpu_of(me) - c0, cpu_of(pids) - w0
        rows.append({'way': f'{n} worker{"s" if n > 1 else ""}', 'cores': n, 'wall': wall,
                     'cpu': here + there, 'here': here, 'startup': startup,
                     'results': results})
    return rows


def _share(tasks: List) -> tuple:
    """Run ``tasks`` here, one after the other: (results, CPU s of this process).

    Each bag hashed first, as every way does for its cache key.
    """
    from spatial_dynamics.fleet.engine import load_modules, process_batch
    from spatial_dynamics.fleet.task import content_key
    load_modules()
    c0 = time.process_time()
    digests: dict = {}
    for task in tasks:
        content_key(task, digests)
    results = process_batch(tasks)
    return results, time.process_time() - c0


def plain_processes(tasks: List, n: int) -> dict:
    """Run ``tasks`` in ``n`` plain processes, each a contiguous share: no engine at all.

    What ``n`` cores give this work on this machine (their shared caches and memory
    bandwidth included): the cluster's overhead is measured against it.
    """
    from concurrent.futures import ProcessPoolExecutor
    shares = [list(tasks[k * len(tasks) // n:(k + 1) * len(tasks) // n]) for k in range(n)]
    with ProcessPoolExecutor(n) as pool:
        list(pool.map(time.sleep, [0.0] * n))          # the processes started apart
        t0 = time.perf_counter()
        done = list(pool.map(_share, shares))
        wall = time.perf_counter() - t0
    return {'way': f'{n} plain', 'cores': n, 'wall': wall, 'cpu': sum(c for _, c in done),
            'startup': 0.0, 'results': [r for results, _ in done for r in results]}


def command_rows(tasks: List, folder: str, baseline_days: float) -> List[dict]:
    """Run the fleet command on ``tasks`` as a user would: --serial, default, cached re-run.

    Each run is a fresh ``python -m spatial_dynamics.fleet`` on a manifest of the tasks
    (written to ``folder``), its wall time and CPU time (user + system of the child)
    measured; ``--serial`` and the default write to their own new ``--out``, the re-run to
    the default's (its cache). Returns one dict a run: way, wall, cpu, the summary line and
    fleet.csv's text.
    """
    import resource
    import shutil
    manifest = os.path.join(folder, 'manifest.csv')
    with open(manifest, 'w', encoding='utf-8') as f:
        f.write('robot,urdf,bag\n' + ''.join(f'{t.robot},{t.urdf},{t.bag}\n' for t in tasks))
    rows = []
    ways = [('--serial', 'serial', ['--serial']), ('default', 'default', []),
            ('re-run', 'default', [])]
    for name in ('serial', 'default'):
        shutil.rmtree(os.path.join(folder, name), ignore_errors=True)
    read_once(tasks)
    for way, out, extra in ways:
        out = os.path.join(folder, out)
        argv = [sys.executable, '-m', 'spatial_dynamics.fleet', manifest, '--out', out,
                '--baseline-days', f'{baseline_days:g}'] + extra
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        done = subprocess.run(argv, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        if done.returncode not in (0, 3, 4):
            raise RuntimeError(f'{" ".join(argv)}: exit {done.returncode}\n{done.stderr}')
        with open(os.path.join(out, 'fleet.csv'), encoding='utf-8') as f:
            csv_text = f.read()
        cpu = after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime
        rows.append({'way': way, 'wall': wall, 'cpu': cpu,
                     'summary': done.stdout.splitlines()[0], 'csv': csv_text})
    return rows


def print_command_rows(rows: List[dict]) -> None:
    """Print the command's runs and the ratios: re-run / first run, default / --serial."""
    by = {r['way']: r for r in rows}
    for r in rows:
        print(f'{"command " + r["way"]:>16}: {r["wall"]:6.2f} s wall, {r["cpu"]:6.2f} s CPU; '
              f'{r["summary"]}', flush=True)
    first, again, serial = by['default'], by['re-run'], by['--serial']
    print(f'cached re-run / first run: {again["wall"] / first["wall"]:.1%} wall '
          f'({again["cpu"] / first["cpu"]:.1%} CPU); fleet.csv '
          f'{"identical" if again["csv"] == first["csv"] else "DIFFERENT"}', flush=True)
    print(f'default / --serial: {first["wall"] / serial["wall"]:.2f} wall '
          f'({first["cpu"] / serial["cpu"]:.2f} CPU); fleet.csv '
          f'{"identical" if first["csv"] == serial["csv"] else "DIFFERENT"}', flush=True)


def memory_of_long_bag(path: str, chunk: float) -> str:
    """Run a bag's tasks (``chunk`` 0: one) in this process: messages held, peak RSS."""
    from spatial_dynamics.fleet.chunks import merge, split
    from spatial_dynamics.fleet.task import process, Task
    urdf = os.path.join(os.path.dirname(path), 'robot.urdf')
    task = Task('long', urdf, path)
    parts, owner = split([task], chunk)
    result, = merge([task], owner, [process(p) for p in parts])
    if not result['ok']:
        return f'failed: {result["reason"]}'
    return (f'{len(parts)} task(s), at most {result["messages"]} messages held, peak RSS '
            f'{result["peak_rss_mb"]:.0f} MB')


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Write or reuse the fleet, time the ways of running it, print the figures."""
    import tempfile
    p = argparse.ArgumentParser(prog='python -m benchmarks.fleet', description=__doc__)
    p.add_argument('--dir',
                   default=os.path.join(tempfile.gettempdir(), 'spatial_dynamics_fleet_bench'),
                   help='where the bags are written and reused (default %(default)s)')
    p.add_argument('--robots', type=int, default=4, help='robots (default %(default)s)')
    p.add_argument('--bags', type=int, default=30, help='bags per robot (default 30)')
    p.add_argument('--seconds', type=float, default=60.0, help='of each bag (default 60)')
    p.add_argument('--rate', type=float, default=500.0, help='Hz (default 500)')
    p.add_argument('--joints', type=int, default=3, help='of the arm (default 3)')
    p.add_argument('--workers', type=int, nargs='*', default=[1, 2],
                   help='Dask worker counts to time, one run each (default 1 2)')
    p.add_argument('--long', type=float, nargs='*', default=[1200.0, 2400.0],
                   help='lengths of the long bags, s (default 1200 2400)')
    p.add_argument('--chunk', type=float, default=300.0, help='their chunks, s (default 300)')
    p.add_argument('--parts', nargs='+', choices=PARTS, default=list(PARTS),
                   help='what runs: the engine\'s ways, the command\'s runs (first, '
                   'cached re-run, default against --serial), the long bags\' memory '
                   '(default: all)')
    p.add_argument('--baseline-days', type=float, default=0.5,
                   help='of the command\'s runs (the bags are an hour apart; default '
                   '%(default)g)')
    p.add_argument('--memory-of', nargs=2, metavar=('BAG', 'CHUNK'), help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.memory_of:
        print(memory_of_long_bag(args.memory_of[0], float(args.memory_of[1])))
        return 0
    tasks = make_fleet(args.dir, args.robots, args.bags, args.seconds, args.rate, args.joints)
    print(f'{len(tasks)} bags of {args.seconds:g} s at {args.rate:g} Hz ({args.joints} joints) '
          f'in {args.dir}; {os.cpu_count()} CPUs, load {os.getloadavg()[0]:.1f}', flush=True)
    if 'command' in args.parts:
        print_command_rows(command_rows(tasks, os.path.join(args.dir, f'{args.joints}joints'),
                                        args.baseline_days))
    if 'engine' in args.parts:
        engine_rows(tasks, args.workers)
    if 'memory' in args.parts:
        long_bags(args)
    print(f'load {os.getloadavg()[0]:.1f} at the end', flush=True)
    return 0


def engine_rows(tasks: List, workers: Sequence[int]) -> None:
    """Time the engine's ways of running ``tasks`` and print their figures."""
    rows = timed_runs(tasks, workers)
    want = [r['sums'] for r in rows[0]['results']]
    for row in rows:
        results = row['results']
        assert all(r['ok'] for r in results), [r for r in results if not r['ok']][:1]
        same = [r['sums'] for r in results] == want
        hours = sum(r['seconds'] for r in results) / 3600.0
        rate = hours / (row['wall'] / 60.0) / row['cores']
        row['rate'] = rate
        per_cpu = hours / (row['cpu'] / 60.0)
        base = next((r for r in rows if r['way'] == f'{row["cores"]} plain'), rows[0])
        over = 1.0 - rate / base['rate']
        cpu_over = row['cpu'] / base['cpu'] - 1.0
        rss = max(r['peak_rss_mb'] for r in results)
        print(f'{row["way"]:>9}: {row["wall"]:6.1f} s wall ({row["startup"]:.1f} s cluster '
              f'start-up apart), {rate:6.2f} bag-h/min/core ({per_cpu:.2f} per CPU-minute), '
              f'overhead per core against {base["way"]} {over:+.1%} wall, {cpu_over:+.1%} '
              f'CPU ({row["cpu"]:.1f} s, '
              f'{row.get("here", row["cpu"]):.1f} s of it in this process); peak RSS per '
              f'process {rss:.0f} MB; sums {"identical" if same else "DIFFERENT"} to serial',
              flush=True)


def long_bags(args) -> None:
    """Print the messages held and the peak RSS of the long bags, whole and in chunks."""
    for seconds in args.long:
        path = os.path.join(args.dir, f'{args.joints}joints', f'long_{seconds:g}s_{args.rate:g}hz')
        if not os.path.exists(os.path.join(path, 'metadata.yaml')):
            shutil_rm(path)
            synthetic_bag(path, arm_urdf(args.joints), seconds, args.rate, T0 - 2 * HOUR, 99)
        for chunk in (0.0, args.chunk):
            out = subprocess.run([sys.executable, '-m', 'benchmarks.fleet', '--memory-of', path,
                                  str(chunk)], capture_output=True, text=True, check=True)
            how = 'whole' if chunk == 0 else f'chunks of {chunk:g} s'
            print(f'long bag {seconds:g} s, {how}: {out.stdout.strip()}', flush=True)


if __name__ == '__main__':
    sys.exit(main())
