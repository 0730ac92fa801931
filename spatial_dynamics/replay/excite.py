# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Plan an excitation trajectory for identification and write it for joint_trajectory_controller.

    python -m spatial_dynamics.replay.excite --urdf URDF --duration 30 --out plan.yaml
        [--harmonics 5] [--period S] [--margin 0.1] [--velocity-fraction 0.8]
        [--effort-fraction 0.6] [--joints J ...] [--locked J=V ...] [--gravity GX GY GZ]
        [--seed 0] [--rate 10] [--controller joint_trajectory_controller] [--list]
    ros2 run spatial_dynamics replay excite ...

Each joint follows a Fourier series of ``--harmonics`` harmonics of one period, optimised
(:mod:`spatial_dynamics.excitation`) for the condition number of the base regressor within
the joint ranges (less ``--margin``), ``--velocity-fraction`` of the velocity limits and
``--effort-fraction`` of the effort limits, at rest at both ends; the period is repeated to
fill ``--duration``. The plan is written as a JointTrajectory (one YAML flow mapping: points
at ``--rate`` Hz with positions, velocities, accelerations and time_from_start), read back,
sampled like joint_trajectory_controller's quintic splines at 1 kHz and checked against the
URDF's limits.

Exit status: 0 written and within the limits, 1 refused (unreadable URDF, unknown joint, no
motion within the limits, the file cannot be written) or a limit of the URDF exceeded by the
plan as the controller interpolates it, 2 bad usage.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import sys
from typing import List, Optional, Sequence, Tuple

import numpy as np

from .. import Model, rnea
from ..bounds import MAX_TRAJECTORY_POINTS, MAX_TRAJECTORY_TIME
from ..excitation import Excitation, excitation
from .arguments import (add_model_arguments, check_gravity, checked, finite, load_model, one_line,
                        positive, Refused)
from . import report, splines

#: Period (s) aimed at when ``--period`` is not given: the duration split into whole periods
#: of about this length (a 0.1 Hz fundamental, Swevers et al. 1997).
PERIOD = 10.0
#: Rate (Hz) the written plan is checked at, as the controller interpolates it.
CHECK_RATE = 1000.0
#: ``ros2 action send_goal`` takes the goal as one shell argument: Linux caps one at 128 KiB.
MAX_ARGUMENT = 128 * 1024


class _Parser(argparse.ArgumentParser):
    """An argument parser whose usage errors are one line on stderr (exit status 2)."""

    def error(self, message: str):
        """Print ``replay excite: error: MESSAGE`` and exit with status 2."""
        self.exit(2, f'{self.prog}: error: {" ".join(message.split())}\n')


def non_negative(text: str) -> float:
    """Parse a finite number ≥ 0 (argparse type)."""
    x = finite(text)
    if not x >= 0.0:
        raise argparse.ArgumentTypeError(f'{text!r}: need a finite number >= 0')
    return x


def fraction(text: str) -> float:
    """Parse a number in (0, 1] (argparse type)."""
    x = finite(text)
    if not 0.0 < x <= 1.0:
        raise argparse.ArgumentTypeError(f'{text!r}: need a number in (0, 1]')
    return x


#: The number of harmonics, 1 .. 50 (argparse type).
harmonics = checked(int, lambda k: 1 <= k <= 50, 'a whole number 1 .. 50')


