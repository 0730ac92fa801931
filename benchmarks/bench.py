# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Run time against error: ``python -m benchmarks.bench [--quick] [--out DIR]``.

Every implementation gets the same states of the same robot in one process:

* ours, ``backend='numpy'``: float64 (a single call on one 1-D state runs on plain Python
  floats, a batch on numpy arrays), float32 and ``np.longdouble`` (numpy arrays, also for
  one state); and ``backend='compiled'`` when the package was built with its C kernels;
* peers, when importable and when they model the same URDF: Pinocchio ``pin.rnea`` (single
  call, and looped from Python for a batch) and its C++ batch ``pin.rneaInParallel``,
  MuJoCo ``mj_inverse`` (damping, armature and friction loss zeroed, constraints disabled)
  and PyBullet ``calculateInverseDynamics`` (``URDF_USE_INERTIA_FROM_FILE``; not on robots
  with links without ``<inertial>`` (it makes them 1 kg), with rotated inertial frames (its
  inverse dynamics gets them wrong) or with more than 128 DOF (wrong beyond)).

Figures: the median single-call time, the median time per sample of a batch of N = 1, 100
and 10,000 states, and the error against a high-precision reference: our RNEA (the component
kernel of :mod:`spatial_dynamics.algorithms.rnea`) evaluated in mpmath at 50 digits on our
float64 parameters, cross-checked against Pinocchio. Timings interleave the implementations
round-robin, and the medians are also given as ratios to Pinocchio (these machines are noisy).

Peers see our joint order mapped by joint name: continuous joints become Pinocchio's
(cos, sin) pair; ``<mimic>`` joints, which peers treat as independent joints, are driven with
``mult·q_src + offset`` and their torques folded back onto the source with ``mult``. Input and
output conversions are never timed; single calls cycle through 32 distinct states. Idle
OpenMP threads are told to sleep (``OMP_WAIT_POLICY=PASSIVE`` unless set) so that they do not
slow down the next implementation. Writes ``DIR/results.csv``, ``DIR/runtime_vs_error.png``
and ``DIR/scaling.png``, and prints markdown tables on stdout; progress goes to stderr.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
from dataclasses import dataclass, field
import functools
import gc
import importlib.metadata
import os
from pathlib import Path
import re
import statistics
import sys
import sysconfig
import tempfile
import time
from types import SimpleNamespace
from typing import Callable, Optional
import xml.etree.ElementTree as ET

import numpy as np

import spatial_dynamics as sd
from spatial_dynamics.tools.driving import demo_urdf
from benchmarks.generate import chain_urdf, tree_urdf
from spatial_dynamics.joints import PR, RA
from spatial_dynamics.backends import layout, python as python_backend
from spatial_dynamics.sim.mujoco_model import dynamics_only, mujoco_model

GRAVITY = (0.0, 0.0, -9.81)
SIZES = (1, 100, 10_000)
DIGITS = 50
CHAINS = (7, 30, 100, 300)
TREE = 40
ROBOTS = ('demo_arm', 'panda', 'ur5', 'talos') + tuple(f'chain{n}' for n in CHAINS) \
    + (f'tree{TREE}',)
#: example-robot-data files (the Talos tree without its gripper mimic joints: 32 DOF).
ERD_FILES = {'panda': 'panda_description/urdf/panda.urdf',
             'ur5': 'ur_description/urdf/ur5_robot.urdf',
             'talos': 'talos_data/robots/talos_reduced.urdf'}
REFERENCE = 'pinocchio'
#: Measured: PyBullet's calculateInverseDynamics is right on a 128-link chain, wrong beyond.
PYBULLET_MAX_DOF = 128


@dataclass(frozen=True)
class Settings:
    """How much to measure: states for the reference, timing rounds and block lengths."""

    ref_states: int
    rounds: int            # round-robin repeats of the single-call and N = 1, 100 timings
    rounds_big: int        # ... of N = 10,000
    block_s: float         # a timed block lasts at least this long (several calls)
    states: int = 32       # distinct states cycled through by the single-call timing
    sizes: tuple = SIZES   # batch sizes N


FULL = Settings(ref_states=5, rounds=9, rounds_big=5, block_s=0.02)
QUICK = Settings(ref_states=3, rounds=5, rounds_big=3, block_s=0.005)
QUICK_ROBOTS = ('demo_arm', 'panda', 'ur5', 'talos', 'chain7', 'chain30', f'tree{TREE}')


class Skip(Exception):
    """An implementation does not apply to a robot; the message says why."""


@dataclass
class Robot:
    """A URDF (as text), our model of it, and per-robot peer set-up shared by entries."""

    name: str
    xml: str
    model: sd.Model
    family: str                       # 'robot', 'chain' or 'tree'
    cache: dict = field(default_factory=dict)

    @property
    def mimic(self) -> dict:
        """``{mimic joint: (our q index, multiplier, offset)}``, resolved to a joint of q."""
        return _mimic_table(self.model.mimics, self.model.joint_names)


@dataclass
class Call:
    """One way to compute τ: ``run(*prep(q, qd, qdd))`` is timed, ``tau(result)`` is not.

    For a single call ``prep`` takes one state (n,) and ``tau`` returns (n,); for a batch
    both handle (N, n). Arrays are float64 in our joint order.
    """

    prep: Callable
    run: Callable
    tau: Callable


@dataclass(frozen=True)
class Impl:
    """A benchmark entry: name, and factories ``Robot -> Call`` (or None) that may raise Skip."""

    name: str
    single: Optional[Callable[[Robot], Call]]
    batched: Optional[Callable[[Robot], Call]]


# --------------------------------------------------------------------------------------------
# Robots


def _erd_dir() -> Optional[Path]:
    """example-robot-data's ``robots`` directory (pip puts it under cmeel.prefix), or None."""
    roots = [sysconfig.get_paths()['purelib'], sysconfig.get_paths()['platlib']]
    roots += [p for p in sys.path if p.endswith('site-packages')]
    for root in roots:
        d = Path(root, 'cmeel.prefix', 'share', 'example-robot-data', 'robots')
        if (d / ERD_FILES['panda']).is_file():
            return d
    try:
        import example_robot_data
        return Path(example_robot_data.getModelPath(ERD_FILES['panda'])).parent
    except Exception:
        return None


