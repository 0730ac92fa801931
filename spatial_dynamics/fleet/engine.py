# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Where the tasks run: in this process, on a local Dask cluster, or on a scheduler's.

The embedded default is ``distributed.LocalCluster``: one worker process per core, one
thread each (the fits are numpy on small matrices: processes avoid the GIL, one BLAS thread
each avoids oversubscribing the cores). ``scheduler='tcp://host:8786'`` uses a cluster
started elsewhere (``dask scheduler``, ``dask worker``); the bags are read where they lie, so
every worker must see the same paths. A task whose worker dies is run again by the scheduler
(``retries``), and the results come back in the order of the tasks whatever the order they
finish in, so every way of running gives the same numbers.

Tasks go to the cluster in batches of consecutive tasks of :data:`BATCH_BYTES` of bag at
least (fewer when the fleet is small: at least eight batches per worker): each submission
costs the scheduler, the client and the worker up to ~30 ms of CPU, as much as a minute of
a 500 Hz bag takes to process, so one task per short bag would spend more than half the
cluster on the engine (``python -m benchmarks.fleet``).
"""

from __future__ import annotations

import json
import os
import sys
import time
from typing import Callable, Dict, List, Optional, Sequence

from ..files import write_atomic
from .task import bag_digest, content_key, process, Task

#: How often a task is started again when its worker is lost or it fails unexpectedly.
RETRIES = 3
#: Bytes of bag one submission to the cluster carries at most (about half a second of work).
BATCH_BYTES = 64 << 20
#: Fewest batches per worker when the fleet is small (the last ones balance the workers).
BATCHES_PER_WORKER = 8


class Cache:
    """Results by content key, one JSON file each in a folder."""

    def __init__(self, folder: Optional[str]) -> None:
        """Use ``folder`` (created); ``None``: no cache."""
        self.folder = folder
        if folder:
            os.makedirs(folder, exist_ok=True)

    def path(self, key: str) -> str:
        """Return the file of ``key``."""
        return os.path.join(self.folder, key + '.json')

    def get(self, key: str) -> Optional[Dict]:
        """Return the result stored for ``key``, or None (also for an unreadable file)."""
        if not self.folder:
            return None
        try:
            with open(self.path(key), encoding='utf-8') as f:
                return json.load(f)
        except (OSError, ValueError):
            return None

    def put(self, key: str, result: Dict) -> None:
        """Store ``result`` (a refused bag is not stored: it is tried again next time)."""
        if self.folder and result.get('ok'):
            write_atomic(self.path(key), json.dumps(result), 'cache entry')


class Progress:
    """``fleet: 12/36 tasks, 0.40 h of data, ETA 0:42`` on a terminal; nothing otherwise."""

    def __init__(self, total: int, stream=None) -> None:
        """Count to ``total``."""
        self.stream = stream or sys.stderr
        self.on = self.stream.isatty()
        self.total, self.done, self.hours = total, 0, 0.0
        self.start = time.monotonic()

    def __call__(self, result: Dict) -> None:
        """One more task (a bag or a chunk of one) done."""
        self.done += 1
        self.hours += result.get('seconds', 0.0) / 3600.0
        if not self.on:
            return
        spent = time.monotonic() - self.start
        left = int(spent / self.done * (self.total - self.done))
        self.stream.write(f'\rfleet: {self.done}/{self.total} tasks, {self.hours:.2f} h of '
                          f'data, ETA {left // 60}:{left % 60:02d} ')
        self.stream.flush()

    def close(self) -> None:
        """End the line."""
        if self.on and self.done:
            self.stream.write('\n')


def local_cluster(workers: Optional[int] = None):
    """Start a LocalCluster of ``workers`` processes (default: the cores), one thread each.

    Without a dashboard, and so without the workers' statistical profiler (it samples the
    running task's stack every 10 ms for the dashboard: 3-4 % of a worker's CPU here). And
    without Dask's ``MALLOC_TRIM_THRESHOLD_`` in the workers' environment: set at all, it
    turns off glibc's adaptive mmap threshold, so every array over 128 kB is mapped and
    unmapped afresh, its pages faulted in each time (a task then takes 20-25 % more CPU).
    """
    import dask
    from distributed import LocalCluster
    n = workers or len(os.sched_getaffinity(0))
    with dask.config.set({'distributed.worker.profile.enabled': False,
                          'distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_': None}):
        return LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                            dashboard_address=None, silence_logs=40)


def run_tasks(tasks: Sequence[Task], cache: Cache, client=None,
              progress: Optional[Callable[[Dict], None]] = None) -> List[Dict]:
    """Return the result of every task, in the order of ``tasks``.

    Cached results are taken as they are; the others run on ``client`` (a
    ``distributed.Client``) or, without one, here one after the other. A task the engine
    gives up on (a worker lost more often than allowed) is a failed bag with the reason.
    """
    digests = {} if client is None else digests_on(client, tasks)
    keys = [content_key(t, digests) for t in tasks]
    results: List[Optional[Dict]] = [cache.get(k) for k in keys]
    todo = [i for i, r in enumerate(results) if r is None]
    for i, r in enumerate(results):
        if r is not None:
            r['cached'] = True
    if client is None:
        for i in todo:
            results[i] = process(tasks[i])
            cache.put(keys[i], results[i])
            if progress:
                progress(results[i])
        return results
    from distributed import as_completed
    workers = max(1, len(client.scheduler_info().get('workers', {})))
    futures = {client.submit(process_batch, [tasks[i] for i in b],
                             key=f'fleet-{keys[b[0]]}-{b[0]}-{len(b)}', pure=False,
                             retries=RETRIES): b
               for b in batches(tasks, todo, workers)}
    for future in as_completed(list(futures)):
        batch = futures[future]
        try:
            done = future.result()
        except Exception as err:        # the engine gave up: these bags, the reason
            done = [gave_up(tasks[i], err) for i in batch]
        for i, result in zip(batch, done):
            results[i] = result
            cache.put(keys[i], result)
            if progress:
                progress(result)
    return results


def digests_on(client, tasks: Sequence[Task]) -> Dict[str, bytes]:
    """Return bag path -> :func:`~.task.bag_digest` of the tasks' bags, hashed by the workers.

    Hashing reads every byte of every bag (2 s of a 16 s serial run at 1 kHz): done here, it
    would keep the workers idle until it ended; on the workers, it is spread over them as the
    tasks are, where the bags are read anyway. A bag a worker cannot hash is left out (the
    caller hashes it, and says what is wrong with it).
    """
    paths = sorted({t.bag for t in tasks})
    workers = max(1, len(client.scheduler_info().get('workers', {})))
    size = max(1, -(-len(paths) // (4 * workers)))      # about four batches per worker
    groups = [paths[i:i + size] for i in range(0, len(paths), size)]
    futures = client.map(digest_batch, groups, pure=False, retries=RETRIES)
    digests: Dict[str, bytes] = {}
    for group, future in zip(groups, futures):
        try:
            found = future.result()
        except Exception:       # the engine gave up on them: the caller hashes them
            continue
        digests.update((p, d) for p, d in zip(group, found) if d is not None)
    return digests


def digest_batch(paths: Sequence[str]) -> List[Optional[bytes]]:
    """Return each bag's :func:`~.task.bag_digest` (None for one that cannot be read)."""
    out: List[Optional[bytes]] = []
    for path in paths:
        try:
            out.append(bag_digest(path))
        except OSError:
            out.append(None)
    return out


