# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Floating-base models (``base='floating'``) against Pinocchio's ``JointModelFreeFlyer``.

Every robot of example-robot-data whose base moves — it walks (quadrupeds, bipeds,
humanoids), flies (quadrotors, flying arms) or drives (mobile manipulators) — loaded with a
free-flyer root joint, on random states with unit quaternions: ``rnea``, ``bias_torque``
(``nonLinearEffects``), ``gravity_torque`` (``computeGeneralizedGravity``) and
``mass_matrix`` (``crba``, full and symmetric), single and batched, numpy and compiled.

The map to Pinocchio: the same ``q`` (position, then the quaternion x y z w), and the base
twist linear first in Pinocchio, ``v_pin[:6] = [v; ω]`` against our ``[ω; v]`` (both in the
base frame); the base rows of τ swap the same way (``[f; n]`` against ``[n; f]``). Mimic
joints are independent joints in Pinocchio, driven and folded as in ``conftest.py``.
"""

import os
import re

from conftest import example_robot_data_dir, strip_mimic
import numpy as np
import pytest
import spatial_dynamics as sd
from urdf_gen import mimic_table

pin = pytest.importorskip('pinocchio')

BASE = example_robot_data_dir()
#: The robots of example-robot-data whose base moves, as listed by its `robots/` folders (a
#: folder per robot; each URDF of a robot that walks, flies or drives): every URDF there
#: except the fixed-base arms, hands and pendulums (UR, Panda, Kinova, xArm, Z1, SO-ARM,
#: Baxter on its pedestal, Allegro, the finger, the double pendulums, the 2-DoF arm, Talos's
#: left arm), Alex with Psyonic hands (refused: a mimic of a missing joint, as in the
#: fixed-base sweep) and Cassie (no URDF in the package).
FLOATING = (
    'a1_description/urdf/a1.urdf',
    'alex_description/urdf/alex_nub_hands.urdf',
    'alex_description/urdf/alex_sake_hands.urdf',
    'alexander_description/urdf/alexander_v1.lowerBodyOnly.urdf',
    'anymal_b_simple_description/robots/anymal-kinova.urdf',
    'anymal_b_simple_description/robots/anymal.urdf',
    'anymal_c_simple_description/urdf/anymal.urdf',
    'b1_description/urdf/b1-z1.urdf',
    'b1_description/urdf/b1.urdf',
    'bolt_description/robots/bolt.urdf',
    'borinot_description/urdf/borinot_flying_arm_2.urdf',
    'centauro_description/urdf/centauro.urdf',
    'g1_description/urdf/g1_29dof_rev_1_0.urdf',
    'g1_description/urdf/g1_29dof_with_hand_rev_1_0.urdf',
    'go1_description/urdf/go1.urdf',
    'go2_description/urdf/go2.urdf',
    'hector_description/robots/quadrotor_base.urdf',
    'hextilt_description/urdf/hextilt_flying_arm_5.urdf',
    'human_description/robots/human.urdf',
    'hyq_description/robots/hyq_no_sensors.urdf',
    'icub_description/robots/icub.urdf',
    'icub_description/robots/icub_reduced.urdf',
    'iris_description/robots/iris.urdf',
    'iris_description/robots/iris_simple.urdf',
    'laikago_description/urdf/laikago.urdf',
    'pr2_description/urdf/pr2.urdf',
    'quadruped_description/urdf/quadruped.urdf',
    'romeo_description/urdf/romeo.urdf',
    'romeo_description/urdf/romeo_laas_small.urdf',
    'romeo_description/urdf/romeo_small.urdf',
    'simple_humanoid_description/urdf/simple_humanoid.urdf',
    'simple_humanoid_description/urdf/simple_humanoid_classical.urdf',
    'solo_description/robots/solo.urdf',
    'solo_description/robots/solo12.urdf',
    'talos_data/robots/talos_full_v2.urdf',
    'talos_data/robots/talos_full_v2_box.urdf',
    'talos_data/robots/talos_reduced.urdf',
    'talos_data/robots/talos_reduced_box.urdf',
    'talos_data/robots/talos_reduced_corrected.urdf',
    'tiago_description/robots/tiago.urdf',
    'tiago_description/robots/tiago_dual.urdf',
    'tiago_description/robots/tiago_no_hand.urdf',
    'tiago_pro_description/robots/tiago_pro.urdf',
)
RTOL = 1e-12    # normwise, relative to max(1, |expected|)


def pinocchio_text(path):
    """The URDF text for Pinocchio: named if it is not, no leading space."""
    with open(path, encoding='utf-8') as f:
        text = f.read().lstrip()
    return re.sub(r'<robot(?=[\s>/])(?![^>]*\bname=)', '<robot name="robot"', text, count=1)


class FloatingOracle:
    """Pinocchio with a free-flyer root joint; our states mapped to its and back."""

    def __init__(self, xml):
        """Build Pinocchio's floating-base model of a URDF text (mimic joints independent)."""
        self.mimic = mimic_table(xml)
        self.model = pin.buildModelFromXML(strip_mimic(xml), pin.JointModelFreeFlyer())
        self.model.armature[:] = 0.0
        self.data = self.model.createData()
        assert self.model.names[1] == 'root_joint' and self.model.joints[1].nq == 7
        self.joints = {}            # name -> (idx_q, idx_v, nq): 1 or 2 (continuous)
        for jid in range(2, self.model.njoints):
            jm = self.model.joints[jid]
            assert jm.nv == 1, self.model.names[jid]
            self.joints[self.model.names[jid]] = (jm.idx_q, jm.idx_v, jm.nq)

    def expand(self, names, q, v, a):
        """Pinocchio's ``(q, v, a)`` from ours (``names`` = our joint_names, root first)."""
        value = {name: (q[6 + k], v[5 + k], a[5 + k]) for k, name in enumerate(names)
                 if k > 0}
        for name, (src, mult, offset) in self.mimic.items():
            qs, vs, as_ = value[src]
            value[name] = (mult * qs + offset, mult * vs, mult * as_)
        q_pin, v_pin, a_pin = (np.zeros(self.model.nq), np.zeros(self.model.nv),
                               np.zeros(self.model.nv))
        q_pin[:7] = q[:7]
        for x_pin, x in ((v_pin, v), (a_pin, a)):
            x_pin[:3], x_pin[3:6] = x[3:6], x[:3]     # [v; ω] from [ω; v]
        for name, (iq, iv, nq) in self.joints.items():
            qi, vi, ai = value[name]
            if nq == 2:
                q_pin[iq:iq + 2] = np.cos(qi), np.sin(qi)
            else:
                q_pin[iq] = qi
            v_pin[iv], a_pin[iv] = vi, ai
        return q_pin, v_pin, a_pin

    def velocity_map(self, names, q):
        """``P`` with ``v_pin = P v``: our τ is ``Pᵀ τ_pin`` and our M ``Pᵀ M_pin P``."""
        nv = len(q) - 1
        zero = np.zeros(nv)
        return np.stack([self.expand(names, q, e, zero)[1] for e in np.eye(nv)], axis=1)

    def terms(self, names, q, v, a, gravity=(0.0, 0.0, -9.81)):
        """Return (rnea, nonLinearEffects, generalized gravity, M) in our coordinates."""
        self.model.gravity.linear = np.asarray(gravity, dtype=float)
        q_pin, v_pin, a_pin = self.expand(names, q, v, a)
        P = self.velocity_map(names, q)
        tau = pin.rnea(self.model, self.data, q_pin, v_pin, a_pin).copy()
        nle = pin.nonLinearEffects(self.model, self.data, q_pin, v_pin).copy()
        g = pin.computeGeneralizedGravity(self.model, self.data, q_pin).copy()
        M = pin.crba(self.model, self.data, q_pin).copy()
        M = np.triu(M) + np.triu(M, 1).T
        return P.T @ tau, P.T @ nle, P.T @ g, P.T @ M @ P


