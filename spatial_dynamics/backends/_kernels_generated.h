/* Copyright 2026 spatial_dynamics contributors
 * SPDX-License-Identifier: Apache-2.0
 *
 * Kernels generated from spatial_dynamics.algorithms: do not edit.
 * Change the source and run `python -m spatial_dynamics.backends.codegen`.
 * Included by _compiled.c; compile without fused multiply-adds (-ffp-contract=off).
 */
#ifndef SPATIAL_DYNAMICS_KERNELS_GENERATED_H
#define SPATIAL_DYNAMICS_KERNELS_GENERATED_H

#include <math.h>

enum {
    RX = 0,
    RY = 1,
    RZ = 2,
    RA = 3,
    PR = 4,
    WORK = 40,
    XUP = 0,
    VEL = 12,
    ACC = 18,
    FRC = 24,
    ICS = 30,
    WIDTH = 30,
    QIDX = 2
};

/* Run components.X_motion of the algorithms, generated from it. */
static inline void X_motion(double e00, double e01, double e02, double e10, double e11, double e12,
    double e20, double e21, double e22, double rx, double ry, double rz, double m0, double m1,
    double m2, double m3, double m4, double m5, double *out)
{
    double u0, u1, u2;
    u0 = m3 - (ry * m2 - rz * m1);
    u1 = m4 - (rz * m0 - rx * m2);
    u2 = m5 - (rx * m1 - ry * m0);
    out[0] = e00 * m0 + e01 * m1 + e02 * m2;
    out[1] = e10 * m0 + e11 * m1 + e12 * m2;
    out[2] = e20 * m0 + e21 * m1 + e22 * m2;
    out[3] = e00 * u0 + e01 * u1 + e02 * u2;
    out[4] = e10 * u0 + e11 * u1 + e12 * u2;
    out[5] = e20 * u0 + e21 * u1 + e22 * u2;
}

/* Run components.XT_force of the algorithms, generated from it. */
static inline void XT_force(double e00, double e01, double e02, double e10, double e11, double e12,
    double e20, double e21, double e22, double rx, double ry, double rz, double n0, double n1,
    double n2, double f0, double f1, double f2, double *out)
{
    double F0, F1, F2;
    F0 = e00 * f0 + e10 * f1 + e20 * f2;
    F1 = e01 * f0 + e11 * f1 + e21 * f2;
    F2 = e02 * f0 + e12 * f1 + e22 * f2;
    out[0] = e00 * n0 + e10 * n1 + e20 * n2 + (ry * F2 - rz * F1);
    out[1] = e01 * n0 + e11 * n1 + e21 * n2 + (rz * F0 - rx * F2);
    out[2] = e02 * n0 + e12 * n1 + e22 * n2 + (rx * F1 - ry * F0);
    out[3] = F0;
    out[4] = F1;
    out[5] = F2;
}

/* Run components.I_motion of the algorithms, generated from it. */
static inline void I_motion(double mass, double hx, double hy, double hz, double Ixx, double Ixy,
    double Ixz, double Iyy, double Iyz, double Izz, double m0, double m1, double m2, double m3,
    double m4, double m5, double *out)
{
    out[0] = Ixx * m0 + Ixy * m1 + Ixz * m2 + (hy * m5 - hz * m4);
    out[1] = Ixy * m0 + Iyy * m1 + Iyz * m2 + (hz * m3 - hx * m5);
    out[2] = Ixz * m0 + Iyz * m1 + Izz * m2 + (hx * m4 - hy * m3);
    out[3] = mass * m3 - (hy * m2 - hz * m1);
    out[4] = mass * m4 - (hz * m0 - hx * m2);
    out[5] = mass * m5 - (hx * m1 - hy * m0);
}

/* Run components.XT_I_X of the algorithms, generated from it. */
static inline void XT_I_X(double e00, double e01, double e02, double e10, double e11, double e12,
    double e20, double e21, double e22, double rx, double ry, double rz, double mass, double hx,
    double hy, double hz, double Ixx, double Ixy, double Ixz, double Iyy, double Iyz, double Izz,
    double *out)
{
    double b00, b01, b02, b11, b12, b22, d, mr0, mr1, mr2, t00, t01;
    double t02, t10, t11, t12, t20, t21, t22, y0, y1, y2;
    y0 = e00 * hx + e10 * hy + e20 * hz;
    y1 = e01 * hx + e11 * hy + e21 * hz;
    y2 = e02 * hx + e12 * hy + e22 * hz;
    t00 = Ixx * e00 + Ixy * e10 + Ixz * e20;
    t01 = Ixx * e01 + Ixy * e11 + Ixz * e21;
    t02 = Ixx * e02 + Ixy * e12 + Ixz * e22;
    t10 = Ixy * e00 + Iyy * e10 + Iyz * e20;
    t11 = Ixy * e01 + Iyy * e11 + Iyz * e21;
    t12 = Ixy * e02 + Iyy * e12 + Iyz * e22;
    t20 = Ixz * e00 + Iyz * e10 + Izz * e20;
    t21 = Ixz * e01 + Iyz * e11 + Izz * e21;
    t22 = Ixz * e02 + Iyz * e12 + Izz * e22;
    b00 = e00 * t00 + e10 * t10 + e20 * t20;
    b01 = e00 * t01 + e10 * t11 + e20 * t21;
    b02 = e00 * t02 + e10 * t12 + e20 * t22;
    b11 = e01 * t01 + e11 * t11 + e21 * t21;
    b12 = e01 * t02 + e11 * t12 + e21 * t22;
    b22 = e02 * t02 + e12 * t12 + e22 * t22;
    {
        const double tmp1_ = mass * rx;
        const double tmp2_ = mass * ry;
        const double tmp3_ = mass * rz;
        mr0 = tmp1_;
        mr1 = tmp2_;
        mr2 = tmp3_;
    }
    d = 2.0 * (rx * y0 + ry * y1 + rz * y2) + (mr0 * rx + mr1 * ry + mr2 * rz);
    out[0] = mass;
    out[1] = y0 + mr0;
    out[2] = y1 + mr1;
    out[3] = y2 + mr2;
    out[4] = b00 - (2.0 * y0 * rx + mr0 * rx) + d;
    out[5] = b01 - (y0 * ry + rx * y1 + mr0 * ry);
    out[6] = b02 - (y0 * rz + rx * y2 + mr0 * rz);
    out[7] = b11 - (2.0 * y1 * ry + mr1 * ry) + d;
    out[8] = b12 - (y1 * rz + ry * y2 + mr1 * rz);
    out[9] = b22 - (2.0 * y2 * rz + mr2 * rz) + d;
}

/* Run rnea.xup_kernel of the algorithms, generated from it. */
static inline void xup_kernel(const double *K, long rows, const double *q, double *work)
{
    long code, i, k;
    double C, ax, ay, az, c, cxy, cxz, cyz, j00, j01, j02, j10;
    double j11, j12, j20, j21, j22, mul, off, qi, rx, ry, rz, s;
    double sx, sy, sz, t00, t01, t02, t10, t11, t12, t20, t21, t22;
    for (i = 1; i < rows; i++) {
        code = (long)K[i * WIDTH + 1];
        k = (long)K[i * WIDTH + 2];
        ax = K[i * WIDTH + 3];
        ay = K[i * WIDTH + 4];
        az = K[i * WIDTH + 5];
        t00 = K[i * WIDTH + 6];
        t01 = K[i * WIDTH + 7];
        t02 = K[i * WIDTH + 8];
        t10 = K[i * WIDTH + 9];
        t11 = K[i * WIDTH + 10];
        t12 = K[i * WIDTH + 11];
        t20 = K[i * WIDTH + 12];
        t21 = K[i * WIDTH + 13];
        t22 = K[i * WIDTH + 14];
        rx = K[i * WIDTH + 15];
        ry = K[i * WIDTH + 16];
        rz = K[i * WIDTH + 17];
        mul = K[i * WIDTH + 28];
        off = K[i * WIDTH + 29];
        qi = (mul == 1.0 && off == 0.0 ? q[k] : mul * q[k] + off);
        if (code == PR) {
            work[i * WORK + XUP + 0] = t00;
            work[i * WORK + XUP + 1] = t01;
            work[i * WORK + XUP + 2] = t02;
            work[i * WORK + XUP + 3] = t10;
            work[i * WORK + XUP + 4] = t11;
            work[i * WORK + XUP + 5] = t12;
            work[i * WORK + XUP + 6] = t20;
            work[i * WORK + XUP + 7] = t21;
            work[i * WORK + XUP + 8] = t22;
            work[i * WORK + XUP + 9] = rx + (t00 * ax + t10 * ay + t20 * az) * qi;
            work[i * WORK + XUP + 10] = ry + (t01 * ax + t11 * ay + t21 * az) * qi;
            work[i * WORK + XUP + 11] = rz + (t02 * ax + t12 * ay + t22 * az) * qi;
            continue;
        }
        {
            const double tmp1_ = cos(qi);
            const double tmp2_ = sin(qi);
            c = tmp1_;
            s = tmp2_;
        }
        if (code == RZ) {
            s = az * s;
            work[i * WORK + XUP + 0] = c * t00 + s * t10;
            work[i * WORK + XUP + 1] = c * t01 + s * t11;
            work[i * WORK + XUP + 2] = c * t02 + s * t12;
            work[i * WORK + XUP + 3] = c * t10 - s * t00;
            work[i * WORK + XUP + 4] = c * t11 - s * t01;
            work[i * WORK + XUP + 5] = c * t12 - s * t02;
            work[i * WORK + XUP + 6] = t20;
            work[i * WORK + XUP + 7] = t21;
            work[i * WORK + XUP + 8] = t22;
            work[i * WORK + XUP + 9] = rx;
            work[i * WORK + XUP + 10] = ry;
            work[i * WORK + XUP + 11] = rz;
        } else if (code == RX) {
            s = ax * s;
            work[i * WORK + XUP + 0] = t00;
            work[i * WORK + XUP + 1] = t01;
            work[i * WORK + XUP + 2] = t02;
            work[i * WORK + XUP + 3] = c * t10 + s * t20;
            work[i * WORK + XUP + 4] = c * t11 + s * t21;
            work[i * WORK + XUP + 5] = c * t12 + s * t22;
            work[i * WORK + XUP + 6] = c * t20 - s * t10;
            work[i * WORK + XUP + 7] = c * t21 - s * t11;
            work[i * WORK + XUP + 8] = c * t22 - s * t12;
            work[i * WORK + XUP + 9] = rx;
            work[i * WORK + XUP + 10] = ry;
            work[i * WORK + XUP + 11] = rz;
        } else if (code == RY) {
            s = ay * s;
            work[i * WORK + XUP + 0] = c * t00 - s * t20;
            work[i * WORK + XUP + 1] = c * t01 - s * t21;
            work[i * WORK + XUP + 2] = c * t02 - s * t22;
            work[i * WORK + XUP + 3] = t10;
            work[i * WORK + XUP + 4] = t11;
            work[i * WORK + XUP + 5] = t12;
            work[i * WORK + XUP + 6] = s * t00 + c * t20;
            work[i * WORK + XUP + 7] = s * t01 + c * t21;
            work[i * WORK + XUP + 8] = s * t02 + c * t22;
            work[i * WORK + XUP + 9] = rx;
            work[i * WORK + XUP + 10] = ry;
            work[i * WORK + XUP + 11] = rz;
        } else {
            C = 1.0 - c;
            {
                const double tmp3_ = c + C * ax * ax;
                const double tmp4_ = c + C * ay * ay;
                const double tmp5_ = c + C * az * az;
                j00 = tmp3_;
                j11 = tmp4_;
                j22 = tmp5_;
            }
            {
                const double tmp6_ = C * ax * ay;
                const double tmp7_ = C * ax * az;
                const double tmp8_ = C * ay * az;
                cxy = tmp6_;
                cxz = tmp7_;
                cyz = tmp8_;
            }
            {
                const double tmp9_ = s * ax;
                const double tmp10_ = s * ay;
                const double tmp11_ = s * az;
                sx = tmp9_;
                sy = tmp10_;
                sz = tmp11_;
            }
            {
                const double tmp12_ = cxy + sz;
                const double tmp13_ = cxz - sy;
                const double tmp14_ = cxy - sz;
                j01 = tmp12_;
                j02 = tmp13_;
                j10 = tmp14_;
            }
            {
                const double tmp15_ = cyz + sx;
                const double tmp16_ = cxz + sy;
                const double tmp17_ = cyz - sx;
                j12 = tmp15_;
                j20 = tmp16_;
                j21 = tmp17_;
            }
            work[i * WORK + XUP + 0] = j00 * t00 + j01 * t10 + j02 * t20;
            work[i * WORK + XUP + 1] = j00 * t01 + j01 * t11 + j02 * t21;
            work[i * WORK + XUP + 2] = j00 * t02 + j01 * t12 + j02 * t22;
            work[i * WORK + XUP + 3] = j10 * t00 + j11 * t10 + j12 * t20;
            work[i * WORK + XUP + 4] = j10 * t01 + j11 * t11 + j12 * t21;
            work[i * WORK + XUP + 5] = j10 * t02 + j11 * t12 + j12 * t22;
            work[i * WORK + XUP + 6] = j20 * t00 + j21 * t10 + j22 * t20;
            work[i * WORK + XUP + 7] = j20 * t01 + j21 * t11 + j22 * t21;
            work[i * WORK + XUP + 8] = j20 * t02 + j21 * t12 + j22 * t22;
            work[i * WORK + XUP + 9] = rx;
            work[i * WORK + XUP + 10] = ry;
            work[i * WORK + XUP + 11] = rz;
        }
    }
}

