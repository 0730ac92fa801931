# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Sphinx configuration: the user guide (Markdown, MyST) and the API reference (autodoc).

Built by plain Sphinx (``sphinx-build -W -b html doc build/doc``, what CI runs) and by
rosdoc2, which finds this file at ``doc/conf.py`` and wraps it.
"""

import os
import re
import sys


def _package_root() -> str:
    """Return the folder holding the package's sources.

    Sphinx runs this file with the doc folder as working directory; rosdoc2 instead runs its
    own wrapping conf.py in a build folder, which executes this file by its absolute path
    (``exec(open("…/doc/conf.py").read())``), so the path is read from the wrapper.
    """
    if os.path.isfile(os.path.join('..', 'package.xml')):
        return os.path.abspath('..')
    with open('conf.py', encoding='utf-8') as f:
        wrapped = re.search(r'exec\(open\("(.+?)"\)', f.read())
    return os.path.dirname(os.path.dirname(wrapped.group(1)))


sys.path.insert(0, _package_root())

project = 'spatial_dynamics'
copyright = '2026, spatial_dynamics contributors'
author = 'spatial_dynamics contributors'

extensions = ['myst_parser', 'sphinx.ext.autodoc', 'sphinx.ext.napoleon', 'sphinx.ext.mathjax']
napoleon_google_docstring = True
napoleon_numpy_docstring = False
source_suffix = {'.rst': 'restructuredtext', '.md': 'markdown'}
master_doc = 'index'
exclude_patterns = ['_build', 'bench/*.csv']
myst_heading_anchors = 3
# The ROS shell and the optional libraries are not needed to document the core.
autodoc_mock_imports = ['rclpy', 'sensor_msgs', 'std_msgs', 'trajectory_msgs',
                        'diagnostic_msgs', 'geometry_msgs', 'rosgraph_msgs', 'mujoco',
                        'rosbags']
autodoc_member_order = 'bysource'
autodoc_typehints = 'none'
html_theme = 'alabaster'