def parser() -> argparse.ArgumentParser:
    """Return the command's argument parser."""
    p = _Parser(prog='replay excite', description=__doc__.split('\n\n')[0],
                formatter_class=argparse.RawDescriptionHelpFormatter,
                epilog='Exit status: 0 written and within the limits, 1 refused or a limit '
                'exceeded, 2 bad usage.')
    add_model_arguments(p)
    p.add_argument('--duration', type=positive, required=True,
                   help='s: the period is repeated to fill it (at least one period)')
    p.add_argument('--out', required=True, metavar='PLAN.yaml',
                   help='the JointTrajectory written (one YAML flow mapping)')
    p.add_argument('--harmonics', type=harmonics, default=5,
                   help='harmonics of the Fourier series (default %(default)d)')
    p.add_argument('--period', type=positive,
                   help=f's (default: the duration in whole periods of about {PERIOD:g} s)')
    p.add_argument('--margin', type=non_negative, default=0.1,
                   help='rad or m kept from each end of a joint range, at most a quarter of '
                   'the range (default %(default)g); continuous joints: ±pi')
    p.add_argument('--velocity-fraction', type=fraction, default=0.8,
                   help='of the URDF velocity limits (default %(default)g; 1 rad/s or '
                   '0.25 m/s where none)')
    p.add_argument('--effort-fraction', type=fraction, default=0.6,
                   help='of the URDF effort limits, RNEA torque (default %(default)g)')
    p.add_argument('--seed', type=int, default=0, help='of the start (default %(default)d)')
    p.add_argument('--rate', type=positive, default=10.0,
                   help='points per second written (default %(default)g: the controller\'s '
                   'quintic splines through positions, velocities and accelerations follow '
                   'the series closely; more points make a longer goal)')
    p.add_argument('--iterations', type=int, default=100,
                   help='of the optimiser, at most (default %(default)d)')
    p.add_argument('--controller', default='joint_trajectory_controller',
                   help='name in the printed commands (default %(default)s)')
    p.add_argument('--list', action='store_true',
                   help='print every base parameter as its combination of standard ones')
    return p


def periods(duration: float, period: Optional[float]) -> Tuple[float, int]:
    """Return ``(period, count)``: ``count`` periods fill ``duration`` (at least one)."""
    if period is None:
        count = max(1, round(duration / PERIOD))
        return duration / count, count
    return period, max(1, math.ceil(duration / period - 1e-9))


# --------------------------------------------------------------------------------------------
# The plan file

def _number(x: float) -> str:
    return '0.0' if abs(x) < 1e-12 else f'{x:.7g}'


def _numbers(values: Sequence[float]) -> str:
    return '[' + ', '.join(_number(x) for x in values) + ']'


def _name(name: str) -> str:
    """Return a joint name as a YAML flow scalar: plain when it can be, else quoted."""
    return name if re.fullmatch(r'[A-Za-z_][A-Za-z0-9_./-]*', name) else json.dumps(name)


def plan_text(joint_names: Sequence[str], points: Sequence[dict]) -> str:
    """Return a JointTrajectory as one YAML flow mapping, positions to 7 digits.

    One mapping, so it can stand inside another: ``"{trajectory: $(cat PLAN.yaml)}"`` is
    the goal of ``ros2 action send_goal`` (compact: the goal is one shell argument).
    """
    lines = []
    for p in points:
        tfs = p['time_from_start']
        fields = [f'{f}: {_numbers(p[f])}' for f in ('positions', 'velocities',
                                                     'accelerations') if f in p]
        fields.append(f'time_from_start: {{sec: {tfs["sec"]}, nanosec: {tfs["nanosec"]}}}')
        lines.append(' {' + ', '.join(fields) + '}')
    return ('{joint_names: [' + ', '.join(_name(j) for j in joint_names) + '],\npoints: [\n'
            + ',\n'.join(lines) + ']}\n')


def write_plan(path: str, text: str) -> None:
    """Write ``text`` to ``path``; :class:`Refused` naming it when it cannot be written."""
    try:
        with open(path, 'w', encoding='utf-8') as f:
            f.write(text)
    except OSError as err:
        raise Refused(f'--out {path}: cannot write it ({err.strerror})') from None


# --------------------------------------------------------------------------------------------
# The check of the plan as the controller interpolates it

