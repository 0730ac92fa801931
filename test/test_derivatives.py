# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""``rnea_derivatives``: ``∂τ/∂q``, ``∂τ/∂q̇`` and ``M`` against Pinocchio, mpmath and physics.

Pinocchio's ``computeRNEADerivatives`` on every robot of example-robot-data, fixed base and
free-flyer (mimic joints independent in Pinocchio, folded with the velocity map ``P``: ours
is ``Pᵀ D_pin P``; its free-flyer rows and columns are linear first, which ``P`` swaps);
a 50-digit mpmath derivative of the library's own RNEA in mpmath; identities (gravity only:
``∂τ/∂q̇ = 0`` and ``∂τ/∂q`` the symmetric Hessian of the potential energy); ``M`` is
``mass_matrix``; the backends agree; every argument ``rnea`` refuses is refused the same way.
"""

import os

from conftest import PinOracle, random_state, robot_urdf_path
import numpy as np
import pytest
import spatial_dynamics as sd
from spatial_dynamics.backends import layout, python
from test_core_floating_base import (FLOATING, FloatingOracle, load, path_of,
                                     random_floating_state)
from test_urdf_robot_sweep import BASE, FILES, pinocchio_text, REFUSED

pin = pytest.importorskip('pinocchio')

RTOL = 1e-12    # normwise, relative to max(1, |expected|)
FIXED = [f for f in FILES if f not in REFUSED]


def close(value, expected, rtol=RTOL):
    """Normwise relative error within ``rtol``; returns (ok, error) for the message."""
    err = np.linalg.norm(np.asarray(value) - expected)
    return err <= rtol * max(1.0, np.linalg.norm(expected)), err


def pinocchio_derivatives(oracle, q_pin, v_pin, a_pin, P, fext=None):
    """Return Pinocchio's ``(∂τ/∂q, ∂τ/∂q̇, M)`` in our coordinates (``Pᵀ D P``)."""
    args = (oracle.model, oracle.data, q_pin, v_pin, a_pin) + ((fext,) if fext else ())
    pin.computeRNEADerivatives(*args)
    M = np.triu(oracle.data.M) + np.triu(oracle.data.M, 1).T
    return tuple(P.T @ D @ P for D in (oracle.data.dtau_dq, oracle.data.dtau_dv, M))


@pytest.mark.parametrize('name', FIXED)
def test_fixed_base_equals_pinocchio_on_every_robot(name, rng):
    """Every URDF of example-robot-data on a fixed base, one state, both backends."""
    path = os.path.join(BASE, name)
    model, _ = load(path)
    if model.nv == 0:
        return
    oracle = PinOracle(pinocchio_text(path))
    q, qd, qdd = random_state(rng, (), model.nq)
    q_pin, P = oracle.velocity_map(model.joint_names, q)
    _, v_pin, a_pin = oracle.expand(model.joint_names, q, qd, qdd)
    oracle.set_gravity(sd.GRAVITY)
    expected = pinocchio_derivatives(oracle, q_pin, v_pin, a_pin, P)
    for backend in ('numpy', 'compiled'):
        ours = sd.rnea_derivatives(model, q, qd, qdd, backend=backend)
        for what, value, want in zip(('dq', 'dv', 'M'), ours, expected):
            ok, err = close(value, want)
            assert ok, (backend, what, err)


@pytest.mark.parametrize('name', FLOATING)
def test_free_flyer_equals_pinocchio_on_every_robot(name, rng):
    """Every robot that walks, flies or drives on a free-flyer: the tangent-space ``∂τ/∂q``."""
    path = path_of(name)
    model, _ = load(path, base='floating')
    oracle = FloatingOracle(pinocchio_text(path))
    q, v, a = random_floating_state(rng, model)
    q_pin, v_pin, a_pin = oracle.expand(model.joint_names, q, v, a)
    P = oracle.velocity_map(model.joint_names, q)
    oracle.model.gravity.linear = np.array(sd.GRAVITY)
    expected = pinocchio_derivatives(oracle, q_pin, v_pin, a_pin, P)
    for backend in ('numpy', 'compiled'):
        ours = sd.rnea_derivatives(model, q, v, a, backend=backend)
        for what, value, want in zip(('dq', 'dv', 'M'), ours, expected):
            ok, err = close(value, want)
            assert ok, (backend, what, err)


