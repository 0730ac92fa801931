# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The node's configuration without ROS: ``spatial_dynamics.ros.config``.

Descriptions and description files, parameter bounds, precedence, validation that changes
nothing, the backend choice, the counters and what
/diagnostics says. No ROS graph and no rclpy: the module is checked not to import it.
"""

import ast
import math
import os
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from node_harness import DEMO_URDF, PENDULUM_URDF  # noqa: E402
import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics.ros import config, configure, descriptions, diagnostics  # noqa: E402
from spatial_dynamics.ros.config import ConfigError  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@pytest.fixture(scope='module')
def demo_text():
    with open(DEMO_URDF) as f:
        return f.read()


def defaults(**changes) -> dict:
    """Every parameter at its declared default (unset arrays as None), then ``changes``."""
    params = {spec.name: spec.default for spec in config.PARAMETERS}
    params.update(changes)
    return params


def checked(**changes):
    """Return the table's ``Params`` of :func:`defaults` with ``changes`` (raises as the node)."""
    return config.PARAMETERS.values(defaults(**changes))


# --------------------------------------------------------------------------------------------
# The module is pure, and the shell around it thin

def test_config_never_imports_rclpy():
    script = textwrap.dedent('''\
        import sys
        from spatial_dynamics.ros import config, configure
        params = {s.name: s.default for s in config.PARAMETERS}
        out = configure.prepare({}, params, None)
        assert out.robot is None and out.params.gravity == (0.0, 0.0, -9.81)
        print('ROS:', sorted(m for m in sys.modules if m.split('.')[0] in
                             ('rclpy', 'rcl_interfaces', 'sensor_msgs', 'std_msgs',
                              'diagnostic_msgs', 'geometry_msgs')))
    ''')
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [ROOT] + [p for p in os.environ.get('PYTHONPATH', '').split(os.pathsep) if p]))
    proc = subprocess.run([sys.executable, '-c', script], capture_output=True, text=True,
                          cwd=ROOT, env=env, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert 'ROS: []' in proc.stdout, proc.stdout


def _functions(path):
    with open(path, encoding='utf-8') as f:
        tree = ast.parse(f.read())
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            yield node.name, node.end_lineno - node.lineno + 1


@pytest.mark.parametrize('module', ['node.py', 'config.py', 'inputs.py'])
def test_no_function_of_the_ros_layer_is_longer_than_60_lines(module):
    path = os.path.join(ROOT, 'spatial_dynamics', 'ros', module)
    long = [(name, lines) for name, lines in _functions(path) if lines > 60]
    assert not long, f'{module}: {long}'


def test_every_parameter_is_in_the_params_file():
    with open(os.path.join(ROOT, 'config', 'inverse_dynamics.yaml')) as f:
        text = f.read()
    for spec in config.PARAMETERS:
        key = spec.name.split('.')[-1]
        assert f'{key}:' in text, f'{spec.name} is not described in inverse_dynamics.yaml'
    read_only = {s.name for s in config.PARAMETERS if s.read_only}
    assert read_only == {'backend', 'trajectory_max_bytes', 'trajectory_annotation_max_values',
                         'base', 'thread_priority', 'cpu_affinity', 'lock_memory'}
    for name in read_only:   # the header says which cannot change: those marked so
        assert f'# {name} (' in text and 'read-only)' in text.split(f'# {name} (')[1][:20]
    assert set(config.SLOW_PARAMETERS) <= set(config.PARAMETER_NAMES)


# --------------------------------------------------------------------------------------------
# Descriptions: text, files, precedence

def without_blocking(function, *args):
    """Call ``function(*args)`` in a thread; fail if it has not returned after a minute.

    Opening a FIFO without a writer, or reading /dev/zero, never returns: the wait is a
    generous bound on a hang (it ends as soon as the call does), not a speed limit.
    """
    outcome = []

    def call():
        try:
            outcome.append((True, function(*args)))
        except BaseException as err:
            outcome.append((False, err))

    thread = threading.Thread(target=call, daemon=True)
    thread.start()
    thread.join(60.0)
    assert outcome, f'{function.__name__}{args!r} blocked (opened a FIFO or a device?)'
    ok, value = outcome[0]
    if not ok:
        raise value
    return value


def test_description_text_is_never_opened_as_a_path(tmp_path, monkeypatch):
    """robot_description (parameter or topic) is XML text: a path is refused, never read."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / 'robot.urdf').write_text(open(DEMO_URDF).read())
    for text in (DEMO_URDF, 'robot.urdf', f'  {DEMO_URDF}\n'):
        with pytest.raises(ConfigError) as info:
            descriptions.parse_description(text, 'topic robot_description')
        message = str(info.value)
        assert 'topic robot_description' in message and 'robot_description_file' in message
        assert 'not URDF XML' in message
    # a named pipe and a device would block or exhaust memory if they were opened
    fifo = tmp_path / 'pipe'
    os.mkfifo(fifo)
    for text in (str(fifo), '/dev/zero'):
        with pytest.raises(ConfigError, match='not URDF XML'):
            without_blocking(descriptions.parse_description, text, 'parameter robot_description')


def test_description_text_with_bom_or_blank_lines_loads(demo_text):
    for text in ('\ufeff' + demo_text, '\n\n  ' + demo_text):
        model = descriptions.parse_description(text, 'parameter robot_description')
        assert model.joint_names == sd.Model.from_urdf(DEMO_URDF).joint_names


def test_description_file_must_be_a_regular_file(tmp_path):
    fifo = tmp_path / 'pipe'
    os.mkfifo(fifo)
    link = tmp_path / 'link_to_pipe.urdf'
    link.symlink_to(fifo)
    for path, kind in [(fifo, 'named pipe'), (link, 'named pipe'), (tmp_path, 'directory'),
                       ('/dev/null', 'character device')]:
        with pytest.raises(ConfigError) as info:
            without_blocking(descriptions.read_description, str(path))
        message = str(info.value)
        assert repr(str(path)) in message and 'not a regular file' in message
        assert kind in message, message
        assert 'robot_description_file' in message
    with pytest.raises(ConfigError, match='no such file'):
        descriptions.read_description(str(tmp_path / 'none.urdf'))


def test_description_file_size_is_limited(tmp_path, demo_text):
    """A file larger than MAX_DESCRIPTION_BYTES is refused before it is read, limit named."""
    big = tmp_path / 'big.urdf'
    with open(big, 'wb') as f:
        f.truncate(32 * 1024 * 1024 + 1)   # sparse: costs no disk
    with pytest.raises(ConfigError) as info:
        descriptions.read_description(str(big))
    message = str(info.value)
    assert 'big.urdf' in message and '32 MiB' in message and 'limit' in message
    assert descriptions.MAX_DESCRIPTION_BYTES == 32 * 1024 * 1024
    ok = tmp_path / 'ok.urdf'
    ok.write_text(demo_text)
    assert descriptions.read_description(str(ok)) == demo_text


def test_description_file_not_utf8_named(tmp_path, demo_text):
    """A file that is not UTF-8 gives a ConfigError naming the file and the byte."""
    bad = tmp_path / 'latin1.urdf'
    bad.write_bytes(demo_text.replace('demo_arm', 'd\xe9mo_arm').encode('latin-1'))
    with pytest.raises(ConfigError) as info:
        descriptions.read_description(str(bad))
    message = str(info.value)
    assert repr(str(bad)) in message and 'UTF-8' in message
    bom = tmp_path / 'bom.urdf'
    bom.write_bytes(b'\xef\xbb\xbf' + demo_text.encode())
    assert descriptions.read_description(str(bom)) == demo_text


def test_a_xacro_file_is_checked_like_any_file_before_xacro_opens_it(tmp_path):
    fifo = tmp_path / 'robot.urdf.xacro'
    os.mkfifo(fifo)
    with pytest.raises(ConfigError, match='named pipe'):
        without_blocking(descriptions.read_description, str(fifo))


def test_description_precedence_parameter_file_topic():
    assert descriptions.description_source(checked()) == 'topic'
    assert descriptions.description_source(checked(robot_description_file=DEMO_URDF)) == 'file'
    assert descriptions.description_source(checked(
        robot_description='<robot/>', robot_description_file=DEMO_URDF)) == 'parameter'


def test_description_change_reads_the_file_set_while_the_string_wins(demo_text):
    previous = checked(robot_description=demo_text)
    changes = {'robot_description_file': PENDULUM_URDF}
    urdf, source, kept = descriptions.description_change(
        previous, config.PARAMETERS.changed(previous, changes), changes)
    assert (urdf, source, kept) == (None, None, PENDULUM_URDF)
    # clearing the string falls back to the file
    previous = config.PARAMETERS.changed(previous, changes)
    changes = {'robot_description': ''}
    urdf, source, kept = descriptions.description_change(
        previous, config.PARAMETERS.changed(previous, changes), changes)
    assert source == f'file {PENDULUM_URDF}' and 'pendulum' in urdf and kept == ''
    # a bad file set while the string wins is refused all the same
    changes = {'robot_description_file': '/nonexistent/robot.urdf'}
    with pytest.raises(ConfigError, match='no such file'):
        descriptions.description_change(checked(robot_description=demo_text),
                                        checked(robot_description=demo_text, **changes),
                                        changes)


# --------------------------------------------------------------------------------------------
# Bounds of absurd values

@pytest.mark.parametrize('gravity', [[0.0, 0.0, -1e308], [1e4, 0.0, 0.0],
                                     [-800.0, 800.0, 0.0]])
def test_absurd_gravity_refused_with_the_bound(gravity):
    with pytest.raises(ConfigError) as info:
        checked(gravity=gravity)
    message = str(info.value)
    assert 'parameter gravity' in message and f'{config.MAX_GRAVITY:g} m/s²' in message


def test_physical_gravity_accepted():
    assert checked(gravity=[0.0, 0.0, -9.81]).gravity == (0.0, 0.0, -9.81)
    # a centrifuge or a test rig may exceed 1 g by far; the bound is 100 g
    assert config.MAX_GRAVITY == 1e3
    assert checked(gravity=[0.0, 0.0, -1e3]).gravity == (0.0, 0.0, -1e3)


def test_absurd_armature_refused_with_the_bound():
    model = sd.Model.from_urdf(DEMO_URDF)
    n = len(model.joint_names)
    for bad in (1e308, 2e6):
        values = [0.1] * n
        values[2] = bad
        with pytest.raises(ConfigError) as info:
            configure.check_armature(model, values)
        message = str(info.value)
        assert 'parameter armature' in message and repr(model.joint_names[2]) in message
        assert f'{config.MAX_ARMATURE:g}' in message
    assert configure.check_armature(model, [config.MAX_ARMATURE] * n).max() == config.MAX_ARMATURE


@pytest.mark.parametrize('field, value, bound', [
    ('mass', 1e308, 'MAX_PAYLOAD_MASS'),
    ('mass', 2e6, 'MAX_PAYLOAD_MASS'),
    ('com', [0.0, 1e308, 0.0], 'MAX_PAYLOAD_COM'),
    ('com', [0.0, 0.0, -2e3], 'MAX_PAYLOAD_COM'),
    ('inertia', [1e308, 0.0, 0.0, 1e308, 0.0, 1e308], 'MAX_PAYLOAD_INERTIA'),
    ('inertia', [1.0, 2e6, 0.0, 1.0, 0.0, 1.0], 'MAX_PAYLOAD_INERTIA'),
])
def test_absurd_payload_refused_with_the_bound(field, value, bound):
    args = dict(link='hand', mass=1.0, com=[0.0] * 3, inertia=[0.01, 0, 0, 0.01, 0, 0.01])
    args[field] = value
    with pytest.raises(ConfigError) as info:
        checked(**{f'payload.{key}': value for key, value in args.items()})
    message = str(info.value)
    assert f'parameter payload.{field}' in message
    assert f'{getattr(config, bound):g}' in message


def test_absurd_locked_position_refused_with_the_bound():
    with pytest.raises(ConfigError) as info:
        checked(locked_joints=['joint2'], locked_positions=[1e300])
    message = str(info.value)
    assert 'parameter locked_positions' in message and f'{config.MAX_LOCKED_POSITION:g}' in message
    assert configure.locked_positions(checked(locked_joints=['joint2'],
                                              locked_positions=[-math.pi])) == {'joint2': -math.pi}


def test_locked_joints_need_the_same_number_of_positions_and_distinct_names():
    with pytest.raises(ConfigError, match='1 values for 2 locked_joints'):
        configure.locked_positions(checked(locked_joints=['a', 'b'], locked_positions=[0.1]))
    with pytest.raises(ConfigError, match='names repeated'):
        checked(locked_joints=['a', 'a'], locked_positions=[])
    assert configure.locked_positions(checked(locked_joints=['a', 'b'], locked_positions=[])) == \
        {'a': 0.0, 'b': 0.0}


# --------------------------------------------------------------------------------------------
# prepare(): validation that changes nothing; build_robot(): what an answer needs

def test_prepare_validates_without_changing_its_inputs(demo_text):
    previous = defaults()
    first = configure.prepare({}, defaults(robot_description=demo_text), None)
    assert first.new_description and first.robot.model.name == 'demo_arm'
    assert previous == defaults()    # the dict passed in is not touched
    # a payload change reuses the parsed model, applies the payload to a copy
    hand = first.robot.model.body_names[-1]
    change = {'payload.link': hand, 'payload.mass': 2.0}
    second = configure.prepare(first.params, change, first.robot)
    assert second.robot.base is first.robot.base and not second.new_description
    assert second.robot.model is not first.robot.model
    assert first.params.payload_link == ''   # the accepted parameters stay as they were
    q = np.linspace(-1.0, 1.0, len(first.robot.joints))
    with_payload = sd.with_payload(first.robot.base, hand, 2.0)
    np.testing.assert_allclose(sd.rnea(second.robot.model, q, q, q),
                               sd.rnea(with_payload, q, q, q), rtol=0, atol=1e-12)
    # a bad value is refused with its name, and nothing is produced
    with pytest.raises(ConfigError, match='parameter gravity'):
        configure.prepare(second.params, {'gravity': [0.0, 0.0, float('nan')]}, second.robot)


def test_without_a_model_what_needs_none_is_checked():
    with pytest.raises(ConfigError, match='parameter payload.mass'):
        configure.prepare({}, defaults(**{'payload.mass': -1.0}), None)
    with pytest.raises(ConfigError, match='parameter friction_model'):
        configure.prepare({}, defaults(friction_model='coulomb'), None)
    with pytest.raises(ConfigError, match='parameter backend'):
        configure.prepare({}, defaults(backend='cuda'), None)
    assert configure.prepare({}, defaults(), None).robot is None


def test_reduction_and_strict_are_reparse_triggers(demo_text):
    params = checked(robot_description=demo_text)
    changed = config.PARAMETERS.changed
    assert not configure.reparse_needed(params, changed(params, {'gravity': [0.0, 0.0, -1.0]}))
    for name, value in (('joints', ['joint1']), ('locked_joints', ['joint2']),
                        ('locked_positions', [0.5]), ('strict_urdf', True)):
        assert configure.reparse_needed(params, changed(params, {name: value})), name


# --------------------------------------------------------------------------------------------
# Backend: the choice (the compiled kernels are built with the package)

def test_auto_and_compiled_run_the_compiled_kernels_numpy_never(monkeypatch):
    assert sd.backends.compiled.ext is not None, sd.backends.compiled.FAILURE
    assert configure.resolve_backend('auto') == 'compiled'
    assert configure.resolve_backend('compiled') == 'compiled'
    assert configure.resolve_backend('numpy') == 'numpy'
    with pytest.raises(ConfigError, match="parameter backend: 'fast'"):
        configure.resolve_backend('fast')
    monkeypatch.setattr(sd.backends.compiled, 'ext', None)     # a build without a compiler
    for setting in ('auto', 'compiled', 'numpy'):
        assert configure.resolve_backend(setting) == 'numpy'


def test_a_model_load_computes_once_and_times_nothing(demo_text, monkeypatch):
    """One inverse-dynamics call proves the model computes; no call is timed at load.

    What an answer costs is measured on the answers themselves (``compute time`` of the
    ``feedforward`` status), so the ``robot model`` status carries no load-time figure.
    """
    calls = []
    rnea = sd.rnea
    monkeypatch.setattr(sd, 'rnea', lambda *a, **k: calls.append(a) or rnea(*a, **k))
    robot = configure.prepare({}, defaults(robot_description=demo_text), None).robot
    assert len(calls) == 1
    np.testing.assert_array_equal(calls[0][1], np.zeros(len(robot.joints)))   # at rest
    assert not hasattr(config, 'plain_call_seconds')


@pytest.mark.parametrize('setting', ['auto', 'compiled'])
def test_the_first_output_runs_compiled(demo_text, setting):
    """No preparation, no switch: the output the node starts with is on the compiled kernels."""
    robot = configure.prepare({}, defaults(robot_description=demo_text, backend=setting),
                              None).robot
    assert (robot.backend, robot.setting) == ('compiled', setting)
    assert diagnostics.backend_text(robot).startswith('compiled (C extension, ')
    q = np.linspace(-1.0, 1.0, len(robot.joints))
    np.testing.assert_allclose(sd.rnea(robot.model, q, q, q, backend=robot.backend),
                               sd.rnea(robot.model, q, q, q, backend='numpy'),
                               rtol=1e-12, atol=1e-12)


def test_numpy_runs_numpy(demo_text):
    robot = configure.prepare({}, defaults(robot_description=demo_text, backend='numpy'),
                              None).robot
    assert (robot.backend, robot.setting) == ('numpy', 'numpy')
    assert diagnostics.backend_text(robot) == 'numpy'


def test_without_the_kernels_the_text_says_why(demo_text, monkeypatch):
    monkeypatch.setattr(sd.backends.compiled, 'ext', None)
    monkeypatch.setattr(sd.backends.compiled, 'FAILURE', 'no module (test)')
    robot = configure.prepare({}, defaults(robot_description=demo_text, backend='auto'),
                              None).robot
    assert robot.backend == 'numpy'
    assert diagnostics.backend_text(robot) == \
        'numpy (compiled kernels unavailable: no module (test))'


# --------------------------------------------------------------------------------------------
# The topic's description parser

def test_parser_keeps_only_the_newest_waiting_request_and_reports_errors():
    started, release = threading.Event(), threading.Event()
    notified = []
    built = []

    def build(request):
        started.set()
        release.wait(10.0)
        built.append(request.generation)
        if request.urdf == 'bad':
            raise ConfigError('topic robot_description: bad')
        if request.urdf == 'crash':
            raise RuntimeError('boom')
        return request.urdf

    parser = descriptions.DescriptionParser(build, lambda: notified.append(1))
    parser.submit(descriptions.ParseRequest(1, 'first', {}, None))
    assert started.wait(60.0)
    for generation, urdf in ((2, 'dropped'), (3, 'bad'), (4, 'crash')):
        parser.submit(descriptions.ParseRequest(generation, urdf, {}, None))
    release.set()
    deadline = time.monotonic() + 60.0   # generous: ends as soon as both are in
    results = []
    while len(results) < 2 and time.monotonic() < deadline:
        results += parser.finished()
        time.sleep(0.01)
    parser.stop()
    assert [r.generation for r, _ in results] == [1, 4] and built == [1, 4]
    assert results[0][1] == 'first'
    assert isinstance(results[1][1], ConfigError) and 'boom' in str(results[1][1])
    assert len(notified) == 2


# --------------------------------------------------------------------------------------------
# Counters and diagnostics

def test_model_status_levels_and_the_backend(demo_text):
    totals = diagnostics.Totals()
    level, message, values = diagnostics.model_status(None, totals, False, '')
    assert (level, message) == ('ERROR', 'waiting for robot_description')
    totals.description_rejected('bad XML')
    robot = configure.prepare({}, defaults(robot_description=demo_text, backend='numpy'),
                              None).robot
    level, message, values = diagnostics.model_status(robot, totals, False, 'numpy')
    kv = dict(values)
    assert level == 'OK' and message == "robot 'demo_arm' loaded, 8 DOF"
    assert kv['backend'] == 'numpy' and kv['backend setting'] == 'numpy'
    assert not [key for key in kv if 'time' in key]   # timings are the answers' (feedforward)
    assert kv['descriptions rejected'] == '1' and kv['last rejection'] == 'bad XML'
    assert kv['model joints'] == ', '.join(robot.model.joint_names)


def test_model_status_of_a_floating_robot_counts_its_joints_and_the_free_flyer():
    """Solo12 floating: 12 joints and the free-flyer, nv 18 (Pinocchio's), never "13 DOF"."""
    pin = pytest.importorskip('pinocchio')
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from conftest import robot_urdf_path
    path = robot_urdf_path('solo12')
    oracle = pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer())
    joints = oracle.njoints - 2               # the universe and the free-flyer aside
    with open(path, encoding='utf-8') as f:
        text = f.read()
    robot = configure.prepare({}, defaults(robot_description=text, base='floating', **{
        'contacts.links': ['FL_FOOT', 'FR_FOOT', 'HL_FOOT', 'HR_FOOT']}), None).robot
    level, message, values = diagnostics.model_status(robot, diagnostics.Totals(), False,
                                                      'numpy')
    expected = f'{joints} joints + free-flyer (nv {oracle.nv})'
    assert message == f'robot {oracle.name!r} loaded, {expected}', message
    assert dict(values)['dof'] == expected


def test_feedforward_status_rates_staleness_and_rejections(demo_text):
    robot = configure.prepare({}, defaults(robot_description=demo_text), None).robot
    totals, window = diagnostics.Totals(), diagnostics.Window()
    settings = config.PARAMETERS.defaults()
    now = window.start_ns + 2_000_000_000                 # a 2 s period
    assert diagnostics.feedforward_status(robot, window, totals, settings, {}, now)[:2] == \
        ('WARN', 'no input received yet')
    assert diagnostics.feedforward_status(None, window, totals, settings, {}, now)[0] == 'ERROR'
    window.received, window.answered = 10, 8
    window.compute_ns, window.compute_max_ns = 8 * 30_000, 50_000
    totals.answered, totals.last_input_ns = 8, now - 100_000_000
    totals.rejected['missing_joint'] += 2
    level, message, values = diagnostics.feedforward_status(
        robot, window, totals, settings, {'hand': (np.ones(6), now + 1), 'old': (None, now - 1)},
        now)
    kv = dict(values)
    assert (level, message) == ('WARN', '4.0 Hz, 2 rejected')
    assert kv['input rate [Hz]'] == '5.0' and kv['compute time mean [us]'] == '30.0'
    assert kv['compute time max [us]'] == '50.0' and kv['stale'] == 'False'
    assert kv['rejected'] == '2' and kv['rejected missing_joint'] == '2'
    assert kv['external wrenches active'] == 'hand'
    totals.last_input_ns = now - int(1e9)                # older than input_timeout 0.5 s
    level, message, values = diagnostics.feedforward_status(robot, window, totals, settings,
                                                            {}, now)
    assert level == 'ERROR' and message.startswith('input stale') and dict(values)['stale'] \
        == 'True'
