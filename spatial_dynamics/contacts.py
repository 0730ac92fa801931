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
"""

from __future__ import annotations

from dataclasses import dataclass, field
import math
import numbers
import weakref
from typing import Mapping, Optional, Sequence

import numpy as np

from .algorithms.arguments import (as_joint_arrays, as_real_array, check_configuration,
                                   check_model)
from .algorithms.jacobian import PLACEMENT
from .algorithms.rnea import xup_kernel
from .algorithms.split import DEPENDENT, RANK_TOLERANCE
from .backends import compiled, GRAVITY, kernels, layout, rnea
from .bounds import (beyond, check_bounded, MAX_ACCELERATION, MAX_GRAVITY, MAX_POSITION,
                     MAX_VELOCITY, MAX_WRENCH)
from .joints import FREE_FLYER, REVOLUTE
from .model import Model

#: How :func:`contact_inverse_dynamics` splits the dynamics (see the module doc).
METHODS = ('torques', 'forces', 'qp')
KINDS = ('point', 'surface')


@dataclass(frozen=True)
class Contact:
    """A contact of a link with the environment.

    Attributes:
        link: a link of the model (lumped links too), by URDF name.
        offset: the contact point in the link's frame (m), within
            ±:data:`~spatial_dynamics.bounds.MAX_POSITION`.
        kind: ``'point'`` (a force, 3 rows) or ``'surface'`` (a wrench, 6 rows).
        normal: the contact normal in world axes, pointing into the robot (up for a floor).
        mu: Coulomb friction coefficient (the cone's half-angle is ``atan(μ)``).
        name: how results name it (the link's name by default).
    """

    link: str
    offset: Sequence[float] = (0.0, 0.0, 0.0)
    kind: str = 'point'
    normal: Sequence[float] = (0.0, 0.0, 1.0)
    mu: float = 0.7
    name: str = ''

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f'contact {self.link!r}: kind must be one of {KINDS}, '
                             f'got {self.kind!r}')
        offset = as_real_array(f'contact {self.link!r} offset', self.offset).astype(float)
        normal = as_real_array(f'contact {self.link!r} normal', self.normal).astype(float)
        if offset.shape != (3,) or beyond(offset, MAX_POSITION).size:
            raise ValueError(f'contact {self.link!r}: offset must be 3 finite numbers within '
                             f'±{MAX_POSITION:g} m (bounds.MAX_POSITION), got {self.offset}')
        if normal.shape != (3,) or not (np.isfinite(normal).all()
                                        and np.abs(normal).max() > 0.0):
            raise ValueError(f'contact {self.name or self.link!r}: normal must be a finite '
                             f'non-zero 3-vector, got {self.normal}')
        if isinstance(self.mu, (bool, np.bool_)) or not isinstance(self.mu, numbers.Real):
            raise TypeError(f'contact {self.link!r}: mu must be a number (the friction '
                            f'coefficient), got {type(self.mu).__name__} {self.mu!r}')
        if not (math.isfinite(self.mu) and self.mu >= 0.0):
            raise ValueError(f'contact {self.link!r}: mu must be a finite number >= 0, '
                             f'got {self.mu}')
        normal = normal / np.abs(normal).max()          # scaled first: 1e200 and 1e-320
        normal = normal / np.linalg.norm(normal)        # have a length
        offset.setflags(write=False)        # immutable, as the model: answers derived from
        normal.setflags(write=False)        # a contact once stay its answers (_plan)
        object.__setattr__(self, 'offset', offset)
        object.__setattr__(self, 'normal', normal)
        object.__setattr__(self, 'name', self.name or self.link)
        object.__setattr__(self, 'mu', float(self.mu))

    @property
    def rows(self) -> int:
        """Rows of the contact in ``J_c`` and entries of its ``λ``: 3 (point) or 6 (surface)."""
        return 3 if self.kind == 'point' else 6


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


def contact_jacobian(model: Model, q, contacts: Sequence[Contact],
                     backend: str = 'auto') -> np.ndarray:
    """Return ``J_c`` (..., rows, nv): the contacts' rows stacked, world axes at the points.

    A point contact's rows are the velocity of its point ``p_c``; a surface contact's
    ``[ω; v_p]`` (Pinocchio's ``LOCAL_WORLD_ALIGNED`` frame Jacobian at the point, angular
    rows first). Column by column (RBDA eq. 4.10 in world axes): a revolute joint ``j`` on
    the contact's path turns about ``s = R_j axis`` through ``p_j``, so its column is
    ``[s; s × (p_c - p_j)]``; a prismatic one ``[0; s]``; the free-flyer's six are those of its
    ``[ω; v]`` in the base frame, ``[R; -(p_c - p_b)× R]`` and ``[0; R]``.

    ``backend`` as :func:`~spatial_dynamics.rnea`'s: ``'numpy'`` builds the columns above
    with numpy; ``'compiled'`` (``'auto'`` when built) takes every body's world-aligned
    Jacobian from one compiled pass (:func:`~.algorithms.jacobian.bodies_kernel`) and
    carries the contact body's to its point, ``[ω; v + ω × d]`` with ``d = R_b r_c``.
    ``q`` (nq,) or a batch (..., nq): the compiled batch entry and the same products, or
    numpy state by state.
    """
    plan = _plan(model, contacts)
    kern = kernels(model, backend)
    if kern is not None:
        Jc = _compiled_jacobian(kern, q, plan)
        if Jc is not None:
            return Jc
    (q,) = as_joint_arrays(model, q)
    if kern is not None and q.dtype == np.float64 and q.size:
        Q = np.ascontiguousarray(q.reshape(-1, q.shape[-1]))
        rows = np.empty((len(Q),) + _rows_shape(kern))
        compiled.ext.bodies_batch(kern, len(Q), Q, rows, compiled.THREADS)
        Jc = _contact_rows(rows[:, plan.bodies], plan, kern.nv)
        return Jc.reshape(q.shape[:-1] + Jc.shape[-2:])
    Jc = [_jacobian(model, x.tolist(), plan.contacts) for x in q.reshape(-1, q.shape[-1])]
    return np.array(Jc).reshape(q.shape[:-1] + (plan.k, len(model.damping)))


def _rows_shape(kern) -> tuple:
    """Return the shape of the compiled bodies' rows of one state: (NB + 1, 16 + 6 nv)."""
    return (kern.rows, PLACEMENT + 6 * kern.nv)


def _compiled_jacobian(kern, q, plan: '_Plan') -> Optional[np.ndarray]:
    """:func:`contact_jacobian` of one state from the compiled bodies' rows, or ``None``.

    ``None`` when the single-state entry declines ``q`` (a batch, a wrong length, …).
    """
    rows = _c_bodies(kern, q)
    if rows is None or rows.dtype != np.float64:
        return None
    return _contact_rows(rows.take(plan.bodies, 0), plan, kern.nv)


def _contact_rows(B: np.ndarray, plan: '_Plan', nv: int) -> np.ndarray:
    """``J_c`` (..., k, nv) from the contact bodies' rows ``B`` (..., nc, 16 + 6 nv).

    Each contact body's row holds its placement ``[R_b p_b; 0 1]`` and ``J_b`` (its origin's
    world-aligned Jacobian, :func:`~.algorithms.jacobian.bodies_kernel`); the point at
    ``r_c`` (body coordinates) moves with ``[ω; v + ω × d]``, ``d = R_b r_c``:
    ``J_c = [1 0; -d× 1] J_b``, whose rows are linear in the placement (``plan.shift``).
    """
    nc, m = plan.shift.shape[0], plan.shift.shape[2] // 6
    batch = B.shape[:-2]
    T = (B[..., None, :PLACEMENT] @ plan.shift).reshape(batch + (nc, m, 6))
    Jc = (T @ B[..., PLACEMENT:].reshape(batch + (nc, 6, nv))).reshape(batch + (nc * m, nv))
    return Jc if plan.rows is None else Jc[..., plan.rows, :]


_c_bodies = compiled.ext.bodies if compiled.ext is not None else None
#: ``_SHIFT[a]`` is the coefficient of ``d_a`` in ``[1 0; -d× 1]`` (6x6)
_SHIFT = np.zeros((3, 6, 6))
_SHIFT[0, 4, 2], _SHIFT[0, 5, 1] = 1.0, -1.0        # -d× = [[0, d2, -d1],
_SHIFT[1, 3, 2], _SHIFT[1, 5, 0] = -1.0, 1.0        # [-d2, 0, d0],
_SHIFT[2, 3, 1], _SHIFT[2, 4, 0] = 1.0, -1.0        # [d1, -d0, 0]]


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
        R, _ = _placements(model, q.tolist())
    result = {}
    for link in links:
        frame = model.frames.get(link)
        if frame is None:
            raise ValueError(f'{link!r} is not a link of {model.name!r}')
        result[link] = R[frame.body] @ frame.lXb[:3, :3].T    # E_lb = lXb's top-left block
    return result


def _jacobian(model: Model, q: list, contacts: Sequence[Contact]) -> np.ndarray:
    """:func:`contact_jacobian` of checked arguments, ``q`` a list of floats (one state)."""
    nv = len(model.damping)
    R, P = _placements(model, q)
    k = sum(c.rows for c in contacts)
    J = np.zeros((k, nv))
    pairs, row = [], 0          # (row of the contact's ω, body) for the joints on each path
    for c in contacts:
        frame = model.frames[c.link]
        i = b = frame.body
        E_lb, r_lb = _Er(frame.lXb)
        p_c = P[b] + R[b] @ (r_lb + E_lb.T @ c.offset)
        w = row if c.kind == 'surface' else row - 3     # ω rows (skipped for a point)
        while i > 0:
            if model.jtype[i] == FREE_FLYER:
                kv, Ri = model.vidx[i], R[i]
                d = p_c - P[i]
                if w >= row:
                    J[w:w + 3, kv:kv + 3] = Ri
                J[w + 3:w + 6, kv:kv + 3] = _cross(Ri.T, d).T       # -d× R = (R col) × d
                J[w + 3:w + 6, kv + 3:kv + 6] = Ri
            else:
                pairs.append((w, i, p_c, c.kind == 'surface'))
            i = model.parent[i]
        row += c.rows
    if pairs:
        w, i, p_c, surface = zip(*pairs)
        w, i, surface = np.array(w), np.array(i), np.array(surface)
        s = np.einsum('nij,nj->ni', R[i], model.axis[i])       # joint axes, world
        d = np.array(p_c) - P[i]
        mul, kv = model.qmul[i], model.vidx[i]
        revolute = model.jtype[i] == REVOLUTE
        ang = (s * (mul * revolute)[:, None])
        lin = np.where(revolute[:, None], _cross(s, d), s) * mul[:, None]
        # J[w + a, kv] += ang[:, a] (surface contacts), J[w + 3 + a, kv] += lin[:, a]; a
        # mimic joint's column adds to its source's, so accumulate (bincount) rather than set
        a = np.arange(3)
        idx = np.r_[((w[surface, None] + a) * nv + kv[surface, None]).ravel(),
                    ((w[:, None] + 3 + a) * nv + kv[:, None]).ravel()]
        J += np.bincount(idx, np.r_[ang[surface].ravel(), lin.ravel()],
                         minlength=k * nv).reshape(k, nv)
    return J


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Return ``a × b`` over the last axis (np.cross without its axis bookkeeping)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], -1)


