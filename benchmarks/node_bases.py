# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Time one answer of the node's answering code on a fixed, a moving and a floating base.

``python -m benchmarks.node_bases`` (from the checkout, after a build): ``time.thread_time``,
the minimum of 7 repeats of 200 answers of ``Answering.joint_state`` (what the node runs per
desired message, without DDS): the demo arm fixed and on an IMU base (``base: moving``),
Solo12 standing on four feet (``base: floating``) with each ``contacts.method``.
"""

import os
import sysconfig
import time

from builtin_interfaces.msg import Time
from geometry_msgs.msg import PoseStamped, TwistStamped
from sensor_msgs.msg import Imu, JointState
from spatial_dynamics.ros import config, configure
from spatial_dynamics.ros.answering import Answering

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


class Quiet:
    """A logger that says nothing."""

    def info(self, *_, **__):
        """Say nothing."""

    warn = info


def per_answer(cfg, msg, inputs=(), n=200, repeats=7) -> float:
    """Return the least thread time (µs) of one answer to ``msg`` over ``repeats`` runs."""
    answering = Answering(Quiet())
    best = float('inf')
    for _ in range(repeats):
        for topic, base_msg in inputs:
            answering.base_input(cfg, topic, base_msg)
        t = time.thread_time()
        for _ in range(n):
            out = answering.joint_state(cfg, msg)
        best = min(best, (time.thread_time() - t) / n)
        assert out.answer is not None
    return best * 1e6


def main() -> None:
    params = {spec.name: spec.default for spec in config.PARAMETERS}
    params['base_input.timeout'] = 3600.0    # a slow run must not make the inputs stale
    demo = dict(params, robot_description_file=os.path.join(ROOT, 'config', 'demo_arm.urdf'))
    fixed = configure.prepare({}, demo, None)
    joints = fixed.robot.joints
    n = len(joints)
    msg = JointState(name=list(joints), position=[0.3] * n, velocity=[0.2] * n,
                     effort=[0.1] * n)
    msg.header.stamp = Time(sec=1)
    imu = Imu()
    imu.header.frame_id = 'base_link'
    imu.linear_acceleration.z, imu.angular_velocity.x = 9.81, 0.2
    moving = configure.prepare({}, dict(demo, base='moving',
                                        **{'base_input.imu_link': 'base_link'}), None)
    print(f'demo arm ({n} joints), fixed base:  {per_answer(fixed, msg):8.1f} µs')
    print(f'demo arm, moving base (IMU):     '
          f'{per_answer(moving, msg, [("base/imu", imu)]):8.1f} µs')
    robots = os.path.join(sysconfig.get_paths()['purelib'], 'cmeel.prefix', 'share',
                          'example-robot-data', 'robots')
    solo = os.path.join(robots, 'solo_description', 'robots', 'solo12.urdf')
    pose, twist = PoseStamped(), TwistStamped()
    pose.pose.position.z, pose.pose.orientation.w = 0.25, 1.0
    for method in ('torques', 'forces', 'qp'):
        cfg = configure.prepare({}, dict(params, robot_description_file=solo, base='floating', **{
            'contacts.links': ['FL_FOOT', 'FR_FOOT', 'HL_FOOT', 'HR_FOOT'],
            'contacts.method': method, 'base_input.acceleration': 'zero'}), None)
        joints = cfg.robot.joints
        q = [{'HAA': 0.0, 'HFE': 0.8 if j[0] == 'F' else -0.8,
              'KFE': -1.6 if j[0] == 'F' else 1.6}[j[3:]] for j in joints]
        solo_msg = JointState(name=list(joints), position=q, velocity=[0.0] * 12,
                              effort=[0.0] * 12)
        print(f'Solo12, floating base, {method:8s}  '
              f'{per_answer(cfg, solo_msg, [("base/pose", pose), ("base/twist", twist)]):8.1f}'
              ' µs')


if __name__ == '__main__':
    main()
