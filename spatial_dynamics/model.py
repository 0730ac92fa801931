# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The kinematic-tree model (RBDA ch. 4) and its construction from a URDF.

A :class:`Model` is immutable and holds flat arrays indexed by body. Body 0 is the fixed
base (the URDF root link and everything fixed to it); bodies ``1..NB`` each hang on one
movable joint, numbered so that ``parent[i] < i``. Links attached by ``fixed`` joints are
lumped into the body they are fixed to; their frames stay reachable through ``frames``.
"""

from __future__ import annotations

import math
import os
import stat
import warnings as _warnings
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Mapping, Optional, Sequence, Union

import numpy as np

from .joints import FIXED, PRISMATIC, REVOLUTE, URDF_KINDS
from .spatial import Eaxis, mcI, plux, plux_Er

Source = Union[str, bytes, os.PathLike]

#: Rounding noise allowed in the inertia checks (positive semi-definite, triangle inequality,
#: inertia without mass): a principal moment may miss by INERTIA_RTOL of the largest one, or by
#: INERTIA_ATOL kg m² however small the inertia (files write "0" as ±1e-20 after a rotation).
INERTIA_RTOL = 1e-6
INERTIA_ATOL = 1e-12
#: Largest magnitude accepted for a URDF number the dynamics uses (lengths, masses, inertias,
#: angles): beyond it products overflow. Limits (``<limit>``) may be any size (±1e16 = none).
MAX_ABS_VALUE = 1e12
#: Largest URDF file read (bytes): a robot description is text of at most a few MB.
MAX_FILE_BYTES = 64 * 1024 * 1024


class URDFWarning(UserWarning):
    """A URDF that loads as written but is physically inconsistent; the message names it.

    Raised as ``ValueError`` instead by ``Model.from_urdf(..., strict=True)``. The messages of
    a model are kept on ``Model.warnings``.
    """


class _Report:
    """Collects what is physically wrong in a URDF: warnings, or errors when ``strict``."""

    def __init__(self, strict: bool) -> None:
        self.strict = strict
        self.messages: list = []

    def __call__(self, message: str) -> None:
        if self.strict:
            raise ValueError(f'{message} (strict mode)')
        if message not in self.messages:
            self.messages.append(message)


@dataclass(frozen=True, eq=False)
class Frame:
    """A URDF link's frame on its body: ``body`` index and ``lXb`` (link ← body, 6×6)."""

    body: int
    lXb: np.ndarray


