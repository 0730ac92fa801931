# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""What the replay writes: CSV files, PNG plots, tables and parameter snippets.

:func:`write_csv` formats numbers with numpy instead of ``np.savetxt`` (which formats every
row in Python): each column is written in fixed-point with a given number of decimals, as
integer digits computed on whole columns at once, four digits a table look-up, chunks of
rows on two threads. Measured on 360 000 rows of 8 columns (2 shared cores):
``np.savetxt(fmt='%.4f')`` 0.81 s, one digit at a time 0.48 s; an hour at 1 kHz (3.6 M rows,
276 MB) 3.8 s one digit at a time, 0.9-1.0 s now (1.7-1.9 s of CPU). ``--residual npy`` and
``none`` remain for when even that is too much.
"""

from __future__ import annotations

from collections import deque
from concurrent.futures import ThreadPoolExecutor
import contextlib
import csv
import io
import json
import math
import multiprocessing
import os
import signal
import sys
from typing import Optional, Sequence

import numpy as np

from ..backends import compiled     # compiled.THREADS: the threads this process may use
from ..files import write_atomic
from ..text import shown

# matplotlib is imported where a plot is drawn (start-up time, and optional: the plot extra)

CHUNK = 1 << 18          # rows formatted at once


#: Largest |x| · 10**decimals written by the integer fast path: well inside int64 and exact
#: in float64 (2**53 ≈ 9.007e15), so every digit it prints is the value's.
FAST_LIMIT = 1e15


#: ``DIGITS[k]``: the 4 ASCII digits of k, zero-padded (k < 10000).
DIGITS = np.array([list(b'%04d' % k) for k in range(10000)], dtype=np.uint8)
#: :data:`DIGITS` as one 4-byte word a row: one gather takes four digits.
QUADS = DIGITS.view(np.uint32).ravel()


def _fixed_point(x: np.ndarray, decimals: int) -> np.ndarray:
    """Format a float column as fixed-point ASCII: (N, width) bytes, right-aligned.

    ``nan`` becomes ``nan``; infinities ``inf``/``-inf``. Digits come from integer arithmetic
    on numpy arrays (Python's formatting of millions of floats would take seconds), four at a
    time from the table :data:`DIGITS`; a value too large for it (``|x| · 10**decimals`` ≥
    :data:`FAST_LIMIT`) is written by Python's ``%.17g``, which reads back as the same double.
    """
    finite = np.isfinite(x)
    big = finite & (np.abs(x) >= FAST_LIMIT / 10.0 ** decimals)
    special = not finite.all() or bool(big.any())        # rows for Python's formatting
    scaled = np.rint((np.where(finite & ~big, x, 0.0) if special else x) * 10.0 ** decimals)
    neg = scaled < 0
    mag = np.abs(scaled).astype(np.int64)
    digits = max(decimals + 1, len(str(int(mag.max()))) if len(mag) else 1)
    point = 1 if decimals > 0 else 0
    width = digits + 1 + point + 1                  # sign, point, at least 'nan'
    texts = {int(i): b'%.17g' % x[i] for i in np.flatnonzero(big)} if special else {}
    width = max([width, 4] + [len(t) for t in texts.values()])
    # all the digits, zero-padded, in groups of four from the right
    groups = -(-digits // 4)
    quads = np.empty((len(x), groups), dtype=np.int64)
    rest = mag
    for g in range(groups - 1, -1, -1):
        rest, quads[:, g] = np.divmod(rest, 10000)
    padded = QUADS.take(quads).view(np.uint8)       # (N, 4 groups): 4 bytes a gather
    out = np.empty((len(x), width), dtype=np.uint8)
    right = width - decimals                        # first column of the decimals
    out[:, right:] = padded[:, 4 * groups - decimals:]
    if point:
        out[:, right - 1] = ord('.')
    out[:, right - point - (digits - decimals):right - point] = \
        padded[:, 4 * groups - digits:4 * groups - decimals]
    # blanks before the first significant digit (at least the one before the point), the
    # minus sign right before it
    used = np.full(len(x), decimals + 1)               # digits shown: at least '0.dddd'
    for k in range(decimals + 1, digits):
        used += mag >= 10 ** k
    lead = width - point - used
    for c in range(width - point - decimals - 1):      # the columns that may be blank
        np.copyto(out[:, c], ord(' '), where=lead > c)
    rows = np.flatnonzero(neg)
    out[rows, lead[rows] - 1] = ord('-')
    if special:
        for bad, text in ((np.isnan(x), b'nan'), (np.isposinf(x), b'inf'),
                          (np.isneginf(x), b'-inf')):
            for row in np.flatnonzero(bad):
                texts[int(row)] = text
    for row, text in texts.items():
        out[row] = ord(' ')
        out[row, width - len(text):] = np.frombuffer(text, dtype=np.uint8)
    return out


def write_csv(path: str, header: Sequence[str], columns: Sequence[np.ndarray],
              decimals: Sequence[int]) -> None:
    """Write columns of floats as CSV with a header line, fixed-point per column.

    Chunks of :data:`CHUNK` rows are formatted on ``compiled.THREADS`` threads (numpy releases
    the GIL in its loops) and written in order: the file does not depend on the threads.
    Written whole or not at all (:func:`~spatial_dynamics.files.write_atomic`).
    """
    N = len(columns[0])

    def chunk(a: int) -> np.ndarray:
        b = min(N, a + CHUNK)
        parts = []
        for c, d in zip(columns, decimals):
            parts.append(_fixed_point(np.asarray(c[a:b], dtype=float), d))
            parts.append(np.full((b - a, 1), ord(','), dtype=np.uint8))
        parts[-1] = np.full((b - a, 1), ord('\n'), dtype=np.uint8)
        return np.hstack(parts)         # C-contiguous bytes: written without a copy

    def write(f) -> None:
        f.write((','.join(header) + '\n').encode())
        starts = range(0, N, CHUNK)
        threads = compiled.THREADS
        if threads < 2 or len(starts) < 2:
            for a in starts:
                f.write(chunk(a))
            return
        with ThreadPoolExecutor(threads) as pool:
            pending = deque()
            for a in starts:
                pending.append(pool.submit(chunk, a))
                if len(pending) > threads:          # bounds the memory held
                    f.write(pending.popleft().result())
            while pending:
                f.write(pending.popleft().result())

    write_atomic(path, write, 'output file')


def write_summary(path: str, rows: Sequence[Sequence], header: Sequence[str]) -> None:
    """Write a small CSV (one row per joint): numbers with ``%.6g``, text quoted as CSV needs.

    A joint name with a comma, a quote or a line break is quoted by the ``csv`` module (it
    broke the row). Whole or not at all.
    """
    def cell(v) -> str:
        if isinstance(v, str):
            return v
        return 'nan' if v is None or (isinstance(v, float) and math.isnan(v)) else f'{v:.6g}'
    text = io.StringIO()
    csv.writer(text, lineterminator='\n').writerows(
        [cell(v) for v in r] for r in [header] + list(rows))
    write_atomic(path, text.getvalue(), 'output file')


def write_npy(path: str, array: np.ndarray) -> None:
    """Write ``array`` as a ``.npy`` file (``np.save``), whole or not at all."""
    write_atomic(path, lambda f: np.save(f, array), 'output file')


def save_figure(fig, path: str, dpi: int = 80) -> None:
    """Save a matplotlib figure as PNG, whole or not at all (a temporary, then a rename)."""
    write_atomic(path, lambda f: fig.savefig(f, format='png', dpi=dpi), 'plot')


def table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    """Align text cells in columns (first column left, the others right)."""
    cells = [list(header)] + [list(r) for r in rows]
    widths = [max(len(c[k]) for c in cells) for k in range(len(header))]
    return '\n'.join('  ' + '  '.join(c.ljust(w) if k == 0 else c.rjust(w)
                                      for k, (c, w) in enumerate(zip(row, widths))).rstrip()
                     for row in cells)


#: The header of :func:`effort_rows`' table.
EFFORT_HEADER = ['joint', 'peak |tau|', 'at (s)', 'limit', 'use', '']


def effort_rows(names: Sequence[str], t: np.ndarray, tau: np.ndarray, limit: np.ndarray):
    """Return the effort check's rows (peak |τ|, when, limit, use) and whether one fails.

    A joint fails when its peak exceeds a positive, finite limit, or a torque is not finite
    (``NOT FINITE``: a non-finite torque is no peak, it fails the check).
    """
    finite = np.isfinite(tau)
    magnitude = np.where(finite, np.abs(tau), np.inf)
    peak, at = np.max(magnitude, axis=0), t[np.argmax(magnitude, axis=0)]
    rows, exceeded = [], False
    for j, name in enumerate(names):
        has = bool(limit[j] > 0 and np.isfinite(limit[j]))
        limit_text = f'{limit[j]:g}' if has else '-'
        if not finite[:, j].all():
            exceeded = True
            rows.append([shown(name, quote=False), 'non-finite', f'{at[j]:.3f}', limit_text, '-',
                         'NOT FINITE'])
            continue
        use = peak[j] / limit[j] if has else np.nan
        over = bool(has and use > 1.0)
        exceeded |= over
        rows.append([shown(name, quote=False), f'{peak[j]:.4g}', f'{at[j]:.3f}', limit_text,
                     f'{100 * use:.1f} %' if has else '-', 'EXCEEDED' if over else ''])
    return rows, exceeded


def yaml_double(x: float) -> str:
    """``x`` with 6 significant digits, always read back as a double (``0.0``, not ``0``).

    A ROS parameter declared double (or double[]) refuses an integer value.
    """
    text = f'{x:.6g}'
    return text if any(c in text for c in '.einf') else text + '.0'


def node_parameters(names: Sequence[str], armature: np.ndarray, threshold: float) -> str:
    """Node parameter YAML for the identified armature, with the URDF friction switched on.

    An armature the recording cannot tell (nan) is written as the node's default, 0.0, and
    named in a comment.
    """
    arm = ', '.join(yaml_double(0.0 if math.isnan(a) else max(a, 0.0)) for a in armature)
    unknown = [n for n, a in zip(names, armature) if math.isnan(a)]
    return '\n'.join([
        'inverse_dynamics:',
        '  ros__parameters:',
        f'    joints: [{", ".join(json.dumps(n) for n in names)}]',   # YAML reads JSON's strings
        f'    armature: [{arm}]'] + ([
            f'    # armature undetermined (the recording cannot tell it; 0.0 is the node\'s '
            f'default): {", ".join(map(shown, unknown))}'] if unknown else []) + [
        '    friction_model: "urdf"',
        f'    friction_velocity_threshold: {yaml_double(threshold)}'])


def urdf_dynamics(names: Sequence[str], damping: np.ndarray, friction: np.ndarray,
                  urdf_damping: np.ndarray, urdf_friction: np.ndarray) -> str:
    """``<dynamics>`` elements to put into each joint of the URDF (negative values as 0).

    A term the recording cannot tell (nan) keeps the URDF's value (``urdf_damping``,
    ``urdf_friction``) and is named undetermined; a joint with neither told keeps its
    element.
    """
    lines = []
    for name, d, f, ud, uf in zip(names, damping, friction, urdf_damping, urdf_friction):
        n = shown(name, quote=False)        # a comment's joint: escaped, cut
        unknown = [w for w, x in (('damping', d), ('friction', f)) if math.isnan(x)]
        if len(unknown) == 2:
            lines.append(f'<!-- joint {n}: damping and friction undetermined (the recording '
                         f'cannot tell them): keep its <dynamics> (damping {ud:.6g}, friction '
                         f'{uf:.6g}) -->')
            continue
        d = ud if math.isnan(d) else max(d, 0.0)
        f = uf if math.isnan(f) else max(f, 0.0)
        lines.append(f'<!-- joint {n} --> <dynamics damping="{d:.6g}" friction="{f:.6g}"/>'
                     + (f' <!-- {unknown[0]} undetermined: the URDF\'s -->' if unknown else ''))
    return '\n'.join(lines)


def plot_joints(path: str, t: np.ndarray, names: Sequence[str], series: dict,
                title: str, limits: Optional[np.ndarray] = None,
                max_points: int = 20000) -> None:
    """Plot one panel per joint of each ``{label: (N, n) array}``; decimated for long runs."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    step = max(1, len(t) // max_points)
    n = len(names)
    fig, axes = plt.subplots(n, 1, figsize=(10, 1.8 * n + 1), sharex=True, squeeze=False)
    for j, ax in enumerate(axes[:, 0]):
        for label, y in series.items():
            ax.plot(t[::step], y[::step, j], label=label, linewidth=0.8)
        if limits is not None and limits[j] > 0:
            for s in (1, -1):
                ax.axhline(s * limits[j], color='r', linestyle='--', linewidth=0.8)
        ax.set_ylabel(names[j], fontsize=8)
        ax.grid(True, alpha=0.3)
    axes[0, 0].legend(loc='upper right', fontsize=8)
    axes[0, 0].set_title(title)
    axes[-1, 0].set_xlabel('time (s)')
    fig.tight_layout()
    try:
        save_figure(fig, path)
    finally:
        plt.close(fig)