#: Two chains on the world (two roots: body 1's columns are taken at once, the other root's
#: one by one): one on a prismatic joint along no frame axis, the other on a revolute joint
#: about no frame axis that mimics a joint of the first chain.
_LINK = ('<link name="{0}"><inertial><origin xyz="{1}" rpy="{2}"/><mass value="{3}"/>'
         '<inertia ixx="0.05" ixy="0.004" ixz="-0.003" iyy="0.07" iyz="0.002" izz="0.06"/>'
         '</inertial></link>')
_JOINT = ('<joint name="{0}" type="{1}"><parent link="{2}"/><child link="{3}"/>'
          '<origin xyz="{4}" rpy="{5}"/><axis xyz="{6}"/>{7}'
          '<limit lower="-3" upper="3" effort="50" velocity="5"/></joint>')
TWO_ROOTS = ('<robot name="two_roots"><link name="world"/>'
             + _LINK.format('cart', '0.1 0.02 -0.03', '0.1 0.2 0.3', 2.0)
             + _LINK.format('pole', '0 0.05 0.3', '0 0 0', 0.7)
             + _LINK.format('a1', '0.2 -0.1 0.05', '0.3 0 0.1', 1.3)
             + _LINK.format('a2', '0.15 0 0', '0 0.2 0', 0.9)
             + _JOINT.format('rail', 'prismatic', 'world', 'cart', '0.3 -0.2 0.5',
                             '0.2 -0.1 0.4', '0.6 0 0.8', '')
             + _JOINT.format('pole', 'revolute', 'cart', 'pole', '0 0.1 0.2', '0.3 0 0',
                             '0 1 0', '')
             + _JOINT.format('arm1', 'revolute', 'world', 'a1', '-0.4 0.3 0.1', '0 0.5 -0.2',
                             '0.48 0.6 0.64',
                             '<mimic joint="pole" multiplier="-0.5" offset="0.1"/>')
             + _JOINT.format('arm2', 'revolute', 'a1', 'a2', '0.2 0 0.3', '0 0 0', '1 0 0', '')
             + '</robot>')


def test_two_roots_a_prismatic_root_and_a_mimic_root_equal_pinocchio(tmp_path, rng):
    """Body 1's columns at once and another root's one by one: Pinocchio's, both backends."""
    path = tmp_path / 'two_roots.urdf'
    path.write_text(TWO_ROOTS, encoding='utf-8')
    model, _ = load(str(path))
    assert model.nv == 3 and sum(1 for p in model.parent[1:] if p == 0) == 2
    oracle = PinOracle(TWO_ROOTS)
    oracle.set_gravity((0.3, -1.2, -9.81))
    for _ in range(3):
        q, qd, qdd = random_state(rng, (), model.nq)
        q_pin, P = oracle.velocity_map(model.joint_names, q)
        _, v_pin, a_pin = oracle.expand(model.joint_names, q, qd, qdd)
        expected = pinocchio_derivatives(oracle, q_pin, v_pin, a_pin, P)
        for backend in ('numpy', 'compiled'):
            ours = sd.rnea_derivatives(model, q, qd, qdd, (0.3, -1.2, -9.81), backend=backend)
            for what, value, want in zip(('dq', 'dv', 'M'), ours, expected):
                ok, err = close(value, want)
                assert ok, (backend, what, err)


