# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0

from glob import glob
import os

from setuptools import find_packages, setup

package_name = 'spatial_dynamics'


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
    install_requires=['numpy', 'lxml'],
    extras_require={
        'test': ['pytest', 'pin', 'example-robot-data', 'hypothesis', 'mpmath', 'flake8',
                 'pydocstyle'],
        'plot': ['matplotlib'],
        'fast': ['numba'],
        'replay': ['rosbags', 'matplotlib', 'pyyaml'],
        'sim': ['mujoco'],
    },
    zip_safe=True,
    maintainer='spatial_dynamics maintainers',
    maintainer_email='maintainer@spatial-dynamics.dev',
    description='Inverse dynamics (RNEA on spatial vectors) from a URDF, with a ROS 2 node '
                'publishing feed-forward joint efforts.',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'inverse_dynamics = spatial_dynamics.ros.node:main',
            'demo = spatial_dynamics.tools.demo:main',
            'check_urdf = spatial_dynamics.check:main',
            'replay = spatial_dynamics.replay.__main__:main',
            'sim = spatial_dynamics.sim.node:main',
        ],
    },
)
