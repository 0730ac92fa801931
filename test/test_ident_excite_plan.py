# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""``replay excite`` judges the plan it writes, as the controller interpolates the file.

What it claims (the limits kept, the base parameters determined, the condition number) is
computed from the text read back and interpolated like joint_trajectory_controller's
splines, not from the Fourier series it meant to write; every number of that text reads
back as the float meant, to its seven digits; every period of the plan is the first.
"""

import contextlib
import io
import math
import re

from conftest import robot_urdf_path
import numpy as np
import pytest
import spatial_dynamics as sd
from spatial_dynamics.excitation import Excitation, excitation, POINTS_PER_CYCLE
from spatial_dynamics.files import load_yaml
from spatial_dynamics.replay import excite, splines
from spatial_dynamics.trajectory import evaluate, sample, Trajectory

WRISTS = ['wrist_1_joint', 'wrist_2_joint', 'wrist_3_joint']
#: A quick plan of the UR5's wrists: 3 periods of 2 s, 2 harmonics, 5 Hz.
QUICK = dict(period=2.0, count=3, harmonics=2, rate=5.0, iterations=8, seed=4)


def run_quick(path, **change):
    """Plan the UR5's wrists with :data:`QUICK` (changed); return (status, stdout, stderr)."""
    o = dict(QUICK, **change)
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = excite.main(['--urdf', robot_urdf_path('ur5'), '--joints', *WRISTS,
                              '--duration', f'{o["period"] * o["count"]:g}',
                              '--period', f'{o["period"]:g}', '--harmonics', str(o['harmonics']),
                              '--rate', f'{o["rate"]:g}', '--iterations', str(o['iterations']),
                              '--seed', str(o['seed']), '--out', str(path)])
    return status, out.getvalue(), err.getvalue()


@pytest.mark.parametrize('x', [5e-05, 1e-300, 1e+20, -0.0, 0.0, 3.0, -2.5e-07, 1 / 3,
                               123456789.0, 6.02214076e23, -1e-5, 5e-324])
def test_every_number_written_reads_back_as_that_float(x):
    """YAML 1.1 reads 5e-05 as a string: the writer's numbers read back as the float meant."""
    text = excite._number(x)
    value = load_yaml(f'[{text}]', 'number')[0]
    assert type(value) is float, (text, value)
    assert value == float(f'{x:.7g}'), (text, value)
    assert math.copysign(1.0, value) == math.copysign(1.0, x)      # -0.0 stays -0.0


def test_a_written_plan_reads_back_as_meant_to_the_digit(tmp_path):
    """The whole file, read by replay's reader, equals the plan's points at 7 digits."""
    path = tmp_path / 'plan.yaml'
    status, out, err = run_quick(path)
    assert status == 0, err
    model = sd.Model.from_urdf(robot_urdf_path('ur5'), joints=WRISTS)
    plan = excitation(model, QUICK['period'], QUICK['harmonics'], seed=QUICK['seed'],
                      maxiter=QUICK['iterations'])
    points = plan.to_points(QUICK['rate'], QUICK['count'])
    traj = splines.from_yaml(str(path))
    assert traj.joint_names == tuple(WRISTS) and len(traj.time) == len(points) == 31
    for field, got in (('positions', traj.positions), ('velocities', traj.velocities),
                       ('accelerations', traj.accelerations)):
        meant = np.array([[float(f'{x:.7g}') for x in p[field]] for p in points])
        np.testing.assert_array_equal(got, meant, err_msg=field)
    ns = [p['time_from_start']['sec'] * 10 ** 9 + p['time_from_start']['nanosec']
          for p in points]
    assert ns == [200_000_000 * k for k in range(31)]
    np.testing.assert_array_equal(traj.time, [k // 5 + k % 5 * 200_000_000 * 1e-9
                                              for k in range(31)])


def test_every_period_of_the_plan_is_the_first(tmp_path):
    """Sampled whole at 1 kHz as the controller interpolates it: the first period, repeated.

    So the check of one period is the check of all (the 1 kHz check of a long plan is
    bounded by its period, not its duration).
    """
    path = tmp_path / 'plan.yaml'
    status, out, err = run_quick(path, period=2.1, rate=4.3)    # 10 points a period of 2.1 s
    assert status == 0, err
    traj = splines.from_yaml(str(path))
    assert len(traj.time) == 31
    t, q, qd, qdd = sample(traj, 1000.0)
    one = t <= 2.1 + 1e-9
    first = evaluate(traj, t[one])
    for k in (1, 2):
        again = evaluate(traj, t[one] + 2.1 * k)
        for a, b in zip(first, again):
            np.testing.assert_allclose(b, a, rtol=0, atol=1e-9)
    assert 'one period of 2.1 s (all 3 are the same)' in out


