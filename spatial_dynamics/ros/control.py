# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""What one answer of the node is, without ROS: output choice, control law, term split.

Pure Python + numpy + the library (no rclpy import), tested in ``test/test_node_control_laws.py``.

**Model part** (parameter ``output``), joint-space, SI units, order of ``model.joint_names``:

=====================  =========================================  ==========================
``output``             model part                                 for
=====================  =========================================  ==========================
``full``               g + C q̇ + M q̈ + armature·q̈ + friction(q̇)   simulators, drives that add
                       − Σ Jᵀ f_ext   (= ID + joint-space terms)   nothing (ros2_control
                                                                  effort interfaces)
``without_gravity``    full − g(q)                                drives that compensate
                                                                  gravity themselves (UR
                                                                  direct torque, Franka, KUKA)
``gravity_only``       g(q)                                       holding an arm still
``none``               0                                          the "PD alone" baseline
=====================  =========================================  ==========================

**Control law** (parameter ``control_mode``), with e = q_d − q (wrapped to (−π, π] on
continuous joints), ė = q̇_d − q̇ and u = Kp e + Kd ė:

===================  ===================================================  ===================
``control_mode``     τ                                                    model part at
===================  ===================================================  ===================
``feedforward``      model(q_d, q̇_d, q̈_d)                                 desired state
``pd_feedforward``   model(q_d, q̇_d, q̈_d) + u            (Kp N·m/rad,      desired state
                                                         Kd N·m·s/rad)
``computed_torque``  model(q, q̇, q̈_d) + (M(q) + armature) u               measured state
                     (= ID(q, q̇, q̈_d + u) + terms, for ``full``;
                     Kp 1/s², Kd 1/s)
===================  ===================================================  ===================

The **terms** (:data:`TERMS`) are computed with RNEA calls only, never by multiplying M:
``gravity`` = RNEA(q, 0, 0), ``velocity_product`` = RNEA(q, q̇, 0) − gravity (C q̇),
``inertial`` = RNEA(q, q̇, q̈) − RNEA(q, q̇, 0) (M q̈), ``external`` = RNEA with the wrenches −
RNEA without (−Σ Jᵀ f_ext), ``armature`` = armature·q̈, ``friction`` = friction(q̇) and
``feedback`` = u (pd_feedforward) or RNEA(q, 0, u, gravity 0) + armature·u (computed_torque).
Only the terms of the answer are listed; they sum to its τ (to rounding).
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Dict, Mapping, Optional, Sequence, Tuple

import numpy as np
import spatial_dynamics as sd
from spatial_dynamics.bounds import MAX_POSITION, MAX_VELOCITY
from spatial_dynamics.ros.inputs import InputError, joint_state_arrays
from spatial_dynamics.ros.parameters import one_of, ParameterError
from spatial_dynamics.ros.text import shown

#: Values of the ``output`` parameter: which model part is published.
OUTPUTS = ('full', 'without_gravity', 'gravity_only', 'none')
#: Values of the ``control_mode`` parameter.
CONTROL_MODES = ('feedforward', 'pd_feedforward', 'computed_torque')
#: The modes that close a loop on the measured state (``joint_states``).
FEEDBACK_MODES = ('pd_feedforward', 'computed_torque')
#: Every term of the ``feedforward_terms`` topic, in the order they are listed and summed.
TERMS = ('gravity', 'velocity_product', 'inertial', 'armature', 'friction', 'external',
         'feedback')
#: The model terms each ``output`` publishes.
OUTPUT_TERMS = {
    'full': TERMS[:6],
    'without_gravity': TERMS[1:6],
    'gravity_only': ('gravity',),
    'none': (),
}

# Bounds beyond which a gain or a measured value cannot be meant: refused, the bound named.
#: Kp: 1e6 N·m/rad is stiffer than any joint servo; 1e6 1/s² is a natural frequency of
#: 1000 rad/s (160 Hz), beyond the bandwidth of any loop this node can close.
MAX_KP = 1e6
#: Kd: 1e4 N·m·s/rad, or 1e4 1/s (2ζω for ζ = 1 at ω = 5000 rad/s).
MAX_KD = 1e4
#: |q| and |q̇| of a measured (and desired) joint: the bounds of every joint state.
MAX_MEASURED_POSITION = MAX_POSITION
MAX_MEASURED_VELOCITY = MAX_VELOCITY

