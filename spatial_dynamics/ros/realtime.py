# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The answering thread and its real-time knobs, named as ros2_control's controller_manager.

The node's inputs are answered in a thread of their own, by a loop that waits on the inputs'
callback group only (:class:`AnsweringLoop`); parameters, descriptions, plans and
diagnostics run in the other executor (:class:`OthersExecutor`), which never waits on the
inputs; :func:`~spatial_dynamics.ros.common.spin` runs the two. Measured on a 2-core machine
at 1 kHz (the demo arm, ``python -m spatial_dynamics.tools.latency``, load 2-8): one
executor for everything took 370-680 µs from a sample's arrival in the middleware to its
callback (p50), the answering thread 180-240 µs; rclpy's events executor cannot hold the
node (it refuses guard conditions, and alone it would run a parameter change's parse where
the answers wait).

The knobs (the node's parameters ``thread_priority``, ``cpu_affinity``, ``lock_memory``) are
applied by :func:`apply` from the answering thread: SCHED_FIFO for it and for the
middleware's receive threads (:data:`RECEIVE_THREADS`), its CPU cores, ``mlockall``. What the
system does not permit is refused with the reason (:class:`InEffect`), never fatal: the node
answers under normal scheduling and says how to grant it (:data:`HOW_TO_GRANT`).

Python's garbage collector: :func:`keep_collector_off_answers` freezes what configuration
allocated (``gc.freeze``) and turns the automatic collections off; :func:`collect` runs the
young generations from the diagnostics timer, once a second, where a pause is one known
stall instead of a generation-1 collection (1-10 ms measured under load) landing on any
answer.
"""

from __future__ import annotations

import ctypes
import errno
import gc
import os
import time
from contextlib import ExitStack
from typing import List, NamedTuple, Optional, Sequence, Tuple

from rclpy.executors import MultiThreadedExecutor
from rclpy.guard_condition import GuardCondition
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.subscription import Subscription

MCL_CURRENT = 1
MCL_FUTURE = 2
#: Name prefixes of the middleware threads that receive samples: Fast DDS (``dds.shm.7411``,
#: ``dds.udp.7411``; its shared-memory watchdog excepted) and Cyclone DDS (``recvUC``...).
RECEIVE_THREADS = ('dds.shm.', 'dds.udp.', 'dds.tcp.', 'recv')
_NOT_RECEIVING = ('dds.shm.wdog',)
HOW_TO_GRANT = (
    'grant it with a realtime group in /etc/security/limits.conf (@realtime - rtprio 99, '
    '@realtime - memlock unlimited), `ulimit -r 99 -l unlimited` in the shell that starts '
    'the node, or `docker run --cap-add=sys_nice --ulimit rtprio=99 --ulimit memlock=-1`')
#: The OS name of the answering thread (``ps -L -p <pid>``).
ANSWERING_THREAD = 'answering'
#: Full collections from the diagnostics timer: one in this many calls of :func:`collect`.
FULL_COLLECTION_EVERY = 60


class InEffect(NamedTuple):
    """What :func:`apply` achieved: each knob in words, and what was refused (with why).

    ``refused``: what the system did not permit (a privilege :data:`HOW_TO_GRANT` grants);
    ``invalid``: what no privilege makes possible (a core not among the allowed ones).
    """

    priority: str
    affinity: str
    memory: str
    refused: Tuple[str, ...] = ()
    invalid: Tuple[str, ...] = ()

    def values(self) -> List[Tuple[str, str]]:
        """Return the key-values of the ``real-time`` diagnostics status."""
        return [('scheduling', self.priority), ('cpu affinity', self.affinity),
                ('memory', self.memory)]


def _reason(err: OSError) -> str:
    return f'{errno.errorcode.get(err.errno, err.errno)}: {os.strerror(err.errno)}'


def set_priority(tid: int, priority: int) -> None:
    """SCHED_FIFO at ``priority`` for thread ``tid`` (0 = this one); 0: normal scheduling."""
    if priority > 0:
        os.sched_setscheduler(tid, os.SCHED_FIFO, os.sched_param(priority))
    else:
        os.sched_setscheduler(tid, os.SCHED_OTHER, os.sched_param(0))


def lock_memory() -> None:
    """Lock the process's current and future pages in RAM (``mlockall``); OSError if not."""
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.mlockall(MCL_CURRENT | MCL_FUTURE) != 0:
        code = ctypes.get_errno()
        raise OSError(code, os.strerror(code))


def name_thread(name: str) -> None:
    """Give the calling thread its name in the OS (``ps -L``, ``chrt -p``, ``top -H``)."""
    PR_SET_NAME = 15
    ctypes.CDLL(None, use_errno=True).prctl(PR_SET_NAME, name.encode()[:15])


def receiving(name: str) -> bool:
    """Tell whether a thread named ``name`` is a middleware receive thread (see above)."""
    return name.startswith(RECEIVE_THREADS) and name not in _NOT_RECEIVING


def receive_threads() -> List[int]:
    """Thread ids of this process's middleware receive threads (by name, see above)."""
    tids = []
    for tid in os.listdir('/proc/self/task'):
        try:
            with open(f'/proc/self/task/{tid}/comm') as f:
                name = f.read().strip()
        except OSError:   # the thread ended meanwhile
            continue
        if receiving(name):
            tids.append(int(tid))
    return tids


def apply(priority: int, cores: Optional[Sequence[int]], memory: bool) -> InEffect:
    """Apply the knobs to the calling thread (the answering one) and the receive threads.

    Never raises for what the system refuses: each refusal is in ``refused``, the thread goes
    on under what it had.
    """
    name_thread(ANSWERING_THREAD)
    refused = []
    invalid = []
    in_effect = inherited_scheduling()
    if priority > 0:
        done = []
        try:
            for tid in [0] + receive_threads():
                try:
                    set_priority(tid, priority)
                except ProcessLookupError:   # the thread ended meanwhile
                    continue
                done.append(tid)
            in_effect = (f'SCHED_FIFO {priority}: the answering thread and '
                         f'{len(done) - 1} middleware receive threads')
        except OSError as err:
            for tid in done:   # none of them, rather than some
                set_priority(tid, 0)
            refused.append(f'thread_priority {priority} (SCHED_FIFO): {_reason(err)}')
    affinity = 'all cores'
    allowed = sorted(os.sched_getaffinity(0))
    outside = sorted(set(cores or ()) - set(allowed))
    if outside:   # the kernel would take the others alone, or widen a taskset's mask
        invalid.append(f'cpu_affinity {list(cores)}: {outside} not among the cores this '
                       f'process may use, {allowed}')
    elif cores:
        try:
            os.sched_setaffinity(0, cores)
            affinity = 'cores ' + ', '.join(map(str, sorted(os.sched_getaffinity(0))))
        except OSError as err:
            if err.errno == errno.EINVAL:   # no core of the list is one this process may use
                invalid.append(f'cpu_affinity {list(cores)}: none of these cores is among the '
                               f'cores this process may use, {allowed} ({_reason(err)})')
            else:
                refused.append(f'cpu_affinity {list(cores)}: {_reason(err)} (allowed: '
                               f'{allowed})')
    locked = 'not locked'
    if memory:
        try:
            lock_memory()
            locked = 'locked (mlockall)'
        except OSError as err:
            refused.append(f'lock_memory: {_reason(err)}')
    return InEffect(in_effect, affinity, locked, tuple(refused), tuple(invalid))


def inherited_scheduling() -> str:
    """Return the calling thread's scheduling as it is: normal, or an inherited real-time one.

    ``thread_priority`` 0 leaves the thread as the process was started (``chrt -f 50 ...``
    makes every thread SCHED_FIFO 50): said as it is, never as normal scheduling.
    """
    policy = os.sched_getscheduler(0)
    if policy in (os.SCHED_FIFO, os.SCHED_RR):
        name = 'SCHED_FIFO' if policy == os.SCHED_FIFO else 'SCHED_RR'
        return (f'{name} {os.sched_getparam(0).sched_priority}: inherited from the process '
                '(thread_priority 0 leaves it)')
    return 'normal (SCHED_OTHER)'


def warning(in_effect: InEffect) -> Optional[str]:
    """Return the one WARN: what was refused, how to grant it (None: all applied).

    The advice on privileges only for what a privilege would grant.
    """
    parts = []
    if in_effect.invalid:
        parts.append('real-time settings impossible here, answering without them: '
                     + '; '.join(in_effect.invalid) + '.')
    if in_effect.refused:
        parts.append('real-time settings not permitted, answering without them: '
                     + '; '.join(in_effect.refused) + '. To use them, ' + HOW_TO_GRANT)
    return ' '.join(parts) or None


def status(in_effect: Optional[InEffect]) -> Tuple[str, str, list]:
    """Return the ``real-time`` diagnostics status: OK, or WARN when a knob was refused."""
    if in_effect is None:
        return 'OK', 'answering thread not started yet', []
    message = in_effect.priority
    values = in_effect.values()
    if in_effect.invalid:
        message += ' (impossible: ' + '; '.join(in_effect.invalid) + ')'
        values.append(('impossible', '; '.join(in_effect.invalid)))
    if in_effect.refused:
        message += ' (not permitted: ' + '; '.join(in_effect.refused) + ')'
        values.append(('refused', '; '.join(in_effect.refused)))
    return ('WARN' if in_effect.refused or in_effect.invalid else 'OK'), message, values


# -- garbage collection ------------------------------------------------------------------------

def keep_collector_off_answers() -> None:
    """Freeze what configuration allocated and turn the automatic collections off."""
    gc.freeze()
    gc.disable()


def collect(calls: int) -> int:
    """Collect the young generations (every call) or all (every ``FULL_COLLECTION_EVERY``).

    Returns the pause in ns. Run where a pause stalls no answer for long: the diagnostics
    timer, once a second.
    """
    t0 = time.perf_counter_ns()
    gc.collect(2 if calls % FULL_COLLECTION_EVERY == 0 else 1)
    return time.perf_counter_ns() - t0


# -- executors ---------------------------------------------------------------------------------

class _Part:
    """The entities of a node that one executor serves: those ``keep`` accepts.

    rclpy's executors gather their wait set through ``can_execute`` but then go over all of a
    node's entities to run what is ready, asking only the entity's callback group; a guard
    condition's "triggered" mark is on the entity itself, set by whichever executor waited on
    it. Two executors on one node therefore ran each other's guard conditions (the parsed
    description's in the answering thread, a plan's outside it), and the executor whose entity
    ran elsewhere was never woken when it ended: its timer left out of its wait set while the
    group was busy, the diagnostics stopped. An executor sees this view of the node instead:
    the same node, with its entity lists cut to the part the executor serves.
    """

    def __init__(self, node, keep) -> None:
        self._node = node
        self._keep = keep

    def __getattr__(self, name: str):
        return getattr(self._node, name)

    def _cut(self, entities) -> list:
        return [entity for entity in entities if self._keep(entity)]

    @property
    def subscriptions(self) -> list:
        return self._cut(self._node.subscriptions)

    @property
    def timers(self) -> list:
        return self._cut(self._node.timers)

    @property
    def clients(self) -> list:
        return self._cut(self._node.clients)

    @property
    def services(self) -> list:
        return self._cut(self._node.services)

    @property
    def guards(self) -> list:
        return self._cut(self._node.guards)

    @property
    def waitables(self) -> list:
        return self._cut(self._node.waitables)


class AnsweringLoop:
    """Wait on the subscriptions and guard conditions of ``group`` and run their callbacks.

    What rclpy's SingleThreadedExecutor does for the group, without what the group does not
    need: the executor rebuilds its wait set, a generator, a Task and a coroutine per message
    (about 300 µs of Python per sample on this 2-core machine under load); this loop keeps one
    wait set (rebuilt only when the group's entities change), takes every sample a ready
    subscription holds, and calls the callback directly. It runs in the thread that calls
    :meth:`spin`, alone: nothing else runs the group (:class:`OthersExecutor` leaves it out),
    so the group's own bookkeeping of who runs it is not needed. Subscriptions and guard
    conditions only: the node puts nothing else in the group.
    """

    def __init__(self, node, group) -> None:
        self._node = node
        self._group = group
        self._context = node.context
        self._wake = GuardCondition(None, None, self._context)
        self._context.on_shutdown(self._wake.trigger)
        self._entities: tuple = ()
        self._handles = ExitStack()
        self._wait_set = None

    def _rebuild(self, subscriptions: tuple, guards: tuple) -> None:
        self._handles.close()
        self._handles = ExitStack()
        for entity in subscriptions + guards + (self._wake, self._context):
            self._handles.enter_context(entity.handle)
        self._entities = (subscriptions, guards)
        self._wait_set = _rclpy.WaitSet(len(subscriptions), len(guards) + 1, 0, 0, 0, 0,
                                        self._context.handle)

    def spin_once(self, timeout_sec: float = 1.0) -> None:
        """Wait up to ``timeout_sec`` and run what became ready."""
        group = self._group
        node = self._node
        subscriptions = tuple(s for s in node.subscriptions if s.callback_group is group)
        guards = tuple(g for g in node.guards if g.callback_group is group)
        if (subscriptions, guards) != self._entities:
            self._rebuild(subscriptions, guards)
        wait_set = self._wait_set
        wait_set.clear_entities()
        for sub in subscriptions:
            wait_set.add_subscription(sub.handle)
        for guard in guards:
            wait_set.add_guard_condition(guard.handle)
        wait_set.add_guard_condition(self._wake.handle)
        wait_set.wait(int(timeout_sec * 1e9))
        if not self._context.ok():
            return
        ready = wait_set.get_ready_entities('subscription')
        if ready:
            for sub in subscriptions:
                if sub.handle.pointer in ready:
                    self._take_all(sub)
        ready = wait_set.get_ready_entities('guard_condition')
        if ready:
            for guard in guards:
                if guard.handle.pointer in ready:
                    guard.callback()

    @staticmethod
    def _take_all(sub) -> None:
        take = sub.handle.take_message
        only_message = sub._callback_type is Subscription.CallbackType.MessageOnly
        while True:
            taken = take(sub.msg_type, sub.raw)
            if taken is None:
                return
            if only_message:
                sub.callback(taken[0])
            else:
                sub.callback(*taken)

    def spin(self) -> None:
        """Run until the context shuts down."""
        try:
            while self._context.ok():
                self.spin_once()
        finally:
            self.shutdown()

    def shutdown(self) -> None:
        """Let go of the entities' handles (they may be destroyed then)."""
        self._handles.close()
        self._entities = ()
        self._wait_set = None


class OthersExecutor(MultiThreadedExecutor):
    """A MultiThreadedExecutor for everything but the callbacks of ``excluded``."""

    def __init__(self, excluded, threads: int, context=None) -> None:
        super().__init__(num_threads=threads, context=context)
        self._excluded = excluded
        self._parts: dict = {}

    def _outside(self, entity) -> bool:
        return entity.callback_group is not self._excluded

    def get_nodes(self) -> list:
        """Return the nodes added, each cut to what is outside the excluded group."""
        nodes = super().get_nodes()
        parts = [self._parts.get(id(node)) for node in nodes]
        if any(part is None or part._node is not node for part, node in zip(parts, nodes)):
            self._parts = {id(node): _Part(node, self._outside) for node in nodes}
            parts = [self._parts[id(node)] for node in nodes]
        return parts
