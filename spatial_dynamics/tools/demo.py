# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Demo: the ``inverse_dynamics`` node on the embedded demo arm, torques live, then a plot.

    python -m spatial_dynamics.tools.demo [--duration 10] [--rate 100] [--plot out/demo.png]

Starts the node as its own process (the installed ``lib/spatial_dynamics/inverse_dynamics``
when the package is found on ``AMENT_PREFIX_PATH``, as ``ros2 run`` would, else
``python -m spatial_dynamics.ros.node``) on ``config/demo_arm.urdf`` in the namespace
``/spatial_dynamics_demo``, and publishes a smooth trajectory there: q, q̇ and q̈ of sinusoids
(consistent: q̇ = dq/dt, q̈ = dq̇/dt) as sensor_msgs/JointState with q̈ in the effort field (the
node's default ``acceleration_source: effort``). The torques the node answers on
``feedforward_efforts`` are shown as a table refreshed in place, until Ctrl-C or
``--duration`` s counted from the node's first answer (a node that has not answered within
:data:`STARTUP_LIMIT` s, or has exited, ends the demo with a message). Then τ over time is
written as a PNG (needs matplotlib; without it the plot is skipped with a note).
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import time
from typing import List, Optional, Sequence, Tuple

from .driving import node_command, pyplot, redraw, robot_model, save_figure, Sinusoids, start, stop

# rclpy and the ROS messages are imported inside the functions that run a node: the options
# are parsed (and --help printed) without ROS, and rclpy alone takes some 0.1 s to import.

NAMESPACE = '/spatial_dynamics_demo'
#: s of wall time the node has to answer first (a cold start on a busy machine takes a few).
STARTUP_LIMIT = 60.0


def parse_args(argv: Optional[Sequence[str]]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog='python -m spatial_dynamics.tools.demo',
                                     description=__doc__.split('\n\n')[0])
    parser.add_argument('--duration', type=float, default=None,
                        help='seconds of answers to show, counted from the node\'s first '
                        'answer (default: until Ctrl-C)')
    parser.add_argument('--rate', type=float, default=100.0,
                        help='publish rate of the trajectory, Hz (default 100)')
    parser.add_argument('--plot', default=os.path.join('out', 'demo_torques.png'),
                        help='PNG of the torques over time (default out/demo_torques.png; '
                             "'' for none)")
    parser.add_argument('--urdf', default=None, help='robot (default: the embedded demo arm)')
    parser.add_argument('--node-log', default=os.path.join('out', 'demo_node.log'),
                        help="file for the node's output (default out/demo_node.log)")
    return parser.parse_args(argv)


class Recorder:
    """The answers: time since start, τ per output joint, and the round-trip latency."""

    def __init__(self) -> None:
        self.t: List[float] = []
        self.first: Optional[float] = None    # time.monotonic() of the first answer
        self.tau: List[Tuple[float, ...]] = []
        self.names: Tuple[str, ...] = ()
        self.latency_ms: List[float] = []
        self.compute_us = ''
        self.t0 = time.monotonic()

    def on_answer(self, msg) -> None:
        now = time.time_ns()
        if self.first is None:
            self.first = time.monotonic()
        self.t.append(time.monotonic() - self.t0)
        self.tau.append(tuple(msg.effort))
        self.names = tuple(msg.name)
        sent = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        self.latency_ms.append((now - sent) * 1e-6)

    def on_diagnostics(self, msg) -> None:
        for status in msg.status:
            if status.name == f'{NAMESPACE.lstrip("/")}/inverse_dynamics: feedforward':
                for kv in status.values:
                    if kv.key == 'compute time mean [us]':
                        self.compute_us = kv.value


def over(recorder: Recorder, duration: Optional[float], start_time: float) -> bool:
    """Whether the demo has shown ``duration`` s of answers (or waited too long for one)."""
    now = time.monotonic()
    if recorder.first is None:
        if now - start_time > STARTUP_LIMIT:
            print(f'the node gave no answer within {STARTUP_LIMIT:.0f} s', file=sys.stderr)
            return True
        return False
    return duration is not None and now - recorder.first >= duration


def table(recorder: Recorder, q, qd, qdd, names: Sequence[str], rate: float) -> List[str]:
    """Lines of the live table: one row per joint, latest τ and the state sent."""
    elapsed = time.monotonic() - recorder.t0
    recent = recorder.latency_ms[-100:]
    lines = [f'inverse_dynamics demo: t = {elapsed:6.1f} s, {rate:g} Hz, '
             f'{len(recorder.t)} answers, latency {sum(recent) / len(recent):5.2f} ms'
             if recent else f'inverse_dynamics demo: t = {elapsed:6.1f} s, waiting for the '
             'node to answer ...',
             f'node compute time {recorder.compute_us or "-"} us (diagnostics)',
             f'{"joint":<16}{"q":>9}{"qd":>9}{"qdd":>9}{"tau [N·m|N]":>14}']
    tau = dict(zip(recorder.names, recorder.tau[-1])) if recorder.tau else {}
    for i, name in enumerate(names):
        value = f'{tau[name]:14.3f}' if name in tau else f'{"-":>14}'
        lines.append(f'{name:<16}{q[i]:9.3f}{qd[i]:9.3f}{qdd[i]:9.3f}{value}')
    lines.append('Ctrl-C to stop')
    return lines


