# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Sphinx configuration: the user guide (Markdown, MyST) and the API reference (autodoc).

Built by plain Sphinx (``sphinx-build -W -b html doc build/doc``, test/test_lint_docs.py) and
by rosdoc2 (docs.ros.org; ``rosdoc2 build --package-path .``, test/test_lint_rosdoc2.py), which
``rosdoc2.yaml`` points at this folder and which wraps this file in a conf.py of its own: the
same pages either way.
"""

import os
import re
import sys


def _package_root() -> str:
    """Return the folder holding the package's sources (and package.xml).

    Sphinx runs this file with the doc folder as working directory. rosdoc2 instead runs a
    wrapping conf.py of its own in a build folder: rosdoc2 0.2.1 executes this file by its
    absolute path (``exec(open("…/doc/conf.py").read())``), so the path is read from the
    wrapper; later rosdoc2 put the package's folder first on ``sys.path`` before.
    """
    candidates = ['..']
    if os.path.isfile('conf.py'):
        with open('conf.py', encoding='utf-8') as f:
            wrapped = re.search(r'exec\(open\("(.+?)"\)', f.read())
        if wrapped:
            candidates.append(os.path.dirname(os.path.dirname(wrapped.group(1))))
    for folder in candidates + sys.path:
        if os.path.isfile(os.path.join(folder, 'package.xml')) and \
                os.path.isdir(os.path.join(folder, 'spatial_dynamics')):
            return os.path.abspath(folder)
    raise RuntimeError(f'doc/conf.py: no package.xml beside a spatial_dynamics folder in '
                       f'{candidates + sys.path} (run Sphinx on the doc folder of a checkout)')


def _not_ours(source: str, doc: str) -> list:
    """Return what a builder wrote into ``source`` beside the pages of ``doc`` (none: both one).

    rosdoc2 builds in a folder of its own, where it copies ``doc/`` and adds its index.rst,
    sphinx-apidoc's page per module, the README and a second copy of ``doc/``: left out, the
    build reads our pages alone (our index, ``api.rst``), each once.
    """
    if os.path.samefile(source, doc):
        return []
    return sorted(set(os.listdir(source)) - set(os.listdir(doc)))


ROOT = _package_root()
sys.path.insert(0, ROOT)

project = 'spatial_dynamics'
copyright = '2026, spatial_dynamics contributors'
author = 'spatial_dynamics contributors'

extensions = ['myst_parser', 'sphinx.ext.autodoc', 'sphinx.ext.napoleon', 'sphinx.ext.mathjax']
napoleon_google_docstring = True
napoleon_numpy_docstring = False
source_suffix = {'.rst': 'restructuredtext', '.md': 'markdown'}
master_doc = 'index'
exclude_patterns = ['_build', 'bench/*.csv'] + _not_ours('.', os.path.join(ROOT, 'doc'))
myst_heading_anchors = 3
# The ROS shell and the optional libraries are not needed to document the core.
autodoc_mock_imports = ['rclpy', 'sensor_msgs', 'std_msgs', 'trajectory_msgs',
                        'diagnostic_msgs', 'geometry_msgs', 'rosgraph_msgs', 'mujoco',
                        'rosbags']
autodoc_member_order = 'bysource'
autodoc_typehints = 'none'
html_theme = 'alabaster'
INCLUDE_ABOVE = re.compile(r'^\.\. include:: \.\./(\S+)\s*$', re.M)


def include_from_root(app, docname: str, source: list) -> None:
    """Point a page's ``.. include:: ../FILE`` at the package's FILE (changelog.rst).

    ``..`` of ``doc/`` is the package; rosdoc2 builds copies of the pages elsewhere, where the
    path is rewritten to the package's file (unchanged for Sphinx run on ``doc/``).
    """
    folder = os.path.dirname(str(app.env.doc2path(docname)))
    source[0] = INCLUDE_ABOVE.sub(
        lambda m: '.. include:: ' + os.path.relpath(os.path.join(ROOT, m.group(1)), folder),
        source[0])


def setup(app) -> None:
    """Connect :func:`include_from_root`."""
    app.connect('source-read', include_from_root)
