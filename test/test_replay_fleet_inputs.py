# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The fleet's inputs: whose a cached result is, cache entries checked, names, bags, options."""

import csv
import json
import os
import shutil
import subprocess
import sys

import pytest

from spatial_dynamics.fleet import main

sys.path.insert(0, os.path.dirname(__file__))
from conftest import robot_urdf_path  # noqa: E402


@pytest.fixture(scope='module')
def small(tmp_path_factory):
    """Two robots, two days of two seconds each, no wear."""
    pytest.importorskip('mujoco')
    from spatial_dynamics.tools.fleet_demo import make_fleet
    out = str(tmp_path_factory.mktemp('small'))
    try:
        make_fleet(out, robots=2, days=2, seconds=2.0, wear=(0, 0, 99, 0.0))
    except RuntimeError as err:
        pytest.skip(str(err))
    return out


def run(argv, capsys):
    status = main([str(a) for a in argv] + ['--serial', '--no-plots'])
    captured = capsys.readouterr()
    return status, captured.out, captured.err


def table(out):
    with open(os.path.join(out, 'fleet.csv'), newline='') as f:
        return list(csv.DictReader(f))


def manifest(path, rows, header='robot,urdf,bag'):
    path.write_text('\n'.join([header] + [','.join(r) for r in rows]) + '\n')
    return path


# -- the cache keeps what the content decides; the run says whose it is -----------------------

def test_a_robot_renamed_in_the_manifest_is_reported_by_its_new_name(small, tmp_path, capsys):
    urdf, bags = os.path.join(small, 'r01', 'robot.urdf'), os.path.join(small, 'r01', 'day*')
    out, cache = tmp_path / 'o', tmp_path / 'cache'
    run([manifest(tmp_path / 'a.csv', [('old', urdf, bags)]), '--out', out, '--cache', cache],
        capsys)
    status, text, _ = run([manifest(tmp_path / 'b.csv', [('new', urdf, bags)]), '--out', out,
                           '--cache', cache], capsys)
    assert '(2 from the cache, 0 failed)' in text
    assert {r['robot'] for r in table(out)} == {'new'}


def test_two_robots_with_the_same_bytes_are_both_reported(small, tmp_path, capsys):
    folder = tmp_path / 'fleet'
    for robot in ('alpha', 'beta'):
        shutil.copytree(os.path.join(small, 'r01', 'day01'), folder / robot / 'day01')
    urdf = os.path.join(small, 'r01', 'robot.urdf')
    for attempt in range(2):
        status, text, _ = run([folder, '--urdf', urdf, '--out', tmp_path / 'o'], capsys)
        rows = table(tmp_path / 'o')
        assert {r['robot'] for r in rows} == {'alpha', 'beta'}, attempt
        assert {r['bag'] for r in rows} == {str(folder / 'alpha' / 'day01'),
                                            str(folder / 'beta' / 'day01')}
    assert '(2 from the cache, 0 failed)' in text


def test_a_moved_archive_reports_the_new_paths(small, tmp_path, capsys):
    shutil.copytree(small, tmp_path / 'before')
    run([tmp_path / 'before', '--out', tmp_path / 'o'], capsys)
    os.rename(tmp_path / 'before', tmp_path / 'after')
    status, text, _ = run([tmp_path / 'after', '--out', tmp_path / 'o'], capsys)
    assert '(4 from the cache, 0 failed)' in text
    assert all(r['bag'].startswith(str(tmp_path / 'after')) for r in table(tmp_path / 'o'))


# -- cache entries are checked before they are used -------------------------------------------

def entries(cache):
    return sorted(os.path.join(cache, f) for f in os.listdir(cache) if f.endswith('.json'))


def edit_a_number(path):
    with open(path) as f:
        doc = json.load(f)
    result = doc.get('result', doc)
    result['sums']['R'][0][0][0] *= 2.0
    result['sums']['G'][0][0][0] *= 4.0
    with open(path, 'w') as f:
        json.dump(doc, f)


@pytest.mark.parametrize('damage', ['malformed', 'edited', 'directory', 'fifo', 'shape',
                                    'nested'])
