# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Latency benchmark: ``inverse_dynamics`` against a trivial relay, in the same run.

    python -m spatial_dynamics.tools.latency [--rate 1000] [--seconds 10] [--robot ur5]
        [--busy 3] [--priority 50] [--plot out/latency.png] [--json out/lat.json]
        [--log-dir out/logs]

Starts the node (on the demo robot) and :mod:`spatial_dynamics.tools.relay` as two processes,
each in its own namespace, and publishes the same smooth trajectory (sensor_msgs/JointState, model
order) to each at ``--rate`` Hz, alternating between them in blocks of ``--block`` seconds until
each got ``--seconds``. The inputs are published by a process of their own that does nothing
else (:class:`~.latency_pacer.Pacer`), on a fixed grid. Latency is input publish ->
``feedforward_efforts`` received by this process's middleware (its reception time stamp),
matched by the header stamp (wall time at publish, unique per message). Reported per target:
messages sent, fraction answered, p50 / p99 / p99.9 / max (a quantile only from enough answers
to tell it from the maximum: p99 from 100, p99.9 from 1000; else '-', null in the JSON), the
CPU time its process's threads ran per message while measured (the scheduler's nanosecond
sums, :func:`~spatial_dynamics.tools.driving.thread_cpu_ns`; '-' where the kernel keeps none),
and how many inputs not answered were followed by the next within a quarter period (the
publisher late: a keep-last-1 input keeps the newer). The relay does everything the node does
except the inverse dynamics and the second publication (``effort_commands``, published first),
so node p50 - relay p50 is the node's own cost.

