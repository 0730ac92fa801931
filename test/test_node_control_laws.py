# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The node's control law without ROS: ``spatial_dynamics.ros.control`` and its parameters.

Gains and modes refused with the reason, the continuous-joint wrap, the measured state by
name with its bounds, and the answers: each mode and output equals its formula written with
the library's public functions, and the terms sum to the answer.
"""

import itertools
import math
import os
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from node_harness import DEMO_URDF  # noqa: E402
import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics.ros import config, configure, control, diagnostics  # noqa: E402
from spatial_dynamics.ros.config import ConfigError  # noqa: E402
from spatial_dynamics.ros.control import (  # noqa: E402
    answer, ControlError, Dynamics, Gains, InputError)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TOL = 1e-10   # N m: the same library, summed in another order


@pytest.fixture(scope='module')
def model():
    return sd.Model.from_urdf(DEMO_URDF)


def defaults(**changes) -> dict:
    """Every parameter at its declared default (unset arrays as None), then ``changes``."""
    params = {spec.name: spec.default for spec in config.PARAMETERS}
    params.update(changes)
    return params


def test_control_never_imports_rclpy():
    script = textwrap.dedent('''\
        import sys
        from spatial_dynamics.ros import control
        print('ROS:', sorted(m for m in sys.modules if m.split('.')[0] in
                             ('rclpy', 'rcl_interfaces', 'sensor_msgs', 'std_msgs')))
    ''')
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [ROOT] + [p for p in os.environ.get('PYTHONPATH', '').split(os.pathsep) if p]))
    proc = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True,
                          cwd=ROOT, env=env, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert 'ROS: []' in proc.stdout, proc.stdout


# --------------------------------------------------------------------------------------------
# Parameters

def test_gains_one_for_all_or_one_per_joint(model):
    n = len(model.joint_names)
    np.testing.assert_array_equal(control.check_gains(model, 'kp', [5.0]), np.full(n, 5.0))
    np.testing.assert_array_equal(control.check_gains(model, 'kd', []), np.zeros(n))
    np.testing.assert_array_equal(control.check_gains(model, 'kd', None), np.zeros(n))
    per = [float(k) for k in range(n)]
    gains = control.check_gains(model, 'kp', per)
    np.testing.assert_array_equal(gains, per)
    assert not gains.flags.writeable


@pytest.mark.parametrize('name, values, words', [
    ('kp', [1.0, 2.0], ['parameter kp', '2 values', 'joint1']),
    ('kp', [-1.0], ['parameter kp', 'joint1', '-1.0', 'from 0']),
    ('kd', [math.nan], ['parameter kd', 'nan']),
    ('kd', [math.inf], ['parameter kd', 'inf']),
    ('kp', [2e6], ['parameter kp', '1e+06', 'N·m/rad', '1/s²']),
    ('kd', [2e4], ['parameter kd', '10000', 'N·m·s/rad', '1/s']),
])
def test_bad_gains_refused_with_the_reason(model, name, values, words):
    with pytest.raises(ControlError) as err:
        control.check_gains(model, name, values)
    for word in words:
        assert word in str(err.value), (word, str(err.value))


def test_bad_gain_of_one_joint_named(model):
    values = [1.0] * len(model.joint_names)
    values[6] = -3.0
    with pytest.raises(ControlError, match="'joint7' has -3.0"):
        control.check_gains(model, 'kd', values)


def test_output_none_refused_in_feedforward_only():
    for mode, output in itertools.product(control.CONTROL_MODES, control.OUTPUTS):
        if (mode, output) == ('feedforward', 'none'):
            with pytest.raises(ControlError, match='zeros'):
                control.check_mode(mode, output)
        else:
            assert control.check_mode(mode, output) == (mode, output)
    with pytest.raises(ControlError, match='parameter output'):
        control.check_mode('feedforward', 'everything')
    with pytest.raises(ControlError, match='parameter control_mode'):
        control.check_mode('pid', 'full')


def test_prepare_checks_modes_and_gains(model):
    text = open(DEMO_URDF).read()
    params = defaults(robot_description=text)
    cfg = configure.prepare({}, params, None)
    assert (cfg.params.control_mode, cfg.params.output) == ('feedforward', 'full')
    np.testing.assert_array_equal(cfg.robot.gains.kp, np.zeros(len(model.joint_names)))
    cfg = configure.prepare(cfg.params, {'control_mode': 'pd_feedforward', 'output': 'none',
                                         'kp': [100.0], 'measured_timeout': 0.2}, cfg.robot)
    assert (cfg.params.control_mode, cfg.params.output, cfg.params.measured_timeout) == \
        ('pd_feedforward', 'none', 0.2)
    np.testing.assert_array_equal(cfg.robot.gains.kp, np.full(len(model.joint_names), 100.0))
    # then back to feedforward while output is none: refused, naming both
    with pytest.raises(ConfigError, match="output 'none' and control_mode 'feedforward'"):
        configure.prepare(cfg.params, {'control_mode': 'feedforward'}, cfg.robot)
    with pytest.raises(ConfigError, match='parameter kp: 3 values'):
        configure.prepare(cfg.params, {'kp': [1.0, 2.0, 3.0]}, cfg.robot)
    # a description with another joint count is refused while kp has one value per joint
    per_joint = configure.prepare(cfg.params, {'kp': [1.0] * 8}, cfg.robot)
    with pytest.raises(ConfigError, match='parameter kp: 8 values for the 1 joints'):
        configure.prepare(per_joint.params, {'robot_description': open(
            os.path.join(ROOT, 'config', 'pendulum.urdf')).read()}, per_joint.robot)
    # without a model, what needs none is checked
    with pytest.raises(ConfigError, match='parameter kd'):
        configure.prepare({}, defaults(kd=[-1.0]), None)


def test_continuous_joints_are_revolute_without_limits(model):
    mask = control.continuous_joints(model)
    assert [name for name, c in zip(model.joint_names, mask) if c] == ['joint7']


# --------------------------------------------------------------------------------------------
# The measured state and the position error

def test_position_error_wraps_continuous_joints_only():
    pi = math.pi
    q_d = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 3.0, 0.1])
    q = np.array([-pi, pi, 3 * pi, -2.5 * pi, 0.3, -3.0, 0.1 + 4 * pi])
    wrapped = control.position_error(q_d, q, np.ones(7, dtype=bool))
    np.testing.assert_allclose(wrapped, [pi, pi, pi, 0.5 * pi, -0.3, 6.0 - 2 * pi, 0.0],
                               rtol=0, atol=1e-12)
    assert ((wrapped > -pi) & (wrapped <= pi)).all()
    np.testing.assert_array_equal(control.position_error(q_d, q, np.zeros(7, dtype=bool)),
                                  q_d - q)


def test_measured_state_by_name(model):
    names = model.joint_names
    n = len(names)
    q, qd = np.linspace(-1, 1, n), np.linspace(2, -2, n)
    order = list(reversed(range(n)))
    got_q, got_qd = control.measured_arrays(
        names, [names[i] for i in order] + ['extra'], list(q[order]) + [99.0],
        list(qd[order]) + [math.nan], True)
    np.testing.assert_array_equal(got_q, q)
    np.testing.assert_array_equal(got_qd, qd)
    got_q, got_qd = control.measured_arrays(names, names, q, [], False)
    assert got_qd is None


@pytest.mark.parametrize('change, reason, words', [
    (dict(velocity=[]), 'no_velocity', ["'velocity' is empty"]),
    (dict(position=[0.0]), 'length_mismatch', ["'position'"]),
    (dict(drop=True), 'missing_joint', ["'finger_joint1'"]),
    (dict(nan=True), 'non_finite', ["'velocity'", "'joint3'"]),
    (dict(big_q=True), 'out_of_bounds', ["'position'", "'joint2'", '100000']),
    (dict(big_qd=True), 'out_of_bounds', ["'velocity'", "'joint4'", '10000']),
])
def test_bad_measured_state_refused_with_the_reason(model, change, reason, words):
    names = list(model.joint_names)
    q, qd = [0.1] * len(names), [0.2] * len(names)
    if change.get('drop'):
        names, q, qd = names[:-1], q[:-1], qd[:-1]
    if change.get('nan'):
        qd[2] = math.nan
    if change.get('big_q'):
        q[1] = 2e5
    if change.get('big_qd'):
        qd[3] = -2e4
    q = change.get('position', q)
    qd = change.get('velocity', qd)
    with pytest.raises(InputError) as err:
        control.measured_arrays(model.joint_names, names, q, qd, True)
    assert err.value.reason == reason
    assert reason in control.MEASURED_REASONS
    for word in words:
        assert word in str(err.value), (word, str(err.value))


# --------------------------------------------------------------------------------------------
# Answers: formulas and the term split

def _setup(model, seed, wrench=True, armature=True, friction=True):
    rng = np.random.default_rng(seed)
    n = len(model.joint_names)
    desired = tuple(rng.uniform(-1.0, 1.0, n) * s for s in (2.0, 1.5, 4.0))
    measured = tuple(d[:] + rng.uniform(-0.3, 0.3, n) for d in desired[:2])
    dyn = Dynamics(model, (0.3, -0.2, -9.7), 'numpy',
                   np.linspace(0.01, 0.2, n) if armature else None,
                   0.05 if friction else None,
                   {'hand': np.array([0.1, -0.2, 0.3, 4.0, -2.0, 10.0])} if wrench else None)
    gains = Gains(np.linspace(10.0, 80.0, n), np.linspace(1.0, 8.0, n),
                  control.continuous_joints(model))
    return dyn, desired, measured, gains


def _full(dyn, q, qd, qdd):
    tau = sd.rnea(dyn.model, q, qd, qdd, gravity=dyn.gravity, f_ext=dyn.f_ext)
    if dyn.armature is not None:
        tau = tau + sd.armature_torque(dyn.armature, qdd)
    if dyn.friction_threshold is not None:
        tau = tau + sd.friction_torque(dyn.model, qd, dyn.friction_threshold)
    return tau


def _expected(dyn, mode, output, desired, measured, gains):
    """Each mode's formula, written with the library's public functions and M(q)."""
    q_d, qd_d, qdd_d = desired
    g = sd.gravity_torque
    if mode == 'feedforward':
        q, qd, fb = q_d, qd_d, 0.0
    else:
        q, qd = measured
        e = control.position_error(q_d, q, gains.continuous)
        u = gains.kp * e + gains.kd * (qd_d - qd)
        if mode == 'pd_feedforward':
            q, qd, fb = q_d, qd_d, u
        else:
            arm = 0.0 if dyn.armature is None else dyn.armature
            fb = sd.mass_matrix(dyn.model, q) @ u + arm * u
    part = {'full': _full(dyn, q, qd, qdd_d),
            'without_gravity': _full(dyn, q, qd, qdd_d) - g(dyn.model, q, dyn.gravity),
            'gravity_only': g(dyn.model, q, dyn.gravity),
            'none': 0.0}[output]
    return part + fb


@pytest.mark.parametrize('mode, output', [
    pair for pair in itertools.product(control.CONTROL_MODES, control.OUTPUTS)
    if pair != ('feedforward', 'none')])
def test_answers_equal_their_formulas_and_terms_sum_to_them(model, mode, output):
    for seed, extras in ((1, {}), (2, dict(wrench=False, armature=False, friction=False))):
        dyn, desired, measured, gains = _setup(model, seed, **extras)
        want = _expected(dyn, mode, output, desired, measured, gains)
        fast, none = answer(dyn, mode, output, desired, measured, gains)
        assert none is None
        np.testing.assert_allclose(fast, want, rtol=0, atol=TOL)
        tau, terms = answer(dyn, mode, output, desired, measured, gains, with_terms=True)
        np.testing.assert_allclose(tau, want, rtol=0, atol=TOL)
        expected_terms = control.OUTPUT_TERMS[output] + (
            ('feedback',) if mode in control.FEEDBACK_MODES else ())
        assert tuple(terms) == expected_terms
        np.testing.assert_array_equal(sum(terms.values()), tau)


def test_computed_torque_full_is_inverse_dynamics_of_the_commanded_acceleration(model):
    dyn, desired, measured, gains = _setup(model, 3)
    q_d, qd_d, qdd_d = desired
    q, qd = measured
    e = control.position_error(q_d, q, gains.continuous)
    qdd = qdd_d + gains.kp * e + gains.kd * (qd_d - qd)
    tau, _ = answer(dyn, 'computed_torque', 'full', desired, measured, gains)
    np.testing.assert_allclose(tau, _full(dyn, q, qd, qdd), rtol=0, atol=TOL)


def test_each_term_is_its_part_of_the_dynamics(model):
    """Check gravity = g(q), velocity_product = C q̇, inertial = M q̈, external = −Σ Jᵀ f."""
    dyn, desired, measured, gains = _setup(model, 4)
    q, qd, qdd = desired
    _, terms = answer(dyn, 'pd_feedforward', 'full', desired, measured, gains, True)
    m = dyn.model
    g = sd.gravity_torque(m, q, dyn.gravity)
    np.testing.assert_allclose(terms['gravity'], g, rtol=0, atol=TOL)
    np.testing.assert_allclose(terms['velocity_product'],
                               sd.bias_torque(m, q, qd, dyn.gravity) - g, rtol=0, atol=TOL)
    np.testing.assert_allclose(terms['inertial'], sd.mass_matrix(m, q) @ qdd, rtol=0,
                               atol=1e-9)
    np.testing.assert_allclose(terms['armature'], dyn.armature * qdd, rtol=0, atol=0)
    np.testing.assert_allclose(terms['friction'], sd.friction_torque(m, qd, 0.05), rtol=0,
                               atol=0)
    zero = np.zeros(len(q))
    np.testing.assert_allclose(
        terms['external'], sd.rnea(m, q, zero, zero, gravity=(0.0, 0.0, 0.0), f_ext=dyn.f_ext),
        rtol=0, atol=TOL)   # −Σ Jᵀ f does not depend on q̇, q̈ or gravity
    e = control.position_error(desired[0], measured[0], gains.continuous)
    np.testing.assert_array_equal(terms['feedback'],
                                  gains.kp * e + gains.kd * (desired[1] - measured[1]))
    names = control.terms_names(('a', 'b'), ('gravity', 'feedback'))
    assert names == ['a/gravity', 'b/gravity', 'a/feedback', 'b/feedback']


def test_feedback_status_names_why_the_measured_state_is_refused(model):
    """Measured states that come and are refused: the status names the refusal, not 'none'."""
    from sensor_msgs.msg import JointState
    from spatial_dynamics.ros.answering import Answering
    from node_harness import Log
    text = open(DEMO_URDF).read()
    cfg = configure.prepare({}, defaults(robot_description=text, control_mode='pd_feedforward'),
                            None)
    answering = Answering(Log())
    joints = cfg.robot.joints
    rest = len(joints) - 1
    msg = JointState(name=list(joints[1:]), position=[0.0] * rest, velocity=[0.0] * rest)
    assert answering.measured(cfg, msg).answer is None      # the first joint missing
    window, _ = answering.period()
    level, message, values = diagnostics.feedforward_status(cfg.robot, window, answering.totals,
                                                            cfg.params, {}, time.monotonic_ns())
    assert level == 'ERROR' and 'no measured state on joint_states yet' in message, message
    assert 'missing_joint' in message and joints[0] in message, message
    assert 'missing_joint' in dict(values)['last measured state rejection']


def test_feedback_status_names_the_stale_measured_state(model):
    text = open(DEMO_URDF).read()
    robot = configure.prepare({}, defaults(robot_description=text), None).robot
    totals, window = diagnostics.Totals(), diagnostics.Window()
    now = window.start_ns + 2_000_000_000
    table = config.PARAMETERS
    settings = table.changed(table.defaults(),
                             {'control_mode': 'pd_feedforward', 'measured_timeout': 0.1})
    level, message, values = diagnostics.feedforward_status(robot, window, totals, settings,
                                                            {}, now)
    assert level == 'ERROR' and 'no measured state' in message
    totals.last_measured_ns = now - 50_000_000
    level, message, _ = diagnostics.feedforward_status(robot, window, totals, settings, {}, now)
    assert level == 'ERROR' and 'no desired state' in message
    totals.last_desired_ns = now - 10_000_000
    window.received = window.answered = 10
    level, message, values = diagnostics.feedforward_status(robot, window, totals, settings,
                                                            {}, now)
    assert (level, message) == ('OK', '5.0 Hz')
    assert dict(values)['control mode'] == 'pd_feedforward'
    totals.last_measured_ns = now - 200_000_000
    level, message, values = diagnostics.feedforward_status(robot, window, totals, settings,
                                                            {}, now)
    assert level == 'ERROR' and message.startswith('measured state stale'), message
    assert dict(values)['measured state stale'] == 'True'
    totals.last_measured_ns = now
    totals.last_desired_ns = now - 600_000_000
    level, message, _ = diagnostics.feedforward_status(robot, window, totals, settings, {}, now)
    assert level == 'ERROR' and message.startswith('desired state stale'), message
    # feedforward ignores the measured state
    settings = config.PARAMETERS.defaults()
    totals.last_input_ns = now
    level, message, _ = diagnostics.feedforward_status(robot, window, totals, settings, {}, now)
    assert level == 'OK'
