# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Plan an excitation trajectory for identification and write it for joint_trajectory_controller.

    python -m spatial_dynamics.replay excite --urdf URDF --duration 30 --out plan.yaml
        [--harmonics 5] [--period S] [--margin 0.1] [--velocity-fraction 0.8]
        [--effort-fraction 0.6] [--joints J ...] [--locked J=V ...] [--gravity GX GY GZ]
        [--seed 0] [--rate 10] [--controller joint_trajectory_controller] [--list]
    ros2 run spatial_dynamics replay excite ...

Each joint follows a Fourier series of ``--harmonics`` harmonics of one period, optimised
(:mod:`spatial_dynamics.excitation`) for the condition number of the base regressor within
the joint ranges (less ``--margin``), ``--velocity-fraction`` of the velocity limits and
``--effort-fraction`` of the effort limits, at rest at both ends; the period is repeated to
fill ``--duration``. The plan is a JointTrajectory (one YAML flow mapping: points at
``--rate`` Hz with positions, velocities, accelerations and time_from_start), the same
points in every period. Before it is written it is read back (the reader of
``replay trajectory``), and judged as joint_trajectory_controller's quintic splines
interpolate it: one period sampled at 1 kHz against the URDF's limits (every period is the
same, point for point), and the base parameters it determines and its condition number
from the same splines. Only a plan that keeps the limits and determines what its series
does is written (a temporary file beside ``--out``, then renamed).

The options are checked before any work: each number within its bounds, ``--rate`` high
enough to represent the series (:func:`~spatial_dynamics.excitation.min_rate`), the plan no
longer than a day and within :data:`MAX_PLAN_VALUES`, ``--out`` a file that can be written
and not an input.

Exit status: 0 written (within the limits, determining what the series does), 1 refused
(unreadable URDF, unknown joint, a joint that cannot move, no motion within the limits,
``--out`` not writable or an input) or a plan not written because it exceeds a limit of the
URDF or determines fewer parameters than its series, 2 bad usage.
"""

from __future__ import annotations

import argparse
import functools
import json
import math
import re
import shlex
import sys
from typing import List, Optional, Sequence, Tuple

import numpy as np

from .. import Model, rnea
from ..bounds import MAX_POSITION, MAX_TRAJECTORY_TIME
from ..excitation import (determined, Excitation, excitation, MAX_ITERATIONS,
                          MAX_SEED, min_rate, period_points, POINTS_PER_CYCLE)
from ..files import check_output, load_yaml, write_atomic
from ..trajectory import evaluate, sample, Trajectory, trajectory
from ..recordings.errors import one_line, Refused
from ..recordings.ranges import checked, finite
from ..text import shown
from .arguments import check_model, model_of, model_parser, Parser
from . import report

#: Period (s) aimed at when ``--period`` is not given: the duration split into whole periods
#: of about this length (a 0.1 Hz fundamental, Swevers et al. 1997).
PERIOD = 10.0
#: Longest ``--period`` (s): the check samples one period at :data:`CHECK_RATE` (a million
#: states at most), and its fundamental is 1 mHz.
MAX_PERIOD = 1000.0
#: Rate (Hz) the plan is checked at, as the controller interpolates it; the highest
#: ``--rate`` too (a controller updates at 100 Hz to 1 kHz: closer points are not followed,
#: and the check would step over them).
CHECK_RATE = 1000.0
#: Numbers (positions, velocities, accelerations) a plan carries, at most: it is read back
#: whole before it is written, ~1 kB of memory and ~10 µs a number (10,000 points of 6
#: joints, 17 min at 10 Hz: ~200 MB, ~2 s). The plan is periodic: send it again to run
#: longer.
MAX_PLAN_VALUES = 180_000
#: ``ros2 action send_goal`` takes the goal as one shell argument: Linux caps one at 128 KiB.
MAX_ARGUMENT = 128 * 1024
#: A controller's name (ROS: tokens of letters, digits and _, not starting with a digit).
CONTROLLER_NAME = re.compile(r'/?[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*')


def non_negative(text: str) -> float:
    """Parse a margin, rad or m: ≥ 0, at most MAX_POSITION (argparse type)."""
    x = finite(text)
    if not 0.0 <= x <= MAX_POSITION:
        raise argparse.ArgumentTypeError(f'{shown(text)}: need a number >= 0, at most '
                                         f'{MAX_POSITION:g} (rad or m)')
    return x


def fraction(text: str) -> float:
    """Parse a number in (0, 1] (argparse type)."""
    x = finite(text)
    if not 0.0 < x <= 1.0:
        raise argparse.ArgumentTypeError(f'{shown(text)}: need a number in (0, 1]')
    return x


def controller_name(text: str) -> str:
    """Parse a controller's ROS name (argparse type): it is printed into shell commands."""
    if not CONTROLLER_NAME.fullmatch(text):
        raise argparse.ArgumentTypeError(f'{shown(text)}: need a ROS name (letters, digits, _ and '
                                         '/, not starting with a digit)')
    return text.lstrip('/')


