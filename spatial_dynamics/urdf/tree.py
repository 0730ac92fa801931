# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""URDF records -> :class:`~spatial_dynamics.model.Model`: the tree, lumping, mimic, reduction.

:func:`_from_robot` orders the links of :func:`.reading._parse_urdf` into bodies (movable joints
start new ones, fixed and locked joints lump their child into the body above; Pinocchio's
order), resolves mimic chains (:func:`_resolve_mimic`) and locks the joints model reduction
leaves out (:func:`_locked_values`).
"""

from __future__ import annotations

import math
from typing import Mapping, Optional, Sequence

import numpy as np

from ..joints import FIXED, FREE_FLYER, PRISMATIC, URDF_KINDS
from ..model import finite, Frame, Model
from ..spatial import Eaxis, plux
from ..text import listed, shown
from .reading import _joint_axis, _Joint, _Report

#: The name of the free-flyer joint of a floating base (Pinocchio's).
ROOT_JOINT = 'root_joint'
#: The name of body 0 of a floating-base model, the world (Pinocchio's).
WORLD = 'universe'
#: The root link a URDF fixes a robot to the world with (ROS and Gazebo's convention).
URDF_WORLD = 'world'


def _from_robot(robot_name: str, links: list, joints: list,
                keep: Optional[Sequence[str]], locked: Optional[Mapping[str, float]],
                report: _Report, floating: bool = False) -> Model:
    link_by_name = {}
    for link in links:
        if link.name in link_by_name:
            raise ValueError(f'duplicate link name {shown(link.name)}')
        link_by_name[link.name] = link
    joint_by_name, parent_joint, children = {}, {}, {name: [] for name in link_by_name}
    for joint in joints:
        if joint.name in joint_by_name:
            raise ValueError(f'duplicate joint name {shown(joint.name)}')
        joint_by_name[joint.name] = joint
        if joint.type not in URDF_KINDS:
            if joint.type in ('floating', 'planar'):
                raise ValueError(f'joint {shown(joint.name)}: {joint.type} joints are not '
                                 'supported (1-DOF joints only; a root link that moves is '
                                 "loaded with base='floating')")
            raise ValueError(f'joint {shown(joint.name)}: unknown joint type {shown(joint.type)}')
        for role, link in (('parent', joint.parent), ('child', joint.child)):
            if link not in link_by_name:
                raise ValueError(f'joint {shown(joint.name)}: unknown {role} link {shown(link)}')
        if joint.child in parent_joint:
            raise ValueError(f'link {shown(joint.child)} is the child of two joints: '
                             f'{shown(parent_joint[joint.child].name)} and {shown(joint.name)}')
        parent_joint[joint.child] = joint
        children[joint.parent].append(joint)
    if not link_by_name:
        raise ValueError(f'robot {shown(robot_name)} has no links')
    roots = [name for name in link_by_name if name not in parent_joint]
    if len(roots) != 1:
        if not roots:
            link, step = next(iter(link_by_name)), {}
            while link not in step:    # every link has a parent joint: walk up to a repeat
                step[link] = len(step)
                link = parent_joint[link].parent
            cycle = list(step)[step[link]:]
            raise ValueError('the joints form a cycle, so there is no root link: '
                             + ' -> '.join(f'{shown(parent_joint[c].name)}' for c in cycle)
                             + f' (links {cycle})')
        raise ValueError(f'several root links (a URDF is one tree): {roots}')

    if floating and ROOT_JOINT in joint_by_name:
        raise ValueError(f'joint {ROOT_JOINT!r}: the URDF has a joint of the name a floating '
                         "base gives its free-flyer joint (base='floating')")
    if floating and roots[0] == URDF_WORLD:
        fixed = [j.name for j in children[roots[0]] if j.type == 'fixed']
        through = (f' through fixed joint{"s" if len(fixed) > 1 else ""} '
                   + ', '.join(shown(j) for j in fixed) if fixed else '')
        report(f'the free-flyer is attached to {URDF_WORLD!r}{through}; did you mean a fixed '
               "base? (the URDF's root link is the world it is fixed to: base='fixed')")
    if floating and keep is not None and not isinstance(keep, str):
        keep = [j for j in keep if j != ROOT_JOINT]     # the free-flyer is always kept
    mimics: dict = {}     # joint name -> its resolved source, mult, offset (_resolve_mimic)
    lock = _locked_values(joint_by_name, keep, locked, mimics)

    # Each link gets its body and the pose (R, p) of its frame in that body's frame;
    # movable joints start new bodies, so parent[i] < i. A floating base: body 0 is the
    # world, body 1 the root link on a free-flyer joint (RBDA §4.5).
    body_names, body_joints, parent, jtype, axis, Xtree = [roots[0]], [''], [-1], [FIXED], \
        [np.zeros(3)], [np.eye(6)]
    if floating:
        body_names[0] = WORLD
        body_names.append(roots[0])
        body_joints.append(ROOT_JOINT)
        parent.append(0)
        jtype.append(FREE_FLYER)
        axis.append(np.zeros(3))
        Xtree.append(np.eye(6))
    pose = {roots[0]: (len(body_names) - 1, np.eye(3), np.zeros(3))}
    order = [roots[0]]
    for joints_below in children.values():
        # Pinocchio's (and urdfdom's, so KDL's) order: children by joint name, byte-wise.
        joints_below.sort(key=lambda j: j.name.encode('utf-8'))
    stack = list(reversed(children[roots[0]]))
    while stack:  # depth-first preorder
        joint = stack.pop()
        b, R_bl, p_bl = pose[joint.parent]
        # Child link frame in body b's frame at q = 0.
        R, p = R_bl @ joint.R, R_bl @ joint.p + p_bl
        if joint.name in lock:
            # A locked joint is a fixed joint displaced by its value.
            R, p = _displaced(joint, lock[joint.name], R, p)
        if URDF_KINDS[joint.type] == FIXED or joint.name in lock:
            pose[joint.child] = (b, R, p)
        else:
            body_names.append(joint.child)
            body_joints.append(joint.name)
            parent.append(b)
            jtype.append(URDF_KINDS[joint.type])
            axis.append(_joint_axis(joint))
            Xtree.append(plux(R.T, p))
            pose[joint.child] = (len(body_names) - 1, np.eye(3), np.zeros(3))
        order.append(joint.child)
        stack.extend(reversed(children[joint.child]))
    if len(order) != len(link_by_name):
        lost = sorted(set(link_by_name) - set(order))
        raise ValueError(f'the joints form a cycle: links {lost} are not reachable from the '
                         f'root link {shown(roots[0])}')
    NB = len(body_names) - 1

    # Inertias of all links, lumped into their bodies: I_b += lXbᵀ I_l lXb (RBDA eq. 2.66).
    inertia = np.zeros((NB + 1, 6, 6))
    frames = {}
    for name in order:
        b, R, p = pose[name]
        lXb = plux(R.T, p)
        frames[name] = Frame(b, lXb)
        frames[name].lXb.setflags(write=False)
        inertia[b] += lXb.T @ link_by_name[name].inertia @ lXb

    # Generalised coordinates: movable non-mimic joints in body order; mimic joints follow
    # their (transitively resolved) source: q_i = mult·q_src + offset. A floating base's
    # free-flyer comes first: 7 coordinates of q, 6 of q̇.
    first = 2 if floating else 1        # the first body on a joint of the URDF
    joint_names = tuple(keep) if keep is not None else tuple(
        j for j in body_joints[first:] if joint_by_name[j].mimic is None)
    index = {j: k for k, j in enumerate(joint_names)}
    qidx, vidx, qmul, qoff = [-1], [-1], [0.0], [0.0]
    if floating:
        qidx.append(0)
        vidx.append(0)
        qmul.append(1.0)
        qoff.append(0.0)
    q0, v0 = (7, 6) if floating else (0, 0)
    for jname in body_joints[first:]:
        src, mult, off = _resolve_mimic(jname, joint_by_name, mimics)
        qidx.append(q0 + index[src])
        vidx.append(v0 + index[src])
        qmul.append(mult)
        qoff.append(off)
    for jname in body_joints[first:]:
        for attr in ('damping', 'friction'):
            value = getattr(joint_by_name[jname], attr)
            if value < 0.0:
                report(f'joint {shown(jname)} <dynamics {attr}>: negative ({value:g}), so the '
                       'joint would gain energy')

    for joint in joints:
        lower, upper = joint.limit['lower'], joint.limit['upper']
        if joint.type in ('revolute', 'prismatic') and lower > upper:
            report(f'joint {shown(joint.name)} <limit>: lower ({lower:g}) is above upper '
                   f'({upper:g}), so no position is within its limits')

    def per_joint(get, names=joint_names, base=math.nan) -> np.ndarray:
        """One value per velocity coordinate: the free-flyer's six ``base``."""
        return np.array([base] * v0 + [get(joint_by_name[j]) for j in names], dtype=float)

    def per_body(get) -> np.ndarray:
        return np.r_[[0.0] * first, [get(joint_by_name[j]) for j in body_joints[first:]]]

    return Model(
        name=robot_name, joint_names=((ROOT_JOINT,) if floating else ()) + joint_names,
        body_names=tuple(body_names), vidx=np.array(vidx, dtype=np.intp),
        body_joints=tuple(body_joints), NB=NB, parent=np.array(parent, dtype=np.intp),
        jtype=np.array(jtype, dtype=np.intp), axis=np.array(axis), Xtree=np.array(Xtree),
        inertia=inertia, qidx=np.array(qidx, dtype=np.intp), qmul=np.array(qmul),
        qoff=np.array(qoff), frames=frames,
        effort_limit=per_joint(lambda j: j.limit['effort']),
        velocity_limit=per_joint(lambda j: j.limit['velocity']),
        lower=per_joint(lambda j: j.limit['lower']),
        upper=per_joint(lambda j: j.limit['upper']),
        damping=per_joint(lambda j: j.damping, base=0.0),
        friction=per_joint(lambda j: j.friction, base=0.0),
        body_damping=per_body(lambda j: j.damping),
        body_friction=per_body(lambda j: j.friction),
        lumped=tuple(n for n in order if pose[n][0] > 0 and body_names[pose[n][0]] != n),
        pruned=tuple(n for n in order[1:] if pose[n][0] == 0),
        locked={j: v for j, v in lock.items() if joint_by_name[j].mimic is None},
        warnings=tuple(report.messages),
        joint_types={name: j.type for name, j in joint_by_name.items()},
        mimics={name: j.mimic for name, j in joint_by_name.items() if j.mimic is not None})