def test_the_free_flyer_columns_are_the_tangent_of_integrate(rng):
    """``τ(q ⊕ δ) − τ(q ⊖ δ) ≈ 2 ∂τ/∂q δ`` with ``⊕`` as ``sd.integrate`` moves ``q``."""
    model, _ = load(path_of('solo_description/robots/solo12.urdf'), base='floating')
    q, v, a = random_floating_state(rng, model)
    dq, _, _ = sd.rnea_derivatives(model, q, v, a)
    h = 1e-6
    for k in range(model.nv):
        e = np.zeros(model.nv)
        e[k] = h
        diff = (sd.rnea(model, sd.integrate(model, q, e, 1.0), v, a)
                - sd.rnea(model, sd.integrate(model, q, -e, 1.0), v, a)) / (2 * h)
        ok, err = close(dq[:, k], diff, 1e-6)
        assert ok, (k, err)


@pytest.mark.parametrize('robot', ['ur5', 'talos', 'solo12'])
def test_gravity_external_forces_and_batches_equal_pinocchio(robot, rng):
    """Another gravity, wrenches on links (Pinocchio's ``fext``) and a batch, both backends."""
    path = robot_urdf_path(robot)
    model = sd.Model.from_urdf(path)
    oracle = PinOracle(pinocchio_text(path))
    links = [link for link in model.frames if model.frames[link].body > 0][-2:]
    f_ext = {link: rng.normal(size=6) for link in links}
    gravity = (1.0, -2.0, -9.0)
    oracle.set_gravity(gravity)
    q, qd, qdd = random_state(rng, (4,), model.nq)
    for backend in ('numpy', 'compiled'):
        batch = sd.rnea_derivatives(model, q, qd, qdd, gravity, f_ext, backend=backend)
        assert all(x.shape == (4, model.nv, model.nv) for x in batch)
        for s in range(4):
            q_pin, P = oracle.velocity_map(model.joint_names, q[s])
            _, v_pin, a_pin = oracle.expand(model.joint_names, q[s], qd[s], qdd[s])
            expected = pinocchio_derivatives(oracle, q_pin, v_pin, a_pin, P,
                                             oracle.fext(f_ext))
            for what, value, want in zip(('dq', 'dv', 'M'), batch, expected):
                ok, err = close(value[s], want)
                assert ok, (backend, s, what, err)


@pytest.mark.parametrize('robot', ['ur5', 'panda'])
def test_equal_to_a_50_digit_derivative_of_the_mpmath_rnea(robot, rng):
    """The float64 result against central differences of our RNEA in 50-digit mpmath.

    With ``h = 1e-20`` at 50 digits the difference quotient is exact to ~1e-30: the
    reference. Panda carries a mimic finger (one coordinate driving two bodies).
    """
    mpmath = pytest.importorskip('mpmath')
    model = sd.Model.from_urdf(robot_urdf_path(robot))
    rows = layout.of(model).rows
    q, qd, qdd = random_state(rng, (), model.nq)
    ours = sd.rnea_derivatives(model, q, qd, qdd)
    with mpmath.workdps(50):
        mq, mqd, mqdd = ([mpmath.mpf(float(x)) for x in v] for v in (q, qd, qdd))
        g = [mpmath.mpf(x) for x in sd.GRAVITY]
        h = mpmath.mpf('1e-20')

        def column(k, which):
            up = [list(mq), list(mqd), list(mqdd)]
            down = [list(mq), list(mqd), list(mqdd)]
            up[which][k] += h
            down[which][k] -= h
            tau_up = python.rnea_rows(rows, *up, g, m=mpmath)
            tau_down = python.rnea_rows(rows, *down, g, m=mpmath)
            return [float((u - d) / (2 * h)) for u, d in zip(tau_up, tau_down)]

        for which, value in enumerate(ours):
            reference = np.array([column(k, which) for k in range(model.nv)]).T
            ok, err = close(value, reference)
            assert ok, (which, err)