def prepare_plots() -> None:
    """Import matplotlib (Agg) and pyplot: half a second of a plotting child's work."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot  # noqa: F401


def _ended(signum, frame) -> None:
    """SIGTERM in a plotting child: end as ``sys.exit`` does (a plot half written is removed)."""
    raise SystemExit(128 + signum)


def _serve(conn, parent_end, prepare) -> None:
    """Be the child of :func:`start_child`: prepare, then run the job sent (none: end).

    Ctrl-C is the parent's (SIGINT is ignored here); the parent ends a child it no longer
    needs with SIGTERM (:func:`stop_child`), which unwinds like ``sys.exit``: the temporary
    of a plot being written is removed, nothing half written is left. A plot that cannot be
    written (a full disk) is one line on stderr and exit status 1.
    """
    parent_end.close()      # the parent's end, inherited: else the pipe would never end
    signal.signal(signal.SIGTERM, _ended)
    try:
        prepare()
        try:
            job = conn.recv()
        except EOFError:        # the parent ended without a job (a refusal): nothing to draw
            return
        if job is not None:
            fn, args = job
            fn(*args)
    except (ValueError, OSError, ImportError) as err:
        what = 'the plots need matplotlib: ' if isinstance(err, ImportError) else ''
        print(f'error: {what}' + ' '.join(str(err).split()), file=sys.stderr)
        sys.exit(1)


@contextlib.contextmanager
def _sigint_ignored():
    """Within: SIGINT is ignored, so that a child forked here ignores it (not the parent)."""
    try:
        before = signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:          # not the main thread: no handler of this thread to change
        yield
        return
    try:
        yield
    finally:
        if before is not None:
            signal.signal(signal.SIGINT, before)


def start_child(prepare=prepare_plots):
    """Fork a child that runs ``prepare()`` now and waits for a job (:func:`run_in`).

    Forked before the bag is read, the child imports matplotlib on the second core while
    this process reads on the first. It ignores Ctrl-C (a terminal sends SIGINT to both):
    the parent, interrupted, ends it (:func:`stop_child`). Returns ``None`` where fork is
    missing (the job then runs in this process).
    """
    if 'fork' not in multiprocessing.get_all_start_methods():
        return None
    ctx = multiprocessing.get_context('fork')
    receive, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_serve, args=(receive, send, prepare), daemon=True)
    with _sigint_ignored():
        proc.start()
    receive.close()
    return proc, send


def run_in(child, fn, *args):
    """Run ``fn(*args)`` in a child of :func:`start_child` (pickled through its pipe).

    Returns the process (for :func:`join_child`), or ``None`` when there is no child and
    ``fn`` already ran here. A child that has ended already (it said why) fails the join.
    """
    if child is None:
        fn(*args)
        return None
    proc, send = child
    try:
        send.send((fn, args))
    except BrokenPipeError:
        pass
    send.close()
    return proc


def end_child(child) -> None:
    """Close the pipe of a child of :func:`start_child`: without a job sent, it ends."""
    if child is not None:
        child[1].close()


def stop_child(child) -> None:
    """End a child of :func:`start_child` now, whatever it is doing, and wait for it.

    For a parent that stops early (Ctrl-C, a refusal): no child is left behind, and a plot
    it was writing is abandoned whole (its temporary removed, see :func:`_serve`).
    """
    if child is None:
        return
    proc, send = child
    send.close()
    if proc.is_alive():
        proc.terminate()
    proc.join()


def join_child(proc) -> bool:
    """Wait for a process of :func:`run_in`; ``True`` when it succeeded (or ran here)."""
    if proc is None:
        return True
    proc.join()
    return proc.exitcode == 0


def ensure_dir(path: str) -> str:
    """Create the output directory (and parents) if needed; return it."""
    os.makedirs(path, exist_ok=True)
    return path
