# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The latency benchmark's targets, node and relay, and what is read from them and the machine.

:class:`Target`: this process's publisher and answer subscription for one target, the inputs
sent and the answers received, summarised in the quantiles of :data:`QUANTILES`;
:class:`NodeDiagnostics`: the node's compute time per answer and its refusals, from its
/diagnostics. The processes: the QoS override of their input depth (:func:`input_depth`),
their logs (:data:`LOGS`), one that exited or refuses its inputs, with its log's reason
(:func:`exited`, :func:`watch`), the CPU time their threads ran (:func:`cpu_reading`), the
scheduling each ran under (:func:`prioritize`, :func:`scheduling_of`,
:func:`scheduling_text`) and the kernel's preemption model (:func:`kernel_preemption`); the
busy loops run beside them (:func:`busy_loop`, :func:`end_loop`).
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from typing import Dict, List, Optional, Sequence, Set, Tuple

import numpy as np

from .driving import die_with_parent_ignoring_ctrl_c, last_error, thread_cpu_ns

# rclpy and the ROS messages are imported inside the functions that use them: the benchmark's
# options are parsed (and --help printed) without ROS, and rclpy alone takes some 0.1 s to import.

#: The quantiles reported: name, percent, and the fewest answers that tell it from the maximum
#: (p99 of fewer than 100 answers is the largest of them, p99.9 of fewer than 1000 too): with
#: fewer it is not reported ('-' in the table, null in the JSON).
QUANTILES = (('p50', 50.0, 1), ('p99', 99.0, 100), ('p99.9', 99.9, 1000))
#: Diagnostics periods in a row in which the node rejected inputs and answered none: it
#: refuses them, and the run ends (one such period is a start-up's: a floating base before
#: its first odometry).
REFUSING_PERIODS = 3


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


def input_depth(namespace: str, depth: Optional[int]) -> Dict[str, str]:
    """Return the QoS override of the ``desired_joint_states`` subscription depth, if any."""
    if depth is None:
        return {}
    return {f'qos_overrides.{namespace}/desired_joint_states.subscription.depth': str(depth)}


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


def busy_loop() -> subprocess.Popen:
    """Start a process that spins a core (the load of a busy machine); end it with SIGKILL."""
    # SIGINT ignored: a Ctrl-C at the terminal reaches it too, and it is killed
    return subprocess.Popen([sys.executable, '-c', 'while True: pass'],
                            preexec_fn=die_with_parent_ignoring_ctrl_c)


def busy_loops(count: int) -> List[subprocess.Popen]:
    """Start ``count`` :func:`busy_loop` processes."""
    return [busy_loop() for _ in range(count)]


def end_loop(loop: subprocess.Popen) -> None:
    """Kill a :func:`busy_loop` and wait for it (none is left a zombie)."""
    loop.kill()
    loop.wait()


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


#: The logs --log-dir holds, one per target (by the target's name).
LOGS = {'relay': 'relay.log', 'inverse_dynamics': 'inverse_dynamics.log'}


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


def cpu_reading(pid: int) -> Optional[Dict[int, int]]:
    """Return :func:`~.driving.thread_cpu_ns` of ``pid``; None if it is not kept or exited."""
    try:
        return thread_cpu_ns(pid)
    except OSError:   # exited: the run's next check says so
        return None
