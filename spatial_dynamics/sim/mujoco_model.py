# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The URDF's rigid-body robot as a MuJoCo model: loading, feet on a floor, applied wrenches.

MuJoCo's URDF import is not the rigid-body robot of the URDF as it stands
(:func:`mujoco_model` undoes each difference):

* it imports ``<dynamics damping friction>`` as ``dof_damping`` and ``dof_frictionloss``, and
  may add ``dof_armature``: zeroed (or set to the values asked for, per joint);
* it makes ``<limit>`` joint-limit constraints and ``<mimic>`` equality constraints (soft,
  so never exact): constraints are disabled (only friction loss, when asked for, stays on);
* it fuses links fixed to each other into one body (``fusestatic``): kept apart, so every
  link is a body with its own name and frame (the inertia is the same either way);
* it loads ``<visual>`` and ``<collision>`` meshes it usually cannot find: dropped.

What is left is the URDF's kinematic tree with the URDF's inertias, and ``mj_inverse`` on it
equals :func:`spatial_dynamics.rnea` (``test/test_sim_robot.py``: UR5, Panda, demo arm).
The robots on it: :class:`~spatial_dynamics.sim.robot.SimulatedRobot` (fixed base, driven by
joint torques) and :class:`~spatial_dynamics.sim.floating.FloatingRobot` (on a floor).

