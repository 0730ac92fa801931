# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Forward dynamics refuses a singular ``M`` however rounding leaves its pivot, on every path.

``M`` is singular when a joint's motion can be made by the rest of its subtree without it:
two joints on one line through a massless link, a floating base's massless root link whose
motion a joint repeats. In exact arithmetic the pivot of that joint is 0; with an axis that
is not axis-aligned rounding leaves it a tiny positive number, and a test of ``pivot <= 0``
answered ``q̈ ~ 1e16`` whose ``rnea`` misses ``τ`` by O(1). The test is the pivot relative to
the joint's own inertia, ``d_k <= PIVOT_TOL M_kk``; it must hold on every path: one state and
a batch, numpy and compiled, with armature (0) on other joints, on a moving base, the
articulated-body kernel and the ``LᵀL`` factorization each on its own. And it refuses no real
robot: every URDF of example-robot-data, fixed and free-flyer, at random states, answers and
round-trips (the robots whose ``M`` is singular, by Pinocchio's ``crba`` and an eigenvalue
test, excepted). Then the batch error's state index, a mimic joint's armature, and
``BaseMotion.gravity_included``.
"""

import glob
import os
import re
import warnings

from conftest import example_robot_data_dir, robot_urdf_path
import numpy as np
import pytest
import spatial_dynamics as sd
from spatial_dynamics.algorithms.forward import PIVOT_TOL
from spatial_dynamics.backends import layout, python
from test_core_floating_base import FLOATING, random_floating_state
from test_urdf_robot_sweep import REFUSED

BACKENDS = ('numpy', 'compiled')
LIMIT = '<limit lower="-3" upper="3" effort="1" velocity="1"/>'
HEAVY = ('<inertial><origin xyz="0 0 0.1"/><mass value="1"/><inertia ixx="0.01" ixy="0" '
         'ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>')


def rotation_xyz(rpy) -> np.ndarray:
    """Return URDF's rotation of ``rpy``: ``Rz(y) Ry(p) Rx(r)`` (fixed axes x, y, z)."""
    r, p, y = rpy
    cx, sx, cy, sy, cz, sz = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    Rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    Ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    Rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


def coincident(offset=0.0, mimic=False) -> str:
    """Return a chain whose ``j1`` and ``j2`` turn about one line through a massless ``l1``.

    ``j1``'s axis is ``(1, 2, 3)/√14``; ``j2`` sits 0.3 along it, in a frame rotated by
    ``rpy = (0.3, 0.2, 0.1)``, its axis the same line in that frame; ``offset`` moves ``j2``
    off the line (m). The mass is beyond ``j3``. With ``mimic``, ``j4`` follows ``j3``.
    """
    u = np.array([1.0, 2.0, 3.0]) / np.sqrt(14.0)
    rpy = (0.3, 0.2, 0.1)
    a2 = rotation_xyz(rpy).T @ u
    o = 0.3 * u + offset * np.cross(u, [0.0, 0.0, 1.0]) / np.linalg.norm(np.cross(u, [0, 0, 1]))
    u, a2, o = ([float(x) for x in v] for v in (u, a2, o))
    tail = ''
    if mimic:
        tail = (f'<link name="l4">{HEAVY}</link><joint name="j4" type="revolute"><parent '
                f'link="l3"/><child link="l4"/><origin xyz="0.1 0 0.2"/><axis xyz="1 0 0"/>'
                f'{LIMIT}<mimic joint="j3" multiplier="0.5"/></joint>')
    return (f'<robot name="r"><link name="base"/><link name="l1"/><link name="l2"/>'
            f'<link name="l3">{HEAVY}</link>'
            f'<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>'
            f'<axis xyz="{u[0]!r} {u[1]!r} {u[2]!r}"/>{LIMIT}</joint>'
            f'<joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>'
            f'<origin xyz="{o[0]!r} {o[1]!r} {o[2]!r}" rpy="{rpy[0]} {rpy[1]} {rpy[2]}"/>'
            f'<axis xyz="{a2[0]!r} {a2[1]!r} {a2[2]!r}"/>{LIMIT}</joint>'
            f'<joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/>'
            f'<origin xyz="0 0 0.2"/><axis xyz="0 1 0"/>{LIMIT}</joint>{tail}</robot>')


