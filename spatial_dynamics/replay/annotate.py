# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""``replay annotate plan.yaml --out out.yaml``: the plan with ``effort`` filled.

The points are resampled by :func:`spatial_dynamics.effort.annotate` so that
joint_trajectory_controller's linear interpolation of effort stays within ``--tolerance`` of
the model torque (``--output`` part), and written in the message's YAML form, readable by
``replay trajectory`` again and publishable with ``ros2 topic pub``. The efforts are checked
against the URDF effort limits as ``replay trajectory`` checks its torques (``EXCEEDED``, exit 1);
a tolerance the 1 ms steps cannot meet is said, exit 1. The output path is checked before
any work (not an input, a writable regular file) and written atomically
(:mod:`spatial_dynamics.files`); nothing else is written.
"""

from __future__ import annotations

import sys

from .. import effort, files
from ..recordings.ranges import effort_tolerance
from ..text import listed
from . import report, splines
from .arguments import add_command, model_of


def run(args) -> int:
    """``replay annotate``: annotate ``args.plan`` into ``args.out``; print what was done.

    Returns 0, or 1 when an effort exceeds its URDF limit or the tolerance is not met (the
    file is written all the same, to be looked at). Errors are ``ValueError`` naming the file
    (exit 1 in the command), raised before anything is written.
    """
    files.check_output(args.out, '--out', (args.plan, args.urdf))
    traj = splines.from_yaml(args.plan)
    model = model_of(args, args.joints or list(traj.joint_names))
    missing = [j for j in model.joint_names if j not in traj.joint_names]
    if missing:
        raise ValueError(f'{args.plan!r}: joint(s) {listed(missing)} not in the '
                         'trajectory')
    extra = [j for j in traj.joint_names if j not in model.joint_names]
    if extra:
        raise ValueError(f'{args.plan!r}: joint(s) {listed(extra)} are not movable '
                         'joints of the model (locked or unknown)')
    try:
        result = effort.annotate(model, traj, args.tolerance, args.output, args.gravity)
    except effort.AnnotationError as err:
        raise ValueError(f'{args.plan!r}: not annotated: {err}') from None
    doc = effort.message_dict(result.trajectory, result.effort)
    import yaml       # optional (the replay extra): the command starts without it
    files.write_atomic(args.out, lambda f: f.write(yaml.safe_dump(
        doc, default_flow_style=None, sort_keys=False, width=1 << 16).encode('utf-8')),
        '--out')
    met = result.max_error <= args.tolerance
    print(f'{args.plan!r}: {len(traj.time)} points ({traj.kind}) -> {args.out!r}: '
          f'{len(result.trajectory.time)} points with effort ({args.output}); JTC\'s linear '
          f'interpolation of effort within {result.max_error:.3g} of the model torque '
          f'(tolerance {args.tolerance:g} N m{"" if met else ", NOT met"})')
    if result.jumps:
        print(f'  the model torque jumps at {len(result.jumps)} point(s) (velocity or '
              f'acceleration not continuous there, or not at rest at the end: {traj.kind} '
              f'interpolation), first at {result.jumps[0][1]:.6g} s; in the last '
              f'{effort.MIN_STEP * 1e3:g} to {2 * effort.MIN_STEP * 1e3:g} ms before each the '
              'interpolated effort cannot follow it')
    rows, exceeded = report.effort_rows(model.joint_names, result.trajectory.time,
                                        result.effort, model.effort_limit)
    print(report.table(report.EFFORT_HEADER, rows))
    status = 0
    if exceeded:
        print('error: an effort limit is exceeded (or an effort is not finite) in the annotated '
              'plan', file=sys.stderr)
        status = 1
    if not met:
        print(f'error: tolerance {args.tolerance:g} N m NOT met: JTC\'s interpolation misses '
              f'the model torque by {result.max_error:.3g} N m at the shortest steps '
              f'({effort.MIN_STEP * 1e3:g} ms)', file=sys.stderr)
        status = 1
    return status


def command(sub) -> None:
    """``replay annotate PLAN.yaml --out OUT.yaml``: the plan with effort for JTC."""
    p = add_command(sub, 'annotate', run, [],
                    'fill a plan\'s effort for joint_trajectory_controller',
                    'Write the plan with effort filled for joint_trajectory_controller, '
                    'resampled so that its linear interpolation of effort stays within '
                    '--tolerance of the model torque; the efforts checked against the URDF '
                    'limits (exit 1). Only --out is written.')
    p.add_argument('plan', metavar='PLAN.yaml', help='a trajectory_msgs/JointTrajectory (YAML)')
    p.add_argument('--out', required=True, metavar='OUT.yaml', help='the annotated plan')
    p.add_argument('--tolerance', type=effort_tolerance, default=0.1,
                   help='|JTC\'s linear interpolation of effort - model torque|, N m (default '
                   '%(default)g)')
    p.add_argument('--output', choices=effort.OUTPUTS, default='full',
                   help='the torque written (default %(default)s)')