MuJoCo is imported by :func:`import_mujoco`, inside the functions that need it (start-up
time, and an optional dependency): importing this module never imports it.
"""

from __future__ import annotations

from dataclasses import dataclass
import os
from typing import Mapping, Optional, Sequence, Union
import xml.etree.ElementTree as ET

import numpy as np

from spatial_dynamics import Contact, GRAVITY, Model
from spatial_dynamics.urdf import read_description

#: The one-line message when MuJoCo cannot be imported.
MUJOCO_MISSING = ('the simulated robot needs MuJoCo, which is not installed: '
                  'pip install mujoco (or spatial_dynamics[sim])')


Source = Union[str, bytes, os.PathLike]


class MujocoMissing(ImportError):
    """MuJoCo cannot be imported; the message is :data:`MUJOCO_MISSING`."""


def import_mujoco():
    """Return the ``mujoco`` module, or raise :class:`MujocoMissing`."""
    try:
        import mujoco
    except ImportError:
        raise MujocoMissing(MUJOCO_MISSING) from None
    return mujoco


def urdf_text(source: Source) -> str:
    """Return the URDF text of a path, an XML string (starting with ``<``) or XML bytes."""
    if isinstance(source, bytes):
        return source.decode('utf-8-sig')
    if isinstance(source, str) and source.lstrip('\ufeff \t\r\n').startswith('<'):
        return source
    return read_description(os.fspath(source))


def dynamics_only(xml: str) -> str:
    """Drop ``<visual>`` and ``<collision>`` from URDF text (meshes MuJoCo would load).

    Parse a URDF that :meth:`~spatial_dynamics.Model.from_urdf` has accepted (no DTD, no
    entities): this one only removes elements.
    """
    root = ET.fromstring(xml.encode('utf-8'))
    for link in root.iter('link'):
        for tag in ('visual', 'collision'):
            for element in link.findall(tag):
                link.remove(element)
    return ET.tostring(root, encoding='unicode')


def without_mimic(xml: str) -> str:
    """Return URDF text with every mimic joint and its source fixed at 0 (Talos's grippers).

    For :class:`~.floating.FloatingRobot`, which simulates no mimic joints.
    """
    root = ET.fromstring(xml.encode('utf-8'))
    names = set()
    for joint in root.iter('joint'):
        mimic = joint.find('mimic')
        if mimic is not None:
            names |= {joint.get('name'), mimic.get('joint')}
            joint.remove(mimic)
    for joint in root.iter('joint'):
        if joint.get('name') in names:
            joint.set('type', 'fixed')
    return ET.tostring(root, encoding='unicode')


def mujoco_model(xml: str, gravity: Sequence[float] = GRAVITY, base: str = 'fixed',
                 imus: Optional[Mapping[str, tuple]] = None, feet: Sequence['Foot'] = ()):
    """Load URDF text into MuJoCo as the URDF's rigid-body robot (see the module doc).

    No geometry, every link a body (``fusestatic`` off), ``dof_damping``,
    ``dof_frictionloss``, ``dof_armature`` and joint stiffness zero, every constraint
    disabled, ``gravity`` (m/s², root-link coordinates; world coordinates for a floating
    base). MuJoCo's joints keep their URDF names; map them by name, never by position.
    ``ValueError`` when MuJoCo cannot load it.

    ``base='floating'``: the root link gets a free joint named ``'root_joint'`` (MuJoCo's
    ``qpos`` position and quaternion **w x y z**, ``qvel`` the linear velocity in the world
    frame then the angular velocity in the body frame). ``imus`` maps a name to ``(link,
    position, quaternion x y z w)``: a site of that name at that pose in the link's frame,
    with an accelerometer ``name + '_accelerometer'`` and a gyro ``name + '_gyro'``.

    ``feet``: a floor (the plane z = 0, named ``'floor'``) and each :class:`Foot`'s geom; the
    contacts of the feet with the floor (and only those) stay on, with the feet's friction
    and :data:`CONTACT` settings; joint limits and equality constraints stay off.
    """
    mujoco = import_mujoco()
    if base not in ('fixed', 'floating'):
        raise ValueError(f"base must be 'fixed' or 'floating', got {base!r}")
    try:
        spec = mujoco.MjSpec.from_string(dynamics_only(xml))
        spec.compiler.fusestatic = False
        spec.compiler.discardvisual = True
        if base == 'floating':
            spec.worldbody.first_body().add_freejoint(name='root_joint')
        for name, (link, position, quat) in (imus or {}).items():
            body = spec.body(link)
            if body is None:
                raise ValueError(f'imus[{name!r}]: no link {link!r}')
            x, y, z, w = (float(c) for c in quat)
            body.add_site(name=name, pos=[float(c) for c in position], quat=[w, x, y, z])
            for kind, suffix in ((mujoco.mjtSensor.mjSENS_ACCELEROMETER, '_accelerometer'),
                                 (mujoco.mjtSensor.mjSENS_GYRO, '_gyro')):
                spec.add_sensor(name=name + suffix, type=kind,
                                objtype=mujoco.mjtObj.mjOBJ_SITE, objname=name)
        if feet:
            _add_feet(mujoco, spec, feet)
        m = spec.compile()
    except ValueError as err:
        raise ValueError(f'MuJoCo cannot load the URDF: {str(err).splitlines()[0]}') from None
    m.dof_damping[:] = 0.0
    m.dof_frictionloss[:] = 0.0
    m.dof_armature[:] = 0.0
    m.jnt_stiffness[:] = 0.0
    bits = mujoco.mjtDisableBit
    if feet:
        m.opt.disableflags |= int(bits.mjDSBL_EQUALITY | bits.mjDSBL_LIMIT)
        m.opt.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
        m.opt.impratio = CONTACT['impratio']
        m.opt.tolerance = CONTACT['tolerance']
        m.opt.iterations = CONTACT['iterations']
        m.opt.noslip_iterations = CONTACT['noslip_iterations']
    else:
        m.opt.disableflags |= int(bits.mjDSBL_CONSTRAINT)
    m.opt.gravity[:] = np.asarray(gravity, dtype=float)
    return m


#: MuJoCo's contact settings for :class:`Foot` geoms (see :class:`~.floating.FloatingRobot`):
#: a stiff, critically damped soft contact (``solref`` time constant 4 ms, ``solimp`` impedance
#: 0.99 to 0.999 over 1 mm), elliptic friction cones (our second-order cones), ``impratio``
#: 10 (tangential forces as stiff as normal ones: little creep), and the solver run to 1e-12.
CONTACT = {'solref': (0.004, 1.0), 'solimp': (0.999, 0.9999, 0.0001, 0.5, 2.0),
           'impratio': 10.0, 'tolerance': 1e-12, 'iterations': 200, 'noslip_iterations': 20}


@dataclass(frozen=True)
class Foot:
    """A foot of a floating-base robot in MuJoCo: its :class:`~spatial_dynamics.Contact` and geom.

    A point contact is a sphere of radius ``size[0]`` centred on the contact's point (MuJoCo
    pushes at its lowest point, ``size[0]`` below: keep it small). A surface contact is a box
    sole ``2 size[0]`` long (link x) and ``2 size[1]`` wide (link y), 2 cm thick, whose
    bottom face is centred on the contact's point (the sole's z axis is its normal). Its
    friction is the contact's ``mu``.
    """

    contact: Contact
    size: tuple = (0.01,)

    def __post_init__(self) -> None:
        size = tuple(float(s) for s in np.atleast_1d(self.size))
        need = 1 if self.contact.kind == 'point' else 2
        if len(size) != need or not all(np.isfinite(s) and s > 0.0 for s in size):
            raise ValueError(f'foot {self.contact.name!r}: size must be {need} positive '
                             f'number(s) (m), got {self.size}')
        object.__setattr__(self, 'size', size)


def _add_feet(mujoco, spec, feet: Sequence[Foot]) -> None:
    """Add the floor and the feet's geoms; only foot-floor pairs collide."""
    spec.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
    spec.worldbody.add_geom(name='floor', type=mujoco.mjtGeom.mjGEOM_PLANE,
                            size=[0.0, 0.0, 1.0], contype=0, conaffinity=1)
    for foot in feet:
        c = foot.contact
        body = spec.body(c.link)
        if body is None:
            raise ValueError(f'foot {c.name!r}: no link {c.link!r}')
        if c.kind == 'point':
            kind, size, pos = mujoco.mjtGeom.mjGEOM_SPHERE, [foot.size[0], 0, 0], c.offset
        else:
            kind, size = mujoco.mjtGeom.mjGEOM_BOX, [foot.size[0], foot.size[1], 0.01]
            pos = np.asarray(c.offset) + [0.0, 0.0, 0.01]       # above the sole plane
        body.add_geom(name=c.name, type=kind, size=size, pos=[float(x) for x in pos],
                      contype=1, conaffinity=0, condim=3, mass=0.0,
                      friction=[c.mu, 0.005, 0.0001], solref=list(CONTACT['solref']),
                      solimp=list(CONTACT['solimp']))


