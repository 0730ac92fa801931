# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A fleet's recordings: every bag's drive fit on a Dask cluster, the trends, the drifts.

    python -m spatial_dynamics.fleet SOURCE [--urdf URDF] [--out DIR] [--cache DIR]
                                     [--workers N | --serial | --scheduler tcp://host:8786]
                                     [--chunk 600] [--baseline-days 5] [--no-plots]

SOURCE is a manifest (``.csv``, ``.yaml``) or a folder ``ROBOT/…/BAG``
(:mod:`spatial_dynamics.fleet.manifest`). Each bag, or each ``--chunk`` seconds of a longer
bag (:mod:`.chunks`), is one task (:func:`.task.process`): read, cleaned and differentiated
as ``replay`` does, the rigid-body residual, and the normal
equations of each joint's damping, Coulomb friction and armature (:mod:`.sums`), which add:
a robot's fit over all its bags is their sum. Written to DIR: fleet.csv (robot, bag, start,
joint, parameter, value, σ, residual RMS, samples: one row per bag, joint and parameter),
robots.csv (each robot's fit over all its bags), drift.txt, trend_ROBOT.png. Results are
cached by the content of the bag, the URDF and the options: a re-run does only new or
changed bags.

Exit status: 0 done, nothing drifted; 3 done, something drifted (drift.txt names it); 1
refused (no usable manifest, no bag usable); 2 bad usage.
"""

from __future__ import annotations

import argparse
import csv
import io
import os
import sys
from typing import Dict, List, Optional, Sequence

import numpy as np

from ..files import check_output, write_atomic
from ..replay.arguments import one_line
from . import drift as drift_of
from .chunks import CHUNK, merge, MIN_CHUNK, split
from .engine import Cache, local_cluster, Progress, run_tasks, warm
from .manifest import ManifestError, read_manifest, scan_folder
from .sums import Sums, solve, total
from ..replay.identify import PARAMETERS

#: Exit status when something drifted.
DRIFTED = 3
COLUMNS = ['robot', 'bag', 'start', 'joint', 'parameter', 'value', 'sigma', 'rms_residual',
           'samples']


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Declare the command's options on ``p`` (its own parser, or a ``replay`` subparser)."""
    p.add_argument('source', help='manifest (.csv, .yaml) or a folder ROBOT/.../BAG')
    p.add_argument('--urdf', help='the URDF of every robot of a folder (default: each robot '
                   "folder's robot.urdf)")
    p.add_argument('--out', default='fleet_out',
                   help='output directory, created (default %(default)s)')
    p.add_argument('--cache', help='results by content hash (default: OUT/cache)')
    where = p.add_mutually_exclusive_group()
    where.add_argument('--workers', type=int, metavar='N',
                       help='local cluster of N worker processes (default: the cores)')
    where.add_argument('--serial', action='store_true',
                       help='no cluster: every bag in this process, one after the other')
    where.add_argument('--scheduler', metavar='ADDRESS',
                       help='an existing Dask scheduler, e.g. tcp://host:8786')
    p.add_argument('--chunk', type=chunk_seconds, default=CHUNK, metavar='SECONDS',
                   help='cut a bag longer than this into tasks of this much bag time, their '
                   'sums added (default %(default)g; 0: one task per bag)')
    p.add_argument('--baseline-days', type=float, default=5.0,
                   help="each robot-joint's baseline: its first days (default %(default)g)")
    p.add_argument('--no-plots', action='store_true', help='write no PNG files')


def chunk_seconds(text: str) -> float:
    """``--chunk``: 0 (one task per bag) or a finite number of seconds >= MIN_CHUNK."""
    try:
        value = float(text)
    except ValueError:
        value = float('nan')
    if not (value == 0 or MIN_CHUNK <= value < float('inf')):
        raise argparse.ArgumentTypeError(
            f'{text!r}: 0 (one task per bag) or a number of seconds >= {MIN_CHUNK:g}')
    return value


def parser() -> argparse.ArgumentParser:
    """Return the command's own parser."""
    p = argparse.ArgumentParser(prog='fleet', description=__doc__.split('\n\n')[0],
                                epilog='Exit status: 0 nothing drifted, 3 something drifted, '
                                '1 refused, 2 bad usage.')
    add_arguments(p)
    return p


def tasks_of(args) -> list:
    """Return the tasks of ``args.source``."""
    if os.path.isdir(args.source):
        return scan_folder(args.source, args.urdf)
    return read_manifest(args.source)


def per_bag_rows(results: List[Dict]) -> List[Dict]:
    """Return fleet.csv's rows: each bag's fit from its own sums."""
    rows = []
    for r in results:
        if not r.get('ok'):
            continue
        fit = solve(Sums.from_dict(r['sums']), r['joints'])
        for j, joint in enumerate(r['joints']):
            for k, parameter in enumerate(PARAMETERS):
                rows.append({'robot': r['robot'], 'bag': r['bag'], 'start_s': r['start'],
                             'joint': joint, 'parameter': parameter,
                             'value': float(getattr(fit, parameter)[j]),
                             'sigma': float(fit.sigma[j, k]),
                             'rms_residual': float(fit.rms_after[j]),
                             'samples': r['samples']})
    return rows


def per_robot(results: List[Dict]) -> Dict[str, object]:
    """Return each robot's fit over all its bags (the sum of their sums, in bag order)."""
    by_robot: Dict[str, List[Dict]] = {}
    for r in results:
        if r.get('ok'):
            by_robot.setdefault(r['robot'], []).append(r)
    out = {}
    for robot, rs in by_robot.items():
        rs = sorted(rs, key=lambda r: (r['start'], r['bag']))
        names = rs[0]['joints']
        same = [r for r in rs if r['joints'] == names]
        out[robot] = (names, solve(total(Sums.from_dict(r['sums']) for r in same), names),
                      sum(r['samples'] for r in same))
    return out


def csv_text(header: Sequence[str], rows: List[Sequence]) -> str:
    """Return rows as CSV text (floats by repr: they read back exactly)."""
    f = io.StringIO()
    w = csv.writer(f, lineterminator='\n')
    w.writerow(header)
    w.writerows(rows)
    return f.getvalue()


def iso(t: float) -> str:
    """Return ``t`` (s since the epoch) as ISO 8601 UTC."""
    from datetime import datetime, timezone
    return datetime.fromtimestamp(t, timezone.utc).isoformat(timespec='seconds')


def plot_trends(out: str, rows: List[Dict], drifts) -> List[str]:
    """Draw trend_ROBOT.png: per joint and parameter, the values with ±σ bands."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    from datetime import datetime, timezone
    written = []
    flagged = {(d.robot, d.joint, d.parameter) for d in drifts}
    for robot in sorted({r['robot'] for r in rows}):
        mine = [r for r in rows if r['robot'] == robot]
        joints = list(dict.fromkeys(r['joint'] for r in mine))
        fig, axes = plt.subplots(len(joints), 3, figsize=(12, 1.8 * len(joints) + 1),
                                 sharex=True, squeeze=False)
        for a, joint in enumerate(joints):
            for b, parameter in enumerate(PARAMETERS):
                rs = sorted((r for r in mine if r['joint'] == joint
                             and r['parameter'] == parameter), key=lambda r: r['start_s'])
                t = [datetime.fromtimestamp(r['start_s'], timezone.utc) for r in rs]
                x = np.array([r['value'] for r in rs])
                s = np.array([r['sigma'] for r in rs])
                ax = axes[a, b]
                color = 'tab:red' if (robot, joint, parameter) in flagged else 'tab:blue'
                ax.fill_between(t, x - s, x + s, color=color, alpha=0.3, lw=0)
                ax.plot(t, x, '.-', color=color, lw=0.8)
                if a == 0:
                    ax.set_title(drift_of.LABELS[parameter])
                if b == 0:
                    ax.set_ylabel(joint, fontsize=8)
        fig.suptitle(f'{robot}: drive parameters per bag (band: ±σ; red: drifted)')
        fig.autofmt_xdate()
        name = f'trend_{robot}.png'
        write_atomic(os.path.join(out, name), lambda f: fig.savefig(f, format='png', dpi=80),
                     'trend plot')
        plt.close(fig)
        written.append(name)
    return written


def run(args) -> int:
    """Run the command on parsed ``args``; return the exit status (0, 1 or 3)."""
    try:
        tasks = tasks_of(args)
        os.makedirs(args.out, exist_ok=True)
        outputs = ['fleet.csv', 'robots.csv', 'drift.txt']
        inputs = [t.bag for t in tasks] + sorted({t.urdf for t in tasks}) + [args.source]
        for name in outputs:
            check_output(os.path.join(args.out, name), name, inputs)
        cache = Cache(args.cache or os.path.join(args.out, 'cache'))
        parts, owner = split(tasks, args.chunk)
        progress = Progress(len(parts))
        try:
            if args.serial:
                results = run_tasks(parts, cache, None, progress)
            else:
                results = _on_cluster(args, parts, cache, progress)
        finally:
            progress.close()
        results = merge(tasks, owner, results)
    except (ManifestError, ValueError, OSError) as err:
        print(f'error: {one_line(err)}', file=sys.stderr)
        return 1
    return report(args, results)


def _on_cluster(args, tasks, cache, progress) -> List[Dict]:
    from distributed import Client
    if args.scheduler:
        with Client(args.scheduler, timeout=30) as client:
            warm(client)
            return run_tasks(tasks, cache, client, progress)
    with local_cluster(args.workers) as cluster, Client(cluster) as client:
        warm(client)
        return run_tasks(tasks, cache, client, progress)


def report(args, results: List[Dict]) -> int:
    """Write the files, print the drift report and the bags that failed; return the status."""
    rows = per_bag_rows(results)
    failed = [r for r in results if not r.get('ok')]
    drifts = drift_of.detect(rows, args.baseline_days)
    write_atomic(os.path.join(args.out, 'fleet.csv'), csv_text(COLUMNS, [
        [r['robot'], r['bag'], iso(r['start_s']), r['joint'], r['parameter'], r['value'],
         r['sigma'], r['rms_residual'], r['samples']] for r in rows]), 'fleet.csv')
    robots = per_robot(results)
    write_atomic(os.path.join(args.out, 'robots.csv'), csv_text(
        ['robot', 'joint', 'parameter', 'value', 'sigma', 'rms_residual', 'samples'],
        [[robot, joint, p, float(getattr(fit, p)[j]), float(fit.sigma[j, k]),
          float(fit.rms_after[j]), n]
         for robot, (names, fit, n) in sorted(robots.items())
         for j, joint in enumerate(names) for k, p in enumerate(PARAMETERS)]), 'robots.csv')
    hours = sum(r['seconds'] for r in results if r.get('ok')) / 3600.0
    cached = sum(1 for r in results if r.get('cached'))
    lines = [f'{len(results)} bags of {len({r["robot"] for r in results})} robots, '
             f'{hours:.3g} h of data ({cached} from the cache, {len(failed)} failed)']
    lines += [f'drift: {d.text()}' for d in drifts] or ['no drift']
    lines += [f'failed: {r["robot"]} {r["bag"]}: {r["reason"]}' for r in failed]
    text = '\n'.join(lines) + '\n'
    write_atomic(os.path.join(args.out, 'drift.txt'), text, 'drift.txt')
    written = ['fleet.csv', 'robots.csv', 'drift.txt']
    if not args.no_plots and rows:
        written += plot_trends(args.out, rows, drifts)
    print(text + f'written to {args.out}: {", ".join(written)}')
    if not rows:
        print('error: no bag could be used (see failed above)', file=sys.stderr)
        return 1
    return DRIFTED if drifts else 0


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Parse ``argv`` and run; return the exit status."""
    p = parser()
    args = p.parse_args(argv)
    if args.workers is not None and args.workers < 1:
        p.error('--workers: at least 1')
    if not args.baseline_days > 0:
        p.error('--baseline-days: a number > 0')
    return run(args)
