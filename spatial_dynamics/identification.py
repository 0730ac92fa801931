# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Which inertial parameters a robot's torques can tell: the base parameters.

The torques are linear in the standard parameters ``π`` of the moving bodies (``τ = Y π``,
:func:`spatial_dynamics.regressor`), but not every column of ``Y`` is independent: a body's
mass on a joint whose axis is along gravity never loads a joint, the mass of a link and the
first moment of its parent enter only as a sum, and so on. Stacking ``Y`` over many states
``W`` and taking a QR decomposition with column pivoting, ``W P = Q [R₁ R₂]`` (Gautier 1990,
the numerical route), gives the rank ``r`` and splits the columns into ``r`` independent ones
(``P[:r]``) and the rest, each a combination of those: ``W_dep = W_ind K`` with
``K = R₁⁻¹ R₂``. Then

    τ = W_ind β,   β = π_ind + K π_dep

so the ``r`` base parameters ``β`` are what a recording can determine, each named as its
combination ("I_zz of link1 + 0.0841 · m of link2 …"), and a column that is zero over every
state is a parameter no torque depends on at all.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import List, Optional, Sequence, Tuple

import numpy as np

from .algorithms.regressor import parameters, PARAMETERS
from .backends import regressor, rnea
from .model import Model

#: A pivot of ``R`` below ``RTOL`` times the largest counts as zero (the rank's threshold).
RTOL = 1e-9
#: Coefficients of ``K`` below this are dropped from the names (not from ``K``).
SHOWN = 1e-9


@dataclass(frozen=True)
class BaseParameters:
    """The base parameters of a model: see the module docstring.

    Attributes:
        names: (10·NB,) the standard parameters, ``'<parameter> of <link>'``.
        independent: (r,) indices into ``π`` of the columns kept, in pivot order.
        dependent: (p − r,) indices of the others.
        K: (r, p − r): ``β = π[independent] + K @ π[dependent]``.
        unexcited: indices of the parameters whose column is zero in every state: no torque
            depends on them (they are among ``dependent``, with a zero column of ``K``).
    """

    names: Tuple[str, ...]
    independent: np.ndarray
    dependent: np.ndarray
    K: np.ndarray
    unexcited: np.ndarray

    @property
    def rank(self) -> int:
        """The number of base parameters."""
        return len(self.independent)

    def beta(self, pi: np.ndarray) -> np.ndarray:
        """Return the base parameters ``β`` (r,) of standard parameters ``π`` (10·NB,)."""
        pi = np.asarray(pi, dtype=float)
        return pi[self.independent] + self.K @ pi[self.dependent]

    def columns(self, Y: np.ndarray) -> np.ndarray:
        """Return the base regressor ``Y[..., independent]``: τ is it times ``beta(π)``."""
        return np.asarray(Y)[..., self.independent]

    def describe(self, k: int) -> str:
        """Name base parameter ``k`` as its combination of standard parameters."""
        text = self.names[self.independent[k]]
        for j, c in enumerate(self.K[k]):
            if abs(c) > SHOWN:
                sign = '+' if c > 0 else '-'
                text += f' {sign} {abs(c):.4g} · {self.names[self.dependent[j]]}'
        return text

    def unexcited_names(self) -> List[str]:
        """Name the parameters no torque depends on."""
        return [self.names[i] for i in self.unexcited]


def parameter_names(model: Model) -> Tuple[str, ...]:
    """Return ``'<parameter> of <link>'`` for every standard parameter, in ``π``'s order."""
    return tuple(f'{p} of {link}' for link in model.body_names[1:] for p in PARAMETERS)


def random_states(model: Model, count: int, seed: int = 0) -> Tuple[np.ndarray, ...]:
    """``count`` states ``(q, q̇, q̈)`` spread over the joint limits (±π when unlimited)."""
    rng = np.random.default_rng(seed)
    n = len(model.joint_names)
    lo = np.where(np.isfinite(model.lower), model.lower, -np.pi)
    hi = np.where(np.isfinite(model.upper), model.upper, np.pi)
    q = rng.uniform(lo, hi, size=(count, n))
    qd = rng.uniform(-2.0, 2.0, size=(count, n))
    qdd = rng.uniform(-5.0, 5.0, size=(count, n))
    return q, qd, qdd


