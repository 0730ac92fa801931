# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The latency benchmark's inputs: the process that publishes them, and pacing on a grid.

:class:`Pacer` runs :func:`pace_inputs` in a process of its own that does nothing else: it
publishes each block of inputs on a fixed grid (:func:`send_block`: it sleeps to each tick,
and a block it cannot send at the rate asked ends :data:`LATE_LIMIT_S` after its due time)
and replies with what it sent (:class:`Sent`: the stamps, how late it woke). Pacing in one
process, which the soak and the node tests use too: :func:`pace`, :func:`prime`,
:func:`spin_until`, and the inputs themselves (:func:`joint_state_for`, :func:`fill`).
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from typing import Callable, List, NamedTuple, Sequence

from .driving import die_with_parent_ignoring_ctrl_c, Sinusoids
from .latency_targets import prioritize, Target

# rclpy and the ROS messages are imported inside the functions that use them: the benchmark's
# options are parsed (and --help printed) without ROS, and rclpy alone takes some 0.1 s to import.

#: A block the publisher could not send at the rate asked ends this long after its due time,
#: s: the run takes about the time asked, however far the publisher falls behind.
LATE_LIMIT_S = 1.0


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
            [sys.executable, '-c', 'from spatial_dynamics.tools.latency_pacer import pace_inputs; '
             'pace_inputs()'], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
            preexec_fn=die_with_parent_ignoring_ctrl_c)
        self._send(setup)
        self.scheduling = ''   # what it runs under: :meth:`wait_ready` reads it

    def wait_ready(self, timeout: float = 60.0) -> None:
        """Wait until the process has started its node, and read what it runs under.

        Apart from starting it: a caller records the process first, so a signal while it
        starts (a second or so of imports) leaves nothing unstopped.
        """
        self.scheduling = self._reply(None, timeout)

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