/* Run rnea.rnea_kernel of the algorithms, generated from it. */
static inline void rnea_kernel(const double *K, long rows, const double *q, const double *qd,
    const double *qdd, double gx, double gy, double gz, const double *f_body, long has_fext,
    double *tau, double *work)
{
    (void)q;
    const long nq = (long)K[QIDX];
    long NB, code, i, k, moving, p, static_, weightless;
    double Ixx, Ixy, Ixz, Iyy, Iyz, Izz, a0, a1, a2, ax, ay, az;
    double e00, e01, e02, e10, e11, e12, e20, e21, e22, f0, f1, f2;
    double fe0, fe1, fe2, fe3, fe4, fe5, g0, g1, g2, g3, g4, g5;
    double hx, hy, hz, j0, j1, j2, k0, k1, k2, l0, l1, l2;
    double m0, m1, m2, mass, mul, n0, n1, n2, pa0, pa1, pa2, pl0;
    double pl1, pl2, pv0, pv1, pv2, pw0, pw1, pw2, qddi, qdi, rx, ry;
    double rz, t, v0, v1, v2, w0, w1, w2, x, zero;
    NB = rows - 1;
    zero = 0.0 * gx;
    moving = 0;
    for (long j1_ = 0; j1_ < nq; j1_++) {
        x = qd[j1_];
        if (x != 0.0) {
            moving = 1;
            break;
        }
    }
    static_ = !moving;
    if (static_) {
        for (long j2_ = 0; j2_ < nq; j2_++) {
            x = qdd[j2_];
            if (x != 0.0) {
                static_ = 0;
                break;
            }
        }
    }
    weightless = !(gx != 0.0 || gy != 0.0 || gz != 0.0);
    work[0 * WORK + VEL + 0] = zero;
    work[0 * WORK + VEL + 1] = zero;
    work[0 * WORK + VEL + 2] = zero;
    work[0 * WORK + VEL + 3] = zero;
    work[0 * WORK + VEL + 4] = zero;
    work[0 * WORK + VEL + 5] = zero;
    work[0 * WORK + ACC + 0] = zero;
    work[0 * WORK + ACC + 1] = zero;
    work[0 * WORK + ACC + 2] = zero;
    work[0 * WORK + ACC + 3] = -gx;
    work[0 * WORK + ACC + 4] = -gy;
    work[0 * WORK + ACC + 5] = -gz;
    for (k = 0; k < nq; k++) {
        tau[k] = zero;
    }
    for (i = 1; i < NB + 1; i++) {
        p = (long)K[i * WIDTH + 0];
        code = (long)K[i * WIDTH + 1];
        k = (long)K[i * WIDTH + 2];
        ax = K[i * WIDTH + 3];
        ay = K[i * WIDTH + 4];
        az = K[i * WIDTH + 5];
        mass = K[i * WIDTH + 18];
        hx = K[i * WIDTH + 19];
        hy = K[i * WIDTH + 20];
        hz = K[i * WIDTH + 21];
        Ixx = K[i * WIDTH + 22];
        Ixy = K[i * WIDTH + 23];
        Ixz = K[i * WIDTH + 24];
        Iyy = K[i * WIDTH + 25];
        Iyz = K[i * WIDTH + 26];
        Izz = K[i * WIDTH + 27];
        mul = K[i * WIDTH + 28];
        e00 = work[i * WORK + XUP + 0];
        e01 = work[i * WORK + XUP + 1];
        e02 = work[i * WORK + XUP + 2];
        e10 = work[i * WORK + XUP + 3];
        e11 = work[i * WORK + XUP + 4];
        e12 = work[i * WORK + XUP + 5];
        e20 = work[i * WORK + XUP + 6];
        e21 = work[i * WORK + XUP + 7];
        e22 = work[i * WORK + XUP + 8];
        rx = work[i * WORK + XUP + 9];
        ry = work[i * WORK + XUP + 10];
        rz = work[i * WORK + XUP + 11];
        if (static_) {
            pl0 = work[p * WORK + ACC + 3];
            pl1 = work[p * WORK + ACC + 4];
            pl2 = work[p * WORK + ACC + 5];
            l0 = e00 * pl0 + e01 * pl1 + e02 * pl2;
            l1 = e10 * pl0 + e11 * pl1 + e12 * pl2;
            l2 = e20 * pl0 + e21 * pl1 + e22 * pl2;
            work[i * WORK + ACC + 0] = zero;
            work[i * WORK + ACC + 1] = zero;
            work[i * WORK + ACC + 2] = zero;
            work[i * WORK + ACC + 3] = l0;
            work[i * WORK + ACC + 4] = l1;
            work[i * WORK + ACC + 5] = l2;
            {
                const double tmp3_ = hy * l2 - hz * l1;
                const double tmp4_ = hz * l0 - hx * l2;
                const double tmp5_ = hx * l1 - hy * l0;
                n0 = tmp3_;
                n1 = tmp4_;
                n2 = tmp5_;
            }
            {
                const double tmp6_ = mass * l0;
                const double tmp7_ = mass * l1;
                const double tmp8_ = mass * l2;
                f0 = tmp6_;
                f1 = tmp7_;
                f2 = tmp8_;
            }
        } else {
            qddi = (mul == 1.0 ? qdd[k] : mul * qdd[k]);
            if (p == 0 && weightless) {
                a0 = a1 = a2 = l0 = l1 = l2 = zero;
            } else {
                pa0 = work[p * WORK + ACC + 0];
                pa1 = work[p * WORK + ACC + 1];
                pa2 = work[p * WORK + ACC + 2];
                pl0 = work[p * WORK + ACC + 3];
                pl1 = work[p * WORK + ACC + 4];
                pl2 = work[p * WORK + ACC + 5];
                {
                    double ret9_[6];
                    X_motion(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, pa0, pa1, pa2, pl0, pl1, pl2, ret9_);
                    a0 = ret9_[0];
                    a1 = ret9_[1];
                    a2 = ret9_[2];
                    l0 = ret9_[3];
                    l1 = ret9_[4];
                    l2 = ret9_[5];
                }
            }
            if (code == PR) {
                {
                    const double tmp10_ = l0 + ax * qddi;
                    const double tmp11_ = l1 + ay * qddi;
                    const double tmp12_ = l2 + az * qddi;
                    l0 = tmp10_;
                    l1 = tmp11_;
                    l2 = tmp12_;
                }
            } else {
                {
                    const double tmp13_ = a0 + ax * qddi;
                    const double tmp14_ = a1 + ay * qddi;
                    const double tmp15_ = a2 + az * qddi;
                    a0 = tmp13_;
                    a1 = tmp14_;
                    a2 = tmp15_;
                }
            }
            w0 = w1 = w2 = v0 = v1 = v2 = zero;
            if (moving) {
                qdi = (mul == 1.0 ? qd[k] : mul * qd[k]);
                pw0 = work[p * WORK + VEL + 0];
                pw1 = work[p * WORK + VEL + 1];
                pw2 = work[p * WORK + VEL + 2];
                pv0 = work[p * WORK + VEL + 3];
                pv1 = work[p * WORK + VEL + 4];
                pv2 = work[p * WORK + VEL + 5];
                {
                    double ret16_[6];
                    X_motion(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, pw0, pw1, pw2, pv0, pv1, pv2, ret16_);
                    w0 = ret16_[0];
                    w1 = ret16_[1];
                    w2 = ret16_[2];
                    v0 = ret16_[3];
                    v1 = ret16_[4];
                    v2 = ret16_[5];
                }
                {
                    const double tmp17_ = ax * qdi;
                    const double tmp18_ = ay * qdi;
                    const double tmp19_ = az * qdi;
                    j0 = tmp17_;
                    j1 = tmp18_;
                    j2 = tmp19_;
                }
                if (code == PR) {
                    {
                        const double tmp20_ = v0 + j0;
                        const double tmp21_ = v1 + j1;
                        const double tmp22_ = v2 + j2;
                        v0 = tmp20_;
                        v1 = tmp21_;
                        v2 = tmp22_;
                    }
                    l0 += w1 * j2 - w2 * j1;
                    l1 += w2 * j0 - w0 * j2;
                    l2 += w0 * j1 - w1 * j0;
                } else {
                    {
                        const double tmp23_ = w0 + j0;
                        const double tmp24_ = w1 + j1;
                        const double tmp25_ = w2 + j2;
                        w0 = tmp23_;
                        w1 = tmp24_;
                        w2 = tmp25_;
                    }
                    a0 += w1 * j2 - w2 * j1;
                    a1 += w2 * j0 - w0 * j2;
                    a2 += w0 * j1 - w1 * j0;
                    l0 += v1 * j2 - v2 * j1;
                    l1 += v2 * j0 - v0 * j2;
                    l2 += v0 * j1 - v1 * j0;
                }
                work[i * WORK + VEL + 0] = w0;
                work[i * WORK + VEL + 1] = w1;
                work[i * WORK + VEL + 2] = w2;
                work[i * WORK + VEL + 3] = v0;
                work[i * WORK + VEL + 4] = v1;
                work[i * WORK + VEL + 5] = v2;
            }
            work[i * WORK + ACC + 0] = a0;
            work[i * WORK + ACC + 1] = a1;
            work[i * WORK + ACC + 2] = a2;
            work[i * WORK + ACC + 3] = l0;
            work[i * WORK + ACC + 4] = l1;
            work[i * WORK + ACC + 5] = l2;
            {
                double ret26_[6];
                I_motion(mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz, a0, a1, a2, l0, l1, l2, ret26_);
                n0 = ret26_[0];
                n1 = ret26_[1];
                n2 = ret26_[2];
                f0 = ret26_[3];
                f1 = ret26_[4];
                f2 = ret26_[5];
            }
            if (moving) {
                {
                    double ret27_[6];
                    I_motion(mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz, w0, w1, w2, v0, v1, v2, ret27_);
                    m0 = ret27_[0];
                    m1 = ret27_[1];
                    m2 = ret27_[2];
                    k0 = ret27_[3];
                    k1 = ret27_[4];
                    k2 = ret27_[5];
                }
                n0 += w1 * m2 - w2 * m1 + (v1 * k2 - v2 * k1);
                n1 += w2 * m0 - w0 * m2 + (v2 * k0 - v0 * k2);
                n2 += w0 * m1 - w1 * m0 + (v0 * k1 - v1 * k0);
                f0 += w1 * k2 - w2 * k1;
                f1 += w2 * k0 - w0 * k2;
                f2 += w0 * k1 - w1 * k0;
            }
        }
        if (has_fext) {
            fe0 = f_body[i * 6 + 0];
            fe1 = f_body[i * 6 + 1];
            fe2 = f_body[i * 6 + 2];
            fe3 = f_body[i * 6 + 3];
            fe4 = f_body[i * 6 + 4];
            fe5 = f_body[i * 6 + 5];
            {
                const double tmp28_ = n0 - fe0;
                const double tmp29_ = n1 - fe1;
                const double tmp30_ = n2 - fe2;
                n0 = tmp28_;
                n1 = tmp29_;
                n2 = tmp30_;
            }
            {
                const double tmp31_ = f0 - fe3;
                const double tmp32_ = f1 - fe4;
                const double tmp33_ = f2 - fe5;
                f0 = tmp31_;
                f1 = tmp32_;
                f2 = tmp33_;
            }
        }
        work[i * WORK + FRC + 0] = n0;
        work[i * WORK + FRC + 1] = n1;
        work[i * WORK + FRC + 2] = n2;
        work[i * WORK + FRC + 3] = f0;
        work[i * WORK + FRC + 4] = f1;
        work[i * WORK + FRC + 5] = f2;
    }
    for (i = NB; i > 0; i--) {
        p = (long)K[i * WIDTH + 0];
        code = (long)K[i * WIDTH + 1];
        k = (long)K[i * WIDTH + 2];
        ax = K[i * WIDTH + 3];
        ay = K[i * WIDTH + 4];
        az = K[i * WIDTH + 5];
        mul = K[i * WIDTH + 28];
        n0 = work[i * WORK + FRC + 0];
        n1 = work[i * WORK + FRC + 1];
        n2 = work[i * WORK + FRC + 2];
        f0 = work[i * WORK + FRC + 3];
        f1 = work[i * WORK + FRC + 4];
        f2 = work[i * WORK + FRC + 5];
        if (code == PR) {
            t = ax * f0 + ay * f1 + az * f2;
        } else {
            t = ax * n0 + ay * n1 + az * n2;
        }
        tau[k] = tau[k] + (mul == 1.0 ? t : mul * t);
        if (p == 0) {
            continue;
        }
        e00 = work[i * WORK + XUP + 0];
        e01 = work[i * WORK + XUP + 1];
        e02 = work[i * WORK + XUP + 2];
        e10 = work[i * WORK + XUP + 3];
        e11 = work[i * WORK + XUP + 4];
        e12 = work[i * WORK + XUP + 5];
        e20 = work[i * WORK + XUP + 6];
        e21 = work[i * WORK + XUP + 7];
        e22 = work[i * WORK + XUP + 8];
        rx = work[i * WORK + XUP + 9];
        ry = work[i * WORK + XUP + 10];
        rz = work[i * WORK + XUP + 11];
        {
            double ret34_[6];
            XT_force(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, n0, n1, n2, f0, f1, f2, ret34_);
            g0 = ret34_[0];
            g1 = ret34_[1];
            g2 = ret34_[2];
            g3 = ret34_[3];
            g4 = ret34_[4];
            g5 = ret34_[5];
        }
        work[p * WORK + FRC + 0] += g0;
        work[p * WORK + FRC + 1] += g1;
        work[p * WORK + FRC + 2] += g2;
        work[p * WORK + FRC + 3] += g3;
        work[p * WORK + FRC + 4] += g4;
        work[p * WORK + FRC + 5] += g5;
    }
}

/* Run crba.crba_kernel of the algorithms, generated from it. */
static inline void crba_kernel(const double *K, long rows, double *work, double *H)
{
    const long nq = (long)K[QIDX];
    long NB, a, cj, code, i, j, k, kj, n, p, pj;
    double F0, F1, F2, F3, F4, F5, Hii, Hij, Ixx, Ixy, Ixz, Iyy;
    double Iyz, Izz, ax, ay, az, bx, by, bz, chx, chy, chz, cm;
    double cxx, cxy, cxz, cyy, cyz, czz, d0, d1, d2, d3, d4, d5;
    double d6, d7, d8, d9, e00, e01, e02, e10, e11, e12, e20, e21;
    double e22, hx, hy, hz, mass, mj, mul, rx, ry, rz;
    NB = rows - 1;
    for (a = 0; a < nq * nq; a++) {
        H[a] = 0.0;
    }
    for (i = 1; i < NB + 1; i++) {
        mass = K[i * WIDTH + 18];
        hx = K[i * WIDTH + 19];
        hy = K[i * WIDTH + 20];
        hz = K[i * WIDTH + 21];
        Ixx = K[i * WIDTH + 22];
        Ixy = K[i * WIDTH + 23];
        Ixz = K[i * WIDTH + 24];
        Iyy = K[i * WIDTH + 25];
        Iyz = K[i * WIDTH + 26];
        Izz = K[i * WIDTH + 27];
        work[i * WORK + ICS + 0] = mass;
        work[i * WORK + ICS + 1] = hx;
        work[i * WORK + ICS + 2] = hy;
        work[i * WORK + ICS + 3] = hz;
        work[i * WORK + ICS + 4] = Ixx;
        work[i * WORK + ICS + 5] = Ixy;
        work[i * WORK + ICS + 6] = Ixz;
        work[i * WORK + ICS + 7] = Iyy;
        work[i * WORK + ICS + 8] = Iyz;
        work[i * WORK + ICS + 9] = Izz;
    }
    for (i = NB; i > 0; i--) {
        p = (long)K[i * WIDTH + 0];
        if (p == 0) {
            continue;
        }
        e00 = work[i * WORK + XUP + 0];
        e01 = work[i * WORK + XUP + 1];
        e02 = work[i * WORK + XUP + 2];
        e10 = work[i * WORK + XUP + 3];
        e11 = work[i * WORK + XUP + 4];
        e12 = work[i * WORK + XUP + 5];
        e20 = work[i * WORK + XUP + 6];
        e21 = work[i * WORK + XUP + 7];
        e22 = work[i * WORK + XUP + 8];
        rx = work[i * WORK + XUP + 9];
        ry = work[i * WORK + XUP + 10];
        rz = work[i * WORK + XUP + 11];
        cm = work[i * WORK + ICS + 0];
        chx = work[i * WORK + ICS + 1];
        chy = work[i * WORK + ICS + 2];
        chz = work[i * WORK + ICS + 3];
        cxx = work[i * WORK + ICS + 4];
        cxy = work[i * WORK + ICS + 5];
        cxz = work[i * WORK + ICS + 6];
        cyy = work[i * WORK + ICS + 7];
        cyz = work[i * WORK + ICS + 8];
        czz = work[i * WORK + ICS + 9];
        {
            double ret1_[10];
            XT_I_X(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, cm, chx, chy, chz, cxx, cxy, cxz, cyy, cyz, czz, ret1_);
            d0 = ret1_[0];
            d1 = ret1_[1];
            d2 = ret1_[2];
            d3 = ret1_[3];
            d4 = ret1_[4];
            d5 = ret1_[5];
            d6 = ret1_[6];
            d7 = ret1_[7];
            d8 = ret1_[8];
            d9 = ret1_[9];
        }
        work[p * WORK + ICS + 0] += d0;
        work[p * WORK + ICS + 1] += d1;
        work[p * WORK + ICS + 2] += d2;
        work[p * WORK + ICS + 3] += d3;
        work[p * WORK + ICS + 4] += d4;
        work[p * WORK + ICS + 5] += d5;
        work[p * WORK + ICS + 6] += d6;
        work[p * WORK + ICS + 7] += d7;
        work[p * WORK + ICS + 8] += d8;
        work[p * WORK + ICS + 9] += d9;
    }
    n = (long)K[0 * WIDTH + 2];
    for (i = 1; i < NB + 1; i++) {
        p = (long)K[i * WIDTH + 0];
        code = (long)K[i * WIDTH + 1];
        k = (long)K[i * WIDTH + 2];
        ax = K[i * WIDTH + 3];
        ay = K[i * WIDTH + 4];
        az = K[i * WIDTH + 5];
        mul = K[i * WIDTH + 28];
        cm = work[i * WORK + ICS + 0];
        chx = work[i * WORK + ICS + 1];
        chy = work[i * WORK + ICS + 2];
        chz = work[i * WORK + ICS + 3];
        cxx = work[i * WORK + ICS + 4];
        cxy = work[i * WORK + ICS + 5];
        cxz = work[i * WORK + ICS + 6];
        cyy = work[i * WORK + ICS + 7];
        cyz = work[i * WORK + ICS + 8];
        czz = work[i * WORK + ICS + 9];
        if (code == PR) {
            {
                double ret2_[6];
                I_motion(cm, chx, chy, chz, cxx, cxy, cxz, cyy, cyz, czz, 0.0, 0.0, 0.0, ax, ay, az, ret2_);
                F0 = ret2_[0];
                F1 = ret2_[1];
                F2 = ret2_[2];
                F3 = ret2_[3];
                F4 = ret2_[4];
                F5 = ret2_[5];
            }
            Hii = ax * F3 + ay * F4 + az * F5;
        } else {
            {
                double ret3_[6];
                I_motion(cm, chx, chy, chz, cxx, cxy, cxz, cyy, cyz, czz, ax, ay, az, 0.0, 0.0, 0.0, ret3_);
                F0 = ret3_[0];
                F1 = ret3_[1];
                F2 = ret3_[2];
                F3 = ret3_[3];
                F4 = ret3_[4];
                F5 = ret3_[5];
            }
            Hii = ax * F0 + ay * F1 + az * F2;
        }
        H[k * n + k] = H[k * n + k] + mul * mul * Hii;
        j = i;
        pj = p;
        while (pj != 0) {
            e00 = work[j * WORK + XUP + 0];
            e01 = work[j * WORK + XUP + 1];
            e02 = work[j * WORK + XUP + 2];
            e10 = work[j * WORK + XUP + 3];
            e11 = work[j * WORK + XUP + 4];
            e12 = work[j * WORK + XUP + 5];
            e20 = work[j * WORK + XUP + 6];
            e21 = work[j * WORK + XUP + 7];
            e22 = work[j * WORK + XUP + 8];
            rx = work[j * WORK + XUP + 9];
            ry = work[j * WORK + XUP + 10];
            rz = work[j * WORK + XUP + 11];
            {
                double ret4_[6];
                XT_force(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, F0, F1, F2, F3, F4, F5, ret4_);
                F0 = ret4_[0];
                F1 = ret4_[1];
                F2 = ret4_[2];
                F3 = ret4_[3];
                F4 = ret4_[4];
                F5 = ret4_[5];
            }
            j = pj;
            pj = (long)K[j * WIDTH + 0];
            cj = (long)K[j * WIDTH + 1];
            kj = (long)K[j * WIDTH + 2];
            bx = K[j * WIDTH + 3];
            by = K[j * WIDTH + 4];
            bz = K[j * WIDTH + 5];
            mj = K[j * WIDTH + 28];
            if (cj == PR) {
                Hij = mul * mj * (bx * F3 + by * F4 + bz * F5);
            } else {
                Hij = mul * mj * (bx * F0 + by * F1 + bz * F2);
            }
            H[k * n + kj] = H[k * n + kj] + Hij;
            H[kj * n + k] = H[kj * n + k] + Hij;
        }
    }
}

