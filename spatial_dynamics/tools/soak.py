# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Soak test of ``inverse_dynamics``: 1 kHz for N minutes, resident memory flat, all answered.

    python -m spatial_dynamics.tools.soak --minutes 2        # by hand: --minutes 60
    python -m spatial_dynamics.tools.soak --minutes 0.5      # short, for CI

Starts the node on the demo robot, publishes the smooth demo trajectory at ``--rate`` Hz with
the joint names in a new random order every message (by default: this churns the node's
name-map cache, whose size must stay bounded), and samples the node's resident set size
(VmRSS in ``/proc/<pid>/status``) every ``--sample`` s. After ``--warmup`` s (imports,
allocator pools, DDS history reach their steady size) the RSS is the baseline. Passes (exit 0)
when the RSS never exceeds the baseline by ``--max-growth-mb`` (default 5) and every message
published after the warm-up was answered; prints the samples and the verdict.
"""

from __future__ import annotations

import argparse
import os
import signal
import random
import sys
import time
from typing import Optional, Sequence, Tuple

from .driving import node_command, robot_model, rss_bytes, Sinusoids, start, stop
from .latency import fill, input_depth, joint_state_for, pace, prime, spin_until, Target

MB = 1024.0 * 1024.0


class NodeCounts:
    """The node's own ``answered`` and ``rejected`` totals, from its diagnostics."""

    def __init__(self, bench, namespace: str) -> None:
        from diagnostic_msgs.msg import DiagnosticArray
        self.name = f'{namespace.lstrip("/")}/inverse_dynamics: feedforward'
        self.latest: Optional[Tuple[int, int]] = None
        self.reports = 0
        bench.create_subscription(DiagnosticArray, '/diagnostics', self._on_diagnostics, 10)

    def _on_diagnostics(self, msg) -> None:
        for status in msg.status:
            if status.name == self.name:
                values = {kv.key: kv.value for kv in status.values}
                self.latest = (int(values['answered']), int(values['rejected']))
                self.reports += 1


