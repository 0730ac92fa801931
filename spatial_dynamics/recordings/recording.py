# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A recording made ready for the model: read, cleaned, sorted, differentiated.

:func:`recording` is what every use of a bag starts with (the comparison, the fits, the
held-out check): the messages of the topic by joint name, samples that cannot be used
dropped with the reason (:func:`clean`), q̇ smoothed and q̈ derived with a zero-phase
Savitzky-Golay filter per stretch between gaps (:func:`rates`), the effort as the model's
torque is compared with (``--measured-effort``). How it is read is a :class:`Reading`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
import sys
import time
from typing import Dict, Sequence, Tuple

import numpy as np

from .. import effort as effort_model
from ..bounds import JOINT_BOUNDS, MIN_STAMP_INTERVAL
from ..model import Model
from ..text import listed, shown
from . import bags, base_topics, differentiate
from .base_topics import BaseTopic
from .errors import Refused

#: Fewest samples a recording may have (the differentiation needs a few around each one).
MIN_SAMPLES = 5


@dataclass(frozen=True)
class Reading:
    """How a recording is read for the model (the replay commands' and the manifest's options).

    ``topic``: the ``sensor_msgs/JointState`` topic; ``window`` (s) and ``order``: the
    Savitzky-Golay filter; ``measured_effort``: what the bag's effort is
    (:data:`spatial_dynamics.effort.MEASURED_EFFORT`); ``gravity`` (m/s², base frame);
    ``base``: a moving base's topic; ``generic``: every message through ``rosbags``.
    """

    topic: str = '/joint_states'
    window: float = 0.05
    order: int = 3
    measured_effort: str = 'full'
    gravity: Sequence[float] = (0.0, 0.0, -9.81)
    base: BaseTopic = field(default_factory=BaseTopic)
    generic: bool = False


class Progress:
    """A one-line progress bar on stderr, drawn only when stderr is a terminal."""

    def __init__(self, label: str, stream=None) -> None:
        """Draw on ``stream`` (stderr) if it is a terminal."""
        self.label = label
        self.stream = stream or sys.stderr
        self.on = self.stream.isatty()
        self.last = 0.0

    def __call__(self, done: int, total: int) -> None:
        """Redraw at most 10 times a second."""
        now = time.monotonic()
        if not self.on or (now - self.last < 0.1 and done < total):
            return
        self.last = now
        frac = min(1.0, done / total) if total else 1.0
        bar = '#' * int(30 * frac)
        self.stream.write(f'\r{self.label} [{bar:<30}] {done}/{total}')
        self.stream.flush()

    def close(self) -> None:
        """End the line."""
        if self.on:
            self.stream.write('\n')


class Stages:
    """Wall-clock and CPU time of each stage of the command (``--timings``).

    The CPU time is this process's, all its threads together (not a plotting child's): on a
    shared machine it says what a stage costs when the wall-clock time is other work's.
    """

    def __init__(self) -> None:
        """Start the clocks."""
        self.times: Dict[str, Tuple[float, float]] = {}
        self.start = (time.perf_counter(), time.process_time())

    def done(self, stage: str) -> None:
        """Record the times since the previous stage ended."""
        now = (time.perf_counter(), time.process_time())
        wall, cpu = self.times.get(stage, (0.0, 0.0))
        self.times[stage] = (wall + now[0] - self.start[0], cpu + now[1] - self.start[1])
        self.start = now

    def text(self) -> str:
        """Return the stages and their sums, one per line: wall-clock s, CPU s."""
        total = [sum(v[k] for v in self.times.values()) for k in (0, 1)]
        return '\n'.join(f'  {k:<16} {w:8.3f} s  (cpu {c:6.3f} s)'
                         for k, (w, c) in list(self.times.items()) + [('total', total)])


