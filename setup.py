# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0

from glob import glob
import os
import runpy
import sys

from setuptools import Extension, find_packages, setup
from setuptools.command.build_ext import build_ext

#: The commands, run by ``ros2 run spatial_dynamics NAME`` from lib/spatial_dynamics (setup.cfg)
#: or from bin/ of a pip install: plain three-line scripts in bin/, not console_scripts entry
#: points, whose wrapper (setuptools' ``setup.py install``, which colcon runs) looks the entry
#: point up through importlib.metadata at every start: ~20 ms with bytecode cached, ~0.13 s
#: without, before the command does anything.
EXECUTABLES = ('inverse_dynamics', 'demo', 'spatial_dynamics_check', 'replay', 'sim')

package_name = 'spatial_dynamics'
HERE = os.path.dirname(os.path.abspath(__file__))
#: The kernels generated from spatial_dynamics/algorithms (backends/codegen.py) as a C
#: extension. The generated C is a build product, written by BuildKernels into the build
#: directory (never into the sources): what it is generated from is what it depends on.
#: The extension is one C file a job around the private header _compiled.h (which lists
#: them); only kernels.c includes the generated header. -ffp-contract=off: no fused
#: multiply-adds, so every operation rounds as in the Python backends. -fvisibility=hidden:
#: the files' shared functions stay inside the shared object (direct calls, no PLT; only
#: PyInit__compiled is exported). It reads numpy arrays through the numpy C API: numpy (its
#: headers, and the generator's import of the package) is a build requirement
#: (pyproject.toml, package.xml).
KERNELS = Extension(
    package_name + '.backends._compiled',
    # every C file in backends/ is a source or a dependency (test/test_compiled_build_depends.py)
    sources=[package_name + '/backends/' + f for f in (
        '_compiled.c', 'arguments.c', 'door.c', 'entries.c', 'kernels.c', 'threads.c')],
    # the private header, and every module the generator reads or imports
    depends=[package_name + '/backends/_compiled.h'] + sorted(
        glob(package_name + '/algorithms/*.py')) + [
        package_name + '/' + f for f in ('backends/codegen.py', 'backends/c_printer.py',
                                         'backends/c_lanes.py', 'backends/layout.py',
                                         'joints.py', 'spatial.py')],
    extra_compile_args=[] if os.name == 'nt' else ['-ffp-contract=off', '-fvisibility=hidden',
                                                   '-pthread'],
    extra_link_args=[] if os.name == 'nt' else ['-pthread'],
)


class BuildKernels(build_ext):
    """Build the compiled kernels; without a working C compiler, install without them.

    The package then runs on plain Python (``backend='auto'`` is ``'numpy'``): one warning
    says so, and how to get the kernels.
    """

    def run(self) -> None:
        """Build the extensions, or warn once and build none."""
        try:
            super().run()
        except Exception as err:     # no compiler at all (DistutilsPlatformError)
            self._skip(err)

    def build_extension(self, ext) -> None:
        """Build ``ext`` (with numpy's headers), or warn once and leave it out."""
        try:
            try:
                import numpy
            except ImportError as err:
                raise RuntimeError(f'numpy, whose C headers they need, is not importable at '
                                   f'build time ({err}); install numpy (Debian/Ubuntu: '
                                   f'python3-numpy)') from None
            generated, digest = self._generate()
            ext.include_dirs = [generated, *ext.include_dirs, numpy.get_include()]
            ext.define_macros = [*ext.define_macros, ('KERNELS_SHA256', f'"{digest}"')]
            super().build_extension(ext)
        except Exception as err:     # the compiler failed (CompileError, LinkError)
            self._skip(err)

    def _generate(self):
        """Write ``_kernels_generated.h`` into the build directory; return it and its SHA-256.

        The extension records the digest (``KERNELS_SHA256``): a test compares it with a
        fresh generation, so a build older than its sources is found.
        """
        import hashlib
        import warnings
        sys.path.insert(0, HERE)
        try:
            with warnings.catch_warnings():   # the package's own warning about the
                warnings.simplefilter('ignore')  # kernels this very build is making
                from spatial_dynamics.backends import codegen
        finally:
            sys.path.remove(HERE)
        text = codegen.generate_c()
        directory = os.path.join(os.path.abspath(self.build_temp), 'generated')
        os.makedirs(directory, exist_ok=True)
        with open(os.path.join(directory, codegen.HEADER), 'w', encoding='utf-8') as f:
            f.write(text)
        return directory, hashlib.sha256(text.encode('utf-8')).hexdigest()

    def get_outputs(self) -> list:
        """List the extensions built (none that failed)."""
        return [path for path in super().get_outputs() if os.path.exists(path)]

    def _skip(self, err: Exception) -> None:
        reason = ' '.join(str(err).split()) or type(err).__name__
        print(f'WARNING: {package_name}: the compiled kernels were not built ({reason}); '
              f'the package runs on plain Python. For the compiled kernels install a C '
              f'compiler and the Python headers (Debian/Ubuntu: build-essential python3-dev) '
              f'and build again.', file=sys.stderr)


def files(pattern):
    """Return the regular files matching a glob pattern, sorted."""
    return sorted(path for path in glob(pattern) if os.path.isfile(path))


setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(include=[package_name, package_name + '.*']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/launch', files('launch/*.launch.py')),
        ('share/' + package_name + '/config', files('config/*')),
    ],
    ext_modules=[KERNELS],
    cmdclass={'build_ext': BuildKernels},
    install_requires=['numpy', 'lxml'],
    # plot, replay, identify, fleet, qp, sim, test: written once, in spatial_dynamics/extras.py
    extras_require=runpy.run_path(os.path.join(HERE, package_name, 'extras.py'))['EXTRAS'],
    zip_safe=False,
    maintainer='spatial_dynamics maintainers',
    maintainer_email='maintainer@spatial-dynamics.dev',
    description='Inverse dynamics (RNEA on spatial vectors) from a URDF, with a ROS 2 node '
                'publishing feed-forward joint efforts.',
    license='Apache-2.0',
    # ros2 run finds them in lib/spatial_dynamics (setup.cfg); plain scripts: bin/*.
    scripts=[os.path.join('bin', name) for name in EXECUTABLES],
)
