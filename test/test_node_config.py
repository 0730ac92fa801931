# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The node's pure validation: descriptions, description files and parameter bounds.

These functions of ``spatial_dynamics.ros.node`` need rclpy importable but no ROS graph: they are
called directly, without a node.
"""

import math
import os
import sys
import time

import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from node_harness import DEMO_URDF  # noqa: E402
import spatial_dynamics as sd  # noqa: E402

node = pytest.importorskip('spatial_dynamics.ros.node')
ConfigError = node.ConfigError


@pytest.fixture(scope='module')
def demo_text():
    with open(DEMO_URDF) as f:
        return f.read()


def test_description_text_is_never_opened_as_a_path(tmp_path, monkeypatch):
    """robot_description (parameter or topic) is XML text: a path is refused, never read."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / 'robot.urdf').write_text(open(DEMO_URDF).read())
    for text in (DEMO_URDF, 'robot.urdf', f'  {DEMO_URDF}\n'):
        with pytest.raises(ConfigError) as info:
            node.parse_description(text, 'topic robot_description')
        message = str(info.value)
        assert 'topic robot_description' in message and 'robot_description_file' in message
        assert 'not URDF XML' in message
    # a named pipe and a device would block or exhaust memory if they were opened
    fifo = tmp_path / 'pipe'
    os.mkfifo(fifo)
    for text in (str(fifo), '/dev/zero'):
        start = time.monotonic()
        with pytest.raises(ConfigError, match='not URDF XML'):
            node.parse_description(text, 'parameter robot_description')
        assert time.monotonic() - start < 5.0


def test_description_text_with_bom_or_blank_lines_loads(demo_text):
    for text in ('\ufeff' + demo_text, '\n\n  ' + demo_text):
        model = node.parse_description(text, 'parameter robot_description')
        assert model.joint_names == sd.Model.from_urdf(DEMO_URDF).joint_names


def test_description_file_must_be_a_regular_file(tmp_path):
    fifo = tmp_path / 'pipe'
    os.mkfifo(fifo)
    link = tmp_path / 'link_to_pipe.urdf'
    link.symlink_to(fifo)
    for path, kind in [(fifo, 'named pipe'), (link, 'named pipe'), (tmp_path, 'directory'),
                       ('/dev/null', 'character device')]:
        start = time.monotonic()
        with pytest.raises(ConfigError) as info:
            node.read_description(str(path))
        assert time.monotonic() - start < 5.0
        message = str(info.value)
        assert repr(str(path)) in message and 'not a regular file' in message
        assert kind in message, message
    with pytest.raises(ConfigError, match='no such file'):
        node.read_description(str(tmp_path / 'none.urdf'))


def test_description_file_size_is_limited(tmp_path, demo_text):
    """A file larger than MAX_DESCRIPTION_BYTES is refused before it is read, limit named."""
    big = tmp_path / 'big.urdf'
    with open(big, 'wb') as f:
        f.truncate(32 * 1024 * 1024 + 1)   # sparse: costs no disk
    with pytest.raises(ConfigError) as info:
        node.read_description(str(big))
    message = str(info.value)
    assert 'big.urdf' in message and '32 MiB' in message and 'limit' in message
    assert node.MAX_DESCRIPTION_BYTES == 32 * 1024 * 1024
    ok = tmp_path / 'ok.urdf'
    ok.write_text(demo_text)
    assert node.read_description(str(ok)) == demo_text


def test_description_file_not_utf8_named(tmp_path, demo_text):
    """A file that is not UTF-8 gives a ConfigError naming the file and the byte."""
    bad = tmp_path / 'latin1.urdf'
    bad.write_bytes(demo_text.replace('demo_arm', 'd\xe9mo_arm').encode('latin-1'))
    with pytest.raises(ConfigError) as info:
        node.read_description(str(bad))
    message = str(info.value)
    assert repr(str(bad)) in message and 'UTF-8' in message
    bom = tmp_path / 'bom.urdf'
    bom.write_bytes(b'\xef\xbb\xbf' + demo_text.encode())
    assert node.read_description(str(bom)) == demo_text


@pytest.mark.parametrize('gravity', [[0.0, 0.0, -1e308], [1e4, 0.0, 0.0],
                                     [-800.0, 800.0, 0.0]])
def test_absurd_gravity_refused_with_the_bound(gravity):
    with pytest.raises(ConfigError) as info:
        node.check_gravity(gravity)
    message = str(info.value)
    assert 'parameter gravity' in message and f'{node.MAX_GRAVITY:g} m/s²' in message


def test_physical_gravity_accepted():
    assert node.check_gravity([0.0, 0.0, -9.81]) == (0.0, 0.0, -9.81)
    # a centrifuge or a test rig may exceed 1 g by far; the bound is 100 g
    assert node.MAX_GRAVITY == 1e3
    assert node.check_gravity([0.0, 0.0, -1e3]) == (0.0, 0.0, -1e3)


def test_absurd_armature_refused_with_the_bound():
    model = sd.Model.from_urdf(DEMO_URDF)
    n = len(model.joint_names)
    for bad in (1e308, 2e6):
        values = [0.1] * n
        values[2] = bad
        with pytest.raises(ConfigError) as info:
            node.check_armature(model, values)
        message = str(info.value)
        assert 'parameter armature' in message and repr(model.joint_names[2]) in message
        assert f'{node.MAX_ARMATURE:g}' in message
    assert node.check_armature(model, [node.MAX_ARMATURE] * n).max() == node.MAX_ARMATURE


@pytest.mark.parametrize('field, value, bound', [
    ('mass', 1e308, 'MAX_PAYLOAD_MASS'),
    ('mass', 2e6, 'MAX_PAYLOAD_MASS'),
    ('com', [0.0, 1e308, 0.0], 'MAX_PAYLOAD_COM'),
    ('com', [0.0, 0.0, -2e3], 'MAX_PAYLOAD_COM'),
    ('inertia', [1e308, 0.0, 0.0, 1e308, 0.0, 1e308], 'MAX_PAYLOAD_INERTIA'),
    ('inertia', [1.0, 2e6, 0.0, 1.0, 0.0, 1.0], 'MAX_PAYLOAD_INERTIA'),
])
def test_absurd_payload_refused_with_the_bound(field, value, bound):
    args = dict(link='hand', mass=1.0, com=[0.0] * 3, inertia=[0.01, 0, 0, 0.01, 0, 0.01])
    args[field] = value
    with pytest.raises(ConfigError) as info:
        node.check_payload(**args)
    message = str(info.value)
    assert f'parameter payload.{field}' in message
    assert f'{getattr(node, bound):g}' in message


def test_absurd_locked_position_refused_with_the_bound():
    with pytest.raises(ConfigError) as info:
        node.check_locked(['joint2'], [1e300])
    message = str(info.value)
    assert 'parameter locked_positions' in message and f'{node.MAX_LOCKED_POSITION:g}' in message
    assert node.check_locked(['joint2'], [-math.pi]) == {'joint2': -math.pi}
