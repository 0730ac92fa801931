# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The answering thread and its real-time knobs: applied where permitted, one WARN where not.

No root needed: a core of the process's own set is always permitted, priority 0 is normal
scheduling, and a refusal (EPERM) is made by replacing the system call. No latency is
asserted anywhere (the benchmark measures; these check behaviour).
"""

import errno
import os
import threading
import time

from diagnostic_msgs.msg import DiagnosticStatus
import numpy as np
from node_harness import (
    DEMO_URDF, Io, joint_state, NodeProcess, pin_oracle, random_states, TIMEOUT)
import pytest
import spatial_dynamics as sd
from spatial_dynamics.ros import realtime
from spatial_dynamics.ros.config import PARAMETERS
from spatial_dynamics.ros.parameters import check, ConfigError, ParameterError


def in_thread(function):
    """Return ``function()`` run in a new thread (the knobs apply to the calling thread)."""
    result = []
    thread = threading.Thread(target=lambda: result.append(function()))
    thread.start()
    thread.join(TIMEOUT)
    return result[0]


def permission_denied(*args):
    raise PermissionError(errno.EPERM, os.strerror(errno.EPERM))


def test_knobs_are_controller_managers_in_the_one_table():
    """Named as ros2_control's controller_manager (Jazzy), read-only; real-time asked for."""
    table = PARAMETERS.by_name
    assert table['thread_priority'].default == 0 and table['thread_priority'].type == 'int'
    assert table['cpu_affinity'].default is None and table['cpu_affinity'].type == 'int[]'
    assert table['lock_memory'].default is False   # Jazzy's default on a standard kernel
    assert all(table[name].read_only for name in ('thread_priority', 'cpu_affinity',
                                                  'lock_memory'))
    assert check(table['cpu_affinity'], [0, 1]) == (0, 1)
    for bad in ([0.5], [-1], [1, 1], 'abc'):
        with pytest.raises(ConfigError, match='cpu_affinity'):
            check(table['cpu_affinity'], bad)
    for bad in (-1, 100):
        with pytest.raises(ParameterError, match='thread_priority'):
            check(table['thread_priority'], bad)


def test_affinity_applies_to_the_answering_thread_only():
    allowed = sorted(os.sched_getaffinity(0))
    core = allowed[-1]

    def answering():
        effect = realtime.apply(0, [core], False)
        return effect, os.sched_getaffinity(0), os.sched_getscheduler(0)

    effect, affinity, policy = in_thread(answering)
    assert affinity == {core} and effect.refused == ()
    assert policy == os.SCHED_OTHER and 'normal' in effect.priority
    assert sorted(os.sched_getaffinity(0)) == allowed   # the other threads keep every core


def test_priority_zero_is_normal_scheduling():
    effect, policy = in_thread(lambda: (realtime.apply(0, None, False),
                                        os.sched_getscheduler(0)))
    assert policy == os.SCHED_OTHER and effect.refused == () and realtime.warning(effect) is None


def test_refused_knobs_warn_once_with_how_to_grant_and_run_on(monkeypatch):
    monkeypatch.setattr(realtime.os, 'sched_setscheduler', permission_denied)
    monkeypatch.setattr(realtime, 'lock_memory', permission_denied)
    core = max(os.sched_getaffinity(0)) + 1   # not a core of this process
    effect, policy, affinity = in_thread(lambda: (
        realtime.apply(50, [core], True), os.sched_getscheduler(0), os.sched_getaffinity(0)))
    assert policy == os.SCHED_OTHER and affinity == os.sched_getaffinity(0)
    assert effect.priority.startswith('normal') and effect.memory == 'not locked'
    assert len(effect.refused) == 2 and len(effect.invalid) == 1
    text = realtime.warning(effect)
    for words in ('thread_priority 50', 'EPERM', 'lock_memory', f'cpu_affinity [{core}]',
                  'limits.conf', 'rtprio', 'memlock', 'ulimit -r', '--cap-add=sys_nice'):
        assert words in text, (words, text)
    level, message, values = realtime.status(effect)
    assert level == 'WARN' and 'normal' in message and 'not permitted' in message


