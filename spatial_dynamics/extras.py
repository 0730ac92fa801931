# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The optional dependencies, grouped as the extras of ``pip install 'spatial_dynamics[…]'``.

``pip install .`` installs what the library needs (numpy, lxml); each command or method that
needs more imports it where it is used, and a missing one is said as the extra to install
(:func:`install_hint`), never as a bare ``ModuleNotFoundError``. setup.py reads
:data:`EXTRAS` from this file (it imports nothing), so the extras are declared once.
"""

#: Each extra: the distributions it installs.
EXTRAS = {
    'plot': ['matplotlib'],
    'replay': ['rosbags', 'matplotlib', 'pyyaml', 'threadpoolctl', 'scipy'],
    'identify': ['scipy', 'threadpoolctl'],
    'fleet': ['rosbags', 'matplotlib', 'pyyaml', 'threadpoolctl', 'scipy', 'dask',
              'distributed'],
    'qp': ['clarabel', 'scipy'],
    'sim': ['mujoco'],
    'test': ['pytest', 'pin', 'example-robot-data', 'hypothesis', 'mpmath', 'flake8',
             'pydocstyle'],
}

#: The module each optional distribution is imported as, and the extra that brings it.
MODULES = {
    'matplotlib': ('matplotlib', 'plot'),
    'rosbags': ('rosbags', 'replay'),
    'yaml': ('pyyaml', 'replay'),
    'threadpoolctl': ('threadpoolctl', 'replay'),
    'scipy': ('scipy', 'identify'),
    'dask': ('dask', 'fleet'),
    'distributed': ('distributed', 'fleet'),
    'clarabel': ('clarabel', 'qp'),
    'mujoco': ('mujoco', 'sim'),
}


def install_hint(err: ImportError, extra: str = '') -> str:
    """Return what to install for ``err``, a failed import of an optional module, or ''.

    ``extra``: the extra of the command that needs it (``'fleet'`` for ``replay fleet``),
    when it brings the module; otherwise the module's own extra.
    """
    name = (getattr(err, 'name', None) or '').split('.')[0]
    if name not in MODULES:
        return ''
    distribution, own = MODULES[name]
    extra = extra if distribution in EXTRAS.get(extra, ()) else own
    return (f'{distribution} is not installed (import {name}): pip install '
            f"'spatial_dynamics[{extra}]' (or pip install {distribution})")
