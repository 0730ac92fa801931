# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""From a recording to a corrected URDF, on a simulated robot whose URDF is wrong.

    python -m spatial_dynamics.tools.identify_demo [--robot ur5|panda] [--seconds 20]
        [--out DIR] [--json FILE] [--seed 1]

The "true" robot is the URDF with every link's mass 20-30 % off (up or down, inertia with
it), every centre of mass moved by ~1.5 cm and a 1.5 kg payload on the tool link, written as
a URDF (:mod:`spatial_dynamics.replay.urdf_writer`) and simulated by MuJoCo
(:class:`~spatial_dynamics.sim.robot.SimulatedRobot`) with drive damping, armature and a
Coulomb friction ``friction·tanh(q̇/0.01)``; the effort recorded is the drive torque plus
0.05 N m of noise, the velocity has 1e-3 rad/s of noise. The controller tracking the motion
is the user's: PD + feed-forward on the original URDF. Then, with the ``replay`` command,
exactly as a user runs it:

a. ``replay excite`` plans the training motion (two periods, four harmonics), followed as
   joint_trajectory_controller interpolates it and recorded; ``--inertias --identify
   --validate HELD --write-urdf`` fits the inertias and drives; the held-out motion (two
   sines per joint, other amplitudes and frequencies) is predicted by the original URDF and
   by the corrected one, and by the true robot's own model (what the recording allows);