def test_a_damaged_cache_entry_is_computed_again(small, tmp_path, capsys, damage):
    out = tmp_path / 'o'
    run([small, '--out', out], capsys)
    want = table(out)
    path = entries(out / 'cache')[0]
    if damage == 'edited':
        edit_a_number(path)
    else:
        os.remove(path)
        if damage == 'malformed':
            open(path, 'w').write('{"ok": true, "sums": ')
        elif damage == 'directory':
            os.mkdir(path)
        elif damage == 'fifo':
            os.mkfifo(path)
        elif damage == 'nested':
            open(path, 'w').write('[' * 100000)
        else:
            open(path, 'w').write(json.dumps({'ok': True, 'joints': ['a'], 'sums': {}}))
    # in a child process: a FIFO must not hang the run (the old reader waited for a writer)
    proc = subprocess.run([sys.executable, '-m', 'spatial_dynamics.fleet', small, '--out',
                           str(out), '--serial', '--no-plots'], capture_output=True, text=True,
                          timeout=300)
    assert 'Traceback' not in proc.stderr, proc.stderr
    assert '(3 from the cache, 0 failed)' in proc.stdout, proc.stdout
    assert table(out) == want


def test_a_bag_edited_in_place_with_its_size_inode_and_mtime_kept_is_hashed_again(
        small, tmp_path, capsys):
    import sqlite3
    import struct
    folder = tmp_path / 'fleet'
    shutil.copytree(small, folder)
    run([folder, '--out', tmp_path / 'o'], capsys)
    db3 = next((folder / 'r01' / 'day01').glob('*.db3'))
    before = os.stat(db3)
    with sqlite3.connect(db3) as con:     # one effort value (the message's last 8 bytes) + 1
        rowid, data = con.execute('SELECT id, data FROM messages ORDER BY id LIMIT 1 OFFSET 50'
                                  ).fetchone()
        tau = struct.unpack('<d', data[-8:])[0] + 1.0
        con.execute('UPDATE messages SET data = ? WHERE id = ?',
                    (data[:-8] + struct.pack('<d', tau), rowid))
    con.close()
    os.utime(db3, ns=(before.st_atime_ns, before.st_mtime_ns))
    after = os.stat(db3)
    assert (after.st_size, after.st_ino, after.st_mtime_ns) == (
        before.st_size, before.st_ino, before.st_mtime_ns)
    status, text, _ = run([folder, '--out', tmp_path / 'o'], capsys)
    assert '(3 from the cache, 0 failed)' in text, text
    fresh = run([folder, '--out', tmp_path / 'fresh'], capsys)
    assert table(tmp_path / 'o') == table(tmp_path / 'fresh')
    assert (status, text.split('\n', 1)[1].replace(str(tmp_path / 'o'), '')) == (
        fresh[0], fresh[1].split('\n', 1)[1].replace(str(tmp_path / 'fresh'), ''))


# -- robot names, missing and repeated bags --------------------------------------------------

@pytest.mark.parametrize('name', ['x/../../../ESCAPED', 'a/b', '../escape', '..', 'r' * 300,
                                  'r02\ndrift: r01 forged', 'tab\there'])
def test_an_unusable_robot_name_is_refused_before_any_work(small, tmp_path, capsys, name):
    (tmp_path / 'o' / 'trend_x').mkdir(parents=True)
    path = tmp_path / 'm.yaml'
    path.write_text(json.dumps([
        {'robot': 'r01', 'urdf': os.path.join(small, 'r01', 'robot.urdf'),
         'bags': [os.path.join(small, 'r01', 'day01')]},
        {'robot': name, 'urdf': os.path.join(small, 'r02', 'robot.urdf'),
         'bags': [os.path.join(small, 'r02', 'day01')]}]))
    status = main([str(path), '--out', str(tmp_path / 'o'), '--serial'])
    err = capsys.readouterr().err
    assert status == 1
    assert 'robot 2: robot name' in err
    assert os.listdir(tmp_path / 'o') == ['trend_x']
    assert sorted(os.listdir(tmp_path)) == ['m.yaml', 'o']


