# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
# flake8: noqa
"""Kernels generated from :mod:`spatial_dynamics.algorithms`: do not edit.

The flat-array form of the one source (the rules of :mod:`.codegen`), from which the C of
``_kernels_generated.h`` is printed; plain Python, run by the tests to check the rewriting.
Change the source and run ``python -m spatial_dynamics.backends.codegen``.
"""
import numpy as np

RX = 0
RY = 1
RZ = 2
RA = 3
PR = 4
WORK = 40
XUP = 0
VEL = 12
ACC = 18
FRC = 24
ICS = 30


def X_motion(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, m0, m1, m2, m3, m4, m5):
    """Run components.X_motion of the algorithms, generated from it."""
    u0 = m3 - (ry * m2 - rz * m1)
    u1 = m4 - (rz * m0 - rx * m2)
    u2 = m5 - (rx * m1 - ry * m0)
    return (e00 * m0 + e01 * m1 + e02 * m2, e10 * m0 + e11 * m1 + e12 * m2, e20 * m0 + e21 * m1 + e22 * m2, e00 * u0 + e01 * u1 + e02 * u2, e10 * u0 + e11 * u1 + e12 * u2, e20 * u0 + e21 * u1 + e22 * u2)


def XT_force(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, n0, n1, n2, f0, f1, f2):
    """Run components.XT_force of the algorithms, generated from it."""
    F0 = e00 * f0 + e10 * f1 + e20 * f2
    F1 = e01 * f0 + e11 * f1 + e21 * f2
    F2 = e02 * f0 + e12 * f1 + e22 * f2
    return (e00 * n0 + e10 * n1 + e20 * n2 + (ry * F2 - rz * F1), e01 * n0 + e11 * n1 + e21 * n2 + (rz * F0 - rx * F2), e02 * n0 + e12 * n1 + e22 * n2 + (rx * F1 - ry * F0), F0, F1, F2)


def I_motion(mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz, m0, m1, m2, m3, m4, m5):
    """Run components.I_motion of the algorithms, generated from it."""
    return (Ixx * m0 + Ixy * m1 + Ixz * m2 + (hy * m5 - hz * m4), Ixy * m0 + Iyy * m1 + Iyz * m2 + (hz * m3 - hx * m5), Ixz * m0 + Iyz * m1 + Izz * m2 + (hx * m4 - hy * m3), mass * m3 - (hy * m2 - hz * m1), mass * m4 - (hz * m0 - hx * m2), mass * m5 - (hx * m1 - hy * m0))


def XT_I_X(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz):
    """Run components.XT_I_X of the algorithms, generated from it."""
    y0 = e00 * hx + e10 * hy + e20 * hz
    y1 = e01 * hx + e11 * hy + e21 * hz
    y2 = e02 * hx + e12 * hy + e22 * hz
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
    mr0, mr1, mr2 = (mass * rx, mass * ry, mass * rz)
    d = 2.0 * (rx * y0 + ry * y1 + rz * y2) + (mr0 * rx + mr1 * ry + mr2 * rz)
    return (mass, y0 + mr0, y1 + mr1, y2 + mr2, b00 - (2.0 * y0 * rx + mr0 * rx) + d, b01 - (y0 * ry + rx * y1 + mr0 * ry), b02 - (y0 * rz + rx * y2 + mr0 * rz), b11 - (2.0 * y1 * ry + mr1 * ry) + d, b12 - (y1 * rz + ry * y2 + mr1 * rz), b22 - (2.0 * y2 * rz + mr2 * rz) + d)


