# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Proof on the simulator: a legged robot standing on the floor in MuJoCo sways its trunk.

    python -m spatial_dynamics.tools.legged --robot solo12 [--seconds 3] [--json out.json]
    python -m spatial_dynamics.tools.legged --robot talos

MuJoCo (:class:`~spatial_dynamics.sim.floating.FloatingRobot`: free base, floor, stiff soft
contacts with elliptic friction cones and a no-slip pass, μ = 0.8, semi-implicit Euler at
1 ms; :data:`~spatial_dynamics.sim.mujoco_model.CONTACT`) simulates, from example-robot-data,
Solo12 on four point feet (spheres of 2 mm radius at its foot frames) or Talos (``talos_reduced``,
its gripper joints fixed) on two soles (20 × 10 cm boxes). After 0.5 s standing still (not
counted) the trunk sways: its position follows ``p_d(t) = p_0 + A (1 - cos ωt)`` (Solo12:
down 3 cm and sideways 3 cm, periods 1.2 s and 1.6 s; Talos: down 3 cm and sideways 2 cm,
periods 2 s and 2.6 s; ``1 - cos`` goes up to 2), its orientation fixed, the feet where they
stand. The joints' ``q_d`` come from inverse kinematics (Gauss-Newton steps on the feet's
points and the soles' orientations with :func:`~spatial_dynamics.contact_jacobian`), ``q̇_d``
from ``J_c v = 0`` and ``q̈_d`` from ``J_c a + J̇_c v = 0``.

Two laws with the same low-gain PD on the joints, critically damped at 10 Hz (Solo12) or
20 Hz (Talos: below that its whole body topples about the ankles) and scaled per joint by
the inertia it moves with the trunk held (:func:`gains`):

* ``PD alone``: ``τ = Kp e + Kd ė``;
* ``PD + contact feed-forward``: ``τ += contact_inverse_dynamics(q_d, v_d, a_d, feet,
  method='qp').tau``, the least torques whose contact forces stay inside the friction cones.

Prints, for each, the RMS tracking error of the joints (rad) and of the trunk (m); and for the
feed-forward run the contact forces: MuJoCo's (``mj_contactForce`` per contact, world axes,
summed per foot) against the QP's, per foot (vertical, N), and their total against
``m (a_com - g)``, the rate of the robot's linear momentum over each step (our
``generalized_momentum`` of MuJoCo's state). ``--json`` writes the figures.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
import json
import os
import sys
import sysconfig
import time

import numpy as np

import spatial_dynamics as sd
from spatial_dynamics.files import check_output, write_atomic
from spatial_dynamics.joints import quaternion_matrix
from spatial_dynamics.sim.floating import FloatingRobot
from spatial_dynamics.sim.mujoco_model import Foot, urdf_text, without_mimic

LAWS = ('PD alone', 'PD + contact feed-forward')
MU = 0.8
TIMESTEP = 1e-3
SETTLE = 0.5        # s standing still before the sway (the feet sink into the soft floor)


@dataclass(frozen=True)
class Setup:
    """A robot of the proof: its URDF, feet, standing posture, sway and PD gains."""

    path: str                       # under example-robot-data's robots/
    feet: tuple                     # Foot
    posture: dict                   # joint -> rad (others 0)
    amplitude: tuple                # trunk's (x, y, z) amplitude A (m)
    period: tuple                   # periods of x, y, z (s)
    frequency: float = 10.0         # of the PD, critically damped (Hz)


def robots_dir() -> str:
    """Return example-robot-data's ``robots`` folder."""
    return os.path.join(sysconfig.get_paths()['purelib'], 'cmeel.prefix', 'share',
                        'example-robot-data', 'robots')


def _solo12() -> Setup:
    legs = ('FL', 'FR', 'HL', 'HR')
    posture = {}
    for leg in legs:
        sign = 1.0 if leg[0] == 'F' else -1.0
        posture[f'{leg}_HFE'], posture[f'{leg}_KFE'] = 0.8 * sign, -1.6 * sign
    feet = tuple(Foot(sd.Contact(f'{leg}_FOOT', mu=MU), (0.002,)) for leg in legs)
    return Setup('solo_description/robots/solo12.urdf', feet, posture, (0.0, 0.03, -0.03),
                 (1.0, 1.6, 1.2))


