# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The latency benchmark's options: out of range or an unwritable output is refused first."""

import os

import pytest

from spatial_dynamics.tools.latency import parse_args


@pytest.mark.parametrize('option, value', [
    ('--rate', '0'), ('--rate', '-5'), ('--rate', '1e6'), ('--rate', 'nan'),
    ('--seconds', '0'), ('--seconds', '3601'), ('--seconds', 'inf'),
    ('--busy', '-1'), ('--busy', str(4 * (os.cpu_count() or 1) + 1)),
    ('--priority', '-1'), ('--priority', '100'),
    ('--input-depth', '0'), ('--block', '0'), ('--warmup', '-1'), ('--warmup', 'inf'),
    ('--warmup', '1e300'), ('--warmup', '61'), ('--input-depth', '2147483648'),
    ('--input-depth', '100001'),
])
def test_out_of_range_numbers_are_refused(option, value, capsys):
    with pytest.raises(SystemExit) as exit:
        parse_args([option, value])
    assert exit.value.code == 2
    assert option in capsys.readouterr().err


def test_the_ranges_keep_the_defaults_and_real_values():
    args = parse_args(['--rate', '1e5', '--seconds', '3600', '--priority', '99', '--busy', '0',
                       '--input-depth', '1', '--warmup', '0', '--block', '0.5'])
    assert (args.rate, args.seconds, args.priority, args.input_depth) == (1e5, 3600, 99, 1)
    defaults = parse_args([])
    assert (defaults.rate, defaults.seconds, defaults.warmup) == (1000.0, 10.0, 1.0)
    longest = parse_args(['--warmup', '60', '--input-depth', '100000'])
    assert (longest.warmup, longest.input_depth) == (60.0, 100_000)


@pytest.mark.parametrize('option', ['--plot', '--json'])
@pytest.mark.parametrize('kind', ['directory', 'fifo', 'folder under a file'])
def test_an_output_that_cannot_be_written_is_refused_first(option, kind, tmp_path, capsys):
    path = tmp_path / 'out'
    if kind == 'directory':
        path.mkdir()
    elif kind == 'fifo':
        os.mkfifo(path)
    else:
        (tmp_path / 'file').write_text('x')
        path = tmp_path / 'file' / 'missing' / 'out'
    with pytest.raises(SystemExit) as exit:
        parse_args([option, str(path)])
    assert exit.value.code == 2
    err = capsys.readouterr().err
    assert option in err and str(path) in err, err


@pytest.mark.parametrize('option, path', [('--json', '/proc/version'),
                                          ('--plot', '/proc/latency.png'),
                                          ('--log-dir', '/proc/sd_latency_logs'),
                                          ('--log-dir', '/sys/sd_latency_logs')])
def test_an_output_in_a_folder_no_file_can_be_created_in_is_refused_first(option, path, capsys):
    """As root, os.access called /proc writable: `--json /proc/version` ran, then failed.

    `--log-dir /sys/foo` ended in os.makedirs' PermissionError traceback. Both are refused
    before the run, with one line naming the option.
    """
    with pytest.raises(SystemExit) as exit:
        parse_args([option, path])
    err = capsys.readouterr().err
    assert exit.value.code == 2 and option in err and path in err, err
    assert 'Traceback' not in err and err.rstrip().splitlines()[-1].count(path) == 1, err


def test_the_results_not_written_at_the_end_name_the_file():
    """A JSON that cannot be written at the end: 'cannot write None: Input/output error'."""
    from spatial_dynamics.tools.latency_report import write_json
    with pytest.raises(ValueError) as caught:
        write_json('/proc/version', {'robot': 'x'})
    assert '--json' in str(caught.value) and "'/proc/version'" in str(caught.value)


@pytest.mark.parametrize('option', ['--plot', '--json', '--urdf', '--log-dir'])
def test_an_empty_path_is_refused(option, capsys):
    """`--plot ''` became '.png'; `--json ''` and `--urdf ''` were silently ignored."""
    with pytest.raises(SystemExit) as exit:
        parse_args([option, ''])
    err = capsys.readouterr().err
    assert exit.value.code == 2 and option in err and 'empty path' in err, err


def test_every_output_creates_its_missing_folders_before_the_run(tmp_path):
    """--log-dir created missing folders while --json and --plot refused them: all create."""
    from spatial_dynamics.tools.latency import make_folders
    args = parse_args(['--plot', str(tmp_path / 'a' / 'h.png'),
                       '--json', str(tmp_path / 'b' / 'c' / 'r.json'),
                       '--log-dir', str(tmp_path / 'd' / 'logs')])
    assert sorted(os.listdir(tmp_path)) == []   # checked, nothing made yet
    make_folders(args)
    assert (tmp_path / 'a').is_dir() and (tmp_path / 'b' / 'c').is_dir()
    assert (tmp_path / 'd' / 'logs').is_dir()
    assert not any(p.is_file() for p in tmp_path.rglob('*'))   # the checks left nothing


def test_a_plot_without_a_suffix_is_checked_as_the_file_written(tmp_path, capsys):
    """For NAME, matplotlib writes NAME.png: a folder NAME.png is refused before the run."""
    (tmp_path / 'hist.png').mkdir()
    with pytest.raises(SystemExit) as exit:
        parse_args(['--plot', str(tmp_path / 'hist')])
    assert exit.value.code == 2 and 'hist.png' in capsys.readouterr().err
    assert parse_args(['--plot', str(tmp_path / 'other')]).plot == str(tmp_path / 'other.png')


@pytest.mark.parametrize('inside', [False, True])
def test_a_log_dir_that_is_a_file_is_refused_first(inside, tmp_path, capsys):
    path = tmp_path / 'file'
    path.write_text('x')
    with pytest.raises(SystemExit) as exit:
        parse_args(['--log-dir', str(path / 'sub' if inside else path)])
    assert exit.value.code == 2 and 'not a folder' in capsys.readouterr().err
    assert parse_args(['--log-dir', str(tmp_path / 'new' / 'logs')]).log_dir
    (tmp_path / 'logs').mkdir()
    os.mkfifo(tmp_path / 'logs' / 'relay.log')   # a log of the run that cannot be written
    with pytest.raises(SystemExit) as exit:
        parse_args(['--log-dir', str(tmp_path / 'logs')])
    assert exit.value.code == 2 and 'relay.log' in capsys.readouterr().err


def test_a_run_that_sends_nothing_is_refused(capsys):
    with pytest.raises(SystemExit) as exit:
        parse_args(['--rate', '1e-3', '--seconds', '1'])
    assert exit.value.code == 2 and 'sends no message' in capsys.readouterr().err


