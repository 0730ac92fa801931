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


@pytest.mark.parametrize('option', ['--plot', '--json'])
@pytest.mark.parametrize('kind', ['directory', 'fifo', 'missing folder'])
def test_an_output_that_cannot_be_written_is_refused_first(option, kind, tmp_path, capsys):
    path = tmp_path / 'out'
    if kind == 'directory':
        path.mkdir()
    elif kind == 'fifo':
        os.mkfifo(path)
    else:
        path = tmp_path / 'missing' / 'out'
    with pytest.raises(SystemExit) as exit:
        parse_args([option, str(path)])
    assert exit.value.code == 2
    err = capsys.readouterr().err
    assert option in err and str(path) in err, err


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
    from spatial_dynamics.tools.latency import Target
    target = Target.__new__(Target)
    target.name, target.sent, target.latency_ns, target.to_answer_ns = 'node', set(), {}, {}
    target.early, target.measuring, target.answers, target.cpu_s = {}, True, 0, 0.0
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
    from spatial_dynamics.tools.latency import busy_loops
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
    from spatial_dynamics.tools.latency import busy_loops
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
    from spatial_dynamics.tools.latency import Pacer
    pacer = Pacer.__new__(Pacer)
    pacer.watch = lambda: None
    pacer.process = subprocess.Popen([sys.executable, '-c', 'pass'], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, text=True)
    pacer.process.wait()
    return pacer


def test_a_pacer_that_exited_is_said_at_once_not_as_a_broken_pipe_or_a_timeout():
    """Killed mid-run: a BrokenPipeError traceback; while priming: 60 s, then 'did not answer'."""
    from spatial_dynamics.tools.latency import Target
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
    from spatial_dynamics.tools.latency import exited, Pacer, Target
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


def measured_target(latencies_ms, late_stamps=()):
    """Return a Target (no DDS) that sent one input per ms and got ``latencies_ms`` answers.

    ``late_stamps``: extra inputs, not answered, each 0.05 ms before the next one (the
    publisher late).
    """
    from spatial_dynamics.tools.latency import Target
    target = Target.__new__(Target)
    target.name, target.latency_ns, target.to_answer_ns = 'node', {}, {}
    target.early, target.measuring, target.answers, target.cpu_s = {}, True, 0, 0.0
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

    from spatial_dynamics.tools.latency import format_table, legend
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
    from spatial_dynamics.tools.latency import difference_line, not_answered_line
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
    from spatial_dynamics.tools.latency import json_safe, Target
    target = Target.__new__(Target)
    target.name, target.sent, target.latency_ns, target.to_answer_ns = 'node', set(), {}, {}
    target.early, target.measuring, target.answers, target.cpu_s = {}, True, 0, 0.0
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

    from spatial_dynamics.tools.latency import json_safe, machine_line, wake_ups
    late_ns = [50_000] * (count - 2) + [1_500_000, 900_000] if count else []
    machine = wake_ups(late_ns, 'none')
    assert machine['wake_ups'] == count and machine['over_1ms'] == (1 if count else 0)
    if count:
        assert machine['max_ms'] == pytest.approx(1.5)
        assert machine['p50_ms'] == pytest.approx(0.05)
        assert machine['p99.9_ms'] == (pytest.approx(np.percentile(np.array(late_ns) * 1e-6,
                                                                   99.9))
                                       if count >= 1000 else None)
    from spatial_dynamics.tools.latency import machine_legend
    label = machine_legend(np.array(late_ns) * 1e-6)
    assert f'{count} wake-ups' in label and (', p99.9 ' in label) == (count >= 1000), label
    line = machine_line(machine, 'SCHED_FIFO 51')
    assert 'SCHED_FIFO 51' in line and 'kernel preemption: none' in line, line
    assert f'({machine["over_1ms"]} of {count} wake-ups over 1 ms)' in line, line
    json.dumps(json_safe([machine]), allow_nan=False)   # no NaN reaches the JSON


def test_the_kernels_preemption_model_is_one_of_linuxs():
    from spatial_dynamics.tools.latency import kernel_preemption
    assert kernel_preemption() in ('none', 'voluntary', 'full', 'lazy', 'rt', 'unknown')