def test_a_core_not_allowed_is_no_permission_problem():
    """EINVAL (no core of the list is the process's) says so, without privilege advice."""
    core = max(os.sched_getaffinity(0)) + 1
    effect = in_thread(lambda: realtime.apply(0, [core], False))
    assert effect.refused == () and len(effect.invalid) == 1
    text = realtime.warning(effect)
    assert f'cpu_affinity [{core}]' in text and 'not among the cores' in text
    assert str(sorted(os.sched_getaffinity(0))) in text
    for advice in ('not permitted', 'limits.conf', 'rtprio', '--cap-add'):
        assert advice not in text, (advice, text)
    level, message, _ = realtime.status(effect)
    assert level == 'WARN' and 'not permitted' not in message and f'[{core}]' in message


def test_a_list_partly_outside_the_allowed_cores_is_refused_whole():
    """[0, 1023]: the kernel would pin to core 0 alone and say nothing; the docs say WARN."""
    allowed = sorted(os.sched_getaffinity(0))
    wanted = [allowed[0], max(allowed) + 1]
    effect, affinity = in_thread(lambda: (realtime.apply(0, wanted, False),
                                          os.sched_getaffinity(0)))
    assert affinity == set(allowed) and effect.affinity == 'all cores'
    assert len(effect.invalid) == 1 and f'[{max(allowed) + 1}]' in effect.invalid[0]
    assert realtime.status(effect)[0] == 'WARN'


def test_an_inherited_real_time_policy_is_reported_as_it_is(monkeypatch):
    """Started under `chrt -f 50` with thread_priority 0: the status says FIFO 50, not normal."""
    monkeypatch.setattr(realtime.os, 'sched_getscheduler', lambda tid: os.SCHED_FIFO)
    monkeypatch.setattr(realtime.os, 'sched_getparam', lambda tid: os.sched_param(50))
    effect = in_thread(lambda: realtime.apply(0, None, False))
    assert effect.priority.startswith('SCHED_FIFO 50') and 'inherited' in effect.priority


def test_garbage_collector_is_frozen_and_collected_off_the_answers():
    import gc
    try:
        realtime.keep_collector_off_answers()
        assert not gc.isenabled() and gc.get_freeze_count() > 0
        cycle = []
        cycle.append(cycle)
        del cycle
        assert realtime.collect(1) >= 0 and gc.garbage == []
    finally:
        gc.unfreeze()
        gc.enable()


@pytest.mark.ros
def test_group_executor_runs_only_its_group_in_its_thread():
    """The answering executor runs its group; the others' never does, whoever spins first."""
    import rclpy
    from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
    from std_msgs.msg import String
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        node = rclpy.create_node('group_executor_test', context=context)
        group = MutuallyExclusiveCallbackGroup()
        threads = {'inputs': set(), 'other': set()}
        node.create_subscription(String, 'inputs', lambda _: threads['inputs'].add(
            threading.get_ident()), 10, callback_group=group)
        node.create_subscription(String, 'other', lambda _: threads['other'].add(
            threading.get_ident()), 10)
        publishers = [node.create_publisher(String, topic, 10) for topic in ('inputs', 'other')]
        answering = realtime.AnsweringLoop(node, group)
        others = realtime.OthersExecutor(group, 2, context)
        others.add_node(node)
        done = threading.Event()
        thread = threading.Thread(target=lambda: [answering.spin_once(0.05)
                                                  for _ in iter(done.is_set, True)])
        thread.start()
        for _ in range(200):
            if threads['inputs'] and threads['other']:
                break
            for publisher in publishers:
                publisher.publish(String(data='x'))
            others.spin_once(0.05)
        done.set()
        thread.join(TIMEOUT)
        assert threads['inputs'] == {thread.ident}
        assert threads['other'] and thread.ident not in threads['other']
        others.shutdown()
        answering.shutdown()
        node.destroy_node()
    finally:
        rclpy.shutdown(context=context)


