# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""External joint torques from measured effort: the generalized-momentum observer (no ROS).

Pure Python + numpy + the library (no rclpy import), tested in ``test/test_node_observer_laws.py``
on a simulated robot. The robot, as the node models it (SI units, order of
``model.joint_names``)::

    (M(q) + A) q̈ + C(q, q̇) q̇ + g(q) + friction(q̇) = τ_m + τ_ext

with ``A = diag(armature)``, ``τ_m`` the measured joint torque and ``τ_ext = Jᵀ w`` the joint
torque of the wrenches the environment applies to the robot. The generalized momentum
``p = (M(q) + A) q̇`` obeys (``Ṁ = C + Cᵀ``)::

    ṗ = τ_m + β(q, q̇) + τ_ext,    β = Cᵀ(q, q̇) q̇ − g(q) − friction(q̇)

and De Luca's observer (De Luca & Mattone, ICRA 2005)::

    r(t) = K_O [p(t) − p(t0) − ∫_{t0}^{t} (τ_m + β + r) ds]

gives ``ṙ = K_O (τ_ext − r)``: ``r`` is ``τ_ext`` through a first-order low pass of time
constant ``1/K_O``, computed from ``q``, ``q̇`` and ``τ_m`` only (no acceleration, no
differentiated velocity). ``p`` and ``Cᵀ q̇`` come from one O(n) pass
(:func:`spatial_dynamics.generalized_momentum`).

Discrete form, sample k at time ``t_k`` (``Δt = t_k − t_{k−1}``): the momentum balance over
the step gives the mean external torque ``ȳ_k = (p_k − p_{k−1})/Δt − ½(w_k + w_{k−1})``
with ``w = τ_m + β`` (trapezoidal rule), and ``r`` is the exact solution of
``ṙ = K_O (ȳ_k − r)`` over the step::

    r_k = e^{−K_O Δt} r_{k−1} + (1 − e^{−K_O Δt}) ȳ_k

(for ``K_O Δt ≪ 1`` this is the Euler step of the integral form above; unlike it, it is
stable and exactly first order for any sample interval). A step of ``τ_ext`` at a sample
gives ``r = (1 − e^{−K_O t}) τ_ext`` at the samples after it.

