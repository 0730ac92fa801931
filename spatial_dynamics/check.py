# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Check a robot description for dynamics: what the model computes with, and every warning.

urdfdom's ``check_urdf`` checks the syntax; this command (``spatial_dynamics_check``: a name of
its own, as urdfdom's is installed beside it) prints what inverse dynamics will use: the joints
in ``q`` order (type, axis, limits, the mimic joints that follow each one), the bodies
after fixed joints are lumped and base links pruned, the total mass, and every
:class:`URDFWarning` of the model (inconsistent inertias and the like, loaded as written).

    python -m spatial_dynamics.check ROBOT.urdf [--strict] [--joints J ...] [--locked J=V ...]
    spatial_dynamics_check ROBOT.urdf        (installed: lib/spatial_dynamics/, or ros2 run)

Exit status: 0 when the model loads, 1 when it is refused (or, with ``--strict``, when it has
warnings), 2 for bad usage.
"""

import argparse
import math
import os
import sys
import textwrap
from typing import Dict, List, Optional, Sequence
import warnings

import numpy as np

from . import mass_matrix, Model, URDFWarning
from .joints import FREE_FLYER, KIND_NAMES
from .recordings.loading import read_description
from .recordings.ranges import locked_item
from .text import shown

WIDTH = 99


def num(x: float) -> str:
    """Format a number with ``%g``; '-' for ``nan`` (a value the URDF does not give)."""
    return '-' if math.isnan(x) else f'{x + 0.0:g}'    # + 0.0: no '-0'


def wrapped(label: str, names: Sequence[str], indent: int) -> List[str]:
    """Wrap ``label name, name, ...`` to the terminal width."""
    return textwrap.wrap(label + ', '.join(names), WIDTH, initial_indent=' ' * indent,
                         subsequent_indent=' ' * (indent + len(label)), break_on_hyphens=False)


def table(header: Sequence[str], rows: Sequence[tuple], left: Sequence[int]) -> List[str]:
    """Align rows of cells (each row ``(cells, notes)``) in columns; notes follow their row.

    Columns are as wide as their widest cell; those in ``left`` are left-aligned.
    """
    cells = [header] + [r[0] for r in rows]
    widths = [max(len(c[k]) for c in cells) for k in range(len(header))]

    def line(row) -> str:
        return '  ' + '  '.join(c.ljust(w) if k in left else c.rjust(w)
                                for k, (c, w) in enumerate(zip(row, widths))).rstrip()

    lines = [line(header)]
    for row, notes in rows:
        lines.append(line(row))
        lines += notes
    return lines


def joint_lines(model: Model, types: Dict[str, str]) -> List[str]:
    """List the joints of ``q`` in order: type, axis, limits, the mimic joints they drive."""
    body = {name: i for i, name in enumerate(model.body_joints)}
    followers: Dict[int, List[int]] = {}       # q index -> the mimic bodies it drives
    for m in range(1, model.NB + 1):
        followers.setdefault(int(model.qidx[m]), []).append(m)
    rows = []
    for k, name in enumerate(model.joint_names):
        i = body[name]
        kv = int(model.vidx[i])         # limits are per velocity coordinate
        limits = (model.lower[kv], model.upper[kv], model.velocity_limit[kv],
                  model.effort_limit[kv])
        mimics = []
        for m in followers.get(k, ()):
            if model.body_joints[m] != name:
                off = float(model.qoff[m])
                mimics.append(f'{"":7}mimic: {model.body_joints[m]} = {num(model.qmul[m])} * '
                              f'{name} {"-" if off < 0 else "+"} {num(abs(off))}')
        rows.append(([str(k), name, types.get(name, KIND_NAMES[int(model.jtype[i])]),
                      ' '.join(num(a) for a in model.axis[i])] + [num(x) for x in limits],
                     mimics))
    return table(('q', 'name', 'type', 'axis', 'lower', 'upper', 'velocity', 'effort'), rows,
                 left=(1, 2, 3))


def body_lines(model: Model) -> List[str]:
    """List the bodies after lumping and pruning: link, joint, parent, mass, links lumped in."""
    links: List[List[str]] = [[] for _ in range(model.NB + 1)]
    for link, frame in model.frames.items():
        if link != model.body_names[frame.body]:
            links[frame.body].append(link)
    rows = []
    for i in range(model.NB + 1):
        label = 'pruned (fixed to the base): ' if i == 0 else 'lumped: '
        base = '(the world)' if model.floating else '(fixed base)'
        rows.append(([str(i), model.body_names[i], model.body_joints[i] or base,
                      '-' if i == 0 else str(int(model.parent[i])), num(model.inertia[i][3, 3])],
                     wrapped(label, links[i], 8) if links[i] else []))
    return table(('body', 'link', 'joint', 'parent', 'mass (kg)'), rows, left=(1, 2))


#: An eigenvalue of ``M`` at most this fraction of its largest counts as zero (rank lost).
#: Rounding leaves ~1e-16 of the largest; the robots of example-robot-data whose every joint
#: moves some inertia have 1e-8 (Tiago) or more, those with a joint that moves none
#: (iCub, Romeo) 1e-17 or less.
RANK_TOLERANCE = 1e-12
#: Largest ``nv`` whose ``M`` is checked for rank (an eigendecomposition is O(nv³)).
RANK_CHECK_LIMIT = 1000
#: Seeded random configurations ``M``'s rank is checked at besides the neutral one.
RANK_SAMPLES = 2


def velocity_names(model: Model) -> List[str]:
    """Name each velocity coordinate: its joint, or ``'root_joint ωz'`` for a free-flyer's."""
    names = [''] * model.nv
    joints = set(model.joint_names)
    for i in range(1, model.NB + 1):
        joint, kv = model.body_joints[i], int(model.vidx[i])
        if joint not in joints:         # a mimic joint: its source's coordinate
            continue
        if int(model.jtype[i]) == FREE_FLYER:
            names[kv:kv + 6] = [f'{joint} {c}' for c in ('ωx', 'ωy', 'ωz', 'vx', 'vy', 'vz')]
        else:
            names[kv] = joint
    return names


