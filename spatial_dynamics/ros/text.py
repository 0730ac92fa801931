# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A user's string as the node's log lines and diagnostics values show it: short and escaped.

Every name the node did not write itself (a message's ``frame_id``, a parameter's link or
frame, the URDF's robot, link and joint names, a remapped topic) goes into a log line or a
diagnostics value through :func:`shown` (one name) or :func:`listed` (names): at most
:data:`LIMIT` characters of it, then how long it was, and every control character escaped,
so a 10,000-character ``frame_id`` costs one short line and a newline in a name cannot forge
a log line. A file path is shown whole (its end names the file), escaped by ``repr``.
Pure Python: no rclpy.
"""

from __future__ import annotations

from typing import Sequence

#: Characters of a user's string shown; the rest is counted.
LIMIT = 60
#: Names listed before the count of the rest.
LISTED = 5


def shown(value: object, quote: bool = True, limit: int = LIMIT) -> str:
    """Return ``value`` (a string) quoted and escaped as ``repr`` writes it, cut to ``limit``.

    ``'hand'`` stays ``'hand'``; a longer one is its first ``limit`` characters, ``…`` and
    ``(N characters)``. ``quote=False`` leaves the quotes out (a diagnostics value that is
    the name alone).
    """
    text = str(value)
    head = repr(text[:limit])
    mark, body = head[-1], head[1:-1]
    more = f'… ({len(text):,} characters)' if len(text) > limit else ''
    if not quote:
        return body + more
    return f'{mark}{body}{mark}{more}'


def listed(names: Sequence[str], quote: bool = True, count: int = LISTED) -> str:
    """Return the first ``count`` of ``names``, each :func:`shown`, then ``...`` if more."""
    head = ', '.join(shown(name, quote) for name in names[:count])
    return head + (', ...' if len(names) > count else '')
