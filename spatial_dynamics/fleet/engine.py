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

import contextlib
import hashlib
import importlib
import json
import logging
import os
import signal
import sys
import threading
import time
from typing import Callable, Dict, Iterable, List, Optional, Sequence, Set, Tuple

import numpy as np

from ..files import read_regular, write_atomic
from .task import bag_digest, content_key, process, Task, VERSION

# dask and distributed are imported where a cluster is made or used: start-up time, and
# optional (the fleet extra): a serial run needs neither

#: How often a task is started again when its worker is lost or it fails unexpectedly.
RETRIES = 3
#: Bytes of bag one submission to the cluster carries at most (about half a second of work).
BATCH_BYTES = 64 << 20
#: Fewest batches per worker when the fleet is small (the last ones balance the workers).
BATCHES_PER_WORKER = 8
#: Bytes of bag to process below which the command runs them here, without a cluster (about
#: 20 s of one core: less than a local cluster's start-up and engine cost on a busy machine).
SERIAL_BYTES = 1 << 30
#: The most local workers a core: more only share the same cores, in more memory.
WORKERS_PER_CORE = 4


class Cache:
    """Results by content key, one JSON file each in a folder.

    An entry holds only what the content decides (never the robot's name or the bag's
    path: those are the current run's), with the cache's own :data:`~.task.VERSION`, its
    key and a SHA-256 of its result. An entry that is not a regular file (a FIFO, a folder),
    is malformed (also nested too deeply for the parser), of another version or key, or
    whose numbers were edited, is not used: the task runs again and its entry is written
    anew.
    """

    def __init__(self, folder: Optional[str]) -> None:
        """Use ``folder`` (created); ``None``: no cache."""
        self.folder = folder
        if folder:
            os.makedirs(folder, exist_ok=True)

    def path(self, key: str) -> str:
        """Return the file of ``key``."""
        return os.path.join(self.folder, key + '.json')

    def get(self, key: str) -> Optional[Dict]:
        """Return the result stored for ``key``, or None (for anything but a valid entry)."""
        if not self.folder:
            return None
        try:
            entry = json.loads(read_regular(self.path(key), 'cache entry', ENTRY_LIMIT))
            result = entry['result']
            if (entry['version'] != VERSION or entry['key'] != key
                    or entry['check'] != checksum(result) or not valid(result)):
                return None
        except (ValueError, TypeError, KeyError, RecursionError):    # nested too deep to parse
            return None
        return result

    def known_digests(self, tasks: Sequence[Task]) -> Dict[str, bytes]:
        """Return bag path -> :func:`~.task.bag_digest` of the bags unchanged since hashed.

        A bag is unchanged when its resolved path and each of its files' name, size,
        ``mtime_ns``, ``ctime_ns``, inode and device are what they were when its bytes were
        hashed (:meth:`remember`): its bytes are not read again. A write changes
        ``ctime_ns`` and so does setting the mtime back (``touch -d``, ``os.utime``): the
        kernel sets it to the current time, no call sets it to a chosen one, so an edit in
        place with the same size and the mtime restored hashes the bag again.
        """
        known: Dict[str, bytes] = {}
        for bag in dict.fromkeys(t.bag for t in tasks):
            try:
                text = read_regular(self._stat_path(bag), 'bag digest', 64).decode('ascii')
                if len(text) == 64:
                    known[bag] = bytes.fromhex(text)
            except (ValueError, OSError, TypeError):
                continue
        return known

    def remember(self, digests: Dict[str, bytes]) -> None:
        """Keep each bag's digest under its files' signature (see :meth:`known_digests`)."""
        for bag, digest in digests.items():
            try:
                write_atomic(self._stat_path(bag), digest.hex(), 'bag digest')
            except (ValueError, OSError):
                pass

    def time_ranges(self, tasks: Sequence[Task], digests: Dict[str, bytes]
                    ) -> Dict[Tuple[str, str], Tuple[int, int]]:
        """Return (bag, topic) -> the topic's first and last bag time (ns), as kept.

        A range is kept by the bag's digest and the topic (:meth:`remember_ranges`): a bag
        unchanged since (``digests``, :meth:`known_digests`) is not opened to cut it into
        chunks again.
        """
        ranges: Dict[Tuple[str, str], Tuple[int, int]] = {}
        for bag, topic in dict.fromkeys((t.bag, t.option('topic')) for t in tasks):
            if bag not in digests:
                continue
            try:
                text = read_regular(self._range_path(digests[bag], topic), 'time range', 64)
                first, last = (int(x) for x in text.decode('ascii').split())
            except (ValueError, OSError, TypeError):
                continue
            if first <= last:
                ranges[bag, topic] = (first, last)
        return ranges

    def remember_ranges(self, ranges: Dict[Tuple[str, str], Tuple[int, int]],
                        digests: Dict[str, bytes]) -> None:
        """Keep each bag's time range under its digest and topic (see :meth:`time_ranges`)."""
        for (bag, topic), (first, last) in ranges.items():
            if bag not in digests:
                continue
            try:
                write_atomic(self._range_path(digests[bag], topic), f'{first} {last}',
                             'time range')
            except (ValueError, OSError):
                pass

    def _range_path(self, digest: bytes, topic: str) -> str:
        if not self.folder:
            raise ValueError('no cache')
        folder = os.path.join(self.folder, 'ranges')
        os.makedirs(folder, exist_ok=True)
        return os.path.join(folder, hashlib.sha256(digest + b'\0' + topic.encode()).hexdigest())

    def _stat_path(self, bag: str) -> str:
        if not self.folder:
            raise ValueError('no cache')
        files = ([os.path.join(bag, f) for f in sorted(os.listdir(bag))]
                 if os.path.isdir(bag) else [bag])
        h = hashlib.sha256(os.path.realpath(bag).encode())
        for name in files:
            info = os.stat(name)
            if os.path.isfile(name):
                h.update(f'\0{os.path.basename(name)}\0{info.st_size}\0{info.st_mtime_ns}'
                         f'\0{info.st_ctime_ns}\0{info.st_ino}\0{info.st_dev}'.encode())
        folder = os.path.join(self.folder, 'bags')
        os.makedirs(folder, exist_ok=True)
        return os.path.join(folder, h.hexdigest())

    def put(self, key: str, result: Dict) -> None:
        """Store ``result`` (a refused bag is not stored: it is tried again next time).

        What cannot be stored (a folder where the entry goes, a full disk) is left out: the
        task runs again next time.
        """
        if not (self.folder and result.get('ok')):
            return
        kept = {k: v for k, v in result.items() if k not in PER_RUN}
        entry = {'version': VERSION, 'key': key, 'check': checksum(kept), 'result': kept}
        try:
            write_atomic(self.path(key), json.dumps(entry), 'cache entry')
        except ValueError:
            pass


