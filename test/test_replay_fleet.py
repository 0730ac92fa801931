# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The fleet command: sums that add, the same results on every engine, the drift found."""

import json
import os
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from spatial_dynamics.fleet import command, main
from spatial_dynamics.fleet.engine import Cache, run_tasks
from spatial_dynamics.fleet.sums import normal_sums, solve, total
from spatial_dynamics.drives import identify

ONSET = 6           # the first day of wear (1-based): r02's elbow_joint


@pytest.mark.parametrize('noise', [0.05, 1e-5])
def test_sums_of_chunks_equal_the_fit_of_the_concatenation(noise):
    # noise 1e-5 N m on torques of ~1.5 N m: the residual sum of squares as rᵀr - θᵀh would
    # be off by ~eps (|r| / 1e-5)² ≈ 5e-6 (it was: 2.9e-5 here); from the triangular factor
    # of [A r] by ~eps |r| / 1e-5 ≈ 3e-11 at worst
    rng = np.random.default_rng(3)
    N, n = 6000, 3
    t = np.arange(N) / 500.0
    qd = np.sin(np.outer(t, [1.3, 2.1, 0.7])) + 0.3 * np.sin(np.outer(t, [9.0, 7.0, 11.0]))
    qdd = np.gradient(qd, t, axis=0)
    truth = np.array([[0.5, 1.0, 0.05], [0.6, 1.2, 0.06], [0.7, 1.4, 0.07]])
    r = (truth[:, 0] * qd + truth[:, 1] * np.tanh(qd / 0.01) + truth[:, 2] * qdd
         + rng.normal(0.0, noise, (N, n)))
    cuts = [0, 700, 2500, 2501, 4100, N]
    parts = [normal_sums(r[a:b], qd[a:b], qdd[a:b], 0.01) for a, b in zip(cuts, cuts[1:])]
    got = solve(total(parts), ['a', 'b', 'c'])
    want = identify(r, qd, qdd, 0.01, ['a', 'b', 'c'])
    for name in ('damping', 'friction', 'armature', 'rms_after', 'sigma'):
        np.testing.assert_allclose(getattr(got, name), getattr(want, name), rtol=1e-10)


@pytest.fixture(scope='module')
def fleet(tmp_path_factory):
    pytest.importorskip('mujoco')
    from spatial_dynamics.tools.fleet_demo import make_fleet
    out = str(tmp_path_factory.mktemp('fleet'))
    try:
        make_fleet(out, robots=3, days=12, seconds=2.0, wear=(1, 2, ONSET - 1, 0.05))
    except RuntimeError as err:
        pytest.skip(str(err))
    return out


def run(argv, capsys):
    status = main(argv)
    return status, capsys.readouterr().out


def test_serial_run_flags_the_worn_joint_and_nothing_else(fleet, tmp_path, capsys):
    status, out = run([fleet, '--out', str(tmp_path / 'o'), '--serial'], capsys)
    assert status == command.DRIFTED
    drifts = [line for line in out.splitlines() if line.startswith('drift:')]
    assert len(drifts) == 1, out
    assert drifts[0].startswith('drift: r02 elbow_joint: Coulomb friction +')
    since = int(drifts[0].split('since 2026-10-')[1][:2])
    assert ONSET <= since <= ONSET + 3
    for name in ('fleet.csv', 'robots.csv', 'drift.txt', 'trend_r01.png'):
        assert os.path.getsize(tmp_path / 'o' / name) > 0
    # a re-run takes every bag from the cache, with the same numbers
    status, again = run([fleet, '--out', str(tmp_path / 'o'), '--serial', '--no-plots'],
                        capsys)
    assert status == command.DRIFTED and '(36 from the cache, 0 failed)' in again
    assert again.split('\n', 1)[1] == out.split('\n', 1)[1].replace(
        ', trend_r01.png, trend_r02.png, trend_r03.png', '')


def fleet_csv(folder):
    with open(os.path.join(folder, 'fleet.csv')) as f:
        return f.read()


