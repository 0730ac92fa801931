# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Inverse dynamics over recorded data: bags of joint states, and trajectories.

``python -m spatial_dynamics.replay BAG --urdf URDF`` compares measured efforts with the
model's torque over a whole recording, identifies per-joint damping, Coulomb friction and
armature (``--identify``), and checks a ``JointTrajectory`` against the effort limits
(``--trajectory``). Modules: :mod:`.bags` (rosbag2 without ROS), :mod:`.differentiate`,
:mod:`.identify`, :mod:`.splines`, :mod:`.report`; the command in :mod:`.__main__`, the
benchmark in :mod:`.bench`. Nothing here imports rclpy.
"""
