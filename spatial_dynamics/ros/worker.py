# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Worker threads off the answering path: the newest item wins; a wait that can be given up.

Work whose size a message decides (a plan to annotate, a topic description to parse) runs on
such a thread (STYLE habit 13): :meth:`Newest.submit` replaces an item not yet started (only
the newest matters), and the work on an item asks ``cancelled()`` whether a newer item came or
the worker was stopped since it started. The thread starts with the first item and is a daemon
(never waited for). Used by :class:`~spatial_dynamics.ros.plans.Annotator` and
:class:`~spatial_dynamics.ros.descriptions.DescriptionParser`.

:func:`abandonable` runs work the caller must wait for (a description set by parameter, parsed
at start-up or in the parameter service's callback) on a daemon thread, and gives the wait up
when the process is asked to end: a 15,000-link description parses for tens of seconds, and
SIGINT waited for all of it. Pure Python: no rclpy.
"""

from __future__ import annotations

import threading
from typing import Callable, Generic, List, Optional, TypeVar

Item = TypeVar('Item')
Result = TypeVar('Result')

#: How often (s) :func:`abandonable` asks whether it should give its wait up.
POLL_PERIOD = 0.05


class Abandoned(Exception):
    """The wait for work was given up (the process is ending); the work runs on, unheard."""


def abandonable(work: Callable[[], Result], alive: Callable[[], bool], name: str,
                poll: float = POLL_PERIOD) -> Result:
    """Return ``work()``, run on a daemon thread, or raise :class:`Abandoned` once not ``alive()``.

    What ``work`` raises is raised here. Given up, the thread is left to finish on its own
    (nothing reads its result) and, a daemon, never holds the process's exit.
    """
    done = threading.Event()
    outcome: List = []

    def run() -> None:
        try:
            outcome.append((True, work()))
        except BaseException as err:  # handed to the waiting thread
            outcome.append((False, err))
        done.set()

    threading.Thread(target=run, daemon=True, name=name).start()
    while not done.wait(poll):
        if not alive():
            raise Abandoned(f'{name}: given up, the process is ending')
    ok, value = outcome[0]
    if not ok:
        raise value
    return value


class Newest(Generic[Item]):
    """A worker thread that calls ``work(item, cancelled)`` on the newest item submitted.

    ``work`` runs on the worker thread, one item at a time; it catches what it raises (the
    worker would end with it). ``cancelled()`` turns true once another item is submitted or
    :meth:`stop` is called: a long computation polls it, a result is delivered only while it is
    false.
    """

    def __init__(self, work: Callable[[Item, Callable[[], bool]], None], name: str) -> None:
        self._work = work
        self._name = name
        self._wake = threading.Condition()
        self._item: Optional[Item] = None
        self._generation = 0          # one per item submitted and one for stop()
        self._stopped = False
        self._thread: Optional[threading.Thread] = None

    @property
    def stopped(self) -> bool:
        """Whether :meth:`stop` was called."""
        return self._stopped

    def submit(self, item: Item) -> Optional[Item]:
        """Work on ``item`` next: an item not yet started is dropped, the current one cancelled.

        Returns the item dropped (None: none was waiting), for the caller to say so.
        """
        with self._wake:
            if self._stopped:
                return None
            dropped, self._item = self._item, item
            self._generation += 1
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, daemon=True, name=self._name)
                self._thread.start()
            self._wake.notify()
        return dropped

    def stop(self) -> None:
        """Let the worker end: the item waiting is dropped, the current one cancelled."""
        with self._wake:
            self._stopped = True
            self._item = None
            self._generation += 1
            self._wake.notify()

    def _run(self) -> None:
        while True:
            with self._wake:
                while self._item is None and not self._stopped:
                    self._wake.wait()
                if self._stopped:
                    return
                item, self._item = self._item, None
                generation = self._generation
            self._work(item, lambda: self._generation != generation)
