# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Every series of a fleet is judged or said not judged; wear within the baseline is seen."""

import os
import shutil

import numpy as np
import pytest

from spatial_dynamics.fleet import command, main
from spatial_dynamics.fleet.drift import detect

DAY = 86400.0


@pytest.fixture(scope='module')
def worn_early(tmp_path_factory):
    """Three robots, eight days; r02's elbow friction doubles from day 2 (in the baseline)."""
    pytest.importorskip('mujoco')
    from spatial_dynamics.tools.fleet_demo import make_fleet
    out = str(tmp_path_factory.mktemp('worn_early'))
    try:
        make_fleet(out, robots=3, days=8, seconds=2.0, wear=(1, 2, 1, 0.0, 1.0))
    except RuntimeError as err:
        pytest.skip(str(err))
    return out


def run(argv, capsys):
    status = main(argv + ['--serial', '--no-plots'])
    return status, capsys.readouterr().out


def lines(out, head):
    return [line for line in out.splitlines() if line.startswith(head)]


def test_friction_doubling_from_day_two_of_a_five_day_baseline_is_flagged(worn_early, tmp_path,
                                                                          capsys):
    status, out = run([worn_early, '--out', str(tmp_path / 'o'), '--baseline-days', '5'],
                      capsys)
    assert status == command.DRIFTED, out
    drifts = lines(out, 'drift:')
    assert any(d.startswith('drift: r02 elbow_joint: Coulomb friction +')
               and 'since 2026-10-02' in d for d in drifts), out
    assert all(d.startswith('drift: r02 elbow_joint') for d in drifts), out
    assert 'no drift' not in out


def subset(fleet, folder, robots, days=None):
    for robot in robots:
        os.makedirs(folder / robot)
        shutil.copy(os.path.join(fleet, robot, 'robot.urdf'), folder / robot)
        for bag in sorted(os.listdir(os.path.join(fleet, robot)))[:days]:
            if bag.startswith('day'):
                shutil.copytree(os.path.join(fleet, robot, bag), folder / robot / bag)
    return str(folder)


def test_a_fleet_shorter_than_its_baseline_is_not_judged_and_never_reads_no_drift(
        worn_early, tmp_path, capsys):
    short = subset(worn_early, tmp_path / 'short', ['r01', 'r02', 'r03'], days=3)
    status, out = run([short, '--out', str(tmp_path / 'o'), '--baseline-days', '5'], capsys)
    assert status == command.NOT_JUDGED, out
    assert 'no drift' not in out and not lines(out, 'drift:')
    assert 'nothing judged' in out
    not_judged = lines(out, 'not judged: ')
    assert len(not_judged) == 3 * 6      # each robot's six joints, their three parameters
    assert all('no estimate after its first 5 days (3 in all)' in line for line in not_judged)
    with open(tmp_path / 'o' / 'drift.txt') as f:
        assert f.read().splitlines() == out.splitlines()[:-1]


def test_healthy_robots_do_not_change_the_verdict_on_the_worn_one(
        worn_early, tmp_path, capsys):
    verdicts = []
    for robots in (['r02'], ['r01', 'r02'], ['r01', 'r02', 'r03']):
        folder = subset(worn_early, tmp_path / '_'.join(robots), robots)
        status, out = run([folder, '--out', str(tmp_path / ('o' + '_'.join(robots)))],
                          capsys)
        assert status == command.DRIFTED
        verdicts.append(lines(out, 'drift: r02'))
    assert verdicts[0] and verdicts[0] == verdicts[1] == verdicts[2]


def series(robot, joint, values, sigma, start=0.0):
    return [{'robot': robot, 'joint': joint, 'parameter': 'friction', 'start_s': start + k * DAY,
             'value': float(v), 'sigma': float(s)}
            for k, (v, s) in enumerate(zip(values, np.broadcast_to(sigma, len(values))))]