def test_missing_and_looping_bags_are_one_failed_line_each_and_the_rest_finish(
        small, tmp_path, capsys):
    os.symlink('loop.db3', tmp_path / 'loop.db3')
    os.symlink('nowhere.db3', tmp_path / 'dangling.db3')
    urdf = os.path.join(small, 'r01', 'robot.urdf')
    path = manifest(tmp_path / 'm.csv', [
        ('r01', urdf, os.path.join(small, 'r01', 'day*')),
        ('r01', urdf, str(tmp_path / 'gone.db3')),
        ('r01', urdf, str(tmp_path / 'loop.db3')),
        ('r01', urdf, str(tmp_path / 'dangling.db3'))])
    status, text, err = run([path, '--out', tmp_path / 'o'], capsys)
    assert status != 1, err
    failed = [line for line in text.splitlines() if line.startswith('failed:')]
    assert len(failed) == 3, text
    for k, name in enumerate(['gone.db3', 'loop.db3', 'dangling.db3']):
        assert name in failed[k] and f'line {k + 3}' in failed[k]
    assert {r['bag'] for r in table(tmp_path / 'o')} == {
        os.path.join(small, 'r01', 'day01'), os.path.join(small, 'r01', 'day02')}


def fleet(argv, timeout=300):
    """Run the command in a child process: a hang is a timeout, not a stuck test run."""
    command = [sys.executable, '-m', 'spatial_dynamics.fleet'] + [str(a) for a in argv]
    return subprocess.run(command, capture_output=True, text=True, timeout=timeout)


def test_a_fifo_or_a_device_as_a_bag_is_one_failed_line_and_the_rest_finish(small, tmp_path):
    folder = tmp_path / 'fleet'
    shutil.copytree(small, folder)
    os.mkfifo(folder / 'r01' / 'fifo.db3')
    os.symlink('/dev/zero', folder / 'r02' / 'zero.mcap')
    os.mkfifo(tmp_path / 'listed.db3')
    urdf = folder / 'r01' / 'robot.urdf'
    path = manifest(tmp_path / 'm.csv', [('r01', str(urdf), str(folder / 'r01' / 'day*')),
                                         ('r01', str(urdf), str(tmp_path / 'listed.db3'))])
    for source, bad in ((folder, ['fifo.db3', 'zero.mcap']), (path, ['listed.db3'])):
        done = fleet([source, '--out', tmp_path / 'o', '--serial', '--no-plots'])
        assert 'Traceback' not in done.stderr and done.returncode != 1, done.stderr
        failed = [line for line in done.stdout.splitlines() if line.startswith('failed:')]
        assert [any(name in line for line in failed) for name in bad] == [True] * len(bad)
        assert len(failed) == len(bad), done.stdout
        assert all('not a regular file' in line for line in failed), failed


@pytest.mark.parametrize('urdf, says', [('/dev/zero', 'a character device'),
                                        ('fifo', 'a named pipe'), ('', 'an empty value'),
                                        ('/nonexistent', 'no such file')])
def test_an_unusable_urdf_option_is_refused_before_any_work(small, tmp_path, urdf, says):
    if urdf == 'fifo':
        urdf = tmp_path / 'robot.urdf'
        os.mkfifo(urdf)
    done = fleet([small, '--urdf', urdf, '--out', tmp_path / 'o', '--serial'], timeout=120)
    assert done.returncode == 2, done.stderr
    assert '--urdf' in done.stderr and says in done.stderr, done.stderr
    assert not os.path.exists(tmp_path / 'o')


@pytest.mark.parametrize('kind', ['csv', 'yaml'])
def test_a_glob_that_matches_nothing_is_one_failed_line_naming_its_row(small, tmp_path,
                                                                       capsys, kind):
    urdf = os.path.join(small, 'r01', 'robot.urdf')
    urdf2 = os.path.join(small, 'r02', 'robot.urdf')
    rows = [('r01', urdf, os.path.join(small, 'r01', 'day*')),
            ('r02', urdf2, str(tmp_path / 'nothing' / '*.mcap')),
            ('r02', urdf2, os.path.join(small, 'r02', 'day*'))]
    if kind == 'csv':
        path, where = manifest(tmp_path / 'm.csv', rows), 'line 3'
    else:
        path, where = tmp_path / 'm.yaml', 'robot 2'
        path.write_text(json.dumps([{'robot': r, 'urdf': u, 'bags': [b]} for r, u, b in rows]))
    status, text, err = run([path, '--out', tmp_path / 'o'], capsys)
    assert status != 1, err
    failed = [line for line in text.splitlines() if line.startswith('failed:')]
    assert len(failed) == 1, text
    assert f'{str(path)!r}, {where}' in failed[0] and '*.mcap' in failed[0], failed
    assert 'no bag matches' in failed[0], failed
    assert {r['bag'] for r in table(tmp_path / 'o')} == {
        os.path.join(small, r, d) for r in ('r01', 'r02') for d in ('day01', 'day02')}


