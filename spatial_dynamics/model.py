# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The kinematic-tree model (RBDA ch. 4): an immutable record, and rigid-body inertias.

A :class:`Model` is immutable and holds flat arrays indexed by body. Body 0 is the fixed
base (the URDF root link and everything fixed to it); bodies ``1..NB`` each hang on one
movable joint, numbered so that ``parent[i] < i``. Links attached by ``fixed`` joints are
lumped into the body they are fixed to; their frames stay reachable through ``frames``.
Models are built from a URDF by :mod:`spatial_dynamics.urdf`, whose
:func:`~spatial_dynamics.urdf.model_from_urdf` is also ``Model.from_urdf``: the parser installs
it on the class, so that this module never imports the parser.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from functools import cached_property
from types import MappingProxyType
from typing import Callable, ClassVar, Mapping, Optional

import numpy as np

from .joints import FREE_FLYER, NQ, NV
from .spatial import mcI
from .text import shown

#: Rounding noise allowed in the inertia checks (positive semi-definite, triangle inequality,
#: inertia without mass): a principal moment may miss by INERTIA_RTOL of the largest one, or by
#: INERTIA_ATOL kg m² however small the inertia (files write "0" as ±1e-20 after a rotation).
INERTIA_RTOL = 1e-6
INERTIA_ATOL = 1e-12
#: Largest magnitude accepted for a number the dynamics uses (lengths, masses, inertias,
#: angles): beyond it products overflow. URDF ``<limit>`` values may be any size.
MAX_ABS_VALUE = 1e12


@dataclass(frozen=True, eq=False)
class Frame:
    """A URDF link's frame on its body: ``body`` index and ``lXb`` (link ← body, 6×6)."""

    body: int
    lXb: np.ndarray


