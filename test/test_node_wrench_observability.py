# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The node's virtual F/T sensor WARNs where a wrench direction is unobservable, pushed or not.

The node's own answering path without ROS: a UR5 at rest, its drives holding its weight
(``effort`` = g(q), nothing pushing), measured at 1 kHz with the observer on and
``wrench_estimate.link`` = ``tool0``; then the ``external torque`` status of the period. With
the elbow straight the force along the arm loads no joint (``Jᵀ u = 0``): a push along it would
read as nothing, so the status WARNs and names that direction although no external torque
crossed ``external_torque_warn``. At a regular pose (σ_min 0.21 > ε) it is OK.
"""

from types import SimpleNamespace

from conftest import robot_urdf_path
import numpy as np
import spatial_dynamics as sd
from spatial_dynamics.ros import config, configure
from spatial_dynamics.ros.answering import Answering
from spatial_dynamics.ros.diagnostics import observer_status
from spatial_dynamics.wrench import EPSILON

LINK = 'tool0'
GAIN = 20.0                                        # 1/s, the default observer_gain
UR5_REGULAR = [0.3, -1.2, 1.5, -1.0, 1.2, 0.4]     # σ_min 0.21 > ε
UR5_ELBOW_STRAIGHT = [0.3, -1.2, 0.0, -1.0, 1.2, 0.4]
AXES = ('n_x', 'n_y', 'n_z', 'f_x', 'f_y', 'f_z')


class Log:
    """The node's logger as the answering code calls it; keeps the warnings."""

    def __init__(self) -> None:
        self.warnings = []

    def info(self, text, **kwargs) -> None:
        pass

    def warn(self, text, **kwargs) -> None:
        self.warnings.append(text)


def joint_state(names, q, effort, k):
    """Return a measured JointState (duck-typed) at rest, stamped k ms after 100 s."""
    stamp = SimpleNamespace(sec=100, nanosec=k * 1_000_000)
    return SimpleNamespace(header=SimpleNamespace(stamp=stamp), name=list(names),
                           position=[float(x) for x in q], velocity=[0.0] * len(names),
                           effort=[float(x) for x in effort])


def status_after(q, effort, changes=()):
    """Return the ``external torque`` status after 0.3 s at rest at ``q``, given ``effort``."""
    text = open(robot_urdf_path('ur5')).read()
    params = {spec.name: spec.default for spec in config.PARAMETERS}
    params.update({'robot_description': text, 'observer_gain': GAIN,
                   'wrench_estimate.link': LINK, **dict(changes)})
    cfg = configure.prepare({}, params, None)
    robot = cfg.robot
    assert tuple(robot.joints) == tuple(robot.model.joint_names)
    log = Log()
    answering = Answering(log)
    for k in range(300):
        msg = joint_state(robot.joints, q, effort, k)
        answering.measured(cfg, msg)
        out = answering.observe(cfg, msg)
        assert out.wrench is not None and out.wrench[1] == LINK
    assert not log.warnings, log.warnings
    _, estimates = answering.period()
    level, message, values = observer_status(robot, GAIN, answering.observer, estimates)
    return level, message, dict(values)


def status_at_rest(q):
    """Return the status with the drives holding the weight (``effort`` = g(q)), no push."""
    model = sd.Model.from_urdf(robot_urdf_path('ur5'))
    return (model,) + status_after(q, sd.gravity_torque(model, np.array(q)))


def test_elbow_straight_warns_naming_the_unobservable_direction_without_a_push():
    model, level, message, kv = status_at_rest(UR5_ELBOW_STRAIGHT)
    # the pose is singular for tool0: one wrench direction loads no joint
    J = sd.jacobian(model, UR5_ELBOW_STRAIGHT, LINK)
    U, sigma, _ = np.linalg.svd(J)
    assert sigma[-1] < 1e-9 < EPSILON < sigma[-2]
    u = U[:, -1]
    assert np.abs(J.T @ u).max() < 1e-9
    # nothing pushes: the estimate stays below external_torque_warn on every joint
    assert all(float(kv[f'rms {joint}']) < 1e-6 for joint in model.joint_names), kv
    assert kv['of them loaded'] == '0' and kv['wrench samples with weak directions'] == '300'
    assert level == 'WARN', (level, message)
    assert f"external wrench at '{LINK}'" in message and 'could not observe' in message
    named = message.split('missing or underestimated: ')[1].split()
    # the direction named is ±u: its components above 0.2, the largest one positive
    v = np.zeros(6)
    for value, axis in zip(named[::2], named[1::2]):
        v[AXES.index(axis)] = float(value)
    assert v[np.argmax(np.abs(v))] > 0.0
    assert abs(v @ u) / np.linalg.norm(v) > 0.99, (named, u)
    assert np.linalg.norm(J.T @ v) / np.linalg.norm(v) < 0.1 * sigma[-2], (named, u)
    assert 'above external_torque_warn:' not in message


def test_regular_pose_at_rest_is_ok():
    model, level, message, kv = status_at_rest(UR5_REGULAR)
    assert np.linalg.svd(sd.jacobian(model, UR5_REGULAR, LINK), compute_uv=False)[-1] > EPSILON
    assert kv['wrench samples with weak directions'] == '0'
    assert level == 'OK', (level, message)
    assert 'could not observe' not in message


def test_a_push_above_the_threshold_at_the_singular_pose_names_joints_and_direction():
    """A push above ``external_torque_warn`` at the singular pose: both warnings, one status."""
    model = sd.Model.from_urdf(robot_urdf_path('ur5'))
    q = np.array(UR5_ELBOW_STRAIGHT)
    w = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 40.0])     # 40 N along tool0's z
    z = np.zeros(model.nq)
    effort = sd.rnea(model, q, z, z, f_ext={LINK: w})   # the drives hold weight and push
    level, message, kv = status_after(q, effort, {'external_torque_warn': [1.0]})
    assert level == 'WARN'
    assert 'above external_torque_warn:' in message and 'could not observe' in message
    assert int(kv['of them loaded']) > 0
