# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Feed-forward terms of issue 6 (library part), each against a hand computation or an oracle.

- payload: ``with_payload`` equals the URDF with the payload merged into the link by hand (a
  fixed child link at the com, or one combined ``<inertial>``), equals Pinocchio with the
  payload appended to the joint's body, and equals the closed-form loaded pendulum; bad
  payloads raise ``ValueError`` naming the problem; the original model never changes.
- armature: ``rnea + armature * qdd`` equals Pinocchio's rnea with ``model.armature`` set;
  ``per_joint`` expands scalar / list / {name: value} and rejects bad input.
- friction: ``damping * qd + friction * tanh(qd / threshold)`` from the URDF ``<dynamics>``,
  continuous at qd = 0, +-friction far from it, zero without ``<dynamics>``.
- f_ext: against Pinocchio's rnea(..., fext) (linear-first, joint frame), against
  ``-J^T w`` with Pinocchio's LOCAL frame Jacobian, batched, and the pendulum by hand.
- clamp: exactly to +-``<limit effort>``, saturated mask, joints without a limit untouched.
- none of these change the default ``rnea``.

The rnea-based checks run on both backends (numpy, and the compiled extension).
"""

import dataclasses
import functools
import math
import os
import xml.etree.ElementTree as ET

from conftest import PinOracle, random_state, read_text, robot_urdf_path
import numpy as np
import pytest
import spatial_dynamics as sd
from spatial_dynamics.backends import compiled, layout
from urdf_gen import inertial_xml, origin_xml, rpy_to_matrix

TOL = 1e-10  # N m (N for prismatic joints); do not loosen
G = 9.81
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CONFIG = os.path.join(ROOT, 'config')

# A payload with products of inertia (principal moments 0.012, 0.009, 0.006 about rotated axes).
PAYLOAD_MASS = 2.3
PAYLOAD_COM = (0.03, -0.02, 0.07)
_R = rpy_to_matrix((0.3, -0.5, 1.1))
PAYLOAD_IC = _R @ np.diag([0.012, 0.009, 0.006]) @ _R.T
PAYLOAD_INERTIA = tuple(float(PAYLOAD_IC[i, j]) for i, j in
                        ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)))


def pinocchio():
    return pytest.importorskip('pinocchio')


BACKENDS = ['numpy', 'compiled']


def rnea_on(backend):
    """Return sd.rnea bound to ``backend`` ('compiled' fails when built without it)."""
    if backend == 'compiled':
        assert compiled.ext is not None, compiled.FAILURE
    return functools.partial(sd.rnea, backend=backend)


def urdf_path(name):
    """Return a robot's URDF path: demo_arm, pendulum from config/, others from ERD."""
    if name in ('demo_arm', 'pendulum'):
        path = os.path.join(CONFIG, f'{name}.urdf')
        if not os.path.isfile(path):
            pytest.skip(f'{path} not found')
        return path
    return robot_urdf_path(name)


@functools.lru_cache(maxsize=None)
def model_of(name):
    return sd.Model.from_urdf(urdf_path(name))


def max_diff(a, b):
    return float(np.abs(np.asarray(a) - np.asarray(b)).max())


def inertia3(six):
    ixx, ixy, ixz, iyy, iyz, izz = six
    return np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]], dtype=float)


def _vec(text, default='0 0 0'):
    return np.array([float(s) for s in (text or default).split()])


def payload_merged_xml(xml, link, mass, com, inertia, how):
    """Return the URDF text with a payload merged into ``link`` by hand.

    how='child': a new link carrying the payload inertial, fixed to ``link`` at the com.
    how='merge': the link's own <inertial> replaced by the combined rigid body (mass, com and
    rotational inertia about the combined com by the parallel-axis theorem, link axes).
    """
    root = ET.fromstring(read_text(xml).encode())
    el = next(e for e in root.iter('link') if e.get('name') == link)
    Ip = inertia3(inertia)
    if how == 'child':
        name = f'{link}__test_payload'
        child = ET.SubElement(root, 'link', {'name': name})
        child.append(ET.fromstring(inertial_xml(mass, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), Ip)))
        joint = ET.SubElement(root, 'joint', {'name': f'{name}_joint', 'type': 'fixed'})
        ET.SubElement(joint, 'parent', {'link': link})
        ET.SubElement(joint, 'child', {'link': name})
        joint.append(ET.fromstring(origin_xml(com, (0.0, 0.0, 0.0))))
        return ET.tostring(root, encoding='unicode')
    bodies = [(float(mass), np.asarray(com, dtype=float), Ip)]
    old = el.find('inertial')
    if old is not None:
        origin = old.find('origin')
        c0 = _vec(None if origin is None else origin.get('xyz'))
        R0 = rpy_to_matrix(_vec(None if origin is None else origin.get('rpy')))
        m0 = float(old.find('mass').get('value'))
        i0 = old.find('inertia')
        keys = ('ixx', 'ixy', 'ixz', 'iyy', 'iyz', 'izz')
        I0 = inertia3([float(i0.get(k, 0.0)) for k in keys])
        bodies.append((m0, c0, R0 @ I0 @ R0.T))
        el.remove(old)
    m = sum(b[0] for b in bodies)
    c = sum(b[0] * b[1] for b in bodies) / m
    Ic = np.zeros((3, 3))
    for mk, ck, Ik in bodies:
        d = ck - c
        Ic += Ik + mk * (d @ d * np.eye(3) - np.outer(d, d))
    el.append(ET.fromstring(inertial_xml(m, c, (0.0, 0.0, 0.0), Ic)))
    return ET.tostring(root, encoding='unicode')


