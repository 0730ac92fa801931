# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Which drive parameter of which joint drifted, since when and by how much: a CUSUM.

Each (robot, joint, parameter) is judged against its own baseline, the estimates of its
first days: robots differ (payload, build, wear at installation), so a fleet-wide value
would flag the odd robot, not the change. Each later estimate becomes a standardized
deviation::

    z_i = (x_i - μ₀) / sqrt(φ (σ_i² + var μ₀))

with σ_i the estimate's own σ (from its fit), μ₀ the baseline's σ-weighted mean and φ ≥ 1
how much more the baseline estimates scatter than their σ say (what the σ of one
recording does not see: a different motion each day, model error), pooled per parameter
over the whole fleet's baselines: a handful of days per joint is too few to measure a
scatter, a fleet's are many. A two-sided CUSUM (Page 1954)
``S⁺ = max(0, S⁺ + z - k)``, ``S⁻ = max(0, S⁻ - z - k)`` sums the deviations that persist:
a friction rising a few per cent a day crosses ``h`` within days, while one odd bag (a
different program, a cold morning) does not; with σ in the denominator a poorly determined
estimate counts for less. The onset is where the sum last left zero.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime, timezone
from typing import List, Optional, Sequence, Tuple

import numpy as np

#: CUSUM allowance and decision interval, in σ: a steady shift of 3σ is found after ~5 bags,
#: of 5σ after ~2-3, while a series without change (Gaussian z) alarms about once in 10⁷
#: bags (Siegmund's approximation): thousands of robot-joint-parameter series stay quiet.
K, H = 1.0, 8.0
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

    def text(self) -> str:
        """``r07 joint 3: Coulomb friction +38 % since 2026-10-02, 6σ``."""
        change = (f'{100 * (self.latest / self.baseline - 1):+.0f} %' if self.baseline
                  else f'{self.latest - self.baseline:+.3g}')
        return (f'{self.robot} {self.joint}: {LABELS[self.parameter]} {change} since '
                f'{day(self.since)}, {abs(self.z):.0f}σ')


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


def dispersion(series, baseline_days: float) -> float:
    """Return φ ≥ 1: how much more the baseline estimates scatter than their σ say (squared).

    Pooled over ``series`` (each ``(start, x, sigma)``): the mean of ``((x - x̄)/σ)²`` over
    every baseline estimate, each series' mean removed (``nb - 1`` degrees of freedom each).
    """
    chi2, dof = 0.0, 0
    for start, x, sigma in series:
        t, x, s = _clean(start, x, sigma)
        nb = _baseline(t, baseline_days)
        if nb >= 2:
            w = 1.0 / s[:nb] ** 2
            mean = np.sum(w * x[:nb]) / np.sum(w)
            chi2 += float(np.sum(w * (x[:nb] - mean) ** 2))
            dof += nb - 1
    return max(chi2 / dof, 1.0) if dof else 1.0


def cusum(start: Sequence[float], x: Sequence[float], sigma: Sequence[float],
          baseline_days: float, phi: float = 1.0) -> Optional[Tuple[int, float, float]]:
    """Return ``(onset index, baseline μ₀, latest z)`` of a detected change, or None.

    ``start`` sorted; the baseline is every estimate within ``baseline_days`` of the first
    (at least two are needed, else nothing is judged); each σ is scaled by ``sqrt(φ)``
    (:func:`dispersion`). The onset index counts the estimates with a finite value and σ.
    """
    t, x, s = _clean(start, x, sigma)
    nb = _baseline(t, baseline_days)
    if nb < 2 or nb >= len(t):
        return None
    w = 1.0 / s[:nb] ** 2
    mu0 = float(np.sum(w * x[:nb]) / np.sum(w))
    z = (x - mu0) / np.sqrt(phi * (s ** 2 + 1.0 / np.sum(w)))
    up = down = 0.0
    up_from = down_from = nb
    for i in range(nb, len(t)):
        if up == 0.0:
            up_from = i
        if down == 0.0:
            down_from = i
        up = max(0.0, up + z[i] - K)
        down = max(0.0, down - z[i] - K)
        if up > H or down > H:
            onset = up_from if up > H else down_from
            return onset, mu0, float(z[-1])
    return None


def detect(rows: List[dict], baseline_days: float) -> List[Drift]:
    """Return the drifts among the per-bag estimates ``rows`` (fleet.csv's rows)."""
    series = {}
    for r in rows:
        series.setdefault((r['robot'], r['joint'], r['parameter']), []).append(r)
    arrays = {}
    for key, rs in series.items():
        rs.sort(key=lambda r: r['start_s'])
        arrays[key] = tuple([r[c] for r in rs] for c in ('start_s', 'value', 'sigma'))
    phi = {p: dispersion([a for k, a in arrays.items() if k[2] == p], baseline_days)
           for p in {k[2] for k in arrays}}
    found = []
    for (robot, joint, parameter), rs in series.items():
        hit = cusum(*arrays[robot, joint, parameter], baseline_days, phi[parameter])
        if hit is not None:
            onset, mu0, z = hit
            good = [r for r in rs if np.isfinite(r['value']) and np.isfinite(r['sigma'])]
            found.append(Drift(robot, joint, parameter, good[onset]['start_s'], mu0,
                               good[-1]['value'], z))
    return sorted(found, key=lambda d: (d.robot, d.joint, d.parameter))