@pytest.mark.parametrize('option, value', [
    ('--seconds', '0'), ('--seconds', '-1'), ('--seconds', 'nan'), ('--frequency', 'nan'),
    ('--frequency', '0'), ('--amplitude', '-0.1'), ('--timeout', '0'), ('--laws', 'bogus'),
    ('--laws', 'pd,xx'), ('--busy', '-1'), ('--priority', '100'),
])
def test_closed_loop_refuses_numbers_out_of_range_first(option, value, capsys):
    """`--seconds 0` printed perfect tracking and exit 0; -1, nan and a bad law a traceback."""
    from spatial_dynamics.tools import closed_loop
    with pytest.raises(SystemExit) as exit:
        closed_loop.parse_args([option, value])
    assert exit.value.code == 2 and option in capsys.readouterr().err
    assert closed_loop.parse_args(['--laws', 'pd,ct', '--seconds', '0.5']).laws == 'pd,ct'


def test_answers_before_their_stamps_are_known_count_and_late_ticks_are_told_apart():
    """The pacer reports a block's stamps after the block: answers read before are kept.

    Five inputs 1 ms apart, of which the third came 0.05 ms before the fourth (the publisher
    late) and was not answered, and the fifth not answered after a full period: two not
    answered, one of them superseded; the early answers match once the stamps are known,
    with their reception time as given.
    """
    from spatial_dynamics.tools.latency_targets import Target
    target = Target.__new__(Target)
    target.name, target.sent, target.latency_ns, target.to_answer_ns = 'node', set(), {}, {}
    target.early, target.measuring, target.answers, target.cpu_ns = {}, True, 0, 0
    target.sending_s = 0.0
    target.period_ns = 1_000_000
    stamps = [10_000_000, 11_000_000, 11_950_000, 12_000_000, 13_000_000]

    class Stamp:
        def __init__(self, key):
            self.sec, self.nanosec = divmod(key, 1_000_000_000)

    class Answer:
        def __init__(self, key):
            self.header = type('Header', (), {'stamp': Stamp(key)})()
    for key in (stamps[0], stamps[1], stamps[3]):
        target._on_answer(Answer(key), {'received_timestamp': key + 400_000,
                                        'source_timestamp': key + 300_000})
    assert target.latency_ns == {}   # the stamps are not known yet
    target.add_sent(stamps)
    assert target.latency_ns == {stamps[i]: 400_000 for i in (0, 1, 3)}
    assert target.to_answer_ns == {stamps[i]: 300_000 for i in (0, 1, 3)}
    summary = target.summary()
    assert (summary['sent'], summary['answered']) == (5, 3)
    assert (summary['not_answered'], summary['not_answered_superseded']) == (2, 1)
    assert summary['p50_ms'] == pytest.approx(0.4)


def test_busy_loops_ignore_the_terminals_ctrl_c():
    """Ctrl-C reaches the busy loops too: they go on (the benchmark kills them), silently."""
    import signal
    import subprocess
    import time
    from spatial_dynamics.tools.driving import cpu_seconds
    from spatial_dynamics.tools.latency_targets import busy_loops
    (loop,) = busy_loops(1)
    try:
        deadline = time.monotonic() + 60.0
        while cpu_seconds(loop.pid) < 0.1:    # its loop runs: Python has started
            assert time.monotonic() < deadline and loop.poll() is None
            time.sleep(0.01)
        loop.send_signal(signal.SIGINT)
        try:
            loop.wait(1.0)
        except subprocess.TimeoutExpired:
            pass
        assert loop.poll() is None, 'a busy loop ended on SIGINT (with a traceback)'
    finally:
        loop.kill()
        loop.wait()


def test_blocks_are_counted_in_messages_and_one_that_holds_none_is_refused(capsys):
    """Blocks of 1 s at 0.5 Hz each rounded to 0 messages: 0 sent, a table of nan, exit 1."""
    from spatial_dynamics.tools.latency import counts
    with pytest.raises(SystemExit) as exit:
        parse_args(['--rate', '0.5', '--seconds', '2', '--block', '1'])
    assert exit.value.code == 2 and '--block' in capsys.readouterr().err
    # rate * seconds messages in all, whatever the blocks round to on their own
    assert counts(1.0, 3.0, 1.5) == [2, 1]
    assert sum(counts(1000.0, 1.0, 0.3)) == 1000
    assert counts(0.5, 2.0, 2.0) == [1]


@pytest.mark.parametrize('plot, json_path', [('hist.json', 'hist.json'), ('hist.txt', None),
                                             ('hist', 'hist.png')])
def test_a_plot_matplotlib_cannot_write_or_that_overwrites_the_json_is_refused_first(
        plot, json_path, tmp_path, capsys):
    """`--plot x.json --json x.json` ran the whole benchmark, then matplotlib's traceback."""
    argv = ['--plot', str(tmp_path / plot)]
    if json_path:
        argv += ['--json', str(tmp_path / json_path)]
    with pytest.raises(SystemExit) as exit:
        parse_args(argv)
    assert exit.value.code == 2 and '--plot' in capsys.readouterr().err
    assert parse_args(['--plot', str(tmp_path / 'h.svg'), '--json', str(tmp_path / 'h.json')])


def test_busy_loops_ignore_a_ctrl_c_while_python_starts():
    """SIGINT before the loop's own code ran ended it (killed, or a traceback from Python)."""
    import signal
    import subprocess
    from spatial_dynamics.tools.latency_targets import busy_loops
    (loop,) = busy_loops(1)
    try:
        loop.send_signal(signal.SIGINT)    # at once: its Python is still starting
        try:
            loop.wait(1.0)
        except subprocess.TimeoutExpired:
            pass
        assert loop.poll() is None, f'a busy loop ended on SIGINT ({loop.returncode})'
    finally:
        loop.kill()
        loop.wait()


class _Idle:
    """An executor with nothing to run."""

    def spin_once(self, timeout_sec):
        import time
        time.sleep(timeout_sec)


def _gone_pacer():
    """Return a Pacer whose process has exited."""
    import subprocess
    import sys
    from spatial_dynamics.tools.latency_pacer import Pacer
    pacer = Pacer.__new__(Pacer)
    pacer.watch = lambda: None
    pacer.process = subprocess.Popen([sys.executable, '-c', 'pass'], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, text=True)
    pacer.process.wait()
    return pacer


