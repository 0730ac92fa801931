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

Every (robot, joint, parameter) series is judged or listed as not judged with the reason
(too few bags in the baseline or after it, no estimate: the joint did not move enough), and
so is every robot none of whose bags could be used. A bag listed twice (overlapping globs,
the same storage file by two paths) is counted once, said in a ``note:`` line (one per
kind, with the count); a bag that cannot be used is one ``failed:`` line naming its
manifest row.

Exit status: 0 done, every series judged, nothing drifted; 3 done, something drifted
(drift.txt names it); 4 done, nothing drifted among the series judged but some (or all)
could not be judged, or a robot had no usable bag (drift.txt says which and why); 1 refused
(no usable manifest, no bag usable); 2 bad usage; 130 interrupted (Ctrl-C), 143 terminated
(SIGTERM): each file is whole or as it was, no temporary left. A failed bag alone does not
change the status: the robot's other bags are judged; a robot left with none is not judged
(4).
"""

from __future__ import annotations

import argparse
import csv
from datetime import datetime, timezone
import hashlib
import io
import json
import os
import shutil
import signal
import sys
import tempfile
import threading
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from ..drives import PARAMETERS
from ..files import check_output, check_outside_recordings, read_regular, write_atomic
from ..recordings.errors import one_line
from ..text import shown
from . import drift as drift_of
from .arguments import add_arguments
from .chunks import merge, split
from .drift import count
from .engine import (bag_bytes, Cache, cluster_size, local_cluster, pending_bags, Progress,
                     run_tasks, SERIAL_BYTES, warm)
from .manifest import ManifestError, once, read_manifest, scan_folder
from .sums import Sums, solve, total
from .task import Task

# matplotlib (the plots) and distributed (a cluster) are imported where they are used: start-up
# time, and optional (the fleet extra): the command starts and says what to install without them

#: Exit status when something drifted.
DRIFTED = 3
#: Exit status when nothing drifted among the series judged, but not every one was judged.
NOT_JUDGED = 4
#: The command in one sentence (its --help's first line, as ``fleet`` and as ``replay fleet``).
SUMMARY = __doc__.split('\n\n')[0]
#: What each exit status says, in every --help.
EXIT_STATUS = ('Exit status: 0 every series judged, nothing drifted; 3 something drifted; '
               '4 nothing drifted but some series or robots not judged (drift.txt says why); '
               '1 refused; 2 bad usage; 130 interrupted; 143 terminated.')
COLUMNS = ['robot', 'bag', 'start', 'joint', 'parameter', 'value', 'sigma', 'rms_residual',
           'samples']


def parser() -> argparse.ArgumentParser:
    """Return the command's own parser."""
    p = argparse.ArgumentParser(prog='fleet', description=SUMMARY,
                                epilog=EXIT_STATUS)
    add_arguments(p)
    return p


def tasks_of(source: str, urdf: Optional[str]
             ) -> Tuple[List[Task], List[Tuple[str, str]], List[Dict]]:
    """Return the tasks of ``source`` (each bag once), the notes and the globs matching none.

    A note ``(kind, which)`` says which bag was left out; a glob of the manifest that
    matches no bag is a failed result naming its row (:func:`~.manifest.read_manifest`). A
    bag is the same bag when it shares a storage file with another (overlapping globs, a
    link, a directory and its own ``.db3``: :func:`~.manifest.once`): it is counted once,
    under its first row.
    """
    if os.path.isdir(source):
        tasks, unmatched = scan_folder(source, urdf), []
    else:
        tasks, unmatched = read_manifest(source)
    tasks, notes = once(tasks)
    return tasks, notes, unmatched