#: The number of harmonics, 1 .. 50 (argparse type).
harmonics = checked(int, lambda k: 1 <= k <= 50, 'a whole number 1 .. 50')
#: The duration, s (argparse type).
duration = checked(float, lambda x: 0.0 < x <= MAX_TRAJECTORY_TIME,
                   f'a number of seconds > 0, at most {MAX_TRAJECTORY_TIME:g} (a day)')
#: The period, s (argparse type).
period_s = checked(float, lambda x: 0.0 < x <= MAX_PERIOD,
                   f'a number of seconds > 0, at most {MAX_PERIOD:g}')
#: Points a second (argparse type).
rate = checked(float, lambda x: 0.0 < x <= CHECK_RATE,
               f'a number of points a second > 0, at most {CHECK_RATE:g}')
#: The optimiser's iterations (argparse type).
iterations = checked(int, lambda k: 1 <= k <= MAX_ITERATIONS,
                     f'a whole number 1 .. {MAX_ITERATIONS:,}')
#: The seed of the start (argparse type).
seed = checked(int, lambda k: 0 <= k <= MAX_SEED, f'a whole number 0 .. {MAX_SEED}')


#: How ``replay excite`` is made: its parser's description, epilog and error style.
PARSER = dict(description=__doc__.split('\n\n')[0],
              formatter_class=argparse.RawDescriptionHelpFormatter, one_line=True,
              epilog='Exit status: 0 written, 1 refused or not written (a limit exceeded, '
              'fewer parameters determined than the series does), 2 bad usage.')


def command(sub) -> None:
    """Register ``replay excite`` with the subparsers ``sub`` of ``replay``."""
    p = sub.add_parser('excite', parents=[model_parser()],
                       help='plan a motion that determines every base parameter',
                       **PARSER)
    add_arguments(p)
    p.set_defaults(run=functools.partial(start, p))