def test_a_pacer_that_exited_is_said_at_once_not_as_a_broken_pipe_or_a_timeout():
    """Killed mid-run: a BrokenPipeError traceback; while priming: 60 s, then 'did not answer'."""
    from spatial_dynamics.tools.latency_targets import Target
    target = Target.__new__(Target)
    target.name, target.answers = 'relay', 0
    for command in (lambda p: p.block(_Idle(), 0, 1000.0, 10, 0.0),
                    lambda p: p.prime(_Idle(), 0, target, timeout=30.0)):
        pacer = _gone_pacer()
        with pytest.raises(RuntimeError, match='pacer process exited'):
            command(pacer)


def test_a_target_that_exits_while_primed_or_measured_ends_the_run():
    """The node killed mid-run: the benchmark went on and printed its numbers, exit 0."""
    import subprocess
    import sys
    from spatial_dynamics.tools.latency_pacer import Pacer
    from spatial_dynamics.tools.latency_targets import exited, Target
    node = subprocess.Popen([sys.executable, '-c', 'pass'])
    node.wait()
    with pytest.raises(RuntimeError, match='inverse_dynamics exited'):
        exited({'relay': subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(30)']),
                'inverse_dynamics': node})
    pacer = Pacer.__new__(Pacer)
    pacer.process = subprocess.Popen([sys.executable, '-c', 'import sys; sys.stdin.read()'],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    pacer.watch = lambda: exited({'inverse_dynamics': node})
    target = Target.__new__(Target)
    target.name, target.answers = 'inverse_dynamics', 0
    try:
        with pytest.raises(RuntimeError, match='inverse_dynamics exited'):
            pacer.prime(_Idle(), 0, target, timeout=30.0)
    finally:
        pacer.process.kill()
        pacer.process.wait()


@pytest.mark.parametrize('signum, status', [('SIGINT', 130), ('SIGTERM', 143)])
def test_ctrl_c_or_sigterm_while_loading_is_one_line(signum, status, monkeypatch, capsys):
    """Ctrl-C while the robot loaded (before the nodes start): a KeyboardInterrupt traceback."""
    import signal
    from spatial_dynamics.tools import latency
    previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}

    def loading(urdf):
        os.kill(os.getpid(), getattr(signal, signum))
        raise AssertionError('the signal did not interrupt')
    monkeypatch.setattr(latency, 'robot_model', loading)
    try:
        assert latency.main(['--seconds', '1']) == status
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and f'interrupted ({signum})' in err, err


def test_a_urdf_that_cannot_be_loaded_is_one_line(tmp_path, capsys):
    """A malformed --urdf: a ValueError traceback."""
    import signal
    from spatial_dynamics.tools import latency
    bad = tmp_path / 'bad.urdf'
    bad.write_text("<robot name='x'><link name='a'/>")
    previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        assert latency.main(['--urdf', str(bad)]) == 1
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and '--urdf' in err and 'malformed' in err, err


@pytest.mark.parametrize('argv', [['--plot', 'x.txt'], ['--plot', 'x.json', '--json', 'x.json'],
                                  ['--json', '.']])
def test_closed_loop_refuses_outputs_it_cannot_write_first(argv, tmp_path, capsys, monkeypatch):
    """Each ran every law, then a traceback (matplotlib's ValueError, IsADirectoryError)."""
    from spatial_dynamics.tools import closed_loop
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exit:
        closed_loop.parse_args(argv)
    assert exit.value.code == 2 and argv[-2] in capsys.readouterr().err


def test_closed_loop_says_a_bad_urdf_and_a_ctrl_c_while_loading_in_one_line(
        tmp_path, capsys, monkeypatch):
    """Both were tracebacks: the handler was installed after the robot was loaded."""
    import signal
    from spatial_dynamics.tools import closed_loop
    bad = tmp_path / 'bad.urdf'
    bad.write_text("<robot name='x'><link name='a'/>")
    previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        assert closed_loop.main(['--urdf', str(bad), '--plot', '']) == 1
        err = capsys.readouterr().err
        assert err.count('\n') == 1 and 'malformed' in err, err

        def loading(urdf):
            os.kill(os.getpid(), signal.SIGINT)
            raise AssertionError('the signal did not interrupt')
        monkeypatch.setattr(closed_loop, 'robot_model', loading)
        assert closed_loop.main(['--plot', '']) == 130
        err = capsys.readouterr().err
        assert err.count('\n') == 1 and 'interrupted (SIGINT)' in err, err
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)


def test_closed_loop_refuses_an_output_that_is_an_input_or_a_log_of_the_run(
        tmp_path, capsys, monkeypatch):
    """Written over the robot's URDF, or over the node's log of the same run, with exit 0."""
    from spatial_dynamics.tools import closed_loop
    monkeypatch.chdir(tmp_path)
    robot = tmp_path / 'r.urdf'
    robot.write_text('<robot name="r"/>')
    (tmp_path / 'link.urdf').symlink_to(robot)
    for argv, said in [
            (['--urdf', str(robot), '--json', str(robot)], 'the file --urdf reads'),
            (['--urdf', 'link.urdf', '--json', str(robot)], 'the file --urdf reads'),
            (['--robot-urdf', str(robot), '--plot', '', '--json', 'r.urdf'],
             'the file --robot-urdf reads'),
            (['--laws', 'pd_ff', '--log-dir', 'logs', '--json',
              'logs/closed_loop_pd_feedforward_full_node.log'], 'name the same path'),
            (['--laws', 'ct', '--plan', '--log-dir', 'logs', '--plot',
              'logs/closed_loop_plan_computed_torque_full_sim.log.png', '--json',
              'logs/closed_loop_plan_computed_torque_full_sim.log'], 'name the same path')]:
        with pytest.raises(SystemExit) as exit:
            closed_loop.parse_args(argv)
        err = capsys.readouterr().err
        assert exit.value.code == 2 and said in err, (argv, err)
    assert robot.read_text() == '<robot name="r"/>'


@pytest.mark.parametrize('make, said', [
    (lambda d: '', 'empty'),
    (lambda d: os.symlink(d / 'nowhere', d / 'ld') or str(d / 'ld'), 'leads to no folder'),
    (lambda d: os.symlink(d / 'loop', d / 'loop') or str(d / 'loop'), 'leads to no folder'),
    (lambda d: str(d / ('b' * 300)), 'longer than a folder name can be')])
