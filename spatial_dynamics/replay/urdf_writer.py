# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Write the user's URDF back with only the identified elements replaced.

The corrected file is the user's text byte for byte, except the ``<inertial>`` of each link
whose parameters were identified and the ``<dynamics>`` of each joint whose damping and
friction were (an element is inserted where the link or joint had none). Elements are found
with expat's byte offsets, so comments, formatting, attribute order, ``<gazebo>`` and
``<ros2_control>`` blocks stay as they were.

The model lumps links fixed to each other into one body; what is identified is the body.
The change ``ΔI = I_identified − I_URDF`` of a body goes into the ``<inertial>`` of the link
that starts it (whose frame is the body's), the links fixed to it keep theirs; should that
leave the link's own inertia physically unrealisable (a big change on a light link with
heavy fixed children), the whole body goes into the link and the fixed links' ``<inertial>``
are removed, which the notes say.
"""

from __future__ import annotations

from dataclasses import dataclass
import re
from typing import Dict, List, Optional, Tuple, Union
from xml.parsers import expat

import numpy as np

from ..identification import _ten, mass_com_inertia, pseudo_inertia
from ..model import Model
from ..text import shown
from ..urdf import _parse_urdf, _Report


@dataclass
class _Element:
    """A top-level ``<link>`` or ``<joint>`` and its children's byte spans."""

    tag: str
    name: str
    start: int              # the '<' of the start tag
    open_end: int           # just after the start tag's '>'
    end: int                # just after the element (its end tag, or '/>')
    empty: bool             # written as <link .../>
    children: Dict[str, Tuple[int, int]]


def _tag_end(data: bytes, at: int) -> int:
    """Return the index just after the ``>`` closing the tag that starts at ``at``."""
    quote = None
    for k in range(at, len(data)):
        ch = data[k]
        if quote is not None:
            if ch == quote:
                quote = None
        elif ch in (0x22, 0x27):        # " '
            quote = ch
        elif ch == 0x3E:                # >
            return k + 1
    raise ValueError('unterminated tag')


#: What may come before the XML declaration in a file the loader reads: a UTF-8 byte order
#: mark (the reader drops it) and whitespace (the loader strips it; expat refuses both).
_LEAD = re.compile(rb'(?:\xef\xbb\xbf)?[ \t\r\n]*')


def _elements(data: bytes) -> Dict[Tuple[str, str], _Element]:
    """Return the robot's links and joints by ``(tag, name)`` with their byte spans.

    As the loader reads the file: from its first ``<`` (a byte order mark and whitespace
    before the XML declaration skipped), tags by their written names (an element of another
    namespace, ``xacro:property``, is no ``link``), attributes as written (no defaults from a
    DTD). ``ValueError`` when expat cannot parse it.
    """
    lead = _LEAD.match(data).end()
    parser = expat.ParserCreate()
    parser.specified_attributes = True
    stack: List[Tuple[str, int, Optional[_Element]]] = []
    found: Dict[Tuple[str, str], _Element] = {}

    def start(tag, attrs):
        at = lead + parser.CurrentByteIndex
        element = None
        if len(stack) == 1 and tag in ('link', 'joint') and 'name' in attrs:
            element = _Element(tag, attrs['name'], at, _tag_end(data, at), 0, False, {})
            found.setdefault((tag, attrs['name']), element)
        stack.append((tag, at, element))

    def end(tag):
        at = lead + parser.CurrentByteIndex
        tag, begin, element = stack.pop()
        # expat reports an empty element's end at (or, in older versions, before) its start
        # tag's end, and any other element's at the '<' of its end tag
        head_end = _tag_end(data, begin)
        empty = at <= head_end
        stop = head_end if empty else _tag_end(data, at)
        if element is not None:
            element.end, element.empty = stop, empty
        elif len(stack) == 2 and tag in ('inertial', 'dynamics') and stack[1][2] is not None:
            stack[1][2].children.setdefault(tag, (begin, stop))

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(data[lead:], True)
    except expat.ExpatError as err:
        raise ValueError(f'not XML the writer can edit: {err}') from None
    return found


@dataclass(frozen=True)
class Source:
    """The user's URDF as the writer edits it, read and checked before anything is fitted.

    ``text`` is the file's bytes, ``elements`` its links and joints with their byte spans
    (:func:`_elements`), ``inertia`` each link's spatial inertia (link frame) as the loader
    reads it from these bytes.
    """

    text: bytes
    elements: Dict[Tuple[str, str], _Element]
    inertia: Dict[str, np.ndarray]


def prepare(text: bytes, model: Model, what: str = 'the URDF') -> Source:
    """Read ``text`` (of which ``model`` was loaded) as the writer will edit it.

    ``ValueError`` naming the file as ``what`` when the writer cannot find one of the model's
    links or joints in it, so that it is said before the fit, not after.
    """
    try:
        found = _elements(text)
        # the bytes the loader was given: the reader drops a byte order mark
        links = _parse_urdf(text[_LEAD.match(text).end():], _Report(strict=False))[1]
    except ValueError as err:
        raise ValueError(f'{what}: cannot write the corrected URDF: {err}') from None
    missing = [f'{tag} {shown(name)}' for tag, names in (('link', model.frames),
                                                         ('joint', model.joint_names))
               for name in names if (tag, name) not in found]
    if missing:
        raise ValueError(f'{what}: cannot write the corrected URDF: the writer does not find '
                         f'{", ".join(missing)} in the file')
    return Source(text, found, {link.name: link.inertia for link in links})


