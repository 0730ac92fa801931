# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""``replay residual BAG``: the model's torque against the measured effort over a recording.

The recording read (:func:`recording`, :mod:`spatial_dynamics.recordings`), the residual of
one batched RNEA (:func:`residual_of`), its files (summary.csv, residual.csv or .npy, the
plots drawn in a forked child) and the report. ``replay identify`` runs the same comparison
with its fits (:mod:`.identify`) hooked in.
"""

from __future__ import annotations

import contextlib
import os
import sys
from typing import Dict, List, NamedTuple, Sequence

import numpy as np

from .. import rnea
from ..model import Model
from ..recordings import differentiate
from ..recordings.base_topics import BaseTopic
from ..recordings.recording import Reading, recording as read_recording, Stages
from ..text import shown
from . import report
from .arguments import add_command, model_of, recording_parser
from .paths import check_matplotlib, check_paths

try:            # private to numpy (:func:`small_pages`): nothing is done where it is missing
    from numpy._core.multiarray import _set_madvise_hugepage
except ImportError:
    try:        # numpy 1.x (Ubuntu 24.04's python3-numpy is 1.26)
        from numpy.core.multiarray import _set_madvise_hugepage
    except ImportError:
        _set_madvise_hugepage = None


#: Points per joint drawn at most (long recordings are decimated).
PLOT_POINTS = 20000


def plot_replay(out: str, topic: str, t: np.ndarray, names: Sequence[str], effort: np.ndarray,
                tau: np.ndarray, residual: np.ndarray) -> None:
    """Draw ``measured_vs_model.png`` and ``residual.png`` into ``out`` (decimated data)."""
    report.plot_joints(os.path.join(out, 'measured_vs_model.png'), t, names,
                       {'measured': effort, 'model (RNEA)': tau},
                       f'{topic}: measured effort and model torque (N m or N)',
                       max_points=len(t))
    report.plot_joints(os.path.join(out, 'residual.png'), t, names,
                       {'measured - model': residual}, 'residual (N m or N)',
                       max_points=len(t))


def rms(x: np.ndarray) -> np.ndarray:
    """Root mean square of each column of ``x`` (N, n), without an (N, n) temporary."""
    return np.sqrt(np.einsum('ij,ij->j', x, x) / len(x))


@contextlib.contextmanager
def small_pages():
    """Within: numpy does not ask the kernel for transparent huge pages for new arrays.

    numpy marks every array of 4 MB or more ``madvise(MADV_HUGEPAGE)``; faulting such pages
    in was erratic and slow on the 2-core VM the replay was timed on (system time of the
    hour's replay 3.2-3.9 s, 0.9-1.0 s without; 1.2 GB of arrays took 0.46-3.8 s to touch,
    0.6 s without). The command touches ~3 GB of fresh arrays once each, where huge pages
    gain little. (``NUMPY_MADVISE_HUGEPAGE=0`` does the same, read when numpy is imported;
    the switch used here is private to numpy, hence doing nothing where it is missing.)
    """
    if _set_madvise_hugepage is None:
        yield
        return
    before = _set_madvise_hugepage(False)
    try:
        yield
    finally:
        _set_madvise_hugepage(before)


class Residual(NamedTuple):
    """Measured effort against the model's torque over a recording."""

    tau: np.ndarray
    residual: np.ndarray
    rms_measured: np.ndarray
    rms_residual: np.ndarray


def reading_of(args) -> Reading:
    """Return how the command line says a recording is read (:class:`Reading`)."""
    return Reading(args.topic, args.window, args.order, args.measured_effort, args.gravity,
                   BaseTopic(args.base_odometry, args.base_imu, args.odometry_link,
                             args.imu_link), args.generic)


def recording(args, bag: str, model: Model, stages: Stages) -> Dict:
    """Read, clean and differentiate ``bag`` as the command line says (:func:`reading_of`)."""
    return read_recording(reading_of(args), bag, model, stages)


def run(args) -> int:
    """``replay residual``: the model against the bag's efforts; the files; return 0."""
    return run_bag(args, None)