@dataclass(frozen=True, eq=False)
class Model:
    """Immutable kinematic tree with flat per-body arrays (index 0 = fixed base).

    Attributes (``NB`` moving bodies, ``n`` = ``len(joint_names)`` generalised coordinates):
        name: robot name.
        joint_names: movable, non-mimic joint names; the order of ``q``.
        body_names: (NB+1,) link name of each body (the link its joint moves).
        body_joints: (NB+1,) name of each body's joint ('' for the base).
        NB: number of moving bodies.
        parent: (NB+1,) parent body index, ``parent[0] = -1``.
        jtype: (NB+1,) joint kind per body (``joints.REVOLUTE``, ``PRISMATIC``; base ``FIXED``).
        axis: (NB+1, 3) unit joint axis in the body frame.
        Xtree: (NB+1, 6, 6) ``iXλ(i)`` at q = 0: parent body → body motion transform.
        inertia: (NB+1, 6, 6) spatial inertia of each body with its lumped links, body frame.
        qidx, qmul, qoff: (NB+1,) body ``i`` moves by ``qmul[i]·q[qidx[i]] + qoff[i]``
            (mimic joints have ``qidx`` of their source); base entries are ``-1, 0, 0``.
        frames: link name → :class:`Frame` for every link, lumped or not.
        effort_limit, velocity_limit, lower, upper, damping, friction: (n,) URDF
            ``<limit>`` and ``<dynamics>`` values per joint of ``q`` (``nan`` when absent).
        body_damping, body_friction: (NB+1,) ``<dynamics>`` of every body's joint, mimic
            joints included (0 when absent).
        lumped: links merged into a moving body by fixed (or locked) joints.
        pruned: links fixed to the base, which no joint's torque depends on.
        locked: joints locked by model reduction and their values.
        warnings: what is physically inconsistent in the URDF but loaded as written (each
            message names the link or joint, the quantity and its values); see
            :class:`URDFWarning`.
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
    _kernel: tuple = field(default=(), repr=False)
    _table: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        for name, value in vars(self).items():
            if isinstance(value, np.ndarray):
                value.setflags(write=False)
        object.__setattr__(self, 'frames', MappingProxyType(dict(self.frames)))
        object.__setattr__(self, 'locked', MappingProxyType(dict(self.locked)))
        object.__setattr__(self, '_kernel', _kernel_data(self))
        object.__setattr__(self, '_table', _kernel_table(self.nq, self._kernel))   # writable

    @property
    def nq(self) -> int:
        """Number of generalised coordinates, ``len(joint_names)``."""
        return len(self.joint_names)

    @classmethod
    def from_urdf(cls, source: Source, joints: Optional[Sequence[str]] = None,
                  locked: Optional[Mapping[str, float]] = None, strict: bool = False
                  ) -> 'Model':
        """Build a model from a URDF file path, an XML string or XML bytes (no meshes loaded).

        A ``str`` starting with ``<`` is XML, any other ``str`` (or ``os.PathLike``) a path of
        a regular file; ``bytes`` are always XML, never a path.

        Model reduction: with ``joints``, only those joints stay movable (in that order as
        ``joint_names``); every other movable joint is locked at ``locked[name]`` (rad or m,
        default 0) and its child lumped into its parent. Links that end up fixed to the base
        cannot change any kept joint's torque and are pruned. Mimic joints follow their
        source: locked with it, or kept with it.

        What cannot be computed raises ``ValueError`` naming the element: malformed XML,
        entities or a DTD, unknown links, cycles, several roots, a non-finite or absurd
        (> ``MAX_ABS_VALUE``) number the dynamics uses, negative mass, a zero-length axis, a
        mimic of a missing joint, unsupported joint types, a bad ``joints``/``locked`` entry.
        What is physically inconsistent but computable (an inertia that is not positive
        semi-definite or breaks the triangle inequality, inertia without mass, negative
        damping or friction, no robot name) loads exactly as written, with a
        :class:`URDFWarning` per problem, also kept in ``model.warnings``; ``strict=True``
        raises ``ValueError`` for the first of them instead. Rounding noise (see
        ``INERTIA_ATOL``) is neither.
        """
        report = _Report(strict)
        model = _from_robot(_parse_urdf(source), joints, locked, report)
        for message in model.warnings:
            _warnings.warn(message, URDFWarning, stacklevel=2)
        return model

    def summary(self) -> str:
        """One line for logs: dof, bodies kept, links lumped and pruned, locked joints."""
        locked = ', '.join(f'{j}={v:g}' for j, v in self.locked.items())
        return (f'{self.name}: {self.nq} dof, {self.NB} moving bodies, '
                f'{len(self.lumped)} links lumped by fixed joints, {len(self.pruned)} links '
                f'pruned (fixed to the base)' + (f', locked: {locked}' if locked else ''))

    def __repr__(self) -> str:
        return (f'Model(name={self.name!r}, dof={self.nq}, bodies={self.NB}, '
                f'links={len(self.frames)})')


# --------------------------------------------------------------------------------------------
# URDF parsing (yourdfpy's element parsers on an lxml tree we parse safely ourselves)

def _parse_urdf(source: Source):
    from lxml import etree
    import yourdfpy

    if isinstance(source, os.PathLike):
        source = os.fspath(source)
    if isinstance(source, bytes):
        text = source
    elif isinstance(source, str) and source.lstrip().startswith('<'):
        text = source.encode('utf-8')
    elif isinstance(source, str):
        text = read_urdf_file(source)
    else:
        raise ValueError(f'URDF source must be a path or an XML string, not {type(source)}')

    # No DTD loading, no entity expansion, no network, no huge trees: an external entity
    # cannot leak a local file and an entity bomb cannot expand.
    parser = etree.XMLParser(resolve_entities=False, load_dtd=False, no_network=True,
                             huge_tree=False, remove_comments=True, remove_pis=True)
    try:
        root = etree.fromstring(text, parser)
    except etree.XMLSyntaxError as err:
        raise ValueError(f'malformed URDF XML: {err}') from None
    docinfo = root.getroottree().docinfo
    if docinfo.system_url or docinfo.public_id:
        raise ValueError(f'URDF refers to an external DTD ({docinfo.system_url!r}): not '
                         'supported')
    dtd = docinfo.internalDTD
    if dtd is not None and any(True for _ in dtd.iterentities()):
        raise ValueError('URDF declares XML entities (<!ENTITY ...>): not supported '
                         '(expand xacro/entities before loading)')
    if root.tag != 'robot':
        raise ValueError(f'URDF root element must be <robot>, not <{root.tag}>')

    links, joints = [], []
    for el in root.findall('link'):
        name = el.get('name')
        if not name:
            raise ValueError('a <link> element has no name attribute')
        try:
            links.append(yourdfpy.URDF._parse_link(el))
        except (ValueError, TypeError, AttributeError, KeyError) as err:
            raise ValueError(f'link {name!r}: cannot parse: {err}') from None
    for el in root.findall('joint'):
        name = el.get('name')
        if not name:
            raise ValueError('a <joint> element has no name attribute')
        if el.find('parent') is None or el.find('child') is None:
            raise ValueError(f'joint {name!r}: missing <parent> or <child> element')
        try:
            joints.append(yourdfpy.URDF._parse_joint(el))
        except (ValueError, TypeError, AttributeError, KeyError) as err:
            raise ValueError(f'joint {name!r}: cannot parse: {err}') from None
    return root.get('name') or '', links, joints


def read_urdf_file(path: str, limit: int = MAX_FILE_BYTES) -> bytes:
    """Return the bytes of a URDF file: a regular file of at most ``limit`` bytes.

    Never blocks on a FIFO or reads a device: the file is opened non-blocking and checked to
    be regular before anything is read. ``ValueError`` names the path and the reason.
    """
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, 'O_NONBLOCK', 0))
    except OSError as err:
        raise ValueError(f'cannot read URDF file {path!r}: {err.strerror}') from None
    with os.fdopen(fd, 'rb') as fh:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise ValueError(f'URDF file {path!r} is not a regular file')
        if info.st_size > limit:
            raise ValueError(f'URDF file {path!r} is too large ({info.st_size} bytes, limit '
                             f'{limit})')
        try:
            text = fh.read(limit + 1)
        except OSError as err:
            raise ValueError(f'cannot read URDF file {path!r}: {err.strerror}') from None
    if len(text) > limit:
        raise ValueError(f'URDF file {path!r} is too large (more than {limit} bytes)')
    return text


def _finite(what: str, values) -> np.ndarray:
    a = np.asarray(values, dtype=float)
    if not np.all(np.isfinite(a)):
        raise ValueError(f'{what}: non-finite number in {a.tolist()}')
    if np.any(np.abs(a) > MAX_ABS_VALUE):
        raise ValueError(f'{what}: absurd magnitude (> {MAX_ABS_VALUE:g}) in {a.tolist()}')
    return a


def _origin(what: str, T) -> tuple[np.ndarray, np.ndarray]:
    """Rotation ``R`` (child → parent coordinates) and position ``p`` of a URDF origin."""
    if T is None:
        return np.eye(3), np.zeros(3)
    T = _finite(f'{what} origin', T)
    return T[:3, :3], T[:3, 3]


def _link_inertia(link, report: _Report) -> np.ndarray:
    """Spatial inertia (6×6) of a URDF link in its own frame; zero without ``<inertial>``."""
    inertial = link.inertial
    if inertial is None:
        return np.zeros((6, 6))
    what = f'link {link.name!r} <inertial>'
    R, c = _origin(what, inertial.origin)
    return rigid_body_inertia(what, 0.0 if inertial.mass is None else inertial.mass, c,
                              np.zeros((3, 3)) if inertial.inertia is None
                              else inertial.inertia, R, report)


def rigid_body_inertia(what: str, mass, com, inertia, R: Optional[np.ndarray] = None,
                       report: Optional[_Report] = None) -> np.ndarray:
    """Return the spatial inertia (6×6) ``mcI(m, c, R Ic Rᵀ)`` of a rigid body (RBDA 2.63).

    ``mass`` (kg) finite and non-negative; ``com`` (m, 3); ``inertia`` (kg m², symmetric 3×3
    about the centre of mass, in a frame rotated by ``R`` from the link frame). What cannot be
    computed raises ``ValueError`` naming ``what``. A physically inconsistent inertia (not
    positive semi-definite, principal moments breaking the triangle inequality, inertia
    without mass) goes to ``report`` and is used as written; without a ``report`` it raises.
    Rounding noise (:data:`INERTIA_RTOL`, :data:`INERTIA_ATOL`) is accepted silently.
    """
    m = float(_finite(f'{what} mass', mass))
    if m < 0.0:
        raise ValueError(f'{what}: negative mass {m}')
    c = _finite(f'{what} centre of mass', com)
    Ii = _finite(f'{what} inertia', np.asarray(inertia, dtype=float))
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
        raise ValueError(f'payload link {link!r} is not a link of {model.name!r}')
    inertia = _finite('payload inertia', inertia)
    if inertia.shape != (6,):
        raise ValueError('payload inertia must be 6 numbers (ixx ixy ixz iyy iyz izz), got '
                         f'{inertia.tolist()}')
    ixx, ixy, ixz, iyy, iyz, izz = inertia
    Ip = rigid_body_inertia(f'payload on {link!r}', mass, com,
                            [[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    inertia6 = np.array(model.inertia)
    inertia6[frame.body] += frame.lXb.T @ Ip @ frame.lXb
    return replace(model, inertia=inertia6)


def _joint_axis(joint) -> np.ndarray:
    """Return the unit joint axis (normalised, as Pinocchio, KDL and MuJoCo do)."""
    axis = _finite(f'joint {joint.name!r} axis', joint.axis if joint.axis is not None
                   else (1.0, 0.0, 0.0))
    if axis.shape != (3,):
        raise ValueError(f'joint {joint.name!r}: axis must have 3 components, got {axis}')
    norm = float(np.linalg.norm(axis))
    if not norm > 1e-12:
        raise ValueError(f'joint {joint.name!r}: zero-length axis {axis.tolist()}')
    return axis / norm


def _number(what: str, value, default: float = math.nan) -> float:
    if value is None:
        return default
    try:
        return float(_finite(what, float(value)))
    except (TypeError, ValueError) as err:
        raise ValueError(f'{what}: {err}') from None


def _limit(what: str, value) -> float:
    """Return a ``<limit>`` value: any magnitude (±1e16 or ±inf mean none), NaN refused."""
    if value is None:
        return math.nan
    try:
        x = float(value)
    except (TypeError, ValueError) as err:
        raise ValueError(f'{what}: {err}') from None
    if math.isnan(x):
        raise ValueError(f'{what}: non-finite number {value!r} (a limit may be any size, '
                         'or ±inf for none, but not NaN)')
    return x


def _from_robot(parsed, keep: Optional[Sequence[str]] = None,
                locked: Optional[Mapping[str, float]] = None,
                report: Optional[_Report] = None) -> Model:
    robot_name, links, joints = parsed
    report = report or _Report(strict=False)
    if not robot_name:
        robot_name = 'robot'
        report("the <robot> element has no name attribute (urdfdom's parser refuses such a "
               "file); the model is named 'robot'")
    link_by_name = {}
    for link in links:
        if link.name in link_by_name:
            raise ValueError(f'duplicate link name {link.name!r}')
        link_by_name[link.name] = link
    joint_by_name, parent_joint, children = {}, {}, {name: [] for name in link_by_name}
    for joint in joints:
        if joint.name in joint_by_name:
            raise ValueError(f'duplicate joint name {joint.name!r}')
        joint_by_name[joint.name] = joint
        if joint.type not in URDF_KINDS:
            if joint.type in ('floating', 'planar'):
                raise ValueError(f'joint {joint.name!r}: {joint.type} joints are not '
                                 'supported (fixed-base, 1-DOF joints only)')
            raise ValueError(f'joint {joint.name!r}: unknown joint type {joint.type!r}')
        for role, link in (('parent', joint.parent), ('child', joint.child)):
            if link not in link_by_name:
                raise ValueError(f'joint {joint.name!r}: unknown {role} link {link!r}')
        if joint.child in parent_joint:
            raise ValueError(f'link {joint.child!r} is the child of two joints: '
                             f'{parent_joint[joint.child].name!r} and {joint.name!r}')
        parent_joint[joint.child] = joint
        children[joint.parent].append(joint)
    if not link_by_name:
        raise ValueError(f'robot {robot_name!r} has no links')
    roots = [name for name in link_by_name if name not in parent_joint]
    if len(roots) != 1:
        if not roots:
            link, cycle = next(iter(link_by_name)), []
            while link not in cycle:   # every link has a parent joint: walk up to a repeat
                cycle.append(link)
                link = parent_joint[link].parent
            cycle = cycle[cycle.index(link):]
            raise ValueError('the joints form a cycle, so there is no root link: '
                             + ' -> '.join(f'{parent_joint[c].name!r}' for c in cycle)
                             + f' (links {cycle})')
        raise ValueError(f'several root links (a URDF is one tree): {roots}')

    lock = _locked_values(joint_by_name, keep, locked)

    # Each link gets its body and the pose (R, p) of its frame in that body's frame;
    # movable joints start new bodies, so parent[i] < i.
    body_names, body_joints, parent, jtype, axis, Xtree = [roots[0]], [''], [-1], [FIXED], \
        [np.zeros(3)], [np.eye(6)]
    pose = {roots[0]: (0, np.eye(3), np.zeros(3))}
    order = [roots[0]]
    for joints_below in children.values():
        # Pinocchio's (and urdfdom's, so KDL's) order: children by joint name, byte-wise.
        joints_below.sort(key=lambda j: j.name.encode('utf-8'))
    stack = list(reversed(children[roots[0]]))
    while stack:  # depth-first preorder
        joint = stack.pop()
        b, R_bl, p_bl = pose[joint.parent]
        R_o, p_o = _origin(f'joint {joint.name!r}', joint.origin)
        # Child link frame in body b's frame at q = 0.
        R, p = R_bl @ R_o, R_bl @ p_o + p_bl
        if joint.name in lock:
            # A locked joint is a fixed joint displaced by its value.
            R, p = _displaced(joint, lock[joint.name], R, p)
        if URDF_KINDS[joint.type] == FIXED or joint.name in lock:
            pose[joint.child] = (b, R, p)
        else:
            body_names.append(joint.child)
            body_joints.append(joint.name)
            parent.append(b)
            jtype.append(URDF_KINDS[joint.type])
            axis.append(_joint_axis(joint))
            Xtree.append(plux(R.T, p))
            pose[joint.child] = (len(body_names) - 1, np.eye(3), np.zeros(3))
        order.append(joint.child)
        stack.extend(reversed(children[joint.child]))
    if len(order) != len(link_by_name):
        lost = sorted(set(link_by_name) - set(order))
        raise ValueError(f'the joints form a cycle: links {lost} are not reachable from the '
                         f'root link {roots[0]!r}')
    NB = len(body_names) - 1

    # Inertias of all links, lumped into their bodies: I_b += lXbᵀ I_l lXb (RBDA eq. 2.66).
    inertia = np.zeros((NB + 1, 6, 6))
    frames = {}
    for name in order:
        b, R, p = pose[name]
        lXb = plux(R.T, p)
        frames[name] = Frame(b, lXb)
        frames[name].lXb.setflags(write=False)
        inertia[b] += lXb.T @ _link_inertia(link_by_name[name], report) @ lXb

    # Generalised coordinates: movable non-mimic joints in body order; mimic joints follow
    # their (transitively resolved) source: q_i = mult·q_src + offset.
    joint_names = tuple(keep) if keep is not None else tuple(
        j for j in body_joints[1:] if joint_by_name[j].mimic is None)
    index = {j: k for k, j in enumerate(joint_names)}
    qidx, qmul, qoff = [-1], [0.0], [0.0]
    for jname in body_joints[1:]:
        src, mult, off = _resolve_mimic(jname, joint_by_name)
        qidx.append(index[src])
        qmul.append(mult)
        qoff.append(off)

    def per_joint(get) -> np.ndarray:
        return np.array([get(joint_by_name[j]) for j in joint_names], dtype=float)

    def limit(attr):
        return per_joint(lambda j: _limit(f'joint {j.name!r} <limit {attr}>',
                                          getattr(j.limit, attr, None)))

    def dyn(attr, names=joint_names):
        values = []
        for j in names:
            what = f'joint {j!r} <dynamics {attr}>'
            x = _number(what, getattr(joint_by_name[j].dynamics, attr, None), 0.0)
            if x < 0.0 and names is not joint_names:   # reported once, for every body
                report(f'{what}: negative ({x:g}), so the joint would gain energy')
            values.append(x)
        return np.array(values)

    return Model(
        name=robot_name, joint_names=joint_names, body_names=tuple(body_names),
        body_joints=tuple(body_joints), NB=NB, parent=np.array(parent, dtype=np.intp),
        jtype=np.array(jtype, dtype=np.intp), axis=np.array(axis), Xtree=np.array(Xtree),
        inertia=inertia, qidx=np.array(qidx, dtype=np.intp), qmul=np.array(qmul),
        qoff=np.array(qoff), frames=frames, effort_limit=limit('effort'),
        velocity_limit=limit('velocity'), lower=limit('lower'), upper=limit('upper'),
        damping=dyn('damping'), friction=dyn('friction'),
        body_damping=np.r_[0.0, dyn('damping', body_joints[1:])],
        body_friction=np.r_[0.0, dyn('friction', body_joints[1:])],
        lumped=tuple(n for n in order if pose[n][0] > 0 and n not in body_names),
        pruned=tuple(n for n in order[1:] if pose[n][0] == 0),
        locked={j: v for j, v in lock.items() if joint_by_name[j].mimic is None},
        warnings=tuple(report.messages))


def _resolve_mimic(jname: str, joint_by_name: dict) -> tuple[str, float, float]:
    """Follow a chain of ``<mimic>`` tags to a non-mimic joint: ``(its name, mult, offset)``.

    The joint then moves by ``mult·q_src + offset``.
    """
    mult, off, seen = 1.0, 0.0, [jname]
    joint = joint_by_name[jname]
    while joint.mimic is not None:
        src = joint.mimic.joint
        what = f'joint {joint.name!r} <mimic>'
        if src not in joint_by_name:
            raise ValueError(f'{what}: mimics a missing joint {src!r}')
        if src in seen:
            raise ValueError(f'{what}: mimic joints form a loop {seen + [src]}')
        if URDF_KINDS.get(joint_by_name[src].type, FIXED) == FIXED:
            raise ValueError(f'{what}: mimics {src!r}, which is not movable')
        m = _number(f'{what} multiplier', joint.mimic.multiplier, 1.0)
        o = _number(f'{what} offset', joint.mimic.offset, 0.0)
        mult, off = mult * m, mult * o + off
        seen.append(src)
        joint = joint_by_name[src]
    return joint.name, mult, off


def _locked_values(joint_by_name: dict, keep, locked) -> dict:
    """Joint name → locked value for every movable joint that model reduction locks."""
    locked = dict(locked or {})
    movable = [j for j, jt in joint_by_name.items() if URDF_KINDS[jt.type] != FIXED]
    independent = {j for j in movable if joint_by_name[j].mimic is None}
    for j, v in locked.items():
        if j not in independent:
            why = 'is a mimic joint (lock its source)' if j in movable else \
                'is not a movable joint of the URDF'
            raise ValueError(f'locked joint {j!r} {why}')
        locked[j] = _number(f'locked joint {j!r} value', v)
    if keep is None:
        if locked:
            raise ValueError(f'locked joints {sorted(locked)} need a list of kept joints')
        return {}
    if isinstance(keep, str):
        raise ValueError('joints must be a list of joint names, not a string')
    for j in keep:
        if j not in independent:
            why = 'is a mimic joint (keep its source)' if j in movable else \
                'is not a movable joint of the URDF'
            raise ValueError(f'kept joint {j!r} {why}')
        if j in locked:
            raise ValueError(f'joint {j!r} is both kept and locked')
    if len(set(keep)) != len(keep):
        raise ValueError(f'joints lists a joint twice: {list(keep)}')
    lock = {j: locked.get(j, 0.0) for j in independent if j not in keep}
    for j in movable:
        src, mult, off = _resolve_mimic(j, joint_by_name)
        if j not in independent and src in lock:
            lock[j] = mult * lock[src] + off
    return lock


def _displaced(joint, value: float, R: np.ndarray, p: np.ndarray):
    """Pose of a joint's child frame moved by ``value`` along/about its axis."""
    axis = _joint_axis(joint)
    if URDF_KINDS[joint.type] == PRISMATIC:
        return R, p + R @ (axis * value)
    return R @ Eaxis(axis, value).T, p


