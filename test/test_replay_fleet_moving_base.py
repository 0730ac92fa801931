# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A fleet of mobile manipulators: each bag's base motion from its own odometry or IMU topic.

The bag of ``test_replay_moving_base.py`` (a UR5 on a base that sways, yaws and rolls; its
effort the moving-base rigid body plus known damping, Coulomb friction and armature; the
base's odometry at 100 Hz and an IMU at 500 Hz in the same bag). With the manifest option
``base_odometry`` or ``base_imu`` a fleet task recovers the drives as ``replay identify
--base-odometry/--base-imu`` does; without it, the residual is the base's acceleration times
the arm. A chunk reads the base topic over its own time range and the chunks add up to the
whole bag's fit.
"""

import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(__file__))
from conftest import robot_urdf_path  # noqa: E402

pytest.importorskip('rosbags')
from test_replay_moving_base import ARMATURE, DAMPING, FRICTION, T0, write_bag  # noqa: E402

from spatial_dynamics.fleet import main  # noqa: E402
from spatial_dynamics.fleet.chunks import merge  # noqa: E402
from spatial_dynamics.fleet.manifest import ManifestError, read_manifest  # noqa: E402
from spatial_dynamics.fleet.sums import solve, Sums  # noqa: E402
from spatial_dynamics.fleet.task import process, Task  # noqa: E402
from spatial_dynamics.drives import PARAMETERS  # noqa: E402


@pytest.fixture(scope='module')
def bag(tmp_path_factory):
    """Write the moving UR5's bag once for the module, as MCAP."""
    return write_bag(tmp_path_factory.mktemp('fleet_moving') / 'bag', storage='mcap')


def fit(result):
    return solve(Sums.from_dict(result['sums']), result['joints'])


@pytest.mark.parametrize('option, topic', [('base_odometry', '/odom'), ('base_imu', '/imu')])
def test_a_fleet_task_on_a_moving_base_recovers_the_drives(bag, option, topic):
    urdf = robot_urdf_path('ur5')
    moving = process(Task('m01', urdf, bag, {option: topic, 'window': 0.1}))
    assert moving['ok'], moving
    got = fit(moving)
    # as replay identify on the same bag (test_replay_moving_base.py): within 5 %
    np.testing.assert_allclose(got.damping, DAMPING, rtol=0.05)
    np.testing.assert_allclose(got.friction, FRICTION, rtol=0.05)
    np.testing.assert_allclose(got.armature, ARMATURE, rtol=0.05)
    # without the base topic: the base's acceleration (up to 6 m/s^2) times the arm
    fixed = process(Task('m01', urdf, bag, {'window': 0.1}))
    assert fixed['ok'] and max(fixed['rms_residual']) > 5.0
    assert max(moving['rms_residual']) < 0.5 * max(fixed['rms_residual'])


def test_chunks_read_the_base_topic_over_their_range_and_add_up_to_the_whole_bag(bag):
    task = Task('m01', robot_urdf_path('ur5'), bag, {'base_imu': '/imu'})
    whole = process(task)
    cuts = [None, T0 + 3 * 10 ** 9, T0 + 7 * 10 ** 9, None]
    parts = [Task(task.robot, task.urdf, task.bag, task.options, start=a, stop=b)
             for a, b in zip(cuts[:-1], cuts[1:])]
    results = [process(p) for p in parts]
    assert all(r['ok'] for r in results), results
    merged, = merge([task], [0] * len(parts), results)
    assert merged['samples'] == whole['samples']
    got, want = fit(merged), fit(whole)
    for name in PARAMETERS + ('rms_after', 'sigma'):
        np.testing.assert_allclose(getattr(got, name), getattr(want, name), rtol=1e-10)


def test_a_bag_without_the_base_topic_is_one_failed_line(bag, tmp_path, capsys):
    manifest = tmp_path / 'fleet.csv'
    manifest.write_text('robot,urdf,bag,base_odometry\n'
                        f'm01,{robot_urdf_path("ur5")},{bag},/base/odom\n')
    status = main([str(manifest), '--out', str(tmp_path / 'out'), '--serial', '--no-plots'])
    out = capsys.readouterr().out
    assert status != 0
    assert "--base-odometry '/base/odom'" in out and "'/base/odom' is not in the bag" in out, out


@pytest.mark.parametrize('columns, values, said', [
    ('base_odometry,base_imu', '/odom,/imu', 'base_odometry and base_imu: give one'),
    ('imu_link', 'base_link', 'imu_link needs base_imu'),
    ('odometry_link', 'base_link', 'odometry_link needs base_odometry'),
])
def test_base_options_that_do_not_go_together_are_refused_naming_the_row(
        bag, tmp_path, columns, values, said):
    manifest = tmp_path / 'fleet.csv'
    manifest.write_text(f'robot,urdf,bag,{columns}\n'
                        f'm01,{robot_urdf_path("ur5")},{bag},{values}\n')
    with pytest.raises(ManifestError) as err:
        read_manifest(str(manifest))
    assert said in str(err.value) and 'fleet.csv' in str(err.value)


def test_the_yaml_manifest_takes_the_base_options(bag, tmp_path):
    manifest = tmp_path / 'fleet.yaml'
    manifest.write_text(f'- robot: m01\n  urdf: {robot_urdf_path("ur5")}\n  bags: [{bag}]\n'
                        '  options: {base_imu: /imu, imu_link: base_link}\n')
    (task,), unmatched = read_manifest(str(manifest))
    assert unmatched == []
    assert task.option('base_imu') == '/imu' and task.option('imu_link') == 'base_link'
    assert task.option('base_odometry') is None