@dataclass(frozen=True, eq=False)
class Model:
    """Immutable kinematic tree with flat per-body arrays (index 0 = fixed base or world).

    ``NB`` moving bodies; ``nq`` position coordinates (``len(q)``) and ``nv`` velocity
    coordinates (``len(q̇)``, ``len(q̈)``, ``len(τ)``). A fixed-base model has ``nq == nv ==
    len(joint_names)``; a floating-base model (``base='floating'``) has body 0 the world and
    body 1 the root link on a free-flyer joint (:mod:`spatial_dynamics.joints`), so
    ``nq = 7 + n`` and ``nv = 6 + n`` for ``n`` joints besides it.

    Attributes:
        name: robot name.
        joint_names: movable, non-mimic joint names (the free-flyer first, named
            ``'root_joint'``, in a floating-base model); the order of ``q`` and ``q̇``.
        body_names: (NB+1,) link name of each body (the link its joint moves).
        body_joints: (NB+1,) name of each body's joint ('' for the base).
        NB: number of moving bodies.
        parent: (NB+1,) parent body index, ``parent[0] = -1``.
        jtype: (NB+1,) joint kind per body (``joints.REVOLUTE``, ``PRISMATIC``,
            ``FREE_FLYER``; body 0 ``FIXED``).
        axis: (NB+1, 3) unit joint axis in the body frame.
        Xtree: (NB+1, 6, 6) ``iXλ(i)`` at q = 0: parent body → body motion transform.
        inertia: (NB+1, 6, 6) spatial inertia of each body with its lumped links, body frame.
        qidx, qmul, qoff: (NB+1,) body ``i`` moves by ``qmul[i]·q[qidx[i]] + qoff[i]``
            (mimic joints have ``qidx`` of their source); base entries are ``-1, 0, 0``. A
            free-flyer's coordinates are ``q[qidx[i]:qidx[i] + 7]`` (``qmul`` 1, ``qoff`` 0).
        vidx: (NB+1,) first index of body ``i``'s joint in ``q̇``, ``q̈`` and ``τ`` (``qidx``
            in a fixed-base model, where both are the same; ``-1`` for body 0).
        frames: link name → :class:`Frame` for every link, lumped or not.
        effort_limit, velocity_limit, lower, upper, damping, friction: (nv,) URDF
            ``<limit>`` and ``<dynamics>`` values per velocity coordinate (``nan`` when
            absent; a free-flyer's six entries ``nan``, and 0 for damping and friction).
        body_damping, body_friction: (NB+1,) ``<dynamics>`` of every body's joint, mimic
            joints included (0 when absent).
        lumped: links merged into a moving body by fixed (or locked) joints.
        pruned: links fixed to the base, which no joint's torque depends on.
        locked: joints locked by model reduction and their values.
        warnings: what is physically inconsistent in the URDF but loaded as written (each
            message names the link or joint, the quantity and its values); see
            :class:`~spatial_dynamics.urdf.URDFWarning`.
        joint_types: joint name → its URDF ``type`` as written (``revolute``,
            ``continuous``, ``prismatic``, ``fixed``), every joint of the URDF, in its order.
        mimics: mimic joint → ``(source joint, multiplier, offset)`` of its ``<mimic>`` tag
            as written (the source may itself be a mimic joint), every one of the URDF.
    """

    name: str
    joint_names: tuple
    body_names: tuple
    body_joints: tuple
    NB: int
    parent: np.ndarray
    jtype: np.ndarray
    axis: np.ndarray
    Xtree: np.ndarray
    inertia: np.ndarray
    qidx: np.ndarray
    qmul: np.ndarray
    qoff: np.ndarray
    frames: Mapping[str, Frame]
    effort_limit: np.ndarray
    velocity_limit: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    damping: np.ndarray
    friction: np.ndarray
    body_damping: np.ndarray = field(default_factory=lambda: np.zeros(1))
    body_friction: np.ndarray = field(default_factory=lambda: np.zeros(1))
    lumped: tuple = ()
    pruned: tuple = ()
    locked: Mapping[str, float] = field(default_factory=dict)
    warnings: tuple = ()
    joint_types: Mapping[str, str] = field(default_factory=dict)
    mimics: Mapping[str, tuple] = field(default_factory=dict)
    vidx: Optional[np.ndarray] = None
    #: ``Model.from_urdf(source, joints=None, locked=None, strict=False, base='fixed')``: the
    #: parser's :func:`spatial_dynamics.urdf.model_from_urdf`, installed on the class by it.
    from_urdf: ClassVar[Callable[..., Model]]

    def __post_init__(self) -> None:
        if self.vidx is None:
            object.__setattr__(self, 'vidx', np.array(self.qidx, dtype=np.intp))
        for name, value in vars(self).items():
            if isinstance(value, np.ndarray):
                value.setflags(write=False)
        object.__setattr__(self, 'frames', MappingProxyType(dict(self.frames)))
        object.__setattr__(self, 'locked', MappingProxyType(dict(self.locked)))

    def __reduce__(self) -> tuple:
        """Pickle (and deep-copy) by the fields: ``frames`` and ``locked`` as plain dicts.

        The read-only views do not pickle; loading builds the record again (read-only arrays,
        views), so a loaded model computes what the original does.
        """
        return (type(self), tuple(dict(v) if isinstance(v, MappingProxyType) else v
                                  for v in (getattr(self, f.name) for f in fields(self))))

    @cached_property
    def nq(self) -> int:
        """Number of position coordinates ``len(q)``: 1 per joint, 7 for a free-flyer."""
        return len(self.joint_names) + sum(NQ[int(k)] - 1 for k in self.jtype[1:])

    @cached_property
    def nv(self) -> int:
        """Number of velocity coordinates ``len(q̇) = len(τ)``: 1 per joint, 6 for a free-flyer."""
        return len(self.joint_names) + sum(NV[int(k)] - 1 for k in self.jtype[1:])

    @cached_property
    def free_flyers(self) -> tuple:
        """``(joint name, k)`` of each free-flyer: its quaternion is ``q[k + 3:k + 7]``."""
        return tuple((self.body_joints[i], int(self.qidx[i])) for i in range(1, self.NB + 1)
                     if int(self.jtype[i]) == FREE_FLYER)

    @property
    def floating(self) -> bool:
        """Whether the base moves: the root link hangs on a free-flyer joint."""
        return bool(self.NB) and int(self.jtype[1]) == FREE_FLYER

    def summary(self) -> str:
        """One line for logs: dof, bodies kept, links lumped and pruned, locked joints."""
        locked = ', '.join(f'{shown(j, quote=False)}={v:g}' for j, v in self.locked.items())
        if self.floating:
            return (f'{shown(self.name, quote=False)}: floating base '
                    f'({shown(self.body_names[1])} on a free-flyer, nq {self.nq}, nv {self.nv}), '
                    f'{self.nv - 6} joint dof, {self.NB} moving '
                    f'bodies, {len(self.lumped)} links lumped by fixed joints'
                    + (f', locked: {locked}' if locked else ''))
        return (f'{shown(self.name, quote=False)}: {self.nq} dof, {self.NB} moving bodies, '
                f'{len(self.lumped)} links lumped by fixed joints, {len(self.pruned)} links '
                f'pruned (fixed to the base)' + (f', locked: {locked}' if locked else ''))

    def __repr__(self) -> str:
        if self.floating:
            return (f'Model(name={shown(self.name)}, floating base, nq={self.nq}, nv={self.nv}, '
                    f'bodies={self.NB}, links={len(self.frames)})')
        return (f'Model(name={shown(self.name)}, dof={self.nq}, bodies={self.NB}, '
                f'links={len(self.frames)})')