def parser() -> argparse.ArgumentParser:
    """Return the argument parser of ``replay excite`` alone."""
    p = Parser(prog='replay excite', parents=[model_parser()], **PARSER)
    add_arguments(p)
    return p


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Declare the options of ``replay excite`` but the model's (a parent parser's)."""
    p.add_argument('--duration', type=duration, required=True,
                   help='s: the period is repeated to fill it (at least one period)')
    p.add_argument('--out', required=True, metavar='PLAN.yaml',
                   help='the JointTrajectory written (one YAML flow mapping)')
    p.add_argument('--harmonics', type=harmonics, default=5,
                   help='harmonics of the Fourier series (default %(default)d)')
    p.add_argument('--period', type=period_s,
                   help=f's (default: the duration in whole periods of about {PERIOD:g} s)')
    p.add_argument('--margin', type=non_negative, default=0.1,
                   help='rad or m kept from each end of a joint range, at most a quarter of '
                   'the range (default %(default)g); continuous joints: ±pi')
    p.add_argument('--velocity-fraction', type=fraction, default=0.8,
                   help='of the URDF velocity limits (default %(default)g; 1 rad/s or '
                   '0.25 m/s where none)')
    p.add_argument('--effort-fraction', type=fraction, default=0.6,
                   help='of the URDF effort limits, RNEA torque (default %(default)g)')
    p.add_argument('--seed', type=seed, default=0,
                   help=f'of the start, 0 .. {MAX_SEED} (default %(default)d)')
    p.add_argument('--rate', type=rate, default=10.0,
                   help='points per second written (default %(default)g; at least '
                   f'{POINTS_PER_CYCLE} x harmonics / period, at most {CHECK_RATE:g}): the '
                   'controller\'s quintic splines through positions, velocities and '
                   'accelerations follow the series closely; more points make a longer goal')
    p.add_argument('--iterations', type=iterations, default=100,
                   help=f'of the optimiser, at most (default %(default)d, 1 .. '
                   f'{MAX_ITERATIONS:,}): it stops there with the best plan found')
    p.add_argument('--controller', type=controller_name, default='joint_trajectory_controller',
                   help='name in the printed commands (default %(default)s)')
    p.add_argument('--list', action='store_true',
                   help='print every base parameter as its combination of standard ones')


def periods(duration: float, period: Optional[float]) -> Tuple[float, int]:
    """Return ``(period, count)``: ``count`` periods fill ``duration`` (at least one)."""
    if period is None:
        count = max(1, round(duration / PERIOD))
        return duration / count, count
    return period, max(1, math.ceil(duration / period - 1e-9))


def check_size(period: float, count: int, harmonics: int, rate: float, given: bool) -> None:
    """``ValueError`` when the plan's points cannot represent the series or last too long.

    ``given``: whether ``--period`` was (else the period comes from ``--duration``).
    """
    lowest = min_rate(period, harmonics)
    if rate < lowest * (1.0 - 1e-12):
        source = '--period' if given else '--duration in whole periods'
        raise ValueError(f'--rate {rate:g} cannot represent --harmonics {harmonics} of a '
                         f'{period:g} s period ({source}): its highest harmonic is '
                         f'{harmonics / period:.4g} Hz and the controller\'s splines need '
                         f'{POINTS_PER_CYCLE} points a cycle of it, so --rate {lowest:.4g} at '
                         'least (or a longer --period, fewer --harmonics)')
    if period * count > MAX_TRAJECTORY_TIME:
        raise ValueError(f'{count} periods of {period:g} s ({period * count:g} s) are more '
                         f'than a trajectory may last ({MAX_TRAJECTORY_TIME:g} s)')


def check_values(period: float, count: int, rate: float, joints: int) -> None:
    """:class:`Refused` when the plan would carry more than :data:`MAX_PLAN_VALUES` numbers."""
    points = count * period_points(period, rate) + 1
    if points * 3 * joints > MAX_PLAN_VALUES:
        raise Refused(f'{period * count:g} s at {rate:g} Hz is {points:,} points of {joints} '
                      f'joint{"s" if joints > 1 else ""}, more than a plan may carry '
                      f'({MAX_PLAN_VALUES:,} positions, velocities and accelerations; it is '
                      'read back whole before it is '
                      'written): lower --duration or --rate (the plan is periodic: send it '
                      'again to run longer)')


# --------------------------------------------------------------------------------------------
# The plan file

def _number(x: float) -> str:
    """Return ``x`` to 7 significant digits as a YAML float: PyYAML (YAML 1.1) reads it back.

    YAML 1.1 reads a number as a float only with a point in its mantissa and a sign on its
    exponent: ``5e-05`` and ``1e+20`` would be strings, ``3`` an integer. So the point is
    always written (``5.0e-05``, ``1.0e+20``, ``3.0``, ``-0.0``); Python writes the sign.
    """
    if not math.isfinite(x):
        return '.nan' if math.isnan(x) else ('.inf' if x > 0 else '-.inf')
    mantissa, e, exponent = f'{x:.7g}'.partition('e')
    return (mantissa if '.' in mantissa else mantissa + '.0') + e + exponent


def _numbers(values: Sequence[float]) -> str:
    return '[' + ', '.join(_number(x) for x in values) + ']'


def _name(name: str) -> str:
    """Return a joint name as a YAML flow scalar: plain when it can be, else quoted."""
    return name if re.fullmatch(r'[A-Za-z_][A-Za-z0-9_./-]*', name) else json.dumps(name)


def plan_text(joint_names: Sequence[str], points: Sequence[dict]) -> str:
    """Return a JointTrajectory as one YAML flow mapping, numbers to 7 digits.

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


