# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""flake8 over the package, as the test `ros2 pkg create` generates.

Uses ament_flake8 when it is importable (a ROS 2 workspace); otherwise runs plain flake8
with the same line length (99). ament_flake8 additionally enables the flake8 plugins it
depends on (quotes, import order, ...), when they are installed.
"""

import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PATHS = ['spatial_dynamics', 'benchmarks', 'test', 'launch', 'setup.py']

try:
    from ament_flake8.main import main_with_errors
except ImportError:
    main_with_errors = None


def _existing(paths):
    return [p for p in paths if os.path.exists(os.path.join(ROOT, p))]


@pytest.mark.flake8
@pytest.mark.linter
def test_flake8():
    paths = _existing(PATHS)
    if main_with_errors is not None:
        cwd = os.getcwd()
        os.chdir(ROOT)
        try:
            rc, errors = main_with_errors(argv=paths)
        finally:
            os.chdir(cwd)
        assert rc == 0, \
            'Found %d code style errors / warnings:\n' % len(errors) + '\n'.join(errors)
        return
    proc = subprocess.run(
        [sys.executable, '-m', 'flake8', '--max-line-length=99', *paths],
        cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, \
        'flake8 found code style errors / warnings:\n' + proc.stdout + proc.stderr