@pytest.mark.slow
def test_local_cluster_and_a_real_scheduler_equal_the_serial_run(fleet, tmp_path, capsys):
    pytest.importorskip('distributed')
    run([fleet, '--out', str(tmp_path / 's'), '--serial', '--no-plots'], capsys)
    status, _ = run([fleet, '--out', str(tmp_path / 'l'), '--workers', '2', '--no-plots'],
                    capsys)
    assert status == command.DRIFTED
    assert fleet_csv(tmp_path / 'l') == fleet_csv(tmp_path / 's')
    # The scheduler picks its own port and writes its address to a file: a port probed free
    # here and given to it could be taken first by a worker's own listener (a CI run's
    # client waited 60 s on a port that answered but was no scheduler)
    address_file = tmp_path / 'scheduler.json'
    procs = [subprocess.Popen([sys.executable, '-m', 'distributed.cli.dask_scheduler', '--host',
                               '127.0.0.1', '--port', '0', '--dashboard-address', ':0',
                               '--scheduler-file', str(address_file)],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        deadline, address = time.monotonic() + 120, None
        while address is None:
            assert procs[0].poll() is None, 'the scheduler exited'
            assert time.monotonic() < deadline, 'the scheduler wrote no address in 120 s'
            try:        # absent, or being written
                address = json.loads(address_file.read_text())['address']
            except (OSError, ValueError, KeyError):
                time.sleep(0.1)
        for _ in range(2):
            procs.append(subprocess.Popen(
                [sys.executable, '-m', 'distributed.cli.dask_worker', address,
                 '--nthreads', '1', '--dashboard-address', ':0'],
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        from distributed import Client
        with Client(address, timeout=60) as client:
            client.wait_for_workers(2, timeout=120)
        status, _ = run([fleet, '--out', str(tmp_path / 'r'), '--scheduler', address,
                         '--no-plots'], capsys)
    finally:
        for p in procs:
            p.send_signal(signal.SIGINT)
        for p in procs:
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                p.kill()
    assert status == command.DRIFTED
    assert fleet_csv(tmp_path / 'r') == fleet_csv(tmp_path / 's')


@pytest.mark.slow
def test_a_killed_worker_is_retried_and_the_results_are_the_same(fleet, tmp_path):
    pytest.importorskip('distributed')
    from distributed import Client, LocalCluster
    from spatial_dynamics.fleet.manifest import scan_folder
    tasks = scan_folder(fleet, None)
    serial = run_tasks(tasks, Cache(None))
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        pids = list(client.run(os.getpid).values())
        killed = []

        def kill_one(result):
            if not killed:
                os.kill(pids[0], signal.SIGKILL)
                killed.append(pids[0])
        results = run_tasks(tasks, Cache(None), client, kill_one)
    assert killed
    assert [r['sums'] for r in results] == [r['sums'] for r in serial]


def test_a_bad_bag_is_one_line_and_the_rest_finish(fleet, tmp_path, capsys):
    folder = tmp_path / 'fleet'
    shutil.copytree(os.path.join(fleet, 'r01'), folder / 'r01')
    (folder / 'r01' / 'broken.db3').write_bytes(b'not a bag')
    status, out = run([str(folder), '--out', str(tmp_path / 'o'), '--serial', '--no-plots'],
                      capsys)
    assert status == 0
    failed = [line for line in out.splitlines() if line.startswith('failed:')]
    assert len(failed) == 1 and 'broken.db3' in failed[0]
    assert '13 bags of 1 robot,' in out and '1 failed' in out


def test_a_missing_manifest_is_refused(tmp_path, capsys):
    assert main([str(tmp_path / 'none.csv'), '--out', str(tmp_path / 'o')]) == 1
    assert 'error: manifest' in capsys.readouterr().err


def test_replay_fleet_is_the_fleet_command(fleet, tmp_path, capsys):
    """``replay fleet`` (the subcommand) writes what ``python -m spatial_dynamics.fleet`` does."""
    from spatial_dynamics.replay.__main__ import main as replay
    status, out = run([fleet, '--out', str(tmp_path / 'a'), '--serial', '--no-plots'], capsys)
    assert replay(['fleet', fleet, '--out', str(tmp_path / 'b'), '--serial',
                   '--no-plots']) == status == command.DRIFTED
    assert fleet_csv(tmp_path / 'a') == fleet_csv(tmp_path / 'b')
    assert replay(['fleet', str(tmp_path / 'missing.yaml'), '--out', str(tmp_path / 'c'),
                   '--serial']) == 1