def load_robot(name: str) -> Robot:
    """Return a benchmark robot by name (see ROBOTS); raises Skip when it is not installed."""
    if name.startswith('chain'):
        xml, family = chain_urdf(int(name[5:])), 'chain'
    elif name.startswith('tree'):
        xml, family = tree_urdf(int(name[4:])), 'tree'
    elif name == 'demo_arm':
        path = Path(demo_urdf())
        if not path.is_file():
            raise Skip('config/demo_arm.urdf not found')
        xml, family = path.read_text(encoding='utf-8'), 'robot'
    elif name in ERD_FILES:
        erd = _erd_dir()
        if erd is None or not (erd / ERD_FILES[name]).is_file():
            raise Skip('example-robot-data is not installed')
        xml, family = (erd / ERD_FILES[name]).read_text(encoding='utf-8'), 'robot'
    else:
        raise Skip(f'unknown robot (known: {", ".join(ROBOTS)})')
    return Robot(name, xml, sd.Model.from_urdf(xml), family)


def random_states(model: sd.Model, rng: np.random.Generator, N: int) -> tuple:
    """N random states (N, n): q uniform in finite joint limits (else ±π), q̇ in ±2, q̈ in ±5."""
    n = model.nq
    lo = np.where(np.isfinite(model.lower), model.lower, -np.pi)
    hi = np.where(np.isfinite(model.upper), model.upper, np.pi)
    return (rng.uniform(lo, hi, (N, n)), rng.uniform(-2.0, 2.0, (N, n)),
            rng.uniform(-5.0, 5.0, (N, n)))


def _mimic_table(direct, joint_names) -> dict:
    """``{mimic joint: (our q index, mult, offset)}`` with chains of mimics resolved.

    ``direct`` is the model's record of the URDF's tags (``Model.mimics``: source,
    multiplier, offset as written, a source may itself be a mimic joint).
    """
    index = {name: k for k, name in enumerate(joint_names)}
    table = {}
    for name in direct:
        mult, off, src = 1.0, 0.0, name
        while src in direct:
            src, m, o = direct[src]
            mult, off = mult * m, mult * o + off
        table[name] = (index[src], mult, off)
    return table


def _peer_joints(robot: Robot, names) -> tuple:
    """For peer joints ``names``: our q index, multiplier and offset of each (arrays)."""
    index = {name: k for k, name in enumerate(robot.model.joint_names)}
    mimic = robot.mimic
    K, MUL, OFF = [], [], []
    for name in names:
        k, mult, off = mimic.get(name, (index.get(name), 1.0, 0.0))
        if k is None:
            raise Skip(f'joint {name!r} is not in our model')
        K.append(k)
        MUL.append(mult)
        OFF.append(off)
    return np.array(K, dtype=np.intp), np.array(MUL), np.array(OFF)


def _fold(K: np.ndarray, MUL: np.ndarray, n: int, tau_peer: np.ndarray) -> np.ndarray:
    """Peer torques (N, len(K)) back to ours (N, n): τ_src += mult·τ_mimic."""
    out = np.zeros(tau_peer.shape[:-1] + (n,))
    for j, (k, mult) in enumerate(zip(K, MUL)):
        out[..., k] += tau_peer[..., j] if mult == 1.0 else mult * tau_peer[..., j]
    return out


_dynamics_only = dynamics_only   # no <visual>, <collision>: meshes a peer would load


# --------------------------------------------------------------------------------------------
# Our implementations


def _ours(dtype, single: bool, backend: str = 'numpy') -> Callable[[Robot], Call]:
    """Entry factory for ``sd.rnea`` on arrays of ``dtype`` with ``backend``."""
    def make(robot: Robot) -> Call:
        model = robot.model
        z = np.zeros(model.nq if single else (2, model.nq), dtype=dtype)
        try:
            sd.rnea(model, z, z, z, GRAVITY, None, backend)   # probe: is the backend there?
        except (TypeError, ImportError, ValueError, NotImplementedError) as err:
            raise Skip(f'{type(err).__name__}: {err}') from None

        def prep(q, qd, qdd):
            # sd.rnea(model, q, qd, qdd, gravity, f_ext, backend), all positional: the cost
            # of a plain call (a keyword through functools.partial would add ~0.1 µs)
            return (model, q.astype(dtype), qd.astype(dtype), qdd.astype(dtype), GRAVITY,
                    None, backend)

        return Call(prep, sd.rnea, np.asarray)
    return make


# --------------------------------------------------------------------------------------------
# Pinocchio


def _pin(robot: Robot) -> SimpleNamespace:
    """Pinocchio on the same URDF (mimic tags stripped: independent joints), shared per robot."""
    if 'pin' not in robot.cache:
        try:
            import pinocchio as pin
        except ImportError:
            raise Skip('pinocchio is not installed') from None
        xml = re.sub(r'<mimic\b(?:[^>]*/>|[^>]*>.*?</mimic\s*>)', '', robot.xml, flags=re.S)
        pm = pin.buildModelFromXML(xml)
        pm.armature[:] = 0.0
        pm.gravity.linear = np.array(GRAVITY)
        names = list(pm.names)[1:]          # (each pm.<vector>[j] copies the whole vector)
        jm = list(pm.joints)[1:]
        if any(j.nv != 1 for j in jm):
            raise Skip('Pinocchio built a joint with several DOF')
        K, MUL, OFF = _peer_joints(robot, names)
        robot.cache['pin'] = SimpleNamespace(
            pin=pin, model=pm, K=K, MUL=MUL, OFF=OFF,
            iq=np.array([j.idx_q for j in jm]), iv=np.array([j.idx_v for j in jm]),
            nq2=np.array([j.nq == 2 for j in jm]))
    return robot.cache['pin']


def _pin_expand(P: SimpleNamespace, Q, QD, QDD) -> tuple:
    """Our (N, n) states to Pinocchio's (N, nq), (N, nv), (N, nv)."""
    theta = Q[..., P.K] * P.MUL + P.OFF
    qp = np.zeros(Q.shape[:-1] + (P.model.nq,))
    one = ~P.nq2
    qp[..., P.iq[one]] = theta[..., one]
    qp[..., P.iq[P.nq2]] = np.cos(theta[..., P.nq2])
    qp[..., P.iq[P.nq2] + 1] = np.sin(theta[..., P.nq2])
    vp = np.zeros(Q.shape[:-1] + (P.model.nv,))
    ap = np.zeros(Q.shape[:-1] + (P.model.nv,))
    vp[..., P.iv] = QD[..., P.K] * P.MUL
    ap[..., P.iv] = QDD[..., P.K] * P.MUL
    return qp, vp, ap