def joint_elements(xml, names):
    root = ET.fromstring(read_text(xml).encode())
    by_name = {j.get('name'): j for j in root.iter('joint')}
    return [by_name[n] for n in names]


# --------------------------------------------------------------------------------------------
# Payload

PAYLOAD_CASES = [
    ('demo_arm', 'hand'),          # massive link lumped through two fixed joints
    ('demo_arm', 'tcp'),           # massless lumped frame, no <inertial>
    ('demo_arm', 'link4'),         # the moving body itself (products of inertia, tilted axis)
    ('demo_arm', 'right_finger'),  # body driven by a <mimic> joint
    ('panda', 'panda_hand'),       # lumped into panda_link7 via link8, rotated -pi/4
    ('panda', 'panda_hand_tcp'),   # massless lumped frame
    ('panda', 'panda_link5'),
    ('ur5', 'tool0'),              # massless lumped frame, rotated
]


@pytest.mark.parametrize('backend', BACKENDS)
@pytest.mark.parametrize('how', ['child', 'merge'])
@pytest.mark.parametrize('robot,link', PAYLOAD_CASES, ids=[c[1] for c in PAYLOAD_CASES])
def test_payload_equals_urdf_with_payload_merged(robot, link, how, backend, rng):
    rnea = rnea_on(backend)
    model = model_of(robot)
    loaded = sd.with_payload(model, link, PAYLOAD_MASS, PAYLOAD_COM, PAYLOAD_INERTIA)
    merged = sd.Model.from_urdf(payload_merged_xml(urdf_path(robot), link, PAYLOAD_MASS,
                                                   PAYLOAD_COM, PAYLOAD_INERTIA, how))
    assert merged.joint_names == loaded.joint_names
    n = model.nq
    for gravity in ((0.0, 0.0, -G), (1.3, -2.1, -9.5)):
        for _ in range(4):
            q, qd, qdd = random_state(rng, (), n)
            tau = rnea(loaded, q, qd, qdd, gravity=gravity)
            assert max_diff(tau, rnea(merged, q, qd, qdd, gravity=gravity)) <= TOL
            # the payload acts (2.3 kg on an arm): the test can tell loaded from unloaded
            assert max_diff(tau, rnea(model, q, qd, qdd, gravity=gravity)) > 1e-2
        Q, QD, QDD = random_state(rng, (2, 3), n)
        assert max_diff(rnea(loaded, Q, QD, QDD, gravity=gravity),
                        rnea(merged, Q, QD, QDD, gravity=gravity)) <= TOL


def test_payload_on_the_fixed_base_changes_nothing(rng):
    model = model_of('demo_arm')
    loaded = sd.with_payload(model, 'base_link', 50.0, (0.1, 0.2, 0.3), PAYLOAD_INERTIA)
    q, qd, qdd = random_state(rng, (5,), model.nq)
    np.testing.assert_array_equal(sd.rnea(loaded, q, qd, qdd), sd.rnea(model, q, qd, qdd))


def test_two_payloads_equal_urdf_with_both_merged(rng):
    model = model_of('panda')
    both = sd.with_payload(sd.with_payload(model, 'panda_hand_tcp', 1.1, (0.0, 0.01, 0.02)),
                           'panda_link3', 0.7, (0.05, 0.0, -0.1), PAYLOAD_INERTIA)
    xml = payload_merged_xml(urdf_path('panda'), 'panda_hand_tcp', 1.1, (0.0, 0.01, 0.02),
                             (0.0,) * 6, 'child')
    xml = payload_merged_xml(xml, 'panda_link3', 0.7, (0.05, 0.0, -0.1), PAYLOAD_INERTIA,
                             'merge')
    merged = sd.Model.from_urdf(xml)
    q, qd, qdd = random_state(rng, (6,), model.nq)
    assert max_diff(sd.rnea(both, q, qd, qdd), sd.rnea(merged, q, qd, qdd)) <= TOL


def test_zero_payload_is_the_identity(rng):
    model = model_of('panda')
    same = sd.with_payload(model, 'panda_hand', 0.0)
    np.testing.assert_array_equal(same.inertia, model.inertia)
    q, qd, qdd = random_state(rng, (), model.nq)
    np.testing.assert_array_equal(sd.rnea(same, q, qd, qdd), sd.rnea(model, q, qd, qdd))


def test_point_payload_on_pendulum_by_hand(rng):
    """A point mass mp at the bob (L = 1 m below the pivot): closed form of the loaded pendulum.

    tau = (m L^2 + I_c + mp L^2) qdd + (m + mp) g L sin(q), with m = 1 kg, I_c = 0.001 kg m^2.
    """
    model = model_of('pendulum')
    mp, L = 0.75, 1.0
    loaded = sd.with_payload(model, 'bob', mp, (0.0, 0.0, -L))
    q, qd, qdd = random_state(rng, (20,), 1)
    expected = (1.0 * L ** 2 + 0.001 + mp * L ** 2) * qdd + (1.0 + mp) * G * L * np.sin(q)
    assert max_diff(sd.rnea(loaded, q, qd, qdd), expected) <= TOL
    # with its own inertia about its com (iyy counts about the hinge axis y)
    loaded = sd.with_payload(model, 'bob', mp, (0.0, 0.0, -L), (0.02, 0.0, 0.0, 0.03, 0.0, 0.04))
    expected = (1.0 + 0.001 + mp + 0.03) * qdd + (1.0 + mp) * G * np.sin(q)
    assert max_diff(sd.rnea(loaded, q, qd, qdd), expected) <= TOL


