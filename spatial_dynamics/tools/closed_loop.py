# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Closed-loop demo: the simulated robot tracks a trajectory under three control laws.

    python -m spatial_dynamics.tools.closed_loop [--urdf ROBOT.urdf] [--seconds 6]
        [--frequency 5] [--plot out/closed_loop.png] [--json out/closed_loop.json]
        [--robot-urdf TRUE.urdf]

For each control law the MuJoCo robot (``python -m spatial_dynamics.sim``, lockstep, 1 ms
steps) and the ``inverse_dynamics`` node start in a namespace of their own; this process
publishes the desired trajectory and records the tracking error ``q_d(t) - q(t)`` of every
measured state:

* ``PD alone``: ``control_mode: pd_feedforward``, ``output: none`` — τ = Kp e + Kd ė;
* ``PD + feed-forward``: ``pd_feedforward``, ``output: full`` — τ = ID(q_d, q̇_d, q̈_d) + Kp e +
  Kd ė;
* ``computed torque``: ``computed_torque`` — τ = ID(q, q̇, q̈_d + Kp e + Kd ė).

Gains: a critically damped loop of natural frequency ``--frequency`` (Hz), ω = 2π f; for the
PD laws scaled by the inertia each joint moves when the others are free, m_i = 1/(M⁻¹)_ii at
the start (M_ii, the inertia with the others held, can be 20× larger on a coupled arm, and a
loop tuned to it is unstable at 1 ms): Kp = m_i ω², Kd = 2 m_i ω (N m/rad, N m s/rad); for
computed torque Kp = ω², Kd = 2ω (1/s², 1/s). The trajectory starts
at rest, ``q_d(t) = q0 + A (1 - cos(w t))`` per joint (periods 2..4 s), so the robot starts
on it.

Timing: the simulator publishes ``joint_states`` at step k and waits for one effort command;
the node answers each measured state with the desired state it holds. This process relays the
node's answers to the simulator and, before it forwards the torque of step k, publishes the
desired state of step k + 1 (:class:`Lockstep`), so every command is computed from the
desired state of its own step, whatever the load on the machine.

With ``--plan`` there is no relay: the node gets the whole trajectory once, as a
``desired_trajectory`` (``JointTrajectory`` sampled every 50 ms with velocities and
accelerations: quintic splines), and follows it by sampling it at each measured state's stamp
(sim time), its commands going straight to the simulator; at half time a second plan replaces
it (back to the start in 1 s, then held), which the node blends in from where the first one
was. The error is then ``q_d - q`` with the ``q_d`` the node echoes for each measured state.

A table of the tracking error per joint is shown live; at the end a PNG plots |e| per joint
over time (log scale) for the three laws, and ``--json`` writes the figures.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import signal
import subprocess
import sys
import time
from typing import Dict, List, Optional, Sequence

import numpy as np

import spatial_dynamics as sd
from spatial_dynamics import files
from .driving import (
    Interrupt, last_error, node_command, outputs_error, path_text, plot_path_error, pyplot,
    redraw, robot_model, save_figure, start, stop)
from .latency import in_range
from .latency_report import write_json
from .latency_targets import busy_loop, end_loop

# rclpy and the ROS messages are imported inside the functions that run a node: the options
# are parsed (and --help printed) without ROS, and rclpy alone takes some 0.1 s to import.

LAWS = (('PD alone', {'control_mode': 'pd_feedforward', 'output': 'none'}),
        ('PD + feed-forward', {'control_mode': 'pd_feedforward', 'output': 'full'}),
        ('computed torque', {'control_mode': 'computed_torque', 'output': 'full'}))
TIMESTEP = 0.001
#: Wall seconds the relay gives the desired state of a step to reach the node before it lets
#: the simulator step (:class:`Lockstep`). DDS does not order two topics: once the node
#: answered within ~100 µs of a sample (its own answering loop), the simulator's next state
#: overtook the desired state of its step in a quarter of the steps with no pause here.
DELIVERY = 0.002
#: Wall seconds without a simulated step that end a law: lockstep waits for a command it
#: takes, and a command it refused (a loop that diverged past 1e6 N m) is not sent again for
#: the same state (the node answers each measurement once).
STALL_S = 10.0
#: The closed loop's sampling: ω·dt of a critically damped PD beyond it diverges at the 1 ms
#: step (semi-implicit Euler); on a coupled arm (the demo arm) it may diverge below it too, and
#: the law then ends within STALL_S.
MAX_OMEGA_DT = 0.5
#: The simulator's command topic: the relay (:class:`Lockstep`) forwards the node's commands.
SIM_COMMANDS = 'sim_effort_commands'


