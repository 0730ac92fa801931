# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A floating base's answer, without ROS: the contact-consistent efforts, the contact wrenches.

Pure Python + numpy + the library (no rclpy import), tested in
``test/test_node_base_inputs.py``. :class:`FloatingDynamics` is the model part of one answer
on a floating base (:func:`~spatial_dynamics.contact_inverse_dynamics`, a pulling split
re-solved by the QP, a split that cannot carry the base refused); :func:`contact_wrenches`
what the node publishes of its solution; :func:`pull_tolerance` and
:func:`residual_tolerance` the bounds it checks, relative to the robot's weight.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import List, Optional, Tuple

import numpy as np
import spatial_dynamics as sd
from spatial_dynamics.contacts import link_orientations
from spatial_dynamics.ros.control import Dynamics
from spatial_dynamics.ros.inputs import InputError
from spatial_dynamics.ros.text import shown

#: A contact pulls when its normal force ``n·f`` is below ``−PULL_TOLERANCE · m · 9.81`` N, ``m``
#: the model's mass (:func:`pull_tolerance`): relative to the weight, because the split's
#: rounding and the QP's convergence tolerance (relative, ~1e-8) scale with the forces, which
#: scale with the weight; an absolute 1e-6 N would refuse a 100 kg robot's QP answers for
#: their solver noise, and let a 0.1 kg one pull a tenth of a mN unseen.
PULL_TOLERANCE = 1e-6
#: A split leaves the base rows unbalanced when a component of its base residual
#: ``(M q̈ + h)_base − J_c,baseᵀ λ`` (N m, N) exceeds ``RESIDUAL_TOLERANCE · m · 9.81``
#: (:func:`residual_tolerance`), relative to the weight as :data:`PULL_TOLERANCE` and for the
#: same reasons: the contacts in force cannot carry the base (one foot, none), the answer is
#: refused (``contacts_unsolved``). A split that carries it leaves rounding (~1e-15 of the
#: weight); the QP its convergence tolerance (~1e-8).
RESIDUAL_TOLERANCE = 1e-6


def pull_tolerance(model: 'sd.Model') -> float:
    """Return the N by which a contact may pull: :data:`PULL_TOLERANCE` of ``m · 9.81``."""
    return PULL_TOLERANCE * float(model.inertia[:, 3, 3].sum()) * 9.81


def residual_tolerance(model: 'sd.Model') -> float:
    """Return the base residual (N m, N) a split may leave: :data:`RESIDUAL_TOLERANCE` · m g."""
    return RESIDUAL_TOLERANCE * float(model.inertia[:, 3, 3].sum()) * 9.81


def qp_missing_warning(robot) -> str:
    """Return the WARN, once at configuration, of a floating base without its QP ('': none)."""
    if robot is None or not robot.qp_missing:
        return ''
    return ('contacts: the QP that re-solves a split making a contact pull cannot run '
            f'({robot.qp_missing}); answering with contacts.method alone, and refusing '
            'each answer whose split makes a contact pull (contacts_pull in /diagnostics)')


