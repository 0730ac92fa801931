# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A long bag cut into chunk tasks: the same fit as the whole bag, bounded messages per task."""

import os

import numpy as np
import pytest

from benchmarks.fleet import arm_urdf, synthetic_bag, T0
from spatial_dynamics.fleet import command, main
from spatial_dynamics.fleet.chunks import merge, split
from spatial_dynamics.fleet.engine import Cache, run_tasks
from spatial_dynamics.fleet.sums import solve, Sums
from spatial_dynamics.fleet.task import process, Task
from spatial_dynamics.drives import PARAMETERS

RATE = 500.0


@pytest.fixture(scope='module')
def robot(tmp_path_factory):
    pytest.importorskip('rosbags')
    folder = tmp_path_factory.mktemp('chunks')
    urdf = str(folder / 'robot.urdf')
    with open(urdf, 'w') as f:
        f.write(arm_urdf())
    return folder, urdf


def bag(robot, name, seconds, storage='sqlite3', **kw):
    folder, urdf = robot
    path = str(folder / name)
    if not os.path.exists(path):
        synthetic_bag(path, arm_urdf(), seconds, RATE, T0, seed=5, storage=storage, **kw)
    return Task('r1', urdf, path)


def fit(result):
    return solve(Sums.from_dict(result['sums']), result['joints'])


@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
def test_a_chunked_bag_has_the_fit_of_the_whole_bag(robot, storage):
    task = bag(robot, f'long_{storage}', 47.3, storage)
    whole = process(task)
    assert whole['ok'] and 'chunk' not in whole
    parts, owner = split([task], 10.0)
    assert len(parts) == 5 and owner == [0] * 5
    assert parts[0].start is None and parts[-1].stop is None
    results = [process(p) for p in parts]
    assert [r['ok'] for r in results] == [True] * 5
    merged, = merge([task], owner, results)
    assert merged['chunks'] == 5
    # each sample in exactly one chunk: the same samples, the same span of stamps
    assert merged['samples'] == whole['samples'] == sum(r['samples'] for r in results)
    assert merged['start'] == whole['start'] and merged['seconds'] == whole['seconds']
    got, want = fit(merged), fit(whole)
    for name in PARAMETERS + ('rms_after', 'sigma'):
        np.testing.assert_allclose(getattr(got, name), getattr(want, name), rtol=1e-10)
    np.testing.assert_allclose(merged['rms_residual'], whole['rms_residual'], rtol=1e-10)


def test_stamps_on_another_clock_than_the_bag_are_owned_by_bag_time(robot):
    # sim time: header stamps start at 0 while the bag times are the wall clock's
    task = bag(robot, 'sim_time', 31.0, latency_ns=T0)
    whole = process(task)
    parts, owner = split([task], 10.0)
    merged, = merge([task], owner, [process(p) for p in parts])
    assert merged['chunks'] == 4 and merged['samples'] == whole['samples']
    np.testing.assert_allclose(fit(merged).friction, fit(whole).friction, rtol=1e-10)


def test_a_chunk_holds_the_same_messages_whatever_the_bag_length(robot):
    held = []
    for seconds in (40.0, 100.0):
        task = bag(robot, f'length_{seconds:g}', seconds)
        parts, _ = split([task], 10.0)
        results = [process(p) for p in parts]
        held.append(max(r['messages'] for r in results))
        # a chunk holds its 10 s and a margin each side, not the bag
        assert held[-1] <= (10.0 + 2 * 1.0) * RATE + 2
        assert process(task)['messages'] == seconds * RATE
    assert held[0] == held[1]


def test_the_command_cuts_long_bags_and_reports_the_same_numbers(robot, tmp_path, capsys):
    folder, urdf = robot
    bag(robot, 'long_sqlite3', 47.3)
    manifest = tmp_path / 'm.csv'
    manifest.write_text(f'robot,urdf,bag\nr1,{urdf},{folder / "long_sqlite3"}\n')
    outs = []
    for chunk in ('0', '10'):
        out = tmp_path / f'o{chunk}'
        # one bag: no series has a baseline and a bag after it, so none is judged
        assert main([str(manifest), '--out', str(out), '--serial', '--no-plots',
                     '--chunk', chunk]) == command.NOT_JUDGED
        outs.append(np.genfromtxt(out / 'robots.csv', delimiter=',', names=True,
                                  dtype=None, encoding='utf-8'))
    capsys.readouterr()
    np.testing.assert_allclose(outs[1]['value'], outs[0]['value'], rtol=1e-10)
    assert list(outs[1]['samples']) == list(outs[0]['samples'])


@pytest.mark.parametrize('prog', ['fleet', 'replay'])
@pytest.mark.parametrize('value', ['2', 'inf', 'nan', '-1', 'ten'])
def test_a_chunk_that_is_not_a_length_is_refused(tmp_path, capsys, prog, value):
    from spatial_dynamics.replay.__main__ import main as replay
    argv = [str(tmp_path), '--chunk', value]
    with pytest.raises(SystemExit) as exit:
        main(argv) if prog == 'fleet' else replay(['fleet'] + argv)
    assert exit.value.code == 2
    assert (f"--chunk: '{value}': 0 (one task per bag) or a number of seconds >= 10"
            in capsys.readouterr().err)


def test_the_engine_runs_chunks_like_bags(robot):
    task = bag(robot, 'long_sqlite3', 47.3)
    parts, owner = split([task], 10.0)
    serial = merge([task], owner, run_tasks(parts, Cache(None)))
    assert serial[0]['chunks'] == 5 and serial[0]['ok']


def test_a_task_runs_the_kernels_and_filters_on_one_thread_of_its_own(robot, monkeypatch):
    # each worker has one core: the kernels' batch threads and the derivatives' filter threads
    # would oversubscribe it (BLAS is held to one thread apart); the limit ends with the task
    import spatial_dynamics
    from spatial_dynamics.backends import compiled
    from spatial_dynamics.recordings import differentiate
    monkeypatch.setattr(compiled, 'THREADS', 4)
    seen = {}
    rnea, savgol_many = spatial_dynamics.rnea, differentiate.savgol_many

    def rnea_seen(*args, **kw):
        seen['rnea'] = compiled.THREADS
        return rnea(*args, **kw)

    def savgol_seen(*args, **kw):
        seen['savgol'] = compiled.THREADS
        return savgol_many(*args, **kw)

    monkeypatch.setattr(spatial_dynamics, 'rnea', rnea_seen)
    monkeypatch.setattr(differentiate, 'savgol_many', savgol_seen)
    result = process(bag(robot, 'long_sqlite3', 47.3))
    assert result['ok'] and seen == {'rnea': 1, 'savgol': 1}
    assert compiled.THREADS == 4