GAIN_UNITS = {'kp': 'N·m/rad (N/m) in pd_feedforward, 1/s² in computed_torque',
              'kd': 'N·m·s/rad (N·s/m) in pd_feedforward, 1/s in computed_torque'}
GAIN_BOUNDS = {'kp': MAX_KP, 'kd': MAX_KD}

#: Why a measured ``joint_states`` message is refused (diagnostics counter keys).
MEASURED_REASONS = ('no_model', 'empty', 'length_mismatch', 'duplicate_joint',
                    'missing_joint', 'non_finite', 'no_velocity', 'out_of_bounds')
#: Why a good measured state gets no answer in a feedback mode. ``repeated``: the stamp of the
#: measured state answered last, again (a simulator in lockstep republishing the state it
#: waits on, a driver sending a sample twice): a controller answers each measurement once.
FEEDBACK_REASONS = ('no_desired', 'desired_stale', 'repeated')


#: A gain or a mode that cannot be used; the message names the parameter.
ControlError = ParameterError


# --------------------------------------------------------------------------------------------
# Parameters

def check_mode(control_mode: str, output: str, kp: Sequence[float] = (1.0,),
               kd: Sequence[float] = (1.0,)) -> Tuple[str, str]:
    """Return ``(control_mode, output)`` if each is valid and they make sense together.

    ``output: none`` leaves only the feedback term, which ``feedforward`` does not have, and
    which is zero in a feedback mode whose gains ``kp`` and ``kd`` are all zero: every answer
    would be zeros (a loaded arm would drop), so those combinations are refused.
    """
    one_of('control_mode', control_mode, CONTROL_MODES)
    one_of('output', output, OUTPUTS)
    if output == 'none' and control_mode != 'feedforward' and not any(kp) and not any(kd):
        raise ControlError(
            f"parameters output 'none', control_mode {control_mode!r} and kp = kd = 0: output "
            'none publishes only the feedback term, which is zero with zero gains, so every '
            'answer would be zeros; set kp and kd first (or all of them atomically), or '
            'choose another output')
    if output == 'none' and control_mode == 'feedforward':
        raise ControlError(
            "parameters output 'none' and control_mode 'feedforward': output none publishes "
            'only the feedback term, and feedforward has none, so every answer would be '
            "zeros; set control_mode to 'pd_feedforward' or 'computed_torque' first (or "
            'both atomically), or choose another output')
    return control_mode, output


def check_gains(model: 'sd.Model', name: str, values: Optional[Sequence[float]],
                joints: Optional[Sequence[str]] = None) -> np.ndarray:
    """``kp`` or ``kd``: one value for all joints, or one per model joint; finite, in [0, bound].

    Empty or unset: 0 for every joint. Returns a read-only (n,) array in the order of
    ``joints`` (default ``model.joint_names``, the ``joints`` parameter's order; a floating
    base's actuated joints).
    """
    values = [] if values is None else list(values)
    joints = model.joint_names if joints is None else tuple(joints)
    n = len(joints)
    if len(values) not in (0, 1, n):
        raise ControlError(
            f'parameter {name}: {len(values)} values for the {n} joints '
            f'{list(joints)} (need one value for all, or one per joint in this '
            'order)')
    gains = np.zeros(n) if not values else np.array(
        values * n if len(values) == 1 else values, dtype=float)
    bound = GAIN_BOUNDS[name]
    for joint, value in zip(joints, gains):
        if not (math.isfinite(value) and 0.0 <= value <= bound):
            raise ControlError(
                f'parameter {name}: joint {shown(joint)} has {value}, need a finite value from 0 '
                f'to {bound:g} ({GAIN_UNITS[name]})')
    gains.setflags(write=False)
    return gains


def check_gains_without_model(name: str, values: Optional[Sequence[float]]) -> None:
    """Check what needs no model: finite, in [0, bound] (the length is checked with one)."""
    bound = GAIN_BOUNDS[name]
    for value in [] if values is None else values:
        if not (math.isfinite(value) and 0.0 <= value <= bound):
            raise ControlError(f'parameter {name}: {value} is not a finite value from 0 to '
                               f'{bound:g} ({GAIN_UNITS[name]})')