def limit_rows(model: Model, t: np.ndarray, q: np.ndarray, qd: np.ndarray, tau: np.ndarray
               ) -> Tuple[List[list], List[list], bool]:
    """Return the torque table's rows, the motion table's rows and whether a limit is exceeded.

    The torque table is ``replay --trajectory``'s (peak |τ|, when, limit, use); the motion
    table holds each joint's range used and peak |q̇| against the URDF's limits.
    """
    torque, exceeded = report.effort_rows(model.joint_names, t, tau, model.effort_limit)
    motion = []
    vpeak = np.max(np.abs(qd), axis=0)
    for j, name in enumerate(model.joint_names):
        lo, hi, vmax = model.lower[j], model.upper[j], model.velocity_limit[j]
        out = q[:, j].min() < lo - 1e-9 or q[:, j].max() > hi + 1e-9
        has_v = vmax > 0 and np.isfinite(vmax)
        fast = bool(has_v and vpeak[j] > vmax)
        exceeded |= bool(out or fast)
        motion.append([name, f'{q[:, j].min():.4g} .. {q[:, j].max():.4g}',
                       f'{lo:g} .. {hi:g}' if np.isfinite(lo) else 'continuous',
                       f'{vpeak[j]:.4g}', f'{vmax:g}' if has_v else '-',
                       f'{100 * vpeak[j] / vmax:.1f} %' if has_v else '-',
                       ' '.join(w for w, bad in (('OUT OF RANGE', out), ('TOO FAST', fast))
                                if bad)])
    return torque, motion, exceeded


def check_plan(path: str, model: Model, gravity: Sequence[float]) -> bool:
    """Read the plan back, sample it like the controller, print the tables; True if exceeded."""
    try:
        traj = splines.from_yaml(path)
    except OSError as err:
        raise Refused(f'{path}: {err.strerror}') from None
    except ValueError as err:
        raise Refused(f'reading the plan back: {err}') from None
    traj = traj.reordered(model.joint_names)
    t, q, qd, qdd = splines.sample(traj, CHECK_RATE)
    tau = rnea(model, q, qd, qdd, gravity)
    torque, motion, exceeded = limit_rows(model, t, q, qd, tau)
    print(f'\n{path}: {len(traj.time)} points, {traj.kind} interpolation, {t[-1]:.3f} s '
          f'sampled at {CHECK_RATE:g} Hz ({len(t)} samples); torque = RNEA')
    print(report.table(report.EFFORT_HEADER, torque))
    print(report.table(['joint', 'range used', 'limits', 'peak |qd|', 'limit', 'use', ''],
                       motion))
    print(f'  at rest at the start and the end: |qd| <= {np.abs(qd[[0, -1]]).max():.2g}, '
          f'|qdd| <= {np.abs(qdd[[0, -1]]).max():.2g}; peak |qdd| '
          + ', '.join(f'{x:.3g}' for x in np.abs(qdd).max(axis=0)))
    return exceeded


# --------------------------------------------------------------------------------------------
# What the plan determines

def structural(plan: Excitation) -> List[str]:
    """Name, by link, the parameters no torque depends on in any motion."""
    by_link = {}
    for name in plan.base.unexcited_names():
        parameter, _, link = name.partition(' of ')
        by_link.setdefault(link, []).append(parameter)
    return [f'{link}: ' + ('all ten' if len(ps) == 10 else ', '.join(ps))
            for link, ps in by_link.items()]


def print_plan(plan: Excitation, model: Model, count: int, args) -> None:
    """Print the optimisation's outcome and what the plan determines."""
    n_std = len(plan.base.names)
    print(f'excitation of {len(model.joint_names)} joints ({", ".join(model.joint_names)}): '
          f'{plan.harmonics} harmonics, period {plan.period:.4g} s x {count} = '
          f'{plan.period * count:.4g} s')
    if model.locked:
        print('  locked: ' + ', '.join(f'{j}={v:g}' for j, v in model.locked.items()))
    print(f'condition number of the base regressor (columns scaled to unit norm): '
          f'{plan.cond_before:.4g} at the start (seed {args.seed}), {plan.cond_after:.4g} '
          f'optimised ({plan.iterations} iterations: {plan.message})')
    print(f'base parameters: the plan determines {plan.rank} of the {plan.base.rank} any '
          f'motion can (of {n_std} standard parameters)')
    if plan.rank < plan.base.rank:
        print(f'  warning: {plan.base.rank - plan.rank} base parameter(s) not excited: try '
              'more harmonics, another --seed or wider limits')
    unexcited = len(plan.base.unexcited)
    print(f'  no motion determines {unexcited} standard parameter(s) (no torque depends on '
          'them)' + (':' if unexcited else ''))
    for line in structural(plan):
        print(f'    {line}')
    combined = n_std - plan.base.rank - unexcited
    print(f'  {combined} more enter only in combinations: each base parameter is a standard '
          'one plus those it absorbs' + (':' if args.list else ' (--list names them)'))
    if args.list:
        for k in range(plan.base.rank):
            print(f'    {k + 1:3d}. {plan.base.describe(k)}')