@pytest.mark.parametrize('robot', ['ur5', 'talos'])
def test_gravity_only_velocity_derivative_is_zero_and_position_one_the_energy_hessian(robot,
                                                                                      rng):
    """At rest ``∂τ/∂q̇ = 0`` and ``∂τ/∂q = ∂g/∂q = ∂²V/∂q²``: symmetric, as Pinocchio's V."""
    path = robot_urdf_path(robot)
    model = sd.Model.from_urdf(path)
    oracle = PinOracle(pinocchio_text(path))
    q, _, _ = random_state(rng, (), model.nq)
    zero = np.zeros(model.nv)
    dq, dv, M = sd.rnea_derivatives(model, q, zero, zero)
    assert np.all(dv == 0.0)
    ok, err = close(dq, dq.T)
    assert ok, err
    # Hessian of Pinocchio's potential energy by central differences (h² ~ 1e-8)
    h = 1e-4
    hessian = np.empty((model.nv, model.nv))
    for i in range(model.nv):
        for j in range(model.nv):
            def V(a, b):
                x = q.copy()
                x[i] += a
                x[j] += b
                return oracle.potential_energy(model.joint_names, x)
            hessian[i, j] = (V(h, h) - V(h, -h) - V(-h, h) + V(-h, -h)) / (4 * h * h)
    ok, err = close(dq, hessian, 1e-5)
    assert ok, err
    ok, err = close(M, sd.mass_matrix(model, q))     # world coordinates: equal to rounding
    assert ok, err


@pytest.mark.parametrize('robot', ['panda', 'solo12'])
def test_M_is_mass_matrix_and_the_backends_agree(robot, rng):
    """``∂τ/∂q̈`` is ``mass_matrix``; numpy and compiled to a few ulps, batches state by state."""
    model = sd.Model.from_urdf(robot_urdf_path(robot))
    q, qd, qdd = random_state(rng, (5,), model.nq)
    compiled = sd.rnea_derivatives(model, q, qd, qdd, backend='compiled')
    numpy = sd.rnea_derivatives(model, q, qd, qdd, backend='numpy')
    for c, n in zip(compiled, numpy):
        assert np.abs(c - n).max() <= 8 * np.finfo(float).eps * np.abs(n).max()
    for s in range(5):
        ok, err = close(compiled[2][s], sd.mass_matrix(model, q[s]))
        assert ok, err
    for s in range(5):
        one = sd.rnea_derivatives(model, q[s], qd[s], qdd[s])
        for b, o in zip(compiled, one):
            assert np.array_equal(b[s], o)
    single = sd.rnea_derivatives(model, list(q[0]), tuple(qd[0]), qdd[0].astype(np.float32))
    assert all(x.dtype == np.float64 for x in single)


def _relative_change(value, reference):
    return np.abs(value - reference).max() / np.abs(reference).max()


def test_nothing_depends_on_how_far_the_free_flyer_is_from_the_world_origin(rng):
    """Translating the whole robot changes no torque: the three matrices are those at 0.

    Solo12 on a free-flyer at the world origin and 1 km, 5000 km (map coordinates), 1e9 m,
    1e300 m from it: one state and a batch, both backends; ``M`` is ``mass_matrix`` there.
    """
    model = sd.Model.from_urdf(path_of('solo_description/robots/solo12.urdf'), base='floating')
    q, qd, qdd = random_floating_state(rng, model)
    q[0:3] = 0.0
    far = (0.0, 1e3, 5e6, 1e9, 1e300)
    qs = np.repeat(q[None], len(far), axis=0)
    qs[:, 0:3] = np.array(far)[:, None] * [1.0, -1.0, 0.5]
    for backend in ('numpy', 'compiled'):
        at_origin = sd.rnea_derivatives(model, q, qd, qdd, backend=backend)
        batch = sd.rnea_derivatives(model, qs, np.repeat(qd[None], len(far), 0),
                                    np.repeat(qdd[None], len(far), 0), backend=backend)
        for s, distance in enumerate(far):
            one = sd.rnea_derivatives(model, qs[s], qd, qdd, backend=backend)
            for what, o, b, ref in zip(('dq', 'dv', 'M'), one, batch, at_origin):
                assert _relative_change(o, ref) <= RTOL, (backend, distance, what)
                assert _relative_change(b[s], ref) <= RTOL, (backend, distance, what, 'batch')
            ok, err = close(one[2], sd.mass_matrix(model, qs[s]))
            assert ok, (backend, distance, err)