/* Run momentum.momentum_kernel of the algorithms, generated from it. */
static inline void momentum_kernel(const double *K, long rows, const double *q, const double *qd,
    double *mom, double *ctq, double *work)
{
    (void)q;
    const long nq = (long)K[QIDX];
    long NB, code, i, k, p;
    double Ixx, Ixy, Ixz, Iyy, Iyz, Izz, ax, ay, az, c, c0, c1;
    double c2, e00, e01, e02, e10, e11, e12, e20, e21, e22, f0, f1;
    double f2, g0, g1, g2, g3, g4, g5, hx, hy, hz, k0, k1;
    double k2, m0, m1, m2, mass, mul, n0, n1, n2, pv0, pv1, pv2;
    double pw0, pw1, pw2, qdi, rx, ry, rz, t, v0, v1, v2, w0;
    double w1, w2;
    NB = rows - 1;
    work[0 * WORK + VEL + 0] = 0.0;
    work[0 * WORK + VEL + 1] = 0.0;
    work[0 * WORK + VEL + 2] = 0.0;
    work[0 * WORK + VEL + 3] = 0.0;
    work[0 * WORK + VEL + 4] = 0.0;
    work[0 * WORK + VEL + 5] = 0.0;
    for (k = 0; k < nq; k++) {
        mom[k] = 0.0;
        ctq[k] = 0.0;
    }
    for (i = 1; i < NB + 1; i++) {
        p = (long)K[i * WIDTH + 0];
        code = (long)K[i * WIDTH + 1];
        k = (long)K[i * WIDTH + 2];
        ax = K[i * WIDTH + 3];
        ay = K[i * WIDTH + 4];
        az = K[i * WIDTH + 5];
        mass = K[i * WIDTH + 18];
        hx = K[i * WIDTH + 19];
        hy = K[i * WIDTH + 20];
        hz = K[i * WIDTH + 21];
        Ixx = K[i * WIDTH + 22];
        Ixy = K[i * WIDTH + 23];
        Ixz = K[i * WIDTH + 24];
        Iyy = K[i * WIDTH + 25];
        Iyz = K[i * WIDTH + 26];
        Izz = K[i * WIDTH + 27];
        mul = K[i * WIDTH + 28];
        e00 = work[i * WORK + XUP + 0];
        e01 = work[i * WORK + XUP + 1];
        e02 = work[i * WORK + XUP + 2];
        e10 = work[i * WORK + XUP + 3];
        e11 = work[i * WORK + XUP + 4];
        e12 = work[i * WORK + XUP + 5];
        e20 = work[i * WORK + XUP + 6];
        e21 = work[i * WORK + XUP + 7];
        e22 = work[i * WORK + XUP + 8];
        rx = work[i * WORK + XUP + 9];
        ry = work[i * WORK + XUP + 10];
        rz = work[i * WORK + XUP + 11];
        qdi = (mul == 1.0 ? qd[k] : mul * qd[k]);
        pw0 = work[p * WORK + VEL + 0];
        pw1 = work[p * WORK + VEL + 1];
        pw2 = work[p * WORK + VEL + 2];
        pv0 = work[p * WORK + VEL + 3];
        pv1 = work[p * WORK + VEL + 4];
        pv2 = work[p * WORK + VEL + 5];
        {
            double ret1_[6];
            X_motion(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, pw0, pw1, pw2, pv0, pv1, pv2, ret1_);
            w0 = ret1_[0];
            w1 = ret1_[1];
            w2 = ret1_[2];
            v0 = ret1_[3];
            v1 = ret1_[4];
            v2 = ret1_[5];
        }
        if (code == PR) {
            {
                const double tmp2_ = v0 + ax * qdi;
                const double tmp3_ = v1 + ay * qdi;
                const double tmp4_ = v2 + az * qdi;
                v0 = tmp2_;
                v1 = tmp3_;
                v2 = tmp4_;
            }
        } else {
            {
                const double tmp5_ = w0 + ax * qdi;
                const double tmp6_ = w1 + ay * qdi;
                const double tmp7_ = w2 + az * qdi;
                w0 = tmp5_;
                w1 = tmp6_;
                w2 = tmp7_;
            }
        }
        work[i * WORK + VEL + 0] = w0;
        work[i * WORK + VEL + 1] = w1;
        work[i * WORK + VEL + 2] = w2;
        work[i * WORK + VEL + 3] = v0;
        work[i * WORK + VEL + 4] = v1;
        work[i * WORK + VEL + 5] = v2;
        {
            double ret8_[6];
            I_motion(mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz, w0, w1, w2, v0, v1, v2, ret8_);
            m0 = ret8_[0];
            m1 = ret8_[1];
            m2 = ret8_[2];
            k0 = ret8_[3];
            k1 = ret8_[4];
            k2 = ret8_[5];
        }
        work[i * WORK + FRC + 0] = m0;
        work[i * WORK + FRC + 1] = m1;
        work[i * WORK + FRC + 2] = m2;
        work[i * WORK + FRC + 3] = k0;
        work[i * WORK + FRC + 4] = k1;
        work[i * WORK + FRC + 5] = k2;
    }
    for (i = NB; i > 0; i--) {
        p = (long)K[i * WIDTH + 0];
        code = (long)K[i * WIDTH + 1];
        k = (long)K[i * WIDTH + 2];
        ax = K[i * WIDTH + 3];
        ay = K[i * WIDTH + 4];
        az = K[i * WIDTH + 5];
        mul = K[i * WIDTH + 28];
        n0 = work[i * WORK + FRC + 0];
        n1 = work[i * WORK + FRC + 1];
        n2 = work[i * WORK + FRC + 2];
        f0 = work[i * WORK + FRC + 3];
        f1 = work[i * WORK + FRC + 4];
        f2 = work[i * WORK + FRC + 5];
        w0 = work[i * WORK + VEL + 0];
        w1 = work[i * WORK + VEL + 1];
        w2 = work[i * WORK + VEL + 2];
        v0 = work[i * WORK + VEL + 3];
        v1 = work[i * WORK + VEL + 4];
        v2 = work[i * WORK + VEL + 5];
        {
            const double tmp9_ = w1 * az - w2 * ay;
            const double tmp10_ = w2 * ax - w0 * az;
            const double tmp11_ = w0 * ay - w1 * ax;
            c0 = tmp9_;
            c1 = tmp10_;
            c2 = tmp11_;
        }
        if (code == PR) {
            t = ax * f0 + ay * f1 + az * f2;
            c = c0 * f0 + c1 * f1 + c2 * f2;
        } else {
            t = ax * n0 + ay * n1 + az * n2;
            c = c0 * n0 + c1 * n1 + c2 * n2 + (v1 * az - v2 * ay) * f0 + (v2 * ax - v0 * az) * f1 + (v0 * ay - v1 * ax) * f2;
        }
        mom[k] = mom[k] + (mul == 1.0 ? t : mul * t);
        ctq[k] = ctq[k] + (mul == 1.0 ? c : mul * c);
        if (p == 0) {
            continue;
        }
        e00 = work[i * WORK + XUP + 0];
        e01 = work[i * WORK + XUP + 1];
        e02 = work[i * WORK + XUP + 2];
        e10 = work[i * WORK + XUP + 3];
        e11 = work[i * WORK + XUP + 4];
        e12 = work[i * WORK + XUP + 5];
        e20 = work[i * WORK + XUP + 6];
        e21 = work[i * WORK + XUP + 7];
        e22 = work[i * WORK + XUP + 8];
        rx = work[i * WORK + XUP + 9];
        ry = work[i * WORK + XUP + 10];
        rz = work[i * WORK + XUP + 11];
        {
            double ret12_[6];
            XT_force(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, n0, n1, n2, f0, f1, f2, ret12_);
            g0 = ret12_[0];
            g1 = ret12_[1];
            g2 = ret12_[2];
            g3 = ret12_[3];
            g4 = ret12_[4];
            g5 = ret12_[5];
        }
        work[p * WORK + FRC + 0] += g0;
        work[p * WORK + FRC + 1] += g1;
        work[p * WORK + FRC + 2] += g2;
        work[p * WORK + FRC + 3] += g3;
        work[p * WORK + FRC + 4] += g4;
        work[p * WORK + FRC + 5] += g5;
    }
}

/* Run regressor.regressor_kernel of the algorithms, generated from it. */
static inline void regressor_kernel(const double *K, long rows, const double *qd,
    const double *qdd, double gx, double gy, double gz, double *Y, double *axes, double *work)
{
    const long nq = (long)K[QIDX];
    long NB, R, W, c, code, i, j, k, kj, p, pj, y;
    double a0, a1, a2, al0, al1, al2, ax, ay, az, b00, b01, b02;
    double b10, b11, b12, b20, b21, b22, e00, e01, e02, e10, e11, e12;
    double e20, e21, e22, j0, j1, j2, l0, l1, l2, mul, p01, p02;
    double p12, pa0, pa1, pa2, pl0, pl1, pl2, pv0, pv1, pv2, pw0, pw1;
    double pw2, q00, q11, q22, qddi, qdi, rx, ry, rz, s0, s1, s2;
    double s3, s4, s5, t0, t1, t2, u0, u1, u2, v0, v1, v2;
    double w0, w1, w2, xx0, xx1, xx2, xy0, xy1, xy2, xz0, xz1, xz2;
    double yy0, yy1, yy2, yz0, yz1, yz2, zero, zz0, zz1, zz2;
    NB = rows - 1;
    R = rows;
    W = 10 * NB;
    zero = 0.0 * gx;
    for (c = 0; c < nq * 10 * (rows - 1); c++) {
        Y[c] = zero;
    }
    work[0 * WORK + VEL + 0] = zero;
    work[0 * WORK + VEL + 1] = zero;
    work[0 * WORK + VEL + 2] = zero;
    work[0 * WORK + VEL + 3] = zero;
    work[0 * WORK + VEL + 4] = zero;
    work[0 * WORK + VEL + 5] = zero;
    work[0 * WORK + ACC + 0] = zero;
    work[0 * WORK + ACC + 1] = zero;
    work[0 * WORK + ACC + 2] = zero;
    work[0 * WORK + ACC + 3] = -gx;
    work[0 * WORK + ACC + 4] = -gy;
    work[0 * WORK + ACC + 5] = -gz;
    for (i = 1; i < NB + 1; i++) {
        p = (long)K[i * WIDTH + 0];
        code = (long)K[i * WIDTH + 1];
        k = (long)K[i * WIDTH + 2];
        ax = K[i * WIDTH + 3];
        ay = K[i * WIDTH + 4];
        az = K[i * WIDTH + 5];
        mul = K[i * WIDTH + 28];
        e00 = work[i * WORK + XUP + 0];
        e01 = work[i * WORK + XUP + 1];
        e02 = work[i * WORK + XUP + 2];
        e10 = work[i * WORK + XUP + 3];
        e11 = work[i * WORK + XUP + 4];
        e12 = work[i * WORK + XUP + 5];
        e20 = work[i * WORK + XUP + 6];
        e21 = work[i * WORK + XUP + 7];
        e22 = work[i * WORK + XUP + 8];
        rx = work[i * WORK + XUP + 9];
        ry = work[i * WORK + XUP + 10];
        rz = work[i * WORK + XUP + 11];
        qdi = (mul == 1.0 ? qd[k] : mul * qd[k]);
        qddi = (mul == 1.0 ? qdd[k] : mul * qdd[k]);
        pw0 = work[p * WORK + VEL + 0];
        pw1 = work[p * WORK + VEL + 1];
        pw2 = work[p * WORK + VEL + 2];
        pv0 = work[p * WORK + VEL + 3];
        pv1 = work[p * WORK + VEL + 4];
        pv2 = work[p * WORK + VEL + 5];
        {
            double ret1_[6];
            X_motion(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, pw0, pw1, pw2, pv0, pv1, pv2, ret1_);
            w0 = ret1_[0];
            w1 = ret1_[1];
            w2 = ret1_[2];
            v0 = ret1_[3];
            v1 = ret1_[4];
            v2 = ret1_[5];
        }
        pa0 = work[p * WORK + ACC + 0];
        pa1 = work[p * WORK + ACC + 1];
        pa2 = work[p * WORK + ACC + 2];
        pl0 = work[p * WORK + ACC + 3];
        pl1 = work[p * WORK + ACC + 4];
        pl2 = work[p * WORK + ACC + 5];
        {
            double ret2_[6];
            X_motion(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, pa0, pa1, pa2, pl0, pl1, pl2, ret2_);
            a0 = ret2_[0];
            a1 = ret2_[1];
            a2 = ret2_[2];
            l0 = ret2_[3];
            l1 = ret2_[4];
            l2 = ret2_[5];
        }
        {
            const double tmp3_ = ax * qdi;
            const double tmp4_ = ay * qdi;
            const double tmp5_ = az * qdi;
            j0 = tmp3_;
            j1 = tmp4_;
            j2 = tmp5_;
        }
        if (code == PR) {
            {
                const double tmp6_ = v0 + j0;
                const double tmp7_ = v1 + j1;
                const double tmp8_ = v2 + j2;
                v0 = tmp6_;
                v1 = tmp7_;
                v2 = tmp8_;
            }
            {
                const double tmp9_ = l0 + ax * qddi;
                const double tmp10_ = l1 + ay * qddi;
                const double tmp11_ = l2 + az * qddi;
                l0 = tmp9_;
                l1 = tmp10_;
                l2 = tmp11_;
            }
            l0 += w1 * j2 - w2 * j1;
            l1 += w2 * j0 - w0 * j2;
            l2 += w0 * j1 - w1 * j0;
            {
                const double tmp12_ = zero;
                const double tmp13_ = zero;
                const double tmp14_ = zero;
                const double tmp15_ = mul * ax;
                const double tmp16_ = mul * ay;
                const double tmp17_ = mul * az;
                s0 = tmp12_;
                s1 = tmp13_;
                s2 = tmp14_;
                s3 = tmp15_;
                s4 = tmp16_;
                s5 = tmp17_;
            }
        } else {
            {
                const double tmp18_ = w0 + j0;
                const double tmp19_ = w1 + j1;
                const double tmp20_ = w2 + j2;
                w0 = tmp18_;
                w1 = tmp19_;
                w2 = tmp20_;
            }
            {
                const double tmp21_ = a0 + ax * qddi;
                const double tmp22_ = a1 + ay * qddi;
                const double tmp23_ = a2 + az * qddi;
                a0 = tmp21_;
                a1 = tmp22_;
                a2 = tmp23_;
            }
            a0 += w1 * j2 - w2 * j1;
            a1 += w2 * j0 - w0 * j2;
            a2 += w0 * j1 - w1 * j0;
            l0 += v1 * j2 - v2 * j1;
            l1 += v2 * j0 - v0 * j2;
            l2 += v0 * j1 - v1 * j0;
            {
                const double tmp24_ = mul * ax;
                const double tmp25_ = mul * ay;
                const double tmp26_ = mul * az;
                const double tmp27_ = zero;
                const double tmp28_ = zero;
                const double tmp29_ = zero;
                s0 = tmp24_;
                s1 = tmp25_;
                s2 = tmp26_;
                s3 = tmp27_;
                s4 = tmp28_;
                s5 = tmp29_;
            }
        }
        work[i * WORK + VEL + 0] = w0;
        work[i * WORK + VEL + 1] = w1;
        work[i * WORK + VEL + 2] = w2;
        work[i * WORK + VEL + 3] = v0;
        work[i * WORK + VEL + 4] = v1;
        work[i * WORK + VEL + 5] = v2;
        work[i * WORK + ACC + 0] = a0;
        work[i * WORK + ACC + 1] = a1;
        work[i * WORK + ACC + 2] = a2;
        work[i * WORK + ACC + 3] = l0;
        work[i * WORK + ACC + 4] = l1;
        work[i * WORK + ACC + 5] = l2;
        al0 = l0 + (w1 * v2 - w2 * v1);
        al1 = l1 + (w2 * v0 - w0 * v2);
        al2 = l2 + (w0 * v1 - w1 * v0);
        {
            const double tmp30_ = w0 * w1;
            const double tmp31_ = w0 * w2;
            const double tmp32_ = w1 * w2;
            p01 = tmp30_;
            p02 = tmp31_;
            p12 = tmp32_;
        }
        {
            const double tmp33_ = w0 * w0;
            const double tmp34_ = w1 * w1;
            const double tmp35_ = w2 * w2;
            q00 = tmp33_;
            q11 = tmp34_;
            q22 = tmp35_;
        }
        {
            const double tmp36_ = -(q11 + q22);
            const double tmp37_ = -(q00 + q22);
            const double tmp38_ = -(q00 + q11);
            b00 = tmp36_;
            b11 = tmp37_;
            b22 = tmp38_;
        }
        {
            const double tmp39_ = p01 - a2;
            const double tmp40_ = p01 + a2;
            b01 = tmp39_;
            b10 = tmp40_;
        }
        {
            const double tmp41_ = p02 + a1;
            const double tmp42_ = p02 - a1;
            b02 = tmp41_;
            b20 = tmp42_;
        }
        {
            const double tmp43_ = p12 - a0;
            const double tmp44_ = p12 + a0;
            b12 = tmp43_;
            b21 = tmp44_;
        }
        {
            const double tmp45_ = a0;
            const double tmp46_ = p02;
            const double tmp47_ = -p01;
            xx0 = tmp45_;
            xx1 = tmp46_;
            xx2 = tmp47_;
        }
        {
            const double tmp48_ = a1 - p02;
            const double tmp49_ = a0 + p12;
            const double tmp50_ = q00 - q11;
            xy0 = tmp48_;
            xy1 = tmp49_;
            xy2 = tmp50_;
        }
        {
            const double tmp51_ = -p12;
            const double tmp52_ = a1;
            const double tmp53_ = p01;
            yy0 = tmp51_;
            yy1 = tmp52_;
            yy2 = tmp53_;
        }
        {
            const double tmp54_ = a2 + p01;
            const double tmp55_ = q22 - q00;
            const double tmp56_ = a0 - p12;
            xz0 = tmp54_;
            xz1 = tmp55_;
            xz2 = tmp56_;
        }
        {
            const double tmp57_ = q11 - q22;
            const double tmp58_ = a2 - p01;
            const double tmp59_ = a1 + p02;
            yz0 = tmp57_;
            yz1 = tmp58_;
            yz2 = tmp59_;
        }
        {
            const double tmp60_ = p12;
            const double tmp61_ = -p02;
            const double tmp62_ = a2;
            zz0 = tmp60_;
            zz1 = tmp61_;
            zz2 = tmp62_;
        }
        j = i;
        while (j != 0) {
            pj = (long)K[j * WIDTH + 0];
            kj = (long)K[j * WIDTH + 2];
            if (j == i) {
                {
                    const double tmp63_ = s0;
                    const double tmp64_ = s1;
                    const double tmp65_ = s2;
                    const double tmp66_ = s3;
                    const double tmp67_ = s4;
                    const double tmp68_ = s5;
                    t0 = tmp63_;
                    t1 = tmp64_;
                    t2 = tmp65_;
                    u0 = tmp66_;
                    u1 = tmp67_;
                    u2 = tmp68_;
                }
            } else {
                c = 6 * (p * R + j);
                {
                    double ret69_[6];
                    X_motion(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, axes[c], axes[c + 1], axes[c + 2], axes[c + 3], axes[c + 4], axes[c + 5], ret69_);
                    t0 = ret69_[0];
                    t1 = ret69_[1];
                    t2 = ret69_[2];
                    u0 = ret69_[3];
                    u1 = ret69_[4];
                    u2 = ret69_[5];
                }
            }
            c = 6 * (i * R + j);
            axes[c] = t0;
            axes[c + 1] = t1;
            axes[c + 2] = t2;
            axes[c + 3] = u0;
            axes[c + 4] = u1;
            axes[c + 5] = u2;
            y = kj * W + 10 * (i - 1);
            Y[y] = Y[y] + (u0 * al0 + u1 * al1 + u2 * al2);
            Y[y + 1] = Y[y + 1] + (al1 * t2 - al2 * t1 + (b00 * u0 + b10 * u1 + b20 * u2));
            Y[y + 2] = Y[y + 2] + (al2 * t0 - al0 * t2 + (b01 * u0 + b11 * u1 + b21 * u2));
            Y[y + 3] = Y[y + 3] + (al0 * t1 - al1 * t0 + (b02 * u0 + b12 * u1 + b22 * u2));
            Y[y + 4] = Y[y + 4] + (t0 * xx0 + t1 * xx1 + t2 * xx2);
            Y[y + 5] = Y[y + 5] + (t0 * xy0 + t1 * xy1 + t2 * xy2);
            Y[y + 6] = Y[y + 6] + (t0 * yy0 + t1 * yy1 + t2 * yy2);
            Y[y + 7] = Y[y + 7] + (t0 * xz0 + t1 * xz1 + t2 * xz2);
            Y[y + 8] = Y[y + 8] + (t0 * yz0 + t1 * yz1 + t2 * yz2);
            Y[y + 9] = Y[y + 9] + (t0 * zz0 + t1 * zz1 + t2 * zz2);
            j = pj;
        }
    }
}

