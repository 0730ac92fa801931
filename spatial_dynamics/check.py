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
import sys
import textwrap
from typing import Dict, List, Optional, Sequence, Tuple
import warnings

import numpy as np

from . import mass_matrix, Model, urdf, URDFWarning
from .bounds import MAX_POSITION
from .joints import KIND_NAMES

WIDTH = 99


def read_description(path: str) -> bytes:
    """Return the URDF XML of a file (:func:`spatial_dynamics.urdf.read_description`)."""
    return urdf.read_description(path, urdf.MAX_FILE_BYTES, path).encode('utf-8')


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
        rows.append(([str(i), model.body_names[i], model.body_joints[i] or '(fixed base)',
                      '-' if i == 0 else str(int(model.parent[i])), num(model.inertia[i][3, 3])],
                     wrapped(label, links[i], 8) if links[i] else []))
    return table(('body', 'link', 'joint', 'parent', 'mass (kg)'), rows, left=(1, 2))


def singular_base(model: Model) -> List[str]:
    """Return a warning when a floating ``model``'s mass matrix is singular, else nothing.

    The base rows of ``M`` at the neutral configuration are the whole robot's spatial inertia
    about its base (RBDA §6.2's composite ``I^c_1``): without mass, or with its mass on a line
    and no rotational inertia, no wrench on the base gives it an acceleration, and ``M``, the
    contact split and the forward dynamics have no answer.
    """
    if not model.floating:
        return []
    q = np.zeros(model.nq)
    q[6] = 1.0
    Ic = mass_matrix(model, q, backend='numpy')[:6, :6]
    eig = np.linalg.eigvalsh(Ic)
    if eig[-1] <= 0.0:
        return ['the tree has no mass: on the free-flyer its mass matrix M is singular (no '
                "wrench moves the base); give the links <inertial>, or load it with "
                "base='fixed'"]
    if eig[0] <= 1e-12 * eig[-1]:
        return [f'the whole robot\'s spatial inertia about its base has rank '
                f'{int(np.sum(eig > 1e-12 * eig[-1]))} of 6: on the free-flyer its mass '
                'matrix M is singular; give the links <inertial> with rotational inertia']
    return []


def report(model: Model, types: Dict[str, str]) -> str:
    """Return the whole check as text: robot, joints, bodies, mass and warnings."""
    base = (f'floating base (link {model.body_names[1]!r} on the free-flyer joint '
            f'{model.joint_names[0]!r}: q has {model.nq} numbers, position and quaternion x y z '
            f'w first, q̇ {model.nv}, the base twist [ω; v] first), '
            if model.floating else '')
    dof = f'{model.nv} dof (the base 6, the joints {model.nv - 6})' if model.floating else \
        f'{model.nq} dof'
    lines = [f'robot {model.name!r}: {base}{dof}, {model.NB} moving bodies, '
             f'{len(model.frames)} links', '',
             f'joints in q order ({len(model.joint_names)}); limits in rad or m, /s, N m or N, '
             "'-' when not given:"]
    lines += joint_lines(model, types)
    if model.locked:
        lines += wrapped('locked by model reduction: ',
                         [f'{j}={num(model.locked[j])}' for j in types if j in model.locked],
                         2)
    lines += ['', f'bodies after lumping fixed joints ({model.NB} moving + the fixed base):']
    lines += body_lines(model)
    mass = model.inertia[:, 3, 3]
    lines += ['', f'total mass: {num(float(np.sum(mass)))} kg '
              f'({num(float(mass[0]))} kg on the fixed base, {num(float(np.sum(mass[1:])))} kg '
              'moving)', '']
    said = list(model.warnings) + singular_base(model)
    if said:
        lines.append(f'warnings ({len(said)}):')
        for w in said:
            lines += textwrap.wrap(w, WIDTH, initial_indent='  - ', subsequent_indent='    ')
    else:
        lines.append('no warnings')
    return '\n'.join(lines)


def locked_item(item: str) -> Tuple[str, float]:
    """Parse ``'name=value'`` to ``(name, value)``; ``ArgumentTypeError`` (usage) if not.

    The value is a joint position: finite, within ±MAX_POSITION (rad or m).
    """
    name, sep, value = item.partition('=')
    try:
        if sep and name and abs(float(value)) <= MAX_POSITION:
            return name, float(value)
    except ValueError:
        pass
    raise argparse.ArgumentTypeError(f'{item!r}: expected NAME=VALUE, the value in rad or m '
                                     f'within ±{MAX_POSITION:g}')


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
    print(report(model, model.joint_types))
    said = len(model.warnings) + len(singular_base(model))
    if args.strict and said:
        print(f'error: {said} warning(s) with --strict', file=sys.stderr)
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