#: A floating base whose root link is massless; ``j1`` (a general axis, at a general pose)
#: turns the only mass about a line that the base can turn about too.
FLOAT_ROOT = f'''<robot name="r"><link name="base"/>
<link name="l1"><inertial><origin xyz="0.1 0 0.1"/><mass value="1"/>
<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.03"/></inertial></link>
<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
<origin xyz="0.1 0.2 0.3" rpy="0.1 0.2 0.3"/><axis xyz="0.6 0 0.8"/>{LIMIT}</joint></robot>'''


def load(text, **kwargs):
    """Load a model, its URDFWarnings (a massless link's joints) silenced."""
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', sd.URDFWarning)
        return sd.Model.from_urdf(text, **kwargs)


def states(model, rng, n=3):
    """Return ``n`` states ``(q, q̇, τ)`` of ``model`` (a unit quaternion on a floating base)."""
    q = rng.uniform(-1.0, 1.0, (n, model.nq))
    if model.floating:
        quat = rng.normal(size=(n, 4))
        q[:, 3:7] = quat / np.linalg.norm(quat, axis=-1, keepdims=True)
    return q, rng.uniform(-1.0, 1.0, (n, model.nv)), rng.uniform(-1.0, 1.0, (n, model.nv))


def pivot_ratios(M) -> np.ndarray:
    """Return ``d_k / M_kk`` of a symmetric positive definite ``M``, factored from the leaves.

    Numpy's Cholesky of ``M`` with its coordinates reversed: ``d_k`` the Schur complement of
    ``M_kk`` in ``M[k:, k:]``, the oracle of the pivots the library's kernels take.
    """
    R = M[::-1, ::-1]
    L = np.linalg.cholesky(R)
    return (np.diag(L) ** 2 / np.diag(R))[::-1]


#: A state of :func:`coincident` where rounding leaves ``j1``'s pivot positive (1e-16 of
#: ``M_kk``): a test of ``pivot <= 0`` answered ``q̈ ~ 2e16`` there, in ABA and in ``LᵀL``.
TRAP = (np.array([0.4, -0.7, 0.5]), np.array([0.3, 0.1, -0.2]), np.array([0.5, -0.2, 0.1]))


def refused_on_every_path(model, joint, coordinate, rng, armed, base=True, first=None):
    """Assert ``forward_dynamics`` names ``joint`` at ``coordinate`` on each path.

    One state and a batch of three (``first`` the first state, else random), both backends,
    without armature and with armature 0 on ``armed`` (another joint), and (``base``) on a
    moving base.
    """
    q, qd, tau = states(model, rng)
    if first is not None:
        q[0], qd[0], tau[0] = first
    message = (rf"not positive definite at velocity coordinate {coordinate}, joint "
               rf"'{joint}'")
    for backend in BACKENDS:
        for x, v, t in ((q[0], qd[0], tau[0]), (q, qd, tau)):
            for armature in (None, {armed: 0.0}):
                with pytest.raises(ValueError, match=message):
                    sd.forward_dynamics(model, x, v, t, backend=backend, armature=armature)
            if base:
                motion = sd.BaseMotion(rng.uniform(-1, 1, 6), rng.uniform(-1, 1, 6))
                with pytest.raises(ValueError, match=message):
                    sd.forward_dynamics(model, x, v, t, backend=backend, base=motion)


def test_two_joints_on_one_general_line_are_refused_on_every_path(rng):
    model = load(coincident())
    q, qd, tau = states(model, rng)
    q[0], qd[0], tau[0] = TRAP
    M = sd.mass_matrix(model, q[0], backend='numpy')
    eig = np.linalg.eigvalsh(M)
    assert eig[0] <= 1e-15 * eig[-1]        # singular (to rounding)
    refused_on_every_path(model, 'j1', 0, rng, 'j3', first=TRAP)
    # each kernel on its own: the articulated-body algorithm, the factorization
    rows = layout.of(model).rows
    _, info = python.aba_rows(rows, q[0].tolist(), qd[0].tolist(), tau[0].tolist(),
                              sd.GRAVITY)
    assert info == 0
    _, failed = python.forward_solve(rows, M, tau[0])
    assert failed == (0, 0)
    _, failed = python.forward_solve(rows, sd.mass_matrix(model, q, backend='numpy'), tau)
    assert failed == (0, 0)