def test_a_plan_whose_points_alias_its_series_is_not_written(tmp_path, monkeypatch):
    """Points one a period (as --period 0.1 at 10 Hz once wrote): judged on the file, exit 1.

    The series determines every base parameter of the wrists; the points, interpolated,
    stand still: the plan determines what gravity alone at one pose does, and says so.
    """
    def aliased(self, rate, periods=1):
        q = self.evaluate(0.0)[0][0].tolist()
        zero = [0.0] * len(q)
        period_ns = round(self.period * 1e9)
        return [{'positions': q, 'velocities': zero, 'accelerations': zero,
                 'time_from_start': {'sec': k * period_ns // 10 ** 9,
                                     'nanosec': k * period_ns % 10 ** 9}}
                for k in range(periods + 1)]

    monkeypatch.setattr(Excitation, 'to_points', aliased)
    path = tmp_path / 'plan.yaml'
    status, out, err = run_quick(path)
    assert status == 1, out
    series = int(re.search(r'the series determines (\d+) of the', out).group(1))
    written = int(re.search(r'the plan determines (\d+) of the', out).group(1))
    assert written < series, out
    assert f'error: the plan determines {written} base parameters, its series {series}' in err
    assert 'not written' in err and 'Traceback' not in err
    assert not path.exists()


def test_a_plan_that_exceeds_a_limit_is_not_written(tmp_path, monkeypatch):
    """A plan whose splines overshoot the URDF's velocity limit: the tables say so, exit 1."""
    def doubled(self, rate, periods=1):
        points = real(self, rate, periods)
        return [dict(p, positions=p['positions'], velocities=[3 * v for v in p['velocities']])
                for p in points]

    real = Excitation.to_points
    monkeypatch.setattr(Excitation, 'to_points', doubled)
    path = tmp_path / 'plan.yaml'
    status, out, err = run_quick(path)
    assert status == 1 and 'TOO FAST' in out, out
    assert 'error: the plan exceeds a limit of the URDF' in err and 'not written' in err
    assert not path.exists()


def test_at_the_lowest_rate_the_plan_determines_what_its_series_does(tmp_path):
    """4 points a cycle of the highest harmonic: the same parameters, the same condition."""
    path = tmp_path / 'plan.yaml'
    status, out, err = run_quick(path, rate=POINTS_PER_CYCLE * QUICK['harmonics']
                                 / QUICK['period'])
    assert status == 0, err
    m = re.search(r'the plan determines (\d+) of the (\d+) base parameters any motion can '
                  r'\(the series: (\d+)\); condition number ([0-9.e+]+) \(the series: '
                  r'([0-9.e+]+)\)', out)
    assert m, out
    written, possible, series = (int(m.group(k)) for k in (1, 2, 3))
    assert written == series == possible, out
    assert float(m.group(4)) == pytest.approx(float(m.group(5)), rel=0.02)


def test_controller_splines_follow_a_sinusoid_at_four_points_a_cycle():
    """The bound POINTS_PER_CYCLE stands on: quintics through exact q, q̇, q̈ of sin(2πt)."""
    w = 2 * np.pi
    t = np.arange(0, 5 * POINTS_PER_CYCLE + 1) / POINTS_PER_CYCLE
    traj = Trajectory(('j',), t, np.sin(w * t)[:, None], (w * np.cos(w * t))[:, None],
                      (-w * w * np.sin(w * t))[:, None])
    ts = np.linspace(0.0, 5.0, 50001)
    q, qd, qdd = (x[:, 0] for x in evaluate(traj, ts))
    assert np.abs(q - np.sin(w * ts)).max() < 2.3e-4
    assert np.abs(qd / w - np.cos(w * ts)).max() < 5e-4
    assert np.abs(qdd / w ** 2 + np.sin(w * ts)).max() < 2.2e-3


def test_the_iteration_limit_reads_as_the_best_found(tmp_path):
    """Stopping at --iterations is not a failure: the output says what it is, plainly."""
    path = tmp_path / 'plan.yaml'
    status, out, err = run_quick(path, iterations=2)
    assert status == 0, err
    assert 'the best found within 2 iterations' in out, out
    assert 'Iteration limit reached' not in out
    assert 'converged' in run_quick(path, iterations=400)[1]


def test_the_printed_commands_survive_the_shell(tmp_path):
    """An --out with a space and a $: the printed goals, run by bash, are the YAML meant."""
    import shutil
    import subprocess
    if shutil.which('bash') is None:
        pytest.skip('bash is needed to run the printed command')
    path = tmp_path / 'my plan $HOME.yaml'
    status, out, err = run_quick(path)
    assert status == 0, err
    prefix = 'ros2 action send_goal /joint_trajectory_controller/follow_joint_trajectory ' \
             'control_msgs/action/FollowJointTrajectory '
    goals = [line.strip()[len(prefix):] for line in out.splitlines()
             if line.strip().startswith(prefix)]
    assert len(goals) == 2, out
    said = [subprocess.run(['bash', '-c', f"printf '%s' {goal}"], cwd=tmp_path, check=True,
                           capture_output=True, text=True).stdout for goal in goals]
    start = load_yaml(said[0], 'start goal')['trajectory']
    assert start['joint_names'] == WRISTS and len(start['points']) == 1
    assert said[1] == '{trajectory: ' + path.read_text().rstrip('\n') + '}'
    plan = load_yaml(said[1], 'plan goal')['trajectory']
    assert plan['points'][0]['positions'] == start['points'][0]['positions']
