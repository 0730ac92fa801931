# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Closed-form inverse dynamics of small mechanisms written by hand.

- single pendulum: tau = (m l^2 + Iyy) qdd + m l (gx cos q - gz sin q) (hinge about +y, com at
  (0, 0, -l) in the arm frame), in several gravity directions and with an offset, rotated,
  non-unit hinge;
- double pendulum (Lagrange, rods with inertia);
- prismatic joint under gravity: tau = m (qdd - g . u), vertical and tilted;
- a slider on a turntable: tau_r = (I + m r^2) thdd + 2 m r rd thd, tau_p = m (rdd - r thd^2);
- external wrenches: tau = -axis . (r x F) for a force F at r on the link (the joint holds the
  load, as in Featherstone's ID and Pinocchio).
"""

import numpy as np
import pytest
import spatial_dynamics as sd
from urdf_gen import fmt, inertial_xml, rpy_to_matrix

G = 9.81
LIMIT = '<limit effort="1000" velocity="100" lower="-10" upper="10"/>'


def joint(name, kind, parent, child, axis=(0.0, 1.0, 0.0), xyz=(0.0, 0.0, 0.0),
          rpy=(0.0, 0.0, 0.0)):
    axis_xml = '' if kind == 'fixed' else f'<axis xyz="{fmt(axis)}"/>{LIMIT}'
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/>'
            f'<child link="{child}"/><origin xyz="{fmt(xyz)}" rpy="{fmt(rpy)}"/>{axis_xml}'
            '</joint>')


def link(name, mass=None, com=(0.0, 0.0, 0.0), Ic=None, rpy=(0.0, 0.0, 0.0)):
    if mass is None:
        return f'<link name="{name}"/>'
    Ic = np.zeros((3, 3)) if Ic is None else np.asarray(Ic, dtype=float)
    return f'<link name="{name}">{inertial_xml(mass, com, rpy, Ic)}</link>'


def robot(*elements):
    return sd.Model.from_urdf('<robot name="analytic">' + ''.join(elements) + '</robot>')


def close(a, b, scale=1.0):
    return np.abs(np.asarray(a) - np.asarray(b)).max() <= 1e-12 * max(scale, 1.0)


# --------------------------------------------------------------------------------------------
# Single pendulum

M1, L1, IYY = 1.7, 0.6, 0.05
ARM_IC = np.diag([0.04, IYY, 0.02])


def pendulum(axis=(0.0, 1.0, 0.0), xyz=(0.0, 0.0, 0.0), rpy=(0.0, 0.0, 0.0)):
    return robot(link('base'), link('arm', M1, (0.0, 0.0, -L1), ARM_IC),
                 joint('hinge', 'revolute', 'base', 'arm', axis, xyz, rpy))


def pendulum_tau(q, qdd, gravity):
    gx, gy, gz = gravity
    return (M1 * L1 ** 2 + IYY) * qdd + M1 * L1 * (gx * np.cos(q) - gz * np.sin(q))


Q = np.linspace(-3.0, 3.0, 13)
QD = np.linspace(2.0, -4.0, 13)
QDD = np.linspace(-5.0, 1.0, 13)


@pytest.mark.parametrize('gravity', [(0.0, 0.0, -G), (0.0, 0.0, G), (G, 0.0, 0.0),
                                     (-2.0, 0.0, -G), (0.0, 0.0, 0.0)])
def test_single_pendulum(gravity):
    model = pendulum()
    assert model.joint_names == ('hinge',)
    tau = sd.rnea(model, Q[:, None], QD[:, None], QDD[:, None], gravity=gravity)[:, 0]
    assert close(tau, pendulum_tau(Q, QDD, gravity), 20.0)
    # hanging at rest: no torque; horizontal against z gravity: m g l
    z = np.zeros(1)
    assert close(sd.rnea(model, z, z, z, gravity=(0.0, 0.0, -G)), [0.0])
    assert close(sd.rnea(model, [np.pi / 2], z, z, gravity=(0.0, 0.0, -G)), [M1 * G * L1])


def test_single_pendulum_default_gravity_and_velocity_independence():
    model = pendulum()
    for q, qd in [(0.4, 0.0), (0.4, 7.0), (0.4, -3.0)]:
        tau = sd.rnea(model, [q], [qd], [1.5])
        assert close(tau, [pendulum_tau(q, 1.5, (0.0, 0.0, -G))], 10.0)


def test_pendulum_gravity_along_the_hinge_gives_no_torque():
    model = pendulum()
    z = np.zeros((13, 1))
    assert close(sd.rnea(model, Q[:, None], z, z, gravity=(0.0, G, 0.0)), z)


def test_pendulum_negative_and_non_unit_axis():
    """Hinge about -y is the same pendulum with q -> -q; the axis length does not matter."""
    gravity = (3.0, 0.0, -G)
    for axis in [(0.0, -1.0, 0.0), (0.0, -2.5, 0.0)]:
        tau = sd.rnea(pendulum(axis), Q[:, None], QD[:, None], QDD[:, None],
                      gravity=gravity)[:, 0]
        assert close(tau, -pendulum_tau(-Q, -QDD, gravity), 20.0)
    tau = sd.rnea(pendulum((0.0, 4.0, 0.0)), Q[:, None], QD[:, None], QDD[:, None],
                  gravity=gravity)[:, 0]
    assert close(tau, pendulum_tau(Q, QDD, gravity), 20.0)


def test_pendulum_on_offset_rotated_mount():
    """The same physical pendulum described in an offset, rotated joint frame: same torque."""
    rpy = (0.3, -0.7, 1.1)
    R = rpy_to_matrix(rpy)
    # the hinge axis y of the plain pendulum, in the rotated joint frame, and the arm's com and
    # inertia likewise: the same physical pendulum, described in a rotated frame.
    axis = R.T @ np.array([0.0, 1.0, 0.0])
    com = R.T @ np.array([0.0, 0.0, -L1])
    Ic = R.T @ ARM_IC @ R
    model = robot(link('base'), link('arm', M1, com, Ic),
                  joint('hinge', 'revolute', 'base', 'arm', 2.0 * axis, (0.4, -0.2, 1.0), rpy))
    gravity = np.array([1.0, 0.5, -G])
    tau = sd.rnea(model, Q[:, None], QD[:, None], QDD[:, None], gravity=gravity)[:, 0]
    assert close(tau, pendulum_tau(Q, QDD, gravity), 20.0)


# --------------------------------------------------------------------------------------------
# Double pendulum

m1, m2, l1, lc1, lc2 = 1.3, 0.9, 0.7, 0.35, 0.4
I1, I2 = m1 * 0.7 ** 2 / 12.0, m2 * 0.8 ** 2 / 12.0  # rods of length 0.7 and 0.8 about com


def double_pendulum_tau(q, qd, qdd, g=G):
    """Lagrange's equations; angles from the downward vertical, q2 relative to link 1."""
    q1, q2 = q
    qd1, qd2 = qd
    c2 = np.cos(q2)
    M11 = m1 * lc1 ** 2 + I1 + m2 * (l1 ** 2 + lc2 ** 2 + 2 * l1 * lc2 * c2) + I2
    M12 = m2 * (lc2 ** 2 + l1 * lc2 * c2) + I2
    M22 = m2 * lc2 ** 2 + I2
    h = -m2 * l1 * lc2 * np.sin(q2)
    g1 = g * ((m1 * lc1 + m2 * l1) * np.sin(q1) + m2 * lc2 * np.sin(q1 + q2))
    g2 = g * m2 * lc2 * np.sin(q1 + q2)
    return np.array([M11 * qdd[0] + M12 * qdd[1] + h * (2 * qd1 * qd2 + qd2 ** 2) + g1,
                     M12 * qdd[0] + M22 * qdd[1] - h * qd1 ** 2 + g2])


def test_double_pendulum(rng):
    rod = np.diag([1.0, 1.0, 0.0])  # a thin rod along z: Ixx = Iyy, Izz = 0
    model = robot(link('world'), link('upper', m1, (0.0, 0.0, -lc1), I1 * rod),
                  link('lower', m2, (0.0, 0.0, -lc2), I2 * rod),
                  joint('shoulder', 'revolute', 'world', 'upper'),
                  joint('elbow', 'continuous', 'upper', 'lower', xyz=(0.0, 0.0, -l1)))
    assert model.joint_names == ('shoulder', 'elbow')
    q = rng.uniform(-np.pi, np.pi, (20, 2))
    qd = rng.uniform(-5.0, 5.0, (20, 2))
    qdd = rng.uniform(-10.0, 10.0, (20, 2))
    tau = sd.rnea(model, q, qd, qdd, gravity=(0.0, 0.0, -G))
    expected = np.array([double_pendulum_tau(*x) for x in zip(q, qd, qdd)])
    assert close(tau, expected, np.abs(expected).max())


# --------------------------------------------------------------------------------------------
# Prismatic joints

MS = 2.3
BOX_IC = np.diag([0.02, 0.03, 0.04])


def slider(axis, rpy=(0.0, 0.0, 0.0)):
    return robot(link('base'), link('carriage', MS, (0.1, -0.2, 0.05), BOX_IC, (0.2, 0.4, 0.1)),
                 joint('slide', 'prismatic', 'base', 'carriage', axis, (0.3, 0.2, 0.1), rpy))


def test_vertical_slider():
    model = slider((0.0, 0.0, 1.0))
    tau = sd.rnea(model, Q[:, None], QD[:, None], QDD[:, None], gravity=(0.0, 0.0, -G))[:, 0]
    assert close(tau, MS * (QDD + G), 50.0)
    # a slider pointing down
    model = slider((0.0, 0.0, -3.0))
    tau = sd.rnea(model, Q[:, None], QD[:, None], QDD[:, None], gravity=(0.0, 0.0, -G))[:, 0]
    assert close(tau, MS * (QDD - G), 50.0)


@pytest.mark.parametrize('gravity', [(0.0, 0.0, -G), (1.0, -2.0, -G), (0.0, G, 0.0)])
def test_tilted_slider(gravity):
    axis, rpy = np.array([1.0, 2.0, 2.0]), (0.5, -0.3, 0.8)
    u = rpy_to_matrix(rpy) @ axis / 3.0  # unit axis in the base frame
    model = slider(axis, rpy)
    tau = sd.rnea(model, Q[:, None], QD[:, None], QDD[:, None], gravity=gravity)[:, 0]
    assert close(tau, MS * (QDD - np.dot(gravity, u)), 50.0)


def test_slider_on_turntable(rng):
    """Turntable about z carrying a radial slider along its x axis (polar coordinates)."""
    Izz_table, Izz_slider = 0.3, 0.05
    model = robot(link('floor'), link('table', 4.0, (0.0, 0.0, 0.1), np.diag([0.2, 0.2,
                                                                              Izz_table])),
                  link('bead', MS, (0.0, 0.0, 0.0), np.diag([0.03, 0.04, Izz_slider])),
                  joint('turn', 'continuous', 'floor', 'table', (0.0, 0.0, 1.0)),
                  joint('radial', 'prismatic', 'table', 'bead', (1.0, 0.0, 0.0)))
    assert model.joint_names == ('turn', 'radial')
    th, r = rng.uniform(-3.0, 3.0, 10), rng.uniform(-1.0, 1.0, 10)
    thd, rd = rng.uniform(-4.0, 4.0, 10), rng.uniform(-2.0, 2.0, 10)
    thdd, rdd = rng.uniform(-5.0, 5.0, 10), rng.uniform(-5.0, 5.0, 10)
    tau = sd.rnea(model, np.stack([th, r], -1), np.stack([thd, rd], -1),
                  np.stack([thdd, rdd], -1), gravity=(0.0, 0.0, -G))
    tau_turn = (Izz_table + Izz_slider + MS * r ** 2) * thdd + 2 * MS * r * rd * thd
    tau_radial = MS * (rdd - r * thd ** 2)
    assert close(tau, np.stack([tau_turn, tau_radial], -1), 100.0)


# --------------------------------------------------------------------------------------------
# External wrenches


def test_force_on_pendulum_gives_minus_r_cross_f(rng):
    """A static pendulum, no gravity: the hinge holds tau = -y . (r x F) (link frame)."""
    model = pendulum()
    for _ in range(10):
        q = rng.uniform(-3.0, 3.0, 1)
        r, F, n = rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)
        z = np.zeros(1)
        tau = sd.rnea(model, q, z, z, gravity=(0.0, 0.0, 0.0),
                      f_ext={'arm': np.concatenate([np.cross(r, F), F])})
        assert close(tau, [-np.cross(r, F)[1]])
        tau = sd.rnea(model, q, z, z, gravity=(0.0, 0.0, 0.0),
                      f_ext={'arm': np.concatenate([n, np.zeros(3)])})
        assert close(tau, [-n[1]])