def xup_kernel(K, q, work):
    """Run rnea.xup_kernel of the algorithms, generated from it."""
    for i in range(1, K.shape[0]):
        code = int(K[i, 1])
        k = int(K[i, 2])
        ax = K[i, 3]
        ay = K[i, 4]
        az = K[i, 5]
        t00 = K[i, 6]
        t01 = K[i, 7]
        t02 = K[i, 8]
        t10 = K[i, 9]
        t11 = K[i, 10]
        t12 = K[i, 11]
        t20 = K[i, 12]
        t21 = K[i, 13]
        t22 = K[i, 14]
        rx = K[i, 15]
        ry = K[i, 16]
        rz = K[i, 17]
        mul = K[i, 28]
        off = K[i, 29]
        qi = q[k] if mul == 1.0 and off == 0.0 else mul * q[k] + off
        if code == PR:
            work[i * WORK + XUP + 0] = t00
            work[i * WORK + XUP + 1] = t01
            work[i * WORK + XUP + 2] = t02
            work[i * WORK + XUP + 3] = t10
            work[i * WORK + XUP + 4] = t11
            work[i * WORK + XUP + 5] = t12
            work[i * WORK + XUP + 6] = t20
            work[i * WORK + XUP + 7] = t21
            work[i * WORK + XUP + 8] = t22
            work[i * WORK + XUP + 9] = rx + (t00 * ax + t10 * ay + t20 * az) * qi
            work[i * WORK + XUP + 10] = ry + (t01 * ax + t11 * ay + t21 * az) * qi
            work[i * WORK + XUP + 11] = rz + (t02 * ax + t12 * ay + t22 * az) * qi
            continue
        c, s = (np.cos(qi), np.sin(qi))
        if code == RZ:
            s = az * s
            work[i * WORK + XUP + 0] = c * t00 + s * t10
            work[i * WORK + XUP + 1] = c * t01 + s * t11
            work[i * WORK + XUP + 2] = c * t02 + s * t12
            work[i * WORK + XUP + 3] = c * t10 - s * t00
            work[i * WORK + XUP + 4] = c * t11 - s * t01
            work[i * WORK + XUP + 5] = c * t12 - s * t02
            work[i * WORK + XUP + 6] = t20
            work[i * WORK + XUP + 7] = t21
            work[i * WORK + XUP + 8] = t22
            work[i * WORK + XUP + 9] = rx
            work[i * WORK + XUP + 10] = ry
            work[i * WORK + XUP + 11] = rz
        elif code == RX:
            s = ax * s
            work[i * WORK + XUP + 0] = t00
            work[i * WORK + XUP + 1] = t01
            work[i * WORK + XUP + 2] = t02
            work[i * WORK + XUP + 3] = c * t10 + s * t20
            work[i * WORK + XUP + 4] = c * t11 + s * t21
            work[i * WORK + XUP + 5] = c * t12 + s * t22
            work[i * WORK + XUP + 6] = c * t20 - s * t10
            work[i * WORK + XUP + 7] = c * t21 - s * t11
            work[i * WORK + XUP + 8] = c * t22 - s * t12
            work[i * WORK + XUP + 9] = rx
            work[i * WORK + XUP + 10] = ry
            work[i * WORK + XUP + 11] = rz
        elif code == RY:
            s = ay * s
            work[i * WORK + XUP + 0] = c * t00 - s * t20
            work[i * WORK + XUP + 1] = c * t01 - s * t21
            work[i * WORK + XUP + 2] = c * t02 - s * t22
            work[i * WORK + XUP + 3] = t10
            work[i * WORK + XUP + 4] = t11
            work[i * WORK + XUP + 5] = t12
            work[i * WORK + XUP + 6] = s * t00 + c * t20
            work[i * WORK + XUP + 7] = s * t01 + c * t21
            work[i * WORK + XUP + 8] = s * t02 + c * t22
            work[i * WORK + XUP + 9] = rx
            work[i * WORK + XUP + 10] = ry
            work[i * WORK + XUP + 11] = rz
        else:
            C = 1.0 - c
            j00, j11, j22 = (c + C * ax * ax, c + C * ay * ay, c + C * az * az)
            cxy, cxz, cyz = (C * ax * ay, C * ax * az, C * ay * az)
            sx, sy, sz = (s * ax, s * ay, s * az)
            j01, j02, j10 = (cxy + sz, cxz - sy, cxy - sz)
            j12, j20, j21 = (cyz + sx, cxz + sy, cyz - sx)
            work[i * WORK + XUP + 0] = j00 * t00 + j01 * t10 + j02 * t20
            work[i * WORK + XUP + 1] = j00 * t01 + j01 * t11 + j02 * t21
            work[i * WORK + XUP + 2] = j00 * t02 + j01 * t12 + j02 * t22
            work[i * WORK + XUP + 3] = j10 * t00 + j11 * t10 + j12 * t20
            work[i * WORK + XUP + 4] = j10 * t01 + j11 * t11 + j12 * t21
            work[i * WORK + XUP + 5] = j10 * t02 + j11 * t12 + j12 * t22
            work[i * WORK + XUP + 6] = j20 * t00 + j21 * t10 + j22 * t20
            work[i * WORK + XUP + 7] = j20 * t01 + j21 * t11 + j22 * t21
            work[i * WORK + XUP + 8] = j20 * t02 + j21 * t12 + j22 * t22
            work[i * WORK + XUP + 9] = rx
            work[i * WORK + XUP + 10] = ry
            work[i * WORK + XUP + 11] = rz