def _Er(X: np.ndarray) -> tuple:
    """``(E, r)`` of a Plücker motion transform ``X = [[E, 0], [-E r×, E]]``."""
    E = X[:3, :3]
    rx = -E.T @ X[3:, :3]
    return E, np.array([rx[2, 1], rx[0, 2], rx[1, 0]])


def _skew(r: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def _placements(model: Model, q: list) -> tuple:
    """Return every body's orientation ``R_i`` (world <- body) and origin ``p_i`` (world).

    From the body transforms ``Xup_i = (E_i, r_i)`` of the one source
    (:func:`~spatial_dynamics.algorithms.rnea.xup_kernel`): ``R_i = R_λ(i) E_iᵀ``,
    ``p_i = p_λ(i) + R_λ(i) r_i``, for all bodies of one depth at once.
    """
    lay = layout.of(model)
    rows = lay.rows
    Xup = [None] * len(rows)
    xup_kernel(rows, q, math, Xup)
    Xup[0] = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)
    X = np.array(Xup)
    Et, r = X[:, :9].reshape(-1, 3, 3).transpose(0, 2, 1), X[:, 9:]
    R, P = np.empty((len(rows), 3, 3)), np.zeros((len(rows), 3))
    R[0] = np.eye(3)
    for bodies, parents in _depths(model):
        Rp = R[parents]
        R[bodies] = Rp @ Et[bodies]
        P[bodies] = P[parents] + np.einsum('nij,nj->ni', Rp, r[bodies])
    return R, P


