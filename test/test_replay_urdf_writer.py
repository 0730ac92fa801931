# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""``--write-urdf`` edits every URDF the loader accepts, and its problems are found before the fit.

The loader (:mod:`spatial_dynamics.urdf`) reads files with whitespace or a byte order mark
before the XML declaration, another XML version, elements of other namespaces inside a link
(``xacro:``, ``gazebo:``) and a DOCTYPE; the writer must find its elements in the same files,
change only the identified ones and keep the rest byte for byte.
"""

import os
import re
import shutil
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(__file__))
from conftest import robot_urdf_path  # noqa: E402

import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics import identification  # noqa: E402
from spatial_dynamics import drives as identify  # noqa: E402
from spatial_dynamics.replay import urdf_writer  # noqa: E402
from spatial_dynamics.replay.__main__ import main  # noqa: E402
from spatial_dynamics.replay.urdf_writer import corrected_urdf  # noqa: E402
from spatial_dynamics.urdf import read_description  # noqa: E402

pytest.importorskip('rosbags')
from test_replay_outputs import motion_bag  # noqa: E402


def variants(text: bytes) -> dict:
    """Return the UR5 file as users' tools write it, each a file the loader reads."""
    declared = text[:text.index(b'?>') + 2]
    body = text[len(declared):]
    gazebo = b'xmlns:gazebo="http://gazebosim.org/schema"'
    return {
        'whitespace before <?xml': b'  \n\t' + text,
        'byte order mark and a blank line': b'\xef\xbb\xbf\n' + text,
        'XML 1.1': declared.replace(b'version="1.0"', b'version="1.1"') + body,
        'prefixed element in a link (xmlns on <robot>)': text.replace(
            b'<link name="forearm_link">',
            b'<link name="forearm_link">\n    <xacro:property name="l" value="0.39"/>'),
        'namespace declared on the link': text.replace(
            b'<link name="wrist_1_link">',
            b'<link name="wrist_1_link" ' + gazebo + b'><gazebo:sensor a=">"/>'),
        'DOCTYPE with a default attribute': declared + b'\n<!DOCTYPE robot [\n'
        b'  <!ATTLIST dynamics damping CDATA "7.0">\n]>' + body,
    }


def strip(text):
    """Remove <inertial> elements and <dynamics/> tags (what the writer may replace)."""
    text = re.sub(rb'\s*<inertial>.*?</inertial>', b'', text, flags=re.S)
    return re.sub(rb'\s*<dynamics[^>]*/>', b'', text)


def load(text: bytes, folder) -> sd.Model:
    """Load URDF bytes as the commands do: the file read by the one reader, then parsed."""
    path = folder / 'robot.urdf'
    path.write_bytes(text)
    return sd.Model.from_urdf(read_description(str(path)))


@pytest.mark.parametrize('case', sorted(variants(b'<?xml version="1.0"?>')))
def test_the_writer_edits_whatever_the_loader_accepts(case, tmp_path):
    text = variants(open(robot_urdf_path('ur5'), 'rb').read())[case]
    model = load(text, tmp_path)                 # the loader accepts it
    forearm = model.frames['forearm_link'].body
    heavier = 1.3 * model.inertia[forearm]
    joint = model.joint_names[2]
    out, notes = corrected_urdf(text, model, {forearm: heavier}, None, {joint: (0.5, 1.25)})
    assert notes == []
    assert strip(out) == strip(text)             # everything else byte for byte
    again = load(out, tmp_path)
    expected = np.array(model.inertia)
    expected[forearm] = heavier
    np.testing.assert_allclose(again.inertia, expected, rtol=1e-10, atol=1e-12)
    assert again.damping[2] == 0.5 and again.friction[2] == 1.25
    np.testing.assert_array_equal(np.delete(again.damping, 2), np.delete(model.damping, 2))


def test_write_urdf_of_a_file_with_whitespace_and_namespaces(tmp_path, capsys):
    """The command end to end: the file loads, the fitted <dynamics> are in it."""
    text = variants(open(robot_urdf_path('ur5'), 'rb').read())
    urdf = tmp_path / 'robot.urdf'
    urdf.write_bytes(text['whitespace before <?xml'].replace(
        b'<link name="forearm_link">',
        b'<link name="forearm_link">\n    <xacro:property name="l" value="0.39"/>'))
    bag = motion_bag(tmp_path / 'bag')
    out = tmp_path / 'corrected.urdf'
    assert main(['identify', bag, '--urdf', str(urdf), '--no-plots', '--residual', 'none',
                 '--out', str(tmp_path / 'o'), '--write-urdf', str(out)]) == 0
    capsys.readouterr()
    corrected = sd.Model.from_urdf(str(out))
    np.testing.assert_allclose(corrected.damping, 0.5, atol=0.05)     # the bag's drives
    np.testing.assert_allclose(corrected.friction, 1.0, atol=0.05)
    assert out.read_bytes().startswith(b'  \n\t<?xml')


def test_the_writers_view_is_prepared_before_the_fit(tmp_path, capsys, monkeypatch):
    """Whatever the writer could not edit is said before any fit runs, naming the file."""
    def fit(*args, **kwargs):
        raise AssertionError('a fit ran before the refusal')
    for name in ('identify_payload', 'identify_inertias'):
        monkeypatch.setattr(identification, name, fit)
    monkeypatch.setattr(identify, 'identify', fit)

    def cannot(data):
        raise ValueError('not what the writer reads')
    monkeypatch.setattr(urdf_writer, '_elements', cannot)
    urdf = tmp_path / 'robot.urdf'
    shutil.copy(robot_urdf_path('ur5'), urdf)
    status = main(['identify', motion_bag(tmp_path / 'bag'), '--urdf', str(urdf),
                   '--no-plots', '--out', str(tmp_path / 'o'), '--write-urdf',
                   str(tmp_path / 'corrected.urdf')])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 1 and len(err) == 1, err
    assert str(urdf) in err[0] and 'not what the writer reads' in err[0], err
    assert not (tmp_path / 'corrected.urdf').exists()
