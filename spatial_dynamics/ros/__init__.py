# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The ROS 2 shell: the node (the only importer of rclpy) and its pure input mapping."""
