# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Loading and checking a description stays linear in the number of links.

Linearity is asserted by counting, not timing: the Python lines executed by ``Model.from_urdf`` and
by the ``spatial_dynamics_check`` report (a deterministic count, whatever the machine's load) grow
at most a little faster than the number of links, from n to 4n links, on plain chains, chains of
mimic joints (each mimicking the one before) and chains of fixed links lumped into one body. A
20,000-link chain is also checked end to end by the command, with a timeout as a hang guard only.
"""

import os
import subprocess
import sys

import numpy as np
import pytest

import spatial_dynamics as sd
from spatial_dynamics import check

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def chain(n: int, kind: str = 'plain') -> bytes:
    """Return a chain of ``n`` links after the base: revolute joints, mimics or fixed ones."""
    inertial = ('<inertial><mass value="1.0"/><origin xyz="0 0 0.05"/><inertia ixx="0.01" '
                'ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>')
    parts = [f'<robot name="chain{n}"><link name="l0"/>']
    for i in range(1, n + 1):
        parts.append(f'<link name="l{i}">{inertial}</link>')
        jtype = 'fixed' if kind == 'fixed' and i > 1 else 'revolute'
        mimic = f'<mimic joint="j{i - 1}" multiplier="0.5" offset="0.1"/>' if (
            kind == 'mimic' and i > 1) else ''
        parts.append(f'<joint name="j{i}" type="{jtype}"><parent link="l{i - 1}"/>'
                     f'<child link="l{i}"/><origin xyz="0 0 0.1" rpy="0 0.1 0"/>'
                     f'<axis xyz="0 1 0"/>{mimic}'
                     '<limit lower="-3" upper="3" effort="10" velocity="2"/></joint>')
    parts.append('</robot>')
    return ''.join(parts).encode()


def lines(fn) -> int:
    """Return the number of Python lines ``fn()`` executes (a deterministic count of work)."""
    count = 0

    def tracer(frame, event, arg):
        nonlocal count
        if event == 'line':
            count += 1
        return tracer
    sys.settrace(tracer)
    try:
        fn()
    finally:
        sys.settrace(None)
    return count


@pytest.mark.parametrize('kind', ['plain', 'mimic', 'fixed'])
def test_loading_and_the_report_are_linear_in_the_links(kind):
    counts = {}
    for n in (100, 400):
        xml = chain(n, kind)
        model = sd.Model.from_urdf(xml)
        types = model.joint_types
        counts[n] = (lines(lambda: sd.Model.from_urdf(xml)),
                     lines(lambda: check.report(model, types)))
    for what, small, large in zip(('from_urdf', 'report'), counts[100], counts[400]):
        assert large <= 4.5 * small, (kind, what, small, large)


def test_a_mimic_chain_loads_with_the_right_coefficients():
    """Each joint of the chain mimics the one before: q_i = 0.5 q_(i-1) + 0.1, resolved."""
    model = sd.Model.from_urdf(chain(40, 'mimic'))
    assert model.joint_names == ('j1',)
    mult, off = 1.0, 0.0
    for m in range(1, model.NB + 1):
        assert model.qidx[m] == 0
        assert np.isclose(model.qmul[m], mult) and np.isclose(model.qoff[m], off), m
        mult, off = 0.5 * mult, 0.5 * off + 0.1


def test_a_20000_link_chain_is_checked_by_the_command(tmp_path):
    path = tmp_path / 'chain.urdf'
    path.write_bytes(chain(20000))
    run = subprocess.run([sys.executable, '-m', 'spatial_dynamics.check', str(path)],
                         capture_output=True, text=True, timeout=600,     # a hang guard
                         env={**os.environ, 'PYTHONPATH': ROOT})
    assert run.returncode == 0, run.stderr
    assert run.stdout.startswith("robot 'chain20000': 20000 dof, 20000 moving bodies")
    assert run.stdout.count('\n') > 40000
