# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The base's motion from a bag's odometry or IMU topic, at the joint states' stamps.

A mobile manipulator's (or a ship's) arm feels its base's motion. ``--base-odometry TOPIC``
(``nav_msgs/Odometry``) or ``--base-imu TOPIC`` (``sensor_msgs/Imu``) names the topic of the
same bag that measured it; :func:`base_motion` reads it, interpolates it linearly to the
joint states' stamps, and differentiates and smooths it with the joints' own zero-phase
Savitzky-Golay filter (``--window``, ``--order``, per stretch between gaps), so the base's
acceleration and the joints' q̈ have the same delay (none) and the same cut-off:

* odometry: the twist ``[ω; v]`` of ``child_frame_id`` (or ``--odometry-link``) smoothed,
  its rate the spatial acceleration, and the pose's orientation for gravity
  (:func:`~spatial_dynamics.base.base_from_odometry`);
* IMU: the gyro's ``ω`` smoothed and differentiated for ``ω̇``, the accelerometer's
  specific force smoothed: the motion with gravity in it, no orientation needed
  (:func:`~spatial_dynamics.base.base_from_imu`), the IMU at the origin of ``--imu-link``
  (default its ``frame_id``) with that link's axes.

The topic is a :class:`BaseTopic` (the commands' ``--base-odometry``/``--base-imu`` and
their links, the fleet's manifest columns). The result is passed as ``base=`` to RNEA and the
regressor. A topic that is missing, has too few usable samples, or does not cover the joint
states' time span (within one of its own periods at each end; no gap of more than 5 of them
inside) is refused, naming it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Sequence, Tuple

import numpy as np

from ..base import base_from_imu, base_from_odometry, BaseMotion
from ..bounds import (MAX_BASE_ANGULAR_ACCELERATION, MAX_BASE_LINEAR_ACCELERATION,
                      MIN_STAMP_INTERVAL)
from ..joints import unit_norms
from ..model import Model
from ..text import shown
from . import bags, differentiate
from .cdr import IMU, ODOMETRY, Stamped
from .errors import Refused

#: Fewest usable messages of a base topic (two interpolate; a few say its period).
MIN_BASE_SAMPLES = 5
#: A base topic's gap longer than this many of its median periods is a hole in the motion.
GAP = 5.0


@dataclass(frozen=True)
class BaseTopic:
    """The topic of the bag a moving base's motion is read from, and the link it is of.

    ``odometry`` (``nav_msgs/Odometry``) or ``imu`` (``sensor_msgs/Imu``), at most one (each
    gives the whole motion); ``odometry_link``/``imu_link``: the link its vectors are in
    (default the message's ``child_frame_id``/``frame_id``). Neither topic: a fixed base.
    """

    odometry: Optional[str] = None
    imu: Optional[str] = None
    odometry_link: Optional[str] = None
    imu_link: Optional[str] = None


def base_motion(base: BaseTopic, bag: str, model: Model, t: np.ndarray,
                spans: Sequence[Tuple[int, int]], window: float, order: int,
                between: Tuple[Optional[int], Optional[int]] = (None, None)
                ) -> Optional[BaseMotion]:
    """Return the base's motion at the joint stamps ``t`` (s), or None without a base topic.

    ``spans``: the stretches of ``t`` between gaps (:func:`.recording.clean`), each
    differentiated on its own as the joints are. ``between``: the bag-time range (ns) of
    the topic read (a chunk of a long bag: its joint states' range and a margin). ``window``
    (s) and ``order``: the joints' Savitzky-Golay filter. :class:`Refused` naming the option
    and the topic when the topic cannot give the motion over ``t``.
    """
    odometry, imu = base.odometry, base.imu
    if not odometry and not imu:
        return None
    option, topic, msgtype = (('--base-odometry', odometry, ODOMETRY) if odometry else
                              ('--base-imu', imu, IMU))
    where = f'{option} {shown(topic)}'
    try:
        found = bags.read_stamped(bag, topic, msgtype, *between)
    except bags.BagError as err:
        raise Refused(f'{where}: {err}') from None
    fields = (('orientation', 'angular', 'linear') if odometry else
              ('angular_velocity', 'linear_acceleration'))
    values = [found.field(f) for f in fields]
    tb = covering(found, values, t, where)
    at = [np.column_stack([np.interp(t, tb, x[:, j]) for j in range(x.shape[1])])
          for x in values]
    if odometry:
        quat, twist = at[0], np.concatenate(at[1:], axis=1)
        (v, a), _ = differentiate.derivatives(t, twist, window, order, (0, 1), spans)
        quat = quat / np.linalg.norm(quat, axis=1, keepdims=True)
        link = link_of(model, base.odometry_link, found.frames[1:], where, 'child_frame_id',
                       '--odometry-link')
        check_base_acceleration(where, t, a)
        try:
            return base_from_odometry(model, v, a, quat, link)
        except ValueError as err:
            raise Refused(f'{where}: {err}') from None
    (w, wd), _ = differentiate.derivatives(t, at[0], window, order, (0, 1), spans)
    (f,), _ = differentiate.derivatives(t, at[1], window, order, (0,), spans)
    check_base_acceleration(where, t, np.concatenate((wd, np.zeros_like(wd)), axis=1))
    link = link_of(model, base.imu_link, found.frames[:1], where, 'frame_id', '--imu-link')
    try:
        return base_from_imu(model, link, f, w, wd)
    except ValueError as err:
        raise Refused(f'{where}: {err}') from None