def base_parameters(model: Model, states: Optional[Sequence[np.ndarray]] = None,
                    gravity: Sequence[float] = (0.0, 0.0, -9.81), rtol: float = RTOL,
                    count: int = 400, seed: int = 0) -> BaseParameters:
    """Find the base parameters from the stacked regressor of ``states`` ``(q, q̇, q̈)``.

    Without ``states``, ``count`` random ones over the joint limits: what a well exciting
    recording can determine. With a recording's states, what that recording can.
    """
    from scipy.linalg import qr
    q, qd, qdd = random_states(model, count, seed) if states is None else states
    W = regressor(model, q, qd, qdd, gravity).reshape(-1, 10 * model.NB)
    scale = np.linalg.norm(W, axis=0)
    unexcited = np.flatnonzero(scale <= rtol * scale.max())
    R, P = qr(W, mode='r', pivoting=True)
    d = np.abs(np.diag(R))
    r = int(np.sum(d > rtol * d[0]))
    K = np.linalg.solve(R[:r, :r], R[:r, r:])
    K[np.abs(K) < 1e-12] = 0.0
    return BaseParameters(parameter_names(model), P[:r].copy(), P[r:].copy(), K, unexcited)


#: A base parameter the recording excites less than WEAK times as well as random motion over
#: the joint limits does (in the recording's direction least like the others) counts as not
#: determined: its error is the recording's noise, and whatever the model does not capture,
#: amplified ten times or more. Measured on the simulated UR5: plans of ``replay excite`` (12
#: and 20 s) have every pivot above 0.16, two sines on every joint above 0.47; the two base
#: joints alone have three below 0.1 (0.018, 0.075, 0.087), and that fit is off by up to
#: 5 N m on other motion.
WEAK = 0.1