def test_one_series_drifting_in_its_baseline_does_not_blind_another():
    # j1 rises 20 % a day from day 2: its baseline scatters ~10⁴ times its σ; pooled over the
    # fleet that scatter hid j2's step of 12σ after its baseline
    rng = np.random.default_rng(5)
    days = 10
    ramp = 1.0 * (1.0 + 0.2 * np.maximum(np.arange(days) - 0, 0)) + rng.normal(0, 1e-4, days)
    step = 2.0 + 0.01 * rng.normal(size=days) + np.where(np.arange(days) >= 6, 0.12, 0.0)
    rows = series('r1', 'j1', ramp, 1e-4) + series('r1', 'j2', step, 0.01)
    got = detect(rows, 5.0)
    flagged = {(d.joint, d.within_baseline) for d in got.drifts}
    assert flagged == {('j1', True), ('j2', False)}
    assert got.judged == 2 and not got.not_judged


def test_a_joint_that_never_moved_is_not_judged_with_the_reason():
    rows = series('r1', 'j1', [np.nan] * 8, np.nan) + series('r1', 'j2', [1.0] * 8, 0.01)
    got = detect(rows, 5.0)
    assert got.judged == 1 and not got.drifts
    assert 'did not move' in got.not_judged['r1', 'j1', 'friction']


def test_a_robot_whose_bags_all_failed_is_not_judged_and_the_status_says_so(
        worn_early, tmp_path, capsys):
    folder = subset(worn_early, tmp_path / 'r01', ['r01'])
    urdf = os.path.join(worn_early, 'r01', 'robot.urdf')
    (tmp_path / 'junk.db3').write_bytes(b'not a bag')
    path = tmp_path / 'm.csv'
    path.write_text(f'robot,urdf,bag\nr01,{urdf},{folder}/r01/day*\n'
                    f'r09,{urdf},{tmp_path}/gone.db3\nr09,{urdf},{tmp_path}/junk.db3\n')
    status, out = run([str(path), '--out', str(tmp_path / 'o')], capsys)
    assert len(lines(out, 'failed: r09')) == 2, out
    assert lines(out, 'not judged: r09: ') == [
        'not judged: r09: all 2 of its bags failed (see failed: below)'], out
    assert 'no drift among the 18 series judged; 1 robot with no usable bag not judged' in out
    assert status == command.NOT_JUDGED
    # r01 alone, every series judged: the same verdict on it, and "no drift"
    status, alone = run([folder, '--out', str(tmp_path / 'o1')], capsys)
    assert status == 0 and 'no drift' in lines(alone, 'no drift')


def test_a_still_bag_after_the_baseline_is_not_judged_as_still_not_as_missing():
    values = [1.0, 1.01, 0.99, 1.0, 1.02, np.nan, np.nan]
    rows = series('r1', 'j1', values, [0.01] * 5 + [np.nan] * 2)
    reason = detect(rows, 5.0).not_judged['r1', 'j1', 'friction']
    assert reason == ('no estimate after its first 5 days: none of its 2 bags after them '
                      'gives one (the joint did not move enough to determine it)')
    reason = detect(rows[:6], 5.0).not_judged['r1', 'j1', 'friction']
    assert 'its one bag after them gives none' in reason
    # and no bag at all after the baseline says that
    assert detect(rows[:5], 5.0).not_judged['r1', 'j1', 'friction'] == (
        'no estimate after its first 5 days (5 in all)')


def test_a_count_of_one_is_singular():
    rows = series('r1', 'j1', [1.0, np.nan], 0.01)
    assert detect(rows[:1], 5.0).not_judged['r1', 'j1', 'friction'] == (
        '1 estimate in its first 5 days; a baseline needs 3')
    rows = series('r1', 'j1', [np.nan], np.nan)
    assert detect(rows, 5.0).not_judged['r1', 'j1', 'friction'] == (
        'no estimate in its one bag (the joint did not move enough to determine it)')
