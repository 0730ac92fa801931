# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A model without joints (one link, or links on fixed joints only) on every backend.

Such a model has ``n = 0``: each public function answers with the shapes of any other model
at n = 0 (τ (..., 0), M (..., 0, 0), Y (..., 0, 0), J (..., 6, 0)) on the numpy and the
compiled backend alike, for one state and for batches, in float64 and float32.
"""

import numpy as np
import pytest
import spatial_dynamics as sd
from spatial_dynamics.algorithms.regressor import parameters, regressor_spatial
from spatial_dynamics.backends import BACKENDS, compiled

INERTIAL = ('<inertial><origin xyz="0.1 0 0"/><mass value="2"/>'
            '<inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>')
URDFS = {
    'one link': f'<robot name="one"><link name="base">{INERTIAL}</link></robot>',
    'fixed joints': f"""<robot name="fixed">
      <link name="base"/><link name="a">{INERTIAL}</link><link name="b">{INERTIAL}</link>
      <joint name="ja" type="fixed"><parent link="base"/><child link="a"/>
        <origin xyz="0 0 1"/></joint>
      <joint name="jb" type="fixed"><parent link="a"/><child link="b"/>
        <origin xyz="0 1 0" rpy="0.1 0.2 0.3"/></joint></robot>""",
}
BATCHES = [(), (1,), (3,), (2, 3), (0,)]


def backends():
    """Return the backends to compare: numpy, and auto and compiled with the extension."""
    return [b for b in BACKENDS if b == 'numpy' or compiled.ext is not None]


def answers(model, batch, dtype, backend):
    """Every public function of ``model`` at zero states of shape ``batch + (0,)``."""
    z = np.zeros(batch + (0,), dtype)
    out = {
        'rnea': sd.rnea(model, z, z, z, backend=backend),
        'rnea f_ext': sd.rnea(model, z, z, z, f_ext={model.body_names[0]: np.ones(6)},
                              backend=backend),
        'gravity_torque': sd.gravity_torque(model, z, backend=backend),
        'bias_torque': sd.bias_torque(model, z, z, backend=backend),
        'mass_matrix': sd.mass_matrix(model, z, backend=backend),
        'regressor': sd.regressor(model, z, z, z, backend=backend),
    }
    out['momentum p'], out['momentum ctq'] = sd.generalized_momentum(model, z, z,
                                                                     backend=backend)
    if batch == ():             # one state as a list too: the single-state entries
        out['rnea list'] = sd.rnea(model, [], [], [], backend=backend)
        out['regressor list'] = sd.regressor(model, [], (), [], backend=backend)
        out['mass_matrix list'] = sd.mass_matrix(model, [], backend=backend)
    return out


@pytest.mark.parametrize('name', sorted(URDFS))
@pytest.mark.parametrize('batch', BATCHES, ids=str)
@pytest.mark.parametrize('dtype', [np.float64, np.float32])
def test_every_public_function_gives_the_same_shapes_on_every_backend(name, batch, dtype):
    model = sd.Model.from_urdf(URDFS[name])
    assert model.nq == 0 and model.NB == 0
    want = {'rnea': (0,), 'rnea f_ext': (0,), 'gravity_torque': (0,), 'bias_torque': (0,),
            'mass_matrix': (0, 0), 'regressor': (0, 0), 'momentum p': (0,),
            'momentum ctq': (0,), 'rnea list': (0,), 'regressor list': (0, 0),
            'mass_matrix list': (0, 0)}
    for backend in backends():
        got = answers(model, batch, dtype, backend)
        for key, value in got.items():
            shape = (() if key.endswith('list') else batch) + want[key]
            assert value.shape == shape, (backend, key, value.shape, shape)
            single = key.endswith('list')
            assert value.dtype == (np.float64 if single else dtype), (backend, key)


@pytest.mark.parametrize('name', sorted(URDFS))
def test_the_reference_and_the_other_public_functions(name):
    """jacobian, rnea_spatial, regressor_spatial, parameters and the joint terms at n = 0."""
    model = sd.Model.from_urdf(URDFS[name])
    for batch in BATCHES:
        z = np.zeros(batch + (0,))
        for link in model.frames:
            for frame in ('local', 'world'):
                assert sd.jacobian(model, z, link, frame).shape == batch + (6, 0)
        assert sd.rnea_spatial(model, z, z, z).shape == batch + (0,)
        assert regressor_spatial(model, z, z, z).shape == batch + (0, 0)
        assert sd.friction_torque(model, z, 0.1).shape == batch + (0,)
        clamped, saturated = sd.clamp_to_effort_limits(model, z)
        assert clamped.shape == saturated.shape == batch + (0,)
        assert sd.armature_torque(np.zeros(0), z).shape == batch + (0,)
    assert parameters(model).shape == (0,)