def _resolve_mimic(jname: str, joint_by_name: dict, resolved: dict
                   ) -> tuple[str, float, float]:
    """Follow a chain of ``<mimic>`` tags to a non-mimic joint: ``(its name, mult, offset)``.

    The joint then moves by ``mult·q_src + offset``: a joint mimicking ``src`` by ``(m, o)``
    moves by ``m·(mult_src·q + off_src) + o``. ``resolved`` (joint name → result) is filled
    for every mimic joint on the way, so resolving all joints walks each tag once.
    """
    if jname in resolved:
        return resolved[jname]
    path, seen = [], {jname: None}     # the mimic joints walked; their names, in order
    joint = joint_by_name[jname]
    while joint.mimic is not None and joint.name not in resolved:
        src, m, o = joint.mimic
        what = f'joint {shown(joint.name)} <mimic>'
        if src not in joint_by_name:
            raise ValueError(f'{what}: mimics a missing joint {shown(src)}')
        if src in seen:
            raise ValueError(f'{what}: mimic joints form a loop {list(seen) + [src]}')
        if URDF_KINDS.get(joint_by_name[src].type, FIXED) == FIXED:
            raise ValueError(f'{what}: mimics {shown(src)}, which is not movable')
        path.append(joint)
        seen[src] = None
        joint = joint_by_name[src]
    source = resolved.get(joint.name)
    for joint in reversed(path):
        _, m, o = joint.mimic
        if source is None:    # mimics a non-mimic joint
            source = resolved[joint.name] = (joint.mimic[0], 1.0 * m, 1.0 * o + 0.0)
        else:
            src, mult, off = source
            source = resolved[joint.name] = (src, m * mult, m * off + o)
    return source if source is not None else (jname, 1.0, 0.0)