@pytest.mark.parametrize('backend', BACKENDS)
@pytest.mark.parametrize('robot,link', PAYLOAD_CASES, ids=[c[1] for c in PAYLOAD_CASES])
def test_payload_against_pinocchio_append_body(robot, link, backend, rng):
    """Pinocchio: the payload's pin.Inertia appended to the joint of the link's frame."""
    pin = pinocchio()
    rnea = rnea_on(backend)
    model = model_of(robot)
    loaded = sd.with_payload(model, link, PAYLOAD_MASS, PAYLOAD_COM, PAYLOAD_INERTIA)
    oracle = PinOracle(urdf_path(robot))
    pm = oracle.model
    frame = pm.frames[pm.getFrameId(link, pin.FrameType.BODY)]
    assert frame.name == link
    pm.appendBodyToJoint(frame.parentJoint,
                         pin.Inertia(PAYLOAD_MASS, np.array(PAYLOAD_COM),
                                     inertia3(PAYLOAD_INERTIA)),
                         frame.placement)
    oracle.data = pm.createData()
    for shape in ((), (6,)):
        q, qd, qdd = random_state(rng, shape, model.nq)
        tau = rnea(loaded, q, qd, qdd)
        assert max_diff(tau, oracle.rnea(model.joint_names, q, qd, qdd)) <= TOL
        assert max_diff(tau, rnea(model, q, qd, qdd)) > 1e-2


BAD_PAYLOADS = [
    (dict(link='no_such_link', mass=1.0), r"'no_such_link'"),
    (dict(link='hand', mass=-0.5), r"payload on 'hand': negative mass"),
    (dict(link='hand', mass=math.nan), r"payload on 'hand' mass: non-finite"),
    (dict(link='hand', mass=math.inf), r"payload on 'hand' mass: non-finite"),
    (dict(link='hand', mass=1.0, com=(0.0, math.nan, 0.0)),
     r"payload on 'hand' centre of mass: non-finite"),
    (dict(link='hand', mass=1.0, com=(0.0, 0.1)), r'centre of mass must be 3 numbers'),
    (dict(link='hand', mass=1.0, inertia=(0.01, 0.0, 0.0, math.nan, 0.0, 0.01)),
     r'payload inertia: non-finite'),
    # a negative principal moment
    (dict(link='hand', mass=1.0, inertia=(-0.01, 0.0, 0.0, 0.01, 0.0, 0.01)),
     r"payload on 'hand': inertia is not positive semi-definite"),
    # indefinite through a product of inertia: eigenvalues 0.01 +- 0.02
    (dict(link='hand', mass=1.0, inertia=(0.01, 0.02, 0.0, 0.01, 0.0, 0.01)),
     r"payload on 'hand': inertia is not positive semi-definite"),
    # positive definite but 0.001 + 0.001 < 0.01: no mass distribution has these moments
    (dict(link='hand', mass=1.0, inertia=(0.001, 0.0, 0.0, 0.001, 0.0, 0.01)),
     r"payload on 'hand': inertia breaks the triangle inequality"),
]


@pytest.mark.parametrize('kwargs,match', BAD_PAYLOADS,
                         ids=['unknown_link', 'negative_mass', 'nan_mass', 'inf_mass',
                              'nan_com', 'short_com', 'nan_inertia', 'negative_moment',
                              'indefinite', 'triangle'])
def test_bad_payload_raises_naming_the_problem(kwargs, match):
    model = model_of('demo_arm')
    before = np.array(model.inertia)
    with pytest.raises(ValueError, match=match):
        sd.with_payload(model, **kwargs)
    np.testing.assert_array_equal(model.inertia, before)


def test_short_payload_inertia_is_named():
    with pytest.raises(ValueError, match='inertia'):
        sd.with_payload(model_of('demo_arm'), 'hand', 1.0, (0.0, 0.0, 0.0),
                        (0.01, 0.0, 0.0, 0.01, 0.0))