_levels: 'weakref.WeakKeyDictionary[Model, tuple]' = weakref.WeakKeyDictionary()


def _depths(model: Model) -> tuple:
    """Return ``((bodies, their parents), ...)`` by depth in the tree, once per model."""
    levels = _levels.get(model)
    if levels is None:
        depth = [0] * (model.NB + 1)
        for i in range(1, model.NB + 1):
            depth[i] = depth[model.parent[i]] + 1
        levels = tuple((np.array(b), model.parent[np.array(b)]) for b in (
            [i for i in range(1, model.NB + 1) if depth[i] == d]
            for d in range(1, max(depth) + 1)))
        _levels[model] = levels
    return levels


@dataclass(frozen=True, eq=False)
class _Plan:
    """What a model and its contacts fix for every state: checked once (:func:`_plan`).

    ``bodies`` (nc,) the contact bodies; ``shift`` (nc, 16, 6 m) gives the rows ``T`` of
    ``[1 0; -d× 1]`` with ``d = R_b r_c`` (``r_c`` the contact point in body coordinates)
    from the body's placement ``H = [R_b p_b; 0 1]`` flat, ``T = H shift``: the three ``v``
    rows (m = 3) when every contact is a point, else all six, of which a point keeps its
    ``v`` (``rows``; ``None``: all). For the result: the contacts' ``names``, their
    ``slices`` of λ ``(first row, rows)``, ``points_only`` (λ is ``(nc, 3)`` forces), and
    per contact ``cones`` ``(name, row of its force, n0, n1, n2, μ)`` (plain floats).
    ``points`` (nc, 5): the compiled entry's contacts, a row each: body, rows, ``r_c``;
    ``floating`` the model's; ``n`` its joints, ``nv - 6``, and ``ones`` n ones (weights).
    """

    contacts: tuple
    bodies: np.ndarray
    shift: np.ndarray
    rows: Optional[np.ndarray]
    k: int
    names: tuple
    slices: tuple
    points_only: bool
    cones: tuple
    points: np.ndarray
    floating: bool
    n: int
    ones: np.ndarray