def _locked_values(joint_by_name: dict, keep, locked, mimics: dict) -> dict:
    """Joint name → locked value for every movable joint that model reduction locks.

    In URDF order; ``mimics`` is the table of :func:`_resolve_mimic`.
    """
    locked = dict(locked or {})
    movable = [j for j, jt in joint_by_name.items() if URDF_KINDS[jt.type] != FIXED]
    independent = {j for j in movable if joint_by_name[j].mimic is None}
    for j, v in locked.items():
        if j not in independent:
            why = 'is a mimic joint (lock its source)' if j in movable else \
                'is not a movable joint of the URDF'
            raise ValueError(f'locked joint {shown(j)} {why}')
        value = finite(f'locked joint {shown(j)} value', v)      # a number: '0.1', True refused
        if value.ndim != 0:
            raise ValueError(f'locked joint {shown(j)} value must be one number, got shape '
                             f'{value.shape}')
        locked[j] = float(value)
    if keep is None:
        if locked:
            raise ValueError(f'locked joints [{listed(sorted(locked))}] need a list of kept '
                             'joints')
        return {}
    if isinstance(keep, str):
        raise ValueError('joints must be a list of joint names, not a string')
    for j in keep:
        if j not in independent:
            why = 'is a mimic joint (keep its source)' if j in movable else \
                'is not a movable joint of the URDF'
            raise ValueError(f'kept joint {shown(j)} {why}')
        if j in locked:
            raise ValueError(f'joint {shown(j)} is both kept and locked')
    kept = set(keep)
    if len(kept) != len(keep):
        raise ValueError(f'joints lists a joint twice: [{listed(list(keep))}]')
    lock = {j: locked.get(j, 0.0) for j in movable if j in independent and j not in kept}
    for j in movable:
        src, mult, off = _resolve_mimic(j, joint_by_name, mimics)
        if j not in independent and src in lock:
            lock[j] = mult * lock[src] + off
    return lock


def _displaced(joint: _Joint, value: float, R: np.ndarray, p: np.ndarray):
    """Pose of a joint's child frame moved by ``value`` along/about its axis."""
    axis = _joint_axis(joint)
    if URDF_KINDS[joint.type] == PRISMATIC:
        return R, p + R @ (axis * value)
    return R @ Eaxis(axis, value).T, p
