# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""What the replay subcommands share on their command line, and how each is run.

The parser class, the options of the model (:func:`add_model_arguments`, built by
:func:`model_of`) and of a recording (:func:`recording_parser`, its moving base), a
subcommand's declaration (:func:`add_command`) and its run (:func:`run`: usage checks, then
refusals as one line and an exit status). The number types and their ranges are
:mod:`spatial_dynamics.recordings.ranges`' (the fleet's manifest shares them); below the
command line, functions take typed arguments.
"""

from __future__ import annotations

import argparse
import functools
import sys
from typing import List, Optional, Sequence

import numpy as np

from .. import effort as effort_model
from ..bounds import MAX_GRAVITY
from ..model import Model
from ..recordings import bags
from ..recordings.errors import one_line, Refused
from ..recordings.loading import load_model
from ..recordings.ranges import gravity_component, locked_item, velocity_threshold, window_s


class Parser(argparse.ArgumentParser):
    """An argument parser whose usage errors may be one line (``one_line=True``).

    The subcommands of ``replay`` are made of this class (argparse makes a subparser of its
    parent's class); ``excite`` says its usage errors in one line on stderr, without the
    usage, as it did as a command of its own.
    """

    def __init__(self, *args, one_line: bool = False, **kwargs) -> None:
        """Make the parser; ``one_line``: a usage error is ``PROG: error: MESSAGE`` alone."""
        super().__init__(*args, **kwargs)
        self.one_line = one_line

    def error(self, message: str):
        """Print the usage error and exit with status 2."""
        if not self.one_line:
            super().error(message)
        self.exit(2, f'{self.prog}: error: {" ".join(message.split())}\n')


def add_model_arguments(p: argparse.ArgumentParser) -> None:
    """Declare the options of the model, the same in every replay command.

    ``--urdf``, ``--joints``/``--locked`` (the model reduction, read by :func:`load_model`)
    and ``--gravity`` (checked by :func:`check_gravity`).
    """
    p.add_argument('--urdf', required=True, help='URDF file (or .xacro)')
    p.add_argument('--joints', nargs='+', metavar='J',
                   help='model reduction: only these joints move (the others are locked)')
    p.add_argument('--locked', nargs='+', metavar='J=V', default=[], type=locked_item,
                   help='value (rad or m) of a joint locked by --joints')
    p.add_argument('--gravity', type=gravity_component, nargs=3, default=(0.0, 0.0, -9.81),
                   metavar=('GX', 'GY', 'GZ'),
                   help='m/s^2 in the base frame (default 0 0 -9.81)')


def model_parser() -> argparse.ArgumentParser:
    """Return a parent parser of the model options (:func:`add_model_arguments`), no help."""
    p = argparse.ArgumentParser(add_help=False)
    add_model_arguments(p)
    return p


def check_model(p: argparse.ArgumentParser, args) -> None:
    """Exit with a usage error of ``p`` when the model options cannot be one model."""
    if args.locked and not args.joints:
        p.error('--locked needs --joints (the joints kept movable)')
    check_gravity(p, args.gravity)


def check_gravity(p: argparse.ArgumentParser, gravity: Sequence[float]) -> None:
    """Exit with a usage error when ``--gravity`` cannot be a mounting."""
    if float(np.linalg.norm(gravity)) > MAX_GRAVITY:
        p.error(f'--gravity: |g| = {np.linalg.norm(gravity):g} m/s^2, more than '
                f'{MAX_GRAVITY:g} (100 g) cannot be a mounting')


def model_of(args, joints: Optional[Sequence[str]] = None) -> Model:
    """Build the model of ``--urdf`` with ``--joints``/``--locked`` (``joints`` instead).

    :class:`~spatial_dynamics.recordings.errors.Refused` when it cannot be built.
    """
    return load_model(args.urdf, joints or args.joints, dict(args.locked))


#: The node's default ``friction_velocity_threshold`` (config/inverse_dynamics.yaml).
NODE_THRESHOLD = 0.01

#: What the exit status says, in every --help.
EXIT_STATUS = ('Exit status: 0 done, 1 refused (or an effort limit exceeded), 2 bad usage, '
               '130 interrupted.')

#: The positional arguments as --help names them.
POSITIONALS = {'bag': 'BAG', 'source': 'PLAN.yaml|BAG', 'plan': 'PLAN.yaml'}


def add_command(sub, name: str, work, parents: List[argparse.ArgumentParser], summary: str,
                description: str) -> argparse.ArgumentParser:
    """Add the subcommand ``name`` that runs ``work(args)`` (:func:`run`); return its parser.

    ``summary`` is its line in ``replay --help``; ``description`` heads its own ``--help``.
    The model options come from one parent parser (:func:`model_parser`), then ``parents``.
    """
    p = sub.add_parser(name, parents=[model_parser()] + parents, help=summary,
                       description=description, epilog=EXIT_STATUS)
    p.set_defaults(run=functools.partial(run, work, p))
    return p


def run(work, p: argparse.ArgumentParser, args) -> int:
    """Check what the parser cannot (usage errors by ``p``), run ``work(args)``.

    Refusals, missing files and a lack of memory are one line on stderr, exit 1;
    Ctrl-C is ``interrupted``, exit 130 (every file is whole or absent, the child ended).
    """
    check_model(p, args)
    check_base_arguments(p, args)
    for dest, value in vars(args).items():      # '' is no path, link, joint or topic
        if value == '' or (isinstance(value, list) and '' in value):
            p.error(POSITIONALS.get(dest, '--' + dest.replace('_', '-')) + ': an empty value')
    try:
        return work(args)
    except (Refused, bags.BagError, bags.MissingDependency, ValueError) as err:
        print(f'error: {one_line(err)}', file=sys.stderr)
    except OSError as err:
        where = f'{err.filename!r}: ' if err.filename else ''
        print(f'error: {where}{err.strerror or one_line(err)}', file=sys.stderr)
    except MemoryError:
        print('error: out of memory (a smaller --rate, a shorter bag or fewer joints?)',
              file=sys.stderr)
    except KeyboardInterrupt:     # Ctrl-C: every file is whole or absent, the child ended
        print('interrupted', file=sys.stderr)
        return 130
    return 1


def recording_parser() -> argparse.ArgumentParser:
    """Return a parent parser of what reads a recording and writes its residual (no help)."""
    p = argparse.ArgumentParser(add_help=False)
    p.add_argument('bag', metavar='BAG', help='rosbag2 directory, or a .db3 / .mcap file')
    p.add_argument('--topic', default='/joint_states',
                   help='sensor_msgs/JointState topic (default %(default)s)')
    p.add_argument('--out', default='replay_out',
                   help='output directory, created (default %(default)s)')
    p.add_argument('--window', type=window_s, default=0.05,
                   help='Savitzky-Golay window, s (default %(default)g)')
    p.add_argument('--order', type=int, choices=range(2, 7), default=3,
                   help='Savitzky-Golay polynomial order (default %(default)d)')
    p.add_argument('--measured-effort', choices=effort_model.MEASURED_EFFORT, default='full',
                   help='what the bag\'s effort is: link-side torque with gravity (full: '
                   'Franka, KUKA) or gravity_compensated (UR); default %(default)s')
    p.add_argument('--residual', choices=('csv', 'npy', 'none'), default='csv',
                   help='per-sample residual file (default %(default)s)')
    p.add_argument('--no-plots', action='store_true', help='write no PNG files')
    p.add_argument('--generic', action='store_true',
                   help='read every message through rosbags (no numpy fast path)')
    p.add_argument('--timings', action='store_true', help='print stage times to stderr')
    add_base_arguments(p)
    return p


def add_base_arguments(p) -> None:
    """Declare ``--base-odometry``/``--base-imu`` (one of them) and their links."""
    g = p.add_argument_group('moving base (a mobile manipulator: the base\'s motion from the '
                             'same bag)')
    g.add_argument('--base-odometry', metavar='TOPIC',
                   help='nav_msgs/Odometry of the base: its twist (differentiated like the '
                   'joints) and orientation (for gravity)')
    g.add_argument('--base-imu', metavar='TOPIC',
                   help='sensor_msgs/Imu on the base: gyro and accelerometer (gravity '
                   'included); instead of --base-odometry')
    g.add_argument('--odometry-link', metavar='LINK',
                   help='the link the odometry\'s twist is of (default: its child_frame_id)')
    g.add_argument('--imu-link', metavar='LINK',
                   help='the link the IMU is at, with its axes (default: its frame_id)')


def check_base_arguments(p, args) -> None:
    """Exit with a usage error for both topics, or a link option without its topic.

    One topic gives the whole motion: the IMU's (gravity in it, the linear velocity, which
    no joint torque depends on, not needed) or the odometry's; both would be two answers.
    """
    if getattr(args, 'base_odometry', None) and getattr(args, 'base_imu', None):
        p.error('--base-odometry and --base-imu: give one (each gives the whole motion of the '
                'base)')
    for link, topic in (('odometry_link', 'base_odometry'), ('imu_link', 'base_imu')):
        if getattr(args, link, None) and not getattr(args, topic, None):
            p.error(f'--{link.replace("_", "-")} needs --{topic.replace("_", "-")}')


def add_threshold(p: argparse.ArgumentParser) -> None:
    """Declare ``--threshold``, the friction velocity threshold (the node's by default)."""
    p.add_argument('--threshold', type=velocity_threshold, default=NODE_THRESHOLD,
                   help='friction velocity threshold, rad/s or m/s (default: the node\'s, '
                   '%(default)g)')
