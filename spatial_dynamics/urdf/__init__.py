# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""URDF → :class:`~spatial_dynamics.model.Model`: parsing, lumping, mimic, reduction, policy.

Only the elements the dynamics uses are read (``<inertial>``, joint ``<origin>``, ``<axis>``,
``<limit>``, ``<dynamics>``, ``<mimic>``); visuals, collisions, meshes, transmissions and
plugins are never looked at. The XML is parsed without DTDs, entities or network access.

The policy, for descriptions as they come out of CAD exporters:

* **refused** (``ValueError`` naming the element): what makes the computation meaningless —
  malformed XML, entities or a DTD, unknown links, cycles, several roots, a non-finite or
  absurd (> ``MAX_ABS_VALUE``) number the dynamics uses, negative mass, a zero-length axis, a
  mimic of a missing joint, unsupported joint types;
* **loaded exactly as written, with a** :class:`URDFWarning`: what is physically inconsistent
  but computable — an inertia that is not positive semi-definite or breaks the triangle
  inequality, inertia on a massless link, negative damping or friction, a lower limit
  above the upper one, no robot name;
  ``strict=True`` refuses these too;
* **silent**: rounding noise (``INERTIA_RTOL``, ``INERTIA_ATOL``), limits of any magnitude
  (``±1e16`` or ``inf`` meaning none), a non-unit axis (normalised, as every tool does).
