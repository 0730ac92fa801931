# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""What delivering one sample to the answering callback costs: the node's loop against rclpy's.

``python -m benchmarks.answering_loop`` (from the checkout, after a build): one process, one
subscription (``sensor_msgs/JointState``, 8 joints, reliable, depth 1000) in a callback group,
a publisher beside it; each of 500 samples is published and then waited for, one at a time
(what 1 kHz looks like: one sample per wait). Process CPU time per sample (publish, wait,
take, callback), the least of 5 repeats, for the node's
:class:`~spatial_dynamics.ros.realtime.AnsweringLoop` and for rclpy's SingleThreadedExecutor
spinning the same group, in the same run; the ratio is what holds on any machine.
"""

import time

import rclpy
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from spatial_dynamics.ros.realtime import AnsweringLoop

SAMPLES = 500
REPEATS = 5


def per_sample(spin_once, publish, received: list) -> float:
    """Return the least process CPU time (µs) per sample over ``REPEATS`` runs."""
    best = float('inf')
    for _ in range(REPEATS):
        received.clear()
        t = time.process_time()
        for i in range(SAMPLES):
            publish()
            while len(received) <= i:
                spin_once(1.0)
        best = min(best, (time.process_time() - t) / SAMPLES * 1e6)
    return best


def main() -> None:
    """Print the CPU per sample of both, and their ratio."""
    rclpy.init()
    try:
        node = rclpy.create_node('answering_loop_benchmark')
        group = MutuallyExclusiveCallbackGroup()
        received: list = []
        qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
        node.create_subscription(JointState, 'samples', received.append, qos,
                                 callback_group=group)
        publisher = node.create_publisher(JointState, 'samples', qos)
        msg = JointState(name=[f'joint{i}' for i in range(8)], position=[0.0] * 8,
                         velocity=[0.0] * 8, effort=[0.0] * 8)
        loop = AnsweringLoop(node, group)
        ours = per_sample(loop.spin_once, lambda: publisher.publish(msg), received)
        loop.shutdown()
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        theirs = per_sample(lambda timeout: executor.spin_once(timeout),
                            lambda: publisher.publish(msg), received)
        executor.shutdown()
        with open('/proc/loadavg') as f:
            load = f.read().split()[0]
        print(f'CPU per sample (publish, wait, take, callback), least of {REPEATS} x {SAMPLES}, '
              f'load {load}:')
        print(f'  AnsweringLoop             {ours:7.1f} µs')
        print(f'  SingleThreadedExecutor    {theirs:7.1f} µs')
        print(f'  ratio                     {ours / theirs:7.2f}')
        node.destroy_node()
    finally:
        rclpy.try_shutdown()


if __name__ == '__main__':
    main()
