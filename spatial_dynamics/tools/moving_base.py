# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Proof on the simulator: a UR5 on a base that accelerates and turns, fed forward from an IMU.

    python -m spatial_dynamics.tools.moving_base [--seconds 4] [--json out/moving_base.json]

MuJoCo simulates the UR5 (example-robot-data) with its base on a free joint whose motion is
**prescribed**: at each 1 ms step the base's acceleration is given (it sways ±0.3 m along x
and y and yaws ±0.8 rad, so it accelerates and turns) and the wrench on the base that makes
it so is solved from MuJoCo's own ``M`` and bias (``F_b = M_bb a_b + M_bj q̈_j + c_b`` with
``q̈_j = M_jj⁻¹ (τ - c_j - M_jb a_b)``), so the arm feels the base's motion exactly. An IMU
site on ``base_link`` (offset and tilted) carries MuJoCo's accelerometer and gyro.

The arm tracks ``q_d(t)`` under three laws, with the same low-gain PD (Kp 200 N m/rad,
Kd 20 N m s/rad):

* ``PD alone``: τ = Kp e + Kd ė;
* ``PD + feed-forward, fixed base``: τ += rnea(q_d, q̇_d, q̈_d) as if the base stood still;
* ``PD + feed-forward, IMU base``: τ += rnea(q_d, q̇_d, q̈_d, base=base_from_imu(...)) from
  the last step's accelerometer and gyro readings (ω̇ from the gyro's difference).

Prints the RMS tracking error (rad) of each and their ratios; ``--json`` writes them.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import sysconfig
import time

import numpy as np

import spatial_dynamics as sd
from spatial_dynamics.files import check_output, write_atomic
from spatial_dynamics.sim.mujoco_model import import_mujoco, mujoco_model, urdf_text

LAWS = ('PD alone', 'PD + feed-forward, fixed base', 'PD + feed-forward, IMU base')
KP, KD = 200.0, 20.0
IMU_POSITION = np.array([0.08, -0.05, 0.04])
IMU_ORIENTATION = np.array([0.1, -0.2, 0.05, 0.97]) / np.linalg.norm([0.1, -0.2, 0.05, 0.97])


def ur5_urdf() -> str:
    """Return the path of example-robot-data's UR5 URDF."""
    return os.path.join(sysconfig.get_paths()['purelib'], 'cmeel.prefix', 'share',
                        'example-robot-data', 'robots', 'ur_description', 'urdf',
                        'ur5_robot.urdf')


def base_motion(t: float) -> tuple:
    """Return the base's prescribed position, yaw and their first and second derivatives."""
    w1, w2, w3 = 2 * math.pi * 0.7, 2 * math.pi * 0.5, 2 * math.pi * 0.4
    p = np.array([0.3 * math.sin(w1 * t), 0.3 * math.sin(w2 * t), 0.0])
    pd = np.array([0.3 * w1 * math.cos(w1 * t), 0.3 * w2 * math.cos(w2 * t), 0.0])
    pdd = np.array([-0.3 * w1 ** 2 * math.sin(w1 * t), -0.3 * w2 ** 2 * math.sin(w2 * t), 0.0])
    yaw = 0.8 * math.sin(w3 * t)
    return p, pd, pdd, yaw, 0.8 * w3 * math.cos(w3 * t), -0.8 * w3 ** 2 * math.sin(w3 * t)


def desired(t: float, q0: np.ndarray) -> tuple:
    """Return ``q_d, q̇_d, q̈_d`` at ``t``: each joint swings ±0.4 rad, periods 1.5 to 3 s."""
    w = 2 * math.pi / np.linspace(1.5, 3.0, len(q0))
    return (q0 + 0.4 * np.sin(w * t), 0.4 * w * np.cos(w * t), -0.4 * w ** 2 * np.sin(w * t))


