# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The ``backend`` parameter: compiled kernels from the first answer, numpy when asked or missing.

Also: the on-set callback only validates and the post-set callback applies (in process), and
the start-up tool measures a correct first answer.
"""

import json
import os
import re
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from node_harness import (  # noqa: E402
    DEMO_URDF, DOMAIN_ID, Io, joint_state, NodeProcess, PENDULUM_URDF, random_states, stamp_key,
    TIMEOUT, values)
import spatial_dynamics as sd  # noqa: E402

TOL = 1e-9


class Feed:
    """Publishes random states of the demo arm by stamp and checks every answer against τ."""

    def __init__(self, io: Io, seed: int) -> None:
        self.io = io
        self.model = sd.Model.from_urdf(DEMO_URDF)
        self.states = random_states(seed, 64, len(self.model.joint_names))
        self.k = 0

    def publish(self) -> None:
        names = self.model.joint_names
        self.io.joint_states.publish(joint_state(names, *self.states[self.k % 64], self.k))
        self.k += 1

    def run(self, seconds: float, period: float = 0.02) -> None:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.publish()
            self.io.driver.spin_for(period)

    def until(self, predicate, timeout: float, what: str) -> None:
        deadline = time.monotonic() + timeout
        while not predicate():
            assert time.monotonic() < deadline, f'timed out waiting for {what}'
            self.run(0.1)

    def check(self, efforts) -> int:
        """Assert each answer equals the library's τ for its state; return how many."""
        for msg in efforts:
            state = self.states[stamp_key(msg.header.stamp) % 64]
            np.testing.assert_allclose(msg.effort, sd.rnea(self.model, *state, backend='numpy'),
                                       rtol=0, atol=TOL)
        return len(efforts)


def backends_seen(io: Io):
    """Return the 'backend' values of the robot model status, in order, without repeats."""
    seen = []
    for msg in io.diagnostics:
        for status in msg.status:
            if status.name == f'{io.node_name}: robot model':
                value = values(status).get('backend')
                if value and (not seen or seen[-1] != value):
                    seen.append(value)
    return seen


@pytest.mark.ros
def test_the_numpy_backend_answers_when_chosen(install, driver, tmp_path):
    node = NodeProcess(install, ['-p', f'robot_description_file:={DEMO_URDF}',
                                 '-p', 'backend:=numpy'], str(tmp_path))
    io = Io(driver)
    feed = Feed(io, 51)
    try:
        io.wait_connected()
        feed.until(lambda: len(io.efforts) >= 20 and len(io.diagnostics) >= 2, TIMEOUT,
                   'answers and diagnostics')
        assert feed.check(io.efforts) >= 20
        kv = values(io.status('robot model'))
        assert kv['backend'] == 'numpy' and kv['backend setting'] == 'numpy'
        assert backends_seen(io) == ['numpy']
        assert 'backend: numpy' in node.log()
    finally:
        io.close()
        assert node.stop() == 0, node.log()


def children_of(pid: int) -> list:
    return subprocess.run(['ps', '-o', 'pid=', '--ppid', str(pid)], capture_output=True,
                          text=True).stdout.split()


@pytest.mark.ros
@pytest.mark.parametrize('setting', ['auto', 'compiled'])
def test_the_compiled_kernels_answer_from_the_first_answer(install, driver, tmp_path, setting):
    """Nothing to prepare: the first diagnostics already name the compiled kernels."""
    node = NodeProcess(install, ['-p', f'robot_description_file:={DEMO_URDF}',
                                 '-p', f'backend:={setting}'], str(tmp_path))
    io = Io(driver)
    feed = Feed(io, 52)
    try:
        io.wait_connected()
        feed.until(lambda: len(io.efforts) >= 20 and len(io.diagnostics) >= 2, TIMEOUT,
                   'answers and diagnostics')
        assert feed.check(io.efforts) >= 20
        seen = backends_seen(io)
        assert len(seen) == 1 and seen[0].startswith('compiled (C extension, '), seen
        assert values(io.status('robot model'))['backend setting'] == setting
        assert children_of(node.proc.pid) == []
        log = node.log()
        assert 'backend: compiled (C extension' in log and 'Traceback' not in log
    finally:
        io.close()
        assert node.stop() == 0, node.log()


