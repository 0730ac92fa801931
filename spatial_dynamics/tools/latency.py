# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Latency benchmark: ``inverse_dynamics`` against a trivial relay, in the same run.

    python -m spatial_dynamics.tools.latency [--rate 1000] [--seconds 10] [--json out/lat.json]

Starts the node (on the demo robot) and :mod:`spatial_dynamics.tools.relay` as two processes,
each in its own namespace, and publishes the same smooth trajectory (sensor_msgs/JointState, model
order) to each at ``--rate`` Hz, alternating between them in blocks of ``--block`` seconds until
each got ``--seconds``. Latency is input publish -> ``feedforward_efforts`` received, in this
process, matched by the header stamp (wall time at publish, unique per message). Reported per
target: messages sent, fraction answered, p50 / p99 / max, and the CPU time (user + system) its
process used per message while measured. The relay does everything the node does except the
inverse dynamics and the second publication (``effort_commands``, published first), so node
p50 - relay p50 is the node's own cost.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import sys
import time
from typing import Callable, Dict, List, Optional, Sequence, Set

import numpy as np

from .driving import cpu_seconds, node_command, robot_model, Sinusoids, start, stop


class Target:
    """Publisher to one node: stamps ``sent`` while measuring, ``latency_ns[stamp]`` answers."""

    def __init__(self, bench, name: str, namespace: str) -> None:
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from sensor_msgs.msg import JointState
        self.name = name
        self.namespace = namespace
        self.sent: Set[int] = set()
        self.latency_ns: Dict[int, int] = {}
        self.measuring = False
        self.publisher = bench.create_publisher(
            JointState, f'{namespace}/desired_joint_states', 10)
        self.subscription = bench.create_subscription(
            JointState, f'{namespace}/feedforward_efforts', self._on_answer,
            QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE))
        self.answers = 0     # all answers, measured or not
        self.published = 0   # all messages, measured or not
        self.cpu_s = 0.0   # CPU time of the target's process while it was measured

    def _on_answer(self, msg) -> None:
        now = time.time_ns()
        self.answers += 1
        key = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        if key in self.sent and key not in self.latency_ns:
            self.latency_ns[key] = now - key

    def publish(self, msg) -> None:
        """Stamp ``msg`` with the wall time now and publish it (counted when measuring)."""
        now = time.time_ns()
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(now, 1_000_000_000)
        if self.measuring:
            self.sent.add(now)
        self.published += 1
        self.publisher.publish(msg)

    def summary(self) -> Dict[str, float]:
        """Sent, answered fraction and latency percentiles in ms."""
        ms = np.array(sorted(self.latency_ns.values()), dtype=float) * 1e-6
        sent = len(self.sent)
        out = {'target': self.name, 'sent': sent, 'answered': len(ms),
               'answered_fraction': len(ms) / sent if sent else float('nan')}
        for key, q in (('p50_ms', 50), ('p99_ms', 99)):
            out[key] = float(np.percentile(ms, q)) if len(ms) else float('nan')
        out['max_ms'] = float(ms.max()) if len(ms) else float('nan')
        out['cpu_us_per_msg'] = 1e6 * self.cpu_s / sent if sent else float('nan')
        out['mean_ms'] = float(ms.mean()) if len(ms) else float('nan')
        return out


def pace(executor, rate: float, seconds: float, publish: Callable[[int], None],
         should_stop: Callable[[], bool] = lambda: False) -> int:
    """Call ``publish(k)`` at ``rate`` Hz for ``seconds`` s, spinning ``executor`` in between.

    Returns the number of messages published. Ticks are on a fixed grid: a late tick is
    published at once, not skipped, so the count is ``rate * seconds``.
    """
    period = 1.0 / rate
    count = int(round(rate * seconds))
    start_time = time.monotonic()
    for k in range(count):
        if should_stop():
            return k
        publish(k)
        next_time = start_time + (k + 1) * period
        while True:
            remaining = next_time - time.monotonic()
            if remaining <= 0.0:
                break
            executor.spin_once(timeout_sec=remaining)
    return count


def spin_until(executor, predicate: Callable[[], bool], timeout: float) -> bool:
    """Spin until ``predicate()`` or ``timeout`` s; returns ``predicate()``."""
    deadline = time.monotonic() + timeout
    while not predicate() and time.monotonic() < deadline:
        executor.spin_once(timeout_sec=0.01)
    return predicate()


def joint_state_for(model_names: Sequence[str]):
    """Return a JointState template with the model's names in model order."""
    from sensor_msgs.msg import JointState
    msg = JointState()
    msg.name = list(model_names)
    return msg


def fill(msg, trajectory: Sinusoids, t: float) -> None:
    """Set position, velocity and effort (= qdd) of ``msg`` from the trajectory at ``t``."""
    q, qd, qdd = trajectory(t)
    msg.position = q.tolist()
    msg.velocity = qd.tolist()
    msg.effort = qdd.tolist()


def prime(executor, target: Target, msg, trajectory: Sinusoids, timeout: float) -> None:
    """Publish at 20 Hz until ``target`` answers (the node has started and connected)."""
    deadline = time.monotonic() + timeout
    while target.answers == 0:
        if time.monotonic() > deadline:
            raise RuntimeError(f'{target.name} did not answer within {timeout:.0f} s')
        fill(msg, trajectory, 0.0)
        target.publish(msg)
        spin_until(executor, lambda: target.answers > 0, 0.05)