def laws(text: str) -> str:
    """Return ``--laws`` checked: 'all' or a comma-separated subset of pd, pd_ff, ct."""
    if text == 'all':
        return text
    names = text.split(',')
    unknown = [name for name in names if name not in ('pd', 'pd_ff', 'ct')]
    if unknown or not names:
        raise argparse.ArgumentTypeError(f'{unknown} not among pd, pd_ff, ct (or all)')
    twice = sorted({name for name in names if names.count(name) > 1})
    if twice:       # a law run twice writes over its own logs, and twice into --json
        raise argparse.ArgumentTypeError(f'{", ".join(twice)} given twice')
    return text


def chosen_laws(text: str) -> List[int]:
    """Return the rows of :data:`LAWS` that ``--laws`` (checked by :func:`laws`) picks."""
    index = {'pd': 0, 'pd_ff': 1, 'ct': 2}
    return list(range(len(LAWS))) if text == 'all' else [index[x] for x in text.split(',')]


def law_slug(settings: Dict[str, str], plan: bool) -> str:
    """Return the namespace of a law's run without its '/': its logs are named after it."""
    return ('closed_loop_' + ('plan_' if plan else '') + settings['control_mode'] + '_'
            + settings['output'])


def laws_error(model, picks: Sequence[int], frequency: float) -> Optional[str]:
    """Why the laws ``picks`` cannot run on ``model`` at ``frequency`` Hz (None if they can).

    A robot without joints has nothing to control; a law's gains (:func:`gains`) must be
    within the node's bounds (``kp`` ≤ MAX_KP, ``kd`` ≤ MAX_KD): the node refuses them at
    start and the run would end with 'the node exited'. Says the highest frequency that fits.
    """
    from spatial_dynamics.ros.control import MAX_KD, MAX_KP
    if not model.joint_names:
        return f'the robot {model.name!r} has no joints: nothing to control'
    sampled = MAX_OMEGA_DT / (2.0 * math.pi * TIMESTEP)
    if frequency > sampled:
        return (f'--frequency {frequency:g}: the loop is sampled every {TIMESTEP * 1e3:g} ms, '
                f'and a critically damped PD diverges beyond ω·dt = {MAX_OMEGA_DT:g}: at most '
                f'{math.floor(sampled * 10) / 10:g} Hz')
    q0 = start_point(model)
    for k in picks:
        name, settings = LAWS[k]
        kp, kd = gains(model, q0, settings['control_mode'], frequency)
        j = int(np.argmax(kp))
        if kp[j] > MAX_KP or kd[j] > MAX_KD:
            # kp = m w², kd = 2 m w (m = 1 under computed torque): both within their bounds
            m = kp[j] / (2.0 * math.pi * frequency) ** 2
            w = min(math.sqrt(MAX_KP / m), MAX_KD / (2.0 * m))
            return (f'--frequency {frequency:g} gives {name} kp {kp[j]:.4g} and kd {kd[j]:.4g} '
                    f'on joint {model.joint_names[j]!r}, beyond what the node takes (kp at '
                    f'most {MAX_KP:g}, kd at most {MAX_KD:g}): at most '
                    f'{math.floor(w / (2.0 * math.pi) * 10) / 10:g} Hz for this robot')
    return None