def _talos() -> Setup:
    posture = {'torso_2_joint': 0.006761}
    for side, s in (('left', 1.0), ('right', -1.0)):
        posture.update({f'leg_{side}_3_joint': -0.411354, f'leg_{side}_4_joint': 0.859395,
                        f'leg_{side}_5_joint': -0.448041, f'leg_{side}_6_joint': -0.001708,
                        f'arm_{side}_1_joint': 0.25847 * s, f'arm_{side}_2_joint': 0.173046 * s,
                        f'arm_{side}_4_joint': -0.525366, f'arm_{side}_7_joint': 0.1})
    feet = tuple(Foot(sd.Contact(f'{side}_sole_link', kind='surface', mu=MU), (0.1, 0.05))
                 for side in ('left', 'right'))
    return Setup('talos_data/robots/talos_reduced.urdf', feet, posture, (0.0, 0.02, -0.03),
                 (1.0, 2.6, 2.0), 20.0)


ROBOTS = {'solo12': _solo12, 'talos': _talos}


class Stance:
    """The desired motion: trunk sway with the feet fixed, joints by inverse kinematics."""

    def __init__(self, robot: FloatingRobot, setup: Setup) -> None:
        self.robot, self.model = robot, robot.model
        self.contacts = [f.contact for f in robot.feet]
        self.A, self.w = np.array(setup.amplitude), 2 * np.pi / np.array(setup.period)
        joints = np.zeros(self.model.nq - 7)
        for name, value in setup.posture.items():
            joints[robot.joint_names.index(name)] = value
        q = robot.on_floor(joints)
        self.q0 = q
        self.targets = self._poses(q)

    def _poses(self, q: np.ndarray) -> list:
        """Return each contact's ``(R, p)``: its link's orientation and its point (world)."""
        out = []
        for c in self.contacts:
            R, p = self.robot.frame_pose(q, c.link)
            out.append((R, p + R @ c.offset))
        return out

    def base(self, t: float) -> tuple:
        """Return the trunk's position, velocity and acceleration (world) at ``t``."""
        s, c = np.sin(self.w * t), np.cos(self.w * t)
        return (self.q0[:3] + self.A * (1 - c), self.A * self.w * s, self.A * self.w ** 2 * c)

    def joints(self, p: np.ndarray, guess: np.ndarray) -> np.ndarray:
        """Return ``q`` with the trunk at ``p`` and the feet where they stand (Gauss-Newton)."""
        q = guess.copy()
        q[:3] = p
        for _ in range(20):
            e = []
            for c, (Rt, pt), (R, pc) in zip(self.contacts, self.targets, self._poses(q)):
                if c.kind == 'surface':
                    E = Rt @ R.T            # rotation error, as a small rotation vector
                    e.append(0.5 * np.array([E[2, 1] - E[1, 2], E[0, 2] - E[2, 0],
                                             E[1, 0] - E[0, 1]]))
                e.append(pt - pc)
            e = np.concatenate(e)
            if np.abs(e).max() < 1e-12:
                return q
            J = sd.contact_jacobian(self.model, q, self.contacts)[:, 6:]
            q[7:] += np.linalg.lstsq(J, e, rcond=None)[0]
        raise RuntimeError(f'the feet cannot stay where they stand with the trunk at {p} '
                           f'(inverse kinematics: {np.abs(e).max():.3g} m or rad off)')

    def plan(self, seconds: float, dt: float) -> list:
        """Return ``(q_d, v_d, a_d)`` every ``dt`` from 0 to ``seconds``.

        The feet stay still: ``J_c v = 0`` gives the joints' ``q̇``, and ``J_c a + J̇_c v = 0``
        their ``q̈``, with ``J̇_c v`` the central difference of ``J_c`` along ``v``.
        """
        h, nv = 1e-6, self.model.nv
        out, q, v = [], self.q0, np.zeros(nv)
        for k in range(int(round(seconds / dt))):
            p, pd, pdd = self.base(k * dt)
            q = self.joints(p, sd.integrate(self.model, q, v, dt) if k else q)
            v, a = np.zeros(nv), np.zeros(nv)
            v[3:6], a[3:6] = pd, pdd    # no turning: base frame = world axes, v̇_b = p̈
            J = sd.contact_jacobian(self.model, q, self.contacts)
            v[6:] = np.linalg.lstsq(J[:, 6:], -J[:, :6] @ v[:6], rcond=None)[0]
            Jd_v = (sd.contact_jacobian(self.model, sd.integrate(self.model, q, v, h),
                                        self.contacts)
                    - sd.contact_jacobian(self.model, sd.integrate(self.model, q, v, -h),
                                          self.contacts)) @ v / (2 * h)
            a[6:] = np.linalg.lstsq(J[:, 6:], -J[:, :6] @ a[:6] - Jd_v, rcond=None)[0]
            out.append((q, v, a))
        return out


