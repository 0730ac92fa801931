# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Shared test helpers: example-robot-data URDF paths and a Pinocchio oracle.

The oracle maps our joint order (``model.joint_names``) to Pinocchio's by joint name, expands
continuous joints to Pinocchio's (cos, sin) coordinates, and models every ``<mimic>`` joint as an
independent joint driven by q = multiplier * q_src + offset, folding its torque back onto the
source joint (tau_src += multiplier * tau_mimic). Pinocchio is linear-first; we are
angular-first.
"""

import os
import re
import sys
import sysconfig
import xml.etree.ElementTree as ET

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from urdf_gen import mimic_table, MOVABLE  # noqa: E402
# The node tests' fixtures (install, driver, demo_model); importing them needs no ROS.
from node_harness import demo_model, driver, install  # noqa: E402,F401

ROBOT_FILES = {
    # Panda with its hand: two fixed sibling links (tcp, fingers) and a <mimic> finger.
    'panda': ('panda_description', 'urdf', 'panda.urdf'),
    'ur5': ('ur_description', 'urdf', 'ur5_robot.urdf'),
    # Talos, full fixed-base tree: 44 revolute joints, 12 of them mimic (grippers).
    'talos': ('talos_data', 'robots', 'talos_full_v2.urdf'),
    # Talos, reduced tree: 32 revolute joints, no gripper mimic.
    'talos_reduced': ('talos_data', 'robots', 'talos_reduced.urdf'),
    'solo12': ('solo_description', 'robots', 'solo12.urdf'),
}


def example_robot_data_dir():
    """Return the example-robot-data 'robots' directory, or None when it is not installed."""
    candidates = []
    try:
        import example_robot_data
        candidates.append(example_robot_data.getModelPath('panda_description/urdf/panda.urdf'))
    except Exception:
        pass
    roots = [sysconfig.get_paths()['purelib'], sysconfig.get_paths()['platlib']]
    roots += [p for p in sys.path if p.endswith('site-packages')]
    try:
        import importlib.util
        spec = importlib.util.find_spec('pinocchio')
        if spec is not None and spec.origin is not None:
            path = os.path.dirname(spec.origin)
            while path != os.path.dirname(path):
                roots.append(path)
                path = os.path.dirname(path)
    except Exception:
        pass
    for root in roots:
        candidates.append(os.path.join(root, 'cmeel.prefix', 'share', 'example-robot-data',
                                       'robots'))
        candidates.append(os.path.join(root, 'share', 'example-robot-data', 'robots'))
    for c in candidates:
        if c and os.path.isfile(os.path.join(c, *ROBOT_FILES['panda'])):
            return c
        if c and os.path.isfile(os.path.join(c, 'robots', *ROBOT_FILES['panda'])):
            return os.path.join(c, 'robots')
    return None


def robot_urdf_path(robot):
    """Return the path of an example-robot-data URDF, skipping the test when it is missing."""
    base = example_robot_data_dir()
    if base is None:
        pytest.skip('example-robot-data is not installed')
    path = os.path.join(base, *ROBOT_FILES[robot])
    if not os.path.isfile(path):
        pytest.skip(f'{path} not found')
    return path


def read_text(source):
    """Return URDF XML text from a path or from the XML itself."""
    if source.lstrip().startswith('<'):
        return source
    with open(source, encoding='utf-8') as f:
        return f.read()


def strip_mimic(urdf_xml):
    """Return the URDF text with every <mimic .../> tag removed (not <mimicJoint> plugins)."""
    return re.sub(r'<mimic\b(?:[^>]*/>|[^>]*>.*?</mimic\s*>)', '', urdf_xml, flags=re.S)


class PinOracle:
    """Pinocchio 4 on the same URDF, fixed base, mimic joints as independent joints."""

    def __init__(self, source):
        """Build the Pinocchio model of a URDF given as a path or an XML string."""
        import pinocchio as pin
        self.pin = pin
        self.xml = read_text(source)
        self.mimic = mimic_table(self.xml)
        self.model = pin.buildModelFromXML(strip_mimic(self.xml))
        self.model.armature[:] = 0.0
        self.data = self.model.createData()
        self.joints = {}  # name -> (idx_q, idx_v, nq)
        for jid in range(1, self.model.njoints):
            jm = self.model.joints[jid]
            assert jm.nv == 1, self.model.names[jid]
            self.joints[self.model.names[jid]] = (jm.idx_q, jm.idx_v, jm.nq)
        root = ET.fromstring(self.xml.encode())
        self.movable = [j.get('name') for j in root.iter('joint') if j.get('type') in MOVABLE
                        and j.get('name') not in self.mimic]
        assert set(self.movable) | set(self.mimic) == set(self.joints)

    def velocity_map(self, joint_names, q):
        """Return Pinocchio's q at our ``q`` and ``P`` with ``v_pin = P q̇`` (mimic joints).

        Our inertia is then ``Pᵀ M_pin P`` and our generalized forces ``Pᵀ τ_pin``.
        """
        n = len(joint_names)
        q_pin, _, _ = self.expand(joint_names, q, np.zeros(n), np.zeros(n))
        P = np.stack([self.expand(joint_names, q, e, np.zeros(n))[1] for e in np.eye(n)],
                     axis=1)
        return q_pin, P

    def expand(self, joint_names, q, qd, qdd):
        """Return Pinocchio's (q, v, a) for one state given in our joint order."""
        value = {}
        for k, name in enumerate(joint_names):
            value[name] = (q[k], qd[k], qdd[k])
        for name, (src, mult, offset) in self.mimic.items():
            qs, qds, qdds = value[src]
            value[name] = (mult * qs + offset, mult * qds, mult * qdds)
        q_pin = np.zeros(self.model.nq)
        v_pin = np.zeros(self.model.nv)
        a_pin = np.zeros(self.model.nv)
        for name, (iq, iv, nq) in self.joints.items():
            qi, qdi, qddi = value[name]
            if nq == 2:
                q_pin[iq:iq + 2] = np.cos(qi), np.sin(qi)
            else:
                q_pin[iq] = qi
            v_pin[iv] = qdi
            a_pin[iv] = qddi
        return q_pin, v_pin, a_pin

    def fold(self, joint_names, tau_pin):
        """Return Pinocchio's torque in our joint order, mimic torques folded onto sources."""
        tau = {name: tau_pin[iv] for name, (iq, iv, nq) in self.joints.items()}
        for name, (src, mult, offset) in self.mimic.items():
            tau[src] += mult * tau[name]
        return np.array([tau[name] for name in joint_names])

    def set_gravity(self, gravity):
        """Set the gravity vector (root frame, m/s^2)."""
        self.model.gravity.linear = np.asarray(gravity, dtype=float)

    def fext(self, f_ext):
        """Return Pinocchio's fext list from our {link: [n; f] in link frame} dict."""
        pin = self.pin
        forces = [pin.Force.Zero() for _ in range(self.model.njoints)]
        for link, wrench in (f_ext or {}).items():
            fid = self.model.getFrameId(link, pin.FrameType.BODY)
            assert fid < self.model.nframes, link
            frame = self.model.frames[fid]
            wrench = np.asarray(wrench, dtype=float)
            f_link = pin.Force(wrench[3:], wrench[:3])  # linear, angular
            forces[frame.parentJoint] += frame.placement.act(f_link)
        return forces

    def rnea(self, joint_names, q, qd, qdd, gravity=(0.0, 0.0, -9.81), f_ext=None):
        """Return inverse dynamics torques in our joint order; q, qd, qdd of shape (..., n)."""
        q, qd, qdd = (np.asarray(x, dtype=float) for x in (q, qd, qdd))
        self.set_gravity(gravity)
        n = len(joint_names)
        shape = q.shape
        Q, QD, QDD = (x.reshape(-1, n) for x in (q, qd, qdd))
        out = np.empty_like(Q)
        for k in range(Q.shape[0]):
            args = self.expand(joint_names, Q[k], QD[k], QDD[k])
            if f_ext is None:
                tau_pin = self.pin.rnea(self.model, self.data, *args)
            else:
                tau_pin = self.pin.rnea(self.model, self.data, *args, self.fext(f_ext))
            out[k] = self.fold(joint_names, tau_pin)
        return out.reshape(shape)

    def potential_energy(self, joint_names, q, gravity=(0.0, 0.0, -9.81)):
        """Return Pinocchio's potential energy V = -sum_i m_i g . c_i (J) at one state."""
        self.set_gravity(gravity)
        z = np.zeros(len(joint_names))
        q_pin = self.expand(joint_names, q, z, z)[0]
        return self.pin.computePotentialEnergy(self.model, self.data, q_pin)

    def kinetic_energy(self, joint_names, q, qd):
        """Return Pinocchio's kinetic energy (J) at one state."""
        z = np.zeros(len(joint_names))
        q_pin, v_pin, _ = self.expand(joint_names, q, qd, z)
        return self.pin.computeKineticEnergy(self.model, self.data, q_pin, v_pin)