def rnea_kernel(K, q, qd, qdd, gx, gy, gz, f_body, has_fext, tau, work):
    """Run rnea.rnea_kernel of the algorithms, generated from it."""
    NB = K.shape[0] - 1
    zero = 0.0 * gx
    moving = False
    for x in qd:
        if x != 0.0:
            moving = True
            break
    static = not moving
    if static:
        for x in qdd:
            if x != 0.0:
                static = False
                break
    weightless = not (gx != 0.0 or gy != 0.0 or gz != 0.0)
    work[0 * WORK + VEL + 0] = zero
    work[0 * WORK + VEL + 1] = zero
    work[0 * WORK + VEL + 2] = zero
    work[0 * WORK + VEL + 3] = zero
    work[0 * WORK + VEL + 4] = zero
    work[0 * WORK + VEL + 5] = zero
    work[0 * WORK + ACC + 0] = zero
    work[0 * WORK + ACC + 1] = zero
    work[0 * WORK + ACC + 2] = zero
    work[0 * WORK + ACC + 3] = -gx
    work[0 * WORK + ACC + 4] = -gy
    work[0 * WORK + ACC + 5] = -gz
    for k in range(len(tau)):
        tau[k] = zero
    for i in range(1, NB + 1):
        p = int(K[i, 0])
        code = int(K[i, 1])
        k = int(K[i, 2])
        ax = K[i, 3]
        ay = K[i, 4]
        az = K[i, 5]
        mass = K[i, 18]
        hx = K[i, 19]
        hy = K[i, 20]
        hz = K[i, 21]
        Ixx = K[i, 22]
        Ixy = K[i, 23]
        Ixz = K[i, 24]
        Iyy = K[i, 25]
        Iyz = K[i, 26]
        Izz = K[i, 27]
        mul = K[i, 28]
        e00 = work[i * WORK + XUP + 0]
        e01 = work[i * WORK + XUP + 1]
        e02 = work[i * WORK + XUP + 2]
        e10 = work[i * WORK + XUP + 3]
        e11 = work[i * WORK + XUP + 4]
        e12 = work[i * WORK + XUP + 5]
        e20 = work[i * WORK + XUP + 6]
        e21 = work[i * WORK + XUP + 7]
        e22 = work[i * WORK + XUP + 8]
        rx = work[i * WORK + XUP + 9]
        ry = work[i * WORK + XUP + 10]
        rz = work[i * WORK + XUP + 11]
        if static:
            pl0 = work[p * WORK + ACC + 3]
            pl1 = work[p * WORK + ACC + 4]
            pl2 = work[p * WORK + ACC + 5]
            l0 = e00 * pl0 + e01 * pl1 + e02 * pl2
            l1 = e10 * pl0 + e11 * pl1 + e12 * pl2
            l2 = e20 * pl0 + e21 * pl1 + e22 * pl2
            work[i * WORK + ACC + 0] = zero
            work[i * WORK + ACC + 1] = zero
            work[i * WORK + ACC + 2] = zero
            work[i * WORK + ACC + 3] = l0
            work[i * WORK + ACC + 4] = l1
            work[i * WORK + ACC + 5] = l2
            n0, n1, n2 = (hy * l2 - hz * l1, hz * l0 - hx * l2, hx * l1 - hy * l0)
            f0, f1, f2 = (mass * l0, mass * l1, mass * l2)
        else:
            qddi = qdd[k] if mul == 1.0 else mul * qdd[k]
            if p == 0 and weightless:
                a0 = a1 = a2 = l0 = l1 = l2 = zero
            else:
                pa0 = work[p * WORK + ACC + 0]
                pa1 = work[p * WORK + ACC + 1]
                pa2 = work[p * WORK + ACC + 2]
                pl0 = work[p * WORK + ACC + 3]
                pl1 = work[p * WORK + ACC + 4]
                pl2 = work[p * WORK + ACC + 5]
                a0, a1, a2, l0, l1, l2 = X_motion(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, pa0, pa1, pa2, pl0, pl1, pl2)
            if code == PR:
                l0, l1, l2 = (l0 + ax * qddi, l1 + ay * qddi, l2 + az * qddi)
            else:
                a0, a1, a2 = (a0 + ax * qddi, a1 + ay * qddi, a2 + az * qddi)
            w0 = w1 = w2 = v0 = v1 = v2 = zero
            if moving:
                qdi = qd[k] if mul == 1.0 else mul * qd[k]
                pw0 = work[p * WORK + VEL + 0]
                pw1 = work[p * WORK + VEL + 1]
                pw2 = work[p * WORK + VEL + 2]
                pv0 = work[p * WORK + VEL + 3]
                pv1 = work[p * WORK + VEL + 4]
                pv2 = work[p * WORK + VEL + 5]
                w0, w1, w2, v0, v1, v2 = X_motion(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, pw0, pw1, pw2, pv0, pv1, pv2)
                j0, j1, j2 = (ax * qdi, ay * qdi, az * qdi)
                if code == PR:
                    v0, v1, v2 = (v0 + j0, v1 + j1, v2 + j2)
                    l0 += w1 * j2 - w2 * j1
                    l1 += w2 * j0 - w0 * j2
                    l2 += w0 * j1 - w1 * j0
                else:
                    w0, w1, w2 = (w0 + j0, w1 + j1, w2 + j2)
                    a0 += w1 * j2 - w2 * j1
                    a1 += w2 * j0 - w0 * j2
                    a2 += w0 * j1 - w1 * j0
                    l0 += v1 * j2 - v2 * j1
                    l1 += v2 * j0 - v0 * j2
                    l2 += v0 * j1 - v1 * j0
                work[i * WORK + VEL + 0] = w0
                work[i * WORK + VEL + 1] = w1
                work[i * WORK + VEL + 2] = w2
                work[i * WORK + VEL + 3] = v0
                work[i * WORK + VEL + 4] = v1
                work[i * WORK + VEL + 5] = v2
            work[i * WORK + ACC + 0] = a0
            work[i * WORK + ACC + 1] = a1
            work[i * WORK + ACC + 2] = a2
            work[i * WORK + ACC + 3] = l0
            work[i * WORK + ACC + 4] = l1
            work[i * WORK + ACC + 5] = l2
            n0, n1, n2, f0, f1, f2 = I_motion(mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz, a0, a1, a2, l0, l1, l2)
            if moving:
                m0, m1, m2, k0, k1, k2 = I_motion(mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz, w0, w1, w2, v0, v1, v2)
                n0 += w1 * m2 - w2 * m1 + (v1 * k2 - v2 * k1)
                n1 += w2 * m0 - w0 * m2 + (v2 * k0 - v0 * k2)
                n2 += w0 * m1 - w1 * m0 + (v0 * k1 - v1 * k0)
                f0 += w1 * k2 - w2 * k1
                f1 += w2 * k0 - w0 * k2
                f2 += w0 * k1 - w1 * k0
        if has_fext:
            fe0 = f_body[i, 0]
            fe1 = f_body[i, 1]
            fe2 = f_body[i, 2]
            fe3 = f_body[i, 3]
            fe4 = f_body[i, 4]
            fe5 = f_body[i, 5]
            n0, n1, n2 = (n0 - fe0, n1 - fe1, n2 - fe2)
            f0, f1, f2 = (f0 - fe3, f1 - fe4, f2 - fe5)
        work[i * WORK + FRC + 0] = n0
        work[i * WORK + FRC + 1] = n1
        work[i * WORK + FRC + 2] = n2
        work[i * WORK + FRC + 3] = f0
        work[i * WORK + FRC + 4] = f1
        work[i * WORK + FRC + 5] = f2
    for i in range(NB, 0, -1):
        p = int(K[i, 0])
        code = int(K[i, 1])
        k = int(K[i, 2])
        ax = K[i, 3]
        ay = K[i, 4]
        az = K[i, 5]
        mul = K[i, 28]
        n0 = work[i * WORK + FRC + 0]
        n1 = work[i * WORK + FRC + 1]
        n2 = work[i * WORK + FRC + 2]
        f0 = work[i * WORK + FRC + 3]
        f1 = work[i * WORK + FRC + 4]
        f2 = work[i * WORK + FRC + 5]
        if code == PR:
            t = ax * f0 + ay * f1 + az * f2
        else:
            t = ax * n0 + ay * n1 + az * n2
        tau[k] = tau[k] + (t if mul == 1.0 else mul * t)
        if p == 0:
            continue
        e00 = work[i * WORK + XUP + 0]
        e01 = work[i * WORK + XUP + 1]
        e02 = work[i * WORK + XUP + 2]
        e10 = work[i * WORK + XUP + 3]
        e11 = work[i * WORK + XUP + 4]
        e12 = work[i * WORK + XUP + 5]
        e20 = work[i * WORK + XUP + 6]
        e21 = work[i * WORK + XUP + 7]
        e22 = work[i * WORK + XUP + 8]
        rx = work[i * WORK + XUP + 9]
        ry = work[i * WORK + XUP + 10]
        rz = work[i * WORK + XUP + 11]
        g0, g1, g2, g3, g4, g5 = XT_force(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, n0, n1, n2, f0, f1, f2)
        work[p * WORK + FRC + 0] += g0
        work[p * WORK + FRC + 1] += g1
        work[p * WORK + FRC + 2] += g2
        work[p * WORK + FRC + 3] += g3
        work[p * WORK + FRC + 4] += g4
        work[p * WORK + FRC + 5] += g5


