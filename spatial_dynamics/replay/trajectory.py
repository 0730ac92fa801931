# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""``replay trajectory PLAN.yaml`` (or ``BAG --topic T``): a plan's torque against the limits.

Sampled as joint_trajectory_controller's splines at ``--rate`` (:mod:`.splines`), the torque
(RNEA, with ``--friction-model urdf`` the URDF's friction) compared with the URDF effort
limits: trajectory.csv and a plot per plan in ``--out``, exit 1 when a limit is exceeded.
"""

from __future__ import annotations

import os
import sys

from .. import friction_torque, rnea
from ..files import check_output
from ..recordings import bags
from ..recordings.errors import Refused
from ..recordings.ranges import sampling_rate
from ..text import listed, shown
from . import report, splines
from .arguments import add_command, add_threshold, model_of
from .paths import check_matplotlib, check_paths, input_files


def run(args) -> int:
    """``replay trajectory``: check a plan, or a bag's plans, against the effort limits.

    Returns 1 when a limit is exceeded (or a torque is not finite), else 0.
    """
    check_paths(args)
    check_matplotlib(args)
    if not args.topic:
        try:
            trajectories = [splines.from_yaml(args.source)]
        except OSError as err:
            raise Refused(f'{args.source!r}: {err.strerror}') from None
        except ValueError as err:
            raise Refused(str(err)) from None
        labels = [repr(os.path.basename(args.source))]
    else:
        msgs = bags.read_messages(args.source, args.topic, bags.JOINT_TRAJECTORY)
        if not msgs:
            raise Refused(f'no messages on {shown(args.topic)}')
        trajectories = [splines.from_message(m) for m in msgs]
        labels = [f'{shown(args.topic)} #{k}' for k in range(len(msgs))]
    bases = [os.path.join(args.out, 'trajectory' + (f'_{k}' if len(trajectories) > 1 else ''))
             for k in range(len(trajectories))]
    for base in bases:            # the names are known now: checked before any work
        for ext in ('.csv',) + (() if args.no_plots else ('.png',)):
            check_output(base + ext, 'output', input_files(args))
    exceeded = False
    for traj, label, base in zip(trajectories, labels, bases):
        model = model_of(args, args.joints or list(traj.joint_names))
        unknown = [j for j in model.joint_names if j not in traj.joint_names]
        if unknown:
            raise Refused(f'{label}: joint(s) {listed(unknown)} not in the trajectory')
        cols = [traj.joint_names.index(j) for j in model.joint_names]
        t, q, qd, qdd = splines.sample(traj, args.rate)
        q, qd, qdd = q[:, cols], qd[:, cols], qdd[:, cols]
        tau = rnea(model, q, qd, qdd, args.gravity)
        if args.friction_model == 'urdf':
            tau = tau + friction_torque(model, qd, args.threshold)
        limit = model.effort_limit
        rows, over = report.effort_rows(model.joint_names, t, tau, limit)
        exceeded |= over
        print(f'{label}: {len(traj.time)} points, {traj.kind} interpolation, '
              f'{t[-1] - t[0]:.3f} s sampled at {args.rate:g} Hz ({len(t)} samples); '
              'torque = RNEA' + (' + URDF friction' if args.friction_model == 'urdf' else ''))
        if model.locked:
            print('  joints not in the trajectory, locked: ' + ', '.join(
                f'{shown(j, quote=False)}={v:g}' for j, v in model.locked.items()))
        print(report.table(report.EFFORT_HEADER, rows))
        report.write_csv(base + '.csv', ['t'] + [f'tau_{n}' for n in model.joint_names],
                         [t] + [tau[:, j] for j in range(model.nq)], [6] + [4] * model.nq)
        if not args.no_plots:
            report.plot_joints(base + '.png', t, model.joint_names, {'tau': tau},
                               f'{label}: torque along the trajectory (N m or N), limits dashed',
                               limits=limit)
    if exceeded:
        print('error: an effort limit is exceeded (or a torque is not finite)', file=sys.stderr)
        return 1
    return 0


def command(sub) -> None:
    """``replay trajectory PLAN.yaml`` (or ``BAG --topic T``): τ against the effort limits."""
    p = add_command(sub, 'trajectory', run, [],
                    'check a plan, or a bag\'s plans, against effort limits',
                    'Sample a plan (trajectory_msgs/JointTrajectory YAML), or every '
                    'JointTrajectory of --topic in a bag, as joint_trajectory_controller\'s '
                    'splines at --rate; compare the torque with the URDF effort limits '
                    '(exit 1 when one is exceeded); trajectory.csv and a plot in --out.')
    p.add_argument('source', metavar='PLAN.yaml|BAG',
                   help='a trajectory_msgs/JointTrajectory (YAML), or a bag with --topic')
    p.add_argument('--topic', metavar='TOPIC',
                   help='check every JointTrajectory of this topic of the bag')
    p.add_argument('--out', default='replay_out',
                   help='output directory, created (default %(default)s)')
    p.add_argument('--rate', type=sampling_rate, default=1000.0,
                   help='sampling rate, Hz (default %(default)g)')
    p.add_argument('--friction-model', choices=('none', 'urdf'), default='none',
                   help='urdf: add the URDF <dynamics> friction, as the node does '
                   '(default %(default)s)')
    add_threshold(p)
    p.add_argument('--no-plots', action='store_true', help='write no PNG files')