def check_base_acceleration(where: str, t: np.ndarray, a: np.ndarray) -> None:
    """Refuse a differentiated base acceleration ``a`` (N, 6) ``[ω̇; v̇]`` no base reaches.

    Bounded by :data:`~spatial_dynamics.bounds.MAX_BASE_ANGULAR_ACCELERATION` and
    :data:`~spatial_dynamics.bounds.MAX_BASE_LINEAR_ACCELERATION` (norms); nan (outside the
    stretches) is not compared.
    """
    for part, bound, what, unit in ((a[:, :3], MAX_BASE_ANGULAR_ACCELERATION, 'angular',
                                     'rad/s²'),
                                    (a[:, 3:], MAX_BASE_LINEAR_ACCELERATION, 'linear', 'm/s²')):
        norm = np.linalg.norm(part, axis=1)
        with np.errstate(invalid='ignore'):
            huge = np.flatnonzero(norm > bound)
        if len(huge):
            k = huge[0]
            raise Refused(f'{where}: the base\'s differentiated {what} acceleration at '
                          f'{t[k] - t[0]:.6f} s is {norm[k]:.3g} {unit}, more than the '
                          f'{bound:g} {unit} no base reaches (stamps closer than the motion, '
                          'or a jump in the topic)')


def joined(bases: Sequence[Optional[BaseMotion]]) -> Optional[BaseMotion]:
    """Return the base motions of several recordings as one (their samples one after another)."""
    if any(b is None for b in bases):
        return None

    def cat(xs):
        return None if xs[0] is None else np.concatenate(xs)
    return BaseMotion(cat([b.v for b in bases]), cat([b.a for b in bases]),
                      cat([b.orientation for b in bases]), bases[0].gravity_included)


def covering(found: Stamped, values: Sequence[np.ndarray], t: np.ndarray, where: str
             ) -> np.ndarray:
    """Return the usable stamps of a base topic, made to cover ``t``; Refused if they cannot.

    Messages with a non-finite value (or a quaternion off unit by more than the library's
    tolerance, :func:`~spatial_dynamics.joints.is_unit`) and repeated stamps are dropped
    (``values`` keep the same rows); the rest must begin and end within one median period of
    ``t``'s ends and have no gap of more than :data:`GAP` periods inside them.
    """
    keep = np.all([np.isfinite(x).all(axis=1) for x in values], axis=0)
    if found.msgtype == ODOMETRY:
        keep &= unit_norms(values[0])
    keep &= np.concatenate(([True], np.diff(found.stamp) > 0))
    tb = found.stamp[keep]
    for k, x in enumerate(values):
        values[k] = x[keep]         # the caller's list: the same rows as the stamps
    said = len(found.stamp) + sum(found.skipped.values())
    if len(tb) < MIN_BASE_SAMPLES:
        raise Refused(f'{where}: {len(tb)} usable message(s) of {said} on the topic (at least '
                      f'{MIN_BASE_SAMPLES} are needed for the base\'s motion)')
    if found.msgtype == ODOMETRY:       # the shorter way between successive quaternions
        q = values[0]
        flip = np.cumsum(np.r_[0, np.einsum('ij,ij->i', q[1:], q[:-1]) < 0]) % 2 == 1
        q[flip] = -q[flip]
    period = float(np.median(np.diff(tb)))
    if period < MIN_STAMP_INTERVAL:
        raise Refused(f'{where}: its messages are stamped {period:.3g} s apart (median), less '
                      f'than {MIN_STAMP_INTERVAL:g} s: no sensor publishes that fast (a clock '
                      'artefact: check its header.stamp)')
    if tb[0] > t[0] + period or tb[-1] < t[-1] - period:
        raise Refused(f'{where}: the topic covers {tb[0] - t[0]:.3f} .. {tb[-1] - t[0]:.3f} s '
                      f'of the joint states\' 0 .. {t[-1] - t[0]:.3f} s: the base\'s motion is '
                      'unknown over part of the recording (record the topic the whole time, '
                      'or cut the bag to the time it covers)')
    inside = np.flatnonzero((tb[1:] > t[0]) & (tb[:-1] < t[-1]))
    gaps = inside[np.diff(tb)[inside] > GAP * period]
    if len(gaps):
        k = gaps[0]
        raise Refused(f'{where}: no message from {tb[k] - t[0]:.3f} to {tb[k + 1] - t[0]:.3f} '
                      f's of the joint states ({(tb[k + 1] - tb[k]) / period:.0f} of its '
                      'periods): the base\'s motion is unknown there')
    return tb


def link_of(model: Model, given: Optional[str], frames: Sequence[str], where: str,
            field: str, option: str) -> str:
    """Return the link the base topic's vectors are in: ``given``, else the message's frame."""
    if given:
        if given not in model.frames:
            raise Refused(f'{option} {shown(given)} is not a link of {shown(model.name)}')
        return given
    frame = frames[0] if frames else ''
    if frame.lstrip('/') in model.frames:
        return frame.lstrip('/')
    raise Refused(f'{where}: its {field} {shown(frame)} is not a link of {shown(model.name)}; '
                  f'name the link (fixed to the base) it is of with {option}')
