# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""``replay --trajectory plan.yaml --annotate out.yaml``: the plan with ``effort`` filled.

The points are resampled by :func:`spatial_dynamics.effort.annotate` so that
joint_trajectory_controller's linear interpolation of effort stays within ``--tolerance`` of
the model torque (``--output`` part), and written in the message's YAML form, readable by
``--trajectory`` again and publishable with ``ros2 topic pub``.
"""

from __future__ import annotations

import yaml

from .. import effort
from . import splines


def run(args, load_model) -> int:
    """Annotate ``args.trajectory`` into ``args.annotate``; print what was done; return 0.

    ``load_model(args, joints)`` builds the model (the command's own, reduction included).
    Errors are ``ValueError`` naming the file (exit 1 in the command).
    """
    traj = splines.from_yaml(args.trajectory)
    model = load_model(args, args.joints or list(traj.joint_names))
    missing = [j for j in model.joint_names if j not in traj.joint_names]
    if missing:
        raise ValueError(f'{args.trajectory}: joint(s) {", ".join(missing)} not in the '
                         'trajectory')
    extra = [j for j in traj.joint_names if j not in model.joint_names]
    if extra:
        raise ValueError(f'{args.trajectory}: joint(s) {", ".join(extra)} are not movable '
                         'joints of the model (locked or unknown)')
    result = effort.annotate(model, traj, args.tolerance, args.output, args.gravity)
    doc = effort.message_dict(result.trajectory, result.effort)
    try:
        with open(args.annotate, 'w', encoding='utf-8') as f:
            yaml.safe_dump(doc, f, default_flow_style=None, sort_keys=False, width=1 << 16)
    except OSError as err:
        raise ValueError(f'{args.annotate}: {err.strerror}') from None
    print(f'{args.trajectory}: {len(traj.time)} points ({traj.kind}) -> {args.annotate}: '
          f'{len(result.trajectory.time)} points with effort ({args.output}); JTC\'s linear '
          f'interpolation of effort within {result.max_error:.3g} of the model torque '
          f'(tolerance {args.tolerance:g} N m)')
    if result.jumps:
        print(f'  the model torque jumps at {len(result.jumps)} point(s) (velocity or '
              f'acceleration not continuous there: {traj.kind} interpolation), first at '
              f'{result.jumps[0][1]:.6g} s; in the last {effort.MIN_STEP * 1e3:g} to '
              f'{2 * effort.MIN_STEP * 1e3:g} ms before each the interpolated effort cannot '
              'follow it')
    return 0
