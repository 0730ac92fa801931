# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Seeded generators of URDF kinematic trees, for the benchmark and the stress tests.

:func:`random_robot_urdf` draws a fixed-base chain or branching tree whose numbers can be
pushed to the edges a robot description meets in practice: random joint axes (unit or not,
of any length from 1e-3 to 1e3), joint and inertial origins at gimbal lock (pitch ±π/2), mass
ratios of many decades, point masses and thin rods, massless links, fixed and ``<mimic>``
joints. :func:`chain_urdf` and :func:`tree_urdf` are the robot-like arms of the benchmark.
Every generated robot is physical (non-negative masses, inertias positive semi-definite and
within the triangle inequality) and loads in spatial_dynamics and in Pinocchio.

numpy only; the XML is written with ``repr`` floats so the parameters round-trip exactly.
"""

from __future__ import annotations

from typing import Iterable, Optional, Sequence

import numpy as np

MOVABLE = ('revolute', 'continuous', 'prismatic')
JOINT_KINDS = MOVABLE + ('fixed',)
#: Kinds of link inertia :func:`random_robot_urdf` draws from.
INERTIA_KINDS = ('solid', 'point', 'rod', 'tiny', 'none')


def rpy_to_matrix(rpy) -> np.ndarray:
    """Return the URDF rotation R = Rz(yaw) Ry(pitch) Rx(roll), mapping child to parent coords."""
    r, p, y = (float(a) for a in rpy)
    cr, sr, cp, s_p, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    ry = np.array([[cp, 0.0, s_p], [0.0, 1.0, 0.0], [-s_p, 0.0, cp]])
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    return rz @ ry @ rx


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    """Return a uniformly distributed rotation matrix (QR of a Gaussian matrix)."""
    Q, R = np.linalg.qr(rng.standard_normal((3, 3)))
    Q = Q * np.sign(np.diag(R))
    if np.linalg.det(Q) < 0.0:
        Q[:, 0] = -Q[:, 0]
    return Q


def fmt(values: Iterable[float]) -> str:
    """Format floats for a URDF attribute with full (round-trip) precision."""
    return ' '.join(repr(float(v)) for v in values)


def origin_xml(xyz, rpy) -> str:
    """Return an <origin> element."""
    return f'<origin xyz="{fmt(xyz)}" rpy="{fmt(rpy)}"/>'


def inertia_xml(Ic: np.ndarray) -> str:
    """Return an <inertia> element for a symmetric 3x3 rotational inertia."""
    names = ('ixx', 'ixy', 'ixz', 'iyy', 'iyz', 'izz')
    values = (Ic[0, 0], Ic[0, 1], Ic[0, 2], Ic[1, 1], Ic[1, 2], Ic[2, 2])
    return '<inertia ' + ' '.join(f'{k}="{float(v)!r}"' for k, v in zip(names, values)) + '/>'


def inertial_xml(mass: float, xyz, rpy, Ic: np.ndarray) -> str:
    """Return an <inertial> element; Ic is about the com, in the frame rotated by rpy."""
    return (f'<inertial>{origin_xml(xyz, rpy)}<mass value="{float(mass)!r}"/>'
            f'{inertia_xml(np.asarray(Ic, dtype=float))}</inertial>')


def _rpy(rng: np.random.Generator, p_gimbal_lock: float) -> np.ndarray:
    """Draw a roll-pitch-yaw; with probability p_gimbal_lock the pitch is exactly ±π/2."""
    rpy = rng.uniform([-np.pi, -np.pi / 2, -np.pi], [np.pi, np.pi / 2, np.pi])
    if rng.random() < p_gimbal_lock:
        rpy[1] = float(rng.choice([-np.pi / 2, np.pi / 2]))
    return rpy


def _principal_inertia(rng: np.random.Generator, mass: float, kind: str,
                       length: float) -> np.ndarray:
    """Principal moments (B + C, A + C, A + B) from second moments A, B, C ≥ 0 of the mass.

    'solid': a body about ``length`` across; 'rod': a thin rod along z (A = B = 0);
    'point': a point mass (all zero); 'tiny': a solid 1e-9 times smaller.
    """
    if kind == 'point':
        return np.zeros(3)
    A, B, C = mass * length ** 2 * rng.uniform(0.002, 0.05, size=3)
    if kind == 'rod':
        A = B = 0.0
    elif kind == 'tiny':
        A, B, C = 1e-9 * A, 1e-9 * B, 1e-9 * C
    return np.array([B + C, A + C, A + B])


def _axis(rng: np.random.Generator, axes: Sequence[str]) -> np.ndarray:
    """Draw a joint axis: 'aligned' (±x, ±y or ±z), 'unit' (random direction) or 'nonunit'."""
    kind = axes[int(rng.integers(len(axes)))]
    if kind == 'aligned':
        axis = np.zeros(3)
        axis[rng.integers(3)] = rng.choice([-1.0, 1.0])
        return axis
    axis = rng.standard_normal(3)
    axis /= np.linalg.norm(axis)
    if kind == 'nonunit':
        axis *= 10.0 ** rng.uniform(-3.0, 3.0)
    return axis


def random_robot_urdf(rng: np.random.Generator, n_links: int, *, branching: bool = False,
                      joint_kinds: Sequence[str] = ('revolute',), p_mimic: float = 0.0,
                      axes: Sequence[str] = ('aligned', 'unit'),
                      length: float = 0.3, mass_range: tuple = (0.5, 5.0),
                      inertia_kinds: Sequence[str] = ('solid',),
                      p_gimbal_lock: float = 0.0, inertial_rpy: bool = True,
                      name: str = 'generated') -> str:
    """Return the XML of a random fixed-base tree of ``n_links`` links (link_0 is the root).

    Link i > 0 hangs from link i - 1 (a chain) or from a random earlier link (``branching``)
    by joint_i, whose kind is drawn from ``joint_kinds`` (the first joint is always movable
    when a movable kind is allowed). Joint origins are ``length`` (m) away from the parent
    frame in a random direction, with a random rpy; axes are drawn from ``axes``
    (see ``_axis``). Masses are log-uniform in ``mass_range`` (kg), so (1e-6, 1e3) spans nine
    decades; each link's inertia kind is drawn from ``inertia_kinds`` ('none' = no
    ``<inertial>``: a massless link). With probability ``p_gimbal_lock`` an origin's pitch is
    exactly ±π/2. Without ``inertial_rpy`` the rotated inertia is written as a full tensor
    in the link frame (rpy = 0; PyBullet mishandles a rotated ``<inertial>`` frame). With
    probability ``p_mimic`` a movable joint mimics an earlier non-mimic joint (multiplier
    ±[0.3, 2], offset in [-0.5, 0.5]) of the same kind (rotational or prismatic).
    """
    if n_links < 2:
        raise ValueError('n_links must be at least 2')
    kinds = [str(kind) for kind in rng.choice(list(joint_kinds), size=n_links - 1)]
    movable = [k for k in joint_kinds if k in MOVABLE]
    if movable and kinds[0] not in MOVABLE:
        kinds[0] = movable[0]
    lo, hi = np.log(mass_range[0]), np.log(mass_range[1])
    links = []
    for i in range(n_links):
        kind = inertia_kinds[int(rng.integers(len(inertia_kinds)))]
        body = ''
        if kind != 'none':
            mass = float(np.exp(rng.uniform(lo, hi)))
            com = rng.normal(0.0, length / 3.0, size=3)
            rpy = _rpy(rng, p_gimbal_lock)
            Ic = np.diag(_principal_inertia(rng, mass, kind, length))
            if not inertial_rpy:
                R = rpy_to_matrix(rpy)
                Ic, rpy = R @ Ic @ R.T, np.zeros(3)
            body = inertial_xml(mass, com, rpy, Ic)
        links.append(f'  <link name="link_{i}">{body}</link>')
    joints, sources = [], {'prismatic': [], 'rotational': []}
    for i, kind in zip(range(1, n_links), kinds):
        parent = int(rng.integers(i)) if branching else i - 1
        direction = rng.standard_normal(3)
        xyz = length * direction / np.linalg.norm(direction)
        parts = [f'  <joint name="joint_{i}" type="{kind}">', f'<parent link="link_{parent}"/>',
                 f'<child link="link_{i}"/>', origin_xml(xyz, _rpy(rng, p_gimbal_lock))]
        if kind in MOVABLE:
            parts.append(f'<axis xyz="{fmt(_axis(rng, axes))}"/>')
            if kind != 'continuous':
                parts.append('<limit effort="1000.0" velocity="10.0" lower="-3.0" upper="3.0"/>')
            same = sources['prismatic' if kind == 'prismatic' else 'rotational']
            if same and rng.random() < p_mimic:
                src = same[int(rng.integers(len(same)))]
                multiplier = float(rng.choice([-1.0, 1.0]) * rng.uniform(0.3, 2.0))
                offset = float(rng.uniform(-0.5, 0.5))
                parts.append(f'<mimic joint="{src}" multiplier="{multiplier!r}" '
                             f'offset="{offset!r}"/>')
            else:
                same.append(f'joint_{i}')
        parts.append('</joint>')
        joints.append(''.join(parts))
    return '\n'.join([f'<?xml version="1.0"?>\n<robot name="{name}">'] + links + joints
                     + ['</robot>\n'])


def chain_urdf(n_links: int, seed: Optional[int] = None) -> str:
    """Return a robot-like serial arm: ``n_links`` revolute joints, 0.3 m links, 0.5-5 kg.

    Axes are aligned with a frame axis or random unit vectors; every link has a solid
    inertia written in the link frame (no ``<inertial>`` rpy), so that MuJoCo and PyBullet
    model it as we do. Seeded by ``n_links`` unless ``seed`` is given.
    """
    rng = np.random.default_rng(n_links if seed is None else seed)
    return random_robot_urdf(rng, n_links + 1, inertial_rpy=False, name=f'chain{n_links}')


def tree_urdf(n_links: int, seed: Optional[int] = None) -> str:
    """Return a robot-like branching tree of ``n_links`` revolute joints (as chain_urdf)."""
    rng = np.random.default_rng(1000 + n_links if seed is None else seed)
    return random_robot_urdf(rng, n_links + 1, branching=True, inertial_rpy=False,
                             name=f'tree{n_links}')
