# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""What the identification prints and writes is what the recording tells, and nothing more.

A parameter no torque depends on reads undetermined (σ infinite, the URDF's value); the node
parameters printed with ``--inertias --identify`` and the URDF written reproduce the joint
fit's residual; a joint the recording never moves keeps the URDF's ``<dynamics>``; a fitted
body that is no link (mass at the fit's floor, centre of mass far outside the robot) is not
written; a fit stopped at its evaluation limit says so.
"""

import csv
import os
import re
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(__file__))
from conftest import robot_urdf_path  # noqa: E402
from test_ident_correction import EPS, motion, record  # noqa: E402
from test_ident_correction import robot_bags as robot_bags_fixture  # noqa: E402

robot_bags = robot_bags_fixture
from test_ident_inertias import perturbed_ur5  # noqa: E402

import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics import identification  # noqa: E402
from spatial_dynamics.algorithms.regressor import parameters  # noqa: E402
from spatial_dynamics.identification import identify_inertias, random_states  # noqa: E402
from spatial_dynamics.replay import correction as correction_of  # noqa: E402
from spatial_dynamics.replay.__main__ import main, parser  # noqa: E402
from spatial_dynamics.recordings.recording import Stages  # noqa: E402
from spatial_dynamics.replay.residual import recording  # noqa: E402

pytest.importorskip('scipy')
pytest.importorskip('rosbags')

PANDA_ARM = [f'panda_joint{k}' for k in range(1, 8)]


def test_a_parameter_no_torque_depends_on_reads_undetermined(capsys):
    """Panda: link2's mass and m·c_z load no joint (its origin is on both axes before it).

    Their regressor columns are zero but for rounding; they must come out undetermined with
    an infinite σ and the URDF's value, in the fit, in parameters.csv's rows and on the
    console, never as 'x ± 0' determined.
    """
    model = sd.Model.from_urdf(robot_urdf_path('panda'), joints=PANDA_ARM)
    q, qd, qdd = random_states(model, 1000, seed=2)
    Y = sd.regressor(model, q, qd, qdd)
    pi0 = parameters(model)
    tau = Y @ (1.2 * pi0) + np.random.default_rng(0).normal(0.0, 0.05, q.shape)
    fit = identify_inertias(model, q, qd, qdd, tau)
    names = identification.parameter_names(model)
    for name in ('m of panda_link2', 'mc_z of panda_link2', 'm of panda_link1'):
        k = names.index(name)
        assert fit.unexcited[k], name
        assert fit.undetermined[k] == 1.0, name
        assert fit.sigma[k] == np.inf, name
    # everything a torque depends on keeps a finite, positive σ
    felt = ~fit.unexcited
    assert np.isfinite(fit.sigma[felt]).all() and (fit.sigma[felt] > 0).all()
    correction = correction_of.from_inertias(model, fit, EPS)
    rows = {(r[0], r[1]): r for r in correction.parameter_rows()}
    for p in ('m', 'mc_z'):
        link, parameter, urdf, identified, sigma, undetermined = rows[('panda_link2', p)]
        assert identified == urdf and sigma == np.inf and undetermined == 1.0
    correction_of.print_inertias(correction)
    table = capsys.readouterr().out
    line = next(t for t in table.splitlines() if t.strip().startswith('panda_link2'))
    assert f'{pi0[10]:.4g} undetermined' in line, line
    assert not re.search(r'± 0(?![.\d])', table), table


def joint_block(text):
    """Return the armature of the '# node parameters' block."""
    block = text.split('# node parameters')[1]
    return np.array([float(x) for x in block.split('armature: [')[1].split(']')[0].split(',')])


def test_the_pasted_node_parameters_and_urdf_reproduce_the_fit(robot_bags, tmp_path, capsys):
    """--inertias --identify: the written URDF with the printed armature is the fit.

    Loaded as the node loads it (friction_model: urdf, the armature printed), it predicts the
    recording's torque with the RMS the fit reports (validation.csv's train_corrected).
    """
    model, true, train, held, _ = robot_bags
    out, urdf = str(tmp_path / 'out'), str(tmp_path / 'corrected.urdf')
    assert main(['identify', train, '--urdf', robot_urdf_path('ur5'), '--out', out,
                 '--inertias', '--drives', '--threshold', str(EPS), '--write-urdf', urdf,
                 '--no-plots', '--residual', 'none']) == 0
    text = capsys.readouterr().out
    armature = joint_block(text)
    written = sd.Model.from_urdf(urdf)
    data = recording(parser().parse_args(['residual', train, '--urdf', urdf]), train, written,
                     Stages())
    q, qd, qdd = data['q'], data['qd'], data['qdd']
    tau = (sd.rnea(written, q, qd, qdd) + sd.friction_torque(written, qd, EPS)
           + armature * qdd)
    pasted = np.sqrt(np.mean((data['effort'] - tau) ** 2, axis=0))
    with open(os.path.join(out, 'validation.csv')) as f:
        fit = np.array([float(r['train_corrected']) for r in csv.DictReader(f)])
    np.testing.assert_allclose(pasted, fit, rtol=1e-3)
    # the URDF's dynamics printed are the written ones
    for j, name in enumerate(written.joint_names):
        assert (f'<!-- joint {name} --> <dynamics damping="{written.damping[j]:.6g}" '
                f'friction="{written.friction[j]:.6g}"/>') in text


def ur5_with_dynamics(path, joint, damping, friction):
    """Write the UR5 with ``joint``'s <dynamics> set; return its path."""
    text = open(robot_urdf_path('ur5'), encoding='utf-8').read()
    head, tail = text.split(f'<joint name="{joint}"', 1)
    tail = re.sub(r'<dynamics [^>]*/>', f'<dynamics damping="{damping}" friction="{friction}"/>',
                  tail, count=1)
    with open(path, 'w', encoding='utf-8') as f:
        f.write(head + f'<joint name="{joint}"' + tail)
    return str(path)


@pytest.mark.parametrize('fit', [[], ['--inertias', '--drives']])
def test_a_joint_never_moved_keeps_the_urdf_dynamics(fit, robot_bags, tmp_path, capsys):
    """wrist_3 held still: its damping, friction and armature are undetermined, not 0."""
    model, true, *_ = robot_bags
    urdf = ur5_with_dynamics(tmp_path / 'ur5.urdf', 'wrist_3_joint', 0.7, 1.5)
    bag = record(tmp_path / 'still', true, *motion(model.nq, 7, only=(0, 1, 2, 3, 4)),
                 seed=16)
    out, written = str(tmp_path / 'out'), str(tmp_path / 'corrected.urdf')
    assert main(['identify', bag, '--urdf', urdf, '--out', out, *fit, '--threshold', str(EPS),
                 '--write-urdf', written, '--no-plots', '--residual', 'none']) == 0
    text = capsys.readouterr().out
    again = sd.Model.from_urdf(written)
    j = again.joint_names.index('wrist_3_joint')
    assert (again.damping[j], again.friction[j]) == (0.7, 1.5)
    assert again.damping[j - 1] != 0.7                # the moving joints' are the fit's
    node = text.split('# node parameters')[1].split('<!--')[0]
    assert re.search(r'# armature undetermined .*wrist_3_joint', node), node
    assert 'joint wrist_3_joint: damping and friction undetermined' in text
    row = next(t for t in text.splitlines() if t.strip().startswith('wrist_3_joint'))
    assert row.count('undetermined') == 3, row
    with open(os.path.join(out, 'parameters.csv')) as f:
        rows = [r for r in csv.DictReader(f) if r['link'] == 'wrist_3_joint']
    assert {r['parameter']: (r['identified'], r['sigma'], r['undetermined']) for r in rows} == {
        'damping': ('0.7', 'inf', '1'), 'friction': ('1.5', 'inf', '1'),
        'armature': ('0', 'inf', '1')}


def test_a_link_the_fit_did_not_find_is_not_written(tmp_path):
    """Mass at the fit's floor, or a centre of mass 1.6 km away: refused, the URDF's kept."""
    model = sd.Model.from_urdf(robot_urdf_path('ur5'))
    text = open(robot_urdf_path('ur5'), 'rb').read()
    body = model.frames['forearm_link'].body
    for mass, com in ((1e-9, (20.0, -1595.0, 0.07)), (2.0, (20.0, -1595.0, 0.07)),
                      (1e-9, (0.0, 0.0, 0.2))):
        wrong = sd.model.rigid_body_inertia('x', mass, com, 1e-3 * np.eye(3))
        fine = 1.1 * model.inertia[body + 1]
        correction = correction_of.Correction(model, {body: wrong, body + 1: fine})
        path = str(tmp_path / 'out.urdf')
        notes = correction.write_urdf(text, path)
        assert any("'forearm_link' not written" in n for n in notes), notes
        again = sd.Model.from_urdf(path)
        np.testing.assert_array_equal(again.inertia[body], model.inertia[body])
        np.testing.assert_allclose(again.inertia[body + 1], fine, atol=1e-12)


def test_a_fit_stopped_at_its_limit_says_so(monkeypatch):
    """The fit's evaluation limit reached: converged False, with the number and why."""
    model, true = perturbed_ur5()
    q, qd, qdd = random_states(model, 1500, seed=2)
    tau = sd.rnea(true, q, qd, qdd) + np.random.default_rng(3).normal(0.0, 0.05, q.shape)
    assert identify_inertias(model, q, qd, qdd, tau).converged
    monkeypatch.setattr(identification, 'EVALUATIONS', 1)
    stopped = identify_inertias(model, q, qd, qdd, tau)
    assert not stopped.converged and stopped.evaluations == 1 and stopped.message


def test_a_bag_of_nan_efforts_is_refused_saying_so(robot_bags, tmp_path, capsys):
    """Efforts all NaN: the refusal says NaN, not only 'empty'."""
    from spatial_dynamics.recordings import bags
    model = robot_bags[0]
    t, q, qd, qdd = motion(model.nq, 8, seconds=1.0)
    t_ns = (1_700_000_000 * 10 ** 9 + np.arange(len(t)) * 2_000_000).astype(np.int64)
    block = bags.encode_joint_states(model.joint_names, t_ns, q, qd, np.full(q.shape, np.nan))
    bag = str(tmp_path / 'nan')
    bags.write_bag(bag, 'sqlite3', [('/joint_states', bags.JOINT_STATE, t_ns,
                                     [r.tobytes() for r in block])])
    assert main(['residual', bag, '--urdf', robot_urdf_path('ur5'), '--out',
                 str(tmp_path / 'o'), '--no-plots']) == 1
    err = capsys.readouterr().err
    assert 'JointState.effort is empty or NaN in every message' in err, err


def test_a_value_is_printed_with_the_digits_its_sigma_allows():
    """The payload's mass line: to σ's second significant digit, never more."""
    from spatial_dynamics.replay.identify import to_sigma
    assert to_sigma(1.498765, 0.0123) == '1.499'
    assert to_sigma(1.498765, 2.3) == '1.5'
    assert to_sigma(1234.5, 45.0) == '1234'
