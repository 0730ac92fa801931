# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Tools on top of the library and the node: benchmark, demo, latency, soak, generators.

They use everything and nothing uses them: ``python -m spatial_dynamics.tools.<name>``.
"""