def crba_kernel(K, work, H):
    """Run crba.crba_kernel of the algorithms, generated from it."""
    NB = K.shape[0] - 1
    for a in range(len(H)):
        H[a] = 0.0
    for i in range(1, NB + 1):
        mass = K[i, 18]
        hx = K[i, 19]
        hy = K[i, 20]
        hz = K[i, 21]
        Ixx = K[i, 22]
        Ixy = K[i, 23]
        Ixz = K[i, 24]
        Iyy = K[i, 25]
        Iyz = K[i, 26]
        Izz = K[i, 27]
        work[i * WORK + ICS + 0] = mass
        work[i * WORK + ICS + 1] = hx
        work[i * WORK + ICS + 2] = hy
        work[i * WORK + ICS + 3] = hz
        work[i * WORK + ICS + 4] = Ixx
        work[i * WORK + ICS + 5] = Ixy
        work[i * WORK + ICS + 6] = Ixz
        work[i * WORK + ICS + 7] = Iyy
        work[i * WORK + ICS + 8] = Iyz
        work[i * WORK + ICS + 9] = Izz
    for i in range(NB, 0, -1):
        p = int(K[i, 0])
        if p == 0:
            continue
        e00 = work[i * WORK + XUP + 0]
        e01 = work[i * WORK + XUP + 1]
        e02 = work[i * WORK + XUP + 2]
        e10 = work[i * WORK + XUP + 3]
        e11 = work[i * WORK + XUP + 4]
        e12 = work[i * WORK + XUP + 5]
        e20 = work[i * WORK + XUP + 6]
        e21 = work[i * WORK + XUP + 7]
        e22 = work[i * WORK + XUP + 8]
        rx = work[i * WORK + XUP + 9]
        ry = work[i * WORK + XUP + 10]
        rz = work[i * WORK + XUP + 11]
        cm = work[i * WORK + ICS + 0]
        chx = work[i * WORK + ICS + 1]
        chy = work[i * WORK + ICS + 2]
        chz = work[i * WORK + ICS + 3]
        cxx = work[i * WORK + ICS + 4]
        cxy = work[i * WORK + ICS + 5]
        cxz = work[i * WORK + ICS + 6]
        cyy = work[i * WORK + ICS + 7]
        cyz = work[i * WORK + ICS + 8]
        czz = work[i * WORK + ICS + 9]
        d0, d1, d2, d3, d4, d5, d6, d7, d8, d9 = XT_I_X(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, cm, chx, chy, chz, cxx, cxy, cxz, cyy, cyz, czz)
        work[p * WORK + ICS + 0] += d0
        work[p * WORK + ICS + 1] += d1
        work[p * WORK + ICS + 2] += d2
        work[p * WORK + ICS + 3] += d3
        work[p * WORK + ICS + 4] += d4
        work[p * WORK + ICS + 5] += d5
        work[p * WORK + ICS + 6] += d6
        work[p * WORK + ICS + 7] += d7
        work[p * WORK + ICS + 8] += d8
        work[p * WORK + ICS + 9] += d9
    n = int(K[0, 2])
    for i in range(1, NB + 1):
        p = int(K[i, 0])
        code = int(K[i, 1])
        k = int(K[i, 2])
        ax = K[i, 3]
        ay = K[i, 4]
        az = K[i, 5]
        mul = K[i, 28]
        cm = work[i * WORK + ICS + 0]
        chx = work[i * WORK + ICS + 1]
        chy = work[i * WORK + ICS + 2]
        chz = work[i * WORK + ICS + 3]
        cxx = work[i * WORK + ICS + 4]
        cxy = work[i * WORK + ICS + 5]
        cxz = work[i * WORK + ICS + 6]
        cyy = work[i * WORK + ICS + 7]
        cyz = work[i * WORK + ICS + 8]
        czz = work[i * WORK + ICS + 9]
        if code == PR:
            F0, F1, F2, F3, F4, F5 = I_motion(cm, chx, chy, chz, cxx, cxy, cxz, cyy, cyz, czz, 0.0, 0.0, 0.0, ax, ay, az)
            Hii = ax * F3 + ay * F4 + az * F5
        else:
            F0, F1, F2, F3, F4, F5 = I_motion(cm, chx, chy, chz, cxx, cxy, cxz, cyy, cyz, czz, ax, ay, az, 0.0, 0.0, 0.0)
            Hii = ax * F0 + ay * F1 + az * F2
        H[k * n + k] = H[k * n + k] + mul * mul * Hii
        j = i
        pj = p
        while pj != 0:
            e00 = work[j * WORK + XUP + 0]
            e01 = work[j * WORK + XUP + 1]
            e02 = work[j * WORK + XUP + 2]
            e10 = work[j * WORK + XUP + 3]
            e11 = work[j * WORK + XUP + 4]
            e12 = work[j * WORK + XUP + 5]
            e20 = work[j * WORK + XUP + 6]
            e21 = work[j * WORK + XUP + 7]
            e22 = work[j * WORK + XUP + 8]
            rx = work[j * WORK + XUP + 9]
            ry = work[j * WORK + XUP + 10]
            rz = work[j * WORK + XUP + 11]
            F0, F1, F2, F3, F4, F5 = XT_force(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, F0, F1, F2, F3, F4, F5)
            j = pj
            pj = int(K[j, 0])
            cj = int(K[j, 1])
            kj = int(K[j, 2])
            bx = K[j, 3]
            by = K[j, 4]
            bz = K[j, 5]
            mj = K[j, 28]
            if cj == PR:
                Hij = mul * mj * (bx * F3 + by * F4 + bz * F5)
            else:
                Hij = mul * mj * (bx * F0 + by * F1 + bz * F2)
            H[k * n + kj] = H[k * n + kj] + Hij
            H[kj * n + k] = H[kj * n + k] + Hij


