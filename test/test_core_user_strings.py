# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A user's name in the core's errors and warnings: shortened and escaped, like the node's.

A URDF's robot, link or joint name and a joint or link asked for by name reach the messages
through :func:`spatial_dynamics.text.shown`: a 100,000-character name with a newline costs a
short message without a raw newline, and a name of at most 60 characters reads exactly as
``repr`` writes it.
"""

import warnings

import numpy as np
import pytest

import spatial_dynamics as sd
from spatial_dynamics.text import LIMIT, listed, shown

#: A hostile name: long, with a newline that would start a forged log line.
HOSTILE = 'x' * 100_000 + '\n[ERROR] [0.0] [inverse_dynamics]: forged'
#: The longest message allowed to carry HOSTILE.
SHORT = 400

ARM = """<robot name="{robot}">
  <link name="base"/>
  <link name="{upper}"><inertial><mass value="1"/><origin xyz="0 0 0.1"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="hand"><inertial><mass value="0.5"/><origin xyz="0 0 0.1"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="{shoulder}" type="revolute"><parent link="base"/><child link="{upper}"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="10" velocity="1"/>{dynamics}</joint>
  <joint name="{elbow}" type="revolute"><parent link="{upper}"/><child link="hand"/>
    <origin xyz="0 0 0.3"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="10"
    velocity="1"/></joint>
</robot>"""


def arm(**names) -> str:
    """Return the two-joint arm's URDF with the names (XML-escaped by the caller) given."""
    fields = dict(robot='arm', upper='upper', shoulder='shoulder', elbow='elbow', dynamics='')
    fields.update(names)
    return ARM.format(**fields)


#: HOSTILE as an XML attribute writes it (a newline kept as &#10;).
XML_HOSTILE = HOSTILE.replace('\n', '&#10;')


def safe(text: str) -> bool:
    """Whether ``text`` is one short line that shows HOSTILE cut, with its length."""
    return (len(text) < SHORT and '\n' not in text and 'forged' not in text
            and f'({len(HOSTILE):,} characters)' in text)


def test_shown_is_repr_up_to_the_limit_and_cut_with_the_length_beyond():
    for name in ('hand', "it's", 'a\nb', 'é' * LIMIT, 1.5, None, ['a', 2]):
        assert shown(name) == repr(name)
    assert shown(HOSTILE) == repr('x' * LIMIT) + f'… ({len(HOSTILE):,} characters)'
    assert shown(['a\n' * 40]).endswith('characters)') and '\n' not in shown(['a\n' * 40])
    assert listed(('a', 'b')) == "'a', 'b'" and listed([HOSTILE]) == shown(HOSTILE)


@pytest.mark.parametrize('call', [
    lambda text: sd.Model.from_urdf(text, joints=[HOSTILE]),
    lambda text: sd.Model.from_urdf(text, joints=['shoulder'], locked={HOSTILE: 0.0}),
    lambda text: sd.Model.from_urdf(text.replace('"shoulder"', f'"{XML_HOSTILE}"'),
                                    joints=[HOSTILE, HOSTILE]),
    lambda text: sd.Model.from_urdf(text, locked={HOSTILE: 0.0}),
    lambda text: sd.jacobian(sd.Model.from_urdf(text), np.zeros(2), HOSTILE),
    lambda text: sd.with_payload(sd.Model.from_urdf(text), HOSTILE, 1.0),
    lambda text: sd.Model.from_urdf(text.replace('"elbow"', f'"{XML_HOSTILE}"')
                                    .replace('"shoulder"', f'"{XML_HOSTILE}"')),
    lambda text: sd.Model.from_urdf(text.replace('<child link="hand"/>',
                                                 f'<child link="{XML_HOSTILE}"/>')),
    lambda text: sd.Model.from_urdf(text.replace('xyz="0 1 0"', f'xyz="{XML_HOSTILE}"')),
], ids=['kept', 'locked', 'kept twice', 'locked without kept', 'jacobian link', 'payload link',
        'duplicate joint', 'unknown child', 'axis text'])
def test_a_hostile_name_in_an_error_is_short_and_one_line(call):
    with pytest.raises(ValueError) as err:
        call(arm())
    assert safe(str(err.value)), str(err.value)[:SHORT]


def test_a_hostile_joint_name_in_a_warning_is_short_and_one_line():
    text = arm(shoulder=XML_HOSTILE, dynamics='<dynamics damping="-1"/>')
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter('always')
        model = sd.Model.from_urdf(text)
    assert model.joint_names[0] == HOSTILE      # loaded as written
    assert model.warnings and all(safe(w) for w in model.warnings), model.warnings[0][:SHORT]
    assert all(safe(str(w.message)) for w in caught)
    with pytest.raises(ValueError) as err:      # strict: the warning is the error
        sd.Model.from_urdf(text, strict=True)
    assert safe(str(err.value))


def test_a_hostile_robot_name_is_short_in_the_summary_and_in_errors():
    model = sd.Model.from_urdf(arm(robot=XML_HOSTILE))
    assert model.name == HOSTILE
    assert safe(model.summary()) and safe(repr(model))
    with pytest.raises(ValueError) as err:
        sd.jacobian(model, np.zeros(2), 'nowhere')
    assert safe(str(err.value))


def test_a_short_name_reads_as_repr_writes_it():
    with pytest.raises(ValueError, match=r"^kept joint 'hand\\n' is not a movable joint of the "
                                         r'URDF$'):
        sd.Model.from_urdf(arm(), joints=['hand\n'])
    with pytest.raises(ValueError, match=r"^joints lists a joint twice: \['shoulder', "
                                         r"'shoulder'\]$"):
        sd.Model.from_urdf(arm(), joints=['shoulder', 'shoulder'])