def test_closed_loop_refuses_a_log_dir_it_cannot_make_first(make, said, tmp_path, capsys):
    """A ``--log-dir`` that cannot be made is one line before anything starts.

    '' printed '(their output in /)', a dangling link or a loop FileExistsError, a 300-byte
    name OSError: tracebacks at os.makedirs, after the header.
    """
    from spatial_dynamics.tools import closed_loop
    with pytest.raises(SystemExit) as exit:
        closed_loop.parse_args(['--log-dir', make(tmp_path), '--plot', ''])
    err = capsys.readouterr().err
    assert exit.value.code == 2 and said in err, err


def test_closed_loop_refuses_an_empty_json_and_a_law_given_twice(capsys):
    """``--json ''`` and a law named twice are refused.

    The first ran and wrote nothing (exit 0); ``pd_ff,pd_ff`` ran the law twice, its logs
    written over and the law twice in the JSON.
    """
    from spatial_dynamics.tools import closed_loop
    for argv, said in [(['--json', ''], 'empty path'),
                       (['--laws', 'pd_ff,pd,pd_ff'], 'pd_ff given twice')]:
        with pytest.raises(SystemExit) as exit:
            closed_loop.parse_args(argv)
        err = capsys.readouterr().err
        assert exit.value.code == 2 and said in err, err


def test_closed_loop_refuses_a_frequency_its_1_ms_sampling_cannot_hold():
    """The highest frequency it suggested (134 Hz on the demo arm) diverged at the 1 ms step.

    That run's lockstep then stalled until ``--timeout``. Above ω·dt = 0.5 it is refused.
    """
    import math
    from spatial_dynamics.tools import closed_loop
    urdf, model = closed_loop.robot_model(None)
    top = closed_loop.MAX_OMEGA_DT / (2.0 * math.pi * closed_loop.TIMESTEP)
    assert closed_loop.laws_error(model, [0, 1, 2], 0.99 * top) is None
    error = closed_loop.laws_error(model, [0], 1.01 * top)
    assert error is not None and 'sampled every 1 ms' in error, error
    assert f'at most {math.floor(top * 10) / 10:g} Hz' in error, error


def test_closed_loop_says_the_highest_frequency_whose_gains_the_node_takes(monkeypatch):
    """``--frequency 600`` is refused first, with the highest frequency that fits.

    It ended with 'the node exited' (its log: kp 1.58e6 beyond 1e6). The frequency said has
    its gains within the node's bounds, and 1 % more is beyond them (the sampling's bound
    lifted here: it is lower on the demo arm).
    """
    import re
    from spatial_dynamics.ros.control import MAX_KD, MAX_KP
    from spatial_dynamics.tools import closed_loop
    monkeypatch.setattr(closed_loop, 'MAX_OMEGA_DT', 1e9)
    urdf, model = closed_loop.robot_model(None)
    q0 = closed_loop.start_point(model)
    for picks in ([0], [2], [0, 1, 2]):
        assert closed_loop.laws_error(model, picks, 5.0) is None
        error = closed_loop.laws_error(model, picks, 999.0)
        assert error is not None and 'beyond what the node takes' in error, error
        top = float(re.search(r'at most ([0-9.]+) Hz', error).group(1))
        for k in picks:
            kp, kd = closed_loop.gains(model, q0, closed_loop.LAWS[k][1]['control_mode'], top)
            assert kp.max() <= MAX_KP and kd.max() <= MAX_KD
        assert closed_loop.laws_error(model, picks, top) is None
        assert closed_loop.laws_error(model, picks, 1.01 * top) is not None


def test_closed_loop_refuses_a_robot_without_joints_and_a_bad_robot_urdf_first(
        tmp_path, capsys, handlers_kept):
    """A robot without joints and a ``--robot-urdf`` it cannot read: one line, first.

    No joints: 'the node exited' (its log: kp needs a value); a --robot-urdf FIFO: the run
    started, then 'the sim exited'.
    """
    from spatial_dynamics.tools import closed_loop
    lone = tmp_path / 'lone.urdf'
    lone.write_text("<robot name='lone'><link name='base'/></robot>")
    fifo = tmp_path / 'fifo'
    os.mkfifo(fifo)
    assert closed_loop.main(['--urdf', str(lone), '--plot', '']) == 1
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'no joints' in err, err
    assert closed_loop.main(['--robot-urdf', str(fifo), '--plot', '']) == 1
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and '--robot-urdf' in err, err


def test_closed_loop_keeps_an_earlier_json_when_a_law_does_not_finish(
        tmp_path, capsys, monkeypatch, handlers_kept):
    """An interrupted or failed run replaced the file with the laws that had run (``[]``)."""
    from spatial_dynamics.tools import closed_loop
    kept = tmp_path / 'keep.json'
    kept.write_text('{"laws": ["an earlier complete run"]}')

    def run_law(name, *args):
        if name == 'computed torque':
            raise RuntimeError(f'{name}: the node exited')
        return closed_loop.Run(name, ['j'])
    monkeypatch.setattr(closed_loop, 'run_law', run_law)
    assert closed_loop.main(['--plot', '', '--json', str(kept)]) == 1
    err = capsys.readouterr().err
    assert 'the node exited' in err and 'not written' in err, err
    assert kept.read_text() == '{"laws": ["an earlier complete run"]}'


def measured_target(latencies_ms, late_stamps=()):
    """Return a Target (no DDS) that sent one input per ms and got ``latencies_ms`` answers.

    ``late_stamps``: extra inputs, not answered, each 0.05 ms before the next one (the
    publisher late).
    """
    from spatial_dynamics.tools.latency_targets import Target
    target = Target.__new__(Target)
    target.name, target.latency_ns, target.to_answer_ns = 'node', {}, {}
    target.early, target.measuring, target.answers, target.cpu_ns = {}, True, 0, 0
    target.sending_s = 0.0
    target.period_ns = 1_000_000
    stamps = [10_000_000 + 1_000_000 * k for k in range(len(latencies_ms))]
    target.sent = set(stamps) | {stamps[k] - 50_000 for k in late_stamps}
    for key, ms in zip(stamps, latencies_ms):
        target.latency_ns[key] = round(ms * 1e6)
        target.to_answer_ns[key] = round(ms * 1e6) // 2
    return target


