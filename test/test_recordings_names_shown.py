# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Names read from a bag, a URDF, a manifest or a command line reach the user short and escaped.

``replay`` and ``fleet`` are run as a user runs them, on names that would forge or flood a
terminal: a newline and an ANSI colour escape in a topic, a joint, a frame, a robot, a CSV
column or a bag's file name, and 10,000-character ones (a YAML key given twice among them).
Each message must stay one line with no raw control character, name the thing by its escaped
beginning, and cut the long one (``… (10,000 characters)``, as
:func:`spatial_dynamics.text.shown` writes it).
"""

import os
import shutil
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(__file__))
from conftest import robot_urdf_path  # noqa: E402
from test_replay_moving_base import joints, messages, RATE, stamps  # noqa: E402
from test_replay_outputs import motion_bag  # noqa: E402

import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics.fleet import main as fleet  # noqa: E402
from spatial_dynamics.recordings import bags, cdr  # noqa: E402
from spatial_dynamics.replay.__main__ import main as replay  # noqa: E402

pytest.importorskip('rosbags')
#: A name that would end a line and turn the terminal red.
FORGED = '/evil\n\x1b[31mname'
#: A name of 10,000 characters.
LONG = '/' + 'n' * 9_999
UR5 = robot_urdf_path('ur5')
UR5_JOINTS = sd.Model.from_urdf(UR5).joint_names


def escaped(name: str) -> str:
    """Return the start of ``name`` as repr writes it (how the message must name it)."""
    return repr(name)[1:21]


def check_line(text: str, name: str) -> None:
    """Assert ``text`` is one line, has no control character, names ``name``, cuts it if long."""
    assert text.count('\n') == 1 and text.endswith('\n'), text
    line = text[:-1]
    assert all(c.isprintable() for c in line), repr(line)
    assert escaped(name) in line, line
    if len(name) > 1000:
        assert f'({len(name):,} characters)' in line and len(line) < 2000, line[:300]


def refused(command, argv, capsys, status=1) -> str:
    """Run ``command(argv)``; return its stderr (the command refused, with ``status``)."""
    assert command(argv) == status
    return capsys.readouterr().err


# --------------------------------------------------------------------------------------------
# replay: a bag's topics and frames, a URDF's joints

@pytest.fixture(scope='module')
def hostile_bag(tmp_path_factory):
    """Return a UR5 bag with /joint_states, and /odom topics of a hostile name or child frame.

    ``/odom_forged`` and ``/odom_long`` give the base's motion of the joint states' 2 s in
    frames named :data:`FORGED` and :data:`LONG`; the topics named so hold the same odometry.
    """
    t_ns, t = stamps(RATE, 0.0, 2.0)
    q, qd, _ = joints(t)
    block = bags.encode_joint_states(UR5_JOINTS, t_ns, q, qd, np.zeros_like(q))
    topics = [('/joint_states', bags.JOINT_STATE, t_ns, [r.tobytes() for r in block])]
    on, ton = stamps(100.0, 0.0, 2.0)
    values = (np.zeros((len(ton), 6)), np.tile([0.0, 0.0, 0.0, 1.0], (len(ton), 1)))   # at rest
    for topic, frame in (('/odom_forged', FORGED), ('/odom_long', LONG), (FORGED, 'base_link'),
                         (LONG, 'base_link')):
        topics.append((topic, cdr.ODOMETRY, on,
                       messages(cdr.ODOMETRY, on, ('odom', frame), values)))
    path = str(tmp_path_factory.mktemp('hostile') / 'bag')
    bags.write_bag(path, 'sqlite3', topics)
    return path


@pytest.mark.parametrize('asked', [FORGED + '/joint_states', LONG + '/joint_states'],
                         ids=['forged', 'long'])
def test_replay_names_a_bags_topics_escaped_and_cut(hostile_bag, asked, tmp_path, capsys):
    """The topic asked for and the bag's own topics: each named, none forging a line."""
    err = refused(replay, ['residual', hostile_bag, '--urdf', UR5, '--topic', asked,
                           '--out', str(tmp_path / 'o'), '--no-plots'], capsys)
    check_line(err, asked)
    for topic in (FORGED, LONG, '/joint_states'):      # the bag's topics, listed
        assert escaped(topic) in err
    assert f'({len(LONG):,} characters) (nav_msgs/msg/Odometry)' in err