def test_nothing_depends_on_how_far_a_fixed_base_is_mounted_from_the_urdf_root():
    """Panda mounted 1 km ... 1e7 m from a root link: the matrices of the arm at the root."""
    text = open(robot_urdf_path('panda'), encoding='utf-8').read()

    def mounted(d):
        mount = (f'<link name="far_root"/><joint name="far_mount" type="fixed"><parent '
                 f'link="far_root"/><child link="panda_link0"/><origin xyz="{d!r} {d!r} 0" '
                 'rpy="0 0 0.3"/></joint>')
        return sd.Model.from_urdf(text.replace('<link name="panda_link0">',
                                               mount + '<link name="panda_link0">', 1))

    base = mounted(0.0)
    rng = np.random.default_rng(7)
    q, qd, qdd = random_state(rng, (3,), base.nq)
    for backend in ('numpy', 'compiled'):
        at_root = sd.rnea_derivatives(base, q, qd, qdd, backend=backend)
        for d in (1e3, 5e6, 1e7):
            model = mounted(d)
            batch = sd.rnea_derivatives(model, q, qd, qdd, backend=backend)
            one = sd.rnea_derivatives(model, q[1], qd[1], qdd[1], backend=backend)
            for what, b, o, ref in zip(('dq', 'dv', 'M'), batch, one, at_root):
                assert _relative_change(b, ref) <= RTOL, (backend, d, what)
                assert _relative_change(o, ref[1]) <= RTOL, (backend, d, what, 'one')
            ok, err = close(one[2], sd.mass_matrix(model, q[1]))
            assert ok, (backend, d, err)


def test_one_state_gives_three_arrays_of_their_own(rng):
    """One state's ``(∂τ/∂q, ∂τ/∂q̇, M)``: three arrays, none a view keeping the others alive.

    float64 and float32 states (float32: the float64 results rounded once), equal to the
    same state in a batch.
    """
    model = sd.Model.from_urdf(robot_urdf_path('panda'))
    q, qd, qdd = random_state(rng, (), model.nq)
    batch = sd.rnea_derivatives(model, q[None], qd[None], qdd[None])
    for dtype in (np.float64, np.float32):
        one = sd.rnea_derivatives(model, *(x.astype(dtype) for x in (q, qd, qdd)))
        assert isinstance(one, tuple) and len(one) == 3
        for x, b in zip(one, batch):
            assert x.shape == (model.nv, model.nv) and x.dtype == dtype
            assert x.flags.owndata and x.flags.c_contiguous, 'a view of a stacked array'
        wide = batch if dtype == np.float64 else sd.rnea_derivatives(
            model, *(x.astype(dtype).astype(np.float64)[None] for x in (q, qd, qdd)))
        for x, w in zip(one, wide):
            assert np.array_equal(x, w[0].astype(dtype))


@pytest.mark.parametrize('robot', ['panda', 'solo12'])
def test_a_batch_is_each_state_alone_bit_for_bit(robot, rng):
    """A batch (several states at once in SIMD lanes, and threads) is each state's single call.

    Sizes around the lanes (2, 4, 8 states) and a chunk of the threads; states at rest among
    moving ones; wrenches shared and per state; a floating base (Solo12) with its quaternion.
    """
    floating = robot == 'solo12'
    path = path_of('solo_description/robots/solo12.urdf') if floating else robot_urdf_path(robot)
    model = sd.Model.from_urdf(path, **({'base': 'floating'} if floating else {}))
    # a link offset from its body where there is one (its wrench is moved to the body term by
    # term, in the same order for a batch as for one state)
    moving = [(np.array_equal(frame.lXb, np.eye(6)), name) for name, frame in
              model.frames.items() if frame.body > 1]
    link = min(moving)[1]
    for N in (1, 3, 7, 9, 17, 300):
        if floating:
            q, qd, qdd = zip(*(random_floating_state(rng, model) for _ in range(N)))
            q, qd, qdd = np.array(q), np.array(qd), np.array(qdd)
        else:
            q, qd, qdd = random_state(rng, (N,), model.nq)
        qd[::3] = 0.0
        for f_ext in (None, {link: rng.normal(size=6)}, {link: rng.normal(size=(N, 6))}):
            batch = sd.rnea_derivatives(model, q, qd, qdd, (0.5, -1.0, -9.0), f_ext)
            for s in range(N):
                one = {} if f_ext is None else {link: np.broadcast_to(f_ext[link], (N, 6))[s]}
                alone = sd.rnea_derivatives(model, q[s], qd[s], qdd[s], (0.5, -1.0, -9.0),
                                            one or None)
                for b, o in zip(batch, alone):
                    assert np.array_equal(b[s], o), (N, s, f_ext is None)