"""

from __future__ import annotations

from dataclasses import dataclass
import math
import os
import re
from typing import Mapping, Optional, Sequence, Union
import warnings

import numpy as np

from .files import read_regular, size_text
from .joints import FIXED, FREE_FLYER, PRISMATIC, URDF_KINDS
from .model import finite, Frame, Model, rigid_body_inertia
from .spatial import Eaxis, plux, rpy_to_R

Source = Union[str, bytes, os.PathLike]

#: Largest URDF file read (bytes): a robot description is text of at most a few MB.
MAX_FILE_BYTES = 64 * 1024 * 1024
#: Largest robot description file the node reads, and ``spatial_dynamics_check`` with it
#: (the largest URDF of example-robot-data is < 1 MiB).
MAX_DESCRIPTION_BYTES = 32 * 1024 * 1024

__all__ = ['MAX_FILE_BYTES', 'model_from_urdf', 'read_description', 'read_urdf_file',
           'URDFWarning']


class URDFWarning(UserWarning):
    """A URDF that loads as written but is physically inconsistent; the message names it.

    ``Model.from_urdf(..., strict=True)`` raises ``ValueError`` instead. The messages of a
    model are kept on ``Model.warnings``.
    """


class _Report:
    """Collects what is physically wrong in a URDF: warnings, or errors when ``strict``."""

    def __init__(self, strict: bool) -> None:
        self.strict = strict
        self._messages: dict = {}     # message -> None: each once, in order of first report

    def __call__(self, message: str) -> None:
        if self.strict:
            raise ValueError(f'{message} (strict mode)')
        self._messages.setdefault(message)

    @property
    def messages(self) -> tuple:
        """The messages reported, each once, in the order they were first reported."""
        return tuple(self._messages)


#: What ``Model.from_urdf(..., base=...)`` takes: the root link fixed to the world, or on a
#: free-flyer joint.
BASES = ('fixed', 'floating')
#: The name of the free-flyer joint of a floating base (Pinocchio's).
ROOT_JOINT = 'root_joint'
#: The name of body 0 of a floating-base model, the world (Pinocchio's).
WORLD = 'universe'
#: The root link a URDF fixes a robot to the world with (ROS and Gazebo's convention).
URDF_WORLD = 'world'


def model_from_urdf(source: Source, joints: Optional[Sequence[str]] = None,
                    locked: Optional[Mapping[str, float]] = None, strict: bool = False,
                    base: str = 'fixed') -> Model:
    """Build a model from a URDF; see :meth:`Model.from_urdf <.model.Model.from_urdf>`."""
    if base not in BASES:
        raise ValueError(f'base must be one of {list(BASES)}, got {base!r}')
    report = _Report(strict)
    model = _from_robot(*_parse_urdf(source, report), joints, locked, report,
                        base == 'floating')
    for message in model.warnings:
        warnings.warn(message, URDFWarning, stacklevel=3)
    return model


# --------------------------------------------------------------------------------------------
# Reading and parsing

def read_urdf_file(path: str, limit: int = MAX_FILE_BYTES) -> bytes:
    """Return the bytes of a URDF file: a regular file of at most ``limit`` bytes.

    Read by :func:`spatial_dynamics.files.read_regular`: never blocks on a FIFO or reads a
    device. ``ValueError`` names the path and the reason.
    """
    return read_regular(path, f'URDF file {path!r}', limit)


def read_description(path: str, limit: int = MAX_FILE_BYTES, what: str = '') -> str:
    """Return the URDF text of a file; a ``.xacro`` file is expanded when xacro is importable.

    The one reader of description files (library, node, ``spatial_dynamics_check``, sim, replay):
    the file is read by :func:`read_urdf_file` (a regular file of at most ``limit`` bytes, never a
    FIFO or a device; a ``.xacro`` file passes the same check before xacro opens it), decoded as
    UTF-8 (a byte order mark is dropped); the expansion of a ``.xacro`` file is held to the same
    limit. ``ValueError`` names the file as ``what`` (default ``URDF file 'path'``).
    """
    what = what or f'URDF file {path!r}'
    data = read_regular(path, what, limit)
    if str(path).endswith('.xacro'):
        try:
            import xacro
        except ImportError:
            raise ValueError(f'{what}: a .xacro file needs the xacro module (pip install '
                             'xacro, or apt ros-jazzy-xacro)') from None
        try:
            text = xacro.process_file(path).toxml()
        except Exception as err:  # xacro raises many types; all mean "cannot expand"
            raise ValueError(f'{what}: xacro failed: {err}') from None
        if len(text) > limit:
            raise ValueError(f'{what}: expands to more than the limit of {size_text(limit)} '
                             'for a robot description')
        return text
    try:
        return data.decode('utf-8-sig')
    except UnicodeDecodeError as err:
        raise ValueError(f'{what}: not UTF-8 text (byte 0x{data[err.start]:02x} at offset '
                         f'{err.start}); a URDF file must be UTF-8') from None


@dataclass(frozen=True)
class _Link:
    name: str
    inertia: np.ndarray       # spatial inertia (6×6) in the link frame


@dataclass(frozen=True)
class _Joint:
    name: str
    type: str
    parent: str
    child: str
    R: np.ndarray             # child frame → parent frame rotation at q = 0 (<origin rpy>)
    p: np.ndarray             # child frame origin in the parent frame (<origin xyz>), m
    axis: tuple               # <axis xyz> as written (checked where used)
    limit: dict               # lower, upper, effort, velocity (nan when absent)
    damping: float
    friction: float
    mimic: Optional[tuple]    # (source joint, multiplier, offset)


_XML_VERSION = re.compile(rb'^(\s*<\?xml\s+version\s*=\s*)(["\'])[^"\']*\2')


def _parse_urdf(source: Source, report: _Report) -> tuple:
    """Return ``(robot name, [_Link], [_Joint])`` of a URDF path, XML string or XML bytes."""
    try:
        from lxml import etree
    except ImportError:
        raise ModuleNotFoundError(
            'reading a URDF needs lxml, which is not installed: pip install lxml (Debian and '
            'Ubuntu: apt install python3-lxml; ROS: rosdep key python3-lxml)',
            name='lxml') from None

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
    # Whitespace before the XML declaration, or a version other than 1.0 in it, does not
    # change what a URDF means (urdfdom reads both; libxml2 refuses them).
    text = _XML_VERSION.sub(rb'\g<1>"1.0"', text.lstrip(b' \t\r\n'), count=1)

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
    name = root.get('name')
    if not name:
        name = 'robot'
        report("the <robot> element has no name attribute (urdfdom's parser refuses such a "
               "file); the model is named 'robot'")
    links = [_parse_link(el, report) for el in root.findall('link')]
    joints = [_parse_joint(el) for el in root.findall('joint')]
    return name, links, joints


def _name(el, tag: str) -> str:
    name = el.get('name')
    if not name:
        raise ValueError(f'a <{tag}> element has no name attribute')
    return name


def _attribute(what: str, el, attr: str, default: Optional[str] = None) -> str:
    value = el.get(attr) if el is not None else None
    if value is None:
        if default is None:
            raise ValueError(f'{what}: missing attribute {attr!r}')
        return default
    return value


def _vector(what: str, text: str, size: int = 3) -> np.ndarray:
    """Return ``size`` finite numbers written as one attribute (``"x y z"``)."""
    parts = text.split()
    if len(parts) != size:
        raise ValueError(f'{what}: need {size} numbers, got {text!r}')
    try:
        values = [float(x) for x in parts]
    except ValueError:
        raise ValueError(f'{what}: not a number in {text!r}') from None
    return finite(what, values)


def _scalar(what: str, text: Optional[str], default: float) -> float:
    if text is None:
        return default
    try:
        x = float(text)
    except ValueError:
        raise ValueError(f'{what}: not a number: {text!r}') from None
    return float(finite(what, x))


def _origin(what: str, el) -> tuple[np.ndarray, np.ndarray]:
    """Rotation ``R`` (child → parent coordinates) and position ``p`` of an ``<origin>``."""
    if el is None:
        return np.eye(3), np.zeros(3)
    what = f'{what} origin'
    p = _vector(what, el.get('xyz', '0 0 0'))
    return rpy_to_R(_vector(what, el.get('rpy', '0 0 0'))), p


def _parse_link(el, report: _Report) -> _Link:
    """Read a ``<link>``: its spatial inertia in the link frame (zero without ``<inertial>``)."""
    name = _name(el, 'link')
    inertial = el.find('inertial')
    if inertial is None:
        return _Link(name, np.zeros((6, 6)))
    what = f'link {name!r} <inertial>'
    R, c = _origin(what, inertial.find('origin'))
    mass_el = inertial.find('mass')
    mass = _scalar(f'{what} mass', mass_el.get('value') if mass_el is not None else None, 0.0)
    inertia_el = inertial.find('inertia')
    if inertia_el is None:
        Ic = np.zeros((3, 3))
    else:
        ixx, ixy, ixz, iyy, iyz, izz = (
            _scalar(f'{what} inertia {k}', _attribute(f'{what} <inertia>', inertia_el, k), 0.0)
            for k in ('ixx', 'ixy', 'ixz', 'iyy', 'iyz', 'izz'))
        Ic = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    return _Link(name, rigid_body_inertia(what, mass, c, Ic, R, report))


def _parse_joint(el) -> _Joint:
    """Read a ``<joint>``: kind, links, origin, axis, limits, dynamics and mimic."""
    name = _name(el, 'joint')
    what = f'joint {name!r}'
    kind = _attribute(what, el, 'type')
    links = []
    for role in ('parent', 'child'):
        tag = el.find(role)
        if tag is None or not tag.get('link'):
            raise ValueError(f'{what}: missing <parent> or <child> element (with a link '
                             'attribute)')
        links.append(tag.get('link'))
    R, p = _origin(what, el.find('origin'))
    axis_el = el.find('axis')
    axis = tuple(_attribute(f'{what} <axis>', axis_el, 'xyz').split()) \
        if axis_el is not None else ('1', '0', '0')
    limit_el = el.find('limit')
    limit = {k: _limit(f'{what} <limit {k}>', limit_el.get(k) if limit_el is not None else None)
             for k in ('lower', 'upper', 'effort', 'velocity')}
    dyn = el.find('dynamics')
    damping, friction = (
        _scalar(f'{what} <dynamics {k}>', dyn.get(k) if dyn is not None else None, 0.0)
        for k in ('damping', 'friction'))
    mimic_el = el.find('mimic')
    mimic = None
    if mimic_el is not None:
        mimic = (_attribute(f'{what} <mimic>', mimic_el, 'joint'),
                 _scalar(f'{what} <mimic> multiplier', mimic_el.get('multiplier'), 1.0),
                 _scalar(f'{what} <mimic> offset', mimic_el.get('offset'), 0.0))
    return _Joint(name, kind, links[0], links[1], R, p, axis, limit, damping, friction, mimic)


def _limit(what: str, text: Optional[str]) -> float:
    """Return a ``<limit>`` value: any magnitude (±1e16 or ±inf mean none), NaN refused."""
    if text is None:
        return math.nan
    try:
        x = float(text)
    except ValueError:
        raise ValueError(f'{what}: not a number: {text!r}') from None
    if math.isnan(x):
        raise ValueError(f'{what}: non-finite number {text!r} (a limit may be any size, '
                         'or ±inf for none, but not NaN)')
    return x


def _joint_axis(joint: _Joint) -> np.ndarray:
    """Return the unit joint axis (normalised, as Pinocchio, KDL and MuJoCo do)."""
    what = f'joint {joint.name!r} axis'
    axis = _vector(what, ' '.join(joint.axis))
    norm = float(np.linalg.norm(axis))
    if not norm > 1e-12:
        raise ValueError(f'joint {joint.name!r}: zero-length axis {axis.tolist()}')
    return axis / norm


# --------------------------------------------------------------------------------------------
# The tree

def _from_robot(robot_name: str, links: list, joints: list,
                keep: Optional[Sequence[str]], locked: Optional[Mapping[str, float]],
                report: _Report, floating: bool = False) -> Model:
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
                                 'supported (1-DOF joints only; a root link that moves is '
                                 "loaded with base='floating')")
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
            link, step = next(iter(link_by_name)), {}
            while link not in step:    # every link has a parent joint: walk up to a repeat
                step[link] = len(step)
                link = parent_joint[link].parent
            cycle = list(step)[step[link]:]
            raise ValueError('the joints form a cycle, so there is no root link: '
                             + ' -> '.join(f'{parent_joint[c].name!r}' for c in cycle)
                             + f' (links {cycle})')
        raise ValueError(f'several root links (a URDF is one tree): {roots}')

    if floating and ROOT_JOINT in joint_by_name:
        raise ValueError(f'joint {ROOT_JOINT!r}: the URDF has a joint of the name a floating '
                         "base gives its free-flyer joint (base='floating')")
    if floating and roots[0] == URDF_WORLD:
        fixed = [j.name for j in children[roots[0]] if j.type == 'fixed']
        through = (f' through fixed joint{"s" if len(fixed) > 1 else ""} '
                   + ', '.join(repr(j) for j in fixed) if fixed else '')
        report(f'the free-flyer is attached to {URDF_WORLD!r}{through}; did you mean a fixed '
               "base? (the URDF's root link is the world it is fixed to: base='fixed')")
    if floating and keep is not None and not isinstance(keep, str):
        keep = [j for j in keep if j != ROOT_JOINT]     # the free-flyer is always kept
    mimics: dict = {}     # joint name -> its resolved source, mult, offset (_resolve_mimic)
    lock = _locked_values(joint_by_name, keep, locked, mimics)

    # Each link gets its body and the pose (R, p) of its frame in that body's frame;
    # movable joints start new bodies, so parent[i] < i. A floating base: body 0 is the
    # world, body 1 the root link on a free-flyer joint (RBDA §4.5).
    body_names, body_joints, parent, jtype, axis, Xtree = [roots[0]], [''], [-1], [FIXED], \
        [np.zeros(3)], [np.eye(6)]
    if floating:
        body_names[0] = WORLD
        body_names.append(roots[0])
        body_joints.append(ROOT_JOINT)
        parent.append(0)
        jtype.append(FREE_FLYER)
        axis.append(np.zeros(3))
        Xtree.append(np.eye(6))
    pose = {roots[0]: (len(body_names) - 1, np.eye(3), np.zeros(3))}
    order = [roots[0]]
    for joints_below in children.values():
        # Pinocchio's (and urdfdom's, so KDL's) order: children by joint name, byte-wise.
        joints_below.sort(key=lambda j: j.name.encode('utf-8'))
    stack = list(reversed(children[roots[0]]))
    while stack:  # depth-first preorder
        joint = stack.pop()
        b, R_bl, p_bl = pose[joint.parent]
        # Child link frame in body b's frame at q = 0.
        R, p = R_bl @ joint.R, R_bl @ joint.p + p_bl
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
        inertia[b] += lXb.T @ link_by_name[name].inertia @ lXb

    # Generalised coordinates: movable non-mimic joints in body order; mimic joints follow
    # their (transitively resolved) source: q_i = mult·q_src + offset. A floating base's
    # free-flyer comes first: 7 coordinates of q, 6 of q̇.
    first = 2 if floating else 1        # the first body on a joint of the URDF
    joint_names = tuple(keep) if keep is not None else tuple(
        j for j in body_joints[first:] if joint_by_name[j].mimic is None)
    index = {j: k for k, j in enumerate(joint_names)}
    qidx, vidx, qmul, qoff = [-1], [-1], [0.0], [0.0]
    if floating:
        qidx.append(0)
        vidx.append(0)
        qmul.append(1.0)
        qoff.append(0.0)
    q0, v0 = (7, 6) if floating else (0, 0)
    for jname in body_joints[first:]:
        src, mult, off = _resolve_mimic(jname, joint_by_name, mimics)
        qidx.append(q0 + index[src])
        vidx.append(v0 + index[src])
        qmul.append(mult)
        qoff.append(off)
    for jname in body_joints[first:]:
        for attr in ('damping', 'friction'):
            value = getattr(joint_by_name[jname], attr)
            if value < 0.0:
                report(f'joint {jname!r} <dynamics {attr}>: negative ({value:g}), so the '
                       'joint would gain energy')

    for joint in joints:
        lower, upper = joint.limit['lower'], joint.limit['upper']
        if joint.type in ('revolute', 'prismatic') and lower > upper:
            report(f'joint {joint.name!r} <limit>: lower ({lower:g}) is above upper '
                   f'({upper:g}), so no position is within its limits')

    def per_joint(get, names=joint_names, base=math.nan) -> np.ndarray:
        """One value per velocity coordinate: the free-flyer's six ``base``."""
        return np.array([base] * v0 + [get(joint_by_name[j]) for j in names], dtype=float)

    def per_body(get) -> np.ndarray:
        return np.r_[[0.0] * first, [get(joint_by_name[j]) for j in body_joints[first:]]]

    return Model(
        name=robot_name, joint_names=((ROOT_JOINT,) if floating else ()) + joint_names,
        body_names=tuple(body_names), vidx=np.array(vidx, dtype=np.intp),
        body_joints=tuple(body_joints), NB=NB, parent=np.array(parent, dtype=np.intp),
        jtype=np.array(jtype, dtype=np.intp), axis=np.array(axis), Xtree=np.array(Xtree),
        inertia=inertia, qidx=np.array(qidx, dtype=np.intp), qmul=np.array(qmul),
        qoff=np.array(qoff), frames=frames,
        effort_limit=per_joint(lambda j: j.limit['effort']),
        velocity_limit=per_joint(lambda j: j.limit['velocity']),
        lower=per_joint(lambda j: j.limit['lower']),
        upper=per_joint(lambda j: j.limit['upper']),
        damping=per_joint(lambda j: j.damping, base=0.0),
        friction=per_joint(lambda j: j.friction, base=0.0),
        body_damping=per_body(lambda j: j.damping),
        body_friction=per_body(lambda j: j.friction),
        lumped=tuple(n for n in order if pose[n][0] > 0 and body_names[pose[n][0]] != n),
        pruned=tuple(n for n in order[1:] if pose[n][0] == 0),
        locked={j: v for j, v in lock.items() if joint_by_name[j].mimic is None},
        warnings=tuple(report.messages),
        joint_types={name: j.type for name, j in joint_by_name.items()},
        mimics={name: j.mimic for name, j in joint_by_name.items() if j.mimic is not None})


