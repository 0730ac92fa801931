# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Inverse dynamics over a recording: measured effort against the model, and a trajectory check.

    python -m spatial_dynamics.replay residual BAG --urdf URDF [--topic /joint_states]
                                      [--out DIR] [--window 0.05] [--residual csv|npy|none]
                                      [--base-odometry TOPIC | --base-imu TOPIC]
    python -m spatial_dynamics.replay identify BAG --urdf URDF [--threshold 0.01]
                                      [--inertias [LINK ...] | --payload LINK] [--drives]
                                      [--also BAG ...] [--validate BAG]
                                      [--write-urdf OUT.urdf]
    python -m spatial_dynamics.replay trajectory FILE.yaml --urdf URDF [--rate 1000]
    python -m spatial_dynamics.replay trajectory BAG --topic /arm/joint_trajectory --urdf URDF
    python -m spatial_dynamics.replay annotate FILE.yaml --urdf URDF --out OUT.yaml
    python -m spatial_dynamics.replay excite --urdf URDF --duration 30 --out plan.yaml
    ros2 run spatial_dynamics replay ...

A bag (rosbag2, sqlite3 or MCAP; no ROS installation needed) gives q, q̇ and the measured
effort by joint name; q̈ comes from a zero-phase Savitzky-Golay derivative of q̇ (of q when
the bag has no velocities). The model torque is the rigid-body RNEA for the whole bag in one
batched call. Written to DIR: summary.csv (per joint), residual.csv (per sample: t, measured
- model per joint), measured_vs_model.png, residual.png (``residual``). ``identify`` fits
per-joint damping, Coulomb friction (tanh(q̇/threshold), as the node) and armature to the
residual. On a moving base (a mobile manipulator) ``--base-odometry`` or ``--base-imu`` reads
the base's motion from the same bag (:mod:`.base_topics`); it goes to RNEA and every fit.

``identify --inertias [LINK ...]`` fits the inertial parameters of the links (default all
moving ones; physically consistent, regularised toward the URDF; with ``--drives`` jointly
with the drives) and warns, naming them, about the combinations the recording does not determine;
``--payload LINK`` fits a payload. What was identified is checked on a held-out recording
(``--validate BAG``: the residual with the URDF and with the correction, validation.csv,
identification.png), listed with one σ (parameters.csv), and ``--write-urdf OUT.urdf``
writes the URDF with only the identified ``<inertial>`` and ``<dynamics>`` replaced.

``excite`` plans a motion that determines every base parameter (:mod:`.excite`), for
joint_trajectory_controller to execute while the bag is recorded.