def parse_args(argv: Optional[Sequence[str]]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog='python -m spatial_dynamics.tools.closed_loop',
                                     description=__doc__.split('\n\n')[0])
    parser.add_argument('--urdf', type=path_text, default=None,
                        help='robot (default: the embedded demo arm)')
    parser.add_argument('--robot-urdf', type=path_text, default=None,
                        help='the simulated robot when it is not the one the node is given '
                             '(default: --urdf): e.g. the true robot, with the node on an '
                             'original or a corrected URDF (replay --write-urdf)')
    parser.add_argument('--seconds', type=in_range(float, 0.0, 3600.0, True), default=6.0,
                        help='simulated seconds per control law, above 0, at most 3600 '
                             '(default 6)')
    parser.add_argument('--frequency', type=in_range(float, 0.0, 1000.0, True), default=5.0,
                        help='natural frequency of the feedback loop, Hz, above 0 (default 5); '
                             'at most 79.5 at the 1 ms step, and the gains it gives must be '
                             "ones the node takes (said before the run)")
    parser.add_argument('--amplitude', type=in_range(float, 0.0, 10.0), default=0.4,
                        help='amplitude A of each joint, rad or m, 0 .. 10 (default 0.4)')
    parser.add_argument('--laws', type=laws, default='all',
                        help='comma-separated subset of: pd, pd_ff, ct (default all)')
    parser.add_argument('--plot', default=os.path.join('out', 'closed_loop.png'),
                        help="PNG of |e| over time (default out/closed_loop.png; '' for none)")
    parser.add_argument('--json', type=path_text, default=None,
                        help='write the figures to this JSON file (only when every law ran '
                             'to its end)')
    parser.add_argument('--log-dir', type=path_text, default='out',
                        help="directory for the nodes' output (default out)")
    parser.add_argument('--plan', action='store_true',
                        help='send the node whole plans (desired_trajectory), replaced at half '
                             'time, instead of relaying a desired state per step')
    parser.add_argument('--timeout', type=in_range(float, 0.0, 86400.0, True), default=120.0,
                        help='wall-clock seconds allowed per law before giving up, above 0 '
                             '(default 120)')
    cpus = os.cpu_count() or 1
    parser.add_argument('--busy', type=in_range(int, 0, 4 * cpus), default=0,
                        help=f'busy loops beside the run, one process each, 0 .. {4 * cpus} '
                             '(the load of a busy machine; default 0)')
    parser.add_argument('--priority', type=in_range(int, 0, 99), default=0,
                        help="the node's thread_priority (SCHED_FIFO of its answering thread), "
                             '0 .. 99 (default 0: normal scheduling)')
    args = parser.parse_args(argv)
    # what a --plot is (a folder, a pipe) before its suffix: '. is not a format' said nothing
    error = outputs_error([('--plot', args.plot)]) or (
        plot_path_error(args.plot, args.json) if args.plot else None)
    if error:
        parser.error(error)
    # their folders are created before the run: one a file cannot be created in is refused;
    # no output may be a log of the run (named after its laws) or a description it reads
    logs = [(f"--log-dir's log of {LAWS[k][0]}", os.path.join(args.log_dir, slug + end))
            for k in chosen_laws(args.laws) for slug in [law_slug(LAWS[k][1], args.plan)]
            for end in ('_sim.log', '_node.log')]
    error = outputs_error([('--plot', args.plot), ('--json', args.json)] + logs,
                          [('--log-dir', args.log_dir)],
                          [('--urdf', args.urdf), ('--robot-urdf', args.robot_urdf)])
    if error:
        parser.error(error)
    return args


class Trajectory:
    """``q_d(t) = q0 + A (1 - cos(w t))``: at rest at t = 0, smooth, periods 2..4 s."""

    def __init__(self, q0: np.ndarray, amplitude: float) -> None:
        n = len(q0)
        self.q0 = np.asarray(q0, dtype=float)
        self.A = amplitude * np.where(np.arange(n) % 2 == 0, 1.0, -1.0)
        self.w = 2.0 * np.pi / np.linspace(2.0, 4.0, n)

    def __call__(self, t: float):
        """``(q, q̇, q̈)`` at time ``t``."""
        c, s = np.cos(self.w * t), np.sin(self.w * t)
        return (self.q0 + self.A * (1.0 - c), self.A * self.w * s, self.A * self.w ** 2 * c)


def start_point(model) -> np.ndarray:
    """Middle of each joint's limits when it has finite ones, else 0; offset off singularities."""
    lo, hi = np.asarray(model.lower, dtype=float), np.asarray(model.upper, dtype=float)
    bounded = np.isfinite(lo) & np.isfinite(hi) & (hi > lo)
    q0 = np.where(bounded, 0.5 * (lo + hi), 0.0)
    return q0 + 0.3


def gains(model, q0: np.ndarray, law: str, frequency: float):
    """``(kp, kd)`` per joint for ``law`` (see the module docstring)."""
    w = 2.0 * math.pi * frequency
    if law == 'computed_torque':
        return np.full(model.nq, w * w), np.full(model.nq, 2.0 * w)
    m = 1.0 / np.diag(np.linalg.inv(sd.mass_matrix(model, q0)))
    return m * w * w, 2.0 * m * w


class Run:
    """One law: the error of every measured state, by simulated time."""

    def __init__(self, name: str, names: Sequence[str]) -> None:
        self.name = name
        self.names = list(names)
        self.t: List[float] = []
        self.e: List[np.ndarray] = []
        self.answers = 0        # answers of the node seen
        self.stale = 0          # of them computed from another step's desired state
        self.stale_older = 0    # of those, from one older than the step before (none may be)
        self.repeated = 0       # of them answering a state answered already (not forwarded)
        self.replaced_at: Optional[float] = None   # --plan: when the second plan took over
        self.end_from_start = float('nan')         # --plan: max |q - q0| at the end

    def summary(self) -> Dict[str, object]:
        e = np.abs(np.array(self.e)) if self.e else np.zeros((0, len(self.names)))
        return {'law': self.name, 'samples': len(self.t),
                'simulated_s': self.t[-1] if self.t else 0.0,
                'rms': float(np.sqrt(np.mean(e ** 2))) if e.size else float('nan'),
                'max': float(e.max()) if e.size else float('nan'),
                'answers': self.answers, 'stale_desired': self.stale,
                'stale_older_than_previous': self.stale_older,
                'repeated_answers': self.repeated, 'plan_replaced_at_s': self.replaced_at,
                'end_from_start': self.end_from_start,
                'rms_per_joint': dict(zip(self.names, np.sqrt(np.mean(e ** 2, axis=0)).tolist()
                                          if e.size else [float('nan')] * len(self.names)))}


