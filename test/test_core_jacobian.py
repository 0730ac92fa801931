# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""sd.jacobian against Pinocchio's getFrameJacobian, forward kinematics and RNEA.

* Pinocchio (LOCAL and LOCAL_WORLD_ALIGNED, linear-first, continuous joints nq = 2, mimic
  joints independent and folded with the oracle's velocity map) on the UR5, the Panda with
  its mimic finger and lumped hand frames, and Talos (a tree with mimic grippers);
* J q̇ equals the link's velocity from a central difference of its pose, computed by a
  homogeneous-matrix forward kinematics written here from the URDF text (no Plücker algebra);
* τ = Jᵀ w equals what RNEA adds for the external wrench ``f_ext = {link: w}`` (link frame).
"""

import functools
import xml.etree.ElementTree as ET

from conftest import PinOracle, read_text, robot_urdf_path
import numpy as np
import pytest
import spatial_dynamics as sd
from urdf_gen import mimic_table

TOL = 1e-10


@functools.lru_cache(maxsize=None)
def robot(name):
    path = robot_urdf_path(name)
    return sd.Model.from_urdf(path), read_text(path)


def links_of(xml):
    return [e.get('name') for e in ET.fromstring(xml.encode()).iter('link')]


LINKS = {
    'ur5': ['tool0', 'wrist_3_link', 'ee_link', 'forearm_link', 'base_link'],
    'panda': ['panda_hand_tcp', 'panda_link8', 'panda_hand', 'panda_leftfinger',
              'panda_rightfinger', 'panda_link4'],
    'talos': None,  # every link
}


# --------------------------------------------------------------------------------------------
# Pinocchio

@pytest.mark.parametrize('name', ['ur5', 'panda', 'talos'])
def test_equals_pinocchio_frame_jacobian(name, rng):
    pin = pytest.importorskip('pinocchio')
    model, xml = robot(name)
    oracle = PinOracle(xml)
    links = LINKS[name] or links_of(xml)
    swap = [3, 4, 5, 0, 1, 2]                          # Pinocchio: [v; ω], ours: [ω; v]
    worst = 0.0
    for _ in range(3):
        q = rng.uniform(-2.0, 2.0, model.nq)
        q_pin, P = oracle.velocity_map(model.joint_names, q)   # v_pin = P q̇
        pin.computeJointJacobians(oracle.model, oracle.data, q_pin)
        pin.updateFramePlacements(oracle.model, oracle.data)
        for link in links:
            fid = oracle.model.getFrameId(link, pin.FrameType.BODY)
            for frame, ref in (('local', pin.ReferenceFrame.LOCAL),
                               ('world', pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)):
                expected = pin.getFrameJacobian(oracle.model, oracle.data, fid, ref)[swap] @ P
                J = sd.jacobian(model, q, link, frame)
                assert J.shape == (6, model.nq)
                worst = max(worst, float(np.abs(J - expected).max()))
    assert worst <= TOL


def test_panda_mimic_finger_column_is_folded(rng):
    """The right finger moves with finger_joint1 through the mimic finger_joint2."""
    model, _ = robot('panda')
    q = rng.uniform(-1.0, 1.0, model.nq)
    k = model.joint_names.index('panda_finger_joint1')
    right = sd.jacobian(model, q, 'panda_rightfinger')
    left = sd.jacobian(model, q, 'panda_leftfinger')
    # Both fingers slide along ±y of the hand: each finger column is a pure translation.
    assert np.allclose(right[:3, k], 0.0) and np.linalg.norm(right[3:, k]) == pytest.approx(1)
    assert np.allclose(left[:3, k], 0.0) and np.linalg.norm(left[3:, k]) == pytest.approx(1)
    hand = sd.jacobian(model, q, 'panda_hand', 'world')
    assert np.allclose(hand[:, k], 0.0)


def test_batched_and_errors(rng):
    model, _ = robot('ur5')
    Q = rng.uniform(-2.0, 2.0, (4, 3, model.nq))
    J = sd.jacobian(model, Q, 'tool0', 'world')
    assert J.shape == (4, 3, 6, model.nq)
    for idx in np.ndindex(4, 3):
        assert np.array_equal(J[idx], sd.jacobian(model, Q[idx], 'tool0', 'world'))
    assert np.array_equal(sd.jacobian(model, Q[0, 0], 'base_link'), np.zeros((6, model.nq)))
    with pytest.raises(ValueError, match="link 'nope' is not a link"):
        sd.jacobian(model, Q[0, 0], 'nope')
    with pytest.raises(ValueError, match="frame must be one of"):
        sd.jacobian(model, Q[0, 0], 'tool0', 'LOCAL')
    with pytest.raises(ValueError, match=r'q must have shape \(\.\.\., 6\)'):
        sd.jacobian(model, np.zeros(5), 'tool0')


# --------------------------------------------------------------------------------------------
# Forward kinematics by homogeneous matrices, from the URDF text

def rpy_matrix(rpy):
    r, p, y = rpy
    Rx = np.array([[1, 0, 0], [0, np.cos(r), -np.sin(r)], [0, np.sin(r), np.cos(r)]])
    Ry = np.array([[np.cos(p), 0, np.sin(p)], [0, 1, 0], [-np.sin(p), 0, np.cos(p)]])
    Rz = np.array([[np.cos(y), -np.sin(y), 0], [np.sin(y), np.cos(y), 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


def axis_angle(axis, angle):
    a = np.asarray(axis) / np.linalg.norm(axis)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def link_pose(xml, joint_names, q, link):
    """Return (R, p): the link's rotation and origin in the root link's frame."""
    values = dict(zip(joint_names, q))
    for name, (src, mul, off) in mimic_table(xml).items():
        values[name] = mul * values[src] + off
    child_joint = {}
    for j in ET.fromstring(xml.encode()).findall('joint'):
        child_joint[j.find('child').get('link')] = j
    R, p = np.eye(3), np.zeros(3)
    while link in child_joint:
        j = child_joint[link]
        o = j.find('origin')
        xyz = np.array([float(x) for x in (o.get('xyz', '0 0 0') if o is not None
                                           else '0 0 0').split()])
        rpy = [float(x) for x in (o.get('rpy', '0 0 0') if o is not None else '0 0 0').split()]
        Rj, pj = rpy_matrix(rpy), xyz
        a = j.find('axis')
        axis = [float(x) for x in (a.get('xyz') if a is not None else '1 0 0').split()]
        if j.get('type') in ('revolute', 'continuous'):
            Rj = Rj @ axis_angle(axis, values[j.get('name')])
        elif j.get('type') == 'prismatic':
            pj = pj + Rj @ (np.asarray(axis) * values[j.get('name')])
        R, p = Rj @ R, Rj @ p + pj                     # parent ← child composed on the left
        link = j.find('parent').get('link')
    return R, p


def vee(W):
    return np.array([W[2, 1], W[0, 2], W[1, 0]])


@pytest.mark.parametrize('name,link', [('ur5', 'tool0'), ('panda', 'panda_hand_tcp'),
                                       ('panda', 'panda_rightfinger'),
                                       ('talos', 'gripper_left_fingertip_3_link')])
def test_J_qd_is_the_velocity_of_the_link_by_finite_differences(name, link, rng):
    model, xml = robot(name)
    assert link in model.frames
    h = 1e-6
    for _ in range(3):
        q = rng.uniform(-1.5, 1.5, model.nq)
        qd = rng.uniform(-1.0, 1.0, model.nq)
        R, _ = link_pose(xml, model.joint_names, q, link)
        Rp, pp = link_pose(xml, model.joint_names, q + h * qd, link)
        Rm, pm = link_pose(xml, model.joint_names, q - h * qd, link)
        w_world = vee((Rp - Rm) / (2 * h) @ R.T)        # Ṙ Rᵀ = ω×, base axes
        v_world = (pp - pm) / (2 * h)                   # velocity of the link origin
        world = np.concatenate([w_world, v_world])
        local = np.concatenate([R.T @ w_world, R.T @ v_world])
        assert np.allclose(sd.jacobian(model, q, link, 'world') @ qd, world, atol=1e-8)
        assert np.allclose(sd.jacobian(model, q, link, 'local') @ qd, local, atol=1e-8)


# --------------------------------------------------------------------------------------------
# Statics: τ = Jᵀ w is RNEA's answer to the wrench w (link frame)

@pytest.mark.parametrize('name,links', [('ur5', ['tool0', 'wrist_2_link']),
                                        ('panda', ['panda_hand_tcp', 'panda_rightfinger']),
                                        ('talos', ['arm_left_7_link', 'leg_right_6_link',
                                                   'gripper_right_fingertip_1_link'])])
def test_J_transpose_w_is_the_torque_rnea_gives_for_the_external_wrench(name, links, rng):
    model, _ = robot(name)
    zero = np.zeros(model.nq)
    q = rng.uniform(-1.5, 1.5, (5, model.nq))
    for link in links:
        w = rng.normal(0.0, 10.0, (5, 6))
        tau = (sd.rnea(model, q, zero, zero, gravity=(0, 0, 0), f_ext={link: w}))
        JT_w = np.einsum('...ij,...i->...j', sd.jacobian(model, q, link), w)
        # RNEA's f_i = I a + v ×* I v - f_ext: the wrench enters with a minus sign
        assert np.abs(tau + JT_w).max() <= 1e-9 * max(1.0, np.abs(JT_w).max())
        assert np.abs(JT_w).max() > 1.0
