# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A simulated robot to try the library on: MuJoCo running the URDF's rigid-body robot.

:mod:`~spatial_dynamics.sim.mujoco_model`, :mod:`~spatial_dynamics.sim.robot` and
:mod:`~spatial_dynamics.sim.floating` are pure (MuJoCo and numpy, no ROS): the URDF made into a
MuJoCo model that is exactly the rigid-body robot of :class:`~spatial_dynamics.Model`, the
fixed-base robot driven by joint torques, and the floating-base robot on a floor.
:mod:`~spatial_dynamics.sim.node` is its ROS 2 shell (``python -m spatial_dynamics.sim``).
MuJoCo is an optional dependency (``pip install spatial_dynamics[sim]``); importing
``spatial_dynamics`` never imports it.
"""
