# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The compiled batch entries check their sizes without overflow.

``N x n`` numbers in bytes wrapped around for N = 2⁶⁰ + 1 (8 · 6 · (2⁶⁰ + 1) is 48 modulo
2⁶⁴: one state's buffer passed the check, and the kernels ran over 2⁶⁰ states of it). Every
count an entry multiplies (states, joints, bodies, the regressor's columns) is checked
against overflow: a size no buffer can have is a ValueError, a negative N too, and a table
whose sizes would overflow is refused. Each check runs in a child process, so that a crash
fails the test instead of ending pytest.
"""

import os
import subprocess
import sys

import pytest
from spatial_dynamics.backends import compiled

pytestmark = pytest.mark.skipif(compiled.ext is None, reason='the batch entries are C')

HERE = os.path.dirname(os.path.abspath(__file__))
HUGE = [2 ** 60 + 1, 2 ** 61 + 3, 2 ** 62 // 3 + 1, (2 ** 63 - 1) // 8 + 1, 2 ** 63 - 1,
        (2 ** 64 + 47) // 48]


def run_child(what):
    """Run ``what`` in a child process; fail with its output when it fails or crashes."""
    code = ('import sys; sys.path.insert(0, %r); import faulthandler; faulthandler.enable(); '
            'import test_compiled_batch_sizes as t; %s' % (HERE, what))
    done = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, (done.returncode, done.stdout[-3000:], done.stderr[-6000:])
    assert 'checked' in done.stdout


def check_the_batch_entries(urdf):
    """Call every batch entry with one state's buffers and a huge or negative N."""
    import numpy as np
    import pytest
    import spatial_dynamics as sd
    from spatial_dynamics.backends import layout
    ext = compiled.ext
    model = sd.Model.from_urdf(urdf)
    lay = layout.of(model)
    n, rows, k = model.nq, lay.table.shape[0], lay.kernels
    one = np.zeros((1, n))
    g = (0.0, 0.0, -9.81)
    entries = {
        'rnea_batch': lambda N, fext=None: ext.rnea_batch(k, N, one, one, one, g, fext,
                                                          np.empty((1, n)), 2),
        'mass_matrix_batch': lambda N: ext.mass_matrix_batch(k, N, one, np.empty((1, n, n)), 2),
        'momentum_batch': lambda N: ext.momentum_batch(k, N, one, one, np.empty((1, n)),
                                                       np.empty((1, n)), 2),
        'regressor_batch': lambda N: ext.regressor_batch(
            k, N, one, one, one, g, np.empty((1, n, 10 * (rows - 1))), 2),
    }
    checked = 0
    for name, entry in entries.items():
        entry(1)                                    # the sizes of one state: fine
        for N in HUGE + [-1, -2 ** 62]:
            with pytest.raises(ValueError, match='must hold|N must be'):
                entry(N)
            checked += 1
        with pytest.raises(OverflowError):
            entry(2 ** 64)
    # external forces: shared (rows x 6) or per state (N x rows x 6)
    shared = np.zeros((rows, 6))
    entries['rnea_batch'](1, shared)
    for N in HUGE:
        with pytest.raises(ValueError):
            entries['rnea_batch'](N, shared)
        checked += 1
    print('checked', checked)


TWO_JOINTS = """<robot name="two">
  <link name="base"/>
  <link name="a"><inertial><mass value="2"/>
    <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.3"/></inertial></link>
  <link name="b"><inertial><mass value="1"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.03"/></inertial></link>
  <link name="c"><inertial><mass value="1"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.03"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/>
    <axis xyz="0 1 0"/><limit effort="10" velocity="1" lower="-3" upper="3"/></joint>
  <joint name="j2" type="revolute"><parent link="a"/><child link="b"/>
    <axis xyz="1 0 0"/><limit effort="10" velocity="1" lower="-3" upper="3"/></joint>
  <joint name="j3" type="revolute"><parent link="b"/><child link="c"/>
    <axis xyz="1 0 0"/><limit effort="10" velocity="1" lower="-3" upper="3"/>
    <mimic joint="j2" multiplier="2"/></joint>
</robot>"""


def test_a_huge_batch_size_is_refused_not_run():
    run_child(f't.check_the_batch_entries({TWO_JOINTS!r})')


def test_a_huge_batch_size_of_a_model_without_joints_is_refused_or_empty():
    """Without joints no buffer bounds N, and there is nothing to compute."""
    run_child('t.check_a_model_without_joints()')


def check_a_model_without_joints():
    import numpy as np
    import pytest
    import spatial_dynamics as sd
    from spatial_dynamics.backends import layout
    ext = compiled.ext
    model = sd.Model.from_urdf('<robot name="one"><link name="base"/></robot>')
    k = layout.of(model).kernels
    none = np.zeros((1, 0))
    for N in (0, 1, 5, 2 ** 40, 2 ** 50):          # no numbers in or out: returns at once
        ext.rnea_batch(k, N, none, none, none, (0.0, 0.0, -9.81), None, none, 2)
        ext.mass_matrix_batch(k, N, none, none, 2)
    for N in HUGE + [-1]:                           # more states than a count can hold
        with pytest.raises(ValueError, match='N must be'):
            ext.rnea_batch(k, N, none, none, none, (0.0, 0.0, -9.81), None, none, 2)
    # and through the public function: a batch of 2**40 states of no joints
    huge = np.broadcast_to(np.zeros((1, 0)), (2 ** 40, 0))
    assert sd.rnea(model, huge, huge, huge, backend='compiled').shape == (2 ** 40, 0)
    print('checked')


def test_a_table_with_more_joints_than_bodies_is_refused():
    """A joint per body at most bounds n: n x n and n x 10 NB then fit."""
    import numpy as np
    ext = compiled.ext
    from spatial_dynamics.backends import layout
    table = np.zeros((1, layout.WIDTH))
    table[0, layout.COLUMN['qidx']] = 5.0           # 5 joints, but no body to move them
    with pytest.raises(ValueError, match='not a tree'):
        ext.Kernels(table)