class Lockstep:
    """Feed a controller in lockstep with a simulator: the desired state of every step in time.

    The simulator (``command_topic: sim_effort_commands``) publishes the state of step k and
    waits for a command; the controller answers each measured state with the desired state it
    holds. This relay sits between them: for the answer to the state of step k (on
    ``feedforward_efforts``, stamped with that state's time, with the q_d it used) it first
    publishes the desired state of step k + 1, then forwards the torque to the simulator. The
    desired state is on its way before the simulator can even step, so the controller holds
    it when the state of step k + 1 arrives, however slowly this process runs (publishing it
    when the state of step k arrives races the controller's answer: under load, hundreds of
    answers per 1000 steps used an older setpoint), and waits :data:`DELIVERY` for it to
    arrive. DDS does not order messages of two topics,
    so on a loaded machine an answer may still come from the setpoint before (three busy
    loops: 0-2 in 3000; 9-49 in 3000 with builds sharing the cores; a wait for the node's
    reader to acknowledge the desired state cannot replace the pause: a best-effort reader
    acknowledges nothing, and a reliable one only at the writer's heartbeat, every few
    seconds): :attr:`stale` counts them from the q_d the node echoes, :attr:`stale_older` those
    of them whose q_d is not the step before's (none may be: the node answers with the
    desired state it holds, and it held the step before's). Where none may
    come from another step, send the trajectory as a plan (``--plan``).
    An answer to a state answered already (the simulator republishes the state it waits on)
    is not forwarded; :attr:`repeated` counts those to a stamped state (step 0 is stamped 0,
    which the node, as any ROS node, reads as unstamped and answers each time).
    ``desired(t)`` returns ``(q, q̇, q̈)``; :meth:`kick` sends the first desired state.
    """

    def __init__(self, node, names: Sequence[str], desired, timestep: float,
                 prefix: str = '', watched=None, depth: int = 1000) -> None:
        """Create the endpoints on ``node``, topics under ``prefix`` (or its namespace).

        ``watched``: the subscription of this process to the measured states, if any;
        :meth:`kick` waits until it is matched too. ``depth``: the answers' queue.
        """
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from sensor_msgs.msg import JointState
        from std_msgs.msg import Float64MultiArray
        reliable = QoSProfile(depth=depth, reliability=ReliabilityPolicy.RELIABLE)
        self.node, self.desired, self.timestep = node, desired, timestep
        self.watched = watched
        self.steps = 0                  # torques forwarded: the simulator is at step `steps`
        self.answers = 0                # answers seen
        self.stale = 0                  # of them computed from another step's desired state
        self.stale_older = 0            # of those, from one older than the step before
        self.repeated = 0               # of them answering a state answered already
        self.sent = {}                  # step -> desired q published for it
        self.msg = JointState(name=list(names))
        self.command = Float64MultiArray()
        self.desired_pub = node.create_publisher(JointState, prefix + 'desired_joint_states',
                                                 reliable)
        self.relay = node.create_publisher(Float64MultiArray, prefix + SIM_COMMANDS, reliable)
        self.answered = node.create_subscription(JointState, prefix + 'feedforward_efforts',
                                                 self._on_answer, reliable)

    def publish_desired(self, t: float) -> None:
        """Publish the desired state at time ``t`` (stamped ``t``)."""
        q, qd, qdd = self.desired(t)
        msg = self.msg
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(int(round(t * 1e9)), 10 ** 9)
        msg.position, msg.velocity, msg.effort = list(map(float, q)), list(map(float, qd)), \
            list(map(float, qdd))
        self.sent[round(t / self.timestep)] = list(msg.position)
        self.desired_pub.publish(msg)

    def kick(self) -> None:
        """Before the first answer: send the desired state of step 0, once all are matched.

        Matched: the node's desired input, the simulator's command input, the node's answers
        and the watched states (on a busy machine discovery can take seconds; a state
        published before the watcher matched is never seen).
        """
        if (self.steps == 0 and self.desired_pub.get_subscription_count() > 0
                and self.relay.get_subscription_count() > 0
                and self.answered.get_publisher_count() > 0
                and (self.watched is None or self.watched.get_publisher_count() > 0)):
            self.publish_desired(0.0)

    def _on_answer(self, msg) -> None:
        step = round((msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9) / self.timestep)
        self.answers += 1
        if step != self.steps:
            # the state of step 0 is stamped 0, which ROS reads as unstamped: the node answers
            # every unstamped state (it cannot tell a republished one), so on a busy machine
            # the simulator's republication of it may be answered again; any other is stamped
            # and a second answer to it would be the node's fault
            self.repeated += step != 0
            return
        if list(msg.position) != self.sent.get(step):
            self.stale += 1
            # the one a late delivery explains: the setpoint of the step before, held by the
            # node while this step's was on its way; anything else would be the node's fault
            self.stale_older += list(msg.position) != self.sent.get(step - 1)
        self.steps += 1
        self.publish_desired(self.steps * self.timestep)
        time.sleep(DELIVERY)
        self.command.data = msg.effort
        self.relay.publish(self.command)

    def close(self) -> None:
        """Destroy the endpoints."""
        self.node.destroy_subscription(self.answered)
        self.node.destroy_publisher(self.relay)
        self.node.destroy_publisher(self.desired_pub)


