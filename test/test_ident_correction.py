# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""From a recording to a corrected URDF: ``replay --inertias/--payload --validate --write-urdf``.

The "true" robot is the UR5 of example-robot-data with every body 25 % heavier and its
centres of mass moved by ~1 cm, driven through joints with damping, Coulomb friction and
armature; its torques (plus 0.05 N m of noise) are recorded in bags along two different
motions, one to fit and one held out. The URDF given to the command is the original one.
"""

import csv
import os
import re
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(__file__))
from conftest import robot_urdf_path  # noqa: E402
from test_ident_inertias import perturbed_ur5  # noqa: E402

import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics.model import rigid_body_inertia  # noqa: E402
from spatial_dynamics.replay.__main__ import main  # noqa: E402
from spatial_dynamics.replay.urdf_writer import corrected_urdf  # noqa: E402

pytest.importorskip('rosbags')
pytest.importorskip('scipy')
from spatial_dynamics.recordings import bags  # noqa: E402

NOISE = 0.05
EPS = 0.01
RATE = 500.0


def drives(n):
    """Return each joint's damping, Coulomb friction and armature of the true robot."""
    k = np.arange(n)
    return 0.5 + 0.1 * k, 1.0 + 0.2 * k, 0.05 + 0.01 * k


def motion(n, seed, seconds=12.0, only=()):
    """Return t, q, q̇, q̈ of two sines per joint (random amplitudes and frequencies)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(RATE * seconds)) / RATE
    amp = rng.uniform(0.6, 1.2, n)
    w1, w2 = 2 * np.pi * rng.uniform(0.15, 0.5, n), 2 * np.pi * rng.uniform(1.5, 2.7, n)
    if only != ():
        amp = np.where(np.isin(np.arange(n), only), amp, 0.0)
    T = t[:, None]
    q = amp * (np.sin(w1 * T) + 0.3 * np.sin(w2 * T))
    qd = amp * (w1 * np.cos(w1 * T) + 0.3 * w2 * np.cos(w2 * T))
    qdd = -amp * (w1 ** 2 * np.sin(w1 * T) + 0.3 * w2 ** 2 * np.sin(w2 * T))
    return t, q, qd, qdd


def true_torque(true, q, qd, qdd):
    """Return the true robot's joint torque: rigid body and drives."""
    damping, friction, armature = drives(true.nq)
    return (sd.rnea(true, q, qd, qdd) + damping * qd + friction * np.tanh(qd / EPS)
            + armature * qdd)


def record(path, true, t, q, qd, qdd, seed):
    """Write a /joint_states bag of the true robot's torque plus noise; return its path."""
    effort = true_torque(true, q, qd, qdd) + np.random.default_rng(seed).normal(
        0.0, NOISE, q.shape)
    t_ns = (1_700_000_000 * 10 ** 9 + np.arange(len(t)) * int(1e9 / RATE)).astype(np.int64)
    block = bags.encode_joint_states(true.joint_names, t_ns, q, qd, effort)
    bags.write_bag(str(path), 'sqlite3', [('/joint_states', bags.JOINT_STATE, t_ns,
                                           [r.tobytes() for r in block])])
    return str(path)


@pytest.fixture(scope='module')
def robot_bags(tmp_path_factory):
    """Return (model, true, training bag, held-out bag, held-out states)."""
    model, true = perturbed_ur5()
    where = tmp_path_factory.mktemp('bags')
    train = record(where / 'train', true, *motion(model.nq, 1), seed=11)
    held_states = motion(model.nq, 2)
    held = record(where / 'held', true, *held_states, seed=12)
    return model, true, train, held, held_states


def read_csv(path):
    """Read a CSV written by the command as {first column: {column: float}}."""
    with open(path) as f:
        rows = list(csv.DictReader(f))
    key = next(iter(rows[0]))
    return {r[key]: {k: float(v) for k, v in r.items() if k != key} for r in rows}


