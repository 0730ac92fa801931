# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The replay's writers: residual.csv's fixed-point numbers, and the plotting child.

The reference formats one digit per pass over the column (the writer's form before the
four-digit table); the writer must produce the same bytes on any number of threads, and its
numbers must read back as the values rounded to their decimals. The plotting child, forked
before the bag is read, runs the job it is sent, or ends when none comes (a refusal).
"""

import os

import numpy as np
import pytest

from spatial_dynamics.replay import report

RNG = np.random.default_rng(8)
EDGES = [0.0, -0.0, np.nan, np.inf, -np.inf, 1e20, -1e20, 0.5e-4, -0.5e-4, -0.00004,
         9999.99995, -9999.99995, 0.49999, -0.5, 1e-300, -1e-300, 123456789.123, -0.0001,
         99999.5, -99999.5, 1.0, -1.0, 10.0, -10.0]


def fixed_point_digit_by_digit(x, decimals):
    """One digit per pass, the minus sign before the first blank (the reference)."""
    finite = np.isfinite(x)
    big = finite & (np.abs(x) >= report.FAST_LIMIT / 10.0 ** decimals)
    scaled = np.rint(np.where(finite & ~big, x, 0.0) * 10.0 ** decimals)
    neg = scaled < 0
    mag = np.abs(scaled).astype(np.int64)
    digits = max(decimals + 1, len(str(int(mag.max()))) if len(mag) else 1)
    width = digits + 1 + (decimals > 0) + 1
    texts = {int(i): b'%.17g' % x[i] for i in np.flatnonzero(big)}
    width = max([width, 4] + [len(t) for t in texts.values()])
    out = np.full((len(x), width), ord(' '), dtype=np.uint8)
    col = width - 1
    rest = mag.copy()
    for k in range(digits):
        if decimals and k == decimals:
            out[:, col] = ord('.')
            col -= 1
        d = rest % 10
        rest //= 10
        significant = (rest > 0) | (d > 0) | (k <= decimals)
        out[:, col] = np.where(significant | (k == 0), d + ord('0'), ord(' '))
        col -= 1
    lead = (out[:, :-1] == ord(' ')).sum(axis=1)
    rows = np.flatnonzero(neg)
    out[rows, lead[rows] - 1] = ord('-')
    for bad, text in ((np.isnan(x), b'nan'), (np.isposinf(x), b'inf'),
                      (np.isneginf(x), b'-inf')):
        for row in np.flatnonzero(bad):
            texts[int(row)] = text
    for row, text in texts.items():
        out[row] = ord(' ')
        out[row, width - len(text):] = np.frombuffer(text, dtype=np.uint8)
    return out


@pytest.mark.parametrize('decimals', [0, 1, 4, 6, 9])
@pytest.mark.parametrize('scale', [1e-6, 0.3, 1e4, 1e9, 1e13])
def test_fixed_point_equals_digit_by_digit(decimals, scale):
    x = RNG.standard_normal(3000) * scale
    x[:len(EDGES)] = EDGES
    got = report._fixed_point(x, decimals)
    ref = fixed_point_digit_by_digit(x, decimals)
    assert got.shape == ref.shape
    np.testing.assert_array_equal(got, ref)
    finite = np.isfinite(x)
    values = np.array([float(row.tobytes()) for row in got])
    np.testing.assert_array_equal(np.isnan(values), np.isnan(x))
    np.testing.assert_allclose(values[finite], x[finite], rtol=1e-15,
                               atol=0.5 * 10.0 ** -decimals * (1 + 1e-9))


@pytest.mark.parametrize('x', [np.zeros(0), np.array([np.nan]), np.array([-1.0]),
                               np.zeros(3), np.array([-np.inf, 5.0])])
def test_fixed_point_small_columns(x):
    for decimals in (0, 4):
        np.testing.assert_array_equal(report._fixed_point(x, decimals),
                                      fixed_point_digit_by_digit(x, decimals))


def test_write_csv_same_file_on_any_threads(tmp_path, monkeypatch):
    N = 3 * report.CHUNK + 17
    t = np.arange(N) * 1e-3
    r = RNG.standard_normal((N, 3))
    r[5, 1], r[N - 1, 2] = np.nan, 1e30
    files = []
    for threads in (1, 2, 3):
        monkeypatch.setattr(report.compiled, 'THREADS', threads)
        path = tmp_path / f'{threads}.csv'
        report.write_csv(str(path), ['t', 'a', 'b', 'c'], [t] + [r[:, j] for j in range(3)],
                         [6, 4, 4, 4])
        files.append(path.read_bytes())
    assert files[0] == files[1] == files[2]
    back = np.genfromtxt(str(tmp_path / '1.csv'), delimiter=',', skip_header=1)
    np.testing.assert_allclose(back[:, 0], t, atol=5e-7)
    np.testing.assert_allclose(back[:, 1:], r, atol=5e-5, rtol=1e-15)


def noop():
    pass


def write_text(path, text):
    with open(path, 'w') as f:
        f.write(text)


def fail():
    raise RuntimeError('drawing failed')


def test_child_runs_the_job_sent(tmp_path):
    child = report.start_child(noop)
    proc = report.run_in(child, write_text, str(tmp_path / 'job'), 'done')
    assert report.join_child(proc)
    assert (tmp_path / 'job').read_text() == 'done'
    report.end_child(child)     # after the job: harmless


def test_child_without_a_job_ends(tmp_path):
    child = report.start_child(noop)
    report.end_child(child)
    child[0].join(timeout=30)
    assert child[0].exitcode == 0


def test_child_failure_is_reported(capfd):
    child = report.start_child(noop)
    assert not report.join_child(report.run_in(child, fail))
    assert 'drawing failed' in capfd.readouterr().err


def test_no_child_runs_the_job_here(tmp_path):
    assert report.run_in(None, write_text, str(tmp_path / 'here'), 'x') is None
    assert report.join_child(None) and os.path.exists(tmp_path / 'here')


def test_small_pages_within_the_command_only():
    """The bag command turns numpy's huge-page advice off while it runs, then back."""
    from spatial_dynamics.replay.residual import small_pages
    core = getattr(np, '_core', None) or np.core             # numpy 2.x or 1.x
    setter = getattr(core.multiarray, '_set_madvise_hugepage', None)
    if setter is None:
        pytest.skip('this numpy has no huge-page switch')
    previous = setter(True)
    try:
        with small_pages():
            assert setter(False) is False       # off inside (the call returns the setting)
        assert setter(True) is True             # and back on after
    finally:
        setter(previous)
