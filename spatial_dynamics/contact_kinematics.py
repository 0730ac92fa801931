# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Where the contacts are and how they move: :class:`Contact`, ``J_c`` and the plan of its rows.

A **point** contact on a link, at an offset in the link's frame, has a force ``f`` (3, world
axes) at that point; a **surface** contact (a foot sole) has a wrench ``[n; f]`` (6, world
axes, moment about the contact point). Each has a normal (world, default up) and a friction
coefficient ``μ``. :func:`contact_jacobian` stacks their rows of ``J_c`` (world axes at the
points, angular rows first), by numpy columns or from the compiled bodies' rows. What a
model and its contacts fix for every state is checked and derived once (:func:`plan_contacts`):
the contact bodies and points, the rows kept, what the result and the compiled entry read.
:mod:`.contacts` splits the dynamics with it.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
import numbers
import weakref
from typing import Optional, Sequence

import numpy as np

from .algorithms.arguments import as_joint_arrays, as_real_array, check_model
from .algorithms.jacobian import PLACEMENT
from .algorithms.rnea import xup_kernel
from .backends import compiled, kernels, layout
from .bounds import beyond, MAX_POSITION
from .joints import FREE_FLYER, REVOLUTE
from .model import Model
from .text import shown

#: The kinds of contact: a point's force (3 rows), a surface's wrench (6 rows).
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
            raise ValueError(f'contact {shown(self.link)}: kind must be one of {KINDS}, '
                             f'got {shown(self.kind)}')
        offset = as_real_array(f'contact {shown(self.link)} offset', self.offset).astype(float)
        normal = as_real_array(f'contact {shown(self.link)} normal', self.normal).astype(float)
        if offset.shape != (3,) or beyond(offset, MAX_POSITION).size:
            raise ValueError(f'contact {shown(self.link)}: offset must be 3 finite numbers within '
                             f'±{MAX_POSITION:g} m (bounds.MAX_POSITION), got {self.offset}')
        if normal.shape != (3,) or not (np.isfinite(normal).all()
                                        and np.abs(normal).max() > 0.0):
            raise ValueError(f'contact {shown(self.name or self.link)}: normal must be a finite '
                             f'non-zero 3-vector, got {self.normal}')
        if isinstance(self.mu, (bool, np.bool_)) or not isinstance(self.mu, numbers.Real):
            raise TypeError(f'contact {shown(self.link)}: mu must be a number (the friction '
                            f'coefficient), got {type(self.mu).__name__} {shown(self.mu)}')
        if not (math.isfinite(self.mu) and self.mu >= 0.0):
            raise ValueError(f'contact {shown(self.link)}: mu must be a finite number >= 0, '
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
    plan = plan_contacts(model, contacts)
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


def _compiled_jacobian(kern, q, plan: 'Plan') -> Optional[np.ndarray]:
    """:func:`contact_jacobian` of one state from the compiled bodies' rows, or ``None``.

    ``None`` when the single-state entry declines ``q`` (a batch, a wrong length, …).
    """
    rows = _c_bodies(kern, q)
    if rows is None or rows.dtype != np.float64:
        return None
    return _contact_rows(rows.take(plan.bodies, 0), plan, kern.nv)


def _contact_rows(B: np.ndarray, plan: 'Plan', nv: int) -> np.ndarray:
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


def _jacobian(model: Model, q: list, contacts: Sequence[Contact]) -> np.ndarray:
    """:func:`contact_jacobian` of checked arguments, ``q`` a list of floats (one state)."""
    nv = len(model.damping)
    R, P = placements(model, q)
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


def placements(model: Model, q: list) -> tuple:
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
class Plan:
    """What a model and its contacts fix for every state: checked once (:func:`plan_contacts`).

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


#: id(model) -> {ids of its contacts: their Plan}, while the model lives (as the backends'
#: layouts); a plan holds its contacts, so their ids stay theirs while it lives (a cache of a
#: pure function of immutable records).
_plans: dict = {}


def plan_contacts(model: Model, contacts) -> Plan:
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
    plan = plans[key] = Plan(contacts, np.array(bodies, dtype=np.intp),
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
            raise ValueError(f'contact {shown(c.name)}: {shown(c.link)} is not a link of '
                             f'{shown(model.name)}')
        if c.name in names:
            raise ValueError(f'contact {shown(c.name)} is given twice (name contacts on one link)')
        names.add(c.name)
    return contacts


_made: dict = {}


def _ones(n: int) -> np.ndarray:
    """Return ``n`` ones, read-only, made once."""
    ones = _made.get(n)
    if ones is None:
        ones = _made[n] = np.ones(n)
        ones.setflags(write=False)
    return ones
