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
import warnings

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
    """Return the URDF text for Pinocchio: named if it is not, no leading space."""
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


def load(path, **kwargs):
    """Load a model with its URDFWarnings recorded, not printed; return it and them."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter('always', sd.URDFWarning)
        model = sd.Model.from_urdf(path, **kwargs)
    return model, [str(w.message) for w in caught if issubclass(w.category, sd.URDFWarning)]


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
    model, said = load(path, base='floating')
    # the URDF's warnings are the links' own, said once each and kept: those of the same file
    # on a fixed base (32 of them over these robots used to leak into the test output)
    assert said == list(model.warnings) == list(load(path)[1])
    assert all(re.match(r"link '[^']+' <inertial>: ", text) for text in said), said
    assert model.joint_names[0] == 'root_joint'
    n = len(model.joint_names) - 1
    assert (model.nq, model.nv) == (7 + n, 6 + n)
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


# -- the other algorithms, identities, reduction, the command -------------------------------

IDENTITY_ROBOTS = ('solo_description/robots/solo12.urdf', 'talos_data/robots/talos_full_v2.urdf',
                   'g1_description/urdf/g1_29dof_rev_1_0.urdf')


def floating_robot(name):
    path = path_of(name)
    return sd.Model.from_urdf(path, base='floating'), FloatingOracle(pinocchio_text(path))


@pytest.mark.parametrize('name', IDENTITY_ROBOTS)
def test_momentum_regressor_and_jacobian_equal_pinocchio(name, rng):
    """M q̇ and Cᵀ q̇ (computeCoriolisMatrix), Y π = τ, and a foot's LOCAL Jacobian."""
    model, oracle = floating_robot(name)
    names = model.joint_names
    q, v, a = random_floating_state(rng, model)
    q_pin, v_pin, _ = oracle.expand(names, q, v, a)
    P = oracle.velocity_map(names, q)
    C = pin.computeCoriolisMatrix(oracle.model, oracle.data, q_pin, v_pin).copy()
    _, _, _, M = oracle.terms(names, q, v, a)
    pi = sd.algorithms.regressor.parameters(model)
    for backend in ('numpy', 'compiled'):
        mom, ctq = sd.generalized_momentum(model, q, v, backend=backend)
        assert close(mom, M @ v)[0], backend
        assert close(ctq, P.T @ C.T @ (P @ v))[0], backend
        Y = sd.regressor(model, q, v, a, backend=backend)
        assert close(Y @ pi, sd.rnea(model, q, v, a, backend=backend))[0], backend
    link = model.body_names[-1]
    J = sd.jacobian(model, q, link)
    pin.computeJointJacobians(oracle.model, oracle.data, q_pin)
    pin.updateFramePlacements(oracle.model, oracle.data)
    fid = oracle.model.getFrameId(link, pin.FrameType.BODY)
    J_pin = pin.getFrameJacobian(oracle.model, oracle.data, fid, pin.LOCAL)
    assert close(J, np.vstack([J_pin[3:], J_pin[:3]]) @ P)[0]


@pytest.mark.parametrize('name', IDENTITY_ROBOTS)
def test_floating_identities(name, rng):
    """M is SPD, M q̈ + (C q̇ + g) = τ, g = ∂V/∂q along q̇, the world frame does not matter.

    Moving the world frame changes nothing but the base pose (and gravity, turned with it).
    """
    model, oracle = floating_robot(name)
    q, v, a = random_floating_state(rng, model)
    M = sd.mass_matrix(model, q)
    assert np.array_equal(M, M.T)
    assert np.linalg.eigvalsh(M).min() > 0.0
    assert close(M @ a + sd.bias_torque(model, q, v), sd.rnea(model, q, v, a))[0]
    # g(q)ᵀ q̇ = dV/dt along the motion q(t) = integrate(q, q̇ t) (central difference)
    h = 1e-5
    V = [pin.computePotentialEnergy(oracle.model, oracle.data, oracle.expand(
        model.joint_names, sd.integrate(model, q, v, s * h), v, a)[0]) for s in (1, -1)]
    dV = (V[0] - V[1]) / (2 * h)
    assert abs(sd.gravity_torque(model, q) @ v - dV) <= 1e-6 * max(1.0, abs(dV))
    # a rigid motion (R, p) of the world: base pose (R p0 + p, R ⊗ quat), gravity R g
    angle, axis = 0.7, np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    turn = np.r_[np.sin(angle / 2) * axis, np.cos(angle / 2)]
    R = sd.joints.quaternion_matrix(turn)
    moved = q.copy()
    moved[:3] = R @ q[:3] + np.array([5.0, -3.0, 1.0])
    u, w = q[3:6], q[6]
    moved[3:6] = turn[3] * u + w * turn[:3] + np.cross(turn[:3], u)
    moved[6] = turn[3] * w - turn[:3] @ u
    g = np.array([0.0, 0.0, -9.81])
    assert close(sd.rnea(model, moved, v, a, R @ g), sd.rnea(model, q, v, a, g))[0]
    assert not close(sd.rnea(model, moved, v, a, g), sd.rnea(model, q, v, a, g))[0]