@pytest.mark.parametrize('count', [1, 99, 100, 999, 1000])
def test_a_quantile_is_reported_only_from_enough_answers_to_tell_it_from_the_maximum(count):
    """p99.9 of 100 answers is their maximum: it needs 1000 answers, p99 needs 100."""
    import json

    import numpy as np

    from spatial_dynamics.tools.latency_report import format_table, legend
    latencies = np.linspace(0.1, 2.0, count)
    summary = measured_target(latencies).summary()
    assert summary['max_ms'] == pytest.approx(latencies.max())
    expected = {'p50': np.percentile(latencies, 50.0),
                'p99': np.percentile(latencies, 99.0) if count >= 100 else None,
                'p99.9': np.percentile(latencies, 99.9) if count >= 1000 else None}
    for prefix, scale in (('', 1.0), ('to_answer_', 0.5)):
        for key, value in expected.items():
            got = summary[f'{prefix}{key}_ms']
            assert got == (None if value is None else pytest.approx(scale * value, abs=1e-6))
    again = json.loads(json.dumps(summary))     # not reported: null, not NaN, in the JSON
    assert again['p99.9_ms'] is None if count < 1000 else again['p99.9_ms'] > 0
    row = format_table([summary]).splitlines()[-1].split()
    cells = row[3:7]                            # p50 p99 p99.9 max of the round trip
    assert [c == '-' for c in cells] == [False, count < 100, count < 1000, False], row
    label = legend('node', latencies, count)
    shown = 'p99.9' if count >= 1000 else 'p99' if count >= 100 else 'p50'
    assert f', {shown} ' in label and label.count(' ms') == 1, label


def test_the_late_publication_note_is_printed_only_when_an_input_was_late():
    from spatial_dynamics.tools.latency_report import difference_line, not_answered_line
    on_time = measured_target([0.4] * 5).summary()
    assert not_answered_line(on_time) == 'node: 0 inputs not answered'
    late = measured_target([0.4] * 5, late_stamps=[2]).summary()
    assert (late['not_answered'], late['not_answered_superseded']) == (1, 1)
    assert 'published late' in not_answered_line(late)
    line = difference_line(late, on_time)
    assert 'p50 +0.000 ms' in line and 'p99 -' in line and 'p99.9 -' in line, line


@pytest.mark.parametrize('tool', ['latency', 'closed_loop'])
@pytest.mark.parametrize('option', ['--priority', '--busy'])
def test_an_integer_option_given_a_fraction_says_it_is_not_an_integer(tool, option, capsys):
    import importlib
    parse = importlib.import_module(f'spatial_dynamics.tools.{tool}').parse_args
    with pytest.raises(SystemExit) as exit:
        parse([option, '1.5'])
    err = capsys.readouterr().err
    assert exit.value.code == 2 and option in err and "not an integer: '1.5'" in err, err
    if tool == 'latency':
        with pytest.raises(SystemExit):
            parse(['--input-depth', '2.5'])
        assert "not an integer: '2.5'" in capsys.readouterr().err


def test_the_json_has_null_where_a_target_had_no_answer():
    """A target that answered nothing has no maximum or mean: null in the JSON, never NaN."""
    import json
    from spatial_dynamics.tools.latency_report import json_safe
    from spatial_dynamics.tools.latency_targets import Target
    target = Target.__new__(Target)
    target.name, target.sent, target.latency_ns, target.to_answer_ns = 'node', set(), {}, {}
    target.early, target.measuring, target.answers, target.cpu_ns = {}, True, 0, 0
    target.sending_s = 0.0
    target.period_ns = 1_000_000
    target.add_sent([10_000_000, 11_000_000])
    rows = json_safe([target.summary()])
    text = json.dumps(rows, allow_nan=False)
    assert json.loads(text)[0]['max_ms'] is None and json.loads(text)[0]['mean_ms'] is None
    assert json.loads(text)[0]['sent'] == 2 and json.loads(text)[0]['answered'] == 0


@pytest.mark.parametrize('count', [0, 999, 1000])
def test_the_machines_floor_is_the_pacers_wake_ups_with_the_kernels_preemption(count):
    """The floor line: quantiles of how late the pacer woke, those over 1 ms counted."""
    import json

    import numpy as np

    from spatial_dynamics.tools.latency_report import json_safe, machine_line, wake_ups
    late_ns = [50_000] * (count - 2) + [1_500_000, 900_000] if count else []
    machine = wake_ups(late_ns, 'none')
    assert machine['wake_ups'] == count and machine['over_1ms'] == (1 if count else 0)
    if count:
        assert machine['max_ms'] == pytest.approx(1.5)
        assert machine['p50_ms'] == pytest.approx(0.05)
        assert machine['p99.9_ms'] == (pytest.approx(np.percentile(np.array(late_ns) * 1e-6,
                                                                   99.9))
                                       if count >= 1000 else None)
    from spatial_dynamics.tools.latency_report import machine_legend
    label = machine_legend(np.array(late_ns) * 1e-6)
    assert f'{count} wake-ups' in label and (', p99.9 ' in label) == (count >= 1000), label
    line = machine_line(machine, 'SCHED_FIFO 51')
    assert 'SCHED_FIFO 51' in line and 'kernel preemption: none' in line, line
    if count:
        assert f'({machine["over_1ms"]} of {count} wake-ups over 1 ms)' in line, line
    else:   # it never slept: no floor, said so (not '0 of 0 wake-ups' and '-')
        assert 'never slept' in line and 'wake-ups' not in line, line
    json.dumps(json_safe([machine]), allow_nan=False)   # no NaN reaches the JSON


def test_the_kernels_preemption_model_is_one_of_linuxs():
    from spatial_dynamics.tools.latency_targets import kernel_preemption
    assert kernel_preemption() in ('none', 'voluntary', 'full', 'lazy', 'rt', 'unknown')


_NAMED_THREADS = """
import ctypes, os, sys, threading
done = threading.Event()
def run(name):
    ctypes.CDLL(None).prctl(15, name.encode())   # PR_SET_NAME, as the node names its threads
    sys.stdout.write(f'{name} {threading.get_native_id()}\\n')   # one write: whole lines
    sys.stdout.flush()
    done.wait()
for name in sys.argv[1:]:
    threading.Thread(target=run, args=(name,), daemon=True).start()
sys.stdin.read()
"""


