# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A user's string in the node's log lines and diagnostics values: shortened and escaped.

A message's ``frame_id``, a URDF's robot or joint name, a parameter's link: the node shows at
most :data:`~spatial_dynamics.ros.text.LIMIT` characters of it, then its length, with every
control character escaped (:func:`~spatial_dynamics.ros.text.shown`), so a 10,000-character
name costs a short line and a newline in it cannot forge a log line. Pure: the answering
module and the diagnostics driven with message objects, no ROS graph.
"""

import os
import sys

from geometry_msgs.msg import WrenchStamped
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from node_harness import DEMO_URDF, Log  # noqa: E402
from spatial_dynamics.ros import config, configure  # noqa: E402
from spatial_dynamics.ros.answering import Answering  # noqa: E402
from spatial_dynamics.ros.base_messages import twist_link  # noqa: E402
from spatial_dynamics.ros.diagnostics import model_status, Totals  # noqa: E402
from spatial_dynamics.ros.inputs import InputError  # noqa: E402
from spatial_dynamics.ros.text import LIMIT, listed, shown  # noqa: E402

#: A hostile name: long, with a newline that would start a forged log line.
FORGED = '\n[ERROR] [0.0] [inverse_dynamics]: forged'
HOSTILE = 'x' * 10_000 + FORGED
#: A line that shows HOSTILE as it must: the limit, the count, the rest of the line.
SHORT = 1000


@pytest.fixture(scope='module')
def demo_text():
    with open(DEMO_URDF) as f:
        return f.read()


def configured(text, **changes):
    params = {spec.name: spec.default for spec in config.PARAMETERS}
    params.update(robot_description=text, **changes)
    return configure.prepare({}, params, None)


def safe(line: str) -> bool:
    """Whether ``line`` is one short line that does not carry the hostile name whole."""
    return len(line) < SHORT and '\n' not in line and 'forged' not in line


def test_shown_is_repr_for_a_name_and_cut_with_its_length_beyond_the_limit():
    assert shown('hand') == repr('hand') and shown("it's") == repr("it's")
    assert shown('hand', quote=False) == 'hand'
    assert shown('a\nb') == repr('a\nb') and '\n' not in shown('a\nb', quote=False)
    text = shown(HOSTILE)
    assert text == repr('x' * LIMIT) + f'… ({len(HOSTILE):,} characters)'
    assert listed(['a', 'b']) == "'a', 'b'"
    assert listed([str(k) for k in range(9)]) == "'0', '1', '2', '3', '4', ..."


def test_a_wrench_on_a_hostile_frame_id_is_warned_in_one_short_line(demo_text):
    cfg = configured(demo_text)
    log = Log()
    answering = Answering(log)
    msg = WrenchStamped()
    msg.header.frame_id = HOSTILE
    msg.wrench.force.z = 1.0
    answering.wrench(cfg, msg)
    assert answering.totals.wrenches_rejected['unknown_link'] == 1
    (level, line), = log.said
    assert level == 'warn' and safe(line) and f'({len(HOSTILE):,} characters)' in line, line


def test_a_hostile_twist_frame_is_refused_in_one_short_line(demo_text):
    model = configured(demo_text).robot.model
    with pytest.raises(InputError) as err:
        twist_link(model, HOSTILE, 'header.frame_id')
    assert safe(str(err.value)), str(err.value)


def test_a_hostile_parameter_link_is_refused_in_one_short_line(demo_text):
    with pytest.raises(config.ConfigError) as err:
        configured(demo_text, **{'payload.link': HOSTILE})
    assert safe(str(err.value)), str(err.value)


def test_a_hostile_robot_name_is_short_in_diagnostics(demo_text):
    name = 'r' * 10_000 + '&#10;forged'     # an XML attribute keeps a newline as &#10;
    robot = configured(demo_text.replace('<robot name="demo_arm">',
                                         f'<robot name="{name}">')).robot
    assert '\n' in robot.model.name
    level, message, values = model_status(robot, Totals(), False, 'numpy')
    kv = dict(values)
    assert safe(message) and safe(kv['robot name']), (message, kv['robot name'])


def test_a_hostile_joints_parameter_is_refused_in_one_short_line(demo_text):
    """The core's message, passed on by the node, shows the name as the node's own do."""
    for joints in ([HOSTILE], ['joint1', HOSTILE]):
        with pytest.raises(config.ConfigError) as err:
            configured(demo_text, joints=joints)
        assert safe(str(err.value)), str(err.value)[:SHORT]
    with pytest.raises(config.ConfigError) as err:
        configured(demo_text, joints=['joint1'], locked_joints=[HOSTILE],
                   locked_positions=[0.1])
    assert safe(str(err.value)), str(err.value)[:SHORT]
