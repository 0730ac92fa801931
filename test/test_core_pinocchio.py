# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Inverse dynamics against Pinocchio (the oracle), max abs difference <= 1e-10 Nm.

Real robots from example-robot-data, fixed base: the Panda with its hand (mimic finger,
sibling fixed links), the UR5, Talos (full tree with mimic grippers, and reduced) and Solo12;
then seeded random trees. Mimic joints are modelled in Pinocchio as independent joints driven
by q = multiplier * q_src + offset, their torque folded onto the source (see conftest.py).
"""

import functools

from conftest import PinOracle, random_state, robot_urdf_path
import numpy as np
import pytest
import spatial_dynamics as sd
from urdf_gen import random_tree_urdf

pin = pytest.importorskip('pinocchio')

TOL = 1e-10  # Nm (N for prismatic joints); do not loosen
ROBOTS = ['panda', 'ur5', 'talos', 'talos_reduced', 'solo12']
GRAVITIES = {'g': (0.0, 0.0, -9.81), 'no_g': (0.0, 0.0, 0.0), 'g_oblique': (1.3, -2.1, -9.5)}


@functools.lru_cache(maxsize=None)
def robot(name):
    """Return (Model, PinOracle) of an example-robot-data robot, built once per session."""
    path = robot_urdf_path(name)
    return sd.Model.from_urdf(path), PinOracle(path)


@functools.lru_cache(maxsize=None)
def random_robot(seed, n_links, branching, mimic):
    """Return (URDF XML, Model, PinOracle) of a seeded random tree."""
    rng = np.random.default_rng(1000 + seed)
    xml = random_tree_urdf(rng, n_links, branching=branching, mimic=mimic)
    return xml, sd.Model.from_urdf(xml), PinOracle(xml)


def max_diff(a, b):
    return float(np.abs(np.asarray(a) - np.asarray(b)).max())


@pytest.mark.parametrize('name', ROBOTS)
def test_joint_names_are_the_movable_non_mimic_joints(name):
    model, oracle = robot(name)
    assert len(set(model.joint_names)) == len(model.joint_names)
    assert set(model.joint_names) == set(oracle.movable)
    assert not set(model.joint_names) & set(oracle.mimic)


def test_panda_hand_structure():
    """The Panda's mimic finger is not a coordinate; the driving finger is; 7 + 1 joints."""
    model, oracle = robot('panda')
    assert len(model.joint_names) == 8
    assert 'panda_finger_joint1' in model.joint_names
    assert 'panda_finger_joint2' not in model.joint_names
    assert oracle.mimic == {'panda_finger_joint2': ('panda_finger_joint1', 1.0, 0.0)}


def test_talos_full_has_mimic_grippers():
    model, oracle = robot('talos')
    assert len(oracle.mimic) >= 2
    assert {mult for _, mult, _ in oracle.mimic.values()} >= {1.0, -1.0}
    assert len(model.joint_names) == len(oracle.joints) - len(oracle.mimic)


@pytest.mark.parametrize('gravity', list(GRAVITIES.values()), ids=list(GRAVITIES))
@pytest.mark.parametrize('name', ROBOTS)
def test_single_states(name, gravity, rng):
    model, oracle = robot(name)
    n = len(model.joint_names)
    worst = 0.0
    for _ in range(10):
        q, qd, qdd = random_state(rng, (), n)
        tau = sd.rnea(model, q, qd, qdd, gravity=gravity)
        assert tau.shape == (n,)
        worst = max(worst, max_diff(tau, oracle.rnea(model.joint_names, q, qd, qdd, gravity)))
    assert worst <= TOL


@pytest.mark.parametrize('name', ROBOTS)
def test_static_and_velocity_only_states(name, rng):
    """Gravity alone (qd = qdd = 0) and velocity product terms alone (gravity, qdd = 0)."""
    model, oracle = robot(name)
    n = len(model.joint_names)
    names = model.joint_names
    q, qd, _ = random_state(rng, (3,), n)
    z = np.zeros_like(q)
    g = GRAVITIES['g']
    assert max_diff(sd.rnea(model, q, z, z, gravity=g), oracle.rnea(names, q, z, z, g)) <= TOL
    no_g = GRAVITIES['no_g']
    assert max_diff(sd.rnea(model, q, qd, z, gravity=no_g),
                    oracle.rnea(names, q, qd, z, no_g)) <= TOL


