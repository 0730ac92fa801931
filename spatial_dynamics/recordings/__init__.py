# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Recordings as the model needs them: bags read, cleaned, differentiated (no rclpy).

The floor every command that reads a recording stands on (``replay``, ``fleet``), as
``rosbags`` keeps its readers apart from any tool: functions take typed arguments (a
:class:`~.recording.Reading`, a :class:`~.base_topics.BaseTopic`, plain values), never a
command's options. Modules: :mod:`.bags` (opening a bag, reading a topic), :mod:`.sqlite` and
:mod:`.mcap` (the fast readers), :mod:`.cdr` (the JointState, Odometry and Imu decoders),
:mod:`.writing` (bags for tests and benchmarks), :mod:`.recording` (cleaning, rates, a whole
recording), :mod:`.differentiate` (zero-phase Savitzky-Golay), :mod:`.base_topics` (a moving
base's motion), :mod:`.loading` (the model a recording is compared with), :mod:`.ranges` (the
numbers' ranges), :mod:`.errors` (the refusals).
"""