def test_a_manifest_whose_globs_all_match_nothing_is_refused_with_each_row(tmp_path, capsys):
    urdf = robot_urdf_path('ur5')
    path = manifest(tmp_path / 'm.csv', [('a', urdf, str(tmp_path / 'x*')),
                                         ('b', urdf, str(tmp_path / 'y*'))])
    status, text, err = run([path, '--out', tmp_path / 'o'], capsys)
    assert status == 1 and 'no bag could be used' in err
    failed = [line for line in text.splitlines() if line.startswith('failed:')]
    assert [('line 2' in f, 'line 3' in f) for f in failed] == [(True, False), (False, True)]


def test_a_bag_listed_twice_is_counted_once_and_said(small, tmp_path, capsys):
    urdf = os.path.join(small, 'r01', 'robot.urdf')
    path = tmp_path / 'm.yaml'
    path.write_text(json.dumps([{'robot': 'r01', 'urdf': urdf, 'bags': [
        os.path.join(small, 'r01', 'day*'), os.path.join(small, 'r01', 'day01'),
        os.path.join(small, 'r01', '..', 'r01', 'day02')]}]))
    status, text, _ = run([path, '--out', tmp_path / 'o'], capsys)
    rows = table(tmp_path / 'o')
    assert len(rows) == 2 * 6 * 3            # two bags, six joints, three parameters
    assert text.startswith('2 bags of 1 robot,')
    twice = [line for line in text.splitlines() if 'listed twice' in line]
    assert len(twice) == 1 and '(2): ' in twice[0]       # one line per kind, with its count


# -- options ---------------------------------------------------------------------------------

@pytest.mark.parametrize('gravity', ['nan 0 -9.81', '0 0 1e300', '0 0 inf'])
def test_an_impossible_gravity_is_refused_naming_the_row(small, tmp_path, capsys, gravity):
    urdf = os.path.join(small, 'r01', 'robot.urdf')
    path = manifest(tmp_path / 'm.csv', [('r01', urdf, os.path.join(small, 'r01', 'day*'),
                                          gravity)], header='robot,urdf,bag,gravity')
    status, _, err = run([path, '--out', tmp_path / 'o'], capsys)
    assert status == 1 and 'line 2: option gravity' in err


@pytest.mark.parametrize('option, value, says', [
    ('--chunk', '1e300', 'a year'), ('--chunk', 'nan', 'a year'),
    ('--scheduler', '', 'tcp://host:port'), ('--scheduler', 'ucx://127.0.0.1:1', "'ucx'"),
    ('--scheduler', 'tcp://127.0.0.1:99999', '65535'), ('--workers', '0', '1 to 4096'),
    ('--scheduler', 'tls://localhost:1', 'certificates'),
    ('--scheduler', 'localhost:8786', 'tcp://localhost:8786'),
    ('--scheduler', 'tcp://a b:1', 'host name'),
    ('--scheduler', 'tcp://user@localhost:1', 'no user@'),
    ('--scheduler', 'tcp://999.999.999.999:1', 'IP address'),
    ('--scheduler', 'tcp://::1:8786', 'IPv6 in brackets'),
    ('--scheduler', 'tcp://no-such-host.invalid:8786', 'resolve'),
    ('--baseline-days', '1e308', 'days')])
def test_an_impossible_option_is_refused_at_once_saying_what_is_allowed(
        tmp_path, capsys, option, value, says):
    from spatial_dynamics.replay.__main__ import main as replay
    for command in (main, lambda argv: replay(['fleet'] + argv)):
        with pytest.raises(SystemExit) as stop:
            command([str(tmp_path), option, value, '--out', str(tmp_path / 'o')])
        assert stop.value.code == 2
        err = capsys.readouterr().err
        assert option in err and says in err