def test_a_batch_over_threads_is_each_state_alone_bit_for_bit(rng):
    """A batch on 1, 2, 3 and 7 threads (a block of its states each) is each state's call.

    Thousands of states (each thread takes 4096 body-states at least), a count that is no
    multiple of the lanes or of a thread's chunk, and an odd ``nv`` (``nv²`` numbers a
    state each: the four lanes' results are transposed four numbers at a time, the rest one
    by one); ``∂τ/∂q``, ``∂τ/∂q̇``, ``M`` bit for bit those of the single-state calls.
    """
    from spatial_dynamics.backends import compiled
    from urdf_gen import random_tree_urdf
    if compiled.ext is None:
        pytest.skip('the batch entry is C')
    model = sd.Model.from_urdf(random_tree_urdf(np.random.default_rng(11), 7, branching=True))
    lay = layout.of(model)
    assert model.nv % 2 == 1
    N = 7 * compiled.ext.MIN_WORK // lay.table.shape[0] + 13
    q, qd, qdd = random_state(rng, (N,), model.nq)
    qd[::5] = 0.0
    g = (0.5, -1.0, -9.0)
    alone = np.array([np.stack(sd.rnea_derivatives(model, q[s], qd[s], qdd[s], g))
                      for s in range(N)])
    for threads in (1, 2, 3, 7):
        D = np.full((3, N, model.nv, model.nv), np.nan)
        compiled.ext.derivatives_batch(lay.kernels, N, q, qd, qdd, g, None, *D, threads)
        np.testing.assert_array_equal(D.transpose(1, 0, 2, 3).view(np.int64),
                                      alone.view(np.int64), err_msg=threads)


def test_a_moving_base_differentiates_the_joint_rows(rng):
    """On a moving base: the joint block, by central differences of ``rnea(base=)``."""
    model = sd.Model.from_urdf(robot_urdf_path('ur5'))
    base = sd.BaseMotion(v=rng.normal(size=6), a=rng.normal(size=6),
                         orientation=np.array([0.1, -0.2, 0.3, 0.9]) / np.linalg.norm(
                             [0.1, -0.2, 0.3, 0.9]))
    q, qd, qdd = random_state(rng, (), model.nq)
    dq, dv, M = sd.rnea_derivatives(model, q, qd, qdd, base=base)
    h = 1e-6
    for k, (x, D) in enumerate(((q, dq), (qd, dv), (qdd, M))):
        for c in range(model.nv):
            e = np.zeros(model.nv)
            e[c] = h
            args_up, args_down = [q, qd, qdd], [q, qd, qdd]
            args_up[k], args_down[k] = x + e, x - e
            diff = (sd.rnea(model, *args_up, base=base)
                    - sd.rnea(model, *args_down, base=base)) / (2 * h)
            ok, err = close(D[:, c], diff, 1e-6)
            assert ok, (k, c, err)
    ok, err = close(M, sd.mass_matrix(model, q))
    assert ok, err