#: Largest cache entry read (a 50-joint robot's sums are ~100 kB).
ENTRY_LIMIT = 16 << 20
#: What a result holds of the current run, not of the content: never stored in the cache.
PER_RUN = ('robot', 'bag', 'where', 'cached')


def checksum(result: Dict) -> str:
    """Return the SHA-256 of a result as JSON with sorted keys (what a cache entry keeps)."""
    return hashlib.sha256(json.dumps(result, sort_keys=True).encode()).hexdigest()


def valid(result: Dict) -> bool:
    """Whether a result has the shape :func:`~.task.process` gives and finite numbers."""
    try:
        joints = result['joints']
        n = len(joints)
        sums = result['sums']
        shapes = {'G': (n, 3, 3), 'rr': (n,), 'R': (n, 4, 4)}
        ok = (result['ok'] is True and n > 0 and all(isinstance(j, str) for j in joints)
              and isinstance(sums['N'], int) and sums['N'] >= 0
              and isinstance(result['samples'], int) and result['samples'] >= 0
              and isinstance(result['messages'], int)
              and np.isfinite(float(result['peak_rss_mb'])))
        for name, shape in shapes.items():
            a = np.asarray(sums[name], dtype=float)
            ok = ok and a.shape == shape and bool(np.isfinite(a).all())
        if result['samples']:
            numbers = np.asarray([result['start'], result['end'], result['seconds'],
                                  result['recorded']] + list(result['rms_residual']),
                                 dtype=float)
            ok = ok and numbers.shape == (4 + n,) and bool(np.isfinite(numbers).all())
        return bool(ok)
    except (KeyError, TypeError, ValueError):
        return False


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


