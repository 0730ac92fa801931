# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The algorithms, each equation written once: the component kernels and the 6×6 spec."""
