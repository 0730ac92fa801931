# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""``ros_cli``'s refusals that need no running node: one error line, never a traceback."""

import pytest

pytest.importorskip('rclpy')

from spatial_dynamics.tools import ros_cli  # noqa: E402


@pytest.mark.parametrize('argv', [
    ['param', 'set', '/inverse_dynamics', 'gravity', '1', '--timeout', '-1'],
    ['param', 'set', '/inverse_dynamics', 'gravity', '1', '--timeout', 'nan'],
    ['topic', 'pub', '/x', 'std_msgs/msg/Empty', '-t', '0'],
    ['topic', 'pub', '/x', 'std_msgs/msg/Empty', '-r', '1e-300'],
    ['topic', 'pub', '/x', 'std_msgs/msg/Empty', '-r', 'inf'],
])
def test_out_of_range_options_are_usage_errors(argv, capsys):
    with pytest.raises(SystemExit) as exit:
        ros_cli.main(argv)
    assert exit.value.code == 2
    assert argv[-2] in capsys.readouterr().err


@pytest.mark.parametrize('argv, named', [
    (['param', 'set', '/a/../b', 'gravity', '1'], '/a/../b'),
    (['param', 'set', '', 'gravity', '1'], "''"),
    (['topic', 'pub', '/a/../b', 'std_msgs/msg/Empty'], '/a/../b'),
    (['topic', 'pub', '', 'std_msgs/msg/Empty'], "''"),
    (['topic', 'pub', '/x', '../../x'], '../../x'),
    (['topic', 'pub', '/x', 'sensor_msgs/msg/JointState', '{name: 5}'], 'name'),
    (['topic', 'pub', '/x', 'sensor_msgs/msg/JointState', '{position: [a]}'], 'position'),
])
def test_bad_names_and_values_are_one_line(argv, named, capsys):
    assert ros_cli.main(argv) == 1
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and err.startswith('error:'), err
    assert named in err, err
