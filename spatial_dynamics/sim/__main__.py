# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""``python -m spatial_dynamics.sim``: the simulated robot node (see :mod:`.node`)."""

import sys

from spatial_dynamics.sim.node import main

sys.exit(main())
