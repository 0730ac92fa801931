# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Start the ``inverse_dynamics`` node with ``config/inverse_dynamics.yaml``.

    ros2 launch spatial_dynamics inverse_dynamics.launch.py \
        robot_description_file:=/path/robot.urdf \
        effort_commands:=/effort_controller/commands

Without ``robot_description_file`` the node takes the URDF from the ``robot_description`` topic
(robot_state_publisher), as ros2_control does.
"""

import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node


def generate_launch_description():
    share = get_package_share_directory('spatial_dynamics')
    arguments = [
        DeclareLaunchArgument(
            'params_file', default_value=os.path.join(share, 'config', 'inverse_dynamics.yaml'),
            description='Parameter file of the node'),
        DeclareLaunchArgument(
            'robot_description_file', default_value='',
            description='URDF or .xacro path; empty: use the robot_description topic'),
        DeclareLaunchArgument(
            'desired_joint_states', default_value='desired_joint_states',
            description='Input topic, sensor_msgs/JointState'),
        DeclareLaunchArgument(
            'effort_commands', default_value='effort_commands',
            description='Output topic, std_msgs/Float64MultiArray, e.g. '
                        '/effort_controller/commands'),
    ]
    node = Node(
        package='spatial_dynamics',
        executable='inverse_dynamics',
        name='inverse_dynamics',
        output='screen',
        emulate_tty=True,
        parameters=[LaunchConfiguration('params_file'),
                    {'robot_description_file': LaunchConfiguration('robot_description_file')}],
        remappings=[('desired_joint_states', LaunchConfiguration('desired_joint_states')),
                    ('effort_commands', LaunchConfiguration('effort_commands'))],
    )
    return LaunchDescription(arguments + [node])