def continuous_joints(model: 'sd.Model', joints: Optional[Sequence[str]] = None
                      ) -> np.ndarray:
    """Mask (n,) of ``joints`` (default the model's) whose URDF type is ``continuous``.

    Their position errors wrap.
    """
    joints = model.joint_names if joints is None else joints
    mask = np.array([model.joint_types.get(name) == 'continuous' for name in joints],
                    dtype=bool)
    mask.setflags(write=False)
    return mask


# --------------------------------------------------------------------------------------------
# The measured state

def measured_arrays(joint_names: Tuple[str, ...], name: Sequence[str],
                    position: Sequence[float], velocity: Sequence[float],
                    need_velocity: bool) -> Tuple[np.ndarray, Optional[np.ndarray]]:
    """``(q, q̇)`` in ``joint_names`` order from a measured ``sensor_msgs/JointState``.

    By name, any order, extra joints ignored; ``position`` required; ``velocity`` required
    when ``need_velocity`` (a feedback mode), else may be empty (then ``q̇`` is None);
    ``effort`` is not read. Raises :class:`~spatial_dynamics.ros.inputs.InputError` with a
    reason of :data:`MEASURED_REASONS`; beyond :data:`MAX_MEASURED_POSITION` or
    :data:`MAX_MEASURED_VELOCITY` it is ``out_of_bounds``.
    """
    if need_velocity and len(velocity) == 0 and len(name) > 0:
        raise InputError('no_velocity', "field 'velocity' is empty: the feedback modes need "
                         'the measured velocity of every model joint')
    q, qd, _ = joint_state_arrays(joint_names, name, position, velocity, None)
    return q, (qd if len(velocity) else None)


def position_error(q_d: np.ndarray, q: np.ndarray, continuous: np.ndarray) -> np.ndarray:
    """``e = q_d − q``; on continuous joints wrapped to (−π, π] (the short way round)."""
    e = q_d - q
    if continuous.any():
        wrapped = e - 2.0 * math.pi * np.ceil((e - math.pi) / (2.0 * math.pi))
        e = np.where(continuous, wrapped, e)
    return e


# --------------------------------------------------------------------------------------------
# One answer

