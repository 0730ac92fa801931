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

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace
from typing import List, Optional, Sequence, Tuple

import numpy as np

from .algorithms.regressor import parameters, PARAMETERS
from .backends import compiled, regressor, rnea
from .base import BaseMotion, check_base_motion
from .model import Model
from .text import shown

# SciPy (seconds to import) and threadpoolctl (the identify extra) are imported inside the fits
# that use them: the package, and commands that never fit, start without them.

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
    """Return ``'<parameter> of <link>'`` for every standard parameter, in ``π``'s order.

    The link as :func:`~spatial_dynamics.text.shown` writes it (escaped, cut): these
    names are printed (a link's name comes from a URDF).
    """
    return tuple(f'{p} of {shown(link, quote=False)}' for link in model.body_names[1:]
                 for p in PARAMETERS)


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
        raise ValueError(f'link {shown(link)} is not a link of {shown(model.name)}; {usable}')
    if frame.body == 0:
        where = ('is the fixed base' if link == model.body_names[0] else
                 f'is fixed to the base {shown(model.body_names[0])}')
        raise ValueError(f'link {shown(link)} does not move with any joint (it {where}): no '
                         f'torque depends on its inertia; {usable}')
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
                     drive_threshold: Optional[float] = None,
                     base: Optional[BaseMotion] = None) -> Payload:
    """Fit a rigid payload on ``link`` to measured torques ``tau`` (N, n), by least squares.

    ``model`` is the robot without the payload; the residual ``tau − rnea(model)`` is
    ``Y_body T π`` for the payload's ten parameters ``π`` in the link frame
    (:func:`link_to_body`). With ``drive_threshold`` (the smooth-sign velocity, rad/s) each
    joint's damping, Coulomb friction and armature (the node's drive terms) are fitted in the
    same least squares, so they cannot absorb the payload. ``base``: the base's motion at
    each sample (a mobile manipulator), as for :func:`~spatial_dynamics.rnea`. Raises
    ``ValueError`` when the states cannot tell the payload (the columns are rank deficient).
    """
    if base is not None:
        check_base_motion(base, model)
    q, qd, qdd, tau = (np.atleast_2d(np.asarray(x, dtype=float)) for x in (q, qd, qdd, tau))
    body, T = link_to_body(model, link)
    Y_all = regressor(model, q, qd, qdd, gravity, base=base)
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
        raise ValueError(f'the recording determines only {rank} of the {what} on {shown(link)}: '
                         'move the joints between the base and it more (rotate the payload '
                         'about several axes, with accelerations; reverse every joint)')
    fit = b - A @ x
    dof = max(len(b) - A.shape[1], 1)
    covariance = ((fit @ fit / dof) * np.linalg.inv(A.T @ A))[:10, :10]
    if not pi[0] > 0.0:
        raise ValueError(f'identified payload mass {pi[0]:.3g} kg on {shown(link)} is not '
                         'positive')
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


#: Samples whose regressor rows are formed at once: small enough that the rows stay in the
#: cache and their buffers are reused (20 000 samples of a 7-joint arm took 78 MB, new pages
#: each time: 9 µs a sample, 4 µs with 2 000); an hour at 1 kHz never lies in memory whole.
CHUNK = 2048
#: Samples whose torques are computed at once (a few MB).
RNEA_CHUNK = 1 << 16


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
                     threshold: Optional[float] = None,
                     base: Optional[BaseMotion] = None) -> np.ndarray:
    """Return ``rnea(model)`` (on ``base``) plus, with ``drives``, :func:`drive_torque`."""
    tau = rnea(model, q, qd, qdd, gravity, base=base)
    if drives is not None:
        tau = tau + drive_torque(qd, qdd, drives, threshold)
    return tau


def base_rows(base: Optional[BaseMotion], rows) -> Optional[BaseMotion]:
    """Return the base's motion at samples ``rows`` (an index or slice) of a recording."""
    if base is None:
        return None

    def part(x):
        return x if x is None or x.ndim == 1 else x[rows]
    return BaseMotion(part(base.v), part(base.a), part(base.orientation), base.gravity_included)