def test_a_reader_that_goes_away_ends_the_output_quietly(small, tmp_path):
    proc = subprocess.Popen([sys.executable, '-m', 'spatial_dynamics.fleet', small, '--out',
                             str(tmp_path / 'o'), '--serial', '--no-plots'],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()                      # as `| head -1` does once it has its line
    err = proc.stderr.read().decode()
    proc.wait(timeout=300)
    assert 'Traceback' not in err and 'BrokenPipe' not in err, err


# -- where the command writes ---------------------------------------------------------------

@pytest.mark.parametrize('option, where, says', [
    ('--out', 'r01/day01', 'in the bag'), ('--out', 'r01/day01/sub', 'in the bag'),
    ('--cache', 'r02/day02', 'in the bag'), ('--out', '.', 'SOURCE'),
    ('--cache', '.', 'SOURCE')])
def test_an_output_in_a_bag_or_the_source_is_refused_before_any_work(
        small, tmp_path, capsys, option, where, says):
    folder = tmp_path / 'fleet'
    shutil.copytree(small, folder)
    before = sorted(str(p) for p in folder.rglob('*'))
    argv = [folder, option, folder / where]
    if option == '--cache':
        argv += ['--out', tmp_path / 'o']
    status, _, err = run(argv, capsys)
    assert status == 1 and err.startswith(f'error: {option} ') and says in err, err
    assert sorted(str(p) for p in folder.rglob('*')) == before
    assert not os.path.exists(tmp_path / 'o')


@pytest.mark.parametrize('option, value', [('--out', ''), ('--cache', ''), ('--out', 'file'),
                                           ('--cache', 'file'), ('--out', 'file/below')])
def test_an_output_folder_that_cannot_be_one_is_a_usage_error(
        small, tmp_path, capsys, option, value):
    (tmp_path / 'file').write_text('kept\n')
    value = str(tmp_path / value) if value else value
    with pytest.raises(SystemExit) as stop:
        main([small, option, value, '--serial'])
    assert stop.value.code == 2
    assert f'argument {option}:' in capsys.readouterr().err
    assert (tmp_path / 'file').read_text() == 'kept\n'


def test_a_local_cluster_leaves_no_scratch_folder(small, tmp_path):
    pytest.importorskip('distributed')
    temp, out = tmp_path / 'tmp', tmp_path / 'o'
    temp.mkdir()
    done = subprocess.run([sys.executable, '-m', 'spatial_dynamics.fleet', small, '--out',
                           str(out), '--workers', '2', '--no-plots'], capture_output=True,
                          text=True, timeout=300, env=dict(os.environ, TMPDIR=str(temp)))
    assert done.returncode in (0, 3, 4), done.stderr
    assert os.listdir(temp) == []
    assert sorted(os.listdir(out)) == ['cache', 'drift.txt', 'fleet.csv', 'robots.csv']


# -- Ctrl-C and SIGTERM ------------------------------------------------------------------------

#: Where the child is stopped: in staging a bag (its metadata read), in writing a plot, in a
#: task (SIGTERM sent to itself).
STOPS = {
    'staging': ('from spatial_dynamics.recordings import bags\n'
                'def stop(*args, **kwargs):\n'
                '    raise KeyboardInterrupt\n'
                'bags.load_yaml = stop\n'),
    'plot': ('from matplotlib.figure import Figure\n'
             'def stop(self, f, **kwargs):\n'
             '    f.write(b"half a plot")\n'
             '    raise KeyboardInterrupt\n'
             'Figure.savefig = stop\n'),
    'sigterm': ('import os, signal\n'
                'from spatial_dynamics.fleet import engine\n'
                'real = engine.process\n'
                'def stop(task):\n'
                '    os.kill(os.getpid(), signal.SIGTERM)\n'
                '    return real(task)\n'
                'engine.process = stop\n')}


@pytest.mark.parametrize('where', sorted(STOPS))
def test_an_interrupted_run_says_so_in_one_line_and_leaves_no_temporary(small, tmp_path, where):
    temp, out = tmp_path / 'tmp', tmp_path / 'o'
    temp.mkdir()
    script = (f'import sys, tempfile\ntempfile.tempdir = {str(temp)!r}\n{STOPS[where]}'
              'from spatial_dynamics.replay.__main__ import main\n'
              f'sys.exit(main(["fleet", {small!r}, "--out", {str(out)!r}, "--serial"]))\n')
    done = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True,
                          timeout=300)
    if where == 'plot':         # the plots come after the tables
        assert sorted(os.listdir(out)) == ['cache', 'drift.txt', 'fleet.csv', 'robots.csv']
    assert (done.returncode, done.stderr) == ((143, 'terminated\n') if where == 'sigterm'
                                              else (130, 'interrupted\n'))
    assert os.listdir(temp) == []
    assert [f for _, _, files in os.walk(out) for f in files if f.endswith('.tmp')] == []


