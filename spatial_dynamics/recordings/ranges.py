# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The range of each number a recording is read and fitted with, and a plan sampled with.

Each is an argparse type (a value outside its range is a usage error naming the option),
shared by the commands (``replay``, ``spatial_dynamics_check``'s ``--locked``) and the
fleet's manifest, whose columns are the same options.
"""

from __future__ import annotations

import argparse
import math
from typing import Callable, Tuple

from ..bounds import FRICTION_THRESHOLD_RANGE, MAX_EFFORT, MAX_GRAVITY, MAX_POSITION
from ..text import shown


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
            raise argparse.ArgumentTypeError(f'{shown(text)}: need {need}')
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


def locked_item(item: str) -> Tuple[str, float]:
    """Parse ``'name=value'`` to ``(name, value)``; ``ArgumentTypeError`` (usage) if not.

    The value is a joint position: finite, within ±MAX_POSITION (rad or m).
    """
    name, sep, value = item.partition('=')
    try:
        if sep and name and abs(float(value)) <= MAX_POSITION:
            return name, float(value)
    except ValueError:
        pass
    raise argparse.ArgumentTypeError(f'{shown(item)}: expected NAME=VALUE, the value in rad or m '
                                     f'within ±{MAX_POSITION:g}')
