# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The latency benchmark's report: the table, the lines under it, ``--json`` and ``--plot``.

From each :class:`~.latency_targets.Target`'s summary: the table of round trips and of the
way to the answer (:func:`format_table`), the inputs not answered, node minus relay, the rate
sent and its warning (:data:`RATE_SHORTFALL`), the machine's floor (:func:`wake_ups`, how
late the pacer woke, :func:`machine_line`); the JSON, NaN as null (:func:`json_safe`,
:func:`write_json`), and the histograms (:func:`plot`, matplotlib).
"""

from __future__ import annotations

import json
import math
import os
import textwrap
from typing import Dict, List, Optional, Sequence

import numpy as np

from spatial_dynamics.files import output_path, write_atomic

from .driving import pyplot, save_figure
from .latency_pacer import LATE_LIMIT_S
from .latency_targets import plural, quantile, QUANTILES, Target

#: Inputs sent this fraction or more below the rate asked are a warning: the rate was not met.
RATE_SHORTFALL = 0.03


def json_safe(rows: List[Dict[str, float]]) -> List[Dict[str, object]]:
    """Return ``rows`` with NaN and ±inf as None (null), in nested dicts and lists too.

    JSON has neither, and strict readers refuse them (``json.dumps(allow_nan=False)``).
    """
    def safe(value):
        if isinstance(value, float):
            return value if math.isfinite(value) else None
        if isinstance(value, dict):
            return {key: safe(v) for key, v in value.items()}
        if isinstance(value, (list, tuple)):
            return [safe(v) for v in value]
        return value
    return [safe(row) for row in rows]


def cell(value: Optional[float], digits: int = 3) -> str:
    """Return the text of a cell of the table (milliseconds: 3 digits); ``-`` if not reported.

    Not reported: None or NaN.
    """
    return '-' if value is None or math.isnan(value) else f'{value:.{digits}f}'


def format_table(rows: List[Dict[str, float]]) -> str:
    """Format the results as a fixed-width text table: round trip, then to the answer."""
    keys = [key for key, _, _ in QUANTILES] + ['max']
    lines = [f'{"":<18}{"":>7}{"":>11}{"round trip ms":^36}{"to answer ms":^36}',
             f'{"target":<18}{"sent":>7}{"answered":>11}'
             + ''.join(f'{k:>9}' for k in keys) * 2 + f'{"CPU us/msg":>12}']
    for r in rows:
        lines.append(f'{r["target"]:<18}{r["sent"]:>7}{100 * r["answered_fraction"]:>10.2f}%'
                     + ''.join(f'{cell(r[k + "_ms"]):>9}' for k in keys)
                     + ''.join(f'{cell(r["to_answer_" + k + "_ms"]):>9}' for k in keys)
                     + f'{cell(r["cpu_us_per_msg"], 1):>12}')
    return '\n'.join(lines)


def not_answered_line(r: Dict[str, float]) -> str:
    """Return the line of a target's inputs not answered; why some were, if any were late."""
    late = r['not_answered_superseded']
    return (f'{r["target"]}: {plural(r["not_answered"], "input")} not answered'
            + (f', {late} of them followed by the next within a quarter period (published '
               'late: a keep-last-1 input keeps the newer)' if late else ''))


def difference_line(node: Dict[str, float], relay: Dict[str, float]) -> str:
    """Return node - relay for each quantile both report (``-`` for the others)."""
    def diff(key: str) -> str:
        a, b = node[key + '_ms'], relay[key + '_ms']
        return '-' if a is None or b is None else f'{a - b:+.3f} ms'
    return 'inverse_dynamics - relay: ' + ', '.join(
        f'{key} {diff(key)}' for key, _, _ in QUANTILES)


def wake_ups(late_ns: Sequence[int], preemption: str) -> Dict[str, object]:
    """Return how late the pacer woke from its sleeps: the machine's floor for any target.

    Each round trip waits for at least one thread woken by the input; none is woken sooner
    than the pacer, which sleeps at a priority above the targets'. Quantiles in ms as
    :func:`Target.summary` reports them (None from too few wake-ups).
    """
    ms = np.array(late_ns, dtype=float) * 1e-6
    out: Dict[str, object] = {'wake_ups': len(ms), 'kernel_preemption': preemption}
    for key, _, _ in QUANTILES:
        out[f'{key}_ms'] = quantile(ms, key)
    out['max_ms'] = float(ms.max()) if len(ms) else float('nan')
    out['over_1ms'] = int((ms > 1.0).sum())
    return out


