# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The model a recording is compared with: a URDF file read as the node reads it, reduced."""

from __future__ import annotations

from typing import Mapping, Optional, Sequence
import warnings

from .. import urdf
from ..model import Model
from ..urdf import model_from_urdf, URDFWarning
from .errors import Refused


def read_description(path: str) -> bytes:
    """Return the URDF XML of a file (a xacro file expanded), read as the node reads it."""
    return urdf.read_description(path, urdf.MAX_DESCRIPTION_BYTES, repr(path)).encode('utf-8')


def load_model(path: str, joints: Optional[Sequence[str]] = None,
               locked: Optional[Mapping[str, float]] = None) -> Model:
    """Build the model of the URDF (or xacro) file ``path``; :class:`.errors.Refused` if not.

    Read with the node's size limit; ``joints``: only these move (model reduction), the
    others locked at ``locked`` (rad or m; 0 when not given). The URDF's warnings are left
    to ``spatial_dynamics_check``.
    """
    try:
        xml = read_description(path)
        with warnings.catch_warnings():
            warnings.simplefilter('ignore', URDFWarning)
            return model_from_urdf(xml, joints=joints, locked=dict(locked or {}) or None)
    except ValueError as err:
        raise Refused(str(err)) from None
