# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The URDF policy, case by case: refused, loaded with a warning, or silent.

Physically inconsistent but computable descriptions load exactly as written (so the torques
equal Pinocchio's on the same file) with a URDFWarning naming the element, the quantity and
its values; ``strict=True`` refuses them; rounding noise and huge limits are silent.
"""

import os
import re
import warnings
import xml.etree.ElementTree as ET

from conftest import example_robot_data_dir, PinOracle, random_state, robot_urdf_path
import numpy as np
import pytest
import spatial_dynamics as sd

ZERO = 'ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"'
GOOD = 'ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.01"'


def arm(upper='1.0', upper_inertia=GOOD, fore='0.5', fore_inertia=GOOD, name=' name="arm"',
        limit='<limit effort="10" velocity="2" lower="-1" upper="1"/>', dynamics=''):
    """Return a two-link arm whose links' inertial values are given."""
    return f"""<?xml version="1.0"?>
<robot{name}>
  <link name="base"/>
  <link name="upper"><inertial><origin xyz="0 0 0.2" rpy="0.3 0 0"/>
    <mass value="{upper}"/><inertia {upper_inertia}/></inertial></link>
  <link name="fore"><inertial><origin xyz="0.1 0 0.15"/>
    <mass value="{fore}"/><inertia {fore_inertia}/></inertial></link>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>{limit}{dynamics}</joint>
  <joint name="elbow" type="revolute"><parent link="upper"/><child link="fore"/>
    <origin xyz="0 0 0.4" rpy="0 0.2 0"/><axis xyz="0 1 0"/>{limit}</joint>
</robot>"""


def load_silently(urdf, **kwargs):
    """Load, failing the test on any URDFWarning."""
    with warnings.catch_warnings():
        warnings.simplefilter('error', sd.URDFWarning)
        return sd.Model.from_urdf(urdf, **kwargs)


# -- silent: rounding noise in the file's decimals ------------------------------------------

NOISE = {
    # iCub's l_ankle_2: an inertia that is zero but for ±1.36e-20 (principal moments ±1.36e-20)
    'zero inertia with 1e-20 noise': dict(
        fore_inertia='ixx="0" ixy="1.35525e-20" ixz="0" iyy="0" iyz="0" izz="0"'),
    # a point mass written with a -2e-22 moment
    'point mass with -2e-22': dict(
        fore_inertia='ixx="-2e-22" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"'),
    'massless link with 1e-20 noise': dict(
        fore='0', fore_inertia='ixx="1e-20" ixy="0" ixz="0" iyy="-1e-20" iyz="0" izz="0"'),
    'massless link without inertia': dict(fore='0', fore_inertia=ZERO),
    # a consistent dummy link of 1 mg and a rod (triangle inequality met with equality)
    'tiny dummy link': dict(fore='1e-6', fore_inertia='ixx="1e-12" ixy="0" ixz="0" '
                            'iyy="1e-12" iyz="0" izz="1e-12"'),
    'thin rod': dict(fore_inertia='ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0"'),
    'limits of 1e16, 1e30 and inf': dict(
        limit='<limit effort="1e30" velocity="inf" lower="-1e16" upper="1e16"/>'),
}


@pytest.mark.parametrize('case', list(NOISE))
def test_rounding_noise_and_huge_limits_are_silent(case):
    model = load_silently(arm(**NOISE[case]))
    assert model.warnings == ()
    assert load_silently(arm(**NOISE[case]), strict=True).warnings == ()


def test_huge_limits_load_as_written_and_clamp_only_where_finite():
    model = load_silently(arm(limit='<limit effort="1e30" velocity="inf" lower="-1e16" '
                              'upper="1e16"/>'))
    assert model.lower.tolist() == [-1e16, -1e16] and model.upper.tolist() == [1e16, 1e16]
    assert model.effort_limit.tolist() == [1e30, 1e30]
    assert np.isinf(model.velocity_limit).all()
    tau = np.array([1e20, -1e25])
    clamped, saturated = sd.clamp_to_effort_limits(model, tau)
    assert clamped.tolist() == tau.tolist() and not saturated.any()


def test_nan_limit_is_refused_naming_it():
    with pytest.raises(ValueError, match=r"joint 'shoulder' <limit effort>.*non-finite"):
        sd.Model.from_urdf(arm(limit='<limit effort="nan" velocity="2"/>'))


# -- loaded with a warning: physically inconsistent, computable -----------------------------

WARNED = {
    # (arm keyword arguments, regex of the one warning: element, quantity and values)
    'not positive semi-definite': (
        dict(upper_inertia='ixx="0.02" ixy="0.05" ixz="0" iyy="0.02" iyz="0" izz="0.01"'),
        r"^link 'upper' <inertial>: inertia is not positive semi-definite \(principal moments "
        r'\[-0\.03, 0\.01, 0\.07\] kg m\^2\)$'),
    'triangle inequality (the xArm6 link2)': (
        dict(fore_inertia='ixx="0.00306" ixy="0" ixz="0" iyy="0.02364" iyz="0" izz="0.0269"'),
        r"^link 'fore' <inertial>: inertia breaks the triangle inequality \(principal moments "
        r'\[0\.00306, 0\.02364, 0\.0269\] kg m\^2: 0\.00306 \+ 0\.02364 < 0\.0269\)$'),
    'inertia without mass': (
        dict(fore='0'),
        r"^link 'fore' <inertial>: inertia on a massless link \(principal moments "
        r'\[0\.01, 0\.02, 0\.02\] kg m\^2, mass 0\)$'),
    'negative damping': (
        dict(dynamics='<dynamics damping="-0.5" friction="0.1"/>'),
        r"^joint 'shoulder' <dynamics damping>: negative \(-0\.5\)"),
    'negative friction': (
        dict(dynamics='<dynamics damping="0.5" friction="-0.1"/>'),
        r"^joint 'shoulder' <dynamics friction>: negative \(-0\.1\)"),
    'no robot name': (dict(name=''), r'^the <robot> element has no name attribute'),
}


@pytest.mark.parametrize('case', list(WARNED))
def test_inconsistent_loads_with_a_warning_naming_element_quantity_and_values(case):
    kwargs, message = WARNED[case]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter('always')
        model = sd.Model.from_urdf(arm(**kwargs))
    urdf_warnings = [str(w.message) for w in caught if w.category is sd.URDFWarning]
    assert len(urdf_warnings) == 1, urdf_warnings
    assert issubclass(sd.URDFWarning, UserWarning)
    assert model.warnings == tuple(urdf_warnings)
    assert re.search(message, model.warnings[0]), model.warnings[0]


@pytest.mark.parametrize('case', list(WARNED))
def test_strict_mode_refuses_with_the_same_message(case):
    kwargs, message = WARNED[case]
    with pytest.raises(ValueError, match=message.rstrip('$')):
        sd.Model.from_urdf(arm(**kwargs), strict=True)


@pytest.mark.parametrize('case', [c for c in WARNED if 'inertia' in c or 'triangle' in c
                                  or 'definite' in c])
def test_inconsistent_inertia_is_used_exactly_as_written(case, rng):
    """Pinocchio builds the same file as written: the torques agree to rounding."""
    urdf = arm(**WARNED[case][0])
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', sd.URDFWarning)
        model = sd.Model.from_urdf(urdf)
    oracle = PinOracle(urdf)
    q, qd, qdd = random_state(rng, (5,), model.nq)
    for backend in ('numpy', 'compiled'):
        tau = sd.rnea(model, q, qd, qdd, backend=backend)
        np.testing.assert_allclose(tau, oracle.rnea(model.joint_names, q, qd, qdd),
                                   rtol=1e-12, atol=1e-12)


def test_warnings_stay_with_derived_models():
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', sd.URDFWarning)
        model = sd.Model.from_urdf(arm(fore='0'))
        reduced = sd.Model.from_urdf(arm(fore='0'), joints=['elbow'])
    assert len(model.warnings) == 1
    assert reduced.warnings == model.warnings
    assert sd.with_payload(model, 'fore', 1.0).warnings == model.warnings


def test_a_bad_payload_is_still_an_error():
    """A payload is a parameter, validated at the edge: inconsistent inertia is refused."""
    model = load_silently(arm())
    with pytest.raises(ValueError, match="payload on 'fore'.*triangle inequality"):
        sd.with_payload(model, 'fore', 1.0, inertia=(1, 0, 0, 1, 0, 3))


# -- joint order: depth-first from the root, children by joint name ---------------------------

def documented_order(path):
    """Joint order as the README states it, computed from the XML alone.

    Depth-first from the root link; the joints below a link in byte order of their names;
    movable (revolute, continuous, prismatic) joints without <mimic>.
    """
    root = ET.parse(path).getroot()
    below, children = {}, set()
    for joint in root.findall('joint'):   # not the <joint> of a <transmission>
        below.setdefault(joint.find('parent').get('link'), []).append(joint)
        children.add(joint.find('child').get('link'))
    (base,) = [link.get('name') for link in root.findall('link')
               if link.get('name') not in children]
    order, stack = [], sorted(below.get(base, []), key=lambda j: j.get('name').encode(),
                              reverse=True)
    while stack:
        joint = stack.pop()
        if joint.get('type') in ('revolute', 'continuous', 'prismatic') and \
                joint.find('mimic') is None:
            order.append(joint.get('name'))
        stack += sorted(below.get(joint.find('child').get('link'), []),
                        key=lambda j: j.get('name').encode(), reverse=True)
    return order


@pytest.mark.parametrize('robot', ['talos', 'panda', 'solo12'])
def test_joint_order_is_the_documented_one(robot):
    path = robot_urdf_path(robot)
    model = load_silently(path)
    assert list(model.joint_names) == documented_order(path)
    if robot == 'talos':  # Pinocchio's order: the legs first, not the torso
        assert model.joint_names[0] == 'leg_left_1_joint'


@pytest.mark.parametrize('name', ['tiago_description/robots/tiago_dual.urdf',
                                  'romeo_description/urdf/romeo.urdf'])
def test_joint_order_is_the_documented_one_on_more_trees(name):
    base = example_robot_data_dir()
    if base is None:
        pytest.skip('example-robot-data is not installed')
    path = os.path.join(base, name)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', sd.URDFWarning)
        model = sd.Model.from_urdf(path)
    assert list(model.joint_names) == documented_order(path)


def test_a_free_flyer_on_the_world_link_is_said_naming_the_fixed_joint():
    # ur5_robot.urdf fixes base_link to 'world': floating, the world link would fly
    path = robot_urdf_path('ur5')
    with pytest.warns(sd.URDFWarning, match=r"the free-flyer is attached to 'world' through "
                      r"fixed joint 'world_joint'; did you mean a fixed base\?"):
        model = sd.Model.from_urdf(path, base='floating')
    assert model.body_names[1] == 'world'
    with pytest.raises(ValueError, match="fixed joint 'world_joint'"):
        sd.Model.from_urdf(path, base='floating', strict=True)
    fixed = load_silently(path)      # the base it meant: no word
    assert fixed.body_names[0] == 'world' and not fixed.floating
    solo = load_silently(robot_urdf_path('solo12'), base='floating')    # one that does fly
    assert solo.floating
