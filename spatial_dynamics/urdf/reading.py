# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Read a URDF: the file, the XML, and each number the dynamics uses, into link and joint records.

:func:`read_description` is the one reader of description files; :func:`_parse_urdf` turns
URDF text into ``(robot name, [_Link], [_Joint])``, refusing what cannot be computed and
reporting to a :class:`_Report` what is physically odd (the policy of
:mod:`spatial_dynamics.urdf`). lxml is imported inside :func:`_parse_urdf` and xacro inside
:func:`read_description`: optional dependencies (the package imports without them; lxml also
costs start-up time), needed only when a URDF is read.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
import os
import re
from typing import Optional, Union

import numpy as np

from ..files import read_regular, size_text
from ..model import finite, rigid_body_inertia
from ..spatial import rpy_to_R
from ..text import shown

Source = Union[str, bytes, os.PathLike]

#: Largest URDF file read (bytes): a robot description is text of at most a few MB.
MAX_FILE_BYTES = 64 * 1024 * 1024
#: Largest robot description file the node reads, and ``spatial_dynamics_check`` with it
#: (the largest URDF of example-robot-data is < 1 MiB).
MAX_DESCRIPTION_BYTES = 32 * 1024 * 1024


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
        raise ValueError(f'URDF refers to an external DTD ({shown(docinfo.system_url)}): not '
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
            raise ValueError(f'{what}: missing attribute {shown(attr)}')
        return default
    return value


def _vector(what: str, text: str, size: int = 3) -> np.ndarray:
    """Return ``size`` finite numbers written as one attribute (``"x y z"``)."""
    parts = text.split()
    if len(parts) != size:
        raise ValueError(f'{what}: need {size} numbers, got {shown(text)}')
    try:
        values = [float(x) for x in parts]
    except ValueError:
        raise ValueError(f'{what}: not a number in {shown(text)}') from None
    return finite(what, values)


def _scalar(what: str, text: Optional[str], default: float) -> float:
    if text is None:
        return default
    try:
        x = float(text)
    except ValueError:
        raise ValueError(f'{what}: not a number: {shown(text)}') from None
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
    what = f'link {shown(name)} <inertial>'
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
    what = f'joint {shown(name)}'
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
        raise ValueError(f'{what}: not a number: {shown(text)}') from None
    if math.isnan(x):
        raise ValueError(f'{what}: non-finite number {shown(text)} (a limit may be any size, '
                         'or ±inf for none, but not NaN)')
    return x


def _joint_axis(joint: _Joint) -> np.ndarray:
    """Return the unit joint axis (normalised, as Pinocchio, KDL and MuJoCo do)."""
    what = f'joint {shown(joint.name)} axis'
    axis = _vector(what, ' '.join(joint.axis))
    norm = float(np.linalg.norm(axis))
    if not norm > 1e-12:
        raise ValueError(f'joint {shown(joint.name)}: zero-length axis {axis.tolist()}')
    return axis / norm
