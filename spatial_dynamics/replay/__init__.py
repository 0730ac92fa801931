# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Inverse dynamics over recorded data: bags of joint states, plans, fleets.

``python -m spatial_dynamics.replay COMMAND``: ``residual`` compares measured efforts with
the model's torque over a whole recording, ``identify`` fits the drives (damping, Coulomb
friction, armature), a payload or link inertias and writes a corrected URDF, ``trajectory``
checks a ``JointTrajectory`` against the effort limits, ``annotate`` fills its effort for
joint_trajectory_controller, ``excite`` plans a motion for identification, ``fleet`` runs a
fleet's bags on a Dask cluster (:mod:`spatial_dynamics.fleet`, run through its entry point).
One module a subcommand: :mod:`.residual`, :mod:`.identify`, :mod:`.trajectory`,
:mod:`.annotate`, :mod:`.excite`, :mod:`.fleet`, dispatched by :mod:`.__main__`; what they
share: :mod:`.arguments` (the command line), :mod:`.paths` (the checks before any work),
:mod:`.correction`, :mod:`.urdf_writer`, :mod:`.splines`, :mod:`.report`. Reading a
recording is :mod:`spatial_dynamics.recordings`', the drive fit
:mod:`spatial_dynamics.drives`'. Nothing here imports rclpy.
"""