@pytest.mark.parametrize('dtype', [np.float32, np.float16])
def test_narrow_floats_are_refused_as_float64_and_answered_rounded_once(dtype, rng):
    """float32 / float16 states: the refusal as in float64, an answer rounded once.

    Computed in their own precision, rounding left a singular ``M``'s pivots at ~eps ``M_kk``
    (1e-8, 1e-3), far above ``PIVOT_TOL``: 7 of 20 float32 states of :func:`coincident`
    answered q̈ ~ 2e8 missing ``τ`` by O(1).
    """
    model = load(coincident())
    q, qd, tau = (x.astype(dtype) for x in states(model, rng, 20))
    for backend in BACKENDS:
        for s in list(range(len(q))) + [slice(None)]:
            with pytest.raises(ValueError, match="not positive definite .* joint 'j1'"):
                sd.forward_dynamics(model, q[s], qd[s], tau[s], backend=backend)
    ur5 = sd.Model.from_urdf(robot_urdf_path('ur5'))
    q, qd, tau = (x.astype(dtype) for x in states(ur5, rng, 4))
    for backend in BACKENDS:
        for s in (0, slice(None)):
            wide = sd.forward_dynamics(ur5, *(x[s].astype(np.float64) for x in (q, qd, tau)),
                                       backend=backend)
            out = sd.forward_dynamics(ur5, q[s], qd[s], tau[s], backend=backend)
            assert out.dtype == dtype and np.array_equal(out, wide.astype(dtype)), backend


def test_a_mimic_model_refuses_on_its_factorization_path(rng):
    """A mimic joint: the compiled kernel takes CRBA + ``LᵀL`` at once (no ABA)."""
    model = load(coincident(mimic=True))
    q, qd, tau = states(model, rng)
    rows = layout.of(model).rows
    _, info = python.aba_rows(rows, q[0].tolist(), qd[0].tolist(), tau[0].tolist(),
                              sd.GRAVITY)
    assert info == -2
    refused_on_every_path(model, 'j1', 0, rng, 'j3', first=TRAP)


def test_a_floating_base_massless_root_link_is_refused_on_every_path(rng):
    model = load(FLOAT_ROOT, base='floating')
    refused_on_every_path(model, 'root_joint', 0, rng, 'j1', base=False)
    q, qd, tau = states(model, rng)
    rows = layout.of(model).rows
    _, info = python.aba_rows(rows, q[0].tolist(), qd[0].tolist(), tau[0].tolist(),
                              sd.GRAVITY)
    assert 0 <= info < 6
    with pytest.raises(ValueError, match=r"joint\(s\) 'j1' and its root link 'base' has no "
                                         r"mass of its own"):
        sd.forward_dynamics(model, q[0], qd[0], tau[0])
    # the advice taken: armature on j1 gives q̈, rnea's inverse
    A = sd.per_joint(model, 'armature', {'j1': 0.1})
    for backend in BACKENDS:
        qdd = sd.forward_dynamics(model, q, qd, tau, backend=backend, armature={'j1': 0.1})
        back = sd.rnea(model, q, qd, qdd) + sd.armature_torque(A, qdd)
        assert np.allclose(back, tau, rtol=0.0, atol=1e-12), backend


def test_a_joint_off_the_line_by_a_picometre_is_refused(rng):
    """``j2`` 1e-12 m off ``j1``'s line: ``d / M_kk ~ 1e-23``, ``M`` singular to rounding."""
    model = load(coincident(offset=1e-12))
    q = states(model, rng)[0]
    assert pivot_ratios(sd.mass_matrix(model, q[0], backend='numpy'))[0] < 1e-13   # rounding
    refused_on_every_path(model, 'j1', 0, rng, 'j3', first=TRAP)
    # a millimetre off the line: a robot, answered
    model = load(coincident(offset=1e-3))
    q, qd, tau = states(model, rng)
    for backend in BACKENDS:
        qdd = sd.forward_dynamics(model, q, qd, tau, backend=backend)
        assert np.allclose(sd.rnea(model, q, qd, qdd), tau, rtol=0.0, atol=1e-9), backend


