# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A trivial relay node: the latency baseline for ``inverse_dynamics``.

Same endpoints as the node, made by the node's own ``subscribe`` and ``advertise``
(``desired_joint_states``: best effort, keep last 1; ``feedforward_efforts``: reliable), no
computation: every message received is published as is. Whatever the node's latency exceeds
the relay's in the same run is the node's own cost.

    python -m spatial_dynamics.tools.relay --ros-args -r __ns:=/baseline
"""

import sys
from typing import Optional, Sequence

from rclpy.node import Node
from sensor_msgs.msg import JointState

from spatial_dynamics.ros.common import advertise, spin, subscribe


class Relay(Node):
    """Republish ``desired_joint_states`` on ``feedforward_efforts`` unchanged."""

    def __init__(self) -> None:
        super().__init__('relay')
        self.publisher = advertise(self, JointState, 'feedforward_efforts')
        subscribe(self, JointState, 'desired_joint_states', self.publisher.publish)


def main(args: Optional[Sequence[str]] = None) -> int:
    """Run the relay until SIGINT/SIGTERM; 0 on a clean exit."""
    return spin(Relay, args, 'relay')


if __name__ == '__main__':
    sys.exit(main())
