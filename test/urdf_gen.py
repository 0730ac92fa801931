# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Seeded generator of random kinematic-tree URDFs, and URDF re-expression helpers.

Every generated robot is physical (positive masses, inertias that are positive definite and
satisfy the triangle inequality) so that it loads in both spatial_dynamics and Pinocchio.
The XML and rotation helpers live in ``benchmarks.generate`` (shared with the
benchmark) and are re-exported here.
"""

from typing import Optional

import numpy as np
# The XML and rotation helpers are shared with the benchmark's generator.
from benchmarks.generate import (  # noqa: F401 (re-exported to the tests)
    fmt, inertia_xml, inertial_xml, MOVABLE, origin_xml, random_rotation, rpy_to_matrix)


def matrix_to_rpy(R: np.ndarray) -> np.ndarray:
    """Return URDF (roll, pitch, yaw) with rpy_to_matrix(rpy) == R (pitch in [-pi/2, pi/2])."""
    pitch = np.arctan2(-R[2, 0], np.hypot(R[0, 0], R[1, 0]))
    if np.hypot(R[0, 0], R[1, 0]) < 1e-12:  # gimbal lock: put all of the rotation in roll
        return np.array([np.arctan2(-R[1, 2], R[1, 1]), pitch, 0.0])
    return np.array([np.arctan2(R[2, 1], R[2, 2]), pitch, np.arctan2(R[1, 0], R[0, 0])])


def random_inertia(rng: np.random.Generator, mass: float) -> np.ndarray:
    """Return a random rotational inertia about the com satisfying the triangle inequality.

    With second moments A, B, C > 0 of the mass distribution along the principal axes the
    principal moments are (B + C, A + C, A + B): every sum of two exceeds the third.
    """
    A, B, C = mass * rng.uniform(0.002, 0.05, size=3)
    Ic = np.diag([B + C, A + C, A + B])
    if rng.random() < 0.6:  # products of inertia as well, not only principal moments
        R = random_rotation(rng)
        Ic = R @ Ic @ R.T
        Ic = 0.5 * (Ic + Ic.T)
    return Ic


def random_axis(rng: np.random.Generator) -> np.ndarray:
    """Return a joint axis: random or axis-aligned, unit or not, of either sign."""
    kind = rng.integers(4)
    if kind == 0:
        axis = rng.standard_normal(3)
        axis /= np.linalg.norm(axis)
    elif kind == 1:
        axis = rng.standard_normal(3) * rng.uniform(0.3, 3.0)
    else:
        axis = np.zeros(3)
        axis[rng.integers(3)] = rng.choice([-1.0, 1.0])
        if kind == 3:
            axis *= rng.uniform(0.3, 3.0)
    return axis


def random_origin(rng: np.random.Generator):
    """Return a random joint origin (xyz, rpy); sometimes the identity or a pure translation."""
    u = rng.random()
    if u < 0.1:
        return np.zeros(3), np.zeros(3)
    xyz = rng.normal(0.0, 0.3, size=3)
    if u < 0.25:
        return xyz, np.zeros(3)
    rpy = rng.uniform([-np.pi, -np.pi / 2, -np.pi], [np.pi, np.pi / 2, np.pi])
    return xyz, rpy


def random_tree_urdf(rng: np.random.Generator, n_links: int, branching: bool = True,
                     joint_kinds=('revolute', 'continuous', 'prismatic', 'fixed'),
                     mimic: bool = False, name: str = 'random_tree',
                     p_inertial: float = 0.8) -> str:
    """Return the XML of a random fixed-base tree of n_links links (link_0 is the root).

    Link i > 0 hangs from a random earlier link (branching) or from link i - 1 (a chain) by
    joint_i of a kind drawn from joint_kinds. At least one joint is movable when joint_kinds
    allows it. Joint origins, axes and inertials (mass, com, rotated principal inertia) are
    random; about 1 - p_inertial of the links have no <inertial> (massless). With mimic, some
    movable joints mimic an earlier non-mimic movable joint with a random multiplier and offset.
    """
    if n_links < 2:
        raise ValueError('n_links must be at least 2')
    kinds = [str(rng.choice(joint_kinds)) for _ in range(1, n_links)]
    if all(k == 'fixed' for k in kinds) and any(k in MOVABLE for k in joint_kinds):
        kinds[0] = next(k for k in joint_kinds if k in MOVABLE)
    links = []
    for i in range(n_links):
        body = ''
        if i == 0 or rng.random() < p_inertial:
            mass = rng.uniform(0.1, 5.0)
            com = rng.normal(0.0, 0.1, size=3)
            rpy = (np.zeros(3) if rng.random() < 0.3 else
                   rng.uniform([-np.pi, -np.pi / 2, -np.pi], [np.pi, np.pi / 2, np.pi]))
            body = inertial_xml(mass, com, rpy, random_inertia(rng, mass))
        links.append(f'  <link name="link_{i}">{body}</link>')
    joints = []
    sources = []  # non-mimic movable joints created so far
    n_mimic = 0
    for i, kind in zip(range(1, n_links), kinds):
        parent = int(rng.integers(i)) if branching else i - 1
        xyz, rpy = random_origin(rng)
        parts = [f'  <joint name="joint_{i}" type="{kind}">', f'<parent link="link_{parent}"/>',
                 f'<child link="link_{i}"/>', origin_xml(xyz, rpy)]
        if kind in MOVABLE:
            parts.append(f'<axis xyz="{fmt(random_axis(rng))}"/>')
            parts.append('<limit effort="100.0" velocity="10.0" lower="-3.0" upper="3.0"/>')
            want_mimic = mimic and sources and (rng.random() < 0.35 or n_mimic == 0)
            if want_mimic:
                src = sources[int(rng.integers(len(sources)))]
                multiplier = float(rng.choice([-1.0, 1.0]) * rng.uniform(0.3, 2.0))
                offset = float(rng.uniform(-0.5, 0.5))
                parts.append(f'<mimic joint="{src}" multiplier="{multiplier!r}" '
                             f'offset="{offset!r}"/>')
                n_mimic += 1
            else:
                sources.append(f'joint_{i}')
        parts.append('</joint>')
        joints.append(''.join(parts))
    return '\n'.join([f'<?xml version="1.0"?>\n<robot name="{name}">'] + links + joints
                     + ['</robot>\n'])


def mimic_table(urdf_xml: str) -> dict:
    """Return {mimic joint name: (source joint name, multiplier, offset)} of a URDF string."""
    import xml.etree.ElementTree as ET
    table = {}
    for joint in ET.fromstring(urdf_xml.encode()).iter('joint'):
        tag = joint.find('mimic')
        if tag is not None and joint.get('type') in MOVABLE:
            table[joint.get('name')] = (tag.get('joint'), float(tag.get('multiplier', 1.0)),
                                        float(tag.get('offset', 0.0)))
    return table


def movable_joint_names(urdf_xml: str, include_mimic: bool = False) -> list:
    """Return the names of the movable joints of a URDF string (non-mimic unless asked)."""
    import xml.etree.ElementTree as ET
    names = []
    for joint in ET.fromstring(urdf_xml.encode()).iter('joint'):
        if joint.get('type') not in MOVABLE:
            continue
        if joint.find('mimic') is not None and not include_mimic:
            continue
        names.append(joint.get('name'))
    return names


def insert_fixed_frame(urdf_xml: str, joint_name: str, X: Optional[tuple] = None,
                       rng: Optional[np.random.Generator] = None) -> str:
    """Re-express a URDF: put a massless link between joint_name's parent and the joint.

    A fixed joint with transform T = (xyz, rpy) goes from the parent link to a new link, and
    joint_name's origin becomes T^-1 * origin, so that the kinematics and dynamics do not change.
    """
    import xml.etree.ElementTree as ET
    root = ET.fromstring(urdf_xml.encode())
    joint = next(j for j in root.iter('joint') if j.get('name') == joint_name)
    if X is None:
        xyz_t, rpy_t = rng.normal(0.0, 0.5, size=3), rng.uniform(-np.pi, np.pi, size=3)
        rpy_t[1] /= 2.0
    else:
        xyz_t, rpy_t = (np.asarray(a, dtype=float) for a in X)
    R_t = rpy_to_matrix(rpy_t)
    origin = joint.find('origin')
    if origin is None:
        origin = ET.SubElement(joint, 'origin')
    xyz_o = np.array([float(s) for s in origin.get('xyz', '0 0 0').split()])
    R_o = rpy_to_matrix([float(s) for s in origin.get('rpy', '0 0 0').split()])
    # parent_T_joint = T * T^-1 * parent_T_joint
    xyz_new = R_t.T @ (xyz_o - xyz_t)
    R_new = R_t.T @ R_o
    origin.set('xyz', fmt(xyz_new))
    origin.set('rpy', fmt(matrix_to_rpy(R_new)))
    parent = joint.find('parent')
    mid = f'{joint_name}_mid_link'
    ET.SubElement(root, 'link', {'name': mid})
    fixed = ET.SubElement(root, 'joint', {'name': f'{joint_name}_mid_joint', 'type': 'fixed'})
    ET.SubElement(fixed, 'parent', {'link': parent.get('link')})
    ET.SubElement(fixed, 'child', {'link': mid})
    ET.SubElement(fixed, 'origin', {'xyz': fmt(xyz_t), 'rpy': fmt(rpy_t)})
    parent.set('link', mid)
    return ET.tostring(root, encoding='unicode')


def move_inertial_to_fixed_child(urdf_xml: str, link_name: str,
                                 rng: np.random.Generator) -> str:
    """Re-express a URDF: move link_name's <inertial> onto a new link fixed to it.

    The new link sits at a random transform T from link_name, and the inertial is rewritten in
    the new link's frame (origin T^-1 * inertial origin), so the mass distribution is unchanged.
    A second, massless fixed sibling is added too.
    """
    import xml.etree.ElementTree as ET
    root = ET.fromstring(urdf_xml.encode())
    link = next(e for e in root.iter('link') if e.get('name') == link_name)
    inertial = link.find('inertial')
    xyz_t, rpy_t = rng.normal(0.0, 0.5, size=3), rng.uniform(-np.pi, np.pi, size=3)
    rpy_t[1] /= 2.0
    R_t = rpy_to_matrix(rpy_t)
    new = ET.SubElement(root, 'link', {'name': f'{link_name}_payload'})
    if inertial is not None:
        link.remove(inertial)
        origin = inertial.find('origin')
        if origin is None:
            origin = ET.SubElement(inertial, 'origin')
        xyz_o = np.array([float(s) for s in origin.get('xyz', '0 0 0').split()])
        R_o = rpy_to_matrix([float(s) for s in origin.get('rpy', '0 0 0').split()])
        origin.set('xyz', fmt(R_t.T @ (xyz_o - xyz_t)))
        origin.set('rpy', fmt(matrix_to_rpy(R_t.T @ R_o)))
        new.append(inertial)
    for child, (xyz, rpy) in ((f'{link_name}_payload', (xyz_t, rpy_t)),
                              (f'{link_name}_marker', random_origin(rng))):
        if child.endswith('_marker'):
            ET.SubElement(root, 'link', {'name': child})
        fixed = ET.SubElement(root, 'joint', {'name': f'{child}_joint', 'type': 'fixed'})
        ET.SubElement(fixed, 'parent', {'link': link_name})
        ET.SubElement(fixed, 'child', {'link': child})
        ET.SubElement(fixed, 'origin', {'xyz': fmt(xyz), 'rpy': fmt(rpy)})
    return ET.tostring(root, encoding='unicode')