def test_the_drive_terms_add_armature_to_M_and_friction_to_the_velocity_derivative(rng):
    """``armature`` adds ``diag`` to ``M``; ``friction_threshold`` adds ``∂/∂q̇`` of friction."""
    urdf = open(robot_urdf_path('ur5'), encoding='utf-8').read().replace(
        '<dynamics damping="0.0" friction="0.0"/>', '<dynamics damping="0.5" friction="2.0"/>')
    model = sd.Model.from_urdf(urdf)
    assert np.any(model.body_friction > 0.0)
    q, qd, qdd = random_state(rng, (), model.nq)
    dq0, dv0, M0 = sd.rnea_derivatives(model, q, qd, qdd)
    armature = np.linspace(0.1, 0.6, model.nv)
    dq, dv, M = sd.rnea_derivatives(model, q, qd, qdd, armature=armature,
                                    friction_threshold=0.05)
    assert np.array_equal(dq, dq0)
    assert np.array_equal(M, M0 + np.diag(armature))
    h = 1e-7
    slope = np.array([(sd.friction_torque(model, qd + h * e, 0.05)
                       - sd.friction_torque(model, qd - h * e, 0.05)) / (2 * h)
                      for e in np.eye(model.nv)]).T
    ok, err = close(dv - dv0, slope, 1e-6)
    assert ok, err


def test_the_drive_terms_keep_the_states_dtype(rng):
    """float32 states: with ``armature`` and ``friction_threshold`` all three are float32.

    As gravity and wrenches leave them (and ``forward_dynamics``): the float64 terms are
    rounded once into the states' dtype, equal to the float64 call to float32's precision.
    """
    urdf = open(robot_urdf_path('ur5'), encoding='utf-8').read().replace(
        '<dynamics damping="0.0" friction="0.0"/>', '<dynamics damping="0.5" friction="2.0"/>')
    model = sd.Model.from_urdf(urdf)
    state = random_state(rng, (), model.nq)
    narrow = [x.astype(np.float32) for x in state]
    wide = [x.astype(np.float64) for x in narrow]
    for terms in ({'armature': 0.1}, {'armature': np.float32(0.1)},
                  {'friction_threshold': 0.05}, {'friction_threshold': np.float32(0.05)},
                  {'armature': np.linspace(0.1, 0.6, model.nv), 'friction_threshold': 0.05}):
        for backend in ('numpy', 'compiled'):
            out = sd.rnea_derivatives(model, *narrow, backend=backend, **terms)
            ref = sd.rnea_derivatives(model, *wide, backend=backend, **terms)
            for what, x, r in zip(('dq', 'dv', 'M'), out, ref):
                assert x.dtype == np.float32, (terms, backend, what, x.dtype)
                assert np.allclose(x, r, rtol=1e-5, atol=1e-5 * np.abs(r).max()), (terms, what)
            if 'armature' in terms:
                qdd = sd.forward_dynamics(model, *narrow, backend=backend,
                                          armature=terms['armature'])
                assert qdd.dtype == np.float32


def test_bad_drive_term_arguments_are_named_wherever_they_are_taken():
    """A string, a complex number or a vector where one real number belongs: the name, said.

    ``armature`` in ``rnea_derivatives``, ``forward_dynamics`` and ``per_joint`` (scalar,
    list, map), ``friction_threshold`` in ``rnea_derivatives``, and ``threshold`` in
    ``friction_torque`` and ``friction_derivative``: ``TypeError`` or ``ValueError`` with the
    argument's name, never a value made of text.
    """
    model = sd.Model.from_urdf(robot_urdf_path('ur5'))
    n, joint = model.nv, model.joint_names[0]
    z = np.full(n, 0.2)
    for bad in ('0.1', 0.1 + 0j, np.complex128(0.1), ['0.1'] * n, [0.1 + 0j] * n,
                {joint: '0.1'}, {joint: 0.1 + 0j}, {joint: [0.1, 0.2]}, object()):
        calls = {'rnea_derivatives': lambda: sd.rnea_derivatives(model, z, z, z, armature=bad),
                 'forward_dynamics': lambda: sd.forward_dynamics(model, z, z, z, armature=bad),
                 'per_joint': lambda: sd.per_joint(model, 'armature', bad)}
        for where, call in calls.items():
            with pytest.raises((TypeError, ValueError), match='armature') as err:
                call()
            assert 'unexpected' not in str(err.value), (where, bad)
    for bad in ('0.01', 0.01 + 0j, np.full(n, 0.01), [0.01], object()):
        with pytest.raises((TypeError, ValueError), match='friction_threshold'):
            sd.rnea_derivatives(model, z, z, z, friction_threshold=bad)
        for term in (sd.friction_torque, sd.friction_derivative):
            with pytest.raises((TypeError, ValueError), match='threshold'):
                term(model, z, bad)
    # good input is kept: numbers of any real dtype, a 0-d array
    ok = sd.rnea_derivatives(model, z, z, z, armature={joint: np.float32(0.1)},
                             friction_threshold=np.array(0.01))
    assert ok[2][0, 0] == sd.rnea_derivatives(model, z, z, z)[2][0, 0] + np.float32(0.1)


