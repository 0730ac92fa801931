# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The compiled extension is rebuilt whenever a source of its generated kernels changes.

setuptools rebuilds an extension when a file of its ``depends`` is newer than the build: so
every module of the package that the kernel generator (``backends/codegen.py``) imports, or
that the modules it reads import, must be listed there. A module left out (as
``backends/c_printer.py`` once was) would let a change to the C printer ship old kernels.
Likewise every C file of the extension (``backends/*.c``, ``*.h``) is one of its ``sources``
or ``depends``, and the source distribution carries it.
"""

import glob
import os
import runpy
import subprocess
import sys
from unittest import mock

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

#: Imported by the generator's modules but not read by it: the runtime dispatch, never a
#: source of the generated C.
RUNTIME = {'spatial_dynamics/__init__.py', 'spatial_dynamics/backends/__init__.py',
           'spatial_dynamics/backends/compiled.py', 'spatial_dynamics/backends/python.py'}


def extension():
    """Return the package's extension, as setup.py declares it."""
    with mock.patch('setuptools.setup') as setup:
        cwd = os.getcwd()
        os.chdir(ROOT)
        try:
            runpy.run_path(os.path.join(ROOT, 'setup.py'), run_name='__main__')
        finally:
            os.chdir(cwd)
    (ext,) = setup.call_args.kwargs['ext_modules']
    return ext


def extension_depends():
    """Return the ``depends`` of the package's extension, as setup.py declares it."""
    return set(extension().depends)


def extension_c_files():
    """Return the C sources and headers in the extension's folder (``backends/``).

    Not the generated header, should one have been written there (``python -m
    spatial_dynamics.backends.codegen DIR``): a build product, never a source.
    """
    from spatial_dynamics.backends import codegen
    pattern = os.path.join(ROOT, 'spatial_dynamics', 'backends', '*.[ch]')
    return {os.path.relpath(path, ROOT) for path in glob.glob(pattern)
            if os.path.basename(path) != codegen.HEADER}


def generator_modules():
    """Return the package's files that generating the kernels imports (in a fresh process)."""
    code = ('import sys\n'
            'from spatial_dynamics.backends import codegen\n'
            'codegen.generate_c()\n'
            'for name, mod in sorted(sys.modules.items()):\n'
            '    if name.startswith("spatial_dynamics") and getattr(mod, "__file__", None):\n'
            '        print(mod.__file__)\n')
    run = subprocess.run([sys.executable, '-c', code], cwd=ROOT, capture_output=True,
                         text=True, check=True)
    files = {os.path.relpath(f, ROOT) for f in run.stdout.split()}
    return {f for f in files if f.endswith('.py')}


def test_every_generator_source_is_a_dependency():
    depends = extension_depends()
    imported = generator_modules()
    # what the generator's own modules import from the package, whatever else comes along
    sources = {f for f in imported
               if f.startswith(('spatial_dynamics/algorithms/', 'spatial_dynamics/backends/'))}
    sources |= {'spatial_dynamics/joints.py', 'spatial_dynamics/spatial.py'}
    missing = sorted(sources - RUNTIME - depends)
    assert not missing, f'setup.py: the extension does not depend on {missing}'
    assert 'spatial_dynamics/backends/c_printer.py' in depends
    assert all(os.path.isfile(os.path.join(ROOT, f)) for f in depends), depends


def test_every_c_file_of_the_extension_is_a_source_or_a_dependency():
    ext = extension()
    c_files = extension_c_files()
    assert 'spatial_dynamics/backends/_compiled.c' in c_files
    assert not set(ext.sources) & set(ext.depends), 'a file both compiled and depended on'
    missing = sorted(c_files - set(ext.sources) - set(ext.depends))
    assert not missing, f'setup.py: the extension neither compiles nor depends on {missing}'
    # what it compiles are the C files beside it; what it depends on exists
    assert set(ext.sources) == {f for f in c_files if f.endswith('.c')}
    assert all(os.path.isfile(os.path.join(ROOT, f)) for f in ext.sources)


def test_the_source_distribution_carries_every_c_file(tmp_path):
    # SOURCES.txt of egg_info is the file list that `setup.py sdist` packs
    command = [sys.executable, 'setup.py', '-q', 'egg_info', '--egg-base', str(tmp_path)]
    subprocess.run(command, cwd=ROOT, capture_output=True, text=True, check=True)
    (listing,) = tmp_path.glob('*.egg-info/SOURCES.txt')
    carried = set(listing.read_text(encoding='utf-8').split())
    missing = sorted(extension_c_files() - carried)
    assert not missing, f'MANIFEST.in: the source distribution leaves out {missing}'