def momentum_kernel(K, q, qd, mom, ctq, work):
    """Run momentum.momentum_kernel of the algorithms, generated from it."""
    NB = K.shape[0] - 1
    work[0 * WORK + VEL + 0] = 0.0
    work[0 * WORK + VEL + 1] = 0.0
    work[0 * WORK + VEL + 2] = 0.0
    work[0 * WORK + VEL + 3] = 0.0
    work[0 * WORK + VEL + 4] = 0.0
    work[0 * WORK + VEL + 5] = 0.0
    for k in range(len(mom)):
        mom[k] = 0.0
        ctq[k] = 0.0
    for i in range(1, NB + 1):
        p = int(K[i, 0])
        code = int(K[i, 1])
        k = int(K[i, 2])
        ax = K[i, 3]
        ay = K[i, 4]
        az = K[i, 5]
        mass = K[i, 18]
        hx = K[i, 19]
        hy = K[i, 20]
        hz = K[i, 21]
        Ixx = K[i, 22]
        Ixy = K[i, 23]
        Ixz = K[i, 24]
        Iyy = K[i, 25]
        Iyz = K[i, 26]
        Izz = K[i, 27]
        mul = K[i, 28]
        e00 = work[i * WORK + XUP + 0]
        e01 = work[i * WORK + XUP + 1]
        e02 = work[i * WORK + XUP + 2]
        e10 = work[i * WORK + XUP + 3]
        e11 = work[i * WORK + XUP + 4]
        e12 = work[i * WORK + XUP + 5]
        e20 = work[i * WORK + XUP + 6]
        e21 = work[i * WORK + XUP + 7]
        e22 = work[i * WORK + XUP + 8]
        rx = work[i * WORK + XUP + 9]
        ry = work[i * WORK + XUP + 10]
        rz = work[i * WORK + XUP + 11]
        qdi = qd[k] if mul == 1.0 else mul * qd[k]
        pw0 = work[p * WORK + VEL + 0]
        pw1 = work[p * WORK + VEL + 1]
        pw2 = work[p * WORK + VEL + 2]
        pv0 = work[p * WORK + VEL + 3]
        pv1 = work[p * WORK + VEL + 4]
        pv2 = work[p * WORK + VEL + 5]
        w0, w1, w2, v0, v1, v2 = X_motion(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, pw0, pw1, pw2, pv0, pv1, pv2)
        if code == PR:
            v0, v1, v2 = (v0 + ax * qdi, v1 + ay * qdi, v2 + az * qdi)
        else:
            w0, w1, w2 = (w0 + ax * qdi, w1 + ay * qdi, w2 + az * qdi)
        work[i * WORK + VEL + 0] = w0
        work[i * WORK + VEL + 1] = w1
        work[i * WORK + VEL + 2] = w2
        work[i * WORK + VEL + 3] = v0
        work[i * WORK + VEL + 4] = v1
        work[i * WORK + VEL + 5] = v2
        m0, m1, m2, k0, k1, k2 = I_motion(mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz, w0, w1, w2, v0, v1, v2)
        work[i * WORK + FRC + 0] = m0
        work[i * WORK + FRC + 1] = m1
        work[i * WORK + FRC + 2] = m2
        work[i * WORK + FRC + 3] = k0
        work[i * WORK + FRC + 4] = k1
        work[i * WORK + FRC + 5] = k2
    for i in range(NB, 0, -1):
        p = int(K[i, 0])
        code = int(K[i, 1])
        k = int(K[i, 2])
        ax = K[i, 3]
        ay = K[i, 4]
        az = K[i, 5]
        mul = K[i, 28]
        n0 = work[i * WORK + FRC + 0]
        n1 = work[i * WORK + FRC + 1]
        n2 = work[i * WORK + FRC + 2]
        f0 = work[i * WORK + FRC + 3]
        f1 = work[i * WORK + FRC + 4]
        f2 = work[i * WORK + FRC + 5]
        w0 = work[i * WORK + VEL + 0]
        w1 = work[i * WORK + VEL + 1]
        w2 = work[i * WORK + VEL + 2]
        v0 = work[i * WORK + VEL + 3]
        v1 = work[i * WORK + VEL + 4]
        v2 = work[i * WORK + VEL + 5]
        c0, c1, c2 = (w1 * az - w2 * ay, w2 * ax - w0 * az, w0 * ay - w1 * ax)
        if code == PR:
            t = ax * f0 + ay * f1 + az * f2
            c = c0 * f0 + c1 * f1 + c2 * f2
        else:
            t = ax * n0 + ay * n1 + az * n2
            c = c0 * n0 + c1 * n1 + c2 * n2 + (v1 * az - v2 * ay) * f0 + (v2 * ax - v0 * az) * f1 + (v0 * ay - v1 * ax) * f2
        mom[k] = mom[k] + (t if mul == 1.0 else mul * t)
        ctq[k] = ctq[k] + (c if mul == 1.0 else mul * c)
        if p == 0:
            continue
        e00 = work[i * WORK + XUP + 0]
        e01 = work[i * WORK + XUP + 1]
        e02 = work[i * WORK + XUP + 2]
        e10 = work[i * WORK + XUP + 3]
        e11 = work[i * WORK + XUP + 4]
        e12 = work[i * WORK + XUP + 5]
        e20 = work[i * WORK + XUP + 6]
        e21 = work[i * WORK + XUP + 7]
        e22 = work[i * WORK + XUP + 8]
        rx = work[i * WORK + XUP + 9]
        ry = work[i * WORK + XUP + 10]
        rz = work[i * WORK + XUP + 11]
        g0, g1, g2, g3, g4, g5 = XT_force(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, n0, n1, n2, f0, f1, f2)
        work[p * WORK + FRC + 0] += g0
        work[p * WORK + FRC + 1] += g1
        work[p * WORK + FRC + 2] += g2
        work[p * WORK + FRC + 3] += g3
        work[p * WORK + FRC + 4] += g4
        work[p * WORK + FRC + 5] += g5


