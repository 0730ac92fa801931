# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The replay's inputs and outputs against careless or hostile users.

Every output path and every input is checked before any work (the bag is not even read): an
output that is an input, a directory, a named pipe, a device or in a missing folder is
refused in one line naming it; a link that no joint moves cannot take a payload or be fitted.
Every file is written whole or not at all (a full disk or a quota midway leaves the old file
and no temporary), and Ctrl-C ends the command quietly (status 130, one line), leaving no
half-written file and no child process.
"""

import os
import resource
import shutil
import signal
import subprocess
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(__file__))
from conftest import robot_urdf_path  # noqa: E402

import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics import identification  # noqa: E402
from spatial_dynamics.recordings import bags  # noqa: E402
from spatial_dynamics import drives as identify  # noqa: E402
from spatial_dynamics.replay import report  # noqa: E402
from spatial_dynamics.replay.__main__ import main  # noqa: E402

pytest.importorskip('rosbags')
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
HANG_GUARD = 120      # s: a hang guard, not a speed assertion
RATE = 250.0


def motion_bag(path, names=None, seconds=4.0, rows=None):
    """Write a UR5 recording (two sines a joint, torque = RNEA + drives); return its path."""
    model = sd.Model.from_urdf(robot_urdf_path('ur5'))
    rng = np.random.default_rng(3)
    t = np.arange(int(RATE * seconds)) / RATE
    n = model.nq
    amp = rng.uniform(0.5, 1.0, n)
    w1, w2 = 2 * np.pi * rng.uniform(0.2, 0.5, n), 2 * np.pi * rng.uniform(1.5, 2.5, n)
    T = t[:, None]
    q = amp * (np.sin(w1 * T) + 0.3 * np.sin(w2 * T))
    qd = amp * (w1 * np.cos(w1 * T) + 0.3 * w2 * np.cos(w2 * T))
    qdd = -amp * (w1 ** 2 * np.sin(w1 * T) + 0.3 * w2 ** 2 * np.sin(w2 * T))
    tau = sd.rnea(model, q, qd, qdd) + 0.5 * qd + np.tanh(qd / 0.01) + 0.05 * qdd
    t_ns = (1_700_000_000 * 10 ** 9 + np.arange(len(t)) * int(1e9 / RATE)).astype(np.int64)
    keep = slice(None) if rows is None else slice(0, rows)
    block = bags.encode_joint_states(names or model.joint_names, t_ns[keep], q[keep], qd[keep],
                                     tau[keep])
    bags.write_bag(str(path), 'sqlite3', [('/joint_states', bags.JOINT_STATE, t_ns[keep],
                                           [r.tobytes() for r in block])])
    return str(path)


@pytest.fixture(scope='module')
def bag(tmp_path_factory):
    return motion_bag(tmp_path_factory.mktemp('bags') / 'run')


@pytest.fixture
def no_work(monkeypatch):
    """Fail the test if a bag is read or anything is fitted."""
    def work(*args, **kwargs):
        raise AssertionError('work was done before the refusal')
    monkeypatch.setattr(bags, 'read_joint_states', work)
    monkeypatch.setattr(identify, 'identify', work)
    monkeypatch.setattr(identification, 'identify_payload', work)
    monkeypatch.setattr(identification, 'identify_inertias', work)


@pytest.fixture
def no_fit(monkeypatch):
    """Fail the test if anything is fitted (the bags may be read)."""
    def fit(*args, **kwargs):
        raise AssertionError('a fit ran before the refusal')
    monkeypatch.setattr(identify, 'identify', fit)
    monkeypatch.setattr(identification, 'identify_payload', fit)
    monkeypatch.setattr(identification, 'identify_inertias', fit)


def refused(capsys, argv):
    """Run the command in this process; return its one line on stderr (status 1)."""
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    lines = err.strip().splitlines()
    assert status == 1 and len(lines) == 1 and 'Traceback' not in err, (status, err)
    return lines[0]


def replay(*args, preexec_fn=None, **kwargs):
    """Run ``python -m spatial_dynamics.replay ARGS``: (status, stdout, stderr)."""
    run = subprocess.run([sys.executable, '-m', 'spatial_dynamics.replay', *map(str, args)],
                         capture_output=True, text=True, timeout=HANG_GUARD, cwd=ROOT,
                         env={**os.environ, 'PYTHONPATH': ROOT}, preexec_fn=preexec_fn,
                         **kwargs)
    return run.returncode, run.stdout, run.stderr


def temporaries(folder):
    return [name for name in os.listdir(folder) if name.endswith('.tmp')]


# --------------------------------------------------------------------------------------------
# Outputs: checked before any work

@pytest.mark.parametrize('case', ['directory', '/dev/full', 'missing folder', 'fifo'])
def test_write_urdf_that_cannot_be_written_is_refused_before_any_work(
        tmp_path, capsys, no_work, bag, case):
    """A directory, /dev/full, a missing folder, a FIFO (which would block forever)."""
    target = {'directory': tmp_path, '/dev/full': '/dev/full',
              'missing folder': tmp_path / 'no' / 'such' / 'out.urdf',
              'fifo': tmp_path / 'fifo.urdf'}[case]
    if case == 'fifo':
        os.mkfifo(target)
    line = refused(capsys, ['identify', bag, '--urdf', robot_urdf_path('ur5'), '--no-plots',
                            '--out', tmp_path / 'o', '--write-urdf', target])
    assert '--write-urdf' in line and str(target) in line, line


def test_outputs_that_are_inputs_are_refused_before_any_work(tmp_path, capsys, no_work, bag):
    urdf = tmp_path / 'robot.urdf'
    shutil.copy(robot_urdf_path('ur5'), urdf)
    before = urdf.read_bytes()
    for same in (urdf, tmp_path / '.' / 'robot.urdf'):
        line = refused(capsys, ['identify', bag, '--urdf', urdf, '--no-plots', '--out',
                                tmp_path / 'o', '--write-urdf', same])
        assert 'also an input' in line and str(same) in line, line
    assert urdf.read_bytes() == before
    # the bag's own directory (or a folder inside it) is no output directory
    files = sorted(os.listdir(bag))
    for out in (bag, os.path.join(bag, 'plots')):
        line = refused(capsys, ['residual', bag, '--urdf', urdf, '--no-plots', '--out', out])
        assert '--out' in line and 'bag' in line, line
    assert sorted(os.listdir(bag)) == files
    # residual.csv that is the bag (a link left in the output folder): never written through
    db3 = os.path.join(bag, next(name for name in files if name.endswith('.db3')))
    size = os.path.getsize(db3)
    out = tmp_path / 'o2'
    out.mkdir()
    os.symlink(db3, out / 'residual.csv')
    line = refused(capsys, ['residual', db3, '--urdf', urdf, '--no-plots', '--out', out])
    assert 'residual.csv' in line and 'also an input' in line, line
    assert os.path.getsize(db3) == size


# --------------------------------------------------------------------------------------------
# Inputs: checked before any work

def test_missing_bags_are_refused_before_any_work(tmp_path, capsys, no_work, bag):
    urdf = robot_urdf_path('ur5')
    for option in ('--validate', '--also'):
        missing = tmp_path / f'missing{option}'
        line = refused(capsys, ['identify', bag, '--urdf', urdf, '--no-plots', '--out',
                                tmp_path / 'o', option, missing])
        assert option in line and str(missing) in line and 'no such bag' in line, line
    line = refused(capsys, ['residual', tmp_path / 'nothing', '--urdf', urdf, '--no-plots',
                            '--out', tmp_path / 'o'])
    assert str(tmp_path / 'nothing') in line and 'no such bag' in line, line


def test_a_held_out_bag_of_other_joints_is_refused_before_the_fit(tmp_path, capsys, no_fit, bag):
    other = motion_bag(tmp_path / 'other', names=[f'other_{k}' for k in range(6)])
    line = refused(capsys, ['identify', bag, '--urdf', robot_urdf_path('ur5'), '--no-plots',
                            '--out', tmp_path / 'o', '--validate', other])
    assert str(other) in line and 'shoulder_pan_joint' in line, line


@pytest.mark.parametrize('option, links, named, why', [
    ('--payload', ['base_link'], 'base_link', 'does not move'),
    ('--inertias', ['base_link'], 'base_link', 'does not move'),
    ('--inertias', ['world'], 'world', 'does not move'),
    ('--inertias', ['shoulder_link', 'base'], 'base', 'does not move'),
    ('--payload', ['tool9'], 'tool9', 'is not a link'),
])
def test_a_link_no_joint_moves_is_refused_naming_it(tmp_path, capsys, no_work, bag, option,
                                                    links, named, why):
    """The root and the links fixed to it carry nothing a recording can tell; say so up front."""
    line = refused(capsys, ['identify', bag, '--urdf', robot_urdf_path('ur5'), '--no-plots',
                            '--out', tmp_path / 'o', option, *links])
    assert f'{option}: link {named!r}' in line and why in line, line
    assert 'shoulder_link' in line and 'wrist_3_link' in line, line    # what can be used


def test_the_library_refuses_a_fixed_link_too():
    model = sd.Model.from_urdf(robot_urdf_path('ur5'))
    q = np.zeros((20, model.nq))
    with pytest.raises(ValueError, match="'base_link' does not move"):
        identification.identify_payload(model, 'base_link', q, q, q, q)
    with pytest.raises(ValueError, match="'world' does not move"):
        identification.identify_inertias(model, q, q, q, q, ['world'])
    assert identification.link_to_body(model, 'tool0')[0] == model.frames['tool0'].body


@pytest.mark.parametrize('rows, said', [(1, 'only 1 usable sample '),
                                        (3, 'only 3 usable samples ')])
def test_too_few_samples_say_why(tmp_path, capsys, bag, rows, said):
    short = motion_bag(tmp_path / 'short', rows=rows)
    line = refused(capsys, ['residual', short, '--urdf', robot_urdf_path('ur5'), '--no-plots',
                            '--out', tmp_path / 'o'])
    assert said in line and str(short) in line and 'at least 5' in line, line
    assert not line.rstrip().endswith(':'), line


# --------------------------------------------------------------------------------------------
# Every file whole or not at all

def quota(limit):
    """Return a preexec_fn: files of at most ``limit`` bytes (a quota; EFBIG past it)."""
    def set_limit():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
    return set_limit


def test_a_write_urdf_that_fails_midway_leaves_the_old_file(tmp_path, bag):
    """The corrected URDF exceeds the quota halfway: the previous file stays, whole."""
    urdf = robot_urdf_path('ur5')
    target = tmp_path / 'corrected.urdf'
    old = b'<?xml version="1.0"?>\n<robot name="previous_fit"/>\n'
    target.write_bytes(old)
    status, out, err = replay('identify', bag, '--urdf', urdf, '--no-plots', '--residual',
                              'none', '--out', tmp_path / 'o', '--write-urdf', target,
                              preexec_fn=quota(os.path.getsize(urdf) // 2))
    lines = err.strip().splitlines()
    assert status == 1 and len(lines) == 1 and str(target) in lines[0], err
    assert 'File too large' in lines[0], err
    assert target.read_bytes() == old
    assert temporaries(tmp_path) == []


def test_a_residual_that_fails_midway_leaves_the_old_file(tmp_path, bag):
    out = tmp_path / 'o'
    out.mkdir()
    (out / 'residual.csv').write_bytes(b't,old\n')
    status, stdout, err = replay('residual', bag, '--urdf', robot_urdf_path('ur5'), '--no-plots',
                                 '--out', out, preexec_fn=quota(20000))
    lines = err.strip().splitlines()
    assert status == 1 and len(lines) == 1 and 'residual.csv' in lines[0], err
    assert (out / 'residual.csv').read_bytes() == b't,old\n'
    assert temporaries(out) == []


def test_every_file_of_the_command_is_written_whole_or_not_at_all(tmp_path, bag, capsys,
                                                                  monkeypatch):
    """A disk that fills at fsync: summary.csv, residual.npy and the plots keep their old bytes."""
    import errno
    out = tmp_path / 'o'
    out.mkdir()
    for name in ('summary.csv', 'residual.npy', 'residual.png'):
        (out / name).write_bytes(b'old ' + name.encode())

    def full(fd):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    monkeypatch.setattr(os, 'fsync', full)
    line = refused(capsys, ['residual', bag, '--urdf', robot_urdf_path('ur5'), '--no-plots',
                            '--out', out, '--residual', 'npy'])
    assert 'summary.csv' in line and 'No space left' in line, line
    monkeypatch.setattr(report, 'write_summary', lambda *args: None)
    line = refused(capsys, ['residual', bag, '--urdf', robot_urdf_path('ur5'), '--no-plots',
                            '--out', out, '--residual', 'npy'])
    assert 'residual.npy' in line and 'No space left' in line, line
    t = np.arange(10.0)
    with pytest.raises(ValueError, match='residual.png'):
        report.plot_joints(str(out / 'residual.png'), t, ['j'], {'x': t[:, None]}, 'title')
    for name in ('summary.csv', 'residual.npy', 'residual.png'):
        assert (out / name).read_bytes() == b'old ' + name.encode()
    assert temporaries(out) == []


# --------------------------------------------------------------------------------------------
# Ctrl-C

INTERRUPTED_RUN = '''
import os, signal, sys
from spatial_dynamics.replay import report
from spatial_dynamics.replay.__main__ import main
real_start, real_format = report.start_child, report._fixed_point


def start(*args):
    child = real_start(*args)
    with open(sys.argv[1], 'w') as f:
        f.write(str(child[0].pid))
    return child


def format_then_interrupt(*args):
    os.killpg(0, signal.SIGINT)       # Ctrl-C in a terminal: the whole process group
    return real_format(*args)


report.start_child, report._fixed_point = start, format_then_interrupt
sys.exit(main(sys.argv[2:]))
'''


def test_ctrl_c_ends_quietly_without_half_files_or_a_child(tmp_path, bag):
    """Interrupted while residual.csv is written (and the plots drawn in the child)."""
    out, pid_file = tmp_path / 'o', tmp_path / 'child.pid'
    run = subprocess.run([sys.executable, '-c', INTERRUPTED_RUN, str(pid_file), 'residual', bag,
                          '--urdf', robot_urdf_path('ur5'), '--out', str(out)],
                         capture_output=True, text=True, timeout=HANG_GUARD, cwd=ROOT,
                         env={**os.environ, 'PYTHONPATH': ROOT}, start_new_session=True,
                         # as from a terminal (a shell's background job would ignore it)
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert run.returncode == 130 and run.stderr == 'interrupted\n', run.stderr
    assert temporaries(out) == [] and not (out / 'residual.csv').exists()
    assert (out / 'summary.csv').read_text().startswith('joint,')
    for name in os.listdir(out):            # a plot the child finished is whole
        if name.endswith('.png'):
            data = (out / name).read_bytes()
            assert data.startswith(b'\x89PNG') and data.endswith(b'IEND\xaeB`\x82'), name
    child = int(pid_file.read_text())
    with pytest.raises(ProcessLookupError):
        os.kill(child, 0)


# --------------------------------------------------------------------------------------------
# Odd values of the other options

@pytest.mark.parametrize('option', ['--payload', '--write-urdf', '--validate', '--urdf',
                                    '--topic', '--out', '--joints', '--also'])
def test_an_empty_value_is_a_usage_error(tmp_path, capsys, no_work, bag, option):
    """'' is no link, file or joint: never ignored as if the option were not given."""
    argv = ['identify', bag, '--urdf', robot_urdf_path('ur5'), '--no-plots', '--out',
            tmp_path / 'o']
    argv = [a for k, a in enumerate(argv) if not (option in ('--urdf', '--out') and
                                                  (a == option or argv[k - 1] == option))]
    with pytest.raises(SystemExit) as usage:
        main([str(a) for a in argv] + [option, ''])
    assert usage.value.code == 2
    assert f'{option}: an empty value' in capsys.readouterr().err


def test_the_same_recording_twice_is_refused(tmp_path, capsys, no_work, bag):
    urdf = robot_urdf_path('ur5')
    line = refused(capsys, ['identify', bag, '--urdf', urdf, '--no-plots', '--out',
                            tmp_path / 'o', '--validate', os.path.join(bag, '.')])
    assert '--validate' in line and 'same recording' in line and 'held-out' in line, line
    line = refused(capsys, ['identify', bag, '--urdf', urdf, '--no-plots', '--out',
                            tmp_path / 'o', '--also', bag])
    assert '--also' in line and 'same recording' in line, line


def test_outputs_that_would_overwrite_a_bag_or_each_other_are_refused(
        tmp_path, capsys, no_work, bag):
    urdf = robot_urdf_path('ur5')
    meta = os.path.join(bag, 'metadata.yaml')
    before = open(meta, 'rb').read()
    line = refused(capsys, ['identify', bag, '--urdf', urdf, '--no-plots', '--out',
                            tmp_path / 'o', '--write-urdf', meta])
    assert '--write-urdf' in line and 'in the bag' in line, line
    assert open(meta, 'rb').read() == before
    line = refused(capsys, ['identify', bag, '--urdf', urdf, '--no-plots', '--out',
                            tmp_path / 'o', '--write-urdf', tmp_path / 'o' / 'summary.csv'])
    assert '--write-urdf' in line and 'summary.csv' in line, line


def test_a_trajectory_output_that_is_the_trajectory_is_refused(tmp_path, capsys):
    plan = tmp_path / 'plan.yaml'
    plan.write_text('joint_names: [shoulder_pan_joint]\npoints:\n- positions: [0.0]\n'
                    '- positions: [0.5]\n  time_from_start: {sec: 2, nanosec: 0}\n')
    out = tmp_path / 'o'
    out.mkdir()
    os.symlink(plan, out / 'trajectory.csv')
    line = refused(capsys, ['trajectory', plan, '--urdf', robot_urdf_path('ur5'),
                            '--joints', 'shoulder_pan_joint', '--no-plots', '--out', out])
    assert 'trajectory.csv' in line and 'also an input' in line, line
    assert plan.read_text().startswith('joint_names')


def test_plots_without_matplotlib_are_refused_before_any_work(
        tmp_path, capsys, no_work, bag, monkeypatch):
    """Without matplotlib the drawing child died and the parent's job hit its closed pipe."""
    monkeypatch.setitem(sys.modules, 'matplotlib', None)        # as if not installed
    line = refused(capsys, ['residual', bag, '--urdf', robot_urdf_path('ur5'), '--out',
                            tmp_path / 'o'])
    assert 'matplotlib' in line and '--no-plots' in line, line


def test_a_plotting_child_that_cannot_draw_says_so_in_one_line(tmp_path, capfd):
    """A child whose preparation fails (a broken matplotlib): one line, the join fails."""
    def broken():
        raise ImportError('No module named matplotlib.pyplot')
    child = report.start_child(broken)
    assert not report.join_child(report.run_in(child, print, 'never drawn'))
    err = capfd.readouterr().err
    assert err == 'error: the plots need matplotlib: No module named matplotlib.pyplot\n', err