def _pin_single(robot: Robot) -> Call:
    P = _pin(robot)
    if not hasattr(P, 'data'):
        P.data = P.model.createData()     # (takes seconds beyond ~300 joints in pin 4.1)

    def prep(q, qd, qdd):
        return (P.model, P.data) + _pin_expand(P, q, qd, qdd)

    return Call(prep, P.pin.rnea, lambda tau: _fold(P.K, P.MUL, robot.model.nq, tau[P.iv]))


def _pin_parallel(threads: int) -> Callable[[Robot], Call]:
    """Pinocchio's own batch loop in C++, ``rneaInParallel(threads, pool, q, v, a)``."""
    def make(robot: Robot) -> Call:
        P = _pin(robot)
        if not hasattr(P.pin, 'rneaInParallel'):
            raise Skip('this Pinocchio has no rneaInParallel')
        pool = P.pin.ModelPool(P.model, threads)

        def prep(Q, QD, QDD):
            return (threads, pool) + tuple(np.asfortranarray(x.T) for x in
                                           _pin_expand(P, Q, QD, QDD))

        return Call(prep, P.pin.rneaInParallel,
                    lambda tau: _fold(P.K, P.MUL, robot.model.nq, tau.T[:, P.iv]))
    return make


def pinocchio_reference_rows(robot: Robot, mp) -> tuple:
    """Return layout rows with Pinocchio's own float64 parameters as exact mpmath numbers.

    The component kernel reads only the rows of :mod:`spatial_dynamics.backends.layout`; this
    builds them from Pinocchio's joint placements ``(R, p)`` (E = Rᵀ, r = p), motion
    subspaces (the axes) and inertias ``(m, c, Ic)``, with ``h = m c`` and
    ``Ibar = Ic + m c× c×ᵀ`` (RBDA eq. 2.63) formed in mpmath. Evaluated in mpmath it gives
    the exact answer on Pinocchio's parameters, so Pinocchio's error against it is its
    arithmetic error alone, without the rounding of the URDF's decimal numbers into float64
    parameters (which differs between libraries).
    """
    P = _pin(robot)
    pm, f = P.model, mp.mpf
    q0 = P.pin.neutral(pm)
    joints, placements = list(pm.joints), list(pm.jointPlacements)
    inertias, parents = list(pm.inertias), list(pm.parents)
    rows = [(-1, 0, robot.model.nq, robot.model.nv, 0) + (0.0,) * (layout.WIDTH - 5)]
    for j in range(1, pm.njoints):
        jm = joints[j]
        jd = jm.createData()
        jm.calc(jd, q0)
        S = np.asarray(jd.S, dtype=float).ravel()          # linear first
        code = PR if np.any(S[:3]) else RA
        axis = tuple(float(a) for a in (S[:3] if code == PR else S[3:]))
        M = placements[j]
        Et = tuple(f(float(x)) for x in M.rotation.T.ravel())
        r = tuple(f(float(x)) for x in M.translation)
        inertia = inertias[j]
        m = f(float(inertia.mass))
        c = [f(float(x)) for x in inertia.lever]
        Ic = [[f(float(x)) for x in row] for row in inertia.inertia]
        cx = [[0, -c[2], c[1]], [c[2], 0, -c[0]], [-c[1], c[0], 0]]
        Ib = [[Ic[a][b] + m * sum(cx[a][k] * cx[b][k] for k in range(3)) for b in range(3)]
              for a in range(3)]
        k, mult, off = P.K[j - 1], P.MUL[j - 1], P.OFF[j - 1]
        rows.append((int(parents[j]), code, int(k), int(k), 1) + axis + Et + r + (m,)
                    + tuple(m * x for x in c)
                    + (Ib[0][0], Ib[0][1], Ib[0][2], Ib[1][1], Ib[1][2], Ib[2][2],
                       float(mult), float(off)))
    return tuple(rows)


# --------------------------------------------------------------------------------------------
# MuJoCo


def _mujoco_single(robot: Robot) -> Call:
    try:
        import mujoco
    except ImportError:
        raise Skip('mujoco is not installed') from None
    try:
        m = mujoco_model(robot.xml, GRAVITY)     # the URDF's rigid-body robot (sim.robot)
    except ValueError as err:
        raise Skip(str(err)) from None
    d = mujoco.MjData(m)
    joints = [m.joint(j) for j in range(m.njnt)]
    if m.nq != m.njnt or m.nv != m.njnt:
        raise Skip('MuJoCo made joints with several DOF')
    K, MUL, OFF = _peer_joints(robot, [j.name for j in joints])
    iq = np.array([j.qposadr[0] for j in joints])
    iv = np.array([j.dofadr[0] for j in joints])
    inverse = mujoco.mj_inverse

    def prep(q, qd, qdd):
        qpos, qvel, qacc = np.zeros(m.nq), np.zeros(m.nv), np.zeros(m.nv)
        qpos[iq] = q[K] * MUL + OFF
        qvel[iv] = qd[K] * MUL
        qacc[iv] = qdd[K] * MUL
        return qpos, qvel, qacc

    def run(qpos, qvel, qacc):
        d.qpos[:] = qpos
        d.qvel[:] = qvel
        d.qacc[:] = qacc
        inverse(m, d)
        return d.qfrc_inverse.copy()

    return Call(prep, run, lambda tau: _fold(K, MUL, robot.model.nq, tau[iv]))


# --------------------------------------------------------------------------------------------
# PyBullet


