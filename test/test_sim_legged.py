# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The proofs on the simulator: Solo12 and Talos standing in MuJoCo, swaying their trunk.

``python -m spatial_dynamics.tools.legged`` (2 s of sway here). Three things hold:

* Newton: the floor's total force in MuJoCo is ``m (a_com - g)``, the rate of the robot's
  linear momentum (our ``generalized_momentum`` of MuJoCo's state) over each 1 ms step. It is
  exact in MuJoCo's discrete dynamics but for the change of ``M`` within a step (O(h²));
  measured 3.6e-4 N of 24.5 N (Solo12) and 2.3e-3 N of 886 N (Talos): required 1e-3 m g,
  whatever the soft contacts do. And against the QP's total, ``m (a_com,d - g)`` of the plan:
  measured 0.27 % and 0.63 % of m g (the robot is where the plan is to a few mm): required 1 %.
* The vertical force at each foot, MuJoCo's against our QP's: each leg's Jacobian is square,
  so the joint torques decide the forces; they differ by what the PD adds to the
  feed-forward and by the soft floor. Measured RMS 0.25 % / max 0.7 % of a foot's mean load
  (Solo12), 1.5 % / 2.8 % (Talos, stiffer PD): required 1 % / 3 % and 3 % / 6 %.
* Tracking: the contact feed-forward + low-gain PD tracks the joints far better than the same
  PD alone: measured 86× (Solo12, 3 s) and 28× (Talos, whose PD alone lets it fall):
  required 30× and 10×.
"""

import os

import pytest

pytest.importorskip('mujoco')
pytest.importorskip('clarabel')
pytestmark = pytest.mark.slow      # ~35 s of MuJoCo: the whole suite runs it, the fast loop not


def run(robot, capsys):
    """Run the tool; check that it said what it was doing as it went (stderr)."""
    from spatial_dynamics.tools.legged import LAWS, main, robots_dir, ROBOTS
    if not os.path.isfile(os.path.join(robots_dir(), ROBOTS[robot]().path)):
        pytest.skip('example-robot-data is not installed')
    out = main(['--robot', robot, '--seconds', '2'])
    progress = capsys.readouterr().err
    assert progress.startswith('planning 2 s of sway'), progress
    for k, law in enumerate(LAWS, 1):
        assert f'[{k}/{len(LAWS)}] {law}: simulating 2.5 s' in progress, progress
        assert f'[{k}/{len(LAWS)}] {law}: done in ' in progress, progress
    return out


def check(out, rms, worst, ratio):
    assert out['total_force_vs_newton_max_N'] < 1e-3 * out['weight_N']
    assert out['total_force_vs_qp_max_N'] < 0.01 * out['weight_N']
    assert out['foot_vertical_force_rms_relative'] < rms
    assert out['foot_vertical_force_max_relative'] < worst
    assert out['ratio_pd_to_feedforward'] > ratio


def test_solo12_sways_on_four_feet_with_the_contact_forces_of_the_qp(capsys):
    check(run('solo12', capsys), 0.01, 0.03, 30.0)


def test_talos_sways_on_two_soles_with_the_contact_forces_of_the_qp(capsys):
    check(run('talos', capsys), 0.03, 0.06, 10.0)