PLAN_STEP = 0.05      # s between the points of a plan sent with --plan
BACK_IN = 1.0         # s: the replacing plan reaches the start in this time, then holds it
RESEND_S = 5.0        # s without an answer or a stepped state before the first plan is resent


def plan_message(names: Sequence[str], points, start: float):
    """Return a ``JointTrajectory`` of ``points`` ``[(t, q, q̇, q̈)]`` from ``start`` (s)."""
    from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
    msg = JointTrajectory(joint_names=list(names))
    msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(int(round(start * 1e9)), 10 ** 9)
    for t, q, qd, qdd in points:
        point = JointTrajectoryPoint(positions=list(map(float, q)),
                                     velocities=list(map(float, qd)),
                                     accelerations=list(map(float, qdd)))
        point.time_from_start.sec, point.time_from_start.nanosec = divmod(
            int(round(t * 1e9)), 10 ** 9)
        msg.points.append(point)
    return msg


class Plans:
    """``--plan``: the whole trajectory once, replaced at half time; errors from the echoes.

    The node answers each measured state with the plan sampled at its stamp and echoes the
    ``q_d`` it used on ``feedforward_efforts``; the error of a step is that ``q_d`` minus the
    measured ``q`` of the same stamp.
    """

    def __init__(self, node, names: Sequence[str], trajectory, seconds: float, run: Run,
                 watched, depth: int = 1000) -> None:
        """Create the endpoints on ``node``; ``watched``: the measured states' subscription.

        ``depth``: the answers' queue (the run's steps: none is dropped while this process
        waits for the CPU).
        """
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from sensor_msgs.msg import JointState
        from trajectory_msgs.msg import JointTrajectory
        reliable = QoSProfile(depth=depth, reliability=ReliabilityPolicy.RELIABLE)
        self.node, self.names, self.run, self.watched = node, list(names), run, watched
        self.q0 = trajectory(0.0)[0]
        times = np.arange(0.0, seconds + PLAN_STEP, PLAN_STEP)
        # stamped 0: starts on receipt, at the node's latest measured stamp (sim time 0)
        self.first = plan_message(names, [(t, *trajectory(t)) for t in times], 0.0)
        self.switch_at = 0.5 * seconds
        self.replaced = None       # the sim time from which the second plan runs
        self.measured: Dict[int, np.ndarray] = {}
        self.desired: Dict[int, np.ndarray] = {}
        self.pub = node.create_publisher(JointTrajectory, 'desired_trajectory', reliable)
        self.sub = node.create_subscription(JointState, 'feedforward_efforts', self._on_answer,
                                            reliable)
        self.last_sent = -float('inf')
        self.stepped = False       # a state past the first seen: the simulator steps
        self.last_q: Optional[np.ndarray] = None
        self.seen: set = set()     # stamps of the measured states seen

    def kick(self) -> None:
        """Until the node follows: send the first plan, once every endpoint is matched.

        The node's plan input, its answers and the watched states: the simulator steps as
        soon as the node answers, so a state published before this process's subscription
        matched (discovery can take seconds on a busy machine) is never seen; a CI run saw
        629 of 3001. Sent again only after :data:`RESEND_S` without an answer or a stepped
        state: a copy is stamped 0 ("now"), so one that reaches a node already following
        restarts the plan from that step (a busy CI run: a copy sent 0.2 s after the first
        arrived at step 3, the plan restarted 3 ms late, PD + feed-forward's error 3e-3 rad
        where it is 1.1e-3); on matched reliable endpoints the first copy is not lost, only
        late while the node starts.
        """
        now = time.monotonic()
        if (self.run.answers == 0 and not self.stepped and self.pub.get_subscription_count() > 0
                and self.sub.get_publisher_count() > 0
                and self.watched.get_publisher_count() > 0
                and now - self.last_sent > RESEND_S):
            self.pub.publish(self.first)
            self.last_sent = now

    def on_state(self, t: float, q: np.ndarray) -> None:
        """Take a measured state: pair it with its echo."""
        key = round(t * 1e9)
        self.stepped = self.stepped or key > 0     # the node answered: it has the plan
        if key in self.seen:     # the simulator republishes the state it waits on
            return
        self.seen.add(key)
        self.measured[key] = q
        self.last_q = q
        self._pair(key)

    def _on_answer(self, msg) -> None:
        """Take an answer (reliable: every one arrives); at the first, schedule the replacement.

        The replacement is sent once the first plan is followed, stamped to start just after
        half time on the measured clock: the node keeps the first plan until then (JTC's
        rule), so the switch is at that step whatever this process's lag. Sent when an
        answer past half time was read, it started wherever the run was by then: on a busy
        machine, tens of steps late and with a jump in q_d.
        """
        self.run.answers += 1
        key = msg.header.stamp.sec * 10 ** 9 + msg.header.stamp.nanosec
        self.desired[key] = np.array(msg.position)
        self._pair(key)
        if self.replaced is None:
            self.replaced = self.switch_at + 0.01
            hold = np.zeros(len(self.names))
            self.pub.publish(plan_message(self.names, [(BACK_IN, self.q0, hold, hold)],
                                          self.replaced))

    def _pair(self, key: int) -> None:
        if key in self.measured and key in self.desired:
            self.run.t.append(key * 1e-9)
            self.run.e.append(self.desired.pop(key) - self.measured.pop(key))

    def sort(self) -> None:
        """Order the errors by time (an echo may come after the next state)."""
        order = np.argsort(self.run.t, kind='stable')
        self.run.t = [self.run.t[i] for i in order]
        self.run.e = [self.run.e[i] for i in order]

    def close(self) -> None:
        """Destroy the endpoints."""
        self.node.destroy_subscription(self.sub)
        self.node.destroy_publisher(self.pub)