def poorly_excited(model: Model, states: Sequence[np.ndarray], bodies: Sequence[int],
                   gravity: Sequence[float] = (0.0, 0.0, -9.81), weak: float = WEAK,
                   samples: int = 4000) -> List[str]:
    """Name the base parameters of ``bodies`` a recording's ``states`` do not determine.

    The structural base parameters (:func:`base_parameters` over random states, what any
    motion could determine) are the columns; each is scaled so that random motion over the
    joint limits gives it unit RMS per sample; a pivoted QR of the recording's scaled base
    regressor (at most ``samples`` states, evenly spaced) then finds the combinations whose
    pivot is below ``weak``: what this recording leaves to the URDF (or to chance).
    """
    from scipy.linalg import qr
    structural = base_parameters(model, gravity=gravity)
    wanted = set(int(i) for i in bodies)

    def involved(k):
        used = [structural.independent[k]] + [
            d for d, c in zip(structural.dependent, structural.K[k]) if abs(c) > SHOWN]
        return {int(i) // 10 + 1 for i in used}

    keep = [k for k in range(structural.rank) if involved(k) & wanted]
    if not keep:
        return []
    q, qd, qdd = (np.atleast_2d(np.asarray(x, dtype=float)) for x in states)
    step = max(1, len(q) // samples)
    W = structural.columns(regressor(model, q[::step], qd[::step], qdd[::step], gravity)
                           ).reshape(-1, structural.rank)
    Wr = structural.columns(regressor(model, *random_states(model, 400, seed=1), gravity)
                            ).reshape(-1, structural.rank)
    # column k then has norm (RMS in the recording) / (RMS under random motion)
    scale = np.linalg.norm(Wr, axis=0) * np.sqrt(len(W) / len(Wr))
    R, P = qr(W / scale, mode='r', pivoting=True)
    d = np.zeros(structural.rank)
    d[P[:min(R.shape)]] = np.abs(np.diag(R))
    return [structural.describe(k) for k in keep if d[k] < weak]


# --------------------------------------------------------------------------------------------
# Payload: the ten parameters of one rigid body added to a link

def _spatial_inertia(pi: np.ndarray) -> np.ndarray:
    """Return the 6×6 spatial inertia ``[[Ī, h×], [-h×, m 1]]`` of the parameters ``pi``."""
    m, hx, hy, hz, ixx, ixy, iyy, ixz, iyz, izz = pi
    h = np.array([[0.0, -hz, hy], [hz, 0.0, -hx], [-hy, hx, 0.0]])
    out = np.zeros((6, 6))
    out[:3, :3] = [[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]
    out[:3, 3:] = h
    out[3:, :3] = -h
    out[3:, 3:] = m * np.eye(3)
    return out


def _ten(inertia: np.ndarray) -> np.ndarray:
    """Return the ten parameters of a 6×6 spatial inertia (:func:`_spatial_inertia` inverted)."""
    hx = inertia[:3, 3:]
    return np.array([inertia[3, 3], hx[2, 1], hx[0, 2], hx[1, 0], inertia[0, 0],
                     inertia[0, 1], inertia[1, 1], inertia[0, 2], inertia[1, 2], inertia[2, 2]])


def mass_com_inertia(pi: np.ndarray) -> Tuple[float, np.ndarray, np.ndarray]:
    """Return the mass, centre of mass (3,) and inertia about it (3×3) of ten parameters.

    The inverse of the parallel-axis step: ``Ī = I_c + m (cᵀc 1 − c cᵀ)`` (RBDA 2.63); a body
    without mass has its centre at the origin.
    """
    m = float(pi[0])
    c = pi[1:4] / m if m > 0 else np.zeros(3)
    ixx, ixy, iyy, ixz, iyz, izz = pi[4:]
    about_origin = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    return m, c, about_origin - m * (c @ c * np.eye(3) - np.outer(c, c))


def link_to_body(model: Model, link: str) -> Tuple[int, np.ndarray]:
    """``(body, T)``: parameters on ``link`` (its frame) add ``T @ π`` to ``body``'s (10×10).

    ``ValueError`` naming the link, and the links that can be used, when it is no link of
    the model or moves with no joint (the fixed base, or a link fixed to it: no torque
    depends on its inertia).
    """
    frame = model.frames.get(link)
    usable = (f'the links that move: {", ".join(model.body_names[1:])} (or a link fixed to '
              'one of them)')
    if frame is None:
        raise ValueError(f'link {link!r} is not a link of {model.name!r}; {usable}')
    if frame.body == 0:
        where = ('is the fixed base' if link == model.body_names[0] else
                 f'is fixed to the base {model.body_names[0]!r}')
        raise ValueError(f'link {link!r} does not move with any joint (it {where}): no torque '
                         f'depends on its inertia; {usable}')
    X = frame.lXb
    T = np.column_stack([_ten(X.T @ _spatial_inertia(e) @ X) for e in np.eye(10)])
    return frame.body, T


@dataclass(frozen=True)
class Payload:
    """A payload identified on ``link``: mass (kg), centre of mass (m, link frame), inertia.

    ``inertia`` is ``[ixx, ixy, ixz, iyy, iyz, izz]`` about the centre of mass (kg m², the
    node's ``payload.inertia`` order); ``pi`` the ten parameters in the link frame and
    ``covariance`` (10×10) their covariance from the fit's residual; ``rms`` the residual per
    joint after the fit. With the drives fitted jointly, ``drives`` is ``(damping, friction,
    armature)`` per joint (each (n,)), else None.
    """

    link: str
    mass: float
    com: np.ndarray
    inertia: np.ndarray
    pi: np.ndarray
    covariance: np.ndarray
    rms: np.ndarray
    drives: Optional[Tuple[np.ndarray, np.ndarray, np.ndarray]] = None

    @property
    def sigma(self) -> np.ndarray:
        """One standard deviation of each of the ten parameters."""
        return np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))

    def node_parameters(self) -> str:
        """Return the node's ``payload.*`` parameters, as a YAML block."""
        fmt = ', '.join
        return (f'payload.link: {self.link}\npayload.mass: {self.mass:.6g}\n'
                f'payload.com: [{fmt(f"{x:.6g}" for x in self.com)}]\n'
                f'payload.inertia: [{fmt(f"{x:.6g}" for x in self.inertia)}]\n')

    def urdf_inertial(self) -> str:
        """Return a URDF ``<inertial>`` of the payload (for a link, or a fixed child of it)."""
        ixx, ixy, ixz, iyy, iyz, izz = self.inertia
        x, y, z = self.com
        return (f'<inertial>\n  <origin xyz="{x:.6g} {y:.6g} {z:.6g}" rpy="0 0 0"/>\n'
                f'  <mass value="{self.mass:.6g}"/>\n'
                f'  <inertia ixx="{ixx:.6g}" ixy="{ixy:.6g}" ixz="{ixz:.6g}" iyy="{iyy:.6g}" '
                f'iyz="{iyz:.6g}" izz="{izz:.6g}"/>\n</inertial>')


def identify_payload(model: Model, link: str, q, qd, qdd, tau,
                     gravity: Sequence[float] = (0.0, 0.0, -9.81),
                     drive_threshold: Optional[float] = None) -> Payload:
    """Fit a rigid payload on ``link`` to measured torques ``tau`` (N, n), by least squares.

    ``model`` is the robot without the payload; the residual ``tau − rnea(model)`` is
    ``Y_body T π`` for the payload's ten parameters ``π`` in the link frame
    (:func:`link_to_body`). With ``drive_threshold`` (the smooth-sign velocity, rad/s) each
    joint's damping, Coulomb friction and armature (the node's drive terms) are fitted in the
    same least squares, so they cannot absorb the payload. Raises ``ValueError`` when the
    states cannot tell the payload (the columns are rank deficient).
    """
    q, qd, qdd, tau = (np.atleast_2d(np.asarray(x, dtype=float)) for x in (q, qd, qdd, tau))
    body, T = link_to_body(model, link)
    Y_all = regressor(model, q, qd, qdd, gravity)
    Y = Y_all[..., 10 * (body - 1):10 * body] @ T
    r = tau - Y_all @ parameters(model)
    A, b = Y.reshape(-1, 10), r.reshape(-1)
    n = q.shape[-1]
    if drive_threshold is not None:       # rows are (sample, joint): joint j's own columns
        A = np.hstack([A, _drive_columns(qd, qdd, drive_threshold).reshape(-1, 3 * n)])
    x, _, rank, _ = np.linalg.lstsq(A, b, rcond=None)
    pi = x[:10]
    if rank < A.shape[1]:
        what = ('10 payload parameters' if A.shape[1] == 10 else
                f'{A.shape[1]} parameters (10 of the payload, 3 of each drive)')
        raise ValueError(f'the recording determines only {rank} of the {what} on {link!r}: '
                         'move the joints between the base and it more (rotate the payload '
                         'about several axes, with accelerations; reverse every joint)')
    fit = b - A @ x
    dof = max(len(b) - A.shape[1], 1)
    covariance = ((fit @ fit / dof) * np.linalg.inv(A.T @ A))[:10, :10]
    if not pi[0] > 0.0:
        raise ValueError(f'identified payload mass {pi[0]:.3g} kg on {link!r} is not positive')
    m, c, Ic = mass_com_inertia(pi)
    inertia = np.array([Ic[0, 0], Ic[0, 1], Ic[0, 2], Ic[1, 1], Ic[1, 2], Ic[2, 2]])
    rms = np.sqrt(np.mean(fit.reshape(r.shape) ** 2, axis=0))
    drives = None if drive_threshold is None else tuple(x[10 + k::3] for k in range(3))
    return Payload(link, float(m), c, inertia, pi, covariance, rms, drives)


# --------------------------------------------------------------------------------------------
# Inertial parameters of the links: physically consistent least squares

def pseudo_inertia(pi: np.ndarray) -> np.ndarray:
    """Return the 4×4 pseudo-inertia ``[[Σ, h], [hᵀ, m]]`` of ten parameters (Wensing 2017).

    ``Σ = ½ tr(Ī) 1 − Ī`` is the second moment of the mass about the frame's origin; a body is
    physically realisable (a non-negative mass density) exactly when this matrix is positive
    semi-definite, which covers positive mass and the triangle inequalities.
    """
    m, hx, hy, hz, ixx, ixy, iyy, ixz, iyz, izz = pi
    Ibar = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    J = np.zeros((4, 4))
    J[:3, :3] = 0.5 * np.trace(Ibar) * np.eye(3) - Ibar
    J[:3, 3] = J[3, :3] = (hx, hy, hz)
    J[3, 3] = m
    return J


def from_pseudo_inertia(J: np.ndarray) -> np.ndarray:
    """Return the ten parameters of a pseudo-inertia (:func:`pseudo_inertia` inverted)."""
    S = J[:3, :3]
    Ibar = np.trace(S) * np.eye(3) - S
    return np.array([J[3, 3], J[0, 3], J[1, 3], J[2, 3], Ibar[0, 0], Ibar[0, 1],
                     Ibar[1, 1], Ibar[0, 2], Ibar[1, 2], Ibar[2, 2]])


_TRIU = np.triu_indices(4)


def log_cholesky(pi: np.ndarray, floor: float = 1e-9) -> np.ndarray:
    """Return the log-Cholesky coordinates θ (10,) of ``pi``: ``J = U Uᵀ``, log of U's diagonal.

    ``from_log_cholesky(θ)`` gives ``pi`` back.

    (Rucker and Wensing 2022.) A ``pi`` that is not realisable is first moved to the
    nearest realisable one (its pseudo-inertia's negative eigenvalues raised to ``floor``).
    """
    J = pseudo_inertia(pi)
    w, V = np.linalg.eigh(J)
    J = (V * np.maximum(w, floor * max(1.0, w.max()))) @ V.T
    # J = U Uᵀ with U upper triangular: the Cholesky factor of J with rows/columns reversed
    P = np.eye(4)[::-1]
    U = P @ np.linalg.cholesky(P @ J @ P) @ P
    theta = U[_TRIU].copy()
    diag = [k for k, (i, j) in enumerate(zip(*_TRIU)) if i == j]
    theta[diag] = np.log(theta[diag])
    return theta


#: |log| of U's diagonal beyond which a trial step of the solver is cut (e^±40: far beyond
#: any body; the cut keeps a wild step finite, so the solver rejects it instead of failing).
LOG_LIMIT = 40.0


def from_log_cholesky(theta: np.ndarray) -> np.ndarray:
    """Return the ten parameters of ``θ`` (:func:`log_cholesky`): always realisable."""
    U = np.zeros((4, 4))
    U[_TRIU] = theta
    U[np.diag_indices(4)] = np.exp(np.clip(np.diag(U), -LOG_LIMIT, LOG_LIMIT))
    return from_pseudo_inertia(U @ U.T)


def log_cholesky_jacobian(theta: np.ndarray) -> np.ndarray:
    """Return ``∂π/∂θ`` (10×10) of :func:`from_log_cholesky` (exact: π is linear in J)."""
    U = np.zeros((4, 4))
    U[_TRIU] = theta
    U[np.diag_indices(4)] = np.exp(np.clip(np.diag(U), -LOG_LIMIT, LOG_LIMIT))
    out = np.zeros((10, 10))
    for k, (i, j) in enumerate(zip(*_TRIU)):
        dU = np.zeros((4, 4))
        dU[i, j] = U[i, j] if i == j else 1.0
        out[:, k] = from_pseudo_inertia(dU @ U.T + U @ dU.T)
    return out


#: Samples whose regressor rows are formed at once: the stacked regressor of an hour at 1 kHz
#: would take gigabytes, its running triangle a few kilobytes.
CHUNK = 20_000


def _drive_columns(qd: np.ndarray, qdd: np.ndarray, threshold: float) -> np.ndarray:
    """Return (N, n, 3n): joint j's damping, Coulomb friction and armature columns."""
    N, n = qd.shape
    drive = np.zeros((N, n, 3 * n))
    for j in range(n):
        drive[:, j, 3 * j] = qd[:, j]
        drive[:, j, 3 * j + 1] = np.tanh(qd[:, j] / threshold)
        drive[:, j, 3 * j + 2] = qdd[:, j]
    return drive


def drive_torque(qd, qdd, drives, threshold: float) -> np.ndarray:
    """Return ``damping q̇ + friction tanh(q̇/threshold) + armature q̈`` per joint."""
    damping, friction, armature = drives
    return damping * qd + friction * np.tanh(qd / threshold) + armature * qdd


def with_bodies(model: Model, inertias) -> Model:
    """Return ``model`` with the spatial inertias of some bodies replaced (body → 6×6)."""
    inertia = np.array(model.inertia)
    for body, value in inertias.items():
        inertia[body] = value
    return replace(model, inertia=inertia)


def predicted_torque(model: Model, q, qd, qdd, gravity, drives=None,
                     threshold: Optional[float] = None) -> np.ndarray:
    """Return ``rnea(model)`` plus, with ``drives``, :func:`drive_torque`."""
    tau = rnea(model, q, qd, qdd, gravity)
    if drives is not None:
        tau = tau + drive_torque(qd, qdd, drives, threshold)
    return tau


def _square_root(model: Model, states, tau: np.ndarray, gravity, cols: np.ndarray,
                 pi0: np.ndarray, drive_threshold: Optional[float]) -> np.ndarray:
    """Return ``F`` with ``Fᵀ F = [A b]ᵀ [A b]``, the recording summed chunk by chunk.

    ``A`` is the regressor's ``cols`` (then the drive columns), ``b`` the torque less what the
    other columns give with ``pi0``; then ``|A x − b|² = |F[:, :-1] x − F[:, -1]|²``: the fit
    runs on as many rows as unknowns, whatever the length of the recording. The Gram matrix
    is summed (one matrix product per chunk: a QR of each chunk costs ten times more) and
    factored at the end by an eigendecomposition after equilibrating its columns; it loses
    the accuracy of directions the data barely sees, far below the regularisation that
    decides those directions anyway (``test_identification``: the same fit as a QR of the
    stacked rows).
    """
    from scipy.linalg.blas import dsyrk
    q, qd, qdd = states
    fixed = np.setdiff1d(np.arange(10 * model.NB), cols)
    every = len(fixed) == 0 and np.array_equal(cols, np.arange(10 * model.NB))
    n = q.shape[-1]
    width = len(cols) + (3 * n if drive_threshold is not None else 0) + 1
    G = np.zeros((width, width))
    for a in range(0, len(q), CHUNK):
        part = slice(a, a + CHUNK)
        Y = regressor(model, q[part], qd[part], qdd[part], gravity).reshape(-1, 10 * model.NB)
        M = np.empty((len(Y), width))        # [A | drives | b], filled in place
        M[:, :len(cols)] = Y if every else Y[:, cols]
        if drive_threshold is not None:
            M[:, len(cols):-1] = _drive_columns(qd[part], qdd[part], drive_threshold
                                                ).reshape(len(Y), -1)
        M[:, -1] = tau[part].reshape(-1)
        if len(fixed):
            M[:, -1] -= Y[:, fixed] @ pi0[fixed]
        # Mᵀ M, its upper triangle (BLAS syrk: half of a matrix product's work)
        G += dsyrk(1.0, M.T, trans=0)
    G = np.triu(G) + np.triu(G, 1).T
    d = np.sqrt(np.diag(G))
    d[d == 0.0] = 1.0
    w, V = np.linalg.eigh(G / d[:, None] / d[None, :])
    return (np.sqrt(np.clip(w, 0.0, None))[:, None] * V.T) * d[None, :]


@dataclass(frozen=True)
class Inertias:
    """Identified inertial parameters of the model's bodies (see :func:`identify_inertias`).

    Attributes:
        pi: (10·NB,) every body's parameters (the fitted ones replaced, the rest the URDF's).
        bodies: the body indices fitted (1..NB).
        before, after: (n,) RMS of the residual per joint with the URDF's and the fitted π
            (and drives).
        covariance: (10·len(bodies), 10·len(bodies)) the fitted parameters' covariance,
            from the residual and the regularised normal equations.
        drives: ``(damping, friction, armature)`` per joint, or None.
        drive_threshold: the friction's smooth-sign velocity, with ``drives``.
        undetermined: (10·len(bodies),) 0 when the data determines the parameter by itself,
            1 when it does not (it is in no combination the data sees, or only in
            combinations with others, and the regularisation toward the URDF chose its
            value): ``diag((AᵀA + W²)⁻¹ W²)``.
    """

    pi: np.ndarray
    bodies: Tuple[int, ...]
    before: np.ndarray
    after: np.ndarray
    covariance: np.ndarray
    drives: Optional[Tuple[np.ndarray, np.ndarray, np.ndarray]] = None
    drive_threshold: Optional[float] = None
    undetermined: Optional[np.ndarray] = None

    @property
    def sigma(self) -> np.ndarray:
        """One standard deviation of each fitted parameter (bodies in order, ten each)."""
        return np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))

    def model(self, model: Model) -> Model:
        """Return ``model`` with the identified inertias (drives are not part of a model)."""
        return with_bodies(model, {i: _spatial_inertia(self.pi[10 * (i - 1):10 * i])
                                   for i in self.bodies})