def test_the_refusal_says_the_pivot_against_the_tolerance():
    """The message gives ``d_k / M_kk`` (numpy's Cholesky the oracle) and ``PIVOT_TOL``.

    ``j2`` 1e-7 m off ``j1``'s line: ``M`` is not singular, only too badly conditioned
    (``d_k ~ 1.6e-13 M_kk``, cond 3e13); on the line, rounding's ~1e-16 is left.
    """
    for offset, low, high in ((1e-7, 1e-14, 1e-12), (0.0, 0.0, 1e-15)):
        model = load(coincident(offset=offset))
        oracle = pivot_ratios(sd.mass_matrix(model, TRAP[0], backend='numpy'))[0]
        assert low < oracle < high
        for backend in BACKENDS:
            with pytest.raises(ValueError, match=r'\(pivot d_k = (\S+) M_kk, at most PIVOT_TOL '
                                                 r'= 1e-12 M_kk; an exactly singular M leaves '
                                                 r'~1e-16\), so no acceleration') as refused:
                sd.forward_dynamics(model, *TRAP, backend=backend)
            shown = float(re.search(r'pivot d_k = (\S+) M_kk', str(refused.value)).group(1))
            if offset:          # two digits of a pivot well above rounding
                assert shown == pytest.approx(oracle, rel=0.05), backend
            else:               # rounding: as small as numpy's
                assert abs(shown) < 1e-15, backend


BASE = example_robot_data_dir()
FILES = sorted(os.path.relpath(p, BASE) for p in glob.glob(
    os.path.join(BASE, '**', '*.urdf'), recursive=True)) if BASE else []
#: URDFs whose ``M`` is singular at every state (checked below against Pinocchio's ``crba``):
#: Romeo's thumbs and gripper move no mass.
SINGULAR = ('romeo_description/urdf/romeo.urdf', 'romeo_description/urdf/romeo_laas_small.urdf')
SWEEP = ([(f, 'fixed') for f in FILES if f not in REFUSED]
         + [(f, 'floating') for f in FLOATING])


@pytest.mark.parametrize('name,base', SWEEP)
def test_no_robot_of_example_robot_data_is_refused(name, base, rng):
    """Sixteen random states each, one batch and one state, both backends: answered.

    ``rnea`` of the answer is ``τ`` to 1e-12 of ``|M| |q̈| + |τ|`` (rounding, in proportion
    to the sizes involved); the pivots (numpy's Cholesky, the oracle) are far above
    ``PIVOT_TOL``. A robot whose ``M`` is singular (its smallest eigenvalue 1e-12 of the
    largest, by Pinocchio's ``crba`` too) is refused instead.
    """
    model = load(os.path.join(BASE, name), base=base)
    if model.nv == 0:
        return
    if base == 'floating':
        q, qd, _ = random_floating_state(rng, model, (16,))
    else:
        q, qd = rng.uniform(-np.pi, np.pi, (16, model.nv)), rng.uniform(-2, 2, (16, model.nv))
    tau = rng.uniform(-3.0, 3.0, qd.shape)
    M = sd.mass_matrix(model, q, backend='numpy')
    eig = np.linalg.eigvalsh(M)
    if name in SINGULAR:
        assert np.all(eig[:, 0] <= 1e-12 * eig[:, -1])
        for backend in BACKENDS:
            with pytest.raises(ValueError, match='not positive definite'):
                sd.forward_dynamics(model, q, qd, tau, backend=backend)
        return
    assert np.all(eig[:, 0] > 1e-12 * eig[:, -1])
    assert min(pivot_ratios(Ms).min() for Ms in M) > 1e3 * PIVOT_TOL
    for backend in BACKENDS:
        for qdd in (sd.forward_dynamics(model, q, qd, tau, backend=backend),
                    sd.forward_dynamics(model, q[0], qd[0], tau[0], backend=backend)[None]):
            k = len(qdd)
            back = sd.rnea(model, q[:k], qd[:k], qdd, backend='numpy')
            size = (np.linalg.norm(M[:k], ord=2, axis=(-2, -1)) * np.linalg.norm(qdd, axis=-1)
                    + np.linalg.norm(tau[:k], axis=-1))
            err = np.linalg.norm(back - tau[:k], axis=-1)
            assert np.all(err <= 1e-12 * size), (backend, k, (err / size).max())