def test_a_local_worker_drops_only_the_heartbeat_its_closing_scheduler_fails():
    """The command's workers drop the heartbeat failure of a closing cluster, and only that.

    Closing the cluster (Ctrl-C too) closes its scheduler first: a worker whose heartbeat then
    found it gone logged a traceback at ERROR after ``interrupted`` (seen in CI).
    """
    import io
    import logging
    from spatial_dynamics.fleet.engine import quiet_closing
    logger = logging.getLogger('distributed.worker')
    stream = io.StringIO()
    handler = logging.StreamHandler(stream)
    logger.addHandler(handler)
    filters = list(logger.filters)
    try:
        quiet_closing()
        quiet_closing()           # once is enough: not a second filter
        assert len(logger.filters) == len(filters) + 1
        try:
            raise OSError('Stream is closed')
        except OSError:
            logger.exception('Failed to communicate with scheduler during heartbeat.')
        logger.error('Compute Failed: a real error')
        assert stream.getvalue() == 'Compute Failed: a real error\n'
    finally:
        logger.removeHandler(handler)
        logger.filters[:] = filters


def test_ctrl_c_on_a_local_cluster_is_one_line_not_a_traceback_per_worker(small, tmp_path):
    pytest.importorskip('distributed')
    # Ctrl-C goes to every process of the terminal's group; the command's own is held back
    # a moment, so that a worker which would print a traceback has the time to
    script = ('import os, signal, sys, time\n'
              'from spatial_dynamics.fleet import command\n'
              'class Progress(command.Progress):\n'
              '    def __call__(self, result):\n'
              '        before = signal.signal(signal.SIGINT, lambda *args: None)\n'
              '        os.killpg(0, signal.SIGINT)\n'
              '        time.sleep(3)\n'
              '        signal.signal(signal.SIGINT, before)\n'
              '        raise KeyboardInterrupt\n'
              'command.Progress = Progress\n'
              'from spatial_dynamics.replay.__main__ import main\n'
              f'sys.exit(main(["fleet", {small!r}, "--out", {str(tmp_path / "o")!r}, '
              '"--workers", "2"]))\n')
    done = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True,
                          timeout=300, start_new_session=True)
    assert (done.returncode, done.stderr) == (130, 'interrupted\n')


# -- a cached re-run reads no bag and starts no cluster --------------------------------------

def test_a_cached_rerun_reads_no_bag_starts_no_cluster_and_draws_no_plot(small, tmp_path,
                                                                         capsys, monkeypatch):
    from spatial_dynamics.fleet import command, task
    from spatial_dynamics.recordings import bags
    out = tmp_path / 'o'
    assert main([small, '--out', str(out), '--serial']) == command.NOT_JUDGED
    first = capsys.readouterr().out
    reads = []

    def counted(name, real):
        def read(*args, **kwargs):
            reads.append((name, args[1] if name == 'hash' else args[0]))
            return real(*args, **kwargs)
        return read
    monkeypatch.setattr(task, '_hash_file', counted('hash', task._hash_file))
    for name in ('read_joint_states', 'read_joint_states_between', 'time_range'):
        monkeypatch.setattr(bags, name, counted(name, getattr(bags, name)))

    from spatial_dynamics.fleet import engine
    kept = []

    def write_atomic(path, text, what):
        kept.append(what)
        return real_write(path, text, what)
    real_write = engine.write_atomic
    monkeypatch.setattr(engine, 'write_atomic', write_atomic)

    def no_cluster(*args, **kwargs):
        raise AssertionError('a cluster was started')
    monkeypatch.setattr(command, 'local_cluster', no_cluster)
    monkeypatch.setattr(command, '_draw', no_cluster)
    assert main([small, '--out', str(out)]) == command.NOT_JUDGED     # no --serial
    again = capsys.readouterr().out
    assert '(4 from the cache, 0 failed)' in again
    assert again.split('\n', 1)[1] == first.split('\n', 1)[1]
    # the URDFs' bytes are hashed (for the content keys), no bag's
    assert {os.path.basename(path) for _, path in reads} == {'robot.urdf'}, reads
    assert kept == [], kept         # nor is what the cache knows of them written again


