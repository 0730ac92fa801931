# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Excitation trajectories: a motion whose torques tell every base parameter (Swevers 1997).

Each joint ``j`` follows a finite Fourier series of period ``T`` (``ω = 2π/T``)::

    q_j(t)  = q0_j + Σ_{l=1..L} a_jl/(ω l) sin(ω l t) − b_jl/(ω l) cos(ω l t)
    q̇_j(t)  = Σ_l a_jl cos(ω l t) + b_jl sin(ω l t)
    q̈_j(t)  = Σ_l ω l (−a_jl sin(ω l t) + b_jl cos(ω l t))

so the motion is periodic (repeat it to average the noise), band-limited (``L/T`` Hz at most:
no resonance excited, accelerations bounded by the velocities) and smooth.

**At rest at both ends.** ``q̇_j(0) = Σ_l a_jl`` and ``q̈_j(0) = ω Σ_l l b_jl``: two linear
equalities per joint, and by periodicity they hold at ``T`` too (and at every repetition).
They are eliminated, not penalised: each joint's coefficients ``x_j = [q0_j, a_j, b_j]`` are
``E z_j`` with ``E`` an orthonormal basis of their null space, so every iterate starts and
ends at rest exactly. (A smooth window would do it too, but it multiplies the series by
another, spreads its spectrum and mixes every coefficient into the limits; the null space
keeps the series a series.)

**The criterion.** The condition number of the stacked regressor of the base parameters,
``W = [Y_b(t_1); …; Y_b(t_N)]`` (``Y_b`` the columns of :func:`~spatial_dynamics.regressor`
that :func:`~spatial_dynamics.identification.base_parameters` keeps, over ``N`` samples of
one period), with its columns scaled to unit norm: ``cond(W D⁻¹)``, ``D = diag(|w_c|)``.
The scaling makes the number independent of the parameters' units (kg, kg m, kg m²); it is
the condition number of the least squares a fit solves after equilibrating the columns.
Its gradient is exact up to the finite differences of ``Y`` in ``q``, ``q̇`` (``q̈`` enters
linearly): ``dσ = uᵀ d(W D⁻¹) v`` for the extreme singular values.