def local_cluster(workers: Optional[int] = None, directory: Optional[str] = None):
    """Start a LocalCluster of ``workers`` processes (default: the cores), one thread each.

    ``directory``: Dask's local directory (its scratch space: the workers' files, spilled
    data), which the caller removes; by default Dask's own ``/tmp/dask-scratch-space``.

    Without a dashboard, and so without the workers' statistical profiler (it samples the
    running task's stack every 10 ms for the dashboard: 3-4 % of a worker's CPU here). Dask
    starts an HTTP server in the scheduler and each worker whatever the dashboard (by default
    the scheduler's on port 8787, serving pages of the cluster's workers and tasks): here it
    serves no page, on a free port of 127.0.0.1 (two runs at once do not compete for 8787). And
    without Dask's ``MALLOC_TRIM_THRESHOLD_`` in the workers' environment: set at all, it
    turns off glibc's adaptive mmap threshold, so every array over 128 kB is mapped and
    unmapped afresh, its pages faulted in each time (a task then takes 20-25 % more CPU).
    """
    import dask
    from distributed import LocalCluster
    n = workers or len(os.sched_getaffinity(0))
    settings = {'distributed.worker.profile.enabled': False,
                'distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_': None,
                'distributed.scheduler.http.routes': [], 'distributed.worker.http.routes': []}
    if directory:
        settings['temporary-directory'] = directory
    with dask.config.set(settings), _workers_ignore_ctrl_c():
        return LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                            dashboard_address=None, silence_logs=40,
                            local_directory=directory,
                            scheduler_kwargs={'dashboard_address': '127.0.0.1:0'})


