# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Spatial vector algebra (Featherstone, RBDA ch. 2 and the seed slides).

Spatial vectors are angular first: a motion vector is ``[omega; v]``, a force vector is
``[n; f]``. A Plücker motion transform ``bXa`` maps motion vectors from frame ``a`` to
frame ``b``; the matching force transform is ``bXa_f = inv(bXa).T``.

Every function accepts leading batch dimensions: ``(..., 3)`` / ``(..., 6)`` vectors,
``(...)`` angles, and returns ``(..., 6, 6)`` or ``(..., 3, 3)`` matrices.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike


def skew(w: ArrayLike) -> np.ndarray:
    """Return the cross-product matrix ``w×``, such that ``w× u = w × u``; (..., 3, 3)."""
    w = np.asarray(w, dtype=float) if not isinstance(w, np.ndarray) else w
    z = np.zeros_like(w[..., 0])
    x, y, s = w[..., 0], w[..., 1], w[..., 2]
    return np.stack([np.stack([z, -s, y], -1),
                     np.stack([s, z, -x], -1),
                     np.stack([-y, x, z], -1)], -2)


def crm(v: ArrayLike) -> np.ndarray:
    """Motion cross product ``v×`` (RBDA eq. 2.31): ``[[w×, 0], [vo×, w×]]``; (..., 6, 6)."""
    v = np.asarray(v)
    wx = skew(v[..., :3])
    vx = skew(v[..., 3:])
    out = np.zeros(v.shape[:-1] + (6, 6), dtype=wx.dtype)
    out[..., :3, :3] = wx
    out[..., 3:, :3] = vx
    out[..., 3:, 3:] = wx
    return out


def crf(v: ArrayLike) -> np.ndarray:
    """Force cross product ``v×*`` (RBDA eq. 2.32), equal to ``-crm(v)ᵀ``; (..., 6, 6)."""
    return -np.swapaxes(crm(v), -1, -2)


def _rot(E: np.ndarray) -> np.ndarray:
    """Plücker transform of a pure coordinate rotation ``E`` (..., 3, 3)."""
    X = np.zeros(E.shape[:-2] + (6, 6), dtype=E.dtype)
    X[..., :3, :3] = E
    X[..., 3:, 3:] = E
    return X


def Erotx(theta: ArrayLike) -> np.ndarray:
    """Coordinate rotation matrix of a frame rotated by ``theta`` about x (RBDA table 2.2)."""
    t = np.asarray(theta, dtype=float)
    c, s = np.cos(t), np.sin(t)
    o, z = np.ones_like(t), np.zeros_like(t)
    return np.stack([np.stack([o, z, z], -1),
                     np.stack([z, c, s], -1),
                     np.stack([z, -s, c], -1)], -2)


def Eroty(theta: ArrayLike) -> np.ndarray:
    """Coordinate rotation matrix of a frame rotated by ``theta`` about y (RBDA table 2.2)."""
    t = np.asarray(theta, dtype=float)
    c, s = np.cos(t), np.sin(t)
    o, z = np.ones_like(t), np.zeros_like(t)
    return np.stack([np.stack([c, z, -s], -1),
                     np.stack([z, o, z], -1),
                     np.stack([s, z, c], -1)], -2)


def Erotz(theta: ArrayLike) -> np.ndarray:
    """Coordinate rotation matrix of a frame rotated by ``theta`` about z (RBDA table 2.2)."""
    t = np.asarray(theta, dtype=float)
    c, s = np.cos(t), np.sin(t)
    o, z = np.ones_like(t), np.zeros_like(t)
    return np.stack([np.stack([c, s, z], -1),
                     np.stack([-s, c, z], -1),
                     np.stack([z, z, o], -1)], -2)


def rotx(theta: ArrayLike) -> np.ndarray:
    """Plücker transform ``rx(theta)``: coordinates rotated by ``theta`` about x; (..., 6, 6)."""
    return _rot(Erotx(theta))


def roty(theta: ArrayLike) -> np.ndarray:
    """Plücker transform ``ry(theta)``: coordinates rotated by ``theta`` about y; (..., 6, 6)."""
    return _rot(Eroty(theta))


def rotz(theta: ArrayLike) -> np.ndarray:
    """Plücker transform ``rz(theta)``: coordinates rotated by ``theta`` about z; (..., 6, 6)."""
    return _rot(Erotz(theta))


def Eaxis(axis: ArrayLike, theta: ArrayLike) -> np.ndarray:
    """Coordinate rotation for a rotation by ``theta`` about the unit ``axis`` (..., 3).

    ``E = R(axis, theta)ᵀ`` with Rodrigues' ``R = c·1 + s·axis× + (1 - c)·axis axisᵀ``.
    """
    a = np.asarray(axis, dtype=float)
    t = np.asarray(theta, dtype=float)
    c = np.cos(t)[..., None, None]
    s = np.sin(t)[..., None, None]
    aaT = a[..., :, None] * a[..., None, :]
    R = c * np.eye(3) + s * skew(a) + (1.0 - c) * aaT
    return np.swapaxes(R, -1, -2)