def test_integrate_is_pinocchios(rng):
    """sd.integrate moves the base along its twist as pin.integrate does (v linear first)."""
    model, oracle = floating_robot('solo_description/robots/solo12.urdf')
    for dt in (0.01, 1.0, 1e-7):
        q, v, a = random_floating_state(rng, model)
        q_pin, v_pin, _ = oracle.expand(model.joint_names, q, v, a)
        ours = sd.integrate(model, q, v, dt)
        theirs = pin.integrate(oracle.model, q_pin, v_pin * dt)
        sign = np.sign(ours[6] * theirs[6]) or 1.0
        assert np.allclose(ours[:3], theirs[:3], rtol=0, atol=1e-12)
        assert np.allclose(ours[3:7], sign * theirs[3:7], rtol=0, atol=1e-12)
        assert np.allclose(ours[7:], q[7:] + v[6:] * dt, rtol=0, atol=1e-15)
    batch = sd.integrate(model, *random_floating_state(rng, model, (4,))[:2], 0.1)
    assert batch.shape == (4, model.nq)
    assert np.allclose(np.linalg.norm(batch[:, 3:7], axis=-1), 1.0)


def test_integrate_refuses_a_step_it_cannot_take_and_takes_one_dt_per_state(rng, capfd):
    """A step that cannot be taken is refused by name, and ``dt`` may be one per state.

    dt = inf, dt = nan and qd = 1e300 gave NaN q and ~15 RuntimeWarnings, a dt of a batch
    shape a bare broadcast error. Now nothing on stderr; a ``dt`` per state is each state's
    Pinocchio step.
    """
    model, oracle = floating_robot('solo_description/robots/solo12.urdf')
    q0 = np.r_[np.zeros(6), 1.0, np.zeros(12)]
    v = np.ones(model.nv)
    for qd, dt, named in ((v, np.inf, 'dt must be finite'), (v, np.nan, 'dt must be finite'),
                          (v, -np.inf, 'dt must be finite'),
                          (v + 1e300, 0.01, r'qd · dt must stay within ±100000'),
                          (v * 1e6, 1.0, r'qd · dt must stay within ±100000'),
                          (np.r_[np.nan, v[1:]], 0.01, r'qd must be finite: qd\[0, 0\] is nan'),
                          (v, np.full(3, 0.01), r'dt must be a number .* batch \(4,\) .* '
                           r'shape \(3,\)')):
        with warnings.catch_warnings():
            warnings.simplefilter('error')
            with pytest.raises(ValueError, match=named):
                sd.integrate(model, np.tile(q0, (4, 1)), qd, dt)
    assert capfd.readouterr().err == ''
    q, qd, _ = random_floating_state(rng, model, (2,))
    dts = np.array([0.01, 0.02])
    ours = sd.integrate(model, q, qd, dts)
    assert ours.shape == (2, model.nq)
    for k in range(2):
        q_pin, v_pin, _ = oracle.expand(model.joint_names, q[k], qd[k], qd[k])
        theirs = pin.integrate(oracle.model, q_pin, v_pin * dts[k])
        sign = np.sign(ours[k, 6] * theirs[6]) or 1.0
        assert np.allclose(ours[k, :3], theirs[:3], rtol=0, atol=1e-12)
        assert np.allclose(ours[k, 3:7], sign * theirs[3:7], rtol=0, atol=1e-12)
    # one state, a dt per row: the batch is dt's
    assert sd.integrate(model, q[0], qd[0], dts).shape == (2, model.nq)


