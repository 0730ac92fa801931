# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Start-up of the node: process start -> first correct answer, with inputs already flowing.

    python -m spatial_dynamics.tools.startup [--urdf PATH] [--runs 3]
        [--backend auto numpy compiled] [--rate 100] [--hold 3] [--json out/startup.json]

For each run and backend, this process publishes ``desired_joint_states`` (a smooth
trajectory of the robot, model order, ``--rate`` Hz) **before** it starts the installed node
(``ros2 run spatial_dynamics inverse_dynamics``, else ``python -m spatial_dynamics.ros.node``)
in a namespace of its own, and measures:

* **first answer**: from just before the process starts to the first ``feedforward_efforts``
  whose efforts equal the library's τ for that message's state (to 1e-9);
* **RSS at first answer** (``VmRSS`` of the node's process then) and **peak** (``VmHWM`` at
  the end: at least ``--hold`` s after the first answer, and after the switch to the compiled
  kernels when the node prepares them);
* **compiled at**: when ``/diagnostics`` first shows the compiled backend (if it does);
* **max gap**: the longest time between two answers after the first (inputs come every
  1/rate s: a compilation that held the node up would show here); **wrong**: answers that
  differ from the library's τ (must be 0).

Each run measures **cold** (a fresh, empty ``PYTHONPYCACHEPREFIX`` for the node: no
bytecode cached, what a read-only install or a new container sees; nothing else is compiled
at run time, the kernels are built with the package) and then **warm** (the same directory
again). The table
gives min / median / max over the runs. The default robot is the UR5 of example-robot-data
(``config/demo_arm.urdf`` when that is not installed).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import shutil
import sys
import sysconfig
import tempfile
import time
from typing import Dict, Iterator, List, Optional, Sequence

import numpy as np

import spatial_dynamics as sd
from spatial_dynamics import files
from .driving import (
    demo_urdf, Interrupt, node_command, outputs_error, path_text, robot_model, rss_bytes,
    Sinusoids, start, stop)
from .latency import in_range
from .latency_report import write_json

# rclpy and the ROS messages are imported inside the functions that run a node: the options
# are parsed (and --help printed) without ROS, and rclpy alone takes some 0.1 s to import.

BACKENDS = ('auto', 'numpy', 'compiled')
TOLERANCE = 1e-9       # N m: an answer is correct when every effort is this close to τ
UR5 = ('ur_description', 'urdf', 'ur5_robot.urdf')
MB = 1024 * 1024
SPIN = 0.1             # s: the longest wait in rclpy, so that a signal is handled this soon


def example_robot(*parts: str) -> Optional[str]:
    """Path of a file of example-robot-data's ``robots`` directory, or None if not installed.

    Looked up where the pip wheel (``cmeel.prefix``), a conda/robotpkg prefix or a ROS
    package (``AMENT_PREFIX_PATH``) puts it.
    """
    prefixes = [os.path.join(sysconfig.get_paths()[key], 'cmeel.prefix')
                for key in ('purelib', 'platlib')]
    prefixes += [sys.prefix, '/opt/openrobots', '/usr']
    prefixes += [p for p in os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep) if p]
    for prefix in prefixes:
        path = os.path.join(prefix, 'share', 'example-robot-data', 'robots', *parts)
        if os.path.isfile(path):
            return path
    return None


def robot_path(urdf: Optional[str]) -> str:
    """Return the robot of ``--urdf``: it, else the UR5 of example-robot-data, else the demo."""
    return urdf or example_robot(*UR5) or demo_urdf()


def proc_status_bytes(pid: int, key: str) -> int:
    """Return a size field (``VmRSS``, ``VmHWM``...) of ``/proc/<pid>/status``, bytes."""
    if key == 'VmRSS':
        return rss_bytes(pid)
    with open(f'/proc/{pid}/status') as f:
        for line in f:
            if line.startswith(key + ':'):
                return int(line.split()[1]) * 1024
    raise RuntimeError(f'no {key} for pid {pid}')


