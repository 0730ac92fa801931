# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A fleet's recordings on a Dask cluster: per-bag drive fits, trends and drift (no rclpy).

``python -m spatial_dynamics.fleet``: :mod:`.command`. Dask is imported only when a cluster
is used.
"""

from .command import add_arguments, main, run

__all__ = ['add_arguments', 'main', 'run']
