# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The momentum observer on a simulated robot: contact torque recovered, zero without contact.

A :class:`~spatial_dynamics.sim.robot.SimulatedRobot` (MuJoCo, 1 ms RK4 steps) tracks a
trajectory under PD + feed-forward (the gains and trajectory of the closed-loop demo); the
observer gets each state after a step with the torque applied during it, as the ``sim`` node
publishes them. A wrench applied to the last link with ``apply_wrench`` is recovered as
``τ_ext = Jᵀw = −RNEA(q, 0, 0, g = 0, f_ext = w)`` at the current q; a step of it follows
``1 − e^{−K t}``; without contact the estimate stays near zero on a fast trajectory; armature
and damping in the simulator show up in the estimate exactly as the model misses them.
"""

import math
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from conftest import robot_urdf_path  # noqa: E402
import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics.ros.inputs import InputError  # noqa: E402
from spatial_dynamics.ros.observer import (  # noqa: E402
    check_warn, EstimateWindow, MAX_OBSERVER_GAIN, measured_effort,
    MomentumObserver, ObserverError, sample_time)
from spatial_dynamics.tools.closed_loop import gains, start_point, Trajectory  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEMO_URDF = os.path.join(ROOT, 'config', 'demo_arm.urdf')
H = 1e-3                    # s, physics step and sample interval
K = 20.0                    # 1/s, observer gain: time constant 50 ms
WRENCH = np.array([0.5, -0.3, 0.2, 10.0, -5.0, 8.0])   # [n; f] N m, N in the link frame


def urdf_of(robot):
    return DEMO_URDF if robot == 'demo_arm' else robot_urdf_path(robot)


def sim_robot(robot, **kwargs):
    pytest.importorskip('mujoco')
    from spatial_dynamics.sim.robot import SimulatedRobot
    return SimulatedRobot(urdf_of(robot), timestep=H, **kwargs)


def contact_torque(model, q, link, wrench):
    """``Jᵀw`` of a wrench ``[n; f]`` on ``link`` (its frame): RNEA with gravity and motion off."""
    z = np.zeros(model.nq)
    return -sd.rnea(model, q, z, z, gravity=(0.0, 0.0, 0.0), f_ext={link: wrench})


def run(robot, observer, steps, trajectory=None, wrench_at=None, link=None):
    """Track ``trajectory`` (None: hold the start) with PD + feed-forward for ``steps`` steps.

    Returns per step ``(t, q, qd, tau, r)`` arrays; the wrench is applied from step
    ``wrench_at`` on (it acts during that step, so the sample after it is the first to see it).
    """
    model = robot.model
    q0 = start_point(model)
    kp, kd = gains(model, q0, 'pd_feedforward', 5.0)
    robot.set_state(q0)
    z = np.zeros(model.nq)
    out = {key: [] for key in ('t', 'q', 'qd', 'tau', 'r')}
    for k in range(steps):
        if trajectory is None:
            q_d, qd_d, qdd_d = q0, z, z
        else:
            q_d, qd_d, qdd_d = trajectory(robot.time + H)
        tau = (sd.rnea(model, q_d, qd_d, qdd_d) + kp * (q_d - robot.q)
               + kd * (qd_d - robot.qd))
        if k == wrench_at:
            robot.apply_wrench(link, WRENCH)
        robot.step(tau)
        r = observer.update(robot.time, robot.q, robot.qd, tau)
        for key, value in zip(out, (robot.time, robot.q, robot.qd, tau, r.copy())):
            out[key].append(value)
    return {key: np.array(value) for key, value in out.items()}


def first_order(x, gain, dt):
    """``x`` (steps, n) through the observer's exact first-order filter, from zero."""
    decay = math.exp(-gain * dt)
    y, out = np.zeros(x.shape[1]), []
    for row in x:
        y = decay * y + (1.0 - decay) * row
        out.append(y)
    return np.array(out)


@pytest.mark.parametrize('name', ['ur5', 'demo_arm'])
def test_constant_wrench_recovered_as_jt_w_after_five_time_constants(name):
    robot = sim_robot(name)
    model = robot.model
    link = list(model.frames)[-1]
    observer = MomentumObserver(model, K)
    start = 200
    out = run(robot, observer, start + int(10 / K / H), wrench_at=start, link=link)
    assert np.abs(out['r'][:start]).max() < 1e-3    # holding still, no contact: ~0
    for k in (start + int(5 / K / H), len(out['t']) - 1):
        ref = contact_torque(model, out['q'][k], link, WRENCH)
        error = np.linalg.norm(out['r'][k] - ref) / np.linalg.norm(ref)
        # 5 time constants: e^-5 = 0.7 % of the step left (measured 0.6 % UR5, 1.3 % demo
        # arm, whose 8 cm deflection moves J); 10: 1e-5 and 2e-4
        assert error < 0.03, (k, error, out['r'][k], ref)