def run_law(name: str, settings: Dict[str, str], urdf: str, model, args, rclpy_mods,
            show, interrupt: Optional[Interrupt] = None) -> Run:
    """Start the sim and the node for one law, drive the trajectory, return the errors.

    Raises KeyboardInterrupt once ``interrupt`` caught a signal, RuntimeError when the
    simulator or the node exits by itself or the run does not finish in time; both stop them.
    """
    q0 = start_point(model)
    trajectory = Trajectory(q0, args.amplitude)
    kp, kd = gains(model, q0, settings['control_mode'], args.frequency)
    namespace = '/' + law_slug(settings, args.plan)
    os.makedirs(args.log_dir, exist_ok=True)
    slug = namespace.strip('/')
    # every process and node made from here on is stopped on the way out, whatever stops the
    # run (a node that cannot start, an interrupt while the driver is made, a timeout)
    with contextlib.ExitStack() as made:
        return _drive(name, settings, urdf, model, args, rclpy_mods, show, interrupt,
                      namespace, slug, q0, trajectory, kp, kd, made)


def _drive(name, settings, urdf, model, args, rclpy_mods, show, interrupt, namespace, slug,
           q0, trajectory, kp, kd, made: contextlib.ExitStack) -> Run:
    """Run the body of :func:`run_law`; what it starts is stopped by ``made`` when it closes."""
    rclpy, JointState = rclpy_mods
    names = model.joint_names
    fmt = '[' + ','.join(repr(float(x)) for x in q0) + ']'
    logs = args.log_dir
    sim = start(node_command('sim', 'spatial_dynamics.sim'), namespace, {
        'robot_description_file': os.path.abspath(args.robot_urdf or urdf),
        'mode': 'lockstep', 'timestep': str(TIMESTEP),
        'initial_positions': fmt,
        'command_topic': 'effort_commands' if args.plan else SIM_COMMANDS},
        os.path.join(logs, f'{slug}_sim.log'))
    made.callback(stop, sim)
    node = start(node_command('inverse_dynamics', 'spatial_dynamics.ros.node'), namespace, {
        'robot_description_file': urdf, 'control_mode': settings['control_mode'],
        'output': settings['output'],
        'kp': '[' + ','.join(repr(float(x)) for x in kp) + ']',
        'kd': '[' + ','.join(repr(float(x)) for x in kd) + ']',
        'thread_priority': str(args.priority)},
        os.path.join(logs, f'{slug}_node.log'))
    made.callback(stop, node)      # stopped first (callbacks run last in, first out)
    run = Run(name, names)
    progress = [-math.inf, None]        # the latest simulated time seen, and when
    driver = rclpy.create_node('closed_loop_driver', namespace=namespace)
    made.callback(driver.destroy_node)
    index = None

    def on_state(state) -> None:
        nonlocal index
        if index is None:
            index = [list(state.name).index(j) for j in names]
        t = state.header.stamp.sec + state.header.stamp.nanosec * 1e-9
        if t > progress[0]:         # the simulator stepped
            progress[:] = [t, time.monotonic()]
        q = np.array(state.position)[index]
        if plans is not None:
            plans.on_state(t, q)
        elif not run.t or t > run.t[-1]:
            run.t.append(t)
            run.e.append(trajectory(t)[0] - q)

    # queues as long as the run: a busy machine may keep this process off the CPU for a while
    depth = int(args.seconds / TIMESTEP) + 100
    states = driver.create_subscription(JointState, 'joint_states', on_state, depth)
    plans = (Plans(driver, names, trajectory, args.seconds, run, states, depth) if args.plan
             else None)
    lockstep = None if args.plan else Lockstep(driver, names, trajectory, TIMESTEP,
                                               watched=states, depth=depth)
    wall0 = time.monotonic()
    next_show = wall0
    sim_log = os.path.join(logs, f'{slug}_sim.log')
    try:
        while not run.t or run.t[-1] < args.seconds:
            if interrupt is not None and interrupt.signal is not None:
                raise KeyboardInterrupt     # swallowed where it was raised: stop here
            if sim.poll() is not None or node.poll() is not None:
                raise RuntimeError(f'{name}: the {"sim" if sim.poll() is not None else "node"} '
                                   f'exited (see {logs}/)')
            if progress[1] is not None and time.monotonic() - progress[1] > STALL_S:
                # a command the simulator refused (a diverged loop: beyond 1e6) is not sent
                # again for the same state (one answer per measurement): lockstep waits
                why = last_error(sim_log, 'refused') or last_error(sim_log)
                raise RuntimeError(f'{name}: no step for {STALL_S:g} s at {progress[0]:.3f} s '
                                   f'simulated: the simulator waits for a command it takes'
                                   + (f' (its log: {why})' if why else ''))
            if time.monotonic() - wall0 > args.timeout:
                raise RuntimeError(f'{name}: {args.timeout:g} s without finishing '
                                   f'({run.t[-1] if run.t else 0:.3f} s simulated)')
            (plans or lockstep).kick()
            rclpy.spin_once(driver, timeout_sec=0.05)
            if time.monotonic() >= next_show:
                show(run)
                next_show += 0.25
    finally:
        if lockstep is not None:
            run.answers, run.stale, run.stale_older, run.repeated = (
                lockstep.answers, lockstep.stale, lockstep.stale_older, lockstep.repeated)
        else:
            run.replaced_at = plans.replaced
            if plans.last_q is not None:
                run.end_from_start = float(np.abs(plans.last_q - plans.q0).max())
            plans.sort()
            plans.close()
    show(run)
    return run