@pytest.mark.ros
def test_without_the_kernels_the_node_stays_on_numpy_and_says_why(install, driver, tmp_path):
    """A package built without a compiler (the extension's import fails): numpy, with why."""
    site = tmp_path / 'no_kernels'
    site.mkdir()
    (site / 'sitecustomize.py').write_text(
        "import sys\nsys.modules['spatial_dynamics.backends._compiled'] = None\n")
    env = {'PYTHONPATH': os.pathsep.join([str(site), install.env()['PYTHONPATH']])}
    node = NodeProcess(install, ['-p', f'robot_description_file:={DEMO_URDF}',
                                 '-p', 'backend:=compiled'], str(tmp_path), env=env)
    io = Io(driver)
    feed = Feed(io, 54)
    try:
        io.wait_connected()
        feed.until(lambda: io.efforts and backends_seen(io), TIMEOUT, 'answers on numpy')
        feed.run(0.5)
        assert feed.check(io.efforts) > 0
        assert backends_seen(io) == [
            'numpy (compiled kernels unavailable: no module spatial_dynamics.backends._compiled'
            ': the package was built without them)'], backends_seen(io)
        assert 'compiled kernels unavailable, answering on numpy' in node.log()
    finally:
        io.close()
        assert node.stop() == 0, node.log()


@pytest.mark.ros
def test_backend_is_read_only_and_checked_at_start(install, driver, tmp_path):
    proc = subprocess.run([install.executable, '--ros-args', '-p',
                           f'robot_description_file:={DEMO_URDF}', '-p', 'backend:=cuda'],
                          env=install.env(), capture_output=True, text=True, timeout=TIMEOUT)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 1 and 'cannot start' in out and "backend: 'cuda'" in out, out
    node = NodeProcess(install, ['-p', f'robot_description_file:={DEMO_URDF}'], str(tmp_path))
    io = Io(driver)
    try:
        io.wait_connected()
        result = io.set_parameters(backend='numpy')[0]
        assert not result.successful and 'read-only' in result.reason, result.reason
    finally:
        io.close()
        assert node.stop() == 0, node.log()


@pytest.mark.ros
def test_on_set_only_validates_and_post_set_applies():
    """In process: the on-set callback changes nothing; the post-set callback swaps."""
    import rclpy
    from rclpy.parameter import Parameter
    from spatial_dynamics.ros.config import PARAMETER_NAMES
    from spatial_dynamics.ros.node import InverseDynamicsNode
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=DOMAIN_ID, args=[
        '--ros-args', '-r', '__ns:=/post_set_test', '-p',
        f'robot_description_file:={DEMO_URDF}', '-p', 'backend:=numpy'])
    node = InverseDynamicsNode(context=context)
    try:
        assert set(PARAMETER_NAMES) <= set(node._parameters)
        robot = node.robot
        gravity = [Parameter('gravity', value=[0.0, -9.81, 0.0])]
        assert node._on_set_parameters(gravity).successful
        assert node.config.params.gravity == (0.0, 0.0, -9.81)
        assert node.config.params.gravity == (0.0, 0.0, -9.81)
        node._on_parameters_set([Parameter('gravity', value=[0.0, -9.81, 0.0])])  # not it
        assert node.config.params.gravity == (0.0, 0.0, -9.81)
        node._on_parameters_set(gravity)
        assert node.config.params.gravity == (0.0, -9.81, 0.0) and node.robot.base is robot.base
        # a description by parameter: validated (parsed) in on-set, swapped in post-set
        with open(PENDULUM_URDF) as f:
            text = f.read()
        change = [Parameter('robot_description', value=text)]
        robot = node.robot
        assert node._on_set_parameters(change).successful
        assert node.robot is robot and node.config.params.robot_description == ''
        node._on_parameters_set(change)
        assert node.robot.model.name == 'pendulum' and node.robot.source == \
            'parameter robot_description'
        # through rclpy: both callbacks, in order; a refused change leaves all as it was
        robot = node.robot
        assert not node.set_parameters([Parameter('payload.mass', value=-1.0)])[0].successful
        assert node.robot is robot and node._pending is None
        assert node.set_parameters([Parameter('gravity', value=[0.0, 0.0, -1.0])])[0].successful
        assert node.config.params.gravity == (0.0, 0.0, -1.0) and node._pending is None
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=context)


