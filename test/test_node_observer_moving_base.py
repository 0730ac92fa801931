# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The node's external-torque observer on a moving base (``base: moving``), without ROS.

A closed-form trajectory of the base (turning about a tilted axis, translating, its pose and
body-frame twist published on ``base/pose`` and ``base/twist``) and of the demo arm's joints;
the measured effort is ``τ_m = rnea(q, q̇, q̈, base=motion) − τ_ext`` with a known step of
``τ_ext``. Oracle: De Luca's observer is ``τ_ext`` through the first-order filter
``ṙ = K_O (τ_ext − r)``; in its discrete form (:mod:`spatial_dynamics.ros.observer`) the
filter of the trapezoidal means of ``τ_ext`` over the samples. Without the base's twist the
observer is off (``base_input.source: imu``) or skips the sample (none held yet), never
computed as if the base were fixed.
"""

import math
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from node_harness import DEMO_URDF  # noqa: E402
import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics.ros.answering import Answering  # noqa: E402
from spatial_dynamics.ros.bases import observer_off  # noqa: E402
from spatial_dynamics.ros.diagnostics import observer_status  # noqa: E402
from spatial_dynamics.ros.observer import MomentumObserver  # noqa: E402
from spatial_dynamics.ros.parameters import ConfigError  # noqa: E402
from test_node_base_inputs import configured, joint_state, Log, pose, twist  # noqa: E402

H = 1e-3                     # s, sample interval (1 kHz joint_states)
K = 20.0                     # 1/s, observer_gain: time constant 50 ms
T0 = 1.0                     # s, the first stamp
STEP = 150                   # the sample from which τ_ext acts
AXIS = np.array([0.3, 0.4, math.sqrt(0.75)])   # the base turns about it (unit, tilted)


@pytest.fixture(scope='module')
def demo_text():
    with open(DEMO_URDF) as f:
        return f.read()


def base_motion(t):
    """Return the base at ``t``: ``(position, quaternion x y z w, twist [ω; v], its rate)``.

    Turning by ``θ(t)`` about the fixed ``AXIS`` (so ``ω = θ̇ AXIS`` in the base frame too);
    the body-frame linear velocity in closed form; the rate is the derivative of the twist's
    components (the spatial acceleration, see :mod:`spatial_dynamics.base`).
    """
    theta, theta_d, theta_dd = (0.6 * math.sin(1.5 * t), 0.9 * math.cos(1.5 * t),
                                -1.35 * math.sin(1.5 * t))
    quat = np.r_[AXIS * math.sin(theta / 2), math.cos(theta / 2)]
    v = np.r_[theta_d * AXIS, 0.4 * math.sin(2 * t), 0.3 * math.cos(1.7 * t), 0.1 * t]
    a = np.r_[theta_dd * AXIS, 0.8 * math.cos(2 * t), -0.51 * math.sin(1.7 * t), 0.1]
    return np.array([0.5 * t, 0.0, 0.2]), quat, v, a


def joints(t, n):
    s = np.arange(1, n + 1)
    return (0.5 * np.sin(1.1 * s * t + s), 0.5 * 1.1 * s * np.cos(1.1 * s * t + s),
            -0.5 * (1.1 * s) ** 2 * np.sin(1.1 * s * t + s))


def run(cfg, samples, tau_ext, with_base=True):
    """Feed ``samples`` of the trajectory to an Answering; return its estimates and what else.

    ``τ_m = rnea(base=...) − τ_ext`` from sample ``STEP`` on; the base's pose and twist come
    just before each joint state (unless ``with_base`` is False).
    """
    robot = cfg.robot
    model = robot.model
    assert robot.joints == model.joint_names
    n = len(robot.joints)
    answering = Answering(Log())
    fixed = MomentumObserver(model, K)          # what a fixed-base observer would say
    out = {'r': [], 'fixed': [], 'ext': []}
    for k in range(samples):
        t = T0 + k * H
        position, quat, v, a = base_motion(t)
        q, qd, qdd = joints(t, n)
        ext = tau_ext if k >= STEP else np.zeros(n)
        tau_m = sd.rnea(model, q, qd, qdd, base=sd.BaseMotion(v, a, quat)) - ext
        if with_base:
            assert answering.base_input(cfg, 'base/pose', pose(t, position, quat)) is None
            assert answering.base_input(cfg, 'base/twist', twist(t, v)) is None
        msg = joint_state(robot.joints, t, q, qd, tau_m)
        answering.measured(cfg, msg)
        estimate = answering.observe(cfg, msg).estimate
        out['r'].append(None if estimate is None else np.array(estimate[2]))
        out['fixed'].append(fixed.update(t, q, qd, tau_m).copy())
        out['ext'].append(ext)
    return answering, out


def first_order(ext, gain, h):
    """Return the discrete observer's response to ``ext`` (samples): trapezoids, filtered."""
    r = np.zeros_like(ext)
    decay = math.exp(-gain * h)
    for k in range(1, len(ext)):
        r[k] = decay * r[k - 1] + (1.0 - decay) * 0.5 * (ext[k] + ext[k - 1])
    return r


