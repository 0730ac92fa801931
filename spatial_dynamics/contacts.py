# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Inverse dynamics of a floating-base robot in contact: joint torques **and** contact forces.

A floating-base robot cannot push on its base with a motor: its equation of motion is::

    M(q) q̈ + h(q, q̇) = Sᵀ τ + J_cᵀ λ,      Sᵀ = [0; 1] (the base's six rows have no motor)

with ``J_c`` the Jacobian of the contact points (rows stacked, world axes) and ``λ`` their
forces (or wrenches). ``M q̈ + h`` is one RNEA call (``rnea(model, q, q̇, q̈)``), so no ``M``
is formed. Three ways to split it (:func:`contact_inverse_dynamics`):

* **measured** contact forces (foot F/T sensors): ``τ = (M q̈ + h)_joints - J_c,jointsᵀ λ``,
  and the base rows' residual ``(M q̈ + h)_base - J_c,baseᵀ λ`` says how consistent the
  measurement is with the motion (zero for a perfect one);
* **contact-consistent** (Mistry, Buchli & Schaal 2010; Righetti et al. 2013): the QR
  decomposition ``J_cᵀ = [Q1 Q2] [R; 0]``; ``Q2ᵀ`` removes the contact forces, and the
  minimum-norm (or ``W``-weighted) torques solve ``Q2ᵀ Sᵀ τ = Q2ᵀ (M q̈ + h)``; then
  ``λ = R⁻¹ Q1ᵀ (M q̈ + h - Sᵀ τ)``. Or ``'forces'``: the least (weighted) contact forces
  that carry the base rows, ``J_c,baseᵀ λ = (M q̈ + h)_base``, and the torques they leave;
* **friction cones as a QP** (Clarabel, second-order cones: exact cones, no pyramid):
  minimise ``½ τᵀ W τ + ½ ε |λ|²`` subject to all the rows of the equation and, per contact,
  ``n·f ≥ 0`` (unilateral, whatever ``μ``) and ``|f_t| ≤ μ f_n``; infeasible problems are
  reported, never answered with a base torque. :func:`warm_qp` imports the solver ahead.
  The problem is scaled so that every coefficient is at most 1 whatever the numbers: the
  weights over their largest, and a cone of ``μ > 1`` written ``|f_t| / μ ≤ f_n``; every
  finite ``μ ≥ 0`` and positive weight is solved (``test_core_contacts.py``: μ 0 to 1e300,
  weights 1e-300 to 1e300).

Every answer says the base rows' residual (never a silent base torque) and which contacts
violate their friction cone or pull on the ground, by how much (:class:`ContactResult`).

Contacts (:class:`Contact`): a **point** contact on a link, at an offset in the link's frame,
has a force ``f`` (3, world axes) at that point; a **surface** contact (a foot sole) has a
wrench ``[n; f]`` (6, world axes, moment about the contact point). Each has a normal (world,
default up) and a friction coefficient ``μ``.

One module a job: :mod:`.contact_kinematics` (the contacts, ``J_c`` and what a model and its
contacts fix for every state), :mod:`.algorithms.split` (the contact-consistent split, numpy
and scalar kernel), :mod:`.contact_qp` (the friction-cone QP); this one splits the dynamics
with them and says how well (:func:`contact_inverse_dynamics`, :class:`ContactResult`).
One float64 state's ``'torques'`` is one call of the compiled ``contact`` entry.
"""

from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import Mapping, Optional, Sequence

import numpy as np

from .algorithms.arguments import (as_joint_arrays, as_real_array, check_configuration,
                                   check_model)
from .algorithms.jacobian import PLACEMENT
# the numpy split under the name this module calls it by (tests replace it here)
from .algorithms.split import contact_rank, RANK_TOLERANCE, split_numpy as _split_numpy
from .backends import compiled, GRAVITY, kernels, rnea
from .bounds import (beyond, check_bounded, MAX_ACCELERATION, MAX_GRAVITY, MAX_POSITION,
                     MAX_VELOCITY, MAX_WRENCH)
from .contact_kinematics import (Contact, contact_jacobian, KINDS, Plan, placements,
                                 plan_contacts)
from .contact_qp import qp
from .model import Model
from .text import shown

__all__ = ['Contact', 'contact_inverse_dynamics', 'contact_jacobian', 'ContactResult', 'KINDS',
           'link_orientations', 'METHODS', 'Violation', 'warm_qp']
#: How :func:`contact_inverse_dynamics` splits the dynamics (see the module doc).
METHODS = ('torques', 'forces', 'qp')
_c_bodies = compiled.ext.bodies if compiled.ext is not None else None


@dataclass(frozen=True)
class Violation:
    """A contact whose force breaks a condition: ``kind`` ``'unilateral'`` or ``'friction'``.

    ``amount``: N by which the normal force is below zero (unilateral), or by which the
    tangential force exceeds ``μ f_n`` (friction).
    """

    contact: str
    kind: str
    amount: float


@dataclass
class ContactResult:
    """The answer of :func:`contact_inverse_dynamics` (one state).

    Attributes:
        tau: joint torques (N m, N), (nv - 6,), in ``model.joint_names[1:]``'s order.
        forces: contact name -> its force (3,) or wrench ``[n; f]`` (6,), world axes, at the
            contact point: what the environment exerts on the robot.
        base_residual: ``(M q̈ + h - Sᵀ τ - J_cᵀ λ)`` of the base's six rows ``[n; f]`` (base
            frame): the wrench on the base nothing provides (zero when consistent).
        violations: each contact that pulls (``unilateral``) or slips (``friction``).
        method: ``'measured'``, ``'torques'``, ``'forces'`` or ``'qp'``.
        status: ``'solved'``, or why not (the QP's ``'infeasible'``, ...).
        rank: the rank found of ``J_c`` (fewer than its rows: redundant contact rows).
    """

    tau: np.ndarray
    forces: dict
    base_residual: np.ndarray
    violations: list = field(default_factory=list)
    method: str = ''
    status: str = 'solved'
    rank: int = 0

    @property
    def feasible(self) -> bool:
        """Solved, with the base rows met (1e-6 N, N m) and no contact violated."""
        return (self.status == 'solved' and not self.violations
                and bool(np.abs(self.base_residual).max() < 1e-6))

    def summary(self) -> str:
        """One line: the status, the base residual and each violation."""
        parts = [f'{self.method}: {self.status}',
                 f'base residual {np.abs(self.base_residual).max():.3g}']
        parts += [f'{v.contact} {v.kind} by {v.amount:.3g} N' for v in self.violations]
        return ', '.join(parts)


def link_orientations(model: Model, q, links: Sequence[str]) -> dict:
    """Return link -> ``R`` (3, 3), the link's orientation (world <- link), at one state ``q``.

    ``R = R_i E_lᵀ`` for the link on body ``i`` (``R_i`` world <- body, ``E_l`` body -> link,
    the link's fixed placement): what turns a contact force from world axes into the link's.
    """
    check_model(model)
    kern = kernels(model)
    rows = None if kern is None else _c_bodies(kern, q)     # placements: the compiled pass
    if rows is not None and rows.dtype == np.float64:
        R = rows[:, :PLACEMENT].reshape(-1, 4, 4)[:, :3, :3]
    else:
        (q,) = as_joint_arrays(model, q)
        if q.ndim != 1:
            raise ValueError(f'link_orientations takes one state, got q of shape {q.shape}')
        R, _ = placements(model, q.tolist())
    result = {}
    for link in links:
        frame = model.frames.get(link)
        if frame is None:
            raise ValueError(f'{shown(link)} is not a link of {shown(model.name)}')
        result[link] = R[frame.body] @ frame.lXb[:3, :3].T    # E_lb = lXb's top-left block
    return result


def contact_inverse_dynamics(model: Model, q, qd, qdd, contacts: Sequence[Contact],
                             measured: Optional[Mapping[str, np.ndarray]] = None,
                             method: str = 'torques', weights=None,
                             gravity: Sequence[float] = GRAVITY,
                             force_weight: float = 1e-6, backend: str = 'auto') -> ContactResult:
    """Joint torques and contact forces that make a floating-base robot follow ``q̈``.

    Args:
        model: a floating-base model.
        q, qd, qdd: one state (nq,), (nv,), (nv,): the desired base and joint accelerations.
        contacts: the :class:`Contact` s in force.
        measured: contact name -> measured force (3,) or wrench (6,) (world axes, at the
            contact point) for every contact: τ directly, the base rows as a check. Each
            component within ±:data:`~spatial_dynamics.bounds.MAX_WRENCH` (1e6 N, N m).
        method: without ``measured``: ``'torques'`` (contact-consistent, least ``τᵀ W τ``),
            ``'forces'`` (least ``λᵀ W λ`` carrying the base rows) or ``'qp'`` (least
            ``½ τᵀ W τ + ½ force_weight |λ|²`` inside the friction cones, Clarabel).
        weights: ``W``, positive, one per joint (``'torques'``, ``'qp'``) or per contact row
            (``'forces'``); default ones. Only their ratios matter: the QP divides them and
            ``force_weight`` by their largest, so any finite positive scale is solved.
        gravity: m/s², world coordinates.
        force_weight: the QP's small weight on the contact forces (makes λ unique).
        backend: as :func:`~spatial_dynamics.rnea`'s. ``'compiled'`` (``'auto'`` when built)
            takes ``M q̈ + h`` and ``J_c`` from the compiled kernels
            (:func:`contact_jacobian`) and splits ``'torques'`` with the compiled
            :func:`~.algorithms.split.split_kernel` (the same equations); ``'numpy'`` runs
            every step in numpy. Both give the same answer to rounding
            (``test/test_core_contacts_compiled.py``).

    Returns:
        a :class:`ContactResult`; ``ValueError`` for arguments that name no contact, model
        or method, never a base torque in ``tau``.
    """
    plan = plan_contacts(model, contacts)
    contacts = plan.contacts
    if not plan.floating:
        raise ValueError(f'{shown(model.name)} has a fixed base: contact inverse dynamics needs a '
                         "floating base (Model.from_urdf(..., base='floating'))")
    if method not in METHODS:
        raise ValueError(f'method must be one of {METHODS}, got {shown(method)}')
    kern = kernels(model, backend)
    n = plan.n
    torques = method == 'torques' and measured is None
    w = np.sqrt(_weights(weights, n, 'joint')) if torques and weights is not None else None
    if torques and kern is not None:      # one float64 state: the whole answer compiled
        residual = np.empty(6)
        split = _split_compiled(kern, plan, q, qd, qdd, gravity, w, residual)
        if split is not None:
            return _result(plan, residual, *split[:2], 'torques', 'solved', split[2])
    b = Jc = None
    if kern is not None:        # one float64 state the compiled entries read as it is
        b = _c_rnea(kern, q, qd, qdd, gravity)
        if b is not None and b.dtype == np.float64:
            Jc = contact_jacobian(model, q, contacts, backend)
    if Jc is None:
        q, qd, qdd = as_joint_arrays(model, q, qd, qdd)
        if q.ndim != 1:
            raise ValueError('contact_inverse_dynamics takes one state, got q of shape '
                             f'{q.shape}')
        if not (np.isfinite(q).all() and np.isfinite(qd).all() and np.isfinite(qdd).all()):
            raise _not_finite(model, q, qd, qdd, gravity)
        b = rnea(model, q, qd, qdd, gravity, backend=backend)   # M q̈ + h
        Jc = contact_jacobian(model, q, contacts, backend)
    with np.errstate(over='ignore', invalid='ignore'):     # the guard's own squares
        finite = math.isfinite(b @ b + np.vdot(Jc, Jc))     # NaN, ∞ or overflow: before LAPACK
    if not finite:
        raise _not_finite(model, q, qd, qdd, gravity)
    if measured is not None:
        lam = _measured(contacts, measured)
        return _result(plan, _residual(b, Jc, lam), b[6:] - Jc[:, 6:].T @ lam, lam,
                       'measured', 'solved', contact_rank(Jc))
    if method == 'qp':
        tau, lam, status = qp(plan, b, Jc, n, _weights(weights, n, 'joint'), force_weight,
                              *_qp_solver())
        if status != 'solved':      # nothing carries the base rows: the residual is b_base
            return ContactResult(tau, {name: lam[k:k + rows] for name, (k, rows) in zip(
                plan.names, plan.slices)}, b[:6].copy(), [], 'qp', status, 0)
        return _result(plan, _residual(b, Jc, lam), tau, lam, 'qp', 'solved', contact_rank(Jc))
    if method == 'forces':
        W = _weights(weights, len(Jc), 'contact row')
        A = Jc[:, :6].T                                 # base rows: A λ = b_base
        AWi = A / W
        lam = AWi.T @ np.linalg.lstsq(AWi @ A.T, b[:6], rcond=None)[0] if len(Jc) else Jc[:, 0]
        return _result(plan, _residual(b, Jc, lam), b[6:] - Jc[:, 6:].T @ lam, lam, 'forces',
                       'solved', contact_rank(Jc))
    # contact-consistent (algorithms/split.py): J_cᵀ P = Q [R; 0] pivoted, Q2ᵀ Sᵀ τ = Q2ᵀ b
    tau, lam, r = _split_numpy(Jc, b, n, np.ones(n) if w is None else w)
    return _result(plan, _residual(b, Jc, lam), tau, lam, 'torques', 'solved', r)


def _residual(b: np.ndarray, Jc: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """Return the base rows' residual ``b_base - J_c,baseᵀ λ`` (6,), base frame."""
    return b[:6] - Jc[:, :6].T @ lam


_c_rnea = compiled.ext.rnea if compiled.ext is not None else None
_c_contact = compiled.ext.contact if compiled.ext is not None else None


def _not_finite(model: Model, q, qd, qdd, gravity) -> ValueError:
    """Return the error of a state whose ``M q̈ + h`` or ``J_c`` is not finite, naming why.

    The first argument holding a NaN or an infinity, else a zero quaternion
    (:func:`~.algorithms.arguments.check_configuration`), else values too large to compute with.
    """
    for what, x in (('q', q), ('qd', qd), ('qdd', qdd), ('gravity', gravity)):
        x = np.asarray(x, dtype=float)
        bad = np.flatnonzero(~np.isfinite(x))
        if bad.size:
            return ValueError(f'{what} must be finite: {what}[{bad[0]}] is {x.flat[bad[0]]}')
    try:
        check_configuration(model, np.asarray(q, dtype=float))
    except ValueError as err:
        return err
    for what, x, bound, unit, name in (
            ('qd', qd, MAX_VELOCITY, 'rad/s or m/s', 'MAX_VELOCITY'),
            ('qdd', qdd, MAX_ACCELERATION, 'rad/s² or m/s²', 'MAX_ACCELERATION'),
            ('gravity', gravity, MAX_GRAVITY, 'm/s²', 'MAX_GRAVITY'),
            ('q', q, MAX_POSITION, 'rad or m', 'MAX_POSITION')):
        why = check_bounded(what, x, bound, unit)
        if why is not None:
            return ValueError(f'M q̈ + h or J_c of this state overflows: {why} '
                              f'(bounds.{name})')
    return ValueError('M q̈ + h or J_c of this state is not finite (or its square overflows): '
                      'q, qd, qdd or gravity too large to compute with')


def _split_compiled(kern, plan: Plan, q, qd, qdd, gravity, w,
                    residual: np.ndarray) -> Optional[tuple]:
    """Return the contact-consistent ``(τ, λ, r)`` of one state, all compiled, or ``None``.

    One call of the extension's ``contact`` entry: ``M q̈ + h`` and the bodies' rows of the
    compiled kernels, ``J_c`` from them (:func:`_contact_rows`' products on scalars), the
    split of :func:`~.algorithms.split.split_kernel` (the numpy split's equations on scalars:
    a Householder QR with column pivoting of ``J_cᵀ`` applied to ``b`` and ``Sᵀ``, ``A Aᵀ``
    by Cholesky, ``λ`` by back substitution or, for redundant contact rows, a second QR);
    the base rows' residual into ``residual``. ``None`` (the general path then answers, or
    names what is wrong) when ``q``, ``qd``, ``qdd`` or ``gravity`` is not one float64
    state, when ``M q̈ + h`` or ``J_c`` is not finite, for fewer contact rows than six and
    for the cases the kernel leaves to the numpy split: base rows the contacts cannot carry.
    """
    return _c_contact(kern, q, qd, qdd, gravity, plan.points, plan.ones if w is None else w,
                      RANK_TOLERANCE, residual)


def _weights(weights, size: int, what: str) -> np.ndarray:
    """``weights`` as ``size`` positive numbers (ones by default); ``ValueError`` otherwise."""
    if weights is None:
        return np.ones(size)
    w = np.broadcast_to(as_real_array('weights', weights).astype(float), (size,)) if np.ndim(
        weights) == 0 else as_real_array('weights', weights).astype(float)
    if w.shape != (size,) or not (np.isfinite(w).all() and (w > 0).all()):
        raise ValueError(f'weights must be {size} positive numbers (one per {what}), got {w}')
    return w


def _measured(contacts, measured) -> np.ndarray:
    """Stack the measured forces in the contacts' order; ``ValueError`` naming a missing one."""
    if not isinstance(measured, Mapping):
        raise TypeError('measured must map contact names to forces or wrenches, got '
                        f'{type(measured).__name__}')
    unknown = set(measured) - {c.name for c in contacts}
    if unknown:
        raise ValueError(f'measured: no contact named {sorted(unknown)}')
    out = []
    for c in contacts:
        if c.name not in measured:
            raise ValueError(f'measured: no force for contact {shown(c.name)}')
        f = as_real_array(f'measured[{shown(c.name)}]', measured[c.name]).astype(float)
        if f.shape != (c.rows,) or beyond(f, MAX_WRENCH).size:
            raise ValueError(f'measured[{shown(c.name)}] must be {c.rows} finite numbers within '
                             f'±{MAX_WRENCH:g} N or N m (bounds.MAX_WRENCH) '
                             f'({"[f]" if c.rows == 3 else "[n; f]"}, world axes), got {f}')
        out.append(f)
    return np.concatenate(out) if out else np.zeros(0)


def _result(plan: Plan, residual, tau, lam, method, status, rank) -> ContactResult:
    """Assemble the result: forces by name, base residual, cone and unilateral checks.

    Per contact, its force ``f`` (the last three of its λ), normal ``n`` and ``μ``: the
    normal force ``f_n = n · f`` and the tangential ``f_t = |f - f_n n|`` (on floats); it
    slips when ``f_t > μ max(f_n, 0) + 1e-9 max(1, |f_n|)`` (compared squared: both sides
    are not negative).
    """
    forces = dict(zip(plan.names, lam.reshape(-1, 3) if plan.points_only else (
        lam[k:k + rows] for k, rows in plan.slices)))
    violations, values = [], lam.tolist()
    for name, j, n0, n1, n2, mu in plan.cones:
        f0, f1, f2 = values[j:j + 3]
        fn = n0 * f0 + n1 * f1 + n2 * f2
        t0, t1, t2 = f0 - fn * n0, f1 - fn * n1, f2 - fn * n2
        bound = mu * fn + 1e-9 * (fn if fn > 1.0 else 1.0) if fn > 0.0 else 1e-9 * (
            -fn if fn < -1.0 else 1.0)
        if fn < 0.0:
            violations.append(Violation(name, 'unilateral', -fn))
        if t0 * t0 + t1 * t1 + t2 * t2 > bound * bound:
            ft = math.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
            violations.append(Violation(name, 'friction', ft - mu * max(fn, 0.0)))
    return ContactResult(tau, forces, residual, violations, method, status, rank)


#: The QP solver's modules once imported and warmed (:func:`warm_qp`): clarabel, scipy.sparse.
_solver: dict = {}


def _qp_solver() -> tuple:
    """Return ``(clarabel, scipy.sparse)``; imported here (only ``'qp'`` needs them)."""
    if not _solver:
        try:
            import clarabel
            from scipy import sparse
        except ImportError as err:
            raise ImportError(f"method='qp' needs clarabel and scipy ({err}): the package's "
                              "'qp' extra, pip install clarabel scipy") from None
        _solver.update(clarabel=clarabel, sparse=sparse)
    return _solver['clarabel'], _solver['sparse']


def warm_qp() -> None:
    """Import the QP solver and solve one small cone problem, so that no answer waits for it.

    The import alone takes 0.3 to 0.7 s; a node calls this where it prepares a configuration
    with ``contacts.method: qp``, never on the path that answers. ``ImportError`` (naming what
    to install) when clarabel or scipy is missing.
    """
    clarabel, sparse = _qp_solver()
    if _solver.get('warm'):
        return
    # min ½ x₀² subject to x₀ + x₁ = 1, x₁ ≥ 0, (x₀, x₁, 0) in the second-order cone
    A = sparse.csc_matrix(np.array([[1.0, 1.0], [0.0, -1.0], [-1.0, 0.0], [0.0, -1.0],
                                    [0.0, 0.0]]))
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    clarabel.DefaultSolver(sparse.csc_matrix(np.diag([1.0, 0.0])), np.zeros(2), A,
                           np.array([1.0, 0.0, 0.0, 0.0, 0.0]),
                           [clarabel.ZeroConeT(1), clarabel.NonnegativeConeT(1),
                            clarabel.SecondOrderConeT(3)], settings).solve()
    _solver['warm'] = True