/* ------------------------------------------------------------------------------------------
 * The same RNEA on several states at once (SIMD across the states of a batch): the kernels
 * printed again by codegen._ToCLanes on GCC and Clang vector extensions. rnea_batch_lanes
 * runs as many states of a batch as fill the lanes and returns how many; a compiler without
 * vector extensions gets SD_LANES undefined, and the batch runs the scalar kernels. */
#if defined(__GNUC__) || defined(__clang__)
#define SD_LANES 8      /* rnea_batch_lanes is defined: up to 8 states at once */
#include <stdint.h>
#include <stdlib.h>
#if defined(__x86_64__)
#define SD_AVX 1
#endif

typedef double sd_vd2 __attribute__((vector_size(16)));

/* x in every lane. */
static inline sd_vd2 sd_splat2(double x)
{
    return (sd_vd2){x, x};
}

/* Whether x is nonzero in some lane. */
static inline long sd_nonzero2(sd_vd2 x)
{
    return x[0] != 0.0 || x[1] != 0.0;
}

/* The C library's sin and cos, lane by lane: each lane's value is the scalar kernel's (the
 * compiler computes the sine and cosine of one lane with one call to sincos). */
static inline sd_vd2 sd_sin2(sd_vd2 x)
{
    return (sd_vd2){sin(x[0]), sin(x[1])};
}

static inline sd_vd2 sd_cos2(sd_vd2 x)
{
    return (sd_vd2){cos(x[0]), cos(x[1])};
}

/* Run components.X_motion on 2 states, generated from it. */
static inline void X_motion_lanes2(sd_vd2 e00, sd_vd2 e01, sd_vd2 e02, sd_vd2 e10, sd_vd2 e11,
    sd_vd2 e12, sd_vd2 e20, sd_vd2 e21, sd_vd2 e22, sd_vd2 rx, sd_vd2 ry, sd_vd2 rz, sd_vd2 m0,
    sd_vd2 m1, sd_vd2 m2, sd_vd2 m3, sd_vd2 m4, sd_vd2 m5, sd_vd2 *out)
{
    sd_vd2 u0, u1, u2;
    u0 = m3 - (ry * m2 - rz * m1);
    u1 = m4 - (rz * m0 - rx * m2);
    u2 = m5 - (rx * m1 - ry * m0);
    out[0] = e00 * m0 + e01 * m1 + e02 * m2;
    out[1] = e10 * m0 + e11 * m1 + e12 * m2;
    out[2] = e20 * m0 + e21 * m1 + e22 * m2;
    out[3] = e00 * u0 + e01 * u1 + e02 * u2;
    out[4] = e10 * u0 + e11 * u1 + e12 * u2;
    out[5] = e20 * u0 + e21 * u1 + e22 * u2;
}

/* Run components.XT_force on 2 states, generated from it. */
static inline void XT_force_lanes2(sd_vd2 e00, sd_vd2 e01, sd_vd2 e02, sd_vd2 e10, sd_vd2 e11,
    sd_vd2 e12, sd_vd2 e20, sd_vd2 e21, sd_vd2 e22, sd_vd2 rx, sd_vd2 ry, sd_vd2 rz, sd_vd2 n0,
    sd_vd2 n1, sd_vd2 n2, sd_vd2 f0, sd_vd2 f1, sd_vd2 f2, sd_vd2 *out)
{
    sd_vd2 F0, F1, F2;
    F0 = e00 * f0 + e10 * f1 + e20 * f2;
    F1 = e01 * f0 + e11 * f1 + e21 * f2;
    F2 = e02 * f0 + e12 * f1 + e22 * f2;
    out[0] = e00 * n0 + e10 * n1 + e20 * n2 + (ry * F2 - rz * F1);
    out[1] = e01 * n0 + e11 * n1 + e21 * n2 + (rz * F0 - rx * F2);
    out[2] = e02 * n0 + e12 * n1 + e22 * n2 + (rx * F1 - ry * F0);
    out[3] = F0;
    out[4] = F1;
    out[5] = F2;
}

/* Run components.I_motion on 2 states, generated from it. */
static inline void I_motion_lanes2(double mass, double hx, double hy, double hz, double Ixx,
    double Ixy, double Ixz, double Iyy, double Iyz, double Izz, sd_vd2 m0, sd_vd2 m1, sd_vd2 m2,
    sd_vd2 m3, sd_vd2 m4, sd_vd2 m5, sd_vd2 *out)
{
    out[0] = Ixx * m0 + Ixy * m1 + Ixz * m2 + (hy * m5 - hz * m4);
    out[1] = Ixy * m0 + Iyy * m1 + Iyz * m2 + (hz * m3 - hx * m5);
    out[2] = Ixz * m0 + Iyz * m1 + Izz * m2 + (hx * m4 - hy * m3);
    out[3] = mass * m3 - (hy * m2 - hz * m1);
    out[4] = mass * m4 - (hz * m0 - hx * m2);
    out[5] = mass * m5 - (hx * m1 - hy * m0);
}

/* Run rnea.xup_kernel on 2 states, generated from it. */
static inline void xup_kernel_lanes2(const double *K, long rows, const sd_vd2 *q, sd_vd2 *work)
{
    long code, i, k;
    sd_vd2 C, c, cxy, cxz, cyz, j00, j01, j02, j10, j11, j12, j20;
    sd_vd2 j21, j22, qi, s, sx, sy, sz;
    double ax, ay, az, mul, off, rx, ry, rz, t00, t01, t02, t10;
    double t11, t12, t20, t21, t22;
    for (i = 1; i < rows; i++) {
        code = (long)K[i * WIDTH + 1];
        k = (long)K[i * WIDTH + 2];
        ax = K[i * WIDTH + 3];
        ay = K[i * WIDTH + 4];
        az = K[i * WIDTH + 5];
        t00 = K[i * WIDTH + 6];
        t01 = K[i * WIDTH + 7];
        t02 = K[i * WIDTH + 8];
        t10 = K[i * WIDTH + 9];
        t11 = K[i * WIDTH + 10];
        t12 = K[i * WIDTH + 11];
        t20 = K[i * WIDTH + 12];
        t21 = K[i * WIDTH + 13];
        t22 = K[i * WIDTH + 14];
        rx = K[i * WIDTH + 15];
        ry = K[i * WIDTH + 16];
        rz = K[i * WIDTH + 17];
        mul = K[i * WIDTH + 28];
        off = K[i * WIDTH + 29];
        qi = (mul == 1.0 && off == 0.0 ? q[k] : mul * q[k] + off);
        if (code == PR) {
            work[i * WORK + XUP + 0] = sd_splat2(t00);
            work[i * WORK + XUP + 1] = sd_splat2(t01);
            work[i * WORK + XUP + 2] = sd_splat2(t02);
            work[i * WORK + XUP + 3] = sd_splat2(t10);
            work[i * WORK + XUP + 4] = sd_splat2(t11);
            work[i * WORK + XUP + 5] = sd_splat2(t12);
            work[i * WORK + XUP + 6] = sd_splat2(t20);
            work[i * WORK + XUP + 7] = sd_splat2(t21);
            work[i * WORK + XUP + 8] = sd_splat2(t22);
            work[i * WORK + XUP + 9] = rx + (t00 * ax + t10 * ay + t20 * az) * qi;
            work[i * WORK + XUP + 10] = ry + (t01 * ax + t11 * ay + t21 * az) * qi;
            work[i * WORK + XUP + 11] = rz + (t02 * ax + t12 * ay + t22 * az) * qi;
            continue;
        }
        {
            const sd_vd2 tmp1_ = sd_cos2(qi);
            const sd_vd2 tmp2_ = sd_sin2(qi);
            c = tmp1_;
            s = tmp2_;
        }
        if (code == RZ) {
            s = az * s;
            work[i * WORK + XUP + 0] = c * t00 + s * t10;
            work[i * WORK + XUP + 1] = c * t01 + s * t11;
            work[i * WORK + XUP + 2] = c * t02 + s * t12;
            work[i * WORK + XUP + 3] = c * t10 - s * t00;
            work[i * WORK + XUP + 4] = c * t11 - s * t01;
            work[i * WORK + XUP + 5] = c * t12 - s * t02;
            work[i * WORK + XUP + 6] = sd_splat2(t20);
            work[i * WORK + XUP + 7] = sd_splat2(t21);
            work[i * WORK + XUP + 8] = sd_splat2(t22);
            work[i * WORK + XUP + 9] = sd_splat2(rx);
            work[i * WORK + XUP + 10] = sd_splat2(ry);
            work[i * WORK + XUP + 11] = sd_splat2(rz);
        } else if (code == RX) {
            s = ax * s;
            work[i * WORK + XUP + 0] = sd_splat2(t00);
            work[i * WORK + XUP + 1] = sd_splat2(t01);
            work[i * WORK + XUP + 2] = sd_splat2(t02);
            work[i * WORK + XUP + 3] = c * t10 + s * t20;
            work[i * WORK + XUP + 4] = c * t11 + s * t21;
            work[i * WORK + XUP + 5] = c * t12 + s * t22;
            work[i * WORK + XUP + 6] = c * t20 - s * t10;
            work[i * WORK + XUP + 7] = c * t21 - s * t11;
            work[i * WORK + XUP + 8] = c * t22 - s * t12;
            work[i * WORK + XUP + 9] = sd_splat2(rx);
            work[i * WORK + XUP + 10] = sd_splat2(ry);
            work[i * WORK + XUP + 11] = sd_splat2(rz);
        } else if (code == RY) {
            s = ay * s;
            work[i * WORK + XUP + 0] = c * t00 - s * t20;
            work[i * WORK + XUP + 1] = c * t01 - s * t21;
            work[i * WORK + XUP + 2] = c * t02 - s * t22;
            work[i * WORK + XUP + 3] = sd_splat2(t10);
            work[i * WORK + XUP + 4] = sd_splat2(t11);
            work[i * WORK + XUP + 5] = sd_splat2(t12);
            work[i * WORK + XUP + 6] = s * t00 + c * t20;
            work[i * WORK + XUP + 7] = s * t01 + c * t21;
            work[i * WORK + XUP + 8] = s * t02 + c * t22;
            work[i * WORK + XUP + 9] = sd_splat2(rx);
            work[i * WORK + XUP + 10] = sd_splat2(ry);
            work[i * WORK + XUP + 11] = sd_splat2(rz);
        } else {
            C = 1.0 - c;
            {
                const sd_vd2 tmp3_ = c + C * ax * ax;
                const sd_vd2 tmp4_ = c + C * ay * ay;
                const sd_vd2 tmp5_ = c + C * az * az;
                j00 = tmp3_;
                j11 = tmp4_;
                j22 = tmp5_;
            }
            {
                const sd_vd2 tmp6_ = C * ax * ay;
                const sd_vd2 tmp7_ = C * ax * az;
                const sd_vd2 tmp8_ = C * ay * az;
                cxy = tmp6_;
                cxz = tmp7_;
                cyz = tmp8_;
            }
            {
                const sd_vd2 tmp9_ = s * ax;
                const sd_vd2 tmp10_ = s * ay;
                const sd_vd2 tmp11_ = s * az;
                sx = tmp9_;
                sy = tmp10_;
                sz = tmp11_;
            }
            {
                const sd_vd2 tmp12_ = cxy + sz;
                const sd_vd2 tmp13_ = cxz - sy;
                const sd_vd2 tmp14_ = cxy - sz;
                j01 = tmp12_;
                j02 = tmp13_;
                j10 = tmp14_;
            }
            {
                const sd_vd2 tmp15_ = cyz + sx;
                const sd_vd2 tmp16_ = cxz + sy;
                const sd_vd2 tmp17_ = cyz - sx;
                j12 = tmp15_;
                j20 = tmp16_;
                j21 = tmp17_;
            }
            work[i * WORK + XUP + 0] = j00 * t00 + j01 * t10 + j02 * t20;
            work[i * WORK + XUP + 1] = j00 * t01 + j01 * t11 + j02 * t21;
            work[i * WORK + XUP + 2] = j00 * t02 + j01 * t12 + j02 * t22;
            work[i * WORK + XUP + 3] = j10 * t00 + j11 * t10 + j12 * t20;
            work[i * WORK + XUP + 4] = j10 * t01 + j11 * t11 + j12 * t21;
            work[i * WORK + XUP + 5] = j10 * t02 + j11 * t12 + j12 * t22;
            work[i * WORK + XUP + 6] = j20 * t00 + j21 * t10 + j22 * t20;
            work[i * WORK + XUP + 7] = j20 * t01 + j21 * t11 + j22 * t21;
            work[i * WORK + XUP + 8] = j20 * t02 + j21 * t12 + j22 * t22;
            work[i * WORK + XUP + 9] = sd_splat2(rx);
            work[i * WORK + XUP + 10] = sd_splat2(ry);
            work[i * WORK + XUP + 11] = sd_splat2(rz);
        }
    }
}