#: id(model) -> {ids of its contacts: their _Plan}, while the model lives (as the backends'
#: layouts); a plan holds its contacts, so their ids stay theirs while it lives (a cache of a
#: pure function of immutable records).
_plans: dict = {}


def _plan(model: Model, contacts) -> _Plan:
    """Check the contacts on ``model`` (once per model and contacts) and plan their rows."""
    plans = _plans.get(id(model))
    if plans is None:       # a model seen first (its id is no other live model's)
        check_model(model)
        plans = _plans[id(model)] = {}
        weakref.finalize(model, _plans.pop, id(model), None)
    if not isinstance(contacts, (tuple, list)):
        contacts = tuple(contacts)
    key = tuple(map(id, contacts))
    plan = plans.get(key)
    if plan is not None:
        return plan
    contacts = _contacts(model, contacts)
    bodies, offsets, rows, slices, cones, row = [], [], [], [], [], 0
    for j, c in enumerate(contacts):
        frame = model.frames[c.link]
        E_lb, r_lb = _Er(frame.lXb)
        bodies.append(frame.body)
        offsets.append(r_lb + E_lb.T @ c.offset)
        rows += range(6 * j + 6 - c.rows, 6 * j + 6)
        slices.append((row, c.rows))
        cones.append((c.name, row + c.rows - 3, *c.normal.tolist(), float(c.mu)))
        row += c.rows
    points = all(c.kind == 'point' for c in contacts)
    kept = slice(3, 6) if points else slice(0, 6)
    nc, m = len(contacts), 3 if points else 6
    # T = [1 0; -d× 1] (its kept rows), d_a = Σ_j R[a, j] r_j: H[4 a + j] r_j _SHIFT[a] + H[15] 1
    shift = np.zeros((nc, 4, 4, m, 6))
    shift[:, :3, :3] = np.einsum('cj,arx->cajrx', np.array(offsets).reshape(-1, 3),
                                 _SHIFT[:, kept])
    shift[:, 3, 3] = np.eye(6)[kept]
    table = np.c_[bodies, [c.rows for c in contacts], np.reshape(offsets, (-1, 3))].reshape(
        nc, 5).astype(float)
    table.setflags(write=False)
    if len(plans) >= 64:        # contacts made anew for each call: keep the last ones
        plans.clear()
    plan = plans[key] = _Plan(contacts, np.array(bodies, dtype=np.intp),
                              shift.reshape(nc, 16, 6 * m),
                              None if points or len(rows) == 6 * nc else np.array(rows), row,
                              tuple(c.name for c in contacts), tuple(slices), points,
                              tuple(cones), table, model.floating, len(model.damping) - 6,
                              _ones(max(len(model.damping) - 6, 0)))
    return plan


