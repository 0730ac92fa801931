# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A user's string as the node's log lines and diagnostics values show it: short and escaped.

Every name the node did not write itself (a message's ``frame_id``, a parameter's link or
frame, the URDF's robot, link and joint names, a remapped topic) goes into a log line or a
diagnostics value through :func:`shown` (one name) or :func:`listed` (names): at most
:data:`LIMIT` characters of it, then how long it was, and every control character escaped,
so a 10,000-character ``frame_id`` costs one short line and a newline in a name cannot forge
a log line. A file path is shown whole (its end names the file), escaped by ``repr``.
The functions live in the core (:mod:`spatial_dynamics.text`), whose own errors and warnings
show names the same way, so a message the node passes on from the core is short as well.
Pure Python: no rclpy.
"""

from spatial_dynamics.text import LIMIT, listed, LISTED, shown

__all__ = ['LIMIT', 'LISTED', 'listed', 'shown']
