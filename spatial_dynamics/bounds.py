# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""What no real robot's state, command or load reaches: the bounds every input is held to.

Each value that can reach a published number or a written file is checked against one of
these where it enters (a message, a parameter, a trajectory file, a bag), by :func:`beyond`,
so a value that cannot be real is refused with its name instead of flowing into torques of
1e300 N m. The bounds are far above any robot (a position of 1e5 rad is 16,000 turns of a
continuous joint) and far below where float64 arithmetic on them overflows.
"""

from __future__ import annotations

from typing import Optional, Sequence

import numpy as np

from .text import shown

#: |q| of a joint, rad or m: 1e5 rad is 16,000 turns of a continuous joint.
MAX_POSITION = 1e5
#: |q̇| of a joint, rad/s or m/s: 1e4 rad/s is 95,000 rpm.
MAX_VELOCITY = 1e4
#: |q̈| of a joint, rad/s² or m/s²: 1e6 rad/s² takes a joint to 95,000 rpm in 10 ms.
MAX_ACCELERATION = 1e6
#: |τ| of a joint, N m or N: a command, a measured effort.
MAX_EFFORT = 1e6
#: Each component of a wrench [n; f], N m and N: external wrenches, a pushed simulated robot.
MAX_WRENCH = 1e6
#: |g|, m/s² (100 g): gravity of a mounting.
MAX_GRAVITY = 1e3
#: Largest bound a user may set on a base's linear acceleration, m/s² (100 g: beyond a crash).
MAX_BASE_LINEAR_ACCELERATION = 1e3
#: Largest bound a user may set on a base's angular acceleration, rad/s².
MAX_BASE_ANGULAR_ACCELERATION = 1e4
#: Default bounds of a base's acceleration (``base_input.max_*_acceleration``): 50 m/s² (5 g)
#: and 100 rad/s² are above a mobile base, a ship or a trotting or jumping quadruped.
BASE_LINEAR_ACCELERATION = 50.0
BASE_ANGULAR_ACCELERATION = 100.0
#: Shortest stamp interval anything divides by, s: no sensor publishes faster than 100 kHz;
#: a smaller difference of stamps is a clock's artefact, not a measurement.
MIN_STAMP_INTERVAL = 1e-5
#: |ω| an IMU reports, rad/s: 100 rad/s (5,700 deg/s) is above the full scale of every common
#: MEMS gyro (±2000 deg/s = 35 rad/s typical, ±4000 deg/s the largest).
MAX_IMU_RATE = 100.0
#: |specific force| an IMU reports, m/s²: 4,000 m/s² (400 g) is above high-g accelerometers;
#: common ones saturate at ±16 g.
MAX_IMU_SPECIFIC_FORCE = 4e3
#: The friction velocity threshold ε of tanh(q̇ / ε), rad/s or m/s: its smallest and largest.
FRICTION_THRESHOLD_RANGE = (1e-9, 1e3)
#: time_from_start of a trajectory point, s (a day).
MAX_TRAJECTORY_TIME = 86400.0
#: Points of one trajectory.
MAX_TRAJECTORY_POINTS = 1_000_000
#: Largest serialized plan (``desired_trajectory``) the node converts, bytes: 128 per point
#: of the most points a plan may have (a 6-joint plan with positions and velocities is ~120
#: bytes a point); a larger one is refused before anything is built from it.
MAX_PLAN_BYTES = 128 * MAX_TRAJECTORY_POINTS
#: Samples computed from one trajectory (``replay --trajectory``): (duration × rate + 1).
MAX_SAMPLES = 10_000_000

#: The bound of each joint-space quantity, by field name (messages and trajectory files).
JOINT_BOUNDS = {
    'position': (MAX_POSITION, 'rad or m'), 'positions': (MAX_POSITION, 'rad or m'),
    'velocity': (MAX_VELOCITY, 'rad/s or m/s'), 'velocities': (MAX_VELOCITY, 'rad/s or m/s'),
    'acceleration': (MAX_ACCELERATION, 'rad/s² or m/s²'),
    'accelerations': (MAX_ACCELERATION, 'rad/s² or m/s²'),
    'effort': (MAX_EFFORT, 'N m or N'), 'efforts': (MAX_EFFORT, 'N m or N'),
}


def beyond(values, bound: float) -> np.ndarray:
    """Return the indices of ``values`` that are not finite or exceed ``bound`` in magnitude."""
    a = np.asarray(values, dtype=np.float64).ravel()
    with np.errstate(invalid='ignore'):
        return np.flatnonzero(~(np.abs(a) <= bound))


def check_bounded(what: str, values, bound: float, unit: str,
                  names: Optional[Sequence[str]] = None) -> Optional[str]:
    """Why ``values`` cannot be real (the first offending one named), or None when they can."""
    bad = beyond(values, bound)
    if not len(bad):
        return None
    i = int(bad[0])
    value = float(np.asarray(values, dtype=np.float64).ravel()[i])
    where = f'{shown(names[i])}' if names is not None and i < len(names) else f'index {i}'
    if not np.isfinite(value):
        return f'{what} is not finite for {where} ({value})'
    return f'{what} of {where} is {value:g}, beyond ±{bound:g} {unit}'