A trajectory (``trajectory`` of a YAML file, or of a bag's ``--topic``) is sampled like
joint_trajectory_controller's splines at ``--rate`` and τ compared with the URDF effort limits;
``annotate`` writes a plan with the effort for joint_trajectory_controller (:mod:`.annotate`).

Exit status: 0 done (samples skipped are listed with the reason), 1 refused (no such bag,
topic or joint, nothing usable, rosbags missing; a trajectory exceeding an effort limit),
2 bad usage, 130 interrupted (Ctrl-C: each file is whole or not there). Every input and
output is checked before any work: an output that is an input, in a bag directory, a
directory, a named pipe or a device is refused; every file is written to a temporary beside
it and renamed.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import importlib.util
import os
import sys
from typing import Dict, List, NamedTuple, Optional, Sequence, Tuple

import numpy as np

from .. import friction_torque, Model, rnea
from ..check import read_description
from .. import effort as effort_model
from ..extras import install_hint
from ..files import check_output, check_outside_recordings
from . import (annotate, bags, base_topics, differentiate, excite, identify, report, splines,
               urdf_writer)
from .recording import recording, Stages
from .. import identification
from .arguments import (check_model, effort_tolerance, load_model, model_parser, one_line,
                        Parser, Refused, sampling_rate, velocity_threshold, window_s)
from ..urdf import read_urdf_file
from . import correction as correction_of

#: The node's default ``friction_velocity_threshold`` (config/inverse_dynamics.yaml).
NODE_THRESHOLD = 0.01


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
    try:
        from numpy._core.multiarray import _set_madvise_hugepage
    except ImportError:
        try:                    # numpy 1.x (Ubuntu 24.04's python3-numpy is 1.26)
            from numpy.core.multiarray import _set_madvise_hugepage
        except ImportError:
            yield
            return
    before = _set_madvise_hugepage(False)
    try:
        yield
    finally:
        _set_madvise_hugepage(before)


def mimic_notes(model: Model) -> List[str]:
    """Say which joints of ``q`` drive mimic joints (their fitted terms include those)."""
    notes = []
    for k, name in enumerate(model.joint_names):
        followers = [model.body_joints[i] for i in range(1, model.NB + 1)
                     if model.qidx[i] == k and model.body_joints[i] != name]
        if followers:
            notes.append(f'{name} drives mimic joint(s) {", ".join(followers)}: its fitted '
                         'terms include theirs (set their <dynamics> to 0)')
    return notes


# --------------------------------------------------------------------------------------------
# The bag command

def to_sigma(x: float, sigma: float) -> str:
    """Return ``x`` with the digits its σ allows (to σ's second significant digit)."""
    if not (np.isfinite(sigma) and sigma > 0):
        return f'{x:.5g}'
    return f'{x:.{max(0, 1 - int(np.floor(np.log10(sigma))))}f}'


def print_payload(payload, names: Sequence[str], args) -> None:
    """Print an identified payload: values with one σ, the node's parameters, a URDF tag."""
    s = payload.sigma
    rms = ', '.join(f'{n} {r:.3g}' for n, r in zip(names, payload.rms))
    print(f'\npayload on {payload.link!r}: {to_sigma(payload.mass, s[0])} kg (σ {s[0]:.2g}), '
          'centre of '
          f'mass {np.array2string(payload.com, precision=4)} m (link frame); residual RMS '
          f'per joint after the fit {rms}')
    print('\n# node parameters (the payload):')
    print(payload.node_parameters(), end='')
    print('\n<!-- URDF: the payload as an <inertial> in the frame of '
          f'{payload.link!r} -->')
    print(payload.urdf_inertial())


class Fitted(NamedTuple):
    """What ``replay identify`` fitted: the correction and what is said of it."""

    correction: correction_of.Correction
    #: The drive terms shown (damping, friction, armature; nan: undetermined), or None.
    shown: Optional[Tuple[np.ndarray, np.ndarray, np.ndarray]]
    #: Residual RMS per joint before and after the fit (None without drive terms).
    rms_before: Optional[np.ndarray]
    rms_after: Optional[np.ndarray]
    #: The joint fit of the drives alone (its notes are printed), or None.
    fit: Optional[identify.Identified]
    payload: Optional[identification.Payload]
    #: What the recording does not determine (said on stderr at the end), or ''.
    warning: str


class Residual(NamedTuple):
    """Measured effort against the model's torque over a recording."""

    tau: np.ndarray
    residual: np.ndarray
    rms_measured: np.ndarray
    rms_residual: np.ndarray


def run_residual(args) -> int:
    """``replay residual``: the model against the bag's efforts; the files; return 0."""
    return run_bag(args, None)


def run_identify(args) -> int:
    """``replay identify``: the residual, the fits, the held-out check; return 0."""
    return run_bag(args, fits)


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


def check_matplotlib(args) -> None:
    """Refuse plots without matplotlib, before any work."""
    if not args.no_plots and importlib.util.find_spec('matplotlib') is None:
        raise Refused('the plots need matplotlib (pip install matplotlib, or apt install '
                      'python3-matplotlib); or --no-plots')


def compare(args, plotter, fit=None) -> int:
    """:func:`run_bag` with its plotting child (from :func:`report.start_child`, or None).

    The jobs in turn: the recording read (:func:`recording`), the residual
    (:func:`residual_of`), the fits when ``fit`` (:func:`fits`), the residual's files
    (:func:`write_residual`), the report (:func:`print_recording`, :func:`print_table`,
    :func:`print_fits`, :func:`corrected`).
    """
    stages = Stages()
    model = load_model(args)
    stages.done('model')
    if fit is not None:
        check_links(args, model)
        urdf_source = urdf_to_write(args, model)    # its problems said before any fit
    s = recording(args, args.bag, model, stages)
    res = residual_of(model, s, args.gravity)
    stages.done('rnea')
    fitted = train = held_out = None
    if fit is not None:
        # what the fits see: this bag and the --also ones, each cleaned and differentiated
        train = {k: s[k] for k in ('q', 'qd', 'qdd', 'effort')}
        if args.also:
            more = [recording(args, bag, model, stages) for bag in args.also]
            train = {k: np.concatenate([train[k]] + [m[k] for m in more]) for k in train}
            train['base'] = base_topics.joined([s['base']] + [m['base'] for m in more])
            print(f'fitted on {args.bag} and {len(more)} more bag(s): {len(train["q"])} '
                  'samples')
        else:
            train['base'] = s['base']
        # read before the fits: a held-out bag that cannot be used is said before them
        held_out = recording(args, args.validate, model, stages) if args.validate else None
        fitted = fit(args, model, train, res, stages)
    drawn = write_residual(args, model.joint_names, s, res, fitted, plotter, stages)
    print_recording(args, model, s)
    print_table(model.joint_names, res, fitted)
    written = residual_files(args.residual, drawn)
    if fitted is not None:
        print_fits(args, model, fitted)
        written += corrected(args, model, fitted.correction, train, stages, held_out,
                             urdf_source)
        if fitted.warning:
            print(fitted.warning, file=sys.stderr)
    print(f'\nwritten to {args.out}: {", ".join(written)}')
    if args.timings:
        print('stages:\n' + stages.text(), file=sys.stderr)
    return 0


def residual_of(model: Model, s: Dict, gravity) -> Residual:
    """Return the model's torque (RNEA, one batched call) and the residual over ``s``."""
    tau = rnea(model, s['q'], s['qd'], s['qdd'], gravity, base=s['base'])
    residual = s['effort'] - tau
    return Residual(tau, residual, rms(s['effort']), rms(residual))


def fits(args, model: Model, train: Dict, res: Residual, stages: Stages) -> Fitted:
    """Fit what ``replay identify`` asks to ``train`` (the bag, with ``--also``'s).

    The drives alone (:func:`identify.identify`, the default), or ``--payload`` or
    ``--inertias`` (with ``--drives``, jointly with each joint's damping, friction and
    armature). ``res`` is the bag's residual (the drives' fit without ``--also``).
    """
    fq, fqd, fqdd, feffort, base = (train[k] for k in ('q', 'qd', 'qdd', 'effort', 'base'))
    names = model.joint_names
    drives = args.drives or (args.payload is None and args.inertias is None)
    threshold = args.threshold if drives else None
    fit = payload = found = None
    correction, excitation_warning = None, ''
    # the fits work on matrices of a hundred columns, or share their chunks among the
    # command's own threads: BLAS threads beside those only oversubscribe the cores
    from threadpoolctl import threadpool_limits
    with threadpool_limits(limits=1, user_api='blas'):
        if args.payload is None and args.inertias is None:
            fresidual = res.residual if not args.also else feffort - rnea(
                model, fq, fqd, fqdd, args.gravity, base=base)
            fit = identify.identify(fresidual, fqd, fqdd, args.threshold, names)
            correction = correction_of.from_drives(model, fit, args.threshold)
            stages.done('identify')
        elif args.payload:
            payload = identification.identify_payload(
                model, args.payload, fq, fqd, fqdd, feffort, args.gravity, threshold,
                base=base)
            correction = correction_of.Correction(model, payload=payload,
                                                  drives=payload.drives,
                                                  threshold=args.threshold)
            stages.done('payload')
        else:
            found = identification.identify_inertias(
                model, fq, fqd, fqdd, feffort, args.inertias or None, args.gravity, threshold,
                base=base)
            if not found.converged:
                print(f'warning: the inertial fit stopped after {found.evaluations} '
                      f'evaluations without converging ({found.message}): its values are '
                      'its last step; judge them by the residual, and the links flagged below',
                      file=sys.stderr)
            correction = correction_of.from_inertias(model, found, args.threshold)
            excitation_warning = correction_of.undetermined_warning(
                model, train, found.bodies, args.gravity)
            stages.done('inertias')
    # one set of drive terms (the joint fit's when there is one), printed and written
    shown = rms_before = rms_after = None
    if correction.drives is not None:
        shown = correction.undetermined_drives()
        if fit is not None:
            rms_before, rms_after = fit.rms_before, fit.rms_after
        elif found is not None:
            rms_before, rms_after = found.before, found.after
        else:
            rms_before, rms_after = (rms(feffort - rnea(model, fq, fqd, fqdd, args.gravity,
                                                        base=base))
                                     if args.also else res.rms_residual), payload.rms
    return Fitted(correction, shown, rms_before, rms_after, fit, payload, excitation_warning)


def write_residual(args, names: Sequence[str], s: Dict, res: Residual,
                   fitted: Optional[Fitted], plotter, stages: Stages) -> bool:
    """Write summary.csv, the residual file and the plots into ``--out``; True if drawn.

    The plots are drawn in the plotting child while this process writes the residual.
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
    print(f'{args.bag} {args.topic}: {len(js.stamp) + sum(js.skipped.values())} messages, '
          f'{len(t)} samples used over {t[-1] - t[0]:.3f} s at {rate:.6g} Hz '
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
              + (f'--base-odometry {args.base_odometry} (twist differentiated with the same '
                 'filter, orientation for gravity)' if args.base_odometry else
                 f'--base-imu {args.base_imu} (gyro differentiated with the same filter, '
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


def print_table(names: Sequence[str], res: Residual, fitted: Optional[Fitted]) -> None:
    """Print the residual RMS per joint (and the drive terms fitted, the drop)."""
    table_rows = [[n, f'{res.rms_measured[j]:.4g}', f'{res.rms_residual[j]:.4g}']
                  for j, n in enumerate(names)]
    head = ['joint', 'rms measured', 'rms residual']
    if fitted is not None and fitted.shown is not None:
        before, after = fitted.rms_before, fitted.rms_after
        head += ['damping', 'friction', 'armature', 'rms identified', 'drop']
        for j, r in enumerate(table_rows):
            drop = 1.0 - after[j] / before[j] if before[j] else 0.0
            r += [_value(x[j]) for x in fitted.shown] + [f'{after[j]:.4g}',
                                                         f'{100 * drop:.0f} %']
    print(report.table(head, table_rows))


def print_fits(args, model: Model, fitted: Fitted) -> None:
    """Print the drive terms as node parameters and URDF ``<dynamics>``, and the payload."""
    names = model.joint_names
    shown = fitted.shown
    if shown is not None:
        what = ('the inertias fitted jointly with each drive' if args.inertias is not None
                else 'the payload fitted jointly with each drive' if args.payload else
                'each drive fitted to the residual')
        print(f'\n{what} (damping, friction, armature: the table above and the parameters '
              f'below are this one fit), friction threshold {args.threshold:g} rad/s (m/s); '
              'undetermined: the recording cannot tell it, the URDF\'s value stays:')
        for note in (fitted.fit.notes if fitted.fit is not None else []) + mimic_notes(model):
            print(f'  note: {note}')
        print('\n# node parameters (config/*.yaml):')
        print(report.node_parameters(names, shown[2], args.threshold))
        print('\n<!-- URDF: each joint\'s <dynamics> (read by friction_model: urdf) -->')
        print(report.urdf_dynamics(names, shown[0], shown[1], model.damping, model.friction))
    if fitted.payload is not None:
        print_payload(fitted.payload, names, args)


def _value(x: float) -> str:
    """Return a drive term for the table: 4 digits, or 'undetermined' (nan)."""
    return 'undetermined' if np.isnan(x) else f'{x:.4g}'


def corrected(args, model: Model, correction, data: Dict, stages: Stages,
              held_out: Optional[Dict] = None,
              urdf_source: Optional[urdf_writer.Source] = None) -> List[str]:
    """Report a correction: inertias, residual before and after (held-out), files written.

    ``held_out`` is the ``--validate`` recording, ``urdf_source`` the ``--write-urdf`` one's
    URDF (:func:`urdf_to_write`).
    """
    written = ['parameters.csv', 'validation.csv']
    if correction.bodies:
        correction_of.print_inertias(correction)
    correction_of.write_parameters(correction, args.out)
    train = correction_of.residuals(correction, data, args.gravity)
    held = None
    if held_out is not None:
        held = correction_of.residuals(correction, held_out, args.gravity)
        stages.done('validate')
    correction_of.print_validation(model.joint_names, train, held, args.out,
                                   not args.no_plots)
    if not args.no_plots:
        written.append('identification.png')
    if args.write_urdf:
        if args.urdf.endswith('.xacro'):
            print(f'note: {args.urdf} is a xacro file: {args.write_urdf} is its expansion '
                  'with the identified elements replaced')
        for note in correction.write_urdf(urdf_source, args.write_urdf):
            print(f'note: {note}')
        print(f'\ncorrected URDF: {args.write_urdf} (only the identified <inertial> and '
              '<dynamics> elements differ from ' + os.path.basename(args.urdf) + ')')
        if correction.drives is not None:
            print('  with the node: friction_model: urdf, friction_velocity_threshold: '
                  f'{args.threshold:g} and the armature above')
    return written


# --------------------------------------------------------------------------------------------
# The trajectory and annotate commands

def run_trajectory(args) -> int:
    """``replay trajectory``: check a plan, or a bag's plans, against the effort limits.

    Returns 1 when a limit is exceeded (or a torque is not finite), else 0.
    """
    check_paths(args)
    check_matplotlib(args)
    if not args.topic:
        try:
            trajectories = [splines.from_yaml(args.source)]
        except OSError as err:
            raise Refused(f'{args.source}: {err.strerror}') from None
        except ValueError as err:
            raise Refused(str(err)) from None
        labels = [os.path.basename(args.source)]
    else:
        msgs = bags.read_messages(args.source, args.topic, bags.JOINT_TRAJECTORY)
        if not msgs:
            raise Refused(f'no messages on {args.topic}')
        trajectories = [splines.from_message(m) for m in msgs]
        labels = [f'{args.topic} #{k}' for k in range(len(msgs))]
    bases = [os.path.join(args.out, 'trajectory' + (f'_{k}' if len(trajectories) > 1 else ''))
             for k in range(len(trajectories))]
    for base in bases:            # the names are known now: checked before any work
        for ext in ('.csv',) + (() if args.no_plots else ('.png',)):
            check_output(base + ext, 'output', input_files(args))
    exceeded = False
    for traj, label, base in zip(trajectories, labels, bases):
        model = load_model(args, args.joints or list(traj.joint_names))
        unknown = [j for j in model.joint_names if j not in traj.joint_names]
        if unknown:
            raise Refused(f'{label}: joint(s) {", ".join(unknown)} not in the trajectory')
        cols = [traj.joint_names.index(j) for j in model.joint_names]
        t, q, qd, qdd = splines.sample(traj, args.rate)
        q, qd, qdd = q[:, cols], qd[:, cols], qdd[:, cols]
        tau = rnea(model, q, qd, qdd, args.gravity)
        if args.friction_model == 'urdf':
            tau = tau + friction_torque(model, qd, args.threshold)
        limit = model.effort_limit
        rows, over = report.effort_rows(model.joint_names, t, tau, limit)
        exceeded |= over
        print(f'{label}: {len(traj.time)} points, {traj.kind} interpolation, '
              f'{t[-1] - t[0]:.3f} s sampled at {args.rate:g} Hz ({len(t)} samples); '
              'torque = RNEA' + (' + URDF friction' if args.friction_model == 'urdf' else ''))
        if model.locked:
            print(f'  joints not in the trajectory, locked: '
                  f'{", ".join(f"{j}={v:g}" for j, v in model.locked.items())}')
        print(report.table(report.EFFORT_HEADER, rows))
        report.write_csv(base + '.csv', ['t'] + [f'tau_{n}' for n in model.joint_names],
                         [t] + [tau[:, j] for j in range(model.nq)], [6] + [4] * model.nq)
        if not args.no_plots:
            report.plot_joints(base + '.png', t, model.joint_names, {'tau': tau},
                               f'{label}: torque along the trajectory (N m or N), limits dashed',
                               limits=limit)
    if exceeded:
        print('error: an effort limit is exceeded (or a torque is not finite)', file=sys.stderr)
        return 1
    return 0


def run_annotate(args) -> int:
    """``replay annotate``: write the plan with effort for JTC (:mod:`.annotate`)."""
    return annotate.run(args, load_model)


# --------------------------------------------------------------------------------------------
# The command line: one function declares a subcommand, COMMANDS registers it

def recording_parser() -> argparse.ArgumentParser:
    """Return a parent parser of what reads a recording and writes its residual (no help)."""
    p = argparse.ArgumentParser(add_help=False)
    p.add_argument('bag', metavar='BAG', help='rosbag2 directory, or a .db3 / .mcap file')
    p.add_argument('--topic', default='/joint_states',
                   help='sensor_msgs/JointState topic (default %(default)s)')
    p.add_argument('--out', default='replay_out',
                   help='output directory, created (default %(default)s)')
    p.add_argument('--window', type=window_s, default=0.05,
                   help='Savitzky-Golay window, s (default %(default)g)')
    p.add_argument('--order', type=int, choices=range(2, 7), default=3,
                   help='Savitzky-Golay polynomial order (default %(default)d)')
    p.add_argument('--measured-effort', choices=effort_model.MEASURED_EFFORT, default='full',
                   help='what the bag\'s effort is: link-side torque with gravity (full: '
                   'Franka, KUKA) or gravity_compensated (UR); default %(default)s')
    p.add_argument('--residual', choices=('csv', 'npy', 'none'), default='csv',
                   help='per-sample residual file (default %(default)s)')
    p.add_argument('--no-plots', action='store_true', help='write no PNG files')
    p.add_argument('--generic', action='store_true',
                   help='read every message through rosbags (no numpy fast path)')
    p.add_argument('--timings', action='store_true', help='print stage times to stderr')
    base_topics.add_base_arguments(p)
    return p


def add_threshold(p: argparse.ArgumentParser) -> None:
    """Declare ``--threshold``, the friction velocity threshold (the node's by default)."""
    p.add_argument('--threshold', type=velocity_threshold, default=NODE_THRESHOLD,
                   help='friction velocity threshold, rad/s or m/s (default: the node\'s, '
                   '%(default)g)')


def add_command(sub, name: str, work, parents: List[argparse.ArgumentParser], summary: str,
                description: str) -> argparse.ArgumentParser:
    """Add the subcommand ``name`` that runs ``work(args)`` (:func:`run`); return its parser.

    ``summary`` is its line in ``replay --help``; ``description`` heads its own ``--help``.
    The model options come from one parent parser (:func:`model_parser`), then ``parents``.
    """
    p = sub.add_parser(name, parents=[model_parser()] + parents, help=summary,
                       description=description, epilog=EXIT_STATUS)
    p.set_defaults(run=functools.partial(run, work, p))
    return p


def residual_command(sub) -> None:
    """``replay residual BAG``: the model's torque against the measured effort."""
    add_command(sub, 'residual', run_residual, [recording_parser()],
                'residual of the model against a bag\'s measured effort',
                'Measured effort against the rigid-body model (RNEA) over a bag: summary.csv '
                '(per joint), residual.csv (per sample) and plots in --out.')


def identify_command(sub) -> None:
    """``replay identify BAG``: the drives, a payload or the inertias fitted to a bag."""
    p = add_command(sub, 'identify', run_identify, [recording_parser()],
                    'fit the drives, a payload or the inertias to bags',
                    'Fit each joint\'s damping, Coulomb friction and armature (the default), a '
                    '--payload or the --inertias (--drives: jointly with the drives) to BAG '
                    '(and --also\'s); check on --validate, write the corrected URDF '
                    '(--write-urdf). Written to --out: the residual\'s files (as residual '
                    'writes them), parameters.csv, validation.csv, identification.png.')
    what = p.add_mutually_exclusive_group()
    what.add_argument('--payload', metavar='LINK',
                      help='identify a rigid payload on LINK (mass, centre of mass, inertia) '
                      'against the URDF without it')
    what.add_argument('--inertias', nargs='*', metavar='LINK',
                      help='identify the inertial parameters of these links (default: every '
                      'moving one), physically consistent, regularised toward the URDF')
    p.add_argument('--drives', action='store_true',
                   help='with --payload or --inertias: fit each joint\'s damping, friction '
                   'and armature jointly with them (alone, the default fit)')
    p.add_argument('--also', nargs='+', metavar='BAG', default=[],
                   help='more recordings to fit on with BAG; the files written are of BAG')
    p.add_argument('--validate', metavar='BAG',
                   help='a held-out recording: the residual with the URDF and with what was '
                   'identified')
    p.add_argument('--write-urdf', metavar='OUT.urdf',
                   help='write the URDF with only the identified <inertial> and <dynamics> '
                   'elements replaced')
    add_threshold(p)


def trajectory_command(sub) -> None:
    """``replay trajectory PLAN.yaml`` (or ``BAG --topic T``): τ against the effort limits."""
    p = add_command(sub, 'trajectory', run_trajectory, [],
                    'check a plan, or a bag\'s plans, against effort limits',
                    'Sample a plan (trajectory_msgs/JointTrajectory YAML), or every '
                    'JointTrajectory of --topic in a bag, as joint_trajectory_controller\'s '
                    'splines at --rate; compare the torque with the URDF effort limits '
                    '(exit 1 when one is exceeded); trajectory.csv and a plot in --out.')
    p.add_argument('source', metavar='PLAN.yaml|BAG',
                   help='a trajectory_msgs/JointTrajectory (YAML), or a bag with --topic')
    p.add_argument('--topic', metavar='TOPIC',
                   help='check every JointTrajectory of this topic of the bag')
    p.add_argument('--out', default='replay_out',
                   help='output directory, created (default %(default)s)')
    p.add_argument('--rate', type=sampling_rate, default=1000.0,
                   help='sampling rate, Hz (default %(default)g)')
    p.add_argument('--friction-model', choices=('none', 'urdf'), default='none',
                   help='urdf: add the URDF <dynamics> friction, as the node does '
                   '(default %(default)s)')
    add_threshold(p)
    p.add_argument('--no-plots', action='store_true', help='write no PNG files')


def annotate_command(sub) -> None:
    """``replay annotate PLAN.yaml --out OUT.yaml``: the plan with effort for JTC."""
    p = add_command(sub, 'annotate', run_annotate, [],
                    'fill a plan\'s effort for joint_trajectory_controller',
                    'Write the plan with effort filled for joint_trajectory_controller, '
                    'resampled so that its linear interpolation of effort stays within '
                    '--tolerance of the model torque; the efforts checked against the URDF '
                    'limits (exit 1). Only --out is written.')
    p.add_argument('plan', metavar='PLAN.yaml', help='a trajectory_msgs/JointTrajectory (YAML)')
    p.add_argument('--out', required=True, metavar='OUT.yaml', help='the annotated plan')
    p.add_argument('--tolerance', type=effort_tolerance, default=0.1,
                   help='|JTC\'s linear interpolation of effort - model torque|, N m (default '
                   '%(default)g)')
    p.add_argument('--output', choices=effort_model.OUTPUTS, default='full',
                   help='the torque written (default %(default)s)')


def fleet_command(sub) -> None:
    """``replay fleet SOURCE``: every bag of a fleet on a Dask cluster, trends and wear."""
    from ..fleet import command as fleet
    p = sub.add_parser('fleet', help='a fleet\'s bags on a Dask cluster: drive trends, wear',
                       description=fleet.__doc__.split('\n\n')[0],
                       epilog=fleet.EXIT_STATUS)
    fleet.add_arguments(p)
    p.set_defaults(run=fleet.run)


#: The subcommands, in the order of ``replay --help``: each a function of the subparsers.
COMMANDS = (residual_command, identify_command, trajectory_command, annotate_command,
            excite.command, fleet_command)

#: The positional arguments as --help names them.
POSITIONALS = {'bag': 'BAG', 'source': 'PLAN.yaml|BAG', 'plan': 'PLAN.yaml'}
#: What the exit status says, in every --help.
EXIT_STATUS = ('Exit status: 0 done, 1 refused (or an effort limit exceeded), 2 bad usage, '
               '130 interrupted.')


def parser() -> argparse.ArgumentParser:
    """Return the command's argument parser: one subparser a job."""
    return parser_and_commands()[0]


def parser_and_commands() -> Tuple[argparse.ArgumentParser, Dict[str, argparse.ArgumentParser]]:
    """Return the command's argument parser and its subcommands' parsers by name."""
    p = Parser(prog='replay', description=__doc__.split('\n\n')[0],
               formatter_class=argparse.RawDescriptionHelpFormatter,
               epilog='Each command has its --help. ' + EXIT_STATUS)
    sub = p.add_subparsers(dest='command', required=True, title='commands')
    for command in COMMANDS:
        command(sub)
    return p, sub.choices


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the command; return the exit status (0, 1, 2 or 130)."""
    argv = sys.argv[1:] if argv is None else list(argv)
    args = parser().parse_args(argv)
    try:
        return args.run(args)
    except ImportError as err:        # an optional dependency: say which extra brings it
        hint = install_hint(err, 'fleet' if args.command == 'fleet' else 'replay')
        if not hint:
            raise
        print(f'error: replay {args.command}: {hint}', file=sys.stderr)
        return 1


def run(work, p: argparse.ArgumentParser, args) -> int:
    """Check what the parser cannot (usage errors by ``p``), run ``work(args)``.

    Refusals, missing files and a lack of memory are one line on stderr, exit 1;
    Ctrl-C is ``interrupted``, exit 130 (every file is whole or absent, the child ended).
    """
    check_model(p, args)
    base_topics.check_base_arguments(p, args)
    for dest, value in vars(args).items():      # '' is no path, link, joint or topic
        if value == '' or (isinstance(value, list) and '' in value):
            p.error(POSITIONALS.get(dest, '--' + dest.replace('_', '-')) + ': an empty value')
    try:
        return work(args)
    except (Refused, bags.BagError, bags.MissingDependency, ValueError) as err:
        print(f'error: {one_line(err)}', file=sys.stderr)
    except OSError as err:
        where = f'{err.filename}: ' if err.filename else ''
        print(f'error: {where}{err.strerror or one_line(err)}', file=sys.stderr)
    except MemoryError:
        print('error: out of memory (a smaller --rate, a shorter bag or fewer joints?)',
              file=sys.stderr)
    except KeyboardInterrupt:     # Ctrl-C: every file is whole or absent, the child ended
        print('interrupted', file=sys.stderr)
        return 130
    return 1


# --------------------------------------------------------------------------------------------
# Before any work: every input there, every output writable and no input

def bag_options(args) -> List[Tuple[str, str]]:
    """Return ``(option, path)`` of each bag the command reads (``'BAG'`` for the first)."""
    if args.command == 'trajectory':
        return [('BAG', args.source)] if args.topic else []
    found = [('BAG', args.bag)] + [('--also', bag) for bag in vars(args).get('also', [])] + [
        ('--validate', vars(args).get('validate'))]
    return [(option, path) for option, path in found if path]


def output_files(args) -> List[str]:
    """Return the names of the files the command writes into ``--out``."""
    if args.command == 'trajectory':
        return ['trajectory.csv'] + ([] if args.no_plots else ['trajectory.png'])
    names = ['summary.csv'] + {'csv': ['residual.csv'], 'npy': ['residual.npy'],
                               'none': []}[args.residual]
    if not args.no_plots:
        names += ['measured_vs_model.png', 'residual.png']
    if args.command == 'identify':
        names += ['parameters.csv', 'validation.csv']
        names += [] if args.no_plots else ['identification.png']
    return names


def input_files(args) -> List[str]:
    """Return the files (and bag directories) the command reads."""
    plan = [args.source] if args.command == 'trajectory' and not args.topic else []
    return [path for path in [args.urdf] + plan + [b for _, b in bag_options(args)] if path]


def check_paths(args) -> None:
    """Refuse, before any work, a bag that cannot be opened and an output that cannot be one.

    Each bag (BAG, ``--also``, ``--validate``) must open (:func:`bags.check_bag`) and be
    given once (a held-out recording that is a training one checks nothing); ``--out`` must
    be a directory (it is created); ``--write-urdf`` and the files written into ``--out``
    must not be an input (``--urdf``, a bag, a plan), in a bag directory, one another, a
    directory, a named pipe or a device (:func:`check_output`). Refused names the option and
    the path.
    """
    given = bag_options(args)
    inputs = input_files(args)
    for k, (option, path) in enumerate(given):
        try:
            bags.check_bag(path)
        except bags.BagError as err:
            raise Refused(str(err) if option == 'BAG' else f'{option} {err}') from None
        for before, other in given[:k]:
            if os.path.samefile(path, other):
                raise Refused(f'{option} {path}: the same recording as {before} {other} ('
                              + ('a held-out check needs another recording)'
                                 if option == '--validate' else 'fitted once is enough)'))
    names = output_files(args)
    write_urdf = vars(args).get('write_urdf')
    outputs = [('--out', args.out)] + [('output', os.path.join(args.out, n)) for n in names]
    if write_urdf:
        outputs.append(('--write-urdf', write_urdf))
        for _, path in outputs[1:-1]:
            if os.path.abspath(path) == os.path.abspath(write_urdf):
                raise Refused(f'--write-urdf {write_urdf}: the command writes '
                              f'{os.path.basename(path)} there (--out {args.out})')
    for what, path in outputs:
        try:
            check_outside_recordings(path, what, given)
        except ValueError as err:
            raise Refused(str(err)) from None
    if write_urdf:
        check_output(write_urdf, '--write-urdf', inputs)
    output_dir(args.out)
    for what, path in outputs[1:len(names) + 1]:
        check_output(path, what, inputs)


def check_links(args, model: Model) -> None:
    """Refuse a ``--payload`` or ``--inertias`` link that is none, or that no joint moves."""
    for option, links in (('--payload', [args.payload] if args.payload else []),
                          ('--inertias', args.inertias or [])):
        for link in links:
            try:
                identification.link_to_body(model, link)
            except ValueError as err:
                raise Refused(f'{option}: {err}') from None


def urdf_to_write(args, model: Model) -> Optional[urdf_writer.Source]:
    """Return ``--urdf`` as ``--write-urdf`` will edit it (None without it); Refused if not.

    Read and parsed before any fit (:func:`urdf_writer.prepare`): what the writer cannot
    edit is said at once. A xacro file is its expansion.
    """
    if not args.write_urdf:
        return None
    text = read_description(args.urdf) if args.urdf.endswith('.xacro') else \
        read_urdf_file(args.urdf)
    try:
        return urdf_writer.prepare(text, model, f'URDF file {args.urdf!r}')
    except ValueError as err:
        raise Refused(str(err)) from None


def output_dir(path: str) -> None:
    """Create the output directory ``path``; Refused naming it when it cannot be one."""
    try:
        report.ensure_dir(path)
    except OSError as err:
        raise Refused(f'--out {path}: cannot be the output directory ({err.strerror})') from None
    if not os.access(path, os.W_OK | os.X_OK):
        raise Refused(f'--out {path}: cannot write in this directory')


if __name__ == '__main__':
    sys.exit(main())