@pytest.mark.parametrize('topic, frame', [('/odom_forged', FORGED), ('/odom_long', LONG)],
                         ids=['forged', 'long'])
def test_replay_names_an_odometry_frame_escaped_and_cut(
        hostile_bag, topic, frame, tmp_path, capsys):
    err = refused(replay, ['residual', hostile_bag, '--urdf', UR5, '--base-odometry', topic,
                           '--out', str(tmp_path / 'o'), '--no-plots'], capsys)
    check_line(err, frame)
    assert 'child_frame_id' in err and 'is not a link of' in err


def one_joint_urdf(path, joint: str) -> str:
    """Write a one-joint robot whose joint is named ``joint`` (XML-escaped); return its path."""
    name = joint.replace('&', '&amp;').replace('\n', '&#10;').replace('"', '&quot;')
    path.write_text(
        '<robot name="one"><link name="base"/><link name="arm"><inertial><mass value="1"/>'
        '<origin xyz="0.1 0 0"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" '
        f'iyz="0"/></inertial></link><joint name="{name}" type="revolute"><parent link="base"/>'
        '<child link="arm"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="10" '
        'velocity="3"/></joint></robot>')
    return str(path)


# XML 1.0 has no escape character, even as a reference: the URDF's forged name ends a line.
@pytest.mark.parametrize('joint', ['evil\njoint', 'j' * 10_000], ids=['forged', 'long'])
def test_replay_names_a_urdfs_joint_the_bag_lacks_escaped_and_cut(
        hostile_bag, joint, tmp_path, capsys):
    urdf = one_joint_urdf(tmp_path / 'one.urdf', joint)
    err = refused(replay, ['residual', hostile_bag, '--urdf', urdf, '--out',
                           str(tmp_path / 'o'), '--no-plots'], capsys)
    check_line(err, joint)
    assert 'never have a position in the topic' in err


# --------------------------------------------------------------------------------------------
# fleet: a manifest's robots, keys and columns, a bag's file name

@pytest.fixture
def urdf(tmp_path):
    shutil.copy(UR5, tmp_path / 'ur5.urdf')
    return 'ur5.urdf'


def yaml_text(text: str) -> str:
    """Return ``text`` as a YAML double-quoted scalar (its control characters escaped)."""
    return '"' + text.replace('\\', '\\\\').replace('\n', '\\n').replace('\x1b', '\\e') + '"'


def csv_text(text: str) -> str:
    """Return ``text`` as a quoted CSV field (a newline inside it stays in the field)."""
    return '"' + text.replace('"', '""') + '"'


LONG_KEY = 'k' * 10_000
MANIFESTS = {
    'robot-forged': ('m.yaml', f'- robot: {yaml_text(FORGED)}\n  urdf: URDF\n  bag: a.db3\n',
                     FORGED),
    'robot-long': ('m.yaml', f'- robot: {LONG[1:]}\n  urdf: URDF\n  bag: a.db3\n', LONG[1:]),
    # explicit keys (? KEY): a plain one is at most 1024 characters
    'yaml-key-twice': ('m.yaml', f'- robot: r01\n  urdf: URDF\n  ? {LONG_KEY}\n  : 1\n'
                       f'  ? {LONG_KEY}\n  : 2\n', LONG_KEY),
    'csv-column-forged': ('m.csv', f'robot,urdf,{csv_text(FORGED)}\nr01,URDF,a.db3\n', FORGED),
    'csv-column-long': ('m.csv', f'robot,urdf,bag,{LONG[1:]}\nr01,URDF,a.db3,x\n', LONG[1:]),
}