def read_back(text: str, what: str) -> Trajectory:
    """Read a plan's text as ``replay trajectory`` reads its file; :class:`Refused` if not.

    :func:`~spatial_dynamics.files.load_yaml` and
    :func:`~spatial_dynamics.trajectory.trajectory`: what the file will say, not what was
    meant to be written.
    """
    try:
        doc = load_yaml(text, what)
        return trajectory(doc['joint_names'], doc['points'], what=what)
    except (ValueError, TypeError, KeyError) as err:
        raise Refused(f'reading the plan back: {one_line(err)}') from None


# --------------------------------------------------------------------------------------------
# The judgement of the plan as the controller interpolates it

def limit_rows(model: Model, t: np.ndarray, q: np.ndarray, qd: np.ndarray, tau: np.ndarray
               ) -> Tuple[List[list], List[list], bool]:
    """Return the torque table's rows, the motion table's rows and whether a limit is exceeded.

    The torque table is ``replay trajectory``'s (peak |τ|, when, limit, use); the motion
    table holds each joint's range used and peak |q̇| against the URDF's limits (a continuous
    joint has no range, whatever its ``<limit>`` says).
    """
    torque, exceeded = report.effort_rows(model.joint_names, t, tau, model.effort_limit)
    motion = []
    vpeak = np.max(np.abs(qd), axis=0)
    for j, name in enumerate(model.joint_names):
        lo, hi, vmax = model.lower[j], model.upper[j], model.velocity_limit[j]
        ranged = (np.isfinite(lo) and np.isfinite(hi)
                  and model.joint_types.get(name) != 'continuous')
        out = ranged and (q[:, j].min() < lo - 1e-9 or q[:, j].max() > hi + 1e-9)
        has_v = vmax > 0 and np.isfinite(vmax)
        fast = bool(has_v and vpeak[j] > vmax)
        exceeded |= bool(out or fast)
        motion.append([name, f'{q[:, j].min():.4g} .. {q[:, j].max():.4g}',
                       f'{lo:g} .. {hi:g}' if ranged else 'continuous',
                       f'{vpeak[j]:.4g}', f'{vmax:g}' if has_v else '-',
                       f'{100 * vpeak[j] / vmax:.1f} %' if has_v else '-',
                       ' '.join(w for w, bad in (('OUT OF RANGE', out), ('TOO FAST', fast))
                                if bad)])
    return torque, motion, exceeded


def first_period(traj: Trajectory, count: int) -> Tuple[Optional[Trajectory], str]:
    """Return the plan's first period, and '' if every period repeats it; else why not.

    Periodic: ``count · m + 1`` points, point ``k · m + i`` equal to point ``i`` (positions,
    velocities, accelerations), ``k`` periods later, and the last equal to the first. Then
    the controller's splines are the same in every period, and checking one checks all.
    """
    total = len(traj.time) - 1
    if total < 1 or total % count:
        return None, f'{len(traj.time)} points are not {count} periods of the same points'
    m = total // count
    span = traj.time[m] - traj.time[0]
    for name, a in (('positions', traj.positions), ('velocities', traj.velocities),
                    ('accelerations', traj.accelerations)):
        if a is None:
            return None, f'the plan has no {name}'
        pattern = np.vstack([a[:m]] * count + [a[:1]])
        if not np.array_equal(a, pattern):
            k = int(np.flatnonzero((a != pattern).any(axis=1))[0])
            return None, f'its point {k} ({name}) differs from point {k % m} a period before'
    times = traj.time[0] + np.arange(count + 1)[:, None] * span
    starts = traj.time[::m]
    offsets = (traj.time[:-1].reshape(count, m) - starts[:-1, None])
    if not (np.allclose(starts, times[:, 0], rtol=0.0, atol=2e-9)
            and np.allclose(offsets, offsets[0], rtol=0.0, atol=2e-9)):
        return None, 'its periods are not equally long, or their points not at the same times'
    one = Trajectory(traj.joint_names, traj.time[:m + 1], traj.positions[:m + 1],
                     traj.velocities[:m + 1], traj.accelerations[:m + 1])
    return one, ''