def hold_wrench(wrenches: dict, model: Model, m, link: str, wrench) -> None:
    """Hold ``[n; f]`` on ``link`` in ``wrenches`` (link -> (MuJoCo body id, wrench)).

    ``None`` removes it; an unknown link or anything but 6 finite numbers is a ValueError.
    """
    if link not in model.frames:
        raise ValueError(f'apply_wrench: unknown link {link!r}')
    if wrench is None:
        wrenches.pop(link, None)
        return
    wrench = np.asarray(wrench, dtype=float)
    if wrench.shape != (6,) or not np.isfinite(wrench).all():
        raise ValueError(f'apply_wrench {link!r}: need 6 finite numbers [n; f], got {wrench}')
    wrenches[link] = (m.body(link).id, wrench.copy())


def xfrc(d, body: int, wrench: np.ndarray) -> np.ndarray:
    """Return MuJoCo's ``xfrc_applied`` ``[f; n]`` of a link's wrench ``[n; f]``.

    The wrench in the link's frame about its origin; the result in world coordinates, about
    the body's centre of mass.
    """
    R = d.xmat[body].reshape(3, 3)
    f = R @ wrench[3:]
    n = R @ wrench[:3] + np.cross(d.xpos[body] - d.xipos[body], f)
    return np.concatenate([f, n])