b. ``--payload LINK --identify`` on a robot whose only error is the payload: its mass;
c. the closed loop on the held-out motion (the node's control laws, :func:`spatial_dynamics.
   ros.control.answer`, 1 kHz) with the original URDF and with the corrected URDF and drives;
d. a poorly exciting recording (the two base joints only): the warning.

The controller runs at 5 kHz while recording (a torque held over a 1 ms step lags the
recorded state by half a step, a residual larger than the noise); the bags are at 500 Hz.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import io
import json
import os
import sys
import tempfile
from typing import Dict, List, Optional, Sequence

import numpy as np

import spatial_dynamics as sd
from spatial_dynamics import identification, trajectory
from spatial_dynamics.model import rigid_body_inertia
from spatial_dynamics.recordings import bags
from spatial_dynamics.recordings.recording import Reading, recording, Stages
from spatial_dynamics.replay import splines
from spatial_dynamics.replay.__main__ import main as replay
from spatial_dynamics.replay.urdf_writer import corrected_urdf
from spatial_dynamics.ros import control
from spatial_dynamics.sim.robot import SimulatedRobot
from .startup import example_robot

#: name -> (example-robot-data file, payload link, joints kept (None: all))
ROBOTS = {
    'ur5': (('ur_description', 'urdf', 'ur5_robot.urdf'), 'tool0', None),
    'panda': (('panda_description', 'urdf', 'panda.urdf'), 'panda_hand',
              tuple(f'panda_joint{k}' for k in range(1, 8))),
}
RATE = 500.0             # Hz, the bags
SUBSTEPS = 10            # controller steps per recorded sample
NOISE_TAU = 0.05         # N m
NOISE_QD = 1e-3          # rad/s
EPS = 0.01               # rad/s, the friction's smooth sign (the node's default)
PAYLOAD = (1.5, (0.0, 0.02, 0.06), (0.004, 0.004, 0.003))    # kg, m, kg m² (diagonal)


def drives(n: int):
    """Return the true drives: damping (N m s/rad), Coulomb friction (N m), armature."""
    k = np.arange(n)
    return 0.5 + 0.1 * k, 1.0 + 0.2 * k, 0.05 + 0.01 * k


def true_urdf(text: bytes, model: sd.Model, payload_link: str, seed: int,
              links_off: bool = True) -> bytes:
    """Return the URDF of the 'true' robot: links off (unless not ``links_off``), a payload."""
    rng = np.random.default_rng(seed)
    bodies = {}
    for i in range(1, model.NB + 1) if links_off else ():
        m, c, Ic = identification.mass_com_inertia(identification._ten(model.inertia[i]))
        if m <= 0.0:
            continue
        scale = 1.0 + rng.choice((-1.0, 1.0)) * rng.uniform(0.2, 0.3)
        bodies[i] = rigid_body_inertia('true body', scale * m, c + rng.normal(0.0, 0.015, 3),
                                       scale * Ic)
    mass, com, diag = PAYLOAD
    payload = rigid_body_inertia('payload', mass, com, np.diag(diag))
    out, _ = corrected_urdf(text, model, bodies, {payload_link: payload})
    return out


class Motion:
    """Two sines per joint about the middle of its range, from rest-like smooth start."""

    def __init__(self, model: sd.Model, seed: int, only: Optional[Sequence[int]] = None,
                 fraction: float = 0.35) -> None:
        """Draw amplitudes and frequencies; ``only``: the joints that move."""
        rng = np.random.default_rng(seed)
        n = model.nq
        lo, hi = np.asarray(model.lower, float), np.asarray(model.upper, float)
        bounded = np.isfinite(lo) & np.isfinite(hi) & (hi > lo)
        self.q0 = np.where(bounded, 0.5 * (lo + hi), 0.0)
        half = np.where(bounded, 0.5 * (hi - lo), np.pi)
        self.amp = np.minimum(fraction * half, 1.0) * rng.uniform(0.7, 1.0, n) / 1.3
        if only is not None:
            self.amp = np.where(np.isin(np.arange(n), list(only)), self.amp, 0.0)
        self.w1 = 2 * np.pi * rng.uniform(0.15, 0.45, n)
        self.w2 = 2 * np.pi * rng.uniform(1.2, 2.2, n)

    def __call__(self, t: float):
        """Return ``(q, q̇, q̈)`` at ``t``."""
        a, w1, w2 = self.amp, self.w1, self.w2
        q = self.q0 + a * (np.sin(w1 * t) + 0.3 * np.sin(w2 * t))
        qd = a * (w1 * np.cos(w1 * t) + 0.3 * w2 * np.cos(w2 * t))
        qdd = -a * (w1 ** 2 * np.sin(w1 * t) + 0.3 * w2 ** 2 * np.sin(w2 * t))
        return q, qd, qdd


class PlanMotion:
    """A JointTrajectory file as joint_trajectory_controller follows it (its splines)."""

    def __init__(self, path: str, names: Sequence[str]) -> None:
        """Read ``path`` (``replay excite``'s plan) for the joints ``names``."""
        self.traj = splines.from_yaml(path)
        self.cols = [self.traj.joint_names.index(n) for n in names]
        self.c = trajectory.coefficients(self.traj)
        self.duration = float(self.traj.time[-1])
        self._evaluate = trajectory.evaluate

    def __call__(self, t: float):
        """Return ``(q, q̇, q̈)`` at ``t``."""
        q, qd, qdd = self._evaluate(self.traj, t, self.c)
        return q[self.cols], qd[self.cols], qdd[self.cols]


def pd_gains(model: sd.Model, q0: np.ndarray, frequency: float):
    """``(kp, kd)``: a critically damped loop of ``frequency`` Hz on each joint's inertia."""
    w = 2 * np.pi * frequency
    m = 1.0 / np.diag(np.linalg.inv(sd.mass_matrix(model, q0)))
    return m * w * w, 2.0 * m * w


def record(true_text: str, joints, model: sd.Model, motion: Motion, seconds: float,
           friction: np.ndarray, substeps: int = SUBSTEPS) -> Dict[str, np.ndarray]:
    """Track ``motion`` on the true robot with PD + feed-forward of ``model``, noise-free.

    The true robot is ``true_text`` with the drives' damping and armature (:func:`drives`) and
    the Coulomb ``friction`` per joint, stepped ``substeps`` times per recorded sample. Returns
    ``t`` (s), ``q``, ``qd`` and ``effort`` (the drive torque) at RATE.
    """
    damping, _, armature = drives(model.nq)
    robot = SimulatedRobot(true_text, joints=joints, timestep=1.0 / (RATE * substeps),
                           damping=damping, armature=armature)
    q0, qd0, _ = motion(0.0)
    robot.set_state(q0, qd0)
    kp, kd = pd_gains(model, q0, 10.0)
    N = int(seconds * RATE)
    Q, QD, TAU = (np.empty((N, model.nq)) for _ in range(3))
    for i in range(N * substeps):
        qr, qdr, qddr = motion(i / (RATE * substeps))
        q, qd = robot.q, robot.qd
        tau = sd.rnea(model, qr, qdr, qddr) + kp * (qr - q) + kd * (qdr - qd)
        if i % substeps == 0:
            Q[i // substeps], QD[i // substeps], TAU[i // substeps] = q, qd, tau
        robot.step(tau - friction * np.tanh(qd / EPS))
    return {'t': np.arange(N) / RATE, 'q': Q, 'qd': QD, 'effort': TAU}


def simulate(true_text: bytes, joints, user_model: sd.Model, motion: Motion, seconds: float,
             seed: int) -> Dict[str, np.ndarray]:
    """Track ``motion`` on the true robot with PD + feed-forward of the user's model.

    Returns ``t`` (s), ``q``, ``qd`` (noisy) and ``effort`` (drive torque plus noise) at RATE.
    """
    _, friction, _ = drives(user_model.nq)
    data = record(true_text.decode(), joints, user_model, motion, seconds, friction)
    rng = np.random.default_rng(seed)
    QD, TAU = data['qd'], data['effort']
    return {'t': data['t'], 'q': data['q'], 'qd': QD + rng.normal(0.0, NOISE_QD, QD.shape),
            'effort': TAU + rng.normal(0.0, NOISE_TAU, TAU.shape)}


def write_bag(path: str, names: Sequence[str], rec: Dict[str, np.ndarray]) -> str:
    """Write ``rec`` as a /joint_states bag; return its path."""
    t_ns = (1_700_000_000 * 10 ** 9 + np.round(rec['t'] * 1e9)).astype(np.int64)
    block = bags.encode_joint_states(names, t_ns, rec['q'], rec['qd'], rec['effort'])
    bags.write_bag(path, 'sqlite3', [('/joint_states', bags.JOINT_STATE, t_ns,
                                      [r.tobytes() for r in block])])
    return path


def run_replay(argv: List[str]) -> Dict[str, str]:
    """Run ``replay`` in this process; return its exit status, stdout and stderr."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = replay(argv)
    return {'status': status, 'out': out.getvalue(), 'err': err.getvalue()}


def read_validation(path: str) -> Dict[str, Dict[str, float]]:
    """Read validation.csv as {joint: {column: value}}."""
    with open(path) as f:
        return {r['joint']: {k: float(v) for k, v in r.items() if k != 'joint'}
                for r in csv.DictReader(f)}


def armature_of(text: str, names: Sequence[str]) -> np.ndarray:
    """Return the armature of replay's node parameters block (the one set it prints)."""
    line = text.split('# node parameters')[1].split('armature: [')[1].split(']')[0]
    return np.array([float(x) for x in line.split(',')])


def floor(true_text: bytes, joints, urdf: str, bag: str) -> np.ndarray:
    """Return the true robot's own residual RMS on ``bag``, read as ``replay`` reads it.

    The torque of the true model and drives at the states and q̈ the replay derives from the
    recording: what no model can beat (the noise, and what the derivative of a recording
    misses: each drive's friction flips within milliseconds at a reversal, faster than a
    50 ms smoothing window follows).
    """
    true = sd.Model.from_urdf(true_text.decode(), joints=joints)
    data = recording(Reading(), bag, true, Stages())       # replay residual's defaults
    damping, friction, armature = drives(true.nq)
    q, qd, qdd = data['q'], data['qd'], data['qdd']
    tau = (sd.rnea(true, q, qd, qdd) + damping * qd + friction * np.tanh(qd / EPS)
           + armature * qdd)
    return np.sqrt(np.mean((data['effort'] - tau) ** 2, axis=0))


def track(true_text: bytes, joints, model: sd.Model, dynamics: control.Dynamics,
          mode: str, motion: Motion, seconds: float, frequency: float) -> np.ndarray:
    """Return the RMS tracking error per joint of a control law at 1 kHz on the true robot."""
    damping, friction, armature = drives(model.nq)
    robot = SimulatedRobot(true_text.decode(), joints=joints, timestep=1e-3, damping=damping,
                           armature=armature)
    q0, qd0, _ = motion(0.0)
    robot.set_state(q0, qd0)
    if mode == 'computed_torque':
        w = 2 * np.pi * frequency
        kp, kd = np.full(model.nq, w * w), np.full(model.nq, 2 * w)
    else:
        kp, kd = pd_gains(model, q0, frequency)
    gains = control.Gains(kp, kd, np.zeros(model.nq, dtype=bool))
    N = int(seconds * 1000)
    err = np.empty((N, model.nq))
    for i in range(N):
        desired = motion(i * 1e-3)
        q, qd = robot.q, robot.qd
        err[i] = desired[0] - q
        tau, _ = control.answer(dynamics, mode, 'full', desired, (q, qd), gains)
        robot.step(tau - friction * np.tanh(qd / EPS))
    return np.sqrt(np.mean(err ** 2, axis=0))


def prove(robot: str, urdf: str, seconds: float, out: str, seed: int = 1,
          frequency: float = 2.0) -> Dict:
    """Run a-d (module docstring) on ``urdf``; return the figures."""
    _, payload_link, joints = ROBOTS[robot]
    text = open(urdf, 'rb').read()
    model = sd.Model.from_urdf(text.decode(), joints=joints)
    names = model.joint_names
    truth = true_urdf(text, model, payload_link, seed)
    with open(os.path.join(out, 'true.urdf'), 'wb') as f:
        f.write(truth)
    plan = os.path.join(out, 'plan.yaml')
    keep = ['--joints', *joints] if joints else []
    e = run_replay(['excite', '--urdf', urdf, *keep, '--duration', f'{seconds:g}',
                    '--period', f'{seconds / 2:g}', '--harmonics', '4', '--iterations', '40',
                    '--seed', str(seed), '--out', plan])
    if e['status'] != 0:
        raise RuntimeError(f'replay excite failed: {e["err"]}')
    train, held = PlanMotion(plan, names), Motion(model, seed + 100, fraction=0.3)
    train_bag = write_bag(os.path.join(out, 'train'), names,
                          simulate(truth, joints, model, train, train.duration, seed))
    held_bag = write_bag(os.path.join(out, 'held_out'), names,
                         simulate(truth, joints, model, held, seconds / 2, seed + 1))
    corrected = os.path.join(out, 'corrected.urdf')
    a = run_replay(['identify', train_bag, '--urdf', urdf, *keep, '--out',
                    os.path.join(out, 'fit'), '--inertias', '--drives', '--validate', held_bag,
                    '--write-urdf',
                    corrected, '--no-plots', '--residual', 'none'])
    if a['status'] != 0:
        raise RuntimeError(f'replay --inertias failed: {a["err"]}')
    v = read_validation(os.path.join(out, 'fit', 'validation.csv'))
    figures = {'robot': robot, 'joints': list(names), 'seconds': seconds,
               'noise': NOISE_TAU, 'held_out_urdf': [v[n]['held_out_urdf'] for n in names],
               'held_out_corrected': [v[n]['held_out_corrected'] for n in names],
               'held_out_true': floor(truth, joints, urdf, held_bag).tolist(),
               'train_corrected': [v[n]['train_corrected'] for n in names],
               'warnings_on_training': a['err'].count('warning')}

    # b. the payload alone
    payload_only = true_urdf(text, model, payload_link, seed, links_off=False)
    bag = write_bag(os.path.join(out, 'payload'), names,
                    simulate(payload_only, joints, model, held, seconds / 2, seed + 2))
    b = run_replay(['identify', bag, '--urdf', urdf, *keep, '--out',
                    os.path.join(out, 'payload_fit'), '--payload', payload_link, '--drives',
                    '--no-plots', '--residual',
                    'none'])
    if b['status'] != 0:
        raise RuntimeError(f'replay --payload failed: {b["err"]}')
    figures['payload_true'] = PAYLOAD[0]
    figures['payload_identified'] = float(b['out'].split('payload.mass: ')[1].split()[0])

    # c. the closed loop with the original and the corrected URDF
    fixed = sd.Model.from_urdf(open(corrected, encoding='utf-8').read(), joints=joints)
    armature = armature_of(a['out'], names)
    laws = {}
    for mode in ('pd_feedforward', 'computed_torque'):
        for label, dyn in (('urdf', control.Dynamics(model)),
                           ('corrected', control.Dynamics(fixed, armature=armature,
                                                          friction_threshold=EPS))):
            laws[f'{mode}/{label}'] = track(truth, joints, model if label == 'urdf' else fixed,
                                            dyn, mode, held, min(seconds / 2, 6.0),
                                            frequency).tolist()
    figures['tracking_rms'] = laws
    figures['tracking_frequency'] = frequency

    # d. a poorly exciting recording
    poor = Motion(model, seed + 200, only=(0, 1))
    bag = write_bag(os.path.join(out, 'poor'), names,
                    simulate(truth, joints, model, poor, seconds / 2, seed + 3))
    d = run_replay(['identify', bag, '--urdf', urdf, *keep, '--out',
                    os.path.join(out, 'poor_fit'), '--inertias', '--validate', held_bag,
                    '--no-plots', '--residual', 'none'])
    warning = next((line for line in d['err'].splitlines() if line.startswith('warning')), '')
    vp = read_validation(os.path.join(out, 'poor_fit', 'validation.csv'))
    figures['poor_warning'] = warning
    figures['poor_held_out_corrected'] = [vp[n]['held_out_corrected'] for n in names]
    return figures


def report(f: Dict) -> str:
    """Return the figures as text."""
    names = f['joints']
    lines = [f"{f['robot']}: {f['seconds']:g} s of training, held-out motion "
             f"{f['seconds'] / 2:g} s; effort noise {f['noise']} N m",
             'a. held-out torque RMS per joint (N m): original URDF -> corrected URDF '
             '(the true robot\'s own on the same recording)']
    for j, n in enumerate(names):
        lines.append(f"   {n:<22} {f['held_out_urdf'][j]:9.4g} -> "
                     f"{f['held_out_corrected'][j]:.4g} ({f['held_out_true'][j]:.4g})")
    m = f['payload_identified']
    lines.append(f"b. payload: {f['payload_true']:g} kg true, {m:.4g} kg identified "
                 f"({100 * (m / f['payload_true'] - 1):+.2f} %)")
    lines.append(f"c. closed loop on the held-out motion, RMS tracking error over the joints "
                 f"(rad), gains for {f['tracking_frequency']:g} Hz:")
    for mode in ('pd_feedforward', 'computed_torque'):
        u = np.sqrt(np.mean(np.square(f['tracking_rms'][f'{mode}/urdf'])))
        c = np.sqrt(np.mean(np.square(f['tracking_rms'][f'{mode}/corrected'])))
        lines.append(f'   {mode:<16} original {u:.3g}, corrected {c:.3g} ({u / c:.0f}x)')
    lines.append(f"d. poorly exciting recording (two joints move): held-out RMS after the fit "
                 f"up to {max(f['poor_held_out_corrected']):.3g} N m; "
                 + (f['poor_warning'][:160] + '...' if f['poor_warning'] else 'NO WARNING'))
    return '\n'.join(lines)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the demonstration; print the figures (and write them with ``--json``)."""
    p = argparse.ArgumentParser(prog='identify_demo', description=__doc__.split('\n\n')[0])
    p.add_argument('--robot', choices=sorted(ROBOTS), default='ur5',
                   help='robot of example-robot-data (default %(default)s)')
    p.add_argument('--urdf', help='the robot\'s URDF (default: example-robot-data\'s)')
    p.add_argument('--seconds', type=float, default=20.0,
                   help='length of the training motion, s (default %(default)s)')
    p.add_argument('--seed', type=int, default=1,
                   help='seed of the wrong URDF and the noise (default %(default)s)')
    p.add_argument('--out', help='directory for the bags, URDFs and reports (default: a '
                   'temporary one)')
    p.add_argument('--json', help='write the figures to this file')
    args = p.parse_args(argv)
    if not (args.seconds >= 2.0 and np.isfinite(args.seconds)):
        p.error('--seconds: at least 2')
    urdf = args.urdf or example_robot(*ROBOTS[args.robot][0])
    if urdf is None:
        print('error: example-robot-data is not installed (pip install example-robot-data) '
              'and no --urdf given', file=sys.stderr)
        return 1
    try:
        with tempfile.TemporaryDirectory() as tmp:
            out = args.out or tmp
            os.makedirs(out, exist_ok=True)
            figures = prove(args.robot, urdf, args.seconds, out, args.seed)
    except (ImportError, RuntimeError, ValueError, OSError) as err:
        print(f'error: {" ".join(str(err).split())}', file=sys.stderr)
        return 1
    print(report(figures))
    if args.json:
        with open(args.json, 'w') as f:
            json.dump(figures, f, indent=1)
    return 0


if __name__ == '__main__':
    sys.exit(main())