def check_plan(traj: Trajectory, count: int, plan: Excitation, model: Model,
               gravity: Sequence[float], what: str) -> List[str]:
    """Judge the plan read back as the controller interpolates it; return what is wrong.

    Prints the limit tables of one period sampled at :data:`CHECK_RATE` (every period is
    the same, :func:`first_period`), then the base parameters the splines determine and
    their condition number, at the samples the series was judged at
    (:attr:`~spatial_dynamics.excitation.Excitation.report_times`). Each entry of the list
    returned is one reason the plan must not be run: a limit of the URDF exceeded, fewer base
    parameters determined than the series does, the points not periodic.
    """
    traj = traj.reordered(model.joint_names)
    one, why = first_period(traj, count)
    if one is None:
        return [f'the plan read back is not periodic: {why}']
    t, q, qd, qdd = sample(one, CHECK_RATE)
    tau = rnea(model, q, qd, qdd, gravity)
    torque, motion, exceeded = limit_rows(model, t, q, qd, tau)
    m = len(one.time) - 1
    print(f'\n{what}: {len(traj.time)} points ({m} a period), {traj.kind} interpolation; one '
          f'period of {t[-1]:.4g} s (all {count} are the same) sampled at {CHECK_RATE:g} Hz '
          f'({len(t)} samples); torque = RNEA')
    print(report.table(report.EFFORT_HEADER, torque))
    print(report.table(['joint', 'range used', 'limits', 'peak |qd|', 'limit', 'use', ''],
                       motion))
    print(f'  at rest at the start and the end of each period: |qd| <= '
          f'{np.abs(qd[[0, -1]]).max():.2g}, |qdd| <= {np.abs(qdd[[0, -1]]).max():.2g}; '
          'peak |qdd| ' + ', '.join(f'{x:.3g}' for x in np.abs(qdd).max(axis=0)))
    rank, cond = determined(model, plan.base, evaluate(one, plan.report_times()), gravity)
    print(f'as the controller interpolates it, the plan determines {rank} of the '
          f'{plan.base.rank} base parameters any motion can (the series: {plan.rank}); '
          f'condition number {cond:.4g} (the series: {plan.cond_after:.4g})')
    wrong = []
    if exceeded:
        wrong.append('the plan exceeds a limit of the URDF (see the tables)')
    if rank < plan.rank:
        wrong.append(f'the plan determines {rank} base parameters, its series {plan.rank}: '
                     'its points do not follow the series (raise --rate)')
    return wrong


# --------------------------------------------------------------------------------------------
# What the plan determines

def structural(plan: Excitation) -> List[str]:
    """Name, by link, the parameters no torque depends on in any motion."""
    by_link = {}
    for name in plan.base.unexcited_names():
        parameter, _, link = name.partition(' of ')
        by_link.setdefault(link, []).append(parameter)
    return [f'{shown(link)}: ' + ('all ten' if len(ps) == 10 else ', '.join(ps))
            for link, ps in by_link.items()]


