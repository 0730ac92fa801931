# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The ROS 2 shell: the ``inverse_dynamics`` node around pure modules.

``node.py`` and ``common.py`` (what every node shares) import rclpy, and ``parameters.py``
only to declare a table; the parameter table (``config.py``), a change made a Config
(``configure.py``), its records (``records.py``), the descriptions, the answers, the bases
(``bases.py``, ``base_messages.py``, ``floating.py``), the plans, the observer and the
diagnostics are pure and tested without a ROS graph.
"""