def refusal(call):
    """Return the exception ``call()`` raises as (type, message), or None when it answers."""
    try:
        call()
    except Exception as err:        # the type and message are what is compared
        return type(err), str(err)
    return None


def random_state(rng, shape, n, scale=(1.5, 2.0, 3.0)):
    """Return random (q, qd, qdd) of shape shape + (n,)."""
    size = tuple(shape) + (n,)
    return tuple(rng.uniform(-s, s, size=size) for s in scale)


def to_pin(x):
    """Our velocity ([ω; v] first) to Pinocchio's free-flyer order ([v; ω] first)."""
    return np.concatenate([x[..., 3:6], x[..., 0:3], x[..., 6:]], axis=-1)


def unit_quaternions(rng, n):
    """Return ``n`` random unit quaternions (n, 4)."""
    quat = rng.normal(size=(n, 4))
    return quat / np.linalg.norm(quat, axis=-1, keepdims=True)


def least_torque_split(Jc, b, tol):
    """Return the contact-consistent least-torque split by an SVD: ``(τ, λ, rank)``.

    ``J_cᵀ = U Σ Vᵀ``; the rank counts the singular values above ``tol`` times ``J_c``'s
    largest row norm (asserted clear of it by a factor 100 either way); ``U2 = U[:, r:]``
    spans what the contacts cannot push, so ``τ`` is the least solution of
    ``U2ᵀ Sᵀ τ = U2ᵀ b`` and ``λ = V1 Σ1⁻¹ U1ᵀ (b - Sᵀ τ)`` the least contact forces.
    """
    floor = tol * np.linalg.norm(Jc, axis=1).max()
    U, s, Vt = np.linalg.svd(Jc.T)
    assert not np.any((s > floor / 100) & (s < floor * 100)), (s, floor)
    r = int(np.sum(s > floor))
    U1, U2 = U[:, :r], U[:, r:]
    tau = np.linalg.lstsq(U2[6:].T, U2.T @ b, rcond=None)[0]
    lam = Vt[:r].T @ ((U1.T @ (b - np.r_[np.zeros(6), tau])) / s[:r])
    return tau, lam, r


