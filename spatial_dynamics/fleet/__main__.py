# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""``python -m spatial_dynamics.fleet``."""

import sys

from .command import main

if __name__ == '__main__':
    sys.exit(main())