def run(law: str, seconds: float = 4.0, dt: float = 1e-3) -> tuple:
    """Simulate one law; return the RMS tracking error (rad) over all joints after 0.5 s.

    And the largest difference between the base's acceleration in MuJoCo and the prescribed
    one (m/s², rad/s²): the base's motion is what it was asked to be.
    """
    mujoco = import_mujoco()
    path = ur5_urdf()
    model = sd.Model.from_urdf(path)
    m = mujoco_model(urdf_text(path), base='floating',
                     imus={'imu': ('base_link', IMU_POSITION, IMU_ORIENTATION)})
    m.opt.timestep = dt
    d = mujoco.MjData(m)
    names = model.joint_names
    qadr = np.array([m.jnt_qposadr[m.joint(n).id] for n in names])
    vadr = np.array([m.jnt_dofadr[m.joint(n).id] for n in names])
    q0 = np.array([0.0, -1.2, 1.4, -1.0, -1.5, 0.0])
    p, pd, _, yaw, yawd, _ = base_motion(0.0)
    d.qpos[:3], d.qpos[3:7] = p, [math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)]
    d.qvel[:3], d.qvel[3:6] = pd, [0.0, 0.0, yawd]
    d.qpos[qadr] = q0
    d.qvel[vadr] = desired(0.0, q0)[1]
    mujoco.mj_forward(m, d)
    gyro_last = d.sensor('imu_gyro').data.copy()
    M = np.zeros((m.nv, m.nv))
    joints = vadr
    base = np.arange(6)
    errors, slip = [], 0.0
    steps = int(round(seconds / dt))
    for k in range(steps):
        t = k * dt
        mujoco.mj_forward(m, d)     # M, bias and the sensors at this state
        qd_, qdd_, qddd_ = desired(t, q0)
        q, qdot = d.qpos[qadr], d.qvel[vadr]
        tau = KP * (qd_ - q) + KD * (qdd_ - qdot)
        if law == LAWS[1]:
            tau = tau + sd.rnea(model, qd_, qdd_, qddd_)
        elif law == LAWS[2]:
            gyro = d.sensor('imu_gyro').data.copy()
            imu = sd.base_from_imu(model, 'base_link', d.sensor('imu_accelerometer').data,
                                   gyro, (gyro - gyro_last) / dt, IMU_POSITION,
                                   IMU_ORIENTATION)
            gyro_last = gyro
            tau = tau + sd.rnea(model, qd_, qdd_, qddd_, base=imu)
        # the base's prescribed acceleration: world-frame linear, body-frame angular
        a_b = np.r_[base_motion(t)[2], 0.0, 0.0, base_motion(t)[5]]
        mujoco.mj_fullM(m, d, M)
        c = d.qfrc_bias
        qdd_j = np.linalg.solve(M[np.ix_(joints, joints)],
                                tau - c[joints] - M[np.ix_(joints, base)] @ a_b)
        d.qfrc_applied[:] = 0.0
        d.qfrc_applied[base] = M[np.ix_(base, base)] @ a_b + M[np.ix_(base, joints)] @ qdd_j \
            + c[base]
        d.qfrc_applied[joints] = tau
        mujoco.mj_step(m, d)
        if t >= 0.5:
            errors.append(qd_ - q)
        slip = max(slip, float(np.abs(d.qacc[base] - a_b).max()))
    return float(np.sqrt(np.mean(np.square(errors)))), slip


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--seconds', type=float, default=4.0,
                        help='simulated seconds of each run (default %(default)s)')
    parser.add_argument('--json', help='write the RMS errors and ratios here')
    args = parser.parse_args(argv)
    if args.json:
        check_output(args.json, 'the JSON of the errors')
    if not os.path.isfile(ur5_urdf()):
        parser.error(f'the UR5 of example-robot-data is not at {ur5_urdf()}: '
                     'pip install example-robot-data')
    runs = {}
    for k, law in enumerate(LAWS, 1):       # progress on stderr: each run takes seconds
        print(f'[{k}/{len(LAWS)}] {law}: simulating {args.seconds:g} s of the UR5 at 1 ms ...',
              file=sys.stderr, flush=True)
        start = time.monotonic()
        runs[law] = run(law, args.seconds)
        print(f'[{k}/{len(LAWS)}] {law}: done in {time.monotonic() - start:.1f} s',
              file=sys.stderr, flush=True)
    rms = {law: r[0] for law, r in runs.items()}
    out = {'rms_error_rad': rms,
           'base_acceleration_error': max(r[1] for r in runs.values()),
           'ratio_imu_to_pd': rms[LAWS[2]] / rms[LAWS[0]],
           'ratio_imu_to_fixed_base_feedforward': rms[LAWS[2]] / rms[LAWS[1]]}
    for law in LAWS:
        print(f'{law:32s} RMS error {rms[law]:.3e} rad')
    print(f'IMU feed-forward / PD alone:           {out["ratio_imu_to_pd"]:.3f}')
    print(f'IMU feed-forward / fixed-base one:     '
          f'{out["ratio_imu_to_fixed_base_feedforward"]:.3f}')
    if args.json:
        write_atomic(args.json, json.dumps(out, indent=2) + '\n', 'the JSON of the errors')
    return out


if __name__ == '__main__':
    main()
