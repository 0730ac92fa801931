# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Run time against error for ∂τ/∂q and ∂τ/∂q̇: ``python -m benchmarks.derivatives [--quick]``.

Per robot (UR5, Panda, Solo12 on a free-flyer, Talos reduced on a free-flyer) every
implementation gets the same states; for each, the median time per state from Python
(interleaved rounds, as :mod:`benchmarks.bench` times) and, beside it, the least of the
rounds (the quietest block: what the call costs when nothing else takes the core, as
``timeit``'s best of N reports it), each as a multiple of Pinocchio's in the same run, and
the error against a 50-digit
reference: ``max |D - D_ref| / max |D_ref|`` over both matrices ``D = [∂τ/∂q, ∂τ/∂q̇]``.

* the reference: central differences of our own RNEA (the component kernel of
  :mod:`spatial_dynamics.algorithms.rnea`) evaluated in mpmath at 50 digits, step 1e-15
  (truncation ~1e-30, rounding ~1e-35; in q̇ the RNEA is quadratic, so its central
  difference is exact);
* ``sd.rnea_derivatives`` (the analytic derivatives), timed as the bare call, and with
  ``out=`` (three arrays made once and reused: a controller's loop, as Pinocchio's ``data``);
* central finite differences of ``sd.rnea`` with steps 1e-3 to 1e-8, the ``4 nv`` perturbed
  states of one state in one batched call;
* Pinocchio's ``computeRNEADerivatives`` (its free-flyer rows and columns ``[v; ω]`` mapped to
  our ``[ω; v]``, a mimic finger's columns folded as for ``rnea``, for the error), timed as
  the bare call.

Complex-step differentiation is not measured: every function of the library refuses complex
arrays (``TypeError: q must be real numbers``), as ``sd.rnea`` does.

On a floating base the derivative in ``q`` is taken on the tangent space, the columns in our
velocity order ``[ω; v; joints]``: ``d/dε τ(q ⊕ ε e_k)`` with ``q ⊕ δ`` the base moved along
``δ`` in its own frame (``sd.integrate``, Pinocchio's ``integrate``). Then forward dynamics:
``sd.forward_dynamics`` against ``pin.aba``, time per state and the largest relative
difference; and a batch of 10,000 states in one ``sd.rnea_derivatives`` call (bare, and
with ``out=`` arrays made once and reused across the rounds) against a Python loop of
``computeRNEADerivatives`` over the same states. Last, each speed target (:data:`TARGETS`)
robot by robot, met or not by the ratio of the least of the rounds, the median's beside it
(:func:`targets`). Writes ``DIR/derivatives.csv``, ``DIR/derivatives_targets.csv`` (the
targets' ratios in full) and ``DIR/derivatives_vs_error.png``, ``DIR`` checked before the
measurement; prints markdown tables on stdout, progress on stderr.
"""

from __future__ import annotations

import argparse
import csv
from dataclasses import dataclass
from functools import partial
import os
from pathlib import Path
import re
import statistics
import sys
from typing import Callable, Optional

import numpy as np

import spatial_dynamics as sd
from spatial_dynamics.backends import layout, python as python_backend
from spatial_dynamics.files import check_folder, check_output
from benchmarks.bench import _erd_dir, interleaved_rounds, Progress, versions

GRAVITY = (0.0, 0.0, -9.81)
DIGITS = 50
STEPS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8)
#: name -> (example-robot-data file, base)
ROBOTS = {'ur5': ('ur_description/urdf/ur5_robot.urdf', 'fixed'),
          'panda': ('panda_description/urdf/panda.urdf', 'fixed'),
          'solo12': ('solo_description/robots/solo12.urdf', 'floating'),
          'talos': ('talos_data/robots/talos_reduced.urdf', 'floating')}
ERR_FLOOR = 1e-18


@dataclass(frozen=True)
class Settings:
    """How much to measure: reference states, timed states, rounds and block length."""

    ref_states: int = 3
    states: int = 16
    rounds: int = 41        # short blocks, many: the least of them finds the machine's quiet
    block_s: float = 0.007
    batch: int = 10_000
    batch_rounds: int = 7


FULL = Settings()
QUICK = Settings(ref_states=2, states=8, rounds=5, block_s=0.005, batch_rounds=3)


def load(name: str) -> sd.Model:
    """Return the model of a robot of :data:`ROBOTS`; ``FileNotFoundError`` when not there."""
    erd = _erd_dir()
    path = None if erd is None else erd / ROBOTS[name][0]
    if path is None or not path.is_file():
        raise FileNotFoundError(f'{name}: example-robot-data is not installed')
    return sd.Model.from_urdf(str(path), base=ROBOTS[name][1])


def random_states(model: sd.Model, rng: np.random.Generator, N: int) -> tuple:
    """N random states ``(q, q̇, q̈)``: joints in ±1.5 rad, a unit quaternion on a free-flyer."""
    q = rng.uniform(-1.5, 1.5, (N, model.nq))
    if model.floating:
        quat = rng.normal(size=(N, 4))
        q[:, 3:7] = quat / np.linalg.norm(quat, axis=-1, keepdims=True)
    return q, rng.uniform(-2.0, 2.0, (N, model.nv)), rng.uniform(-5.0, 5.0, (N, model.nv))


# --------------------------------------------------------------------------------------------
# The 50-digit reference


def _quat_mul(a, b) -> list:
    """Return the quaternion product ``a ⊗ b`` (x y z w), on any scalars."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return [aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz]


def _moved(model: sd.Model, q: list, k: int, eps, mp) -> list:
    """Return ``q`` moved by ``eps`` along velocity coordinate ``k``.

    Any curve through ``q`` with tangent ``e_k`` gives the derivative; on a free-flyer ``e_k``
    is in the base frame's ``[ω; v]``, and the quaternion is renormalised.
    """
    q = list(q)
    if not model.floating:
        q[k] += eps
        return q
    if k >= 6:
        q[k + 1] += eps
        return q
    x, y, z, w = q[3:7]
    if k < 3:                                   # turn about the base's own axis k
        d = [mp.mpf(0)] * 3
        d[k] = eps / 2
        quat = _quat_mul([x, y, z, w], d + [mp.mpf(1)])
        norm = mp.sqrt(sum(c * c for c in quat))
        q[3:7] = [c / norm for c in quat]
        return q
    # move along the base's own axis k - 3: p += R e eps (R the base's orientation)
    R = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
         [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
         [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    for i in range(3):
        q[i] += R[i][k - 3] * eps
    return q


def reference(model: sd.Model, q, qd, qdd, digits: int = DIGITS) -> np.ndarray:
    """``[∂τ/∂q, ∂τ/∂q̇]`` (nv, 2 nv) of one state: central differences of the mpmath RNEA.

    Python floats convert to mpf exactly, so this differentiates the exact RNEA of the float64
    inputs on the model's float64 parameters (the quaternion normalised in mpmath).
    """
    import mpmath as mp
    with mp.workdps(digits):
        rows = layout.of(model).rows
        Q, QD, QDD = ([mp.mpf(float(x)) for x in v] for v in (q, qd, qdd))
        if model.floating:
            norm = mp.sqrt(sum(c * c for c in Q[3:7]))
            Q[3:7] = [c / norm for c in Q[3:7]]
        g = [mp.mpf(x) for x in GRAVITY]

        def tau(a, b):
            return python_backend.rnea_rows(rows, a, b, QDD, g, None, mp)

        h = mp.mpf('1e-15')
        cols = []
        for k in range(model.nv):
            plus, minus = tau(_moved(model, Q, k, h, mp), QD), tau(_moved(model, Q, k, -h, mp), QD)
            cols.append([(a - b) / (2 * h) for a, b in zip(plus, minus)])
        one = mp.mpf(1)         # τ is quadratic in q̇: the central difference is exact
        for k in range(model.nv):
            up, down = list(QD), list(QD)
            up[k] += one
            down[k] -= one
            cols.append([(a - b) / 2 for a, b in zip(tau(Q, up), tau(Q, down))])
        return np.array([[float(c[i]) for c in cols] for i in range(model.nv)])


# --------------------------------------------------------------------------------------------
# The implementations: each ``make(model) -> run(q, qd, qdd) -> (nv, 2 nv)``


def _finite_differences(step: float) -> Callable:
    """Central differences of ``sd.rnea`` with ``step``: one batch of ``4 nv`` states."""
    def make(model: sd.Model) -> Callable:
        nv = model.nv
        E = np.vstack([np.eye(nv) * step, -np.eye(nv) * step])

        def run(q, qd, qdd):
            Qs = (sd.integrate(model, q, E, 1.0) if model.floating
                  else q + E)
            Q = np.vstack([Qs, np.broadcast_to(q, (2 * nv, len(q)))])
            QD = np.vstack([np.broadcast_to(qd, (2 * nv, nv)), qd + E])
            tau = sd.rnea(model, Q, QD, np.broadcast_to(qdd, (4 * nv, nv)))
            dq = (tau[:nv] - tau[nv:2 * nv]) / (2 * step)
            dv = (tau[2 * nv:3 * nv] - tau[3 * nv:]) / (2 * step)
            return np.hstack([dq.T, dv.T])
        return run
    return make


def _analytic(model: sd.Model) -> Callable:
    """``sd.rnea_derivatives`` (its ∂τ/∂q and ∂τ/∂q̇)."""
    def run(q, qd, qdd):
        dq, dv = sd.rnea_derivatives(model, q, qd, qdd)[:2]
        return np.hstack([dq, dv])
    return run


def _analytic_out(model: sd.Model) -> Callable:
    """``sd.rnea_derivatives`` with ``out=``: three arrays made once, written each call."""
    out = tuple(np.empty((model.nv, model.nv)) for _ in range(3))

    def run(q, qd, qdd):
        dq, dv = sd.rnea_derivatives(model, q, qd, qdd, out=out)[:2]
        return np.hstack([dq, dv])
    return run


def _pinocchio_model(model: sd.Model, xml: str):
    """Pinocchio's model of ``xml`` (mimic tags stripped) and ``P``: ``v_pin = P q̇``, q map."""
    import pinocchio as pin
    xml = re.sub(r'<mimic\b(?:[^>]*/>|[^>]*>.*?</mimic\s*>)', '', xml, flags=re.S)
    pm = (pin.buildModelFromXML(xml, pin.JointModelFreeFlyer()) if model.floating
          else pin.buildModelFromXML(xml))
    pm.armature[:] = 0.0
    pm.gravity.linear = np.array(GRAVITY)
    first = 2 if model.floating else 1
    base = 6 if model.floating else 0
    index = {name: k for k, name in enumerate(model.joint_names)}
    P = np.zeros((pm.nv, model.nv))
    if model.floating:
        P[0:3, 3:6] = P[3:6, 0:3] = np.eye(3)           # [v; ω] from [ω; v]
    joints = []     # (our coordinate k, multiplier, offset, pin idx_q, idx_v, nq)
    for jid in range(first, pm.njoints):
        name, jm = pm.names[jid], pm.joints[jid]
        mult, off, src = 1.0, 0.0, name
        while src in model.mimics:
            src, m, o = model.mimics[src]
            mult, off = mult * m, mult * o + off
        k = base + index[src] - (1 if model.floating else 0)
        P[jm.idx_v, k] = mult
        joints.append((k, mult, off, jm.idx_q, jm.idx_v, jm.nq))
    return pin, pm, P, joints


def _pinocchio(model: sd.Model, xml: str) -> tuple:
    """Return :func:`_pinocchio_model`'s and ``computeRNEADerivatives`` (ours is ``Pᵀ D P``)."""
    pin, pm, P, joints = _pinocchio_model(model, xml)
    data = pm.createData()

    def run(qp, vp, ap):
        dq, dv, _ = pin.computeRNEADerivatives(pm, data, qp, vp, ap)
        return dq, dv
    return pin, pm, P, joints, run


def to_pinocchio(model: sd.Model, pm, P: np.ndarray, joints: list, q, qd, qdd) -> tuple:
    """Return our state as Pinocchio's ``(q, v, a)`` (``q̈`` or ``τ`` mapped alike)."""
    qp = np.zeros(pm.nq)
    if model.floating:
        qp[:7] = q[:7]
    for k, mult, off, iq, iv, n in joints:
        theta = mult * q[k + (1 if model.floating else 0)] + off
        if n == 2:
            qp[iq:iq + 2] = np.cos(theta), np.sin(theta)
        else:
            qp[iq] = theta
    return qp, P @ qd, P @ qdd


# --------------------------------------------------------------------------------------------
# The run


def _rel(value: np.ndarray, ref: np.ndarray) -> float:
    return float(np.abs(value - ref).max() / np.abs(ref).max())


def bench_robot(name: str, model: sd.Model, xml: str, settings: Settings, log: Callable,
                rng: np.random.Generator) -> tuple:
    """Return the rows (implementation, µs a state, relative error) and the FD rows of a robot."""
    Q, QD, QDD = random_states(model, rng, settings.states)
    log(f'{name}: the 50-digit reference on {settings.ref_states} states')
    refs = [reference(model, Q[k], QD[k], QDD[k]) for k in range(settings.ref_states)]
    errors, notes = {}, []
    states = list(zip(Q, QD, QDD))
    entries = {'sd.rnea_derivatives': (_analytic(model), states),
               'sd.rnea_derivatives, out=': (_analytic_out(model), states)}
    for step in STEPS:
        entries[f'central differences of sd.rnea, h={step:g}'] = (
            _finite_differences(step)(model), states)
    # What is timed: the call that gives the derivatives. The analytic rows are the bare
    # functions (their stacking into D for the error check is no part of either); a
    # finite-difference row is the whole of its method.
    timed = dict(entries)
    timed['sd.rnea_derivatives'] = (sd.rnea_derivatives, [(model,) + s for s in states])
    out = tuple(np.empty((model.nv, model.nv)) for _ in range(3))      # made once, reused
    timed['sd.rnea_derivatives, out='] = (partial(sd.rnea_derivatives, out=out),
                                          [(model,) + s for s in states])
    pin = None
    try:
        pin, pm, P, joints, prun = _pinocchio(model, xml)
        pstates = [to_pinocchio(model, pm, P, joints, *s) for s in states]
        entries['pinocchio computeRNEADerivatives'] = (prun, pstates)
        data = pm.createData()
        timed['pinocchio computeRNEADerivatives'] = (
            pin.computeRNEADerivatives, [(pm, data) + s for s in pstates])
    except ImportError:
        notes.append(f'{name}: pinocchio is not installed')
    for label, (run, args) in entries.items():
        worst = 0.0
        for k, ref in enumerate(refs):
            out = run(*args[k])
            if label.startswith('pinocchio'):
                out = np.hstack([P.T @ out[0] @ P, P.T @ out[1] @ P])
            worst = max(worst, _rel(out, ref))
        errors[label] = worst
    log(f'{name}: timing {len(entries)} implementations')
    times = interleaved_rounds(timed, settings.rounds, settings.block_s, 1)
    rows = [{'robot': name, 'nv': model.nv, 'implementation': label,
             'us_per_state': statistics.median(times[label]) * 1e6,
             'us_least': min(times[label]) * 1e6, 'rel_err': errors[label]}
            for label in entries]
    fd, batch = {}, {}
    if pin is not None:
        fd = forward_row(name, model, xml, states, settings)
        log(f'{name}: a batch of {settings.batch} states against a loop of Pinocchio')
        batch = batch_row(name, model, (pin, pm, P, joints), settings, rng)
    return rows, fd, batch, notes


def batch_row(name: str, model: sd.Model, pinocchio: tuple, settings: Settings,
              rng: np.random.Generator) -> dict:
    """Time one ``sd.rnea_derivatives`` call on a batch against Pinocchio looped over it.

    Per state: the batch call's time over ``settings.batch`` states (the compiled backend's
    threads on the cores there are), bare and with ``out=`` (three arrays made once, written
    every round), and a Python loop of ``computeRNEADerivatives`` over the same states, in
    alternating rounds (the median, and the ratio of the least of each). The largest
    difference of the batch from the one-state calls on its first states, relative to the
    largest entry, is in the row (``out=``'s too).
    """
    pin, pm, P, joints = pinocchio     # bench_robot's model of the robot (_pinocchio)
    data = pm.createData()
    Q, QD, QDD = random_states(model, rng, settings.batch)
    pstates = [to_pinocchio(model, pm, P, joints, *s) for s in zip(Q, QD, QDD)]
    derivatives = pin.computeRNEADerivatives

    out = tuple(np.empty((settings.batch, model.nv, model.nv)) for _ in range(3))

    def ours() -> None:
        sd.rnea_derivatives(model, Q, QD, QDD)

    def ours_out() -> None:
        sd.rnea_derivatives(model, Q, QD, QDD, out=out)

    def theirs() -> None:
        for qp, vp, ap in pstates:
            derivatives(pm, data, qp, vp, ap)
    batched = sd.rnea_derivatives(model, Q, QD, QDD)
    ours_out()
    worst = worst_out = 0.0
    for k in range(8):
        one = sd.rnea_derivatives(model, Q[k], QD[k], QDD[k])
        worst = max(worst, max(_rel(b[k], o) for b, o in zip(batched, one)))
        worst_out = max(worst_out, max(_rel(b[k], o) for b, o in zip(out, one)))
    times = interleaved_rounds({'ours': (ours, [()]), 'ours_out': (ours_out, [()]),
                                'pin': (theirs, [()])}, settings.batch_rounds, 0.0,
                               settings.batch)
    median = {key: statistics.median(t) for key, t in times.items()}
    return {'robot': name, 'nv': model.nv, 'states': settings.batch,
            'batch_us': median['ours'] * 1e6, 'pin_loop_us': median['pin'] * 1e6,
            'rel_diff': worst, 'out_us': median['ours_out'] * 1e6, 'out_rel_diff': worst_out,
            'least_ratio': min(times['ours']) / min(times['pin']),
            'out_least_ratio': min(times['ours_out']) / min(times['pin'])}


def forward_row(name: str, model: sd.Model, xml: str, states: list, settings: Settings) -> dict:
    """Time ``sd.forward_dynamics`` against ``pin.aba`` on the same states; their difference.

    Both on the URDF without its ``<mimic>`` tags (Pinocchio's ``aba`` has no mimic joints),
    ``τ`` the RNEA of the states.
    """
    free = sd.Model.from_urdf(re.sub(r'<mimic\b(?:[^>]*/>|[^>]*>.*?</mimic\s*>)', '', xml,
                                     flags=re.S), base='floating' if model.floating else 'fixed')
    pin, pm, P, joints = _pinocchio_model(free, xml)
    data = pm.createData()
    ours, theirs, worst = [], [], 0.0
    for q, qd, qdd in states:
        q = np.resize(q, free.nq)
        qd, qdd = np.resize(qd, free.nv), np.resize(qdd, free.nv)
        tau = sd.rnea(free, q, qd, qdd)
        ours.append((free, q, qd, tau))
        theirs.append((pm, data) + to_pinocchio(free, pm, P, joints, q, qd, tau))
        a_pin = P.T @ pin.aba(*theirs[-1])          # P is a permutation: P⁻¹ = Pᵀ
        worst = max(worst, _rel(sd.forward_dynamics(*ours[-1]), a_pin))
    times = interleaved_rounds({'ours': (sd.forward_dynamics, ours), 'pin': (pin.aba, theirs)},
                               settings.rounds, settings.block_s, 1)
    return {'robot': name, 'nv': free.nv, 'fd_us': statistics.median(times['ours']) * 1e6,
            'aba_us': statistics.median(times['pin']) * 1e6,
            'least_ratio': min(times['ours']) / min(times['pin']), 'rel_diff': worst}


def markdown(rows: list, fds: list, batches: list = ()) -> str:
    """Return the markdown tables of the run."""
    out = ['| robot (nv) | implementation | µs a state | ×pin '
           '| max rel. error of [∂τ/∂q, ∂τ/∂q̇] | least µs | ×pin, least |',
           '|---|---|---|---|---|---|---|']
    pin = {r['robot']: r for r in rows if r['implementation'].startswith('pinocchio')}
    for r in rows:
        p = pin.get(r['robot'])
        ratio = f"{r['us_per_state'] / p['us_per_state']:.2f}×" if p else '–'
        least = f"{r['us_least'] / p['us_least']:.2f}×" if p else '–'
        out.append(f"| {r['robot']} ({r['nv']}) | {r['implementation']} | "
                   f"{r['us_per_state']:.3g} | {ratio} | {r['rel_err']:.1e} | "
                   f"{r['us_least']:.3g} | {least} |")
    if fds:
        out += ['', '| robot (nv) | sd.forward_dynamics µs | pin.aba µs | ratio | '
                'max rel. difference | ratio, least |', '|---|---|---|---|---|---|']
        for f in fds:
            out.append(f"| {f['robot']} ({f['nv']}) | {f['fd_us']:.3g} | {f['aba_us']:.3g} | "
                       f"{f['fd_us'] / f['aba_us']:.2f}× | {f['rel_diff']:.1e} | "
                       f"{f['least_ratio']:.2f}× |")
    if batches:
        out += ['', '| robot (nv) | states | sd.rnea_derivatives batch µs a state | '
                'computeRNEADerivatives loop µs a state | ratio | max rel. difference from '
                'one state | ratio, least |', '|---|---|---|---|---|---|---|']
        for b in batches:
            out.append(f"| {b['robot']} ({b['nv']}) | {b['states']:,} | {b['batch_us']:.3g} | "
                       f"{b['pin_loop_us']:.3g} | {b['batch_us'] / b['pin_loop_us']:.2f}× | "
                       f"{b['rel_diff']:.1e} | {b['least_ratio']:.2f}× |")
        for b in batches:       # the same call with out=, below the bare calls
            out.append(f"| {b['robot']} ({b['nv']}) | {b['states']:,}, out= | "
                       f"{b['out_us']:.3g} | {b['pin_loop_us']:.3g} | "
                       f"{b['out_us'] / b['pin_loop_us']:.2f}× | {b['out_rel_diff']:.1e} | "
                       f"{b['out_least_ratio']:.2f}× |")
    return '\n'.join(out)


#: The speed targets the benchmark checks: (what, its bound on the ratio to Pinocchio).
TARGETS = (('one state, sd.rnea_derivatives / computeRNEADerivatives', 0.5),
           ('a batch, sd.rnea_derivatives(out=) / a loop of computeRNEADerivatives', 0.2),
           ('a batch, sd.rnea_derivatives (fresh result) / a loop of computeRNEADerivatives',
            0.2),
           ('sd.forward_dynamics / pin.aba', 0.7))


def target_rows(rows: list, fds: list, batches: list = ()) -> list:
    """Return ``[what, bound, robot, least ratio, median ratio, met]`` of each target and robot.

    The verdict is by the ratio of the least of the rounds (each side's own least, as
    ``timeit`` advises: what the code takes when nothing else runs on its core), the median's
    ratio beside it. On a machine whose cores are shared the medians move by ±20 % from one
    run to the next, ours more than Pinocchio's when a core's other thread is busy; the
    least does not.
    """
    pin = {r['robot']: r for r in rows if r['implementation'].startswith('pinocchio')}
    found = {TARGETS[0][0]: [(r['robot'], r['us_least'] / pin[r['robot']]['us_least'],
                              r['us_per_state'] / pin[r['robot']]['us_per_state'])
                             for r in rows if r['implementation'] == 'sd.rnea_derivatives'
                             and r['robot'] in pin],
             TARGETS[1][0]: [(b['robot'], b['out_least_ratio'], b['out_us'] / b['pin_loop_us'])
                             for b in batches],
             TARGETS[2][0]: [(b['robot'], b['least_ratio'], b['batch_us'] / b['pin_loop_us'])
                             for b in batches],
             TARGETS[3][0]: [(f['robot'], f['least_ratio'], f['fd_us'] / f['aba_us'])
                             for f in fds]}
    return [[what, bound, robot, least, median, least <= bound]
            for what, bound in TARGETS for robot, least, median in found[what]]


def targets(rows: list, fds: list, batches: list = ()) -> str:
    """Return the table of :func:`target_rows`: ratios to 3 digits (0.703 is over 0.7)."""
    out = ['| target | robot | ratio, least | ratio, median | met (by the least) |',
           '|---|---|---|---|---|']
    for what, bound, robot, least, median, met in target_rows(rows, fds, batches):
        out.append(f"| {what} ≤ {bound}× | {robot} | {least:.3f}× | {median:.3f}× | "
                   f"{'yes' if met else 'no'} |")
    return '\n'.join(out)


def plot(rows: list, out: Path, log: Callable) -> Optional[Path]:
    """Write derivatives_vs_error.png (time per state against error); None without matplotlib."""
    try:
        import matplotlib
        matplotlib.use('Agg')
        import matplotlib.pyplot as plt
    except ImportError:
        log('matplotlib is not installed: no plot')
        return None
    impls = list(dict.fromkeys(re.sub(r', h=.*', '', r['implementation']) for r in rows))
    robots = list(dict.fromkeys(r['robot'] for r in rows))
    colour = {n: plt.get_cmap('tab10')(i % 10) for i, n in enumerate(impls)}
    marker = {n: 'osD^v<>p'[i % 8] for i, n in enumerate(robots)}
    fig, ax = plt.subplots(figsize=(10, 6.5))
    for r in rows:
        impl = re.sub(r', h=.*', '', r['implementation'])
        ax.scatter(r['us_per_state'], max(r['rel_err'], ERR_FLOOR), color=colour[impl],
                   marker=marker[r['robot']], s=40)
        if ', h=' in r['implementation']:
            ax.annotate(r['implementation'].split('h=')[1], (r['us_per_state'],
                        max(r['rel_err'], ERR_FLOOR)), fontsize=6, alpha=0.7)
    ax.set_xscale('log')
    ax.set_yscale('log')
    ax.set_xlabel('time per state from Python (µs)')
    ax.set_ylabel('max |D − D_ref| / max |D_ref|  (mpmath reference, 50 digits)')
    handles = [plt.Line2D([], [], color=colour[n], marker='o', ls='', label=n) for n in impls]
    handles += [plt.Line2D([], [], color='0.3', marker=marker[r], ls='', label=r)
                for r in robots]
    ax.legend(handles=handles, fontsize=8)
    ax.grid(True, which='major', alpha=0.3)
    ax.set_title('Derivatives of inverse dynamics: run time against error (lower left is better)')
    fig.tight_layout()
    path = out / 'derivatives_vs_error.png'
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def out_folder(text: str) -> Path:
    """Return ``--out`` as a Path; '' is refused (``Path('')`` is the current folder)."""
    if not text:
        raise argparse.ArgumentTypeError('an empty path names no folder')
    return Path(text)


def main(argv: Optional[list] = None) -> int:
    """Command-line entry point."""
    parser = argparse.ArgumentParser(prog='python -m benchmarks.derivatives',
                                     description=__doc__.split('\n')[0])
    parser.add_argument('--quick', action='store_true', help='fewer states and rounds')
    parser.add_argument('--out', default='out/derivatives', type=out_folder,
                        help='output directory (default: out/derivatives)')
    parser.add_argument('--robots', nargs='+', choices=list(ROBOTS), metavar='ROBOT',
                        help=f'robots to run (default: all of {" ".join(ROBOTS)})')
    args = parser.parse_args(argv)
    twice = sorted({r for r in args.robots or () if args.robots.count(r) > 1})
    if twice:       # a robot run twice was judged against the other run's Pinocchio
        parser.error(f'--robots: {", ".join(twice)} given twice')
    try:            # before the measurement, not after it (its tables are printed last)
        if not str(args.out):
            raise ValueError('--out: an empty path')
        check_folder(args.out, f'--out {str(args.out)!r}', missing=True)
        for name in ('derivatives.csv', 'derivatives_targets.csv', 'derivatives_vs_error.png'):
            check_output(args.out / name, f'--out {str(args.out)!r}: {name}',
                         missing_folders=True)
    except ValueError as err:
        parser.error(str(err))
    settings = QUICK if args.quick else FULL
    args.out.mkdir(parents=True, exist_ok=True)
    log = Progress()
    setup = versions()
    log(setup)
    rng = np.random.default_rng(0)
    rows, fds, batches, notes = [], [], [], []
    for name in args.robots or list(ROBOTS):
        try:
            model = load(name)
        except FileNotFoundError as err:
            notes.append(str(err))
            continue
        xml = (_erd_dir() / ROBOTS[name][0]).read_text(encoding='utf-8')
        robot_rows, fd, batch, robot_notes = bench_robot(name, model, xml, settings, log, rng)
        rows += robot_rows
        notes += robot_notes
        if fd:
            fds.append(fd)
        if batch:
            batches.append(batch)
    with open(args.out / 'derivatives.csv', 'w', newline='', encoding='utf-8') as f:
        writer = csv.DictWriter(f, ['robot', 'nv', 'implementation', 'us_per_state', 'rel_err',
                                    'us_least'])
        writer.writeheader()
        writer.writerows(rows)
    path = plot(rows, args.out, log)
    print(f'Command: python -m benchmarks.derivatives {" ".join(argv or sys.argv[1:])}')
    print(f'Setup: {setup}\n')
    print(markdown(rows, fds, batches))
    if any(r['implementation'].startswith('pinocchio') for r in rows):
        print('\nThe targets, by the ratio of the least of the rounds (the median beside):\n')
        print(targets(rows, fds, batches))
        with open(args.out / 'derivatives_targets.csv', 'w', newline='', encoding='utf-8') as f:
            writer = csv.writer(f)
            writer.writerow(['target', 'bound', 'robot', 'ratio_least', 'ratio_median', 'met'])
            writer.writerows(target_rows(rows, fds, batches))
    print('\nComplex step: not measured (the library refuses complex arrays).')
    for note in notes:
        print(f'Note: {note}')
    print(f'\nWrote {args.out / "derivatives.csv"}' + (f', {path}' if path else '')
          + f' (load average at the end: {os.getloadavg()[0]:.1f})')
    return 0


if __name__ == '__main__':
    sys.exit(main())