def table(runs: List[Run], names: Sequence[str]) -> List[str]:
    """Rows: each law, its simulated time and the latest |e| per joint (rad or m)."""
    head = f'{"law":<20}{"t [s]":>7}' + ''.join(f'{n[:11]:>12}' for n in names) + f'{"rms":>11}'
    lines = [head]
    for run in runs:
        if not run.e:
            lines.append(f'{run.name:<20}{"-":>7}')
            continue
        recent = np.abs(np.array(run.e[-200:]))
        lines.append(f'{run.name:<20}{run.t[-1]:7.2f}'
                     + ''.join(f'{x:12.2e}' for x in recent[-1])
                     + f'{np.sqrt(np.mean(np.array(run.e) ** 2)):11.2e}')
    return lines


def plot(runs: List[Run], path: str, robot: str, frequency: float) -> str:
    """Write |e| per joint over time (log scale), one panel per joint; returns a note."""
    plt = pyplot()
    if plt is None:
        return 'matplotlib is not installed: plot skipped (pip install matplotlib)'
    names = runs[0].names
    cols = 2 if len(names) > 3 else 1
    rows = math.ceil(len(names) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(11, 2.2 * rows + 0.8), dpi=100,
                             sharex=True, squeeze=False)
    for j, name in enumerate(names):
        ax = axes[j // cols][j % cols]
        for run in runs:
            e = np.abs(np.array(run.e)[:, j])
            ax.semilogy(run.t, np.maximum(e, 1e-12), label=run.name, linewidth=1.0)
        ax.set_title(name, fontsize='small')
        ax.grid(True, which='both', alpha=0.3)
        ax.set_ylabel('|q_d - q|')
    for j in range(len(names), rows * cols):
        axes[j // cols][j % cols].axis('off')
    for ax in axes[-1]:
        ax.set_xlabel('simulated time [s]')
    axes[0][0].legend(fontsize='small', loc='lower right')
    fig.suptitle(f'tracking error, {robot}, MuJoCo lockstep 1 ms, feedback {frequency:g} Hz')
    save_figure(plt, fig, path)
    return f'plot written to {files.output_path(path)}'


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the laws one after the other; 0 when every run finished."""
    args = parse_args(argv)
    interrupt = Interrupt().install()   # from here on: also while loading
    try:
        import rclpy
        from rclpy.signals import SignalHandlerOptions
        from sensor_msgs.msg import JointState
        option = '--urdf'
        urdf, model = robot_model(args.urdf)
        if args.robot_urdf:     # the simulator's: refused here, not as 'the sim exited'
            option = '--robot-urdf'
            simulated = robot_model(args.robot_urdf)[1]
            if sorted(simulated.joint_names) != sorted(model.joint_names):
                raise ValueError(f'its joints {sorted(simulated.joint_names)} are not those '
                                 f'of --urdf {sorted(model.joint_names)}: the simulator '
                                 'takes the node\'s command for every joint of --urdf')
    except KeyboardInterrupt:
        print(f'closed loop: interrupted ({interrupt.name}) while loading', file=sys.stderr)
        return interrupt.status
    except ValueError as err:
        print(f'closed loop: {option} {getattr(args, option[2:].replace("-", "_"))!r}: {err}',
              file=sys.stderr)
        return 1
    picks = chosen_laws(args.laws)
    error = laws_error(model, picks, args.frequency)
    if error:
        print(f'closed loop: {error}', file=sys.stderr)
        return 1
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    live = sys.stdout.isatty()
    runs: List[Run] = []
    shown = 0

    def show(current: Run) -> None:
        nonlocal shown
        if live:
            shown = redraw(table(runs + [current], model.joint_names), shown)

    print(f'closed loop on {urdf}'
          + (f' (the simulated robot: {args.robot_urdf})' if args.robot_urdf else '')
          + f': {args.seconds:g} s per law, feedback {args.frequency:g} Hz\n'
          f'simulator: {" ".join(node_command("sim", "spatial_dynamics.sim"))}\n'
          f'controller: {" ".join(node_command("inverse_dynamics", "spatial_dynamics.ros.node"))}'
          f'\n(their output in {args.log_dir}/)', flush=True)
    status = 0
    loops: List[subprocess.Popen] = []
    try:
        for _ in range(args.busy):   # each recorded before a signal may interrupt
            with interrupt.held():
                loops.append(busy_loop())
        if args.busy or args.priority:
            print(f'{args.busy} busy loops beside the run; node thread_priority '
                  f'{args.priority}; load {os.getloadavg()[0]:.2f}', flush=True)
        for k in picks:
            name, settings = LAWS[k]
            runs.append(run_law(name, settings, urdf, model, args, (rclpy, JointState), show,
                                interrupt))
            if not live:      # a log: the header with the first row, then each row
                lines = table(runs, model.joint_names)
                print('\n'.join(lines if len(runs) == 1 else lines[-1:]), flush=True)
    except (KeyboardInterrupt, RuntimeError) as err:
        if interrupt.signal is None and isinstance(err, RuntimeError):
            print(f'closed loop: {err}', file=sys.stderr)
            status = 1
        else:   # the children got the signal too: their exit is no failure
            name = signal.Signals(interrupt.signal or signal.SIGINT).name
            print(f'closed loop: interrupted ({name}); the simulator and the node stopped',
                  file=sys.stderr)
            status = interrupt.status
    finally:
        try:
            with interrupt.held(), contextlib.ExitStack() as ending:   # each, whatever one raised
                for loop in loops:
                    ending.callback(end_loop, loop)
                ending.callback(rclpy.try_shutdown)
        except KeyboardInterrupt:   # a second signal while they were ended: its status
            status = interrupt.status
    summaries = [run.summary() for run in runs]
    for s in summaries:
        print(f'{s["law"]:<20} rms {s["rms"]:.3e}  max {s["max"]:.3e}  '
              f'({s["samples"]} states, {s["simulated_s"]:.2f} s; {s["answers"]} answers, '
              f'{s["stale_desired"]} from another step\'s desired state '
              f'({s["stale_older_than_previous"]} older than the step before), '
              f'{s["repeated_answers"]} to a state answered already)')
    if args.json and (status or len(runs) < len(picks)):
        # figures of some of the laws are no run's figures: an earlier file is kept
        print(f'closed loop: --json {args.json!r} not written (not every law ran to its end)',
              file=sys.stderr)
    elif args.json:     # whole or not at all: a reader never sees half of it
        try:
            write_json(args.json, {
                'robot': model.name, 'urdf': urdf, 'robot_urdf': args.robot_urdf or urdf,
                'frequency_hz': args.frequency, 'busy': args.busy,
                'thread_priority': args.priority, 'timestep_s': TIMESTEP, 'laws': summaries})
        except (OSError, ValueError) as err:
            print(f'closed loop: {err}', file=sys.stderr)
            status = status or 1
    if args.plot and runs:
        print(plot(runs, args.plot, model.name, args.frequency))
    return status


if __name__ == '__main__':
    sys.exit(main())
