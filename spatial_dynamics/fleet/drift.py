# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Which drive parameter of which joint drifted, since when and by how much: a CUSUM.

Each (robot, joint, parameter) series is judged against its own baseline, the estimates of
its first days: robots differ (payload, build, wear at installation), so a fleet-wide value
would flag the odd robot, not the change. Each later estimate becomes a standardized
deviation::

    z_i = (x_i - μ₀) / sqrt(φ (σ_i² + var μ₀))

with σ_i the estimate's own σ (from its fit), μ₀ the baseline's σ-weighted mean and φ ≥ 1
how much more the series scatters than its σ say (what the σ of one recording does not see:
a different motion each day, model error). φ is the series' own, from the robust scale
(1.4826 × the median absolute deviation) of its standardized successive differences
``(x_i - x_{i-1}) / sqrt(σ_i² + σ_{i-1}²)`` around their median: a step changes one
difference and a steady trend shifts them all alike, so neither inflates it, and one series'
wear never blinds another's (nor does the number of robots in the fleet change a verdict).
A two-sided CUSUM (Page 1954) ``S⁺ = max(0, S⁺ + z - k)``, ``S⁻ = max(0, S⁻ - z - k)`` sums
the deviations that persist: a friction rising a few per cent a day crosses ``h`` within
days, while one odd bag (a different program, a cold morning) does not; with σ in the
denominator a poorly determined estimate counts for less. The onset is where the sum last
left zero.

A baseline that itself drifts (wear that starts within the first days) is found by its own
scatter: ``Σ w (x - μ₀)² / φ`` over the baseline against the χ² with ``nb - 1`` degrees of
freedom, at :data:`P_BASELINE`; it is reported as a drift, its onset from a CUSUM against
the first estimate. A series is judged only with :data:`MIN_BASELINE` estimates in its
baseline, at least one after it and :data:`MIN_SCATTER` successive differences for its
scatter; any other is reported as not judged, with the reason.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from datetime import datetime, timezone
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from ..text import shown

#: CUSUM allowance and decision interval, in σ: a steady shift of 3σ is found after ~5 bags,
#: of 5σ after ~2-3, while a series without change (Gaussian z) alarms about once in 10⁷
#: bags (Siegmund's approximation): thousands of robot-joint-parameter series stay quiet.
K, H = 1.0, 8.0
#: Fewest estimates in a baseline (its mean and its own test for a drift need them).
MIN_BASELINE = 3
#: Fewest successive differences a series' own scatter φ is measured from.
MIN_SCATTER = 4
#: How unlikely a steady baseline's scatter must be to call the baseline drifting.
P_BASELINE = 1e-9
LABELS = {'damping': 'viscous damping', 'friction': 'Coulomb friction',
          'armature': 'armature'}


@dataclass
class Drift:
    """One drifted parameter: the onset, the latest value against the baseline."""

    robot: str
    joint: str
    parameter: str
    since: float            # s since the epoch: the first bag of the change
    baseline: float
    latest: float
    z: float                # the latest estimate's deviation, in σ
    within_baseline: bool = False

    def text(self) -> str:
        """``r07 joint 3: Coulomb friction +38 % since 2026-10-02, 6σ``."""
        change = (f'{100 * (self.latest / self.baseline - 1):+.0f} %' if self.baseline
                  else f'{self.latest - self.baseline:+.3g}')
        where = ' (within its baseline days)' if self.within_baseline else ''
        return (f'{self.robot} {shown(self.joint, quote=False)}: {LABELS[self.parameter]} '
                f'{change} since {day(self.since)}, {abs(self.z):.0f}σ{where}')


@dataclass
class Judgement:
    """The drifts found, and the series that could not be judged with the reason of each."""

    drifts: List[Drift] = field(default_factory=list)
    judged: int = 0
    not_judged: Dict[Tuple[str, str, str], str] = field(default_factory=dict)


def count(n: int, noun: str) -> str:
    """``1 robot``, ``2 robots``: ``n`` and ``noun``, plural unless ``n`` is 1."""
    return f'{n} {noun}' + ('' if n == 1 else 's')


def day(t: float) -> str:
    """Return the UTC date of ``t`` (s since the epoch)."""
    return datetime.fromtimestamp(t, timezone.utc).strftime('%Y-%m-%d')


def _clean(start, x, sigma):
    t, x, s = (np.asarray(a, float) for a in (start, x, sigma))
    ok = np.isfinite(x) & np.isfinite(s) & (s > 0.0)
    return t[ok], x[ok], s[ok]


def _baseline(t: np.ndarray, baseline_days: float) -> int:
    """Return how many estimates form the baseline (those within ``baseline_days``)."""
    return int(np.searchsorted(t, t[0] + baseline_days * 86400.0, side='left')) if len(t) else 0