def configurations(model: Model, samples: int = RANK_SAMPLES) -> List[np.ndarray]:
    """Return the neutral ``q`` and ``samples`` seeded random ones within the joints' limits.

    A joint without finite limits is drawn in ``[-π, π]``, a free-flyer's orientation
    uniformly (its position stays 0: ``M`` does not depend on it).
    """
    rng = np.random.default_rng(0)
    neutral = np.zeros(model.nq)
    for _, k in model.free_flyers:
        neutral[k + 6] = 1.0
    out = [neutral]
    joints = set(model.joint_names)
    for _ in range(samples):
        q = neutral.copy()
        for i in range(1, model.NB + 1):
            if model.body_joints[i] not in joints:
                continue
            k, kv = int(model.qidx[i]), int(model.vidx[i])
            if int(model.jtype[i]) == FREE_FLYER:
                u = rng.normal(size=4)
                q[k + 3:k + 7] = u / np.linalg.norm(u)
                continue
            lo, hi = model.lower[kv], model.upper[kv]
            finite = np.isfinite(lo) and np.isfinite(hi) and lo <= hi
            q[k] = rng.uniform(lo, hi) if finite else rng.uniform(-np.pi, np.pi)
        out.append(q)
    return out


def singular_mass_matrix(model: Model) -> List[str]:
    """Return a warning when ``model``'s mass matrix ``M`` is singular, else nothing.

    ``M`` (RBDA §6.2) at the neutral configuration and at :data:`RANK_SAMPLES` seeded random
    ones (:func:`configurations`) is singular when its smallest eigenvalue is at most
    :data:`RANK_TOLERANCE` of its largest: some motion ``q̇`` moves no inertia (a joint whose
    links have no inertia about its axis; a floating tree without mass, or whose base yaw
    and a joint turn the same inertia), so no torque accelerates it and forward dynamics
    (the simulator), the contact split and a floating base's dynamics have no answer;
    inverse dynamics still does. The warning names the coordinates of the lost motions
    (their weight in the null space of ``M``, the largest first). A model of more than
    :data:`RANK_CHECK_LIMIT` coordinates is not judged, and says so.
    """
    if model.nv == 0:
        return []
    if model.nv > RANK_CHECK_LIMIT:
        return [f'the rank of the mass matrix M was not checked: {model.nv} coordinates, '
                f'above the {RANK_CHECK_LIMIT} an eigendecomposition is run for']
    qs = configurations(model)
    where = ['the neutral configuration'] + ['a seeded random configuration'] * RANK_SAMPLES
    for q, at in zip(qs, where):
        M = mass_matrix(model, q)
        lam, V = np.linalg.eigh(0.5 * (M + M.T))
        if lam[-1] <= 0.0:
            if model.floating:
                return ['the tree has no mass: on the free-flyer its mass matrix M is '
                        'singular (no wrench moves the base); give the links <inertial>, or '
                        "load it with base='fixed'"]
            return ['no joint moves any mass: the mass matrix M is zero (no torque '
                    'accelerates a joint); give the links <inertial>']
        lost = lam <= RANK_TOLERANCE * lam[-1]
        if lost.any():
            return [lost_motions(model, lam, V[:, lost], at)]
    return []


def lost_motions(model: Model, lam: np.ndarray, null: np.ndarray, at: str) -> str:
    """Describe a singular ``M``: its rank and the coordinates of the motions it loses."""
    names = velocity_names(model)
    weight = np.sum(null ** 2, axis=1)      # diagonal of the null space's projector
    order = [int(k) for k in np.argsort(-weight, kind='stable') if weight[k] >= 1e-2]
    shown = ', '.join(names[k] for k in order[:8]) + (
        f' and {len(order) - 8} more' if len(order) > 8 else '')
    if null.shape[1] == 1:
        v = null[:, 0] * np.sign(null[order[0], 0])
        motion = ' + '.join(f'{v[k]:.2g} {names[k]}' for k in order[:8]).replace('+ -', '- ')
        lost = f'the motion {motion} moves no inertia, so no torque accelerates it'
    else:
        lost = (f'{null.shape[1]} motions of {shown} move no inertia, so no torque '
                'accelerates them')
    return (f'the mass matrix M is singular at {at} (rank {model.nv - null.shape[1]} of '
            f'{model.nv}; eigenvalues {lam[0]:.3g} to {lam[-1]:.3g}, below '
            f'{RANK_TOLERANCE:g} of the largest counted as zero): {lost} and forward '
            'dynamics and a contact split have no answer; give '
            'the links these joints move <inertial> with inertia about their axes')