def parse_args(argv: Optional[Sequence[str]]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog='python -m spatial_dynamics.tools.soak', description=__doc__.split('\n\n')[0])
    parser.add_argument('--minutes', type=float, default=2.0, help='length (default 2)')
    parser.add_argument('--rate', type=float, default=1000.0, help='Hz (default 1000)')
    parser.add_argument('--warmup', type=float, default=None,
                        help='seconds before the baseline (default: 20 %% of the run, '
                             '10..60 s)')
    parser.add_argument('--sample', type=float, default=5.0, help='RSS sample period, s')
    parser.add_argument('--max-growth-mb', type=float, default=5.0)
    parser.add_argument('--fixed-order', action='store_true',
                        help='publish the names in model order (default: shuffled)')
    parser.add_argument('--input-depth', type=int, default=None,
                        help='override the depth of the node\'s input subscription (QoS '
                             'override parameter; default: keep last 1)')
    parser.add_argument('--urdf', default=None, help='robot (default: the demo arm)')
    parser.add_argument('--log', default=None, help='node log file (default: none)')
    return parser.parse_args(argv)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the soak; 0 if memory stayed flat and every message was answered."""
    args = parse_args(argv)
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.signals import SignalHandlerOptions

    seconds = 60.0 * args.minutes
    warmup = args.warmup if args.warmup is not None else min(max(0.2 * seconds, 10.0), 60.0)
    urdf, model = robot_model(args.urdf)
    trajectory = Sinusoids.for_model(model)
    namespace = f'/sd_soak_{os.getpid()}'
    proc = start(node_command('inverse_dynamics', 'spatial_dynamics.ros.node'), namespace,
                 {'robot_description_file': urdf, **input_depth(namespace, args.input_depth)},
                 args.log)
    signal.signal(signal.SIGINT, signal.default_int_handler)  # Ctrl-C even if ignored at start
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    bench = rclpy.create_node('soak_bench')
    executor = SingleThreadedExecutor()
    executor.add_node(bench)
    target = Target(bench, 'inverse_dynamics', namespace)
    counts = NodeCounts(bench, namespace)
    msg = joint_state_for(model.joint_names)
    names = list(model.joint_names)
    rng = random.Random(0)
    status = 1
    try:
        prime(executor, target, msg, trajectory, timeout=60.0)
        depth = 'keep last 1' if args.input_depth is None else f'depth {args.input_depth}'
        print(f'soak: {model.name}, {args.rate:g} Hz for {seconds:g} s '
              f'({"model" if args.fixed_order else "shuffled"} name order, input {depth}), '
              f'node pid {proc.pid}, warm-up {warmup:g} s, RSS every {args.sample:g} s')
        t0 = time.monotonic()
        samples = []   # (t, rss)

        def publish(k: int) -> None:
            t = time.monotonic() - t0
            if not args.fixed_order:
                order = list(range(len(names)))
                rng.shuffle(order)
                fill(msg, trajectory, t)
                msg.name = [names[i] for i in order]
                msg.position = [msg.position[i] for i in order]
                msg.velocity = [msg.velocity[i] for i in order]
                msg.effort = [msg.effort[i] for i in order]
            else:
                fill(msg, trajectory, t)
            target.measuring = t >= warmup
            target.publish(msg)
            if not samples or t - samples[-1][0] >= args.sample:
                samples.append((t, rss_bytes(proc.pid)))
                baseline = next((r for s, r in samples if s >= warmup), None)
                growth = '' if baseline is None else \
                    f'  growth {(samples[-1][1] - baseline) / MB:+.2f} MB'
                print(f'  t={t:7.1f} s  RSS {samples[-1][1] / MB:8.2f} MB  answered '
                      f'{len(target.latency_ns)}/{len(target.sent)}{growth}', flush=True)

        pace(executor, args.rate, seconds, publish, lambda: proc.poll() is not None)
        target.measuring = False
        spin_until(executor, lambda: len(target.latency_ns) == len(target.sent), 2.0)
        samples.append((time.monotonic() - t0, rss_bytes(proc.pid)))
        after = [r for t, r in samples if t >= warmup]
        baseline = after[0]
        growth = (max(after) - baseline) / MB
        end_growth = (after[-1] - baseline) / MB
        reports = counts.reports   # totals final once a report after the last message came
        spin_until(executor, lambda: counts.reports >= reports + 2, 3.0)
        summary = target.summary()
        missed = summary['sent'] - summary['answered']
        print(f'RSS after warm-up {baseline / MB:.2f} MB, max growth {growth:+.2f} MB, at the end '
              f'{end_growth:+.2f} MB (limit {args.max_growth_mb:g} MB)')
        print(f'answered {summary["answered"]} of {summary["sent"]} after warm-up '
              f'({missed} missed); latency p50 {summary["p50_ms"]:.3f} ms, p99 '
              f'{summary["p99_ms"]:.3f} ms, max {summary["max_ms"]:.3f} ms')
        if counts.latest is not None:
            answered, rejected = counts.latest
            print(f'whole run incl. warm-up: published {target.published}, the node answered '
                  f'{answered} and rejected {rejected} (its diagnostics), this process received '
                  f'{target.answers} answers: {target.published - answered - rejected} inputs '
                  f'never reached the node (best effort, {depth}), {answered - target.answers}'
                  ' answers were lost on the way back')
        ok = growth < args.max_growth_mb and missed == 0 and summary['sent'] > 0
        print('PASS' if ok else 'FAIL')
        status = 0 if ok else 1
    except KeyboardInterrupt:
        status = 130
    finally:
        bench.destroy_node()
        rclpy.try_shutdown()
        exit_status = stop(proc)
        if exit_status != 0 and status == 0:
            print(f'FAIL: node exit status {exit_status}')
            status = 1
    return status


if __name__ == '__main__':
    sys.exit(main())
