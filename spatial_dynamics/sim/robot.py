# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The URDF's rigid-body robot simulated by MuJoCo, in our joint order (no ROS).

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

Mimic and locked joints (model reduction, ``joints`` / ``locked``) are simulated exactly:
MuJoCo keeps every URDF joint as a degree of freedom, and :class:`SimulatedRobot` constrains
its accelerations to ``q̈_mj = G q̈`` (``G`` maps our ``q`` to MuJoCo's: 1 for a joint of ``q``,
the multiplier for a mimic joint, 0 for a locked joint) by Gauss's principle, and the state
``(q, q̇)`` is integrated in those coordinates, so ``q_mj = G q + q0`` holds exactly (see
:meth:`SimulatedRobot.step`).
"""

from __future__ import annotations

from dataclasses import dataclass
import os
from typing import Mapping, Optional, Sequence, Union
import xml.etree.ElementTree as ET

import numpy as np

from spatial_dynamics import Contact, GRAVITY, Model
from spatial_dynamics.bounds import check_bounded, MAX_POSITION, MAX_VELOCITY
from spatial_dynamics.terms import per_joint, PerJoint
from spatial_dynamics.urdf import read_description

#: The one-line message when MuJoCo cannot be imported.
MUJOCO_MISSING = ('the simulated robot needs MuJoCo, which is not installed: '
                  'pip install mujoco (or spatial_dynamics[sim])')
#: Integrators of :class:`SimulatedRobot`; ``auto`` is ``rk4``. Measured over 1 s from rest at
#: a random q, zero torque, 1 ms steps, against a 10 µs-step reference: on the UR5, rk4 ends
#: 3e-9 rad off and keeps the energy to 3e-9 J (9 µs a step), MuJoCo's semi-implicit euler
#: ends 2.7e-2 rad off and gains 0.4 J (3 µs a step); on the Panda arm euler ends 1.2 rad off.
#: (implicitfast differs from euler only through damping, which it makes implicit.)
INTEGRATORS = ('auto', 'euler', 'rk4')

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

    For :class:`FloatingRobot`, which simulates no mimic joints.
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


#: MuJoCo's contact settings for :class:`Foot` geoms (see :class:`FloatingRobot`): a stiff,
#: critically damped soft contact (``solref`` time constant 4 ms, ``solimp`` impedance
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


class SimulatedRobot:
    """The rigid-body robot of a URDF, simulated by MuJoCo, driven by joint torques.

    Every array is in the order of ``joint_names`` (= ``model.joint_names``; with ``joints``,
    the reduced model's order, the other joints locked at ``locked[name]``, default 0, as in
    :meth:`~spatial_dynamics.Model.from_urdf`); SI units (rad, m, N m, N).

    Args:
        urdf: a URDF path, XML text or XML bytes.
        joints, locked: model reduction, as in :meth:`~spatial_dynamics.Model.from_urdf`.
        timestep: physics step ``h`` (s).
        damping: viscous friction per joint (N m s/rad or N s/m): ``τ = -damping·q̇``,
            explicit (MuJoCo's implicit Euler damping is switched off, so one step is
            exactly the forward dynamics; stable while ``h·damping/M_ii`` is well below 2).
        friction: MuJoCo's friction loss per joint (N m or N), a constraint: a dry friction
            force of at most ``friction`` opposing the motion (see ``test_sim_robot``). Not
            with mimic or locked joints.
        armature: reflected rotor inertia per joint (kg m² or kg), added to ``M_ii``.
        gravity: m/s² in root-link coordinates.
        integrator: ``'rk4'`` (classical 4th-order Runge-Kutta), ``'euler'``
            (semi-implicit Euler, ``q̇ += h q̈`` then ``q += h q̇``) or ``'auto'`` (default:
            rk4, see :data:`INTEGRATORS`). MuJoCo's own, or with mimic or locked joints the
            same schemes on ``(q, q̇)`` (:meth:`step`).

    ``damping``, ``friction`` and ``armature`` are a scalar, a list in joint order or a
    ``{joint: value}`` map (:func:`~spatial_dynamics.terms.per_joint`); none of the URDF's
    ``<dynamics>`` is used unless passed here (``model.damping``, ``model.friction``).
    """

    def __init__(self, urdf: Source, joints: Optional[Sequence[str]] = None,
                 locked: Optional[Mapping[str, float]] = None, timestep: float = 1e-3,
                 damping: Optional[PerJoint] = None, friction: Optional[PerJoint] = None,
                 armature: Optional[PerJoint] = None, gravity: Sequence[float] = GRAVITY,
                 integrator: str = 'auto') -> None:
        mujoco = import_mujoco()
        self._mj = mujoco
        xml = urdf_text(urdf)
        self.model = Model.from_urdf(xml.encode('utf-8'), joints, locked)
        self.joint_names = self.model.joint_names
        if not (np.isfinite(timestep) and timestep > 0.0):
            raise ValueError(f'timestep must be a positive number of seconds, got {timestep}')
        if integrator not in INTEGRATORS:
            raise ValueError(f'integrator {integrator!r}: one of {", ".join(INTEGRATORS)}')
        self.m = m = mujoco_model(xml, gravity)
        self._map_joints(m, self.model.mimics)
        if integrator == 'auto':
            integrator = 'rk4'
        model = self.model
        self.damping = per_joint(model, 'damping', 0.0 if damping is None else damping,
                                 nonnegative=True)
        self.friction = per_joint(model, 'friction', 0.0 if friction is None else friction,
                                  nonnegative=True)
        self.armature = per_joint(model, 'armature', 0.0 if armature is None else armature,
                                  nonnegative=True)
        m.dof_damping[self._dof] = self.damping
        m.dof_frictionloss[self._dof] = self.friction
        m.dof_armature[self._dof] = self.armature
        if self.friction.any():
            if self.constrained:
                raise ValueError(f'friction: friction loss is a MuJoCo constraint, not '
                                 f'simulated exactly with mimic or locked joints '
                                 f'({", ".join(self._coupled)})')
            bits = mujoco.mjtDisableBit
            m.opt.disableflags &= ~int(bits.mjDSBL_CONSTRAINT)
            m.opt.disableflags |= int(bits.mjDSBL_CONTACT | bits.mjDSBL_EQUALITY
                                      | bits.mjDSBL_LIMIT)
        m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_EULERDAMP)
        m.opt.timestep = float(timestep)
        m.opt.integrator = {'euler': mujoco.mjtIntegrator.mjINT_EULER,
                            'rk4': mujoco.mjtIntegrator.mjINT_RK4}[integrator]
        self.integrator = integrator
        self.d = mujoco.MjData(m)
        self._scratch = mujoco.MjData(m)     # for inverse(): never disturbs the simulation
        self._M = np.zeros((m.nv, m.nv))
        self._wrenches: dict = {}
        self.resets = 0          # restarts after the state diverged (:meth:`_check_state`)
        self.reset_reason = ''
        self.set_state(np.zeros(model.nq), np.zeros(model.nq))

    # ----------------------------------------------------------------------------------------
    # Joint map: q_mj = G q + q0

    def _map_joints(self, m, mimic: dict) -> None:
        """Build ``G`` (nv, n), ``q0`` (nq,) and the primary dof of each joint of q."""
        mujoco, model = self._mj, self.model
        kinds = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
        body_of = {name: i for i, name in enumerate(model.body_joints) if i > 0}
        n = model.nq
        self.G = G = np.zeros((m.nv, n))
        self.q0 = np.zeros(m.nq)
        dof = np.full(n, -1)
        coupled = []

        def locked_value(name: str) -> float:
            if name in model.locked:
                return model.locked[name]
            if name in mimic:
                src, mult, off = mimic[name]
                return mult * locked_value(src) + off
            raise ValueError(f'joint {name!r}: MuJoCo made a joint our model does not have')

        for j in range(m.njnt):
            name = m.joint(j).name
            if m.jnt_type[j] not in kinds:
                raise ValueError(f'joint {name!r}: not a revolute, continuous or prismatic '
                                 f'joint (MuJoCo type {m.jnt_type[j]}); not simulated')
            a, v = m.jnt_qposadr[j], m.jnt_dofadr[j]
            if name in body_of:
                i = body_of[name]
                k = model.qidx[i]
                G[v, k] = model.qmul[i]
                self.q0[a] = model.qoff[i]
                if name == self.joint_names[k]:
                    dof[k] = v
                else:
                    coupled.append(f'{name} (mimic of {self.joint_names[k]})')
            else:
                self.q0[a] = locked_value(name)
                coupled.append(f'{name} (locked at {self.q0[a]:g})')
        missing = [self.joint_names[k] for k in range(n) if dof[k] < 0]
        if missing or m.nq != m.nv:
            raise ValueError(f'MuJoCo did not make the joints {missing} of the URDF')
        self._dof = dof                  # MuJoCo dof (= qpos index) of each joint of q
        self._coupled = coupled
        #: Whether MuJoCo has degrees of freedom beyond q (mimic or locked joints).
        self.constrained = bool(coupled)

    def _vector(self, what: str, x) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        if x.shape != (self.model.nq,):
            raise ValueError(f'{what}: expected {self.model.nq} values for '
                             f'{list(self.joint_names)}, got shape {x.shape}')
        if not np.isfinite(x).all():
            raise ValueError(f'{what}: non-finite value for joint '
                             f'{self.joint_names[int(np.argmin(np.isfinite(x)))]!r}')
        return x

    # ----------------------------------------------------------------------------------------
    # State

    @property
    def q(self) -> np.ndarray:
        """Return the joint positions (n,), rad or m."""
        return self.d.qpos[self._dof].copy()

    @property
    def qd(self) -> np.ndarray:
        """Return the joint velocities (n,), rad/s or m/s."""
        return self.d.qvel[self._dof].copy()

    @property
    def time(self) -> float:
        """Return the seconds simulated since the start."""
        return float(self.d.time)

    def set_state(self, q, qd=None) -> None:
        """Put the robot at ``q`` with velocity ``qd`` (default 0); time is kept.

        ``q`` is also where a diverged simulation restarts (:meth:`step`).
        """
        q = self._vector('q', q)
        qd = np.zeros_like(q) if qd is None else self._vector('qd', qd)
        for what, x, bound in (('q', q, MAX_POSITION), ('qd', qd, MAX_VELOCITY)):
            reason = check_bounded(what, x, bound, 'rad or m (/s)', self.joint_names)
            if reason:
                raise ValueError(reason)
        self.home = q.copy()
        self.d.qpos[:] = self.G @ q + self.q0
        self.d.qvel[:] = self.G @ qd
        self.d.qacc_warmstart[:] = 0.0
        self._mj.mj_forward(self.m, self.d)

    def step(self, tau, n: int = 1) -> None:
        """Advance ``n`` physics steps with joint torques ``tau`` (n,) held constant.

        ``tau`` acts on q (``qfrc_applied`` of each joint's dof) and MuJoCo steps
        (``mj_step``). With mimic or locked joints, the state is ``(q, q̇)`` and the step is
        ours, Euler or RK4 on ``q̈ = FD(q, q̇, τ)`` from :meth:`_reduced_qdd`.
        """
        tau = self._vector('tau', tau)
        m, d, mj = self.m, self.d, self._mj
        f = np.zeros(m.nv)
        f[self._dof] = tau
        for _ in range(int(n)):
            if self.constrained:
                self._reduced_step(f)
            else:
                if self._wrenches:
                    mj.mj_kinematics(m, d)
                    self._apply_wrenches(d)
                d.qfrc_applied[:] = f
                mj.mj_step(m, d)
            self._check_state()

    def _check_state(self) -> None:
        """Restart at :attr:`home` at rest when the state left what a robot can reach.

        A torque far beyond the robot (1e6 N m on a finger of a few grams) drives any explicit
        integrator into non-finite numbers that never leave again. As MuJoCo does on a bad
        acceleration (``mjWARN_BADQACC``), the simulation restarts instead (time is kept), and
        :attr:`resets` and :attr:`reset_reason` say it: a simulated robot never reports NaN.
        """
        q, qd = self.q, self.qd
        reason = (check_bounded('position', q, MAX_POSITION, 'rad or m', self.joint_names)
                  or check_bounded('velocity', qd, MAX_VELOCITY, 'rad/s or m/s',
                                   self.joint_names))
        if reason:
            self.resets += 1
            self.reset_reason = f'at t = {self.time:.6g} s the {reason}'
            self.set_state(self.home)

    def _reduced_qdd(self, q: np.ndarray, qd: np.ndarray, f: np.ndarray) -> np.ndarray:
        """Forward dynamics of q with mimic and locked joints, by Gauss's principle.

        MuJoCo's accelerations of all its dofs, ``a0 = M⁻¹(f + f_ext - c)`` (``mj_forward``
        at ``q_mj = G q + q0``, ``q̇_mj = G q̇``), projected onto the motions ``G q̈`` allowed:
        ``(GᵀMG) q̈ = GᵀM a0``, i.e. the reduced dynamics ``M_q q̈ = τ - c_q``.
        """
        m, d, mj = self.m, self.d, self._mj
        d.qpos[:] = self.G @ q + self.q0
        d.qvel[:] = self.G @ qd
        if self._wrenches:
            mj.mj_kinematics(m, d)
            self._apply_wrenches(d)
        d.qfrc_applied[:] = f
        mj.mj_forward(m, d)
        mj.mj_fullM(m, d, self._M)
        MG = self._M @ self.G
        return np.linalg.solve(self.G.T @ MG, MG.T @ d.qacc)

    def _reduced_step(self, f: np.ndarray) -> None:
        """One step of ``(q, q̇)``: semi-implicit Euler (as MuJoCo's) or classical RK4."""
        h, q, qd = self.m.opt.timestep, self.q, self.qd
        a1 = self._reduced_qdd(q, qd, f)
        if self.integrator == 'euler':
            qd = qd + h * a1
            q = q + h * qd
        else:
            v2 = qd + 0.5 * h * a1
            a2 = self._reduced_qdd(q + 0.5 * h * qd, v2, f)
            v3 = qd + 0.5 * h * a2
            a3 = self._reduced_qdd(q + 0.5 * h * v2, v3, f)
            v4 = qd + h * a3
            a4 = self._reduced_qdd(q + h * v3, v4, f)
            q = q + h / 6.0 * (qd + 2.0 * v2 + 2.0 * v3 + v4)
            qd = qd + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
        self.d.qpos[:] = self.G @ q + self.q0
        self.d.qvel[:] = self.G @ qd
        self.d.time += h

    # ----------------------------------------------------------------------------------------
    # External wrenches

    def apply_wrench(self, link: str, wrench) -> None:
        """Apply a spatial force ``[n; f]`` (N m, N) to ``link`` from the next step on.

        Angular first, expressed in ``link``'s frame and taken about its origin: the
        convention of ``f_ext`` in :func:`spatial_dynamics.rnea`. The wrench is fixed in
        the link (it turns with it) and stays until replaced; ``None`` removes it. It is
        converted at each step into MuJoCo's ``xfrc_applied`` of the link's body (world
        coordinates, force first, torque about the body's centre of mass).
        """
        hold_wrench(self._wrenches, self.model, self.m, link, wrench)

    def _apply_wrenches(self, d) -> None:
        d.xfrc_applied[:] = 0.0
        for body, wrench in self._wrenches.values():
            d.xfrc_applied[body] += xfrc(d, body, wrench)

    # ----------------------------------------------------------------------------------------
    # Inverse dynamics

    def inverse(self, q, qd, qdd, f_ext: Optional[Mapping[str, np.ndarray]] = None
                ) -> np.ndarray:
        """Return MuJoCo's inverse dynamics (``mj_inverse``) in our joint order, (n,).

        ``τ = Gᵀ qfrc_inverse(G q + q0, G q̇, G q̈) - Gᵀ Jᵀ f_ext``: mimic torques fold onto
        their source with the multiplier, locked joints' reactions drop out. It includes
        ``damping·q̇``, ``armature·q̈`` and friction loss (constraint forces from MuJoCo's
        inverse constraint model) of this robot. ``f_ext`` as in :func:`spatial_dynamics.rnea`
        (link → ``[n; f]`` in the link's frame); the wrenches of :meth:`apply_wrench` are not
        included.
        """
        q, qd, qdd = self._vector('q', q), self._vector('qd', qd), self._vector('qdd', qdd)
        d, mj = self._scratch, self._mj
        d.qpos[:] = self.G @ q + self.q0
        d.qvel[:] = self.G @ qd
        d.qacc[:] = self.G @ qdd
        d.xfrc_applied[:] = 0.0
        mj.mj_inverse(self.m, d)
        tau = self.G.T @ d.qfrc_inverse
        if f_ext:
            qfrc = np.zeros(self.m.nv)
            for link, wrench in f_ext.items():
                body = self.m.body(link).id
                push = xfrc(d, body, np.asarray(wrench, dtype=float))
                mj.mj_applyFT(self.m, d, push[:3], push[3:], d.xipos[body], body, qfrc)
            tau = tau - self.G.T @ qfrc
        return tau


class FloatingRobot:
    """A floating-base robot of a URDF standing on a floor in MuJoCo, in our coordinates.

    The URDF's rigid-body robot as :func:`mujoco_model` makes it, its root link on MuJoCo's
    free joint, with a floor and a geom per :class:`Foot` (the only contacts). The state is
    that of ``Model.from_urdf(urdf, base='floating')`` (``self.model``): ``q`` (nq) = base
    position (world), quaternion **x y z w**, joints; ``v`` (nv) = base twist ``[ω; v]`` in the
    base frame, joints. MuJoCo's free joint has ``qpos`` = position, quaternion **w x y z**
    and ``qvel`` = ``[ṗ; ω]``, the origin's velocity in **world** axes then ``ω`` in the base
    frame, so (``R`` the base's orientation, exact both ways)::

        qvel = [R v_b; ω_b]      qacc = [R (v̇_b + ω_b × v_b); ω̇_b]     qfrc = [R f_b; n_b]

    (the last by duality: ``qfrcᵀ qvel = [n; f]ᵀ [ω; v]``). Contacts: :data:`CONTACT`
    (stiff soft contacts, elliptic cones); integrator semi-implicit Euler, ``timestep``
    0.5 ms by default. Joint torques act on the joints; the base has no motor.
    """

    def __init__(self, urdf: Source, feet: Sequence[Foot] = (), timestep: float = 5e-4,
                 gravity: Sequence[float] = GRAVITY) -> None:
        mujoco = import_mujoco()
        self._mj = mujoco
        xml = urdf_text(urdf)
        self.model = model = Model.from_urdf(xml.encode('utf-8'), base='floating')
        if model.mimics:
            raise ValueError(f'FloatingRobot: mimic joints are not simulated '
                             f'({", ".join(sorted(model.mimics))}); fix them with '
                             f'without_mimic(urdf)')
        if not (np.isfinite(timestep) and timestep > 0.0):
            raise ValueError(f'timestep must be a positive number of seconds, got {timestep}')
        self.feet = tuple(feet)
        for foot in self.feet:     # MuJoCo's spec.body('world') is the world: never a foot
            if foot.contact.link not in model.frames:
                raise ValueError(f'foot {foot.contact.name!r}: no link {foot.contact.link!r} '
                                 f'in robot {model.name!r}')
        self.m = m = mujoco_model(xml, gravity, base='floating', feet=self.feet)
        m.opt.timestep = float(timestep)
        m.opt.integrator = mujoco.mjtIntegrator.mjINT_EULER
        m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_EULERDAMP)
        self.joint_names = model.joint_names[1:]
        self._qadr = np.array([m.jnt_qposadr[m.joint(n).id] for n in self.joint_names], int)
        self._vadr = np.array([m.jnt_dofadr[m.joint(n).id] for n in self.joint_names], int)
        if m.nq != model.nq or m.nv != model.nv:
            raise ValueError(f'MuJoCo made {m.nq} coordinates and {m.nv} velocities, our model '
                             f'{model.nq} and {model.nv}')
        self._foot_of = {m.geom(f.contact.name).id: k for k, f in enumerate(self.feet)}
        self.integrator = 'euler'
        self.d = mujoco.MjData(m)
        self._scratch = mujoco.MjData(m)
        self._wrenches: dict = {}
        self.resets = 0          # restarts after a bad acceleration or a diverged state
        self.reset_reason = ''
        self._q_names = ('base x', 'base y', 'base z', 'base qx', 'base qy', 'base qz',
                         'base qw') + tuple(self.joint_names)
        self._v_names = ('base angular x', 'base angular y', 'base angular z',
                         'base linear x', 'base linear y', 'base linear z'
                         ) + tuple(self.joint_names)
        q = np.zeros(model.nq)
        q[6] = 1.0
        self.set_state(q)

    # ----------------------------------------------------------------------------------------
    # Our coordinates <-> MuJoCo's

    def _rotation(self, quat_xyzw: np.ndarray) -> np.ndarray:
        R = np.zeros(9)
        x, y, z, w = quat_xyzw
        self._mj.mju_quat2Mat(R, np.array([w, x, y, z]) / np.linalg.norm(quat_xyzw))
        return R.reshape(3, 3)

    def to_mujoco(self, q, v=None, a=None) -> tuple:
        """Return MuJoCo's ``(qpos, qvel, qacc)`` of our ``(q, v, a)`` (zeros when omitted)."""
        q = self._vector('q', q, self.model.nq)
        v = np.zeros(self.model.nv) if v is None else self._vector('v', v, self.model.nv)
        a = np.zeros(self.model.nv) if a is None else self._vector('a', a, self.model.nv)
        R = self._rotation(q[3:7])
        qpos, qvel, qacc = np.zeros(self.m.nq), np.zeros(self.m.nv), np.zeros(self.m.nv)
        qpos[:3], qpos[3], qpos[4:7] = q[:3], q[6], q[3:6]
        qvel[:3], qvel[3:6] = R @ v[3:6], v[:3]
        qacc[:3], qacc[3:6] = R @ (a[3:6] + np.cross(v[:3], v[3:6])), a[:3]
        qpos[self._qadr], qvel[self._vadr], qacc[self._vadr] = q[7:], v[6:], a[6:]
        return qpos, qvel, qacc

    def from_mujoco(self, qpos, qvel) -> tuple:
        """Return our ``(q, v)`` of MuJoCo's ``(qpos, qvel)``."""
        q, v = np.zeros(self.model.nq), np.zeros(self.model.nv)
        q[:3], q[3:6], q[6] = qpos[:3], qpos[4:7], qpos[3]
        R = self._rotation(q[3:7])
        v[:3], v[3:6] = qvel[3:6], R.T @ qvel[:3]
        q[7:], v[6:] = qpos[self._qadr], qvel[self._vadr]
        return q, v

    def _vector(self, what: str, x, size: int) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        if x.shape != (size,) or not np.isfinite(x).all():
            raise ValueError(f'{what}: expected {size} finite values, got shape {x.shape}')
        return x

    # ----------------------------------------------------------------------------------------
    # State and steps

    @property
    def q(self) -> np.ndarray:
        """Return our configuration (nq,): base position, quaternion x y z w, joints."""
        return self.from_mujoco(self.d.qpos, self.d.qvel)[0]

    @property
    def v(self) -> np.ndarray:
        """Return our velocity (nv,): base ``[ω; v]`` in the base frame, joints."""
        return self.from_mujoco(self.d.qpos, self.d.qvel)[1]

    @property
    def time(self) -> float:
        """Return the seconds simulated since the start."""
        return float(self.d.time)

    @property
    def qd(self) -> np.ndarray:
        """Return the joints' velocities (nv - 6,), in the order of :attr:`joint_names`."""
        return self.d.qvel[self._vadr].copy()

    def on_floor(self, joint_positions=None) -> np.ndarray:
        """Return ``q`` standing: upright above the origin, its lowest foot on the floor.

        The joints at ``joint_positions`` (default 0); the foot touches, it does not press.
        """
        q = np.zeros(self.model.nq)
        q[6] = 1.0
        if joint_positions is not None:
            q[7:] = self._vector('joint positions', joint_positions, self.model.nq - 7)
        if self.feet:
            self._scratch.qpos[:] = self.to_mujoco(q)[0]
            self._mj.mj_kinematics(self.m, self._scratch)
            q[2] = -min(p[2] - (f.size[0] if f.contact.kind == 'point' else 0.0)
                        for f, p in zip(self.feet, self._contact_points(self._scratch)))
        return q

    def set_state(self, q, v=None) -> None:
        """Put the robot at ``q`` with velocity ``v`` (default 0); time is kept.

        ``q`` is also where the simulation restarts if it diverges (:meth:`step`).
        """
        self.d.qpos[:], self.d.qvel[:], _ = self.to_mujoco(q, v)
        self.home = np.array(q, dtype=float)
        self.d.qacc_warmstart[:] = 0.0
        self._mj.mj_forward(self.m, self.d)

    def step(self, tau, n: int = 1) -> None:
        """Advance ``n`` steps with joint torques ``tau`` (nv - 6,) held constant.

        When MuJoCo finds a bad acceleration (``mjWARN_BADQACC``: a torque far beyond the
        robot), it restarts; the robot then restarts at :attr:`home` at rest instead, and
        :attr:`resets` and :attr:`reset_reason` say so. So it does when the state leaves what
        a robot reaches (a position beyond ±``MAX_POSITION``, a velocity beyond
        ±``MAX_VELOCITY``), as :meth:`SimulatedRobot.step`.
        """
        tau = self._vector('tau', tau, self.model.nv - 6)
        m, d, mj = self.m, self.d, self._mj
        bad = d.warning[int(mj.mjtWarning.mjWARN_BADQACC)]
        for _ in range(int(n)):
            if self._wrenches:
                mj.mj_kinematics(m, d)
                d.xfrc_applied[:] = 0.0
                for body, wrench in self._wrenches.values():
                    d.xfrc_applied[body] += xfrc(d, body, wrench)
            d.qfrc_applied[:] = 0.0
            d.qfrc_applied[self._vadr] = tau
            count = bad.number
            mj.mj_step(m, d)
            if bad.number != count:
                self.resets += 1
                self.reset_reason = (f'at t = {self.time:.6g} s MuJoCo found a bad '
                                     f'acceleration (dof {bad.lastinfo})')
                self.set_state(self.home)
                continue
            q, v = self.from_mujoco(d.qpos, d.qvel)
            reason = (check_bounded('position', q, MAX_POSITION, 'rad or m', self._q_names)
                      or check_bounded('velocity', v, MAX_VELOCITY, 'rad/s or m/s',
                                       self._v_names))
            if reason:
                self.resets += 1
                self.reset_reason = f'at t = {self.time:.6g} s the {reason}'
                self.set_state(self.home)

    def apply_wrench(self, link: str, wrench) -> None:
        """Apply ``[n; f]`` (link frame, about its origin) from the next step on.

        ``None`` removes it, as :meth:`SimulatedRobot.apply_wrench`.
        """
        hold_wrench(self._wrenches, self.model, self.m, link, wrench)
        if not self._wrenches:
            self.d.xfrc_applied[:] = 0.0

    # ----------------------------------------------------------------------------------------
    # Inverse dynamics and contact forces

    def inverse(self, q, v, a) -> np.ndarray:
        """Return MuJoCo's ``mj_inverse`` in our coordinates (nv,), contacts off.

        The base's six rows are the wrench ``[n; f]`` (base frame, about its origin) that
        makes the motion, as :func:`spatial_dynamics.rnea` gives it: ``[qfrc[3:6];
        Rᵀ qfrc[:3]]``.
        """
        d, mj = self._scratch, self._mj
        d.qpos[:], d.qvel[:], d.qacc[:] = self.to_mujoco(q, v, a)
        flags = self.m.opt.disableflags
        self.m.opt.disableflags |= int(mj.mjtDisableBit.mjDSBL_CONSTRAINT)
        try:
            mj.mj_inverse(self.m, d)
        finally:
            self.m.opt.disableflags = flags
        R = self._rotation(np.asarray(q, dtype=float)[3:7])
        f = d.qfrc_inverse
        return np.r_[f[3:6], R.T @ f[:3], f[self._vadr]]

    def contact_forces(self) -> dict:
        """Return what the floor exerts on each foot now, by contact name (world axes).

        MuJoCo's contact forces (``mj_contactForce``, contact frame) turned into world axes
        and summed per foot: a force (3,) for a point contact, a wrench ``[n; f]`` (6,) about
        the contact's point for a surface contact, as
        :class:`~spatial_dynamics.ContactResult` gives them. Feet off the floor: zeros.
        """
        m, d, mj = self.m, self.d, self._mj
        out = {f.contact.name: np.zeros(f.contact.rows) for f in self.feet}
        points = self._contact_points(d)
        f6 = np.zeros(6)
        for i in range(d.ncon):
            con = d.contact[i]
            g1, g2 = int(con.geom[0]), int(con.geom[1])
            if g2 in self._foot_of:
                k, sign = self._foot_of[g2], 1.0
            elif g1 in self._foot_of:
                k, sign = self._foot_of[g1], -1.0
            else:
                continue
            mj.mj_contactForce(m, d, i, f6)
            f = sign * con.frame.reshape(3, 3).T @ f6[:3]
            c = self.feet[k].contact
            if c.kind == 'point':
                out[c.name] += f
            else:
                out[c.name] += np.r_[np.cross(con.pos - points[k], f), f]
        return out

    def _contact_points(self, d) -> list:
        """World position of each foot's contact point in ``d`` (after its kinematics)."""
        out = []
        for foot in self.feet:
            b = self.m.body(foot.contact.link).id
            out.append(d.xpos[b] + d.xmat[b].reshape(3, 3) @ foot.contact.offset)
        return out

    def frame_pose(self, q, link: str) -> tuple:
        """Return ``(R, p)`` of ``link``'s frame at our ``q``: orientation and origin (world)."""
        d, mj = self._scratch, self._mj
        d.qpos[:] = self.to_mujoco(q)[0]
        mj.mj_kinematics(self.m, d)
        b = self.m.body(link).id
        return d.xmat[b].reshape(3, 3).copy(), d.xpos[b].copy()