@pytest.mark.parametrize('backend', BACKENDS)
def test_with_payload_leaves_the_model_unchanged(backend, rng):
    rnea = rnea_on(backend)
    model = model_of('panda')
    q, qd, qdd = random_state(rng, (), model.nq)
    Q, QD, QDD = random_state(rng, (4,), model.nq)
    tau0, tau0_batch = rnea(model, q, qd, qdd), rnea(model, Q, QD, QDD)
    inertia0, rows0 = np.array(model.inertia), layout.of(model).rows
    loaded = sd.with_payload(model, 'panda_hand', PAYLOAD_MASS, PAYLOAD_COM, PAYLOAD_INERTIA)
    assert isinstance(loaded, sd.Model) and loaded is not model
    # new arrays, read-only like the original's; the original's are untouched
    assert loaded.inertia is not model.inertia
    for m in (model, loaded):
        assert not m.inertia.flags.writeable
        with pytest.raises(ValueError):
            m.inertia[1, 0, 0] = 1.0
        with pytest.raises(dataclasses.FrozenInstanceError):
            m.inertia = np.zeros_like(m.inertia)
    np.testing.assert_array_equal(model.inertia, inertia0)
    assert layout.of(model).rows == rows0      # what the backends derived stays too
    # only the body of panda_hand (panda_link7's) changed; the rest is shared
    changed = [b for b in range(model.NB + 1)
               if not np.array_equal(loaded.inertia[b], model.inertia[b])]
    assert changed == [model.frames['panda_hand'].body]
    assert loaded.joint_names == model.joint_names
    np.testing.assert_array_equal(loaded.Xtree, model.Xtree)
    # same q through both models (each has its own derived layout): each keeps its answer
    tau1 = rnea(loaded, q, qd, qdd)
    assert max_diff(tau1, tau0) > 1e-2
    np.testing.assert_array_equal(rnea(model, q, qd, qdd), tau0)
    np.testing.assert_array_equal(rnea(model, Q, QD, QDD), tau0_batch)
    np.testing.assert_array_equal(rnea(loaded, q, qd, qdd), tau1)
    assert max_diff(rnea(loaded, Q, QD, QDD), tau0_batch) > 1e-2


# --------------------------------------------------------------------------------------------
# Armature (rotor inertia): tau += armature * qdd


def test_pinocchio_rnea_adds_armature_times_a(rng):
    """The oracle's premise (Pinocchio 3/4): rnea with model.armature adds armature * a."""
    pin = pinocchio()
    oracle = PinOracle(urdf_path('ur5'))
    pm = oracle.model
    q_pin = pin.randomConfiguration(pm)
    v, a = rng.normal(size=pm.nv), rng.normal(size=pm.nv)
    tau0 = pin.rnea(pm, oracle.data, q_pin, v, a).copy()
    pm.armature[:] = rng.uniform(0.1, 2.0, pm.nv)
    tau1 = pin.rnea(pm, oracle.data, q_pin, v, a).copy()
    assert max_diff(tau1 - tau0, pm.armature * a) <= 1e-12


@pytest.mark.parametrize('robot', ['panda', 'ur5'])
def test_armature_against_pinocchio(robot, rng):
    model = model_of(robot)
    names = model.joint_names
    values = {name: float(v) for name, v in zip(names, rng.uniform(0.05, 1.5, model.nq))}
    armature = sd.per_joint(model, 'armature', values)
    oracle = PinOracle(urdf_path(robot))
    for name, value in values.items():
        oracle.model.armature[oracle.joints[name][1]] = value  # mimic joints keep 0
    for shape in ((), (5,), (2, 3)):
        q, qd, qdd = random_state(rng, shape, model.nq)
        tau = sd.rnea(model, q, qd, qdd) + sd.armature_torque(armature, qdd)
        assert tau.shape == shape + (model.nq,)
        assert max_diff(tau, oracle.rnea(names, q, qd, qdd)) <= TOL
        assert max_diff(tau, sd.rnea(model, q, qd, qdd)) > 1e-2


def test_armature_on_pendulum_by_hand(rng):
    """The 1 kg, 1 m pendulum: tau = (1.001 + armature) qdd + g sin(q)."""
    model = model_of('pendulum')
    armature = sd.per_joint(model, 'armature', {'pivot': 0.4})
    q, qd, qdd = random_state(rng, (10,), 1)
    tau = sd.rnea(model, q, qd, qdd) + sd.armature_torque(armature, qdd)
    assert max_diff(tau, (1.001 + 0.4) * qdd + G * np.sin(q)) <= TOL


def test_per_joint_forms():
    model = model_of('demo_arm')
    n, names = model.nq, model.joint_names
    np.testing.assert_array_equal(sd.per_joint(model, 'armature', 0.25), np.full(n, 0.25))
    np.testing.assert_array_equal(sd.per_joint(model, 'armature', 2), np.full(n, 2.0))
    values = [0.1 * (k + 1) for k in range(n)]
    np.testing.assert_array_equal(sd.per_joint(model, 'armature', values), values)
    np.testing.assert_array_equal(sd.per_joint(model, 'armature', np.array(values)), values)
    out = sd.per_joint(model, 'armature', {'joint3': 0.7, 'finger_joint1': 0.05})
    expected = np.zeros(n)
    expected[names.index('joint3')] = 0.7
    expected[names.index('finger_joint1')] = 0.05
    np.testing.assert_array_equal(out, expected)
    out = sd.per_joint(model, 'armature', {'joint3': 0.7}, default=0.1)
    assert out[names.index('joint3')] == 0.7
    assert np.all(np.delete(out, names.index('joint3')) == 0.1)
    assert out.dtype == np.float64 and out.shape == (n,)