def test_reduction_keeps_the_free_flyer(rng):
    """Reduce a floating base: the free-flyer stays, the rest as for a fixed base.

    The reduced model's torques are the full model's rows at the locked value.
    """
    path = path_of('solo_description/robots/solo12.urdf')
    kept = ['FL_HFE', 'FL_KFE', 'HR_KFE']
    model = sd.Model.from_urdf(path, base='floating', joints=kept, locked={'FL_HAA': 0.3})
    assert model.joint_names == ('root_joint', *kept)
    assert (model.nq, model.nv) == (10, 9)
    full = sd.Model.from_urdf(path, base='floating')
    q, v, a = random_floating_state(rng, model)
    qf = np.zeros(full.nq)
    qf[:7] = q[:7]
    vf, af = np.zeros(full.nv), np.zeros(full.nv)
    vf[:6], af[:6] = v[:6], a[:6]
    at = {j: k for k, j in enumerate(full.joint_names)}
    qf[6 + at['FL_HAA']] = 0.3
    for k, j in enumerate(kept):
        qf[6 + at[j]], vf[5 + at[j]], af[5 + at[j]] = q[7 + k], v[6 + k], a[6 + k]
    tau_full = sd.rnea(full, qf, vf, af)
    rows = [0, 1, 2, 3, 4, 5] + [5 + at[j] for j in kept]
    for backend in ('numpy', 'compiled'):
        assert close(sd.rnea(model, q, v, a, backend=backend), tau_full[rows])[0]


def test_a_fixed_base_model_is_unchanged_by_the_option(rng):
    """base='fixed' (the default) is today's model: nq == nv, no free-flyer, same torques."""
    path = path_of('solo_description/robots/solo12.urdf')
    fixed, default = (sd.Model.from_urdf(path, base='fixed'), sd.Model.from_urdf(path))
    assert fixed.nq == fixed.nv == len(fixed.joint_names) == 12 and not fixed.floating
    q, v, a = (rng.uniform(-1, 1, 12) for _ in range(3))
    assert np.array_equal(sd.rnea(fixed, q, v, a), sd.rnea(default, q, v, a))
    with pytest.raises(ValueError, match="base must be one of"):
        sd.Model.from_urdf(path, base='flying')


def test_shapes_are_named_when_wrong():
    model = sd.Model.from_urdf(path_of('solo_description/robots/solo12.urdf'), base='floating')
    with pytest.raises(ValueError, match=r'qd must have shape \(\.\.\., 18\)'):
        sd.rnea(model, np.zeros(19), np.zeros(19), np.zeros(18))
    with pytest.raises(ValueError, match=r'q must have shape \(\.\.\., 19\)'):
        sd.gravity_torque(model, np.zeros(18))


def test_summary_and_check_urdf_say_floating_base(capsys):
    from spatial_dynamics import check
    path = path_of('solo_description/robots/solo12.urdf')
    model = sd.Model.from_urdf(path, base='floating')
    assert 'floating base' in model.summary() and 'nq 19, nv 18' in model.summary()
    assert 'floating base' not in sd.Model.from_urdf(path).summary()
    assert check.main(['--base', 'floating', path]) == 0
    out = capsys.readouterr().out
    assert "floating base (link 'base_link' on the free-flyer joint 'root_joint'" in out
    assert '18 dof (the base 6, the joints 12)' in out


def test_a_table_whose_free_flyer_overruns_q_is_refused():
    """The compiled kernels bound a free-flyer's 7 coordinates of q and 6 of q̇ by the table."""
    from spatial_dynamics.backends import compiled, layout
    if compiled.ext is None:
        pytest.skip('built without the compiled kernels')
    model = sd.Model.from_urdf(path_of('solo_description/robots/solo12.urdf'), base='floating')
    table = layout.of(model).table.copy()
    compiled.ext.Kernels(table)
    nq, nv = model.nq, model.nv
    C = layout.COLUMN
    for row, column, value in ((1, C['qidx'], nq - 6.0), (1, C['vidx'], nv - 5.0),
                               (1, C['dof'], 1.0), (2, C['code'], 5.0), (2, C['dof'], 6.0),
                               (2, C['vidx'], nv + 0.0), (0, C['vidx'], nq + 1.0)):
        bad = table.copy()
        bad[row, column] = value
        with pytest.raises(ValueError, match='not a tree'):
            compiled.ext.Kernels(bad)


