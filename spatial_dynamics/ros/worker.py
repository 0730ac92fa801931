# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""One worker thread that works on the newest item given to it, off the answering path.

Work whose size a message decides (a plan to annotate, a topic description to parse) runs on
such a thread (STYLE habit 13): :meth:`Newest.submit` replaces an item not yet started (only
the newest matters), and the work on an item asks ``cancelled()`` whether a newer item came or
the worker was stopped since it started. The thread starts with the first item and is a daemon
(never waited for). Used by :class:`~spatial_dynamics.ros.plans.Annotator` and
:class:`~spatial_dynamics.ros.descriptions.DescriptionParser`. Pure Python: no rclpy.
"""

from __future__ import annotations

import threading
from typing import Callable, Generic, Optional, TypeVar

Item = TypeVar('Item')


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
