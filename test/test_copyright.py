# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Every Python file carries a copyright line and the Apache-2.0 licence identifier.

This replaces the ament_copyright test `ros2 pkg create` generates: ament_copyright only
recognises the full Apache header text, not the SPDX short form used here
(ament/ament_lint#462).
"""

import os
import re

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SKIP_DIRS = {'build', 'install', 'log', 'out', '__pycache__'}
HEADER_LINES = 5
COPYRIGHT = re.compile(r'^#\s*Copyright\s+(\(c\)\s+)?\d{4}(-\d{4})?\s+\S', re.IGNORECASE)
LICENCE = re.compile(
    r'^#\s*(SPDX-License-Identifier:\s*Apache-2\.0\s*$'
    r'|Licensed under the Apache License, Version 2\.0)')


def python_files():
    """Yield the package's .py files, relative to the repository root."""
    for dirpath, dirnames, filenames in os.walk(ROOT):
        dirnames[:] = sorted(
            d for d in dirnames
            if not d.startswith('.') and d not in SKIP_DIRS and not d.endswith('.egg-info'))
        for name in sorted(filenames):
            if name.endswith('.py'):
                yield os.path.relpath(os.path.join(dirpath, name), ROOT)


def header_problems(path):
    """Return what is missing from the first lines of a file (empty list if none)."""
    with open(os.path.join(ROOT, path), encoding='utf-8') as f:
        lines = [f.readline().rstrip('\n') for _ in range(HEADER_LINES)]
    problems = []
    if not any(COPYRIGHT.match(line) for line in lines):
        problems.append('copyright line')
    if not any(LICENCE.match(line) for line in lines):
        problems.append("'# SPDX-License-Identifier: Apache-2.0' line")
    return problems


@pytest.mark.copyright
@pytest.mark.linter
def test_copyright():
    files = list(python_files())
    assert 'setup.py' in files
    missing = {path: problems for path in files if (problems := header_problems(path))}
    assert not missing, 'Missing licence header (first %d lines):\n' % HEADER_LINES + '\n'.join(
        '%s: no %s' % (path, ', no '.join(problems)) for path, problems in missing.items())
