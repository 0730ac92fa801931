# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The derivatives' kernel computes each product its structure needs, and no other.

The products it skips are identities: body 1's frame is the world (``ᵂX_1 = 1``), a 1-dof
column ``s`` has ``v_i = v_λ + s q̇`` (so ``α' = (v_λ + v_i) × s = 2 v_λ × s = 2β``), the
zeros of ``S`` and the zero mass of ``İC`` multiply nothing. The products are counted on the
Python backend, which runs the one source the C kernels are generated from; the values are
checked against Pinocchio and mpmath in test_derivatives.py.
"""

from collections import Counter

from conftest import random_state, robot_urdf_path
import numpy as np
import pytest
import spatial_dynamics as sd
from test_core_floating_base import random_floating_state
from spatial_dynamics.algorithms import components, derivatives
from spatial_dynamics.backends import layout
from spatial_dynamics.joints import CODES, joint_axis, joint_world_axis
from spatial_dynamics.spatial import plux, plux_inv, rotx, roty, rotz

COUNTED = ('XT_I_X', 'X_compose', 'crm_motion', 'crf_force', 'I_motion', 'Irate_motion',
           'Xinv_motion', 'joint_axis', 'joint_world_axis')


def _rotation(rng):
    a, b, c = rng.uniform(-np.pi, np.pi, 3)
    return (rotz(a) @ roty(b) @ rotx(c))[:3, :3]      # the rotations are Plücker (6 x 6)


@pytest.mark.parametrize('kind,axis', [('RX', (-1.0, 0.0, 0.0)), ('RY', (0.0, 1.0, 0.0)),
                                       ('RZ', (0.0, 0.0, -1.0)), ('RA', (0.6, 0.0, 0.8)),
                                       ('PR', (0.0, 0.6, -0.8))])
def test_a_one_dof_column_is_X_inverse_S_without_the_zeros_of_S(kind, axis):
    """``joint_world_axis`` is ``X⁻¹ S`` (RBDA 2.26), the values of ``Xinv_motion(S)``."""
    rng = np.random.default_rng(7)
    code = CODES[kind]
    for _ in range(20):
        E, r = _rotation(rng), rng.uniform(-2.0, 2.0, 3)
        got = np.array(joint_world_axis(code, *E.ravel(), *r, *axis))
        S = np.array(joint_axis(code, 0, *axis))
        assert np.allclose(got, plux_inv(plux(E, r)) @ S, rtol=0.0, atol=1e-15)
        assert np.array_equal(got, components.Xinv_motion(*E.ravel(), *r, *S))


def test_the_rate_of_an_inertia_acts_as_an_inertia_of_no_mass():
    """``Irate_motion(g, Ī', m)`` is ``I_motion(0, g, Ī', m)``: ``İ m`` of :func:`I_rate`."""
    rng = np.random.default_rng(8)
    for _ in range(20):
        g, m = rng.normal(size=9), rng.normal(size=6)
        assert np.array_equal(components.Irate_motion(*g, *m),
                              components.I_motion(0.0, *g, *m))


def _expected(rows) -> Counter:
    """Return the products of the kernel's passes, from the tree alone (module docstring)."""
    NB = len(rows) - 1
    once = NB > 0 and rows[1][4] > 1       # body 1's columns at once: a free-flyer's six
    n = Counter()
    for i in range(1, NB + 1):
        p, dof = rows[i][0], rows[i][4]
        n['XT_I_X'] += i != 1                           # body 1's inertia is in its frame
        n['X_compose'] += p > 1                         # ᵢX_W = Xup_i below body 1
        n['crm_motion'] += 1                            # v_i × v_J
        n['I_motion'] += 2                              # h_i, I_i a_i
        n['crf_force'] += 1                             # v_i ×* h_i
        n['joint_world_axis' if dof == 1 else 'joint_axis'] += dof
        n['Xinv_motion'] += dof if dof > 1 else 0
        if not (i == 1 and once):
            # ψ, s × a_λ, v_λ × ψ; α' a product only for a joint of several columns
            n['crm_motion'] += dof * (3 + (dof > 1))
        n['I_motion'] += dof                            # A = IC s
        n['Irate_motion'] += dof                        # İC s
        n['crf_force'] += dof                           # s ×* hC
        if p != 0:
            n['I_motion'] += 2 * dof                    # IC α, IC α'
            n['Irate_motion'] += dof                    # İC β
            n['crf_force'] += 2 * dof                   # β ×* hC, s ×* F
        if once:
            n['crf_force'] += 2 * dof                   # a_0 ×* A, v_1 ×* A
    return n


@pytest.mark.parametrize('robot,base', [('ur5', 'fixed'), ('panda', 'fixed'),
                                        ('solo12', 'floating')])
def test_the_kernel_computes_the_products_of_its_structure_only(robot, base, monkeypatch):
    """Per body and column the products the tree asks for (counted on the one source).

    UR5 and Panda: a fixed base whose body 1 turns about one axis is walked as any ancestor
    (``β = 0`` there), not taken at once (two force products a column below it); Solo12's
    free-flyer is (six columns, two products a column below it). Body 1 is the world frame:
    no transform of its inertia or of its children's; a 1-dof column is ``X⁻¹ S`` of S's
    nonzeros and its ``α'`` is ``2β``; ``İC`` is applied without a mass.
    """
    model = sd.Model.from_urdf(robot_urdf_path(robot), base=base)
    seen = Counter()
    for name in COUNTED:
        function = getattr(derivatives, name, None)
        if function is None:
            continue

        def counted(*args, _f=function, _name=name):
            seen[_name] += 1
            return _f(*args)
        monkeypatch.setattr(derivatives, name, counted)
    rng = np.random.default_rng(3)
    q, qd, qdd = (random_floating_state(rng, model) if model.floating
                  else random_state(rng, (), model.nq))
    sd.rnea_derivatives(model, q, qd, qdd, backend='numpy')
    expected = _expected(layout.of(model).rows)
    assert {k: seen[k] for k in COUNTED} == {k: expected[k] for k in COUNTED}
