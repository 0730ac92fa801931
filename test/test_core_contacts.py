# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Inverse dynamics on contacts: ``M q̈ + h = Sᵀ τ + J_cᵀ λ`` for a floating-base robot.

Oracles: Pinocchio's frame Jacobians (``LOCAL_WORLD_ALIGNED`` at a frame placed at the contact
point) and ``pin.rnea``; physics: Solo12 standing on four feet and Talos on two soles carry
their weight (the contact forces sum to ``m g``), the base rows hold to 1e-9, the torques are
``rnea - J_cᵀ λ``; the friction-cone QP (Clarabel) stays inside the cones or says it cannot.
"""

import os
import sys
import warnings

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from conftest import least_torque_split, robot_urdf_path, to_pin  # noqa: E402
import spatial_dynamics as sd  # noqa: E402

pin = pytest.importorskip('pinocchio')
FEET = ('FL_FOOT', 'FR_FOOT', 'HL_FOOT', 'HR_FOOT')
SOLES = ('left_sole_link', 'right_sole_link')


@pytest.fixture(scope='module')
def solo():
    path = robot_urdf_path('solo12')
    pm = pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer())
    return sd.Model.from_urdf(path, base='floating'), pm


@pytest.fixture(scope='module')
def talos():
    path = robot_urdf_path('talos_reduced')
    pm = pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer())
    return sd.Model.from_urdf(path, base='floating'), pm


def mass(model):
    return model.inertia[:, 3, 3].sum()


def standing_solo(model):
    """Solo12 on its four feet, knees bent, its trunk tilted a little (q, nq)."""
    q = np.zeros(model.nq)
    q[2], q[3:7] = 0.25, np.array([0.02, -0.03, 0.01, 1.0]) / np.sqrt(1.0014)
    for k, name in enumerate(model.joint_names[1:]):
        front = name.startswith('F')
        q[7 + k] = {'HAA': 0.05, 'HFE': 0.8 if front else -0.8,
                    'KFE': -1.6 if front else 1.6}[name[3:]]
    return q


def pin_contact_jacobian(pm, q, contacts):
    """``J_c`` from Pinocchio: a frame at each contact point, LOCAL_WORLD_ALIGNED, [ω; v]."""
    pm = pm.copy()
    ids = []
    for c in contacts:
        parent = pm.frames[pm.getFrameId(c.link)]
        placement = parent.placement * pin.SE3(np.eye(3), np.array(c.offset))
        ids.append(pm.addFrame(pin.Frame(f'{c.name}_point', parent.parentJoint, parent.parentFrame
                                         if hasattr(parent, 'parentFrame') else 0, placement,
                                         pin.FrameType.OP_FRAME)))
    pd = pm.createData()
    pin.computeJointJacobians(pm, pd, q)
    pin.framesForwardKinematics(pm, pd, q)
    rows = []
    for c, i in zip(contacts, ids):
        J = to_pin(pin.getFrameJacobian(pm, pd, i, pin.LOCAL_WORLD_ALIGNED))  # our columns
        J = np.r_[J[3:], J[:3]]                                               # rows [ω; v]
        rows.append(J[3:] if c.kind == 'point' else J)
    return np.vstack(rows)


def test_contact_jacobian_against_pinocchio(solo, talos):
    rng = np.random.default_rng(0)
    for model, pm, links in ((*solo, FEET), (*talos, SOLES)):
        q = rng.normal(size=model.nq) * 0.5
        q[3:7] /= np.linalg.norm(q[3:7])
        contacts = [sd.Contact(link, offset=rng.normal(size=3) * 0.05,
                               kind=('point', 'surface')[k % 2]) for k, link in enumerate(links)]
        np.testing.assert_allclose(sd.contact_jacobian(model, q, contacts),
                                   pin_contact_jacobian(pm, q, contacts), atol=1e-12)


@pytest.mark.parametrize('method', ['torques', 'forces', 'qp'])
def test_solo12_standing_carries_its_weight(solo, method):
    model, pm = solo
    q = standing_solo(model)
    zero = np.zeros(model.nv)
    feet = [sd.Contact(f, offset=(0.0, 0.0, -0.0)) for f in FEET]
    r = sd.contact_inverse_dynamics(model, q, zero, zero, feet, method=method)
    assert r.status == 'solved' and r.feasible, r.summary()
    total = sum(r.forces.values())
    np.testing.assert_allclose(total, [0.0, 0.0, mass(model) * 9.81], atol=1e-9)
    assert np.abs(r.base_residual).max() < 1e-9
    # τ = rnea - J_cᵀ λ, all from Pinocchio
    lam = np.concatenate([r.forces[f] for f in FEET])
    pd = pm.createData()
    b = pin.rnea(pm, pd, q, np.zeros(pm.nv), np.zeros(pm.nv))
    Jc = pin_contact_jacobian(pm, q, feet)
    np.testing.assert_allclose(r.tau, b[6:] - (Jc.T @ lam)[6:], rtol=1e-10, atol=1e-10)


def test_talos_on_two_soles_carries_its_weight(talos):
    model, pm = talos
    q = np.zeros(model.nq)
    q[2], q[6] = 1.02, 1.0
    zero = np.zeros(model.nv)
    soles = [sd.Contact(s, kind='surface', mu=0.8) for s in SOLES]
    for method in ('torques', 'forces', 'qp'):
        r = sd.contact_inverse_dynamics(model, q, zero, zero, soles, method=method)
        assert r.feasible, r.summary()
        total = sum(w[3:] for w in r.forces.values())
        np.testing.assert_allclose(total, [0.0, 0.0, mass(model) * 9.81], atol=1e-8)
        assert np.abs(r.base_residual).max() < 1e-9
        lam = np.concatenate([r.forces[s] for s in SOLES])
        b = pin.rnea(pm, pm.createData(), q, np.zeros(pm.nv), np.zeros(pm.nv))
        Jc = pin_contact_jacobian(pm, q, soles)
        np.testing.assert_allclose(r.tau, b[6:] - (Jc.T @ lam)[6:], rtol=1e-9, atol=1e-9)


def test_contact_consistent_torques_are_the_least_torques(solo):
    # Moving (q̇, q̈ random): every torque that meets the equation with some λ is
    # τ* + (null space of Q2ᵀ Sᵀ); τ* is the shortest of them.
    model, pm = solo
    rng = np.random.default_rng(1)
    q = standing_solo(model)
    qd, qdd = rng.normal(size=(2, model.nv))
    feet = [sd.Contact(f) for f in FEET]
    r = sd.contact_inverse_dynamics(model, q, qd, qdd, feet)
    assert np.abs(r.base_residual).max() < 1e-9
    Jc = sd.contact_jacobian(model, q, feet)
    b = sd.rnea(model, q, qd, qdd)
    lam = np.concatenate([r.forces[f] for f in FEET])
    np.testing.assert_allclose(np.r_[np.zeros(6), r.tau] + Jc.T @ lam, b, atol=1e-9)
    # another solution: λ + δ with J_c,baseᵀ δ = 0 changes τ by -J_c,jointsᵀ δ; never shorter
    null = np.linalg.svd(Jc[:, :6].T)[2][6:]
    for delta in rng.normal(size=(20, null.shape[0])) @ null:
        assert np.linalg.norm(r.tau - Jc[:, 6:].T @ delta) >= np.linalg.norm(r.tau) - 1e-12


def test_measured_contact_forces(solo):
    model, _ = solo
    q = standing_solo(model)
    zero = np.zeros(model.nv)
    feet = [sd.Contact(f) for f in FEET]
    solved = sd.contact_inverse_dynamics(model, q, zero, zero, feet)
    r = sd.contact_inverse_dynamics(model, q, zero, zero, feet, measured=solved.forces)
    np.testing.assert_allclose(r.tau, solved.tau, atol=1e-10)
    assert r.method == 'measured' and np.abs(r.base_residual).max() < 1e-9
    # a sensor reading 5 N too little upwards on one foot: the base rows miss 5 N (base frame)
    wrong = dict(solved.forces, FL_FOOT=solved.forces['FL_FOOT'] - [0.0, 0.0, 5.0])
    r = sd.contact_inverse_dynamics(model, q, zero, zero, feet, measured=wrong)
    R = sd.joints.quaternion_matrix(q[3:7])
    np.testing.assert_allclose(R @ r.base_residual[3:], [0.0, 0.0, 5.0], atol=1e-9)
    assert not r.feasible


def test_friction_violations_are_reported(solo):
    # A slippery floor (μ = 0.1): the least torques lean on the feet sideways; the result names
    # each foot that slips and by how much.
    model, _ = solo
    q = standing_solo(model)
    zero = np.zeros(model.nv)
    feet = [sd.Contact(f, mu=0.1) for f in FEET]
    r = sd.contact_inverse_dynamics(model, q, zero, zero, feet)
    assert {v.contact for v in r.violations} == set(FEET)
    for v in r.violations:
        f = r.forces[v.contact]
        assert v.kind == 'friction'
        assert v.amount == pytest.approx(np.hypot(f[0], f[1]) - 0.1 * f[2], abs=1e-12)
    # the cone QP finds forces inside the cones for the same stance
    qp = sd.contact_inverse_dynamics(model, q, zero, zero, feet, method='qp')
    assert qp.feasible, qp.summary()
    for f in qp.forces.values():
        assert np.hypot(f[0], f[1]) <= 0.1 * f[2] * (1 + 1e-6)


def test_qp_reports_infeasibility(solo):
    # Asking the trunk to accelerate sideways at 3 m/s² on ice (μ = 0.05): no forces in the
    # cones can push it, and the answer says so instead of returning a base torque.
    model, _ = solo
    q = standing_solo(model)
    qdd = np.zeros(model.nv)
    qdd[4] = 3.0
    feet = [sd.Contact(f, mu=0.05) for f in FEET]
    r = sd.contact_inverse_dynamics(model, q, np.zeros(model.nv), qdd, feet, method='qp')
    assert 'infeasible' in r.status and not r.feasible
    assert np.isnan(r.tau).all()
    assert np.abs(r.base_residual).max() > 1.0


def test_unilateral_violation_is_reported(solo):
    # Pulling the trunk down faster than gravity: the feet would have to pull on the floor.
    model, _ = solo
    q = standing_solo(model)
    qdd = np.zeros(model.nv)
    qdd[5] = -20.0
    feet = [sd.Contact(f) for f in FEET]
    r = sd.contact_inverse_dynamics(model, q, np.zeros(model.nv), qdd, feet)
    kinds = {(v.contact, v.kind) for v in r.violations}
    assert {(f, 'unilateral') for f in FEET} <= kinds
    for v in r.violations:
        if v.kind == 'unilateral':
            assert v.amount == pytest.approx(-r.forces[v.contact][2], abs=1e-12)


def test_bad_contact_arguments_are_refused(solo):
    model, _ = solo
    q = standing_solo(model)
    zero = np.zeros(model.nv)
    fixed = sd.Model.from_urdf(robot_urdf_path('solo12'))
    with pytest.raises(ValueError, match='fixed base'):
        sd.contact_inverse_dynamics(fixed, q[7:], zero[6:], zero[6:], [sd.Contact('FL_FOOT')])
    with pytest.raises(ValueError, match="'nowhere' is not a link"):
        sd.contact_inverse_dynamics(model, q, zero, zero, [sd.Contact('nowhere')])
    with pytest.raises(ValueError, match='kind must be one of'):
        sd.Contact('FL_FOOT', kind='line')
    with pytest.raises(ValueError, match='mu must be'):
        sd.Contact('FL_FOOT', mu=-1)
    with pytest.raises(ValueError, match="no force for contact 'FR_FOOT'"):
        sd.contact_inverse_dynamics(model, q, zero, zero,
                                    [sd.Contact('FL_FOOT'), sd.Contact('FR_FOOT')],
                                    measured={'FL_FOOT': [0, 0, 1.0]})
    with pytest.raises(ValueError, match='method must be one of'):
        sd.contact_inverse_dynamics(model, q, zero, zero, [sd.Contact('FL_FOOT')],
                                    method='magic')


@pytest.mark.parametrize('path', ['compiled', 'numpy'])
def test_link_orientations_are_pinocchios_frame_rotations(solo, talos, path, monkeypatch):
    """``link_orientations`` (what turns a contact force into the link's axes) = ``oMf.R``."""
    if path == 'numpy':      # the compiled pass declines: the numpy placements answer
        monkeypatch.setattr(sd.contacts, '_c_bodies', lambda kern, q: None)
    rng = np.random.default_rng(7)
    for (model, pm), links in ((solo, FEET), (talos, SOLES + ('arm_left_7_link',))):
        pd = pm.createData()
        for _ in range(5):
            q = pin.randomConfiguration(pm, -np.ones(pm.nq), np.ones(pm.nq))
            q[:3] = rng.uniform(-3.0, 3.0, 3)
            R = sd.contacts.link_orientations(model, q, links)
            pin.framesForwardKinematics(pm, pd, q)
            for link in links:
                np.testing.assert_allclose(R[link], pd.oMf[pm.getFrameId(link)].rotation,
                                           rtol=0, atol=1e-12)


# -------------------------------------------------------------------------------------------
# redundant contact rows: two contacts on one rigid body

#: The rank tolerance of J_c, relative to its largest row norm (doc/floating_base.md).
RANK_TOLERANCE = 1e-6


def corners(sole):
    """Return the four corners of a 20 x 10 cm sole: points on one body (rank 6 of 12)."""
    return [sd.Contact(sole, offset=(x, y, 0.0), name=f'{sole} {x:+} {y:+}')
            for x in (0.1, -0.1) for y in (0.05, -0.05)]


def beside_fl_foot(*extra):
    """Return Solo12's feet, ``extra`` (on FL's lower leg) right after FL_FOOT."""
    return [sd.Contact('FL_FOOT'), *extra] + [sd.Contact(f) for f in FEET[1:]]


def toe_heel(foot):
    return [sd.Contact(foot, offset=(0.02, 0.0, 0.0), name=f'{foot} toe'),
            sd.Contact(foot, offset=(-0.02, 0.0, 0.0), name=f'{foot} heel')]


#: Each layout the issue lists: (robot, contacts), the redundant rows before the others.
REDUNDANT = {
    'talos, four corners of each sole': ('talos', lambda: corners(SOLES[0]) + corners(SOLES[1])),
    'solo12, a point 1 cm ahead of FL_FOOT': ('solo', lambda: beside_fl_foot(
        sd.Contact('FL_FOOT', offset=(0.01, 0.0, 0.0), name='FL toe'))),
    'solo12, a point 1e-9 m ahead of FL_FOOT': ('solo', lambda: beside_fl_foot(
        sd.Contact('FL_FOOT', offset=(1e-9, 0.0, 0.0), name='FL toe'))),
    'solo12, the 1 cm point first': ('solo', lambda: [
        sd.Contact('FL_FOOT', offset=(0.01, 0.0, 0.0), name='FL toe')] + [
        sd.Contact(f) for f in FEET]),
    'solo12, foot and shin': ('solo', lambda: beside_fl_foot(
        sd.Contact('FL_LOWER_LEG', offset=(0.0, 0.0, -0.08), name='FL shin'))),
    'solo12, toe and heel of both front feet (k = nv)': ('solo', lambda: toe_heel('FL_FOOT')
                                                         + toe_heel('FR_FOOT')
                                                         + [sd.Contact(f) for f in FEET[2:]]),
}


def standing_talos(model):
    q = np.zeros(model.nq)
    q[2], q[6] = 1.02, 1.0
    return q


@pytest.mark.parametrize('backend', ['numpy', 'compiled'])
@pytest.mark.parametrize('layout', list(REDUNDANT))
def test_redundant_contacts_split_is_the_least_torque(solo, talos, layout, backend,
                                                      monkeypatch):
    """Contacts sharing a body: the split carries the base and its τ is the least.

    Oracle: Pinocchio's ``J_c`` and ``rnea``, split by an SVD (conftest's
    ``least_torque_split``); the QP (the cones added) never needs less torque, nor do the
    least contact forces (``'forces'``).
    """
    from spatial_dynamics.backends import compiled
    if backend == 'compiled':
        if compiled.ext is None:
            pytest.skip('built without the kernels')

        def no_numpy(*args):
            raise AssertionError('the compiled split left this case to numpy')
        monkeypatch.setattr(sd.contacts, '_split_numpy', no_numpy)
    robot, make = REDUNDANT[layout]
    model, pm = solo if robot == 'solo' else talos
    contacts = make()
    rng = np.random.default_rng(11)
    q0 = standing_solo(model) if robot == 'solo' else standing_talos(model)
    for k in range(4):
        q, qd, qdd = q0.copy(), np.zeros(model.nv), np.zeros(model.nv)
        if k:                               # moving: joints off the stance, rates, accelerations
            q[7:] += rng.normal(size=model.nq - 7) * 0.05
            qd, qdd = rng.normal(size=(2, model.nv)) * 0.5
        r = sd.contact_inverse_dynamics(model, q, qd, qdd, contacts, backend=backend)
        b = to_pin(pin.rnea(pm, pm.createData(), q, to_pin(qd), to_pin(qdd)))
        Jc = pin_contact_jacobian(pm, q, contacts)
        tau, lam, rank = least_torque_split(Jc, b, RANK_TOLERANCE)
        assert r.status == 'solved' and r.rank == rank < len(Jc), (layout, r.rank, rank)
        assert np.abs(r.base_residual).max() < 1e-11, (layout, r.summary())
        got = np.concatenate([r.forces[c.name] for c in contacts])
        np.testing.assert_allclose(np.r_[np.zeros(6), r.tau] + Jc.T @ got, b, atol=1e-9)
        np.testing.assert_allclose(r.tau, tau, rtol=0, atol=1e-9 * max(1.0, np.abs(tau).max()))
        scale = 1e-9 * max(1.0, np.abs(lam).max())
        if 'e-9 m' in layout:       # nearly one point: the rows left out carry nothing
            assert ((got[:3] == 0) | (got[3:6] == 0)).all(), got[:6]
            np.testing.assert_allclose(got[:6].reshape(2, 3).sum(0), lam[:6].reshape(2, 3).sum(0),
                                       rtol=0, atol=scale)
            np.testing.assert_allclose(got[6:], lam[6:], rtol=0, atol=scale)
        else:                       # dependent rows share the load: the least λ
            np.testing.assert_allclose(got, lam, rtol=0, atol=scale)
        forces = sd.contact_inverse_dynamics(model, q, qd, qdd, contacts, method='forces')
        assert np.abs(forces.base_residual).max() < 1e-9
        assert np.linalg.norm(r.tau) <= np.linalg.norm(forces.tau) + 1e-9
        qp = sd.contact_inverse_dynamics(model, q, qd, qdd, contacts, method='qp')
        if qp.status == 'solved':
            assert np.linalg.norm(r.tau) <= np.linalg.norm(qp.tau) * (1 + 1e-6) + 1e-9


# -------------------------------------------------------------------------------------------
# unilateral contact in the QP; what the split refuses

@pytest.mark.parametrize('mu', [0.0, 0.7])
def test_qp_feet_never_pull_whatever_mu(solo, mu):
    """The trunk accelerating down at 30 m/s² (> g): only pulling feet could; the QP says so.

    Standing still on frictionless feet (μ = 0) is feasible: vertical pushes only.
    """
    model, _ = solo
    q = standing_solo(model)
    zero = np.zeros(model.nv)
    feet = [sd.Contact(f, mu=mu) for f in FEET]
    R = sd.joints.quaternion_matrix(q[3:7])
    qdd = zero.copy()
    qdd[3:6] = R.T @ [0.0, 0.0, -30.0]                  # base frame, world down
    r = sd.contact_inverse_dynamics(model, q, zero, qdd, feet, method='qp')
    assert 'infeasible' in r.status and not r.feasible, r.summary()
    assert np.isnan(r.tau).all()
    r = sd.contact_inverse_dynamics(model, q, zero, zero, feet, method='qp')
    assert r.feasible, r.summary()
    for name, f in r.forces.items():
        assert f[2] > 0.0 and np.hypot(f[0], f[1]) <= mu * f[2] + 1e-6, (name, f)


def test_non_finite_or_zero_normals_are_refused_or_scaled():
    """(0, 0, 1e200) is up; (0, 0, ∞), NaN and zero normals are refused, naming the contact."""
    np.testing.assert_array_equal(sd.Contact('FL_FOOT', normal=(0.0, 0.0, 1e200)).normal,
                                  [0.0, 0.0, 1.0])
    np.testing.assert_allclose(sd.Contact('FL_FOOT', normal=(1e-320, 0.0, 1e-320)).normal,
                               [np.sqrt(0.5), 0.0, np.sqrt(0.5)], rtol=1e-15)
    for normal in ((0.0, 0.0, np.inf), (0.0, np.nan, 1.0), (0.0, 0.0, 0.0)):
        with pytest.raises(ValueError, match="contact 'toe': normal must be a finite non-zero"):
            sd.Contact('FL_FOOT', normal=normal, name='toe')


@pytest.mark.parametrize('backend', ['numpy', 'compiled'])
@pytest.mark.parametrize('method', ['torques', 'forces', 'qp', 'measured'])
def test_non_finite_state_is_one_clear_error_before_lapack(solo, backend, method, capfd):
    """Refuse NaN or ∞ in q, qd, qdd, gravity, or a zero quaternion: a ValueError naming it.

    Never numpy's LinAlgError, nothing on stderr (LAPACK's "DLASCL parameter 4"), never a QP
    that calls a NaN state "infeasible".
    """
    model, _ = solo
    q0 = standing_solo(model)
    zero = np.zeros(model.nv)
    feet = [sd.Contact(f) for f in FEET]
    kw = {'measured': {f: [0.0, 0.0, 6.0] for f in FEET}} if method == 'measured' else {
        'method': method}
    cases = []
    for what, index in (('q', 2), ('q', 9), ('qd', 4), ('qdd', 10)):
        for bad in (np.nan, np.inf):
            args = {'q': q0.copy(), 'qd': zero.copy(), 'qdd': zero.copy()}
            args[what][index] = bad
            cases.append((args, {}, rf'{what} must be finite: {what}\[{index}\] is {bad}'))
    zero_quat = q0.copy()
    zero_quat[3:7] = 0.0
    cases.append(({'q': zero_quat, 'qd': zero, 'qdd': zero}, {},
                  r"q: the free-flyer quaternion of joint 'root_joint' at q\[3:7\] has "
                  r'norm 0'))
    cases.append(({'q': q0, 'qd': zero, 'qdd': zero}, {'gravity': (0.0, 0.0, np.nan)},
                  r'gravity must be finite: gravity\[2\] is nan'))
    for args, more, match in cases:
        with pytest.raises(ValueError, match=match):
            sd.contact_inverse_dynamics(model, args['q'], args['qd'], args['qdd'], feet,
                                        backend=backend, **kw, **more)
    assert capfd.readouterr().err == ''


@pytest.mark.parametrize('backend', ['numpy', 'compiled'])
@pytest.mark.parametrize('method', ['torques', 'forces', 'qp', 'measured'])
def test_a_state_too_large_to_compute_is_named_without_a_warning(solo, backend, method, capfd):
    """``qdd = 1e300`` printed numpy's overflow RuntimeWarning before the ValueError.

    The argument beyond what a real robot reaches is named (the bounds the node holds its
    inputs to), and nothing is printed on stderr.
    """
    model, _ = solo
    q = standing_solo(model)
    zero = np.zeros(model.nv)
    feet = [sd.Contact(f) for f in FEET]
    kw = {'measured': {f: [0.0, 0.0, 6.0] for f in FEET}} if method == 'measured' else {
        'method': method}
    for qd, qdd, match in ((zero, zero + 1e300, r'qdd of index 0 is 1e\+300, beyond ±1e\+06'),
                           (zero + 1e200, zero, r'qd of index 0 is 1e\+200, beyond ±10000')):
        with warnings.catch_warnings():
            warnings.simplefilter('error')
            with pytest.raises(ValueError, match=match):
                sd.contact_inverse_dynamics(model, q, qd, qdd, feet, backend=backend, **kw)
    assert capfd.readouterr().err == ''


def test_contact_arguments_out_of_any_range_are_refused_by_name(solo):
    """A measured wrench, an offset and a mu no robot has are refused, each by its name.

    A measured 1e300 N was 'solved' with τ = inf, an offset of 1e300 m blamed the state, and
    mu='0.5' was a bare TypeError from np.isfinite.
    """
    model, _ = solo
    q = standing_solo(model)
    zero = np.zeros(model.nv)
    feet = [sd.Contact(f) for f in FEET]
    for value in (1e300, 1.1e6, -2e6):
        measured = {f: [0.0, 0.0, 6.0] for f in FEET}
        measured['FL_FOOT'] = [0.0, 0.0, value]
        with pytest.raises(ValueError, match=r"measured\['FL_FOOT'\] must be 3 finite numbers "
                           r'within ±1e\+06 N or N m'):
            sd.contact_inverse_dynamics(model, q, zero, zero, feet, measured=measured)
    # a real foot sensor's reading (1e6 N at most) is taken: τ = b - J_cᵀ λ (Pinocchio)
    measured = {f: [0.0, 0.0, 1e6 if f == 'FL_FOOT' else 6.0] for f in FEET}
    r = sd.contact_inverse_dynamics(model, q, zero, zero, feet, measured=measured)
    _, pm = solo
    b = pin.rnea(pm, pm.createData(), q, np.zeros(pm.nv), np.zeros(pm.nv))
    lam = np.concatenate([measured[f] for f in FEET])
    np.testing.assert_allclose(r.tau, b[6:] - (pin_contact_jacobian(pm, q, feet).T @ lam)[6:],
                               rtol=1e-10, atol=1e-6)
    for offset in ((1e300, 0.0, 0.0), (0.0, -2e5, 0.0), (np.inf, 0.0, 0.0)):
        with pytest.raises(ValueError, match=r"contact 'FL_FOOT': offset must be 3 finite "
                           r'numbers within ±100000 m'):
            sd.Contact('FL_FOOT', offset=offset)
    for mu in ('0.5', None, [0.5], True):
        with pytest.raises(TypeError, match=r"contact 'FL_FOOT': mu must be a number"):
            sd.Contact('FL_FOOT', mu=mu)
    for mu in (np.float32(0.5), np.int64(1), 0.5):
        assert sd.Contact('FL_FOOT', mu=mu).mu == float(mu)


# -------------------------------------------------------------------------------------------
# the QP across the range of μ and of the weights

def qp_reference(pm, q, contacts, a=1.0, c=1e-6, normal_only=False):
    """Return the QP's answer when no cone is active from Pinocchio: ``(τ, λ)`` by its KKT.

    Least ``½ a |τ|² + ½ c |λ|²`` with ``τ = b_j - J_jᵀ λ`` and the base rows
    ``J_bᵀ λ = b_b``; with ``normal_only`` each force along its normal (μ = 0), ``λ = N s``.
    """
    b = to_pin(pin.rnea(pm, pm.createData(), q, np.zeros(pm.nv), np.zeros(pm.nv)))  # ours
    Jc = pin_contact_jacobian(pm, q, contacts)
    N = np.eye(len(Jc))
    if normal_only:
        N = np.zeros((len(Jc), len(contacts)))
        for j, contact in enumerate(contacts):
            N[3 * j:3 * j + 3, j] = contact.normal
    Jj, Jb = N.T @ Jc[:, 6:], N.T @ Jc[:, :6]
    m = len(N.T)
    K = np.block([[a * Jj @ Jj.T + c * N.T @ N, Jb], [Jb.T, np.zeros((6, 6))]])
    s = np.linalg.lstsq(K, np.r_[a * Jj @ b[6:], b[:6]], rcond=None)[0][:m]
    return b[6:] - Jj.T @ s, N @ s


def qp(model, q, feet, **options):
    zero = np.zeros(model.nv)
    return sd.contact_inverse_dynamics(model, q, zero, zero, feet, method='qp', **options)


def test_qp_is_solved_for_every_mu_a_wider_cone_never_worse(solo):
    """μ 1e6 was 'not solved', 1e9 to 1e20 'infeasible', 1e100 and 1e300 a numerical error.

    A wider cone cannot make a standing robot infeasible: beyond the μ where no cone is
    active (0.7 here) the answer is the KKT solution of the equality QP (Pinocchio's ``b``
    and ``J_c``), at μ = 0 that of vertical forces; between, the least torque never grows
    with μ.
    """
    model, pm = solo
    q = standing_solo(model)

    def solved(mu):
        feet = [sd.Contact(f, mu=mu) for f in FEET]
        r = qp(model, q, feet)
        assert r.status == 'solved' and r.feasible, (mu, r.summary())
        return feet, r

    for mu in (0.7, 1.0, 10.0, 1e3, 1e6, 1e9, 1e12, 1e20, 1e100, 1e200, 1e300):
        feet, r = solved(mu)
        tau, lam = qp_reference(pm, q, feet)
        np.testing.assert_allclose(r.tau, tau, atol=1e-8, err_msg=f'mu={mu}')
        np.testing.assert_allclose(np.concatenate([r.forces[f] for f in FEET]), lam,
                                   atol=1e-8, err_msg=f'mu={mu}')
    feet, r = solved(0.0)
    tau, lam = qp_reference(pm, q, feet, normal_only=True)
    np.testing.assert_allclose(r.tau, tau, atol=1e-8)
    least = [r.tau @ r.tau]
    for mu in (1e-3, 0.1, 0.3, 0.7):
        least.append(solved(mu)[1].tau @ solved(mu)[1].tau)
    assert all(b <= a + 1e-6 for a, b in zip(least, least[1:])), least


@pytest.mark.parametrize('what', ['weights', 'force_weight'])
def test_qp_is_solved_for_every_weight_scale(solo, what):
    """``weights=1e300`` or ``force_weight=1e300`` stopped with InsufficientProgress.

    The argmin depends on the weights' ratio only: each is Pinocchio's KKT answer with the
    weights over their largest.
    """
    model, pm = solo
    q = standing_solo(model)
    feet = [sd.Contact(f) for f in FEET]
    for w in (1e-300, 1e-200, 1e-100, 1e-12, 1e-6, 1.0, 1e6, 1e12, 1e100, 1e200, 1e300):
        W, eps = (w, 1e-6) if what == 'weights' else (1.0, w)
        r = qp(model, q, feet, **{what: w})
        assert r.status == 'solved' and r.feasible, (w, r.summary())
        top = max(W, eps)
        tau, lam = qp_reference(pm, q, feet, a=W / top, c=eps / top)
        np.testing.assert_allclose(r.tau, tau, atol=1e-8, err_msg=f'{what}={w}')
        np.testing.assert_allclose(np.concatenate([r.forces[f] for f in FEET]), lam,
                                   atol=1e-8, err_msg=f'{what}={w}')