def clean(js: bags.JointStates, window: float) -> Dict:
    """Drop what cannot be used, sort by stamp, cut at gaps; return arrays and the reasons.

    Returns ``{t, q, qd (or None), effort, skipped: {reason: count}, segments}``.
    ``Refused`` when a joint is never present, the bag has no effort, or nothing is left.
    """
    skipped = dict(js.skipped)
    names = js.names
    if len(js.stamp) == 0:
        raise Refused('no JointState messages could be read' + (
            f' ({"; ".join(f"{v} {k}" for k, v in skipped.items())})' if skipped else ''))
    have_q = np.isfinite(js.position)
    never = [n for n, seen in zip(names, have_q.any(axis=0)) if not seen]
    if never:
        raise Refused(f'joint(s) {listed(never)} never have a position in the topic; keep '
                      'only the recorded joints with --joints (the others are locked)')
    if not np.isfinite(js.effort).any():
        raise Refused('the topic has no measured effort: JointState.effort is empty or NaN in '
                      'every message')
    has_velocity = bool(np.isfinite(js.velocity).any())
    fields = [('position', js.position), ('effort', js.effort)]
    if has_velocity:
        fields.insert(1, ('velocity', js.velocity))
    keep = np.ones(len(js.stamp), dtype=bool)
    for what, a in fields:
        bound, unit = JOINT_BOUNDS[what]
        # all within ±bound (so finite): the usual case, found without a float temporary
        if ((a >= -bound) & (a <= bound)).all():
            continue
        bad = ~np.isfinite(a)
        with np.errstate(invalid='ignore'):
            huge = np.abs(a) > bound
        for j, name in enumerate(names):
            for rows, reason in (
                    (bad[:, j] & keep,
                     f'{shown(name)}: no finite {what} (joint missing from the message, or NaN)'),
                    (huge[:, j] & keep, f'{shown(name)}: {what} beyond ±{bound:g} {unit}')):
                if rows.any():
                    skipped[reason] = skipped.get(reason, 0) + int(rows.sum())
                    keep &= ~rows
    everything = bool(keep.all())
    t = js.stamp if everything else js.stamp[keep]
    backwards = int(np.sum(np.diff(t) < 0))
    idx = None if everything else np.flatnonzero(keep)
    if backwards:
        order = np.argsort(t, kind='stable')
        t = t[order]
        idx = order if idx is None else idx[order]
    repeated = np.concatenate(([False], np.diff(t) <= 0))
    if repeated.any():
        skipped['repeated stamp (first kept)'] = int(repeated.sum())
        t = t[~repeated]
        idx = np.flatnonzero(~repeated) if idx is None else idx[~repeated]
    if len(t) < MIN_SAMPLES:
        messages = len(js.stamp) + sum(js.skipped.values())
        raise Refused(f'only {len(t)} usable sample{"" if len(t) == 1 else "s"} of {messages} '
                      f'message{"" if messages == 1 else "s"} on the topic (at least '
                      f'{MIN_SAMPLES} are needed to differentiate)' + (': ' + '; '.join(
                          f'{v} skipped, {k}' for k, v in skipped.items()) if skipped else ''))
    seg = differentiate.segments(t, window)
    if seg.period < MIN_STAMP_INTERVAL:
        raise Refused(f'the joint states are stamped {seg.period:.3g} s apart (median), less '
                      f'than {MIN_STAMP_INTERVAL:g} s: no sensor publishes that fast, and '
                      'differentiating over such stamps gives rates no joint reaches (a clock '
                      'artefact: check header.stamp of the driver)')
    if seg.dropped:
        skipped['in a stretch between gaps shorter than the window'] = seg.dropped
    if not seg.spans:
        raise Refused('no stretch of samples without gaps is as long as the window '
                      f'({window} s); lower --window')
    inside = np.zeros(len(t), dtype=bool)
    for a, b in seg.spans:
        inside[a:b] = True
    # Renumber the spans onto the samples kept.
    starts = np.cumsum(np.concatenate(([0], inside[:-1])))
    spans = [(int(starts[a]), int(starts[a]) + (b - a)) for a, b in seg.spans]
    if inside.all():
        rows = idx if idx is not None else slice(None)     # a slice: no copies
    else:
        rows = (idx if idx is not None else np.arange(len(t)))[inside]
        t = t[inside]
    return {'t': t, 'q': js.position[rows], 'qd': js.velocity[rows] if has_velocity
            else None, 'effort': js.effort[rows], 'skipped': skipped, 'spans': spans,
            'period': seg.period, 'out_of_order': backwards}


def rates(s: Dict, window: float, order: int):
    """Return ``(q̇, q̈, resampled)`` of cleaned samples ``s`` (:func:`clean`), per stretch.

    From the measured velocity when the bag has it, smoothed by the same zero-phase filter
    (without it the velocity noise stays in the residual: test_replay, 0.08 instead of
    0.05 N m), else from the positions.
    """
    if s['qd'] is not None:
        (qd, qdd), resampled = differentiate.derivatives(s['t'], s['qd'], window, order,
                                                         (0, 1), s['spans'])
    else:
        (qd, qdd), resampled = differentiate.derivatives(s['t'], s['q'], window, order,
                                                         (1, 2), s['spans'])
    for what, x in (('velocity', qd), ('acceleration', qdd)):
        bound, unit = JOINT_BOUNDS[what]
        with np.errstate(invalid='ignore'):
            huge = np.abs(x) > bound           # nan (outside the spans) is not compared
        if huge.any():
            k, j = np.argwhere(huge)[0]
            raise Refused(f'the differentiated {what} of joint {j} at {s["t"][k] - s["t"][0]:.6f} '
                          f's is {x[k, j]:.3g}, beyond ±{bound:g} {unit}: the stamps are closer '
                          'than the motion (a clock artefact), or the positions jump')
    return qd, qdd, resampled


def recording(reading: Reading, bag: str, model: Model, stages: Stages) -> Dict:
    """Read, clean and differentiate ``bag``: ``{t, q, qd, qdd, effort, ...}`` for the model.

    ``effort`` is what the model's torque is compared with (``reading.measured_effort``);
    ``base`` the base's motion at each sample (``reading.base``,
    :func:`.base_topics.base_motion`) or None; the rest of the keys are :func:`clean`'s and
    ``js`` (the messages read), ``source`` and ``resampled`` (how q̈ was found).
    """
    bar = Progress('reading')
    try:
        js = bags.read_joint_states(bag, reading.topic, model.joint_names,
                                    fast=not reading.generic, progress=bar)
        stages.done('read+decode')
        s = clean(js, reading.window)
    except (Refused, bags.BagError) as err:     # with --also and --validate: which bag
        text = str(err)
        raise Refused(text if bag in text else f'bag {bag!r}: {text}') from None
    finally:
        bar.close()
    t, q, spans = s['t'], s['q'], s['spans']
    stages.done('clean+sort')
    qd, qdd, resampled = rates(s, reading.window, reading.order)
    source = 'velocity' if s['qd'] is not None else 'position (the bag has no velocities)'
    stages.done('differentiate')
    try:
        base = base_topics.base_motion(reading.base, bag, model, t, spans, reading.window,
                                       reading.order)
    except Refused as err:
        raise Refused(f'bag {bag!r}: {err}') from None
    if base is not None:
        stages.done('base')
    effort = effort_model.with_gravity(model, q, s['effort'], reading.measured_effort,
                                       reading.gravity)
    return dict(s, qd=qd, qdd=qdd, effort=effort, js=js, source=source, resampled=resampled,
                base=base)