**On a moving base** (a mobile manipulator, a ship: the node's ``base: moving``) the same
observer runs on the joint rows of the floating twin (:func:`~spatial_dynamics.floating_twin`)
with the base's twist ``v_b`` and orientation given, ``ν = [v_b; q̇]``::

    p = M_jb v_b + (M_jj + A) q̇,    β = (Cᵀ(q, ν) ν)_j − g_j(q, orientation) − friction(q̇)

(:func:`spatial_dynamics.generalized_momentum` with ``base=``): the joints are true
coordinates, so ``ṗ = τ_m + β + τ_ext`` holds as on a fixed base. It needs the base's twist
and orientation, never its acceleration.
"""

from __future__ import annotations

import math
from typing import Callable, Optional, Sequence, Tuple

import numpy as np
import spatial_dynamics as sd
from spatial_dynamics.bounds import MAX_EFFORT, MIN_STAMP_INTERVAL
from spatial_dynamics.ros.inputs import InputError, name_index
from spatial_dynamics.ros.records import Robot
from spatial_dynamics.ros.text import shown

#: ``observer_gain`` K_O (1/s) at most (the bound of its entry in the node's parameter table,
#: which checks it): a time constant of 1 ms, one sample at 1 kHz. Beyond
#: it the estimate is the raw difference quotient of the momentum (differentiated
#: velocities, all their noise) at any joint_states rate a node can take.
MAX_OBSERVER_GAIN = 1000.0
#: ``external_torque_warn`` (N m or N, per-joint RMS) at most.
MAX_EXTERNAL_TORQUE_WARN = 1e6
#: Why a good measured state does not update the observer (diagnostics counter keys).
#: ``no_effort`` (empty effort: not an error, the observer just waits), ``length_mismatch``
#: (effort and name differ in length), ``non_finite`` (NaN/Inf effort of a model joint),
#: ``out_of_bounds`` (|effort| beyond :data:`~spatial_dynamics.bounds.MAX_EFFORT`: one such
#: sample integrated would poison every later estimate),
#: ``no_velocity`` (the observer needs q̇), ``unstamped`` (header stamp 0, see
#: :func:`sample_time`), ``repeated`` (the stamp of the previous sample),
#: ``interval_too_short`` (stamped less than :data:`~spatial_dynamics.bounds.
#: MIN_STAMP_INTERVAL` after the previous sample: :meth:`MomentumObserver.update`).
SKIP_REASONS = ('no_effort', 'length_mismatch', 'non_finite', 'out_of_bounds', 'no_velocity',
                'unstamped', 'repeated', 'interval_too_short')
#: On a moving base, also (counted only when they happen): ``base_missing`` (no base twist or
#: pose yet), ``base_stale`` (older than ``base_input.timeout``).
BASE_SKIP_REASONS = ('base_missing', 'base_stale')

Friction = Callable[[np.ndarray], np.ndarray]


class ObserverError(ValueError):
    """An observer parameter that cannot be used; the message names it."""


def check_warn(joint_names: Optional[Sequence[str]], values: Sequence[float]) -> np.ndarray:
    """``external_torque_warn``: one value for all joints or one per joint; > 0, bounded.

    N m (N for prismatic joints), compared with the RMS of the estimate per joint over a
    diagnostics period. ``joint_names`` None checks the values only (no model yet). Returns
    a read-only (n,) array (or the values as given when there is no model).
    """
    values = [float(v) for v in values or ()]
    for value in values:
        if not (math.isfinite(value) and 0.0 < value <= MAX_EXTERNAL_TORQUE_WARN):
            raise ObserverError(
                f'parameter external_torque_warn: {value} is not a finite value above 0 and '
                f'at most {MAX_EXTERNAL_TORQUE_WARN:g} (N m, or N for a prismatic joint)')
    if joint_names is None:
        return np.array(values)
    n = len(joint_names)
    if len(values) not in (1, n):
        raise ObserverError(
            f'parameter external_torque_warn: {len(values)} values for the {n} joints '
            f'{list(joint_names)} (need one value for all, or one per joint in this order)')
    warn = np.array(values * n if len(values) == 1 else values)
    warn.setflags(write=False)
    return warn


def measured_effort(joint_names: Tuple[str, ...], name: Sequence[str],
                    effort: Sequence[float]) -> np.ndarray:
    """``τ_m`` (n,) in ``joint_names`` order from a measured JointState's ``effort``, by name.

    Raises :class:`~spatial_dynamics.ros.inputs.InputError` with a reason of
    :data:`SKIP_REASONS`: ``no_effort`` when ``effort`` is empty; beyond
    :data:`~spatial_dynamics.bounds.MAX_EFFORT` it is ``out_of_bounds`` (the sample is skipped,
    never integrated).
    """
    if len(effort) == 0:
        raise InputError('no_effort', "field 'effort' is empty")
    if len(effort) != len(name):
        raise InputError('length_mismatch', f"field 'effort' has {len(effort)} values for "
                         f'{len(name)} names')
    tau = np.asarray(effort, dtype=np.float64)[name_index(joint_names, tuple(name))]
    if not np.isfinite(tau).all():
        bad = [joint_names[i] for i in np.flatnonzero(~np.isfinite(tau))]
        raise InputError('non_finite', f"field 'effort' is not finite for joint(s) {bad}")
    huge = np.flatnonzero(np.abs(tau) > MAX_EFFORT)
    if huge.size:
        raise InputError('out_of_bounds', f"field 'effort' of joint "
                         f'{shown(joint_names[huge[0]])} is {tau[huge[0]]:g}, beyond '
                         f'±{MAX_EFFORT:g} N m or N')
    return tau


def sample_time(sec: int, nanosec: int) -> Optional[float]:
    """Time (s) of a measurement from its header stamp; None for a zero stamp.

    The observer integrates over the time the state was measured, never over its receipt:
    transport jitter (a millisecond is common) is as large as a 1 kHz sample interval and
    would enter ``Δp/Δt`` in full. A zero stamp is "not stamped" (joint_state_broadcaster
    always stamps): such a message does not update the observer (``unstamped``). A lockstep
    simulator's state at time 0, republished while it waits for the first command, is
    skipped the same way; its first step starts the observer.
    """
    if sec == 0 and nanosec == 0:
        return None
    return sec + nanosec * 1e-9


class MomentumObserver:
    """Generalized-momentum observer of the external joint torques (see the module doc).

    Args:
        model: the robot (with its payload), order of ``model.joint_names``.
        gain: K_O in 1/s (> 0): time constant ``1/K_O``.
        armature: None or (n,) rotor inertia, kg m² (kg): added to ``M``.
        friction: None or ``friction(q̇) -> (n,)`` torque the joints lose (N m, N), e.g. the
            node's ``friction_model``.
        gravity: m/s² in the root-link frame.
        max_gap: a sample more than this many seconds after the previous one restarts the
            observer (the integral across a gap means nothing).
        backend: of the library calls (``'auto'``, ``'numpy'``, ``'compiled'``).

    :meth:`update` takes one sample and returns ``r`` (n,), N m or N; zeros on the first
    sample after a (re)start. ``resets`` counts the restarts, ``reset_reason`` says why the
    last one happened, ``samples`` counts the samples since it; ``refused_reason`` says why
    the last sample refused was (stamped closer than any sensor publishes).
    """

    def __init__(self, model: 'sd.Model', gain: float, armature: Optional[np.ndarray] = None,
                 friction: Optional[Friction] = None,
                 gravity: Sequence[float] = sd.GRAVITY, max_gap: float = math.inf,
                 backend: str = 'auto') -> None:
        if not (math.isfinite(gain) and gain > 0.0):
            raise ObserverError(f'observer gain must be a positive number of 1/s, got {gain}')
        self.model = model
        self.gain = float(gain)
        self.armature = None if armature is None else np.asarray(armature, dtype=float)
        self.friction = friction
        self.gravity = tuple(float(g) for g in gravity)
        self.max_gap = float(max_gap)
        self.backend = backend
        self.resets = 0
        self.reset_reason = ''
        self.refused_reason = ''
        self.reset()

    def reset(self, reason: str = '') -> None:
        """Forget the past: the next sample starts the observer again (``r`` = 0)."""
        if reason:
            self.resets += 1
            self.reset_reason = reason
        self.samples = 0
        self._t: Optional[float] = None
        self._p: Optional[np.ndarray] = None
        self._w: Optional[np.ndarray] = None
        self.r = np.zeros(len(self.model.joint_names))

    def momentum(self, q: np.ndarray, qd: np.ndarray, base: Optional['sd.BaseMotion'] = None
                 ) -> Tuple[np.ndarray, np.ndarray]:
        """``(p, β)``: ``p = (M + A) q̇`` and ``β = Cᵀ q̇ − g − friction(q̇)``.

        On a moving ``base`` (its twist and orientation; its acceleration is not used), the
        joint rows of the floating twin's (see the module doc).
        """
        if base is None:
            p, ctq = sd.generalized_momentum(self.model, q, qd, backend=self.backend)
            g = sd.gravity_torque(self.model, q, self.gravity, backend=self.backend)
        elif base.gravity_included:
            raise ObserverError("the observer needs the base's orientation for gravity, not an "
                                "IMU's specific force: give its twist and orientation")
        else:
            p, ctq = sd.generalized_momentum(self.model, q, qd, backend=self.backend,
                                             base=base)
            g = sd.gravity_torque(self.model, q, self.gravity, backend=self.backend,
                                  base=sd.BaseMotion.at_rest(base.orientation))
        beta = ctq - g
        if self.armature is not None:
            p = p + self.armature * qd
        if self.friction is not None:
            beta -= self.friction(qd)
        return p, beta

    def update(self, t: float, q: np.ndarray, qd: np.ndarray, tau: np.ndarray,
               base: Optional['sd.BaseMotion'] = None) -> Optional[np.ndarray]:
        """Take the sample ``(q, q̇, τ_m)`` measured at time ``t`` (s); return ``r`` (n,).

        ``base``: a moving base's motion at ``t`` (its twist and orientation), None for a
        fixed base.

        None when ``t`` equals the previous sample's time (the same measurement again:
        nothing new). A time before the previous one, or more than ``max_gap`` after it,
        restarts the observer at this sample. A time less than
        :data:`~spatial_dynamics.bounds.MIN_STAMP_INTERVAL` (10 µs: no joint sensor publishes
        faster than 100 kHz) after it is a clock's artefact, not a measurement: the sample is
        refused (``InputError`` ``interval_too_short``) and the observer keeps its state;
        ``Δp/Δt`` is only taken over intervals a sensor can give, and ``r`` moves by at most
        ``(1 − e^{−K Δt}) ȳ`` over them.
        """
        if self._t is not None:
            dt = t - self._t
            if dt == 0.0:
                return None
            if 0.0 < dt < MIN_STAMP_INTERVAL:
                self.refused_reason = (
                    f'a sample stamped {dt:.3g} s after the previous one, less than '
                    f'{MIN_STAMP_INTERVAL:g} s: no sensor publishes that fast (check the '
                    'header.stamp of joint_states); not integrated, the estimate kept')
                raise InputError('interval_too_short', self.refused_reason)
            if dt < 0.0:
                self.reset(f'time went backwards by {-dt:.6f} s')
            elif dt > self.max_gap:
                self.reset(f'gap of {dt:.3f} s between samples (more than {self.max_gap:g} s)')
        p, beta = self.momentum(q, qd, base)
        w = tau + beta
        if self._t is not None:
            dt = t - self._t
            y = (p - self._p) / dt - 0.5 * (w + self._w)   # mean τ_ext over the step
            decay = math.exp(-self.gain * dt)
            self.r = decay * self.r + (1.0 - decay) * y
        self._t, self._p, self._w = t, p, w
        self.samples += 1
        return self.r


class EstimateWindow:
    """The estimates of one diagnostics period: count and per-joint sum of squares."""

    def __init__(self, n: int = 0) -> None:
        self.count = 0
        self.sum_squares = np.zeros(n)
        self.skipped = {reason: 0 for reason in SKIP_REASONS}
        self.wrench: Optional[dict] = None   # the virtual F/T sensor's period (add_wrench)

    def add_wrench(self, link: str, estimate, loaded: bool) -> None:
        """Count one published wrench estimate (:class:`~spatial_dynamics.wrench.WrenchEstimate`).

        Keeps the link, the samples with a weak (unobservable or damped) direction and those
        of them ``loaded`` (an external torque above ``external_torque_warn``: a wrench the
        sensor may misread), the smallest ``sigma_min`` and the rank of the period.
        """
        w = self.wrench
        if w is None or w['link'] != link:
            w = self.wrench = {'link': link, 'count': 0, 'weak': 0, 'weak_loaded': 0,
                               'sigma_min': math.inf, 'rank': 6, 'last_weak': None}
        w['count'] += 1
        w['sigma_min'] = min(w['sigma_min'], float(estimate.sigma_min))
        w['rank'] = min(w['rank'], int(estimate.rank))
        if estimate.weak.any():
            w['weak'] += 1
            w['weak_loaded'] += loaded
            w['last_weak'] = estimate.unobservable()

    def add(self, r: np.ndarray) -> None:
        """Count one published estimate."""
        if self.sum_squares.shape != r.shape:   # first estimate, or a model with other joints
            self.count, self.sum_squares = 0, np.zeros(r.shape)
        self.count += 1
        self.sum_squares += r * r

    def rms(self) -> Optional[np.ndarray]:
        """RMS per joint of the period's estimates, or None when there were none."""
        return np.sqrt(self.sum_squares / self.count) if self.count else None


# --------------------------------------------------------------------------------------------
# The node's observer: what it depends on

def observer_key(robot: Robot, params) -> tuple:
    """Return what the estimate depends on; the node restarts the observer when it changes.

    The model (the base, by identity: a parameter change that does not re-parse keeps it),
    payload, armature, friction model, and of the node's ``params`` gravity, gain, the gap
    that restarts it (``measured_timeout``) and what the measured effort holds; not the
    backend (the compiled kernels compute the same numbers).
    """
    armature = None if robot.armature is None else robot.armature.tobytes()
    return (id(robot.base), robot.payload, armature, robot.friction_threshold,
            tuple(params.gravity), params.observer_gain, params.measured_timeout,
            params.measured_effort)


def make_observer(robot: Robot, params) -> MomentumObserver:
    """Return the observer of ``robot``'s model (payload included) with the node's terms."""
    model, threshold = robot.model, robot.friction_threshold
    friction = None if threshold is None else (
        lambda qd: sd.friction_torque(model, qd, threshold))
    return MomentumObserver(model, params.observer_gain, robot.armature, friction,
                            params.gravity, params.measured_timeout, robot.backend)
