# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The start-up benchmark's options and robot: what cannot run is refused in one line, first."""

import os
import shutil

import pinocchio
import pytest

from spatial_dynamics.tools import startup
from spatial_dynamics.tools.driving import demo_urdf
from spatial_dynamics.tools.startup import main, parse_args

NO_JOINTS = """<robot name="one_link">
  <link name="base">
    <inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/>
    </inertial>
  </link>
</robot>
"""


def refusal(argv, capsys) -> str:
    """Return the message of the refusal of parse_args (exit status 2)."""
    with pytest.raises(SystemExit) as exit:
        parse_args(argv)
    assert exit.value.code == 2
    return capsys.readouterr().err


@pytest.mark.parametrize('option, value', [
    ('--rate', '0'), ('--rate', 'nan'), ('--rate', '1e-9'), ('--rate', '1e9'),
    ('--rate', '0.5'), ('--rate', '10001'), ('--lead', 'nan'), ('--lead', '-1'),
    ('--lead', '61'), ('--hold', 'inf'), ('--hold', '-0.1'), ('--hold', '3601'),
    ('--timeout', 'nan'), ('--timeout', '0'), ('--timeout', '-1'), ('--timeout', '86401'),
    ('--runs', '0'), ('--runs', '-1'), ('--runs', '1001'), ('--runs', '1.5'),
])
def test_out_of_range_numbers_are_refused(option, value, capsys):
    assert option in refusal([option, value], capsys)


def test_the_ranges_keep_the_defaults_and_real_values():
    args = parse_args(['--rate', '1', '--lead', '0', '--hold', '0', '--runs', '1',
                       '--timeout', '86400', '--backend', 'auto', 'numpy', 'compiled'])
    assert (args.rate, args.lead, args.hold, args.runs, args.timeout) == (1.0, 0.0, 0.0, 1,
                                                                          86400.0)
    assert args.backend == ['auto', 'numpy', 'compiled']
    top = parse_args(['--rate', '10000', '--lead', '60', '--hold', '3600', '--runs', '1000'])
    assert (top.rate, top.lead, top.hold, top.runs) == (10000.0, 60.0, 3600.0, 1000)
    defaults = parse_args([])
    assert (defaults.rate, defaults.runs, defaults.timeout, defaults.backend) == (
        100.0, 3, 300.0, ['auto'])


def test_a_backend_given_twice_is_refused(capsys):
    err = refusal(['--backend', 'numpy', 'auto', 'numpy'], capsys)
    assert '--backend numpy given more than once' in err, err


@pytest.mark.parametrize('option', ['--json', '--urdf', '--log-dir'])
def test_an_empty_path_is_refused(option, capsys):
    assert f'argument {option}: an empty path' in refusal([option, ''], capsys)


@pytest.mark.parametrize('kind', ['dangling link', 'link loop', 'long name'])
def test_a_log_dir_no_folder_can_be_made_at_is_refused(kind, tmp_path, capsys):
    folder = tmp_path / 'logs'
    if kind == 'dangling link':
        folder.symlink_to(tmp_path / 'missing')
    elif kind == 'link loop':
        folder.symlink_to(folder)
    else:
        folder = tmp_path / ('x' * 300)
    err = refusal(['--log-dir', str(folder)], capsys)
    assert err.splitlines()[-1].startswith(
        'python -m spatial_dynamics.tools.startup: error: --log-dir'), err
    assert not os.path.isdir(folder)


@pytest.mark.parametrize('how', ['the same path', 'a link to it', 'a hard link'])
def test_the_json_cannot_be_the_robot_read(how, tmp_path, capsys):
    urdf = tmp_path / 'r.urdf'
    shutil.copy(demo_urdf(), urdf)
    text = urdf.read_text()
    out = urdf
    if how == 'a link to it':
        out = tmp_path / 'out.json'
        out.symlink_to(urdf)
    elif how == 'a hard link':
        out = tmp_path / 'out.json'
        os.link(urdf, out)
    err = refusal(['--urdf', str(urdf), '--json', str(out)], capsys)
    assert f"--json '{out}' is the file --urdf reads" in err, err
    assert urdf.read_text() == text


def test_the_json_cannot_be_the_default_robot(capsys):
    robot = startup.robot_path(None)
    err = refusal(['--json', robot], capsys)
    assert '--urdf reads' in err, err


def test_the_json_and_the_robot_cannot_be_a_node_log(tmp_path, capsys):
    logs = tmp_path / 'logs'
    err = refusal(['--log-dir', str(logs), '--backend', 'numpy', 'auto', '--runs', '2',
                   '--json', str(logs / 'auto_warm_7.log')], capsys)
    assert "--log-dir's log" in err and 'same path' in err, err
    logs.mkdir()
    urdf = logs / 'numpy_cold_0.log'
    shutil.copy(demo_urdf(), urdf)
    err = refusal(['--log-dir', str(logs), '--backend', 'numpy', '--urdf', str(urdf)],
                  capsys)
    assert '--urdf reads' in err, err


def test_a_robot_with_no_joints_is_refused_at_start(tmp_path, capsys, handlers_kept):
    urdf = tmp_path / 'one_link.urdf'
    urdf.write_text(NO_JOINTS)
    assert pinocchio.buildModelFromUrdf(str(urdf)).nv == 0     # nothing to answer indeed
    # --timeout 1: the run it would start gives up soon instead of after 300 s
    assert main(['--urdf', str(urdf), '--runs', '1', '--timeout', '1']) == 1
    err = capsys.readouterr().err
    assert err == f"start-up: --urdf '{urdf}': the robot has no joints: nothing to answer\n"


def test_a_fifo_as_the_robot_is_one_line(tmp_path, capsys, handlers_kept):
    fifo = tmp_path / 'robot.urdf'
    os.mkfifo(fifo)
    assert main(['--urdf', str(fifo), '--runs', '1', '--timeout', '1']) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"start-up: --urdf '{fifo}': ") and 'named pipe' in err, err
    assert err.count('\n') == 1, err