def xlt(r: ArrayLike) -> np.ndarray:
    """Plücker translation by ``r``: ``[[1, 0], [-r×, 1]]`` (RBDA eq. 2.28); (..., 6, 6)."""
    r = np.asarray(r, dtype=float)
    X = np.zeros(r.shape[:-1] + (6, 6))
    X[..., :3, :3] = np.eye(3)
    X[..., 3:, 3:] = np.eye(3)
    X[..., 3:, :3] = -skew(r)
    return X


def plux(E: ArrayLike, r: ArrayLike) -> np.ndarray:
    """Plücker motion transform from rotation ``E`` and translation ``r`` (RBDA eq. 2.24).

    ``bXa = [[E, 0], [-E r×, E]]`` where ``r`` is the position of b's origin in a-coordinates
    and ``E`` rotates a-coordinates into b-coordinates.
    """
    E = np.asarray(E, dtype=float)
    r = np.asarray(r, dtype=float)
    X = np.zeros(np.broadcast_shapes(E.shape[:-2], r.shape[:-1]) + (6, 6))
    X[..., :3, :3] = E
    X[..., 3:, 3:] = E
    X[..., 3:, :3] = -E @ skew(r)
    return X


def plux_Er(X: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Split a Plücker motion transform into ``(E, r)``, the inverse of :func:`plux`."""
    X = np.asarray(X, dtype=float)
    E = X[..., :3, :3]
    rx = -np.swapaxes(E, -1, -2) @ X[..., 3:, :3]
    r = np.stack([rx[..., 2, 1], rx[..., 0, 2], rx[..., 1, 0]], -1)
    return E, r


def plux_inv(X: ArrayLike) -> np.ndarray:
    """Inverse of a Plücker motion transform without a matrix inversion.

    ``inv([[E, 0], [-E r×, E]]) = [[Eᵀ, 0], [r× Eᵀ, Eᵀ]]`` (RBDA eq. 2.26).
    """
    X = np.asarray(X, dtype=float)
    Et = np.swapaxes(X[..., :3, :3], -1, -2)
    B = X[..., 3:, :3]
    out = np.zeros_like(X)
    out[..., :3, :3] = Et
    out[..., 3:, 3:] = Et
    out[..., 3:, :3] = -Et @ B @ Et
    return out


def plux_force(X: ArrayLike) -> np.ndarray:
    """Force transform ``X_f = inv(X)ᵀ = [[E, -E r×], [0, E]]`` for a motion transform ``X``."""
    X = np.asarray(X, dtype=float)
    out = np.zeros_like(X)
    out[..., :3, :3] = X[..., :3, :3]
    out[..., 3:, 3:] = X[..., 3:, 3:]
    out[..., :3, 3:] = X[..., 3:, :3]
    return out


def mcI(m: ArrayLike, c: ArrayLike, Ic: ArrayLike) -> np.ndarray:
    """Spatial inertia from mass ``m``, centre of mass ``c`` and rotational inertia ``Ic``.

    ``I = [[Ic + m c× c×ᵀ, m c×], [m c×ᵀ, m 1]]`` (RBDA eq. 2.63), with ``Ic`` about the
    centre of mass, all expressed in the body frame. Units kg, m, kg m².
    """
    m = np.asarray(m, dtype=float)
    c = np.asarray(c, dtype=float)
    Ic = np.asarray(Ic, dtype=float)
    C = skew(c)
    mm = m[..., None, None]
    out = np.zeros(np.broadcast_shapes(m.shape, c.shape[:-1], Ic.shape[:-2]) + (6, 6))
    out[..., :3, :3] = Ic + mm * C @ np.swapaxes(C, -1, -2)
    out[..., :3, 3:] = mm * C
    out[..., 3:, :3] = mm * np.swapaxes(C, -1, -2)
    out[..., 3:, 3:] = mm * np.eye(3)
    return out


def rpy_to_R(rpy: ArrayLike) -> np.ndarray:
    """Rotation matrix of URDF roll-pitch-yaw: ``R = Rz(yaw) Ry(pitch) Rx(roll)``.

    ``R`` maps child-frame coordinates to parent-frame coordinates, so the Plücker rotation
    part of ``childXparent`` is ``E = Rᵀ``.
    """
    roll, pitch, yaw = (float(v) for v in rpy)
    cr, sr = np.cos(roll), np.sin(roll)
    cp, sp = np.cos(pitch), np.sin(pitch)
    cy, sy = np.cos(yaw), np.sin(yaw)
    return np.array([
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr]])