def _touches(model: Model) -> np.ndarray:
    """Return (n, NB+1) bools: joint ``j``'s torque depends on body ``i``'s parameters.

    Body ``i`` loads the joints of its ancestors and its own (RBDA's backward pass carries
    ``fᵢ`` to the root): every other entry of the regressor's row ``j`` is zero.
    """
    touches = np.zeros((len(model.joint_names), model.NB + 1), dtype=bool)
    for i in range(1, model.NB + 1):
        b = i
        while b > 0:
            touches[model.qidx[b], i] = True
            b = model.parent[b]
    return touches


def _square_root(model: Model, states, tau: np.ndarray, gravity, cols: np.ndarray,
                 pi0: np.ndarray, drive_threshold: Optional[float],
                 base: Optional[BaseMotion] = None) -> np.ndarray:
    """Return ``F`` with ``Fᵀ F = [A b]ᵀ [A b]``, the recording summed chunk by chunk.

    ``A`` is the regressor's ``cols`` (then the drive columns), ``b`` the torque less what the
    other columns give with ``pi0``; then ``|A x − b|² = |F[:, :-1] x − F[:, -1]|²``: the fit
    runs on as many rows as unknowns, whatever the length of the recording. The Gram matrix
    is summed joint by joint, each joint's rows over only the columns its torque depends on
    (:func:`_touches`; its own drive terms, the torque), and factored at the end by an
    eigendecomposition after equilibrating its columns; it loses the accuracy of directions
    the data barely sees, far below the regularisation that decides those directions anyway
    (``test_ident_inertias``: the same fit as a QR of the stacked rows). The chunks are
    shared by ``compiled.THREADS`` threads, each summing its own (every such chunk) in a
    fixed order: the result does not depend on the timing. Call it with the BLAS on one
    thread (:func:`identify_inertias` does): these threads are the parallelism.
    """
    from scipy.linalg.blas import dsyrk
    q, qd, qdd = states
    n = q.shape[-1]
    fixed = np.setdiff1d(np.arange(10 * model.NB), cols)
    drives = drive_threshold is not None
    width = len(cols) + (3 * n if drives else 0) + 1
    body_of = cols // 10 + 1
    touches = _touches(model)
    # per joint: the columns of Y it needs (positions in cols), its places in G, Y's fixed
    # columns it needs
    where, place, rest = [], [], []
    for j in range(n):
        mine = np.flatnonzero(touches[j, body_of])
        run = len(mine) and np.array_equal(np.diff(cols[mine]), np.ones(len(mine) - 1))
        # a run of columns (a chain's joint j needs the bodies from j on) is read as a slice
        where.append(slice(cols[mine[0]], cols[mine[0]] + len(mine)) if run else cols[mine])
        own = np.arange(len(cols) + 3 * j, len(cols) + 3 * j + 3) if drives else []
        place.append(np.concatenate([mine, own, [width - 1]]).astype(int))
        rest.append(fixed[touches[j, fixed // 10 + 1]])

    def gram(chunks: range) -> np.ndarray:
        G = np.zeros((width, width))
        for a in chunks:
            part = slice(a, a + CHUNK)
            Y = regressor(model, q[part], qd[part], qdd[part], gravity,
                          base=base_rows(base, part))
            for j in range(n):
                k = len(place[j]) - (4 if drives else 1)
                M = np.empty((len(Y), len(place[j])))      # [Y_j | drives_j | τ_j]
                M[:, :k] = Y[:, j, where[j]]
                if drives:
                    M[:, k] = qd[part, j]
                    np.tanh(qd[part, j] / drive_threshold, out=M[:, k + 1])
                    M[:, k + 2] = qdd[part, j]
                M[:, -1] = tau[part, j]
                if len(rest[j]):
                    M[:, -1] -= Y[:, j][:, rest[j]] @ pi0[rest[j]]
                # Mᵀ M, its upper triangle (BLAS syrk: half of a matrix product's work)
                S = dsyrk(1.0, M.T, trans=0)
                G[np.ix_(place[j], place[j])] += np.triu(S) + np.triu(S, 1).T
        return G

    starts = range(0, len(q), CHUNK)
    workers = max(1, min(compiled.THREADS, len(starts)))
    if workers == 1:
        G = gram(starts)
    else:
        with ThreadPoolExecutor(workers) as pool:
            parts = list(pool.map(gram, [starts[w::workers] for w in range(workers)]))
        G = sum(parts[1:], parts[0])
    # a column no torque depends on (zero, or rounding noise: RTOL of the largest, as in
    # base_parameters) stays exactly zero; factored with the others, the eigendecomposition
    # would spread the rounding of the other directions into it, ~1e-12 of the largest
    d = np.sqrt(np.diag(G))
    felt = d > RTOL * (d[:-1].max() if width > 1 else 0.0)
    felt[-1] = True
    F = np.zeros((width, width))
    sub = np.ix_(felt, felt)
    d = np.where(d[felt] > 0.0, d[felt], 1.0)
    w, V = np.linalg.eigh(G[sub] / d[:, None] / d[None, :])
    F[:len(w)][:, felt] = (np.sqrt(np.clip(w, 0.0, None))[:, None] * V.T) * d[None, :]
    return F


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
        drives: ``(damping, friction, armature)`` per joint, or None; what the recording
            cannot tell is the URDF's ``<dynamics>`` (armature: 0, the node's default).
        drive_threshold: the friction's smooth-sign velocity, with ``drives``.
        undetermined: (10·len(bodies),) 0 when the data determines the parameter by itself,
            1 when it does not (it is in no combination the data sees, or only in
            combinations with others, and the regularisation toward the URDF chose its
            value): ``diag((AᵀA + W²)⁻¹ W²)``.
        unexcited: (10·len(bodies),) True for a parameter no torque of the recording
            depends on (its regressor column is zero): undetermined, σ infinite.
        drive_sigma: ``(damping, friction, armature)`` σ per joint (inf: undetermined).
        drive_unexcited: ``(damping, friction, armature)``, True where no torque of the
            recording depends on the term (the joint never moves, or never accelerates):
            the URDF's value is kept.
        converged: False when the fit stopped at its evaluation limit; ``message`` says why.
    """

    pi: np.ndarray
    bodies: Tuple[int, ...]
    before: np.ndarray
    after: np.ndarray
    covariance: np.ndarray
    drives: Optional[Tuple[np.ndarray, np.ndarray, np.ndarray]] = None
    drive_threshold: Optional[float] = None
    undetermined: Optional[np.ndarray] = None
    unexcited: Optional[np.ndarray] = None
    drive_sigma: Optional[Tuple[np.ndarray, np.ndarray, np.ndarray]] = None
    drive_unexcited: Optional[Tuple[np.ndarray, np.ndarray, np.ndarray]] = None
    converged: bool = True
    evaluations: int = 0
    message: str = ''

    @property
    def sigma(self) -> np.ndarray:
        """One standard deviation of each fitted parameter (bodies in order, ten each).

        Infinite for a parameter no torque depends on: the recording says nothing of it.
        """
        sigma = np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))
        if self.unexcited is not None:
            sigma[self.unexcited] = np.inf
        return sigma

    def model(self, model: Model) -> Model:
        """Return ``model`` with the identified inertias (drives are not part of a model)."""
        return with_bodies(model, {i: _spatial_inertia(self.pi[10 * (i - 1):10 * i])
                                   for i in self.bodies})


#: The inertial fit's evaluations at most, None: scipy's default (100 per unknown).
EVALUATIONS: Optional[int] = None


def _realisable_strictly(pi: np.ndarray) -> bool:
    """Tell whether ten parameters are a body with a positive definite pseudo-inertia."""
    w = np.linalg.eigvalsh(pseudo_inertia(pi))
    return bool(w[0] > 1e-12 * w[-1])


def drive_prior(model: Model) -> np.ndarray:
    """Return (3n,) each joint's URDF damping, friction and armature 0, as the fit orders them."""
    n = len(model.joint_names)
    out = np.zeros(3 * n)
    out[0::3], out[1::3] = model.damping, model.friction
    return out


def identify_inertias(model: Model, q, qd, qdd, tau, links: Optional[Sequence[str]] = None,
                      gravity: Sequence[float] = (0.0, 0.0, -9.81),
                      drive_threshold: Optional[float] = None,
                      regularisation: float = 1e-3,
                      base: Optional[BaseMotion] = None) -> Inertias:
    """Fit the inertial parameters of ``links`` (default: every moving body) to ``tau``.

    Least squares on ``Y π (+ drives) − τ`` plus ``regularisation`` · (π − π_URDF), scaled
    by the regressor's column norms: where the data says nothing (a combination no motion
    excites) the URDF's values stay. With ``drive_threshold`` each joint's damping, Coulomb
    friction (``tanh(q̇/threshold)``) and armature are fitted jointly; a drive term no torque
    depends on keeps the URDF's value. The recording is reduced chunk by chunk to a triangle
    (:func:`_square_root`), so its length costs time, not memory, and the fit that follows
    works on that triangle only.

    The problem is convex in π (a quadratic over the physically realisable bodies, whose
    pseudo-inertias are positive semi-definite): its unconstrained minimum, one linear
    solve, is the answer when every body is realisable there. Otherwise the fit goes on
    from it (each body moved to the nearest realisable one) in the log-Cholesky parameters
    ``θ`` (:func:`scipy.optimize.least_squares`, trust region, the exact Jacobian), which
    keep every body realisable whatever the data. ``base``: the base's motion at each sample
    (a mobile manipulator), as for :func:`~spatial_dynamics.rnea`.
    """
    from threadpoolctl import threadpool_limits
    if base is not None:
        check_base_motion(base, model)
    q, qd, qdd, tau = (np.atleast_2d(np.asarray(x, dtype=float)) for x in (q, qd, qdd, tau))
    if links is None:
        bodies = tuple(range(1, model.NB + 1))
    else:
        bodies = tuple(sorted({link_to_body(model, link)[0] for link in links}))
    pi0 = parameters(model)
    cols = np.concatenate([np.arange(10 * (i - 1), 10 * i) for i in bodies])
    # the BLAS on one thread: the Gram matrix's chunks are shared by the command's own
    # threads (BLAS threads beside them only oversubscribe the cores: a 30 s bag took 129 s
    # at load 4 with OpenBLAS's default, 16.6 s with one), and the fit works on matrices of
    # a hundred columns, where threads cost more than they give
    with threadpool_limits(limits=1, user_api='blas'):
        F = _square_root(model, (q, qd, qdd), tau, gravity, cols, pi0, drive_threshold, base)
        return _fit(model, (q, qd, qdd), tau, gravity, bodies, cols, pi0, F,
                    drive_threshold, regularisation, base)


def _fit(model: Model, states, tau, gravity, bodies, cols, pi0, F, drive_threshold,
         regularisation, base: Optional[BaseMotion] = None) -> Inertias:
    """:func:`identify_inertias` on the recording's triangle ``F`` (:func:`_square_root`)."""
    from scipy.optimize import least_squares
    q, qd, qdd = states
    n = q.shape[-1]
    R, c = F[:, :-1], F[:, -1]
    nb = 10 * len(bodies)
    ndrive = R.shape[1] - nb
    scale = np.linalg.norm(R, axis=0)          # = the column norms of A (0: no torque felt)
    unexcited = scale[:nb] == 0.0
    weight = regularisation * np.where(unexcited, scale[:nb].max() or 1.0, scale[:nb])
    prior = np.concatenate([pi0[cols], drive_prior(model) if ndrive else []])
    free = np.concatenate([np.ones(nb, dtype=bool), scale[nb:] > 0.0])   # the unknowns
    Ru = R[:, free]
    # the unconstrained minimum of |R x − c|² + |W (π − π_URDF)|² (drives unregularised)
    top = c - R[:, ~free] @ prior[~free]
    A = np.vstack([Ru, np.hstack([np.diag(weight), np.zeros((nb, Ru.shape[1] - nb))])])
    with np.errstate(all='ignore'):
        x, *_ = np.linalg.lstsq(A, np.concatenate([top, weight * pi0[cols]]), rcond=None)
    blocks = range(len(bodies))
    converged, evaluations, message = True, 0, ''
    if not all(_realisable_strictly(x[10 * k:10 * k + 10]) for k in blocks):
        def pi_of(t):
            return np.concatenate([from_log_cholesky(t[10 * k:10 * k + 10]) for k in blocks])

        def residual(t):
            p = pi_of(t[:nb])
            return np.concatenate([Ru @ np.concatenate([p, t[nb:]]) - top,
                                   weight * (p - pi0[cols])])

        def jacobian(t):
            D = np.zeros((nb, nb))
            for k in blocks:
                D[10 * k:10 * k + 10, 10 * k:10 * k + 10] = log_cholesky_jacobian(
                    t[10 * k:10 * k + 10])
            return np.vstack([np.hstack([Ru[:, :nb] @ D, Ru[:, nb:]]),
                              np.hstack([weight[:, None] * D, np.zeros((nb, len(t) - nb))])])

        # from the unconstrained minimum, each body moved to the nearest realisable one
        t0 = np.concatenate([log_cholesky(x[10 * k:10 * k + 10]) for k in blocks] + [x[nb:]])
        result = least_squares(residual, t0, jac=jacobian, method='trf', x_scale=1.0,
                               max_nfev=EVALUATIONS)
        x = np.concatenate([pi_of(result.x[:nb]), result.x[nb:]])
        converged, evaluations = result.status > 0, int(result.nfev)
        message = result.message
    pi = pi0.copy()
    pi[cols] = x[:nb]
    drives = drive_sigma = drive_unexcited = None
    full = prior.copy()
    full[free] = x
    if ndrive:
        drives = tuple(full[nb + k::3].copy() for k in range(3))
        drive_unexcited = tuple(~free[nb + k::3] for k in range(3))
    found = Inertias(pi, bodies, np.zeros(n), np.zeros(n), np.zeros((nb, nb)), drives,
                     drive_threshold if ndrive else None)
    corrected = found.model(model)     # built once: each new model has its own kernels
    before, after = np.zeros(n), np.zeros(n)
    for a in range(0, len(q), RNEA_CHUNK):
        part = slice(a, a + RNEA_CHUNK)
        states = q[part], qd[part], qdd[part]
        on = base_rows(base, part)
        before += np.sum((tau[part] - rnea(model, *states, gravity, base=on)) ** 2, axis=0)
        after += np.sum((tau[part] - predicted_torque(corrected, *states, gravity, drives,
                                                      drive_threshold, on)) ** 2, axis=0)
    # the covariance of the linearised, regularised estimate: s² (AᵀA + W²)⁻¹
    s2 = float(after.sum()) / max(tau.size - Ru.shape[1], 1)
    normal = Ru.T @ Ru
    normal[np.arange(nb), np.arange(nb)] += weight ** 2
    inverse = np.linalg.pinv(normal)
    undetermined = np.clip(np.diag(inverse)[:nb] * weight ** 2, 0.0, 1.0)
    undetermined[unexcited] = 1.0
    if ndrive:
        variance = np.full(ndrive, np.inf)
        variance[free[nb:]] = s2 * np.clip(np.diag(inverse)[nb:], 0.0, None)
        drive_sigma = tuple(np.sqrt(variance[k::3]) for k in range(3))
    return replace(found, before=np.sqrt(before / len(q)), after=np.sqrt(after / len(q)),
                   covariance=s2 * inverse[:nb, :nb], undetermined=undetermined,
                   unexcited=unexcited, drive_sigma=drive_sigma,
                   drive_unexcited=drive_unexcited, converged=converged,
                   evaluations=evaluations, message=message)
