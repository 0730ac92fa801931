# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""What the node says in /diagnostics: its counters and the text of each status.

Pure: the node fills :class:`Window` (one diagnostics period) and :class:`Totals` (since the
start) as messages come, and once a second publishes what :func:`model_status`,
:func:`feedforward_status`, :func:`observer_status` and :func:`base_status` make of them.
"""

from __future__ import annotations

from collections import Counter
import time
from typing import Dict, List, Optional, Tuple

import numpy as np
from spatial_dynamics import backends, Model
from spatial_dynamics.ros.bases import BaseInputs, BaseWindow, source_hint
from spatial_dynamics.ros.config import NODE_REASONS, URDF_WARNINGS_LISTED, WRENCH_REASONS
from spatial_dynamics.ros.control import FEEDBACK_MODES, MEASURED_REASONS
from spatial_dynamics.ros.inputs import REASONS
from spatial_dynamics.ros.observer import BASE_SKIP_REASONS, EstimateWindow, MomentumObserver
from spatial_dynamics.ros.records import Robot
from spatial_dynamics.ros.text import shown


# --------------------------------------------------------------------------------------------
# Counters and what /diagnostics says about them

class Window:
    """Counts and compute times over one diagnostics period."""

    def __init__(self) -> None:
        self.start_ns = time.monotonic_ns()
        self.received = 0
        self.answered = 0
        self.compute_ns = 0
        self.compute_max_ns = 0
        self.delay_ns = 0
        self.delay_count = 0
        self.delay_max_ns = 0
        self.measured = 0          # good measured states (joint_states)
        self.above_limit = 0       # answers published above a joint's URDF effort limit
        self.above_worst: Optional[Tuple[float, str, float, float]] = None
        #                            (|τ| / limit, joint, τ, limit) of the worst of them


class Totals:
    """Counters since the start: answers, rejections by reason, saturation, wrenches, models."""

    def __init__(self) -> None:
        self.answered = 0
        self.last_input_ns: Optional[int] = None     # monotonic ns of the last answered input
        self.last_desired_ns: Optional[int] = None   # receipt of the last good desired state
        self.last_measured_ns: Optional[int] = None  # receipt of the last good measured state
        self.measured_received = 0
        self.measured_rejected: Counter = Counter({reason: 0 for reason in MEASURED_REASONS})
        self.rejected: Counter = Counter({reason: 0 for reason in REASONS + NODE_REASONS})
        #: (reason, 'topic: why', monotonic ns) of the last input refused an answer, and of
        #: the last measured state refused: what the ``feedforward`` status names
        self.last_rejected: Optional[Tuple[str, str, int]] = None
        self.last_measured_rejected: Optional[Tuple[str, str, int]] = None
        self.saturated = 0                  # answers with at least one clamped joint
        self.saturated_joints: Counter = Counter()
        self.wrenches_received = 0
        self.wrenches_rejected: Counter = Counter({reason: 0 for reason in WRENCH_REASONS})
        self.descriptions_rejected = 0
        self.last_description_error = ''
        self.descriptions_superseded = 0    # topic descriptions dropped for a newer one

    def description_rejected(self, reason: str) -> None:
        """Count a rejected description and remember why."""
        self.descriptions_rejected += 1
        self.last_description_error = reason


#: A diagnostics status without ROS: level ('OK', 'WARN', 'ERROR'), message, key-values.
Status = Tuple[str, str, List[Tuple[str, str]]]


def backend_text(robot: Robot) -> str:
    """Name what the answers run on, for logs and diagnostics (the backend's name first)."""
    if robot.backend == 'compiled':
        return backends.describe('compiled')
    if robot.setting != 'numpy':
        return f'numpy (compiled kernels unavailable: {backends.compiled.FAILURE})'
    return 'numpy'


def dof_text(model: Model) -> str:
    """Return the model's degrees of freedom as a user counts them.

    A floating model's ``joint_names`` start with the free-flyer: Solo12's are 13 names for
    12 joints and a base of six degrees of freedom (nv 18).
    """
    if model.floating:
        return f'{model.nv - 6} joints + free-flyer (nv {model.nv})'
    return f'{model.nv} DOF'


def model_status(robot: Optional[Robot], totals: Totals, strict: bool,
                 backend: str) -> Status:
    """Return the ``robot model`` status: what is loaded, from where, backend, warnings."""
    rejections = [('descriptions rejected', str(totals.descriptions_rejected)),
                  ('last rejection', totals.last_description_error),
                  ('descriptions superseded', str(totals.descriptions_superseded))]
    if robot is None:
        return 'ERROR', 'waiting for robot_description', rejections
    # WARN while the loaded description has URDF warnings: the torques are those of the
    # file as written, but the file is physically inconsistent somewhere.
    model, urdf_warnings = robot.model, robot.base.warnings
    message = f'robot {shown(model.name)} loaded, {dof_text(model)}'
    if urdf_warnings:
        message += f', {len(urdf_warnings)} URDF warning(s)'
    # 'dof' stays the number of a fixed-base robot (what tools read); a floating one says it
    values = [('robot name', shown(model.name, quote=False)),
              ('dof', dof_text(model) if model.floating else str(model.nv)),
              ('model joints', ', '.join(shown(name, quote=False) for name in model.joint_names)),
              ('output joints', ', '.join(shown(name, quote=False) for name in robot.joints)),
              ('source', robot.source),
              ('summary', robot.base.summary()), ('backend', backend),
              ('backend setting', robot.setting)]
    values += rejections + [('strict urdf', str(bool(strict))),
                            ('urdf warnings', str(len(urdf_warnings)))]
    values += [(f'urdf warning {i}', text)
               for i, text in enumerate(urdf_warnings[:URDF_WARNINGS_LISTED], 1)]
    return ('WARN' if urdf_warnings else 'OK'), message, values


def _us(ns: float) -> str:
    return f'{ns * 1e-3:.1f}'


def _age(last_ns: Optional[int], now_ns: int) -> Optional[float]:
    return None if last_ns is None else (now_ns - last_ns) * 1e-9


def _feedback_state(params, totals: Totals, now_ns: int) -> Optional[Tuple[str, str]]:
    """Level and message when a feedback mode cannot answer (stale or missing state)."""
    mode = params.control_mode
    for what, where, source, last_ns, timeout in (
            ('measured', ' on joint_states', 'joint_states', totals.last_measured_ns,
             'measured_timeout'),
            ('desired', '', 'desired input', totals.last_desired_ns, 'input_timeout')):
        age, limit = _age(last_ns, now_ns), getattr(params, timeout)
        refused = (_refused(totals.last_measured_rejected, last_ns, now_ns, 'joint_states')
                   if what == 'measured' else '')
        if age is None:
            return 'ERROR', f'no {what} state{where} yet ({mode}){refused}; not publishing'
        if age > limit:
            return 'ERROR', (f'{what} state stale: no good {source} for {age:.2f} s '
                             f'({timeout} {limit} s, {mode}){refused}; not publishing')
    return None


def _refused(last: Optional[Tuple[str, str, int]], since_ns: Optional[int], now_ns: int,
             what: str = 'input') -> str:
    """Say ``last`` (reason, why, when) rejected, if after ``since_ns``: '' when not."""
    if last is None or (since_ns is not None and last[2] <= since_ns):
        return ''
    reason, text, when_ns = last
    return (f'; the last {what}, {(now_ns - when_ns) * 1e-9:.2f} s ago, was rejected '
            f"({reason}): {text.removesuffix('; not publishing')}")


def _input_state(robot: Optional[Robot], window: Window, params, period: float,
                 age: Optional[float], totals: Optional[Totals] = None, now_ns: int = 0
                 ) -> Tuple[str, str]:
    """Level and message of the ``feedforward`` status.

    No answer (yet, or for longer than ``input_timeout``) while inputs were rejected since
    the last one: ERROR naming the last rejection, not "no input" (the base's or the
    contacts' inputs, a refused plan, ...).
    """
    rejected_now = window.received - window.answered
    if robot is None:
        return 'ERROR', 'no robot model'
    feedback = params.control_mode in FEEDBACK_MODES and totals is not None
    if feedback:
        stale = _feedback_state(params, totals, now_ns)
        if stale is not None:
            return stale
    last = None if totals is None else totals.last_rejected
    refused = _refused(last, None if totals is None else totals.last_input_ns, now_ns)
    if refused and (age is None or age > params.input_timeout):
        return 'ERROR', ('no answer yet' if age is None else f'no answer for {age:.2f} s') + (
            f'{refused}; not publishing')
    if not feedback:
        if age is None:
            return 'WARN', 'no input received yet'
        if age > params.input_timeout:
            return 'ERROR', (f'input stale: no good input for {age:.2f} s '
                             f'(input_timeout {params.input_timeout} s); not publishing')
    above = ''    # said, not a fault: the URDF's limits are often wrong, clamping is opt-in
    if window.above_limit:
        ratio, joint, value, limit = window.above_worst
        above = (f', {window.above_limit} answer(s) above the URDF effort limit (worst '
                 f'{shown(joint)} {value:+.4g}, limit {limit:g}, {ratio:.3g}x)')
    if rejected_now:
        return 'WARN', (f'{window.answered / period:.1f} Hz, {rejected_now} rejected{above}'
                        + _refused(last, window.start_ns, now_ns))
    return 'OK', f'{window.answered / period:.1f} Hz{above}'


def _window_values(window: Window, period: float) -> List[Tuple[str, str]]:
    answered, delays = window.answered, window.delay_count
    worst = window.above_worst
    return [
        ('above effort limit', str(window.above_limit)),
        ('above effort limit worst', '' if worst is None else
         f'{worst[1]}: {worst[2]:+.4g} (limit {worst[3]:g}, {worst[0]:.3g}x)'),
        ('input rate [Hz]', f'{window.received / period:.1f}'),
        ('output rate [Hz]', f'{answered / period:.1f}'),
        ('compute time mean [us]', _us(window.compute_ns / answered) if answered else ''),
        ('compute time max [us]', _us(window.compute_max_ns) if answered else ''),
        ('input delay mean [ms]', f'{window.delay_ns / delays * 1e-6:.3f}' if delays else ''),
        ('input delay max [ms]', f'{window.delay_max_ns * 1e-6:.3f}' if delays else ''),
    ]


def _terms_values(robot: Robot) -> List[Tuple[str, str]]:
    return [('payload', str(robot.payload)),
            ('armature', 'none' if robot.armature is None else str(robot.armature.tolist())),
            ('friction model', 'none' if robot.friction_threshold is None
             else f'urdf (threshold {robot.friction_threshold:g})'),
            ('clamp to effort limits', str(robot.clamp))] + (
        [] if robot.gains is None else
        [('kp', str(robot.gains.kp.tolist())), ('kd', str(robot.gains.kd.tolist())),
         ('continuous joints', ', '.join(name for name, c in zip(
             robot.joints, robot.gains.continuous) if c))])


def feedforward_status(robot: Optional[Robot], window: Window, totals: Totals,
                       params, wrenches: Dict[str, tuple], now_ns: int) -> Status:
    """Return the ``feedforward`` status: rates, compute time, delays, staleness, rejections.

    ``window`` is the period that ends at ``now_ns`` (monotonic); ``params`` the node's
    parameters (the table's ``Params``); ``wrenches`` maps a link to ``(wrench, expiry ns)``.
    """
    period = max((now_ns - window.start_ns) * 1e-9, 1e-9)
    last = totals.last_input_ns
    age = None if last is None else (now_ns - last) * 1e-9
    level, message = _input_state(robot, window, params, period, age, totals, now_ns)
    measured_age = _age(totals.last_measured_ns, now_ns)
    values = _window_values(window, period) + [
        ('last input age [s]', '' if age is None else f'{age:.3f}'),
        ('input timeout [s]', str(params.input_timeout)),
        ('stale', str(age is None or age > params.input_timeout)),
        ('answered', str(totals.answered)),
        ('rejected', str(sum(totals.rejected.values()))),
        ('last rejection', '' if totals.last_rejected is None else
         '({}) {}'.format(*totals.last_rejected[:2]))]
    values += [(f'rejected {reason}', str(count)) for reason, count in totals.rejected.items()]
    values += [
        ('control mode', params.control_mode), ('output', params.output),
        ('measured state rate [Hz]', f'{window.measured / period:.1f}'),
        ('measured state age [s]', '' if measured_age is None else f'{measured_age:.3f}'),
        ('measured timeout [s]', str(params.measured_timeout)),
        ('measured state stale', str(measured_age is None
                                     or measured_age > params.measured_timeout)),
        ('measured states received', str(totals.measured_received)),
        ('measured states rejected', str(sum(totals.measured_rejected.values()))),
        ('last measured state rejection', '' if totals.last_measured_rejected is None else
         '({}) {}'.format(*totals.last_measured_rejected[:2]))]
    values += [(f'measured states rejected {reason}', str(count))
               for reason, count in totals.measured_rejected.items()]
    values += [('gravity [m/s^2]', str(list(params.gravity))),
               ('acceleration source', params.acceleration_source)]
    if robot is not None:
        values += _terms_values(robot)
    values += [
        ('saturated', str(totals.saturated)),
        ('saturated joints', ', '.join(f'{name}: {count}' for name, count
                                       in sorted(totals.saturated_joints.items()))),
        ('external wrenches active', ', '.join(sorted(
            link for link, (_, expiry) in wrenches.items() if expiry >= now_ns))),
        ('external wrenches received', str(totals.wrenches_received)),
        ('external wrenches rejected', str(sum(totals.wrenches_rejected.values())))]
    values += [(f'external wrenches rejected {reason}', str(count))
               for reason, count in totals.wrenches_rejected.items()]
    return level, message, values


def observer_status(robot: Optional[Robot], gain: float,
                    observer: Optional[MomentumObserver], window: EstimateWindow,
                    off: str = '') -> Status:
    """Return the ``external torque`` status: RMS of the estimate per joint over the period.

    WARN, naming the joints, when a joint's RMS exceeds ``external_torque_warn``; WARN, naming
    the directions, when the virtual F/T sensor (``wrench_estimate.link``) had a sample in the
    period where some direction of the wrench was unobservable or damped (fewer than six
    joints, a singular pose), whether or not anything pushed: a wrench along it would be
    missed or underestimated. ``off``: why the observer cannot run on this base
    (:func:`~spatial_dynamics.ros.bases.observer_off`), '' when it can.
    """
    values = [('observer gain [1/s]', f'{gain:g}'),
              ('time constant [ms]', f'{1e3 / gain:.1f}' if gain > 0.0 else '')]
    if gain <= 0.0:
        return 'OK', 'observer off (observer_gain 0)', values
    if off:
        return 'OK', f'observer off ({off})', values
    if robot is None:
        return 'OK', 'no robot model', values
    values += [('estimates', str(window.count))]
    values += [(f'skipped {reason}', str(count)) for reason, count in window.skipped.items()]
    if observer is not None:
        values += [('samples since restart', str(observer.samples)),
                   ('restarts', str(observer.resets)),
                   ('last restart', observer.reset_reason),
                   ('last refused sample', observer.refused_reason)]
    rms = window.rms()
    if rms is None or len(rms) != len(robot.joints):
        skipped = [f'{reason} {count}' for reason, count in window.skipped.items()
                   if count and reason != 'no_effort']
        if skipped:   # measured states came and were skipped: why, not "no effort"
            base = any(window.skipped.get(reason) for reason in BASE_SKIP_REASONS)
            return 'WARN', ('no estimate in this period: measured states skipped ('
                            + ', '.join(skipped) + ')' + (
                                '; the base status names the base input' if base else '')
                            ), values
        return 'OK', 'no measured effort in this period (observer waiting)', values
    wrench = _wrench_text(window.wrench, values)
    warn = robot.external_torque_warn
    values += [(f'rms {joint}', f'{value:.4g}') for joint, value in zip(robot.joints, rms)]
    values += [('warn above', ', '.join(f'{x:g}' for x in warn))]
    over = np.flatnonzero(rms > warn)
    worst = int(np.argmax(rms / warn))
    if over.size:
        return 'WARN', ('external torque above external_torque_warn: ' + ', '.join(
            f'{robot.joints[i]} {rms[i]:.3g} (RMS) > {warn[i]:g}' for i in over)
            + (f'; {wrench}' if wrench else '')), values
    if wrench:
        return 'WARN', wrench, values
    return 'OK', (f'largest RMS {rms[worst]:.3g} on {robot.joints[worst]} '
                  f'(warn above {warn[worst]:g})'), values


_AXES = ('n_x', 'n_y', 'n_z', 'f_x', 'f_y', 'f_z')


def _direction(u: np.ndarray) -> str:
    """Name a unit wrench by its largest components, e.g. ``'0.74 f_y -0.55 f_z 0.38 f_x'``.

    A direction has no sign (the SVD gives either): the largest component is made positive,
    so the same direction reads the same in every period.
    """
    u = u if u[np.argmax(np.abs(u))] >= 0.0 else -u
    parts = [(abs(c), f'{c:+.2g} {axis}') for c, axis in zip(u, _AXES) if abs(c) > 0.2]
    parts.sort(reverse=True)
    return ' '.join(text for _, text in parts).lstrip('+')


def _wrench_text(wrench: Optional[dict], values: list) -> str:
    """Add the virtual F/T sensor's figures to ``values``; return what it could not observe.

    The text names the weak directions of the period's last sample that had one, and how
    many of those samples carried an external torque above ``external_torque_warn`` (a real
    wrench that may have been misread); '' when every sample observed all six directions.
    """
    if wrench is None:
        return ''
    values += [('wrench estimate link', wrench['link']),
               ('wrench estimates', str(wrench['count'])),
               ('wrench rank (lowest)', str(wrench['rank'])),
               ('wrench sigma_min (lowest)', f"{wrench['sigma_min']:.3g}"),
               ('wrench samples with weak directions', str(wrench['weak'])),
               ('of them loaded', str(wrench['weak_loaded']))]
    if not wrench['weak']:
        return ''
    directions = wrench['last_weak']
    named = '; '.join(_direction(directions[:, i]) for i in range(directions.shape[1]))
    return (f"external wrench at {shown(wrench['link'])}: {wrench['weak']} of {wrench['count']} "
            f"samples could not observe every direction (rank {wrench['rank']}, sigma_min "
            f"{wrench['sigma_min']:.3g}, {wrench['weak_loaded']} of them loaded past "
            f"external_torque_warn); missing or underestimated: {named}")


def base_status(params, robot, inputs: BaseInputs, window: BaseWindow, now_ns: int):
    """Return the ``base`` status: what the base's inputs are, the contacts' figures.

    ERROR while a needed input is missing or stale (nothing is published; the text says
    which, and its last refused message: :meth:`~.bases.BaseInputs.blocked`), WARN when a
    contact solution of the period violated a friction cone or pulled on the ground, left
    a base residual above :func:`~.floating.residual_tolerance` (measured wrenches), when an answer
    was refused because its split made a contact pull and the QP could not re-solve it, or
    because its contacts could not carry the base. Answers re-solved by the QP
    (a contact would have pulled) are counted, with the worst pull seen: that is the node
    working as documented, not a warning.
    """
    values = [('base', params.base)]
    needed = []
    if params.base == 'moving':
        values.append(('source', params.base_input_source))
        needed = ([('base/imu', inputs.imu)] if params.base_input_source == 'imu'
                  else [('base/pose', inputs.pose), ('base/twist', inputs.twist)])
    elif params.base == 'floating':
        needed = [('base/pose', inputs.pose), ('base/twist', inputs.twist),
                  ('contact_states', inputs.flags)]
        if params.contacts_measured:
            needed += [(f'measured_contact_wrenches {link}', inputs.measured.get(link))
                       for link in params.contacts_links or ()]
    values += [('base acceleration', params.base_input_acceleration),
               ('base timeout [s]', str(params.base_input_timeout))]
    for topic, held in needed:
        age = None if held is None else (now_ns - held.receipt_ns) * 1e-9
        values.append((f'{topic} age [s]', '' if age is None else f'{age:.3f}'))
    values += [(f'{topic} received', str(count)) for topic, count in inputs.received.items()]
    values += [(f'rejected {key}', str(count)) for key, count in inputs.rejected.items()]
    values += [(f'last refused {topic}', f'({reason}) {text}')
               for topic, (reason, text, _) in inputs.refused.items()]
    if params.base == 'floating':
        values += [('contacts', ', '.join(params.contacts_links or ())),
                   ('contacts method', params.contacts_method),
                   ('contact solutions', str(window.solved)),
                   ('base residual max', f'{window.residual_max:.3g}'),
                   ('last solution', '' if window.last is None else window.last.summary())]
        values += [(f'violation {key}', f'{count} (worst {window.worst[key]:.3g} N)')
                   for key, count in window.violations.items()]
        values += [('contact pull tolerance [N]', f'{robot.pull_tolerance:.3g}' if robot
                    else ''),
                   ('qp fallback', (robot.qp_missing or 'ready') if robot else ''),
                   ('re-solved by qp (a contact would pull)', str(window.resolved)),
                   ('worst pull [N]', f'{window.pull_max:.3g}' + (
                       f' ({window.pull_contact})' if window.pull_contact else ''))]
        values += [(f'refused {reason} (a contact would pull)', str(count))
                   for reason, count in window.refused.items()]
        values += [('refused: the contacts cannot carry the base (contacts_unsolved, '
                    'no_contact)', str(window.unsolved)),
                   ('worst refused base residual', f'{window.unsolved_residual:.3g}')]
    if robot is None:
        return 'ERROR', 'no robot model', values
    problems = inputs.blocked(params, now_ns)
    hint = source_hint(params, inputs)
    if problems and hint:
        problems.append(hint)
    if problems:
        return 'ERROR', '; '.join(problems) + '; not publishing', values
    warnings = []
    if window.refused:
        warnings.append(f'{sum(window.refused.values())} answer(s) refused, a contact would '
                        f'pull: {window.refused_last}')
    if window.violations:
        warnings.append('contact violations: ' + ', '.join(
            f'{key} ({count}x, worst {window.worst[key]:.3g} N)'
            for key, count in window.violations.items()))
    if window.unsolved:
        warnings.append(f'{window.unsolved} answer(s) refused, the contacts cannot carry the '
                        f'base (worst base residual {window.unsolved_residual:.3g}): '
                        f'{window.unsolved_last}')
    if window.residual_max > robot.residual_tolerance:
        warnings.append(f'base residual {window.residual_max:.3g} (the measured contact '
                        'wrenches do not carry the base rows)')
    if warnings:
        return 'WARN', '; '.join(warnings), values
    return 'OK', f'base {params.base}: inputs fresh', values
