# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A user's string as a message shows it: short and escaped.

Every name the package did not write itself (a URDF's robot, link and joint names, a joint or
link asked for by name, a message's ``frame_id``) goes into an error, a warning, a log line or
a diagnostics value through :func:`shown` (one name) or :func:`listed` (names): at most
:data:`LIMIT` characters of it, then how long it was, and every control character escaped,
so a 100,000-character joint name costs one short line and a newline in a name cannot forge
a log line. A name of at most :data:`LIMIT` characters is shown exactly as ``repr`` writes
it. A file path is shown whole (its end names the file), escaped by ``repr``.
Pure Python: the core's messages and the node's log lines use the same two functions.
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
    the name alone). A value that is not a string (a number, a list) is its ``repr``, cut
    and counted the same way, control characters escaped.
    """
    if not isinstance(value, str):      # a number, a list: as repr writes it, cut likewise
        text = repr(value)
        more = f'… ({len(text):,} characters)' if len(text) > limit else ''
        return ''.join(c if c.isprintable() else repr(c)[1:-1] for c in text[:limit]) + more
    text = value
    head = repr(text[:limit])
    mark, body = head[-1], head[1:-1]
    more = f'… ({len(text):,} characters)' if len(text) > limit else ''
    if not quote:
        return body + more
    return f'{mark}{body}{mark}{more}'


def listed(names: Sequence[str], quote: bool = True, count: int = LISTED) -> str:
    """Return the first ``count`` of ``names``, each :func:`shown`, then ``...`` if more."""
    names = list(names)
    head = ', '.join(shown(name, quote) for name in names[:count])
    return head + (', ...' if len(names) > count else '')


def at_state(index: Sequence[int]) -> str:
    """Return where in a batch a message's state is: ``' (state 3)'``, ``' (state (1, 2))'``.

    ``index`` is the state's index in the batch shape, its integers numpy's (``np.argwhere``,
    ``np.unravel_index``) or Python's, written as plain numbers (never ``np.int64(3)``); one
    number alone; ``''`` for no batch (an empty index).
    """
    k = tuple(int(i) for i in index)
    if not k:
        return ''
    return f' (state {k[0] if len(k) == 1 else k})'