@pytest.mark.parametrize('shape', [(5,), (2, 3)], ids=['5', '2x3'])
@pytest.mark.parametrize('name', ROBOTS)
def test_batched_states(name, shape, rng):
    model, oracle = robot(name)
    n = len(model.joint_names)
    q, qd, qdd = random_state(rng, shape, n)
    tau = sd.rnea(model, q, qd, qdd, gravity=GRAVITIES['g'])
    assert tau.shape == shape + (n,)
    assert max_diff(tau, oracle.rnea(model.joint_names, q, qd, qdd, GRAVITIES['g'])) <= TOL


@pytest.mark.parametrize('name', ROBOTS)
def test_default_gravity_is_minus_z(name, rng):
    model, oracle = robot(name)
    q, qd, qdd = random_state(rng, (2,), len(model.joint_names))
    assert max_diff(sd.rnea(model, q, qd, qdd),
                    oracle.rnea(model.joint_names, q, qd, qdd, (0.0, 0.0, -9.81))) <= TOL


def pick_links(rng, model, oracle, k):
    """Return k link names with bodies (frames of the URDF's <link> elements), root included."""
    import xml.etree.ElementTree as ET
    links = [e.get('name') for e in ET.fromstring(oracle.xml.encode()).iter('link')]
    return [links[i] for i in rng.choice(len(links), size=min(k, len(links)), replace=False)]


@pytest.mark.parametrize('name', ROBOTS)
def test_external_wrenches(name, rng):
    model, oracle = robot(name)
    n = len(model.joint_names)
    for _ in range(3):
        links = pick_links(rng, model, oracle, 6)
        f_ext = {link: rng.normal(0.0, 10.0, 6) for link in links}
        q, qd, qdd = random_state(rng, (), n)
        tau = sd.rnea(model, q, qd, qdd, gravity=GRAVITIES['g'], f_ext=f_ext)
        expected = oracle.rnea(model.joint_names, q, qd, qdd, GRAVITIES['g'], f_ext)
        assert max_diff(tau, expected) <= TOL, links
        # batched states with the same wrenches
        Q, QD, QDD = random_state(rng, (4,), n)
        tau = sd.rnea(model, Q, QD, QDD, gravity=GRAVITIES['g'], f_ext=f_ext)
        assert max_diff(tau, oracle.rnea(model.joint_names, Q, QD, QDD, GRAVITIES['g'],
                                         f_ext)) <= TOL


def test_panda_wrench_on_lumped_hand_links(rng):
    """Wrenches on fixed-lumped links: tcp frame, link8, hand; and on the mimic finger."""
    model, oracle = robot('panda')
    n = len(model.joint_names)
    for link in ['panda_hand_tcp', 'panda_link8', 'panda_hand', 'panda_rightfinger',
                 'panda_leftfinger']:
        f_ext = {link: rng.normal(0.0, 10.0, 6)}
        q, qd, qdd = random_state(rng, (), n)
        tau = sd.rnea(model, q, qd, qdd, f_ext=f_ext)
        assert max_diff(tau, oracle.rnea(model.joint_names, q, qd, qdd, f_ext=f_ext)) <= TOL
        assert max_diff(tau, sd.rnea(model, q, qd, qdd)) > 1e-3, link  # the wrench acted


def test_panda_mimic_finger_torque_is_folded(rng):
    """tau_finger1 includes tau_finger2 (multiplier 1): differs from the stripped-mimic model."""
    model, oracle = robot('panda')
    names = model.joint_names
    q, qd, qdd = random_state(rng, (), len(names))
    tau = sd.rnea(model, q, qd, qdd)
    q_pin, v_pin, a_pin = oracle.expand(names, q, qd, qdd)
    oracle.set_gravity((0.0, 0.0, -9.81))
    tau_pin = pin.rnea(oracle.model, oracle.data, q_pin, v_pin, a_pin)
    i1 = oracle.joints['panda_finger_joint1'][1]
    i2 = oracle.joints['panda_finger_joint2'][1]
    k = names.index('panda_finger_joint1')
    assert abs(tau[k] - (tau_pin[i1] + tau_pin[i2])) <= TOL
    assert abs(tau_pin[i2]) > 1e-3


