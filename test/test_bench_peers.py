# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The benchmark's machinery: reference, peer adaptors (joint order, mimic, continuous), output.

The mpmath reference is cross-checked against Pinocchio to 1e-12 here and in every bench run.
Peers are only checked when importable.
"""

import csv
import os

from conftest import PinOracle, robot_urdf_path
import numpy as np
import pytest
import spatial_dynamics as sd
from benchmarks import bench
from spatial_dynamics.tools.driving import demo_urdf

TINY = bench.Settings(ref_states=2, rounds=1, rounds_big=1, block_s=0.0005, states=4,
                      sizes=(1, 10))


def demo_arm():
    path = demo_urdf()
    if not os.path.isfile(path):
        pytest.skip('config/demo_arm.urdf not found')
    return path


@pytest.mark.parametrize('robot', ['panda', 'ur5', 'demo_arm'])
def test_mpmath_reference_matches_pinocchio(robot):
    """Our RNEA in mpmath (50 digits) on our float64 parameters vs Pinocchio: ≤ 1e-12 N m."""
    path = demo_arm() if robot == 'demo_arm' else robot_urdf_path(robot)
    model = sd.Model.from_urdf(str(path))
    Q, QD, QDD = bench.random_states(model, np.random.default_rng(4), 4)
    ref = bench.reference(model, Q, QD, QDD).astype(float)
    tau_pin = PinOracle(str(path)).rnea(model.joint_names, Q, QD, QDD)
    assert np.abs(ref - tau_pin).max() <= 1e-12
    assert np.abs(ref - sd.rnea(model, Q, QD, QDD)).max() <= 1e-12


def test_pinocchio_parameters_reference_is_close_to_ours():
    """The reference on Pinocchio's float64 parameters differs from ours by their rounding."""
    mpmath = pytest.importorskip('mpmath')
    robot = bench.load_robot('chain30')
    Q, QD, QDD = bench.random_states(robot.model, np.random.default_rng(5), 2)
    ref = bench.reference(robot.model, Q, QD, QDD)
    ref_pin = bench.reference(bench.pinocchio_reference_rows(robot, mpmath), Q, QD, QDD)
    assert float(np.abs(ref - ref_pin).max()) <= 1e-13 * float(np.abs(ref).max())


@pytest.mark.parametrize('name', ['panda', 'demo_arm', 'chain7', 'tree40'])
def test_every_implementation_agrees_with_the_reference(name):
    """Each entry's joint mapping is right: float64 ones at rounding level, float32 at 1e-5."""
    try:
        robot = bench.load_robot(name)
    except bench.Skip as err:
        pytest.skip(str(err))
    rows, check = bench.bench_robot(robot, bench.implementations(), TINY, lambda msg: None)
    by_name = {r['implementation']: r for r in rows}
    assert 'ours float64' in by_name and 'ours longdouble' in by_name
    limit = {'ours float32': 1e-5, 'ours longdouble': 1e-17, 'pybullet': 1e-9}
    for r in rows:
        assert r['rel_err'] <= limit.get(r['implementation'], 1e-13), r
        for key in ('single_us', 'n1_us', 'n10_us'):
            assert key not in r or r[key] > 0.0
        if 'pinocchio' in by_name and 'single_us' in r:
            assert r['single_vs_pin'] == pytest.approx(
                r['single_us'] / by_name['pinocchio']['single_us'])
    if 'pinocchio' in by_name:
        assert check['ref_vs_pin'] <= 1e-12
        assert check['pin_own_err'] <= 1e-13


def test_pybullet_is_left_out_where_it_models_another_robot():
    pytest.importorskip('pybullet')
    with pytest.raises(bench.Skip, match='DOF'):
        bench._pybullet_single(bench.load_robot('chain300'))
    demo_arm()
    robot = bench.load_robot('demo_arm')
    with pytest.raises(bench.Skip, match='inertial'):
        bench._pybullet_single(robot)


def test_command_line_writes_results(tmp_path, capsys):
    code = bench.main(['--quick', '--robots', 'chain7', 'nosuchrobot', '--impls',
                       'ours float64', 'pinocchio', '--out', str(tmp_path)])
    assert code == 0
    out = capsys.readouterr().out
    assert '| chain7 (7) | ours float64 |' in out
    with open(tmp_path / 'results.csv', encoding='utf-8') as fh:
        rows = list(csv.DictReader(fh))
    assert {r['implementation'] for r in rows} >= {'ours float64'}
    assert all(float(r['n10000_us']) > 0.0 for r in rows)
    pytest.importorskip('matplotlib')
    assert (tmp_path / 'runtime_vs_error.png').stat().st_size > 0
    assert (tmp_path / 'scaling.png').stat().st_size > 0


def test_terms_table_compares_each_term_with_pinocchio():
    """The benchmark's g, C q̇ + g and M rows state agreement with Pinocchio to ~1e-15."""
    table = bench.terms_table(['ur5', 'panda'], rounds=1)
    rows = [line.split('|')[1:-1] for line in table.splitlines()[2:]]
    assert [(r[0].strip(), r[1].strip()) for r in rows] == [
        (robot, term) for robot in ('ur5 (6 dof)', 'panda (8 dof)')
        for term in ('g(q)', 'C q̇ + g', 'M(q)')]
    for row in rows:
        assert float(row[5]) < 1e-13, row


def test_regressor_table_times_each_implementation_beside_rnea():
    """One row per backend and the 6×6 specification (and Pinocchio's, when importable)."""
    table = bench.regressor_table(['ur5'], rounds=1, N=50)
    rows = [[c.strip() for c in line.split('|')[1:-1]] for line in table.splitlines()[2:]]
    labels = [r[1] for r in rows]
    assert labels[0] == 'sd.regressor, numpy' and '6×6 specification' in labels
    assert all(r[0] == 'ur5 (6 dof)' for r in rows)
    for r in rows[:labels.index('6×6 specification') + 1]:
        assert float(r[2]) > 0 and float(r[3]) > 0 and r[5].endswith('×')
