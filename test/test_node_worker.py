# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The node's worker thread (spatial_dynamics.ros.worker): the newest item wins, stop cancels.

Both of the node's workers (the plan annotator, the topic description parser) are this one
thread; no DDS here. The waits are events with generous limits, never a duration asserted.
"""

import threading

from spatial_dynamics.ros import descriptions, plans
import pytest

from spatial_dynamics.ros.worker import Abandoned, abandonable, Newest

WAIT = 60.0   # a limit for a stuck thread, never reached when the code is right


class Recorder:
    """Work that blocks on its first item until released, and records what it saw."""

    def __init__(self):
        self.started = threading.Event()
        self.release = threading.Event()
        self.finished = threading.Event()
        self.seen = []       # (item, cancelled() when the work ended)

    def __call__(self, item, cancelled):
        if not self.seen:
            self.started.set()
            assert self.release.wait(WAIT)
        self.seen.append((item, cancelled()))
        self.finished.set()


def test_the_newest_waiting_item_replaces_the_others_and_cancels_the_current_one():
    work = Recorder()
    worker = Newest(work, 'test worker')
    worker.submit(1)
    assert work.started.wait(WAIT)
    for item in (2, 3, 4):
        worker.submit(item)
    work.release.set()
    while len(work.seen) < 2:
        work.finished.clear()
        assert work.finished.wait(WAIT)
    worker.stop()
    assert work.seen == [(1, True), (4, False)]   # 2 and 3 never started; 1 was superseded


def test_submit_returns_the_item_it_drops_unstarted():
    """The caller learns which waiting item a newer one replaced (to say so in its log)."""
    work = Recorder()
    worker = Newest(work, 'test worker')
    assert worker.submit(1) is None
    assert work.started.wait(WAIT)
    assert worker.submit(2) is None       # 1 runs (cancelled), nothing was waiting
    assert worker.submit(3) == 2          # 2 never started: dropped
    work.release.set()
    worker.stop()


def test_stop_cancels_the_current_item_drops_the_waiting_one_and_ends_the_thread():
    work = Recorder()
    worker = Newest(work, 'test worker')
    worker.submit('current')
    assert work.started.wait(WAIT)
    worker.submit('waiting')
    worker.stop()
    worker.submit('after')                        # refused: stopped
    work.release.set()
    worker._thread.join(WAIT)
    assert not worker._thread.is_alive() and worker.stopped
    assert work.seen == [('current', True)]


def test_the_annotator_publishes_the_newest_plan_only():
    published = []
    started, release = threading.Event(), threading.Event()

    class Annotator(plans.Annotator):
        def build(self, job, cancelled=lambda: False):
            if job == 'first':
                started.set()
                assert release.wait(WAIT)
            return f'annotated {job}'

    done = threading.Event()
    annotator = Annotator(lambda msg: (published.append(msg), done.set()), log=None)
    annotator.submit('first')
    assert started.wait(WAIT)
    annotator.submit('second')
    release.set()
    assert done.wait(WAIT)
    annotator.stop()
    assert published == ['annotated second']      # 'first' finished after it was superseded


def test_the_parser_delivers_nothing_after_stop():
    started, release = threading.Event(), threading.Event()
    notified = []

    def build(request):
        started.set()
        assert release.wait(WAIT)
        return request.urdf

    parser = descriptions.DescriptionParser(build, lambda: notified.append(1))
    parser.submit(descriptions.ParseRequest(1, 'urdf', {}, None))
    assert started.wait(WAIT)
    parser.stop()
    release.set()
    parser._worker._thread.join(WAIT)
    assert parser.finished() == [] and notified == []


def test_abandonable_returns_raises_and_gives_up_a_wait_when_no_longer_alive():
    """Work waited for on a daemon thread: its result, its error, or Abandoned on shutdown.

    The node parses a description set by parameter this way: a signal during a long parse
    ends the wait (the node exits) while the parse runs on, unheard, on a daemon thread.
    """
    assert abandonable(lambda: 42, lambda: True, 'test work') == 42
    with pytest.raises(ValueError, match='bad description'):
        abandonable(lambda: (_ for _ in ()).throw(ValueError('bad description')),
                    lambda: True, 'test work')
    release = threading.Event()
    started = threading.Event()
    threads = []

    def work():
        threads.append(threading.current_thread())
        started.set()
        assert release.wait(WAIT)
        return 'parsed'

    alive = threading.Event()
    alive.set()
    stopper = threading.Thread(target=lambda: (started.wait(WAIT), alive.clear()))
    stopper.start()
    with pytest.raises(Abandoned):
        abandonable(work, alive.is_set, 'test work', poll=0.01)
    assert not release.is_set()               # given up while the work still ran
    assert threads[0].daemon and threads[0].is_alive()   # never holds the process's exit
    release.set()
    threads[0].join(WAIT)
    stopper.join(WAIT)