/* Run rnea.rnea_kernel on 2 states, generated from it. */
static inline void rnea_kernel_lanes2(const double *K, long rows, const sd_vd2 *q,
    const sd_vd2 *qd, const sd_vd2 *qdd, double gx, double gy, double gz, const sd_vd2 *f_body,
    long has_fext, sd_vd2 *tau, sd_vd2 *work)
{
    (void)q;
    const long nq = (long)K[QIDX];
    long NB, code, i, k, moving, p, static_, weightless;
    double Ixx, Ixy, Ixz, Iyy, Iyz, Izz, ax, ay, az, hx, hy, hz;
    double mass, mul, zero;
    sd_vd2 a0, a1, a2, e00, e01, e02, e10, e11, e12, e20, e21, e22;
    sd_vd2 f0, f1, f2, fe0, fe1, fe2, fe3, fe4, fe5, g0, g1, g2;
    sd_vd2 g3, g4, g5, j0, j1, j2, k0, k1, k2, l0, l1, l2;
    sd_vd2 m0, m1, m2, n0, n1, n2, pa0, pa1, pa2, pl0, pl1, pl2;
    sd_vd2 pv0, pv1, pv2, pw0, pw1, pw2, qddi, qdi, rx, ry, rz, t;
    sd_vd2 v0, v1, v2, w0, w1, w2, x;
    NB = rows - 1;
    zero = 0.0 * gx;
    moving = 0;
    for (long j1_ = 0; j1_ < nq; j1_++) {
        x = qd[j1_];
        if (sd_nonzero2(x)) {
            moving = 1;
            break;
        }
    }
    static_ = !moving;
    if (static_) {
        for (long j2_ = 0; j2_ < nq; j2_++) {
            x = qdd[j2_];
            if (sd_nonzero2(x)) {
                static_ = 0;
                break;
            }
        }
    }
    weightless = !(gx != 0.0 || gy != 0.0 || gz != 0.0);
    work[0 * WORK + VEL + 0] = sd_splat2(zero);
    work[0 * WORK + VEL + 1] = sd_splat2(zero);
    work[0 * WORK + VEL + 2] = sd_splat2(zero);
    work[0 * WORK + VEL + 3] = sd_splat2(zero);
    work[0 * WORK + VEL + 4] = sd_splat2(zero);
    work[0 * WORK + VEL + 5] = sd_splat2(zero);
    work[0 * WORK + ACC + 0] = sd_splat2(zero);
    work[0 * WORK + ACC + 1] = sd_splat2(zero);
    work[0 * WORK + ACC + 2] = sd_splat2(zero);
    work[0 * WORK + ACC + 3] = sd_splat2(-gx);
    work[0 * WORK + ACC + 4] = sd_splat2(-gy);
    work[0 * WORK + ACC + 5] = sd_splat2(-gz);
    for (k = 0; k < nq; k++) {
        tau[k] = sd_splat2(zero);
    }
    for (i = 1; i < NB + 1; i++) {
        p = (long)K[i * WIDTH + 0];
        code = (long)K[i * WIDTH + 1];
        k = (long)K[i * WIDTH + 2];
        ax = K[i * WIDTH + 3];
        ay = K[i * WIDTH + 4];
        az = K[i * WIDTH + 5];
        mass = K[i * WIDTH + 18];
        hx = K[i * WIDTH + 19];
        hy = K[i * WIDTH + 20];
        hz = K[i * WIDTH + 21];
        Ixx = K[i * WIDTH + 22];
        Ixy = K[i * WIDTH + 23];
        Ixz = K[i * WIDTH + 24];
        Iyy = K[i * WIDTH + 25];
        Iyz = K[i * WIDTH + 26];
        Izz = K[i * WIDTH + 27];
        mul = K[i * WIDTH + 28];
        e00 = work[i * WORK + XUP + 0];
        e01 = work[i * WORK + XUP + 1];
        e02 = work[i * WORK + XUP + 2];
        e10 = work[i * WORK + XUP + 3];
        e11 = work[i * WORK + XUP + 4];
        e12 = work[i * WORK + XUP + 5];
        e20 = work[i * WORK + XUP + 6];
        e21 = work[i * WORK + XUP + 7];
        e22 = work[i * WORK + XUP + 8];
        rx = work[i * WORK + XUP + 9];
        ry = work[i * WORK + XUP + 10];
        rz = work[i * WORK + XUP + 11];
        if (static_) {
            pl0 = work[p * WORK + ACC + 3];
            pl1 = work[p * WORK + ACC + 4];
            pl2 = work[p * WORK + ACC + 5];
            l0 = e00 * pl0 + e01 * pl1 + e02 * pl2;
            l1 = e10 * pl0 + e11 * pl1 + e12 * pl2;
            l2 = e20 * pl0 + e21 * pl1 + e22 * pl2;
            work[i * WORK + ACC + 0] = sd_splat2(zero);
            work[i * WORK + ACC + 1] = sd_splat2(zero);
            work[i * WORK + ACC + 2] = sd_splat2(zero);
            work[i * WORK + ACC + 3] = l0;
            work[i * WORK + ACC + 4] = l1;
            work[i * WORK + ACC + 5] = l2;
            {
                const sd_vd2 tmp3_ = hy * l2 - hz * l1;
                const sd_vd2 tmp4_ = hz * l0 - hx * l2;
                const sd_vd2 tmp5_ = hx * l1 - hy * l0;
                n0 = tmp3_;
                n1 = tmp4_;
                n2 = tmp5_;
            }
            {
                const sd_vd2 tmp6_ = mass * l0;
                const sd_vd2 tmp7_ = mass * l1;
                const sd_vd2 tmp8_ = mass * l2;
                f0 = tmp6_;
                f1 = tmp7_;
                f2 = tmp8_;
            }
        } else {
            qddi = (mul == 1.0 ? qdd[k] : mul * qdd[k]);
            if (p == 0 && weightless) {
                a0 = a1 = a2 = l0 = l1 = l2 = sd_splat2(zero);
            } else {
                pa0 = work[p * WORK + ACC + 0];
                pa1 = work[p * WORK + ACC + 1];
                pa2 = work[p * WORK + ACC + 2];
                pl0 = work[p * WORK + ACC + 3];
                pl1 = work[p * WORK + ACC + 4];
                pl2 = work[p * WORK + ACC + 5];
                {
                    sd_vd2 ret9_[6];
                    X_motion_lanes2(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, pa0, pa1, pa2, pl0, pl1, pl2, ret9_);
                    a0 = ret9_[0];
                    a1 = ret9_[1];
                    a2 = ret9_[2];
                    l0 = ret9_[3];
                    l1 = ret9_[4];
                    l2 = ret9_[5];
                }
            }
            if (code == PR) {
                {
                    const sd_vd2 tmp10_ = l0 + ax * qddi;
                    const sd_vd2 tmp11_ = l1 + ay * qddi;
                    const sd_vd2 tmp12_ = l2 + az * qddi;
                    l0 = tmp10_;
                    l1 = tmp11_;
                    l2 = tmp12_;
                }
            } else {
                {
                    const sd_vd2 tmp13_ = a0 + ax * qddi;
                    const sd_vd2 tmp14_ = a1 + ay * qddi;
                    const sd_vd2 tmp15_ = a2 + az * qddi;
                    a0 = tmp13_;
                    a1 = tmp14_;
                    a2 = tmp15_;
                }
            }
            w0 = w1 = w2 = v0 = v1 = v2 = sd_splat2(zero);
            if (moving) {
                qdi = (mul == 1.0 ? qd[k] : mul * qd[k]);
                pw0 = work[p * WORK + VEL + 0];
                pw1 = work[p * WORK + VEL + 1];
                pw2 = work[p * WORK + VEL + 2];
                pv0 = work[p * WORK + VEL + 3];
                pv1 = work[p * WORK + VEL + 4];
                pv2 = work[p * WORK + VEL + 5];
                {
                    sd_vd2 ret16_[6];
                    X_motion_lanes2(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, pw0, pw1, pw2, pv0, pv1, pv2, ret16_);
                    w0 = ret16_[0];
                    w1 = ret16_[1];
                    w2 = ret16_[2];
                    v0 = ret16_[3];
                    v1 = ret16_[4];
                    v2 = ret16_[5];
                }
                {
                    const sd_vd2 tmp17_ = ax * qdi;
                    const sd_vd2 tmp18_ = ay * qdi;
                    const sd_vd2 tmp19_ = az * qdi;
                    j0 = tmp17_;
                    j1 = tmp18_;
                    j2 = tmp19_;
                }
                if (code == PR) {
                    {
                        const sd_vd2 tmp20_ = v0 + j0;
                        const sd_vd2 tmp21_ = v1 + j1;
                        const sd_vd2 tmp22_ = v2 + j2;
                        v0 = tmp20_;
                        v1 = tmp21_;
                        v2 = tmp22_;
                    }
                    l0 += w1 * j2 - w2 * j1;
                    l1 += w2 * j0 - w0 * j2;
                    l2 += w0 * j1 - w1 * j0;
                } else {
                    {
                        const sd_vd2 tmp23_ = w0 + j0;
                        const sd_vd2 tmp24_ = w1 + j1;
                        const sd_vd2 tmp25_ = w2 + j2;
                        w0 = tmp23_;
                        w1 = tmp24_;
                        w2 = tmp25_;
                    }
                    a0 += w1 * j2 - w2 * j1;
                    a1 += w2 * j0 - w0 * j2;
                    a2 += w0 * j1 - w1 * j0;
                    l0 += v1 * j2 - v2 * j1;
                    l1 += v2 * j0 - v0 * j2;
                    l2 += v0 * j1 - v1 * j0;
                }
                work[i * WORK + VEL + 0] = w0;
                work[i * WORK + VEL + 1] = w1;
                work[i * WORK + VEL + 2] = w2;
                work[i * WORK + VEL + 3] = v0;
                work[i * WORK + VEL + 4] = v1;
                work[i * WORK + VEL + 5] = v2;
            }
            work[i * WORK + ACC + 0] = a0;
            work[i * WORK + ACC + 1] = a1;
            work[i * WORK + ACC + 2] = a2;
            work[i * WORK + ACC + 3] = l0;
            work[i * WORK + ACC + 4] = l1;
            work[i * WORK + ACC + 5] = l2;
            {
                sd_vd2 ret26_[6];
                I_motion_lanes2(mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz, a0, a1, a2, l0, l1, l2, ret26_);
                n0 = ret26_[0];
                n1 = ret26_[1];
                n2 = ret26_[2];
                f0 = ret26_[3];
                f1 = ret26_[4];
                f2 = ret26_[5];
            }
            if (moving) {
                {
                    sd_vd2 ret27_[6];
                    I_motion_lanes2(mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz, w0, w1, w2, v0, v1, v2, ret27_);
                    m0 = ret27_[0];
                    m1 = ret27_[1];
                    m2 = ret27_[2];
                    k0 = ret27_[3];
                    k1 = ret27_[4];
                    k2 = ret27_[5];
                }
                n0 += w1 * m2 - w2 * m1 + (v1 * k2 - v2 * k1);
                n1 += w2 * m0 - w0 * m2 + (v2 * k0 - v0 * k2);
                n2 += w0 * m1 - w1 * m0 + (v0 * k1 - v1 * k0);
                f0 += w1 * k2 - w2 * k1;
                f1 += w2 * k0 - w0 * k2;
                f2 += w0 * k1 - w1 * k0;
            }
        }
        if (has_fext) {
            fe0 = f_body[i * 6 + 0];
            fe1 = f_body[i * 6 + 1];
            fe2 = f_body[i * 6 + 2];
            fe3 = f_body[i * 6 + 3];
            fe4 = f_body[i * 6 + 4];
            fe5 = f_body[i * 6 + 5];
            {
                const sd_vd2 tmp28_ = n0 - fe0;
                const sd_vd2 tmp29_ = n1 - fe1;
                const sd_vd2 tmp30_ = n2 - fe2;
                n0 = tmp28_;
                n1 = tmp29_;
                n2 = tmp30_;
            }
            {
                const sd_vd2 tmp31_ = f0 - fe3;
                const sd_vd2 tmp32_ = f1 - fe4;
                const sd_vd2 tmp33_ = f2 - fe5;
                f0 = tmp31_;
                f1 = tmp32_;
                f2 = tmp33_;
            }
        }
        work[i * WORK + FRC + 0] = n0;
        work[i * WORK + FRC + 1] = n1;
        work[i * WORK + FRC + 2] = n2;
        work[i * WORK + FRC + 3] = f0;
        work[i * WORK + FRC + 4] = f1;
        work[i * WORK + FRC + 5] = f2;
    }
    for (i = NB; i > 0; i--) {
        p = (long)K[i * WIDTH + 0];
        code = (long)K[i * WIDTH + 1];
        k = (long)K[i * WIDTH + 2];
        ax = K[i * WIDTH + 3];
        ay = K[i * WIDTH + 4];
        az = K[i * WIDTH + 5];
        mul = K[i * WIDTH + 28];
        n0 = work[i * WORK + FRC + 0];
        n1 = work[i * WORK + FRC + 1];
        n2 = work[i * WORK + FRC + 2];
        f0 = work[i * WORK + FRC + 3];
        f1 = work[i * WORK + FRC + 4];
        f2 = work[i * WORK + FRC + 5];
        if (code == PR) {
            t = ax * f0 + ay * f1 + az * f2;
        } else {
            t = ax * n0 + ay * n1 + az * n2;
        }
        tau[k] = tau[k] + (mul == 1.0 ? t : mul * t);
        if (p == 0) {
            continue;
        }
        e00 = work[i * WORK + XUP + 0];
        e01 = work[i * WORK + XUP + 1];
        e02 = work[i * WORK + XUP + 2];
        e10 = work[i * WORK + XUP + 3];
        e11 = work[i * WORK + XUP + 4];
        e12 = work[i * WORK + XUP + 5];
        e20 = work[i * WORK + XUP + 6];
        e21 = work[i * WORK + XUP + 7];
        e22 = work[i * WORK + XUP + 8];
        rx = work[i * WORK + XUP + 9];
        ry = work[i * WORK + XUP + 10];
        rz = work[i * WORK + XUP + 11];
        {
            sd_vd2 ret34_[6];
            XT_force_lanes2(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, n0, n1, n2, f0, f1, f2, ret34_);
            g0 = ret34_[0];
            g1 = ret34_[1];
            g2 = ret34_[2];
            g3 = ret34_[3];
            g4 = ret34_[4];
            g5 = ret34_[5];
        }
        work[p * WORK + FRC + 0] += g0;
        work[p * WORK + FRC + 1] += g1;
        work[p * WORK + FRC + 2] += g2;
        work[p * WORK + FRC + 3] += g3;
        work[p * WORK + FRC + 4] += g4;
        work[p * WORK + FRC + 5] += g5;
    }
}

/* RNEA of the states [0, N - N % 2) of a batch, 2 at a time: rows of Q, QD, QDD (n numbers
 * each) into the same rows of TAU, with the external forces F (rows x 6 numbers for every
 * state, or for each state with F_each) or none (NULL); `work` holds rows * WORK + 4 n +
 * 6 rows vectors. Each state's torques are, bit for bit, those of xup_kernel and rnea_kernel
 * on that state alone. */
static void rnea_batch_lanes2(const double *K, long rows, long N, const double *Q,
    const double *QD, const double *QDD, double gx, double gy, double gz, const double *F,
    long F_each, double *TAU, sd_vd2 *work)
{
    const long n = (long)K[QIDX];
    sd_vd2 *q = work + rows * WORK, *qd = q + n, *qdd = qd + n, *tau = qdd + n;
    sd_vd2 *f_body = tau + n;
    for (long b = 0; b + 2 <= N; b += 2) {
        for (long k = 0; k < n; k++)
            for (int s = 0; s < 2; s++) {
                q[k][s] = Q[(b + s) * n + k];
                qd[k][s] = QD[(b + s) * n + k];
                qdd[k][s] = QDD[(b + s) * n + k];
            }
        for (long k = 0; F != NULL && k < rows * 6; k++)
            for (int s = 0; s < 2; s++)
                f_body[k][s] = F[(F_each ? b + s : 0) * rows * 6 + k];
        xup_kernel_lanes2(K, rows, q, work);
        rnea_kernel_lanes2(K, rows, q, qd, qdd, gx, gy, gz, f_body, F != NULL, tau, work);
        for (long k = 0; k < n; k++)
            for (int s = 0; s < 2; s++)
                TAU[(b + s) * n + k] = tau[k][s];
    }
}

#ifdef SD_AVX
#ifdef __clang__
#pragma clang attribute push (__attribute__((target("avx"))), apply_to = function)
#else
#pragma GCC push_options
#pragma GCC target("avx")
#endif
typedef double sd_vd4 __attribute__((vector_size(32)));

/* x in every lane. */
static inline sd_vd4 sd_splat4(double x)
{
    return (sd_vd4){x, x, x, x};
}

/* Whether x is nonzero in some lane. */
static inline long sd_nonzero4(sd_vd4 x)
{
    return x[0] != 0.0 || x[1] != 0.0 || x[2] != 0.0 || x[3] != 0.0;
}

/* The C library's sin and cos, lane by lane: each lane's value is the scalar kernel's (the
 * compiler computes the sine and cosine of one lane with one call to sincos). */
static inline sd_vd4 sd_sin4(sd_vd4 x)
{
    return (sd_vd4){sin(x[0]), sin(x[1]), sin(x[2]), sin(x[3])};
}

static inline sd_vd4 sd_cos4(sd_vd4 x)
{
    return (sd_vd4){cos(x[0]), cos(x[1]), cos(x[2]), cos(x[3])};
}

/* Run components.X_motion on 4 states, generated from it. */
static inline void X_motion_lanes4(sd_vd4 e00, sd_vd4 e01, sd_vd4 e02, sd_vd4 e10, sd_vd4 e11,
    sd_vd4 e12, sd_vd4 e20, sd_vd4 e21, sd_vd4 e22, sd_vd4 rx, sd_vd4 ry, sd_vd4 rz, sd_vd4 m0,
    sd_vd4 m1, sd_vd4 m2, sd_vd4 m3, sd_vd4 m4, sd_vd4 m5, sd_vd4 *out)
{
    sd_vd4 u0, u1, u2;
    u0 = m3 - (ry * m2 - rz * m1);
    u1 = m4 - (rz * m0 - rx * m2);
    u2 = m5 - (rx * m1 - ry * m0);
    out[0] = e00 * m0 + e01 * m1 + e02 * m2;
    out[1] = e10 * m0 + e11 * m1 + e12 * m2;
    out[2] = e20 * m0 + e21 * m1 + e22 * m2;
    out[3] = e00 * u0 + e01 * u1 + e02 * u2;
    out[4] = e10 * u0 + e11 * u1 + e12 * u2;
    out[5] = e20 * u0 + e21 * u1 + e22 * u2;
}

/* Run components.XT_force on 4 states, generated from it. */
static inline void XT_force_lanes4(sd_vd4 e00, sd_vd4 e01, sd_vd4 e02, sd_vd4 e10, sd_vd4 e11,
    sd_vd4 e12, sd_vd4 e20, sd_vd4 e21, sd_vd4 e22, sd_vd4 rx, sd_vd4 ry, sd_vd4 rz, sd_vd4 n0,
    sd_vd4 n1, sd_vd4 n2, sd_vd4 f0, sd_vd4 f1, sd_vd4 f2, sd_vd4 *out)
{
    sd_vd4 F0, F1, F2;
    F0 = e00 * f0 + e10 * f1 + e20 * f2;
    F1 = e01 * f0 + e11 * f1 + e21 * f2;
    F2 = e02 * f0 + e12 * f1 + e22 * f2;
    out[0] = e00 * n0 + e10 * n1 + e20 * n2 + (ry * F2 - rz * F1);
    out[1] = e01 * n0 + e11 * n1 + e21 * n2 + (rz * F0 - rx * F2);
    out[2] = e02 * n0 + e12 * n1 + e22 * n2 + (rx * F1 - ry * F0);
    out[3] = F0;
    out[4] = F1;
    out[5] = F2;
}

/* Run components.I_motion on 4 states, generated from it. */
static inline void I_motion_lanes4(double mass, double hx, double hy, double hz, double Ixx,
    double Ixy, double Ixz, double Iyy, double Iyz, double Izz, sd_vd4 m0, sd_vd4 m1, sd_vd4 m2,
    sd_vd4 m3, sd_vd4 m4, sd_vd4 m5, sd_vd4 *out)
{
    out[0] = Ixx * m0 + Ixy * m1 + Ixz * m2 + (hy * m5 - hz * m4);
    out[1] = Ixy * m0 + Iyy * m1 + Iyz * m2 + (hz * m3 - hx * m5);
    out[2] = Ixz * m0 + Iyz * m1 + Izz * m2 + (hx * m4 - hy * m3);
    out[3] = mass * m3 - (hy * m2 - hz * m1);
    out[4] = mass * m4 - (hz * m0 - hx * m2);
    out[5] = mass * m5 - (hx * m1 - hy * m0);
}

