# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Numerical stress suite (``-m stress``): extreme generated robots and states.

Robots come from the seeded generator ``benchmarks.generate.random_robot_urdf``: serial
chains and branching trees up to 500 links mixing revolute, continuous, prismatic, fixed and
``<mimic>`` joints; axes along a frame axis, random unit and non-unit (length 1e-3 to 1e3);
joint and inertial origins at gimbal lock (pitch exactly ±π/2); masses log-uniform in
[1e-6, 1e3] kg; solid bodies, point masses, thin rods, near-zero (1e-9 scaled) inertias and
massless links. States: |q| ≤ 1e4 rad on rotational joints (prismatic ones ±2 m, mimics of
the same kind), |q̇| ≤ 100, |q̈| ≤ 1e3; and moderate ones.

Tolerances are in units of eps = 2.2e-16 and of NB, the number of moving bodies, because the
rounding error of RNEA grows with the length of the paths through the tree. Each constant
says what was measured on these robots (by this suite's own numbers, printed with -s).
"""

import functools

from conftest import PinOracle
import numpy as np
import pytest
import spatial_dynamics as sd
from benchmarks import bench
from benchmarks.generate import (chain_urdf, INERTIA_KINDS, JOINT_KINDS,  # noqa: E402
                                 random_robot_urdf)
from spatial_dynamics.joints import PRISMATIC

pytestmark = [pytest.mark.stress, pytest.mark.slow]

EPS = float(np.finfo(float).eps)
ZERO_G = (0.0, 0.0, 0.0)

#: |τ - τ_pin| ≤ AGREE·eps·NB·max|τ_pin| (the scale is the robot's largest torque over its
#: sampled states). Measured worst: 12.5, on a 2-link chain, over 260 robots from this test's
#: generator (seeds 0-19 at 2-100 links, 0-3 at 200 and 300, 0-1 at 500, chains and trees),
#: both state ranges, numpy and compiled backends, single and batched. Both libraries round
#: (each about eps·NB), and they also differ by how they round the URDF's numbers into float64
#: parameters.
AGREE = 32.0
#: Our error against the mpmath reference on our float64 parameters, relative to max|τ|:
#: ≤ OURS_GROWTH·eps·NB. Measured: at most 0.42·eps·NB (3.4 eps at 8 bodies, 14 eps at 367).
OURS_GROWTH = 2.0
#: err_ours / max(err_pin, 4 eps) ≤ GROWTH_RATIO at every chain length, where each library is
#: compared with the mpmath reference on its own float64 parameters. Measured: at most 1.7
#: (typically 0.2-1.3; ours is the smaller at 300 links on the robot-like chains).
GROWTH_RATIO = 4.0
#: |M - Mᵀ| ≤ SYM·eps·NB·max|M|. Measured: at most 0.21.
SYM = 4.0
#: λ_min(M) ≥ -PSD·eps·NB·λ_max(M) when some links are point masses, rods or massless (M may
#: be singular). Measured: λ_min/λ_max ≥ -0.41 eps.
PSD = 1.0
#: |q̇·τ - dT/dt| ≤ POWER·Σ|q̇_i τ_i|, dT/dt by a 5-point difference. Measured: at most 1.2e-9
#: (the finite difference's own error); a wrong Coriolis term is off by O(1).
POWER = 1e-7

EXTREME = dict(joint_kinds=JOINT_KINDS, p_mimic=0.2, axes=('aligned', 'unit', 'nonunit'),
               mass_range=(1e-6, 1e3), inertia_kinds=INERTIA_KINDS, p_gimbal_lock=0.3)


def extreme_urdf(seed, n_links, branching, **overrides):
    """Generate a robot of n_links + 1 links with every extreme of EXTREME (or overrides)."""
    rng = np.random.default_rng([seed, n_links, int(branching)])
    return random_robot_urdf(rng, n_links + 1, branching=branching,
                             **dict(EXTREME, **overrides)), rng


def prismatic_joints(model):
    """Return a mask over q: True where the joint is prismatic."""
    mask = np.zeros(model.nq, dtype=bool)
    for i in range(1, model.NB + 1):
        k = model.qidx[i]
        if model.body_joints[i] == model.joint_names[k]:
            mask[k] = model.jtype[i] == PRISMATIC
    return mask


def states(rng, model, count, extreme=True):
    """Random (q, qd, qdd) of shape (count, n): extreme or moderate ranges."""
    qmax = np.where(prismatic_joints(model), 2.0, 1e4 if extreme else 3.0)
    qdmax, qddmax = (100.0, 1e3) if extreme else (2.0, 5.0)
    shape = (count, model.nq)
    return (rng.uniform(-qmax, qmax, shape), rng.uniform(-qdmax, qdmax, shape),
            rng.uniform(-qddmax, qddmax, shape))


@functools.lru_cache(maxsize=None)
def backends():
    """Return the backends to stress: numpy, and compiled when it can be imported."""
    names = ['numpy']
    try:
        sd.rnea(sd.Model.from_urdf(chain_urdf(2)), np.zeros(2), np.zeros(2), np.zeros(2),
                backend='compiled')
        names.append('compiled')
    except (ImportError, TypeError, ValueError):
        pass
    return tuple(names)


def mass_matrix(model, q):
    """M(q) from unit accelerations in one batched call (column j = rnea(q, 0, e_j), g = 0)."""
    n = model.nq
    return sd.rnea(model, np.broadcast_to(q, (n, n)), np.zeros((n, n)), np.eye(n),
                   gravity=ZERO_G).T


# --------------------------------------------------------------------------------------------
# Finite, and equal to Pinocchio's, on extreme robots and states

AGREE_CASES = ([(n, seed, b) for n in (2, 5, 10, 20, 50) for seed in range(4)
                for b in (False, True)]
               + [(n, seed, b) for n in (100, 200) for seed in range(2) for b in (False, True)]
               + [(n, 0, b) for n in (300, 500) for b in (False, True)])


@pytest.mark.parametrize('n_links,seed,branching', AGREE_CASES,
                         ids=[f'{"tree" if b else "chain"}{n}-seed{s}'
                              for n, s, b in AGREE_CASES])
def test_extreme_robots_finite_and_agree_with_pinocchio(n_links, seed, branching):
    xml, rng = extreme_urdf(seed, n_links, branching)
    model = sd.Model.from_urdf(xml)
    oracle = PinOracle(xml)
    names = model.joint_names
    for extreme in (True, False):
        q, qd, qdd = states(rng, model, 3, extreme)
        tau_pin = oracle.rnea(names, q, qd, qdd)
        assert np.all(np.isfinite(tau_pin))
        scale = float(np.abs(tau_pin).max())
        tol = AGREE * EPS * model.NB * scale
        for backend in backends():
            batched = sd.rnea(model, q, qd, qdd, backend=backend)
            single = np.array([sd.rnea(model, *s, backend=backend) for s in zip(q, qd, qdd)])
            for how, tau in (('batched', batched), ('single', single)):
                assert np.all(np.isfinite(tau)), (backend, how)
                err = float(np.abs(tau - tau_pin).max())
                assert err <= tol, (f'{backend} {how}: |τ - τ_pin| = {err:.3g} > {tol:.3g} '
                                    f'= {AGREE}·eps·{model.NB}·{scale:.3g}')


# --------------------------------------------------------------------------------------------
# Error growth with chain length, against the 50-digit reference


def growth_errors(xml, rng, extreme):
    """Return (NB, our relative error, Pinocchio's) against mpmath on each one's parameters."""
    import mpmath
    model = sd.Model.from_urdf(xml)
    q, qd, qdd = states(rng, model, 3, extreme)
    ref = bench.reference(model, q, qd, qdd)
    scale = float(np.abs(ref).max())
    err = float(np.abs(sd.rnea(model, q, qd, qdd).astype(np.longdouble) - ref).max()) / scale
    robot = bench.Robot('chain', xml, model, 'chain')
    ref_pin = bench.reference(bench.pinocchio_reference_rows(robot, mpmath), q, qd, qdd)
    tau_pin = PinOracle(xml).rnea(model.joint_names, q, qd, qdd)
    return model.NB, err, float(np.abs(tau_pin.astype(np.longdouble) - ref_pin).max()) / scale


GROWTH = [('robot-like', 0), ('robot-like', 1), ('extreme, no mimic', 0),
          ('extreme, no mimic', 1)]


@pytest.mark.parametrize('family,seed', GROWTH, ids=[f'{f}-seed{s}' for f, s in GROWTH])
def test_error_grows_no_faster_than_pinocchio(family, seed):
    """Error vs links on chains of 10..500 links: ours ≤ GROWTH_RATIO × Pinocchio's.

    Each library is compared with mpmath (50 digits) on its own float64 parameters, so the
    figures are arithmetic error, not the different rounding of the URDF's decimal numbers
    (which the benchmark shows separately). Chains without ``<mimic>`` here: at |q| = 1e4 the
    float64 mimic angle mult·q + offset carries an error of ~1e4 eps that both libraries share
    and that would hide everything else. The robot-like chains stop at 300 links because
    Pinocchio 4.1 needs 15-45 s to create its Data for 500 joints; the extreme 500-link chains
    keep about 370 moving bodies (the rest are fixed joints, lumped) and are quick.
    """
    curve = []
    for n in (10, 30, 100, 300) + (() if family == 'robot-like' else (500,)):
        if family == 'robot-like':
            xml, rng = chain_urdf(n, seed=seed), np.random.default_rng(seed)
        else:
            xml, rng = extreme_urdf(seed, n, False, p_mimic=0.0)
        NB, ours, pin = growth_errors(xml, rng, family != 'robot-like')
        curve.append((NB, ours / EPS, pin / EPS))
        assert ours <= OURS_GROWTH * EPS * NB, curve
        assert ours <= GROWTH_RATIO * max(pin, 4 * EPS), curve
    print(f'\n{family} seed {seed}: (NB, ours/eps, pinocchio/eps) =',
          [(n, round(a, 2), round(b, 2)) for n, a, b in curve])


# --------------------------------------------------------------------------------------------
# Mass matrix and power balance on extreme robots

MM_CASES = [(n, seed, b) for n in (3, 10, 30, 100) for seed in range(3) for b in (False, True)]
MM_IDS = [f'{"tree" if b else "chain"}{n}-seed{s}' for n, s, b in MM_CASES]


@pytest.mark.parametrize('n_links,seed,branching', MM_CASES, ids=MM_IDS)
def test_mass_matrix_symmetric_positive_definite(n_links, seed, branching):
    """Solid (or 1e-9-scaled) bodies everywhere: M is positive definite (Cholesky)."""
    xml, rng = extreme_urdf(seed, n_links, branching, inertia_kinds=('solid', 'tiny'))
    model = sd.Model.from_urdf(xml)
    for q in states(rng, model, 2)[0]:
        M = mass_matrix(model, q)
        assert np.abs(M - M.T).max() <= SYM * EPS * model.NB * np.abs(M).max()
        np.linalg.cholesky(0.5 * (M + M.T))


@pytest.mark.parametrize('n_links,seed,branching', MM_CASES, ids=MM_IDS)
def test_mass_matrix_psd_with_degenerate_bodies(n_links, seed, branching):
    """Point masses, rods and massless links: M symmetric positive semi-definite."""
    xml, rng = extreme_urdf(seed, n_links, branching)
    model = sd.Model.from_urdf(xml)
    for q in states(rng, model, 2)[0]:
        M = mass_matrix(model, q)
        top = np.abs(M).max()
        assert np.abs(M - M.T).max() <= SYM * EPS * model.NB * top
        lam = np.linalg.eigvalsh(0.5 * (M + M.T))
        assert lam[0] >= -PSD * EPS * model.NB * max(lam[-1], 0.0), lam[[0, -1]]


def five_point(fun, x, h):
    """Return the 5-point central difference derivative of fun at x (error O(h^4))."""
    return (fun(x - 2 * h) - 8 * fun(x - h) + 8 * fun(x + h) - fun(x + 2 * h)) / (12 * h)


@pytest.mark.parametrize('n_links,seed,branching', MM_CASES, ids=MM_IDS)
def test_power_balance(n_links, seed, branching):
    """q̇·τ = dT/dt with T = ½ q̇ᵀ M(q) q̇ along q(t) = q + q̇ t + q̈ t²/2 (no gravity)."""
    xml, rng = extreme_urdf(seed, n_links, branching)
    model = sd.Model.from_urdf(xml)
    for q, qd, qdd in zip(*states(rng, model, 2)):
        def kinetic(t):
            qt, qdt = q + qd * t + 0.5 * qdd * t * t, qd + qdd * t
            return 0.5 * qdt @ sd.rnea(model, qt, np.zeros_like(qt), qdt, gravity=ZERO_G)

        tau = sd.rnea(model, q, qd, qdd, gravity=ZERO_G)
        h = 1e-3 / (1.0 + np.abs(qd).max() + np.sqrt(np.abs(qdd).max()))
        dT = five_point(kinetic, 0.0, h)
        assert abs(qd @ tau - dT) <= POWER * np.abs(qd * tau).sum(), (qd @ tau, dT)


# --------------------------------------------------------------------------------------------
# Degenerate descriptions fail clearly, naming the element

ARM = """<?xml version="1.0"?>
<robot name="degenerate">
  <link name="base"/>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="upper"/>
    <origin xyz="0 0 0.1" rpy="0 0 0"/>
    <axis xyz="0 0 1"/>
    <limit effort="10" velocity="1" lower="-1" upper="1"/>
  </joint>
  <link name="upper">
    <inertial><origin xyz="0 0 0.2" rpy="0 0 0"/><mass value="1.5"/>
      <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.01"/></inertial>
  </link>
  <joint name="elbow" type="continuous">
    <parent link="upper"/><child link="fore"/>
    <origin xyz="0 0 0.4" rpy="0 1.5707963267948966 0"/>
    <axis xyz="0 1 0"/>
  </joint>
  <link name="fore">
    <inertial><origin xyz="0.1 0 0" rpy="0 0 0"/><mass value="0.8"/>
      <inertia ixx="0.003" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.004"/></inertial>
  </link>
  <joint name="finger" type="prismatic">
    <parent link="fore"/><child link="tip"/>
    <origin xyz="0.2 0 0" rpy="0 0 0"/>
    <axis xyz="1 0 0"/>
    <mimic joint="elbow" multiplier="0.01" offset="0"/>
  </joint>
  <link name="tip">
    <inertial><mass value="0.1"/>
      <inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-5" iyz="0" izz="1e-5"/></inertial>
  </link>
</robot>
"""

# (case, text in ARM, replacement, regex the error must match: it names the element)
DEGENERATE = [
    ('zero-length axis', '<axis xyz="0 1 0"/>', '<axis xyz="0 0 0"/>',
     r"joint 'elbow'.*zero-length axis"),
    ('1e-15 axis', '<axis xyz="0 1 0"/>', '<axis xyz="0 1e-15 0"/>',
     r"joint 'elbow'.*zero-length axis"),
    ('negative mass', '<mass value="1.5"/>', '<mass value="-1.5"/>',
     r"link 'upper'.*negative mass"),
    ('NaN mass', '<mass value="1.5"/>', '<mass value="nan"/>', r"link 'upper'.*non-finite"),
    ('Inf inertia', 'ixx="0.003"', 'ixx="inf"', r"link 'fore'.*non-finite"),
    ('overflowing 1e400', 'ixx="0.003"', 'ixx="1e400"', r"link 'fore'.*non-finite"),
    ('NaN joint xyz', 'xyz="0 0 0.1"', 'xyz="0 nan 0.1"', r"joint 'shoulder'.*non-finite"),
    ('-Inf joint rpy', 'rpy="0 1.5707963267948966 0"', 'rpy="0 -inf 0"',
     r"joint 'elbow'.*non-finite"),
    ('NaN inertial origin', 'xyz="0 0 0.2"', 'xyz="0 0 nan"', r"link 'upper'.*non-finite"),
    ('Inf axis', '<axis xyz="1 0 0"/>', '<axis xyz="inf 0 0"/>', r"joint 'finger'.*non-finite"),
    ('NaN limit', 'effort="10"', 'effort="nan"', r"joint 'shoulder'.*limit.*non-finite"),
    ('NaN mimic multiplier', 'multiplier="0.01"', 'multiplier="nan"',
     r"joint 'finger'.*mimic.*non-finite"),
    ('1e308 joint xyz', 'xyz="0 0 0.1"', 'xyz="0 0 1e308"', r"joint 'shoulder'.*absurd"),
    ('1e308 mass', '<mass value="0.8"/>', '<mass value="1e308"/>', r"link 'fore'.*absurd"),
    ('1e308 inertia', 'izz="0.01"', 'izz="1e308"', r"link 'upper'.*absurd"),
    ('1e308 axis', '<axis xyz="0 0 1"/>', '<axis xyz="0 0 1e308"/>', r"joint 'shoulder'.*absurd"),
    ('1e308 mimic offset', 'offset="0"', 'offset="1e308"', r"joint 'finger'.*mimic.*absurd"),
]


# Physically inconsistent but computable: refused in strict mode, else loaded with a warning.
INCONSISTENT = [
    ('negative principal moment', 'izz="0.01"', 'izz="-0.01"',
     r"link 'upper'.*not positive semi-definite"),
    ('indefinite products of inertia', 'ixy="0" ixz="0" iyy="0.02"', 'ixy="0.05" ixz="0" '
     'iyy="0.02"', r"link 'upper'.*not positive semi-definite"),
    ('triangle inequality', 'izz="0.004"', 'izz="0.006"', r"link 'fore'.*triangle inequality"),
]


def test_degenerate_base_arm_loads():
    model = sd.Model.from_urdf(ARM)
    assert model.joint_names == ('shoulder', 'elbow')
    assert np.all(np.isfinite(sd.rnea(model, np.ones(2), np.ones(2), np.ones(2))))


@pytest.mark.filterwarnings('ignore:invalid value encountered:RuntimeWarning')
@pytest.mark.parametrize('case,old,new,message', DEGENERATE, ids=[d[0] for d in DEGENERATE])
def test_degenerate_urdf_fails_naming_the_element(case, old, new, message):
    assert ARM.count(old) == 1, case
    with pytest.raises(ValueError, match=message):
        sd.Model.from_urdf(ARM.replace(old, new))


@pytest.mark.parametrize('case,old,new,message', INCONSISTENT, ids=[d[0] for d in INCONSISTENT])
def test_inconsistent_urdf_fails_in_strict_mode_and_warns_otherwise(case, old, new, message):
    assert ARM.count(old) == 1, case
    with pytest.raises(ValueError, match=message):
        sd.Model.from_urdf(ARM.replace(old, new), strict=True)
    with pytest.warns(sd.URDFWarning, match=message):
        model = sd.Model.from_urdf(ARM.replace(old, new))
    assert np.all(np.isfinite(sd.rnea(model, np.ones(2), np.ones(2), np.ones(2))))