def test_per_joint_rejects_bad_values():
    model = model_of('demo_arm')
    n = model.nq
    for name in ('no_such_joint', 'world_joint'):
        with pytest.raises(ValueError, match=f"armature: unknown joint '{name}'"):
            sd.per_joint(model, 'armature', {'joint1': 0.1, name: 0.2})
    # a mimic joint is not a coordinate: said so, with the joint whose coordinate it is
    with pytest.raises(ValueError, match="armature: joint 'finger_joint2' is a mimic joint: it "
                                         "follows 'finger_joint1' .*give it to 'finger_joint1'"):
        sd.per_joint(model, 'armature', {'joint1': 0.1, 'finger_joint2': 0.2})
    for bad, got in (([0.1] * (n - 1), n - 1), ([0.1] * (n + 1), n + 1),
                     (np.ones((n, 1)), r'\(8, 1\)'), ([], 0)):
        with pytest.raises(ValueError, match=rf'armature: expected {n} values for .*'
                                             rf"'joint1'.*'finger_joint1'.*got {got}"):
            sd.per_joint(model, 'armature', bad)
    for bad in (math.nan, math.inf, [0.1] * (n - 1) + [math.nan], {'joint2': math.nan},
                {'joint2': -math.inf}):
        with pytest.raises(ValueError, match="armature: joint '.*' .* need a finite"):
            sd.per_joint(model, 'armature', bad)


def test_per_joint_nan_message_names_the_joint():
    with pytest.raises(ValueError, match='joint2'):
        sd.per_joint(model_of('demo_arm'), 'armature', {'joint2': math.nan})


# --------------------------------------------------------------------------------------------
# Friction and damping from the URDF <dynamics>


def urdf_dynamics(xml, names):
    """Return (damping, friction) per joint, read from the URDF text by hand (0 when absent)."""
    damping, friction = [], []
    for j in joint_elements(xml, names):
        dyn = j.find('dynamics')
        damping.append(0.0 if dyn is None else float(dyn.get('damping', 0.0)))
        friction.append(0.0 if dyn is None else float(dyn.get('friction', 0.0)))
    return np.array(damping), np.array(friction)


def urdf_mimics(xml, names):
    """Return [(source index, mimic joint name, multiplier)] read from the URDF text by hand."""
    root = ET.fromstring(read_text(xml).encode())
    out = []
    for j in root.iter('joint'):
        mimic = j.find('mimic')
        if mimic is not None:
            out.append((names.index(mimic.get('joint')), j.get('name'),
                        float(mimic.get('multiplier', 1.0))))
    return out


def friction_by_hand(xml, names, qd, threshold, coulomb=None):
    """Return τ_k = d_k q̇_k + f_k s(q̇_k) plus the folded mimic terms, by hand.

    Each mimic joint adds its own term at its rate mult·q̇_src, folded back with its
    multiplier; ``coulomb`` replaces tanh(q̇/threshold) (e.g. np.sign).
    """
    s = coulomb or (lambda v: np.tanh(v / threshold))
    damping, friction = urdf_dynamics(xml, names)
    tau = damping * qd + friction * s(qd)
    for k, name, mult in urdf_mimics(xml, names):
        (dm,), (fm,) = urdf_dynamics(xml, [name])
        rate = mult * qd[..., k]
        tau[..., k] += mult * (dm * rate + fm * s(rate))
    return tau


def test_friction_by_hand_from_urdf_dynamics(rng):
    model = model_of('demo_arm')
    damping, friction = urdf_dynamics(urdf_path('demo_arm'), model.joint_names)
    assert np.all(friction > 0) and np.all(damping > 0)   # the demo arm sets both everywhere
    # joint1: damping 0.5, friction 0.3: at qd = 0.2 rad/s, threshold 0.05 rad/s
    qd = np.zeros(model.nq)
    qd[0] = 0.2
    tau = sd.friction_torque(model, qd, 0.05)
    assert tau[0] == pytest.approx(0.5 * 0.2 + 0.3 * math.tanh(4.0), rel=1e-15, abs=0.0)
    assert np.all(tau[1:] == 0.0)
    # the mimic finger (finger_joint2 = finger_joint1, multiplier 1) adds its own <dynamics>
    (k, mimic, mult), = urdf_mimics(urdf_path('demo_arm'), model.joint_names)
    (dm,), (fm,) = urdf_dynamics(urdf_path('demo_arm'), [mimic])
    assert dm > 0 and fm > 0
    qd = np.zeros(model.nq)
    qd[k] = 0.1
    tau = sd.friction_torque(model, qd, 0.01)
    assert tau[k] == pytest.approx(damping[k] * 0.1 + friction[k] * math.tanh(10.0)
                                   + mult * (dm * mult * 0.1 + fm * math.tanh(mult * 10.0)),
                                   rel=1e-14)
    for threshold in (1e-3, 0.05, 0.7):
        for shape in ((), (7,), (2, 3)):
            qd = rng.uniform(-2.0, 2.0, shape + (model.nq,))
            tau = sd.friction_torque(model, qd, threshold)
            assert tau.shape == qd.shape
            np.testing.assert_allclose(
                tau, friction_by_hand(urdf_path('demo_arm'), model.joint_names, qd, threshold),
                rtol=1e-14, atol=1e-15)


def test_urdf_dynamics_match_pinocchio():
    """Pinocchio's parser reads the same <dynamics> (model.damping / model.friction)."""
    pinocchio()
    for robot in ('demo_arm', 'panda', 'ur5'):
        model = model_of(robot)
        oracle = PinOracle(urdf_path(robot))
        iv = [oracle.joints[name][1] for name in model.joint_names]
        np.testing.assert_array_equal(model.damping, oracle.model.damping[iv])
        np.testing.assert_array_equal(model.friction, oracle.model.friction[iv])


