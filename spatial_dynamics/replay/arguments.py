# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""What the replay commands share on their command line: number types, the model, refusals."""

from __future__ import annotations

import argparse
import math
from typing import Optional, Sequence
import warnings

import numpy as np

from .. import Model, URDFWarning
from ..bounds import MAX_GRAVITY
from ..check import read_description


class Refused(Exception):
    """The input cannot be used; the message says why (exit status 1)."""


def finite(text: str) -> float:
    """Parse a finite number (argparse type)."""
    try:
        x = float(text)
    except ValueError:
        x = float('nan')
    if not math.isfinite(x):
        raise argparse.ArgumentTypeError(f'{text!r}: need a finite number')
    return x


def positive(text: str) -> float:
    """Parse a finite number > 0 (argparse type)."""
    try:
        x = float(text)
    except ValueError:
        x = float('nan')
    if not (x > 0.0 and math.isfinite(x)):
        raise argparse.ArgumentTypeError(f'{text!r}: need a finite number > 0')
    return x


def check_gravity(p: argparse.ArgumentParser, gravity: Sequence[float]) -> None:
    """Exit with a usage error when ``--gravity`` cannot be a mounting."""
    if float(np.linalg.norm(gravity)) > MAX_GRAVITY:
        p.error(f'--gravity: |g| = {np.linalg.norm(gravity):g} m/s^2, more than '
                f'{MAX_GRAVITY:g} (100 g) cannot be a mounting')


def load_model(args, joints: Optional[Sequence[str]] = None) -> Model:
    """Build the model from ``--urdf`` with ``--joints``/``--locked``; :class:`Refused` if not."""
    try:
        xml = read_description(args.urdf)
        with warnings.catch_warnings():
            warnings.simplefilter('ignore', URDFWarning)
            return Model.from_urdf(xml, joints=joints or args.joints,
                                   locked=dict(args.locked) or None)
    except ValueError as err:
        raise Refused(str(err)) from None


def one_line(err: BaseException) -> str:
    """Return an exception's message on one line."""
    return ' '.join(str(err).split()) or type(err).__name__