def random_floating_state(rng, model, shape=()):
    """Random ``(q, v, a)``: a base pose with a unit quaternion, joints as the sweep's."""
    n = model.nv - 6
    quat = rng.normal(size=tuple(shape) + (4,))
    quat /= np.linalg.norm(quat, axis=-1, keepdims=True)
    q = np.concatenate([rng.uniform(-2.0, 2.0, tuple(shape) + (3,)), quat,
                        rng.uniform(-1.5, 1.5, tuple(shape) + (n,))], axis=-1)
    v = rng.uniform(-2.0, 2.0, tuple(shape) + (model.nv,))
    a = rng.uniform(-3.0, 3.0, tuple(shape) + (model.nv,))
    return q, v, a


def path_of(name):
    if BASE is None:
        pytest.skip('example-robot-data is not installed')
    return os.path.join(BASE, name)


def close(value, expected, rtol=RTOL):
    err = np.linalg.norm(np.asarray(value) - expected)
    return err <= rtol * max(1.0, np.linalg.norm(expected)), err


def test_the_list_holds_every_robot_that_walks_flies_or_drives():
    if BASE is None:
        pytest.skip('example-robot-data is not installed')
    for name in FLOATING:
        assert os.path.isfile(os.path.join(BASE, name)), name
    folders = {name.split('/')[0] for name in FLOATING}
    assert {'solo_description', 'go1_description', 'go2_description', 'a1_description',
            'anymal_b_simple_description', 'anymal_c_simple_description', 'hyq_description',
            'b1_description', 'talos_data', 'g1_description', 'icub_description',
            'romeo_description', 'borinot_description', 'tiago_description'} <= folders