def _resolve_mimic(jname: str, joint_by_name: dict, resolved: dict
                   ) -> tuple[str, float, float]:
    """Follow a chain of ``<mimic>`` tags to a non-mimic joint: ``(its name, mult, offset)``.

    The joint then moves by ``mult·q_src + offset``: a joint mimicking ``src`` by ``(m, o)``
    moves by ``m·(mult_src·q + off_src) + o``. ``resolved`` (joint name → result) is filled
    for every mimic joint on the way, so resolving all joints walks each tag once.
    """
    if jname in resolved:
        return resolved[jname]
    path, seen = [], {jname: None}     # the mimic joints walked; their names, in order
    joint = joint_by_name[jname]
    while joint.mimic is not None and joint.name not in resolved:
        src, m, o = joint.mimic
        what = f'joint {joint.name!r} <mimic>'
        if src not in joint_by_name:
            raise ValueError(f'{what}: mimics a missing joint {src!r}')
        if src in seen:
            raise ValueError(f'{what}: mimic joints form a loop {list(seen) + [src]}')
        if URDF_KINDS.get(joint_by_name[src].type, FIXED) == FIXED:
            raise ValueError(f'{what}: mimics {src!r}, which is not movable')
        path.append(joint)
        seen[src] = None
        joint = joint_by_name[src]
    source = resolved.get(joint.name)
    for joint in reversed(path):
        _, m, o = joint.mimic
        if source is None:    # mimics a non-mimic joint
            source = resolved[joint.name] = (joint.mimic[0], 1.0 * m, 1.0 * o + 0.0)
        else:
            src, mult, off = source
            source = resolved[joint.name] = (src, m * mult, m * off + o)
    return source if source is not None else (jname, 1.0, 0.0)


