# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Soak test of ``inverse_dynamics``: 1 kHz for N minutes, resident memory flat, all answered.

    python -m spatial_dynamics.tools.soak --minutes 2        # by hand: --minutes 60
    python -m spatial_dynamics.tools.soak --minutes 0.5      # short, for CI

Starts the node on the demo robot, publishes the smooth demo trajectory at ``--rate`` Hz with
the joint names in a new random order every message (by default: this churns the node's
name-map cache, whose size must stay bounded), and samples the node's resident set size
(VmRSS in ``/proc/<pid>/status``) every ``--sample`` s. After ``--warmup`` s (imports,
allocator pools, DDS history reach their steady size) the RSS is the baseline.

Passes (exit 0) on what the node controls: the RSS never exceeded the baseline by
``--max-growth-mb`` (default 5), the node answered every input it received (its own
``answered`` and ``rejected`` totals in /diagnostics: none of these valid inputs rejected),
it answered inputs after the warm-up (the memory was watched under load), and it exited with
status 0. What the transport lost is reported, never judged: inputs are best effort (keep
last 1 unless ``--input-depth``), so a busy machine drops some before the node sees them,
and the reliable answers keep the last 10; rates and latency are the latency benchmark's.
"""

from __future__ import annotations

import argparse
import os
import signal
import random
import sys
import time
from typing import List, Optional, Sequence, Tuple

from .driving import node_command, robot_model, rss_bytes, Sinusoids, start, stop
from .latency_pacer import fill, joint_state_for, pace, prime, spin_until
from .latency_report import cell
from .latency_targets import input_depth, Target

# rclpy and the ROS messages are imported inside the functions that run a node: the options
# are parsed (and --help printed) without ROS, and rclpy alone takes some 0.1 s to import.

MB = 1024.0 * 1024.0


class NodeCounts:
    """The node's own ``answered`` and ``rejected`` totals, from its diagnostics."""

    def __init__(self, bench, namespace: str) -> None:
        from diagnostic_msgs.msg import DiagnosticArray
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        self.name = f'{namespace.lstrip("/")}/inverse_dynamics: feedforward'
        self.latest: Optional[Tuple[int, int]] = None
        self.previous: Optional[Tuple[int, int]] = None
        self.reports = 0
        bench.create_subscription(DiagnosticArray, '/diagnostics', self._on_diagnostics,
                                  QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))

    def _on_diagnostics(self, msg) -> None:
        for status in msg.status:
            if status.name == self.name:
                values = {kv.key: kv.value for kv in status.values}
                self.previous = self.latest
                self.latest = (int(values['answered']), int(values['rejected']))
                self.reports += 1

    def settled(self) -> bool:
        """Two reports in a row with the same totals: the node has nothing left to answer."""
        return self.latest is not None and self.latest == self.previous


def verdict(growth_mb: float, max_growth_mb: float, at_warmup: Optional[Tuple[int, int]],
            final: Optional[Tuple[int, int]], settled: bool) -> List[str]:
    """Return why the soak failed (empty: it passed), from what the node controls.

    ``at_warmup`` and ``final`` are the node's ``(answered, rejected)`` totals when the RSS
    baseline was taken and after the run; ``settled``: ``final`` no longer changed.
    """
    failures = []
    if growth_mb >= max_growth_mb:
        failures.append(f'resident memory grew {growth_mb:+.2f} MB after warm-up (limit '
                        f'{max_growth_mb:g} MB)')
    if final is None or not settled:
        failures.append('the node\'s totals never settled in /diagnostics after the run')
        return failures
    answered, rejected = final
    if rejected:
        failures.append(f'the node rejected {rejected} of the {answered + rejected} valid '
                        'inputs it received')
    if answered <= (at_warmup or (0, 0))[0]:
        failures.append('the node answered nothing after the warm-up (no load was measured)')
    return failures