/* Run rnea.xup_kernel on 4 states, generated from it. */
static inline void xup_kernel_lanes4(const double *K, long rows, const sd_vd4 *q, sd_vd4 *work)
{
    long code, i, k;
    sd_vd4 C, c, cxy, cxz, cyz, j00, j01, j02, j10, j11, j12, j20;
    sd_vd4 j21, j22, qi, s, sx, sy, sz;
    double ax, ay, az, mul, off, rx, ry, rz, t00, t01, t02, t10;
    double t11, t12, t20, t21, t22;
    for (i = 1; i < rows; i++) {
        code = (long)K[i * WIDTH + 1];
        k = (long)K[i * WIDTH + 2];
        ax = K[i * WIDTH + 3];
        ay = K[i * WIDTH + 4];
        az = K[i * WIDTH + 5];
        t00 = K[i * WIDTH + 6];
        t01 = K[i * WIDTH + 7];
        t02 = K[i * WIDTH + 8];
        t10 = K[i * WIDTH + 9];
        t11 = K[i * WIDTH + 10];
        t12 = K[i * WIDTH + 11];
        t20 = K[i * WIDTH + 12];
        t21 = K[i * WIDTH + 13];
        t22 = K[i * WIDTH + 14];
        rx = K[i * WIDTH + 15];
        ry = K[i * WIDTH + 16];
        rz = K[i * WIDTH + 17];
        mul = K[i * WIDTH + 28];
        off = K[i * WIDTH + 29];
        qi = (mul == 1.0 && off == 0.0 ? q[k] : mul * q[k] + off);
        if (code == PR) {
            work[i * WORK + XUP + 0] = sd_splat4(t00);
            work[i * WORK + XUP + 1] = sd_splat4(t01);
            work[i * WORK + XUP + 2] = sd_splat4(t02);
            work[i * WORK + XUP + 3] = sd_splat4(t10);
            work[i * WORK + XUP + 4] = sd_splat4(t11);
            work[i * WORK + XUP + 5] = sd_splat4(t12);
            work[i * WORK + XUP + 6] = sd_splat4(t20);
            work[i * WORK + XUP + 7] = sd_splat4(t21);
            work[i * WORK + XUP + 8] = sd_splat4(t22);
            work[i * WORK + XUP + 9] = rx + (t00 * ax + t10 * ay + t20 * az) * qi;
            work[i * WORK + XUP + 10] = ry + (t01 * ax + t11 * ay + t21 * az) * qi;
            work[i * WORK + XUP + 11] = rz + (t02 * ax + t12 * ay + t22 * az) * qi;
            continue;
        }
        {
            const sd_vd4 tmp1_ = sd_cos4(qi);
            const sd_vd4 tmp2_ = sd_sin4(qi);
            c = tmp1_;
            s = tmp2_;
        }
        if (code == RZ) {
            s = az * s;
            work[i * WORK + XUP + 0] = c * t00 + s * t10;
            work[i * WORK + XUP + 1] = c * t01 + s * t11;
            work[i * WORK + XUP + 2] = c * t02 + s * t12;
            work[i * WORK + XUP + 3] = c * t10 - s * t00;
            work[i * WORK + XUP + 4] = c * t11 - s * t01;
            work[i * WORK + XUP + 5] = c * t12 - s * t02;
            work[i * WORK + XUP + 6] = sd_splat4(t20);
            work[i * WORK + XUP + 7] = sd_splat4(t21);
            work[i * WORK + XUP + 8] = sd_splat4(t22);
            work[i * WORK + XUP + 9] = sd_splat4(rx);
            work[i * WORK + XUP + 10] = sd_splat4(ry);
            work[i * WORK + XUP + 11] = sd_splat4(rz);
        } else if (code == RX) {
            s = ax * s;
            work[i * WORK + XUP + 0] = sd_splat4(t00);
            work[i * WORK + XUP + 1] = sd_splat4(t01);
            work[i * WORK + XUP + 2] = sd_splat4(t02);
            work[i * WORK + XUP + 3] = c * t10 + s * t20;
            work[i * WORK + XUP + 4] = c * t11 + s * t21;
            work[i * WORK + XUP + 5] = c * t12 + s * t22;
            work[i * WORK + XUP + 6] = c * t20 - s * t10;
            work[i * WORK + XUP + 7] = c * t21 - s * t11;
            work[i * WORK + XUP + 8] = c * t22 - s * t12;
            work[i * WORK + XUP + 9] = sd_splat4(rx);
            work[i * WORK + XUP + 10] = sd_splat4(ry);
            work[i * WORK + XUP + 11] = sd_splat4(rz);
        } else if (code == RY) {
            s = ay * s;
            work[i * WORK + XUP + 0] = c * t00 - s * t20;
            work[i * WORK + XUP + 1] = c * t01 - s * t21;
            work[i * WORK + XUP + 2] = c * t02 - s * t22;
            work[i * WORK + XUP + 3] = sd_splat4(t10);
            work[i * WORK + XUP + 4] = sd_splat4(t11);
            work[i * WORK + XUP + 5] = sd_splat4(t12);
            work[i * WORK + XUP + 6] = s * t00 + c * t20;
            work[i * WORK + XUP + 7] = s * t01 + c * t21;
            work[i * WORK + XUP + 8] = s * t02 + c * t22;
            work[i * WORK + XUP + 9] = sd_splat4(rx);
            work[i * WORK + XUP + 10] = sd_splat4(ry);
            work[i * WORK + XUP + 11] = sd_splat4(rz);
        } else {
            C = 1.0 - c;
            {
                const sd_vd4 tmp3_ = c + C * ax * ax;
                const sd_vd4 tmp4_ = c + C * ay * ay;
                const sd_vd4 tmp5_ = c + C * az * az;
                j00 = tmp3_;
                j11 = tmp4_;
                j22 = tmp5_;
            }
            {
                const sd_vd4 tmp6_ = C * ax * ay;
                const sd_vd4 tmp7_ = C * ax * az;
                const sd_vd4 tmp8_ = C * ay * az;
                cxy = tmp6_;
                cxz = tmp7_;
                cyz = tmp8_;
            }
            {
                const sd_vd4 tmp9_ = s * ax;
                const sd_vd4 tmp10_ = s * ay;
                const sd_vd4 tmp11_ = s * az;
                sx = tmp9_;
                sy = tmp10_;
                sz = tmp11_;
            }
            {
                const sd_vd4 tmp12_ = cxy + sz;
                const sd_vd4 tmp13_ = cxz - sy;
                const sd_vd4 tmp14_ = cxy - sz;
                j01 = tmp12_;
                j02 = tmp13_;
                j10 = tmp14_;
            }
            {
                const sd_vd4 tmp15_ = cyz + sx;
                const sd_vd4 tmp16_ = cxz + sy;
                const sd_vd4 tmp17_ = cyz - sx;
                j12 = tmp15_;
                j20 = tmp16_;
                j21 = tmp17_;
            }
            work[i * WORK + XUP + 0] = j00 * t00 + j01 * t10 + j02 * t20;
            work[i * WORK + XUP + 1] = j00 * t01 + j01 * t11 + j02 * t21;
            work[i * WORK + XUP + 2] = j00 * t02 + j01 * t12 + j02 * t22;
            work[i * WORK + XUP + 3] = j10 * t00 + j11 * t10 + j12 * t20;
            work[i * WORK + XUP + 4] = j10 * t01 + j11 * t11 + j12 * t21;
            work[i * WORK + XUP + 5] = j10 * t02 + j11 * t12 + j12 * t22;
            work[i * WORK + XUP + 6] = j20 * t00 + j21 * t10 + j22 * t20;
            work[i * WORK + XUP + 7] = j20 * t01 + j21 * t11 + j22 * t21;
            work[i * WORK + XUP + 8] = j20 * t02 + j21 * t12 + j22 * t22;
            work[i * WORK + XUP + 9] = sd_splat4(rx);
            work[i * WORK + XUP + 10] = sd_splat4(ry);
            work[i * WORK + XUP + 11] = sd_splat4(rz);
        }
    }
}

/* Run rnea.rnea_kernel on 4 states, generated from it. */
static inline void rnea_kernel_lanes4(const double *K, long rows, const sd_vd4 *q,
    const sd_vd4 *qd, const sd_vd4 *qdd, double gx, double gy, double gz, const sd_vd4 *f_body,
    long has_fext, sd_vd4 *tau, sd_vd4 *work)
{
    (void)q;
    const long nq = (long)K[QIDX];
    long NB, code, i, k, moving, p, static_, weightless;
    double Ixx, Ixy, Ixz, Iyy, Iyz, Izz, ax, ay, az, hx, hy, hz;
    double mass, mul, zero;
    sd_vd4 a0, a1, a2, e00, e01, e02, e10, e11, e12, e20, e21, e22;
    sd_vd4 f0, f1, f2, fe0, fe1, fe2, fe3, fe4, fe5, g0, g1, g2;
    sd_vd4 g3, g4, g5, j0, j1, j2, k0, k1, k2, l0, l1, l2;
    sd_vd4 m0, m1, m2, n0, n1, n2, pa0, pa1, pa2, pl0, pl1, pl2;
    sd_vd4 pv0, pv1, pv2, pw0, pw1, pw2, qddi, qdi, rx, ry, rz, t;
    sd_vd4 v0, v1, v2, w0, w1, w2, x;
    NB = rows - 1;
    zero = 0.0 * gx;
    moving = 0;
    for (long j1_ = 0; j1_ < nq; j1_++) {
        x = qd[j1_];
        if (sd_nonzero4(x)) {
            moving = 1;
            break;
        }
    }
    static_ = !moving;
    if (static_) {
        for (long j2_ = 0; j2_ < nq; j2_++) {
            x = qdd[j2_];
            if (sd_nonzero4(x)) {
                static_ = 0;
                break;
            }
        }
    }
    weightless = !(gx != 0.0 || gy != 0.0 || gz != 0.0);
    work[0 * WORK + VEL + 0] = sd_splat4(zero);
    work[0 * WORK + VEL + 1] = sd_splat4(zero);
    work[0 * WORK + VEL + 2] = sd_splat4(zero);
    work[0 * WORK + VEL + 3] = sd_splat4(zero);
    work[0 * WORK + VEL + 4] = sd_splat4(zero);
    work[0 * WORK + VEL + 5] = sd_splat4(zero);
    work[0 * WORK + ACC + 0] = sd_splat4(zero);
    work[0 * WORK + ACC + 1] = sd_splat4(zero);
    work[0 * WORK + ACC + 2] = sd_splat4(zero);
    work[0 * WORK + ACC + 3] = sd_splat4(-gx);
    work[0 * WORK + ACC + 4] = sd_splat4(-gy);
    work[0 * WORK + ACC + 5] = sd_splat4(-gz);
    for (k = 0; k < nq; k++) {
        tau[k] = sd_splat4(zero);
    }
    for (i = 1; i < NB + 1; i++) {
        p = (long)K[i * WIDTH + 0];
        code = (long)K[i * WIDTH + 1];
        k = (long)K[i * WIDTH + 2];
        ax = K[i * WIDTH + 3];
        ay = K[i * WIDTH + 4];
        az = K[i * WIDTH + 5];
        mass = K[i * WIDTH + 18];
        hx = K[i * WIDTH + 19];
        hy = K[i * WIDTH + 20];
        hz = K[i * WIDTH + 21];
        Ixx = K[i * WIDTH + 22];
        Ixy = K[i * WIDTH + 23];
        Ixz = K[i * WIDTH + 24];
        Iyy = K[i * WIDTH + 25];
        Iyz = K[i * WIDTH + 26];
        Izz = K[i * WIDTH + 27];
        mul = K[i * WIDTH + 28];
        e00 = work[i * WORK + XUP + 0];
        e01 = work[i * WORK + XUP + 1];
        e02 = work[i * WORK + XUP + 2];
        e10 = work[i * WORK + XUP + 3];
        e11 = work[i * WORK + XUP + 4];
        e12 = work[i * WORK + XUP + 5];
        e20 = work[i * WORK + XUP + 6];
        e21 = work[i * WORK + XUP + 7];
        e22 = work[i * WORK + XUP + 8];
        rx = work[i * WORK + XUP + 9];
        ry = work[i * WORK + XUP + 10];
        rz = work[i * WORK + XUP + 11];
        if (static_) {
            pl0 = work[p * WORK + ACC + 3];
            pl1 = work[p * WORK + ACC + 4];
            pl2 = work[p * WORK + ACC + 5];
            l0 = e00 * pl0 + e01 * pl1 + e02 * pl2;
            l1 = e10 * pl0 + e11 * pl1 + e12 * pl2;
            l2 = e20 * pl0 + e21 * pl1 + e22 * pl2;
            work[i * WORK + ACC + 0] = sd_splat4(zero);
            work[i * WORK + ACC + 1] = sd_splat4(zero);
            work[i * WORK + ACC + 2] = sd_splat4(zero);
            work[i * WORK + ACC + 3] = l0;
            work[i * WORK + ACC + 4] = l1;
            work[i * WORK + ACC + 5] = l2;
            {
                const sd_vd4 tmp3_ = hy * l2 - hz * l1;
                const sd_vd4 tmp4_ = hz * l0 - hx * l2;
                const sd_vd4 tmp5_ = hx * l1 - hy * l0;
                n0 = tmp3_;
                n1 = tmp4_;
                n2 = tmp5_;
            }
            {
                const sd_vd4 tmp6_ = mass * l0;
                const sd_vd4 tmp7_ = mass * l1;
                const sd_vd4 tmp8_ = mass * l2;
                f0 = tmp6_;
                f1 = tmp7_;
                f2 = tmp8_;
            }
        } else {
            qddi = (mul == 1.0 ? qdd[k] : mul * qdd[k]);
            if (p == 0 && weightless) {
                a0 = a1 = a2 = l0 = l1 = l2 = sd_splat4(zero);
            } else {
                pa0 = work[p * WORK + ACC + 0];
                pa1 = work[p * WORK + ACC + 1];
                pa2 = work[p * WORK + ACC + 2];
                pl0 = work[p * WORK + ACC + 3];
                pl1 = work[p * WORK + ACC + 4];
                pl2 = work[p * WORK + ACC + 5];
                {
                    sd_vd4 ret9_[6];
                    X_motion_lanes4(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, pa0, pa1, pa2, pl0, pl1, pl2, ret9_);
                    a0 = ret9_[0];
                    a1 = ret9_[1];
                    a2 = ret9_[2];
                    l0 = ret9_[3];
                    l1 = ret9_[4];
                    l2 = ret9_[5];
                }
            }
            if (code == PR) {
                {
                    const sd_vd4 tmp10_ = l0 + ax * qddi;
                    const sd_vd4 tmp11_ = l1 + ay * qddi;
                    const sd_vd4 tmp12_ = l2 + az * qddi;
                    l0 = tmp10_;
                    l1 = tmp11_;
                    l2 = tmp12_;
                }
            } else {
                {
                    const sd_vd4 tmp13_ = a0 + ax * qddi;
                    const sd_vd4 tmp14_ = a1 + ay * qddi;
                    const sd_vd4 tmp15_ = a2 + az * qddi;
                    a0 = tmp13_;
                    a1 = tmp14_;
                    a2 = tmp15_;
                }
            }
            w0 = w1 = w2 = v0 = v1 = v2 = sd_splat4(zero);
            if (moving) {
                qdi = (mul == 1.0 ? qd[k] : mul * qd[k]);
                pw0 = work[p * WORK + VEL + 0];
                pw1 = work[p * WORK + VEL + 1];
                pw2 = work[p * WORK + VEL + 2];
                pv0 = work[p * WORK + VEL + 3];
                pv1 = work[p * WORK + VEL + 4];
                pv2 = work[p * WORK + VEL + 5];
                {
                    sd_vd4 ret16_[6];
                    X_motion_lanes4(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, pw0, pw1, pw2, pv0, pv1, pv2, ret16_);
                    w0 = ret16_[0];
                    w1 = ret16_[1];
                    w2 = ret16_[2];
                    v0 = ret16_[3];
                    v1 = ret16_[4];
                    v2 = ret16_[5];
                }
                {
                    const sd_vd4 tmp17_ = ax * qdi;
                    const sd_vd4 tmp18_ = ay * qdi;
                    const sd_vd4 tmp19_ = az * qdi;
                    j0 = tmp17_;
                    j1 = tmp18_;
                    j2 = tmp19_;
                }
                if (code == PR) {
                    {
                        const sd_vd4 tmp20_ = v0 + j0;
                        const sd_vd4 tmp21_ = v1 + j1;
                        const sd_vd4 tmp22_ = v2 + j2;
                        v0 = tmp20_;
                        v1 = tmp21_;
                        v2 = tmp22_;
                    }
                    l0 += w1 * j2 - w2 * j1;
                    l1 += w2 * j0 - w0 * j2;
                    l2 += w0 * j1 - w1 * j0;
                } else {
                    {
                        const sd_vd4 tmp23_ = w0 + j0;
                        const sd_vd4 tmp24_ = w1 + j1;
                        const sd_vd4 tmp25_ = w2 + j2;
                        w0 = tmp23_;
                        w1 = tmp24_;
                        w2 = tmp25_;
                    }
                    a0 += w1 * j2 - w2 * j1;
                    a1 += w2 * j0 - w0 * j2;
                    a2 += w0 * j1 - w1 * j0;
                    l0 += v1 * j2 - v2 * j1;
                    l1 += v2 * j0 - v0 * j2;
                    l2 += v0 * j1 - v1 * j0;
                }
                work[i * WORK + VEL + 0] = w0;
                work[i * WORK + VEL + 1] = w1;
                work[i * WORK + VEL + 2] = w2;
                work[i * WORK + VEL + 3] = v0;
                work[i * WORK + VEL + 4] = v1;
                work[i * WORK + VEL + 5] = v2;
            }
            work[i * WORK + ACC + 0] = a0;
            work[i * WORK + ACC + 1] = a1;
            work[i * WORK + ACC + 2] = a2;
            work[i * WORK + ACC + 3] = l0;
            work[i * WORK + ACC + 4] = l1;
            work[i * WORK + ACC + 5] = l2;
            {
                sd_vd4 ret26_[6];
                I_motion_lanes4(mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz, a0, a1, a2, l0, l1, l2, ret26_);
                n0 = ret26_[0];
                n1 = ret26_[1];
                n2 = ret26_[2];
                f0 = ret26_[3];
                f1 = ret26_[4];
                f2 = ret26_[5];
            }
            if (moving) {
                {
                    sd_vd4 ret27_[6];
                    I_motion_lanes4(mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz, w0, w1, w2, v0, v1, v2, ret27_);
                    m0 = ret27_[0];
                    m1 = ret27_[1];
                    m2 = ret27_[2];
                    k0 = ret27_[3];
                    k1 = ret27_[4];
                    k2 = ret27_[5];
                }
                n0 += w1 * m2 - w2 * m1 + (v1 * k2 - v2 * k1);
                n1 += w2 * m0 - w0 * m2 + (v2 * k0 - v0 * k2);
                n2 += w0 * m1 - w1 * m0 + (v0 * k1 - v1 * k0);
                f0 += w1 * k2 - w2 * k1;
                f1 += w2 * k0 - w0 * k2;
                f2 += w0 * k1 - w1 * k0;
            }
        }
        if (has_fext) {
            fe0 = f_body[i * 6 + 0];
            fe1 = f_body[i * 6 + 1];
            fe2 = f_body[i * 6 + 2];
            fe3 = f_body[i * 6 + 3];
            fe4 = f_body[i * 6 + 4];
            fe5 = f_body[i * 6 + 5];
            {
                const sd_vd4 tmp28_ = n0 - fe0;
                const sd_vd4 tmp29_ = n1 - fe1;
                const sd_vd4 tmp30_ = n2 - fe2;
                n0 = tmp28_;
                n1 = tmp29_;
                n2 = tmp30_;
            }
            {
                const sd_vd4 tmp31_ = f0 - fe3;
                const sd_vd4 tmp32_ = f1 - fe4;
                const sd_vd4 tmp33_ = f2 - fe5;
                f0 = tmp31_;
                f1 = tmp32_;
                f2 = tmp33_;
            }
        }
        work[i * WORK + FRC + 0] = n0;
        work[i * WORK + FRC + 1] = n1;
        work[i * WORK + FRC + 2] = n2;
        work[i * WORK + FRC + 3] = f0;
        work[i * WORK + FRC + 4] = f1;
        work[i * WORK + FRC + 5] = f2;
    }
    for (i = NB; i > 0; i--) {
        p = (long)K[i * WIDTH + 0];
        code = (long)K[i * WIDTH + 1];
        k = (long)K[i * WIDTH + 2];
        ax = K[i * WIDTH + 3];
        ay = K[i * WIDTH + 4];
        az = K[i * WIDTH + 5];
        mul = K[i * WIDTH + 28];
        n0 = work[i * WORK + FRC + 0];
        n1 = work[i * WORK + FRC + 1];
        n2 = work[i * WORK + FRC + 2];
        f0 = work[i * WORK + FRC + 3];
        f1 = work[i * WORK + FRC + 4];
        f2 = work[i * WORK + FRC + 5];
        if (code == PR) {
            t = ax * f0 + ay * f1 + az * f2;
        } else {
            t = ax * n0 + ay * n1 + az * n2;
        }
        tau[k] = tau[k] + (mul == 1.0 ? t : mul * t);
        if (p == 0) {
            continue;
        }
        e00 = work[i * WORK + XUP + 0];
        e01 = work[i * WORK + XUP + 1];
        e02 = work[i * WORK + XUP + 2];
        e10 = work[i * WORK + XUP + 3];
        e11 = work[i * WORK + XUP + 4];
        e12 = work[i * WORK + XUP + 5];
        e20 = work[i * WORK + XUP + 6];
        e21 = work[i * WORK + XUP + 7];
        e22 = work[i * WORK + XUP + 8];
        rx = work[i * WORK + XUP + 9];
        ry = work[i * WORK + XUP + 10];
        rz = work[i * WORK + XUP + 11];
        {
            sd_vd4 ret34_[6];
            XT_force_lanes4(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, n0, n1, n2, f0, f1, f2, ret34_);
            g0 = ret34_[0];
            g1 = ret34_[1];
            g2 = ret34_[2];
            g3 = ret34_[3];
            g4 = ret34_[4];
            g5 = ret34_[5];
        }
        work[p * WORK + FRC + 0] += g0;
        work[p * WORK + FRC + 1] += g1;
        work[p * WORK + FRC + 2] += g2;
        work[p * WORK + FRC + 3] += g3;
        work[p * WORK + FRC + 4] += g4;
        work[p * WORK + FRC + 5] += g5;
    }
}