@pytest.mark.parametrize('threshold', [1e-4, 0.01, 0.5])
def test_friction_is_continuous_at_zero_velocity(threshold):
    model = model_of('demo_arm')
    damping, friction = model.damping, model.friction
    slope = damping + friction / threshold            # d tau / d qd at qd = 0, the steepest
    for k, name, mult in urdf_mimics(urdf_path('demo_arm'), model.joint_names):
        (dm,), (fm,) = urdf_dynamics(urdf_path('demo_arm'), [name])
        slope[k] += mult * mult * (dm + fm / threshold)   # the folded mimic joint's share
        friction = friction.copy()
        friction[k] += abs(mult) * fm
    n = model.nq
    assert np.all(sd.friction_torque(model, np.zeros(n), threshold) == 0.0)
    eps = 1e-9
    jump = sd.friction_torque(model, np.full(n, eps), threshold) \
        - sd.friction_torque(model, np.full(n, -eps), threshold)
    assert np.all(jump >= 0.0)
    assert np.all(jump <= 2 * eps * slope * (1 + 1e-6))
    assert np.all(jump < 1e-6 * (friction / threshold))
    # Lipschitz on a fine grid through zero: no step anywhere
    qd = np.linspace(-20 * threshold, 20 * threshold, 4001)[:, None] * np.ones(n)
    tau = sd.friction_torque(model, qd, threshold)
    assert np.all(np.diff(tau, axis=0) >= 0.0)  # monotonic in qd
    assert np.all(np.diff(tau, axis=0) <= slope * (qd[1] - qd[0]) * (1 + 1e-9))


def test_friction_saturates_to_coulomb_far_from_zero():
    model = model_of('demo_arm')
    threshold = 0.01
    for qd in (0.5, 3.0):  # 50 and 300 thresholds: tanh == 1 in float64
        for sign in (1.0, -1.0):
            v = np.full(model.nq, sign * qd)
            tau = sd.friction_torque(model, v, threshold)
            np.testing.assert_allclose(
                tau, friction_by_hand(urdf_path('demo_arm'), model.joint_names, v, threshold,
                                      coulomb=np.sign), rtol=0.0, atol=1e-15)
    # at qd = threshold the Coulomb part is tanh(1) ~ 76 % of the friction
    v = np.full(model.nq, threshold)
    tau = sd.friction_torque(model, v, threshold)
    np.testing.assert_allclose(
        tau, friction_by_hand(urdf_path('demo_arm'), model.joint_names, v, threshold,
                              coulomb=lambda x: math.tanh(1.0) * np.sign(x)), rtol=1e-15)


def test_friction_is_zero_without_dynamics(rng):
    stripped = read_text(urdf_path('demo_arm'))
    root = ET.fromstring(stripped.encode())
    for j in root.iter('joint'):
        for dyn in j.findall('dynamics'):
            j.remove(dyn)
    for model in (model_of('pendulum'), model_of('ur5'),  # none; all 0.0
                  sd.Model.from_urdf(ET.tostring(root, encoding='unicode'))):
        qd = rng.uniform(-3.0, 3.0, (5, model.nq))
        assert np.all(sd.friction_torque(model, qd, 0.01) == 0.0)
    # damping only (friction attribute removed): pure viscous term
    xml = stripped.replace(' friction="0.3"/>', '/>')
    model = sd.Model.from_urdf(xml)
    damping, friction = urdf_dynamics(xml, model.joint_names)
    assert friction[0] == 0.0 and damping[0] == 0.5
    qd = rng.uniform(-3.0, 3.0, model.nq)
    tau = sd.friction_torque(model, qd, 0.01)
    np.testing.assert_allclose(tau, friction_by_hand(xml, model.joint_names, qd, 0.01),
                               rtol=1e-14)
    assert tau[0] == 0.5 * qd[0]


@pytest.mark.parametrize('threshold', [0.0, -0.0, -0.01, math.nan, math.inf, -math.inf])
def test_bad_friction_threshold_raises(threshold):
    model = model_of('demo_arm')
    with pytest.raises(ValueError, match='friction velocity threshold must be > 0'):
        sd.friction_torque(model, np.zeros(model.nq), threshold)


# --------------------------------------------------------------------------------------------
# External wrenches


def pin_local_jacobian_torque(oracle, names, q, link, wrench):
    """-J^T [f; n]: Pinocchio's LOCAL frame Jacobian of ``link`` (linear-first) at one state."""
    pin = oracle.pin
    pm = oracle.model
    z = np.zeros(len(names))
    q_pin = oracle.expand(names, q, z, z)[0]
    J = pin.computeFrameJacobian(pm, oracle.data, q_pin, pm.getFrameId(link, pin.FrameType.BODY),
                                 pin.LOCAL)
    wrench = np.asarray(wrench, dtype=float)
    return oracle.fold(names, -J.T @ np.concatenate([wrench[3:], wrench[:3]]))


WRENCH_LINKS = [('panda_hand',), ('panda_link5',), ('panda_hand', 'panda_link5')]