def scatter(x: np.ndarray, s: np.ndarray) -> float:
    """Return φ ≥ 1 of one series: its robust scatter beyond its σ, squared.

    1.4826 × the median absolute deviation of the standardized successive differences
    around their median (the module's docstring), squared; NaN with fewer than
    :data:`MIN_SCATTER` differences.
    """
    if len(x) - 1 < MIN_SCATTER:
        return float('nan')
    d = np.diff(x) / np.sqrt(s[1:] ** 2 + s[:-1] ** 2)
    mad = float(np.median(np.abs(d - np.median(d))))
    return max((1.4826 * mad) ** 2, 1.0)


def _crossing(z: np.ndarray, first: int) -> Optional[int]:
    """Return the onset index of the first crossing of the two-sided CUSUM, or None."""
    up = down = 0.0
    up_from = down_from = first
    for i in range(first, len(z)):
        if up == 0.0:
            up_from = i
        if down == 0.0:
            down_from = i
        up = max(0.0, up + z[i] - K)
        down = max(0.0, down - z[i] - K)
        if up > H or down > H:
            return up_from if up > H else down_from
    return None


def cusum(start: Sequence[float], x: Sequence[float], sigma: Sequence[float],
          baseline_days: float) -> Tuple[Optional[Tuple[int, float, float, bool]],
                                         Optional[str]]:
    """Judge one series: ``((onset index, reference, latest z, within baseline), None)``.

    ``start`` sorted. Returns ``(None, None)`` when judged without a change, ``(None,
    reason)`` when it cannot be judged: a bag without an estimate (NaN) counts where it is,
    so a still bag after the baseline reads as such, not as no bag after it. The onset index
    counts the estimates with a finite value and σ; the reference is the baseline's mean
    (the first estimate's value when the baseline itself drifts).
    """
    every = np.asarray(start, float)
    t, x, s = _clean(start, x, sigma)
    still = ' (the joint did not move enough to determine it)'
    if not len(t):
        bags = 'its one bag' if len(every) == 1 else f'any of its {len(every)} bags'
        return None, f'no estimate in {bags}{still}'
    nb = _baseline(t, baseline_days)
    end = t[0] + baseline_days * 86400.0
    if nb < MIN_BASELINE:
        idle = int(np.sum(every < end)) - nb
        return None, (f'{count(nb, "estimate")} in its first {baseline_days:g} days; a '
                      f'baseline needs {MIN_BASELINE}'
                      + (f'; {count(idle, "bag")} there gave none{still}' if idle else ''))
    if nb >= len(t):
        idle = int(np.sum(every >= end))
        if idle:
            return None, (f'no estimate after its first {baseline_days:g} days: '
                          + ('its one bag after them gives none' if idle == 1 else
                             f'none of its {idle} bags after them gives one') + still)
        return None, (f'no estimate after its first {baseline_days:g} days '
                      f'({len(t)} in all)')
    phi = scatter(x, s)
    if not np.isfinite(phi):
        return None, (f'{count(len(t), "estimate")}; its scatter needs {MIN_SCATTER + 1} at '
                      'least')
    w = 1.0 / s[:nb] ** 2
    mu0 = float(np.sum(w * x[:nb]) / np.sum(w))
    # chi2.isf, imported here: start-up time (scipy.stats takes seconds), and optional
    from scipy.special import chdtri
    if np.sum(w * (x[:nb] - mu0) ** 2) / phi > chdtri(nb - 1, P_BASELINE):
        z = (x - x[0]) / np.sqrt(phi * (s ** 2 + s[0] ** 2))
        onset = _crossing(z, 1)
        return (1 if onset is None else onset, float(x[0]), float(z[-1]), True), None
    z = (x - mu0) / np.sqrt(phi * (s ** 2 + 1.0 / np.sum(w)))
    onset = _crossing(z, nb)
    if onset is None:
        return None, None
    return (onset, mu0, float(z[-1]), False), None


def detect(rows: List[dict], baseline_days: float) -> Judgement:
    """Judge every (robot, joint, parameter) series of the per-bag estimates ``rows``."""
    series: Dict[Tuple[str, str, str], List[dict]] = {}
    for r in rows:
        series.setdefault((r['robot'], r['joint'], r['parameter']), []).append(r)
    out = Judgement()
    for key, rs in series.items():
        rs.sort(key=lambda r: r['start_s'])
        hit, reason = cusum(*([r[c] for r in rs] for c in ('start_s', 'value', 'sigma')),
                            baseline_days)
        if reason is not None:
            out.not_judged[key] = reason
            continue
        out.judged += 1
        if hit is not None:
            onset, mu0, z, within = hit
            good = [r for r in rs if np.isfinite(r['value']) and np.isfinite(r['sigma'])
                    and r['sigma'] > 0.0]
            out.drifts.append(Drift(*key, good[onset]['start_s'], mu0, good[-1]['value'], z,
                                    within))
    out.drifts.sort(key=lambda d: (d.robot, d.joint, d.parameter))
    return out
