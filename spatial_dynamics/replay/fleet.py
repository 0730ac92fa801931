# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""``replay fleet SOURCE``: the fleet command (:mod:`spatial_dynamics.fleet`) as a subcommand.

The fleet is a command of its own, beside this one: it is dispatched through its package's
entry point (``add_arguments``, ``run``, its description and exit status), never its modules.
"""

from __future__ import annotations

from .. import fleet


def command(sub) -> None:
    """``replay fleet SOURCE``: every bag of a fleet on a Dask cluster, trends and wear."""
    p = sub.add_parser('fleet', help='a fleet\'s bags on a Dask cluster: drive trends, wear',
                       description=fleet.SUMMARY, epilog=fleet.EXIT_STATUS)
    fleet.add_arguments(p)
    p.set_defaults(run=fleet.run)
