# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Every URDF of example-robot-data, as a new user would try them.

Each one loads (as written: physically inconsistent inertias give a URDFWarning, never an
error) unless the policy refuses it for a reason named below; its joints come in Pinocchio's
order; its torques equal Pinocchio's on random states, single and batched, on each backend,
and so do its M(q), M q̇ and Cᵀ q̇.
"""

import glob
import os
import re
import warnings

from conftest import example_robot_data_dir, PinOracle, random_state
import numpy as np
import pytest
import spatial_dynamics as sd

BASE = example_robot_data_dir()
FILES = sorted(os.path.relpath(p, BASE) for p in glob.glob(
    os.path.join(BASE, '**', '*.urdf'), recursive=True)) if BASE else []

# What the policy refuses, and the message that must name it. A mimic of a missing joint
# cannot be computed as written (Pinocchio with mimic joints refuses this file too); ur3.urdf
# has everything inside one comment (Pinocchio refuses it as well).
REFUSED = {
    os.path.join('alex_description', 'urdf', 'alex_psyonic_hands.urdf'):
        r"joint 'Left_index_q2' <mimic>: mimics a missing joint 'index_q1'",
    os.path.join('ur_description', 'urdf', 'ur3.urdf'): r'has no links',
}
TOLERANCE = 1e-9   # normwise, relative to max(1, |tau|)


def load(path, **kwargs):
    """Load a model with its URDFWarnings recorded, not printed."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter('always', sd.URDFWarning)
        model = sd.Model.from_urdf(path, **kwargs)
    return model, [str(w.message) for w in caught if issubclass(w.category, sd.URDFWarning)]


def pinocchio_text(path):
    """Return the URDF text for Pinocchio, named if it is not (urdfdom refuses no name)."""
    with open(path, encoding='utf-8') as f:
        text = f.read().lstrip()     # (the oracle's own XML parser wants no leading space)
    return re.sub(r'<robot(?=[\s>/])(?![^>]*\bname=)', '<robot name="robot"', text,
                  count=1)


def test_the_sweep_sees_every_robot():
    if BASE is None:
        pytest.skip('example-robot-data is not installed')
    assert len(FILES) >= 60
    assert set(REFUSED) <= set(FILES)


@pytest.mark.parametrize('name', [f for f in FILES if f in REFUSED])
def test_refused_for_the_named_reason(name):
    with pytest.raises(ValueError, match=REFUSED[name]):
        load(os.path.join(BASE, name))


@pytest.mark.parametrize('name', [f for f in FILES if f not in REFUSED])
def test_loads_in_pinocchio_order_with_pinocchio_torques(name, rng):
    path = os.path.join(BASE, name)
    model, caught = load(path)
    assert caught == list(model.warnings)            # each warning raised once, and kept
    oracle = PinOracle(pinocchio_text(path))
    pin_order = [n for n in oracle.model.names[1:] if n not in oracle.mimic]
    assert list(model.joint_names) == pin_order
    n = model.nq
    if n == 0:
        return
    for backend in ('numpy', 'compiled'):
        for shape in ((), (3,)):
            q, qd, qdd = random_state(rng, shape, n)
            tau = sd.rnea(model, q, qd, qdd, backend=backend)
            expected = oracle.rnea(model.joint_names, q, qd, qdd)
            assert tau.shape == expected.shape
            err = np.linalg.norm(tau - expected, axis=-1)
            scale = np.maximum(1.0, np.linalg.norm(expected, axis=-1))
            assert np.all(err <= TOLERANCE * scale), (backend, shape, err.max())


@pytest.mark.parametrize('name', [f for f in FILES if f not in REFUSED])
def test_mass_matrix_and_momentum_equal_pinocchio(name, rng):
    """M(q) (CRBA), M q̇ and Cᵀ q̇ against Pinocchio's crba and Coriolis matrix, both backends."""
    path = os.path.join(BASE, name)
    model, _ = load(path)
    n = model.nq
    if n == 0:
        return
    oracle = PinOracle(pinocchio_text(path))
    pin = oracle.pin
    q, qd, _ = random_state(rng, (), n)
    q_pin, P = oracle.velocity_map(model.joint_names, q)
    M = pin.crba(oracle.model, oracle.data, q_pin).copy()
    M = P.T @ (np.triu(M) + np.triu(M, 1).T) @ P
    C = pin.computeCoriolisMatrix(oracle.model, oracle.data, q_pin, P @ qd).copy()
    ctq = P.T @ (C.T @ (P @ qd))
    for backend in ('numpy', 'compiled'):
        ours = sd.mass_matrix(model, q, backend=backend)
        assert np.linalg.norm(ours - M) <= TOLERANCE * max(1.0, np.linalg.norm(M)), backend
        mom, ct = sd.generalized_momentum(model, q, qd, backend=backend)
        for value, expected in ((mom, M @ qd), (ct, ctq)):
            err = np.linalg.norm(value - expected)
            assert err <= TOLERANCE * max(1.0, np.linalg.norm(expected)), (backend, err)


@pytest.mark.parametrize('name', [f for f in FILES if f not in REFUSED])
def test_strict_mode_refuses_exactly_the_files_with_warnings(name):
    path = os.path.join(BASE, name)
    model, _ = load(path)
    if not model.warnings:
        assert sd.Model.from_urdf(path, strict=True).joint_names == model.joint_names
        return
    with pytest.raises(ValueError, match=re.escape(model.warnings[0])):
        sd.Model.from_urdf(path, strict=True)


# -- another public collection on PyPI: pybullet's data (arms, quadrupeds, objects) ----------

def pybullet_files():
    """Return (directory, relative paths) of pybullet_data's URDFs, or skip without it."""
    pybullet_data = pytest.importorskip('pybullet_data')
    base = pybullet_data.getDataPath()
    return base, sorted(os.path.relpath(p, base) for p in glob.glob(
        os.path.join(base, '**', '*.urdf'), recursive=True))


def test_every_pybullet_robot_pinocchio_loads_loads_with_its_torques():
    """Wherever Pinocchio loads a file, so do we, in its order and with its torques."""
    import pinocchio as pin
    base, files = pybullet_files()
    assert len(files) > 1000
    rng = np.random.default_rng(7)
    mismatches, compared = [], 0
    for name in files:
        path = os.path.join(base, name)
        try:
            pin.buildModelFromXML(pinocchio_text(path))
        except (RuntimeError, ValueError):
            continue              # Pinocchio refuses it (a spherical joint, a '$(optenv)')
        try:
            model, _ = load(path)
        except ValueError as err:
            mismatches.append(f'{name}: refused: {err}')
            continue
        oracle = PinOracle(pinocchio_text(path))
        if list(model.joint_names) != [n for n in oracle.model.names[1:]
                                       if n not in oracle.mimic]:
            mismatches.append(f'{name}: joint order {model.joint_names}')
            continue
        if model.nq == 0:
            continue
        q, qd, qdd = random_state(rng, (2,), model.nq)
        expected = oracle.rnea(model.joint_names, q, qd, qdd)
        err = np.linalg.norm(sd.rnea(model, q, qd, qdd) - expected, axis=-1)
        if np.any(err > TOLERANCE * np.maximum(1.0, np.linalg.norm(expected, axis=-1))):
            mismatches.append(f'{name}: torque error {err.max():.3g}')
        compared += 1
    assert not mismatches, '\n'.join(mismatches)
    assert compared >= 30       # robots with joints (arms, quadrupeds, hands, a humanoid)
