# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A fleet's recordings on a Dask cluster: per-bag drive fits, trends and drift (no rclpy).

``python -m spatial_dynamics.fleet``: :mod:`.command`. Dask is imported only when a cluster
is used. The command's entry point, what ``replay fleet`` dispatches to: ``add_arguments``
(its options on a parser), ``run`` (parsed arguments -> exit status), ``main``, ``SUMMARY``
and ``EXIT_STATUS`` (its --help's first and last lines).
"""

from .command import add_arguments, EXIT_STATUS, main, run, SUMMARY

__all__ = ['add_arguments', 'EXIT_STATUS', 'main', 'run', 'SUMMARY']
