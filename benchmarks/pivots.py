# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The smallest pivot of ``M`` per robot: ``python -m benchmarks.pivots [--states N]``.

Forward dynamics refuses a joint whose pivot ``d_k`` (``M``'s factorization from the leaves,
ABA's ``D_i``) is at most ``PIVOT_TOL M_kk`` (:mod:`spatial_dynamics.algorithms.forward`).
This measures what real robots have: every URDF of example-robot-data, fixed base and (those
that walk, fly or drive) free-flyer, at ``N`` random states each (joints uniform in
``[-π, π]``, a random unit quaternion), and random trees of :mod:`benchmarks.generate`
(branching, revolute and prismatic joints on any axis, masses over nine decades, every
inertia kind but massless links) at 50 states each. ``d_k /
M_kk`` comes from numpy's Cholesky of ``M`` with its coordinates reversed (``d_k = L_kk²``),
independent of the library's kernels. Prints a markdown table: per robot the smallest ratio,
its joint and ``cond(M)`` there; a robot whose ``M`` is singular at a state (Cholesky fails,
or a ratio at rounding's 1e-13) says so.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings

import numpy as np

import spatial_dynamics as sd
from spatial_dynamics.algorithms.forward import PIVOT_TOL
from benchmarks.bench import _erd_dir
from benchmarks.generate import random_robot_urdf

#: The robots that also get a free-flyer (as the tests' ``FLOATING``): a fixed-base arm does not.
ARMS = ('allegro', 'asr_twodof', 'baxter', 'double_pendulum', 'finger_edu', 'kinova', 'panda',
        'so_arm', 'ur_description', 'xarm', 'z1_description')


def ratios(M: np.ndarray) -> np.ndarray:
    """Return ``d_k / M_kk`` (..., nv) of symmetric ``M`` (..., nv, nv); NaN where not SPD."""
    R = M[..., ::-1, ::-1]
    out = np.full(M.shape[:-1], np.nan)
    for s in np.ndindex(M.shape[:-2]):
        try:
            L = np.linalg.cholesky(R[s])
        except np.linalg.LinAlgError:
            continue
        out[s] = (np.diagonal(L) ** 2 / np.diagonal(R[s]))[::-1]
    return out


def scan(model: sd.Model, q: np.ndarray) -> tuple:
    """Return ``(smallest ratio, its joint, cond(M) there, states singular)`` over ``q``."""
    M = sd.mass_matrix(model, q)
    r = ratios(M)
    worst = np.where(np.isnan(r), 0.0, r).min(axis=-1)
    singular = int(np.sum(worst <= 1e-13))
    s = int(np.argmin(np.where(worst <= 1e-13, np.inf, worst))) if singular < len(q) else 0
    k = int(np.argmin(r[s])) if singular < len(q) else 0
    eig = np.linalg.eigvalsh(M[s])
    base = 6 if model.floating else 0
    joint = 'the base' if k < base else model.joint_names[k - base + (1 if base else 0)]
    return float(r[s].min()), joint, float(eig[-1] / max(eig[0], 1e-300)), singular


def states(rng: np.random.Generator, model: sd.Model, n: int) -> np.ndarray:
    """Return ``n`` random configurations of ``model``."""
    q = rng.uniform(-np.pi, np.pi, (n, model.nq))
    if model.floating:
        quat = rng.normal(size=(n, 4))
        q[:, 3:7] = quat / np.linalg.norm(quat, axis=-1, keepdims=True)
    return q


def main(argv=None) -> int:
    """Print the table; progress on stderr."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--states', type=int, default=200, help='random states a robot')
    parser.add_argument('--trees', type=int, default=200, help='random trees')
    args = parser.parse_args(argv)
    rng = np.random.default_rng(1)
    erd = _erd_dir()
    if erd is None:
        print('example-robot-data is not installed', file=sys.stderr)
        return 1
    files = sorted(p.relative_to(erd).as_posix() for p in erd.glob('**/*.urdf'))
    print(f'PIVOT_TOL = {PIVOT_TOL:g}; {args.states} states a robot\n')
    print('| robot | base | smallest d_k / M_kk | joint | cond(M) there | singular states |')
    print('|---|---|---|---|---|---|')
    least = {}
    for base in ('fixed', 'floating'):
        for name in files:
            if base == 'floating' and name.startswith(ARMS):
                continue
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter('ignore')
                    model = sd.Model.from_urdf(os.path.join(erd, name), base=base)
            except ValueError:
                continue        # refused by the parser (test_urdf_robot_sweep.py's REFUSED)
            if model.nv == 0:
                continue
            r, joint, cond, singular = scan(model, states(rng, model, args.states))
            if singular < args.states:
                least[base] = min(least.get(base, 1.0), r)
            if singular == args.states:
                print(f'| {name} | {base} | singular | | | {singular} |')
            else:
                print(f'| {name} | {base} | {r:.2e} | {joint} | {cond:.1e} | {singular} |')
            print(name, base, file=sys.stderr)
    tree_least, singular_trees = 1.0, 0
    for seed in range(args.trees):
        tree = np.random.default_rng(seed)
        xml = random_robot_urdf(tree, int(tree.integers(2, 40)), branching=bool(seed % 2),
                                joint_kinds=('revolute', 'prismatic', 'fixed'),
                                axes=('aligned', 'unit'), mass_range=(1e-6, 1e3),
                                inertia_kinds=('solid', 'point', 'rod', 'tiny'))
        with warnings.catch_warnings():
            warnings.simplefilter('ignore')
            model = sd.Model.from_urdf(xml)
        if model.nv == 0:
            continue
        r, _, _, singular = scan(model, states(rng, model, 50))
        if singular == 50:
            singular_trees += 1
        else:
            tree_least = min(tree_least, r)
    print(f'\nsmallest over the states that are not singular: fixed {least.get("fixed", 1):.1e}, '
          f'floating {least.get("floating", 1):.1e}; random trees {tree_least:.1e} '
          f'({singular_trees} of {args.trees} singular at every state)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