/* RNEA of the states [0, N - N % 4) of a batch, 4 at a time: rows of Q, QD, QDD (n numbers
 * each) into the same rows of TAU, with the external forces F (rows x 6 numbers for every
 * state, or for each state with F_each) or none (NULL); `work` holds rows * WORK + 4 n +
 * 6 rows vectors. Each state's torques are, bit for bit, those of xup_kernel and rnea_kernel
 * on that state alone. */
static void rnea_batch_lanes4(const double *K, long rows, long N, const double *Q,
    const double *QD, const double *QDD, double gx, double gy, double gz, const double *F,
    long F_each, double *TAU, sd_vd4 *work)
{
    const long n = (long)K[QIDX];
    sd_vd4 *q = work + rows * WORK, *qd = q + n, *qdd = qd + n, *tau = qdd + n;
    sd_vd4 *f_body = tau + n;
    for (long b = 0; b + 4 <= N; b += 4) {
        for (long k = 0; k < n; k++)
            for (int s = 0; s < 4; s++) {
                q[k][s] = Q[(b + s) * n + k];
                qd[k][s] = QD[(b + s) * n + k];
                qdd[k][s] = QDD[(b + s) * n + k];
            }
        for (long k = 0; F != NULL && k < rows * 6; k++)
            for (int s = 0; s < 4; s++)
                f_body[k][s] = F[(F_each ? b + s : 0) * rows * 6 + k];
        xup_kernel_lanes4(K, rows, q, work);
        rnea_kernel_lanes4(K, rows, q, qd, qdd, gx, gy, gz, f_body, F != NULL, tau, work);
        for (long k = 0; k < n; k++)
            for (int s = 0; s < 4; s++)
                TAU[(b + s) * n + k] = tau[k][s];
    }
}
#ifdef __clang__
#pragma clang attribute pop
#else
#pragma GCC pop_options
#endif

#ifdef __clang__
#pragma clang attribute push (__attribute__((target("avx512f"))), apply_to = function)
#else
#pragma GCC push_options
#pragma GCC target("avx512f")
#endif
typedef double sd_vd8 __attribute__((vector_size(64)));

/* x in every lane. */
static inline sd_vd8 sd_splat8(double x)
{
    return (sd_vd8){x, x, x, x, x, x, x, x};
}

/* Whether x is nonzero in some lane. */
static inline long sd_nonzero8(sd_vd8 x)
{
    return x[0] != 0.0 || x[1] != 0.0 || x[2] != 0.0 || x[3] != 0.0 || x[4] != 0.0 || x[5] != 0.0 || x[6] != 0.0 || x[7] != 0.0;
}

/* The C library's sin and cos, lane by lane: each lane's value is the scalar kernel's (the
 * compiler computes the sine and cosine of one lane with one call to sincos). */
static inline sd_vd8 sd_sin8(sd_vd8 x)
{
    return (sd_vd8){sin(x[0]), sin(x[1]), sin(x[2]), sin(x[3]), sin(x[4]), sin(x[5]), sin(x[6]), sin(x[7])};
}

static inline sd_vd8 sd_cos8(sd_vd8 x)
{
    return (sd_vd8){cos(x[0]), cos(x[1]), cos(x[2]), cos(x[3]), cos(x[4]), cos(x[5]), cos(x[6]), cos(x[7])};
}

/* Run components.X_motion on 8 states, generated from it. */
static inline void X_motion_lanes8(sd_vd8 e00, sd_vd8 e01, sd_vd8 e02, sd_vd8 e10, sd_vd8 e11,
    sd_vd8 e12, sd_vd8 e20, sd_vd8 e21, sd_vd8 e22, sd_vd8 rx, sd_vd8 ry, sd_vd8 rz, sd_vd8 m0,
    sd_vd8 m1, sd_vd8 m2, sd_vd8 m3, sd_vd8 m4, sd_vd8 m5, sd_vd8 *out)
{
    sd_vd8 u0, u1, u2;
    u0 = m3 - (ry * m2 - rz * m1);
    u1 = m4 - (rz * m0 - rx * m2);
    u2 = m5 - (rx * m1 - ry * m0);
    out[0] = e00 * m0 + e01 * m1 + e02 * m2;
    out[1] = e10 * m0 + e11 * m1 + e12 * m2;
    out[2] = e20 * m0 + e21 * m1 + e22 * m2;
    out[3] = e00 * u0 + e01 * u1 + e02 * u2;
    out[4] = e10 * u0 + e11 * u1 + e12 * u2;
    out[5] = e20 * u0 + e21 * u1 + e22 * u2;
}

/* Run components.XT_force on 8 states, generated from it. */
static inline void XT_force_lanes8(sd_vd8 e00, sd_vd8 e01, sd_vd8 e02, sd_vd8 e10, sd_vd8 e11,
    sd_vd8 e12, sd_vd8 e20, sd_vd8 e21, sd_vd8 e22, sd_vd8 rx, sd_vd8 ry, sd_vd8 rz, sd_vd8 n0,
    sd_vd8 n1, sd_vd8 n2, sd_vd8 f0, sd_vd8 f1, sd_vd8 f2, sd_vd8 *out)
{
    sd_vd8 F0, F1, F2;
    F0 = e00 * f0 + e10 * f1 + e20 * f2;
    F1 = e01 * f0 + e11 * f1 + e21 * f2;
    F2 = e02 * f0 + e12 * f1 + e22 * f2;
    out[0] = e00 * n0 + e10 * n1 + e20 * n2 + (ry * F2 - rz * F1);
    out[1] = e01 * n0 + e11 * n1 + e21 * n2 + (rz * F0 - rx * F2);
    out[2] = e02 * n0 + e12 * n1 + e22 * n2 + (rx * F1 - ry * F0);
    out[3] = F0;
    out[4] = F1;
    out[5] = F2;
}

/* Run components.I_motion on 8 states, generated from it. */
static inline void I_motion_lanes8(double mass, double hx, double hy, double hz, double Ixx,
    double Ixy, double Ixz, double Iyy, double Iyz, double Izz, sd_vd8 m0, sd_vd8 m1, sd_vd8 m2,
    sd_vd8 m3, sd_vd8 m4, sd_vd8 m5, sd_vd8 *out)
{
    out[0] = Ixx * m0 + Ixy * m1 + Ixz * m2 + (hy * m5 - hz * m4);
    out[1] = Ixy * m0 + Iyy * m1 + Iyz * m2 + (hz * m3 - hx * m5);
    out[2] = Ixz * m0 + Iyz * m1 + Izz * m2 + (hx * m4 - hy * m3);
    out[3] = mass * m3 - (hy * m2 - hz * m1);
    out[4] = mass * m4 - (hz * m0 - hx * m2);
    out[5] = mass * m5 - (hx * m1 - hy * m0);
}

/* Run rnea.xup_kernel on 8 states, generated from it. */
static inline void xup_kernel_lanes8(const double *K, long rows, const sd_vd8 *q, sd_vd8 *work)
{
    long code, i, k;
    sd_vd8 C, c, cxy, cxz, cyz, j00, j01, j02, j10, j11, j12, j20;
    sd_vd8 j21, j22, qi, s, sx, sy, sz;
    double ax, ay, az, mul, off, rx, ry, rz, t00, t01, t02, t10;
    double t11, t12, t20, t21, t22;
    for (i = 1; i < rows; i++) {
        code = (long)K[i * WIDTH + 1];
        k = (long)K[i * WIDTH + 2];
        ax = K[i * WIDTH + 3];
        ay = K[i * WIDTH + 4];
        az = K[i * WIDTH + 5];
        t00 = K[i * WIDTH + 6];
        t01 = K[i * WIDTH + 7];
        t02 = K[i * WIDTH + 8];
        t10 = K[i * WIDTH + 9];
        t11 = K[i * WIDTH + 10];
        t12 = K[i * WIDTH + 11];
        t20 = K[i * WIDTH + 12];
        t21 = K[i * WIDTH + 13];
        t22 = K[i * WIDTH + 14];
        rx = K[i * WIDTH + 15];
        ry = K[i * WIDTH + 16];
        rz = K[i * WIDTH + 17];
        mul = K[i * WIDTH + 28];
        off = K[i * WIDTH + 29];
        qi = (mul == 1.0 && off == 0.0 ? q[k] : mul * q[k] + off);
        if (code == PR) {
            work[i * WORK + XUP + 0] = sd_splat8(t00);
            work[i * WORK + XUP + 1] = sd_splat8(t01);
            work[i * WORK + XUP + 2] = sd_splat8(t02);
            work[i * WORK + XUP + 3] = sd_splat8(t10);
            work[i * WORK + XUP + 4] = sd_splat8(t11);
            work[i * WORK + XUP + 5] = sd_splat8(t12);
            work[i * WORK + XUP + 6] = sd_splat8(t20);
            work[i * WORK + XUP + 7] = sd_splat8(t21);
            work[i * WORK + XUP + 8] = sd_splat8(t22);
            work[i * WORK + XUP + 9] = rx + (t00 * ax + t10 * ay + t20 * az) * qi;
            work[i * WORK + XUP + 10] = ry + (t01 * ax + t11 * ay + t21 * az) * qi;
            work[i * WORK + XUP + 11] = rz + (t02 * ax + t12 * ay + t22 * az) * qi;
            continue;
        }
        {
            const sd_vd8 tmp1_ = sd_cos8(qi);
            const sd_vd8 tmp2_ = sd_sin8(qi);
            c = tmp1_;
            s = tmp2_;
        }
        if (code == RZ) {
            s = az * s;
            work[i * WORK + XUP + 0] = c * t00 + s * t10;
            work[i * WORK + XUP + 1] = c * t01 + s * t11;
            work[i * WORK + XUP + 2] = c * t02 + s * t12;
            work[i * WORK + XUP + 3] = c * t10 - s * t00;
            work[i * WORK + XUP + 4] = c * t11 - s * t01;
            work[i * WORK + XUP + 5] = c * t12 - s * t02;
            work[i * WORK + XUP + 6] = sd_splat8(t20);
            work[i * WORK + XUP + 7] = sd_splat8(t21);
            work[i * WORK + XUP + 8] = sd_splat8(t22);
            work[i * WORK + XUP + 9] = sd_splat8(rx);
            work[i * WORK + XUP + 10] = sd_splat8(ry);
            work[i * WORK + XUP + 11] = sd_splat8(rz);
        } else if (code == RX) {
            s = ax * s;
            work[i * WORK + XUP + 0] = sd_splat8(t00);
            work[i * WORK + XUP + 1] = sd_splat8(t01);
            work[i * WORK + XUP + 2] = sd_splat8(t02);
            work[i * WORK + XUP + 3] = c * t10 + s * t20;
            work[i * WORK + XUP + 4] = c * t11 + s * t21;
            work[i * WORK + XUP + 5] = c * t12 + s * t22;
            work[i * WORK + XUP + 6] = c * t20 - s * t10;
            work[i * WORK + XUP + 7] = c * t21 - s * t11;
            work[i * WORK + XUP + 8] = c * t22 - s * t12;
            work[i * WORK + XUP + 9] = sd_splat8(rx);
            work[i * WORK + XUP + 10] = sd_splat8(ry);
            work[i * WORK + XUP + 11] = sd_splat8(rz);
        } else if (code == RY) {
            s = ay * s;
            work[i * WORK + XUP + 0] = c * t00 - s * t20;
            work[i * WORK + XUP + 1] = c * t01 - s * t21;
            work[i * WORK + XUP + 2] = c * t02 - s * t22;
            work[i * WORK + XUP + 3] = sd_splat8(t10);
            work[i * WORK + XUP + 4] = sd_splat8(t11);
            work[i * WORK + XUP + 5] = sd_splat8(t12);
            work[i * WORK + XUP + 6] = s * t00 + c * t20;
            work[i * WORK + XUP + 7] = s * t01 + c * t21;
            work[i * WORK + XUP + 8] = s * t02 + c * t22;
            work[i * WORK + XUP + 9] = sd_splat8(rx);
            work[i * WORK + XUP + 10] = sd_splat8(ry);
            work[i * WORK + XUP + 11] = sd_splat8(rz);
        } else {
            C = 1.0 - c;
            {
                const sd_vd8 tmp3_ = c + C * ax * ax;
                const sd_vd8 tmp4_ = c + C * ay * ay;
                const sd_vd8 tmp5_ = c + C * az * az;
                j00 = tmp3_;
                j11 = tmp4_;
                j22 = tmp5_;
            }
            {
                const sd_vd8 tmp6_ = C * ax * ay;
                const sd_vd8 tmp7_ = C * ax * az;
                const sd_vd8 tmp8_ = C * ay * az;
                cxy = tmp6_;
                cxz = tmp7_;
                cyz = tmp8_;
            }
            {
                const sd_vd8 tmp9_ = s * ax;
                const sd_vd8 tmp10_ = s * ay;
                const sd_vd8 tmp11_ = s * az;
                sx = tmp9_;
                sy = tmp10_;
                sz = tmp11_;
            }
            {
                const sd_vd8 tmp12_ = cxy + sz;
                const sd_vd8 tmp13_ = cxz - sy;
                const sd_vd8 tmp14_ = cxy - sz;
                j01 = tmp12_;
                j02 = tmp13_;
                j10 = tmp14_;
            }
            {
                const sd_vd8 tmp15_ = cyz + sx;
                const sd_vd8 tmp16_ = cxz + sy;
                const sd_vd8 tmp17_ = cyz - sx;
                j12 = tmp15_;
                j20 = tmp16_;
                j21 = tmp17_;
            }
            work[i * WORK + XUP + 0] = j00 * t00 + j01 * t10 + j02 * t20;
            work[i * WORK + XUP + 1] = j00 * t01 + j01 * t11 + j02 * t21;
            work[i * WORK + XUP + 2] = j00 * t02 + j01 * t12 + j02 * t22;
            work[i * WORK + XUP + 3] = j10 * t00 + j11 * t10 + j12 * t20;
            work[i * WORK + XUP + 4] = j10 * t01 + j11 * t11 + j12 * t21;
            work[i * WORK + XUP + 5] = j10 * t02 + j11 * t12 + j12 * t22;
            work[i * WORK + XUP + 6] = j20 * t00 + j21 * t10 + j22 * t20;
            work[i * WORK + XUP + 7] = j20 * t01 + j21 * t11 + j22 * t21;
            work[i * WORK + XUP + 8] = j20 * t02 + j21 * t12 + j22 * t22;
            work[i * WORK + XUP + 9] = sd_splat8(rx);
            work[i * WORK + XUP + 10] = sd_splat8(ry);
            work[i * WORK + XUP + 11] = sd_splat8(rz);
        }
    }
}