def parse_args(argv: Optional[Sequence[str]]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog='python -m spatial_dynamics.tools.soak', description=__doc__.split('\n\n')[0])
    parser.add_argument('--minutes', type=float, default=2.0, help='length (default 2)')
    parser.add_argument('--rate', type=float, default=1000.0, help='Hz (default 1000)')
    parser.add_argument('--warmup', type=float, default=None,
                        help='seconds before the baseline (default: 20 %% of the run, '
                             '10..60 s)')
    parser.add_argument('--sample', type=float, default=5.0,
                        help='RSS sample period, s (default %(default)s)')
    parser.add_argument('--max-growth-mb', type=float, default=5.0,
                        help='fail when the resident memory grows more than this after the '
                        'warm-up, MB (default %(default)s)')
    parser.add_argument('--fixed-order', action='store_true',
                        help='publish the names in model order (default: shuffled)')
    parser.add_argument('--input-depth', type=int, default=None,
                        help='override the depth of the node\'s input subscription (QoS '
                             'override parameter; default: keep last 1)')
    parser.add_argument('--urdf', default=None, help='robot (default: the demo arm)')
    parser.add_argument('--log', default=None, help='node log file (default: none)')
    return parser.parse_args(argv)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the soak; 0 if memory stayed flat and the node answered every input it received."""
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
        at_warmup = []   # the node's totals when the RSS baseline was taken

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
                if t >= warmup and not at_warmup:
                    at_warmup.append(counts.latest)
                baseline = next((r for s, r in samples if s >= warmup), None)
                growth = '' if baseline is None else \
                    f'  growth {(samples[-1][1] - baseline) / MB:+.2f} MB'
                print(f'  t={t:7.1f} s  RSS {samples[-1][1] / MB:8.2f} MB  answered '
                      f'{len(target.latency_ns)}/{len(target.sent)}{growth}', flush=True)

        pace(executor, args.rate, seconds, publish, lambda: proc.poll() is not None)
        target.measuring = False
        if proc.poll() is not None:
            print(f'FAIL: the node exited with status {proc.returncode} during the run')
            return 1
        samples.append((time.monotonic() - t0, rss_bytes(proc.pid)))
        after = [r for t, r in samples if t >= warmup]
        baseline = after[0]
        growth = (max(after) - baseline) / MB
        end_growth = (after[-1] - baseline) / MB
        # generous waits that end as soon as they hold: the node works off what it queued
        # (its totals stop changing), then the answers still in flight arrive
        reports = counts.reports
        spin_until(executor, lambda: counts.reports >= reports + 2 and counts.settled(), 60.0)
        final, settled = counts.latest, counts.settled()
        spin_until(executor, lambda: final is not None and target.answers >= final[0], 10.0)
        summary = target.summary()
        print(f'RSS after warm-up {baseline / MB:.2f} MB, max growth {growth:+.2f} MB, at the end '
              f'{end_growth:+.2f} MB (limit {args.max_growth_mb:g} MB)')
        print(f'this process received answers to {summary["answered"]} of the {summary["sent"]} '
              f'inputs after warm-up; latency p50 {cell(summary["p50_ms"])} ms, p99 '
              f'{cell(summary["p99_ms"])} ms, max {cell(summary["max_ms"])} ms')
        if final is not None:
            answered, rejected = final
            print(f'whole run incl. warm-up: published {target.published}, the node received '
                  f'{answered + rejected}, answered {answered} and rejected {rejected} (its '
                  f'diagnostics), this process received {target.answers} answers; the transport '
                  f'lost {target.published - answered - rejected} inputs on the way to the node '
                  f'(best effort, {depth}) and {answered - target.answers} answers on the way '
                  'back (not judged: rates are the latency benchmark\'s)')
        failures = verdict(growth, args.max_growth_mb, at_warmup[0] if at_warmup else None,
                           final, settled)
        print('\n'.join(f'FAIL: {text}' for text in failures) or 'PASS')
        status = 1 if failures else 0
    except KeyboardInterrupt:
        status = 130
    finally:
        bench.destroy_node()
        rclpy.try_shutdown()
        exit_status = stop(proc, 60.0)   # generous: a loaded machine is slow to clean up
        if exit_status != 0 and status == 0:
            print(f'FAIL: node exit status {exit_status}')
            status = 1
    return status


if __name__ == '__main__':
    sys.exit(main())