def test_batches_broadcast_and_run_in_lanes_bit_for_bit(rng):
    """A batch of floating states (SIMD lanes) gives each state's single-call torques exactly.

    q of shape (N, nq) broadcasts against one q̇ of shape (nv,).
    """
    model = sd.Model.from_urdf(path_of('talos_data/robots/talos_full_v2.urdf'), base='floating')
    Q, V, A = random_floating_state(rng, model, (19,))
    batch = sd.rnea(model, Q, V, A, backend='compiled')
    single = np.array([sd.rnea(model, Q[s], V[s], A[s], backend='compiled') for s in range(19)])
    assert np.array_equal(batch, single)
    assert np.allclose(sd.rnea(model, Q, V, A, backend='numpy'), batch, rtol=0, atol=1e-9)
    spread = sd.rnea(model, Q, V[0], A[0])
    assert spread.shape == (19, model.nv)
    assert np.array_equal(spread[3], sd.rnea(model, Q[3], V[0], A[0]))
    assert sd.generalized_momentum(model, Q[:2], V[:2])[0].shape == (2, model.nv)
    assert sd.regressor(model, Q[:2], V[:2], A[:2]).shape == (2, model.nv, 10 * model.NB)


def test_external_wrenches_on_a_floating_base_equal_pinocchio(rng):
    """f_ext on a foot and on the base itself, in their link frames, as Pinocchio's fext."""
    model, oracle = floating_robot('solo_description/robots/solo12.urdf')
    names = model.joint_names
    q, v, a = random_floating_state(rng, model)
    f_ext = {'FL_FOOT': rng.normal(size=6), 'base_link': rng.normal(size=6)}
    forces = [pin.Force.Zero() for _ in range(oracle.model.njoints)]
    for link, w in f_ext.items():
        frame = oracle.model.frames[oracle.model.getFrameId(link, pin.FrameType.BODY)]
        forces[frame.parentJoint] += frame.placement.act(pin.Force(w[3:], w[:3]))
    q_pin, v_pin, a_pin = oracle.expand(names, q, v, a)
    oracle.model.gravity.linear = np.array([0.0, 0.0, -9.81])
    P = oracle.velocity_map(names, q)
    expected = P.T @ pin.rnea(oracle.model, oracle.data, q_pin, v_pin, a_pin, forces)
    for backend in ('numpy', 'compiled'):
        assert close(sd.rnea(model, q, v, a, f_ext=f_ext, backend=backend), expected)[0]


def test_the_flat_kernels_the_c_is_printed_from_compute_the_floating_source(rng):
    """The generator's flat rewrite of the kernels (joints inlined by C) on a floating model."""
    from spatial_dynamics.backends import codegen, layout, python
    flat = codegen.flat_module()
    model = sd.Model.from_urdf(path_of('talos_data/robots/talos_full_v2.urdf'), base='floating')
    lay = layout.of(model)
    q, v, a = random_floating_state(rng, model)
    rows = lay.table.shape[0]
    work = np.zeros(rows * flat.WORK)
    tau = np.zeros(model.nv)
    flat.xup_kernel(lay.table, q, work)
    flat.rnea_kernel(lay.table, q, v, a, 0.5, 0.0, -9.8, np.zeros((1, 6)), False, tau, work)
    assert tau.tolist() == python.rnea_rows(lay.rows, q.tolist(), v.tolist(), a.tolist(),
                                            (0.5, 0.0, -9.8))
    H = np.zeros(model.nv ** 2)
    flat.crba_kernel(lay.table, work, H)
    assert H.tolist() == python.mass_matrix_rows(lay.rows, q.tolist())
    mom, ctq = np.zeros(model.nv), np.zeros(model.nv)
    flat.momentum_kernel(lay.table, q, v, mom, ctq, work)
    assert (mom.tolist(), ctq.tolist()) == python.momentum_rows(lay.rows, q.tolist(), v.tolist())
    Y = np.zeros(model.nv * 10 * (rows - 1))
    flat.xup_kernel(lay.table, q, work)
    flat.regressor_kernel(lay.table, v, a, 0.5, 0.0, -9.8, Y, np.zeros(6 * rows * (rows + 5)),
                          work)
    assert Y.tolist() == python.regressor_rows(lay.rows, q.tolist(), v.tolist(), a.tolist(),
                                               (0.5, 0.0, -9.8))