@contextlib.contextmanager
def _workers_ignore_ctrl_c():
    """Start the worker processes with SIGINT ignored (an ignored signal stays so in a child).

    Ctrl-C reaches every process of the terminal's group: the command unwinds and closes the
    cluster; a worker would print its own KeyboardInterrupt traceback, one per worker.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    before = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, before)


def run_tasks(tasks: Sequence[Task], cache: Cache, client=None,
              progress: Optional[Callable[[Dict], None]] = None,
              digests: Optional[Dict[str, bytes]] = None) -> List[Dict]:
    """Return the result of every task, in the order of ``tasks``.

    Cached results are taken as they are, with the current task's robot and bag; the others
    run on ``client`` (a ``distributed.Client``) or, without one, here one after the other.
    A bag that cannot be hashed (missing, a symlink loop, unreadable) or a task the engine
    gives up on (a worker lost more often than allowed) is a failed bag with the reason.
    ``digests``: the bags' digests known already (:meth:`Cache.known_digests`).
    """
    known = dict(digests or {})
    digests = dict(known)
    if client is not None:
        digests.update(digests_on(client, [t for t in tasks if t.bag not in digests]))
    keys: List[Optional[str]] = []
    results: List[Optional[Dict]] = []
    for t in tasks:
        try:
            keys.append(content_key(t, digests))
        except (OSError, ValueError) as err:
            keys.append(None)
            results.append(unreadable(t, err))
            continue
        r = cache.get(keys[-1])
        results.append(None if r is None else dict(r, **_head(t), cached=True))
    cache.remember({bag: d for bag, d in digests.items() if bag not in known})
    todo = [i for i, r in enumerate(results) if r is None]
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


def pending_bags(tasks: Sequence[Task], cache: Cache, digests: Dict[str, bytes]) -> Set[str]:
    """Return the bags of the tasks not in ``cache`` (a bag not hashed yet: pending).

    A bag that cannot be hashed is not pending: its task fails without running.
    """
    pending = set()
    for t in tasks:
        try:
            if t.bag in digests and cache.get(content_key(t, dict(digests))) is not None:
                continue
        except (OSError, ValueError):
            continue
        pending.add(t.bag)
    return pending


def bag_bytes(bags: Iterable[str]) -> int:
    """Return the bytes of the bags (a bag that cannot be listed: 0)."""
    return sum(_bytes(bag) for bag in bags)


def cluster_size(workers: Optional[int]) -> Tuple[int, Optional[str]]:
    """Return the local cluster's worker count for ``--workers`` and a note if it was cut.

    Default: the cores this process may use. At most :data:`WORKERS_PER_CORE` a core: each
    worker is a process of its own (~100 MB before its first bag), and more of them only
    share the same cores.
    """
    cores = len(os.sched_getaffinity(0))
    bound = WORKERS_PER_CORE * cores
    if workers is None:
        return cores, None
    if workers > bound:
        return bound, (f'note: --workers {workers} is more than {WORKERS_PER_CORE} a core '
                       f'({cores} here): {bound} workers')
    return workers, None


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
        except (OSError, ValueError):       # missing, a loop, a FIFO or a device
            out.append(None)
    return out


def process_batch(tasks: Sequence[Task]) -> List[Dict]:
    """Run tasks one after the other (what a worker runs for one submission)."""
    return [process(t) for t in tasks]


def _head(task: Task) -> Dict:
    """Return what a result holds of the current run: the robot, the bag (and the chunk)."""
    head = {'robot': task.robot, 'bag': task.bag}
    if task.chunked:
        head['chunk'] = [task.start, task.stop]
    return head


def unreadable(task: Task, err: Exception) -> Dict:
    """Return the failed result of a bag that cannot be read to be hashed."""
    if isinstance(err, OSError):
        reason = f'{err.strerror or type(err).__name__} ({(err.filename or task.bag)!r})'
    else:
        reason = ' '.join(str(err).split())
    return dict(_head(task), ok=False, reason=f'cannot read the bag: {reason}')


def gave_up(task: Task, err: Exception) -> Dict:
    """Return the failed result of a task the engine gave up on (a worker lost too often)."""
    return dict(_head(task), ok=False,
                reason=f'the engine gave up on it: {type(err).__name__}: '
                       + ' '.join(str(err).split()))


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


def warm(client, local: bool = False) -> None:
    """Import what the tasks need on every worker (part of starting the cluster, not a bag).

    ``local``: the command's own cluster, whose workers also drop the heartbeat failure that
    closing it can make them log (:func:`quiet_closing`).
    """
    client.run(load_modules)
    if local:
        client.run(quiet_closing)


#: What a worker of a local cluster logs (ERROR, with a traceback) when its heartbeat finds
#: the scheduler gone: closing the cluster (after Ctrl-C too) closes the scheduler first.
HEARTBEAT_LOST = 'Failed to communicate with scheduler during heartbeat'


class _NotHeartbeatLost(logging.Filter):
    """Drop :data:`HEARTBEAT_LOST` records; let every other record through."""

    def filter(self, record: logging.LogRecord) -> bool:
        return not record.getMessage().startswith(HEARTBEAT_LOST)


def quiet_closing() -> None:
    """Keep a local worker from logging :data:`HEARTBEAT_LOST` (its scheduler is the command's).

    The command's scheduler goes only when the command closes it (or the command fails on its
    own, with its message): the record is a traceback on the terminal after ``interrupted``,
    never news. Every other record of the worker is kept.
    """
    logger = logging.getLogger('distributed.worker')
    if not any(isinstance(f, _NotHeartbeatLost) for f in logger.filters):
        logger.addFilter(_NotHeartbeatLost())


#: The modules a task imports when it first runs.
MODULES = ('threadpoolctl', 'spatial_dynamics.recordings.bags',
           'spatial_dynamics.recordings.recording', 'spatial_dynamics.fleet.task')


def load_modules() -> None:
    """Import :data:`MODULES` (what :func:`warm` runs on each worker)."""
    for name in MODULES:
        importlib.import_module(name)
