# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A simulated robot to try the library on: MuJoCo running the URDF's rigid-body robot.

:mod:`~spatial_dynamics.sim.robot` is pure (MuJoCo and numpy, no ROS): the URDF made into a
MuJoCo model that is exactly the rigid-body robot of :class:`~spatial_dynamics.Model`.
:mod:`~spatial_dynamics.sim.node` is its ROS 2 shell (``python -m spatial_dynamics.sim``).
MuJoCo is an optional dependency (``pip install spatial_dynamics[sim]``); importing
``spatial_dynamics`` never imports it.
"""
