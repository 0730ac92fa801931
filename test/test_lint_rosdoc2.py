# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The docs as docs.ros.org builds them: ``rosdoc2 build`` on a copy of the package, no warnings.

rosdoc2 wraps ``doc/conf.py`` in a conf.py of its own, in a folder where it also writes its
index, sphinx-apidoc's pages and copies of the README and of ``doc/``; ``rosdoc2.yaml`` and
``doc/conf.py`` make it build our pages alone (our index, ``doc/api.rst``), so that its Sphinx
run prints no warning. rosdoc2 gives Sphinx no ``-W``: its output is read instead.
"""

import os
import re
import shutil
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# what the build of the checkout adds beside the sources (not the package's)
BUILT = shutil.ignore_patterns('.git', '.venv*', 'build', 'install', 'log', '__pycache__',
                               '*.egg-info', '.pytest_cache', '.hypothesis')
ALARM = re.compile(r'\b(WARNING|ERROR|CRITICAL|SEVERE)\b|\[rosdoc2\] \[(WARNING|ERROR)\]')


def rosdoc2():
    """Return the rosdoc2 command beside this interpreter, else on PATH (None: not installed)."""
    here = os.path.dirname(sys.executable)
    return shutil.which('rosdoc2', path=here + os.pathsep + os.environ.get('PATH', ''))


@pytest.fixture(scope='module')
def built(tmp_path_factory):
    """Run ``rosdoc2 build`` on a copy of the package; return (the run, its output folder)."""
    command = rosdoc2()
    assert command is not None, 'no rosdoc2 beside this Python or on PATH: ' \
        '.ci/requirements.txt lists it (scripts/dev installs it into .venv)'
    work = tmp_path_factory.mktemp('rosdoc2')
    package = work / 'spatial_dynamics'
    shutil.copytree(ROOT, package, ignore=BUILT, symlinks=True)
    # rosdoc2 runs sphinx-apidoc by name: its own folder first on PATH
    env = dict(os.environ, PATH=os.path.dirname(command) + os.pathsep + os.environ['PATH'])
    env.pop('ROS_DISTRO', None)   # later rosdoc2 look the distribution up on the network
    run = subprocess.run([command, 'build', '--package-path', str(package),
                          '--output-directory', str(work / 'docs_output'),
                          '--doc-build-directory', str(work / 'docs_build'),
                          '--cross-reference-directory', str(work / 'cross_reference')],
                         cwd=work, env=env, capture_output=True, text=True)
    return run, work / 'docs_output' / 'spatial_dynamics'


def test_rosdoc2_builds_without_warnings(built):
    run, _ = built
    output = run.stdout + run.stderr
    assert run.returncode == 0, output[-5000:]
    alarms = [line for line in output.splitlines() if ALARM.search(line)]
    assert not alarms, '\n'.join(alarms[:40])


def test_rosdoc2_builds_our_pages_alone(built):
    """Our index and API page, each once: no sphinx-apidoc pages, no second copy of doc/."""
    run, html = built
    assert run.returncode == 0, (run.stdout + run.stderr)[-5000:]
    pages = sorted(os.path.relpath(os.path.join(d, f), html)
                   for d, _, files in os.walk(html) for f in files if f.endswith('.html'))
    ours = [os.path.splitext(f)[0] + '.html' for f in os.listdir(os.path.join(ROOT, 'doc'))
            if f.endswith(('.md', '.rst'))]
    assert pages == sorted(ours + ['genindex.html', 'search.html', 'py-modindex.html']), pages
    with open(html / 'index.html', encoding='utf-8') as f:
        index = f.read()
    assert 'the user guide and the reference' in index     # doc/index.md, not rosdoc2's own
    with open(html / 'changelog.html', encoding='utf-8') as f:
        assert 'Changelog' in f.read()                     # CHANGELOG.rst, included