@pytest.fixture
def handlers_kept():
    """Restore SIGINT's and SIGTERM's handlers after a tool's ``main`` installed its own."""
    import signal
    previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    yield
    for s, handler in previous.items():
        signal.signal(s, handler)


@pytest.fixture
def rng():
    """Return a seeded random generator."""
    return np.random.default_rng(20260121)


def pytest_collection_modifyitems(config, items):
    """Refuse a test that talks DDS (the ``driver`` fixture) without the ``ros`` marker.

    The fast loop (``-m "not ros and not slow"``) must not start a node; a test that does and
    is not marked would slip into it.
    """
    unmarked = [item.nodeid for item in items
                if 'driver' in getattr(item, 'fixturenames', ())
                and item.get_closest_marker('ros') is None]
    if unmarked:
        raise pytest.UsageError('DDS tests without the ros marker: ' + ', '.join(unmarked))


#: One link on one revolute joint, and a second on a prismatic one: small enough to read.
TWO_JOINTS = """<robot name="two">
  <link name="base"/>
  <link name="a"><inertial><origin xyz="0.1 0 0.2"/><mass value="2"/>
    <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.3"/></inertial></link>
  <link name="b"><inertial><origin xyz="0 0.1 0"/><mass value="1"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.03"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/>
    <axis xyz="0 1 0"/><limit effort="10" velocity="1" lower="-3" upper="3"/></joint>
  <joint name="j2" type="prismatic"><parent link="a"/><child link="b"/><origin xyz="0 0 0.5"/>
    <axis xyz="1 0 0"/><limit effort="10" velocity="1" lower="-3" upper="3"/></joint>
</robot>"""