@pytest.mark.parametrize('backend', BACKENDS)
@pytest.mark.parametrize('links', WRENCH_LINKS, ids=['+'.join(c) for c in WRENCH_LINKS])
def test_external_wrench_against_pinocchio(links, backend, rng):
    pin = pinocchio()
    rnea = rnea_on(backend)
    model = model_of('panda')
    names = model.joint_names
    oracle = PinOracle(urdf_path('panda'))
    for _ in range(5):
        f_ext = {link: rng.normal(0.0, 10.0, 6) for link in links}
        q, qd, qdd = random_state(rng, (), model.nq)
        tau = rnea(model, q, qd, qdd, f_ext=f_ext)
        # Pinocchio's rnea(..., fext): one pin.Force per joint, linear first, joint frame
        fext = pin.StdVec_Force()
        fext.extend(oracle.fext(f_ext))
        assert len(fext) == oracle.model.njoints
        oracle.set_gravity((0.0, 0.0, -G))
        tau_pin = pin.rnea(oracle.model, oracle.data, *oracle.expand(names, q, qd, qdd), fext)
        assert max_diff(tau, oracle.fold(names, tau_pin)) <= TOL
        # the wrench's share by the Jacobian transpose, no fext conversion involved
        share = sum(pin_local_jacobian_torque(oracle, names, q, link, w)
                    for link, w in f_ext.items())
        assert max_diff(tau - rnea(model, q, qd, qdd), share) <= TOL
        assert np.abs(share).max() > 1e-1
        # angular-first matters: swapping n and f is a different answer
        swapped = {link: np.concatenate([w[3:], w[:3]]) for link, w in f_ext.items()}
        assert max_diff(rnea(model, q, qd, qdd, f_ext=swapped), tau) > 1e-1


@pytest.mark.parametrize('backend', BACKENDS)
@pytest.mark.parametrize('link', ['panda_hand', 'panda_link5'])
def test_batched_external_wrenches_against_pinocchio(link, backend, rng):
    pinocchio()
    rnea = rnea_on(backend)
    model = model_of('panda')
    names = model.joint_names
    oracle = PinOracle(urdf_path('panda'))
    # one wrench per state: q (6, n) with f (6, 6)
    Q, QD, QDD = random_state(rng, (6,), model.nq)
    F = rng.normal(0.0, 10.0, (6, 6))
    tau = rnea(model, Q, QD, QDD, f_ext={link: F})
    assert tau.shape == Q.shape
    for k in range(6):
        expected = oracle.rnea(names, Q[k], QD[k], QDD[k], f_ext={link: F[k]})
        assert max_diff(tau[k], expected) <= TOL
        assert max_diff(tau[k], rnea(model, Q[k], QD[k], QDD[k], f_ext={link: F[k]})) <= TOL
    # broadcast: states (2, 3, n), wrenches (3, 6) shared along the first axis
    Q, QD, QDD = random_state(rng, (2, 3), model.nq)
    F = rng.normal(0.0, 10.0, (3, 6))
    tau = rnea(model, Q, QD, QDD, f_ext={link: F})
    assert tau.shape == Q.shape
    for i in range(2):
        for k in range(3):
            expected = oracle.rnea(names, Q[i, k], QD[i, k], QDD[i, k], f_ext={link: F[k]})
            assert max_diff(tau[i, k], expected) <= TOL
    # the batched components kernel and the 6x6 reference agree
    assert max_diff(tau, sd.rnea_spatial(model, Q, QD, QDD, f_ext={link: F})) <= TOL


def test_force_on_pendulum_by_hand():
    """config/pendulum.urdf: hinge about +y, bob 1 m below it (link frame at the pivot).

    A force F = (2, 0, 0) N on the bob at r = (0, 0, -1) m: r x F = (0, -2, 0). f_ext acts ON
    the link, so the hinge holds tau = g sin(q) - (r x F) . y = g sin(q) + 2 N m: the push is
    toward negative q and the joint must resist it.
    """
    model = model_of('pendulum')
    r, F = np.array([0.0, 0.0, -1.0]), np.array([2.0, 0.0, 0.0])
    wrench = np.concatenate([np.cross(r, F), F])
    assert np.array_equal(np.cross(r, F), [0.0, -2.0, 0.0])
    z = np.zeros(1)
    tau = sd.rnea(model, z, z, z, f_ext={'bob': wrench})
    assert abs(tau[0] - 2.0) <= TOL
    for q in (-2.0, -0.5, 0.3, 1.2, 3.0):
        tau = sd.rnea(model, [q], [0.0], [0.0], f_ext={'bob': wrench})
        assert abs(tau[0] - (G * math.sin(q) + 2.0)) <= TOL
    # the weight's own pull, applied as an external force in the link frame, doubles gravity
    q = 0.8
    down = 1.0 * G * np.array([math.sin(q), 0.0, -math.cos(q)])   # world -z in the bob frame
    tau = sd.rnea(model, [q], [0.0], [0.0], f_ext={'bob': np.concatenate([np.cross(r, down),
                                                                          down])})
    assert abs(tau[0] - 2 * G * math.sin(q)) <= TOL
    # a force through the hinge axis and a pure moment about x, y
    tau = sd.rnea(model, [q], [0.0], [0.0], f_ext={'bob': [0.0, 0.0, 0.0, 0.0, 5.0, 0.0]})
    assert abs(tau[0] - G * math.sin(q)) <= TOL
    tau = sd.rnea(model, [q], [0.0], [0.0], f_ext={'bob': [4.0, -3.0, 7.0, 0.0, 0.0, 0.0]})
    assert abs(tau[0] - (G * math.sin(q) + 3.0)) <= TOL


# --------------------------------------------------------------------------------------------
# Effort limits


def urdf_efforts(xml, names):
    out = []
    for j in joint_elements(xml, names):
        lim = j.find('limit')
        out.append(math.nan if lim is None or lim.get('effort') is None
                   else float(lim.get('effort')))
    return np.array(out)