@contextlib.contextmanager
def bytecode_cache(path: str) -> Iterator[None]:
    """Cache the bytecode of the processes started inside in ``path`` (``PYTHONPYCACHEPREFIX``).

    Writing is allowed there even when ``PYTHONDONTWRITEBYTECODE`` is set, so that the cold
    run fills what the warm run reads.
    """
    saved = {key: os.environ.get(key) for key in ('PYTHONPYCACHEPREFIX',
                                                  'PYTHONDONTWRITEBYTECODE')}
    os.environ['PYTHONPYCACHEPREFIX'] = path
    os.environ.pop('PYTHONDONTWRITEBYTECODE', None)
    try:
        yield
    finally:
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


class Probe:
    """Inputs to and answers of one node: the states sent by stamp, answers checked on arrival."""

    def __init__(self, bench, namespace: str, model) -> None:
        from diagnostic_msgs.msg import DiagnosticArray
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from sensor_msgs.msg import JointState
        self.bench = bench
        self.model = model
        self.status_name = namespace.lstrip('/') + '/inverse_dynamics: robot model'
        self.states: Dict[int, tuple] = {}
        self.sent = 0
        self.answers = 0
        self.wrong = 0
        self.first: Optional[float] = None     # monotonic time of the first correct answer
        self.last: Optional[float] = None
        self.max_gap = 0.0
        self.max_gap_at = 0.0                  # monotonic time at which it ended
        self.backend = ''                      # latest 'backend' of /diagnostics
        self.compiled_at: Optional[float] = None
        self.on_first = None                   # called at the first correct answer
        self.publisher = bench.create_publisher(JointState, f'{namespace}/desired_joint_states',
                                                10)
        self.subscriptions = [
            bench.create_subscription(
                JointState, f'{namespace}/feedforward_efforts', self._on_answer,
                QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)),
            bench.create_subscription(DiagnosticArray, '/diagnostics', self._on_diagnostics,
                                      10)]
        self.msg = JointState(name=list(model.joint_names))

    def publish(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> None:
        """Publish one state with a unique stamp (the message count) and remember it."""
        k = self.sent = self.sent + 1
        self.msg.header.stamp.sec, self.msg.header.stamp.nanosec = divmod(k, 1000)
        self.msg.position, self.msg.velocity, self.msg.effort = q.tolist(), qd.tolist(), \
            qdd.tolist()
        self.states[k] = (q, qd, qdd)
        self.states.pop(k - 5000, None)
        self.publisher.publish(self.msg)

    def _on_answer(self, msg) -> None:
        now = time.monotonic()
        state = self.states.get(msg.header.stamp.sec * 1000 + msg.header.stamp.nanosec)
        ok = state is not None and len(msg.effort) == len(state[0]) and np.allclose(
            msg.effort, sd.rnea(self.model, *state, backend='numpy'), rtol=0.0, atol=TOLERANCE)
        self.answers += 1
        if not ok:
            self.wrong += 1
            return
        if self.first is None:
            self.first = now
            if self.on_first is not None:
                self.on_first()
        elif now - self.last > self.max_gap:
            self.max_gap, self.max_gap_at = now - self.last, now
        self.last = now

    def _on_diagnostics(self, msg) -> None:
        for status in msg.status:
            if status.name == self.status_name:
                for kv in status.values:
                    if kv.key == 'backend':
                        self.backend = kv.value
                        if kv.value.startswith('compiled') and self.compiled_at is None:
                            self.compiled_at = time.monotonic()

    def close(self) -> None:
        """Remove the publisher and subscriptions."""
        for sub in self.subscriptions:
            self.bench.destroy_subscription(sub)
        self.bench.destroy_publisher(self.publisher)


def log_name(label: str, index: int) -> str:
    """Return the name of a node's log in ``--log-dir``: ``<backend>_<cache>_<index>.log``."""
    return f'{label.replace(" ", "_")}_{index}.log'


def run_once(executor, bench, model, urdf: str, backend: str, cache_dir: str, label: str,
             args: argparse.Namespace, index: int, interrupt: Interrupt) -> Dict[str, object]:
    """Start one node with inputs flowing; measure until it is settled; stop it.

    Raises RuntimeError when the node exits or gives no settled answer within
    ``args.timeout`` s (of its start; after ``--hold``), KeyboardInterrupt on a signal
    (``interrupt``); the node is stopped and waited for either way.
    """
    namespace = f'/sd_startup_{os.getpid()}_{index}'
    probe = Probe(bench, namespace, model)
    trajectory = Sinusoids.for_model(model)
    period = 1.0 / args.rate
    t0 = time.monotonic()

    def tick(until, deadline: float, late: str) -> None:
        """Publish on the period's grid and spin until ``until()`` (or ``deadline``)."""
        while not until():
            now = time.monotonic()
            if now > deadline:
                raise RuntimeError(f'{label}: {late} (answers {probe.answers}, '
                                   f'wrong {probe.wrong})')
            if now >= t0 + probe.sent * period:
                probe.publish(*trajectory(now - t0))
            # bounded: a signal is handled only once rclpy returns
            executor.spin_once(timeout_sec=min(SPIN, max(0.0, t0 + probe.sent * period
                                                         - time.monotonic())))

    proc = None
    try:
        # inputs flowing before the start
        tick(lambda: time.monotonic() - t0 > args.lead, float('inf'), '')
        log = args.log_dir and os.path.join(args.log_dir, log_name(label, index))
        with bytecode_cache(cache_dir), interrupt.held():   # a signal: once proc is recorded
            started = time.monotonic()
            proc = start(node_command('inverse_dynamics', 'spatial_dynamics.ros.node'),
                         namespace, {'robot_description_file': urdf, 'backend': backend}, log)
        rss_first: List[int] = []
        probe.on_first = lambda: rss_first.append(proc_status_bytes(proc.pid, 'VmRSS'))
        matched: List[float] = []

        def answered() -> bool:
            if not matched and probe.publisher.get_subscription_count():
                matched.append(time.monotonic() - started)
            return probe.first is not None or proc.poll() is not None

        tick(answered, started + args.timeout,
             f'no correct answer within --timeout {args.timeout:g} s of the start')
        if probe.first is None:
            raise RuntimeError(f'{label}: the node exited with status {proc.returncode}'
                               + (f' (see {log})' if log else ''))
        tick(lambda: time.monotonic() - probe.first > args.hold and probe.backend
             and 'preparing' not in probe.backend,
             probe.first + args.hold + args.timeout,
             f'its backend not settled within --timeout {args.timeout:g} s after --hold '
             f'(backend {probe.backend!r})')
        row = {
            'backend': backend, 'cache': label.split()[-1],
            'first_answer_s': probe.first - started,
            'matched_s': matched[0] if matched else None,
            'rss_first_mb': rss_first[0] / MB,
            'peak_mb': proc_status_bytes(proc.pid, 'VmHWM') / MB,
            'rss_end_mb': proc_status_bytes(proc.pid, 'VmRSS') / MB,
            'compiled_at_s': None if probe.compiled_at is None else probe.compiled_at - started,
            'max_gap_ms': probe.max_gap * 1e3,
            'max_gap_end_s': probe.max_gap_at - started if probe.max_gap else None,
            'answers': probe.answers,
            'wrong': probe.wrong, 'backend_in_use': probe.backend}
    finally:
        with interrupt.held():      # a second signal: once the node is waited for
            row_exit = None if proc is None else stop(proc)
            probe.close()
    row['exit_status'] = row_exit
    return row


def _stats(values: Sequence[Optional[float]], fmt: str) -> str:
    values = [v for v in values if v is not None]
    if not values:
        return '-'
    low, mid, high = min(values), float(np.median(values)), max(values)
    return ' / '.join(format(v, fmt) for v in (low, mid, high))


COLUMNS = (('first answer s', 'first_answer_s', '.2f'), ('discovered s', 'matched_s', '.2f'),
           ('RSS at first MB', 'rss_first_mb', '.0f'), ('peak MB', 'peak_mb', '.0f'),
           ('compiled at s', 'compiled_at_s', '.1f'), ('max gap ms', 'max_gap_ms', '.0f'))


def format_table(rows: List[Dict[str, object]]) -> str:
    """One line per (backend, cache): min / median / max over the runs of each column.

    ``discovered s`` is when this process saw the node's input subscription (DDS discovery,
    part of the first answer's time).
    """
    keys = list(dict.fromkeys((row['backend'], row['cache']) for row in rows))
    cells = [['backend', 'cache', 'runs'] + [title for title, _, _ in COLUMNS] + ['wrong']]
    for backend, cache in keys:
        group = [r for r in rows if (r['backend'], r['cache']) == (backend, cache)]
        cells.append([backend, cache, str(len(group))]
                     + [_stats([r[key] for r in group], fmt) for _, key, fmt in COLUMNS]
                     + [str(sum(r['wrong'] for r in group))])
    widths = [max(len(row[i]) for row in cells) for i in range(len(cells[0]))]
    return '\n'.join('  '.join(cell.ljust(width) for cell, width in zip(row, widths)).rstrip()
                     for row in cells)


RUNS = 1000            # at most: each run is a few seconds per backend


def parse_args(argv: Optional[Sequence[str]]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog='python -m spatial_dynamics.tools.startup', description=__doc__.split('\n\n')[0])
    parser.add_argument('--urdf', type=path_text, default=None,
                        help='robot (default: the UR5 of example-robot-data, else the demo arm)')
    parser.add_argument('--runs', type=in_range(int, 1, RUNS), default=3,
                        help=f'cold + warm pairs, 1 .. {RUNS} (default 3)')
    parser.add_argument('--backend', nargs='+', choices=BACKENDS, default=['auto'],
                        help="the node's backend parameter, one or more, each once "
                             '(default auto)')
    parser.add_argument('--rate', type=in_range(float, 1.0, 10000.0), default=100.0,
                        help='input Hz, 1 .. 10000 (default 100)')
    parser.add_argument('--lead', type=in_range(float, 0.0, 60.0), default=0.5,
                        help='seconds of input before the node starts, 0 .. 60 (default 0.5)')
    parser.add_argument('--hold', type=in_range(float, 0.0, 3600.0), default=3.0,
                        help='seconds after the first answer before the peak is read, '
                             '0 .. 3600 (default 3; longer while compiled kernels are '
                             'prepared)')
    parser.add_argument('--timeout', type=in_range(float, 0.0, 86400.0, True), default=300.0,
                        help='give up on a node with no correct answer this many seconds '
                             'after its start (and with its backend not settled this long '
                             'after --hold), above 0, at most 86400 (default 300)')
    parser.add_argument('--json', type=path_text, default=None,
                        help='also write the rows here (only when every run ran to its end)')
    parser.add_argument('--log-dir', type=path_text, default=None,
                        help='node logs (default: none)')
    args = parser.parse_args(argv)
    twice = sorted({b for b in args.backend if args.backend.count(b) > 1})
    if twice:
        parser.error(f'--backend {" ".join(twice)} given more than once')
    # their folders are created before the run: one a file cannot be created in is refused;
    # no output may be the robot description read (the default one too) nor a node's log
    urdf = robot_path(args.urdf)
    outputs = [('--json', args.json)]
    if args.log_dir:        # of its logs (thousands), those that are another path of the run
        taken = {files.output_path(p) for p in (args.json, urdf) if p}
        labels = [f'{backend} {cache}' for _ in range(args.runs) for backend in args.backend
                  for cache in ('cold', 'warm')]
        for index, label in enumerate(labels):
            path = os.path.join(args.log_dir, log_name(label, index))
            if files.output_path(path) in taken:
                outputs.append(("--log-dir's log", path))
    error = outputs_error(outputs, [('--log-dir', args.log_dir)], [('--urdf', urdf)])
    if error:
        parser.error(error)
    return args


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Measure; print the table; 0 if every run answered correctly.

    1 when a run did not end (the node exited, no settled answer in time) or the robot
    cannot be loaded or has no joints; 128 + the signal's number on SIGINT or SIGTERM, once
    the node running is stopped.
    """
    args = parse_args(argv)
    interrupt = Interrupt().install()   # from here on: also while loading
    try:
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.signals import SignalHandlerOptions
        urdf, model = robot_model(robot_path(args.urdf))
    except KeyboardInterrupt:
        print(f'start-up: interrupted ({interrupt.name}) while loading', file=sys.stderr)
        return interrupt.status
    except (OSError, ValueError) as err:
        print(f'start-up: --urdf {robot_path(args.urdf)!r}: {err}', file=sys.stderr)
        return 1
    if not model.joint_names:
        print(f'start-up: --urdf {urdf!r}: the robot has no joints: nothing to answer',
              file=sys.stderr)
        return 1
    if args.log_dir:
        os.makedirs(args.log_dir, exist_ok=True)
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    bench = rclpy.create_node('startup_bench')
    executor = SingleThreadedExecutor()
    executor.add_node(bench)
    rows: List[Dict[str, object]] = []
    index = 0
    status = 0
    try:
        for run in range(args.runs):
            for backend in args.backend:
                cache_dir = tempfile.mkdtemp(prefix='sd_pycache_')
                try:
                    for cache in ('cold', 'warm'):
                        rows.append(run_once(executor, bench, model, urdf, backend, cache_dir,
                                             f'{backend} {cache}', args, index, interrupt))
                        index += 1
                        print(_row_line(rows[-1]), flush=True)
                finally:
                    shutil.rmtree(cache_dir, ignore_errors=True)
    except (KeyboardInterrupt, RuntimeError) as err:
        # a KeyboardInterrupt raised inside rclpy's message conversion comes as RuntimeError;
        # Ctrl-C reaches the node too: its exit then is no failure
        if interrupt.signal is None and isinstance(err, RuntimeError):
            print(f'start-up: {err}', file=sys.stderr)
            status = 1
        else:
            print(f'start-up: interrupted ({interrupt.name}); the node stopped',
                  file=sys.stderr)
            status = interrupt.status
    finally:
        try:
            with interrupt.held():
                bench.destroy_node()
                rclpy.try_shutdown()
        except KeyboardInterrupt:   # a second signal meanwhile: its status
            status = interrupt.status
    if status and interrupt.signal is not None:
        return status
    print(f'start-up: {model.name} ({len(model.joint_names)} joints, {urdf}), inputs at '
          f'{args.rate:g} Hz from before the start; min / median / max of '
          f'{len(rows) // (2 * len(args.backend))} run(s)')
    if rows:
        print(format_table(rows))
    if status:
        if args.json:   # figures of some of the runs are no run's figures: keep an earlier file
            print(f'start-up: --json {args.json!r} not written (not every run ran to its end)',
                  file=sys.stderr)
        return status
    if args.json:       # whole or not at all: a reader never sees half of it
        try:
            write_json(args.json, {'robot': model.name, 'urdf': urdf, 'rate_hz': args.rate,
                                   'rows': rows})
        except (OSError, ValueError) as err:
            print(f'start-up: {err}', file=sys.stderr)
            return 1
    return 0 if all(r['wrong'] == 0 and r['exit_status'] == 0 for r in rows) else 1


def _row_line(row: Dict[str, object]) -> str:
    compiled = row['compiled_at_s']
    return (f'  {row["backend"]} {row["cache"]}: first answer {row["first_answer_s"]:.2f} s '
            f'(subscription seen at {row["matched_s"] or float("nan"):.2f} s), '
            f'RSS {row["rss_first_mb"]:.0f} MB, peak {row["peak_mb"]:.0f} MB, '
            + (f'compiled at {compiled:.1f} s, ' if compiled is not None else '')
            + f'max gap {row["max_gap_ms"]:.0f} ms (ending at {row["max_gap_end_s"] or 0:.1f} s), '
            f'backend {row["backend_in_use"]!r}, '
            f'exit {row["exit_status"]}')


if __name__ == '__main__':
    sys.exit(main())
