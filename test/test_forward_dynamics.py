# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Forward dynamics: ``sd.forward_dynamics`` against Pinocchio's ``aba``, and as rnea's inverse.

Every URDF of example-robot-data, fixed base and (the robots that walk, fly or drive) free
flyer, against ``pin.aba`` on the same URDF with its ``<mimic>`` tags removed on both sides
(Pinocchio's ``aba`` has no mimic joints: each finger its own coordinate), single states and
batches, numpy and compiled; then ``rnea(q, q̇, forward_dynamics(q, q̇, τ)) = τ`` with every
term rnea takes (gravity, external wrenches, a moving base, armature, a floating base's
wrench), and the refusals of rnea's checks, unchanged.
"""

import glob
import os
import warnings

from conftest import example_robot_data_dir, refusal, strip_mimic
import numpy as np
import pytest
import spatial_dynamics as sd
from test_core_floating_base import FLOATING, FloatingOracle, pinocchio_text, \
    random_floating_state
from test_urdf_robot_sweep import REFUSED

pin = pytest.importorskip('pinocchio')

BASE = example_robot_data_dir()
FILES = sorted(os.path.relpath(p, BASE) for p in glob.glob(
    os.path.join(BASE, '**', '*.urdf'), recursive=True)) if BASE else []
RTOL = 1e-12    # normwise, relative to max(1, |q̈|)
BACKENDS = ('numpy', 'compiled')


def load(text, **kwargs):
    """Load a model from URDF text, its URDFWarnings (inconsistent inertias) silenced."""
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', sd.URDFWarning)
        return sd.Model.from_urdf(text, **kwargs)


def close(value, expected, rtol=RTOL):
    """Whether ``value`` is ``expected`` to ``rtol`` normwise, relative to max(1, |expected|)."""
    err = np.linalg.norm(np.asarray(value) - expected)
    return err <= rtol * max(1.0, np.linalg.norm(expected)), err


def agrees(model, q, value, expected):
    """Whether ``value`` is Pinocchio's q̈ ``expected`` at each state of ``q``; the worst errors.

    In τ (the backward error: ``M (q̈ - q̈_pin)``, what rounding leaves of the equation) to
    :data:`RTOL` of ``|M| |q̈|``, on every robot; in q̈ (the forward error) to :data:`RTOL`
    where ``cond(M) <= 1e7``, beyond that (PR2, the TIAGos, the full Talos: up to 6e7, iCub:
    up to 1.6e9, its finger links weigh grams) to ``RTOL cond(M) / 1e7``: rounding in any
    float64 solve moves q̈ in proportion to ``cond(M)`` (measured on iCub: 2e-12 at 2e8).
    """
    worst = [0.0, 0.0]
    for k in np.ndindex(q.shape[:-1]):
        M = sd.mass_matrix(model, q[k], backend='numpy')
        e = expected[k]
        scale = max(1.0, np.linalg.norm(M, 2) * np.linalg.norm(e))
        backward = np.linalg.norm(M @ (value[k] - e)) / scale
        forward = np.linalg.norm(value[k] - e) / max(1.0, np.linalg.norm(e))
        worst = [max(worst[0], backward), max(worst[1], forward)]
        if backward > RTOL or forward > RTOL * max(1.0, np.linalg.cond(M) / 1e7):
            return False, worst
    return True, worst


def singular(M):
    """Whether a symmetric ``M`` is singular to rounding: a joint that moves no mass."""
    eig = np.linalg.eigvalsh(M)
    return eig[0] <= 1e-12 * eig[-1]


@pytest.mark.parametrize('name', [f for f in FILES if f not in REFUSED])
def test_fixed_base_equals_pinocchio_aba(name, rng):
    from conftest import PinOracle
    text = strip_mimic(pinocchio_text(os.path.join(BASE, name)))
    model = load(text)
    if model.nv == 0:
        for backend in BACKENDS:
            assert sd.forward_dynamics(model, [], [], [], backend=backend).shape == (0,)
        return
    oracle = PinOracle(text)
    q, qd, tau = (rng.uniform(-s, s, (3, model.nv)) for s in (1.5, 2.0, 3.0))
    expected = np.empty_like(tau)
    for k in range(len(q)):
        args = oracle.expand(model.joint_names, q[k], qd[k], tau[k])
        a_pin = pin.aba(oracle.model, oracle.data, *args)
        expected[k] = [a_pin[oracle.joints[j][1]] for j in model.joint_names]
    M = pin.crba(oracle.model, oracle.data, args[0])
    for backend in BACKENDS:
        if singular(np.triu(M) + np.triu(M, 1).T):
            # Romeo's thumbs and gripper: Pinocchio's aba divides by a zero inertia
            with pytest.raises(ValueError, match=r"not positive definite .* joint '\w+'"):
                sd.forward_dynamics(model, q[0], qd[0], tau[0], backend=backend)
            continue
        single = np.array([sd.forward_dynamics(model, q[k], qd[k], tau[k], backend=backend)
                           for k in range(len(q))])
        ok, err = agrees(model, q, single, expected)
        assert ok, (backend, err)
        ok, err = agrees(model, q, sd.forward_dynamics(model, q, qd, tau, backend=backend),
                         expected)
        assert ok, (backend, 'batch', err)


@pytest.mark.parametrize('name', FLOATING)
def test_free_flyer_equals_pinocchio_aba(name, rng):
    text = strip_mimic(pinocchio_text(os.path.join(BASE, name)))
    model = load(text, base='floating')
    oracle = FloatingOracle(text)
    q, qd, tau = random_floating_state(rng, model, (3,))
    expected = np.empty_like(tau)
    for k in range(len(q)):
        args = oracle.expand(model.joint_names, q[k], qd[k], tau[k])
        a_pin = pin.aba(oracle.model, oracle.data, *args)
        P = oracle.velocity_map(model.joint_names, q[k])      # a_pin = P q̈: a permutation
        expected[k] = P.T @ a_pin
    M = sd.mass_matrix(model, q[0], backend='numpy')
    for backend in BACKENDS:
        if singular(M):
            with pytest.raises(ValueError, match=r"not positive definite .* joint '\w+'"):
                sd.forward_dynamics(model, q[0], qd[0], tau[0], backend=backend)
            continue
        single = np.array([sd.forward_dynamics(model, q[k], qd[k], tau[k], backend=backend)
                           for k in range(len(q))])
        ok, err = agrees(model, q, single, expected)
        assert ok, (backend, err)
        ok, err = agrees(model, q, sd.forward_dynamics(model, q, qd, tau, backend=backend),
                         expected)
        assert ok, (backend, 'batch', err)


def robot(name, base='fixed'):
    """Load a robot of example-robot-data as the library does (mimic joints folded)."""
    from conftest import robot_urdf_path
    return load(robot_urdf_path(name), base=base)


def state(rng, model, shape=()):
    """Return a random ``(q, q̇, q̈)`` of ``model`` (a unit quaternion on a floating base)."""
    if model.floating:
        return random_floating_state(rng, model, shape)
    return tuple(rng.uniform(-s, s, tuple(shape) + (model.nv,)) for s in (1.5, 2.0, 3.0))


def round_trip(model, q, qd, qdd, backend, **terms):
    """Run ``rnea``, then ``forward_dynamics`` with the same terms: q̈ back, τ back from it."""
    tau = sd.rnea(model, q, qd, qdd, backend=backend, **terms)
    back = sd.forward_dynamics(model, q, qd, tau, backend=backend, **terms)
    return tau, back, sd.rnea(model, q, qd, back, backend=backend, **terms)


#: The robots of the round trips: UR5, Panda (its mimic finger folded: the dense solve), the
#: full Talos (44 joints, 12 mimic), Solo12 on a free-flyer.
TRIPS = [('ur5', 'fixed'), ('panda', 'fixed'), ('talos', 'fixed'), ('solo12', 'floating')]


@pytest.mark.parametrize('backend', BACKENDS)
@pytest.mark.parametrize('name,base', TRIPS)
def test_rnea_of_forward_dynamics_is_tau(name, base, backend, rng):
    model = robot(name, base)
    link = model.body_names[-1]
    wrench = {link: rng.uniform(-5.0, 5.0, 6)}
    for shape in ((), (4,), (2, 3)):
        q, qd, qdd = state(rng, model, shape)
        for terms in ({}, {'gravity': (0.3, -2.0, -9.7)}, {'f_ext': wrench},
                      {'f_ext': {link: rng.uniform(-5.0, 5.0, tuple(shape) + (6,))}}):
            tau, back, tau_back = round_trip(model, q, qd, qdd, backend, **terms)
            assert back.shape == qdd.shape
            ok, err = close(tau_back, tau)
            assert ok, (shape, terms, err)
            ok, err = close(back, qdd, 1e-9)      # q̈ itself, to the conditioning of M
            assert ok, (shape, terms, err)


@pytest.mark.parametrize('backend', BACKENDS)
def test_a_moving_base_is_given_and_the_joints_accelerate(backend, rng):
    model = robot('ur5')
    motion = sd.BaseMotion(rng.uniform(-1, 1, (3, 6)), rng.uniform(-2, 2, (3, 6)),
                           [0.1, 0.2, -0.3, 0.927])
    q, qd, qdd = state(rng, model, (3,))
    tau, back, tau_back = round_trip(model, q, qd, qdd, backend, base=motion)
    assert close(tau_back, tau)[0] and close(back, qdd, 1e-9)[0]
    # the base's motion is in the answer: the fixed-base q̈ of the same τ differs
    assert np.abs(sd.forward_dynamics(model, q, qd, tau, backend=backend) - qdd).max() > 1e-3


@pytest.mark.parametrize('backend', BACKENDS)
def test_armature_goes_into_the_mass_matrix(backend, rng):
    model = robot('panda')
    armature = {name: 0.1 * (k + 1) for k, name in enumerate(model.joint_names)}
    A = sd.per_joint(model, 'armature', armature)
    q, qd, qdd = state(rng, model, (5,))
    tau = sd.rnea(model, q, qd, qdd, backend=backend) + sd.armature_torque(A, qdd)
    back = sd.forward_dynamics(model, q, qd, tau, backend=backend, armature=armature)
    ok, err = close(sd.rnea(model, q, qd, back, backend=backend)
                    + sd.armature_torque(A, back), tau)
    assert ok, err
    assert close(back, qdd, 1e-9)[0]
    # Pinocchio's aba with the same model.armature (the Panda's finger mimic stripped there)
    from conftest import PinOracle, robot_urdf_path
    text = strip_mimic(open(robot_urdf_path('panda'), encoding='utf-8').read())
    free = load(text)
    oracle = PinOracle(text)
    arm = np.array([0.1 * (k + 1) for k in range(free.nv)])
    oracle.model.armature[:] = [arm[free.joint_names.index(n)] for n in oracle.joints]
    data = oracle.model.createData()
    q1, qd1, tau1 = state(rng, free)
    a_pin = pin.aba(oracle.model, data, *oracle.expand(free.joint_names, q1, qd1, tau1))
    expected = np.array([a_pin[oracle.joints[n][1]] for n in free.joint_names])
    for b in BACKENDS:
        ok, err = close(sd.forward_dynamics(free, q1, qd1, tau1, backend=b, armature=arm),
                        expected)
        assert ok, (b, err)


@pytest.mark.parametrize('backend', BACKENDS)
def test_hostile_input_is_refused_as_rnea_refuses_it(backend, rng):
    model = robot('ur5')
    floating = robot('solo12', 'floating')
    q, qd, qdd = state(rng, model)
    good = {'model': model, 'q': q, 'qd': qd, 'x': qdd}
    nan = np.full(6, np.nan)
    cases = [
        {'model': None}, {'model': 'ur5.urdf'},
        {'q': q[:5]}, {'q': 'abc'}, {'q': [1, 2, 'x', 4, 5, 6]}, {'q': np.ones((2, 7))},
        {'q': np.array([1 + 2j] * 6)}, {'q': None}, {'q': np.ones((2, 6), dtype=object)},
        {'qd': qd[:4]}, {'qd': {'a': 1}}, {'qd': np.ones((3, 6)), 'q': np.ones((2, 6))},
        {'x': qdd[:3]}, {'x': 'fast'}, {'x': np.ones(7)},
        {'gravity': (0.0, -9.81)}, {'gravity': 'down'},
        {'gravity': [0, 0, None]},
        {'f_ext': {'no_such_link': np.zeros(6)}}, {'f_ext': {'wrist_3_link': np.zeros(5)}},
        {'f_ext': [np.zeros(6)]}, {'f_ext': {'wrist_3_link': 'push'}},
        {'backend': 'gpu'}, {'backend': None},
        {'base': 'moving'}, {'base': sd.BaseMotion(np.zeros((2, 6)), np.zeros((3, 6)))},
        {'model': floating, 'q': np.zeros(floating.nq), 'qd': np.zeros(floating.nv),
         'x': np.zeros(floating.nv)},                      # a zero quaternion
        {'model': floating, 'q': np.r_[0, 0, 0, 0, 0, 0, 2.0, np.zeros(12)],
         'qd': np.zeros(floating.nv), 'x': np.zeros(floating.nv)},
        {'model': floating, 'q': np.r_[0, 0, 0, 0, 0, 0, 1.0, np.zeros(12)],
         'qd': np.zeros(floating.nv), 'x': np.zeros(floating.nv),
         'base': sd.BaseMotion(np.zeros(6), np.zeros(6))},  # a moving base on a floating one
    ]
    for case in cases:
        args = {**good, 'backend': backend, **case}
        model_, q_, qd_, x = (args.pop(k) for k in ('model', 'q', 'qd', 'x'))
        expected = refusal(lambda: sd.rnea(model_, q_, qd_, x, **args))
        assert expected is not None, case
        got = refusal(lambda: sd.forward_dynamics(model_, q_, qd_, x, **args))
        assert got is not None, case
        assert got[0] is expected[0], (case, got, expected)
        assert got[1] == expected[1].replace('qdd', 'tau'), (case, got, expected)
    # NaN in, NaN out, as rnea answers it (not a refusal)
    assert np.isnan(sd.rnea(model, nan, qd, qdd, backend=backend)).all()
    assert np.isnan(sd.forward_dynamics(model, nan, qd, qdd, backend=backend)).all()
    assert np.isnan(sd.forward_dynamics(model, np.tile(nan, (2, 1)), qd, qdd,
                                        backend=backend)).all()
    assert np.isnan(sd.forward_dynamics(model, q, qd, qdd, (np.nan, 0, 0), backend=backend)).all()


MASSLESS = '''<robot name="massless">
  <link name="base"/>
  <link name="arm"><inertial><mass value="2"/><origin xyz="0.5 0 0"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
  <link name="tip"/>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="0 0 1"/><limit effort="10" velocity="1" lower="-3" upper="3"/></joint>
  <joint name="wrist" type="revolute"><parent link="arm"/><child link="tip"/>
    <origin xyz="1 0 0"/><axis xyz="0 0 1"/>
    <limit effort="10" velocity="1" lower="-3" upper="3"/></joint>
</robot>'''


@pytest.mark.parametrize('backend', BACKENDS)
def test_a_joint_that_moves_no_mass_is_named_and_armature_gives_it_one(backend, rng):
    model = load(MASSLESS)
    q, qd, tau = state(rng, model, (3,))
    for x in (q[0], q):
        with pytest.raises(ValueError, match=r"not positive definite at velocity coordinate 1"
                                             r", joint 'wrist'.*give it armature"):
            sd.forward_dynamics(model, x, qd[0], tau[0], backend=backend)
    armature = {'wrist': 0.02}
    qdd = sd.forward_dynamics(model, q, qd, tau, backend=backend, armature=armature)
    A = sd.per_joint(model, 'armature', armature)
    ok, err = close(sd.rnea(model, q, qd, qdd, backend=backend) + sd.armature_torque(A, qdd),
                    tau)
    assert ok, err
    with pytest.raises(ValueError, match=r"armature: joint 'wrist' has the value -1.0"):
        sd.forward_dynamics(model, q, qd, tau, backend=backend, armature={'wrist': -1.0})
    with pytest.raises(ValueError, match=r"armature: unknown joint 'elbow'"):
        sd.forward_dynamics(model, q, qd, tau, backend=backend, armature={'elbow': 1.0})


MASSLESS_ROOT = '''<robot name="massless_root">
  <link name="body"/>
  <link name="rotor"><inertial><mass value="1"/><origin xyz="0 0 0"/>
    <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
  <joint name="spin" type="revolute"><parent link="body"/><child link="rotor"/>
    <axis xyz="0 0 1"/><limit effort="10" velocity="1" lower="-3" upper="3"/></joint>
</robot>'''
REPEATED = MASSLESS.replace('<link name="arm"><inertial><mass value="2"/>',
                            '<link name="arm"><inertial><mass value="0"/>').replace(
    '<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/>',
    '<inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/>').replace(
    '<link name="tip"/>', '<link name="tip"><inertial><mass value="1"/><origin xyz="0.2 0 0"/>'
    '<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>'
).replace('<origin xyz="1 0 0"/><axis', '<origin xyz="0 0 0.1"/><axis')


@pytest.mark.parametrize('backend', BACKENDS)
def test_a_singular_M_is_explained_with_advice_the_library_takes(backend):
    """The advice of the error, followed, gives ``q̈``; armature is never advised for the base.

    A massless root link whose yaw the joint ``spin`` repeats: give ``spin`` armature (or the
    root link mass). A massless free body: its link needs an <inertial>. A massless ``arm``
    whose ``shoulder`` motion ``wrist`` repeats (one axis, the mass beyond ``wrist``).
    """
    model = load(MASSLESS_ROOT, base='floating')
    q = np.zeros(model.nq)
    q[6] = 1.0
    v, tau = np.zeros(model.nv), np.ones(model.nv)
    with pytest.raises(ValueError) as err:
        sd.forward_dynamics(model, q, v, tau, backend=backend)
    message = str(err.value)
    assert "give 'spin' armature, or the root link an <inertial>" in message, message
    assert "'body'" in message and 'give it armature' not in message, message
    qdd = sd.forward_dynamics(model, q, v, tau, backend=backend, armature={'spin': 0.1})
    A = sd.per_joint(model, 'armature', {'spin': 0.1})
    ok, error = close(sd.rnea(model, q, v, qdd) + sd.armature_torque(A, qdd), tau)
    assert ok, error

    box = load('<robot name="b"><link name="b"/></robot>', base='floating')
    with pytest.raises(ValueError, match=r"root link 'b' .*needs an <inertial>") as err:
        sd.forward_dynamics(box, [0, 0, 0, 0, 0, 0, 1], np.zeros(6), np.zeros(6),
                            backend=backend)
    assert 'give it armature' not in str(err.value)

    arm = load(REPEATED)
    q, qd, tau = np.array([0.3, -0.2]), np.array([0.1, 0.2]), np.array([1.0, 0.5])
    with pytest.raises(ValueError, match=r"joint 'shoulder': the joint moves no mass that the "
                                         r"joint\(s\) 'wrist' do not move too.*give it or "
                                         r"'wrist' armature"):
        sd.forward_dynamics(arm, q, qd, tau, backend=backend)
    for joint in ('shoulder', 'wrist'):
        qdd = sd.forward_dynamics(arm, q, qd, tau, backend=backend, armature={joint: 0.1})
        A = sd.per_joint(arm, 'armature', {joint: 0.1})
        ok, error = close(sd.rnea(arm, q, qd, qdd) + sd.armature_torque(A, qdd), tau)
        assert ok, (joint, error)


def test_backends_dtypes_and_single_states_agree(rng):
    model = robot('talos', 'fixed')
    q, qd, tau = state(rng, model, (6,))
    compiled = sd.forward_dynamics(model, q, qd, tau, backend='compiled')
    numpy = sd.forward_dynamics(model, q, qd, tau, backend='numpy')
    assert close(compiled, numpy)[0]
    # one state in C equals the same state of a batch on threads, bit for bit
    for k in range(len(q)):
        assert np.array_equal(sd.forward_dynamics(model, q[k], qd[k], tau[k]), compiled[k])
        assert np.array_equal(sd.forward_dynamics(model, list(q[k]), tuple(qd[k]), tau[k]),
                              compiled[k])
    for backend in BACKENDS:
        out = sd.forward_dynamics(model, q.astype(np.float32), qd.astype(np.float32),
                                  tau.astype(np.float32), backend=backend)
        assert out.dtype == np.float32
        assert np.allclose(out, compiled, rtol=1e-3, atol=1e-3 * np.abs(compiled).max())
    long = sd.forward_dynamics(model, *(x[:2].astype(np.longdouble) for x in (q, qd, tau)))
    assert long.dtype == np.longdouble and close(long.astype(float), compiled[:2])[0]