def machine_line(machine: Dict[str, object], scheduling: str) -> str:
    """Return the line of the machine's floor (:func:`wake_ups`) under ``scheduling``.

    A publisher that never slept (it could not keep up with the rate) measured no floor.
    """
    if not machine['wake_ups']:
        return (f'machine: the publisher ({scheduling}) never slept to its grid: it could not '
                'keep up with the rate and sent every input late, so no floor was measured; '
                f'kernel preemption: {machine["kernel_preemption"]}')
    keys = [key for key, _, _ in QUANTILES] + ['max']
    return (f'machine: the publisher woke late from its sleeps to the grid ({scheduling}) by '
            + ', '.join(f'{key} {cell(machine[key + "_ms"])}' for key in keys)
            + f' ms ({machine["over_1ms"]} of {machine["wake_ups"]} wake-ups over 1 ms); '
            f'kernel preemption: {machine["kernel_preemption"]} — no round trip has a '
            'shorter tail than a wake-up')


def sent_rate(rows: Sequence[Dict[str, float]]) -> float:
    """Return the rate the inputs were sent at, Hz: the lower of the targets' (NaN if none)."""
    rates = [r['input_rate_hz'] for r in rows if not math.isnan(r['input_rate_hz'])]
    return min(rates) if rates else float('nan')


def rate_warning(asked: float, rows: Sequence[Dict[str, float]]) -> Optional[str]:
    """Return the warning of a publisher that sent below the rate asked (None if it did not).

    More than :data:`RATE_SHORTFALL` below: the figures are of the lower rate.
    """
    sent = sent_rate(rows)
    if math.isnan(sent) or sent >= (1.0 - RATE_SHORTFALL) * asked:
        return None
    return (f'warning: the publisher sent {sent:.0f} Hz of the {asked:g} Hz asked '
            f'({100 * sent / asked:.1f} %): it could not keep up (each block ended '
            f'{LATE_LIMIT_S:g} s after its due time); the figures are of {sent:.0f} Hz')


def machine_legend(late_ms: np.ndarray) -> str:
    """Return the legend of the pacer's wake-ups: the highest quantile they tell."""
    told = [(key, quantile(late_ms, key)) for key, _, _ in QUANTILES]
    told = [(key, value) for key, value in told if value is not None]
    top = f', {told[-1][0]} {told[-1][1]:.2f} ms' if told else ''
    return f'publisher woke late (the machine\'s floor): {len(late_ms)} wake-ups{top}'


def legend(name: str, values: np.ndarray, sent: int) -> str:
    """Return a histogram's legend: answered, and the highest quantile the answers tell."""
    told = [(key, quantile(values, key)) for key, _, _ in QUANTILES]
    told = [(key, value) for key, value in told if value is not None]
    top = f', {told[-1][0]} {told[-1][1]:.2f} ms' if told else ''
    return f'{name}: {100 * len(values) / max(sent, 1):.1f} % answered{top}'


def plot(path: str, targets: List[Target], title: str,
         woke_late_ns: Sequence[int] = ()) -> Optional[str]:
    """Draw the histograms of the round trips (log counts) to ``path``; None if no matplotlib.

    With ``woke_late_ns``, that of the pacer's wake-ups too (the machine's floor, dotted).
    """
    plt = pyplot()
    if plt is None:
        return None
    fig, ax = plt.subplots(figsize=(7.0, 3.6))
    values = [np.array(list(t.latency_ns.values()), dtype=float) * 1e-6 for t in targets]
    top = max((np.percentile(v, 99.9) for v in values if len(v)), default=1.0)   # the range
    bins = np.linspace(0.0, max(top * 1.2, 0.5), 120)
    for target, v in zip(targets, values):
        ax.hist(np.minimum(v, bins[-1]), bins=bins, histtype='step', log=True,
                label=legend(target.name, v, len(target.sent)))
    if len(woke_late_ns):
        late = np.array(woke_late_ns, dtype=float) * 1e-6
        ax.hist(np.minimum(late, bins[-1]), bins=bins, histtype='step', log=True,
                linestyle=':', color='0.4',
                label=machine_legend(late))
    ax.set_xlabel('round trip; the publisher\'s lateness waking, ms (the last bin holds '
                  'everything beyond)')
    ax.set_ylabel('answers')
    ax.set_title('\n'.join(textwrap.wrap(title, 100)), fontsize=8)
    ax.legend(fontsize=8)
    save_figure(plt, fig, path)
    return path


def write_json(path: str, results: Dict[str, object]) -> None:
    """Write ``results`` to ``path`` (``--json``), all or nothing; ValueError names the path.

    Strict JSON (:func:`json_safe`: null for NaN and ±inf, nested too); the folder the file
    goes in (:func:`~spatial_dynamics.files.output_path`) is made first.
    """
    os.makedirs(os.path.dirname(output_path(path)), exist_ok=True)
    write_atomic(path, json.dumps(json_safe([results])[0], indent=2, allow_nan=False) + '\n',
                 '--json')


def rate_text(hz: float) -> str:
    """Return a rate as the output says it: whole Hz from 100 Hz, 3 digits below."""
    return f'{hz:.0f}' if hz >= 100.0 else f'{hz:.3g}'