@pytest.mark.ros
def test_executors_never_run_each_others_guard_conditions():
    """A guard condition runs in the loop or executor that serves its group, only there.

    rclpy marks a ready guard condition on the entity and then runs whatever of the node's
    guards is marked: the answering executor ran the description's guard condition (rclpy's
    default group) while the other executor had left the group's timer out of its wait set;
    nothing woke that executor again and the diagnostics stopped (CI, a 6000-link description
    on a busy machine). Each must run only its part of the node.
    """
    import rclpy
    from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        node = rclpy.create_node('guard_executor_test', context=context)
        group = MutuallyExclusiveCallbackGroup()
        ran = []
        inside = node.create_guard_condition(lambda: ran.append(('inside', threading.get_ident())),
                                             callback_group=group)
        outside = node.create_guard_condition(lambda: ran.append(('outside',
                                                                  threading.get_ident())))
        answering = realtime.AnsweringLoop(node, group)
        others = realtime.OthersExecutor(group, 2, context)
        others.add_node(node)
        # the marks an executor's wait leaves on the guard conditions it saw ready
        outside._executor_triggered = True
        inside._executor_triggered = True
        answering.spin_once(0.0)
        assert ran == [], 'the answering loop ran a guard condition of another group'
        deadline = time.monotonic() + TIMEOUT
        while not ran and time.monotonic() < deadline:
            others.spin_once(0.01)
        assert [name for name, _ in ran] == ['outside'], ran
        assert ran[0][1] != threading.get_ident()   # in the others' pool
        inside.trigger()
        answering.spin_once(TIMEOUT)
        assert [name for name, _ in ran] == ['outside', 'inside'], ran
        assert ran[1][1] == threading.get_ident()
        others.shutdown()
        answering.shutdown()
        node.destroy_node()
    finally:
        rclpy.shutdown(context=context)


def answering_thread(pid: int) -> int:
    """Return the id of the node's answering thread (:data:`realtime.ANSWERING_THREAD`)."""
    for tid in os.listdir(f'/proc/{pid}/task'):
        with open(f'/proc/{pid}/task/{tid}/comm') as f:
            if f.read().strip() == realtime.ANSWERING_THREAD:
                return int(tid)
    raise AssertionError('no answering thread')


@pytest.mark.ros
def test_node_pins_its_answering_thread_and_answers(install, driver, tmp_path):
    core = max(os.sched_getaffinity(0))
    node = NodeProcess(install, ['-p', f'robot_description_file:={DEMO_URDF}',
                                 '-p', 'thread_priority:=0', '-p', f'cpu_affinity:=[{core}]'],
                       str(tmp_path))
    io = Io(driver)
    try:
        io.wait_connected()
        node.wait_for_log('real-time: normal')
        tid = answering_thread(node.proc.pid)
        assert os.sched_getaffinity(tid) == {core}
        assert os.sched_getscheduler(tid) == os.SCHED_OTHER
        assert_answers_equal_the_library(io)
        status = io.fresh_status('real-time')
        assert status.level == DiagnosticStatus.OK and 'normal' in status.message
        assert f'cores {core}' in dict((v.key, v.value) for v in status.values)['cpu affinity']
    finally:
        io.close()
        node.stop()


@pytest.mark.ros
def test_node_refused_a_knob_warns_once_and_answers(install, driver, tmp_path):
    core = max(os.sched_getaffinity(0)) + 1   # not permitted: not a core of the process
    node = NodeProcess(install, ['-p', f'robot_description_file:={DEMO_URDF}',
                                 '-p', f'cpu_affinity:=[{core}]'], str(tmp_path))
    io = Io(driver)
    try:
        io.wait_connected()
        assert_answers_equal_the_library(io)
        status = io.fresh_status('real-time')
        assert status.level == DiagnosticStatus.WARN and f'[{core}]' in status.message
        log = node.log()
        assert log.count('real-time settings impossible here') == 1, log
        assert f'cpu_affinity [{core}]' in log and 'limits.conf' not in log
        assert 'Traceback' not in log
    finally:
        io.close()
        node.stop()


def assert_answers_equal_the_library(io: Io) -> None:
    """Answers from the answering thread: Pinocchio's RNEA of the states sent."""
    oracle = pin_oracle(DEMO_URDF)
    names = sd.Model.from_urdf(DEMO_URDF).joint_names
    states = random_states(36, 5, len(names))
    for k, (q, qd, qdd) in enumerate(states):
        io.efforts.clear()
        io.publish_until_answered(lambda _: joint_state(names, q, qd, qdd, k))
        np.testing.assert_allclose(io.efforts[-1].effort, oracle.rnea(names, q, qd, qdd),
                                   rtol=1e-9, atol=1e-9)
