# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The core (spatial, joints, model, rnea) never imports ROS: checked in a fresh interpreter."""

import os
import subprocess
import sys
import textwrap

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

SCRIPT = textwrap.dedent('''\
    import sys
    import numpy as np
    import spatial_dynamics as sd
    from spatial_dynamics import joints, model, rnea, spatial  # noqa: F401
    urdf = (
        '<robot name="r"><link name="base"/><link name="arm"><inertial><mass value="1"/>'
        '<origin xyz="0 0 -0.5"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" '
        'izz="0.1"/></inertial></link><joint name="j" type="revolute"><parent link="base"/>'
        '<child link="arm"/><axis xyz="0 1 0"/>'
        '<limit effort="1" velocity="1" lower="-1" upper="1"/></joint></robot>')
    m = sd.Model.from_urdf(urdf)
    tau = sd.rnea(m, np.ones((2, 1)), np.ones((2, 1)), np.ones((2, 1)))
    assert tau.shape == (2, 1)
    ros = sorted(name for name in sys.modules
                 if name.split('.')[0] in ('rclpy', 'rcl_interfaces', 'sensor_msgs',
                                           'std_msgs', 'trajectory_msgs', 'rosidl_runtime_py'))
    print('ROS MODULES:', ros)
    print('node imported:', 'spatial_dynamics.ros.node' in sys.modules)
''')


def test_core_does_not_import_rclpy():
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [ROOT] + [p for p in os.environ.get('PYTHONPATH', '').split(os.pathsep) if p]))
    proc = subprocess.run([sys.executable, '-c', SCRIPT], capture_output=True, text=True,
                          cwd=ROOT, env=env, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert 'ROS MODULES: []' in proc.stdout, proc.stdout
    assert 'node imported: False' in proc.stdout, proc.stdout
