# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The cluster gets batches of consecutive bags, big enough to make the engine's cost small."""

import os

import pytest

from spatial_dynamics.fleet import engine
from spatial_dynamics.fleet.task import Task


def bags_of(folder, sizes):
    tasks = []
    for k, size in enumerate(sizes):
        path = os.path.join(folder, f'b{k:03d}.db3')
        with open(path, 'wb') as f:
            f.truncate(size)
        tasks.append(Task('r', 'robot.urdf', path))
    return tasks


def test_many_short_bags_go_in_a_few_batches_of_consecutive_bags(tmp_path):
    tasks = bags_of(tmp_path, [6 << 20] * 120)      # a minute at 500 Hz each
    todo = list(range(3, 120))
    got = engine.batches(tasks, todo, workers=2)
    assert [i for b in got for i in b] == todo
    assert 8 * 2 <= len(got) <= 8 * 2 + 2
    assert all(len(b) >= 6 for b in got[:-1])


def test_big_bags_and_chunks_go_one_by_one_and_a_chunk_weighs_its_share(tmp_path):
    big = bags_of(tmp_path, [engine.BATCH_BYTES + 1] * 3)
    assert engine.batches(big, [0, 1, 2], workers=1) == [[0], [1], [2]]
    long, = bags_of(tmp_path / '..', [40 * engine.BATCH_BYTES])
    chunks = [Task('r', 'robot.urdf', long.bag, start=k, stop=k + 1) for k in range(80)]
    got = engine.batches(chunks, list(range(80)), workers=2)
    assert [len(b) for b in got] == [2] * 40


def test_a_small_fleet_still_gives_every_worker_several_batches(tmp_path):
    tasks = bags_of(tmp_path, [1000] * 36)
    assert len(engine.batches(tasks, list(range(36)), workers=2)) == 18


def test_the_local_cluster_workers_run_no_profiler_and_keep_mallocs_own_thresholds(
        monkeypatch):
    # nobody reads the profile (no dashboard) and it samples the running task every 10 ms;
    # MALLOC_TRIM_THRESHOLD_ (Dask's default) makes every large numpy array an mmap + munmap.
    # A default LocalCluster started earlier in this process leaves it in os.environ.
    pytest.importorskip('distributed')
    monkeypatch.delenv('MALLOC_TRIM_THRESHOLD_', raising=False)
    from distributed import Client
    with engine.local_cluster(1) as cluster, Client(cluster) as client:
        got = client.run(lambda: (__import__('dask').config.get(
            'distributed.worker.profile.enabled'), 'MALLOC_TRIM_THRESHOLD_' in os.environ))
    assert list(got.values()) == [(False, False)]


def test_the_workers_hash_the_bags_and_a_bag_they_cannot_read_is_left_out(tmp_path,
                                                                          monkeypatch):
    """The content keys' hashes come from the workers (the client hashes nothing itself)."""
    pytest.importorskip('distributed')
    from distributed import Client
    from spatial_dynamics.fleet import task as task_module
    tasks = bags_of(tmp_path, [1000 + k for k in range(9)])
    for k, t in enumerate(tasks):
        with open(t.bag, 'wb') as f:
            f.write(bytes([k]) * (1000 + k))
    expected = {t.bag: task_module.bag_digest(t.bag) for t in tasks}
    missing = Task('r', 'robot.urdf', str(tmp_path / 'gone.db3'))

    def not_here(path):
        raise AssertionError(f'hashed {path} in the client')
    monkeypatch.setattr(engine, 'bag_digest', not_here)
    monkeypatch.setattr(task_module, 'bag_digest', not_here)
    with engine.local_cluster(2) as cluster, Client(cluster) as client:
        got = engine.digests_on(client, tasks + [missing])
    assert got == expected