def process_batch(tasks: Sequence[Task]) -> List[Dict]:
    """Run tasks one after the other (what a worker runs for one submission)."""
    return [process(t) for t in tasks]


def gave_up(task: Task, err: Exception) -> Dict:
    """Return the failed result of a task the engine gave up on (a worker lost too often)."""
    result = {'robot': task.robot, 'bag': task.bag, 'ok': False,
              'reason': f'the engine gave up on it: {type(err).__name__}: '
                        + ' '.join(str(err).split())}
    if task.chunked:
        result['chunk'] = [task.start, task.stop]
    return result


def batches(tasks: Sequence[Task], todo: Sequence[int], workers: int) -> List[List[int]]:
    """Group the tasks ``todo`` (indices, in order) into consecutive runs to submit together.

    A task weighs its bag's bytes (a chunk: its share of them); a run weighs at most
    :data:`BATCH_BYTES`, or the fleet's weight over ``BATCHES_PER_WORKER × workers`` if
    that is less (a task heavier than that is a run of its own).
    """
    size: Dict[str, int] = {}
    parts: Dict[str, int] = {}
    for i in todo:
        bag = tasks[i].bag
        parts[bag] = parts.get(bag, 0) + 1
        if bag not in size:
            size[bag] = _bytes(bag)
    weight = {i: size[tasks[i].bag] / parts[tasks[i].bag] for i in todo}
    target = min(BATCH_BYTES, sum(weight.values()) / (BATCHES_PER_WORKER * workers))
    out: List[List[int]] = []
    run: List[int] = []
    held = 0.0
    for i in todo:
        if run and held + weight[i] > target:
            out.append(run)
            run, held = [], 0.0
        run.append(i)
        held += weight[i]
    if run:
        out.append(run)
    return out


def _bytes(path: str) -> int:
    """Bytes of a bag (a directory's files, or the file); 0 if it cannot be listed."""
    try:
        if not os.path.isdir(path):
            return os.path.getsize(path)
        return sum(os.path.getsize(os.path.join(path, f)) for f in os.listdir(path)
                   if os.path.isfile(os.path.join(path, f)))
    except OSError:
        return 0


def warm(client) -> None:
    """Import what the tasks need on every worker (part of starting the cluster, not a bag)."""
    client.run(load_modules)


#: The modules a task imports when it first runs.
MODULES = ('threadpoolctl', 'spatial_dynamics.replay.arguments', 'spatial_dynamics.replay.bags',
           'spatial_dynamics.replay.recording', 'spatial_dynamics.fleet.sums')


def load_modules() -> None:
    """Import :data:`MODULES` (what :func:`warm` runs on each worker)."""
    import importlib
    for name in MODULES:
        importlib.import_module(name)
