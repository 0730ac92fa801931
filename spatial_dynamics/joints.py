# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Joint models, each kind in one home: its kernel code, ``XJ``, ``S``, ``S q̇`` and ``Sᵀ f``.

As Pinocchio's ``joint-*.hpp`` and spatial_v2's ``jcalc``: everything an algorithm needs to
know about a kind is here, so an algorithm asks the joint instead of branching on its kind.

* **Kinds** (``Model.jtype``): :data:`FIXED` (body 0, the world or fixed base),
  :data:`REVOLUTE` and :data:`PRISMATIC` (RBDA table 4.1, about or along a unit ``axis`` in
  the child frame), :data:`FREE_FLYER` (RBDA §4.5: the floating base, 6 DoF).
* **Kernel codes** (the per-body rows of :mod:`spatial_dynamics.backends.layout`):
  :func:`joint_code` classifies once; revolute joints about ±x, ±y, ±z get the cheaper forms
  :data:`RX`, :data:`RY`, :data:`RZ` (the axis keeps its sign), any other axis :data:`RA`.
* **Operations on scalar components** (:func:`joint_transform`, :func:`joint_motion`,
  :func:`joint_velocity`, :func:`joint_torque`, :func:`joint_ctq`, :func:`joint_axis`,
  :func:`joint_world_axis`, :func:`joint_crba`, :func:`joint_pair`): what the component
  kernels of :mod:`spatial_dynamics.algorithms` call per body, on any scalar kind (floats,
  (N,) arrays, mpmath); the compiled backend translates them with the kernels
  (:mod:`spatial_dynamics.backends.codegen`), and the C compiler inlines them. A joint's
  coordinates start at ``k`` in ``q`` and at ``kv`` in ``q̇``, ``q̈`` and ``τ``; a mimic
  joint moves by ``mul q + off`` of its source.
* :func:`jcalc`: the same on 6×6 matrices, batch-aware (the executable specifications).