#: A ball joint of three revolute joints (z, x, y) at one point through massless links, as
#: the human's shoulder of example-robot-data: at ``roll = ±π/2`` (gimbal lock) ``yaw`` and
#: ``pitch`` turn about one line and ``M`` is singular; elsewhere it is not.
ARM = HEAVY.replace('0.01" iyy', '0.02" iyy')
GIMBAL = f'''<robot name="g"><link name="base"/><link name="l1"/><link name="l2"/>
<link name="arm">{ARM}</link>
<joint name="yaw" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
{LIMIT}</joint>
<joint name="roll" type="revolute"><parent link="l1"/><child link="l2"/><axis xyz="1 0 0"/>
{LIMIT}</joint>
<joint name="pitch" type="revolute"><parent link="l2"/><child link="arm"/><axis xyz="0 1 0"/>
{LIMIT}</joint></robot>'''


def test_a_batch_error_names_its_state_in_plain_numbers(rng):
    """``(state 1)``, ``(state (0, 1))``: never ``np.int64(1)``; as a quaternion's error."""
    leaf = load(GIMBAL.replace(ARM, ''))
    for backend in BACKENDS:      # singular at every state: a leaf that moves no mass
        for shape, where in (((2,), 'state 0'), ((1, 2), r'state \(0, 0\)')):
            with pytest.raises(ValueError, match=rf"joint 'pitch' \({where}\): ") as err:
                sd.forward_dynamics(leaf, np.zeros(shape + (3,)), np.zeros(3), np.ones(3),
                                    backend=backend)
            assert 'np.' not in str(err.value)
    model = load(GIMBAL)
    q = np.array([[0.2, 0.3, -0.4], [0.2, np.pi / 2, -0.4]])     # the second at the lock
    qd, tau = rng.uniform(-1, 1, (2, 3)), rng.uniform(-1, 1, (2, 3))
    for backend in BACKENDS:
        qdd = sd.forward_dynamics(model, q[0], qd[0], tau[0], backend=backend)
        assert np.allclose(sd.rnea(model, q[0], qd[0], qdd), tau[0], rtol=0.0, atol=1e-12)
        with pytest.raises(ValueError, match=r"joint 'yaw' \(state 1\): ") as err:
            sd.forward_dynamics(model, q, qd, tau, backend=backend)
        assert 'np.' not in str(err.value)
        with pytest.raises(ValueError, match=r"joint 'yaw' \(state \(0, 1\)\): ") as err:
            sd.forward_dynamics(model, q[None], qd, tau, backend=backend)
        assert 'np.' not in str(err.value)
    floating = load(FLOAT_ROOT, base='floating')
    qf = states(floating, rng, 2)[0]
    qf[1, 3:7] = [0.0, 0.0, 0.0, 2.0]
    with pytest.raises(ValueError, match=r'\(state 1\) has norm 2'):
        sd.rnea(floating, qf, np.zeros((2, 7)), np.zeros((2, 7)))


def test_a_mimic_joints_armature_is_refused_with_its_source():
    model = load(coincident(mimic=True))
    assert model.mimics['j4'][0] == 'j3'
    with pytest.raises(ValueError, match=r"armature: joint 'j4' is a mimic joint: it follows "
                                         r"'j3' .*give it to 'j3'"):
        sd.per_joint(model, 'armature', {'j4': 0.1})
    with pytest.raises(ValueError, match=r"armature: unknown joint 'j9'"):
        sd.per_joint(model, 'armature', {'j9': 0.1})


def test_gravity_included_takes_a_bool_only():
    for value in ('yes', 'False', '', 1, 0, None, 1.0):
        with pytest.raises(TypeError, match=r'base.gravity_included must be a bool'):
            sd.BaseMotion(np.zeros(6), np.zeros(6), gravity_included=value)
    for value, expected in ((True, True), (False, False), (np.bool_(True), True),
                            (np.bool_(False), False)):
        motion = sd.BaseMotion(np.zeros(6), np.zeros(6), gravity_included=value)
        assert motion.gravity_included is expected
