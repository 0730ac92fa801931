# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""ROS 2 node ``sim``: the URDF's robot simulated by MuJoCo, driven by effort commands.

``python -m spatial_dynamics.sim`` or ``ros2 run spatial_dynamics sim``. The robot is a
:class:`~spatial_dynamics.sim.robot.SimulatedRobot`: the URDF's rigid-body robot exactly (no
joint limits, contacts, damping or friction; mimic joints follow their source). With
``floating``, a :class:`~spatial_dynamics.sim.floating.FloatingRobot`: the root link on a free
joint, standing on a floor on its ``feet`` (contacts, friction ``friction``).

Topics (relative, so they follow the namespace and can be remapped):

=====================  ====================================  =================================
``effort_commands``    std_msgs/Float64MultiArray, in        reliable, keep last 10; one
                                                             torque (N m or N) per joint of
                                                             ``joints``, in that order (as a
                                                             ros2_control forward command
                                                             controller with interface effort)
``applied_wrench``     geometry_msgs/WrenchStamped, in       reliable, keep last 10; a push
                                                             on link ``header.frame_id``:
                                                             torque, force (N m, N) in that
                                                             link's frame, at its origin;
                                                             held (turning with the link)
                                                             until replaced, zero removes it
``joint_states``       sensor_msgs/JointState, out           reliable; position, velocity and
                                                             effort = the applied command
``base_pose``          geometry_msgs/PoseStamped, out        with ``floating``, each state: the
                                                             root link's pose in ``world``
``base_twist``         geometry_msgs/TwistStamped, out       with ``floating``: its angular
                                                             and linear velocity in its own
                                                             frame (``frame_id``)
``/clock``             rosgraph_msgs/Clock, out              with ``publish_clock``: sim time
=====================  ====================================  =================================

Modes (parameter ``mode``):

* ``realtime``: the physics runs against the wall clock; a state is published each physics
  step (if the process falls behind, the steps due run at once and the last state is
  published). The last good command is held for ``command_timeout`` s, then the torque drops
  to zero with a throttled warning: without commands the drive goes limp and the robot falls.
  Stamps are wall-clock time.
* ``lockstep``: the state of step k is published, then the node waits for exactly one good
  command, applies it for one step and publishes step k+1. While it waits, it republishes the
  current state every 0.1 s of wall time, so a controller that starts late or a lost state
  message cannot deadlock it (a controller must therefore answer each state once, within 0.1 s, or
  its extra answers drive the next steps). Stamps are sim time, from 0.