def _number(x: float) -> str:
    """Return ``x`` to 12 significant digits (far beyond what a fit determines)."""
    text = f'{float(x):.12g}'
    return '0' if text in ('0', '-0') or abs(float(text)) < 1e-15 else text


def inertial_text(inertia: np.ndarray, indent: str) -> str:
    """Return an ``<inertial>`` element (in the link frame) of a 6×6 spatial inertia."""
    m, c, Ic = mass_com_inertia(_ten(inertia))
    inner = indent + '  '
    values = dict(ixx=Ic[0, 0], ixy=Ic[0, 1], ixz=Ic[0, 2], iyy=Ic[1, 1], iyz=Ic[1, 2],
                  izz=Ic[2, 2])
    return (f'<inertial>\n{inner}<origin xyz="{" ".join(_number(x) for x in c)}" '
            f'rpy="0 0 0"/>\n{inner}<mass value="{_number(m)}"/>\n{inner}<inertia '
            + ' '.join(f'{k}="{_number(v)}"' for k, v in values.items())
            + f'/>\n{indent}</inertial>')


def _realisable(inertia: np.ndarray) -> bool:
    """Tell whether a spatial inertia is a rigid body's (positive semi-definite pseudo-inertia)."""
    w = np.linalg.eigvalsh(pseudo_inertia(_ten(inertia)))
    return bool(w[0] >= -1e-12 * max(abs(w[-1]), 1e-300)) and inertia[3, 3] > 0.0


def _indent_of(data: bytes, at: int) -> str:
    """Return the whitespace before the line's first character up to ``at``."""
    line = data.rfind(b'\n', 0, at) + 1
    head = data[line:at]
    return head.decode() if not head.strip() else ''


def corrected_urdf(text: Union[bytes, Source], model: Model, body_inertia: Dict[int, np.ndarray],
                   link_additions: Optional[Dict[str, np.ndarray]] = None,
                   dynamics: Optional[Dict[str, Tuple[float, float]]] = None
                   ) -> Tuple[bytes, List[str]]:
    """Return the URDF ``text`` with identified elements replaced, and notes.

    ``body_inertia``: body index → its identified 6×6 spatial inertia (body frame);
    ``link_additions``: link → a 6×6 spatial inertia (link frame) added to that link's own,
    a payload; ``dynamics``: joint → ``(damping, friction)`` for its ``<dynamics>``.
    ``model`` is the one ``text`` was loaded as (same joints kept and locked); ``text`` is
    the file's bytes or their :class:`Source` from :func:`prepare`.
    """
    source = text if isinstance(text, Source) else prepare(text, model)
    text, found = source.text, source.elements
    notes: List[str] = []
    new_inertial: Dict[str, Optional[np.ndarray]] = {}     # link -> inertia, None: remove

    def link_inertia(name):
        return source.inertia.get(name, np.zeros((6, 6)))

    for body, inertia in body_inertia.items():
        link = model.body_names[body]
        new = link_inertia(link) + inertia - model.inertia[body]
        if _realisable(new):
            new_inertial[link] = new
            continue
        fixed = [name for name, frame in model.frames.items()
                 if frame.body == body and name != link]
        new_inertial[link] = inertia
        for name in fixed:
            if 'inertial' in found[('link', name)].children:
                new_inertial[name] = None
        notes.append(f'link {shown(link)}: the identified body less its fixed links '
                     f'({", ".join(map(shown, fixed))}) is not a rigid body, so the whole body is '
                     f'written into {shown(link)} and their <inertial> removed')
    for link, added in (link_additions or {}).items():
        base = new_inertial.get(link)
        new_inertial[link] = (link_inertia(link) if base is None else base) + added

    edits: List[Tuple[int, int, bytes]] = []
    for link, inertia in new_inertial.items():
        element = found[('link', link)]
        span = element.children.get('inertial')
        if inertia is None:
            line = text.rfind(b'\n', 0, span[0])
            cut = line if not text[line + 1:span[0]].strip() else span[0]
            edits.append((cut, span[1], b''))
        elif span is not None:
            edits.append((span[0], span[1],
                          inertial_text(inertia, _indent_of(text, span[0])).encode()))
        else:
            edits.append(_insert(text, element,
                                 lambda indent, i=inertia: inertial_text(i, indent)))
    for joint, (damping, friction) in (dynamics or {}).items():
        element = found[('joint', joint)]
        tag = f'<dynamics damping="{_number(damping)}" friction="{_number(friction)}"/>'
        span = element.children.get('dynamics')
        if span is not None:
            edits.append((span[0], span[1], tag.encode()))
        else:
            edits.append(_insert(text, element, lambda indent, t=tag: t))
    out = text
    for a, b, new in sorted(edits, key=lambda e: e[0], reverse=True):
        out = out[:a] + new + out[b:]
    return out, notes


def _insert(text: bytes, element: _Element, make) -> Tuple[int, int, bytes]:
    """Return ``(a, b, new)``: ``text[a:b] = new`` adds ``make(indent)`` as the first child."""
    outer = _indent_of(text, element.start)
    inner = outer + '  '
    child = (inner + make(inner)).encode()
    if element.empty:                 # <link name="x"/> becomes <link name="x"> ... </link>
        head = text[element.start:element.end - 2].rstrip()
        return (element.start, element.end,
                head + b'>\n' + child + f'\n{outer}</{element.tag}>'.encode())
    return (element.open_end, element.open_end, b'\n' + child)