def run_bag(args, fit) -> int:
    """Compare measured efforts with the model over a bag, ``fit`` (or None) to identify."""
    check_paths(args)         # before any computation: bad inputs and outputs said at once
    check_matplotlib(args)
    with small_pages():
        # the plotting child imports matplotlib while this process reads the bag
        plotter = None if args.no_plots else report.start_child()
        try:
            return compare(args, plotter, fit)
        except BaseException:               # a refusal, Ctrl-C: the child ends, drawn or not
            report.stop_child(plotter)
            raise
        finally:
            report.end_child(plotter)


def compare(args, plotter, fit=None) -> int:
    """:func:`run_bag` with its plotting child (from :func:`report.start_child`, or None).

    The jobs in turn: the recording read (:func:`recording`), the residual
    (:func:`residual_of`), the residual's files (:func:`write_residual`), the report
    (:func:`print_recording`, :func:`print_table`). ``fit``: ``replay identify``'s part
    (:class:`.identify.Identification`: its checks before the bag is read, the fits after
    the residual, their report at the end), or None.
    """
    stages = Stages()
    model = model_of(args)
    stages.done('model')
    if fit is not None:
        fit.check(model)            # its problems said before the bag is read
    s = recording(args, args.bag, model, stages)
    res = residual_of(model, s, args.gravity)
    stages.done('rnea')
    fitted = fit.fit(model, s, res, stages) if fit is not None else None
    drawn = write_residual(args, model.joint_names, s, res, fitted, plotter, stages)
    print_recording(args, model, s)
    print_table(model.joint_names, res, fitted)
    written = residual_files(args.residual, drawn)
    if fitted is not None:
        written += fit.report(model, fitted, stages)
    print(f'\nwritten to {args.out!r}: {", ".join(written)}')
    if args.timings:
        print('stages:\n' + stages.text(), file=sys.stderr)
    return 0


def residual_of(model: Model, s: Dict, gravity) -> Residual:
    """Return the model's torque (RNEA, one batched call) and the residual over ``s``."""
    tau = rnea(model, s['q'], s['qd'], s['qdd'], gravity, base=s['base'])
    residual = s['effort'] - tau
    return Residual(tau, residual, rms(s['effort']), rms(residual))


