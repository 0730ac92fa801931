# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A long bag as several tasks: cut by bag time, each chunk's sums added back.

:func:`split` cuts a bag whose topic spans more than ``chunk`` seconds of bag time into
chunks ``[b_k, b_k+1)`` of ``chunk`` seconds (the first open at the start, the last at the
end); each chunk reads its range and a margin each side (:mod:`.task`), so each sample is
differentiated, in exactly one chunk, with the neighbours it has in the whole bag. A task
then holds at most ``chunk`` plus the margins of messages, whatever the bag's length.
:func:`merge` adds the chunks' sums in bag-time order back into the bag's result: the fit
of the chunked bag is the fit of the whole bag to rounding.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from ..recordings import bags
from .sums import Sums, total
from .task import Task

#: The default chunk length, s (10 minutes: 600 000 messages at 1 kHz).
CHUNK = 600.0
#: The shortest chunk, s: ten times the margin each chunk reads on each side.
MIN_CHUNK = 10.0


def split(tasks: Sequence[Task], chunk: float,
          ranges: Optional[Dict[Tuple[str, str], Tuple[int, int]]] = None
          ) -> Tuple[List[Task], List[int]]:
    """Return the tasks to run and, for each, the index of the bag task it belongs to.

    ``chunk`` s: a bag spanning more is cut; ``0`` never cuts. A bag whose time range cannot
    be read stays whole (its task then says what is wrong with it). ``ranges``: (bag, topic)
    -> its first and last bag time (ns), known already (a bag in it is not opened); the
    ranges read are added to it.
    """
    ranges = {} if ranges is None else ranges
    parts: List[Task] = []
    owner: List[int] = []
    step = int(round(chunk * 1e9))
    for i, task in enumerate(tasks):
        cuts: List[int] = []
        if step > 0:
            try:
                first, last = _time_range(task, ranges)
                cuts = list(range(first + step, last + 1, step))
            except (bags.BagError, bags.MissingDependency, ValueError, OSError):
                cuts = []
        if not cuts:
            parts.append(task)
            owner.append(i)
            continue
        for start, stop in zip([None] + cuts, cuts + [None]):
            parts.append(replace(task, start=start, stop=stop))
            owner.append(i)
    return parts, owner


def _time_range(task: Task, ranges: Dict[Tuple[str, str], Tuple[int, int]]
                ) -> Tuple[int, int]:
    """Return the task's bag time range from ``ranges``, or read it and add it there."""
    key = (task.bag, task.option('topic'))
    if key not in ranges:
        ranges[key] = bags.time_range(*key)
    return ranges[key]


def merge(tasks: Sequence[Task], owner: Sequence[int], results: Sequence[Dict]
          ) -> List[Dict]:
    """Return one result per bag task: a whole bag's as it is, a chunked bag's chunks summed.

    A chunk that failed fails its bag (the reason names the chunk's bag-time range); a bag
    none of whose chunks has a usable sample fails with the first chunk's reason.
    """
    mine: Dict[int, List[Dict]] = {}
    for i, r in zip(owner, results):
        mine.setdefault(i, []).append(r)
    out = []
    for i, task in enumerate(tasks):
        rs = mine[i]
        if len(rs) == 1 and 'chunk' not in rs[0]:
            out.append(rs[0])
            continue
        out.append(_merged(task, rs))
    return out


def _merged(task: Task, rs: List[Dict]) -> Dict:
    head = {'robot': task.robot, 'bag': task.bag}
    for r in rs:
        if not r.get('ok'):
            return dict(head, ok=False, reason=f'chunk {_range(r["chunk"])}: {r["reason"]}')
    used = [r for r in rs if r['samples']]
    if not used:
        return dict(head, ok=False, reason=rs[0].get('empty', 'no usable sample'))
    sums = total(Sums.from_dict(r['sums']) for r in used)
    skipped: Dict[str, int] = {}
    for r in used:
        for k, v in r.get('skipped', {}).items():
            skipped[k] = skipped.get(k, 0) + v
    start, end = min(r['start'] for r in used), max(r['end'] for r in used)
    return dict(head, ok=True, start=start, end=end, seconds=end - start,
                recorded=min(r['recorded'] for r in used), samples=sums.N,
                joints=used[0]['joints'], sums=sums.to_dict(),
                rms_residual=np.sqrt(sums.rr / sums.N).tolist(), skipped=skipped,
                chunks=len(rs), messages=max(r['messages'] for r in rs),
                peak_rss_mb=max(r['peak_rss_mb'] for r in rs),
                cached=all(r.get('cached') for r in rs))


def _range(chunk: Sequence) -> str:
    """``[start, stop)`` of a chunk as bag times in s (``...`` for an open end)."""
    a, b = (('...' if x is None else f'{x * 1e-9:.3f}') for x in chunk)
    return f'[{a}, {b}) s'
