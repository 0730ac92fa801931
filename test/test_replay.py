# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The replay command on bags written with rosbags: identification, bad bags, exit codes.

The recording comes from MuJoCo (sim.SimulatedRobot, UR5) tracking sinusoids with a PD law
and a feed-forward: known damping and armature in MuJoCo, and a Coulomb friction
``friction·tanh(q̇/ε)`` (the node's model) subtracted from the applied torque each step;
the bag's effort is the drive torque plus Gaussian noise, its velocity has noise too.
"""

import csv
import os
import subprocess
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(__file__))
from conftest import robot_urdf_path  # noqa: E402

import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics.recordings import bags  # noqa: E402
from spatial_dynamics.replay.__main__ import main  # noqa: E402

pytest.importorskip('rosbags')
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DAMPING = np.array([2.0, 3.0, 1.5, 0.8, 0.5, 0.3])
FRICTION = np.array([3.0, 4.0, 2.0, 1.0, 0.6, 0.4])
ARMATURE = np.array([0.4, 0.5, 0.3, 0.1, 0.08, 0.05])
EPS = 0.01                 # the friction threshold (the node's default)
NOISE_TAU = 0.05           # N m, effort noise
NOISE_QD = 1e-3            # rad/s, velocity noise
RATE = 1000.0
DURATION = 12.0
# The drive's torque is held over a physics step (zero-order hold): at 1 kHz that is a
# half-sample delay between the recorded torque and the state's acceleration, a residual of
# about |dτ/dt|·0.5 ms (0.2 N m on the shoulder here). The simulated controller runs at
# SUBSTEPS x RATE so that what is left is the measurement noise.
SUBSTEPS = 10


@pytest.fixture(scope='module')
def recording():
    """Simulate the UR5 for DURATION s at RATE; return (urdf, names, t_ns, q, qd, effort)."""
    robot_mod = pytest.importorskip('spatial_dynamics.sim.robot')
    pytest.importorskip('mujoco')
    urdf = robot_urdf_path('ur5')
    robot = robot_mod.SimulatedRobot(urdf, timestep=1.0 / (SUBSTEPS * RATE), damping=DAMPING,
                                     armature=ARMATURE)
    model = robot.model
    n = model.nq
    k = np.arange(n)
    amp, freq = 0.6 / (1 + 0.2 * k), 0.3 + 0.17 * k       # rad, Hz: a different one per joint

    def ref(t):
        w = 2 * np.pi * freq
        s1, c1 = np.sin(w * t), np.cos(w * t)
        s3, c3 = np.sin(3.1 * w * t), np.cos(3.1 * w * t)
        q = amp * (s1 + 0.3 * s3)
        qd = amp * w * (c1 + 0.93 * c3)
        qdd = -amp * w * w * (s1 + 0.3 * 9.61 * s3)
        return q, qd, qdd

    q0, qd0, _ = ref(0.0)
    robot.set_state(q0, qd0)
    N = int(DURATION * RATE)
    rng = np.random.default_rng(7)
    Q, QD, TAU = np.empty((N, n)), np.empty((N, n)), np.empty((N, n))
    kp, kd = 400.0, 40.0
    for i in range(N * SUBSTEPS):
        t = i / (RATE * SUBSTEPS)
        qr, qdr, qddr = ref(t)
        q, qd = robot.q, robot.qd
        qdd_cmd = qddr + kp * (qr - q) + kd * (qdr - qd)
        tau = (sd.rnea(model, q, qd, qdd_cmd) + ARMATURE * qdd_cmd + DAMPING * qd
               + FRICTION * np.tanh(qd / EPS))
        if i % SUBSTEPS == 0:
            Q[i // SUBSTEPS], QD[i // SUBSTEPS], TAU[i // SUBSTEPS] = q, qd, tau
        robot.step(tau - FRICTION * np.tanh(qd / EPS))
    t_ns = (1_700_000_000 * 10 ** 9 + np.arange(N) * int(1e9 / RATE)).astype(np.int64)
    effort = TAU + rng.normal(0.0, NOISE_TAU, TAU.shape)
    return urdf, model.joint_names, t_ns, Q, QD + rng.normal(0.0, NOISE_QD, QD.shape), effort


def write(path, names, t_ns, q, qd, effort, storage='sqlite3', extra=()):
    """Write a /joint_states bag (and extra topics) with rosbags."""
    block = bags.encode_joint_states(names, t_ns, q, qd, effort)
    bags.write_bag(str(path), storage, [('/joint_states', bags.JOINT_STATE, t_ns,
                                         [r.tobytes() for r in block])] + list(extra))
    return str(path)


def summary(out):
    """Read summary.csv as {joint: {column: value}}."""
    with open(os.path.join(out, 'summary.csv')) as f:
        return {r['joint']: {k: (v if k == 'joint' else float(v)) for k, v in r.items()}
                for r in csv.DictReader(f)}


@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
def test_identification_recovers_the_simulated_drive(recording, tmp_path, storage, capsys):
    urdf, names, t_ns, q, qd, effort = recording
    bag = write(tmp_path / 'bag', names, t_ns, q, qd, effort, storage)
    out = str(tmp_path / 'out')
    # A 0.1 s window (cut-off ~12 Hz; the motion is below 4 Hz): the velocity noise, through
    # the derivative and the inertia, then adds little to the effort noise.
    assert main(['identify', bag, '--urdf', urdf, '--out', out, '--no-plots',
                 '--window', '0.1']) == 0
    text = capsys.readouterr().out
    s = summary(out)
    for j, name in enumerate(names):
        row = s[name]
        assert row['samples'] == len(t_ns)
        assert row['damping'] == pytest.approx(DAMPING[j], rel=0.05), name
        assert row['friction'] == pytest.approx(FRICTION[j], rel=0.05), name
        assert row['armature'] == pytest.approx(ARMATURE[j], rel=0.05), name
        # the residual before is the drive's torque; after, the noise is what is left
        assert row['rms_residual'] > 5 * NOISE_TAU
        assert row['rms_residual_identified'] < 1.5 * NOISE_TAU, name
    assert 'friction_model: "urdf"' in text and '<dynamics damping=' in text
    residual = np.loadtxt(os.path.join(out, 'residual.csv'), delimiter=',', skiprows=1)
    assert residual.shape == (len(t_ns), 1 + len(names))
    assert residual[1, 0] == pytest.approx(1.0 / RATE)


@pytest.mark.parametrize('interleave', [True, False])
def test_fast_reader_equals_rosbags_deserialiser(tmp_path, interleave):
    """Mixed layouts in one topic: the numpy path and rosbags' agree to the bit.

    Interleaved (runs of a message or two) and in runs of one layout (whole blocks: names
    in another order, a subset, an extra joint).
    """
    rng = np.random.default_rng(3)
    names = ['a', 'b', 'c']
    parts = []
    t0 = 10 ** 18
    for k, (cols, fields, frame) in enumerate([
            ([0, 1, 2], (True, True, True), ''), ([2, 0], (True, False, True), 'base'),
            ([0, 1, 2], (True, True, False), 'x' * 5), (['b', 'a', 'c', 'd'], None, '')]):
        m = 50 + 7 * k
        t = t0 + k * 10 ** 9 + np.arange(m) * 10 ** 6
        if fields is None:       # other joint names, an extra one
            blk = bags.encode_joint_states(cols, t, *(rng.standard_normal((m, 4))
                                                      for _ in range(3)))
        else:
            arrays = [rng.standard_normal((m, len(cols))) if f else None for f in fields]
            blk = bags.encode_joint_states([names[c] for c in cols], t, *arrays,
                                           frame_id=frame)
        parts += [(int(ti), r.tobytes()) for ti, r in zip(t, blk)]
    order = rng.permutation(len(parts)) if interleave else np.arange(len(parts))
    times = np.array([parts[i][0] for i in order])
    raw = [parts[i][1] for i in order]
    raw[5] = raw[5][:-3]                          # a truncated message
    fast = bags.joint_states_from_raw(raw, times, names)
    slow = bags.joint_states_from_raw(raw, times, names, fast=False)
    assert fast.fast > 0 and slow.fast == 0
    for f in ('stamp', 'position', 'velocity', 'effort'):
        assert np.array_equal(getattr(fast, f), getattr(slow, f), equal_nan=True), f
    assert fast.skipped == slow.skipped and sum(fast.skipped.values()) == 1
    assert bags.verify_layout(raw[0] if len(raw[0]) % 8 else raw[1])


def test_fast_and_generic_bag_readers_agree(recording, tmp_path):
    urdf, names, t_ns, q, qd, effort = recording
    m = 3000
    for storage in ('sqlite3', 'mcap'):
        bag = write(tmp_path / storage, names, t_ns[:m], q[:m], qd[:m], effort[:m], storage)
        fast = bags.read_joint_states(bag, '/joint_states', names)
        slow = bags.read_joint_states(bag, '/joint_states', names, fast=False)
        assert fast.fast == m and slow.generic == m
        for f in ('stamp', 'position', 'velocity', 'effort'):
            assert np.array_equal(getattr(fast, f), getattr(slow, f)), (storage, f)
        assert np.array_equal(fast.position, q[:m])


def test_a_damaged_bag_is_reported_not_a_crash(recording, tmp_path, capsys):
    """Missing joints, NaN, out-of-order stamps: skipped with the reason, exit 0."""
    urdf, names, t_ns, q, qd, effort = recording
    m = 4000
    t_ns, q, qd, effort = t_ns[:m].copy(), q[:m].copy(), qd[:m].copy(), effort[:m].copy()
    q[100, 2] = np.nan
    effort[200:203, 4] = np.nan
    t_ns[[300, 301]] = t_ns[[301, 300]]                       # out of order
    short = bags.encode_joint_states(names[:-1], t_ns[400:410], q[400:410, :-1],
                                     qd[400:410, :-1], effort[400:410, :-1])
    full = bags.encode_joint_states(names, t_ns, q, qd, effort)
    raw = [r.tobytes() for r in full]
    raw[400:410] = [r.tobytes() for r in short]               # a joint missing
    bag = str(tmp_path / 'bag')
    bags.write_bag(bag, 'mcap', [('/joint_states', bags.JOINT_STATE, t_ns, raw)])
    out = str(tmp_path / 'out')
    assert main(['residual', bag, '--urdf', urdf, '--out', out, '--no-plots']) == 0
    text = capsys.readouterr().out
    assert f"1 sample(s): '{names[2]}': no finite position" in text
    assert f"3 sample(s): '{names[4]}': no finite effort" in text
    assert f"10 sample(s): '{names[-1]}': no finite position" in text
    assert '1 stamp(s) earlier than the one before' in text
    assert summary(out)[names[0]]['samples'] == m - 14


def test_refusals_exit_1_with_the_reason(recording, tmp_path, capsys):
    urdf, names, t_ns, q, qd, effort = recording
    m = 500
    bag = write(tmp_path / 'bag', names, t_ns[:m], q[:m], qd[:m], effort[:m])
    out = str(tmp_path / 'out')
    assert main(['residual', bag, '--urdf', urdf, '--topic', '/nope', '--out', out]) == 1
    err = capsys.readouterr().err
    assert "topic '/nope' is not in the bag" in err and '/joint_states' in err
    assert main(['residual', str(tmp_path / 'missing'), '--urdf', urdf, '--out', out]) == 1
    assert 'no such bag' in capsys.readouterr().err
    no_effort = str(tmp_path / 'no_effort')
    blk = bags.encode_joint_states(names, t_ns[:m], q[:m], qd[:m], None)
    bags.write_bag(no_effort, 'sqlite3', [('/joint_states', bags.JOINT_STATE, t_ns[:m],
                                           [r.tobytes() for r in blk])])
    assert main(['residual', no_effort, '--urdf', urdf, '--out', out]) == 1
    assert 'no measured effort' in capsys.readouterr().err
    # a joint the bag never has
    demo = os.path.join(ROOT, 'config', 'demo_arm.urdf')
    assert main(['residual', bag, '--urdf', demo, '--out', out]) == 1
    assert 'never have a position' in capsys.readouterr().err
    with pytest.raises(SystemExit) as usage:
        main(['residual', '--urdf', urdf])
    assert usage.value.code == 2


def test_help_works_without_rclpy(tmp_path):
    """The command never imports rclpy: --help works with rclpy unimportable."""
    blocker = tmp_path / 'rclpy'
    blocker.mkdir()
    (blocker / '__init__.py').write_text('raise ImportError("rclpy blocked")\n')
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path), ROOT]))
    code = ('import sys, runpy; sys.argv = ["replay", "--help"]\n'
            'try:\n    runpy.run_module("spatial_dynamics.replay", run_name="__main__")\n'
            'except SystemExit as e:\n    assert e.code == 0\n'
            'assert "rclpy" not in sys.modules or sys.modules["rclpy"] is None\n')
    r = subprocess.run([sys.executable, '-c', code], env=env, capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 0, r.stderr
    assert 'Exit status' in r.stdout


def test_node_parameters_are_doubles_the_node_accepts():
    """The printed YAML holds doubles: a ROS double[] parameter refuses ``[0, 0]``."""
    import yaml
    from spatial_dynamics.replay.report import node_parameters
    text = node_parameters(['a', 'b', 'c'], np.array([0.0, -1e-5, 0.25]), 1.0)
    params = yaml.safe_load(text)['inverse_dynamics']['ros__parameters']
    assert params['armature'] == [0.0, 0.0, 0.25]
    assert all(type(x) is float for x in params['armature'])
    assert type(params['friction_velocity_threshold']) is float
    assert params['joints'] == ['a', 'b', 'c']


def test_plots_and_residual_file_are_written(recording, tmp_path):
    """The plots (drawn in a forked child) and one residual row per sample."""
    urdf, names, t_ns, q, qd, effort = recording
    m = 2000
    bag = write(tmp_path / 'bag', names, t_ns[:m], q[:m], qd[:m], effort[:m], 'mcap')
    out = str(tmp_path / 'out')
    assert main(['residual', bag, '--urdf', urdf, '--out', out]) == 0
    for name in ('measured_vs_model.png', 'residual.png'):
        with open(os.path.join(out, name), 'rb') as f:
            assert f.read(8) == b'\x89PNG\r\n\x1a\n', name
    with open(os.path.join(out, 'residual.csv')) as f:
        rows = list(csv.reader(f))
    assert rows[0] == ['t'] + list(names)
    assert len(rows) == 1 + m
    assert float(rows[1][0]) == 0.0


def test_a_payload_is_identified_from_a_bag_with_the_drives(tmp_path, capsys):
    """With --payload tool0 --identify: 1.2 kg on the UR5's tool0, drives with friction.

    The bag holds a smooth motion of every joint (positions and velocities as a driver
    records them, 500 Hz) and the torques of the robot with the payload plus each drive's
    damping, Coulomb friction and armature and 0.05 N m of noise; the fit is against the URDF
    without the payload, jointly with the drives.
    """
    model = sd.Model.from_urdf(robot_urdf_path('ur5'))
    n = model.nq
    rate, seconds = 500.0, 20.0
    t = np.arange(int(rate * seconds)) / rate
    k = np.arange(n)
    amp, freq = 1.0 / (1 + 0.15 * k), 0.21 + 0.13 * k
    w = 2 * np.pi * freq
    q = amp * (np.sin(w * t[:, None]) + 0.4 * np.sin(2.3 * w * t[:, None]))
    qd = amp * w * (np.cos(w * t[:, None]) + 0.92 * np.cos(2.3 * w * t[:, None]))
    qdd = -amp * w * w * (np.sin(w * t[:, None]) + 0.4 * 5.29 * np.sin(2.3 * w * t[:, None]))
    heavy = sd.with_payload(model, 'tool0', 1.2, (0.0, 0.03, 0.06),
                            (0.003, 0.0, 0.0, 0.003, 0.0, 0.002))
    damping, friction, armature = 0.5 + 0.1 * k, 1.0 + 0.2 * k, 0.05 + 0.01 * k
    tau = (sd.rnea(heavy, q, qd, qdd) + damping * qd + friction * np.tanh(qd / EPS)
           + armature * qdd)
    effort = tau + np.random.default_rng(2).normal(0.0, 0.05, tau.shape)
    t_ns = (1_700_000_000 * 10 ** 9 + np.arange(len(t)) * int(1e9 / rate)).astype(np.int64)
    bag = write(tmp_path / 'bag', model.joint_names, t_ns, q, qd, effort)
    out = str(tmp_path / 'out')
    assert main(['identify', bag, '--urdf', robot_urdf_path('ur5'), '--out', out, '--payload',
                 'tool0', '--drives', '--threshold', str(EPS), '--no-plots']) == 0
    text = capsys.readouterr().out
    mass = float(text.split('payload.mass: ')[1].split()[0])
    com = [float(x) for x in text.split('payload.com: [')[1].split(']')[0].split(',')]
    assert mass == pytest.approx(1.2, rel=0.02), text
    np.testing.assert_allclose(com, (0.0, 0.03, 0.06), rtol=0, atol=3e-3)
    assert "payload on 'tool0'" in text and '<mass value=' in text
    assert 'fitted jointly with each drive' in text