def _pybullet_single(robot: Robot) -> Call:
    try:
        import pybullet as pb
    except ImportError:
        raise Skip('pybullet is not installed') from None
    root = ET.fromstring(robot.xml.encode())
    for link in root.findall('link'):
        inertial = link.find('inertial')
        has_parent = any(j.find('child').get('link') == link.get('name')
                         for j in root.findall('joint'))
        if inertial is None and has_parent:
            raise Skip(f'link {link.get("name")!r} has no <inertial>: PyBullet makes it 1 kg')
        origin = None if inertial is None else inertial.find('origin')
        rpy = [] if origin is None else [float(x) for x in origin.get('rpy', '0 0 0').split()]
        if any(rpy):
            raise Skip(f'link {link.get("name")!r} has a rotated <inertial> frame, which '
                       "PyBullet's inverse dynamics mishandles")
    if 'pybullet' not in robot.cache:
        client = pb.connect(pb.DIRECT)
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, f'{robot.name}.urdf')
            with open(path, 'w', encoding='utf-8') as fh:
                fh.write(_dynamics_only(robot.xml))
            body = pb.loadURDF(path, useFixedBase=True, flags=pb.URDF_USE_INERTIA_FROM_FILE,
                               physicsClientId=client)
        pb.setGravity(*GRAVITY, physicsClientId=client)
        names = []
        for j in range(pb.getNumJoints(body, physicsClientId=client)):
            info = pb.getJointInfo(body, j, physicsClientId=client)
            if info[2] != pb.JOINT_FIXED:
                names.append(info[1].decode())
        robot.cache['pybullet'] = (client, body, names)
    client, body, names = robot.cache['pybullet']
    if len(names) > PYBULLET_MAX_DOF:
        raise Skip(f'{len(names)} DOF: PyBullet 3.2.7 returns wrong torques beyond '
                   f'{PYBULLET_MAX_DOF} DOF (a 129-link chain is off by 0.4 %)')
    K, MUL, OFF = _peer_joints(robot, names)
    run = functools.partial(pb.calculateInverseDynamics, body, physicsClientId=client)

    def prep(q, qd, qdd):
        return ((q[K] * MUL + OFF).tolist(), (qd[K] * MUL).tolist(), (qdd[K] * MUL).tolist())

    return Call(prep, run, lambda tau: _fold(K, MUL, robot.model.nq, np.asarray(tau)))


def _looped(single: Callable[[Robot], Call]) -> Callable[[Robot], Call]:
    """Make a batch a Python loop of single calls (how a peer without a batch API is used)."""
    def make(robot: Robot) -> Call:
        one = single(robot)
        run1 = one.run

        def prep(Q, QD, QDD):
            return ([one.prep(*s) for s in zip(Q, QD, QDD)],)

        def run(args):
            return [run1(*a) for a in args]

        return Call(prep, run, lambda out: np.array([one.tau(t) for t in out]))
    return make


def implementations() -> list:
    """All entries; the ones that do not apply (not installed, no such backend) skip later."""
    impls = [
        Impl('ours float64', _ours(np.float64, True), _ours(np.float64, False)),
        Impl('ours float32', _ours(np.float32, True), _ours(np.float32, False)),
        Impl('ours longdouble', _ours(np.longdouble, True), _ours(np.longdouble, False)),
        Impl('ours compiled', _ours(np.float64, True, 'compiled'),
             _ours(np.float64, False, 'compiled')),
        Impl('pinocchio', _pin_single, _looped(_pin_single)),
        Impl('pinocchio batch 1 thread', None, _pin_parallel(1)),
    ]
    threads = os.cpu_count() or 1
    if threads > 1:
        impls.append(Impl(f'pinocchio batch {threads} threads', None, _pin_parallel(threads)))
    impls += [Impl('mujoco', _mujoco_single, _looped(_mujoco_single)),
              Impl('pybullet', _pybullet_single, _looped(_pybullet_single))]
    return impls


# --------------------------------------------------------------------------------------------
# Reference and errors


def reference(model, Q, QD, QDD, digits: int = DIGITS) -> np.ndarray:
    """τ from the component kernel in mpmath at ``digits`` digits, as np.longdouble (K, n).

    ``model`` is a Model, or layout rows (:func:`pinocchio_reference_rows`).

    Python floats convert to mpf exactly, so this is the exact RNEA of the float64 inputs on
    the model's float64 parameters, up to 10^-digits (then rounded to long double, so that
    errors of long double results show too).
    """
    import mpmath
    with mpmath.workdps(digits):
        mpf = mpmath.mpf
        rows = layout.of(model).rows if isinstance(model, sd.Model) else model
        out = []
        for q, qd, qdd in zip(Q, QD, QDD):
            tau = python_backend.rnea_rows(rows, [mpf(float(x)) for x in q],
                                           [mpf(float(x)) for x in qd],
                                           [mpf(float(x)) for x in qdd],
                                           [mpf(g) for g in GRAVITY], None, mpmath)
            out.append([np.longdouble(mpmath.nstr(t, 25, strip_zeros=False)) for t in tau])
    return np.array(out, dtype=np.longdouble)


def _max_err(out, ref: np.ndarray) -> float:
    """Return max |out - ref| in long double (so long double results keep their digits)."""
    return float(np.abs(np.asarray(out).astype(np.longdouble) - ref).max())


# --------------------------------------------------------------------------------------------
# Timing