/* Run rnea.rnea_kernel on 8 states, generated from it. */
static inline void rnea_kernel_lanes8(const double *K, long rows, const sd_vd8 *q,
    const sd_vd8 *qd, const sd_vd8 *qdd, double gx, double gy, double gz, const sd_vd8 *f_body,
    long has_fext, sd_vd8 *tau, sd_vd8 *work)
{
    (void)q;
    const long nq = (long)K[QIDX];
    long NB, code, i, k, moving, p, static_, weightless;
    double Ixx, Ixy, Ixz, Iyy, Iyz, Izz, ax, ay, az, hx, hy, hz;
    double mass, mul, zero;
    sd_vd8 a0, a1, a2, e00, e01, e02, e10, e11, e12, e20, e21, e22;
    sd_vd8 f0, f1, f2, fe0, fe1, fe2, fe3, fe4, fe5, g0, g1, g2;
    sd_vd8 g3, g4, g5, j0, j1, j2, k0, k1, k2, l0, l1, l2;
    sd_vd8 m0, m1, m2, n0, n1, n2, pa0, pa1, pa2, pl0, pl1, pl2;
    sd_vd8 pv0, pv1, pv2, pw0, pw1, pw2, qddi, qdi, rx, ry, rz, t;
    sd_vd8 v0, v1, v2, w0, w1, w2, x;
    NB = rows - 1;
    zero = 0.0 * gx;
    moving = 0;
    for (long j1_ = 0; j1_ < nq; j1_++) {
        x = qd[j1_];
        if (sd_nonzero8(x)) {
            moving = 1;
            break;
        }
    }
    static_ = !moving;
    if (static_) {
        for (long j2_ = 0; j2_ < nq; j2_++) {
            x = qdd[j2_];
            if (sd_nonzero8(x)) {
                static_ = 0;
                break;
            }
        }
    }
    weightless = !(gx != 0.0 || gy != 0.0 || gz != 0.0);
    work[0 * WORK + VEL + 0] = sd_splat8(zero);
    work[0 * WORK + VEL + 1] = sd_splat8(zero);
    work[0 * WORK + VEL + 2] = sd_splat8(zero);
    work[0 * WORK + VEL + 3] = sd_splat8(zero);
    work[0 * WORK + VEL + 4] = sd_splat8(zero);
    work[0 * WORK + VEL + 5] = sd_splat8(zero);
    work[0 * WORK + ACC + 0] = sd_splat8(zero);
    work[0 * WORK + ACC + 1] = sd_splat8(zero);
    work[0 * WORK + ACC + 2] = sd_splat8(zero);
    work[0 * WORK + ACC + 3] = sd_splat8(-gx);
    work[0 * WORK + ACC + 4] = sd_splat8(-gy);
    work[0 * WORK + ACC + 5] = sd_splat8(-gz);
    for (k = 0; k < nq; k++) {
        tau[k] = sd_splat8(zero);
    }
    for (i = 1; i < NB + 1; i++) {
        p = (long)K[i * WIDTH + 0];
        code = (long)K[i * WIDTH + 1];
        k = (long)K[i * WIDTH + 2];
        ax = K[i * WIDTH + 3];
        ay = K[i * WIDTH + 4];
        az = K[i * WIDTH + 5];
        mass = K[i * WIDTH + 18];
        hx = K[i * WIDTH + 19];
        hy = K[i * WIDTH + 20];
        hz = K[i * WIDTH + 21];
        Ixx = K[i * WIDTH + 22];
        Ixy = K[i * WIDTH + 23];
        Ixz = K[i * WIDTH + 24];
        Iyy = K[i * WIDTH + 25];
        Iyz = K[i * WIDTH + 26];
        Izz = K[i * WIDTH + 27];
        mul = K[i * WIDTH + 28];
        e00 = work[i * WORK + XUP + 0];
        e01 = work[i * WORK + XUP + 1];
        e02 = work[i * WORK + XUP + 2];
        e10 = work[i * WORK + XUP + 3];
        e11 = work[i * WORK + XUP + 4];
        e12 = work[i * WORK + XUP + 5];
        e20 = work[i * WORK + XUP + 6];
        e21 = work[i * WORK + XUP + 7];
        e22 = work[i * WORK + XUP + 8];
        rx = work[i * WORK + XUP + 9];
        ry = work[i * WORK + XUP + 10];
        rz = work[i * WORK + XUP + 11];
        if (static_) {
            pl0 = work[p * WORK + ACC + 3];
            pl1 = work[p * WORK + ACC + 4];
            pl2 = work[p * WORK + ACC + 5];
            l0 = e00 * pl0 + e01 * pl1 + e02 * pl2;
            l1 = e10 * pl0 + e11 * pl1 + e12 * pl2;
            l2 = e20 * pl0 + e21 * pl1 + e22 * pl2;
            work[i * WORK + ACC + 0] = sd_splat8(zero);
            work[i * WORK + ACC + 1] = sd_splat8(zero);
            work[i * WORK + ACC + 2] = sd_splat8(zero);
            work[i * WORK + ACC + 3] = l0;
            work[i * WORK + ACC + 4] = l1;
            work[i * WORK + ACC + 5] = l2;
            {
                const sd_vd8 tmp3_ = hy * l2 - hz * l1;
                const sd_vd8 tmp4_ = hz * l0 - hx * l2;
                const sd_vd8 tmp5_ = hx * l1 - hy * l0;
                n0 = tmp3_;
                n1 = tmp4_;
                n2 = tmp5_;
            }
            {
                const sd_vd8 tmp6_ = mass * l0;
                const sd_vd8 tmp7_ = mass * l1;
                const sd_vd8 tmp8_ = mass * l2;
                f0 = tmp6_;
                f1 = tmp7_;
                f2 = tmp8_;
            }
        } else {
            qddi = (mul == 1.0 ? qdd[k] : mul * qdd[k]);
            if (p == 0 && weightless) {
                a0 = a1 = a2 = l0 = l1 = l2 = sd_splat8(zero);
            } else {
                pa0 = work[p * WORK + ACC + 0];
                pa1 = work[p * WORK + ACC + 1];
                pa2 = work[p * WORK + ACC + 2];
                pl0 = work[p * WORK + ACC + 3];
                pl1 = work[p * WORK + ACC + 4];
                pl2 = work[p * WORK + ACC + 5];
                {
                    sd_vd8 ret9_[6];
                    X_motion_lanes8(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, pa0, pa1, pa2, pl0, pl1, pl2, ret9_);
                    a0 = ret9_[0];
                    a1 = ret9_[1];
                    a2 = ret9_[2];
                    l0 = ret9_[3];
                    l1 = ret9_[4];
                    l2 = ret9_[5];
                }
            }
            if (code == PR) {
                {
                    const sd_vd8 tmp10_ = l0 + ax * qddi;
                    const sd_vd8 tmp11_ = l1 + ay * qddi;
                    const sd_vd8 tmp12_ = l2 + az * qddi;
                    l0 = tmp10_;
                    l1 = tmp11_;
                    l2 = tmp12_;
                }
            } else {
                {
                    const sd_vd8 tmp13_ = a0 + ax * qddi;
                    const sd_vd8 tmp14_ = a1 + ay * qddi;
                    const sd_vd8 tmp15_ = a2 + az * qddi;
                    a0 = tmp13_;
                    a1 = tmp14_;
                    a2 = tmp15_;
                }
            }
            w0 = w1 = w2 = v0 = v1 = v2 = sd_splat8(zero);
            if (moving) {
                qdi = (mul == 1.0 ? qd[k] : mul * qd[k]);
                pw0 = work[p * WORK + VEL + 0];
                pw1 = work[p * WORK + VEL + 1];
                pw2 = work[p * WORK + VEL + 2];
                pv0 = work[p * WORK + VEL + 3];
                pv1 = work[p * WORK + VEL + 4];
                pv2 = work[p * WORK + VEL + 5];
                {
                    sd_vd8 ret16_[6];
                    X_motion_lanes8(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, pw0, pw1, pw2, pv0, pv1, pv2, ret16_);
                    w0 = ret16_[0];
                    w1 = ret16_[1];
                    w2 = ret16_[2];
                    v0 = ret16_[3];
                    v1 = ret16_[4];
                    v2 = ret16_[5];
                }
                {
                    const sd_vd8 tmp17_ = ax * qdi;
                    const sd_vd8 tmp18_ = ay * qdi;
                    const sd_vd8 tmp19_ = az * qdi;
                    j0 = tmp17_;
                    j1 = tmp18_;
                    j2 = tmp19_;
                }
                if (code == PR) {
                    {
                        const sd_vd8 tmp20_ = v0 + j0;
                        const sd_vd8 tmp21_ = v1 + j1;
                        const sd_vd8 tmp22_ = v2 + j2;
                        v0 = tmp20_;
                        v1 = tmp21_;
                        v2 = tmp22_;
                    }
                    l0 += w1 * j2 - w2 * j1;
                    l1 += w2 * j0 - w0 * j2;
                    l2 += w0 * j1 - w1 * j0;
                } else {
                    {
                        const sd_vd8 tmp23_ = w0 + j0;
                        const sd_vd8 tmp24_ = w1 + j1;
                        const sd_vd8 tmp25_ = w2 + j2;
                        w0 = tmp23_;
                        w1 = tmp24_;
                        w2 = tmp25_;
                    }
                    a0 += w1 * j2 - w2 * j1;
                    a1 += w2 * j0 - w0 * j2;
                    a2 += w0 * j1 - w1 * j0;
                    l0 += v1 * j2 - v2 * j1;
                    l1 += v2 * j0 - v0 * j2;
                    l2 += v0 * j1 - v1 * j0;
                }
                work[i * WORK + VEL + 0] = w0;
                work[i * WORK + VEL + 1] = w1;
                work[i * WORK + VEL + 2] = w2;
                work[i * WORK + VEL + 3] = v0;
                work[i * WORK + VEL + 4] = v1;
                work[i * WORK + VEL + 5] = v2;
            }
            work[i * WORK + ACC + 0] = a0;
            work[i * WORK + ACC + 1] = a1;
            work[i * WORK + ACC + 2] = a2;
            work[i * WORK + ACC + 3] = l0;
            work[i * WORK + ACC + 4] = l1;
            work[i * WORK + ACC + 5] = l2;
            {
                sd_vd8 ret26_[6];
                I_motion_lanes8(mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz, a0, a1, a2, l0, l1, l2, ret26_);
                n0 = ret26_[0];
                n1 = ret26_[1];
                n2 = ret26_[2];
                f0 = ret26_[3];
                f1 = ret26_[4];
                f2 = ret26_[5];
            }
            if (moving) {
                {
                    sd_vd8 ret27_[6];
                    I_motion_lanes8(mass, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz, w0, w1, w2, v0, v1, v2, ret27_);
                    m0 = ret27_[0];
                    m1 = ret27_[1];
                    m2 = ret27_[2];
                    k0 = ret27_[3];
                    k1 = ret27_[4];
                    k2 = ret27_[5];
                }
                n0 += w1 * m2 - w2 * m1 + (v1 * k2 - v2 * k1);
                n1 += w2 * m0 - w0 * m2 + (v2 * k0 - v0 * k2);
                n2 += w0 * m1 - w1 * m0 + (v0 * k1 - v1 * k0);
                f0 += w1 * k2 - w2 * k1;
                f1 += w2 * k0 - w0 * k2;
                f2 += w0 * k1 - w1 * k0;
            }
        }
        if (has_fext) {
            fe0 = f_body[i * 6 + 0];
            fe1 = f_body[i * 6 + 1];
            fe2 = f_body[i * 6 + 2];
            fe3 = f_body[i * 6 + 3];
            fe4 = f_body[i * 6 + 4];
            fe5 = f_body[i * 6 + 5];
            {
                const sd_vd8 tmp28_ = n0 - fe0;
                const sd_vd8 tmp29_ = n1 - fe1;
                const sd_vd8 tmp30_ = n2 - fe2;
                n0 = tmp28_;
                n1 = tmp29_;
                n2 = tmp30_;
            }
            {
                const sd_vd8 tmp31_ = f0 - fe3;
                const sd_vd8 tmp32_ = f1 - fe4;
                const sd_vd8 tmp33_ = f2 - fe5;
                f0 = tmp31_;
                f1 = tmp32_;
                f2 = tmp33_;
            }
        }
        work[i * WORK + FRC + 0] = n0;
        work[i * WORK + FRC + 1] = n1;
        work[i * WORK + FRC + 2] = n2;
        work[i * WORK + FRC + 3] = f0;
        work[i * WORK + FRC + 4] = f1;
        work[i * WORK + FRC + 5] = f2;
    }
    for (i = NB; i > 0; i--) {
        p = (long)K[i * WIDTH + 0];
        code = (long)K[i * WIDTH + 1];
        k = (long)K[i * WIDTH + 2];
        ax = K[i * WIDTH + 3];
        ay = K[i * WIDTH + 4];
        az = K[i * WIDTH + 5];
        mul = K[i * WIDTH + 28];
        n0 = work[i * WORK + FRC + 0];
        n1 = work[i * WORK + FRC + 1];
        n2 = work[i * WORK + FRC + 2];
        f0 = work[i * WORK + FRC + 3];
        f1 = work[i * WORK + FRC + 4];
        f2 = work[i * WORK + FRC + 5];
        if (code == PR) {
            t = ax * f0 + ay * f1 + az * f2;
        } else {
            t = ax * n0 + ay * n1 + az * n2;
        }
        tau[k] = tau[k] + (mul == 1.0 ? t : mul * t);
        if (p == 0) {
            continue;
        }
        e00 = work[i * WORK + XUP + 0];
        e01 = work[i * WORK + XUP + 1];
        e02 = work[i * WORK + XUP + 2];
        e10 = work[i * WORK + XUP + 3];
        e11 = work[i * WORK + XUP + 4];
        e12 = work[i * WORK + XUP + 5];
        e20 = work[i * WORK + XUP + 6];
        e21 = work[i * WORK + XUP + 7];
        e22 = work[i * WORK + XUP + 8];
        rx = work[i * WORK + XUP + 9];
        ry = work[i * WORK + XUP + 10];
        rz = work[i * WORK + XUP + 11];
        {
            sd_vd8 ret34_[6];
            XT_force_lanes8(e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, n0, n1, n2, f0, f1, f2, ret34_);
            g0 = ret34_[0];
            g1 = ret34_[1];
            g2 = ret34_[2];
            g3 = ret34_[3];
            g4 = ret34_[4];
            g5 = ret34_[5];
        }
        work[p * WORK + FRC + 0] += g0;
        work[p * WORK + FRC + 1] += g1;
        work[p * WORK + FRC + 2] += g2;
        work[p * WORK + FRC + 3] += g3;
        work[p * WORK + FRC + 4] += g4;
        work[p * WORK + FRC + 5] += g5;
    }
}

/* RNEA of the states [0, N - N % 8) of a batch, 8 at a time: rows of Q, QD, QDD (n numbers
 * each) into the same rows of TAU, with the external forces F (rows x 6 numbers for every
 * state, or for each state with F_each) or none (NULL); `work` holds rows * WORK + 4 n +
 * 6 rows vectors. Each state's torques are, bit for bit, those of xup_kernel and rnea_kernel
 * on that state alone. */
static void rnea_batch_lanes8(const double *K, long rows, long N, const double *Q,
    const double *QD, const double *QDD, double gx, double gy, double gz, const double *F,
    long F_each, double *TAU, sd_vd8 *work)
{
    const long n = (long)K[QIDX];
    sd_vd8 *q = work + rows * WORK, *qd = q + n, *qdd = qd + n, *tau = qdd + n;
    sd_vd8 *f_body = tau + n;
    for (long b = 0; b + 8 <= N; b += 8) {
        for (long k = 0; k < n; k++)
            for (int s = 0; s < 8; s++) {
                q[k][s] = Q[(b + s) * n + k];
                qd[k][s] = QD[(b + s) * n + k];
                qdd[k][s] = QDD[(b + s) * n + k];
            }
        for (long k = 0; F != NULL && k < rows * 6; k++)
            for (int s = 0; s < 8; s++)
                f_body[k][s] = F[(F_each ? b + s : 0) * rows * 6 + k];
        xup_kernel_lanes8(K, rows, q, work);
        rnea_kernel_lanes8(K, rows, q, qd, qdd, gx, gy, gz, f_body, F != NULL, tau, work);
        for (long k = 0; k < n; k++)
            for (int s = 0; s < 8; s++)
                TAU[(b + s) * n + k] = tau[k][s];
    }
}
#ifdef __clang__
#pragma clang attribute pop
#else
#pragma GCC pop_options
#endif

#endif  /* SD_AVX */

/* RNEA of the first states of a batch of N (see above) in lanes: the number of states done
 * (N rounded down to the lanes), or -1 without memory. */
static long rnea_batch_lanes(const double *K, long rows, long N, const double *Q,
    const double *QD, const double *QDD, double gx, double gy, double gz, const double *F,
    long F_each, double *TAU)
{
    const long n = (long)K[QIDX], size = 8 * (rows * WORK + 4 * n + 6 * rows);   /* doubles */
    long lanes = 2;
#ifdef SD_AVX
    lanes = __builtin_cpu_supports("avx512f") ? 8 : __builtin_cpu_supports("avx") ? 4 : 2;
#endif
    if (N < lanes)
        return 0;
    double *raw = malloc(sizeof(double) * size + 64);
    if (raw == NULL)
        return -1;
    void *work = (void *)(((uintptr_t)raw + 63) & ~(uintptr_t)63);
#ifdef SD_AVX
    if (lanes == 8)
        rnea_batch_lanes8(K, rows, N, Q, QD, QDD, gx, gy, gz, F, F_each, TAU, work);
    else if (lanes == 4)
        rnea_batch_lanes4(K, rows, N, Q, QD, QDD, gx, gy, gz, F, F_each, TAU, work);
    else
#endif
        rnea_batch_lanes2(K, rows, N, Q, QD, QDD, gx, gy, gz, F, F_each, TAU, work);
    free(raw);
    return N - N % lanes;
}
#endif  /* vector extensions */

#endif  /* SPATIAL_DYNAMICS_KERNELS_GENERATED_H */