def write_residual(args, names: Sequence[str], s: Dict, res: Residual,
                   fitted, plotter, stages: Stages) -> bool:
    """Write summary.csv, the residual file and the plots into ``--out``; True if drawn.

    ``fitted``: ``replay identify``'s :class:`.identify.Fitted` (its drive terms are columns
    of summary.csv), or None. The plots are drawn in the plotting child while this process
    writes the residual.
    """
    t, effort = s['t'], s['effort']
    report.ensure_dir(args.out)
    header = ['joint', 'samples', 'rms_measured', 'rms_residual']
    rows = [[n, len(t), res.rms_measured[j], res.rms_residual[j]] for j, n in enumerate(names)]
    if fitted is not None and fitted.shown is not None:
        header += ['damping', 'friction', 'armature', 'rms_residual_identified']
        for j, r in enumerate(rows):      # nan: undetermined (the URDF's value stays)
            r += [fitted.shown[0][j], fitted.shown[1][j], fitted.shown[2][j],
                  fitted.rms_after[j]]
    report.write_summary(os.path.join(args.out, 'summary.csv'), rows, header)
    if not args.no_plots:
        # the child gets only the points drawn (decimated here, as plot_joints would)
        step = max(1, len(t) // PLOT_POINTS)
        plotter = report.run_in(plotter, plot_replay, args.out, args.topic,
                                t[::step] - t[0], names, effort[::step], res.tau[::step],
                                res.residual[::step])
    if args.residual == 'csv':
        report.write_csv(os.path.join(args.out, 'residual.csv'), ['t'] + list(names),
                         [t - t[0]] + [res.residual[:, j] for j in range(len(names))],
                         [6] + [4] * len(names))
    elif args.residual == 'npy':
        report.write_npy(os.path.join(args.out, 'residual.npy'),
                         np.column_stack((t - t[0], res.residual)))
    stages.done('write residual')
    if args.no_plots:
        return False
    drawn = report.join_child(plotter)
    if not drawn:
        print('replay: drawing the plots failed (see above); the CSV files are complete',
              file=sys.stderr)
    stages.done('plots (the rest)')
    return drawn


def residual_files(residual: str, drawn: bool) -> List[str]:
    """Return the names of the residual's files written (``--residual``, plots drawn)."""
    return ['summary.csv'] + {'csv': ['residual.csv'], 'npy': ['residual.npy'],
                              'none': []}[residual] + (
        ['measured_vs_model.png', 'residual.png'] if drawn else [])


def print_recording(args, model: Model, s: Dict) -> None:
    """Print what was read of the bag and how q̈ was found."""
    js, t = s['js'], s['t']
    window = differentiate.window_samples(args.window, s['period'])
    rate = 1.0 / s['period']
    print(f'{args.bag!r} {shown(args.topic)}: {len(js.stamp) + sum(js.skipped.values())} '
          f'messages, {len(t)} samples used over {t[-1] - t[0]:.3f} s at {rate:.6g} Hz '
          f'(median period), {len(s["spans"])} stretch(es) between gaps')
    print(f'model: {model.summary()}; torque = rigid-body RNEA only (no URDF <dynamics>, no '
          'armature)')
    print(f'q_dd from the {s["source"]}: Savitzky-Golay order {args.order}, window {window} '
          f'samples ({window / rate:.3g} s), cut-off about '
          f'{differentiate.cutoff(window, args.order, rate):.3g} Hz, zero phase'
          + (f'; {s["resampled"]} stretch(es) with uneven stamps resampled'
             if s['resampled'] else ''))
    if s['base'] is not None:
        print('base: moving, its motion from '
              + (f'--base-odometry {shown(args.base_odometry)} (twist differentiated with the '
                 'same filter, orientation for gravity)' if args.base_odometry else
                 f'--base-imu {shown(args.base_imu)} (gyro differentiated with the same filter, '
                 'accelerometer with gravity in it)') + ', interpolated to the joint stamps')
    if s['out_of_order']:
        print(f'{s["out_of_order"]} stamp(s) earlier than the one before: samples sorted by '
              'header stamp')
    if s['skipped']:
        print('skipped:')
        for reason, count in s['skipped'].items():
            print(f'  {count} sample(s): {reason}')
    if js.generic:
        print(f'{js.generic} message(s) of a different layout read by rosbags\' deserialiser')


def print_table(names: Sequence[str], res: Residual, fitted) -> None:
    """Print the residual RMS per joint (and the drive terms fitted, the drop)."""
    table_rows = [[shown(n, quote=False), f'{res.rms_measured[j]:.4g}',
                   f'{res.rms_residual[j]:.4g}'] for j, n in enumerate(names)]
    head = ['joint', 'rms measured', 'rms residual']
    if fitted is not None and fitted.shown is not None:
        before, after = fitted.rms_before, fitted.rms_after
        head += ['damping', 'friction', 'armature', 'rms identified', 'drop']
        for j, r in enumerate(table_rows):
            drop = 1.0 - after[j] / before[j] if before[j] else 0.0
            r += [term(x[j]) for x in fitted.shown] + [f'{after[j]:.4g}',
                                                       f'{100 * drop:.0f} %']
    print(report.table(head, table_rows))


def term(x: float) -> str:
    """Return a drive term for the table: 4 digits, or 'undetermined' (nan)."""
    return 'undetermined' if np.isnan(x) else f'{x:.4g}'


def command(sub) -> None:
    """``replay residual BAG``: the model's torque against the measured effort."""
    add_command(sub, 'residual', run, [recording_parser()],
                'residual of the model against a bag\'s measured effort',
                'Measured effort against the rigid-body model (RNEA) over a bag: summary.csv '
                '(per joint), residual.csv (per sample) and plots in --out.')
