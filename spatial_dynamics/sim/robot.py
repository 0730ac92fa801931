# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The URDF's rigid-body robot simulated by MuJoCo, driven by joint torques, in our joint order.

:class:`SimulatedRobot` runs the MuJoCo model of :func:`~.mujoco_model.mujoco_model` (the
URDF's rigid-body robot, no ROS) with the drive terms asked for and one of
:data:`INTEGRATORS`.

Mimic and locked joints (model reduction, ``joints`` / ``locked``) are simulated exactly:
MuJoCo keeps every URDF joint as a degree of freedom, and :class:`SimulatedRobot` constrains
its accelerations to ``q̈_mj = G q̈`` (``G`` maps our ``q`` to MuJoCo's: 1 for a joint of ``q``,
the multiplier for a mimic joint, 0 for a locked joint) by Gauss's principle, and the state
``(q, q̇)`` is integrated in those coordinates, so ``q_mj = G q + q0`` holds exactly (see
:meth:`SimulatedRobot.step`).

The floating-base robot on a floor is :class:`~.floating.FloatingRobot`; it and the loading
functions of :mod:`~.mujoco_model` are importable from here too, where they were first
documented.
"""

from __future__ import annotations

from typing import Mapping, Optional, Sequence

import numpy as np

from spatial_dynamics import GRAVITY, Model
from spatial_dynamics.bounds import check_bounded, MAX_POSITION, MAX_VELOCITY
from spatial_dynamics.terms import per_joint, PerJoint

from .floating import FloatingRobot
from .mujoco_model import (CONTACT, dynamics_only, Foot, hold_wrench, import_mujoco,
                           MUJOCO_MISSING, mujoco_model, MujocoMissing, Source, urdf_text,
                           without_mimic, xfrc)

__all__ = ['CONTACT', 'dynamics_only', 'FloatingRobot', 'Foot', 'import_mujoco', 'INTEGRATORS',
           'MUJOCO_MISSING', 'mujoco_model', 'MujocoMissing', 'SimulatedRobot', 'urdf_text',
           'without_mimic']

#: Integrators of :class:`SimulatedRobot`; ``auto`` is ``rk4``. Measured over 1 s from rest at
#: a random q, zero torque, 1 ms steps, against a 10 µs-step reference: on the UR5, rk4 ends
#: 3e-9 rad off and keeps the energy to 3e-9 J (9 µs a step), MuJoCo's semi-implicit euler
#: ends 2.7e-2 rad off and gains 0.4 J (3 µs a step); on the Panda arm euler ends 1.2 rad off.
#: (implicitfast differs from euler only through damping, which it makes implicit.)
INTEGRATORS = ('auto', 'euler', 'rk4')


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
