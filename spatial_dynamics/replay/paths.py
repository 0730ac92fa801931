# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Before any work: every input there, every output writable and none an input.

What ``residual``, ``identify`` and ``trajectory`` check before they read a bag: each bag
opens and is given once, ``--out`` is a directory, and no output is an input, in a bag
directory, one another, a directory, a named pipe or a device.
"""

from __future__ import annotations

import importlib.util
import os
from typing import List, Tuple

from ..files import check_output, check_outside_recordings
from ..recordings import bags
from ..recordings.errors import Refused
from . import report


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
                raise Refused(f'{option} {path!r}: the same recording as {before} {other!r} ('
                              + ('a held-out check needs another recording)'
                                 if option == '--validate' else 'fitted once is enough)'))
    names = output_files(args)
    write_urdf = vars(args).get('write_urdf')
    outputs = [('--out', args.out)] + [('output', os.path.join(args.out, n)) for n in names]
    if write_urdf:
        outputs.append(('--write-urdf', write_urdf))
        for _, path in outputs[1:-1]:
            if os.path.abspath(path) == os.path.abspath(write_urdf):
                raise Refused(f'--write-urdf {write_urdf!r}: the command writes '
                              f'{os.path.basename(path)} there (--out {args.out!r})')
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


def output_dir(path: str) -> None:
    """Create the output directory ``path``; Refused naming it when it cannot be one."""
    try:
        report.ensure_dir(path)
    except OSError as err:
        raise Refused(f'--out {path!r}: cannot be the output directory ({err.strerror})') from None
    if not os.access(path, os.W_OK | os.X_OK):
        raise Refused(f'--out {path!r}: cannot write in this directory')


def check_matplotlib(args) -> None:
    """Refuse plots without matplotlib, before any work."""
    if not args.no_plots and importlib.util.find_spec('matplotlib') is None:
        raise Refused('the plots need matplotlib (pip install matplotlib, or apt install '
                      'python3-matplotlib); or --no-plots')