# --------------------------------------------------------------------------------------------
# Flat per-body data for the component-wise RNEA kernel (plain floats, see rnea.py)

#: Kernel joint codes: revolute about ±x, ±y, ±z (the axis keeps its sign) or a general axis;
#: prismatic.
RX, RY, RZ, RA, PR = 0, 1, 2, 3, 4


def _kernel_data(model: Model) -> tuple:
    rows = []
    for i in range(1, model.NB + 1):
        E, r = plux_Er(model.Xtree[i])
        ax = model.axis[i]
        if model.jtype[i] == REVOLUTE:
            code = RA
            for k in range(3):
                if abs(ax[k]) == 1.0 and ax[(k + 1) % 3] == 0.0 and ax[(k + 2) % 3] == 0.0:
                    code = k    # about ±x, ±y or ±z: the cheaper form (sin times ±1)
        elif model.jtype[i] == PRISMATIC:
            code = PR
        else:  # pragma: no cover - bodies always hang on movable joints
            raise AssertionError('body without a movable joint')
        Ii = model.inertia[i]
        m = float(Ii[3, 3])
        # I = [[Ibar, h×], [h×ᵀ, m 1]] with h = m c (RBDA eq. 2.63): read h off I[:3, 3:].
        h = (float(Ii[2, 4]), float(Ii[0, 5]), float(Ii[1, 3]))
        Ibar = (float(Ii[0, 0]), float(Ii[0, 1]), float(Ii[0, 2]),
                float(Ii[1, 1]), float(Ii[1, 2]), float(Ii[2, 2]))
        rows.append((int(model.parent[i]), code, tuple(float(x) for x in ax),
                     tuple(float(x) for x in E.ravel()), tuple(float(x) for x in r),
                     m, h, Ibar, int(model.qidx[i]), float(model.qmul[i]),
                     float(model.qoff[i])))
    return tuple(rows)