def input_depth(namespace: str, depth: Optional[int]) -> Dict[str, str]:
    """Return the QoS override of the ``desired_joint_states`` subscription depth, if any."""
    if depth is None:
        return {}
    return {f'qos_overrides.{namespace}/desired_joint_states.subscription.depth': str(depth)}


def format_table(rows: List[Dict[str, float]]) -> str:
    """Format the results as a fixed-width text table."""
    lines = [f'{"target":<18}{"sent":>7}{"answered":>11}{"p50 ms":>9}{"p99 ms":>9}'
             f'{"max ms":>9}{"CPU us/msg":>12}']
    for r in rows:
        lines.append(f'{r["target"]:<18}{r["sent"]:>7}{100 * r["answered_fraction"]:>10.2f}%'
                     f'{r["p50_ms"]:>9.3f}{r["p99_ms"]:>9.3f}{r["max_ms"]:>9.3f}'
                     f'{r["cpu_us_per_msg"]:>12.1f}')
    return '\n'.join(lines)


def parse_args(argv: Optional[Sequence[str]]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog='python -m spatial_dynamics.tools.latency', description=__doc__.split('\n\n')[0])
    parser.add_argument('--rate', type=float, default=1000.0, help='Hz (default 1000)')
    parser.add_argument('--seconds', type=float, default=10.0,
                        help='measured seconds per target (default 10)')
    parser.add_argument('--block', type=float, default=2.0,
                        help='seconds per block; targets alternate (default 2)')
    parser.add_argument('--warmup', type=float, default=1.0,
                        help='unmeasured seconds at full rate per target first (default 1)')
    parser.add_argument('--urdf', default=None, help='robot (default: the demo arm)')
    parser.add_argument('--json', default=None, help='also write the results here')
    parser.add_argument('--input-depth', type=int, default=None,
                        help='override the input subscription depth of node and relay (QoS '
                             'override parameter; default: their keep last 1)')
    parser.add_argument('--log-dir', default=None, help='node and relay logs (default: none)')
    return parser.parse_args(argv)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the benchmark; print the table; 0 if both targets answered."""
    args = parse_args(argv)
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.signals import SignalHandlerOptions

    urdf, model = robot_model(args.urdf)
    trajectory = Sinusoids.for_model(model)
    namespace = f'/sd_latency_{os.getpid()}'
    logs = args.log_dir
    if logs:
        os.makedirs(logs, exist_ok=True)
    procs = {
        'relay': start(node_command('relay', 'spatial_dynamics.tools.relay'), f'{namespace}/relay',
                       input_depth(f'{namespace}/relay', args.input_depth),
                       logs and os.path.join(logs, 'relay.log')),
        'inverse_dynamics': start(node_command('inverse_dynamics', 'spatial_dynamics.ros.node'),
                                  f'{namespace}/node',
                                  {'robot_description_file': urdf,
                                   **input_depth(f'{namespace}/node', args.input_depth)},
                                  logs and os.path.join(logs, 'inverse_dynamics.log')),
    }
    signal.signal(signal.SIGINT, signal.default_int_handler)  # Ctrl-C even if ignored at start
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    bench = rclpy.create_node('latency_bench')
    executor = SingleThreadedExecutor()
    executor.add_node(bench)
    targets = [Target(bench, 'relay', f'{namespace}/relay'),
               Target(bench, 'inverse_dynamics', f'{namespace}/node')]
    msg = joint_state_for(model.joint_names)
    status = 0
    try:
        for target in targets:
            prime(executor, target, msg, trajectory, timeout=60.0)
        t0 = time.monotonic()

        def send(target: Target) -> Callable[[int], None]:
            def publish(k: int) -> None:
                fill(msg, trajectory, time.monotonic() - t0)
                target.publish(msg)
            return publish

        for target in targets:
            pace(executor, args.rate, args.warmup, send(target))
        measured = {t.name: 0.0 for t in targets}
        while any(v < args.seconds for v in measured.values()):
            for target in targets:
                block = min(args.block, args.seconds - measured[target.name])
                if block <= 0:
                    continue
                pid = procs[target.name].pid
                cpu = cpu_seconds(pid)
                target.measuring = True
                pace(executor, args.rate, block, send(target))
                target.measuring = False
                executor.spin_once(timeout_sec=0.05)  # let the last answers of a block land
                target.cpu_s += cpu_seconds(pid) - cpu
                measured[target.name] += block
        spin_until(executor, lambda: all(len(t.latency_ns) == len(t.sent) for t in targets),
                   1.0)
        rows = [t.summary() for t in targets]
        depth = 'keep last 1' if args.input_depth is None else f'depth {args.input_depth}'
        print(f'latency: {model.name} ({len(model.joint_names)} joints), {args.rate:g} Hz, '
              f'{args.seconds:g} s per target in {args.block:g} s blocks, same run, input '
              f'{depth}')
        print(format_table(rows))
        diff = rows[1]['p50_ms'] - rows[0]['p50_ms']
        print(f'inverse_dynamics - relay: p50 {diff:+.3f} ms, '
              f'p99 {rows[1]["p99_ms"] - rows[0]["p99_ms"]:+.3f} ms')
        if args.json:
            os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
            with open(args.json, 'w') as f:
                json.dump({'robot': model.name, 'rate_hz': args.rate,
                           'seconds_per_target': args.seconds, 'targets': rows}, f, indent=2)
        status = 0 if all(r['answered'] for r in rows) else 1
    except KeyboardInterrupt:
        status = 130
    finally:
        bench.destroy_node()
        rclpy.try_shutdown()
        for proc in procs.values():
            stop(proc)
    return status


if __name__ == '__main__':
    sys.exit(main())
