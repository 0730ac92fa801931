# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""``replay identify BAG``: the drives, a payload or the inertias fitted to recordings.

The comparison of ``replay residual`` (:mod:`.residual`) with the fits hooked in
(:class:`Identification`): the links and the URDF to write checked before any fit, the
training recordings (BAG and ``--also``'s) and the held-out one (``--validate``) read, the
fit (:func:`fits`: :func:`spatial_dynamics.drives.identify`,
:func:`~spatial_dynamics.identification.identify_payload` or
:func:`~spatial_dynamics.identification.identify_inertias`), and its report
(:func:`print_fits`, :func:`corrected`: parameters.csv, validation.csv, identification.png,
the corrected URDF).
"""

from __future__ import annotations

import os
import sys
from typing import Dict, List, NamedTuple, Optional, Sequence, Tuple

import numpy as np

from .. import drives, identification, rnea
from ..model import Model
from ..recordings import base_topics
from ..recordings.errors import Refused
from ..recordings.loading import read_description
from ..recordings.recording import Stages
from ..text import shown
from ..urdf import read_urdf_file
from . import correction as correction_of
from . import report, urdf_writer
from .arguments import add_command, add_threshold, recording_parser
from .residual import recording, Residual, rms, run_bag


def mimic_notes(model: Model) -> List[str]:
    """Say which joints of ``q`` drive mimic joints (their fitted terms include those)."""
    notes = []
    for k, name in enumerate(model.joint_names):
        followers = [model.body_joints[i] for i in range(1, model.NB + 1)
                     if model.qidx[i] == k and model.body_joints[i] != name]
        if followers:
            notes.append(f'{shown(name)} drives mimic joint(s) '
                         f'{", ".join(map(shown, followers))}: its fitted '
                         'terms include theirs (set their <dynamics> to 0)')
    return notes


def to_sigma(x: float, sigma: float) -> str:
    """Return ``x`` with the digits its σ allows (to σ's second significant digit)."""
    if not (np.isfinite(sigma) and sigma > 0):
        return f'{x:.5g}'
    return f'{x:.{max(0, 1 - int(np.floor(np.log10(sigma))))}f}'


def print_payload(payload, names: Sequence[str], args) -> None:
    """Print an identified payload: values with one σ, the node's parameters, a URDF tag."""
    s = payload.sigma
    rms = ', '.join(f'{shown(n, quote=False)} {r:.3g}' for n, r in zip(names, payload.rms))
    print(f'\npayload on {shown(payload.link)}: {to_sigma(payload.mass, s[0])} kg (σ {s[0]:.2g}), '
          'centre of '
          f'mass {np.array2string(payload.com, precision=4)} m (link frame); residual RMS '
          f'per joint after the fit {rms}')
    print('\n# node parameters (the payload):')
    print(payload.node_parameters(), end='')
    print('\n<!-- URDF: the payload as an <inertial> in the frame of '
          f'{shown(payload.link)} -->')
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
    fit: Optional[drives.Identified]
    payload: Optional[identification.Payload]
    #: What the recording does not determine (said on stderr at the end), or ''.
    warning: str


def run(args) -> int:
    """``replay identify``: the residual, the fits, the held-out check; return 0."""
    return run_bag(args, Identification(args))


class Identification:
    """``replay identify``'s part of the comparison (:func:`.residual.compare`).

    :meth:`check` before the bag is read (the links, the URDF to write), :meth:`fit` after
    its residual (the training and held-out recordings read, :func:`fits`), :meth:`report`
    at the end (:func:`print_fits`, :func:`corrected`).
    """

    def __init__(self, args) -> None:
        """Keep the parsed command line."""
        self.args = args
        self.urdf_source: Optional[urdf_writer.Source] = None
        self.train: Optional[Dict] = None
        self.held_out: Optional[Dict] = None

    def check(self, model: Model) -> None:
        """Refuse a link or a URDF to write that cannot be, before any work."""
        check_links(self.args, model)
        self.urdf_source = urdf_to_write(self.args, model)

    def fit(self, model: Model, s: Dict, res: Residual, stages: Stages) -> Fitted:
        """Fit what is asked to the bag ``s`` (with ``--also``'s); read ``--validate`` first."""
        args = self.args
        # what the fits see: this bag and the --also ones, each cleaned and differentiated
        train = {k: s[k] for k in ('q', 'qd', 'qdd', 'effort')}
        if args.also:
            more = [recording(args, bag, model, stages) for bag in args.also]
            train = {k: np.concatenate([train[k]] + [m[k] for m in more]) for k in train}
            train['base'] = base_topics.joined([s['base']] + [m['base'] for m in more])
            print(f'fitted on {args.bag!r} and {len(more)} more bag(s): {len(train["q"])} '
                  'samples')
        else:
            train['base'] = s['base']
        # read before the fits: a held-out bag that cannot be used is said before them
        self.held_out = (recording(args, args.validate, model, stages) if args.validate
                         else None)
        self.train = train
        return fits(args, model, train, res, stages)

    def report(self, model: Model, fitted: Fitted, stages: Stages) -> List[str]:
        """Print the fits and their check; return the names of the files written."""
        print_fits(self.args, model, fitted)
        written = corrected(self.args, model, fitted.correction, self.train, stages,
                            self.held_out, self.urdf_source)
        if fitted.warning:
            print(fitted.warning, file=sys.stderr)
        return written


def fits(args, model: Model, train: Dict, res: Residual, stages: Stages) -> Fitted:
    """Fit what ``replay identify`` asks to ``train`` (the bag, with ``--also``'s).

    The drives alone (:func:`spatial_dynamics.drives.identify`, the default), or
    ``--payload`` or ``--inertias`` (with ``--drives``, jointly with each joint's damping,
    friction and armature). ``res`` is the bag's residual (the drives' fit without ``--also``).
    """
    fq, fqd, fqdd, feffort, base = (train[k] for k in ('q', 'qd', 'qdd', 'effort', 'base'))
    names = model.joint_names
    with_drives = args.drives or (args.payload is None and args.inertias is None)
    threshold = args.threshold if with_drives else None
    fit = payload = found = None
    correction, excitation_warning = None, ''
    # the fits work on matrices of a hundred columns, or share their chunks among the
    # command's own threads: BLAS threads beside those only oversubscribe the cores
    # (threadpoolctl is optional, the replay extra: imported here, the command starts without)
    from threadpoolctl import threadpool_limits
    with threadpool_limits(limits=1, user_api='blas'):
        if args.payload is None and args.inertias is None:
            fresidual = res.residual if not args.also else feffort - rnea(
                model, fq, fqd, fqdd, args.gravity, base=base)
            fit = drives.identify(fresidual, fqd, fqdd, args.threshold, names)
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
            print(f'note: {args.urdf!r} is a xacro file: {args.write_urdf!r} is its expansion '
                  'with the identified elements replaced')
        for note in correction.write_urdf(urdf_source, args.write_urdf):
            print(f'note: {note}')
        print(f'\ncorrected URDF: {args.write_urdf!r} (only the identified <inertial> and '
              '<dynamics> elements differ from ' + repr(os.path.basename(args.urdf)) + ')')
        if correction.drives is not None:
            print('  with the node: friction_model: urdf, friction_velocity_threshold: '
                  f'{args.threshold:g} and the armature above')
    return written


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


def command(sub) -> None:
    """``replay identify BAG``: the drives, a payload or the inertias fitted to a bag."""
    p = add_command(sub, 'identify', run, [recording_parser()],
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