def gains(model: sd.Model, q: np.ndarray, frequency: float) -> tuple:
    """Return ``(Kp, Kd)`` per joint: critically damped at ``frequency``, trunk held.

    Scaled by the inertia each joint moves when the other joints are free and the trunk is
    held, ``m_i = 1 / (M_jj⁻¹)_ii``: ``Kp = ω² m_i``, ``Kd = 2 ω m_i`` (``Kd h / m_i`` =
    0.13 at 10 Hz and 1 ms, well inside the explicit step's bound).
    """
    M = sd.mass_matrix(model, q)[6:, 6:]
    m = 1.0 / np.diag(np.linalg.inv(M))
    w = 2 * np.pi * frequency
    return w * w * m, 2 * w * m


def run(setup: Setup, plan: list, law: str) -> dict:
    """Simulate one law along ``plan``; return its errors and contact forces per step."""
    robot = FloatingRobot(without_mimic(urdf_text(os.path.join(robots_dir(), setup.path))),
                          setup.feet, timestep=TIMESTEP)
    model, contacts = robot.model, [f.contact for f in setup.feet]
    q0, zero = plan[0][0], np.zeros(model.nv)
    robot.set_state(q0)
    mass = float(model.inertia[:, 3, 3].sum())
    kp, kd = gains(model, q0, setup.frequency)

    def control(q_d, v_d, a_d) -> tuple:
        q, v = robot.q, robot.v
        tau = kp * (q_d[7:] - q[7:]) + kd * (v_d[6:] - v[6:])
        if law == LAWS[0]:
            return tau, None
        result = sd.contact_inverse_dynamics(model, q_d, v_d, a_d, contacts, method='qp')
        if result.status != 'solved':
            raise RuntimeError(f'{law}: the QP of the plan is {result.status}')
        return tau + result.tau, np.array([result.forces[c.name][-3:] for c in contacts])

    for _ in range(int(round(SETTLE / TIMESTEP))):     # stand still on the soft floor first
        robot.step(control(q0, zero, zero)[0])
    e_joints, e_base, ours, theirs, momentum = [], [], [], [], []
    for q_d, v_d, a_d in plan:
        q = robot.q
        tau, forces = control(q_d, v_d, a_d)
        if forces is not None:
            ours.append(forces)
        e_joints.append(q_d[7:] - q[7:])
        e_base.append(q_d[:3] - q[:3])
        # linear momentum, world axes: the base rows of M v (base frame) turned by R
        p = sd.generalized_momentum(model, q, robot.v)[0]
        momentum.append(quaternion_matrix(q[3:7]) @ p[3:6])
        robot.step(tau)
        forces = robot.contact_forces()         # those of the step just made, at (q, v)
        theirs.append(np.array([forces[c.name][-3:] for c in contacts]))
    return {'joints': np.array(e_joints), 'base': np.array(e_base), 'ours': np.array(ours),
            'theirs': np.array(theirs), 'momentum': np.array(momentum), 'mass': mass,
            'gravity': robot.m.opt.gravity.copy()}


def rms(x: np.ndarray) -> float:
    """Root mean square of all entries."""
    return float(np.sqrt(np.mean(np.square(x))))


def say(text: str) -> None:
    """Print a progress line on stderr (the figures go to stdout)."""
    print(text, file=sys.stderr, flush=True)


