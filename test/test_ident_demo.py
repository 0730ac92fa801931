# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The proof of identification on a simulated UR5 whose URDF is wrong (tools.identify_demo).

MuJoCo simulates the true robot (links 20-30 % off, centres of mass moved, a 1.5 kg payload,
drive friction and armature); the user's PD + feed-forward on the original URDF tracks a
motion; ``replay`` fits the bag and writes the corrected URDF. Checked: (a) on a held-out
motion the corrected model is as good as the true robot's own model on the same recording
(what the recording allows) where the URDF is tens of times worse; (b) a payload alone comes
back within 1 %; (c) the closed loop with the corrected URDF tracks far better; (d) a
recording of two joints only is flagged and its fit is not trusted on other motion.
"""

import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(__file__))
from conftest import robot_urdf_path  # noqa: E402

pytest.importorskip('mujoco')
pytest.importorskip('rosbags')
pytest.importorskip('scipy')

pytestmark = pytest.mark.slow     # the whole demonstration: minutes on 2 cores


@pytest.fixture(scope='module')
def figures(tmp_path_factory):
    """Run the whole demonstration once (12 s of training motion)."""
    from spatial_dynamics.tools.identify_demo import prove
    return prove('ur5', robot_urdf_path('ur5'), 12.0, str(tmp_path_factory.mktemp('proof')))


def test_held_out_torque_is_predicted_as_well_as_the_true_model_does(figures):
    """(a) Corrected within 25 % of the true model's own residual; the URDF 10x worse."""
    corrected = np.array(figures['held_out_corrected'])
    true = np.array(figures['held_out_true'])
    urdf = np.array(figures['held_out_urdf'])
    assert (corrected <= 1.25 * true).all(), (corrected, true)
    assert (true < 6 * figures['noise']).all(), true      # the recording is not garbage
    assert (urdf > 10 * true).sum() >= 5, (urdf, true)
    assert figures['warnings_on_training'] == 0


def test_the_payload_comes_back(figures):
    """(b) 1.5 kg on tool0, found from the recording against the URDF without it."""
    assert figures['payload_identified'] == pytest.approx(figures['payload_true'], rel=0.01)


def test_the_corrected_urdf_tracks_better_in_closed_loop(figures):
    """(c) PD + feed-forward and computed torque on the true robot: ten times less error."""
    for law in ('pd_feedforward', 'computed_torque'):
        urdf = np.array(figures['tracking_rms'][f'{law}/urdf'])
        corrected = np.array(figures['tracking_rms'][f'{law}/corrected'])
        assert np.sqrt(np.mean(corrected ** 2)) < 0.1 * np.sqrt(np.mean(urdf ** 2)), law


def test_a_poorly_exciting_recording_is_flagged(figures):
    """(d) The two base joints alone: a warning naming parameters, and a fit not to trust."""
    assert figures['poor_warning'].startswith('warning: the recording does not determine')
    assert ' of ' in figures['poor_warning']          # names like 'mc_x of wrist_1_link'
    assert max(figures['poor_held_out_corrected']) > 5 * max(figures['held_out_true'])