def _raised(call):
    try:
        call()
    except Exception as err:        # the class and the message, compared between functions
        return type(err), str(err)
    return None


def _hostile(model, good_q):
    nq, nv = model.nq, model.nv
    z = np.zeros(nv)
    return [
        ((good_q[:-1], z, z), {}), ((good_q, z[:-1], z), {}), ((good_q, z, np.zeros(nv + 1)), {}),
        (('abc', z, z), {}), ((None, z, z), {}), ((good_q + 0j, z, z), {}),
        ((good_q, z, [[1.0, 2.0], [3.0]]), {}), ((np.zeros((2, nq + 1)), z, z), {}),
        ((good_q, z, z), {'gravity': (0.0, 9.81)}), ((good_q, z, z), {'gravity': 'down'}),
        ((good_q, z, z), {'f_ext': {'no_such_link': np.zeros(6)}}),
        ((good_q, z, z), {'f_ext': [np.zeros(6)]}),
        ((good_q, z, z), {'f_ext': {model.body_names[-1]: np.zeros(5)}}),
        ((good_q, z, z), {'backend': 'gpu'}), ((good_q, z, z), {'base': 'moving'}),
    ]


@pytest.mark.parametrize('robot', ['ur5', 'solo12'])
def test_every_argument_rnea_refuses_is_refused_the_same_way(robot):
    """The same class and message as ``sd.rnea``, fixed and floating; zero quaternions too."""
    floating = robot == 'solo12'
    model = sd.Model.from_urdf(robot_urdf_path(robot), base='floating' if floating else 'fixed')
    q = np.zeros(model.nq)
    if floating:
        q[6] = 1.0
    cases = _hostile(model, q)
    if floating:
        for quat in ((0.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 2.0), (np.nan, 0.0, 0.0, 1.0)):
            bad = q.copy()
            bad[3:7] = quat
            z = np.zeros(model.nv)
            cases += [((bad, z, z), {}), ((np.stack([q, bad]), z, z), {})]
        # a moving base of a model that floats already
        cases += [((q, np.zeros(model.nv), np.zeros(model.nv)),
                   {'base': sd.BaseMotion(v=np.zeros(6), a=np.zeros(6))})]
    cases.append(((q, np.zeros(model.nv), np.zeros(model.nv)), {'model': None}))
    for args, kwargs in cases:
        kwargs = dict(kwargs)
        m = kwargs.pop('model', model)
        expected = _raised(lambda: sd.rnea(m, *args, **kwargs))
        assert expected is not None, (args, kwargs)
        assert _raised(lambda: sd.rnea_derivatives(m, *args, **kwargs)) == expected


def test_nan_propagates_as_in_rnea():
    """A NaN state is not refused by ``rnea`` (it returns NaN): the derivatives are NaN too."""
    model = sd.Model.from_urdf(robot_urdf_path('ur5'))
    q = np.zeros(model.nq)
    q[2] = np.nan
    z = np.zeros(model.nv)
    assert np.isnan(sd.rnea(model, q, z, z)).any()
    dq, _, _ = sd.rnea_derivatives(model, q, z, z)
    assert np.isnan(dq).any()
