# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""What the replay commands share on their command line: number types, the model, refusals."""

from __future__ import annotations

import argparse
import math
from typing import Callable, Optional, Sequence
import warnings

import numpy as np

from .. import Model, URDFWarning
from ..bounds import FRICTION_THRESHOLD_RANGE, MAX_EFFORT, MAX_GRAVITY
from ..check import locked_item, read_description


class Refused(Exception):
    """The input cannot be used; the message says why (exit status 1)."""


class Parser(argparse.ArgumentParser):
    """An argument parser whose usage errors may be one line (``one_line=True``).

    The subcommands of ``replay`` are made of this class (argparse makes a subparser of its
    parent's class); ``excite`` says its usage errors in one line on stderr, without the
    usage, as it did as a command of its own.
    """

    def __init__(self, *args, one_line: bool = False, **kwargs) -> None:
        """Make the parser; ``one_line``: a usage error is ``PROG: error: MESSAGE`` alone."""
        super().__init__(*args, **kwargs)
        self.one_line = one_line

    def error(self, message: str):
        """Print the usage error and exit with status 2."""
        if not self.one_line:
            super().error(message)
        self.exit(2, f'{self.prog}: error: {" ".join(message.split())}\n')


def checked(parse: Callable[[str], float], ok: Callable[[float], bool], need: str):
    """Return an argparse type: ``parse(text)`` if ``ok`` of it, else an error saying ``need``.

    Text that does not parse is refused the same way (as ``nan``, which no check accepts).
    """
    def convert(text: str) -> float:
        try:
            x = parse(text)
        except ValueError:
            x = math.nan
        if not ok(x):
            raise argparse.ArgumentTypeError(f'{text!r}: need {need}')
        return x
    return convert


#: A finite number (argparse type).
finite = checked(float, math.isfinite, 'a finite number')
#: A finite number > 0 (argparse type).
positive = checked(float, lambda x: x > 0.0 and math.isfinite(x), 'a finite number > 0')

#: The longest differentiation window, s: a longer one smooths away the motion a fit needs
#: (and in samples it overflowed: ``--window 1e308``).
MAX_WINDOW = 10.0
#: The highest rate a plan is sampled at, Hz (a sample a microsecond).
MAX_RATE = 1e6
_LOW, _HIGH = FRICTION_THRESHOLD_RANGE

# Each number option of the replay commands and the fleet's manifest, with its range: a
# value outside it (huge, NaN, inf, negative, zero where zero means nothing) is a usage error
# naming the option, before any file is read.
#: ``--window``, s (argparse type).
window_s = checked(float, lambda x: 0.0 < x <= MAX_WINDOW,
                   f'a number of seconds > 0, at most {MAX_WINDOW:g}')
#: ``--threshold``, the friction velocity threshold (argparse type; the node's range).
velocity_threshold = checked(float, lambda x: _LOW <= x <= _HIGH,
                             f'a velocity from {_LOW:g} to {_HIGH:g} rad/s or m/s')
#: ``--rate`` of a plan's sampling, Hz (argparse type).
sampling_rate = checked(float, lambda x: 0.0 < x <= MAX_RATE,
                        f'a rate > 0, at most {MAX_RATE:g} Hz')
#: ``--tolerance`` of an annotated effort, N m or N (argparse type).
effort_tolerance = checked(float, lambda x: 0.0 < x <= MAX_EFFORT,
                           f'a torque > 0, at most {MAX_EFFORT:g} N m')
#: A component of ``--gravity``, m/s² (argparse type; |g| is checked by check_gravity).
gravity_component = checked(float, lambda x: abs(x) <= MAX_GRAVITY,
                            f'a number of m/s^2 within ±{MAX_GRAVITY:g}')


def add_model_arguments(p: argparse.ArgumentParser) -> None:
    """Declare the options of the model, the same in every replay command.

    ``--urdf``, ``--joints``/``--locked`` (the model reduction, read by :func:`load_model`)
    and ``--gravity`` (checked by :func:`check_gravity`).
    """
    p.add_argument('--urdf', required=True, help='URDF file (or .xacro)')
    p.add_argument('--joints', nargs='+', metavar='J',
                   help='model reduction: only these joints move (the others are locked)')
    p.add_argument('--locked', nargs='+', metavar='J=V', default=[], type=locked_item,
                   help='value (rad or m) of a joint locked by --joints')
    p.add_argument('--gravity', type=gravity_component, nargs=3, default=(0.0, 0.0, -9.81),
                   metavar=('GX', 'GY', 'GZ'),
                   help='m/s^2 in the base frame (default 0 0 -9.81)')


def model_parser() -> argparse.ArgumentParser:
    """Return a parent parser of the model options (:func:`add_model_arguments`), no help."""
    p = argparse.ArgumentParser(add_help=False)
    add_model_arguments(p)
    return p


def check_model(p: argparse.ArgumentParser, args) -> None:
    """Exit with a usage error of ``p`` when the model options cannot be one model."""
    if args.locked and not args.joints:
        p.error('--locked needs --joints (the joints kept movable)')
    check_gravity(p, args.gravity)


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