# The same rows as one float64 table (NB+1, TABLE_WIDTH) for the compiled kernel (one array
# is one argument to unbox per call): row ``i`` = body ``i``; columns below. Small integers
# (parent, joint code, index into q) are exact in float64. Row 0 (the fixed base) holds
# parent -1, and ``n = len(q)`` in its QIDX column, which the kernel checks lengths against.
# Private and, alone among the model's arrays, left writable: numba types a read-only array
# on its slow path, which costs ~30 ns of a ~1 µs call. Nothing writes to it.
(T_PARENT, T_CODE, T_QIDX, T_AXIS, T_E, T_R, T_MASS, T_H, T_IBAR, T_MUL, T_OFF,
 TABLE_WIDTH) = 0, 1, 2, 3, 6, 15, 18, 19, 22, 28, 29, 30


def _kernel_table(n: int, rows: tuple) -> np.ndarray:
    K = np.zeros((len(rows) + 1, TABLE_WIDTH))
    K[0, T_PARENT], K[0, T_QIDX] = -1, n
    for i, (p, code, axis, Et, r, mass, h, Ib, k, mul, off) in enumerate(rows, start=1):
        K[i, T_PARENT], K[i, T_CODE], K[i, T_QIDX] = p, code, k
        K[i, T_AXIS:T_AXIS + 3] = axis
        K[i, T_E:T_E + 9] = Et
        K[i, T_R:T_R + 3] = r
        K[i, T_MASS] = mass
        K[i, T_H:T_H + 3] = h
        K[i, T_IBAR:T_IBAR + 6] = Ib
        K[i, T_MUL], K[i, T_OFF] = mul, off
    return K
