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
else (:class:`Pacer`), on a fixed grid. Latency is input publish -> ``feedforward_efforts``
received by this process's middleware (its reception time stamp), matched by the header stamp
(wall time at publish, unique per message). Reported per target: messages sent, fraction
answered, p50 / p99 / p99.9 / max (a quantile only from enough answers to tell it from the
maximum: p99 from 100, p99.9 from 1000; else '-', null in the JSON), the CPU time its
process's threads ran per message while measured (the scheduler's nanosecond sums,
:func:`~spatial_dynamics.tools.driving.thread_cpu_ns`; '-' where the kernel keeps none), and
how many inputs not answered were followed by the next within a quarter period (the
publisher late: a keep-last-1 input keeps the newer). The relay does everything the node
does except the inverse dynamics and the second publication (``effort_commands``, published
first), so node p50 - relay p50 is the node's own cost.

Each round trip is split at the answer's publication (its DDS source timestamp, the same
clock on one machine): ``to answer`` is input publish -> answer published by the target (the
way in, the executor, the answer), the rest is the way back to this process. The node's
compute time per answer (mean and max of each diagnostics period) comes from its
``/diagnostics``. ``--busy N`` runs N busy loops (one process each) beside the run, the load
of a busy machine; ``--priority P`` asks SCHED_FIFO P for node, relay and this process's
receive threads, P + 1 for the publishing process (a tick never waits for a target's
thread); 0: normal scheduling for all; it needs the rtprio limit, see the node's
``thread_priority``. What each process ran under is read from it after the run (node and
relay: their answering thread's policy, :func:`scheduling_of`), not taken from the request:
a priority not granted reads as normal scheduling. ``--plot`` draws the histograms of the
round trips (matplotlib).

The rate the inputs were sent at is reported beside the one asked: a publisher that cannot
keep up (``--rate`` too high for the machine) sends back to back, never sleeps, and ends a
block :data:`LATE_LIMIT_S` after its due time with fewer inputs; a warning says so when it
sent more than :data:`RATE_SHORTFALL` below the rate asked. A target that refuses its inputs
(the node's ``/diagnostics`` count them rejected, none answered, for
:data:`REFUSING_PERIODS` periods) or exits ends the run with its reason (its log's error
line), at any phase.

The machine's floor, measured in the same run: how late the publishing process woke from
each sleep to its grid (it sleeps at a priority above the targets', so no thread of theirs
wakes sooner), with the kernel's preemption model (:func:`kernel_preemption`). A round trip
wakes at least one thread: its tail cannot be shorter than the wake-ups' tail.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import sysconfig
import tempfile
import textwrap
import time
from typing import Callable, Dict, List, NamedTuple, Optional, Sequence, Set, Tuple

import numpy as np

from spatial_dynamics.files import write_atomic

from .driving import (
    cpu_ns_between, die_with_parent_ignoring_ctrl_c, Interrupt, last_error, node_command,
    outputs_error, plot_path_error, pyplot, robot_model, save_figure, Sinusoids, start, stop,
    thread_cpu_ns)

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
#: The quantiles reported: name, percent, and the fewest answers that tell it from the maximum
#: (p99 of fewer than 100 answers is the largest of them, p99.9 of fewer than 1000 too): with
#: fewer it is not reported ('-' in the table, null in the JSON).
QUANTILES = (('p50', 50.0, 1), ('p99', 99.0, 100), ('p99.9', 99.9, 1000))
#: A block the publisher could not send at the rate asked ends this long after its due time,
#: s: the run takes about the time asked, however far the publisher falls behind.
LATE_LIMIT_S = 1.0
#: Inputs sent this fraction or more below the rate asked are a warning: the rate was not met.
RATE_SHORTFALL = 0.03
#: Diagnostics periods in a row in which the node rejected inputs and answered none: it
#: refuses them, and the run ends (one such period is a start-up's: a floating base before
#: its first odometry).
REFUSING_PERIODS = 3
#: The largest --input-depth: a second of inputs at the highest --rate (rclpy itself takes a
#: QoS depth up to 2**31 - 1; a deeper queue holds nothing more here).
MAX_INPUT_DEPTH = 100_000
#: The longest --warmup, s (the node's caches and the middleware settle within the first).
MAX_WARMUP_S = 60.0


def quantile(values: np.ndarray, key: str) -> Optional[float]:
    """Return the quantile ``key`` of :data:`QUANTILES` of ``values``; None if too few."""
    percent, fewest = next((q, n) for k, q, n in QUANTILES if k == key)
    return float(np.percentile(values, percent)) if len(values) >= fewest else None


class Target:
    """Publisher to one node: stamps ``sent`` while measuring, ``latency_ns[stamp]`` answers."""

    def __init__(self, bench, name: str, namespace: str, depth: int = 1000) -> None:
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from sensor_msgs.msg import JointState
        self.name = name
        self.namespace = namespace
        self.sent: Set[int] = set()
        self.latency_ns: Dict[int, int] = {}
        self.to_answer_ns: Dict[int, int] = {}   # input publish -> answer published
        self.early: Dict[int, Tuple[int, int]] = {}   # answers before their stamp was known
        self.measuring = False
        self.publisher = bench.create_publisher(
            JointState, f'{namespace}/desired_joint_states', 10)
        self.subscription = bench.create_subscription(
            JointState, f'{namespace}/feedforward_efforts', self._on_answer,
            QoSProfile(depth=depth, reliability=ReliabilityPolicy.RELIABLE))
        self.period_ns = 0   # of the inputs while measured (set by the caller)
        self.answers = 0     # all answers, measured or not
        self.published = 0   # all messages, measured or not
        # CPU ns the target's threads ran while it was measured (None: not kept), and the
        # seconds the measured inputs took to send
        self.cpu_ns: Optional[int] = 0
        self.sending_s = 0.0

    def _on_answer(self, msg, info) -> None:
        # the middleware's reception time (same clock): what this process's own executor
        # does before it runs the callback is not the target's latency
        now = info['received_timestamp'] or time.time_ns()
        self.answers += 1
        key = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        if key in self.sent:
            if key not in self.latency_ns:
                self.latency_ns[key] = now - key
                self.to_answer_ns[key] = info['source_timestamp'] - key
        elif self.measuring:   # published by the pacer, its stamp not reported yet
            self.early.setdefault(key, (now, info['source_timestamp']))

    def add_sent(self, stamps: Sequence[int]) -> None:
        """Count ``stamps`` as sent while measured (the pacer's), matching early answers."""
        for key in stamps:
            self.sent.add(key)
            if key in self.early and key not in self.latency_ns:
                received, published = self.early[key]
                self.latency_ns[key] = received - key
                self.to_answer_ns[key] = published - key
        self.early.clear()

    def publish(self, msg) -> None:
        """Stamp ``msg`` with the wall time now and publish it (counted when measuring)."""
        now = time.time_ns()
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(now, 1_000_000_000)
        if self.measuring:
            self.sent.add(now)
        self.published += 1
        self.publisher.publish(msg)

    def summary(self) -> Dict[str, float]:
        """Sent, answered fraction and latency percentiles in ms (round trip, to answer)."""
        ms = np.array(sorted(self.latency_ns.values()), dtype=float) * 1e-6
        sent = len(self.sent)
        out = {'target': self.name, 'sent': sent, 'answered': len(ms),
               'answered_fraction': len(ms) / sent if sent else float('nan')}
        to_answer = np.array(list(self.to_answer_ns.values()), dtype=float) * 1e-6
        for prefix, values in (('', ms), ('to_answer_', to_answer)):
            for key, _, _ in QUANTILES:
                out[f'{prefix}{key}_ms'] = quantile(values, key)
            out[f'{prefix}max_ms'] = float(values.max()) if len(values) else float('nan')
        out['cpu_us_per_msg'] = (1e-3 * self.cpu_ns / sent if sent and self.cpu_ns is not None
                                 else float('nan'))
        out['input_rate_hz'] = sent / self.sending_s if self.sending_s > 0 else float('nan')
        # an input not answered whose next one was published within a quarter of the
        # period: the publisher was late and a keep-last-1 input keeps the newer of the two
        stamps = np.array(sorted(self.sent), dtype=np.int64)
        lost = np.array([key not in self.latency_ns for key in stamps.tolist()], dtype=bool)
        gaps = np.diff(stamps, append=np.iinfo(np.int64).max)
        out['not_answered'] = int(lost.sum())
        out['not_answered_superseded'] = int((lost & (gaps < self.period_ns // 4)).sum())
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


class NoAnswer(RuntimeError):
    """A target running but not answering: it has not started answering, or cannot hear us."""


class Sent(NamedTuple):
    """A block as :func:`send_block` sent it: stamps (ns), lateness waking (ns), seconds.

    ``seconds``: the grid's time for the inputs sent, or longer if the sender fell behind.
    """

    stamps: List[int]
    woke_late_ns: List[int]
    seconds: float


def send_block(send: Callable[[int], int], rate: float, count: int,
               late_limit: float = LATE_LIMIT_S) -> Sent:
    """Call ``send(k)`` (it returns the input's stamp) ``count`` times on a grid at ``rate`` Hz.

    Sleeps to each tick's due time, and records how late it woke; a late tick is sent at
    once, not skipped. A sender that cannot keep up is stopped ``late_limit`` s after the
    block's due time, with fewer inputs sent: the block takes about the time asked, however
    slow the sender.
    """
    period = 1.0 / rate
    stamps, woke_late = [], []
    start_time = sent_at = time.monotonic()
    give_up = start_time + count * period + late_limit
    for k in range(count):
        if sent_at > give_up:   # behind: it cannot keep up with the rate
            break
        stamps.append(send(k))
        sent_at = time.monotonic()
        due = start_time + (k + 1) * period
        if due > sent_at:   # a late tick is sent at once, not skipped
            time.sleep(due - sent_at)
            woke_late.append(round((time.monotonic() - due) * 1e9))
    # the grid's time, or longer when the last input was sent after its period had ended
    return Sent(stamps, woke_late, max(sent_at - start_time, len(stamps) * period))


class Pacer:
    """The inputs' publisher, in a process of its own that does nothing else.

    Publishing from the process that also receives the answers made the inputs' period depend
    on that process: a tick delayed by its receiving (or by the collector) was followed at
    once by the next, and a keep-last-1 input kept only the second — measured, most inputs
    the node did not answer had come less than 0.1 ms before the next. This process paces
    the inputs on a fixed grid by sleeping (SCHED_FIFO with ``--priority``, collector off)
    and reports the stamps it published; the benchmark's process only receives. Commands and
    replies are JSON lines on the child's stdin and stdout (a plain subprocess: nothing of
    the benchmark's own script is run again in it, as multiprocessing's spawn would).
    """

    def __init__(self, namespaces: Sequence[str], trajectory: Sinusoids, priority: int,
                 watch: Callable[[], None] = lambda: None) -> None:
        self.watch = watch   # raises RuntimeError when a target has exited
        self.woke_late_ns: List[int] = []   # of the measured blocks and the warm-up
        setup = {'namespaces': list(namespaces), 'joint_names': list(trajectory.joint_names),
                 'lower': (trajectory.c - 2.0 * trajectory.a).tolist(),
                 'upper': (trajectory.c + 2.0 * trajectory.a).tolist(), 'priority': priority}
        self.process = subprocess.Popen(
            [sys.executable, '-c', 'from spatial_dynamics.tools.latency import pace_inputs; '
             'pace_inputs()'], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
            preexec_fn=die_with_parent_ignoring_ctrl_c)
        self._send(setup)
        self.scheduling = self._reply(None, 60.0)

    def _send(self, command) -> None:
        try:
            self.process.stdin.write(json.dumps(command) + '\n')
            self.process.stdin.flush()
        except OSError:   # a broken pipe: it is gone
            raise RuntimeError(f'the pacer process exited ({self.process.wait()})') from None

    def _check(self) -> None:
        """Raise RuntimeError when the pacer or (``watch``) a target has exited."""
        if self.process.poll() is not None:
            raise RuntimeError(f'the pacer process exited ({self.process.returncode})')
        self.watch()

    def _reply(self, executor, timeout: float):
        """Wait for the pacer's reply, spinning ``executor`` (if any) meanwhile."""
        import select
        deadline = time.monotonic() + timeout
        while not select.select([self.process.stdout], [], [], 0.0 if executor else 0.05)[0]:
            self._check()
            if time.monotonic() > deadline:
                raise RuntimeError(f'the pacer did not answer within {timeout:.0f} s')
            if executor is not None:
                executor.spin_once(timeout_sec=0.01)
        line = self.process.stdout.readline()
        if not line:
            raise RuntimeError(f'the pacer process exited ({self.process.wait()})')
        return json.loads(line)

    def prime(self, executor, index: int, target: Target, timeout: float) -> None:
        """Publish to target ``index`` at 20 Hz until it answers (started and connected)."""
        self._send(['prime', index])

        def answered() -> bool:
            self._check()
            return target.answers > 0
        if not spin_until(executor, answered, timeout):
            raise NoAnswer(f'{target.name} did not answer within {timeout:.0f} s')
        self._send(['stop'])
        self._reply(executor, 10.0)

    def block(self, executor, index: int, rate: float, count: int, t0: float) -> Sent:
        """Publish ``count`` inputs at ``rate`` Hz to target ``index``: what it sent.

        Fewer when the pacer fell behind (:func:`send_block`). How late it woke from each
        sleep to its grid is added to ``woke_late_ns``.
        """
        self._send(['block', index, rate, count, t0])
        reply = self._reply(executor, count / rate + LATE_LIMIT_S + 60.0)
        sent = Sent(**reply)
        self.woke_late_ns.extend(sent.woke_late_ns)
        return sent

    def close(self, interrupted: bool = False) -> None:
        """Stop the process (it also dies with this one); ``interrupted``: at once.

        Interrupted, it may be in the middle of a block (that reads no command) or priming
        (that takes the next line for its stop): it is killed, not waited for.
        """
        if not interrupted:
            try:
                self._send(['exit'])
                self.process.stdin.close()   # end of its commands, whatever it waits for
                self.process.wait(5.0)
                return
            except (OSError, ValueError, RuntimeError, subprocess.TimeoutExpired):
                pass
        self.process.kill()
        self.process.wait()


def pace_inputs() -> None:
    """Run the :class:`Pacer`'s process: JSON commands on stdin, replies on stdout."""
    import gc
    import select
    setup = json.loads(sys.stdin.readline())
    import rclpy
    from rclpy.signals import SignalHandlerOptions
    from sensor_msgs.msg import JointState
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node('latency_pacer')
    publishers = [node.create_publisher(JointState, f'{ns}/desired_joint_states', 10)
                  for ns in setup['namespaces']]
    trajectory = Sinusoids(setup['joint_names'], setup['lower'], setup['upper'])
    msg = joint_state_for(trajectory.joint_names)

    def reply(value) -> None:
        sys.stdout.write(json.dumps(value) + '\n')
        sys.stdout.flush()
    # one above the targets: a tick must not wait for a target's thread on its core
    priority = setup['priority']
    reply(prioritize(min(priority + 1, 99) if priority > 0 else 0))
    gc.freeze()
    gc.disable()
    try:
        for line in sys.stdin:
            command = json.loads(line)
            if command[0] == 'exit':
                return
            publisher = publishers[command[1]]
            if command[0] == 'prime':
                fill(msg, trajectory, 0.0)
                while not select.select([sys.stdin], [], [], 0.05)[0]:
                    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(
                        time.time_ns(), 1_000_000_000)
                    publisher.publish(msg)
                sys.stdin.readline()   # stop
                reply(None)
                continue
            _, _, rate, count, t0 = command

            def send(k: int) -> int:
                fill(msg, trajectory, time.monotonic() - t0)
                stamp = time.time_ns()
                msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp, 1_000_000_000)
                publisher.publish(msg)
                return stamp
            reply(send_block(send, rate, count)._asdict())
    except BrokenPipeError:   # the benchmark is gone
        return
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


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


def json_safe(rows: List[Dict[str, float]]) -> List[Dict[str, object]]:
    """Return ``rows`` with NaN as None (null): JSON has no NaN, and strict readers refuse it."""
    return [{key: None if isinstance(value, float) and math.isnan(value) else value
             for key, value in row.items()} for row in rows]


def cell(value: Optional[float], digits: int = 3) -> str:
    """Return a table cell (milliseconds: 3 digits): ``-`` for a value not reported (None, NaN)."""
    return '-' if value is None or math.isnan(value) else f'{value:.{digits}f}'


def format_table(rows: List[Dict[str, float]]) -> str:
    """Format the results as a fixed-width text table: round trip, then to the answer."""
    keys = [key for key, _, _ in QUANTILES] + ['max']
    lines = [f'{"":<18}{"":>7}{"":>11}{"round trip ms":^36}{"to answer ms":^36}',
             f'{"target":<18}{"sent":>7}{"answered":>11}'
             + ''.join(f'{k:>9}' for k in keys) * 2 + f'{"CPU us/msg":>12}']
    for r in rows:
        lines.append(f'{r["target"]:<18}{r["sent"]:>7}{100 * r["answered_fraction"]:>10.2f}%'
                     + ''.join(f'{cell(r[k + "_ms"]):>9}' for k in keys)
                     + ''.join(f'{cell(r["to_answer_" + k + "_ms"]):>9}' for k in keys)
                     + f'{cell(r["cpu_us_per_msg"], 1):>12}')
    return '\n'.join(lines)


def not_answered_line(r: Dict[str, float]) -> str:
    """Return the line of a target's inputs not answered; why some were, if any were late."""
    late = r['not_answered_superseded']
    return (f'{r["target"]}: {plural(r["not_answered"], "input")} not answered'
            + (f', {late} of them followed by the next within a quarter period (published '
               'late: a keep-last-1 input keeps the newer)' if late else ''))


def difference_line(node: Dict[str, float], relay: Dict[str, float]) -> str:
    """Return node - relay for each quantile both report (``-`` for the others)."""
    def diff(key: str) -> str:
        a, b = node[key + '_ms'], relay[key + '_ms']
        return '-' if a is None or b is None else f'{a - b:+.3f} ms'
    return 'inverse_dynamics - relay: ' + ', '.join(
        f'{key} {diff(key)}' for key, _, _ in QUANTILES)


def kernel_preemption() -> str:
    """Return the running kernel's preemption model: none, voluntary, full, rt or unknown.

    A thread woken at a high priority still waits for the kernel code running on its core to
    reach a point where it may be preempted: with ``none`` (servers' kernels) that can be
    milliseconds; PREEMPT_RT kernels are what real-time control runs on. Read from the
    scheduler's debug file, else ``uname -v``, the boot options and the kernel's config.
    """
    try:   # e.g. 'none voluntary (full) lazy': the one in parentheses is in effect
        with open('/sys/kernel/debug/sched/preempt') as f:
            text = f.read()
        if '(' in text:
            return text[text.index('(') + 1:text.index(')')]
    except (OSError, ValueError):
        pass
    if 'PREEMPT_RT' in os.uname().version:
        return 'rt'
    try:
        with open('/proc/cmdline') as f:
            for option in f.read().split():
                if option.startswith('preempt='):
                    return option.split('=', 1)[1]
    except OSError:
        pass
    try:
        import gzip
        with gzip.open('/proc/config.gz', 'rt') as f:
            config = set(line.strip() for line in f)
    except OSError:
        return 'unknown'
    for option, model in (('CONFIG_PREEMPT_RT=y', 'rt'), ('CONFIG_PREEMPT=y', 'full'),
                          ('CONFIG_PREEMPT_VOLUNTARY=y', 'voluntary'),
                          ('CONFIG_PREEMPT_NONE=y', 'none')):
        if option in config:
            return model
    return 'unknown'


def wake_ups(late_ns: Sequence[int], preemption: str) -> Dict[str, object]:
    """Return how late the pacer woke from its sleeps: the machine's floor for any target.

    Each round trip waits for at least one thread woken by the input; none is woken sooner
    than the pacer, which sleeps at a priority above the targets'. Quantiles in ms as
    :func:`Target.summary` reports them (None from too few wake-ups).
    """
    ms = np.array(late_ns, dtype=float) * 1e-6
    out: Dict[str, object] = {'wake_ups': len(ms), 'kernel_preemption': preemption}
    for key, _, _ in QUANTILES:
        out[f'{key}_ms'] = quantile(ms, key)
    out['max_ms'] = float(ms.max()) if len(ms) else float('nan')
    out['over_1ms'] = int((ms > 1.0).sum())
    return out


def machine_line(machine: Dict[str, object], scheduling: str) -> str:
    """Return the line of the machine's floor (:func:`wake_ups`) under ``scheduling``.

    A publisher that never slept (it could not keep up with the rate) measured no floor.
    """
    if not machine['wake_ups']:
        return (f'machine: the publisher ({scheduling}) never slept to its grid: it could not '
                'keep up with the rate and sent every input late, so no floor was measured; '
                f'kernel preemption: {machine["kernel_preemption"]}')
    keys = [key for key, _, _ in QUANTILES] + ['max']
    return (f'machine: the publisher woke late from its sleeps to the grid ({scheduling}) by '
            + ', '.join(f'{key} {cell(machine[key + "_ms"])}' for key in keys)
            + f' ms ({machine["over_1ms"]} of {machine["wake_ups"]} wake-ups over 1 ms); '
            f'kernel preemption: {machine["kernel_preemption"]} — no round trip has a '
            'shorter tail than a wake-up')


def sent_rate(rows: Sequence[Dict[str, float]]) -> float:
    """Return the rate the inputs were sent at, Hz: the lower of the targets' (NaN if none)."""
    rates = [r['input_rate_hz'] for r in rows if not math.isnan(r['input_rate_hz'])]
    return min(rates) if rates else float('nan')


def rate_warning(asked: float, rows: Sequence[Dict[str, float]]) -> Optional[str]:
    """Return the warning of a publisher that sent below the rate asked (None if it did not).

    More than :data:`RATE_SHORTFALL` below: the figures are of the lower rate.
    """
    sent = sent_rate(rows)
    if math.isnan(sent) or sent >= (1.0 - RATE_SHORTFALL) * asked:
        return None
    return (f'warning: the publisher sent {sent:.0f} Hz of the {asked:g} Hz asked '
            f'({100 * sent / asked:.1f} %): it could not keep up (each block ended '
            f'{LATE_LIMIT_S:g} s after its due time); the figures are of {sent:.0f} Hz')


def machine_legend(late_ms: np.ndarray) -> str:
    """Return the legend of the pacer's wake-ups: the highest quantile they tell."""
    told = [(key, quantile(late_ms, key)) for key, _, _ in QUANTILES]
    told = [(key, value) for key, value in told if value is not None]
    top = f', {told[-1][0]} {told[-1][1]:.2f} ms' if told else ''
    return f'publisher woke late (the machine\'s floor): {len(late_ms)} wake-ups{top}'


def legend(name: str, values: np.ndarray, sent: int) -> str:
    """Return a histogram's legend: answered, and the highest quantile the answers tell."""
    told = [(key, quantile(values, key)) for key, _, _ in QUANTILES]
    told = [(key, value) for key, value in told if value is not None]
    top = f', {told[-1][0]} {told[-1][1]:.2f} ms' if told else ''
    return f'{name}: {100 * len(values) / max(sent, 1):.1f} % answered{top}'


def plural(count: int, word: str) -> str:
    """Return ``count`` and ``word``, with an ``s`` unless one: ``1 period``, ``2 periods``."""
    return f'{count} {word}' + ('' if count == 1 else 's')


class NodeDiagnostics:
    """The node's /diagnostics: its compute time per answer while measured, and refusals.

    Compute: the means and maxima of each diagnostics period while measured. Refusals: the
    node's totals of answered and rejected inputs; a period in which rejected inputs rose
    while none was answered counts toward :data:`REFUSING_PERIODS`, one with an answer
    starts the count again.
    """

    def __init__(self, bench, namespace: str) -> None:
        from diagnostic_msgs.msg import DiagnosticArray
        self.name = f'{namespace.strip("/")}/inverse_dynamics: feedforward'
        self.means_us: List[float] = []
        self.maxima_us: List[float] = []
        self.measuring = False
        self.answered = self.rejected = 0   # the node's totals, as last reported
        self.rejected_by_reason: Dict[str, int] = {}
        self.refusing = 0   # periods in a row with inputs rejected and none answered
        bench.create_subscription(DiagnosticArray, '/diagnostics', self._on_diagnostics, 10)

    def _on_diagnostics(self, msg) -> None:
        for status in msg.status:
            if status.name != self.name:
                continue
            values = {kv.key: kv.value for kv in status.values}
            self._count(values)
            if self.measuring and values.get('compute time mean [us]'):
                self.means_us.append(float(values['compute time mean [us]']))
                self.maxima_us.append(float(values['compute time max [us]']))

    def _count(self, values: Dict[str, str]) -> None:
        try:
            answered, rejected = int(values['answered']), int(values['rejected'])
        except (KeyError, ValueError):
            return
        if answered > self.answered:
            self.refusing = 0
        elif rejected > self.rejected:
            self.refusing += 1
        self.answered, self.rejected = answered, rejected
        self.rejected_by_reason = {key[len('rejected '):]: int(value)
                                   for key, value in values.items()
                                   if key.startswith('rejected ') and value.isdigit()}

    def reasons(self) -> str:
        """Return the rejections by reason, as the node counts them: ``empty 12, ...``."""
        return ', '.join(f'{reason} {count}'
                         for reason, count in sorted(self.rejected_by_reason.items()) if count)

    def refusal(self) -> Optional[str]:
        """Return why the node refuses its inputs (None while it answers them)."""
        if self.refusing < REFUSING_PERIODS:
            return None
        return (f'refuses its inputs: {self.rejected} rejected ({self.reasons()}), none '
                f'answered for {plural(self.refusing, "diagnostics period")}')

    def text(self) -> str:
        """One line: the mean of the period means and the largest period maximum."""
        if not self.means_us:
            line = 'inverse_dynamics compute per answer: no diagnostics period while measured'
        else:
            line = (f'inverse_dynamics compute per answer (its /diagnostics, '
                    f'{plural(len(self.means_us), "period")}): mean '
                    f'{np.mean(self.means_us):.1f} us, max {max(self.maxima_us):.1f} us')
        if self.rejected:
            line += (f'; it rejected {plural(self.rejected, "input")} in the run '
                     f'({self.reasons()})')
        return line


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


def busy_loops(count: int) -> List[subprocess.Popen]:
    """Start ``count`` processes that spin a core each (the load of a busy machine)."""
    # SIGINT ignored: a Ctrl-C at the terminal reaches them too, and they are killed
    return [subprocess.Popen([sys.executable, '-c', 'while True: pass'],
                             preexec_fn=die_with_parent_ignoring_ctrl_c) for _ in range(count)]


def prioritize(priority: int, this_thread: bool = True) -> str:
    """SCHED_FIFO ``priority`` for this process's receive threads and this thread (0: none).

    ``this_thread``: False where this thread only reads what the receive threads stamped.
    """
    from spatial_dynamics.ros import realtime
    if priority <= 0:
        return 'normal scheduling'
    done = []
    try:
        for tid in [0] * this_thread + realtime.receive_threads():
            realtime.set_priority(tid, priority)
            done.append(tid)
    except OSError as err:
        for tid in done:   # none of them, rather than some: what is said is what holds
            realtime.set_priority(tid, 0)
        return (f'normal scheduling (SCHED_FIFO {priority} not permitted: '
                f'{os.strerror(err.errno)})')
    return f'SCHED_FIFO {priority}'


#: How a thread's scheduling policy is said.
POLICIES = {os.SCHED_OTHER: 'normal scheduling', os.SCHED_FIFO: 'SCHED_FIFO',
            os.SCHED_RR: 'SCHED_RR', os.SCHED_BATCH: 'SCHED_BATCH', os.SCHED_IDLE: 'SCHED_IDLE'}


def thread_policy(tid: int) -> str:
    """Return the scheduling thread ``tid`` (of any process) runs under: ``SCHED_FIFO 50``."""
    policy = os.sched_getscheduler(tid)
    name = POLICIES.get(policy, f'policy {policy}')
    return f'{name} {os.sched_getparam(tid).sched_priority}' if policy in (
        os.SCHED_FIFO, os.SCHED_RR) else name


def scheduling_of(pid: int) -> str:
    """Return what the answering thread of process ``pid`` (node or relay) runs under.

    Read from the thread itself, whatever was asked: its policy (``normal scheduling``,
    ``SCHED_FIFO 50``), and with a real-time one how many of the middleware's receive
    threads share it. ``unknown`` when the process has no thread named as the answering one
    (it has not started answering) or has exited.
    """
    from spatial_dynamics.ros import realtime
    names = {}
    try:
        for tid in os.listdir(f'/proc/{pid}/task'):
            try:
                with open(f'/proc/{pid}/task/{tid}/comm') as f:
                    names[int(tid)] = f.read().strip()
            except OSError:   # the thread ended meanwhile
                continue
        answering = [tid for tid, name in names.items() if name == realtime.ANSWERING_THREAD]
        if not answering:
            return 'unknown (no answering thread)'
        policy = thread_policy(answering[0])
        if policy.startswith(('normal', 'SCHED_BATCH', 'SCHED_IDLE')):
            return policy
        receive = [tid for tid, name in names.items() if realtime.receiving(name)]
        shared = 0
        for tid in receive:
            try:
                shared += thread_policy(tid) == policy
            except OSError:   # the thread ended meanwhile
                pass
        return (f'{policy} (answering thread, {shared} of '
                f'{plural(len(receive), "receive thread")})')
    except OSError:   # the process has exited
        return 'unknown (exited)'


#: The processes whose scheduling the run reports, as :func:`scheduling_text` names them.
SCHEDULED = {'inverse_dynamics': 'node', 'relay': 'relay', 'publisher': 'publisher',
             'receiver': "this process's receive threads"}


def scheduling_text(priority: int, of: Dict[str, str]) -> str:
    """Say what each of :data:`SCHEDULED` ran under, and to which ``--priority`` was not granted.

    ``of``: name -> the scheduling read from it (:func:`scheduling_of`, :func:`prioritize`);
    the policy alone where all ran under the same one.
    """
    def policy(text: str) -> str:   # without the note in parentheses
        return text.split(' (')[0]
    if len({policy(text) for text in of.values()}) == 1:
        text = f'{policy(of["relay"])} for all'
    elif of['inverse_dynamics'] == of['relay']:
        text = f'node and relay {of["relay"]}, ' + ', '.join(
            f'{SCHEDULED[name]} {of[name]}' for name in ('publisher', 'receiver'))
    else:
        text = ', '.join(f'{label} {of[name]}' for name, label in SCHEDULED.items())
    if priority > 0:
        missing = [label for name, label in SCHEDULED.items()
                   if policy(of[name]) != 'SCHED_FIFO %d' % (
                       min(priority + 1, 99) if name == 'publisher' else priority)]
        if missing:
            text += (f' (--priority {priority} not granted to {", ".join(missing)}: see the '
                     "node's thread_priority)")
    return text


def plot(path: str, targets: List[Target], title: str,
         woke_late_ns: Sequence[int] = ()) -> Optional[str]:
    """Draw the histograms of the round trips (log counts) to ``path``; None if no matplotlib.

    With ``woke_late_ns``, that of the pacer's wake-ups too (the machine's floor, dotted).
    """
    plt = pyplot()
    if plt is None:
        return None
    fig, ax = plt.subplots(figsize=(7.0, 3.6))
    values = [np.array(list(t.latency_ns.values()), dtype=float) * 1e-6 for t in targets]
    top = max((np.percentile(v, 99.9) for v in values if len(v)), default=1.0)   # the range
    bins = np.linspace(0.0, max(top * 1.2, 0.5), 120)
    for target, v in zip(targets, values):
        ax.hist(np.minimum(v, bins[-1]), bins=bins, histtype='step', log=True,
                label=legend(target.name, v, len(target.sent)))
    if len(woke_late_ns):
        late = np.array(woke_late_ns, dtype=float) * 1e-6
        ax.hist(np.minimum(late, bins[-1]), bins=bins, histtype='step', log=True,
                linestyle=':', color='0.4',
                label=machine_legend(late))
    ax.set_xlabel('round trip; the publisher\'s lateness waking, ms (the last bin holds '
                  'everything beyond)')
    ax.set_ylabel('answers')
    ax.set_title('\n'.join(textwrap.wrap(title, 100)), fontsize=8)
    ax.legend(fontsize=8)
    save_figure(plt, fig, path)
    return path


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


def path_text(text: str) -> str:
    """Return ``text``, an argparse type of a path: an empty one is refused (it names nothing)."""
    if not text:
        raise argparse.ArgumentTypeError('an empty path names no file')
    return text


#: The logs --log-dir holds, one per target (by the target's name).
LOGS = {'relay': 'relay.log', 'inverse_dynamics': 'inverse_dynamics.log'}


def parse_args(argv: Optional[Sequence[str]]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog='python -m spatial_dynamics.tools.latency', description=__doc__.split('\n\n')[0],
        epilog='--plot, --json and --log-dir create the folders they name that do not exist '
               'yet; each is checked before the run (a folder a file can be created in, an '
               'output that is not a folder, a named pipe or a device).')
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
    outputs = [('--plot', args.plot), ('--json', args.json)]
    if args.plot is not None and not os.path.splitext(args.plot)[1]:
        args.plot += '.png'   # what matplotlib writes for a name without a suffix
        outputs.append(('--plot', args.plot))
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

    RuntimeError names the option (:func:`parse_args` checked them: this fails only when the
    file system changed since).
    """
    for option, folder in (('--plot', args.plot and os.path.dirname(os.path.abspath(args.plot))),
                           ('--json', args.json and os.path.dirname(os.path.abspath(args.json))),
                           ('--log-dir', args.log_dir)):
        if folder:
            try:
                os.makedirs(folder, exist_ok=True)
            except OSError as err:
                raise RuntimeError(f'{option}: cannot create the folder {folder!r}: '
                                   f'{err.strerror}') from None


def exited(procs: Dict[str, subprocess.Popen], logs: Optional[Dict[str, str]] = None) -> None:
    """Raise RuntimeError naming the first of ``procs`` that has exited, and why.

    ``logs``: name -> its log, whose error line (:func:`~.driving.last_error`) is the why.
    """
    for name, proc in procs.items():
        if proc.poll() is not None:
            why = last_error((logs or {}).get(name))
            raise RuntimeError(f'{name} exited ({proc.returncode}) during the run'
                               + (f': {why}' if why else ''))


def watch(procs: Dict[str, subprocess.Popen], logs: Dict[str, str],
          diagnostics: Optional['NodeDiagnostics']) -> None:
    """Raise RuntimeError when a target exited or the node refuses its inputs, with why.

    Called while the run waits for anything (the pacer, an answer): it ends at once.
    """
    exited(procs, logs)
    refusal = diagnostics.refusal() if diagnostics is not None else None
    if refusal:
        why = last_error(logs.get('inverse_dynamics'), 'rejected')
        raise RuntimeError(f'inverse_dynamics {refusal}' + (f'; its log: {why}' if why else ''))


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
        return run(args)
    except KeyboardInterrupt:
        print(f'latency: interrupted ({interrupt.name}); the node, the relay and the '
              'publisher stopped', file=sys.stderr)
        return interrupt.status
    except RuntimeError as err:
        print(f'latency: {err}', file=sys.stderr)
        return 1


def write_json(path: str, results: Dict[str, object]) -> None:
    """Write ``results`` to ``path`` (``--json``), all or nothing; ValueError names the path."""
    write_atomic(path, json.dumps(json_safe([results])[0], indent=2, allow_nan=False) + '\n',
                 '--json')


def rate_text(hz: float) -> str:
    """Return a rate as the output says it: whole Hz from 100 Hz, 3 digits below."""
    return f'{hz:.0f}' if hz >= 100.0 else f'{hz:.3g}'


def cpu_reading(pid: int) -> Optional[Dict[int, int]]:
    """Return :func:`~.driving.thread_cpu_ns` of ``pid``; None if it is not kept or exited."""
    try:
        return thread_cpu_ns(pid)
    except OSError:   # exited: the run's next check says so
        return None


def run(args: argparse.Namespace) -> int:
    """Run the benchmark of ``args`` (see :func:`main`); raises on a process that exited."""
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
    folder = args.log_dir or scratch.name
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
        procs['relay'] = start(node_command('relay', 'spatial_dynamics.tools.relay'),
                               f'{namespace}/relay',
                               {**priority, **input_depth(f'{namespace}/relay', args.input_depth)},
                               logs['relay'])
        procs['inverse_dynamics'] = start(
            node_command('inverse_dynamics', 'spatial_dynamics.ros.node'), f'{namespace}/node',
            {'robot_description_file': urdf, **priority, **floating,
             **input_depth(f'{namespace}/node', args.input_depth)},
            logs['inverse_dynamics'])
        loops += busy_loops(args.busy)
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
        pacer = Pacer([t.namespace for t in targets], trajectory, args.priority,
                      lambda: watch(procs, logs, diagnostics))
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
        if pacer is not None:
            pacer.close(interrupted)
        if bench is not None:
            bench.destroy_node()
        rclpy.try_shutdown()
        for proc in procs.values():
            stop(proc)
        for loop in loops:
            loop.kill()
            loop.wait()
        if scratch is not None:
            scratch.cleanup()
    return status


if __name__ == '__main__':
    sys.exit(main())
