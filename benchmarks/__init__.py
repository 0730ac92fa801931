# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Benchmarks and generated robots, run from a checkout (not installed with the package).

    python -m benchmarks.bench [--quick] [--out DIR]      (scripts/dev bench)
    python -m benchmarks.replay [--seconds 3600]           the replay command on an hour's bag

They measure the installed or checked-out package through its public API where they can
(the benchmark also times the backends one by one, so it reaches into them by name).
``benchmarks.generate`` writes the chains, trees and random robots the benchmark and the
stress tests use.
"""