RANDOM = [(s, n, b, m) for s, (n, b, m) in enumerate(
    [(2, False, False), (3, True, False), (6, True, True), (8, False, True), (10, True, False),
     (12, True, True), (15, False, False), (18, True, True), (22, True, True),
     (25, False, True)])]


@pytest.mark.parametrize('seed,n_links,branching,mimic', RANDOM)
def test_random_trees(seed, n_links, branching, mimic):
    xml, model, oracle = random_robot(seed, n_links, branching, mimic)
    rng = np.random.default_rng(seed)
    n = len(model.joint_names)
    assert set(model.joint_names) == set(oracle.movable)
    for gravity in GRAVITIES.values():
        q, qd, qdd = random_state(rng, (6,), n)
        tau = sd.rnea(model, q, qd, qdd, gravity=gravity)
        assert max_diff(tau, oracle.rnea(model.joint_names, q, qd, qdd, gravity)) <= TOL
        tau1 = sd.rnea(model, q[0], qd[0], qdd[0], gravity=gravity)
        assert max_diff(tau1, oracle.rnea(model.joint_names, q[0], qd[0], qdd[0],
                                          gravity)) <= TOL


@pytest.mark.parametrize('seed,n_links,branching,mimic', RANDOM)
def test_random_trees_external_wrenches(seed, n_links, branching, mimic):
    xml, model, oracle = random_robot(seed, n_links, branching, mimic)
    rng = np.random.default_rng(100 + seed)
    n = len(model.joint_names)
    links = [f'link_{i}' for i in rng.choice(n_links, size=min(4, n_links), replace=False)]
    f_ext = {link: rng.normal(0.0, 10.0, 6) for link in links}
    q, qd, qdd = random_state(rng, (3,), n)
    tau = sd.rnea(model, q, qd, qdd, f_ext=f_ext)
    assert max_diff(tau, oracle.rnea(model.joint_names, q, qd, qdd, f_ext=f_ext)) <= TOL


def test_random_tree_continuous_joints_wrap():
    """A continuous joint at q and q + 2 pi gives the same torque (Pinocchio uses cos, sin)."""
    rng = np.random.default_rng(5)
    xml = random_tree_urdf(rng, 8, joint_kinds=('continuous',))
    model, oracle = sd.Model.from_urdf(xml), PinOracle(xml)
    n = len(model.joint_names)
    q, qd, qdd = random_state(rng, (), n)
    tau = sd.rnea(model, q, qd, qdd)
    assert max_diff(tau, oracle.rnea(model.joint_names, q, qd, qdd)) <= TOL
    assert max_diff(sd.rnea(model, q + 2 * np.pi, qd, qdd), tau) <= 1e-9


@pytest.mark.parametrize('name', ['panda', 'talos'])
def test_repeated_and_mutated_states(name, rng):
    """Same q with new qd, qdd, gravity; then q changed in place: always the oracle's answer."""
    model, oracle = robot(name)
    names = model.joint_names
    n = len(names)
    q = random_state(rng, (), n)[0]
    for gravity in GRAVITIES.values():
        for _ in range(3):
            _, qd, qdd = random_state(rng, (), n)
            tau = sd.rnea(model, q, qd, qdd, gravity=gravity)
            assert max_diff(tau, oracle.rnea(names, q, qd, qdd, gravity)) <= TOL
        q[::2] += 0.3  # in place: the same array object now holds another state
        tau = sd.rnea(model, q, qd, qdd, gravity=gravity)
        assert max_diff(tau, oracle.rnea(names, q, qd, qdd, gravity)) <= TOL


@pytest.mark.parametrize('name', ['panda', 'ur5'])
def test_lists_and_integer_arrays_are_accepted(name, rng):
    model, oracle = robot(name)
    n = len(model.joint_names)
    q = rng.integers(-2, 3, n)
    qd, qdd = np.ones(n, dtype=int), np.arange(n)
    expected = oracle.rnea(model.joint_names, q, qd, qdd)
    assert max_diff(sd.rnea(model, q, qd, qdd), expected) <= TOL
    assert max_diff(sd.rnea(model, list(q), list(qd), list(qdd)), expected) <= TOL
    assert max_diff(sd.rnea(model, q.astype(float).tolist(), qd.astype(float), qdd.astype(float)),
                    expected) <= TOL
