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

The work is in two modules: :mod:`.reading` reads the file and the XML into records of the
links and joints, checking each number; :mod:`.tree` makes the records a
:class:`~spatial_dynamics.model.Model` (the tree, lumping, mimic, reduction). This module is
the entry point, :func:`model_from_urdf`, also reachable as ``Model.from_urdf`` (installed
here: the model is a record that knows no parser).
"""

from __future__ import annotations

from typing import Mapping, Optional, Sequence
import warnings

from ..model import Model
from ..text import shown
from .reading import (_parse_urdf, _Report, MAX_DESCRIPTION_BYTES, MAX_FILE_BYTES,
                      read_description, read_urdf_file, Source)
from .tree import _from_robot, ROOT_JOINT, URDF_WORLD, WORLD

__all__ = ['BASES', 'MAX_DESCRIPTION_BYTES', 'MAX_FILE_BYTES', 'model_from_urdf',
           'read_description', 'read_urdf_file', 'ROOT_JOINT', 'URDF_WORLD', 'URDFWarning',
           'WORLD']


class URDFWarning(UserWarning):
    """A URDF that loads as written but is physically inconsistent; the message names it.

    ``Model.from_urdf(..., strict=True)`` raises ``ValueError`` instead. The messages of a
    model are kept on ``Model.warnings``.
    """


#: What ``Model.from_urdf(..., base=...)`` takes: the root link fixed to the world, or on a
#: free-flyer joint.
BASES = ('fixed', 'floating')


def model_from_urdf(source: Source, joints: Optional[Sequence[str]] = None,
                    locked: Optional[Mapping[str, float]] = None, strict: bool = False,
                    base: str = 'fixed') -> Model:
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
    damping or friction, no robot name) loads exactly as written, with a ``URDFWarning``
    per problem, also kept in ``model.warnings``; ``strict=True`` raises ``ValueError``
    for the first of them instead. Rounding noise (see ``INERTIA_ATOL``) is neither.

    ``base='fixed'`` (default): the root link is fixed to the world. ``base='floating'``:
    the root link moves on a free-flyer joint named ``'root_joint'`` (first in
    ``joint_names``; ``q`` starts with the root link's position and unit quaternion x y z
    w in the world, ``q̇`` with its twist ``[ω; v]`` in its own frame: see
    :mod:`spatial_dynamics.joints` and doc/floating_base.md), so ``nq = 7 + n``,
    ``nv = 6 + n`` and every algorithm returns the base's six rows too (the base wrench
    in the root link's frame); gravity is then given in world coordinates.
    """
    if base not in BASES:
        raise ValueError(f'base must be one of {list(BASES)}, got {shown(base)}')
    report = _Report(strict)
    model = _from_robot(*_parse_urdf(source, report), joints, locked, report,
                        base == 'floating')
    for message in model.warnings:
        warnings.warn(message, URDFWarning, stacklevel=2)
    return model


#: ``Model.from_urdf(...)``, the public spelling: the parser's function on the record it
#: builds, so that :mod:`spatial_dynamics.model` never imports the parser.
Model.from_urdf = staticmethod(model_from_urdf)