def print_plan(plan: Excitation, model: Model, count: int, args) -> None:
    """Print the optimisation's outcome and what its series determines."""
    n_std = len(plan.base.names)
    print(f'excitation of {len(model.joint_names)} joints '
          f'({", ".join(map(shown, model.joint_names))}): '
          f'{plan.harmonics} harmonics, period {plan.period:.4g} s x {count} = '
          f'{plan.period * count:.4g} s')
    if model.locked:
        print('  locked: ' + ', '.join(f'{shown(j, quote=False)}={v:g}'
                                       for j, v in model.locked.items()))
    if plan.converged:
        outcome = f'optimised ({plan.iterations} iterations, converged)'
    elif plan.iteration_limit:
        outcome = (f'the best found within {plan.iterations} iterations (--iterations: the '
                   'optimiser had not yet converged; more may lower it a little)')
    else:
        outcome = (f'the best found in {plan.iterations} iterations (the optimiser stopped: '
                   f'{plan.message})')
    print(f'condition number of the base regressor (columns scaled to unit norm): '
          f'{plan.cond_before:.4g} at the start (seed {args.seed}), {plan.cond_after:.4g} '
          f'{outcome}')
    print(f'base parameters: the series determines {plan.rank} of the {plan.base.rank} any '
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
    """Print how to run the plan with joint_trajectory_controller (shell-quoted)."""
    action = (f'ros2 action send_goal /{controller}/follow_joint_trajectory '
              'control_msgs/action/FollowJointTrajectory')
    q0 = plan.evaluate(0.0)[0][0]
    start = ('{trajectory: {joint_names: [' + ', '.join(_name(j) for j in plan.joint_names)
             + '], points: '
             '[{positions: ' + _numbers(q0) + ', time_from_start: {sec: 10}}]}}')
    print('\nto run it (joint_trajectory_controller): the plan\'s first point is at time 0, so '
          'the robot must already be there; move it to that point first, slowly (10 s here; '
          'longer if it is far from it):')
    print(f'  {action} {shlex.quote(start)}')
    print('then record the joint states (ros2 bag record /joint_states) and send the plan:')
    print(f'  {action} "{{trajectory: $(cat {shlex.quote(path)})}}"')
    if size > MAX_ARGUMENT:
        print(f'  note: the plan is {size // 1024} KiB, more than one shell argument carries '
              f'({MAX_ARGUMENT // 1024} KiB): lower --rate, or send it from a script')
    print('the limits are the joints\' only: nothing checks collisions with the robot itself '
          'or its surroundings; try it in simulation first')


def run(args, period: float, count: int) -> int:
    """Plan, judge, write; return the exit status (0 or 1)."""
    model = model_of(args)
    check_values(period, count, args.rate, len(model.joint_names))
    try:
        plan = excitation(model, period, args.harmonics, args.gravity, args.margin,
                          args.velocity_fraction, args.effort_fraction, args.seed,
                          maxiter=args.iterations)
    except ValueError as err:
        raise Refused(str(err)) from None
    print_plan(plan, model, count, args)
    text = plan_text(model.joint_names, plan.to_points(args.rate, count))
    wrong = check_plan(read_back(text, args.out), count, plan, model, args.gravity, args.out)
    if wrong:
        for reason in wrong:
            print(f'error: {reason}', file=sys.stderr)
        print(f'not written: {args.out!r}', file=sys.stderr)
        return 1
    try:
        write_atomic(args.out, text, '--out')
    except ValueError as err:
        raise Refused(str(err)) from None
    print(f'\nwritten: {args.out!r} ({len(text) // 1024} KiB)')
    print_commands(args.out, plan, args.controller, len(text.encode()))
    return 0


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the command; return the exit status (0, 1 or 2)."""
    p = parser()
    return start(p, p.parse_args(argv))


def start(p: argparse.ArgumentParser, args) -> int:
    """Check the options (usage errors by ``p``), plan; return the exit status (0 or 1)."""
    check_model(p, args)
    period, count = periods(args.duration, args.period)
    try:
        check_size(period, count, args.harmonics, args.rate, args.period is not None)
    except ValueError as err:
        p.error(str(err))
    try:
        check_output(args.out, '--out', inputs=[args.urdf])
    except ValueError as err:
        print(f'error: {one_line(err)}', file=sys.stderr)
        return 1
    try:
        return run(args, period, count)
    except Refused as err:
        print(f'error: {one_line(err)}', file=sys.stderr)
    except MemoryError:
        print('error: out of memory (fewer harmonics or joints?)', file=sys.stderr)
    return 1


if __name__ == '__main__':
    sys.exit(main())