def identify_inertias(model: Model, q, qd, qdd, tau, links: Optional[Sequence[str]] = None,
                      gravity: Sequence[float] = (0.0, 0.0, -9.81),
                      drive_threshold: Optional[float] = None,
                      regularisation: float = 1e-3) -> Inertias:
    """Fit the inertial parameters of ``links`` (default: every moving body) to ``tau``.

    Least squares (:func:`scipy.optimize.least_squares`, trust region, the exact Jacobian,
    unscaled: scaling by the Jacobian's columns sends the barely excited ones flying) on
    ``Y π(θ) (+ drives) − τ`` with every fitted body in the log-Cholesky
    parameters ``θ`` (so each stays physically realisable whatever the data), plus
    ``regularisation`` · (π − π_URDF), scaled by the regressor's column norms: where the data
    says nothing (a combination no motion excites) the URDF's values stay. With
    ``drive_threshold`` each joint's damping, Coulomb friction (``tanh(q̇/threshold)``) and
    armature are fitted jointly. The recording is reduced chunk by chunk to a triangle
    (:func:`_square_root`), so its length costs time, not memory.
    """
    from scipy.optimize import least_squares
    q, qd, qdd, tau = (np.atleast_2d(np.asarray(x, dtype=float)) for x in (q, qd, qdd, tau))
    n = q.shape[-1]
    if links is None:
        bodies = tuple(range(1, model.NB + 1))
    else:
        bodies = tuple(sorted({link_to_body(model, link)[0] for link in links}))
    pi0 = parameters(model)
    cols = np.concatenate([np.arange(10 * (i - 1), 10 * i) for i in bodies])
    F = _square_root(model, (q, qd, qdd), tau, gravity, cols, pi0, drive_threshold)
    R, c = F[:, :-1], F[:, -1]
    nb = 10 * len(bodies)
    ndrive = R.shape[1] - nb
    scale = np.linalg.norm(R[:, :nb], axis=0)            # = the column norms of A
    weight = regularisation * np.where(scale > 0, scale, scale.max() or 1.0)
    theta0 = np.concatenate([log_cholesky(pi0[10 * (i - 1):10 * i]) for i in bodies])

    def pi_of(x):
        return np.concatenate([from_log_cholesky(x[10 * k:10 * k + 10])
                               for k in range(len(bodies))])

    def residual(x):
        p = pi_of(x[:nb])
        full = np.concatenate([p, x[nb:]])
        return np.concatenate([R @ full - c, weight * (p - pi0[cols])])

    def jacobian(x):
        D = np.zeros((nb, nb))
        for k in range(len(bodies)):
            D[10 * k:10 * k + 10, 10 * k:10 * k + 10] = log_cholesky_jacobian(
                x[10 * k:10 * k + 10])
        top = np.hstack([R[:, :nb] @ D, R[:, nb:]])
        bottom = np.hstack([weight[:, None] * D, np.zeros((nb, ndrive))])
        return np.vstack([top, bottom])

    x0 = np.concatenate([theta0, np.zeros(ndrive)])
    result = least_squares(residual, x0, jac=jacobian, method='trf', x_scale=1.0)
    pi = pi0.copy()
    fitted = pi_of(result.x[:nb])
    pi[cols] = fitted
    drives = None if not ndrive else tuple(result.x[nb + k::3] for k in range(3))
    found = Inertias(pi, bodies, np.zeros(n), np.zeros(n), np.zeros((nb, nb)), drives,
                     drive_threshold if ndrive else None)
    corrected = found.model(model)     # built once: each new model has its own kernels
    before, after = np.zeros(n), np.zeros(n)
    for a in range(0, len(q), CHUNK):
        part = slice(a, a + CHUNK)
        states = q[part], qd[part], qdd[part]
        before += np.sum((tau[part] - rnea(model, *states, gravity)) ** 2, axis=0)
        after += np.sum((tau[part] - predicted_torque(corrected, *states, gravity, drives,
                                                      drive_threshold)) ** 2, axis=0)
    rows = tau.size
    # the covariance of the linearised, regularised estimate: s² (AᵀA + W²)⁻¹
    s2 = float(after.sum()) / max(rows - R.shape[1], 1)
    normal = R.T @ R
    normal[np.arange(nb), np.arange(nb)] += weight ** 2
    inverse = np.linalg.pinv(normal)[:nb, :nb]
    return replace(found, before=np.sqrt(before / len(q)), after=np.sqrt(after / len(q)),
                   covariance=s2 * inverse,
                   undetermined=np.clip(np.diag(inverse) * weight ** 2, 0.0, 1.0))