def print_commands(path: str, plan: Excitation, controller: str, size: int) -> None:
    """Print how to run the plan with joint_trajectory_controller."""
    action = (f'ros2 action send_goal /{controller}/follow_joint_trajectory '
              'control_msgs/action/FollowJointTrajectory')
    q0 = plan.evaluate(0.0)[0][0]
    start = ('{trajectory: {joint_names: [' + ', '.join(_name(j) for j in plan.joint_names)
             + '], points: '
             '[{positions: ' + _numbers(q0) + ', time_from_start: {sec: 10}}]}}')
    print('\nto run it (joint_trajectory_controller): the plan\'s first point is at time 0, so '
          'the robot must already be there; move it to that point first, slowly (10 s here; '
          'longer if it is far from it):')
    print(f'  {action} "{start}"')
    print('then record the joint states (ros2 bag record /joint_states) and send the plan:')
    print(f'  {action} "{{trajectory: $(cat {path})}}"')
    if size > MAX_ARGUMENT:
        print(f'  note: the plan is {size // 1024} KiB, more than one shell argument carries '
              f'({MAX_ARGUMENT // 1024} KiB): lower --rate, or send it from a script')
    print('the limits are the joints\' only: nothing checks collisions with the robot itself '
          'or its surroundings; try it in simulation first')


def run(args) -> int:
    """Plan, write, check; return the exit status (0 or 1)."""
    model = load_model(args)
    period, count = periods(args.duration, args.period)
    if period * count > MAX_TRAJECTORY_TIME:
        raise Refused(f'{period * count:g} s is more than a trajectory may last '
                      f'({MAX_TRAJECTORY_TIME:g} s)')
    if period * count * args.rate + 1 > MAX_TRAJECTORY_POINTS:
        raise Refused(f'{period * count:g} s at {args.rate:g} Hz is more than '
                      f'{MAX_TRAJECTORY_POINTS:,} points: lower --rate')
    try:
        plan = excitation(model, period, args.harmonics, args.gravity, args.margin,
                          args.velocity_fraction, args.effort_fraction, args.seed,
                          maxiter=args.iterations)
    except ValueError as err:
        raise Refused(str(err)) from None
    print_plan(plan, model, count, args)
    text = plan_text(model.joint_names, plan.to_points(args.rate, count))
    write_plan(args.out, text)
    print(f'\nwritten: {args.out} ({len(text) // 1024} KiB)')
    exceeded = check_plan(args.out, model, args.gravity)
    print_commands(args.out, plan, args.controller, len(text.encode()))
    if exceeded:
        print('error: the plan exceeds a limit of the URDF (see the tables)', file=sys.stderr)
        return 1
    return 0


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the command; return the exit status (0, 1 or 2)."""
    p = parser()
    args = p.parse_args(argv)
    if args.locked and not args.joints:
        p.error('--locked needs --joints (the joints moved)')
    if args.iterations < 1:
        p.error(f'--iterations: need a whole number >= 1, got {args.iterations}')
    check_gravity(p, args.gravity)
    if os.path.isdir(args.out):
        p.error(f'--out {args.out}: is a directory; name the file to write')
    try:
        return run(args)
    except Refused as err:
        print(f'error: {one_line(err)}', file=sys.stderr)
    except MemoryError:
        print('error: out of memory (fewer harmonics or joints?)', file=sys.stderr)
    return 1


if __name__ == '__main__':
    sys.exit(main())