The free-flyer's conventions: ``q = [x, y, z, qx, qy, qz, qw]``, the position of the body's
origin in the parent (world) frame and the unit quaternion of its orientation, in the order of
``geometry_msgs/Pose`` (and of Pinocchio's ``q``). A quaternion whose norm is within
:data:`QUATERNION_TOLERANCE` of 1 (rounding noise, float32, integration drift) is normalised
where it is used; any other (zero, not finite, 0.5, 2) is refused where it enters, by
:func:`check_quaternion`, as a rotation matrix that is not one by :func:`check_rotation`.
``q̇`` (we say ``v``) is the body's
spatial velocity in its own frame, angular first ``[ω; v]`` like every spatial vector here;
``S = 1`` (6×6), so ``τ`` of the joint is the body wrench ``[n; f]`` in the body frame.
Pinocchio's free-flyer velocity is the same twist linear first, ``[v; ω]`` (``LOCAL``).
"""

from __future__ import annotations

import numpy as np

from .spatial import Eaxis, Erotx, Eroty, Erotz, _rot, plux, xlt
from .text import at_state

#: Joint kinds stored in ``Model.jtype``. Body 0 (the world or the fixed base) has ``FIXED``.
FIXED, REVOLUTE, PRISMATIC, FREE_FLYER = 0, 1, 2, 3
KIND_NAMES = {FIXED: 'fixed', REVOLUTE: 'revolute', PRISMATIC: 'prismatic',
              FREE_FLYER: 'free-flyer'}
#: Coordinates of a joint of each kind in ``q`` (NQ) and in ``q̇``, ``q̈``, ``τ`` (NV).
NQ = {FIXED: 0, REVOLUTE: 1, PRISMATIC: 1, FREE_FLYER: 7}
NV = {FIXED: 0, REVOLUTE: 1, PRISMATIC: 1, FREE_FLYER: 6}

#: URDF joint types and the kind that models them.
URDF_KINDS = {'revolute': REVOLUTE, 'continuous': REVOLUTE, 'prismatic': PRISMATIC,
              'fixed': FIXED}

#: Kernel codes: revolute about ±x, ±y, ±z (the axis keeps its sign) or a general axis;
#: prismatic; free-flyer.
RX, RY, RZ, RA, PR, FF = 0, 1, 2, 3, 4, 5
CODES = {'RX': RX, 'RY': RY, 'RZ': RZ, 'RA': RA, 'PR': PR, 'FF': FF}

_AXIS_E = (Erotx, Eroty, Erotz)

#: ``|‖quaternion‖ − 1|`` accepted, then normalised where it is used: rounding noise, float32
#: messages and integration drift pass; a zero, 0.5 or 2 is no orientation but a bug.
QUATERNION_TOLERANCE = 1e-2
#: Largest entry of ``RᵀR − 1`` accepted of a rotation matrix (float32 sources give ~1e-7).
ROTATION_TOLERANCE = 1e-6
#: The squared norms within QUATERNION_TOLERANCE of 1 (what the compiled entry compares).
_UNIT_SQUARED = ((1.0 - QUATERNION_TOLERANCE) ** 2, (1.0 + QUATERNION_TOLERANCE) ** 2)


def frame_axis(axis) -> tuple[int, float]:
    """Return ``(k, sign)`` when ``axis`` is ``±`` the frame axis ``k`` (0, 1, 2), else (-1, 0)."""
    for k in range(3):
        if abs(axis[k]) == 1.0 and axis[(k + 1) % 3] == 0.0 and axis[(k + 2) % 3] == 0.0:
            return k, float(axis[k])
    return -1, 0.0


def joint_code(jtype: int, axis) -> int:
    """Kernel code of a joint: RX/RY/RZ about ±x/±y/±z, RA another axis, PR, FF."""
    if jtype == PRISMATIC:
        return PR
    if jtype == FREE_FLYER:
        return FF
    if jtype != REVOLUTE:
        raise ValueError(f'no kernel code for a {KIND_NAMES.get(jtype, jtype)} joint')
    k, _ = frame_axis(axis)
    return RA if k < 0 else (RX, RY, RZ)[k]


def motion_subspace(jtype: int, axis: np.ndarray) -> np.ndarray:
    """Return ``S`` (6, NV): ``[axis; 0]`` revolute, ``[0; axis]`` prismatic, ``1`` free-flyer."""
    if jtype == FREE_FLYER:
        return np.eye(6)
    S = np.zeros((6, NV[jtype]))
    if jtype == REVOLUTE:
        S[:3, 0] = axis
    elif jtype == PRISMATIC:
        S[3:, 0] = axis
    return S


def jcalc(jtype: int, axis: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joint transform and motion subspace (RBDA table 4.1 and §4.5), batch-aware.

    ``q``: (...) in rad or m for a 1-DoF joint (its value, mimic multiplier applied), (..., 7)
    for a free-flyer. Returns ``XJ`` (..., 6, 6) mapping parent-side joint-frame coordinates to
    child coordinates, and ``S`` (6, NV) in child coordinates. Revolute: ``XJ = rot(E(axis,
    q))`` (``rx``/``ry``/``rz`` for ±x/±y/±z), prismatic: ``XJ = xlt(axis q)``, free-flyer:
    ``XJ = plux(Rᵀ, p)`` with ``R`` the rotation of the (normalised) quaternion.
    """
    q = np.asarray(q, dtype=float)
    S = motion_subspace(jtype, axis)
    if jtype == REVOLUTE:
        k, sign = frame_axis(axis)
        XJ = _rot(_AXIS_E[k](sign * q) if k >= 0 else Eaxis(axis, q))
    elif jtype == PRISMATIC:
        XJ = xlt(q[..., None] * axis)
    elif jtype == FREE_FLYER:
        XJ = plux(np.swapaxes(quaternion_matrix(q[..., 3:7]), -1, -2), q[..., :3])
    else:
        XJ = np.broadcast_to(np.eye(6), q.shape + (6, 6))
    return XJ, S


def joint_coordinates(jtype: int, q: np.ndarray, k: int, mul: float, off: float) -> np.ndarray:
    """Return a joint's coordinates in ``q`` (..., nq), as :func:`jcalc` takes them.

    A 1-DoF joint's value ``mul q[k] + off`` (...); a free-flyer's ``q[k:k + 7]`` (..., 7).
    """
    if jtype == FREE_FLYER:
        return q[..., k:k + NQ[jtype]]
    return mul * q[..., k] + off


def quaternion_matrix(quat) -> np.ndarray:
    """Rotation matrix (..., 3, 3) of a quaternion ``(x, y, z, w)`` (..., 4), normalised.

    ``R = 1 + 2 w [u]× + 2 [u]×²`` for the unit quaternion ``(u, w)``; it maps the body's
    coordinates to the parent's (``p_parent = R p_body + position``).
    """
    quat = np.asarray(quat, dtype=float)
    x, y, z, w = (quat[..., j] for j in range(4))
    s = 2.0 / (x * x + y * y + z * z + w * w)
    xs, ys, zs = x * s, y * s, z * s
    wx, wy, wz = w * xs, w * ys, w * zs
    xx, xy, xz = x * xs, x * ys, x * zs
    yy, yz, zz = y * ys, y * zs, z * zs
    return np.stack([np.stack([1.0 - (yy + zz), xy - wz, xz + wy], -1),
                     np.stack([xy + wz, 1.0 - (xx + zz), yz - wx], -1),
                     np.stack([xz - wy, yz + wx, 1.0 - (xx + yy)], -1)], -2)


def is_unit(x, y, z, w):
    """Return whether the quaternion ``(x, y, z, w)`` has a finite norm within the tolerance.

    ``(1 − tol)² ≤ x² + y² + z² + w² ≤ (1 + tol)²`` (:data:`QUATERNION_TOLERANCE`), on
    Python floats or arrays (then elementwise): a NaN, an infinity or a norm ≥ 1e155 (whose
    square overflows) is not. The compiled entry compares the same.
    """
    n2 = x * x + y * y + z * z + w * w
    return (n2 >= _UNIT_SQUARED[0]) & (n2 <= _UNIT_SQUARED[1])


def unit_norms(quat) -> np.ndarray:
    """Return :func:`is_unit` of each quaternion (..., 4): a boolean array (...)."""
    quat = np.asarray(quat, dtype=float)
    with np.errstate(over='ignore', invalid='ignore'):
        return is_unit(*(quat[..., j] for j in range(4)))


def check_quaternion(what: str, quat) -> None:
    """Refuse quaternions (..., 4) that are no orientation: ``ValueError`` naming ``what``.

    Each must have a finite norm within :data:`QUATERNION_TOLERANCE` of 1 (it is normalised
    where it is used); in a batch the error names the first bad state's index.
    """
    quat = np.asarray(quat, dtype=float)
    ok = unit_norms(quat)
    if ok.all():
        return
    k = tuple(int(i) for i in np.argwhere(~ok)[0])
    x = quat[k]
    big = float(np.max(np.abs(x))) if np.isfinite(x).all() else 0.0
    norm = big * float(np.linalg.norm(x / big)) if big > 0.0 else float(np.linalg.norm(x))
    state = at_state(k)
    raise ValueError(f'{what}{state} has norm {norm:.6g} ({", ".join(f"{v:g}" for v in x)}); '
                     f'a unit quaternion (x, y, z, w) within {QUATERNION_TOLERANCE:g} is '
                     'expected')


def check_rotation(what: str, R) -> None:
    """Refuse matrices (..., 3, 3) that are no rotation: ``ValueError`` naming ``what``.

    Each must be finite, orthonormal (every entry of ``RᵀR − 1`` within
    :data:`ROTATION_TOLERANCE`) and proper (``det R > 0``: no reflection); in a batch the
    error names the first bad state's index.
    """
    R = np.asarray(R, dtype=float)
    finite = np.isfinite(R).all(axis=(-2, -1))
    Rs = np.where(finite[..., None, None], R, 0.0)
    off = np.abs(np.swapaxes(Rs, -1, -2) @ Rs - np.eye(3)).max(axis=(-2, -1))
    det = np.linalg.det(Rs)
    ok = finite & (off <= ROTATION_TOLERANCE) & (det > 0.0)
    if ok.all():
        return
    k = tuple(int(i) for i in np.argwhere(~ok)[0])
    state = at_state(k)
    why = ('is not finite' if not finite[k] else
           f'is not orthonormal (RᵀR − 1 has an entry of {off[k]:.3g})'
           if off[k] > ROTATION_TOLERANCE else f'is a reflection (det {det[k]:.6g})')
    raise ValueError(f'{what}{state} {why}; a rotation matrix (RᵀR = 1 within '
                     f'{ROTATION_TOLERANCE:g}, det +1) is expected')


def joint_integrate(jtype: int, q: np.ndarray, v: np.ndarray, dt) -> np.ndarray:
    """Return a joint's coordinates ``q`` (..., NQ) moved by its velocity ``v`` (..., NV), ``dt``.

    ``q + v dt`` for a 1-DoF joint; a free-flyer moves along the screw of its twist
    (:func:`integrate_free_flyer`).
    """
    if jtype == FREE_FLYER:
        return integrate_free_flyer(q, v, dt)
    return q + v * dt


def integrate_free_flyer(q: np.ndarray, v: np.ndarray, dt) -> np.ndarray:
    """Return a free-flyer's pose moved by its twist ``v = [ω; v]`` (base frame) for ``dt`` s.

    ``q`` (..., 7) position and quaternion x y z w; returns the pose ``M exp(v dt)`` (..., 7):
    the body moves along the screw of its twist (Pinocchio's ``integrate``, whose
    ``v[:6]`` is the same twist linear first). This is not ``q + q̇ dt``: the twist is
    the body's velocity, not the rate of its coordinates (``ṗ = R v``, and the quaternion's
    rate is ``½ q ⊗ (ω, 0)``).
    """
    q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
    w, u = v[..., :3] * dt, v[..., 3:6] * dt
    t2 = np.sum(w * w, axis=-1)
    t = np.sqrt(t2)
    small = t < 1e-4
    ts = np.where(small, 1.0, t)
    # exp of the twist: rotation (w/t sin(t/2), cos(t/2)); translation V u with
    # V = 1 + (1 - cos t)/t² w× + (t - sin t)/t³ w×² (Taylor series near t = 0)
    half = np.where(small, 0.5 - t2 / 48.0, np.sin(ts / 2.0) / ts)
    a = np.where(small, 0.5 - t2 / 24.0, (1.0 - np.cos(ts)) / (ts * ts))
    b = np.where(small, 1.0 / 6.0 - t2 / 120.0, (ts - np.sin(ts)) / (ts * ts * ts))
    wu = np.cross(w, u)
    p_d = u + a[..., None] * wu + b[..., None] * np.cross(w, wu)
    d_u, d_w = half[..., None] * w, np.cos(t / 2.0)
    quat = q[..., 3:7] / np.linalg.norm(q[..., 3:7], axis=-1, keepdims=True)
    c_u, c_w = quat[..., :3], quat[..., 3]
    new_u = c_w[..., None] * d_u + d_w[..., None] * c_u + np.cross(c_u, d_u)
    new_w = c_w * d_w - np.sum(c_u * d_u, axis=-1)
    new = np.concatenate([new_u, new_w[..., None]], axis=-1)
    new /= np.linalg.norm(new, axis=-1, keepdims=True)
    p = q[..., :3] + np.einsum('...ij,...j->...i', quaternion_matrix(quat), p_d)
    return np.concatenate([p, new], axis=-1)


# --------------------------------------------------------------------------------------------
# The operations on scalar components (the rules of algorithms/rnea.py): each branches on the
# kernel code, so that the algorithms do not.

def rotation_product(a00, a01, a02, a10, a11, a12, a20, a21, a22,
                     b00, b01, b02, b10, b11, b12, b20, b21, b22):
    """Return the 3×3 product ``A B`` of two rotations given by rows, as 9 scalars by rows."""
    return (a00 * b00 + a01 * b10 + a02 * b20,
            a00 * b01 + a01 * b11 + a02 * b21,
            a00 * b02 + a01 * b12 + a02 * b22,
            a10 * b00 + a11 * b10 + a12 * b20,
            a10 * b01 + a11 * b11 + a12 * b21,
            a10 * b02 + a11 * b12 + a12 * b22,
            a20 * b00 + a21 * b10 + a22 * b20,
            a20 * b01 + a21 * b11 + a22 * b21,
            a20 * b02 + a21 * b12 + a22 * b22)


def joint_transform(code, q, k, mul, off, ax, ay, az, t00, t01, t02, t10, t11, t12, t20, t21,
                    t22, rx, ry, rz, m):
    """Body transform ``Xup = XJ(q) Xtree`` as ``(E (9 scalars), r (3))``.

    RBDA table 4.1 for ``XJ`` and eq. 2.27 for the product ``(E_J, r_J)(E_t, r_t) = (E_J E_t,
    r_t + E_tᵀ r_J)``: revolute ``E = E_J E_t``, ``r = r_t``; prismatic ``E = E_t``,
    ``r = r_t + E_tᵀ axis q``; free-flyer (RBDA §4.5) ``E_J = Rᵀ`` and ``r_J = p`` from
    ``q[k:k + 7] = (p, quaternion x y z w)``. ``m`` provides ``sin`` and ``cos``.
    """
    if code <= RA:          # revolute
        qi = q[k] if mul == 1.0 and off == 0.0 else mul * q[k] + off
        c, s = m.cos(qi), m.sin(qi)
        if code == RZ:
            s = az * s     # about ±Z
            return (c * t00 + s * t10, c * t01 + s * t11, c * t02 + s * t12,
                    c * t10 - s * t00, c * t11 - s * t01, c * t12 - s * t02,
                    t20, t21, t22, rx, ry, rz)
        if code == RX:
            s = ax * s     # about ±X
            return (t00, t01, t02,
                    c * t10 + s * t20, c * t11 + s * t21, c * t12 + s * t22,
                    c * t20 - s * t10, c * t21 - s * t11, c * t22 - s * t12,
                    rx, ry, rz)
        if code == RY:
            s = ay * s     # about ±Y
            return (c * t00 - s * t20, c * t01 - s * t21, c * t02 - s * t22,
                    t10, t11, t12,
                    s * t00 + c * t20, s * t01 + c * t21, s * t02 + c * t22,
                    rx, ry, rz)
        # general axis: E_J = R(axis, q)ᵀ = c 1 - s axis× + (1 - c) axis axisᵀ
        C = 1.0 - c
        j00, j11, j22 = c + C * ax * ax, c + C * ay * ay, c + C * az * az
        cxy, cxz, cyz = C * ax * ay, C * ax * az, C * ay * az
        sx, sy, sz = s * ax, s * ay, s * az
        j01, j02, j10 = cxy + sz, cxz - sy, cxy - sz
        j12, j20, j21 = cyz + sx, cxz + sy, cyz - sx
        e00, e01, e02, e10, e11, e12, e20, e21, e22 = rotation_product(
            j00, j01, j02, j10, j11, j12, j20, j21, j22,
            t00, t01, t02, t10, t11, t12, t20, t21, t22)
        return (e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz)
    if code == PR:
        qi = q[k] if mul == 1.0 and off == 0.0 else mul * q[k] + off
        return (t00, t01, t02, t10, t11, t12, t20, t21, t22,
                rx + (t00 * ax + t10 * ay + t20 * az) * qi,
                ry + (t01 * ax + t11 * ay + t21 * az) * qi,
                rz + (t02 * ax + t12 * ay + t22 * az) * qi)
    # free-flyer
    x, y, z, w = q[k + 3], q[k + 4], q[k + 5], q[k + 6]
    s = 2.0 / (x * x + y * y + z * z + w * w)        # R of the normalised quaternion
    xs, ys, zs = x * s, y * s, z * s
    wx, wy, wz = w * xs, w * ys, w * zs
    xx, xy, xz = x * xs, x * ys, x * zs
    yy, yz, zz = y * ys, y * zs, z * zs
    r00, r01, r02 = 1.0 - (yy + zz), xy - wz, xz + wy
    r10, r11, r12 = xy + wz, 1.0 - (xx + zz), yz - wx
    r20, r21, r22 = xz - wy, yz + wx, 1.0 - (xx + yy)
    px, py, pz = q[k], q[k + 1], q[k + 2]
    e00, e01, e02, e10, e11, e12, e20, e21, e22 = rotation_product(     # E = Rᵀ E_t
        r00, r10, r20, r01, r11, r21, r02, r12, r22,
        t00, t01, t02, t10, t11, t12, t20, t21, t22)
    return (e00, e01, e02, e10, e11, e12, e20, e21, e22,
            rx + (t00 * px + t10 * py + t20 * pz),        # r = r_t + E_tᵀ p
            ry + (t01 * px + t11 * py + t21 * pz),
            rz + (t02 * px + t12 * py + t22 * pz))


def joint_motion(code, dq, kv, mul, ax, ay, az, m0, m1, m2, m3, m4, m5):
    """``m + S dq`` for the joint's part of ``dq`` (``q̇`` or ``q̈``), ``m`` a motion vector."""
    if code <= RA:          # revolute
        xi = dq[kv] if mul == 1.0 else mul * dq[kv]
        return m0 + ax * xi, m1 + ay * xi, m2 + az * xi, m3, m4, m5
    if code == PR:
        xi = dq[kv] if mul == 1.0 else mul * dq[kv]
        return m0, m1, m2, m3 + ax * xi, m4 + ay * xi, m5 + az * xi
    return (m0 + dq[kv], m1 + dq[kv + 1], m2 + dq[kv + 2], m3 + dq[kv + 3], m4 + dq[kv + 4],
            m5 + dq[kv + 5])


def joint_velocity(code, qd, kv, mul, ax, ay, az, w0, w1, w2, v0, v1, v2, a0, a1, a2, l0, l1,
                   l2):
    """``v_i = v + vJ`` and ``a + v_i × vJ`` with ``vJ = S q̇`` (RBDA table 5.1): 12 scalars.

    ``[w; v]`` is ``Xup v_λ(i)``, ``[a; l]`` the acceleration so far; returns the body velocity
    then the acceleration with the velocity product ``v_i × vJ``.
    """
    if code <= RA:          # revolute
        qdi = qd[kv] if mul == 1.0 else mul * qd[kv]
        j0, j1, j2 = ax * qdi, ay * qdi, az * qdi
        w0, w1, w2 = w0 + j0, w1 + j1, w2 + j2
        return (w0, w1, w2, v0, v1, v2,
                a0 + (w1 * j2 - w2 * j1), a1 + (w2 * j0 - w0 * j2), a2 + (w0 * j1 - w1 * j0),
                l0 + (v1 * j2 - v2 * j1), l1 + (v2 * j0 - v0 * j2), l2 + (v0 * j1 - v1 * j0))
    if code == PR:
        qdi = qd[kv] if mul == 1.0 else mul * qd[kv]
        j0, j1, j2 = ax * qdi, ay * qdi, az * qdi
        v0, v1, v2 = v0 + j0, v1 + j1, v2 + j2
        return (w0, w1, w2, v0, v1, v2, a0, a1, a2,
                l0 + (w1 * j2 - w2 * j1), l1 + (w2 * j0 - w0 * j2), l2 + (w0 * j1 - w1 * j0))
    j0, j1, j2, j3, j4, j5 = qd[kv], qd[kv + 1], qd[kv + 2], qd[kv + 3], qd[kv + 4], qd[kv + 5]
    w0, w1, w2, v0, v1, v2 = w0 + j0, w1 + j1, w2 + j2, v0 + j3, v1 + j4, v2 + j5
    return (w0, w1, w2, v0, v1, v2,
            a0 + (w1 * j2 - w2 * j1), a1 + (w2 * j0 - w0 * j2), a2 + (w0 * j1 - w1 * j0),
            l0 + ((w1 * j5 - w2 * j4) + (v1 * j2 - v2 * j1)),
            l1 + ((w2 * j3 - w0 * j5) + (v2 * j0 - v0 * j2)),
            l2 + ((w0 * j4 - w1 * j3) + (v0 * j1 - v1 * j0)))


def joint_torque(code, tau, kv, mul, ax, ay, az, n0, n1, n2, f0, f1, f2) -> None:
    """``τ += Sᵀ f`` into the joint's entries of ``tau`` (``mul`` times it for a mimic joint)."""
    if code <= RA:          # revolute
        t = ax * n0 + ay * n1 + az * n2
    elif code == PR:
        t = ax * f0 + ay * f1 + az * f2
    else:
        tau[kv] = tau[kv] + n0
        tau[kv + 1] = tau[kv + 1] + n1
        tau[kv + 2] = tau[kv + 2] + n2
        tau[kv + 3] = tau[kv + 3] + f0
        tau[kv + 4] = tau[kv + 4] + f1
        tau[kv + 5] = tau[kv + 5] + f2
        return
    tau[kv] = tau[kv] + (t if mul == 1.0 else mul * t)


def joint_ctq(code, ctq, kv, mul, ax, ay, az, w0, w1, w2, v0, v1, v2, n0, n1, n2, f0, f1,
              f2) -> None:
    """``ctq += (v × S)ᵀ h`` into the joint's entries: ``v = [w; v]`` the body's velocity.

    ``v × S = [w × s_ω; w × s_v + v × s_ω]`` column by column; for the free-flyer (``S = 1``)
    ``(v×)ᵀ h = [n × w + f × v; f × w]``.
    """
    if code == FF:
        ctq[kv] = ctq[kv] + ((n1 * w2 - n2 * w1) + (f1 * v2 - f2 * v1))
        ctq[kv + 1] = ctq[kv + 1] + ((n2 * w0 - n0 * w2) + (f2 * v0 - f0 * v2))
        ctq[kv + 2] = ctq[kv + 2] + ((n0 * w1 - n1 * w0) + (f0 * v1 - f1 * v0))
        ctq[kv + 3] = ctq[kv + 3] + (f1 * w2 - f2 * w1)
        ctq[kv + 4] = ctq[kv + 4] + (f2 * w0 - f0 * w2)
        ctq[kv + 5] = ctq[kv + 5] + (f0 * w1 - f1 * w0)
        return
    c0, c1, c2 = w1 * az - w2 * ay, w2 * ax - w0 * az, w0 * ay - w1 * ax
    if code == PR:
        c = c0 * f0 + c1 * f1 + c2 * f2
    else:
        c = (c0 * n0 + c1 * n1 + c2 * n2 + (v1 * az - v2 * ay) * f0
             + (v2 * ax - v0 * az) * f1 + (v0 * ay - v1 * ax) * f2)
    ctq[kv] = ctq[kv] + (c if mul == 1.0 else mul * c)


def joint_axis(code, col, ax, ay, az):
    """Column ``col`` of ``S`` (6 scalars): ``[axis; 0]``, ``[0; axis]`` or the unit vector."""
    if code <= RA:          # revolute
        return ax, ay, az, 0.0, 0.0, 0.0
    if code == PR:
        return 0.0, 0.0, 0.0, ax, ay, az
    return (1.0 if col == 0 else 0.0, 1.0 if col == 1 else 0.0, 1.0 if col == 2 else 0.0,
            1.0 if col == 3 else 0.0, 1.0 if col == 4 else 0.0, 1.0 if col == 5 else 0.0)


def joint_world_axis(code, e00, e01, e02, e10, e11, e12, e20, e21, e22, rx, ry, rz, ax, ay, az):
    """Return a 1-dof joint's ``S`` in the coordinates ``X = (E, r)`` maps from: ``X⁻¹ S``.

    ``X⁻¹ [ω; v] = [Eᵀ ω; Eᵀ v + r × Eᵀ ω]`` without the products with the zeros of ``S``:
    revolute ``[w; r × w]`` with ``w = Eᵀ a`` (about a frame axis ``±e_k``: a row of ``E``
    times ``±1``), prismatic ``[0; Eᵀ a]``.
    """
    if code == RX:
        w0, w1, w2 = e00 * ax, e01 * ax, e02 * ax
    elif code == RY:
        w0, w1, w2 = e10 * ay, e11 * ay, e12 * ay
    elif code == RZ:
        w0, w1, w2 = e20 * az, e21 * az, e22 * az
    elif code == RA:
        w0 = e00 * ax + e10 * ay + e20 * az
        w1 = e01 * ax + e11 * ay + e21 * az
        w2 = e02 * ax + e12 * ay + e22 * az
    else:       # prismatic
        return (0.0, 0.0, 0.0, e00 * ax + e10 * ay + e20 * az, e01 * ax + e11 * ay + e21 * az,
                e02 * ax + e12 * ay + e22 * az)
    return w0, w1, w2, ry * w2 - rz * w1, rz * w0 - rx * w2, rx * w1 - ry * w0


def joint_crba(code, H, n, row, kj, mm, both, ax, ay, az, F0, F1, F2, F3, F4, F5) -> None:
    """``H[row, kj + d] += mm S[:, d]ᵀ F`` for each column ``d`` of the joint's ``S`` (CRBA).

    ``H`` is ``n × n`` row-major; with ``both``, ``H[kj + d, row]`` gets the same (an entry
    off the diagonal block: ``M`` is symmetric).
    """
    if code <= RA:          # revolute
        t = ax * F0 + ay * F1 + az * F2
    elif code == PR:
        t = ax * F3 + ay * F4 + az * F5
    else:       # free-flyer: S = 1, the six components of F
        r = row * n + kj
        H[r] = H[r] + mm * F0
        H[r + 1] = H[r + 1] + mm * F1
        H[r + 2] = H[r + 2] + mm * F2
        H[r + 3] = H[r + 3] + mm * F3
        H[r + 4] = H[r + 4] + mm * F4
        H[r + 5] = H[r + 5] + mm * F5
        if both:
            H[kj * n + row] = H[kj * n + row] + mm * F0
            H[(kj + 1) * n + row] = H[(kj + 1) * n + row] + mm * F1
            H[(kj + 2) * n + row] = H[(kj + 2) * n + row] + mm * F2
            H[(kj + 3) * n + row] = H[(kj + 3) * n + row] + mm * F3
            H[(kj + 4) * n + row] = H[(kj + 4) * n + row] + mm * F4
            H[(kj + 5) * n + row] = H[(kj + 5) * n + row] + mm * F5
        return
    H[row * n + kj] = H[row * n + kj] + mm * t
    if both:
        H[kj * n + row] = H[kj * n + row] + mm * t


def joint_pair(code, D, n, row, kj, mm, ax, ay, az, F0, F1, F2, F3, F4, F5, P0, P1, P2, P3, P4,
               P5) -> None:
    """``D[row, kj + d] += mm S[:, d]ᵀ F``, ``D[kj + d, row] += mm S[:, d]ᵀ P`` for each ``d``.

    ``D`` is ``n × n`` row-major: a row and a column of a matrix that is not symmetric (the
    derivatives' ``∂τ/∂q`` and ``∂τ/∂q̇``), each from its own force (``M``'s: ``F = P``).
    """
    if code <= RA:          # revolute
        t = ax * F0 + ay * F1 + az * F2
        u = ax * P0 + ay * P1 + az * P2
    elif code == PR:
        t = ax * F3 + ay * F4 + az * F5
        u = ax * P3 + ay * P4 + az * P5
    else:       # free-flyer: S = 1, the six components of F and of P (its mm is 1: a
        # free-flyer mimics no joint)
        r = row * n + kj
        D[r] = D[r] + F0
        D[r + 1] = D[r + 1] + F1
        D[r + 2] = D[r + 2] + F2
        D[r + 3] = D[r + 3] + F3
        D[r + 4] = D[r + 4] + F4
        D[r + 5] = D[r + 5] + F5
        D[kj * n + row] = D[kj * n + row] + P0
        D[(kj + 1) * n + row] = D[(kj + 1) * n + row] + P1
        D[(kj + 2) * n + row] = D[(kj + 2) * n + row] + P2
        D[(kj + 3) * n + row] = D[(kj + 3) * n + row] + P3
        D[(kj + 4) * n + row] = D[(kj + 4) * n + row] + P4
        D[(kj + 5) * n + row] = D[(kj + 5) * n + row] + P5
        return
    D[row * n + kj] = D[row * n + kj] + mm * t
    D[kj * n + row] = D[kj * n + row] + mm * u