@pytest.mark.ros
def test_startup_tool_measures_a_correct_first_answer(install, tmp_path):
    out = tmp_path / 'startup.json'
    proc = subprocess.run(
        [sys.executable, '-m', 'spatial_dynamics.tools.startup', '--urdf', DEMO_URDF,
         '--runs', '1', '--backend', 'numpy', '--hold', '0.5', '--json', str(out)],
        env=install.env(), capture_output=True, text=True, timeout=TIMEOUT + 60, cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    rows = json.loads(out.read_text())['rows']
    assert [(r['backend'], r['cache']) for r in rows] == [('numpy', 'cold'), ('numpy', 'warm')]
    for row in rows:
        assert row['wrong'] == 0 and row['answers'] > 0 and row['exit_status'] == 0
        assert 0.0 < row['first_answer_s'] < TIMEOUT
        assert 10.0 < row['rss_first_mb'] <= row['peak_mb'] < 10_000.0
        assert row['backend_in_use'] == 'numpy'
        assert row['compiled_at_s'] is None
    assert 'first answer s' in proc.stdout
    assert re.search(r'^numpy\s+cold\s+1\s+\d', proc.stdout, re.M), proc.stdout
    assert re.search(r'^numpy\s+warm\s+1\s+\d', proc.stdout, re.M), proc.stdout


FAILING_NODE = """
import sys
from spatial_dynamics.tools import startup
startup.node_command = lambda *names: [sys.executable, '-c', 'import sys; sys.exit(3)']
sys.exit(startup.main(sys.argv[1:]))
"""


@pytest.mark.ros
def test_startup_tool_says_in_one_line_why_a_run_failed(install, tmp_path):
    out = tmp_path / 'startup.json'
    proc = subprocess.run(
        [sys.executable, '-c', FAILING_NODE, '--urdf', DEMO_URDF, '--runs', '1',
         '--backend', 'numpy', '--hold', '0.5', '--timeout', str(TIMEOUT), '--json', str(out)],
        env=install.env(), capture_output=True, text=True, timeout=TIMEOUT + 60, cwd=tmp_path)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert 'Traceback' not in proc.stderr, proc.stderr
    assert 'start-up: numpy cold: the node exited with status 3\n' in proc.stderr, proc.stderr
    assert not out.exists()


def tool_children(pid: int):
    """Return the pids of the children of process ``pid`` (all its threads')."""
    children = []
    for tid in os.listdir(f'/proc/{pid}/task'):
        with open(f'/proc/{pid}/task/{tid}/children') as f:
            children += [int(c) for c in f.read().split()]
    return children


@pytest.mark.ros
def test_startup_tool_on_sigterm_stops_its_node_before_it_exits(install, tmp_path):
    log = tmp_path / 'logs' / 'numpy_cold_0.log'
    # --hold: the node is still running when the signal comes, however slow the machine
    tool = subprocess.Popen(
        [sys.executable, '-m', 'spatial_dynamics.tools.startup', '--urdf', DEMO_URDF,
         '--runs', '1', '--backend', 'numpy', '--hold', '600', '--log-dir',
         str(tmp_path / 'logs')],
        env=install.env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        cwd=tmp_path)
    try:
        deadline = time.monotonic() + TIMEOUT
        while not (log.exists() and log.read_text().strip()):      # the node is up
            assert tool.poll() is None and time.monotonic() < deadline, tool.communicate()
            time.sleep(0.1)
        nodes = tool_children(tool.pid)
        assert len(nodes) == 1, nodes
        tool.send_signal(signal.SIGTERM)       # to the tool only
        out, err = tool.communicate(timeout=TIMEOUT)
    finally:
        if tool.poll() is None:
            tool.kill()
            tool.wait()
    assert tool.returncode == 128 + signal.SIGTERM, out + err
    assert 'Traceback' not in err and 'interrupted (SIGTERM)' in err, err
    assert not os.path.exists(f'/proc/{nodes[0]}'), 'the node outlived the tool'