@pytest.mark.parametrize('robot', ['demo_arm', 'panda'])
def test_clamp_to_urdf_effort_limits(robot, rng):
    model = model_of(robot)
    effort = urdf_efforts(urdf_path(robot), model.joint_names)
    assert np.all(effort > 0)
    n_over = n_inside = 0
    for shape in ((), (9,), (2, 4)):
        tau = rng.uniform(-3.0, 3.0, shape + (model.nq,)) * effort
        clamped, saturated = sd.clamp_to_effort_limits(model, tau)
        assert clamped.shape == saturated.shape == tau.shape and saturated.dtype == bool
        over = np.abs(tau) > effort
        np.testing.assert_array_equal(saturated, over)
        np.testing.assert_array_equal(clamped[over], (np.sign(tau) * effort
                                                      * np.ones_like(tau))[over])
        np.testing.assert_array_equal(clamped[~over], tau[~over])
        n_over, n_inside = n_over + over.sum(), n_inside + (~over).sum()
    assert n_over > 10 and n_inside > 10  # both cases were exercised
    # exactly at the limit: passed through, not saturated; just above: clamped
    for sign in (1.0, -1.0):
        clamped, saturated = sd.clamp_to_effort_limits(model, sign * effort)
        np.testing.assert_array_equal(clamped, sign * effort)
        assert not saturated.any()
        clamped, saturated = sd.clamp_to_effort_limits(model, sign * np.nextafter(effort, 1e9))
        np.testing.assert_array_equal(clamped, sign * effort)
        assert saturated.all()
    # the input is not modified
    tau = 5.0 * effort
    kept = tau.copy()
    sd.clamp_to_effort_limits(model, tau)
    np.testing.assert_array_equal(tau, kept)


def test_clamp_leaves_joints_without_positive_limit(rng):
    root = ET.fromstring(read_text(urdf_path('demo_arm')).encode())
    joints = {j.get('name'): j for j in root.iter('joint')}
    del joints['joint3'].find('limit').attrib['effort']            # no effort attribute
    joints['joint5'].find('limit').set('effort', '0')              # zero: no limit
    joints['joint7'].remove(joints['joint7'].find('limit'))       # continuous, no <limit>
    model = sd.Model.from_urdf(ET.tostring(root, encoding='unicode'))
    names = model.joint_names
    free = [names.index(j) for j in ('joint3', 'joint5', 'joint7')]
    assert np.isnan(model.effort_limit[free[0]]) and model.effort_limit[free[1]] == 0.0
    assert np.isnan(model.effort_limit[free[2]])
    tau = np.full(model.nq, 1e6) * rng.choice([-1.0, 1.0], model.nq)
    clamped, saturated = sd.clamp_to_effort_limits(model, tau)
    effort = urdf_efforts(urdf_path('demo_arm'), names)
    for k in range(model.nq):
        if k in free:
            assert clamped[k] == tau[k] and not saturated[k], names[k]
        else:
            assert clamped[k] == math.copysign(effort[k], tau[k]) and saturated[k], names[k]


# --------------------------------------------------------------------------------------------
# None of these change the default


@pytest.mark.parametrize('backend', BACKENDS)
@pytest.mark.parametrize('robot', ['demo_arm', 'panda'])
def test_terms_do_not_change_default_rnea(robot, backend, rng):
    rnea = rnea_on(backend)
    model = model_of(robot)
    n = model.nq
    q, qd, qdd = random_state(rng, (), n)
    Q, QD, QDD = random_state(rng, (3,), n)
    state = [a.copy() for a in (q, qd, qdd)]
    tau0, tau0_batch = rnea(model, q, qd, qdd), rnea(model, Q, QD, QDD)
    arrays = {k: np.array(getattr(model, k)) for k in
              ('inertia', 'damping', 'friction', 'effort_limit', 'Xtree')}
    link = 'hand' if robot == 'demo_arm' else 'panda_hand'
    f_ext = {link: rng.normal(size=6)}
    f_kept = {k: v.copy() for k, v in f_ext.items()}

    sd.with_payload(model, link, PAYLOAD_MASS, PAYLOAD_COM, PAYLOAD_INERTIA)
    armature = sd.per_joint(model, 'armature', 0.3)
    sd.armature_torque(armature, qdd)
    sd.friction_torque(model, qd, 0.01)
    sd.clamp_to_effort_limits(model, 1e3 * tau0)
    rnea(model, q, qd, qdd, f_ext=f_ext)
    rnea(model, Q, QD, QDD, f_ext=f_ext)

    np.testing.assert_array_equal(rnea(model, q, qd, qdd), tau0)
    np.testing.assert_array_equal(rnea(model, Q, QD, QDD), tau0_batch)
    for k, v in arrays.items():
        np.testing.assert_array_equal(getattr(model, k), v, err_msg=k)
    for a, b in zip((q, qd, qdd), state):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(f_ext[link], f_kept[link])
    # the extras' neutral values give the default exactly
    for empty in (None, {}):
        np.testing.assert_array_equal(rnea(model, q, qd, qdd, f_ext=empty), tau0)
    assert max_diff(rnea(model, q, qd, qdd, f_ext={link: np.zeros(6)}), tau0) <= 1e-12
    assert np.all(sd.armature_torque(sd.per_joint(model, 'armature', {}), qdd) == 0.0)