@pytest.mark.slow
def test_a_corrected_urdf_predicts_held_out_motion(robot_bags, tmp_path, capsys):
    """--inertias --identify --validate --write-urdf: the written URDF is the robot.

    The held-out residual drops from the URDF's (several N m) to the noise, and the
    corrected file, loaded as is, with its <dynamics> (the node's friction_model: urdf) and
    the armature printed, gives the true torques on the held-out motion within 2x the noise.
    """
    model, true, train, held, (t, q, qd, qdd) = robot_bags
    out, urdf = str(tmp_path / 'out'), str(tmp_path / 'corrected.urdf')
    assert main(['identify', train, '--urdf', robot_urdf_path('ur5'), '--out', out,
                 '--inertias', '--drives', '--threshold', str(EPS), '--validate', held,
                 '--write-urdf', urdf, '--no-plots']) == 0
    text, err = capsys.readouterr()
    assert 'warning' not in err, err
    v = read_csv(os.path.join(out, 'validation.csv'))
    for joint, row in v.items():
        assert row['held_out_corrected'] < 2 * NOISE, (joint, row)
        assert row['train_corrected'] < 2 * NOISE, (joint, row)
    assert sum(row['held_out_urdf'] > 20 * NOISE for row in v.values()) >= 5, v
    corrected = sd.Model.from_urdf(urdf)
    assert not corrected.warnings
    # the node's block: the armature fitted jointly with the inertias
    block = text.split('# node parameters')[1].split('armature: [')[1].split(']')[0]
    armature = [float(x) for x in block.split(',')]
    predicted = (sd.rnea(corrected, q, qd, qdd) + sd.friction_torque(corrected, qd, EPS)
                 + np.array(armature) * qdd)
    error = np.sqrt(np.mean((predicted - true_torque(true, q, qd, qdd)) ** 2, axis=0))
    assert (error < 2 * NOISE).all(), error
    params = list(csv.DictReader(open(os.path.join(out, 'parameters.csv'))))
    assert len(params) == 10 * model.NB + 3 * model.nq     # every body's ten, each drive's 3
    assert all(float(r['sigma']) >= 0.0 for r in params)


def test_two_recordings_fit_together(robot_bags, tmp_path, capsys):
    """--also: a recording of joints 1-2 and one of joints 3-6, each poor alone, fit as one.

    Alone, the first is flagged and misses the held-out motion; together (every joint moved,
    in one or the other) nothing is flagged and the held-out residual is the noise.
    """
    model, true, train, held, _ = robot_bags
    first = record(tmp_path / 'first', true, *motion(model.nq, 5, only=(0, 1)), seed=14)
    second = record(tmp_path / 'second', true, *motion(model.nq, 6, only=(2, 3, 4, 5)),
                    seed=15)
    urdf = robot_urdf_path('ur5')
    out = str(tmp_path / 'alone')
    assert main(['identify', first, '--urdf', urdf, '--out', out, '--inertias', '--drives',
                 '--threshold', str(EPS), '--validate', held, '--no-plots']) == 0
    assert 'warning: the recording does not determine' in capsys.readouterr().err
    alone = read_csv(os.path.join(out, 'validation.csv'))
    assert max(r['held_out_corrected'] for r in alone.values()) > 10 * NOISE
    out = str(tmp_path / 'both')
    assert main(['identify', first, '--also', second, '--urdf', urdf, '--out', out,
                 '--inertias', '--drives', '--threshold', str(EPS), '--validate', held,
                 '--no-plots']) == 0
    text, err = capsys.readouterr()
    assert 'fitted on' in text and 'warning' not in err, err
    both = read_csv(os.path.join(out, 'validation.csv'))
    assert max(r['held_out_corrected'] for r in both.values()) < 2 * NOISE, both


