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
