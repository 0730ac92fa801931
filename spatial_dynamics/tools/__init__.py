# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Tools on top of the library and the node: demos, measurements and their helpers.

``demo``, ``closed_loop`` and ``identify_demo`` (what the package does, end to end);
``latency``, ``soak`` and ``startup`` (what the node costs, over time, to start); ``relay``
(the trivial node ``latency`` compares with) and ``driving`` (what they share); ``ros_cli``
(``ros2 param set`` and ``ros2 topic pub`` where ros2cli is not installed). They use
everything and nothing uses them: ``python -m spatial_dynamics.tools.<name>``. The benchmark
and the robot generators are not installed: ``benchmarks/`` in the checkout.
``latency_pacer``, ``latency_targets`` and ``latency_report`` are parts of ``latency``,
not commands.
"""