@pytest.mark.parametrize('name', FLOATING)
def test_floating_terms_equal_pinocchio_free_flyer(name, rng):
    """rnea, C q̇ + g, g and M against Pinocchio, one state at a time and batched."""
    path = path_of(name)
    model = sd.Model.from_urdf(path, base='floating')
    assert model.joint_names[0] == 'root_joint'
    assert (model.nq, model.nv) == (7 + len(model.joint_names) - 1, 6 + len(model.joint_names) - 1)
    oracle = FloatingOracle(pinocchio_text(path))
    names = model.joint_names
    assert sorted(names[1:]) == sorted(oracle.joints.keys() - oracle.mimic.keys())
    gravity = (0.4, -0.3, -9.81)
    Q, V, A = random_floating_state(rng, model, (3,))
    expected = [oracle.terms(names, Q[s], V[s], A[s], gravity) for s in range(3)]
    tau_e, nle_e, g_e, M_e = (np.array([e[t] for e in expected]) for t in range(4))
    for backend in ('numpy', 'compiled'):
        for s in range(3):
            for value, want in ((sd.rnea(model, Q[s], V[s], A[s], gravity, backend=backend),
                                 tau_e[s]),
                                (sd.bias_torque(model, Q[s], V[s], gravity, backend=backend),
                                 nle_e[s]),
                                (sd.gravity_torque(model, Q[s], gravity, backend=backend),
                                 g_e[s]),
                                (sd.mass_matrix(model, Q[s], backend=backend), M_e[s])):
                ok, err = close(value, want)
                assert ok, (backend, s, err)
        for value, want in ((sd.rnea(model, Q, V, A, gravity, backend=backend), tau_e),
                            (sd.bias_torque(model, Q, V, gravity, backend=backend), nle_e),
                            (sd.gravity_torque(model, Q, gravity, backend=backend), g_e),
                            (sd.mass_matrix(model, Q, backend=backend), M_e)):
            assert value.shape == want.shape
            for s in range(3):
                ok, err = close(value[s], want[s])
                assert ok, (backend, 'batch', s, err)
