# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Docstring style (PEP 257), as the test `ros2 pkg create` generates.

Uses ament_pep257 when it is importable (a ROS 2 workspace); otherwise runs pydocstyle with
the pep257 convention and ament_pep257's ignore list (missing docstrings D100-D107, and
D203, D212, D404 are not reported).
"""

import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PATHS = ['spatial_dynamics', 'benchmarks', 'test', 'launch', 'setup.py']
AMENT_IGNORE = ['D100', 'D101', 'D102', 'D103', 'D104', 'D105', 'D106', 'D107',
                'D203', 'D212', 'D404']

try:
    from ament_pep257.main import main
except ImportError:
    main = None


def _existing(paths):
    return [p for p in paths if os.path.exists(os.path.join(ROOT, p))]


def _have_pydocstyle():
    try:
        import pydocstyle  # noqa: F401
    except ImportError:
        return False
    return True


@pytest.mark.linter
@pytest.mark.pep257
def test_pep257():
    paths = _existing(PATHS)
    if main is not None:
        cwd = os.getcwd()
        os.chdir(ROOT)
        try:
            rc = main(argv=paths)
        finally:
            os.chdir(cwd)
        assert rc == 0, 'Found code style errors / warnings'
        return
    if not _have_pydocstyle():
        pytest.skip('neither ament_pep257 nor pydocstyle is installed')
    proc = subprocess.run(
        [sys.executable, '-m', 'pydocstyle', '--convention=pep257',
         '--add-ignore=' + ','.join(AMENT_IGNORE),
         r'--match=.*\.py', r'--match-dir=[^\._].*', *paths],
        cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, \
        'pydocstyle found docstring errors / warnings:\n' + proc.stdout + proc.stderr
