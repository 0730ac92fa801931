# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The replay and spatial_dynamics_check against what a careless or malicious user hands them.

Each case runs the command as a user does (a subprocess, with a timeout as a hang guard) and
asserts the exit status and one line on stderr naming the problem, never a traceback; the
bags in oddly named directories must read their own data. The one safe reader
(:mod:`spatial_dynamics.files`) and the CSV writer are checked against the library they stand
in for (PyYAML, Python's float formatting).
"""

import csv
import os
import sqlite3
import subprocess
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(__file__))
from conftest import robot_urdf_path  # noqa: E402

import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics.files import load_yaml, read_regular  # noqa: E402
from spatial_dynamics.recordings import bags  # noqa: E402
from spatial_dynamics.replay import report, splines  # noqa: E402

pytest.importorskip('rosbags')
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
HANG_GUARD = 120      # s: a hang guard, not a speed assertion
UR5_JOINTS = ['shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint', 'wrist_1_joint',
              'wrist_2_joint', 'wrist_3_joint']
PLAN = ('joint_names: [' + ', '.join(UR5_JOINTS) + ']\n'
        'points:\n'
        '- positions: [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]\n'
        '  time_from_start: {sec: 0, nanosec: 0}\n'
        '- positions: [0.5, -0.5, 0.5, 0.0, 0.0, 0.0]\n'
        '  time_from_start: {sec: 2, nanosec: 0}\n')


def replay(*args, cwd=None):
    """Run ``python -m spatial_dynamics.replay ARGS``: (status, stdout, stderr)."""
    run = subprocess.run([sys.executable, '-m', 'spatial_dynamics.replay', *map(str, args)],
                         capture_output=True, text=True, timeout=HANG_GUARD, cwd=cwd or ROOT,
                         env={**os.environ, 'PYTHONPATH': ROOT})
    return run.returncode, run.stdout, run.stderr


def one_line(err: str) -> str:
    """Return the single line of stderr (no traceback)."""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and 'Traceback' not in err, err
    return lines[0]


def write_bag(path, q_value, storage='sqlite3'):
    """Write a 1 s, 100 Hz UR5 bag whose every position is ``q_value``, named as ros2 does.

    rosbags' writer opens SQLite by an unquoted URI too, so the bag is written under a plain
    name and then renamed: directory ``NAME`` holding ``NAME_0.db3`` (or ``.mcap``), as
    ``ros2 bag record -o NAME`` makes it.
    """
    import yaml
    path = str(path)
    plain = os.path.join(os.path.dirname(path), f'plain_{abs(hash(path))}')
    t = 10 ** 18 + np.arange(100) * 10 ** 7
    q = np.full((100, 6), q_value)
    block = bags.encode_joint_states(UR5_JOINTS, t, q, np.zeros((100, 6)),
                                     np.full((100, 6), 1.0))
    bags.write_bag(plain, storage, [('/joint_states', bags.JOINT_STATE, t,
                                     [r.tobytes() for r in block])])
    name = os.path.basename(path)
    meta_path = os.path.join(plain, 'metadata.yaml')
    with open(meta_path) as f:
        meta = yaml.safe_load(f)
    info = meta['rosbag2_bagfile_information']
    old = info['relative_file_paths'][0]
    new = f'{name}_0{os.path.splitext(old)[1]}'
    os.rename(os.path.join(plain, old), os.path.join(plain, new))
    info['relative_file_paths'] = [new]
    for entry in info.get('files') or []:
        entry['path'] = new
    with open(meta_path, 'w') as f:
        yaml.safe_dump(meta, f)
    os.rename(plain, path)
    return path


# --------------------------------------------------------------------------------------------
# Item 1: a path is a path, never a URI

@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
def test_bag_paths_with_uri_characters_read_their_own_data(tmp_path, storage):
    """pct%41 is not pctA; run#1 and run?mode=rw open; each bag reads its own positions."""
    names = {'pct%41': 0.41, 'pctA': 0.65, 'run#1': 0.11, 'run?mode=rw': 0.22,
             'with space': 0.33, 'ünï': 0.44}
    for name, value in names.items():
        write_bag(tmp_path / name, value, storage)
    for name, value in names.items():
        js = bags.read_joint_states(str(tmp_path / name), '/joint_states', UR5_JOINTS)
        assert len(js.stamp) == 100, name
        assert np.all(js.position == value), (name, js.position[0])
        slow = bags.read_joint_states(str(tmp_path / name), '/joint_states', UR5_JOINTS,
                                      fast=False)
        assert np.all(slow.position == value), name


@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
@pytest.mark.parametrize('claimed', [10 ** 15, 3, 0, 'many'])
def test_metadata_message_counts_are_only_a_hint(tmp_path, claimed, storage):
    """A bag's metadata claiming 10**15 messages (or too few, or junk) reads its 100.

    The count sizes the arrays: taken as it is, 10**15 would ask for petabytes.
    """
    import yaml
    bag = write_bag(tmp_path / 'bag', 0.3, storage)
    meta_path = os.path.join(bag, 'metadata.yaml')
    with open(meta_path) as f:
        meta = yaml.safe_load(f)
    for entry in meta['rosbag2_bagfile_information']['topics_with_message_count']:
        entry['message_count'] = claimed
    with open(meta_path, 'w') as f:
        yaml.safe_dump(meta, f)
    js = bags.read_joint_states(bag, '/joint_states', UR5_JOINTS)
    assert len(js.stamp) == 100 and js.fast == 100
    assert np.all(js.position == 0.3) and np.all(js.effort == 1.0)


def test_a_single_storage_file_with_uri_characters(tmp_path):
    """A .db3 file named pct%41.db3 beside pctA.db3 reads its own data."""
    for name, value in (('pct%41', 0.41), ('pctA', 0.65)):
        write_bag(tmp_path / name, value)
        os.rename(tmp_path / name / f'{name}_0.db3', tmp_path / f'{name}.db3')
    js = bags.read_joint_states(str(tmp_path / 'pct%41.db3'), '/joint_states', UR5_JOINTS)
    assert np.all(js.position == 0.41)


# --------------------------------------------------------------------------------------------
# Items 8, 10, 11: one line and exit 1, never a hang

def test_fifo_as_storage_file_or_metadata_is_refused_at_once(tmp_path):
    urdf = robot_urdf_path('ur5')
    bag = write_bag(tmp_path / 'bag', 0.1)
    db = next((tmp_path / 'bag').glob('*.db3'))
    os.remove(db)
    os.mkfifo(db)
    status, out, err = replay('residual', bag, '--urdf', urdf, '--no-plots', '--out',
                              tmp_path / 'o')
    assert status == 1 and 'not a regular file' in one_line(err) and 'named pipe' in err, err
    bag2 = write_bag(tmp_path / 'bag2', 0.1)
    os.remove(tmp_path / 'bag2' / 'metadata.yaml')
    os.mkfifo(tmp_path / 'bag2' / 'metadata.yaml')
    status, out, err = replay('residual', bag2, '--urdf', urdf, '--no-plots', '--out',
                              tmp_path / 'o')
    assert status == 1 and 'metadata.yaml' in one_line(err) and 'named pipe' in err, err


@pytest.mark.parametrize('damage', ['no_data_column', 'text_data'])
def test_a_database_that_is_not_a_bag_is_one_line(tmp_path, damage):
    urdf = robot_urdf_path('ur5')
    bag = write_bag(tmp_path / 'bag', 0.1)
    db = next((tmp_path / 'bag').glob('*.db3'))
    con = sqlite3.connect(db)
    if damage == 'no_data_column':
        con.execute('ALTER TABLE messages RENAME COLUMN data TO payload')
    else:
        con.execute("UPDATE messages SET data = 'some text'")
    con.commit()
    con.close()
    status, out, err = replay('residual', bag, '--urdf', urdf, '--no-plots', '--out',
                              tmp_path / 'o')
    assert status == 1 and 'not a rosbag2 sqlite3 database' in one_line(err), err


def test_out_that_cannot_be_a_directory_is_refused_before_the_computation(tmp_path):
    urdf = robot_urdf_path('ur5')
    bag = write_bag(tmp_path / 'bag', 0.1)
    a_file = tmp_path / 'file'
    a_file.write_text('x')
    for out in (a_file, '/proc/spatial_dynamics_out'):
        status, stdout, err = replay('residual', bag, '--urdf', urdf, '--no-plots', '--out', out)
        assert status == 1 and f'--out {str(out)!r}' in one_line(err), err
        assert stdout == ''          # refused before anything was computed
        status, stdout, err = replay('trajectory', tmp_path / 'none.yaml', '--urdf', urdf,
                                     '--out', out)
        assert status == 1 and f'--out {str(out)!r}' in one_line(err), err


def _plan(tmp_path, text: str, name='plan.yaml'):
    path = tmp_path / name
    path.write_text(text)
    return path


BAD_PLANS = {
    'malformed': ('joint_names: [a, b\n', 'not valid YAML'),
    'python_tag': ('!!python/object/apply:os.system ["echo hacked"]\n', 'python/object'),
    'scalar_points': ('joint_names: [a]\npoints: [1, 2]\n', 'point 0 must be a mapping'),
    'joint_names_5': ('joint_names: 5\npoints: []\n', 'joint_names must be a list'),
    'sec_list': (PLAN.replace('sec: 2,', 'sec: [2],'), 'time_from_start.sec'),
    'two_billion_s': (PLAN.replace('sec: 2,', 'sec: 2000000000,'), 'time_from_start is 2e+09'),
    'huge_position': (PLAN.replace('0.5, -0.5', '1.0e+300, -0.5'), 'beyond ±100000'),
    'nan_position': (PLAN.replace('0.5, -0.5', '.nan, -0.5'), 'not finite'),
    'not_a_mapping': ('- 1\n- 2\n', 'no JointTrajectory mapping'),
}


@pytest.mark.parametrize('case', sorted(BAD_PLANS))
def test_bad_trajectory_files_are_one_line(tmp_path, case):
    text, expected = BAD_PLANS[case]
    status, out, err = replay('trajectory', _plan(tmp_path, text), '--urdf',
                              robot_urdf_path('ur5'), '--no-plots', '--out', tmp_path / 'o')
    assert status == 1 and expected in one_line(err), err


@pytest.mark.parametrize('special', ['fifo', '/dev/zero', 'directory'])
def test_trajectory_that_is_not_a_regular_file_is_refused_at_once(tmp_path, special):
    path = {'fifo': tmp_path / 'fifo.yaml', '/dev/zero': '/dev/zero',
            'directory': tmp_path}[special]
    if special == 'fifo':
        os.mkfifo(path)
    status, out, err = replay('trajectory', path, '--urdf', robot_urdf_path('ur5'),
                              '--no-plots', '--out', tmp_path / 'o')
    assert status == 1 and 'not a regular file' in one_line(err), err


def billion_laughs(levels: int = 9) -> str:
    """Nested aliases: ~400 bytes that stand for 9**levels strings."""
    text = 'a0: &a0 [' + ', '.join(['lol'] * 9) + ']\n'
    for k in range(1, levels):
        text += f'a{k}: &a{k} [' + ', '.join([f'*a{k - 1}'] * 9) + ']\n'
    return text + f'joint_names: *a{levels - 1}\npoints: *a{levels - 1}\n'


def test_yaml_alias_bomb_is_refused_by_its_budget(tmp_path):
    """The bomb is refused by the expanded-node budget, in a process held to 1 GiB."""
    bomb = billion_laughs()
    assert len(bomb) < 600
    with pytest.raises(ValueError, match='aliases are expanded'):
        load_yaml(bomb, 'bomb')
    # the same document without its last level is within the budget and loads
    small = billion_laughs(4)
    assert load_yaml(small, 'small')['points'][0][0][0][0] == 'lol'
    path = _plan(tmp_path, bomb)
    code = ('import resource, sys; resource.setrlimit(resource.RLIMIT_AS, (1 << 30, 1 << 30)); '
            'from spatial_dynamics.replay.__main__ import main; sys.exit(main(sys.argv[1:]))')
    run = subprocess.run([sys.executable, '-c', code, 'trajectory', str(path), '--urdf',
                          robot_urdf_path('ur5'), '--no-plots', '--out', str(tmp_path / 'o')],
                         capture_output=True, text=True, timeout=HANG_GUARD,
                         env={**os.environ, 'PYTHONPATH': ROOT})
    assert run.returncode == 1 and 'alias' in one_line(run.stderr), run.stderr


def test_load_yaml_equals_pyyaml_safe_load_on_real_documents():
    import yaml
    for text in (PLAN, 'a: &x {b: [1, 2.5, .nan]}\nc: *x\n', '', '---\n', 'x: 1\n---\ny: 2\n'):
        expected = next(iter(yaml.safe_load_all(text)), None)
        got = load_yaml(text, 'doc')
        assert repr(got) == repr(expected), text


# --------------------------------------------------------------------------------------------
# Item 6: no torque that is not finite passes the effort-limit check

def test_gravity_that_is_not_finite_or_absurd_is_usage(tmp_path):
    plan = _plan(tmp_path, PLAN)
    for g in (['nan', 'nan', 'nan'], ['0', '0', '1e300']):
        status, out, err = replay('trajectory', plan, '--urdf', robot_urdf_path('ur5'),
                                  '--no-plots', '--out', tmp_path / 'o', '--gravity', *g)
        assert status == 2 and '--gravity' in err and 'Traceback' not in err, err


def test_non_finite_torque_fails_the_check(tmp_path, monkeypatch, capsys):
    """Should a torque come out non-finite anyway, the check fails and names the joint."""
    from spatial_dynamics.replay import __main__ as cli
    from spatial_dynamics.replay import trajectory

    def poisoned(model, q, qd, qdd, gravity):
        tau = sd.rnea(model, q, qd, qdd, gravity=gravity)
        tau[5, 1] = np.nan
        return tau
    monkeypatch.setattr(trajectory, 'rnea', poisoned)
    status = cli.main(['trajectory', str(_plan(tmp_path, PLAN)), '--urdf',
                       robot_urdf_path('ur5'), '--no-plots', '--out', str(tmp_path / 'o')])
    out, err = capsys.readouterr()
    assert status == 1
    line = next(x for x in out.splitlines() if 'shoulder_lift_joint' in x)
    assert 'NOT FINITE' in line and 'nan %' not in out
    assert 'not finite' in err


def test_sampling_beyond_the_sample_budget_is_refused():
    traj = splines.trajectory(['a'], [{'positions': [0.0]},
                                      {'positions': [1.0], 'time_from_start': {'sec': 86400}}])
    with pytest.raises(ValueError, match='samples'):
        splines.sample(traj, 1000.0)


# --------------------------------------------------------------------------------------------
# Item 5: the CSV writer writes every float it is given

def test_csv_writer_round_trips_every_magnitude(tmp_path):
    values = np.array([0.0, -0.5, 123.456789, 9.2e14, 9.3e14, 1e15, -1e15, 1e300, -1e300,
                       5e-324, np.nan, np.inf, -np.inf, 2.0 ** 63, 1.7976931348623157e308])
    path = tmp_path / 'x.csv'
    report.write_csv(str(path), ['t', 'v'], [np.arange(len(values), dtype=float), values],
                     [6, 4])
    with open(path) as f:
        rows = list(csv.reader(f))[1:]
    got = np.array([float(r[1]) for r in rows])
    # the reference: Python's own formatting of each value at 4 decimals
    expected = np.array([float(f'{v:.4f}') for v in values])
    assert np.array_equal(got, expected, equal_nan=True), (got, expected)


# --------------------------------------------------------------------------------------------
# The one reader: spatial_dynamics_check refuses what the library refuses

def test_check_urdf_reads_through_the_safe_reader(tmp_path):
    fifo = tmp_path / 'robot.urdf'
    os.mkfifo(fifo)
    run = subprocess.run([sys.executable, '-m', 'spatial_dynamics.check', str(fifo)],
                         capture_output=True, text=True, timeout=HANG_GUARD,
                         env={**os.environ, 'PYTHONPATH': ROOT})
    assert run.returncode == 1 and 'named pipe' in one_line(run.stderr), run.stderr
    with pytest.raises(ValueError, match='too large'):
        read_regular(robot_urdf_path('ur5'), 'ur5', 100)
