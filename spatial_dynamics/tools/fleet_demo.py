# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A simulated fleet: robots with different payloads, one daily bag each, one joint wearing.

    python -m spatial_dynamics.tools.fleet_demo OUT [--robots 4] [--days 30] [--seconds 4]
        [--wear-robot 2] [--wear-joint 3] [--onset 12] [--rate 0.05] [--jump 0]

Each robot is the UR5 of example-robot-data carrying its own payload on ``tool0`` (0.5 to
2.5 kg), simulated by MuJoCo with the drives of :mod:`.identify_demo` and tracking, every
day, its own program (two sines per joint) with PD + feed-forward of its URDF (which has the
payload); the effort and velocity carry the identification demonstration's noise. From day
``onset`` on, the Coulomb friction of one joint of one robot rises by ``rate`` (a fraction
of its value) a day, after a jump of ``jump`` at the onset. Written: ``OUT/rNN/robot.urdf``
(the URDF with the robot's payload) and ``OUT/rNN/dayDD`` (rosbag2, sqlite3), the layout
``fleet`` reads.
"""

from __future__ import annotations

import argparse
import os
import sys
from typing import Dict, Optional, Sequence

import numpy as np

import spatial_dynamics as sd
from spatial_dynamics.model import rigid_body_inertia
from spatial_dynamics.recordings import bags
from spatial_dynamics.replay.urdf_writer import corrected_urdf
from .identify_demo import drives, Motion, NOISE_QD, NOISE_TAU, record, ROBOTS
from .startup import example_robot

#: The first day's midnight (UTC), s since the epoch: 2026-10-01.
DAY0 = 1790812800
SUBSTEPS = 5        # controller steps per recorded sample (2.5 kHz)


def simulate(true_text: str, model: sd.Model, motion: Motion, seconds: float,
             friction: np.ndarray) -> Dict[str, np.ndarray]:
    """Track ``motion`` on the true robot; return ``t, q, qd, effort`` at RATE (no noise)."""
    return record(true_text, None, model, motion, seconds, friction, SUBSTEPS)


def friction_of(n: int, robot: int, day: int, wear) -> np.ndarray:
    """Return the true Coulomb friction of ``robot`` on ``day``.

    ``wear``: the robot, the joint, the onset day (0-based), the rise a day (a fraction) and
    optionally a jump at the onset (a fraction: 1.0 doubles the friction from that day on).
    """
    friction = drives(n)[1].copy()
    w_robot, w_joint, onset, rate, *jump = wear
    if robot == w_robot and day >= onset:
        friction[w_joint] *= 1.0 + sum(jump) + rate * (day - onset + 1)
    return friction


def make_fleet(out: str, robots: int = 4, days: int = 30, seconds: float = 4.0,
               wear=(1, 2, 12, 0.05), urdf: Optional[str] = None, seed: int = 1) -> str:
    """Write the fleet under ``out`` (see the module's docstring); return ``out``."""
    urdf = urdf or example_robot(*ROBOTS['ur5'][0])
    if urdf is None:
        raise RuntimeError('example-robot-data is not installed')
    text = open(urdf, 'rb').read()
    model = sd.Model.from_urdf(text.decode())
    names = model.joint_names
    for r in range(robots):
        folder = os.path.join(out, f'r{r + 1:02d}')
        os.makedirs(folder, exist_ok=True)
        mass = 0.5 + 2.0 * r / max(robots - 1, 1)
        payload = rigid_body_inertia('payload', mass, (0.0, 0.02, 0.06),
                                     np.diag((0.004, 0.004, 0.003)) * mass / 1.5)
        truth, _ = corrected_urdf(text, model, {}, {ROBOTS['ur5'][1]: payload})
        with open(os.path.join(folder, 'robot.urdf'), 'wb') as f:
            f.write(truth)
        model = sd.Model.from_urdf(truth.decode())
        motion, runs = Motion(model, seed + 1000 * r), {}
        for d in range(days):
            friction = friction_of(model.nq, r, d, wear)
            if friction.tobytes() not in runs:      # the same program every day
                runs[friction.tobytes()] = simulate(truth.decode(), model, motion, seconds,
                                                    friction)
            clean = runs[friction.tobytes()]
            rng = np.random.default_rng(seed + 1000 * r + d)
            rec = dict(clean, qd=clean['qd'] + rng.normal(0.0, NOISE_QD, clean['qd'].shape),
                       effort=clean['effort'] + rng.normal(0.0, NOISE_TAU,
                                                           clean['effort'].shape))
            t_ns = ((DAY0 + 86400 * d + 3600 * 8) * 10 ** 9
                    + np.round(rec['t'] * 1e9)).astype(np.int64)
            block = bags.encode_joint_states(names, t_ns, rec['q'], rec['qd'], rec['effort'])
            bags.write_bag(os.path.join(folder, f'day{d + 1:02d}'), 'sqlite3',
                           [('/joint_states', bags.JOINT_STATE, t_ns,
                             [x.tobytes() for x in block])])
    return out


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Write the simulated fleet."""
    p = argparse.ArgumentParser(prog='fleet_demo', description=__doc__.split('\n\n')[0])
    p.add_argument('out', help='folder to write (ROBOT/dayDD)')
    p.add_argument('--robots', type=int, default=4,
                   help='robots in the fleet, each with its own payload (default %(default)s)')
    p.add_argument('--days', type=int, default=30,
                   help='days recorded, one bag per robot a day (default %(default)s)')
    p.add_argument('--seconds', type=float, default=4.0,
                   help='length of each bag, s of robot time (default %(default)s)')
    p.add_argument('--wear-robot', type=int, default=2,
                   help='the robot that wears, 1-based (default %(default)s)')
    p.add_argument('--wear-joint', type=int, default=3,
                   help='its joint that wears, 1-based (default %(default)s)')
    p.add_argument('--onset', type=int, default=12,
                   help='first day of wear, 1-based (default %(default)s)')
    p.add_argument('--rate', type=float, default=0.05,
                   help='rise of the Coulomb friction a day, a fraction of its value '
                   '(default %(default)s)')
    p.add_argument('--jump', type=float, default=0.0,
                   help='friction jump at the onset, a fraction of its value (1: doubled; '
                   'default %(default)s)')
    args = p.parse_args(argv)
    make_fleet(args.out, args.robots, args.days, args.seconds,
               (args.wear_robot - 1, args.wear_joint - 1, args.onset - 1, args.rate,
                args.jump))
    print(f'written to {args.out}: {args.robots} robots x {args.days} days')
    return 0


if __name__ == '__main__':
    sys.exit(main())