def test_a_poorly_exciting_recording_is_named_not_trusted(robot_bags, tmp_path, capsys):
    """Only the first joint moves: the warning names what the recording cannot tell.

    The fit still matches its own recording (it is a fit), but not the held-out motion:
    the numbers it cannot determine stay near the URDF's instead of being made up, and the
    user is told which combinations those are.
    """
    model, true, train, held, _ = robot_bags
    poor = record(tmp_path / 'poor', true, *motion(model.nq, 3, only=0), seed=13)
    out = str(tmp_path / 'out')
    assert main(['identify', poor, '--urdf', robot_urdf_path('ur5'), '--out', out, '--inertias',
                 '--validate', held, '--no-plots']) == 0
    text, err = capsys.readouterr()
    assert 'warning: the recording does not determine' in err
    assert 'wrist_3_link' in err and 'replay excite' in err
    v = read_csv(os.path.join(out, 'validation.csv'))
    assert max(row['held_out_corrected'] for row in v.values()) > 20 * NOISE


def test_a_payload_goes_into_the_urdf(tmp_path, capsys):
    """--payload tool0 --write-urdf: the link's <inertial> gains the payload, nothing else."""
    model = sd.Model.from_urdf(robot_urdf_path('ur5'))
    heavy = sd.with_payload(model, 'tool0', 1.5, (0.0, 0.02, 0.05),
                            (0.004, 0.0, 0.0, 0.003, 0.0, 0.002))
    t, q, qd, qdd = motion(model.nq, 4, seconds=10.0)
    tau = sd.rnea(heavy, q, qd, qdd) + np.random.default_rng(5).normal(0.0, NOISE, q.shape)
    t_ns = (1_700_000_000 * 10 ** 9 + np.arange(len(t)) * int(1e9 / RATE)).astype(np.int64)
    block = bags.encode_joint_states(model.joint_names, t_ns, q, qd, tau)
    bag = str(tmp_path / 'bag')
    bags.write_bag(bag, 'sqlite3', [('/joint_states', bags.JOINT_STATE, t_ns,
                                     [r.tobytes() for r in block])])
    urdf = str(tmp_path / 'with_payload.urdf')
    assert main(['identify', bag, '--urdf', robot_urdf_path('ur5'), '--out',
                 str(tmp_path / 'out'), '--payload', 'tool0', '--write-urdf', urdf,
                 '--no-plots']) == 0
    corrected = sd.Model.from_urdf(urdf)
    b = model.frames['tool0'].body
    np.testing.assert_allclose(corrected.inertia[b], heavy.inertia[b], rtol=0, atol=0.02)
    for i in range(1, model.NB + 1):
        if i != b:
            np.testing.assert_array_equal(corrected.inertia[i], model.inertia[i])
    err = np.sqrt(np.mean((sd.rnea(corrected, q, qd, qdd) - sd.rnea(heavy, q, qd, qdd)) ** 2,
                          axis=0))
    assert (err < NOISE).all(), err


def strip(text):
    """Remove comments, <inertial> elements and <dynamics/> tags (what the writer may replace)."""
    text = re.sub(rb'<!--.*?-->', b'', text, flags=re.S)
    text = re.sub(rb'\s*<inertial>.*?</inertial>', b'', text, flags=re.S)
    return re.sub(rb'\s*<dynamics[^>]*/>', b'', text)


@pytest.mark.parametrize('robot, link', [('ur5', 'tool0'), ('panda', 'panda_hand')])
def test_the_writer_changes_only_the_identified_elements(robot, link):
    """Bodies 20 % heavier, a payload, one joint's dynamics: reloaded exactly, rest as is."""
    path = robot_urdf_path(robot)
    text = open(path, 'rb').read()
    model = sd.Model.from_urdf(path)
    bodies = {i: 1.2 * model.inertia[i] for i in range(1, model.NB + 1)}
    payload = rigid_body_inertia('payload', 1.5, (0.0, 0.02, 0.05), np.diag([1e-3, 2e-3, 3e-3]))
    joint = model.joint_names[0]
    out, notes = corrected_urdf(text, model, bodies, {link: payload}, {joint: (0.5, 1.25)})
    assert notes == []
    assert strip(out) == strip(text)
    again = sd.Model.from_urdf(out.decode())
    expected = np.array(model.inertia)
    for i, value in bodies.items():
        expected[i] = value
    frame = model.frames[link]
    expected[frame.body] += frame.lXb.T @ payload @ frame.lXb
    np.testing.assert_allclose(again.inertia, expected, rtol=1e-10, atol=1e-12)
    assert again.damping[0] == 0.5 and again.friction[0] == 1.25
    np.testing.assert_array_equal(again.damping[1:], model.damping[1:])


