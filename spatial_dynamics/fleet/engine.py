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
"""

from __future__ import annotations

import json
import os
import sys
import time
from typing import Callable, Dict, List, Optional, Sequence

from ..files import write_atomic
from .task import content_key, process, Task

#: How often a task is started again when its worker is lost or it fails unexpectedly.
RETRIES = 3


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
    """Start a LocalCluster of ``workers`` processes (default: the cores), one thread each."""
    from distributed import LocalCluster
    n = workers or len(os.sched_getaffinity(0))
    return LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                        dashboard_address=None, silence_logs=40)


def run_tasks(tasks: Sequence[Task], cache: Cache, client=None,
              progress: Optional[Callable[[Dict], None]] = None) -> List[Dict]:
    """Return the result of every task, in the order of ``tasks``.

    Cached results are taken as they are; the others run on ``client`` (a
    ``distributed.Client``) or, without one, here one after the other. A task the engine
    gives up on (a worker lost more often than allowed) is a failed bag with the reason.
    """
    digests: Dict[str, bytes] = {}
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
    futures = {client.submit(process, tasks[i], key=f'fleet-{keys[i]}-{i}', pure=False,
                             retries=RETRIES): i for i in todo}
    for future in as_completed(list(futures)):
        i = futures[future]
        try:
            results[i] = future.result()
        except Exception as err:        # the engine gave up: one bag, its reason
            results[i] = {'robot': tasks[i].robot, 'bag': tasks[i].bag, 'ok': False,
                          'reason': f'the engine gave up on it: {type(err).__name__}: '
                                    + ' '.join(str(err).split())}
            if tasks[i].chunked:
                results[i]['chunk'] = [tasks[i].start, tasks[i].stop]
        cache.put(keys[i], results[i])
        if progress:
            progress(results[i])
    return results
