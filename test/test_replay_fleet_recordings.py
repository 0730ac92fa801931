# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A fleet's bags as recorded: dated by their bag time, read whole or said not to be."""

import csv
import os
import shutil

import numpy as np
import pytest

from spatial_dynamics.fleet import command, main
from spatial_dynamics.recordings import bags

ONSET = 6           # the first day of wear (1-based): r01's elbow_joint


@pytest.fixture(scope='module')
def worn(tmp_path_factory):
    """One robot, ten days; its elbow friction rises 10 % a day from day 6."""
    pytest.importorskip('mujoco')
    from spatial_dynamics.tools.fleet_demo import make_fleet
    out = str(tmp_path_factory.mktemp('worn'))
    try:
        make_fleet(out, robots=1, days=10, seconds=2.0, wear=(0, 2, ONSET - 1, 0.1))
    except RuntimeError as err:
        pytest.skip(str(err))
    return out


def run(argv, capsys):
    status = main([str(a) for a in argv] + ['--serial', '--no-plots'])
    return status, capsys.readouterr().out


def dates(out):
    with open(os.path.join(out, 'fleet.csv'), newline='') as f:
        return sorted({(os.path.basename(r['bag']), r['start']) for r in csv.DictReader(f)})


def on_sim_clock(src, dst, start_s=5.0, recorder_too=False, storage='sqlite3'):
    """Copy bag ``src`` to ``dst`` with header stamps from ``start_s`` (a simulation's clock).

    The bag times (when each message was recorded) stay the wall clock's, unless
    ``recorder_too`` (a recorder on the simulated clock as well).
    """
    reader = bags.open_reader(src)
    try:
        _, received = bags.read_raw(reader, '/joint_states', bags.JOINT_STATE)
    finally:
        reader.close()
    js = bags.read_joint_states(src, '/joint_states', _names(src))
    stamp = np.round((js.stamp - js.stamp[0] + start_s) * 1e9).astype(np.int64)
    block = bags.encode_joint_states(js.names, stamp, js.position, js.velocity, js.effort)
    received = stamp if recorder_too else received
    bags.write_bag(dst, storage, [('/joint_states', bags.JOINT_STATE, received,
                                   [x.tobytes() for x in block])])


def _names(bag):
    reader = bags.open_reader(bag)
    try:
        raw, _ = bags.read_raw(reader, '/joint_states', bags.JOINT_STATE)
    finally:
        reader.close()
    return tuple(bags.typestore().deserialize_cdr(raw[0], bags.JOINT_STATE).name)


def copy(fleet, folder, sim_days):
    shutil.copytree(fleet, folder)
    for d in sim_days:
        bag = os.path.join(folder, 'r01', f'day{d:02d}')
        shutil.rmtree(bag)
        on_sim_clock(os.path.join(fleet, 'r01', f'day{d:02d}'), bag)
    return folder


@pytest.mark.parametrize('sim_days', [range(1, 11), [3]], ids=['every bag', 'one bag'])
def test_bags_with_stamps_on_a_simulated_clock_are_dated_by_when_they_were_recorded(
        worn, tmp_path, capsys, sim_days):
    status, want = run([worn, '--out', tmp_path / 'wall'], capsys)
    assert status == command.DRIFTED
    drifts = [line for line in want.splitlines() if line.startswith('drift:')]
    assert len(drifts) == 1 and drifts[0].startswith('drift: r01 elbow_joint: Coulomb ')
    since = int(drifts[0].split('since 2026-10-')[1][:2])
    assert ONSET <= since <= ONSET + 3
    sim = copy(worn, tmp_path / 'sim', sim_days)
    status, got = run([sim, '--out', tmp_path / 'o'], capsys)
    assert status == command.DRIFTED, got
    assert [line for line in got.splitlines() if line.startswith('drift:')] == drifts
    assert dates(tmp_path / 'o') == dates(tmp_path / 'wall')
    assert all(start.startswith('2026-10-') for _, start in dates(tmp_path / 'o'))


def test_a_bag_recorded_on_a_simulated_clock_is_dated_by_it_and_said(worn, tmp_path, capsys):
    folder = copy(worn, tmp_path / 'sim', [])
    shutil.rmtree(folder / 'r01' / 'day03')
    on_sim_clock(os.path.join(worn, 'r01', 'day03'), folder / 'r01' / 'day03',
                 recorder_too=True)
    status, out = run([folder, '--out', tmp_path / 'o'], capsys)
    notes = [line for line in out.splitlines() if line.startswith('note:')]
    day03 = str(folder / 'r01' / 'day03')
    assert notes == [f'note: {command.EARLY} (1): r01 {day03!r} on 1970-01-01'], out
    assert ('day03', '1970-01-01T00:00:05+00:00') in dates(tmp_path / 'o')


def damaged(folder):
    """Overwrite 4000 bytes a third into the MCAP file of bag ``folder``; return its path."""
    path = os.path.join(folder, [f for f in os.listdir(folder) if f.endswith('.mcap')][0])
    with open(path, 'r+b') as f:
        f.seek(os.path.getsize(path) // 3)
        f.write(b'\xff' * 4000)
    return path


def test_a_damaged_mcap_is_refused_saying_how_much_of_it_could_be_read(worn, tmp_path, capsys):
    source = os.path.join(worn, 'r01', 'day01')
    listed = len(bags.read_joint_states(source, '/joint_states', _names(source)).stamp)
    folder = copy(worn, tmp_path / 'f', [])
    bag = folder / 'r01' / 'day11'
    on_sim_clock(source, bag, storage='mcap')
    whole = bags.read_joint_states(str(bag), '/joint_states', _names(source))
    assert len(whole.stamp) == listed              # read whole before the damage
    mcap = damaged(bag)
    for path in (str(bag), mcap):                  # metadata.yaml's count, the MCAP summary's
        with pytest.raises(bags.BagError) as err:
            bags.read_joint_states(path, '/joint_states', _names(source))
        assert f"of the {listed} messages of '/joint_states'" in str(err.value)
        assert 'damaged' in str(err.value)
    status, out = run([folder, '--out', tmp_path / 'o'], capsys)
    failed = [line for line in out.splitlines() if line.startswith('failed:')]
    assert len(failed) == 1 and 'day11' in failed[0] and f'of the {listed} messages' in failed[0]
    assert '(0 from the cache, 1 failed)' in out