# --------------------------------------------------------------------------------------------
# Rigid bodies: validated inertias, payloads

def refuse_masked(what: str, values) -> None:
    """``ValueError`` naming ``what`` when ``values`` is a masked array with masked entries.

    numpy reads a masked array as the numbers under its mask (``np.asarray`` drops it): a
    value the user marked as missing would be computed with. One with none masked is read.
    """
    if isinstance(values, np.ma.MaskedArray) and np.ma.is_masked(values):
        raise ValueError(f'{what} has {np.ma.count_masked(values)} masked entries: give the '
                         'numbers to use in their place (a masked array\'s filled())')


def real_numbers(what: str, values) -> np.ndarray:
    """Return ``values`` (a number, or a list, tuple or array of them) as a float array.

    ``TypeError`` naming ``what`` for anything but real numbers: text (``'0.1'``), ``None``,
    complex numbers, objects, ragged lists, and booleans (``True`` is no mass, armature or
    friction). Integers and floats of any width are numbers. ``ValueError`` for masked
    entries (:func:`refuse_masked`).
    """
    refuse_masked(what, values)
    try:
        a = np.asarray(values)
    except (TypeError, ValueError) as err:
        raise TypeError(f'{what} must be real numbers, got {type(values).__name__}: '
                        f'{err}') from None
    if a.dtype.kind not in 'iuf':
        got = (f'{shown(values)}' if a.dtype.kind == 'b' and a.ndim == 0
               else f'{type(values).__name__} of dtype {a.dtype}')
        raise TypeError(f'{what} must be real numbers, got {got}')
    if a.dtype.kind == 'f' and _holds_a_boolean(values):   # numpy read [True, 0.5] as floats
        raise TypeError(f'{what} must be real numbers, got a boolean in {shown(values)}')
    return a.astype(float)


def _holds_a_boolean(values) -> bool:
    """Whether the (nested) lists or tuples ``values`` hold a ``bool`` or ``np.bool_``."""
    if isinstance(values, (bool, np.bool_)):
        return True
    return isinstance(values, (list, tuple)) and any(_holds_a_boolean(v) for v in values)


def finite(what: str, values) -> np.ndarray:
    """Return ``values`` as floats; ``ValueError`` naming ``what`` if non-finite or absurd.

    ``TypeError`` naming ``what`` when they are not real numbers (:func:`real_numbers`).
    """
    a = real_numbers(what, values)
    if not np.all(np.isfinite(a)):
        raise ValueError(f'{what}: non-finite number in {a.tolist()}')
    if np.any(np.abs(a) > MAX_ABS_VALUE):
        raise ValueError(f'{what}: absurd magnitude (> {MAX_ABS_VALUE:g}) in {a.tolist()}')
    return a


