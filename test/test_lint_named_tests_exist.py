# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Every test file the package's text names exists: a reader sent to a test finds it.

``test/test_x.py`` in a docstring, a comment or a generated header. The package's modules,
the documentation and the benchmarks are read whole.
"""

import os
import re

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TEST = os.path.join(ROOT, 'test')
NAMED = re.compile(r'\btest_[A-Za-z0-9_]+\.py\b')
PLACES = ('spatial_dynamics', 'doc', 'benchmarks', 'README.md')


def texts():
    """Yield (path relative to the checkout, text) of each file of :data:`PLACES`."""
    for place in PLACES:
        top = os.path.join(ROOT, place)
        if os.path.isfile(top):
            paths = [top]
        else:
            paths = [os.path.join(folder, name) for folder, _, names in os.walk(top)
                     for name in sorted(names) if name.endswith(('.py', '.md', '.c'))]
        for path in paths:
            with open(path, encoding='utf-8') as f:
                yield os.path.relpath(path, ROOT), f.read()


def test_named_tests_are_found():
    assert NAMED.findall('tested in ``test/test_node_config.py``, test_node_config.py.') == [
        'test_node_config.py', 'test_node_config.py']


def test_every_test_file_named_exists():
    missing = sorted({(where, name) for where, text in texts() for name in NAMED.findall(text)
                      if not os.path.isfile(os.path.join(TEST, name))})
    assert not missing, f'test files named but absent (where, name): {missing}'