def test_step_on_a_moving_base_follows_the_first_order_response(demo_text):
    cfg = configured(robot_description=demo_text, base='moving', observer_gain=K,
                     **{'base_input.source': 'twist', 'base_input.acceleration': 'zero',
                        'base_input.timeout': 3600.0})
    n = len(cfg.robot.joints)
    tau_ext = np.linspace(2.0, -1.5, n)
    samples = STEP + int(5 / K / H) + 1
    answering, out = run(cfg, samples, tau_ext)
    r = np.array(out['r'])
    expected = first_order(np.array(out['ext']), K, H)
    # The base's motion is large in the momentum: the fixed-base observer of the same data is
    # off by more than the step itself.
    assert np.abs(np.array(out['fixed'])[STEP - 1]).max() > np.abs(tau_ext).max()
    # Before the step ~0, after it (1 − e^{−K t}) τ_ext; the only error is the trapezoidal
    # rule's on the smooth part of w = τ_m + β over each 1 ms step, h²/12 |ẅ| (measured
    # 6.8e-5 N m: the last joint swings at up to 4.4 rad/s, 39 rad/s²): 1e-4 of the step.
    np.testing.assert_allclose(r, expected, rtol=0, atol=1e-4 * np.abs(tau_ext).max())
    k = STEP + int(round(1 / K / H))     # one time constant after the step: 1 − 1/e of it
    np.testing.assert_allclose(r[k], (1 - math.exp(-K * (k - STEP + 0.5) * H)) * tau_ext,
                               rtol=0, atol=1e-4 * np.abs(tau_ext).max())
    # 5 time constants: e^-5 = 0.7 % of the step left
    np.testing.assert_allclose(r[-1], tau_ext, rtol=0, atol=0.01 * np.abs(tau_ext).max())
    assert answering.observer.samples == samples
    level, text, values = observer_status(cfg.robot, K, answering.observer,
                                          answering.period()[1], observer_off(cfg.params))
    assert level == 'OK' and 'observer off' not in text, text
    assert dict(values)['estimates'] == str(samples)


def test_without_the_base_twist_nothing_is_estimated(demo_text):
    # source twist, but no base/twist or base/pose yet: each sample skipped (base_missing),
    # never estimated as if the base were fixed.
    cfg = configured(robot_description=demo_text, base='moving', observer_gain=K,
                     **{'base_input.source': 'twist'})
    n = len(cfg.robot.joints)
    answering, out = run(cfg, 20, np.ones(n), with_base=False)
    assert all(r is None for r in out['r'])
    _, estimates = answering.period()
    assert estimates.count == 0 and estimates.skipped['base_missing'] == 20
    level, text, _ = observer_status(cfg.robot, K, answering.observer, estimates,
                                     observer_off(cfg.params))
    assert level == 'WARN' and 'skipped (base_missing 20)' in text, text
    assert 'no measured effort' not in text, text


def test_the_observer_is_off_with_an_imu_and_says_why(demo_text):
    cfg = configured(robot_description=demo_text, base='moving', observer_gain=K,
                     **{'base_input.source': 'imu', 'base_input.imu_link': 'base_link'})
    n = len(cfg.robot.joints)
    answering = Answering(Log())
    msg = joint_state(cfg.robot.joints, T0, np.zeros(n), np.zeros(n), np.ones(n))
    answering.measured(cfg, msg)
    assert answering.observe(cfg, msg).estimate is None and answering.observer is None
    level, text, _ = observer_status(cfg.robot, K, None, answering.period()[1],
                                     observer_off(cfg.params))
    assert level == 'OK' and text.startswith('observer off (base moving with '
                                             'base_input.source imu:'), text
    assert "needs the base's twist" in text
    assert observer_off(configured(robot_description=demo_text).params) == ''


def test_the_wrench_estimate_follows_the_observer(demo_text):
    # wrench_estimate.link needs the observer: accepted and published where it runs (source
    # twist), refused where it is off (source imu)
    link = list(sd.Model.from_urdf(DEMO_URDF).frames)[-1]
    cfg = configured(robot_description=demo_text, base='moving', observer_gain=K,
                     **{'base_input.source': 'twist', 'base_input.timeout': 3600.0,
                        'wrench_estimate.link': link})
    n = len(cfg.robot.joints)
    answering = Answering(Log())
    position, quat, v, _ = base_motion(T0)
    answering.base_input(cfg, 'base/pose', pose(T0, position, quat))
    answering.base_input(cfg, 'base/twist', twist(T0, v))
    for k in range(2):
        msg = joint_state(cfg.robot.joints, T0 + k * H, np.zeros(n), np.zeros(n), np.ones(n))
        answering.measured(cfg, msg)
        out = answering.observe(cfg, msg)
        assert out.estimate is not None and out.wrench[1] == link and out.wrench[2].shape == (6,)
    with pytest.raises(ConfigError, match='wrench_estimate.link: not supported with base '
                       'moving with base_input.source imu'):
        configured(robot_description=demo_text, base='moving',
                   **{'base_input.source': 'imu', 'base_input.imu_link': 'base_link',
                      'wrench_estimate.link': link})