@dataclass(frozen=True)
class FloatingDynamics(Dynamics):
    """A floating base's model part: contact-consistent joint efforts (one answer).

    ``q, q̇, q̈`` of the methods are the joints'; the base's are ``base_q`` (position, x y z w),
    ``base_v`` and ``base_a`` (``[ω; v]``, base frame). Each :meth:`full` solves
    :func:`~spatial_dynamics.contact_inverse_dynamics` with ``contacts`` by ``method`` and
    keeps its result in ``results`` (the contact wrenches to publish); with ``measured``
    (link -> ``[n; f]`` in the link's frame) :meth:`full` takes those instead of solving
    for them (their base residual is the check); the efforts never
    include the base's rows. Armature and friction (``friction_threshold``) add to the
    joints' (the rotors' torque; the drives' friction).

    A split (``torques``, ``forces``) that makes a contact pull by more than
    ``pull_tolerance`` N (:func:`pull_tolerance`) in :meth:`full` or :meth:`gravity_torque`
    is re-solved by ``'qp'`` (friction cones of the contacts' ``μ``, ``n·f ≥ 0``), whose
    answer is used; each such pull is kept in ``pulls``. InputError ``contacts_unsolved``
    when the QP finds none, ``contacts_pull`` when ``qp_missing`` says why the QP cannot run
    (or it pulls itself). :meth:`inertia_times` is not checked for pulls: its forces are the
    increments of a linear split (no gravity), which have no sign of their own.

    Every split (each method, :meth:`inertia_times` too) must carry the base: a base
    residual above ``residual_tolerance`` (N m, N; :func:`residual_tolerance`) is
    InputError ``contacts_unsolved``, its residual kept in ``unsolved``, and no contact in
    force at all (in flight) InputError ``no_contact``, whatever the residual. The split's
    residual is the least any ``λ`` leaves (``J_cᵀ``'s range), so the QP, bound by the same
    rows, cannot carry what it could not: it is refused, not re-solved. Measured wrenches
    are the sensors': their residual is reported, not refused.
    """

    base_q: np.ndarray = None
    base_v: np.ndarray = None
    base_a: np.ndarray = None
    contacts: Tuple['sd.Contact', ...] = ()
    method: str = 'torques'
    results: List = None
    measured: Optional[dict] = None
    qp_missing: str = ''
    pull_tolerance: float = 0.0
    pulls: List = None
    residual_tolerance: float = 0.0
    unsolved: List = None

    def _solve(self, q, qd, qdd, base_v, base_a, gravity, measured=None,
               unilateral: bool = True) -> np.ndarray:
        q_full = np.concatenate((self.base_q, q))
        if measured is not None:   # world axes, as contact_inverse_dynamics takes them
            rotations = link_orientations(self.model, q_full, list(measured))
            measured = {c.name: _world(rotations[c.link], measured[c.link], c.rows)
                        for c in self.contacts}
        state = (self.model, q_full, np.concatenate((base_v, qd)),
                 np.concatenate((base_a, qdd)), self.contacts)
        result = sd.contact_inverse_dynamics(*state, measured=measured, method=self.method,
                                             gravity=gravity)
        if result.status != 'solved' and self.contacts:   # the QP: no forces in the cones
            self.unsolved.append(float(np.abs(result.base_residual).max()))
            raise InputError('contacts_unsolved', f'contacts {self.method}: the contacts in '
                             f'contact {[c.link for c in self.contacts]} cannot carry the '
                             f'base: {result.summary()}; not publishing')
        if measured is None or not self.contacts:
            self._carries(result)
        if measured is not None or not unilateral:
            return result
        pull = _worst_pull(result, self.pull_tolerance)
        if pull is None:      # the fast path: the violations _result found, usually none
            return result
        self.pulls.append(pull)
        what = (f'contacts {self.method}: contact {shown(pull.contact)} would pull '
                f'{pull.amount:.3g} N (n·f < 0; tolerance {self.pull_tolerance:.3g} N)')
        if self.method == 'qp' or self.qp_missing:
            raise InputError('contacts_pull', what + (
                '; not publishing' if self.method == 'qp' else
                f'; the QP that re-solves it cannot run ({self.qp_missing}); not publishing'))
        result = sd.contact_inverse_dynamics(*state, method='qp', gravity=gravity)
        if result.status != 'solved':
            raise InputError('contacts_unsolved', f'{what}; re-solved by qp: '
                             f'{result.summary()}; not publishing')
        self._carries(result)
        again = _worst_pull(result, self.pull_tolerance)
        if again is not None:
            raise InputError('contacts_pull', f'{what}; re-solved by qp, contact '
                             f'{shown(again.contact)} still pulls {again.amount:.3g} N; '
                             'not publishing')
        return result

    def _carries(self, result: 'sd.ContactResult') -> None:
        """Refuse ``result`` unless it carries the base rows (InputError ``contacts_unsolved``).

        ``no_contact`` whatever its residual when no contact is in force (in flight).
        """
        residual = float(np.abs(result.base_residual).max())
        if not self.contacts:
            self.unsolved.append(residual)
            raise InputError('no_contact', 'no contact carries the base: no link of '
                             'contacts.links is in contact (contact_states all 0: in flight), '
                             f'base residual {residual:.3g} (N m, N); not publishing')
        if residual > self.residual_tolerance:
            self.unsolved.append(residual)
            raise InputError('contacts_unsolved', f'contacts {result.method}: the contacts in '
                             f'contact {[c.link for c in self.contacts]} cannot carry the '
                             f'base: base residual {residual:.3g} (N m, N; tolerance '
                             f'{self.residual_tolerance:.3g}, 1e-6 m g); not publishing')

    def full(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        """Return the joints' efforts of ``M q̈ + h = Sᵀ τ + J_cᵀ λ``, + armature, friction."""
        result = self._solve(q, qd, qdd, self.base_v, self.base_a, self.gravity, self.measured)
        self.results.append(result)
        tau = np.array(result.tau)
        if self.armature is not None:
            tau += self.armature * qdd
        if self.friction_threshold is not None:
            tau += sd.friction_torque(self.model, np.concatenate((self.base_v, qd)),
                                      self.friction_threshold)[6:]
        return tau

    def gravity_torque(self, q: np.ndarray) -> np.ndarray:
        """Return the joints' efforts that hold the robot still on its contacts (q̇ = q̈ = 0)."""
        zero, six = np.zeros(len(q)), np.zeros(6)
        return np.array(self._solve(q, zero, zero, six, six, self.gravity).tau)

    def inertia_times(self, q: np.ndarray, u: np.ndarray) -> np.ndarray:
        """Return the contact-consistent efforts of joint accelerations ``u`` (no gravity)."""
        zero, six = np.zeros(len(q)), np.zeros(6)
        tau = np.array(self._solve(q, zero, u, six, six, (0.0, 0.0, 0.0),
                                   unilateral=False).tau)
        if self.armature is not None:
            tau += self.armature * u
        return tau


def _worst_pull(result: 'sd.ContactResult', tolerance: float
                ) -> Optional['sd.contacts.Violation']:
    """Return the contact of ``result`` that pulls most beyond ``tolerance`` N (None: none)."""
    worst = None
    for violation in result.violations:
        if (violation.kind == 'unilateral' and violation.amount > tolerance
                and (worst is None or violation.amount > worst.amount)):
            worst = violation
    return worst


def _world(R: np.ndarray, wrench: np.ndarray, rows: int) -> np.ndarray:
    """Return a link-frame ``[n; f]`` in world axes: a point contact's force (3), else both."""
    if rows == 3:
        return R @ wrench[3:]
    return np.r_[R @ wrench[:3], R @ wrench[3:]]


class ContactWrenches:
    """One answer's contact wrenches, computed when first read (:func:`contact_wrenches`).

    Iterated as ``(link, [n; f])`` pairs. An answer carries this instead of the wrenches: the
    node reads them only while somebody subscribes to ``contact_wrenches`` (measured on
    Solo12: 20-25 µs to compute, ~45 µs each of the four messages to build and publish, on
    every answer nobody listens to).
    """

    __slots__ = ('_state', '_wrenches')

    def __init__(self, model: 'sd.Model', base_q: np.ndarray, q: np.ndarray,
                 result: 'sd.ContactResult') -> None:
        self._state = (model, base_q, q, result)
        self._wrenches: Optional[tuple] = None

    def __iter__(self):
        if self._wrenches is None:
            self._wrenches = contact_wrenches(*self._state)
            self._state = None
        return iter(self._wrenches)


def contact_wrenches(model: 'sd.Model', base_q: np.ndarray, q: np.ndarray,
                     result: 'sd.ContactResult') -> Tuple[Tuple[str, np.ndarray], ...]:
    """Each contact's wrench ``[n; f]`` (6,) on the robot, in its link's frame, at its origin.

    ``result.forces`` are in world axes at the contact point (the link's origin: contacts of
    the node have no offset); a point contact's moment is zero.
    """
    links = tuple(result.forces)
    rotations = link_orientations(model, np.concatenate((base_q, q)), links)
    out = []
    for link in links:
        R = rotations[link]
        force = np.asarray(result.forces[link], dtype=float)
        wrench = np.zeros(6)
        if len(force) == 3:
            wrench[3:] = R.T @ force
        else:
            wrench[:3], wrench[3:] = R.T @ force[:3], R.T @ force[3:]
        out.append((link, wrench))
    return tuple(out)