@pytest.mark.parametrize('name', ['ur5', 'demo_arm'])
def test_step_of_the_wrench_follows_the_first_order_response(name):
    robot = sim_robot(name)
    model = robot.model
    link = list(model.frames)[-1]
    observer = MomentumObserver(model, K)
    start = 200
    out = run(robot, observer, start + int(2 / K / H) + 1, wrench_at=start, link=link)
    # t = 1/K after the step: 1 - e^-1 of Jᵀw (the arm deflects a little meanwhile)
    k = start + int(round(1 / K / H))
    ref = contact_torque(model, out['q'][k], link, WRENCH)
    fraction = out['r'][k] @ ref / (ref @ ref)
    assert fraction == pytest.approx(1.0 - math.exp(-1.0), abs=0.02)
    # exactly: the first-order filter of Jᵀw(q(t)) as it was at each sample
    refs = np.array([contact_torque(model, q, link, WRENCH) if i >= start else np.zeros(model.nq)
                     for i, q in enumerate(out['q'])])
    filtered = first_order(refs, K, H)
    scale = np.linalg.norm(ref)
    assert np.abs(out['r'] - filtered).max() < 0.01 * scale


@pytest.mark.parametrize('name', ['ur5', 'demo_arm'])
def test_no_contact_stays_near_zero_on_a_fast_trajectory(name):
    robot = sim_robot(name)
    model = robot.model
    observer = MomentumObserver(model, K)
    out = run(robot, observer, 4000, Trajectory(start_point(model), 0.4))
    torque = np.abs(out['tau']).max()
    level = np.abs(out['r'][int(5 / K / H):]).max()
    # measured: 0.027 N m of 62 N m (UR5), 0.065 of 51 N m (demo arm): half a sample of
    # torque rate, as the simulator's effort is the command held over the step before
    assert level < 2.5e-3 * torque, (level, torque)
    assert torque > 20.0    # the trajectory is fast: the torques are large


def test_armature_and_damping_given_cancel_not_given_show_the_mismatch():
    armature = np.array([0.3, 0.3, 0.2, 0.05, 0.05, 0.05])
    damping = np.array([3.0, 3.0, 2.0, 0.5, 0.5, 0.5])
    robot = sim_robot('ur5', armature=armature, damping=damping)
    model = robot.model
    trajectory = Trajectory(start_point(model), 0.4)
    told = MomentumObserver(model, K, armature=armature, friction=lambda qd: damping * qd)
    out = run(robot, told, 3000, trajectory)
    torque = np.abs(out['tau']).max()
    assert np.abs(out['r'][int(5 / K / H):]).max() < 2.5e-3 * torque

    robot = sim_robot('ur5', armature=armature, damping=damping)
    naive = MomentumObserver(model, K)        # a model without rotor inertia and damping
    out = run(robot, naive, 3000, trajectory)
    # what the model misses, per step: -(A q̈ + D q̇), means over the step, filtered
    qd = np.vstack([np.zeros(model.nq), out['qd']])
    missed = -(armature * np.diff(qd, axis=0) / H + damping * 0.5 * (qd[1:] + qd[:-1]))
    expected = first_order(missed, K, H)
    assert np.abs(expected).max() > 1.0       # a mismatch worth seeing (N m)
    assert np.abs(out['r'] - expected).max() < 0.01 * np.abs(expected).max()


def test_repeats_gaps_and_time_going_back():
    model = sd.Model.from_urdf(DEMO_URDF)
    n = model.nq
    q, qd = np.full(n, 0.2), np.full(n, 0.1)
    tau = sd.rnea(model, q, np.zeros(n), np.zeros(n))
    observer = MomentumObserver(model, K, max_gap=0.5)
    assert not observer.update(1.0, q, qd, tau).any()       # the first sample: r = 0
    r = observer.update(1.001, q, qd, tau + 1.0)
    assert r.any()
    assert observer.update(1.001, q, qd, tau + 5.0) is None     # the same sample again
    assert observer.update(1.0005, q, qd, tau) is not None      # back in time: restart
    assert observer.resets == 1 and 'backwards' in observer.reset_reason
    assert observer.samples == 1 and not observer.r.any()
    observer.update(1.7, q, qd, tau)                            # 0.7 s gap > max_gap
    assert observer.resets == 2 and 'gap' in observer.reset_reason
    observer.reset()
    assert observer.resets == 2 and observer.samples == 0