A bad command (wrong length, NaN or infinite, magnitude above 1e6) is refused with the
reason logged and is not applied; in lockstep it does not count as the step's command.
A wrench on an unknown link, or with a NaN, infinite or larger than 1e6 component, is
refused the same way. An applied wrench acts from the next physics step on (the effort in
``joint_states`` stays the command: the wrench is the environment's push, what an
external-torque observer should find).
"""

from __future__ import annotations

import math
import sys
import time
from typing import Optional, Sequence

from builtin_interfaces.msg import Time
from geometry_msgs.msg import PoseStamped, TwistStamped, WrenchStamped
import numpy as np
from rclpy.node import Node
from rclpy.qos import HistoryPolicy, QoSProfile, QoSReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from spatial_dynamics.bounds import MAX_EFFORT, MAX_POSITION, MAX_WRENCH
from spatial_dynamics.ros.descriptions import read_description

from spatial_dynamics.ros.parameters import ConfigError, Param, ParameterError, Table
from spatial_dynamics.ros.common import advertise, spin
from spatial_dynamics.ros.usage import launch
from spatial_dynamics import Contact
from spatial_dynamics.sim.floating import FloatingRobot
from spatial_dynamics.sim.mujoco_model import Foot, import_mujoco, MujocoMissing
from spatial_dynamics.sim.robot import INTEGRATORS, SimulatedRobot
from std_msgs.msg import Float64MultiArray

NODE_NAME = 'sim'
MODES = ('realtime', 'lockstep')
MAX_COMMAND = MAX_EFFORT      # N m or N: beyond it a command is refused
TIMESTEP_RANGE = (1e-6, 1.0)  # s: the physics step
MAX_COMMAND_TIMEOUT = 3600.0  # s
REPUBLISH_PERIOD = 0.1        # s of wall time, lockstep: the state is sent again while waiting
MAX_CATCH_UP_STEPS = 100      # realtime: steps run in one go when the process fell behind
WARN_PERIOD = 1.0             # s between two warnings of one kind
WRENCH_FIELDS = ('torque.x', 'torque.y', 'torque.z', 'force.x', 'force.y', 'force.z')

#: The sim node's parameters, each written once (read-only: set at start-up).
PARAMETERS = Table(NODE_NAME, [
    Param('robot_description', 'string', '', 'URDF XML text (takes precedence over the '
          'file).', read_only=True),
    Param('robot_description_file', 'string', '', 'Path of a URDF (or .xacro) file.',
          read_only=True),
    Param('joints', 'string[]', None, 'Joints simulated and the order of the commands '
          '(default: all, in the model order); the others are locked at 0, as with the '
          "inverse_dynamics node's joints.", read_only=True),
    Param('command_topic', 'string', 'effort_commands', 'std_msgs/Float64MultiArray of '
          'joint torques, one per joint (reliable, depth 10).', read_only=True),
    Param('state_topic', 'string', 'joint_states', 'sensor_msgs/JointState published each '
          'step: position, velocity, effort = the applied command.', read_only=True),
    Param('timestep', 'double', 0.001, 'Physics step.', unit='s', bounds=TIMESTEP_RANGE,
          read_only=True),
    Param('mode', 'string', 'realtime', 'realtime: against the wall clock, wall-clock '
          'stamps; lockstep: one step per command, sim-time stamps from 0.', choices=MODES,
          read_only=True),
    Param('initial_positions', 'double[]', None, 'Initial position of each joint of joints '
          '(default 0).', unit='rad or m', bounds=(-MAX_POSITION, MAX_POSITION),
          read_only=True),
    Param('command_timeout', 'double', 0.1, 'realtime: a command older than this gives '
          'zero torque (the drive goes limp, the robot falls).', unit='s',
          bounds=(1e-6, MAX_COMMAND_TIMEOUT), read_only=True),
    Param('publish_clock', 'bool', False, 'Publish /clock (rosgraph_msgs/Clock) with the sim '
          'time, for use_sim_time.', read_only=True),
    Param('integrator', 'string', 'auto', 'auto (rk4), rk4 or euler (semi-implicit).',
          choices=INTEGRATORS, read_only=True),
    Param('floating', 'bool', False, 'The root link on a free joint, standing on a floor '
          '(z = 0) on its feet, upright above the origin with its lowest foot on the floor '
          '(contacts on, semi-implicit Euler); base_pose and base_twist carry the base.',
          read_only=True),
    Param('feet', 'string[]', None, 'floating: the links that touch the floor (a contact '
          'geom at the origin of each).', read_only=True),
    Param('foot_size', 'double[]', [0.01], 'floating: one value, a sphere of that radius '
          "centred at each foot's origin; two, a box sole of those half length (x) and "
          "half width (y) whose bottom face is at the foot's origin.", unit='m',
          bounds=(1e-4, 10.0), read_only=True),
    Param('friction', 'double', 0.8, "floating: Coulomb friction coefficient of the feet "
          'on the floor.', bounds=(0.0, 10.0), read_only=True),
], header=(
    'Copyright 2026 spatial_dynamics contributors\n'
    'SPDX-License-Identifier: Apache-2.0\n'
    '\n'
    'Parameters of the `sim` node (spatial_dynamics), all read-only (set at start-up):\n'
    '  ros2 run spatial_dynamics sim --ros-args --params-file config/sim.yaml\n'
    'Generated from the table in spatial_dynamics/sim/node.py (test/test_node_parameter_tables.py '
    'checks it).'))


def command_qos() -> QoSProfile:
    """Command QoS: reliable, keep last 10 (a ros2_control forward command controller's)."""
    return QoSProfile(reliability=QoSReliabilityPolicy.RELIABLE,
                      history=HistoryPolicy.KEEP_LAST, depth=10)


def _first_bad(values: Sequence[float], bound: float, names) -> Optional[str]:
    """Why ``values`` cannot be applied: the first non-finite one, else one beyond ``bound``.

    ``names(i)`` names value ``i`` in the message; None when all are good.
    """
    x = np.asarray(values, dtype=float)
    finite = np.isfinite(x)
    if not finite.all():
        return f'non-finite {names(int(np.argmin(finite)))}'
    if np.abs(x).max(initial=0.0) > bound:
        return f'{names(int(np.argmax(np.abs(x))))} above {bound:g}'
    return None


def check_command(data: Sequence[float], n: int) -> Optional[str]:
    """Why a command cannot be applied to ``n`` joints, or None when it can."""
    if len(data) != n:
        return f'{len(data)} values for {n} joints'
    return _first_bad(data, MAX_COMMAND, lambda i: f'value at index {i}')


def check_wrench(link: str, wrench: Sequence[float], links) -> Optional[str]:
    """Why a wrench ``[n; f]`` cannot be applied to ``link`` (one of ``links``), or None."""
    if link not in links:
        return (f'header.frame_id {link!r} is not a link of the robot (links: '
                f'{", ".join(links)})')
    return _first_bad(wrench, MAX_WRENCH, lambda i: f'component {WRENCH_FIELDS[i]}')


def to_time(seconds: float) -> Time:
    """Convert ``seconds`` (≥ 0) to a builtin_interfaces/Time."""
    sec = math.floor(seconds)
    nanosec = min(int(round((seconds - sec) * 1e9)), 999_999_999)
    return Time(sec=int(sec), nanosec=nanosec)


class SimNode(Node):
    """Steps a :class:`SimulatedRobot` with the commanded torques and publishes its state."""

    def __init__(self, **kwargs) -> None:
        super().__init__(NODE_NAME, **kwargs)
        try:
            params = PARAMETERS.declare(self)
        except ParameterError as err:
            raise ConfigError(str(err)) from None
        p = {param.name: getattr(params, param.field) for param in PARAMETERS.params}
        if p['robot_description']:
            urdf, source = p['robot_description'], 'robot_description'
        elif p['robot_description_file']:
            urdf = read_description(p['robot_description_file'])
            source = f'robot_description_file {p["robot_description_file"]!r}'
        else:
            raise ConfigError('no robot: set robot_description (URDF XML) or '
                              'robot_description_file (a path)')
        self.floating = p['floating']
        try:
            if self.floating:
                self.robot = floating_robot(urdf, p)
                n = len(self.robot.joint_names)
                self.robot.set_state(self.robot.on_floor(p['initial_positions'] or None))
            else:
                self.robot = SimulatedRobot(urdf, joints=p['joints'] or None,
                                            timestep=p['timestep'],
                                            integrator=p['integrator'])
                n = self.robot.model.nq
                q0 = np.zeros(n) if not p['initial_positions'] else p['initial_positions']
                self.robot.set_state(q0, np.zeros(n))
        except ValueError as err:
            raise ConfigError(f'{source}: {err}') from None
        self.mode = p['mode']
        self.timestep = p['timestep']
        self.command_timeout = p['command_timeout']
        self.tau = np.zeros(n)                 # the applied command
        self.command_at: Optional[float] = None
        self.steps = 0
        self.refused = 0
        self._warned = {}
        self.state_pub = advertise(self, JointState, p['state_topic'])
        if self.floating:
            root = self.robot.model.body_names[1]
            self.pose_msg = PoseStamped()
            self.pose_msg.header.frame_id = 'world'
            self.twist_msg = TwistStamped()
            self.twist_msg.header.frame_id = root
            self.pose_pub = advertise(self, PoseStamped, 'base_pose')
            self.twist_pub = advertise(self, TwistStamped, 'base_twist')
        self.clock_pub = None
        if p['publish_clock']:
            self.clock_pub = self.create_publisher(Clock, '/clock', 10)
            self._clock_msg = Clock
        self.create_subscription(Float64MultiArray, p['command_topic'], self._on_command,
                                 command_qos())
        self.create_subscription(WrenchStamped, 'applied_wrench', self._on_wrench,
                                 command_qos())
        self.msg = JointState(name=list(self.robot.joint_names))
        self.get_logger().info(
            f'{self.robot.model.summary()}; {self.mode}, step {self.timestep:g} s '
            f'({self.robot.integrator}); commands on {self.resolve_topic_name(p["command_topic"])}'
            f' for {list(self.robot.joint_names)}')
        self.republish_timer = None
        if self.mode == 'lockstep':
            # restarted at every publish, so it fires REPUBLISH_PERIOD after the last one
            self.republish_timer = self.create_timer(REPUBLISH_PERIOD, self._publish)
        else:
            self.start = time.monotonic()
            self.create_timer(self.timestep, self._realtime_tick)
        self._publish()

    def _warn(self, kind: str, text: str) -> None:
        now = time.monotonic()
        if now - self._warned.get(kind, -math.inf) >= WARN_PERIOD:
            self._warned[kind] = now
            self.get_logger().warning(text)

    def _on_command(self, msg: Float64MultiArray) -> None:
        why = check_command(msg.data, len(self.tau))
        if why is not None:
            self.refused += 1
            self._warn('refused', f'command refused ({self.refused} so far): {why}; '
                       f'expected {len(self.tau)} finite torques for {self.msg.name}')
            return
        self.tau = np.array(msg.data, dtype=float)
        self.command_at = time.monotonic()
        if self.mode == 'lockstep':
            self._step(1)
            self._publish()

    def _on_wrench(self, msg: WrenchStamped) -> None:
        """Apply (or, when zero, remove) the wrench on link ``header.frame_id``."""
        link = msg.header.frame_id
        t, f = msg.wrench.torque, msg.wrench.force
        wrench = [t.x, t.y, t.z, f.x, f.y, f.z]          # [n; f], angular first
        why = check_wrench(link, wrench, list(self.robot.model.frames))
        if why is not None:
            self.refused += 1
            kind = 'wrench link' if link not in self.robot.model.frames else 'wrench value'
            self._warn(kind, f'applied_wrench refused ({self.refused} refused so far): {why}')
            return
        self.robot.apply_wrench(link, wrench if any(wrench) else None)
        self.get_logger().info(f'applied_wrench on {link!r}: '
                               + ('removed' if not any(wrench) else f'[n; f] = {wrench}'),
                               throttle_duration_sec=WARN_PERIOD)

    def _realtime_tick(self) -> None:
        now = time.monotonic()
        due = int((now - self.start) / self.timestep) - self.steps
        if due <= 0:
            return
        if self.command_at is not None and now - self.command_at > self.command_timeout:
            self._warn('timeout', f'no command for {now - self.command_at:.3f} s (timeout '
                       f'{self.command_timeout:g} s): zero torque, the robot goes limp')
            self.tau = np.zeros_like(self.tau)
            self.command_at = None
        if due > MAX_CATCH_UP_STEPS:       # fell far behind: the sim slows down instead
            self.start += (due - MAX_CATCH_UP_STEPS) * self.timestep
            due = MAX_CATCH_UP_STEPS
        self._step(due)
        self._publish()

    def _step(self, count: int) -> None:
        """Run ``count`` physics steps with the held command; say when the state diverged."""
        resets = self.robot.resets
        self.robot.step(self.tau, count)
        self.steps += count
        if self.robot.resets != resets:
            self.get_logger().error(
                f'the simulation diverged and restarted at its initial positions, at rest '
                f'({self.robot.resets} restart(s) so far): {self.robot.reset_reason}; '
                f'command {self.tau.tolist()}', throttle_duration_sec=WARN_PERIOD)

    def _publish(self) -> None:
        msg = self.msg
        if self.mode == 'lockstep':
            msg.header.stamp = to_time(self.robot.time)
        else:
            msg.header.stamp = self.get_clock().now().to_msg()
        q = self.robot.q
        msg.position = (q[7:] if self.floating else q).tolist()
        msg.velocity = self.robot.qd.tolist()
        msg.effort = self.tau.tolist()
        self.state_pub.publish(msg)
        if self.floating:
            self._publish_base(q, self.robot.v, msg.header.stamp)
        if self.clock_pub is not None:
            self.clock_pub.publish(self._clock_msg(clock=to_time(self.robot.time)))
        if self.republish_timer is not None:
            self.republish_timer.reset()

    def _publish_base(self, q: np.ndarray, v: np.ndarray, stamp) -> None:
        """Publish the base's pose (world) and twist (``[ω; v]`` in the base frame)."""
        pose, twist = self.pose_msg, self.twist_msg
        pose.header.stamp = twist.header.stamp = stamp
        p, o = pose.pose.position, pose.pose.orientation
        p.x, p.y, p.z = (float(x) for x in q[:3])
        o.x, o.y, o.z, o.w = (float(x) for x in q[3:7])
        w, u = twist.twist.angular, twist.twist.linear
        w.x, w.y, w.z = (float(x) for x in v[:3])
        u.x, u.y, u.z = (float(x) for x in v[3:6])
        self.pose_pub.publish(pose)
        self.twist_pub.publish(twist)


def floating_robot(urdf: str, p: dict) -> FloatingRobot:
    """Return the :class:`FloatingRobot` of the ``floating`` parameters.

    ``ConfigError`` naming the parameter that cannot be.
    """
    if not p['feet']:
        raise ConfigError('floating: set feet, the links that touch the floor')
    if p['joints']:
        raise ConfigError('floating: joints (model reduction) is not simulated on a '
                          'floating base; leave it unset')
    if p['integrator'] == 'rk4':
        raise ConfigError('floating: the contacts are stepped by semi-implicit Euler; '
                          'integrator must be auto or euler')
    size = tuple(p['foot_size'])
    if len(size) not in (1, 2):
        raise ConfigError(f'foot_size: one value (a sphere) or two (a box sole), got '
                          f'{list(size)}')
    kind = 'point' if len(size) == 1 else 'surface'
    feet = [Foot(Contact(link, kind=kind, mu=p['friction']), size) for link in p['feet']]
    return FloatingRobot(urdf, feet, timestep=p['timestep'])


def main(args: Optional[Sequence[str]] = None) -> int:
    """Run the simulator until SIGINT/SIGTERM; 0 on a clean exit, 1 on a bad start-up.

    With ``-h``/``--help``: its usage, exit 0, nothing started; an unknown option: exit 2.
    """
    def run() -> int:
        try:
            import_mujoco()
        except MujocoMissing as err:
            print(f'{NODE_NAME}: {err}', file=sys.stderr)
            return 1
        return spin(SimNode, args, name=NODE_NAME, threads=1)

    return launch(args, PARAMETERS, 'The URDF\'s robot simulated by MuJoCo, driven by effort '
                  'commands (std_msgs/Float64MultiArray on effort_commands), its joint states '
                  'on joint_states.', 'doc/simulator.md', run)


if __name__ == '__main__':
    sys.exit(main())