@pytest.mark.parametrize('where', [['--workers', '2'], ['--scheduler', 'tcp://127.0.0.1:1']])
def test_a_cached_rerun_starts_or_contacts_no_cluster_whatever_the_options(
        small, tmp_path, capsys, monkeypatch, where):
    pytest.importorskip('distributed')
    import distributed
    from spatial_dynamics.fleet import command
    out = str(tmp_path / 'o')
    first = main([small, '--out', out, '--serial', '--no-plots'])
    capsys.readouterr()

    def no_cluster(*args, **kwargs):
        raise AssertionError('a cluster was started or contacted')
    monkeypatch.setattr(command, 'local_cluster', no_cluster)
    monkeypatch.setattr(distributed, 'Client', no_cluster)
    assert main([small, '--out', out, '--no-plots'] + where) == first
    said = capsys.readouterr()
    assert '(4 from the cache, 0 failed)' in said.out
    assert said.err.splitlines() == [
        'note: every bag is in the cache: no cluster '
        + ('contacted' if '--scheduler' in where else 'started')]


def test_more_workers_than_four_a_core_are_cut_to_that_and_said(small, tmp_path, capsys,
                                                                monkeypatch):
    from spatial_dynamics.fleet import command
    asked = []

    def local_cluster(workers, *rest):
        asked.append(workers)
        raise ValueError('no cluster in this test')
    monkeypatch.setattr(command, 'local_cluster', local_cluster)
    assert main([small, '--out', str(tmp_path / 'o'), '--workers', '4096']) == 1
    cores = len(os.sched_getaffinity(0))
    assert asked == [4 * cores]
    assert f'--workers 4096 is more than 4 a core ({cores} here)' in capsys.readouterr().err


def test_the_local_cluster_serves_no_dashboard_nor_any_page(tmp_path):
    pytest.importorskip('distributed')
    import urllib.error
    import urllib.request
    from spatial_dynamics.fleet.engine import local_cluster
    with local_cluster(1, str(tmp_path)) as cluster:
        server = cluster.scheduler.http_server
        assert server.address == '127.0.0.1'
        for page in ('/', '/status', '/health', '/info/main/workers.html', '/metrics',
                     '/json/counts.json'):
            with pytest.raises(urllib.error.HTTPError) as answer:
                urllib.request.urlopen(f'http://127.0.0.1:{server.port}{page}', timeout=60)
            assert answer.value.code == 404, page


#: What a cached re-run needs none of: the plots', the cluster's, the bags' readers, and
#: scipy.stats (seconds to import on a busy machine, for one χ² quantile).
NOT_ON_A_RERUN = ('matplotlib', 'dask', 'distributed', 'rosbags', 'yaml', 'scipy.stats')


def test_a_cached_rerun_imports_nothing_it_does_not_use(small, tmp_path):
    out = str(tmp_path / 'o')
    script = ('import sys\n'
              'from spatial_dynamics.fleet import main\n'
              f'status = main([{small!r}, "--out", {out!r}, "--baseline-days", "0.5"])\n'
              f'print(status, [m for m in {NOT_ON_A_RERUN!r} if m in sys.modules])\n')
    for attempt in ('first', 'again'):
        done = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True,
                              timeout=600)
        assert done.returncode == 0, done.stderr
    status, imported = done.stdout.splitlines()[-1].split(' ', 1)
    assert '(4 from the cache, 0 failed)' in done.stdout
    assert int(status) in (0, 3, 4) and imported == '[]', done.stdout
