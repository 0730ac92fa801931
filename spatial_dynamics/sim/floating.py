# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A floating-base robot of a URDF on a floor, simulated by MuJoCo, in our coordinates.

:class:`FloatingRobot`: the MuJoCo model of :func:`~.mujoco_model.mujoco_model` with its root
link on a free joint and the feet's contacts with a floor, read and written in the
coordinates of ``Model.from_urdf(urdf, base='floating')`` (no ROS).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from spatial_dynamics import GRAVITY, Model
from spatial_dynamics.bounds import check_bounded, MAX_POSITION, MAX_VELOCITY

from .mujoco_model import (Foot, hold_wrench, import_mujoco, mujoco_model, Source, urdf_text,
                           xfrc)


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

    (the last by duality: ``qfrcᵀ qvel = [n; f]ᵀ [ω; v]``). Contacts:
    :data:`~.mujoco_model.CONTACT` (stiff soft contacts, elliptic cones); integrator
    semi-implicit Euler, ``timestep`` 0.5 ms by default. Joint torques act on the joints; the
    base has no motor.
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
        ±``MAX_VELOCITY``), as :meth:`.robot.SimulatedRobot.step`.
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

        ``None`` removes it, as :meth:`.robot.SimulatedRobot.apply_wrench`.
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
