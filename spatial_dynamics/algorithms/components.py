# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Spatial algebra on scalar components: the products every component kernel shares.

A transform ``X = (E, r)`` is kept as its rotation (9 scalars, row-major) and translation (3)
(RBDA §2.12), a spatial inertia as ``(m, h, Ibar)`` with ``h = m c`` and ``Ibar`` the
rotational inertia about the body origin (xx xy xz yy yz zz) (RBDA eq. 2.63), motion and force
vectors as 6 scalars, angular first. Each product is written once here; the kernels of
:mod:`.rnea` and :mod:`.crba` call these, and the compiled backend inlines the same text
(:mod:`spatial_dynamics.backends.codegen`). They run on any scalar kind (floats, numpy arrays,
mpmath numbers).
"""

from __future__ import annotations


def X_motion(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, m0, m1, m2, m3, m4, m5):
    """Apply ``X = (E, r)`` to a motion vector ``[ω; v]``: ``[E ω; E (v - r × ω)]`` (RBDA 2.24)."""
    u0 = m3 - (ry * m2 - rz * m1)
    u1 = m4 - (rz * m0 - rx * m2)
    u2 = m5 - (rx * m1 - ry * m0)
    return (e00 * m0 + e01 * m1 + e02 * m2, e10 * m0 + e11 * m1 + e12 * m2,
            e20 * m0 + e21 * m1 + e22 * m2, e00 * u0 + e01 * u1 + e02 * u2,
            e10 * u0 + e11 * u1 + e12 * u2, e20 * u0 + e21 * u1 + e22 * u2)


def cross(x0, x1, x2, y0, y1, y2):
    """``x × y`` of two 3-vectors."""
    return x1 * y2 - x2 * y1, x2 * y0 - x0 * y2, x0 * y1 - x1 * y0


def XT_force(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, n0, n1, n2, f0, f1, f2):
    """Apply ``Xᵀ`` to a force ``[n; f]`` (child to parent): ``[Eᵀ n + r × Eᵀ f; Eᵀ f]``."""
    F0 = e00 * f0 + e10 * f1 + e20 * f2
    F1 = e01 * f0 + e11 * f1 + e21 * f2
    F2 = e02 * f0 + e12 * f1 + e22 * f2
    return (e00 * n0 + e10 * n1 + e20 * n2 + (ry * F2 - rz * F1),
            e01 * n0 + e11 * n1 + e21 * n2 + (rz * F0 - rx * F2),
            e02 * n0 + e12 * n1 + e22 * n2 + (rx * F1 - ry * F0),
            F0, F1, F2)


def XT_force_plus(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, n0, n1, n2, f0, f1,
                  f2, p0, p1, p2, p3, p4, p5):
    """``p + Xᵀ f``: a child's force added to its parent's ``p`` (``f_λ(i) += λXᵢ* fᵢ``).

    :func:`XT_force`'s expressions, written out rather than called: the backward pass runs
    this once per body, and on plain floats the nested call cost ~4 % of a Panda RNEA.
    """
    F0 = e00 * f0 + e10 * f1 + e20 * f2
    F1 = e01 * f0 + e11 * f1 + e21 * f2
    F2 = e02 * f0 + e12 * f1 + e22 * f2
    return (p0 + (e00 * n0 + e10 * n1 + e20 * n2 + (ry * F2 - rz * F1)),
            p1 + (e01 * n0 + e11 * n1 + e21 * n2 + (rz * F0 - rx * F2)),
            p2 + (e02 * n0 + e12 * n1 + e22 * n2 + (rx * F1 - ry * F0)),
            p3 + F0, p4 + F1, p5 + F2)


def I_motion(mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz, m0, m1, m2, m3, m4, m5):
    """Apply a spatial inertia to a motion vector ``[ω; v]`` (RBDA eq. 2.63).

    ``I = [[Ibar, h×], [h×ᵀ, m 1]]``, ``h = m c``: ``I [ω; v] = [Ibar ω + h × v; m v - h × ω]``.
    """
    return (Ixx * m0 + Ixy * m1 + Ixz * m2 + (hy * m5 - hz * m4),
            Ixy * m0 + Iyy * m1 + Iyz * m2 + (hz * m3 - hx * m5),
            Ixz * m0 + Iyz * m1 + Izz * m2 + (hx * m4 - hy * m3),
            mass * m3 - (hy * m2 - hz * m1),
            mass * m4 - (hz * m0 - hx * m2),
            mass * m5 - (hx * m1 - hy * m0))


def Irate_motion(g0, g1, g2, g3, g4, g5, g6, g7, g8, m0, m1, m2, m3, m4, m5):
    """Apply an inertia of no mass (:func:`I_rate`'s ``(g, Ī')``) to a motion vector.

    :func:`I_motion` with ``mass = 0`` and its products with it left out.
    """
    return (g3 * m0 + g4 * m1 + g5 * m2 + (g1 * m5 - g2 * m4),
            g4 * m0 + g6 * m1 + g7 * m2 + (g2 * m3 - g0 * m5),
            g5 * m0 + g7 * m1 + g8 * m2 + (g0 * m4 - g1 * m3),
            -(g1 * m2 - g2 * m1), -(g2 * m0 - g0 * m2), -(g0 * m1 - g1 * m0))


def XT_I_X(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz,
           mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz):
    """Express a spatial inertia in the parent's coordinates: ``Xᵀ I X`` (RBDA table 2.8).

    With ``y = Eᵀ h``: ``m' = m``, ``h' = y + m r``,
    ``Ibar' = Eᵀ Ibar E - r× y× - h'× r×``
    ``      = Eᵀ Ibar E - (y rᵀ + r yᵀ + m r rᵀ) + (2 r·y + m r·r) 1``.
    """
    y0 = e00 * hx + e10 * hy + e20 * hz
    y1 = e01 * hx + e11 * hy + e21 * hz
    y2 = e02 * hx + e12 * hy + e22 * hz
    # T = Ibar E, then B = Eᵀ T (symmetric: six entries)
    t00 = Ixx * e00 + Ixy * e10 + Ixz * e20
    t01 = Ixx * e01 + Ixy * e11 + Ixz * e21
    t02 = Ixx * e02 + Ixy * e12 + Ixz * e22
    t10 = Ixy * e00 + Iyy * e10 + Iyz * e20
    t11 = Ixy * e01 + Iyy * e11 + Iyz * e21
    t12 = Ixy * e02 + Iyy * e12 + Iyz * e22
    t20 = Ixz * e00 + Iyz * e10 + Izz * e20
    t21 = Ixz * e01 + Iyz * e11 + Izz * e21
    t22 = Ixz * e02 + Iyz * e12 + Izz * e22
    b00 = e00 * t00 + e10 * t10 + e20 * t20
    b01 = e00 * t01 + e10 * t11 + e20 * t21
    b02 = e00 * t02 + e10 * t12 + e20 * t22
    b11 = e01 * t01 + e11 * t11 + e21 * t21
    b12 = e01 * t02 + e11 * t12 + e21 * t22
    b22 = e02 * t02 + e12 * t12 + e22 * t22
    mr0, mr1, mr2 = mass * rx, mass * ry, mass * rz
    d = 2.0 * (rx * y0 + ry * y1 + rz * y2) + (mr0 * rx + mr1 * ry + mr2 * rz)
    return (mass, y0 + mr0, y1 + mr1, y2 + mr2,
            b00 - (2.0 * y0 * rx + mr0 * rx) + d,
            b01 - (y0 * ry + rx * y1 + mr0 * ry),
            b02 - (y0 * rz + rx * y2 + mr0 * rz),
            b11 - (2.0 * y1 * ry + mr1 * ry) + d,
            b12 - (y1 * rz + ry * y2 + mr1 * rz),
            b22 - (2.0 * y2 * rz + mr2 * rz) + d)


def XT_I_X_plus(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz,
                mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz,
                c0, c1, c2, c3, c4, c5, c6, c7, c8, c9):
    """``c + Xᵀ I X``: a child's composite inertia added to its parent's ``c`` (RBDA 6.2)."""
    d0, d1, d2, d3, d4, d5, d6, d7, d8, d9 = XT_I_X(
        e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz,
        mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz)
    return (c0 + d0, c1 + d1, c2 + d2, c3 + d3, c4 + d4, c5 + d5, c6 + d6, c7 + d7, c8 + d8,
            c9 + d9)


def X_compose(a00, a01, a02, a10, a11, a12, a20, a21, a22, ar0, ar1, ar2,
              b00, b01, b02, b10, b11, b12, b20, b21, b22, br0, br1, br2):
    """Return the product ``A B`` of two transforms ``(E, r)`` (RBDA eq. 2.27).

    ``(E_A, r_A)(E_B, r_B) = (E_A E_B, r_B + E_Bᵀ r_A)``.
    """
    return (a00 * b00 + a01 * b10 + a02 * b20, a00 * b01 + a01 * b11 + a02 * b21,
            a00 * b02 + a01 * b12 + a02 * b22, a10 * b00 + a11 * b10 + a12 * b20,
            a10 * b01 + a11 * b11 + a12 * b21, a10 * b02 + a11 * b12 + a12 * b22,
            a20 * b00 + a21 * b10 + a22 * b20, a20 * b01 + a21 * b11 + a22 * b21,
            a20 * b02 + a21 * b12 + a22 * b22,
            br0 + (b00 * ar0 + b10 * ar1 + b20 * ar2),
            br1 + (b01 * ar0 + b11 * ar1 + b21 * ar2),
            br2 + (b02 * ar0 + b12 * ar1 + b22 * ar2))


def Xinv_motion(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, m0, m1, m2, m3, m4,
                m5):
    """Apply ``X⁻¹`` of ``X = (E, r)`` to a motion vector: ``[Eᵀ ω; Eᵀ v + r × Eᵀ ω]``."""
    w0 = e00 * m0 + e10 * m1 + e20 * m2
    w1 = e01 * m0 + e11 * m1 + e21 * m2
    w2 = e02 * m0 + e12 * m1 + e22 * m2
    return (w0, w1, w2,
            e00 * m3 + e10 * m4 + e20 * m5 + (ry * w2 - rz * w1),
            e01 * m3 + e11 * m4 + e21 * m5 + (rz * w0 - rx * w2),
            e02 * m3 + e12 * m4 + e22 * m5 + (rx * w1 - ry * w0))


def crm_motion(a0, a1, a2, a3, a4, a5, b0, b1, b2, b3, b4, b5):
    """Return ``a × b`` of two motion vectors (``crm(a) b``, RBDA eq. 2.31).

    ``[ω; v] × [ω'; v'] = [ω × ω'; ω × v' + v × ω']``.
    """
    return (a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0,
            (a1 * b5 - a2 * b4) + (a4 * b2 - a5 * b1),
            (a2 * b3 - a0 * b5) + (a5 * b0 - a3 * b2),
            (a0 * b4 - a1 * b3) + (a3 * b1 - a4 * b0))


def crf_force(a0, a1, a2, a3, a4, a5, n0, n1, n2, f0, f1, f2):
    """Return ``a ×* f`` of a motion vector and a force (``crf(a) f``, RBDA eq. 2.32).

    ``[ω; v] ×* [n; f] = [ω × n + v × f; ω × f]``.
    """
    return ((a1 * n2 - a2 * n1) + (a4 * f2 - a5 * f1),
            (a2 * n0 - a0 * n2) + (a5 * f0 - a3 * f2),
            (a0 * n1 - a1 * n0) + (a3 * f1 - a4 * f0),
            a1 * f2 - a2 * f1, a2 * f0 - a0 * f2, a0 * f1 - a1 * f0)


def I_rate(mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz, w0, w1, w2, u0, u1, u2):
    """Return the rate ``İ = v ×* I − I v×`` of an inertia moving with ``v = [ω; u]``.

    9 scalars: ``İ = [[Ī', g×], [g×ᵀ, 0]]`` (symmetric, a spatial inertia of no mass), with
    ``g = ω × h + m u`` and ``Ī' = ω×Ī − Īω× − (u hᵀ + h uᵀ) + 2 (u·h) 1``; returns
    ``(g, Ī')`` as ``I_motion`` takes them after a zero mass.
    """
    # P = Ī ω× column by column (Ī (ω × e_c)); ω×Ī − Īω× = −(P + Pᵀ)
    p00, p01, p02 = Ixy * w2 - Ixz * w1, Ixz * w0 - Ixx * w2, Ixx * w1 - Ixy * w0
    p10, p11, p12 = Iyy * w2 - Iyz * w1, Iyz * w0 - Ixy * w2, Ixy * w1 - Iyy * w0
    p20, p21, p22 = Iyz * w2 - Izz * w1, Izz * w0 - Ixz * w2, Ixz * w1 - Iyz * w0
    d = 2.0 * (u0 * hx + u1 * hy + u2 * hz)
    return (w1 * hz - w2 * hy + mass * u0, w2 * hx - w0 * hz + mass * u1,
            w0 * hy - w1 * hx + mass * u2,
            -2.0 * p00 - 2.0 * u0 * hx + d, -(p01 + p10) - (u0 * hy + hx * u1),
            -(p02 + p20) - (u0 * hz + hx * u2), -2.0 * p11 - 2.0 * u1 * hy + d,
            -(p12 + p21) - (u1 * hz + hy * u2), -2.0 * p22 - 2.0 * u2 * hz + d)


def I_articulated(mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz):
    """Write a rigid body's spatial inertia as a symmetric 6x6: its upper triangle, 21 scalars.

    ``I = [[Ibar, h×], [h×ᵀ, m 1]]`` (RBDA eq. 2.63), row by row: ``I_00 … I_05, I_11 …
    I_15, …, I_55``, the form of an articulated-body inertia (RBDA §7.1), which is no rigid
    body's.
    """
    zero = 0.0 * mass
    return (Ixx, Ixy, Ixz, zero, -hz, hy,
            Iyy, Iyz, hz, zero, -hx,
            Izz, -hy, hx, zero,
            mass, zero, zero,
            mass, zero,
            mass)


def IA_motion(i00, i01, i02, i03, i04, i05, i11, i12, i13, i14, i15, i22, i23, i24, i25,
              i33, i34, i35, i44, i45, i55, m0, m1, m2, m3, m4, m5):
    """Apply a symmetric 6x6 (its upper triangle, :func:`I_articulated`) to a 6-vector."""
    return (i00 * m0 + i01 * m1 + i02 * m2 + i03 * m3 + i04 * m4 + i05 * m5,
            i01 * m0 + i11 * m1 + i12 * m2 + i13 * m3 + i14 * m4 + i15 * m5,
            i02 * m0 + i12 * m1 + i22 * m2 + i23 * m3 + i24 * m4 + i25 * m5,
            i03 * m0 + i13 * m1 + i23 * m2 + i33 * m3 + i34 * m4 + i35 * m5,
            i04 * m0 + i14 * m1 + i24 * m2 + i34 * m3 + i44 * m4 + i45 * m5,
            i05 * m0 + i15 * m1 + i25 * m2 + i35 * m3 + i45 * m4 + i55 * m5)


def XT_IA_X_plus(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz,
                 i00, i01, i02, i03, i04, i05, i11, i12, i13, i14, i15, i22, i23, i24, i25,
                 i33, i34, i35, i44, i45, i55,
                 c00, c01, c02, c03, c04, c05, c11, c12, c13, c14, c15, c22, c23, c24, c25,
                 c33, c34, c35, c44, c45, c55):
    """``c + Xᵀ I X``: a child's articulated inertia added to its parent's (RBDA table 7.1).

    ``I = [[A, B], [Bᵀ, C]]`` any symmetric 6x6 (upper triangles, :func:`I_articulated`),
    ``X = (E, r) = [[E, 0], [0, E]] [[1, 0], [-r×, 1]]``. Rotated, ``A' = Eᵀ A E``,
    ``B' = Eᵀ B E``, ``C' = Eᵀ C E``; then moved by ``r``: ``C'' = C'``,
    ``B'' = B' + r× C'``, ``A'' = A' + r× B'ᵀ - B'' r×``.
    """
    # A' = Eᵀ A E (upper triangle), via A E
    t00 = i00 * e00 + i01 * e10 + i02 * e20
    t01 = i00 * e01 + i01 * e11 + i02 * e21
    t02 = i00 * e02 + i01 * e12 + i02 * e22
    t10 = i01 * e00 + i11 * e10 + i12 * e20
    t11 = i01 * e01 + i11 * e11 + i12 * e21
    t12 = i01 * e02 + i11 * e12 + i12 * e22
    t20 = i02 * e00 + i12 * e10 + i22 * e20
    t21 = i02 * e01 + i12 * e11 + i22 * e21
    t22 = i02 * e02 + i12 * e12 + i22 * e22
    a00 = e00 * t00 + e10 * t10 + e20 * t20
    a01 = e00 * t01 + e10 * t11 + e20 * t21
    a02 = e00 * t02 + e10 * t12 + e20 * t22
    a11 = e01 * t01 + e11 * t11 + e21 * t21
    a12 = e01 * t02 + e11 * t12 + e21 * t22
    a22 = e02 * t02 + e12 * t12 + e22 * t22
    # C' = Eᵀ C E
    t00 = i33 * e00 + i34 * e10 + i35 * e20
    t01 = i33 * e01 + i34 * e11 + i35 * e21
    t02 = i33 * e02 + i34 * e12 + i35 * e22
    t10 = i34 * e00 + i44 * e10 + i45 * e20
    t11 = i34 * e01 + i44 * e11 + i45 * e21
    t12 = i34 * e02 + i44 * e12 + i45 * e22
    t20 = i35 * e00 + i45 * e10 + i55 * e20
    t21 = i35 * e01 + i45 * e11 + i55 * e21
    t22 = i35 * e02 + i45 * e12 + i55 * e22
    k00 = e00 * t00 + e10 * t10 + e20 * t20
    k01 = e00 * t01 + e10 * t11 + e20 * t21
    k02 = e00 * t02 + e10 * t12 + e20 * t22
    k11 = e01 * t01 + e11 * t11 + e21 * t21
    k12 = e01 * t02 + e11 * t12 + e21 * t22
    k22 = e02 * t02 + e12 * t12 + e22 * t22
    # B' = Eᵀ B E (B_jk = I_j,3+k)
    t00 = i03 * e00 + i04 * e10 + i05 * e20
    t01 = i03 * e01 + i04 * e11 + i05 * e21
    t02 = i03 * e02 + i04 * e12 + i05 * e22
    t10 = i13 * e00 + i14 * e10 + i15 * e20
    t11 = i13 * e01 + i14 * e11 + i15 * e21
    t12 = i13 * e02 + i14 * e12 + i15 * e22
    t20 = i23 * e00 + i24 * e10 + i25 * e20
    t21 = i23 * e01 + i24 * e11 + i25 * e21
    t22 = i23 * e02 + i24 * e12 + i25 * e22
    b00 = e00 * t00 + e10 * t10 + e20 * t20
    b01 = e00 * t01 + e10 * t11 + e20 * t21
    b02 = e00 * t02 + e10 * t12 + e20 * t22
    b10 = e01 * t00 + e11 * t10 + e21 * t20
    b11 = e01 * t01 + e11 * t11 + e21 * t21
    b12 = e01 * t02 + e11 * t12 + e21 * t22
    b20 = e02 * t00 + e12 * t10 + e22 * t20
    b21 = e02 * t01 + e12 * t11 + e22 * t21
    b22 = e02 * t02 + e12 * t12 + e22 * t22
    # B'' = B' + r× C'
    d00 = b00 + (ry * k02 - rz * k01)
    d01 = b01 + (ry * k12 - rz * k11)
    d02 = b02 + (ry * k22 - rz * k12)
    d10 = b10 + (rz * k00 - rx * k02)
    d11 = b11 + (rz * k01 - rx * k12)
    d12 = b12 + (rz * k02 - rx * k22)
    d20 = b20 + (rx * k01 - ry * k00)
    d21 = b21 + (rx * k11 - ry * k01)
    d22 = b22 + (rx * k12 - ry * k02)
    # A'' = A' + r× B'ᵀ - B'' r×:  (r× M)_0k = ry M_2k - rz M_1k, …;  (M r×)_j0 = rz M_j1 -
    # ry M_j2, (M r×)_j1 = rx M_j2 - rz M_j0, (M r×)_j2 = ry M_j0 - rx M_j1
    return (c00 + (a00 + (ry * b02 - rz * b01) - (rz * d01 - ry * d02)),
            c01 + (a01 + (ry * b12 - rz * b11) - (rx * d02 - rz * d00)),
            c02 + (a02 + (ry * b22 - rz * b21) - (ry * d00 - rx * d01)),
            c03 + d00, c04 + d01, c05 + d02,
            c11 + (a11 + (rz * b10 - rx * b12) - (rx * d12 - rz * d10)),
            c12 + (a12 + (rz * b20 - rx * b22) - (ry * d10 - rx * d11)),
            c13 + d10, c14 + d11, c15 + d12,
            c22 + (a22 + (rx * b21 - ry * b20) - (ry * d20 - rx * d21)),
            c23 + d20, c24 + d21, c25 + d22,
            c33 + k00, c34 + k01, c35 + k02,
            c44 + k11, c45 + k12,
            c55 + k22)