def _contacts(model: Model, contacts) -> tuple:
    """Check the contacts (their links, names); return them as a tuple."""
    contacts = tuple(contacts)
    names = set()
    for c in contacts:
        if not isinstance(c, Contact):
            raise TypeError(f'contacts must be spatial_dynamics.Contact, got {type(c).__name__}')
        if c.link not in model.frames:
            raise ValueError(f'contact {c.name!r}: {c.link!r} is not a link of {model.name!r}')
        if c.name in names:
            raise ValueError(f'contact {c.name!r} is given twice (name contacts on one link)')
        names.add(c.name)
    return contacts


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
    plan = _plan(model, contacts)
    contacts = plan.contacts
    if not plan.floating:
        raise ValueError(f'{model.name!r} has a fixed base: contact inverse dynamics needs a '
                         "floating base (Model.from_urdf(..., base='floating'))")
    if method not in METHODS:
        raise ValueError(f'method must be one of {METHODS}, got {method!r}')
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
            Jc = _compiled_jacobian(kern, q, plan)
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
                       'measured', 'solved', _rank(Jc))
    if method == 'qp':
        return _qp(plan, b, Jc, n, _weights(weights, n, 'joint'), force_weight)
    if method == 'forces':
        W = _weights(weights, len(Jc), 'contact row')
        A = Jc[:, :6].T                                 # base rows: A λ = b_base
        AWi = A / W
        lam = AWi.T @ np.linalg.lstsq(AWi @ A.T, b[:6], rcond=None)[0] if len(Jc) else Jc[:, 0]
        return _result(plan, _residual(b, Jc, lam), b[6:] - Jc[:, 6:].T @ lam, lam, 'forces',
                       'solved', _rank(Jc))
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