**The limits** hold at ``Nc`` samples of the period (SciPy's SLSQP, inequality constraints):
positions within ``[lower + margin, upper − margin]`` (a continuous joint: ±π), ``|q̇|``
within ``velocity_fraction`` of the velocity limit (:data:`DEFAULT_VELOCITY` when the URDF
gives none), ``|τ| = |rnea|`` within ``effort_fraction`` of the effort limit (none when
the URDF gives none). Positions and velocities are linear in the coefficients; the
torques' Jacobian comes from finite differences of the RNEA.

The start is seeded: random coefficients (harmonic ``l`` weighted ``1/l``) about the middle
of each joint's range, scaled to the largest amplitude that keeps the limits; its condition
number is reported as ``cond_before``.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from .backends import regressor, rnea
from .identification import base_parameters, BaseParameters
from .model import Model
from .text import shown

# scipy is imported inside rest_basis and excitation, the two functions that use it: it takes
# seconds to import, and the commands importing this module (replay) need it only to design.

#: Velocity limit (rad/s, m/s) assumed for a joint whose URDF gives none.
DEFAULT_VELOCITY = {'revolute': 1.0, 'prismatic': 0.25}
#: Half range (rad) of a joint without position limits (continuous), about 0.
DEFAULT_HALF_RANGE = math.pi
#: A margin never takes more than this fraction of a joint's range from each end.
MAX_MARGIN_FRACTION = 0.25
#: The velocity and effort constraints hold at the samples with this much to spare: between
#: samples (``40 L`` a period, 40 a cycle of the highest harmonic) a sinusoid peaks at most
#: ``1 − cos(π/40)`` ≈ 0.3 % above them.
SLACK = 0.005
#: Finite-difference step in q and q̇ (rad, rad/s).
STEP = 1e-6
#: Points a written plan puts on each cycle of its highest harmonic, at least: twice
#: Nyquist's two (:func:`min_rate`). joint_trajectory_controller's quintics through exact
#: positions, velocities and accelerations four times a cycle follow a sinusoid within
#: 2.3e-4 of its amplitude in position, 5e-4 in velocity and 2.2e-3 in acceleration (twice
#: a cycle: 1.8e-2, 2e-2, 4.5e-2).
POINTS_PER_CYCLE = 4
#: The optimiser's iterations, at most (SLSQP's ``maxiter``; one takes ~0.02-0.1 s).
MAX_ITERATIONS = 10_000
#: The seeds accepted: NumPy's generator takes any whole number ≥ 0; these are 32 bits.
MAX_SEED = 2 ** 32 - 1
#: A value of the plan below this (rad, rad/s, rad/s², m ...) is the series' rounding noise
#: about zero (rest at the ends): written as 0.
NOISE = 1e-12


@dataclass(frozen=True)
class Limits:
    """The box the trajectory keeps to, each (n,).

    ``lower``/``upper`` (rad or m, the margins taken off), ``velocity`` (rad/s or m/s, the
    fraction applied) and ``effort`` (N m or N, the fraction applied; ``inf`` where the URDF
    gives no limit).
    """

    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray
    effort: np.ndarray


def limits(model: Model, margin: float = 0.1, velocity_fraction: float = 0.8,
           effort_fraction: float = 0.6) -> Limits:
    """Return the :class:`Limits` of ``model``'s joints (see the module docstring).

    ``margin`` (rad or m) comes off both ends of each range, but at most
    :data:`MAX_MARGIN_FRACTION` of the range (a 4 cm gripper keeps some travel).
    """
    kinds = [model.joint_types.get(j, 'revolute') for j in model.joint_names]
    check_ranges(model)
    bounded = np.isfinite(model.lower) & np.isfinite(model.upper) & np.array(
        [k != 'continuous' for k in kinds], dtype=bool)
    lo = np.where(bounded, model.lower, -DEFAULT_HALF_RANGE)
    hi = np.where(bounded, model.upper, DEFAULT_HALF_RANGE)
    m = np.minimum(margin, MAX_MARGIN_FRACTION * (hi - lo))
    vmax = np.array([v if np.isfinite(v) and v > 0 else
                     DEFAULT_VELOCITY['prismatic' if k == 'prismatic' else 'revolute']
                     for v, k in zip(model.velocity_limit, kinds)])
    emax = np.where((model.effort_limit > 0) & np.isfinite(model.effort_limit),
                    model.effort_limit, np.inf)
    return Limits(lo + m, hi - m, velocity_fraction * vmax, effort_fraction * emax)


def check_ranges(model: Model) -> None:
    """Refuse a joint no excitation can move: ``ValueError`` naming it.

    A joint whose lower limit is above its upper one has no position within its limits; one
    whose limits are equal cannot move, so nothing its motion would tell can be found. A
    continuous joint's limits are not read (URDF: it has none; exporters write 0 and 0).
    """
    for j, name in enumerate(model.joint_names):
        if model.joint_types.get(name) == 'continuous':
            continue
        lo, hi = float(model.lower[j]), float(model.upper[j])
        if lo > hi:
            raise ValueError(f'joint {shown(name)}: its lower limit ({lo:g}) is above its upper '
                             f'limit ({hi:g}), so no position is within them')
        if lo == hi:
            raise ValueError(f'joint {shown(name)}: its lower and upper limits are equal '
                             f'({lo:g}), so it cannot move; lock it at that value instead of '
                             'exciting it')


def min_rate(period: float, harmonics: int) -> float:
    """Return the lowest rate (Hz) of points that represents the series (``4 L / T``).

    :data:`POINTS_PER_CYCLE` points a cycle of the highest harmonic (``L / T`` Hz), twice
    Nyquist's rate: slower points alias the series (a period of 0.1 s at 10 Hz puts every
    point at the same phase, a plan standing still).
    """
    return POINTS_PER_CYCLE * harmonics / period


def period_points(period: float, rate: float) -> int:
    """Return the points a period of ``period`` s has at ``rate`` Hz: ``⌈T · rate⌉``."""
    return max(1, math.ceil(period * rate - 1e-9))


def _basis(t: np.ndarray, omega: float, L: int) -> Tuple[np.ndarray, ...]:
    """Return Φ, Φ', Φ'' (N, 1 + 2L): ``q_j = Φ x_j`` with ``x_j = [q0_j, a_j1.., b_j1..]``."""
    wl = omega * np.arange(1, L + 1)
    s, c = np.sin(np.outer(t, wl)), np.cos(np.outer(t, wl))
    one, zero = np.ones((len(t), 1)), np.zeros((len(t), 1))
    return (np.hstack([one, s / wl, -c / wl]), np.hstack([zero, c, s]),
            np.hstack([zero, -wl * s, wl * c]))


def rest_basis(L: int) -> np.ndarray:
    """Return ``E`` (1 + 2L, 2L − 1): orthonormal, ``x = E z`` starts and ends at rest.

    The null space of ``Σ_l a_l = 0`` (q̇(0) = 0) and ``Σ_l l b_l = 0`` (q̈(0) = 0).
    """
    from scipy.linalg import null_space
    C = np.zeros((2, 1 + 2 * L))
    C[0, 1:L + 1] = 1.0
    C[1, L + 1:] = np.arange(1, L + 1)
    return null_space(C)


@dataclass(frozen=True)
class Excitation:
    """An optimised excitation trajectory of ``joint_names`` (model order), one period.

    Attributes:
        q0: (n,) rad or m, the mean position of each joint.
        a, b: (n, L) rad/s or m/s, the coefficients of the series (module docstring).
        period: ``T``, s.
        cond_before, cond_after: the criterion at the start and at the optimum, both over
            the same samples (:meth:`condition`).
        base: the model's base parameters (structural: random states over the limits).
        rank: how many of them the trajectory determines (the rank of its ``W``).
        limits: the :class:`Limits` it was optimised within.
        iterations, message, status: SLSQP's (status 0: converged; 9: the iteration limit
            was reached, the plan is the best found within it; −1: SLSQP ended outside the
            limits, the start is returned).
        samples: how many samples of one period ``cond_*`` and ``rank`` were computed at
            (:meth:`report_times`).
    """

    joint_names: Tuple[str, ...]
    q0: np.ndarray
    a: np.ndarray
    b: np.ndarray
    period: float
    cond_before: float
    cond_after: float
    base: BaseParameters
    rank: int
    limits: Limits
    iterations: int
    message: str
    status: int = 0
    samples: int = 160

    @property
    def harmonics(self) -> int:
        """``L``, the number of harmonics."""
        return self.a.shape[1]

    @property
    def converged(self) -> bool:
        """Say whether SLSQP converged; if not, the plan is the best found when it stopped."""
        return self.status == 0

    @property
    def iteration_limit(self) -> bool:
        """Say whether SLSQP stopped at its iteration limit (the best found within it)."""
        return self.status == 9

    def evaluate(self, t) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return ``q``, ``q̇``, ``q̈`` (N, n) at times ``t`` (N,) s (periodic in ``t``)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        X = np.hstack([self.q0[:, None], self.a, self.b])
        return tuple(P @ X.T for P in _basis(t, 2 * math.pi / self.period, self.harmonics))

    def report_times(self) -> np.ndarray:
        """Return the times (s) of one period at which ``cond_*`` and ``rank`` were computed."""
        return np.arange(self.samples) * self.period / self.samples

    def times(self, rate: float, periods: int = 1) -> np.ndarray:
        """Return evenly spaced times from 0 to ``periods · T`` inclusive, at least ``rate`` Hz."""
        total = periods * self.period
        return np.linspace(0.0, total, int(math.ceil(total * rate - 1e-9)) + 1)

    def sample(self, rate: float, periods: int = 1) -> Tuple[np.ndarray, ...]:
        """Return ``t`` (N,), ``q``, ``q̇``, ``q̈`` (N, n): ``periods`` periods at ``rate`` Hz."""
        t = self.times(rate, periods)
        return (t,) + self.evaluate(t)

    def point_times(self, rate: float) -> List[int]:
        """Return the times (whole ns) of one period's points: ``m = ⌈T · rate⌉`` of them.

        Spread evenly from 0 to before ``T`` (each rounded to the nanosecond), so every
        period of a plan has its points at the same phases. ``ValueError`` when ``rate`` is
        below :func:`min_rate` (the points would alias the series).
        """
        lowest = min_rate(self.period, self.harmonics)
        if not (math.isfinite(rate) and rate >= lowest * (1.0 - 1e-12)):
            raise ValueError(f'{rate:g} points a second cannot represent {self.harmonics} '
                             f'harmonics of a {self.period:g} s period: at least {lowest:.4g} '
                             f'({POINTS_PER_CYCLE} a cycle of the highest harmonic)')
        period_ns = round(self.period * 1e9)
        m = period_points(self.period, rate)
        return [(2 * i * period_ns + m) // (2 * m) for i in range(m)]

    def to_points(self, rate: float, periods: int = 1) -> List[Dict]:
        """Return JointTrajectory points (positions, velocities, accelerations, time_from_start).

        The mapping form of ``trajectory_msgs/JointTrajectoryPoint`` that
        :func:`spatial_dynamics.trajectory.trajectory` and ``ros2 action send_goal`` read.
        One period's points (:meth:`point_times`) are computed once and repeated ``periods``
        times, then the first again at the end: the plan is periodic exactly, value for value
        and nanosecond for nanosecond, so the controller's splines are the same in every
        period. Values below :data:`NOISE` in magnitude are 0 (rest at the ends); the
        repeated points share their lists.
        """
        ns = self.point_times(rate)
        period_ns = round(self.period * 1e9)
        states = self.evaluate(np.array(ns, dtype=float) * 1e-9)
        q, qd, qdd = (np.where(np.abs(x) < NOISE, 0.0, x).tolist() for x in states)

        def point(i: int, t: int) -> Dict:
            return {'positions': q[i], 'velocities': qd[i], 'accelerations': qdd[i],
                    'time_from_start': {'sec': t // 1_000_000_000,
                                        'nanosec': t % 1_000_000_000}}

        points = [point(i, k * period_ns + t) for k in range(periods)
                  for i, t in enumerate(ns)]
        return points + [point(0, periods * period_ns)]


class _Problem:
    """The criterion and the constraints as functions of ``z`` (n · (2L − 1),)."""

    def __init__(self, model: Model, base: BaseParameters, lim: Limits, period: float, L: int,
                 gravity: Sequence[float], samples: int, constraint_samples: int) -> None:
        self.model, self.base, self.lim, self.gravity = model, base, lim, tuple(gravity)
        self.n, self.L = model.nq, L
        self.E = rest_basis(L)
        omega = 2 * math.pi / period
        t = np.arange(samples) * period / samples
        tc = np.arange(constraint_samples) * period / constraint_samples
        self.B = [P @ self.E for P in _basis(t, omega, L)]          # (N, 2L − 1) each
        self.Bc = [P @ self.E for P in _basis(tc, omega, L)]
        self.limited = np.flatnonzero(np.isfinite(lim.effort))
        self.effort = (1.0 - SLACK) * lim.effort
        velocity = (1.0 - SLACK) * lim.velocity
        # the linear constraints (positions, velocities), each row scaled to O(1)
        n, m = self.n, self.E.shape[1]
        rows, rhs = [], []
        span = lim.upper - lim.lower
        for j in range(n):
            for P, lo, hi, scale in ((self.Bc[0], lim.lower[j], lim.upper[j], span[j]),
                                     (self.Bc[1], -velocity[j], velocity[j], velocity[j])):
                block = np.zeros((len(tc), n * m))
                block[:, j * m:(j + 1) * m] = P / scale
                rows += [block, -block]                 # P z − lo ≥ 0,  hi − P z ≥ 0
                rhs += [np.full(len(tc), -lo / scale), np.full(len(tc), hi / scale)]
        self.A_lin, self.b_lin = np.vstack(rows), np.concatenate(rhs)
        self._cache: Dict[bytes, tuple] = {}

    def states(self, z: np.ndarray, B) -> Tuple[np.ndarray, ...]:
        """Return q, q̇, q̈ (N, n) of ``z`` on the basis ``B`` (one of ``self.B``, ``self.Bc``)."""
        Z = z.reshape(self.n, -1)
        return tuple(P @ Z.T for P in B)

    def perturbed(self, q, qd, qdd) -> Tuple[np.ndarray, ...]:
        """Stack the state and its 3n perturbations: (1 + 3n, N, n) each, and the steps."""
        n = self.n
        eye = np.eye(n)
        Q = np.repeat(q[None], 1 + 3 * n, axis=0)
        Qd, Qdd = np.repeat(qd[None], 1 + 3 * n, axis=0), np.repeat(qdd[None], 1 + 3 * n, 0)
        for j in range(n):
            Q[1 + j] += STEP * eye[j]
            Qd[1 + n + j] += STEP * eye[j]
            Qdd[1 + 2 * n + j] += eye[j]
        steps = np.concatenate([np.full(2 * n, STEP), np.ones(n)])
        return Q, Qd, Qdd, steps

    def chain(self, G: np.ndarray, B) -> np.ndarray:
        """Map ``G`` (3, ..., N, n) = ∂/∂(q, q̇, q̈) per sample onto ``z``: (..., n · (2L−1))."""
        out = sum(np.einsum('...kj,km->...jm', G[p], B[p]) for p in range(3))
        return out.reshape(out.shape[:-2] + (-1,))

    # ----------------------------------------------------------------------------------
    # the criterion: log cond(W D⁻¹)

    def log_cond(self, z: np.ndarray) -> Tuple[float, np.ndarray]:
        """Return ``log cond`` of the scaled base regressor of ``z`` and its gradient."""
        Q, Qd, Qdd, steps = self.perturbed(*self.states(z, self.B))
        Y = self.base.columns(regressor(self.model, Q, Qd, Qdd, self.gravity))
        N, n, r = Y.shape[1:]
        W = Y[0].reshape(N * n, r)
        d = np.linalg.norm(W, axis=0)
        d = np.where(d > 0, d, 1.0)
        Ws = W / d
        # the extreme singular pairs from the r × r Gram matrix: LAPACK's SVD of the tall W
        # is no faster and, on a loaded machine, OpenBLAS's threads make it 100x slower
        lam, V = np.linalg.eigh(Ws.T @ Ws)
        s = np.sqrt(np.maximum(lam[[-1, 0]], 1e-300))               # σ_max, σ_min
        M = np.zeros_like(Ws)
        for k, sign in ((0, 1.0), (1, -1.0)):      # d log σ = uᵀ d(W D⁻¹) v / σ
            v = V[:, -1 if k == 0 else 0]
            u, sk = Ws @ v / s[k], s[k]
            M += sign * (np.outer(u, v) - sk * Ws * v ** 2) / (d * sk)
        dY = (Y[1:] - Y[0]) / steps[:, None, None, None]            # (3n, N, n, r)
        G = np.einsum('pkic,kic->pk', dY, M.reshape(N, n, r))       # (3n, N)
        G = G.reshape(3, n, N).transpose(0, 2, 1)                   # (3, N, n)
        return float(np.log(s[0] / s[1])), self.chain(G, self.B)

    # ----------------------------------------------------------------------------------
    # the constraints: ≥ 0, each scaled by its limit

    def _torques(self, z: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
        key = z.tobytes()
        if key not in self._cache:
            Q, Qd, Qdd, steps = self.perturbed(*self.states(z, self.Bc))
            tau = rnea(self.model, Q, Qd, Qdd, self.gravity)[..., self.limited]
            dtau = (tau[1:] - tau[0]) / steps[:, None, None]         # (3n, Nc, nl)
            n = self.n
            G = dtau.reshape(3, n, *tau.shape[1:]).transpose(0, 3, 2, 1)  # (3, nl, Nc, n)
            J = sum(np.einsum('ikj,km->ikjm', G[p], self.Bc[p]) for p in range(3))
            J = J.reshape(J.shape[:2] + (-1,))                       # (nl, Nc, n · m)
            self._cache = {key: (tau[0], J)}
        return self._cache[key]

    def constraints(self, z: np.ndarray) -> np.ndarray:
        """Return every constraint's value (≥ 0 where the limits hold)."""
        out = [self.A_lin @ z + self.b_lin]
        if len(self.limited):
            tau = self._torques(z)[0] / self.effort[self.limited]
            out += [(1.0 - tau).T.ravel(), (1.0 + tau).T.ravel()]
        return np.concatenate(out)

    def constraints_jacobian(self, z: np.ndarray) -> np.ndarray:
        """Return the Jacobian of :meth:`constraints`."""
        out = [self.A_lin]
        if len(self.limited):
            J = self._torques(z)[1] / self.effort[self.limited][:, None, None]
            J = J.reshape(-1, J.shape[-1])
            out += [-J, J]
        return np.vstack(out)


def determined(model: Model, base: BaseParameters, states: Sequence[np.ndarray],
               gravity: Sequence[float] = (0.0, 0.0, -9.81)) -> Tuple[int, float]:
    """Return how many base parameters ``states`` ``(q, q̇, q̈)`` determine, and :func:`condition`.

    The count is the rank of their stacked regressor (:func:`base_parameters` of them): the
    number any least squares on their torques can tell apart.
    """
    return (base_parameters(model, states, gravity).rank,
            condition(model, base, *states, gravity))


def condition(model: Model, base: BaseParameters, q, qd, qdd,
              gravity: Sequence[float] = (0.0, 0.0, -9.81)) -> float:
    """Return ``cond(W D⁻¹)``: the scaled base regressor stacked over the states given."""
    Y = base.columns(regressor(model, q, qd, qdd, gravity))
    W = Y.reshape(-1, Y.shape[-1])
    d = np.linalg.norm(W, axis=0)
    s = np.linalg.svd(W / np.where(d > 0, d, 1.0), compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0 else math.inf


def excitation(model: Model, period: float = 10.0, harmonics: int = 5,
               gravity: Sequence[float] = (0.0, 0.0, -9.81), margin: float = 0.1,
               velocity_fraction: float = 0.8, effort_fraction: float = 0.6, seed: int = 0,
               samples: Optional[int] = None, constraint_samples: Optional[int] = None,
               maxiter: int = 100, base: Optional[BaseParameters] = None) -> Excitation:
    """Optimise a periodic excitation trajectory of ``model``'s joints (module docstring).

    ``period`` s, ``harmonics`` ``L``; ``samples`` (default ``8 L``, at least 40) the
    criterion's samples over the period, ``constraint_samples`` (default ``40 L``, at least
    100) the limits'. Deterministic for a given ``seed``. ``ValueError`` for arguments no
    trajectory can have (a non-positive period, no harmonics, fractions outside (0, 1], a
    seed or ``maxiter`` out of range), for a joint that cannot move (:func:`check_ranges`)
    and when no start within the limits exists (the effort limits cannot even hold the robot
    still in the middle of its ranges).
    """
    from scipy.optimize import minimize
    if not (math.isfinite(period) and period > 0):
        raise ValueError(f'the period must be a finite number > 0 s, got {shown(period)}')
    if not (isinstance(harmonics, (int, np.integer)) and 1 <= harmonics <= 50):
        raise ValueError(f'the number of harmonics must be 1 .. 50, got {shown(harmonics)}')
    for name, f in (('velocity_fraction', velocity_fraction),
                    ('effort_fraction', effort_fraction)):
        if not 0.0 < f <= 1.0:
            raise ValueError(f'{name} must be in (0, 1], got {shown(f)}')
    if not (math.isfinite(margin) and margin >= 0):
        raise ValueError(f'the margin must be a finite number ≥ 0, got {shown(margin)}')
    if not (isinstance(seed, (int, np.integer)) and 0 <= seed <= MAX_SEED):
        raise ValueError(f'the seed must be a whole number 0 .. {MAX_SEED}, got {shown(seed)}')
    if not (isinstance(maxiter, (int, np.integer)) and 1 <= maxiter <= MAX_ITERATIONS):
        raise ValueError(f'the iterations must be a whole number 1 .. {MAX_ITERATIONS:,}, '
                         f'got {shown(maxiter)}')
    L = int(harmonics)
    lim = limits(model, margin, velocity_fraction, effort_fraction)
    base = base_parameters(model, gravity=gravity, seed=seed) if base is None else base
    samples = samples or max(40, 8 * L)
    problem = _Problem(model, base, lim, period, L, gravity, samples,
                       constraint_samples or max(100, 40 * L))
    z0 = _start(problem, seed)
    if z0 is None:
        raise ValueError('no motion keeps the limits: the effort limits (times the effort '
                         'fraction) do not hold the robot still in the middle of its ranges')
    result = minimize(problem.log_cond, z0, jac=True, method='SLSQP',
                      constraints=[{'type': 'ineq', 'fun': problem.constraints,
                                    'jac': problem.constraints_jacobian}],
                      options={'maxiter': int(maxiter), 'ftol': 1e-6})
    z = result.x
    if not (np.all(np.isfinite(z)) and problem.constraints(z).min() >= -1e-6):
        z = z0                  # SLSQP ended outside the limits: keep the start, say so
    t = np.arange(4 * samples) * period / (4 * samples)       # the report's samples

    def states(z):
        X = z.reshape(problem.n, -1) @ problem.E.T             # (n, 1 + 2L)
        return X, tuple(P @ X.T for P in _basis(t, 2 * math.pi / period, L))

    rank, cond = determined(model, base, states(z)[1], gravity)
    X = states(z)[0]
    message = str(result.message) + ('' if z is result.x else
                                     ' (ended outside the limits: the start is returned)')
    return Excitation(tuple(model.joint_names), X[:, 0].copy(), X[:, 1:L + 1].copy(),
                      X[:, L + 1:].copy(), float(period),
                      condition(model, base, *states(z0)[1], gravity), cond, base, rank,
                      lim, int(result.nit), message, int(result.status) if z is result.x
                      else -1, len(t))


def _start(problem: _Problem, seed: int) -> Optional[np.ndarray]:
    """Return the seeded start, or None when even standing still breaks the limits.

    Random coefficients about the middle of each range, each joint's scaled to the largest
    oscillation its position and velocity limits allow, then all by one factor (bisection)
    until the torques keep theirs.
    """
    rng = np.random.default_rng(seed)
    n, L = problem.n, problem.L
    lim = problem.lim
    mid = 0.5 * (lim.lower + lim.upper)
    X = np.zeros((n, 1 + 2 * L))
    weight = 1.0 / np.arange(1, L + 1)
    X[:, 1:L + 1] = rng.normal(size=(n, L)) * weight
    X[:, L + 1:] = rng.normal(size=(n, L)) * weight
    Bq, Bqd = problem.Bc[0] @ problem.E.T, problem.Bc[1] @ problem.E.T   # on x, not z
    q, qd = X @ Bq.T, X @ Bqd.T                         # (n, Nc): the oscillation alone
    with np.errstate(divide='ignore'):                  # each joint scaled to its own box
        scale = np.min([(lim.upper - mid) / q.max(axis=1), (mid - lim.lower) / -q.min(axis=1),
                        lim.velocity / np.abs(qd).max(axis=1)], axis=0)
    osc = (X * np.where(np.isfinite(scale), 0.99 * scale, 0.0)[:, None]) @ problem.E
    centre = np.zeros((n, 1 + 2 * L))
    centre[:, 0] = mid
    still = centre @ problem.E

    def feasible(s):
        return problem.constraints((still + s * osc).ravel()).min() >= 0.0

    if not feasible(0.0):
        return None
    if feasible(1.0):
        return (still + osc).ravel()
    lo, hi = 0.0, 1.0                                   # the torques: one common scale
    for _ in range(30):
        s = 0.5 * (lo + hi)
        lo, hi = (s, hi) if feasible(s) else (lo, s)
    return (still + lo * osc).ravel()
