# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Inputs at the edge of what the dynamics functions take, the same on every path.

``sd.rnea``, ``sd.rnea_derivatives``, ``sd.forward_dynamics``, ``sd.gravity_torque``,
``sd.bias_torque``, ``sd.mass_matrix``: one state and batches, ``backend='numpy'`` and the
compiled kernels. A batch row is the same state alone, to the bit, with per-state wrenches on
links offset from their body (Talos' soles and wrist sensors); infinite numbers give NaN as NaN
does; numbers as text are refused on every path; the dtype rule holds for float16; per-joint
terms refuse booleans.
"""

from decimal import Decimal
import functools
import warnings

from conftest import PinOracle, random_state, refusal, robot_urdf_path
import numpy as np
import pytest
import spatial_dynamics as sd

BACKENDS = ('numpy', 'compiled')


@functools.lru_cache(maxsize=None)
def robot(name):
    """Return the Model of an example-robot-data robot, built once per session."""
    return sd.Model.from_urdf(robot_urdf_path(name))


def offset_links(model):
    """Links of a moving body whose frame is not the body's (fixed joints merged into it)."""
    return [name for name, frame in model.frames.items()
            if frame.body != 0 and not np.allclose(frame.lXb, np.eye(6))]


# A per-state wrench on a link offset from its body: a batch row is the state alone

@pytest.mark.parametrize('backend', BACKENDS)
@pytest.mark.parametrize('name', ['talos', 'panda'])
def test_a_batch_row_with_wrenches_on_offset_links_is_the_state_alone(name, backend, rng):
    model = robot(name)
    links = offset_links(model)
    assert len(links) >= 3, links        # soles, wrist sensors, the hand's TCP
    N = 40
    q, qd, qdd = random_state(rng, (N,), model.nv)
    for link in links[:4]:
        f = rng.normal(0.0, 10.0, (N, 6))
        tau = sd.rnea(model, q, qd, qdd, f_ext={link: f}, backend=backend)
        D = sd.rnea_derivatives(model, q, qd, qdd, f_ext={link: f}, backend=backend)
        for s in range(N):
            one = {link: f[s]}
            assert np.array_equal(tau[s], sd.rnea(model, q[s], qd[s], qdd[s], f_ext=one,
                                                  backend=backend)), (link, s)
            alone = sd.rnea_derivatives(model, q[s], qd[s], qdd[s], f_ext=one, backend=backend)
            for d, a in zip(D, alone):
                assert np.array_equal(d[s], a), (link, s)
        if backend == 'compiled':
            # (the numpy backend solves a batch with LAPACK's Cholesky: equal to rounding)
            qdd_fd = sd.forward_dynamics(model, q, qd, tau, f_ext={link: f}, backend=backend)
            for s in range(N):
                assert np.array_equal(qdd_fd[s], sd.forward_dynamics(
                    model, q[s], qd[s], tau[s], f_ext={link: f[s]}, backend=backend))


@pytest.mark.parametrize('backend', BACKENDS)
def test_per_state_wrenches_on_offset_links_agree_with_pinocchio(backend, rng):
    """Talos (full: grippers with mimic fingers, sole and wrist sensor frames) and its fext."""
    pytest.importorskip('pinocchio')
    model = robot('talos')
    oracle = PinOracle(robot_urdf_path('talos'))
    links = offset_links(model)
    N = 4
    q, qd, qdd = random_state(rng, (N,), model.nv)
    f = {link: rng.normal(0.0, 10.0, (N, 6)) for link in links[:4]}
    tau = sd.rnea(model, q, qd, qdd, f_ext=f, backend=backend)
    for s in range(N):
        expected = oracle.rnea(model.joint_names, q[s], qd[s], qdd[s],
                               f_ext={link: w[s] for link, w in f.items()})
        assert np.abs(tau[s] - expected).max() <= 1e-10, s


# The functions of the class, each called as (model, q, qd, x, backend, **options): x is qdd,
# or tau for forward_dynamics; those without qd or x ignore them.

FUNCTIONS = {
    'rnea': lambda m, q, qd, x, b, **o: sd.rnea(m, q, qd, x, backend=b, **o),
    'rnea_derivatives': lambda m, q, qd, x, b, **o: sd.rnea_derivatives(m, q, qd, x, backend=b,
                                                                        **o),
    'forward_dynamics': lambda m, q, qd, x, b, **o: sd.forward_dynamics(m, q, qd, x, backend=b,
                                                                        **o),
    'gravity_torque': lambda m, q, qd, x, b, **o: sd.gravity_torque(m, q, backend=b, **o),
    'bias_torque': lambda m, q, qd, x, b, **o: sd.bias_torque(m, q, qd, backend=b, **o),
    'mass_matrix': lambda m, q, qd, x, b, **o: sd.mass_matrix(m, q, backend=b),
    'generalized_momentum': lambda m, q, qd, x, b, **o: sd.generalized_momentum(m, q, qd,
                                                                                backend=b),
    'regressor': lambda m, q, qd, x, b, **o: sd.regressor(m, q, qd, x, backend=b, **o),
}
#: the arguments each function reads (0: q, 1: qd, 2: qdd or tau)
READS = {'gravity_torque': (0,), 'mass_matrix': (0,), 'bias_torque': (0, 1),
         'generalized_momentum': (0, 1)}


def outcome(call):
    """Return ``call()``'s answer as a tuple of arrays, with every warning an error."""
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        out = call()
    return tuple(np.asarray(x) for x in (out if isinstance(out, tuple) else (out,)))


def ur5_state(rng, shape=()):
    model = robot('ur5')
    q, qd, qdd = random_state(rng, shape, model.nv)
    return model, q, qd, qdd


# ±inf: NaN out as NaN gives, on every path, without an exception or a warning

@pytest.mark.parametrize('name, where', [(name, where) for name in sorted(FUNCTIONS)
                                         for where in READS.get(name, (0, 1, 2))])
def test_an_infinite_number_answers_as_nan_does(name, where, rng):
    model, q, qd, x = ur5_state(rng)
    function = FUNCTIONS[name]
    for value in (np.inf, -np.inf):
        for batch in (False, True):
            args = [np.stack([a, a]) if batch else a.copy() for a in (q, qd, x)]
            at = (0, 3) if batch else 3         # the first state's fourth joint
            for backend in BACKENDS:
                nan_args = [a.copy() for a in args]
                nan_args[where][at] = np.nan
                args[where][at] = value
                for form in (np.asarray, list):
                    got = outcome(lambda: function(model, *(form(a.tolist()) if form is list
                                                            else a for a in args), backend))
                    nan = outcome(lambda: function(model, *nan_args, backend))
                    assert any((~np.isfinite(n)).any() for n in nan), (name, backend)
                    for g, n in zip(got, nan):
                        assert np.array_equal(np.isfinite(g), np.isfinite(n)), (
                            name, where, value, batch, backend, form)
                        if batch:       # the other state is untouched
                            assert np.isfinite(g[1]).all()


@pytest.mark.parametrize('backend', BACKENDS)
def test_infinite_gravity_and_wrenches_answer_as_nan_does(backend, rng):
    model, q, qd, qdd = ur5_state(rng, (3,))
    for name in ('rnea', 'rnea_derivatives', 'forward_dynamics'):
        for options in ({'gravity': (0.0, 0.0, np.inf)}, {'f_ext': {'tool0': [np.inf] * 6}},
                        {'f_ext': {'tool0': np.full((3, 6), -np.inf)}}):
            nan = {k: ({'tool0': np.full(np.shape(v['tool0']), np.nan)} if k == 'f_ext'
                       else (0.0, 0.0, np.nan)) for k, v in options.items()}
            for s in (slice(None), 0):
                one = {k: ({'tool0': np.asarray(v['tool0'])[..., :] if np.ndim(v['tool0']) == 1
                            else np.asarray(v['tool0'])[s]} if k == 'f_ext' else v)
                       for k, v in options.items()}
                one_nan = {k: ({'tool0': np.asarray(v['tool0'])[..., :]
                                if np.ndim(v['tool0']) == 1 else np.asarray(v['tool0'])[s]}
                               if k == 'f_ext' else v) for k, v in nan.items()}
                got = outcome(lambda: FUNCTIONS[name](model, q[s], qd[s], qdd[s], backend,
                                                      **one))
                expected = outcome(lambda: FUNCTIONS[name](model, q[s], qd[s], qdd[s], backend,
                                                           **one_nan))
                assert any((~np.isfinite(n)).any() for n in expected)
                for g, n in zip(got, expected):
                    assert np.array_equal(np.isfinite(g), np.isfinite(n)), (name, options, s)


# Numbers as text (and None, Decimal, bytes) are refused on every path, in the same words

@pytest.mark.parametrize('where', [0, 1, 2])
def test_numbers_as_text_are_refused_on_every_path_in_the_same_words(where, rng):
    model, q, qd, qdd = ur5_state(rng)
    texts = {
        'list of str': lambda a: [str(v) for v in a],
        'tuple of np.str_': lambda a: tuple(np.str_(v) for v in a),
        'list of bytes': lambda a: [str(v).encode() for v in a],
        'str array': lambda a: a.astype(str),
        'one None': lambda a: [None] + a.tolist()[1:],
        'Decimal': lambda a: [Decimal(str(v)) for v in a],
        'batch of str': lambda a: [[str(v) for v in a]] * 2,
    }
    for text, make in texts.items():
        for name, function in FUNCTIONS.items():
            if where not in READS.get(name, (0, 1, 2)):
                continue
            said = set()
            for backend in BACKENDS:
                args = [q, qd, qdd]
                args[where] = make(args[where])
                said.add(refusal(lambda: function(model, *args, backend)))
            assert len(said) == 1, (text, name, said)
            (kind, message), = said
            what = ('q', 'qd', 'tau' if name == 'forward_dynamics' else 'qdd')[where]
            assert kind is TypeError and message.startswith(
                f'{what} must be an array of real numbers'), (text, name, message)
    # gravity too
    for gravity in (('0', '0', '-9.81'), ['0', 0.0, -9.81], (0.0, 0.0, None)):
        said = {refusal(lambda: FUNCTIONS[name](model, q, qd, qdd, backend, gravity=gravity))
                for name in ('rnea', 'rnea_derivatives', 'forward_dynamics', 'gravity_torque',
                             'bias_torque', 'regressor') for backend in BACKENDS}
        assert len(said) == 1, said
        (kind, message), = said
        assert kind is TypeError and message.startswith('gravity must be'), message


# float16: every function keeps it (the library's dtype rule), forward dynamics too

@pytest.mark.parametrize('backend', BACKENDS)
def test_float16_states_give_float16_in_every_function(backend, rng):
    model, q, qd, qdd = ur5_state(rng, (3,))
    tau = sd.rnea(model, q, qd, qdd)
    for name, function in FUNCTIONS.items():
        for s in (0, slice(None)):
            x = tau if name == 'forward_dynamics' else qdd
            args = [a[s].astype(np.float16) for a in (q, qd, x)]
            for out in outcome(lambda: function(model, *args, backend)):
                assert out.dtype == np.float16, (name, s, out.dtype)
            # one argument wider: numpy's promotion (float64), as rnea
            wide = [args[0], args[1].astype(np.float64), args[2]]
            if 1 in READS.get(name, (0, 1, 2)):
                for out in outcome(lambda: function(model, *wide, backend)):
                    assert out.dtype == np.float64, (name, s, out.dtype)


def test_float16_forward_dynamics_is_pinocchios_aba_to_float16_rounding(rng):
    pin = pytest.importorskip('pinocchio')
    model, q, qd, _ = ur5_state(rng, (5,))
    tau = rng.uniform(-5.0, 5.0, q.shape)
    oracle = PinOracle(robot_urdf_path('ur5'))
    h = [a.astype(np.float16) for a in (q, qd, tau)]
    for backend in BACKENDS:
        qdd = sd.forward_dynamics(model, *h, backend=backend)
        assert qdd.dtype == np.float16
        for s in range(len(q)):
            expected = pin.aba(oracle.model, oracle.data,
                               *oracle.expand(model.joint_names, *(a[s].astype(float) for a in h)))
            # float16 keeps 11 bits: a few hundred ulps of cond(M) amplification
            scale = max(1.0, np.abs(expected).max())
            assert np.abs(qdd[s].astype(float) - expected).max() <= 0.1 * scale, (backend, s)


# Booleans and text are no number for the per-joint terms, the payload or a locked joint

def test_booleans_and_text_are_refused_for_numeric_terms_naming_them(rng):
    model, q, qd, qdd = ur5_state(rng)
    joint, n = model.joint_names[0], model.nv
    for bad in (True, np.True_, [True] * n, np.ones(n, dtype=bool), {joint: True},
                {joint: np.False_}, [0.1] * (n - 1) + [True], '0.1', ['0.1'] * n,
                {joint: '0.1'}):
        calls = {
            'armature': [lambda: sd.forward_dynamics(model, q, qd, qdd, armature=bad),
                         lambda: sd.rnea_derivatives(model, q, qd, qdd, armature=bad),
                         lambda: sd.per_joint(model, 'armature', bad)],
            'damping': [lambda: sd.per_joint(model, 'damping', bad)],
        }
        for what, each in calls.items():
            for call in each:
                with pytest.raises(TypeError, match=f'^{what}.* must be real numbers'):
                    call()
    for bad in (True, np.True_, '0.01'):
        with pytest.raises(TypeError, match='^friction_threshold must be real numbers'):
            sd.rnea_derivatives(model, q, qd, qdd, friction_threshold=bad)
        with pytest.raises(TypeError, match='^threshold must be real numbers'):
            sd.friction_torque(model, qd, bad)
    with pytest.raises(TypeError, match='^armature must be real numbers'):
        sd.armature_torque(True, qdd)
    for kwargs, what in (({'mass': True}, 'mass'), ({'mass': '2'}, 'mass'),
                         ({'mass': 2.0, 'com': (True, 0.0, 0.0)}, 'centre of mass'),
                         ({'mass': 2.0, 'com': ('0', '0', '0')}, 'centre of mass'),
                         ({'mass': 2.0, 'inertia': [True] * 6}, 'inertia')):
        with pytest.raises(TypeError, match=f'payload.* {what} must be real numbers'):
            sd.with_payload(model, 'tool0', **kwargs)
    path = robot_urdf_path('ur5')
    for bad in (True, '0.1', None):
        with pytest.raises(TypeError, match=f"locked joint '{joint}' value must be real"):
            sd.Model.from_urdf(path, joints=model.joint_names[1:], locked={joint: bad})
    # real numbers of any width are kept, and act as the same float
    _, _, M = sd.rnea_derivatives(model, q, qd, qdd)
    for good in (np.float32(0.5), 1, np.int8(1), np.array(0.5), {joint: np.float16(0.5)}):
        _, _, Ma = sd.rnea_derivatives(model, q, qd, qdd, armature=good)
        a = sd.per_joint(model, 'armature', good)
        assert np.array_equal(Ma, M + np.diag(a)) and a[0] == float(np.asarray(
            good[joint] if isinstance(good, dict) else good))
    heavy = sd.with_payload(model, 'tool0', 2, com=(0, 0, 1))
    assert np.array_equal(heavy.inertia, sd.with_payload(model, 'tool0', 2.0,
                                                         com=(0.0, 0.0, 1.0)).inertia)
    assert sd.Model.from_urdf(path, joints=model.joint_names[1:],
                              locked={joint: np.float32(0.5)}).locked[joint] == 0.5


# Batches that do not broadcast, and masked arrays: refused naming the arguments

THREE_VECTORS = {
    'rnea': lambda m, q, qd, x, **kw: sd.rnea(m, q, qd, x, **kw),
    'rnea_derivatives': lambda m, q, qd, x, **kw: sd.rnea_derivatives(m, q, qd, x, **kw),
    'forward_dynamics': lambda m, q, qd, x, **kw: sd.forward_dynamics(m, q, qd, x, **kw),
}


@pytest.mark.parametrize('backend', BACKENDS)
@pytest.mark.parametrize('function', sorted(THREE_VECTORS))
def test_batches_that_do_not_broadcast_are_refused_naming_the_arguments(function, backend):
    """The user's names, where numpy's own message says ``arg 0 with shape (3,)``."""
    model, call = robot('ur5'), THREE_VECTORS[function]
    n = model.nv
    third = 'tau' if function == 'forward_dynamics' else 'qdd'
    with pytest.raises(ValueError, match=rf'do not broadcast: q of shape \(3, {n}\), qd of '
                                         rf'shape \(2, {n}\), {third} of shape \({n},\)'):
        call(model, np.zeros((3, n)), np.zeros((2, n)), np.zeros(n), backend=backend)
    with pytest.raises(ValueError, match=r"do not broadcast: .*f_ext\['wrist_3_link'\] of "
                                         r'shape \(2, 6\)'):
        call(model, np.zeros((3, n)), np.zeros(n), np.zeros(n), backend=backend,
             f_ext={'wrist_3_link': np.zeros((2, 6))})
    motion = sd.BaseMotion(np.zeros((2, 6)), np.zeros(6))
    with pytest.raises(ValueError, match=r'do not broadcast: .* of shape \(3, 6\), base\.v of '
                                         r'shape \(2, 6\), base\.a of shape \(6,\)$'):
        call(model, np.zeros((3, n)), np.zeros(n), np.zeros(n), backend=backend, base=motion)
    with pytest.raises(ValueError, match=r'do not broadcast: q of shape \(3, 6\), base\.v of '
                                         r'shape \(2, 6\)'):
        sd.mass_matrix(model, np.zeros((3, n)), backend=backend, base=motion)


@pytest.mark.parametrize('backend', BACKENDS)
@pytest.mark.parametrize('function', sorted(THREE_VECTORS))
def test_a_masked_entry_is_refused_and_an_unmasked_array_read(function, backend, rng):
    """A masked array's mask must not be dropped silently (numpy reads the data under it).

    A masked array with nothing masked is its numbers (the answer equals the plain array's, to
    the bit); one with a masked entry is refused naming the argument, one state or a batch.
    """
    model, call = robot('ur5'), THREE_VECTORS[function]
    q, qd, x = (rng.uniform(-1, 1, (3, model.nv)) for _ in range(3))
    for s in (0, slice(None)):
        plain = call(model, q[s], qd[s], x[s], backend=backend)
        unmasked = call(model, np.ma.masked_array(q[s]), qd[s], x[s], backend=backend)
        for a, b in zip(*(o if isinstance(o, tuple) else (o,) for o in (plain, unmasked))):
            assert np.array_equal(np.asarray(a), np.asarray(b))
        masked = np.ma.masked_array(qd[s], mask=np.zeros_like(qd[s], dtype=bool))
        masked[..., 2] = np.ma.masked
        with pytest.raises(ValueError, match=r'qd has [13] masked entries: give the numbers'):
            call(model, q[s], masked, x[s], backend=backend)


def test_a_masked_entry_is_refused_in_every_number_the_library_reads(rng):
    """Armature, per-joint terms, thresholds, a payload, a locked joint: no mask dropped."""
    model = robot('ur5')
    n = model.nv
    q, qd, x = (rng.uniform(-1, 1, n) for _ in range(3))
    one = np.ma.masked_array(np.full(n, 0.1), mask=[True] + [False] * (n - 1))
    calls = {
        'armature': lambda: sd.forward_dynamics(model, q, qd, x, armature=one),
        'armature ': lambda: sd.rnea_derivatives(model, q, qd, x, armature=one),
        'armature  ': lambda: sd.armature_torque(one, x),
        'damping': lambda: sd.per_joint(model, 'damping', one),
        'friction_threshold': lambda: sd.rnea_derivatives(
            model, q, qd, x, friction_threshold=np.ma.masked_array(0.05, mask=True)),
        'payload mass': lambda: sd.with_payload(model, 'wrist_3_link',
                                                np.ma.masked_array(1.0, mask=True)),
        'payload centre of mass': lambda: sd.with_payload(
            model, 'wrist_3_link', 1.0, np.ma.masked_array([0, 0, 1.0], mask=[0, 1, 0])),
        'locked joint': lambda: sd.Model.from_urdf(
            robot_urdf_path('ur5'), joints=model.joint_names[1:],
            locked={model.joint_names[0]: np.ma.masked_array(0.3, mask=True)}),
    }
    for what, call in calls.items():
        with pytest.raises(ValueError, match=rf'{what.strip().replace(" ", ".*")}.* has 1 '
                                             'masked entries'):
            call()
    # nothing masked: the numbers
    plain = sd.forward_dynamics(model, q, qd, x, armature=np.full(n, 0.1))
    assert np.array_equal(sd.forward_dynamics(model, q, qd, x,
                                              armature=np.ma.masked_array(np.full(n, 0.1))),
                          plain)


def test_a_jacobian_and_armature_torque_name_arguments_that_do_not_broadcast():
    """Name the arguments where numpy said "operands could not be broadcast"; 'local' too."""
    model = robot('ur5')
    n = model.nv
    base = sd.BaseMotion(np.zeros(6), np.zeros(6), orientation=np.tile([0, 0, 0, 1.0], (4, 1)))
    for frame in ('world', 'local'):
        with pytest.raises(ValueError, match=rf'do not broadcast: q of shape \(3, {n}\), '
                                             r'base\.v .*base\.orientation of shape \(4, 4\)'):
            sd.jacobian(model, np.zeros((3, n)), 'wrist_3_link', frame, base=base)
    with pytest.raises(ValueError, match=rf'do not broadcast: armature of shape \(4, {n}\), '
                                         rf'qdd of shape \(3, {n}\)'):
        sd.armature_torque(np.ones((4, n)), np.ones((3, n)))
    with pytest.raises(ValueError, match='armature has 6 values a state and qdd 5'):
        sd.armature_torque(np.ones(6), np.ones(5))
    # what broadcasts is answered, as a loop over the states
    Q = np.random.default_rng(0).uniform(-1, 1, (4, n))
    J = sd.jacobian(model, Q, 'wrist_3_link', 'world', base=base)
    for k in range(4):
        assert np.array_equal(J[k], sd.jacobian(model, Q[k], 'wrist_3_link', 'world',
                                                base=sd.BaseMotion(np.zeros(6), np.zeros(6))))