def _locked_values(joint_by_name: dict, keep, locked, mimics: dict) -> dict:
    """Joint name → locked value for every movable joint that model reduction locks.

    In URDF order; ``mimics`` is the table of :func:`_resolve_mimic`.
    """
    locked = dict(locked or {})
    movable = [j for j, jt in joint_by_name.items() if URDF_KINDS[jt.type] != FIXED]
    independent = {j for j in movable if joint_by_name[j].mimic is None}
    for j, v in locked.items():
        if j not in independent:
            why = 'is a mimic joint (lock its source)' if j in movable else \
                'is not a movable joint of the URDF'
            raise ValueError(f'locked joint {j!r} {why}')
        try:
            value = float(v)
        except (TypeError, ValueError) as err:
            raise ValueError(f'locked joint {j!r} value: {err}') from None
        locked[j] = float(finite(f'locked joint {j!r} value', value))
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
    kept = set(keep)
    if len(kept) != len(keep):
        raise ValueError(f'joints lists a joint twice: {list(keep)}')
    lock = {j: locked.get(j, 0.0) for j in movable if j in independent and j not in kept}
    for j in movable:
        src, mult, off = _resolve_mimic(j, joint_by_name, mimics)
        if j not in independent and src in lock:
            lock[j] = mult * lock[src] + off
    return lock


def _displaced(joint: _Joint, value: float, R: np.ndarray, p: np.ndarray):
    """Pose of a joint's child frame moved by ``value`` along/about its axis."""
    axis = _joint_axis(joint)
    if URDF_KINDS[joint.type] == PRISMATIC:
        return R, p + R @ (axis * value)
    return R @ Eaxis(axis, value).T, p