def figures(setup: Setup, seconds: float) -> dict:
    """Run both laws; return the RMS errors and the contact-force comparison."""
    robot = FloatingRobot(without_mimic(urdf_text(os.path.join(robots_dir(), setup.path))),
                          setup.feet, timestep=TIMESTEP)
    say(f'planning {seconds:g} s of sway: inverse kinematics on the feet at every 1 ms step ...')
    plan = Stance(robot, setup).plan(seconds, TIMESTEP)
    runs = {}
    for k, law in enumerate(LAWS, 1):
        say(f'[{k}/{len(LAWS)}] {law}: simulating {seconds + 0.5:g} s at 1 ms'
            + (' (a contact QP every step)' if k == len(LAWS) else '') + ' ...')
        start = time.monotonic()
        runs[law] = run(setup, plan, law)
        say(f'[{k}/{len(LAWS)}] {law}: done in {time.monotonic() - start:.1f} s')
    ff = runs[LAWS[1]]
    mg = ff['mass'] * float(np.linalg.norm(ff['gravity']))
    # the total force of the floor against m (a_com - g): the momentum's rate over each step
    rate = np.diff(ff['momentum'], axis=0) / TIMESTEP
    total = ff['theirs'][:-1].sum(axis=1)
    newton = rate - ff['mass'] * ff['gravity']
    fz_ours, fz_theirs = ff['ours'][:, :, 2], ff['theirs'][:, :, 2]
    out = {
        'rms_joint_error_rad': {law: rms(r['joints']) for law, r in runs.items()},
        'rms_trunk_error_m': {law: rms(r['base']) for law, r in runs.items()},
        'weight_N': mg,
        'total_force_vs_newton_max_N': float(np.abs(total - newton).max()),
        'total_vertical_force_range_N': [float(total[:, 2].min()), float(total[:, 2].max())],
        'foot_vertical_force_rms_difference_N': rms(fz_theirs - fz_ours),
        'foot_vertical_force_max_difference_N': float(np.abs(fz_theirs - fz_ours).max()),
        'foot_vertical_force_mean_N': float(np.mean(fz_ours)),
        'total_force_vs_qp_max_N': float(np.abs(total - ff['ours'][:-1].sum(axis=1)).max()),
    }
    out['foot_vertical_force_rms_relative'] = (out['foot_vertical_force_rms_difference_N']
                                               / out['foot_vertical_force_mean_N'])
    out['foot_vertical_force_max_relative'] = (out['foot_vertical_force_max_difference_N']
                                               / out['foot_vertical_force_mean_N'])
    out['ratio_pd_to_feedforward'] = (out['rms_joint_error_rad'][LAWS[0]]
                                      / out['rms_joint_error_rad'][LAWS[1]])
    return out


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--robot', choices=sorted(ROBOTS), default='solo12',
                        help='robot of example-robot-data (default %(default)s)')
    parser.add_argument('--seconds', type=float, default=3.0,
                        help='simulated seconds of swaying after 0.5 s standing, at most 600 '
                        '(default %(default)s; ~20 s of wall time a simulated second on a '
                        'busy core)')
    parser.add_argument('--json', help='write the figures here')
    args = parser.parse_args(argv)
    if not (np.isfinite(args.seconds) and 0.0 < args.seconds <= 600.0):
        parser.error(f'--seconds must be between 0 and 600, got {args.seconds}')
    if args.json:
        check_output(args.json, 'the JSON of the figures')
    setup = ROBOTS[args.robot]()
    if not os.path.isfile(os.path.join(robots_dir(), setup.path)):
        parser.error(f'{args.robot} of example-robot-data is not at '
                     f'{os.path.join(robots_dir(), setup.path)}: pip install example-robot-data')
    out = figures(setup, args.seconds)
    for law in LAWS:
        print(f'{law:27s} RMS error joints {out["rms_joint_error_rad"][law]:.3e} rad, '
              f'trunk {out["rms_trunk_error_m"][law]:.3e} m')
    print(f'PD alone / PD + feed-forward (joints): {out["ratio_pd_to_feedforward"]:.1f}')
    print(f'weight m g {out["weight_N"]:.2f} N; floor force total, MuJoCo, vertical '
          f'{out["total_vertical_force_range_N"][0]:.2f} .. '
          f'{out["total_vertical_force_range_N"][1]:.2f} N; '
          f'minus m (a_com - g): max {out["total_force_vs_newton_max_N"]:.2e} N')
    print(f'vertical force per foot, MuJoCo minus QP: RMS '
          f'{out["foot_vertical_force_rms_difference_N"]:.3f} N, max '
          f'{out["foot_vertical_force_max_difference_N"]:.3f} N '
          f'(mean per foot {out["foot_vertical_force_mean_N"]:.2f} N: '
          f'{out["foot_vertical_force_rms_relative"]:.2%}, '
          f'{out["foot_vertical_force_max_relative"]:.2%})')
    print(f'floor force total, MuJoCo minus QP: max {out["total_force_vs_qp_max_N"]:.3f} N')
    if args.json:
        write_atomic(args.json, json.dumps(out, indent=2) + '\n', 'the JSON of the figures')
    return out


if __name__ == '__main__':
    main()
