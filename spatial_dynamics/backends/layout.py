# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The per-body rows the component kernels read, derived from a Model (never stored on it).

Row ``i`` describes body ``i`` (row 0 is the world or fixed base) in :data:`COLUMNS` order:
parent ``λ(i)``, joint code (:func:`spatial_dynamics.joints.joint_code`), the first index of
the joint's coordinates in ``q`` and in ``q̇`` (``q̈``, ``τ``), its number of velocity
coordinates (``dof``: 1, or 6 for a free-flyer), joint axis (3), ``E_tree`` row-major (9) and
``r_tree`` (3) of ``Xtree = (E, r)``, mass, ``h = m c`` (3), ``Ibar`` (xx xy xz yy yz zz),
mimic multiplier and offset. The Python backends read the rows as tuples; the compiled one as
one float64 table (the small integers are exact in float64; row 0 holds ``nq = len(q)`` and
``nv = len(q̇)`` in its index columns), which the C extension copies once (``kernels``).

:func:`of` derives a model's :class:`Layout` once and keeps it for as long as the model
lives: a cache of a pure function of an immutable record, which never changes a result.
"""

from __future__ import annotations

from dataclasses import dataclass
import weakref

import numpy as np

from . import compiled
from ..algorithms.arguments import check_model
from ..joints import FREE_FLYER, joint_code, NV
from ..model import Model
from ..spatial import plux_Er

#: Column names and widths of a row, in order.
COLUMNS = (('parent', 1), ('code', 1), ('qidx', 1), ('vidx', 1), ('dof', 1), ('axis', 3),
           ('E', 9), ('r', 3),
           ('mass', 1), ('h', 3), ('Ibar', 6), ('mul', 1), ('off', 1))
#: First column of each field, e.g. ``COLUMN['mass']``; ``WIDTH`` columns in all.
COLUMN = {}
_c = 0
for _name, _width in COLUMNS:
    COLUMN[_name] = _c
    _c += _width
WIDTH = _c
#: Columns holding integers (cast back to int by the compiled kernels).
INTEGER_COLUMNS = (COLUMN['parent'], COLUMN['code'], COLUMN['qidx'], COLUMN['vidx'],
                   COLUMN['dof'])


@dataclass(frozen=True, eq=False)
class Layout:
    """A model's rows: ``rows`` (tuples, ints where integer) and ``table`` (NB+1, WIDTH).

    ``n`` is ``len(q)`` (``model.nq``), ``nv`` that of ``q̇``, ``q̈`` and ``τ``.
    """

    n: int
    nv: int
    rows: tuple
    table: np.ndarray     # read-only
    zeros: np.ndarray     # (nv,) read-only zeros: q̇ or q̈ of the terms at rest
    kernels: object       # the compiled extension's copy of the table, or None without it


def derive(model: Model) -> Layout:
    """Build the rows and the table of ``model`` (see the module docstring)."""
    rows = [(-1, 0, model.nq, model.nv, 0) + (0.0,) * (WIDTH - 5)]
    floating = [i for i in range(1, model.NB + 1) if model.jtype[i] == FREE_FLYER]
    if floating not in ([], [1]) or (floating and model.parent[1] != 0):
        # The regressor's scratch keeps a free-flyer's five more columns once, after the
        # bodies' (see algorithms/regressor.py): one free-flyer, the root's joint.
        raise ValueError('a free-flyer joint is the root link\'s joint only')
    for i in range(1, model.NB + 1):
        E, r = plux_Er(model.Xtree[i])
        Ii = model.inertia[i]
        # I = [[Ibar, h×], [h×ᵀ, m 1]] with h = m c (RBDA eq. 2.63): read h off I[:3, 3:].
        h = (Ii[2, 4], Ii[0, 5], Ii[1, 3])
        Ibar = (Ii[0, 0], Ii[0, 1], Ii[0, 2], Ii[1, 1], Ii[1, 2], Ii[2, 2])
        jt = model.jtype[i]
        rows.append((int(model.parent[i]), joint_code(jt, model.axis[i]), int(model.qidx[i]),
                     int(model.vidx[i]), NV[jt])
                    + tuple(float(x) for x in (*model.axis[i], *E.ravel(), *r, Ii[3, 3], *h,
                                               *Ibar, model.qmul[i], model.qoff[i])))
    table = np.array(rows, dtype=np.float64)
    table.flags.writeable = False
    zeros = np.zeros(model.nv)
    zeros.flags.writeable = False
    return Layout(model.nq, model.nv, tuple(rows), table, zeros, compiled.kernels(table))


#: id(model) -> Layout, each removed when its model is collected.
LAYOUTS: dict = {}
#: id(model) -> its ``Layout.kernels`` (the compiled extension's entries look models up here).
KERNELS: dict = {}


def of(model: Model) -> Layout:
    """Return the :class:`Layout` of ``model``, derived on first use.

    ``TypeError`` when ``model`` is no :class:`~spatial_dynamics.Model` (``None``, a name, a
    table): the public functions' first argument.
    """
    layout = LAYOUTS.get(id(model))
    if layout is None:
        check_model(model)
        layout = LAYOUTS[id(model)] = derive(model)
        weakref.finalize(model, LAYOUTS.pop, id(model), None)
        if layout.kernels is not None:
            KERNELS[id(model)] = layout.kernels
            weakref.finalize(model, KERNELS.pop, id(model), None)
    return layout