def _split_numpy(Jc: np.ndarray, b: np.ndarray, n: int, w: np.ndarray) -> tuple:
    """Return the contact-consistent ``(τ, λ, r)``: :mod:`~.algorithms.split`'s equations.

    The pivoted QR is :func:`_pivoted_qr` (the kernel's steps, the same rank); ``τ`` the least
    solution by ``A Aᵀ`` when the contacts carry the base rows, else numpy's least squares
    (``A τ ≈ y``: the base residual says what is left); ``λ`` the least solution of
    ``[R11 R12] Pᵀ λ = Q1ᵀ (b - Sᵀ τ)`` when the rows left out are dependent to rounding
    (:data:`~.algorithms.split.DEPENDENT`), else ``R11 z1 = …`` with those rows' ``λ`` zero.
    """
    k, nv = Jc.shape
    M = np.zeros((nv, k + 1 + n))                   # [J_cᵀ, b, Sᵀ], Sᵀ = [0; 1]
    M[:, :k], M[:, k] = Jc.T, b
    M[nv - n:, k + 1:] = np.eye(n)
    r, perm, scale = _pivoted_qr(M, k)
    A, y = M[r:, k + 1:] / w, M[r:, k]               # Q2ᵀ Sᵀ (τ / w) ... = Q2ᵀ b
    try:        # the least-norm solution Aᵀ (A Aᵀ)⁻¹ y, A of full row rank (feasible base rows)
        tau = A.T @ np.linalg.solve(A @ A.T, y) / w
        if not np.allclose(A @ (tau * w), y, rtol=1e-9, atol=1e-9 * max(1.0, np.abs(y).max(
                initial=0.0))):
            raise np.linalg.LinAlgError
    except np.linalg.LinAlgError:   # too few contacts to carry the base rows: least squares
        tau = np.linalg.lstsq(A, y, rcond=None)[0] / w
    c = M[:r, k] - M[:r, k + 1:] @ tau              # Q1ᵀ (b - Sᵀ τ)
    z = np.zeros(k)
    if r < k and np.abs(M[r:, r:k]).max(initial=0.0) <= DEPENDENT * scale:
        z = np.linalg.lstsq(M[:r, :k], c, rcond=None)[0]    # the least z of [R11 R12] z = c
    elif r:                                                 # R11 z1 = c, z2 = 0
        z[:r] = np.linalg.solve(M[:r, :r], c)
    lam = np.empty(k)
    lam[perm] = z
    return tau, lam, r


def _pivoted_qr(M: np.ndarray, k: int) -> tuple:
    """Reduce ``M = [J_cᵀ, …]`` (nv, ≥ k) to ``Qᵀ M P`` in place; return ``(r, P, scale)``.

    ``P`` is the columns' order, ``scale`` the largest norm of the first ``k`` columns.

    The steps of :func:`~.algorithms.split.split_kernel`: step ``j`` swaps in the column of
    the first ``k`` whose norm below row ``j`` is largest and stops when that norm is not
    above :data:`~.algorithms.split.RANK_TOLERANCE` times ``J_c``'s largest row norm (``r``
    steps made); a Householder reflector then zeroes it below row ``j`` in every column.
    """
    nv = len(M)
    perm = np.arange(k)
    scale = np.sqrt(np.einsum('ij,ij->j', M[:, :k], M[:, :k]).max(initial=0.0))
    floor = RANK_TOLERANCE * scale
    r = 0
    for j in range(min(k, nv)):
        below = np.einsum('ij,ij->j', M[j:, j:k], M[j:, j:k])
        p = j + int(np.argmax(below))
        if not np.sqrt(below[p - j]) > floor:
            break
        M[:, [j, p]], perm[[j, p]] = M[:, [p, j]], perm[[p, j]]
        x = M[j:, j]
        alpha = -np.sqrt(below[p - j]) if x[0] >= 0.0 else np.sqrt(below[p - j])
        v = x.copy()
        v[0] -= alpha
        vv = v @ v
        if vv > 0.0:
            M[j:, j + 1:] -= np.outer(v, (2.0 / vv) * (v @ M[j:, j + 1:]))
        M[j, j], M[j + 1:, j] = alpha, 0.0
        r = j + 1
    return r, perm, scale


def _rank(Jc: np.ndarray) -> int:
    """Return the rank of ``J_c`` (k, nv) that the split finds (:func:`_pivoted_qr`)."""
    return _pivoted_qr(Jc.T.copy(), len(Jc))[0]