def warnings_of(model: Model) -> List[str]:
    """Return every warning of the check: the model's and a singular mass matrix's."""
    return list(model.warnings) + singular_mass_matrix(model)


def report(model: Model, types: Dict[str, str], said: Optional[List[str]] = None) -> str:
    """Return the whole check as text: robot, joints, bodies, mass and warnings.

    ``said``: the warnings (:func:`warnings_of`) when they were computed already.
    """
    base = (f'floating base (link {shown(model.body_names[1])} on the free-flyer joint '
            f'{shown(model.joint_names[0])}: q has {model.nq} numbers, position and quaternion '
            f'x y z w first, q̇ {model.nv}, the base twist [ω; v] first), '
            if model.floating else '')
    dof = f'{model.nv} dof (the base 6, the joints {model.nv - 6})' if model.floating else \
        f'{model.nq} dof'
    lines = [f'robot {shown(model.name)}: {base}{dof}, {model.NB} moving bodies, '
             f'{len(model.frames)} links', '',
             f'joints in q order ({len(model.joint_names)}); limits in rad or m, /s, N m or N, '
             "'-' when not given:"]
    lines += joint_lines(model, types)
    if model.locked:
        lines += wrapped('locked by model reduction: ',
                         [f'{j}={num(model.locked[j])}' for j in types if j in model.locked],
                         2)
    lines += ['', f'bodies after lumping fixed joints ({model.NB} moving + '
              f'{"the world" if model.floating else "the fixed base"}):']
    lines += body_lines(model)
    mass = model.inertia[:, 3, 3]
    if model.floating:      # body 0 is the world: body 1 (the root link) moves on the base
        share = (f'{num(float(mass[1]))} kg on the root link {shown(model.body_names[1])} (on the '
                 f'free-flyer), {num(float(np.sum(mass[2:])))} kg on the links beyond it')
    else:
        share = (f'{num(float(mass[0]))} kg on the fixed base, '
                 f'{num(float(np.sum(mass[1:])))} kg moving')
    lines += ['', f'total mass: {num(float(np.sum(mass)))} kg ({share})', '']
    if said is None:
        said = warnings_of(model)
    if said:
        lines.append(f'warnings ({len(said)}):')
        for w in said:
            lines += textwrap.wrap(w, WIDTH, initial_indent='  - ', subsequent_indent='    ')
    else:
        lines.append('no warnings')
    return '\n'.join(lines)


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Print the check of a robot description; return the exit status (0, 1 or 2)."""
    parser = argparse.ArgumentParser(prog='spatial_dynamics_check',
                                     description=__doc__.split('\n\n')[0])
    parser.add_argument('urdf', help='URDF file (or .xacro, expanded when xacro is installed)')
    parser.add_argument('--strict', action='store_true',
                        help='exit 1 when the model has warnings (all are still printed)')
    parser.add_argument('--joints', nargs='+', metavar='J',
                        help='model reduction: keep only these joints, in this order; the '
                        'others are locked at 0 or at their --locked value')
    parser.add_argument('--locked', nargs='+', metavar='J=V', default=[], type=locked_item,
                        help='value (rad or m) of a joint locked by --joints')
    parser.add_argument('--base', choices=('fixed', 'floating'), default='fixed',
                        help="'floating': the root link moves on a free-flyer joint "
                        "(Model.from_urdf(..., base='floating')); default %(default)s")
    args = parser.parse_args(argv)
    locked = dict(args.locked)
    names = [name for name, _ in args.locked]
    twice = sorted({name for name in names if names.count(name) > 1})
    if twice:   # as the node refuses a joint repeated in locked_joints
        parser.error(f'--locked: joint(s) given more than once: {", ".join(twice)}')
    if locked and not args.joints:
        parser.error('--locked needs --joints (the joints kept movable)')
    try:
        xml = read_description(args.urdf)
        with warnings.catch_warnings():
            warnings.simplefilter('ignore', URDFWarning)    # printed below, from the model
            model = Model.from_urdf(xml, joints=args.joints, locked=locked or None,
                                    base=args.base)
    except ValueError as err:
        print(f'error: {err}', file=sys.stderr)
        return 1
    said = warnings_of(model)
    try:
        print(report(model, model.joint_types, said), flush=True)
    except BrokenPipeError:   # | head: the reader has what it wanted
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    if args.strict and said:
        print(f'error: {len(said)} warning(s) with --strict', file=sys.stderr)
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