def test_the_scheduling_reported_is_read_from_the_threads_not_taken_from_the_request():
    """`--priority 50` without the privilege: the header said 'node and relay SCHED_FIFO 50'.

    Node and relay logged EPERM and answered under normal scheduling. What each ran under is
    now read from its answering thread (and the receive threads that share a real-time one).
    """
    import subprocess
    import sys
    from spatial_dynamics.tools.latency_targets import scheduling_of, scheduling_text
    child = subprocess.Popen(
        [sys.executable, '-c', _NAMED_THREADS, 'answering', 'dds.udp.7411'],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    plain = subprocess.Popen([sys.executable, '-c', 'import sys; sys.stdin.read()'],
                             stdin=subprocess.PIPE)
    try:
        tids = dict(child.stdout.readline().split() for _ in range(2))
        answering, receive = int(tids['answering']), int(tids['dds.udp.7411'])
        assert scheduling_of(child.pid) == 'normal scheduling'
        assert scheduling_of(plain.pid).startswith('unknown')   # not answering yet
        refused = 'normal scheduling (SCHED_FIFO 51 not permitted: EPERM)'
        text = scheduling_text(50, {'inverse_dynamics': scheduling_of(child.pid),
                                    'relay': 'normal scheduling', 'publisher': refused,
                                    'receiver': 'SCHED_FIFO 50'})
        assert text.startswith('node and relay normal scheduling'), text
        assert 'not granted to node, relay, publisher:' in text, text
        assert 'SCHED_FIFO 50 not' not in text and "receive threads SCHED_FIFO 50" in text
        assert scheduling_text(0, dict.fromkeys(
            ('inverse_dynamics', 'relay', 'publisher', 'receiver'),
            'normal scheduling')) == 'normal scheduling for all'
        try:   # granted (root, or the rtprio limit): said as it is
            os.sched_setscheduler(answering, os.SCHED_FIFO, os.sched_param(1))
        except PermissionError:
            return
        assert scheduling_of(child.pid) == (
            'SCHED_FIFO 1 (answering thread, 0 of 1 receive thread)')
        os.sched_setscheduler(receive, os.SCHED_FIFO, os.sched_param(1))
        assert scheduling_of(child.pid) == (
            'SCHED_FIFO 1 (answering thread, 1 of 1 receive thread)')
        granted = 'SCHED_FIFO 1 (answering thread, 1 of 1 receive thread)'
        assert 'not granted' not in scheduling_text(1, {
            'inverse_dynamics': granted, 'relay': granted, 'publisher': 'SCHED_FIFO 2',
            'receiver': 'SCHED_FIFO 1'})
    finally:
        for process in (child, plain):
            process.kill()
            process.wait()


def test_a_robot_without_joints_is_refused_before_anything_starts(
        tmp_path, capsys, monkeypatch):
    """One link, no joint: the node refused every input as `empty` and the run hung silent."""
    import signal
    from spatial_dynamics.tools import latency
    box = tmp_path / 'box.urdf'
    box.write_text('<robot name="box"><link name="box"><inertial><mass value="2"/><inertia '
                   'ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>'
                   '</robot>')

    def started(*args, **kwargs):
        raise AssertionError('a node was started')
    monkeypatch.setattr(latency, 'start', started)
    previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        assert latency.main(['--urdf', str(box)]) == 1
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and '--urdf' in err and 'no joint' in err, err


class _Status:
    """A diagnostics status as the node publishes it (name, key-values), without ROS."""

    def __init__(self, name, values):
        self.name = name
        self.values = [type('KeyValue', (), {'key': k, 'value': v})() for k, v in values.items()]


def _diagnostics():
    from spatial_dynamics.tools.latency_targets import NodeDiagnostics
    bench = type('Bench', (), {'create_subscription': lambda *args: None})()
    return NodeDiagnostics(bench, '/ns/node')


def _period(diagnostics, answered, rejected, **reasons):
    values = {'answered': str(answered), 'rejected': str(rejected)}
    values.update({f'rejected {reason}': str(n) for reason, n in reasons.items()})
    diagnostics._on_diagnostics(type('Array', (), {
        'status': [_Status('ns/node/inverse_dynamics: feedforward', values)]})())


def test_a_node_that_refuses_its_inputs_ends_the_run_with_its_reason(tmp_path):
    """Every input refused (a robot the inputs do not fit): the run waited, silent.

    Rejected inputs and none answered for REFUSING_PERIODS diagnostics periods end it, with
    the node's counts by reason and its log's line; a start-up's rejections (a floating base
    before its odometry) followed by answers, and periods without input, do not.
    """
    import subprocess
    import sys
    from spatial_dynamics.tools.latency_pacer import Pacer
    from spatial_dynamics.tools.latency_targets import REFUSING_PERIODS, Target, watch
    starting = _diagnostics()
    _period(starting, 0, 5, base_stale=5)
    _period(starting, 300, 5, base_stale=5)
    for _ in range(REFUSING_PERIODS):
        _period(starting, 300, 5, base_stale=5)   # no input meanwhile (the relay's block)
    assert starting.refusal() is None
    assert 'rejected 5 inputs in the run (base_stale 5)' in starting.text()
    refusing = _diagnostics()
    for k in range(1, REFUSING_PERIODS + 1):
        assert refusing.refusal() is None
        _period(refusing, 0, 20 * k, empty=20 * k)
    log = tmp_path / 'inverse_dynamics.log'
    log.write_text("[WARN] [1.0] [node]: desired_joint_states: message rejected (empty): field "
                   "'name' is empty: no joints in the message\n[WARN] [1.1] [node]: other\n")
    pacer = Pacer.__new__(Pacer)
    pacer.process = subprocess.Popen([sys.executable, '-c', 'import sys; sys.stdin.read()'],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    pacer.watch = lambda: watch({}, {'inverse_dynamics': str(log)}, refusing)
    target = Target.__new__(Target)
    target.name, target.answers = 'inverse_dynamics', 0
    try:
        with pytest.raises(RuntimeError) as caught:
            pacer.prime(_Idle(), 0, target, timeout=600.0)
    finally:
        pacer.process.kill()
        pacer.process.wait()
    text = str(caught.value)
    assert 'inverse_dynamics refuses its inputs: 60 rejected (empty 60)' in text, text
    assert "field 'name' is empty" in text, text


def test_a_target_that_exits_says_its_own_error_line(tmp_path):
    """`--input-depth 2147483648`: only 'inverse_dynamics exited (1) during the run'."""
    import subprocess
    import sys
    from spatial_dynamics.tools.driving import last_error
    from spatial_dynamics.tools.latency_targets import exited
    log = tmp_path / 'node.log'
    log.write_text('[INFO] [1.0] [node]: model loaded\nTraceback (most recent call last):\n'
                   '  File "node.py", line 1, in <module>\n    main()\nTypeError: '
                   '__init__(): incompatible constructor arguments.\n\nInvoked with: 2147483648\n')
    node = subprocess.Popen([sys.executable, '-c', 'raise SystemExit(1)'])
    node.wait()
    with pytest.raises(RuntimeError) as caught:
        exited({'inverse_dynamics': node}, {'inverse_dynamics': str(log)})
    assert str(caught.value) == ('inverse_dynamics exited (1) during the run: TypeError: '
                                 '__init__(): incompatible constructor arguments.')
    log.write_text("[INFO] [1.0] [node]: x\n[FATAL] [1.1] [node]: cannot start: the "
                   "middleware refused the QoS\n[INFO] [1.2] [node]: shutting down\n")
    assert last_error(str(log)).startswith('[FATAL]') and 'QoS' in last_error(str(log))
    log.write_text('[INFO] [1.0] [node]: last words\n')
    assert last_error(str(log)) == '[INFO] [1.0] [node]: last words'
    assert last_error(str(tmp_path / 'none.log')) == '' and last_error(None) == ''


def test_a_publisher_that_cannot_keep_up_stops_and_says_the_rate_it_sent():
    """`--rate 100000 --seconds 0.5`: 18.6 s, and the header still said 100000 Hz.

    A sender slower than the rate (each input 5 ms, asked 0.1 ms) never sleeps and stops
    `late_limit` after the block's due time with fewer inputs; the rate it sent is reported,
    with a warning, and the machine line says it never slept (not '0 of 0 wake-ups').
    """
    import time
    from spatial_dynamics.tools.latency_pacer import send_block
    from spatial_dynamics.tools.latency_report import machine_line, rate_warning, wake_ups
    sent = []

    def slow(k):
        time.sleep(0.005)
        sent.append(k)
        return k
    block = send_block(slow, 1e4, 1000, late_limit=0.2)
    assert len(block.stamps) == len(sent) < 1000 and block.woke_late_ns == []
    line = machine_line(wake_ups(block.woke_late_ns, 'none'), 'SCHED_FIFO 51')
    assert 'never slept' in line and 'of 0 wake-ups' not in line, line
    target = measured_target([0.4] * 5)
    target.sending_s = 5 / 800.0   # five inputs sent at 800 Hz
    rows = [target.summary()]
    assert rows[0]['input_rate_hz'] == pytest.approx(800.0)
    warning = rate_warning(1000.0, rows)
    assert 'sent 800 Hz of the 1000 Hz asked' in warning and 'keep up' in warning, warning
    target.sending_s = 5 / 999.0   # a tick's lateness short of the rate: met
    assert rate_warning(1000.0, [target.summary()]) is None
    on_time = send_block(lambda k: k, 10.0, 3)   # 0.1 s to send each: it sleeps each time
    assert on_time.stamps == [0, 1, 2] and len(on_time.woke_late_ns) == 3
    assert on_time.seconds == pytest.approx(0.3)   # the grid's, not the last wake-up's


def test_the_cpu_clock_resolves_less_than_a_clock_tick():
    """'CPU us/msg' of 0.02 s: 0.0 for the relay, 500.0 for the node (10 ms ticks / 20 inputs).

    A child answers a line (a few microseconds of work) and waits again: the CPU time its
    threads ran meanwhile is above 0 and below one clock tick, which a tick count cannot be.
    """
    import subprocess
    import sys
    from spatial_dynamics.tools.driving import cpu_ns_between, thread_cpu_ns
    child = subprocess.Popen([sys.executable, '-c', 'import sys\nfor line in sys.stdin: '
                              'print(line, end="", flush=True)'],
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)

    def asleep():   # blocked in its read: its counters are brought up to date
        while True:
            with open(f'/proc/{child.pid}/stat') as f:
                if f.read().rsplit(')', 1)[1].split()[0] == 'S':
                    return thread_cpu_ns(child.pid)

    def exchange():
        child.stdin.write('x\n')
        child.stdin.flush()
        assert child.stdout.readline() == 'x\n'
    try:
        exchange()   # its first line: start-up done
        before = asleep()
        if before is None:
            pytest.skip('this kernel keeps no schedstat')
        exchange()
        used = cpu_ns_between(before, asleep())
        assert 0 < used < 1e9 / os.sysconf('SC_CLK_TCK'), used
    finally:
        child.kill()
        child.wait()
    assert cpu_ns_between(None, {1: 5}) is None
    assert cpu_ns_between({1: 5, 2: 7}, {1: 9, 3: 4}) == 8   # a new thread counts whole


def test_a_cpu_time_not_kept_is_not_printed_and_counts_are_said_in_the_singular():
    """'1 periods' in the compute line; a CPU time the kernel did not keep printed as nan."""
    from spatial_dynamics.tools.latency_report import format_table, not_answered_line
    from spatial_dynamics.tools.latency_targets import plural
    target = measured_target([0.4] * 5)
    target.cpu_ns = None
    row = target.summary()
    assert format_table([row]).splitlines()[-1].split()[-1] == '-'
    target.cpu_ns = 1_234_567
    assert format_table([target.summary()]).splitlines()[-1].split()[-1] == '246.9'
    diagnostics = _diagnostics()
    diagnostics.means_us, diagnostics.maxima_us = [100.0], [150.0]
    assert '(its /diagnostics, 1 period)' in diagnostics.text()
    row.update(not_answered=1, not_answered_superseded=0)
    assert not_answered_line(row) == 'node: 1 input not answered'
    assert (plural(0, 'busy loop'), plural(1, 'busy loop')) == ('0 busy loops', '1 busy loop')


@pytest.mark.parametrize('tool, option', [('closed_loop', '--log-dir'), ('closed_loop', '--json'),
                                          ('closed_loop', '--plot'), ('startup', '--log-dir'),
                                          ('startup', '--json')])
def test_the_other_tools_refuse_an_output_no_file_can_be_created_in_first(tool, option, capsys):
    """`--log-dir /sys/foo` of closed_loop and startup: os.makedirs' PermissionError traceback."""
    import importlib
    parse = importlib.import_module(f'spatial_dynamics.tools.{tool}').parse_args
    path = {'--log-dir': '/proc/sd_logs', '--json': '/proc/version',
            '--plot': '/proc/sd.png'}[option]
    with pytest.raises(SystemExit) as exit:
        parse([option, path])
    err = capsys.readouterr().err
    assert exit.value.code == 2 and option in err and path in err, err


@pytest.mark.parametrize('argv, options', [
    (['--plot', '{t}/x.png', '--log-dir', '{t}/x.png'], ('--plot', '--log-dir')),
    (['--json', '{t}/logs/relay.log', '--log-dir', '{t}/logs'], ('--json', '--log-dir')),
    (['--json', '{t}/logs/inverse_dynamics.log', '--log-dir', '{t}/logs'],
     ('--json', '--log-dir')),
    (['--json', '{t}/r.json', '--plot', '{t}/r.json/h.png'], ('--json', '--plot')),
    (['--json', '{t}/r.json', '--log-dir', '{t}/r.json/logs'], ('--json', '--log-dir')),
    (['--json', '{t}/link.json', '--plot', '{t}/real.png'], ('--json', '--plot')),
])
def test_an_output_that_is_or_holds_another_output_is_refused_first(
        argv, options, tmp_path, capsys):
    """`--plot x.png --log-dir x.png` ran, then 'Is a directory'; a JSON over the relay's log."""
    os.symlink(tmp_path / 'real.png', tmp_path / 'link.json')
    with pytest.raises(SystemExit) as exit:
        parse_args([a.format(t=tmp_path) for a in argv])
    err = capsys.readouterr().err.rstrip().splitlines()[-1]   # the error, not the usage
    assert exit.value.code == 2 and all(option in err for option in options), err
    # a file of its own in the log folder is fine
    assert parse_args(['--json', str(tmp_path / 'logs' / 'r.json'),
                       '--log-dir', str(tmp_path / 'logs')])


def test_a_json_through_a_missing_folder_and_dotdot_is_written_where_it_was_checked(tmp_path):
    """`--json a/new1/../new2/x.json` made new2, then 'cannot write --json: No such file'."""
    from spatial_dynamics.tools.latency import make_folders
    from spatial_dynamics.tools.latency_report import write_json
    args = parse_args(['--json', os.path.join(tmp_path, 'a', 'new1', '..', 'new2', 'x.json')])
    make_folders(args)
    write_json(args.json, {'robot': 'x'})
    assert os.path.isfile(tmp_path / 'a' / 'new2' / 'x.json')


def test_a_runtime_error_raised_by_an_interrupted_rclpy_call_says_interrupted(
        monkeypatch, capsys):
    """A SIGINT mid-run printed pybind11's 'Unable to convert call argument '0' ...' (exit 1).

    rclpy turns a KeyboardInterrupt raised while it builds a message into that RuntimeError.
    """
    import signal
    from spatial_dynamics.tools import latency
    previous = signal.getsignal(signal.SIGINT)

    def loading(urdf):
        try:
            os.kill(os.getpid(), signal.SIGINT)
            raise AssertionError('the signal did not interrupt')
        except KeyboardInterrupt:
            raise RuntimeError("Unable to convert call argument '0' to Python object") from None
    monkeypatch.setattr(latency, 'robot_model', loading)
    try:
        assert latency.main(['--seconds', '1']) == 130
    finally:
        signal.signal(signal.SIGINT, previous)
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'interrupted (SIGINT)' in err, err


@pytest.mark.parametrize('tool, argv, started', [
    ('latency', ['--seconds', '1', '--busy', '3'], 4),   # relay, node, then 2 busy loops
    ('closed_loop', ['--plot', '', '--busy', '3'], 2),
])
def test_every_child_is_waited_for_when_a_signal_comes_while_one_starts(
        tool, argv, started, monkeypatch, capsys):
    """SIGINT while a busy loop started (after its fork): it was lost, never killed nor waited.

    Left running until the tool exited, then killed by its parent-death signal: a zombie
    where nothing reaps orphans. closed_loop also printed a KeyboardInterrupt traceback.
    """
    import importlib
    import signal
    import subprocess
    import sys
    module = importlib.import_module(f'spatial_dynamics.tools.{tool}')
    children = []
    real = subprocess.Popen

    class Recorded(real):
        def __init__(self, command, *args, **kwargs):
            super().__init__(command, *args, **kwargs)
            children.append(self)
            if len(children) == started:
                os.kill(os.getpid(), signal.SIGINT)   # arrives before Popen returns
    sleeper = [sys.executable, '-c', 'import time; time.sleep(60)']
    monkeypatch.setattr(subprocess, 'Popen', Recorded)
    monkeypatch.setattr(module, 'node_command', lambda *names: sleeper)
    previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        assert module.main(argv) == 130
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
        left = [child for child in children if child.returncode is None]
        for child in children:
            child.kill()
            child.wait()
    assert len(children) == started and not left, [c.args for c in left]
    assert children[-1].args[-1] == 'while True: pass'
    assert 'interrupted (SIGINT)' in capsys.readouterr().err


def test_a_plot_through_a_missing_folder_and_dotdot_is_saved_where_its_folder_was_made(
        tmp_path):
    """`--plot a/new1/../new2/h.png`: new2 was made, then savefig failed (no a/new1)."""
    from spatial_dynamics.tools.driving import save_figure

    class Figure:
        def tight_layout(self):
            pass

        def savefig(self, path):
            with open(path, 'wb') as f:   # as matplotlib opens it
                f.write(b'png')

    class Pyplot:
        def close(self, fig):
            pass
    save_figure(Pyplot(), Figure(), os.path.join(tmp_path, 'new1', '..', 'new2', 'h.png'))
    assert (tmp_path / 'new2' / 'h.png').read_bytes() == b'png'


def test_closed_loop_says_what_a_plot_is_before_its_suffix(tmp_path, capsys):
    """A ``--plot`` folder or FIFO said "'. is not a format matplotlib writes'"."""
    from spatial_dynamics.tools import closed_loop
    fifo = tmp_path / 'fifo'
    os.mkfifo(fifo)
    for path, said in [(tmp_path, 'not a regular file'), (fifo, 'not a regular file')]:
        with pytest.raises(SystemExit) as exit:
            closed_loop.parse_args(['--plot', str(path)])
        err = capsys.readouterr().err
        assert exit.value.code == 2 and said in err and 'format' not in err, err


def test_closed_loop_refuses_a_simulated_robot_of_other_joints_and_a_path_with_a_line_break(
        tmp_path, capsys, handlers_kept):
    """A --robot-urdf whose joints are not --urdf's, a path with a line break: refused first.

    Both started the nodes, then "the sim exited" (its log: "q: expected 6 values, got shape
    (8,)") or "the node exited" (the line break read as a space by the -p rule's YAML).
    """
    from spatial_dynamics.tools import closed_loop
    lone = tmp_path / 'lone.urdf'
    lone.write_text("<robot name='lone'><link name='base'/></robot>")
    assert closed_loop.main(['--robot-urdf', str(lone), '--plot', '']) == 1
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'are not those of --urdf' in err, err
    for option in ('--urdf', '--robot-urdf', '--json', '--log-dir'):
        with pytest.raises(SystemExit) as exit:
            closed_loop.parse_args([option, str(tmp_path / 'a\nb'), '--plot', ''])
        err = capsys.readouterr().err
        assert exit.value.code == 2 and 'line break' in err, err