def regressor_kernel(K, qd, qdd, gx, gy, gz, Y, axes, work):
    """Run regressor.regressor_kernel of the algorithms, generated from it."""
    NB = K.shape[0] - 1
    R = K.shape[0]
    W = 10 * NB
    zero = 0.0 * gx
    for c in range(len(Y)):
        Y[c] = zero
    work[0 * WORK + VEL + 0] = zero
    work[0 * WORK + VEL + 1] = zero
    work[0 * WORK + VEL + 2] = zero
    work[0 * WORK + VEL + 3] = zero
    work[0 * WORK + VEL + 4] = zero
    work[0 * WORK + VEL + 5] = zero
    work[0 * WORK + ACC + 0] = zero
    work[0 * WORK + ACC + 1] = zero
    work[0 * WORK + ACC + 2] = zero
    work[0 * WORK + ACC + 3] = -gx
    work[0 * WORK + ACC + 4] = -gy
    work[0 * WORK + ACC + 5] = -gz
    for i in range(1, NB + 1):
        p = int(K[i, 0])
        code = int(K[i, 1])
        k = int(K[i, 2])
        ax = K[i, 3]
        ay = K[i, 4]
        az = K[i, 5]
        mul = K[i, 28]
        e00 = work[i * WORK + XUP + 0]
        e01 = work[i * WORK + XUP + 1]
        e02 = work[i * WORK + XUP + 2]
        e10 = work[i * WORK + XUP + 3]
        e11 = work[i * WORK + XUP + 4]
        e12 = work[i * WORK + XUP + 5]
        e20 = work[i * WORK + XUP + 6]
        e21 = work[i * WORK + XUP + 7]
        e22 = work[i * WORK + XUP + 8]
        rx = work[i * WORK + XUP + 9]
        ry = work[i * WORK + XUP + 10]
        rz = work[i * WORK + XUP + 11]
        qdi = qd[k] if mul == 1.0 else mul * qd[k]
        qddi = qdd[k] if mul == 1.0 else mul * qdd[k]
        pw0 = work[p * WORK + VEL + 0]
        pw1 = work[p * WORK + VEL + 1]
        pw2 = work[p * WORK + VEL + 2]
        pv0 = work[p * WORK + VEL + 3]
        pv1 = work[p * WORK + VEL + 4]
        pv2 = work[p * WORK + VEL + 5]
        w0, w1, w2, v0, v1, v2 = X_motion(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, pw0, pw1, pw2, pv0, pv1, pv2)
        pa0 = work[p * WORK + ACC + 0]
        pa1 = work[p * WORK + ACC + 1]
        pa2 = work[p * WORK + ACC + 2]
        pl0 = work[p * WORK + ACC + 3]
        pl1 = work[p * WORK + ACC + 4]
        pl2 = work[p * WORK + ACC + 5]
        a0, a1, a2, l0, l1, l2 = X_motion(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, pa0, pa1, pa2, pl0, pl1, pl2)
        j0, j1, j2 = (ax * qdi, ay * qdi, az * qdi)
        if code == PR:
            v0, v1, v2 = (v0 + j0, v1 + j1, v2 + j2)
            l0, l1, l2 = (l0 + ax * qddi, l1 + ay * qddi, l2 + az * qddi)
            l0 += w1 * j2 - w2 * j1
            l1 += w2 * j0 - w0 * j2
            l2 += w0 * j1 - w1 * j0
            s0, s1, s2, s3, s4, s5 = (zero, zero, zero, mul * ax, mul * ay, mul * az)
        else:
            w0, w1, w2 = (w0 + j0, w1 + j1, w2 + j2)
            a0, a1, a2 = (a0 + ax * qddi, a1 + ay * qddi, a2 + az * qddi)
            a0 += w1 * j2 - w2 * j1
            a1 += w2 * j0 - w0 * j2
            a2 += w0 * j1 - w1 * j0
            l0 += v1 * j2 - v2 * j1
            l1 += v2 * j0 - v0 * j2
            l2 += v0 * j1 - v1 * j0
            s0, s1, s2, s3, s4, s5 = (mul * ax, mul * ay, mul * az, zero, zero, zero)
        work[i * WORK + VEL + 0] = w0
        work[i * WORK + VEL + 1] = w1
        work[i * WORK + VEL + 2] = w2
        work[i * WORK + VEL + 3] = v0
        work[i * WORK + VEL + 4] = v1
        work[i * WORK + VEL + 5] = v2
        work[i * WORK + ACC + 0] = a0
        work[i * WORK + ACC + 1] = a1
        work[i * WORK + ACC + 2] = a2
        work[i * WORK + ACC + 3] = l0
        work[i * WORK + ACC + 4] = l1
        work[i * WORK + ACC + 5] = l2
        al0 = l0 + (w1 * v2 - w2 * v1)
        al1 = l1 + (w2 * v0 - w0 * v2)
        al2 = l2 + (w0 * v1 - w1 * v0)
        p01, p02, p12 = (w0 * w1, w0 * w2, w1 * w2)
        q00, q11, q22 = (w0 * w0, w1 * w1, w2 * w2)
        b00, b11, b22 = (-(q11 + q22), -(q00 + q22), -(q00 + q11))
        b01, b10 = (p01 - a2, p01 + a2)
        b02, b20 = (p02 + a1, p02 - a1)
        b12, b21 = (p12 - a0, p12 + a0)
        xx0, xx1, xx2 = (a0, p02, -p01)
        xy0, xy1, xy2 = (a1 - p02, a0 + p12, q00 - q11)
        yy0, yy1, yy2 = (-p12, a1, p01)
        xz0, xz1, xz2 = (a2 + p01, q22 - q00, a0 - p12)
        yz0, yz1, yz2 = (q11 - q22, a2 - p01, a1 + p02)
        zz0, zz1, zz2 = (p12, -p02, a2)
        j = i
        while j != 0:
            pj = int(K[j, 0])
            kj = int(K[j, 2])
            if j == i:
                t0, t1, t2, u0, u1, u2 = (s0, s1, s2, s3, s4, s5)
            else:
                c = 6 * (p * R + j)
                t0, t1, t2, u0, u1, u2 = X_motion(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, axes[c], axes[c + 1], axes[c + 2], axes[c + 3], axes[c + 4], axes[c + 5])
            c = 6 * (i * R + j)
            axes[c] = t0
            axes[c + 1] = t1
            axes[c + 2] = t2
            axes[c + 3] = u0
            axes[c + 4] = u1
            axes[c + 5] = u2
            y = kj * W + 10 * (i - 1)
            Y[y] = Y[y] + (u0 * al0 + u1 * al1 + u2 * al2)
            Y[y + 1] = Y[y + 1] + (al1 * t2 - al2 * t1 + (b00 * u0 + b10 * u1 + b20 * u2))
            Y[y + 2] = Y[y + 2] + (al2 * t0 - al0 * t2 + (b01 * u0 + b11 * u1 + b21 * u2))
            Y[y + 3] = Y[y + 3] + (al0 * t1 - al1 * t0 + (b02 * u0 + b12 * u1 + b22 * u2))
            Y[y + 4] = Y[y + 4] + (t0 * xx0 + t1 * xx1 + t2 * xx2)
            Y[y + 5] = Y[y + 5] + (t0 * xy0 + t1 * xy1 + t2 * xy2)
            Y[y + 6] = Y[y + 6] + (t0 * yy0 + t1 * yy1 + t2 * yy2)
            Y[y + 7] = Y[y + 7] + (t0 * xz0 + t1 * xz1 + t2 * xz2)
            Y[y + 8] = Y[y + 8] + (t0 * yz0 + t1 * yz1 + t2 * yz2)
            Y[y + 9] = Y[y + 9] + (t0 * zz0 + t1 * zz1 + t2 * zz2)
            j = pj