def _block(run: Callable, args: list, calls: int) -> float:
    """Seconds per call of ``run(*a)`` over ``calls`` calls cycling through ``args``."""
    seq = (args * (calls // len(args) + 1))[:calls]
    t0 = time.perf_counter()
    for a in seq:
        run(*a)
    return (time.perf_counter() - t0) / calls


def _calls_for(run: Callable, args: list, block_s: float) -> int:
    """Return the calls per block for a block of about ``block_s`` (from a warm-up call)."""
    t = _block(run, args, 1)
    if t < block_s / 20:
        t = _block(run, args, min(len(args), 20))
    return max(1, min(100_000, int(block_s / max(t, 1e-9))))


def interleaved(entries: dict, rounds: int, block_s: float, per: int) -> dict:
    """Median seconds per ``per`` (calls × samples) of each ``{name: (run, args)}``.

    One round times one block of every entry, the order rotated every round, so slow drifts
    of the machine hit all of them alike.
    """
    return {name: statistics.median(t)
            for name, t in interleaved_rounds(entries, rounds, block_s, per).items()}


def interleaved_rounds(entries: dict, rounds: int, block_s: float, per: int) -> dict:
    """Seconds per ``per`` of each entry in every round of :func:`interleaved` (a list each)."""
    calls = {name: _calls_for(run, args, block_s) for name, (run, args) in entries.items()}
    times = {name: [] for name in entries}
    names = list(entries)
    gc_was = gc.isenabled()
    gc.disable()
    try:
        for r in range(rounds):
            for name in names[r % len(names):] + names[:r % len(names)]:
                run, args = entries[name]
                times[name].append(_block(run, args, calls[name]) / per)
    finally:
        if gc_was:
            gc.enable()
    return times


# --------------------------------------------------------------------------------------------
# The run


class Progress:
    """Progress lines on stderr with the elapsed time."""

    def __init__(self) -> None:
        self.t0 = time.perf_counter()

    def __call__(self, msg: str) -> None:
        print(f'[bench {time.perf_counter() - self.t0:6.1f} s] {msg}', file=sys.stderr,
              flush=True)


def bench_robot(robot: Robot, impls: list, settings: Settings, log: Progress,
                seed: int = 0) -> tuple:
    """Measure every applicable implementation on one robot; returns (rows, check)."""
    model = robot.model
    rng = np.random.default_rng(seed)
    sizes = settings.sizes
    Q, QD, QDD = random_states(model, rng, max(sizes + (settings.states,)))
    K = settings.ref_states
    rows, singles, batches = {}, {}, {}
    for impl in impls:
        row = rows[impl.name] = {'robot': robot.name, 'dof': model.nq, 'bodies': model.NB,
                                 'implementation': impl.name, 'note': ''}
        for kind, factory, store in (('single', impl.single, singles),
                                     ('batched', impl.batched, batches)):
            if factory is None:
                continue
            try:
                store[impl.name] = factory(robot)
            except Skip as err:
                row['note'] = str(err)
        if impl.name not in singles and impl.name not in batches:
            log(f'{robot.name}: {impl.name} skipped: {row["note"]}')
            del rows[impl.name]

    # Errors against the mpmath reference on the first K states.
    check = {'robot': robot.name}
    log(f'{robot.name}: {model.nq} DOF, {model.NB} bodies; mpmath reference on {K} states')
    try:
        ref = reference(model, Q[:K], QD[:K], QDD[:K])
    except ImportError:
        ref = None
        log('mpmath is not installed: no errors')
    if ref is not None:
        scale = float(np.abs(ref).max())
        check['tau_scale'] = scale
        for name, row in rows.items():
            err = 0.0
            if name in singles:
                c = singles[name]
                out = [c.tau(c.run(*c.prep(Q[k], QD[k], QDD[k]))) for k in range(K)]
                err = max(err, _max_err(out, ref))
            if name in batches:
                c = batches[name]
                err = max(err, _max_err(c.tau(c.run(*c.prep(Q[:K], QD[:K], QDD[:K]))), ref))
            row.update(max_abs_err=err, tau_scale=scale, rel_err=err / scale)
            if err > 1e-6 * scale and not name.startswith('ours'):
                row['note'] = 'differs from the reference by > 1e-6: not the same model?'
                log(f'{robot.name}: {name}: {row["note"]}')
        if REFERENCE in singles:
            import mpmath
            pin_ref = reference(pinocchio_reference_rows(robot, mpmath), Q[:K], QD[:K], QDD[:K])
            c = singles[REFERENCE]
            out = [c.tau(c.run(*c.prep(Q[k], QD[k], QDD[k]))) for k in range(K)]
            check.update(ref_vs_pin=_max_err(out, ref) / scale,
                         param_gap=_max_err(pin_ref, ref) / scale,
                         pin_own_err=_max_err(out, pin_ref) / scale)
            for name in rows:
                if name.startswith(REFERENCE):
                    rows[name]['own_param_rel_err'] = check['pin_own_err']
        for name, row in rows.items():
            if name.startswith('ours'):
                row['own_param_rel_err'] = row['rel_err']

    # Single-call medians, all implementations interleaved.
    entries = {}
    for name, c in singles.items():
        entries[name] = (c.run, [c.prep(Q[k], QD[k], QDD[k]) for k in range(settings.states)])
    log(f'{robot.name}: single call, {len(entries)} implementations x {settings.rounds} rounds')
    for name, t in interleaved(entries, settings.rounds, settings.block_s, 1).items():
        rows[name]['single_us'] = 1e6 * t

    # Per-sample medians of batches of N.
    for N in sizes:
        entries = {name: (c.run, [c.prep(Q[:N], QD[:N], QDD[:N])])
                   for name, c in batches.items()}
        rounds = settings.rounds_big if N == max(sizes) else settings.rounds
        log(f'{robot.name}: batches of N = {N}, {len(entries)} implementations x {rounds} rounds')
        for name, t in interleaved(entries, rounds, settings.block_s, N).items():
            rows[name][f'n{N}_us'] = 1e6 * t
        del entries

    # Ratios to Pinocchio in the same run (single call; looped from Python for batches).
    base = rows.get(REFERENCE, {})
    for row in rows.values():
        for key in ['single_us'] + [f'n{N}_us' for N in sizes]:
            if key in row and key in base:
                row[key.replace('_us', '_vs_pin')] = row[key] / base[key]
    return list(rows.values()), check


def columns(sizes: tuple = SIZES) -> list:
    """Return the columns of results.csv."""
    return (['robot', 'dof', 'bodies', 'implementation', 'single_us']
            + [f'n{N}_us' for N in sizes] + ['single_vs_pin'] + [f'n{N}_vs_pin' for N in sizes]
            + ['max_abs_err', 'tau_scale', 'rel_err', 'own_param_rel_err', 'note'])


def write_csv(path: Path, rows: list, sizes: tuple = SIZES) -> None:
    """Write the result rows (all times in µs, errors in N m or N, ratios to Pinocchio)."""
    with open(path, 'w', newline='', encoding='utf-8') as fh:
        w = csv.DictWriter(fh, columns(sizes), extrasaction='ignore')
        w.writeheader()
        for row in rows:
            w.writerow({k: (f'{v:.6g}' if isinstance(v, float) else v) for k, v in row.items()})


def _us(x: Optional[float]) -> str:
    if x is None:
        return '–'
    return f'{x:.3g}' if x < 1000 else f'{x:,.0f}'


def _ratio(x: Optional[float]) -> str:
    return '–' if x is None else f'{x:.2g}×' if x < 10 else f'{x:,.0f}×'


def _err(x: Optional[float]) -> str:
    return '–' if x is None else f'{x:.1e}'


def markdown(rows: list, checks: list, sizes: tuple = SIZES) -> str:
    """Format the results as markdown: run time and error; the reference cross-check."""
    big = max(sizes)
    label = {N: f'{N // 1000}k' if N >= 1000 and N % 1000 == 0 else str(N) for N in sizes}
    head = ('| robot (DOF) | implementation | single call µs | ×pin | per sample µs, '
            + ' | '.join(f'N={label[N]}' for N in sizes)
            + f' | ×pin (N={label[big]}) | max abs error | relative error |')
    lines = [head, '|' + '---|' * (8 + len(sizes) - 1)]
    for r in rows:
        times = ' | '.join(_us(r.get(f'n{N}_us')) for N in sizes)
        lines.append(f"| {r['robot']} ({r['dof']}) | {r['implementation']} "
                     f"| {_us(r.get('single_us'))} | {_ratio(r.get('single_vs_pin'))} "
                     f"| {times} | {_ratio(r.get(f'n{big}_vs_pin'))} "
                     f"| {_err(r.get('max_abs_err'))} | {_err(r.get('rel_err'))} |")
    lines += ['', 'Reference cross-check, relative to max |τ_ref| (mpmath, 50 digits):', '',
              '| robot | max \\|τ_ref\\| | Pinocchio vs reference '
              '| Pinocchio vs mpmath on its own parameters '
              '| mpmath on our parameters vs on Pinocchio\'s |', '|---|---|---|---|---|']
    for c in checks:
        lines.append(f"| {c['robot']} | {c.get('tau_scale', float('nan')):.3g} "
                     f"| {_err(c.get('ref_vs_pin'))} | {_err(c.get('pin_own_err'))} "
                     f"| {_err(c.get('param_gap'))} |")
    return '\n'.join(lines)


# --------------------------------------------------------------------------------------------
# Figures

ERR_FLOOR = 1e-21


def _pareto(points: list) -> list:
    """Return the indices of the points (time, error) that no other point beats in both."""
    return [i for i, (t, e) in enumerate(points)
            if not any((t2 <= t and e2 <= e) and (t2 < t or e2 < e) for t2, e2 in points)]


def plot(rows: list, out: Path, log: Progress, sizes: tuple = SIZES) -> list:
    """Write runtime_vs_error.png and scaling.png; returns the paths (none without matplotlib)."""
    try:
        import matplotlib
        matplotlib.use('Agg')
        import matplotlib.pyplot as plt
    except ImportError:
        log('matplotlib is not installed: no plots')
        return []
    impls = list(dict.fromkeys(r['implementation'] for r in rows))
    robots = list(dict.fromkeys(r['robot'] for r in rows))
    colour = {name: plt.get_cmap('tab10')(i % 10) for i, name in enumerate(impls)}
    markers = 'osD^v<>pPXh*'
    marker = {name: markers[i % len(markers)] for i, name in enumerate(robots)}

    fig, axes = plt.subplots(1, 2, figsize=(14, 6.5), sharey=True)
    for ax, key, title in ((axes[0], 'single_us', 'single call'),
                           (axes[1], f'n{max(sizes)}_us',
                            f'per sample, batch of N = {max(sizes):,}')):
        for robot in robots:
            pts = [(r[key], max(r['rel_err'], ERR_FLOOR), r['implementation']) for r in rows
                   if r['robot'] == robot and key in r and 'rel_err' in r]
            for t, e, name in pts:
                ax.scatter(t, e, color=colour[name], marker=marker[robot], s=40, zorder=3)
            front = sorted(pts[i] for i in _pareto([(t, e) for t, e, _ in pts]))
            if front:
                ax.step([p[0] for p in front], [p[1] for p in front], where='post',
                        color='0.5', lw=0.7, alpha=0.5, zorder=1)
                ax.scatter([p[0] for p in front], [p[1] for p in front], s=130,
                           facecolors='none', edgecolors='k', lw=1.0, zorder=4)
        ax.set_xscale('log')
        ax.set_yscale('log')
        ax.set_xlabel(f'time, {title} (µs)')
        ax.grid(True, which='major', alpha=0.3)
    axes[0].set_ylabel('max |τ − τ_ref| / max |τ_ref|  (mpmath reference, 50 digits)')
    handles = [plt.Line2D([], [], color=colour[n], marker='o', ls='', label=n) for n in impls]
    handles += [plt.Line2D([], [], color='0.3', marker=marker[r], ls='', label=r)
                for r in robots]
    handles.append(plt.Line2D([], [], marker='o', ms=11, mfc='none', mec='k', ls='-',
                              color='0.6', label='Pareto front (per robot)'))
    fig.legend(handles=handles, loc='center right', fontsize=8)
    fig.suptitle('Run time against error (one point per implementation × robot; '
                 'lower left is better)')
    fig.tight_layout(rect=(0, 0, 0.83, 0.95))
    paths = [out / 'runtime_vs_error.png']
    fig.savefig(paths[0], dpi=110)
    plt.close(fig)

    chain = [r for r in rows if r['robot'].startswith('chain')]
    if chain:
        fig, axes = plt.subplots(2, 2, figsize=(13, 9))
        panels = (('single_us', 'single call (µs)'),
                  (f'n{max(sizes)}_us', f'per sample, batch of N = {max(sizes):,} (µs)'),
                  ('max_abs_err', 'max |τ − τ_ref| (N m)'),
                  ('rel_err', 'max |τ − τ_ref| / max |τ_ref|'))
        links = sorted({r['bodies'] for r in chain})
        for ax, (key, label) in zip(axes.ravel(), panels):
            for name in impls:
                pts = sorted((r['bodies'], r[key]) for r in chain
                             if r['implementation'] == name and key in r)
                if pts:
                    ax.plot([p[0] for p in pts], [max(p[1], ERR_FLOOR) for p in pts], 'o-',
                            color=colour[name], label=name)
            ax.set_xscale('log')
            ax.set_yscale('log')
            ax.set_xticks(links, [str(n) for n in links])
            ax.minorticks_off()
            ax.set_xlabel('links in the serial chain')
            ax.set_ylabel(label)
            ax.grid(True, which='major', alpha=0.3)
        handles = [plt.Line2D([], [], color=colour[n], marker='o', label=n) for n in impls
                   if any(r['implementation'] == n for r in chain)]
        fig.legend(handles=handles, loc='center right', fontsize=8)
        fig.suptitle('Scaling with chain length (generated chains, same states for all)')
        fig.tight_layout(rect=(0, 0, 0.84, 0.96))
        paths.append(out / 'scaling.png')
        fig.savefig(paths[1], dpi=110)
        plt.close(fig)
    return paths


@contextlib.contextmanager
def _stdout_to_stderr():
    """Send file descriptor 1 to stderr for a while (C libraries printing to stdout)."""
    sys.stdout.flush()
    try:
        saved = os.dup(1)
    except OSError:           # no real stdout (embedded use): nothing to redirect
        yield
        return
    os.dup2(2, 1)
    try:
        yield
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)


def versions() -> str:
    """Name the machine, its load and the versions of everything measured, in one line."""
    parts = [f'python {sys.version.split()[0]}', f'numpy {np.__version__}',
             f'spatial_dynamics {sd.__version__}']
    try:
        from spatial_dynamics import backends
        parts.append(f"ours compiled = {backends.describe('compiled')}")
    except Exception as err:        # built without the compiled kernels
        parts.append(f'ours compiled: {type(err).__name__}')
    for dist in ('pin', 'mujoco', 'pybullet', 'mpmath'):
        try:
            parts.append(f'{dist} {importlib.metadata.version(dist)}')
        except importlib.metadata.PackageNotFoundError:
            parts.append(f'{dist} not installed')
    parts.append(f'{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f}')
    parts.append(f"OMP_WAIT_POLICY={os.environ.get('OMP_WAIT_POLICY', '')}")
    return ', '.join(parts)


def skipped_work_table(rounds: int = 9) -> str:
    """Markdown table: single-call time of what the model and state let us skip.

    Model reduction (one Talos arm of the 32-joint tree: the others locked and lumped, the
    rest pruned) and the runtime fast paths (q̇ = 0 skips every velocity-product term,
    q̇ = q̈ = 0 everything but gravity, zero gravity the base's acceleration), for each
    backend, medians of ``rounds``.
    """
    try:
        robot = load_robot('talos')
    except Skip as err:
        return f'(skipped-work table: {err})'
    full = robot.model
    arm = [j for j in full.joint_names if j.startswith('arm_left_')]
    reduced = sd.Model.from_urdf(robot.xml, joints=arm)
    rng = np.random.default_rng(11)
    backends = ['numpy'] + (['compiled'] if _has_compiled() else [])
    rows = ['| robot, case | backend | single call µs | vs whole Talos, new q each call |',
            '|---|---|---|---|']
    no_g = (0.0, 0.0, 0.0)
    for backend in backends:
        cases = []
        for label, model in (('whole Talos (32 dof)', full),
                             ('left arm only (7 dof, reduced)', reduced)):
            states = [rng.uniform(-1, 1, (3, model.nq)) for _ in range(32)]
            z = np.zeros(model.nq)
            for case, args in (
                    ('new q each call', [(q, qd, qdd, GRAVITY) for q, qd, qdd in states]),
                    ('q̇ = 0 (gravity + inertia)', [(q, z, qdd, GRAVITY) for q, _, qdd in states]),
                    ('q̇ = q̈ = 0 (gravity only)', [(q, z, z, GRAVITY) for q, _, _ in states]),
                    ('zero gravity', [(q, qd, qdd, no_g) for q, qd, qdd in states])):
                cases.append((f'{label}, {case}', model,
                              [(model,) + a + (None, backend) for a in args]))
        times = {label: [] for label, _, _ in cases}
        for _ in range(rounds):                      # interleaved rounds
            for label, _, calls in cases:
                t0 = time.perf_counter()
                for a in calls:
                    sd.rnea(*a)
                times[label].append((time.perf_counter() - t0) / len(calls) * 1e6)
        base = statistics.median(times[cases[0][0]])
        for label, _, _ in cases:
            t = statistics.median(times[label])
            rows.append(f'| {label} | {backend} | {t:.3g} | {t / base:.2f}× |')
    return '\n'.join(rows)


def terms_table(names: list, rounds: int = 9) -> str:
    """Markdown table: g(q), C q̇ + g and M(q) (CRBA), ours against Pinocchio's, single call.

    Ours on the default backend (``'auto'``) vs ``computeGeneralizedGravity``,
    ``nonLinearEffects`` and ``crba`` (which fills the upper triangle only), medians of
    ``rounds`` interleaved rounds over 32 random states; the error is the largest difference
    relative to max(1, the largest entry), over those states.
    """
    rows = ['| robot | term | ours µs | Pinocchio µs | ratio | max rel. difference |',
            '|---|---|---|---|---|---|']
    rng = np.random.default_rng(12)
    for name in [r for r in ('ur5', 'panda', 'talos') if r in names]:
        try:
            robot = load_robot(name)
            P = _pin(robot)
        except Skip as err:
            rows.append(f'| {name} | skipped: {err} | | | | |')
            continue
        model, n = robot.model, robot.model.nq
        data = P.model.createData()
        Q, QD = rng.uniform(-1, 1, (32, n)), rng.uniform(-1, 1, (32, n))
        QP, VP, _ = _pin_expand(P, Q, QD, QD)
        S = np.zeros((P.model.nv, n))           # v_pin = S q̇ (mimic followers)
        S[P.iv, P.K] = P.MUL
        pin = P.pin
        cases = (
            ('g(q)', lambda s: sd.gravity_torque(model, Q[s]),
             lambda s: pin.computeGeneralizedGravity(P.model, data, QP[s]),
             lambda out: S.T @ out),
            ('C q̇ + g', lambda s: sd.bias_torque(model, Q[s], QD[s]),
             lambda s: pin.nonLinearEffects(P.model, data, QP[s], VP[s]),
             lambda out: S.T @ out),
            ('M(q)', lambda s: sd.mass_matrix(model, Q[s]),
             lambda s: pin.crba(P.model, data, QP[s]),
             lambda out: S.T @ (np.triu(out) + np.triu(out, 1).T) @ S))
        for term, ours, theirs, convert in cases:
            err = 0.0
            for s in range(32):
                ref = convert(np.array(theirs(s)))
                err = max(err, float(np.abs(ours(s) - ref).max()
                                     / max(1.0, float(np.abs(ref).max()))))
            t_ours, t_pin = [], []
            for _ in range(rounds):
                for fn, acc in ((ours, t_ours), (theirs, t_pin)):
                    t0 = time.perf_counter()
                    for s in range(32):
                        fn(s)
                    acc.append((time.perf_counter() - t0) / 32 * 1e6)
            a, b = statistics.median(t_ours), statistics.median(t_pin)
            rows.append(f'| {name} ({n} dof) | {term} | {a:.3g} | {b:.3g} | {a / b:.2f}× '
                        f'| {err:.1e} |')
    return '\n'.join(rows)


def regressor_table(names: list, rounds: int = 5, N: int = 20_000) -> str:
    """Markdown table: the joint-torque regressor ``Y`` per state, against ``rnea``.

    ``sd.regressor`` on each backend and the 6×6 specification (``regressor_spatial``, numpy),
    one call on one state (median over 32 states) and a batch of ``N`` states per state
    (medians of ``rounds``), beside ``sd.rnea`` on the same backend and states, and
    Pinocchio's ``computeJointTorqueRegressor`` (one state) where importable. Run alone:
    ``python -c "from benchmarks import bench; print(bench.regressor_table(['ur5',
    'panda']))"``.
    """
    from spatial_dynamics.algorithms.regressor import regressor_spatial
    rows = ['| robot | implementation | one state µs | batch µs/state | rnea batch µs/state '
            '| ratio to rnea (batch) |', '|---|---|---|---|---|---|']
    rng = np.random.default_rng(13)
    for name in names:
        try:
            robot = load_robot(name)
        except Skip as err:
            rows.append(f'| {name} | skipped: {err} | | | | |')
            continue
        model, n = robot.model, robot.model.nq
        Q, QD, QDD = rng.uniform(-1, 1, (3, N, n))
        impls = [(f'sd.regressor, {b}', functools.partial(sd.regressor, backend=b),
                  functools.partial(sd.rnea, backend=b))
                 for b in ('numpy',) + (('compiled',) if _has_compiled() else ())]
        impls.append(('6×6 specification', regressor_spatial,
                      functools.partial(sd.rnea, backend='numpy')))
        for label, fn, rnea in impls:
            one, big, ref = [], [], []
            for _ in range(rounds):
                t0 = time.perf_counter()
                for s in range(32):
                    fn(model, Q[s], QD[s], QDD[s])
                one.append((time.perf_counter() - t0) / 32 * 1e6)
                for f, acc in ((fn, big), (rnea, ref)):
                    t0 = time.perf_counter()
                    f(model, Q, QD, QDD)
                    acc.append((time.perf_counter() - t0) / N * 1e6)
            a, b = statistics.median(big), statistics.median(ref)
            rows.append(f'| {name} ({n} dof) | {label} | {statistics.median(one):.3g} '
                        f'| {a:.3g} | {b:.3g} | {a / b:.1f}× |')
        try:
            P = _pin(robot)
        except Skip:
            continue
        data = P.model.createData()
        QP, VP, AP = _pin_expand(P, Q[:32], QD[:32], QDD[:32])
        one = []
        for _ in range(rounds):
            t0 = time.perf_counter()
            for s in range(32):
                P.pin.computeJointTorqueRegressor(P.model, data, QP[s], VP[s], AP[s])
            one.append((time.perf_counter() - t0) / 32 * 1e6)
        rows.append(f'| {name} ({n} dof) | Pinocchio computeJointTorqueRegressor '
                    f'| {statistics.median(one):.3g} | | | |')
    return '\n'.join(rows)


def _has_compiled() -> bool:
    from spatial_dynamics.backends import compiled
    return compiled.ext is not None


def main(argv: Optional[list] = None) -> int:
    """Command-line entry point."""
    parser = argparse.ArgumentParser(
        prog='python -m benchmarks.bench', description=__doc__.split('\n')[0])
    parser.add_argument('--quick', action='store_true',
                        help='fewer robots, states and rounds (under 2 minutes)')
    parser.add_argument('--out', default='out/bench', type=Path,
                        help='output directory (default: out/bench)')
    parser.add_argument('--robots', nargs='+', metavar='ROBOT',
                        help=f'robots to run (default: all; known: {" ".join(ROBOTS)})')
    parser.add_argument('--impls', nargs='+', metavar='NAME',
                        help='only implementations whose name starts with one of these')
    args = parser.parse_args(argv)
    # Idle OpenMP threads (Pinocchio's batch) sleep instead of spinning, so that they
    # do not slow down whichever implementation is timed next on a small machine.
    os.environ.setdefault('OMP_WAIT_POLICY', 'PASSIVE')
    settings = QUICK if args.quick else FULL
    names = args.robots or (QUICK_ROBOTS if args.quick else ROBOTS)
    impls = implementations()
    if args.impls:
        impls = [i for i in impls if any(i.name.startswith(p) for p in args.impls)]
    args.out.mkdir(parents=True, exist_ok=True)
    log = Progress()
    setup = versions()
    log(setup)
    rows, checks = [], []
    with _stdout_to_stderr():      # peers print from C (PyBullet); stdout is for the tables
        for i, name in enumerate(names, start=1):
            try:
                robot = load_robot(name)
            except Skip as err:
                log(f'[{i}/{len(names)}] {name}: skipped: {err}')
                continue
            log(f'[{i}/{len(names)}] {name}')
            robot_rows, check = bench_robot(robot, impls, settings, log)
            rows += robot_rows
            checks.append(check)
            write_csv(args.out / 'results.csv', rows, settings.sizes)
        skipped = skipped_work_table(settings.rounds) if 'talos' in names else ''
        terms = terms_table(names, settings.rounds)
        regressors = regressor_table([r for r in ('ur5', 'panda') if r in names],
                                     min(settings.rounds, 3), 2_000 if args.quick else 20_000)
    table = markdown(rows, checks, settings.sizes)
    if skipped:
        table += '\n\nWhat the code skips (single call, Talos):\n\n' + skipped
    if terms.count('\n') > 1:
        table += ('\n\nThe terms of τ = M q̈ + C q̇ + g (single call, indexing of the 32 '
                  'states included in both):\n\n' + terms)
    if regressors.count('\n') > 1:
        table += '\n\nThe joint-torque regressor Y (τ = Y π), per state:\n\n' + regressors
    paths = plot(rows, args.out, log, settings.sizes)
    print(f'Command: python -m benchmarks.bench {" ".join(argv or sys.argv[1:])}')
    print(f'Setup: {setup}\n')
    print(table)
    print(f'\nWrote {args.out / "results.csv"}' + ''.join(f', {p}' for p in paths)
          + f' (load average at the end: {os.getloadavg()[0]:.1f})')
    bad = [c['robot'] for c in checks if c.get('ref_vs_pin', 0.0) > 1e-12]
    if bad:
        print(f'WARNING: the mpmath reference and Pinocchio differ by more than 1e-12 (relative)'
              f' on {bad}', file=sys.stderr)
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