HANDWRITTEN = b'''<?xml version="1.0"?>
<!-- a comment with <inertial> in it -->
<robot name="r">
  <link name="base"/>
  <link name="arm">
      <visual><geometry><box size="1 2 3"/></geometry></visual>
  </link>
  <link name="tip"><inertial><mass value="2.0"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1"
     iyz="0" izz="0.1"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="10" velocity="1"/></joint>
  <joint name="fix" type="fixed"><parent link="arm"/><child link="tip"/>
    <origin xyz="0.5 0 0"/></joint>
</robot>
'''


def test_elements_are_inserted_and_a_body_too_light_for_its_fixed_links_is_merged():
    """A link without <inertial> gets one; a joint without <dynamics> too (nothing else moves).

    The body of 'arm' is arm + tip; identified lighter than tip alone, 'arm' cannot hold the
    difference, so the whole body goes into 'arm' and tip's <inertial> is removed (a note).
    """
    model = sd.Model.from_urdf(HANDWRITTEN.decode())
    light = rigid_body_inertia('x', 1.0, (0.4, 0.0, 0.0), np.diag([0.05, 0.2, 0.2]))
    out, notes = corrected_urdf(HANDWRITTEN, model, {1: light}, None, {'j1': (0.1, 0.2)})
    assert len(notes) == 1 and "'tip'" in notes[0]
    again = sd.Model.from_urdf(out.decode())
    np.testing.assert_allclose(again.inertia[1], light, atol=1e-12)
    assert again.damping[0] == 0.1 and again.friction[0] == 0.2
    assert strip(out).replace(b'\n', b'').replace(b' ', b'') == \
        strip(HANDWRITTEN).replace(b'\n', b'').replace(b' ', b'')
    assert b'<!-- a comment with <inertial> in it -->' in out
    heavier = 1.5 * model.inertia[1]             # realisable as arm + tip: tip is kept
    out, notes = corrected_urdf(HANDWRITTEN, model, {1: heavier})
    assert notes == [] and b'<link name="tip"><inertial><mass value="2.0"/>' in out
    np.testing.assert_allclose(sd.Model.from_urdf(out.decode()).inertia[1], heavier,
                               atol=1e-12)


def test_usage_errors_are_one_line(robot_bags, tmp_path, capsys):
    """What cannot work is refused before the bag is read: exit 2 (usage) or 1, one line."""
    model, true, train, held, _ = robot_bags
    urdf = robot_urdf_path('ur5')
    out = str(tmp_path / 'o')
    for argv, status, words in (
            (['residual', train, '--validate', held], 2, 'unrecognized arguments'),
            (['residual', train, '--also', held], 2, 'unrecognized arguments'),
            (['residual', train, '--write-urdf', str(tmp_path / 'x.urdf')], 2,
             'unrecognized arguments'),
            (['identify', train, '--inertias', '--payload', 'tool0'], 2, 'not allowed with'),
            (['identify', train, '--inertias', 'no_such_link'], 1,
             "'no_such_link' is not a link"),
            (['identify', train, '--inertias', '--validate', str(tmp_path / 'nothing')], 1,
             'nothing')):
        with pytest.raises(SystemExit) if status == 2 else _no_exit() as caught:
            assert main(argv + ['--urdf', urdf, '--out', out, '--no-plots']) == status
        if status == 2:
            assert caught.value.code == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert words in err[-1], err
        assert not any('Traceback' in line for line in err)


class _no_exit:
    """A context manager that expects no exception."""

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False