def per_bag_rows(results: List[Dict]) -> List[Dict]:
    """Return fleet.csv's rows: each bag's fit from its own sums.

    A bag's date (``start_s``, the trend's time axis) is when its first message was
    recorded (the storage's bag time), not its ``header.stamp``: the stamps may run on
    another clock (a simulation's, restarting at 0 in every bag).
    """
    rows = []
    for r in results:
        if not r.get('ok'):
            continue
        fit = solve(Sums.from_dict(r['sums']), r['joints'])
        for j, joint in enumerate(r['joints']):
            for k, parameter in enumerate(PARAMETERS):
                rows.append({'robot': r['robot'], 'bag': r['bag'], 'start_s': r['recorded'],
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
        rs = sorted(rs, key=lambda r: (r['recorded'], r['bag']))
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
    return datetime.fromtimestamp(t, timezone.utc).isoformat(timespec='seconds')


def plot_trends(out: str, rows: List[Dict], drifts, keys: Optional[str] = None) -> List[str]:
    """Draw trend_ROBOT.png: per joint and parameter, the values with ±σ bands.

    ``keys``: a folder keeping a hash of what each plot was drawn from; a plot whose
    inputs are the same is not drawn again.
    """
    written = []
    flagged = {(d.robot, d.joint, d.parameter) for d in drifts}
    for robot in sorted({r['robot'] for r in rows}):
        mine = [r for r in rows if r['robot'] == robot]
        name = f'trend_{robot}.png'
        key = hashlib.sha256(json.dumps(
            [mine, sorted(f for f in flagged if f[0] == robot)], sort_keys=True,
            default=str).encode()).hexdigest()
        key_path = os.path.join(keys, name + '.key') if keys else None
        try:
            if (key_path and os.path.isfile(inside(out, name))
                    and read_regular(key_path, 'plot key', 64) == key.encode()):
                written.append(name)
                continue
        except ValueError:
            pass
        _draw(out, name, robot, mine, flagged)
        if key_path:
            try:
                os.makedirs(keys, exist_ok=True)
                write_atomic(key_path, key, 'plot key')
            except (ValueError, OSError):
                pass
        written.append(name)
    return written


def _draw(out: str, name: str, robot: str, mine: List[Dict], flagged) -> None:
    """Draw one robot's trend plot into ``out``/``name``."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
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
    write_atomic(inside(out, name), lambda f: fig.savefig(f, format='png', dpi=80),
                 'trend plot')
    plt.close(fig)


def inside(out: str, name: str) -> str:
    """Return the path of output ``name`` in ``out``; refuse one that would land elsewhere."""
    path = os.path.join(out, name)
    folder = os.path.realpath(os.path.dirname(os.path.abspath(path)))
    if os.path.basename(path) != name or folder != os.path.realpath(out):
        raise ValueError(f'output {name!r} would be written outside --out {out!r}')
    return path


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the command is, to unwind as Ctrl-C does."""


def run(args) -> int:
    """Run the command on parsed ``args``; return the exit status (0, 1, 3, 4, 130 or 143).

    Ctrl-C is one line ``interrupted``, exit 130, and SIGTERM ``terminated``, 143: either
    unwinds the work (the cluster is closed, the bags' staging folders and the temporaries
    of the files being written are removed; each output is whole or as it was).
    """
    main_thread = threading.current_thread() is threading.main_thread()
    if main_thread:
        before = signal.signal(signal.SIGTERM, _terminate)
    try:
        return _run(args)
    except Terminated:
        print('terminated', file=sys.stderr)
        return 143
    except KeyboardInterrupt:
        print('interrupted', file=sys.stderr)
        return 130
    finally:
        if main_thread:
            signal.signal(signal.SIGTERM, before)


def _terminate(signum, frame) -> None:
    raise Terminated()


def _run(args) -> int:
    try:
        tasks, notes, unmatched = tasks_of(args.source, args.urdf)
        check_folders(args, tasks)
        make_folder(args.out, '--out')
        outputs = ['fleet.csv', 'robots.csv', 'drift.txt']
        if not args.no_plots:
            outputs += [f'trend_{robot}.png' for robot in sorted({t.robot for t in tasks})]
        inputs = [t.bag for t in tasks] + sorted({t.urdf for t in tasks}) + [args.source]
        for name in outputs:
            check_output(inside(args.out, name), name, inputs)
        cache = Cache(make_folder(args.cache, '--cache') if args.cache
                      else os.path.join(args.out, 'cache'))
        digests = cache.known_digests(tasks)
        ranges = cache.time_ranges(tasks, digests)     # an unchanged bag is not opened
        known = len(ranges)
        parts, owner = split(tasks, args.chunk, ranges)
        # a cluster only for work worth its start-up, unless asked for (--workers, --scheduler),
        # and never for none
        pending = pending_bags(parts, cache, digests)
        asked = args.workers is not None or args.scheduler is not None
        serial = (args.serial or not pending
                  or (not asked and bag_bytes(pending) < SERIAL_BYTES))
        if asked and not pending:
            print('note: every bag is in the cache: no cluster '
                  + ('contacted' if args.scheduler else 'started'), file=sys.stderr)
        progress = Progress(len(parts))
        try:
            if serial:
                results = run_tasks(parts, cache, None, progress, digests)
            else:
                results = _on_cluster(args, parts, cache, progress, digests)
        finally:
            progress.close()
        if len(ranges) > known:     # the bags just hashed: their ranges kept by digest
            cache.remember_ranges(ranges, cache.known_digests(tasks))
        results = merge(tasks, owner, results)
    except (ManifestError, ValueError, OSError) as err:
        print(f'error: {one_line(err)}', file=sys.stderr)
        return 1
    for task, result in zip(tasks, results):      # this run's names, whatever the cache's
        result.update(robot=task.robot, bag=task.bag, where=task.where)
    return report(args, results + unmatched, notes)


def check_folders(args, tasks: Sequence[Task]) -> None:
    """Refuse ``--out`` or ``--cache`` in a bag directory or equal to SOURCE, before any work.

    As ``replay`` refuses an output in a recording (a recording is left as it was made);
    ``ValueError`` names the option.
    """
    recordings = [(t.where or t.robot, t.bag) for t in tasks]
    for option, folder in (('--out', args.out), ('--cache', args.cache)):
        if folder is None:
            continue
        check_outside_recordings(folder, option, recordings)
        if os.path.realpath(folder) == os.path.realpath(args.source):
            raise ValueError(f'{option} {folder!r}: the fleet\'s own SOURCE; choose another '
                             'place (an input is left as it is)')


def make_folder(path: str, option: str) -> str:
    """Create the folder ``path`` of ``option`` (with its parents); return it."""
    try:
        os.makedirs(path, exist_ok=True)
    except OSError as err:
        raise ValueError(f'{option} {path!r}: cannot be created ({err.strerror})') from None
    return path


def _on_cluster(args, tasks, cache, progress, digests) -> List[Dict]:
    from distributed import Client
    if args.scheduler:
        with Client(args.scheduler, timeout=30) as client:
            warm(client)
            return run_tasks(tasks, cache, client, progress, digests)
    workers, note = cluster_size(args.workers)
    if note:
        print(note, file=sys.stderr)
    scratch = tempfile.mkdtemp(prefix='.dask-scratch-', dir=args.out)    # Dask's files
    try:
        with local_cluster(workers, scratch) as cluster, Client(cluster) as client:
            warm(client, local=True)
            return run_tasks(tasks, cache, client, progress, digests)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def verdict(judgement: drift_of.Judgement, unusable: Optional[Dict[str, int]] = None
            ) -> List[str]:
    """Return drift.txt's verdict lines: the drifts or no drift, and what was not judged.

    "no drift" only when every series was judged and every robot had a usable bag; each
    series not judged is listed with the reason (a joint's parameters with the same reason on
    one line), and each robot of ``unusable`` (robot -> its bags, all failed) as not judged.
    """
    unusable = unusable or {}
    lines = [f'drift: {d.text()}' for d in judgement.drifts]
    missing = len(judgement.not_judged)
    total_series = judgement.judged + missing
    left = ([f'{missing} of {total_series} series not judged'] if missing else []) + (
        [f'{count(len(unusable), "robot")} with no usable bag not judged'] if unusable else [])
    if not judgement.judged:
        lines.append(f'nothing judged: none of the {total_series} series (robot, joint, '
                     'parameter) could be judged' if total_series else
                     'nothing judged: no bag could be used')
    elif not lines:
        lines.append('no drift' if not left else
                     f'no drift among the {judgement.judged} series judged; ' + '; '.join(left))
    elif left:
        lines.append('; '.join(left))
    lines += [f'not judged: {robot}: ' + (f'all {n} of its bags failed' if n > 1 else
                                          'its one bag failed') + ' (see failed: below)'
              for robot, n in sorted(unusable.items())]
    grouped: Dict[Tuple[str, str, str], List[str]] = {}
    for (robot, joint, parameter), reason in judgement.not_judged.items():
        grouped.setdefault((robot, joint, reason), []).append(drift_of.LABELS[parameter])
    lines += [f'not judged: {robot} {shown(joint, quote=False)} ({", ".join(labels)}): {reason}'
              for (robot, joint, reason), labels in sorted(grouped.items())]
    return lines


#: The earliest bag time taken for a wall-clock date without a note (2000-01-01).
PLAUSIBLE = 946684800.0
#: The note of a bag whose bag time is before :data:`PLAUSIBLE`.
EARLY = ('bags recorded before 2000 (recorded on a simulated clock?), dated and ordered by '
         'that time')
#: How many examples a note of one kind shows (a manifest of 20 000 repeated rows is one line).
NOTE_EXAMPLES = 3


def noted(notes: Sequence[Tuple[str, str]]) -> List[str]:
    """Return one ``note:`` line per kind of ``notes`` ``(kind, which)``: its count, examples.

    ``note: bags listed twice, each counted once (2): A (row) is B of r01 (row); C ...``;
    kinds in the order they first appear, at most :data:`NOTE_EXAMPLES` examples each.
    """
    kinds: Dict[str, List[str]] = {}
    for kind, which in notes:
        kinds.setdefault(kind, []).append(which)
    lines = []
    for kind, which in kinds.items():
        more = len(which) - NOTE_EXAMPLES
        lines.append(f'note: {kind} ({len(which)}): ' + '; '.join(which[:NOTE_EXAMPLES])
                     + (f'; and {more} more' if more > 0 else ''))
    return lines


def report(args, results: List[Dict], notes: Sequence[Tuple[str, str]] = ()) -> int:
    """Write the files, print the verdict and the bags that failed; return the status."""
    rows = per_bag_rows(results)
    failed = [r for r in results if not r.get('ok')]
    judgement = drift_of.detect(rows, args.baseline_days)
    drifts = judgement.drifts
    write_atomic(inside(args.out, 'fleet.csv'), csv_text(COLUMNS, [
        [r['robot'], r['bag'], iso(r['start_s']), r['joint'], r['parameter'], r['value'],
         r['sigma'], r['rms_residual'], r['samples']] for r in rows]), 'fleet.csv')
    robots = per_robot(results)
    write_atomic(inside(args.out, 'robots.csv'), csv_text(
        ['robot', 'joint', 'parameter', 'value', 'sigma', 'rms_residual', 'samples'],
        [[robot, joint, p, float(getattr(fit, p)[j]), float(fit.sigma[j, k]),
          float(fit.rms_after[j]), n]
         for robot, (names, fit, n) in sorted(robots.items())
         for j, joint in enumerate(names) for k, p in enumerate(PARAMETERS)]), 'robots.csv')
    hours = sum(r['seconds'] for r in results if r.get('ok')) / 3600.0
    cached = sum(1 for r in results if r.get('cached'))
    n_robots = len({r['robot'] for r in results})
    lines = [f'{count(len(results), "bag")} of {count(n_robots, "robot")}, '
             f'{hours:.3g} h of data ({cached} from the cache, {len(failed)} failed)']
    lines += noted(list(notes) + [
        (EARLY, f'{r["robot"]} {r["bag"]!r} on {drift_of.day(r["recorded"])}') for r in results
        if r.get('ok') and r['recorded'] < PLAUSIBLE])
    usable = {r['robot'] for r in results if r.get('ok')}
    unusable: Dict[str, int] = {}
    for r in failed:
        if r['robot'] not in usable:
            unusable[r['robot']] = unusable.get(r['robot'], 0) + 1
    lines += verdict(judgement, unusable)
    lines += [f'failed: {r["robot"]} {r["bag"]!r}'
              + (f' ({r["where"]})' if r.get('where') else '') + f': {r["reason"]}'
              for r in failed]
    text = '\n'.join(lines) + '\n'
    write_atomic(inside(args.out, 'drift.txt'), text, 'drift.txt')
    written = ['fleet.csv', 'robots.csv', 'drift.txt']
    if not args.no_plots and rows:
        written += plot_trends(args.out, rows, drifts,
                               os.path.join(args.cache or os.path.join(args.out, 'cache'),
                                            'plots'))
    status = DRIFTED if drifts else NOT_JUDGED if judgement.not_judged or unusable else 0
    if not rows:
        status = 1
    say(text + f'written to {args.out!r}: {", ".join(written)}')
    if not rows:
        print('error: no bag could be used (see failed above)', file=sys.stderr)
    return status


def say(text: str) -> None:
    """Print ``text``; a reader that has gone (``| head -1``) ends the output quietly."""
    try:
        print(text, flush=True)
    except BrokenPipeError:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())     # nothing more to flush at exit either
        os.close(devnull)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Parse ``argv`` and run; return the exit status."""
    return run(parser().parse_args(argv))