@pytest.mark.parametrize('case', MANIFESTS)
def test_fleet_names_a_manifests_names_escaped_and_cut(case, urdf, tmp_path, capsys):
    name, text, hostile = MANIFESTS[case]
    (tmp_path / name).write_text(text.replace('URDF', urdf), encoding='utf-8')
    err = refused(fleet, [str(tmp_path / name), '--out', str(tmp_path / 'o'), '--serial',
                          '--no-plots'], capsys)
    check_line(err, hostile)
    assert err.startswith(f'error: manifest {str(tmp_path / name)!r}')


def test_fleet_names_a_bag_file_escaped_in_its_report(urdf, tmp_path, capsys):
    """A bag whose file name ends a line and colours the terminal: one ``failed:`` line."""
    bag = tmp_path / 'run\n\x1bc.db3'      # ESC c: a terminal's reset ('[' is a glob)
    bag.write_bytes(b'not a bag')
    (tmp_path / 'm.csv').write_text(f'robot,urdf,bag\nr01,{urdf},{csv_text(bag.name)}\n',
                                    encoding='utf-8')
    assert fleet([str(tmp_path / 'm.csv'), '--out', str(tmp_path / 'o'), '--serial',
                  '--no-plots']) == 1
    out = capsys.readouterr().out
    with open(tmp_path / 'o' / 'drift.txt', encoding='utf-8') as f:
        drift = f.read()
    for text in (out, drift):
        assert all(c.isprintable() for line in text.splitlines() for c in line), repr(text)
        failed = [line for line in text.splitlines() if line.startswith('failed:')]
        assert len(failed) == 1 and escaped(bag.name) in failed[0], text


def test_a_motion_bag_of_plain_names_still_reads(tmp_path, capsys):
    """The names a real robot has are shown as before: the residual's table names them all."""
    bag = motion_bag(tmp_path / 'run', seconds=1.0)
    assert replay(['residual', bag, '--urdf', UR5, '--out', str(tmp_path / 'o'),
                   '--no-plots']) == 0
    out = capsys.readouterr().out
    for joint in UR5_JOINTS:
        assert f'  {joint} ' in out
    assert f"{bag!r} '/joint_states': " in out


# Names written into files: quoted as the file's format needs, read back whole

ODD = ('plain', 'with,comma', 'with "double" and \'single\' quotes', 'line\nbreak', 'ünï')


def test_a_summary_csv_keeps_each_name_in_its_cell(tmp_path):
    """A comma, a quote or a line break in a joint name broke the summary's row."""
    import csv
    from spatial_dynamics.replay.report import write_summary
    path = tmp_path / 'summary.csv'
    write_summary(str(path), [[name, 1.5, None] for name in ODD], ['joint', 'rms', 'peak'])
    with open(path, newline='') as f:
        rows = list(csv.reader(f))
    assert rows == [['joint', 'rms', 'peak']] + [[name, '1.5', 'nan'] for name in ODD]


def test_the_node_parameters_yaml_reads_back_every_joint_name():
    """``repr`` with ``'`` swapped for ``"`` broke on a name holding a quote."""
    import yaml
    from spatial_dynamics.replay.report import node_parameters
    text = node_parameters(ODD, np.array([0.1, np.nan, 0.2, 0.3, 0.0]), 0.05)
    params = yaml.safe_load(text)['inverse_dynamics']['ros__parameters']
    assert params['joints'] == list(ODD)
    assert params['armature'] == [0.1, 0.0, 0.2, 0.3, 0.0]


def test_identification_names_a_urdfs_link_escaped():
    """A parameter's name is printed (undetermined parameters): its link escaped, one line."""
    from spatial_dynamics.identification import parameter_names
    urdf = ('<robot name="r"><link name="base"/><link name="arm&#10;&#13;x"><inertial><mass '
            'value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/>'
            '</inertial></link><joint name="j" type="revolute"><parent link="base"/><child '
            'link="arm&#10;&#13;x"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" '
            'velocity="1"/></joint></robot>')
    names = parameter_names(sd.Model.from_urdf(urdf))
    assert len(names) == 10 and all(n.endswith(r' of arm\n\rx') for n in names), names