def plot(recorder: Recorder, path: str, robot: str) -> str:
    """Write τ(t) per joint to ``path``; returns a note of what was done."""
    if not recorder.t:
        return 'no answers received: no plot'
    plt = pyplot()
    if plt is None:
        return 'matplotlib is not installed: plot skipped (pip install matplotlib)'
    fig, ax = plt.subplots(figsize=(10, 5.5), dpi=100)
    for i, name in enumerate(recorder.names):
        ax.plot(recorder.t, [tau[i] for tau in recorder.tau], label=name, linewidth=1.2)
    ax.set_xlabel('time [s]')
    ax.set_ylabel('τ [N·m] (revolute), [N] (prismatic)')
    ax.set_title(f'inverse_dynamics feed-forward torques, {robot}, smooth sinusoid trajectory')
    ax.grid(True, alpha=0.3)
    ax.legend(loc='upper right', ncol=4, fontsize='small')
    save_figure(plt, fig, path)
    return f'plot of {len(recorder.t)} answers written to {path}'


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the demo; 0 when the node answered and exited cleanly."""
    args = parse_args(argv)
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from rclpy.signals import SignalHandlerOptions
    from diagnostic_msgs.msg import DiagnosticArray
    from sensor_msgs.msg import JointState

    urdf, model = robot_model(args.urdf)
    names = model.joint_names
    trajectory = Sinusoids.for_model(model)
    command = node_command('inverse_dynamics', 'spatial_dynamics.ros.node')
    if args.node_log:
        os.makedirs(os.path.dirname(os.path.abspath(args.node_log)), exist_ok=True)
    print(f'starting {" ".join(command)} on {urdf} in {NAMESPACE} (its output: '
          f'{args.node_log or "discarded"})', flush=True)
    node_proc = start(command, NAMESPACE, {'robot_description_file': urdf}, args.node_log)

    # Ctrl-C (even when started with SIGINT ignored, as `cmd &` in a script does) and SIGTERM:
    # stop, let the node exit, still write the plot.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    demo = rclpy.create_node('demo_publisher', namespace=NAMESPACE)
    executor = SingleThreadedExecutor()
    executor.add_node(demo)
    recorder = Recorder()
    publisher = demo.create_publisher(JointState, 'desired_joint_states', 10)
    demo.create_subscription(JointState, 'feedforward_efforts', recorder.on_answer,
                             QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))
    demo.create_subscription(DiagnosticArray, '/diagnostics', recorder.on_diagnostics, 10)

    live = sys.stdout.isatty()
    shown = 0
    msg = JointState()
    msg.name = list(names)
    period = 1.0 / args.rate
    start_time = time.monotonic()
    next_show = start_time
    k = 0
    try:
        while not over(recorder, args.duration, start_time):
            if node_proc.poll() is not None:
                print(f'the node exited with status {node_proc.returncode}', file=sys.stderr)
                break
            t = time.monotonic() - start_time
            q, qd, qdd = trajectory(t)
            msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(time.time_ns(),
                                                                    1_000_000_000)
            msg.position, msg.velocity, msg.effort = q.tolist(), qd.tolist(), qdd.tolist()
            publisher.publish(msg)
            k += 1
            if time.monotonic() >= next_show:
                lines = table(recorder, q, qd, qdd, names, args.rate)
                if live:
                    shown = redraw(lines, shown)
                else:
                    print(lines[0].split(':', 1)[1].strip()
                          + ('  tau: ' + ' '.join(f'{x:.2f}' for x in recorder.tau[-1])
                             if recorder.tau else ''))
                sys.stdout.flush()
                next_show += 0.2 if live else 1.0
            deadline = start_time + k * period
            while (remaining := deadline - time.monotonic()) > 0:
                executor.spin_once(timeout_sec=remaining)
    except KeyboardInterrupt:
        print()
    finally:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        demo.destroy_node()
        rclpy.try_shutdown()
        status = stop(node_proc)
    latency = sorted(recorder.latency_ms)
    print(f'{len(recorder.t)} answers to {k} messages'
          + (f', latency p50 {latency[len(latency) // 2]:.2f} ms' if latency else '')
          + f'; node exit status {status}')
    if args.plot:
        print(plot(recorder, args.plot, model.name))
    return 0 if recorder.t and status == 0 else 1


if __name__ == '__main__':
    sys.exit(main())
