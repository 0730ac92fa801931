# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Joints in one home: the kinds, their kernel codes and operations live in joints.py only.

One axis classifier (a −axis is the cheaper form as well as +axis), the kernel operations
equal the 6×6 ``jcalc`` of each kind, and no algorithm branches on a joint's kind.
"""

import ast
import glob
import os

import numpy as np
import pytest
import spatial_dynamics as sd
from spatial_dynamics import joints
from spatial_dynamics.backends import layout
from spatial_dynamics.spatial import Eaxis, plux_Er

ALGORITHMS = os.path.join(os.path.dirname(sd.__file__), 'algorithms')
KIND_NAMES = {'FIXED', 'REVOLUTE', 'PRISMATIC', 'FREE_FLYER', 'RX', 'RY', 'RZ', 'RA', 'PR', 'FF'}


@pytest.mark.parametrize('path', sorted(glob.glob(os.path.join(ALGORITHMS, '*.py'))),
                         ids=os.path.basename)
def test_no_algorithm_names_a_joint_kind(path):
    """The algorithms ask the joint (joints.py); none compares or imports a kind or code."""
    with open(path, encoding='utf-8') as f:
        tree = ast.parse(f.read())
    named = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)} | {
        a.name for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) for a in n.names}
    assert not named & KIND_NAMES, sorted(named & KIND_NAMES)


@pytest.mark.parametrize('axis,code', [((1, 0, 0), joints.RX), ((-1, 0, 0), joints.RX),
                                       ((0, 1, 0), joints.RY), ((0, -1, 0), joints.RY),
                                       ((0, 0, 1), joints.RZ), ((0, 0, -1), joints.RZ),
                                       ((0.6, 0.8, 0), joints.RA)])
def test_one_axis_classifier_for_both_signs(axis, code):
    axis = np.array(axis, dtype=float)
    assert joints.joint_code(joints.REVOLUTE, axis) == code
    # jcalc takes the same form: for -axis the rotation by -q about +axis, exactly Eaxis's
    XJ, S = joints.jcalc(joints.REVOLUTE, axis, 0.7)
    assert np.allclose(XJ[:3, :3], Eaxis(axis, 0.7), rtol=0, atol=1e-15)
    assert np.array_equal(S[:, 0], np.r_[axis, 0, 0, 0])


@pytest.mark.parametrize('jtype,axis,q', [
    (joints.REVOLUTE, (0, 0, -1), 0.4), (joints.REVOLUTE, (0.6, 0, 0.8), -1.1),
    (joints.PRISMATIC, (0, 0.6, 0.8), 0.3),
    (joints.FREE_FLYER, (0, 0, 0), (0.1, -0.2, 0.3, 0.2, -0.4, 0.1, 0.8))])
def test_the_kernel_transform_is_jcalc_composed_with_xtree(jtype, axis, q):
    """joint_transform (what the kernels run) is XJ(q) Xtree of jcalc (the 6×6 text)."""
    axis = np.array(axis, dtype=float)
    rng = np.random.default_rng(3)
    E_t = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    r_t = rng.normal(size=3)
    from spatial_dynamics.spatial import plux
    Xtree = plux(E_t, r_t)
    qv = np.atleast_1d(np.array(q, dtype=float))
    XJ, _ = joints.jcalc(jtype, axis, qv if jtype == joints.FREE_FLYER else qv[0])
    E, r = plux_Er(XJ @ Xtree)
    code = joints.joint_code(jtype, axis)
    got = joints.joint_transform(code, list(qv), 0, 1.0, 0.0, *axis, *E_t.ravel(), *r_t, np)
    assert np.allclose(got[:9], E.ravel(), atol=1e-14) and np.allclose(got[9:], r, atol=1e-14)


def test_a_free_flyer_has_six_velocity_coordinates_and_s_is_identity():
    assert (joints.NQ[joints.FREE_FLYER], joints.NV[joints.FREE_FLYER]) == (7, 6)
    XJ, S = joints.jcalc(joints.FREE_FLYER, np.zeros(3), np.r_[0, 0, 0, 0, 0, 0, 1.0])
    assert np.array_equal(S, np.eye(6)) and np.allclose(XJ, np.eye(6))
    # a quaternion that is not unit is normalised where it is used
    q = np.r_[1.0, 2.0, 3.0, 0.1, 0.2, 0.3, 0.9]
    q2 = q.copy()
    q2[3:] *= 3.0
    assert np.allclose(joints.jcalc(joints.FREE_FLYER, np.zeros(3), q)[0],
                       joints.jcalc(joints.FREE_FLYER, np.zeros(3), q2)[0], atol=1e-15)


def test_the_layout_asks_the_joint_for_its_code():
    model = sd.Model.from_urdf('''<robot name="r"><link name="a"/><link name="b"/><link name="c"/>
      <joint name="j1" type="revolute"><parent link="a"/><child link="b"/>
        <axis xyz="0 -1 0"/></joint>
      <joint name="j2" type="prismatic"><parent link="b"/><child link="c"/>
        <axis xyz="0 0 1"/></joint></robot>''', base='floating')
    codes = [row[layout.COLUMN['code']] for row in layout.of(model).rows[1:]]
    assert codes == [joints.FF, joints.RY, joints.PR]
