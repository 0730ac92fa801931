# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A trivial relay node: the latency baseline for ``inverse_dynamics``.

Same endpoints as the node, made by the node's own ``subscribe`` and ``advertise``
(``desired_joint_states``: best effort, keep last 1; ``feedforward_efforts``: reliable), the
same answering thread (its callback group spun alone, :func:`~spatial_dynamics.ros.common.spin`)
and the same ``thread_priority`` (default 0 here: the benchmark passes the node's), no
computation: every message received is published as is. Whatever the node's latency exceeds
the relay's in the same run is the node's own cost.

    python -m spatial_dynamics.tools.relay --ros-args -r __ns:=/baseline
"""

import sys
from typing import Optional, Sequence

from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.node import Node
from sensor_msgs.msg import JointState

from spatial_dynamics.ros import realtime
from spatial_dynamics.ros.common import advertise, spin, subscribe


class Relay(Node):
    """Republish ``desired_joint_states`` on ``feedforward_efforts`` unchanged."""

    def __init__(self) -> None:
        super().__init__('relay')
        self.priority = self.declare_parameter('thread_priority', 0).value
        self.answering_group = MutuallyExclusiveCallbackGroup()
        self.publisher = advertise(self, JointState, 'feedforward_efforts')
        subscribe(self, JointState, 'desired_joint_states', self.publisher.publish,
                  group=self.answering_group)

    def on_answering_thread(self) -> None:
        """Apply ``thread_priority`` as the node does; what is refused is one WARN."""
        warning = realtime.warning(realtime.apply(self.priority, None, False))
        if warning:
            self.get_logger().warn(warning)
        realtime.keep_collector_off_answers()


def main(args: Optional[Sequence[str]] = None) -> int:
    """Run the relay until SIGINT/SIGTERM; 0 on a clean exit."""
    return spin(Relay, args, 'relay', threads=3)   # as the node: answering + two others


if __name__ == '__main__':
    sys.exit(main())
