# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The old spellings of ``replay`` (one command, every job an option), kept for one release.

    replay BAG ...                          -> replay residual BAG ...
    replay BAG --identify ...               -> replay identify BAG ...
    replay BAG --payload L [--identify]     -> replay identify BAG --payload L [--drives]
    replay BAG --inertias [L ...] [--identify]
                                            -> replay identify BAG --inertias [L ...] [--drives]
    replay --urdf U --trajectory F          -> replay trajectory F --urdf U
    replay --urdf U --trajectory F --annotate OUT
                                            -> replay annotate F --urdf U --out OUT
    replay BAG --urdf U --trajectory-topic T
                                            -> replay trajectory BAG --topic T --urdf U

:func:`new_spelling` parses an old command line as before (the same options, the same usage
errors), says the new spelling on stderr in one line, and returns it: the new command runs it,
so the old spelling writes the same files and exits with the same status. An option the old
command took and ignored for the job (``--rate`` of a bag run, ``--out`` with ``--annotate``)
is left out. This module goes with the old spellings.
"""

from __future__ import annotations

import argparse
import shlex
import sys
from typing import Dict, List, Sequence

from .. import effort as effort_model
from .arguments import (add_model_arguments, check_gravity, effort_tolerance, sampling_rate,
                        velocity_threshold, window_s)

#: The node's default ``friction_velocity_threshold`` (config/inverse_dynamics.yaml).
NODE_THRESHOLD = 0.01


def parser() -> argparse.ArgumentParser:
    """Return the argument parser of the old spellings (every option of every job)."""
    p = argparse.ArgumentParser(prog='replay', description=__doc__.split('\n\n')[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog='Exit status: 0 done, 1 refused (or an effort limit '
                                'exceeded), 2 bad usage, 130 interrupted.')
    p.add_argument('bag', nargs='?', help='rosbag2 directory, or a .db3 / .mcap file')
    add_model_arguments(p)
    p.add_argument('--topic', default='/joint_states', help='sensor_msgs/JointState topic')
    p.add_argument('--out', default='replay_out', help='output directory (created)')
    p.add_argument('--identify', action='store_true',
                   help='fit damping, friction and armature per joint to the residual')
    p.add_argument('--payload', metavar='LINK',
                   help="identify a rigid payload on LINK (mass, centre of mass, inertia) "
                        "against the URDF without it; with --identify, jointly with each "
                        "joint's damping, friction and armature")
    p.add_argument('--inertias', nargs='*', metavar='LINK',
                   help='identify the inertial parameters of these links (default: every '
                   'moving one), physically consistent, regularised toward the URDF; with '
                   '--identify jointly with the drives')
    p.add_argument('--also', nargs='+', metavar='BAG', default=[],
                   help='more recordings to fit on (--identify, --payload, --inertias) with '
                   'BAG; the files written are of BAG')
    p.add_argument('--validate', metavar='BAG',
                   help='a held-out recording: the residual with the URDF and with what was '
                   'identified (--inertias, --payload, --identify)')
    p.add_argument('--write-urdf', metavar='OUT.urdf',
                   help='write the URDF with only the identified <inertial> and <dynamics> '
                   'elements replaced')
    p.add_argument('--threshold', type=velocity_threshold, default=NODE_THRESHOLD,
                   help='friction velocity threshold, rad/s or m/s (default: the node\'s, '
                   '%(default)g)')
    p.add_argument('--window', type=window_s, default=0.05,
                   help='Savitzky-Golay window, s (default %(default)g)')
    p.add_argument('--order', type=int, choices=range(2, 7), default=3,
                   help='Savitzky-Golay polynomial order (default %(default)d)')
    p.add_argument('--residual', choices=('csv', 'npy', 'none'), default='csv',
                   help='per-sample residual file (default %(default)s)')
    p.add_argument('--no-plots', action='store_true', help='write no PNG files')
    p.add_argument('--trajectory', metavar='FILE.yaml',
                   help='check a trajectory_msgs/JointTrajectory (YAML) against effort limits')
    p.add_argument('--trajectory-topic', metavar='TOPIC',
                   help='check every JointTrajectory of this topic of BAG')
    p.add_argument('--rate', type=sampling_rate, default=1000.0,
                   help='trajectory sampling rate, Hz (default %(default)g)')
    p.add_argument('--friction-model', choices=('none', 'urdf'), default='none',
                   help='trajectory check: add the URDF <dynamics> friction (as the node)')
    p.add_argument('--measured-effort', choices=effort_model.MEASURED_EFFORT, default='full',
                   help='what the bag\'s effort is: link-side torque with gravity (full: '
                   'Franka, KUKA) or gravity_compensated (UR); default %(default)s')
    p.add_argument('--annotate', metavar='OUT.yaml',
                   help='with --trajectory: write it with effort filled for '
                   'joint_trajectory_controller (resampled to --tolerance)')
    p.add_argument('--tolerance', type=effort_tolerance, default=0.1,
                   help='--annotate: |JTC\'s linear interpolation of effort - model torque|, '
                   'N m (default %(default)g)')
    p.add_argument('--output', choices=effort_model.OUTPUTS, default='full',
                   help='--annotate: the torque written (default %(default)s)')
    p.add_argument('--generic', action='store_true',
                   help='read every message through rosbags (no numpy fast path)')
    p.add_argument('--timings', action='store_true', help='print stage times to stderr')
    return p


def check(p: argparse.ArgumentParser, args) -> None:
    """Check the options as the old command did, with its texts (usage errors, exit 2)."""
    if args.trajectory and args.trajectory_topic:
        p.error('--trajectory and --trajectory-topic exclude each other')
    if not args.trajectory and not args.bag:
        p.error('a BAG is needed (or --trajectory FILE.yaml)')
    if args.locked and not args.joints:
        p.error('--locked needs --joints (the joints kept movable)')
    if args.annotate and not args.trajectory:
        p.error('--annotate needs --trajectory FILE.yaml')
    identifies = args.inertias is not None or args.payload or args.identify
    if (args.validate or args.write_urdf or args.also) and not identifies:
        p.error('--validate, --write-urdf and --also need something identified: --inertias, '
                '--payload or --identify')
    if args.inertias is not None and args.payload:
        p.error('--inertias and --payload exclude each other (--inertias fits the payload '
                'with the link that holds it)')
    if identifies and (args.trajectory or args.trajectory_topic):
        p.error('--inertias, --payload and --identify work on a recording, not with '
                '--trajectory or --trajectory-topic')
    check_gravity(p, args.gravity)


def job(args) -> tuple:
    """Return ``(subcommand, positional, {old dest: new dest or None (left out)})``."""
    if args.annotate:
        return 'annotate', args.trajectory, {'annotate': 'out', 'out': None, 'trajectory': None}
    if args.trajectory or args.trajectory_topic:
        return 'trajectory', args.trajectory or args.bag, {
            'trajectory_topic': 'topic', 'topic': None, 'trajectory': None, 'bag': None}
    if args.inertias is not None or args.payload or args.identify:
        jointly = args.inertias is not None or args.payload
        return 'identify', args.bag, {'identify': 'drives' if jointly else None, 'bag': None}
    return 'residual', args.bag, {'bag': None}


def text(value) -> str:
    """Return an option's value as it is typed (``J=V`` for a locked joint)."""
    if isinstance(value, tuple):
        return f'{value[0]}={value[1]!r}'
    return repr(value) if isinstance(value, float) else str(value)


def new_spelling(argv: Sequence[str], commands: Dict[str, argparse.ArgumentParser]
                 ) -> List[str]:
    """Parse an old command line; say its new spelling on stderr; return it.

    ``commands`` are the subcommands' parsers (by name). The new command line has the old
    one's values of every option its subcommand takes, in that subcommand's order.
    """
    p = parser()
    args = p.parse_args(argv)
    check(p, args)
    name, positional, renamed = job(args)
    given = {}
    for dest, value in vars(args).items():
        default = p.get_default(dest)
        if renamed.get(dest, dest) is None or value is None or value is False or \
                value == default or (isinstance(default, tuple) and list(default) == value):
            continue
        given[renamed.get(dest, dest)] = value
    new = [name, positional]
    for action in commands[name]._actions:
        if action.option_strings and action.dest in given:
            value = given[action.dest]
            new += [action.option_strings[0]] + (
                [] if value is True else [text(v) for v in value]
                if isinstance(value, (list, tuple)) and action.nargs is not None
                else [text(value)])
    print(f'replay: deprecated spelling, kept for one release; use: replay {shlex.join(new)}',
          file=sys.stderr)
    return new
