# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Model reduction: kept joints give the full model's τ with the others locked and still."""

import numpy as np
import pytest

from conftest import robot_urdf_path
import spatial_dynamics as sd
from urdf_gen import random_tree_urdf


def full_state(full, reduced, locked, q, qd, qdd):
    """Embed a reduced state in the full model: locked joints at their values, zero rates."""
    Q = np.array([locked.get(j, 0.0) for j in full.joint_names])
    Qd, Qdd = np.zeros(full.nq), np.zeros(full.nq)
    index = [full.joint_names.index(j) for j in reduced.joint_names]
    Q[index], Qd[index], Qdd[index] = q, qd, qdd
    return Q, Qd, Qdd, index


def check_equal(full, reduced, locked, rng, gravity=(0.0, 0.0, -9.81)):
    for _ in range(5):
        q, qd, qdd = rng.uniform(-2.0, 2.0, (3, reduced.nq))
        Q, Qd, Qdd, index = full_state(full, reduced, locked, q, qd, qdd)
        for backend in ('numpy', 'auto'):
            expected = sd.rnea(full, Q, Qd, Qdd, gravity=gravity, backend=backend)[index]
            got = sd.rnea(reduced, q, qd, qdd, gravity=gravity, backend=backend)
            np.testing.assert_allclose(got, expected, rtol=0, atol=1e-10)


def test_one_talos_arm_equals_the_whole_talos():
    path = robot_urdf_path('talos')
    full = sd.Model.from_urdf(path)
    arm = [j for j in full.joint_names if j.startswith('arm_left_')]
    rng = np.random.default_rng(3)
    locked = {j: float(rng.uniform(-1, 1)) for j in full.joint_names if j not in arm}
    for lock in ({}, locked):
        reduced = sd.Model.from_urdf(path, joints=arm[::-1], locked=lock)
        assert reduced.joint_names == tuple(arm[::-1])          # the order asked for
        assert reduced.nq == 7 and reduced.NB < full.NB
        # legs, head, the other arm and the torso cannot change an arm torque: pruned
        assert any(link.startswith('leg_') for link in reduced.pruned)
        assert any(link.startswith('arm_right') for link in reduced.pruned)
        others = [j for j in full.joint_names if j not in arm]
        assert dict(reduced.locked) == {j: lock.get(j, 0.0) for j in others}
        check_equal(full, reduced, lock, rng)
        check_equal(full, reduced, lock, rng, gravity=(3.0, -2.0, -9.0))
        assert 'pruned' in reduced.summary()


def test_panda_without_fingers_locks_the_mimic_pair():
    path = robot_urdf_path('panda')
    full = sd.Model.from_urdf(path)
    arm = [j for j in full.joint_names if 'finger' not in j]
    locked = {'panda_finger_joint1': 0.03}    # the mimic finger2 follows: 0.03 as well
    reduced = sd.Model.from_urdf(path, joints=arm, locked=locked)
    assert reduced.NB == 7 and reduced.nq == 7
    check_equal(full, reduced, locked, np.random.default_rng(4))


@pytest.mark.parametrize('seed', range(4))
def test_random_trees_reduced_to_random_subsets(seed):
    rng = np.random.default_rng(100 + seed)
    xml = random_tree_urdf(rng, 12, branching=True, mimic=True)
    full = sd.Model.from_urdf(xml)
    keep = list(rng.permutation(full.joint_names)[:max(1, full.nq // 2)])
    locked = {j: float(rng.uniform(-1, 1)) for j in full.joint_names if j not in keep}
    reduced = sd.Model.from_urdf(xml, joints=keep, locked=locked)
    assert reduced.joint_names == tuple(keep)
    check_equal(full, reduced, locked, rng)


def test_keeping_every_joint_changes_nothing():
    path = robot_urdf_path('ur5')
    full = sd.Model.from_urdf(path)
    same = sd.Model.from_urdf(path, joints=full.joint_names)
    check_equal(full, same, {}, np.random.default_rng(5))
    assert same.NB == full.NB and not same.locked


@pytest.mark.parametrize('joints, locked, match', [
    (['nope'], None, "kept joint 'nope' is not a movable joint"),
    (['panda_finger_joint2'], None, "'panda_finger_joint2' is a mimic joint"),
    (['panda_joint1', 'panda_joint1'], None, 'twice'),
    (['panda_joint1'], {'panda_joint1': 0.1}, 'both kept and locked'),
    (['panda_joint1'], {'panda_joint2': float('nan')}, 'panda_joint2'),
    (['panda_joint1'], {'panda_finger_joint2': 0.0}, 'mimic joint'),
    (None, {'panda_joint2': 0.0}, 'need a list of kept joints'),
    ('panda_joint1', None, 'list of joint names'),
])
def test_bad_reduction_requests_name_the_joint(joints, locked, match):
    with pytest.raises(ValueError, match=match):
        sd.Model.from_urdf(robot_urdf_path('panda'), joints=joints, locked=locked)
