# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Inverse dynamics over recorded data: bags of joint states, plans, fleets.

``python -m spatial_dynamics.replay COMMAND``: ``residual`` compares measured efforts with
the model's torque over a whole recording, ``identify`` fits the drives (damping, Coulomb
friction, armature), a payload or link inertias and writes a corrected URDF, ``trajectory``
checks a ``JointTrajectory`` against the effort limits, ``annotate`` fills its effort for
joint_trajectory_controller, ``excite`` plans a motion for identification, ``fleet`` runs a
fleet's bags on a Dask cluster (:mod:`spatial_dynamics.fleet`). Modules: :mod:`.bags`
(rosbag2 without ROS), :mod:`.cdr`, :mod:`.recording`, :mod:`.differentiate`,
:mod:`.identify`, :mod:`.correction`, :mod:`.urdf_writer`, :mod:`.splines`, :mod:`.report`;
the command in :mod:`.__main__`. Nothing here imports rclpy.
"""