def test_force_balancing_gravity():
    """Pushing the com up with m g (in the link frame) cancels gravity at any angle."""
    model = pendulum()
    for q in Q:
        up = M1 * G * np.array([-np.sin(q), 0.0, np.cos(q)])  # world +z in the arm frame
        r = np.array([0.0, 0.0, -L1])
        tau = sd.rnea(model, [q], [0.0], [0.0], f_ext={'arm': np.concatenate([np.cross(r, up),
                                                                              up])})
        assert close(tau, [0.0], 10.0)


def test_force_on_a_fixed_tool_frame(rng):
    """A wrench on a link fixed to the arm, expressed in that link's (rotated) frame."""
    xyz_t, rpy_t = np.array([0.1, 0.05, -0.9]), (0.4, 1.0, -0.6)
    R_t = rpy_to_matrix(rpy_t)  # tool -> arm coordinates
    model = robot(link('base'), link('arm', M1, (0.0, 0.0, -L1), ARM_IC), link('tool'),
                  joint('hinge', 'revolute', 'base', 'arm'),
                  joint('tool_mount', 'fixed', 'arm', 'tool', xyz=xyz_t, rpy=rpy_t))
    assert model.joint_names == ('hinge',)
    for _ in range(5):
        q, qd, qdd = rng.uniform(-3.0, 3.0, (3, 1))
        n_t, F_t = rng.normal(size=3), rng.normal(size=3)
        n_arm = R_t @ n_t + np.cross(xyz_t, R_t @ F_t)
        tau = sd.rnea(model, q, qd, qdd, f_ext={'tool': np.concatenate([n_t, F_t])})
        assert close(tau, pendulum_tau(q, qdd, (0.0, 0.0, -G)) - n_arm[1], 20.0)


def test_force_on_the_fixed_base_does_nothing(rng):
    model = pendulum()
    q, qd, qdd = rng.uniform(-3.0, 3.0, (3, 1))
    assert close(sd.rnea(model, q, qd, qdd, f_ext={'base': rng.normal(size=6)}),
                 sd.rnea(model, q, qd, qdd), 10.0)