@dataclass(frozen=True)
class Dynamics:
    """The model and the settings the model part is computed with (one answer).

    ``gravity`` m/s² in the base frame; ``armature`` None or (n,); ``friction_threshold``
    None (no friction) or the smooth-sign velocity; ``f_ext`` None or link → ``[n; f]``
    in the link frame (N m, N); ``base`` None (a fixed base) or the base's motion
    (:class:`~spatial_dynamics.BaseMotion`, a moving base: ``base=`` of every RNEA call but
    :meth:`inertia_times`, since ``M(q)`` does not depend on it).
    """

    model: 'sd.Model'
    gravity: Tuple[float, float, float] = (0.0, 0.0, -9.81)
    backend: str = 'numpy'
    armature: Optional[np.ndarray] = None
    friction_threshold: Optional[float] = None
    f_ext: Optional[Mapping[str, np.ndarray]] = None
    base: Optional['sd.BaseMotion'] = None

    def full(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        """``ID(q, q̇, q̈, f_ext) + armature·q̈ + friction(q̇)``: one RNEA call."""
        tau = sd.rnea(self.model, q, qd, qdd, gravity=self.gravity, f_ext=self.f_ext,
                      backend=self.backend, base=self.base)
        if self.armature is not None:
            tau += self.armature * qdd
        if self.friction_threshold is not None:
            tau += sd.friction_torque(self.model, qd, self.friction_threshold)
        return tau

    def gravity_torque(self, q: np.ndarray) -> np.ndarray:
        """``g(q)``: RNEA at q̇ = q̈ = 0."""
        return sd.gravity_torque(self.model, q, self.gravity, backend=self.backend,
                                 base=self.base)

    def inertia_times(self, q: np.ndarray, u: np.ndarray) -> np.ndarray:
        """``(M(q) + armature) u``: RNEA at q̇ = 0, q̈ = u, without gravity."""
        tau = sd.rnea(self.model, q, np.zeros_like(u), u, gravity=(0.0, 0.0, 0.0),
                      backend=self.backend)
        if self.armature is not None:
            tau += self.armature * u
        return tau

    def model_part(self, output: str, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray
                   ) -> np.ndarray:
        """Return the model part ``output`` selects, with the fewest RNEA calls (0 to 2)."""
        if output == 'full':
            return self.full(q, qd, qdd)
        if output == 'without_gravity':
            return self.full(q, qd, qdd) - self.gravity_torque(q)
        if output == 'gravity_only':
            return self.gravity_torque(q)
        return np.zeros(len(q))

    def terms(self, output: str, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray
              ) -> Dict[str, np.ndarray]:
        """Return the model terms of ``output`` (:data:`OUTPUT_TERMS`), each from RNEA calls."""
        wanted = OUTPUT_TERMS[output]
        if not wanted:
            return {}
        n = len(q)
        g = self.gravity_torque(q)
        result = {'gravity': g}
        if len(wanted) > 1:
            bias = sd.bias_torque(self.model, q, qd, self.gravity, backend=self.backend,
                                  base=self.base)
            tau = sd.rnea(self.model, q, qd, qdd, gravity=self.gravity, backend=self.backend,
                          base=self.base)
            result['velocity_product'] = bias - g
            result['inertial'] = tau - bias
            result['armature'] = (np.zeros(n) if self.armature is None
                                  else self.armature * qdd)
            result['friction'] = (
                np.zeros(n) if self.friction_threshold is None
                else sd.friction_torque(self.model, qd, self.friction_threshold))
            result['external'] = np.zeros(n) if not self.f_ext else sd.rnea(
                self.model, q, qd, qdd, gravity=self.gravity, f_ext=self.f_ext,
                backend=self.backend, base=self.base) - tau
        return {term: result[term] for term in wanted}


@dataclass(frozen=True)
class Gains:
    """Per-joint ``kp``, ``kd`` (n,) and the continuous-joint mask (n,) of one model."""

    kp: np.ndarray
    kd: np.ndarray
    continuous: np.ndarray


State = Tuple[np.ndarray, ...]


def answer(dynamics: Dynamics, control_mode: str, output: str, desired: State,
           measured: Optional[State] = None, gains: Optional[Gains] = None,
           with_terms: bool = False) -> Tuple[np.ndarray, Optional[Dict[str, np.ndarray]]]:
    """Compute τ of one reply, and its terms when asked (else None); see the module docstring.

    ``desired`` is ``(q_d, q̇_d, q̈_d)``; ``measured`` ``(q, q̇)``, needed in the feedback
    modes (with ``gains``). With ``with_terms``, τ is the sum of the terms, in the order of
    :data:`TERMS`; without, τ takes the fewest RNEA calls (the same value to rounding).
    """
    q_d, qd_d, qdd_d = desired
    if control_mode == 'feedforward':
        q, qd, u = q_d, qd_d, None
    else:
        q, qd = measured
        u = (gains.kp * position_error(q_d, q, gains.continuous)
             + gains.kd * (qd_d - qd))
        if control_mode == 'pd_feedforward':
            q, qd = q_d, qd_d        # the model part at the desired state
    if with_terms:
        terms = dynamics.terms(output, q, qd, qdd_d)
        if u is not None:
            terms['feedback'] = (u if control_mode == 'pd_feedforward'
                                 else dynamics.inertia_times(q, u))
        tau = np.zeros(len(q_d))
        for value in terms.values():
            tau = tau + value
        return tau, terms
    if u is None:
        return dynamics.model_part(output, q, qd, qdd_d), None
    if control_mode == 'pd_feedforward':
        return dynamics.model_part(output, q, qd, qdd_d) + u, None
    if output in ('full', 'without_gravity'):   # ID(q, q̇, q̈_d + u): one call for both
        return dynamics.model_part(output, q, qd, qdd_d + u), None
    return dynamics.model_part(output, q, qd, qdd_d) + dynamics.inertia_times(q, u), None


def terms_names(joints: Sequence[str], terms: Sequence[str]) -> list:
    """``<joint>/<term>`` names of the ``feedforward_terms`` message, term by term."""
    return [f'{joint}/{term}' for term in terms for joint in joints]