Each round trip is split at the answer's publication (its DDS source timestamp, the same
clock on one machine): ``to answer`` is input publish -> answer published by the target (the
way in, the executor, the answer), the rest is the way back to this process. The node's
compute time per answer (mean and max of each diagnostics period) comes from its
``/diagnostics``. ``--busy N`` runs N busy loops (one process each) beside the run, the load
of a busy machine; ``--priority P`` asks SCHED_FIFO P for node, relay and this process's
receive threads, P + 1 for the publishing process (a tick never waits for a target's
thread); 0: normal scheduling for all; it needs the rtprio limit, see the node's
``thread_priority``. What each process ran under is read from it after the run (node and
relay: their answering thread's policy, :func:`~.latency_targets.scheduling_of`), not taken
from the request: a priority not granted reads as normal scheduling. ``--plot`` draws the
histograms of the round trips (matplotlib).

The rate the inputs were sent at is reported beside the one asked: a publisher that cannot
keep up (``--rate`` too high for the machine) sends back to back, never sleeps, and ends a
block :data:`~.latency_pacer.LATE_LIMIT_S` after its due time with fewer inputs; a warning
says so when it sent more than :data:`~.latency_report.RATE_SHORTFALL` below the rate asked.
A target that refuses its inputs (the node's ``/diagnostics`` count them rejected, none
answered, for :data:`~.latency_targets.REFUSING_PERIODS` periods) or exits ends the run with
its reason (its log's error line), at any phase.

The machine's floor, measured in the same run: how late the publishing process woke from
each sleep to its grid (it sleeps at a priority above the targets', so no thread of theirs
wakes sooner), with the kernel's preemption model
(:func:`~.latency_targets.kernel_preemption`). A round trip wakes at least one thread: its
tail cannot be shorter than the wake-ups' tail.

This module is the command: its options (:func:`parse_args`), the run (:func:`run`) and
:func:`main`. The inputs' process is in :mod:`.latency_pacer`, the targets' processes and
what is read from them in :mod:`.latency_targets`, the statistics' table, lines, JSON and
plot in :mod:`.latency_report`.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import subprocess
import sys
import sysconfig
import tempfile
import time
from typing import Callable, Dict, List, Optional, Sequence

import numpy as np

from spatial_dynamics.files import output_path

from .driving import (
    cpu_ns_between, Interrupt, last_error, node_command, outputs_error, path_text,
    plot_path_error, robot_model, Sinusoids, start, stop)
from .latency_pacer import NoAnswer, Pacer, spin_until
from .latency_report import (
    difference_line, format_table, json_safe, machine_line, not_answered_line, plot, rate_text,
    rate_warning, sent_rate, wake_ups, write_json)
from .latency_targets import (
    busy_loop, cpu_reading, end_loop, exited, input_depth, kernel_preemption, LOGS,
    NodeDiagnostics, plural, prioritize, scheduling_of, scheduling_text, Target, watch)

# rclpy and the ROS messages are imported inside the functions that run a node: the options
# are parsed (and --help printed) without ROS, and rclpy alone takes some 0.1 s to import.

#: Robots ``--robot`` names: the embedded demo arm, or example-robot-data's (a test dependency).
ROBOTS = {'demo_arm': None, 'ur5': 'ur_description/urdf/ur5_robot.urdf',
          'solo12': 'solo_description/robots/solo12.urdf'}
#: Robots run on a floating base: the node's parameters, and the root link the odometry is of.
FLOATING = {'solo12': ({'base': 'floating',
                        'contacts.links': '[FL_FOOT, FR_FOOT, HL_FOOT, HR_FOOT]'}, 'base_link')}
#: A floating robot's legs move ±0.05 rad around its standing posture: every foot keeps
#: pushing on the floor (larger motions make a foot pull, and the node rightly refuses them).
STANDING = {'solo12': {f'{leg}_{joint}': angle * (1.0 if leg[0] == 'F' else -1.0)
                       for leg in ('FL', 'FR', 'HL', 'HR')
                       for joint, angle in (('HFE', 0.8), ('KFE', -1.6))}}
STANDING_SWAY = 0.05   # rad
#: Base odometry beside the desired states of a floating robot, Hz (a state estimator's rate).
ODOMETRY_RATE = 200.0
#: The largest --input-depth: a second of inputs at the highest --rate (rclpy itself takes a
#: QoS depth up to 2**31 - 1; a deeper queue holds nothing more here).
MAX_INPUT_DEPTH = 100_000
#: The longest --warmup, s (the node's caches and the middleware settle within the first).
MAX_WARMUP_S = 60.0


def robot_path(robot: str) -> Optional[str]:
    """Return the URDF of ``--robot``: None for the demo arm, else example-robot-data's."""
    if ROBOTS[robot] is None:
        return None
    path = os.path.join(sysconfig.get_paths()['purelib'], 'cmeel.prefix', 'share',
                        'example-robot-data', 'robots', ROBOTS[robot])
    if not os.path.isfile(path):
        raise SystemExit(f'--robot {robot}: needs example-robot-data (pip install '
                         'example-robot-data), or give its URDF with --urdf')
    return path


def publish_odometry(bench, topic: str, root: str) -> None:
    """Publish a standing base's odometry on ``topic`` at :data:`ODOMETRY_RATE` (a timer).

    The floating node holds the base's pose and twist from it (they go stale without it);
    the base stands still 0.3 m up, upright: the desired joint states move the legs.
    """
    from nav_msgs.msg import Odometry
    publisher = bench.create_publisher(Odometry, topic, 10)
    msg = Odometry()
    msg.header.frame_id = 'odom'
    msg.child_frame_id = root
    msg.pose.pose.position.z = 0.3
    msg.pose.pose.orientation.w = 1.0

    def tick() -> None:
        msg.header.stamp = bench.get_clock().now().to_msg()
        publisher.publish(msg)
    bench.create_timer(1.0 / ODOMETRY_RATE, tick)


def in_range(kind: Callable[[str], float], low: float, high: float, low_open: bool = False):
    """Return an argparse type: ``kind`` of the text, within ``low`` .. ``high``.

    ``low_open``: ``low`` itself is refused (above 0). A bound of ``inf`` is none; NaN and
    infinities never pass.
    """
    def convert(text: str):
        try:
            value = kind(text)
        except ValueError:
            what = 'an integer' if kind is int else 'a number'
            raise argparse.ArgumentTypeError(f'not {what}: {text!r}') from None
        above = value > low if low_open else value >= low
        if not (above and value <= high and math.isfinite(value)):
            where = f'above {low:g}' if low_open else f'at least {low:g}'
            limit = '' if high == float('inf') else f' and at most {high:g}'
            raise argparse.ArgumentTypeError(f'{where}{limit}, got {text}')
        return value
    return convert


def parse_args(argv: Optional[Sequence[str]]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog='python -m spatial_dynamics.tools.latency', description=__doc__.split('\n\n')[0],
        epilog='--plot, --json and --log-dir create the folders they name that do not exist '
               'yet; each is checked before the run (a folder a file can be created in, an '
               'output that is not a folder, a named pipe or a device, nor another output or '
               "one of --log-dir's logs). A path is taken as realpath resolves it: a link is "
               "written through to its target, and a '..' after a folder not made yet cancels "
               'it (a/new/../b/x.json is a/b/x.json). CPU per input is all the time the '
               "target's threads ran while measured over the inputs sent: it includes the "
               "target's idle cost (timers, the middleware), a larger share at a low --rate.")
    parser.add_argument('--rate', type=in_range(float, 0.0, 1e5, True), default=1000.0,
                        help='Hz, above 0 and at most 1e5 (default 1000); the rate the inputs '
                             'were sent at is reported beside it')
    parser.add_argument('--seconds', type=in_range(float, 0.0, 3600.0, True), default=10.0,
                        help='measured seconds per target, at most 3600 (default 10)')
    parser.add_argument('--block', type=in_range(float, 0.0, float('inf'), True), default=2.0,
                        help='seconds per block; targets alternate (default 2)')
    parser.add_argument('--warmup', type=in_range(float, 0.0, MAX_WARMUP_S), default=1.0,
                        help='unmeasured seconds at full rate per target first, 0 .. '
                             f'{MAX_WARMUP_S:g} (default 1)')
    parser.add_argument('--robot', choices=sorted(ROBOTS), default='demo_arm',
                        help='robot (default demo_arm; ur5 and solo12 from example-robot-data; '
                             'solo12 on a floating base, standing on its four feet, its base '
                             f'odometry published at {ODOMETRY_RATE:g} Hz beside the inputs)')
    parser.add_argument('--urdf', type=path_text, default=None,
                        help='any other robot, on a fixed base, with at least one joint '
                             '(overrides --robot)')
    cpus = os.cpu_count() or 1
    parser.add_argument('--busy', type=in_range(int, 0, 4 * cpus), default=0,
                        help=f'busy loops beside the run, one process each, 0 .. {4 * cpus} '
                             '(4 per core; default 0)')
    parser.add_argument('--priority', type=in_range(int, 0, 99), default=0,
                        help='SCHED_FIFO priority asked for node, relay and publisher, 0 .. 99 '
                             '(default 0: normal scheduling); what each ran under is read '
                             'from it and reported')
    parser.add_argument('--plot', type=path_text, default=None,
                        help='draw the histograms here (PNG when the name has no suffix)')
    parser.add_argument('--json', type=path_text, default=None,
                        help='also write the results here')
    parser.add_argument('--input-depth', type=in_range(int, 1, MAX_INPUT_DEPTH), default=None,
                        help='override the input subscription depth of node and relay, 1 .. '
                             f'{MAX_INPUT_DEPTH} (QoS override parameter; default: their keep '
                             'last 1)')
    parser.add_argument('--log-dir', type=path_text, default=None,
                        help='write node and relay logs (' + ', '.join(LOGS.values())
                             + ') here (default: none kept)')
    args = parser.parse_args(argv)
    # a --plot without a suffix: its name checked as a file too, the .png written compared
    error = outputs_error([('--plot', args.plot)])
    if error:
        parser.error(error)
    if args.plot is not None and not os.path.splitext(args.plot)[1]:
        args.plot += '.png'   # what matplotlib writes for a name without a suffix
    outputs = [('--plot', args.plot), ('--json', args.json)]
    if args.log_dir is not None:
        outputs += [('--log-dir', os.path.join(args.log_dir, name)) for name in LOGS.values()]
    error = outputs_error(outputs, [('--log-dir', args.log_dir)])
    if error:
        parser.error(error)
    if args.plot is not None:
        error = plot_path_error(args.plot, args.json)
        if error:
            parser.error(error)
    if round(args.rate * args.seconds) < 1:
        parser.error(f'--rate {args.rate:g} for --seconds {args.seconds:g} sends no message')
    if round(args.rate * args.block) < 1:
        parser.error(f'--block {args.block:g} at --rate {args.rate:g} holds no message')
    return args


def make_folders(args: argparse.Namespace) -> None:
    """Create the folders of ``--plot``, ``--json`` and ``--log-dir`` that do not exist yet.

    Those of the files written, :func:`~spatial_dynamics.files.output_path` (as checked).

    RuntimeError names the option (:func:`parse_args` checked them: this fails only when the
    file system changed since).
    """
    for option, folder in (('--plot', args.plot and os.path.dirname(output_path(args.plot))),
                           ('--json', args.json and os.path.dirname(output_path(args.json))),
                           ('--log-dir', args.log_dir and output_path(args.log_dir))):
        if folder:
            try:
                os.makedirs(folder, exist_ok=True)
            except OSError as err:
                raise RuntimeError(f'{option}: cannot create the folder {folder!r}: '
                                   f'{err.strerror}') from None


def counts(rate: float, seconds: float, block: float) -> List[int]:
    """Each block's messages: ``round(rate * block)``, ``round(rate * seconds)`` in all.

    Counted in messages, not seconds: a block's ``rate * block`` rounded on its own summed to
    other than ``rate * seconds`` (0 for each block of 1 s at 0.5 Hz: nothing sent).
    """
    total, size = int(round(rate * seconds)), max(int(round(rate * block)), 1)
    return [min(size, total - start) for start in range(0, total, size)]


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the benchmark; print the table; 0 if both targets answered.

    1 with one line on stderr when a process of the run exited or the robot cannot be
    loaded; 130 (SIGINT) or 143 (SIGTERM) with one line when interrupted, at any phase.
    """
    args = parse_args(argv)
    interrupt = Interrupt().install()   # from here on: also while loading and starting
    try:
        return run(args, interrupt)
    except (KeyboardInterrupt, Exception) as err:
        # after a signal, whatever it raised is the interrupt: rclpy turns a KeyboardInterrupt
        # raised while it builds a message (Subscription.take_message) into pybind11's
        # RuntimeError 'Unable to convert call argument '0' to Python object'
        if isinstance(err, KeyboardInterrupt) or interrupt.signal is not None:
            print(f'latency: interrupted ({interrupt.name}); the node, the relay and the '
                  'publisher stopped', file=sys.stderr)
            return interrupt.status
        if isinstance(err, RuntimeError):
            print(f'latency: {err}', file=sys.stderr)
            return 1
        raise


def run(args: argparse.Namespace, interrupt: Optional[Interrupt] = None) -> int:
    """Run the benchmark of ``args`` (see :func:`main`); raises on a process that exited.

    Every process it starts is recorded as it starts (``interrupt`` held meanwhile), and
    each is stopped and waited for however the run ends, a step that fails included.
    """
    interrupt = interrupt or Interrupt()
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.signals import SignalHandlerOptions

    try:
        urdf, model = robot_model(args.urdf or robot_path(args.robot))
    except ValueError as err:
        raise RuntimeError(f'--urdf {args.urdf!r}: {err}' if args.urdf else str(err)) from None
    if not model.joint_names:   # the node would refuse every input (no joint to name)
        raise RuntimeError(f'--urdf {args.urdf!r}: robot {model.name!r} has no joint that '
                           'moves: it has no torques to time')
    trajectory = Sinusoids.for_model(model)
    if args.urdf is None and args.robot in STANDING:
        posture = np.array([STANDING[args.robot].get(name, 0.0) for name in model.joint_names])
        trajectory = Sinusoids(model.joint_names, posture - 2.0 * STANDING_SWAY,
                               posture + 2.0 * STANDING_SWAY)
    namespace = f'/sd_latency_{os.getpid()}'
    make_folders(args)
    # the targets' logs: kept in --log-dir, else for the run only (their error line is the
    # reason said when one exits or refuses its inputs)
    scratch = None if args.log_dir else tempfile.TemporaryDirectory(prefix='sd_latency_')
    folder = output_path(args.log_dir) if args.log_dir else scratch.name
    logs = {name: os.path.join(folder, file) for name, file in LOGS.items()}
    priority = {'thread_priority': str(args.priority)}
    floating, root = FLOATING.get(args.robot, ({}, None)) if args.urdf is None else ({}, None)
    # every process is stopped in the end, whenever the run ends (Ctrl-C while starting too)
    procs: Dict[str, subprocess.Popen] = {}
    loops: List[subprocess.Popen] = []
    bench = pacer = None
    status = 0
    interrupted = True   # until the run ends by itself
    try:
        # each child recorded before a signal may interrupt: it is stopped and waited for
        with interrupt.held():
            procs['relay'] = start(
                node_command('relay', 'spatial_dynamics.tools.relay'), f'{namespace}/relay',
                {**priority, **input_depth(f'{namespace}/relay', args.input_depth)},
                logs['relay'])
        with interrupt.held():
            procs['inverse_dynamics'] = start(
                node_command('inverse_dynamics', 'spatial_dynamics.ros.node'),
                f'{namespace}/node', {'robot_description_file': urdf, **priority, **floating,
                                      **input_depth(f'{namespace}/node', args.input_depth)},
                logs['inverse_dynamics'])
        for _ in range(args.busy):
            with interrupt.held():
                loops.append(busy_loop())
        rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
        bench = rclpy.create_node('latency_bench')
        executor = SingleThreadedExecutor()
        executor.add_node(bench)
        # the answers of a whole block (and a second more) wait in this process's middleware:
        # its Python thread, under normal scheduling, may read them late but loses none
        depth = min(int(args.rate * (min(args.block, args.seconds) + 1.0)) + 1000, 100_000)
        targets = [Target(bench, 'relay', f'{namespace}/relay', depth),
                   Target(bench, 'inverse_dynamics', f'{namespace}/node', depth)]
        diagnostics = NodeDiagnostics(bench, f'{namespace}/node')
        if root is not None:
            publish_odometry(bench, f'{namespace}/node/base/odometry', root)
        # this process's receive threads stamp the answers' reception; its Python thread that
        # reads them stays under normal scheduling, off the node's and the pacer's cores' way
        receiver = prioritize(args.priority, this_thread=False)
        with interrupt.held():
            pacer = Pacer([t.namespace for t in targets], trajectory, args.priority,
                          lambda: watch(procs, logs, diagnostics))
        pacer.wait_ready()
        for index, target in enumerate(targets):
            try:
                pacer.prime(executor, index, target, timeout=60.0)
            except NoAnswer as err:
                why = last_error(logs[target.name])
                raise RuntimeError(f'{err}' + (f'; its log: {why}' if why else '')) from None
        t0 = time.monotonic()
        for index, target in enumerate(targets):
            pacer.block(executor, index, args.rate, int(round(args.rate * args.warmup)), t0)
        pacer.woke_late_ns.clear()   # the machine's floor: of the measured blocks only
        for target in targets:
            target.period_ns = int(1e9 / args.rate)
        for block in counts(args.rate, args.seconds, args.block):
            for index, target in enumerate(targets):
                pid = procs[target.name].pid
                cpu = cpu_reading(pid)
                target.measuring = True
                diagnostics.measuring = target.name == 'inverse_dynamics'
                sent = pacer.block(executor, index, args.rate, block, t0)
                target.add_sent(sent.stamps)
                target.sending_s += sent.seconds
                spin_until(executor, lambda: False, 0.05)  # let the last answers of a block land
                target.measuring = diagnostics.measuring = False
                exited(procs, logs)   # a target gone during the block: its numbers mean nothing
                used = cpu_ns_between(cpu, cpu_reading(pid))
                target.cpu_ns = None if target.cpu_ns is None or used is None else (
                    target.cpu_ns + used)
        # the answers still waiting in this process's middleware: read until all came or
        # none came for a second
        last, quiet_since = -1, time.monotonic()
        while (not all(len(t.latency_ns) == len(t.sent) for t in targets)
               and time.monotonic() - quiet_since < 1.0):
            executor.spin_once(timeout_sec=0.01)
            answers = sum(t.answers for t in targets)
            if answers != last:
                last, quiet_since = answers, time.monotonic()
        exited(procs, logs)
        # what each process ran under, read from it (a priority asked may not be granted)
        of = {name: scheduling_of(procs[name].pid) for name in ('inverse_dynamics', 'relay')}
        of.update(publisher=pacer.scheduling, receiver=receiver)
        scheduling = scheduling_text(args.priority, of)
        rows = [t.summary() for t in targets]
        depth = 'keep last 1' if args.input_depth is None else f'depth {args.input_depth}'
        base = ', floating base' if root is not None else ''
        title = (f'latency: {model.name} ({plural(len(model.joint_names), "joint")}{base}), '
                 f'{args.rate:g} Hz asked ({rate_text(sent_rate(rows))} Hz sent), '
                 f'{args.seconds:g} s per target in {args.block:g} s blocks, same run, input '
                 f'{depth}; {plural(args.busy, "busy loop")}; {scheduling}; load '
                 f'{os.getloadavg()[0]:.2f}')
        print(title)
        warning = rate_warning(args.rate, rows)
        if warning:
            print(warning)
        print(format_table(rows))
        for r in rows:
            print(not_answered_line(r))
        print(diagnostics.text())
        print(difference_line(rows[1], rows[0]))
        machine = wake_ups(pacer.woke_late_ns, kernel_preemption())
        print(machine_line(machine, pacer.scheduling))
        status = 0 if all(r['answered'] for r in rows) else 1
        # the results first: a plot that fails to be written loses nothing else
        if args.json:
            results = {'robot': model.name, 'rate_hz': args.rate,
                       'rate_sent_hz': sent_rate(rows), 'busy': args.busy,
                       'scheduling': scheduling, 'scheduling_of': of,
                       'seconds_per_target': args.seconds, 'load': os.getloadavg()[0],
                       'compute_us_means': diagnostics.means_us,
                       'rejected_by_the_node': diagnostics.rejected_by_reason,
                       'machine': json_safe([machine])[0], 'targets': json_safe(rows)}
            try:
                write_json(args.json, results)
            except ValueError as err:
                print(f'latency: {err}', file=sys.stderr)
                status = 1
        if args.plot:
            try:
                if plot(args.plot, targets, title, pacer.woke_late_ns) is None:
                    print('--plot: matplotlib is not installed, no histogram drawn')
            except (OSError, ValueError) as err:
                reason = getattr(err, 'strerror', None) or str(err)
                print(f'latency: cannot write --plot {args.plot!r}: {reason}', file=sys.stderr)
                status = 1
        interrupted = False
    finally:
        # every step runs whatever one before it raised (an ExitStack runs them last first),
        # and a second signal waits until each child has been waited for
        with interrupt.held(), contextlib.ExitStack() as ending:
            if scratch is not None:
                ending.callback(scratch.cleanup)
            for loop in loops:
                ending.callback(end_loop, loop)
            for proc in procs.values():
                ending.callback(stop, proc)
            ending.callback(rclpy.try_shutdown)
            if bench is not None:
                ending.callback(bench.destroy_node)
            if pacer is not None:
                ending.callback(pacer.close, interrupted)
    return status


if __name__ == '__main__':
    sys.exit(main())