def _split_compiled(kern, plan: _Plan, q, qd, qdd, gravity, w,
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


_made: dict = {}


def _ones(n: int) -> np.ndarray:
    """Return ``n`` ones, read-only, made once."""
    ones = _made.get(n)
    if ones is None:
        ones = _made[n] = np.ones(n)
        ones.setflags(write=False)
    return ones


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
            raise ValueError(f'measured: no force for contact {c.name!r}')
        f = as_real_array(f'measured[{c.name!r}]', measured[c.name]).astype(float)
        if f.shape != (c.rows,) or beyond(f, MAX_WRENCH).size:
            raise ValueError(f'measured[{c.name!r}] must be {c.rows} finite numbers within '
                             f'±{MAX_WRENCH:g} N or N m (bounds.MAX_WRENCH) '
                             f'({"[f]" if c.rows == 3 else "[n; f]"}, world axes), got {f}')
        out.append(f)
    return np.concatenate(out) if out else np.zeros(0)


def _result(plan: _Plan, residual, tau, lam, method, status, rank) -> ContactResult:
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


def _tangents(normal: np.ndarray) -> tuple:
    """Two unit vectors orthogonal to ``normal`` and to each other."""
    t1 = np.cross(normal, [1.0, 0.0, 0.0] if abs(normal[0]) < 0.9 else [0.0, 1.0, 0.0])
    t1 /= np.linalg.norm(t1)
    return t1, np.cross(normal, t1)


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


def _qp(plan: _Plan, b, Jc, n, W, force_weight) -> ContactResult:
    """Solve the friction-cone QP with Clarabel; see :func:`contact_inverse_dynamics`."""
    contacts = plan.contacts
    clarabel, sparse = _qp_solver()
    k = len(Jc)
    nx = n + k
    if not (np.isfinite(force_weight) and force_weight > 0.0):
        raise ValueError(f'force_weight must be a positive number, got {force_weight}')
    # the argmin is that of the weights over their largest: every weight in (0, 1]
    top = max(W.max(initial=0.0), force_weight)
    P = sparse.diags(np.r_[W / top, np.full(k, force_weight / top)]).tocsc()
    # equality (zero cone): [Sᵀ J_cᵀ] x = b, all nv rows
    A_eq = np.zeros((len(b), nx))
    A_eq[6:, :n] = np.eye(n)
    A_eq[:, n:] = Jc.T
    # unilateral (nonnegative cone): n·f ≥ 0 of each contact, whatever its μ
    N = np.zeros((len(contacts), nx))
    for j, (c, (row, rows)) in enumerate(zip(contacts, plan.slices)):
        N[j, n + row + rows - 3:n + row + rows] = c.normal
    blocks = [A_eq, -N]
    cones, row = [clarabel.ZeroConeT(len(b)), clarabel.NonnegativeConeT(len(contacts))], 0
    for c in contacts:
        t1, t2 = _tangents(c.normal)
        # s = (μ n·f, t1·f, t2·f) in the second-order cone; for μ > 1 the same cone as
        # (n·f, t1·f / μ, t2·f / μ): every coefficient at most 1, whatever μ
        G = np.zeros((3, nx))
        j = n + row + c.rows - 3    # the force's entries of λ
        a, t = (c.mu, 1.0) if c.mu <= 1.0 else (1.0, 1.0 / c.mu)
        G[0, j:j + 3], G[1, j:j + 3], G[2, j:j + 3] = a * c.normal, t * t1, t * t2
        blocks.append(-G)
        cones.append(clarabel.SecondOrderConeT(3))
        row += c.rows
    A = sparse.csc_matrix(np.vstack(blocks))
    rhs = np.r_[b, np.zeros(A.shape[0] - len(b))]
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    solution = clarabel.DefaultSolver(P, np.zeros(nx), A, rhs, cones, settings).solve()
    status = str(solution.status)
    x = np.array(solution.x)
    if 'Solved' not in status or 'Almost' in status:
        kind = ('infeasible: no contact forces inside the friction cones carry the base rows'
                if 'Infeasible' in status else f'not solved ({status})')
        nan = np.full(nx, np.nan)
        result = _result(plan, b[:6].copy(), nan[:n], nan[n:], 'qp', kind, 0)
        result.violations = []      # nothing carries the base rows: the residual is b_base
        return result
    return _result(plan, _residual(b, Jc, x[n:]), x[:n], x[n:], 'qp', 'solved', _rank(Jc))