def test_at_rest_holding_gravity_the_estimate_is_the_extra_torque():
    model = sd.Model.from_urdf(DEMO_URDF)
    n = model.nq
    q, z = np.linspace(-0.5, 0.5, n), np.zeros(n)
    g = sd.gravity_torque(model, q)
    extra = np.linspace(1.0, 2.0, n)
    observer = MomentumObserver(model, K)
    for k in range(200):                # at rest: measured = g - τ_ext, so r -> τ_ext
        r = observer.update(k * 0.01, q, z, g - extra)
    assert r == pytest.approx(extra * (1.0 - math.exp(-K * 199 * 0.01)), rel=1e-9)
    # a sample interval ten times the time constant is stable (exact discretisation)
    observer = MomentumObserver(model, MAX_OBSERVER_GAIN)
    for k in range(5):
        r = observer.update(k * 0.01, q, z, g - extra)
    assert r == pytest.approx(extra, rel=1e-4)


def test_the_observer_gain_is_checked_by_its_table_entry_alone():
    """``observer_gain``'s bounds are written once, in the node's table: no second check."""
    from spatial_dynamics.ros import config, observer
    from spatial_dynamics.ros.parameters import ConfigError
    defaults = config.PARAMETERS.defaults()
    for good in (0.0, 20, MAX_OBSERVER_GAIN):
        assert config.PARAMETERS.changed(defaults, {'observer_gain': good}).observer_gain == good
    for bad in (-1.0, math.nan, math.inf, MAX_OBSERVER_GAIN * 1.01):
        with pytest.raises(ConfigError, match='observer_gain'):
            config.PARAMETERS.changed(defaults, {'observer_gain': bad})
    assert not hasattr(observer, 'check_observer_gain')


def test_parameters_and_measured_effort_refused_with_the_reason():
    names = ('a', 'b', 'c')
    assert check_warn(names, [5.0]).tolist() == [5.0] * 3
    assert check_warn(names, [1.0, 2.0, 3.0]).tolist() == [1.0, 2.0, 3.0]
    for bad in ([0.0], [-1.0], [math.nan], [1e7]):
        with pytest.raises(ObserverError, match='external_torque_warn'):
            check_warn(names, bad)
    with pytest.raises(ObserverError, match='2 values for the 3 joints'):
        check_warn(names, [1.0, 2.0])
    assert measured_effort(names, ['c', 'x', 'a', 'b'], [3.0, 9.0, 1.0, 2.0]).tolist() == [
        1.0, 2.0, 3.0]
    for effort, reason in (([], 'no_effort'), ([1.0, 2.0], 'length_mismatch'),
                           ([1.0, math.nan, 3.0], 'non_finite'),
                           ([1.0, 1e308, 3.0], 'out_of_bounds'),
                           ([-1e300, 2.0, 3.0], 'out_of_bounds')):
        with pytest.raises(InputError) as err:
            measured_effort(names, ['a', 'b', 'c'], effort)
        assert err.value.reason == reason
    with pytest.raises(InputError) as err:
        measured_effort(names, ['a', 'b', 'x'], [1.0, 2.0, 3.0])
    assert err.value.reason == 'missing_joint'
    assert sample_time(1, 500_000_000) == 1.5 and sample_time(0, 1) == 1e-9
    assert sample_time(0, 0) is None     # not stamped: never the receipt time


def test_window_rms_per_joint():
    window = EstimateWindow()
    assert window.rms() is None
    for r in ([3.0, 0.0], [-4.0, 1.0]):
        window.add(np.array(r))
    assert window.rms().tolist() == pytest.approx([math.sqrt(12.5), math.sqrt(0.5)])


def test_a_sample_stamped_closer_than_any_sensor_is_refused_and_the_estimate_kept():
    # Δp/Δt over 1 µs would be a clock's artefact, not a measurement: refused with the
    # reason, the observer's state kept, and the next real sample integrated as if the
    # refused one had never come (the estimate of an observer that never saw it)
    model = sd.Model.from_urdf(DEMO_URDF)
    n = model.nq
    q, z = np.linspace(-0.5, 0.5, n), np.zeros(n)
    g = sd.gravity_torque(model, q)
    extra = np.linspace(1.0, 2.0, n)
    observer, reference = MomentumObserver(model, K), MomentumObserver(model, K)
    for t in (1.0, 1.001):
        observer.update(t, q, z, g - extra)
        reference.update(t, q, z, g - extra)
    r = observer.r.copy()
    with pytest.raises(InputError) as refused:
        observer.update(1.001 + 1e-6, q, np.full(n, 0.5), g + 100.0)
    assert refused.value.reason == 'interval_too_short' and '1e-06 s' in str(refused.value)
    assert observer.refused_reason == str(refused.value)
    np.testing.assert_array_equal(observer.r, r)
    assert observer.samples == 2 and observer.resets == 0
    np.testing.assert_array_equal(observer.update(1.002, q, z, g - extra),
                                  reference.update(1.002, q, z, g - extra))
    assert observer.r == pytest.approx(extra * (1.0 - math.exp(-K * 0.002)), rel=1e-9)
    # a real sensor's fastest interval is taken
    assert observer.update(1.002 + 2e-5, q, z, g - extra) is not None