def rigid_body_inertia(what: str, mass, com, inertia, R: Optional[np.ndarray] = None,
                       report: Optional[Callable[[str], None]] = None) -> np.ndarray:
    """Return the spatial inertia (6×6) ``mcI(m, c, R Ic Rᵀ)`` of a rigid body (RBDA 2.63).

    ``mass`` (kg) finite and non-negative; ``com`` (m, 3); ``inertia`` (kg m², symmetric 3×3
    about the centre of mass, in a frame rotated by ``R`` from the link frame). What cannot be
    computed raises ``ValueError`` naming ``what``. A physically inconsistent inertia (not
    positive semi-definite, principal moments breaking the triangle inequality, inertia
    without mass) goes to ``report`` and is used as written; without a ``report`` it raises.
    Rounding noise (:data:`INERTIA_RTOL`, :data:`INERTIA_ATOL`) is accepted silently.
    """
    m = float(finite(f'{what} mass', mass))
    if m < 0.0:
        raise ValueError(f'{what}: negative mass {m}')
    c = finite(f'{what} centre of mass', com)
    Ii = finite(f'{what} inertia', inertia)
    if c.shape != (3,) or Ii.shape != (3, 3):
        raise ValueError(f'{what}: centre of mass must be 3 numbers and inertia 3×3')
    if not np.allclose(Ii, Ii.T, rtol=0.0, atol=1e-12 * max(np.abs(Ii).max(), 1e-300)):
        raise ValueError(f'{what}: inertia matrix is not symmetric')
    for problem in inertia_problems(m, Ii):
        if report is None:
            raise ValueError(f'{what}: {problem}')
        report(f'{what}: {problem}')
    if R is not None:
        Ii = R @ Ii @ R.T
    return mcI(m, c, Ii)


def inertia_problems(mass: float, Ic: np.ndarray) -> list:
    """List what is physically inconsistent in a rotational inertia ``Ic`` (kg m², at the com).

    A rigid body's principal moments are non-negative and obey the triangle inequality
    ``λ1 + λ2 ≥ λ3``; a body without mass has no inertia. Each is checked up to rounding noise:
    ``max(INERTIA_RTOL · max|λ|, INERTIA_ATOL)``. Returns messages (empty when consistent).
    """
    lam = np.linalg.eigvalsh(Ic)
    tol = max(INERTIA_RTOL * float(np.abs(lam).max()), INERTIA_ATOL)
    moments = f'principal moments {[float(f"{x:.6g}") for x in lam]} kg m^2'
    problems = []
    if lam[0] < -tol:
        problems.append(f'inertia is not positive semi-definite ({moments})')
    elif lam[0] + lam[1] < lam[2] - tol:
        problems.append(f'inertia breaks the triangle inequality ({moments}: '
                        f'{lam[0]:.6g} + {lam[1]:.6g} < {lam[2]:.6g})')
    if mass == 0.0 and lam[2] > tol:
        problems.append(f'inertia on a massless link ({moments}, mass 0)')
    return problems


def with_payload(model: Model, link: str, mass: float, com=(0.0, 0.0, 0.0),
                 inertia=(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)) -> Model:
    """Return a new model with a rigid payload attached to ``link`` (models are immutable).

    ``mass`` in kg, ``com`` (x, y, z) in m in the link frame, ``inertia``
    (ixx, ixy, ixz, iyy, iyz, izz) in kg m² about the payload's centre of mass, axes of the
    link frame. The payload's spatial inertia joins the link's body: ``I_b += lXbᵀ I_p lXb``.
    """
    frame = model.frames.get(link)
    if frame is None:
        raise ValueError(f'payload link {shown(link)} is not a link of {shown(model.name)}')
    inertia = finite('payload inertia', inertia)
    if inertia.shape != (6,):
        raise ValueError('payload inertia must be 6 numbers (ixx ixy ixz iyy iyz izz), got '
                         f'{inertia.tolist()}')
    ixx, ixy, ixz, iyy, iyz, izz = inertia
    Ip = rigid_body_inertia(f'payload on {shown(link)}', mass, com,
                            [[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    inertia6 = np.array(model.inertia)
    inertia6[frame.body] += frame.lXb.T @ Ip @ frame.lXb
    return replace(model, inertia=inertia6)
