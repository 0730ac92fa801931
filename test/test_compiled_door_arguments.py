# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The public functions' arguments as the compiled door sees them: the model, duplicates.

- anything but a :class:`~spatial_dynamics.Model` as the model is a ``TypeError`` naming the
  argument, on every backend, before and after a call on a model, and after that model was
  collected (a dead weak reference must not stand for ``None``);
- a door lets go of a collected model's kernels;
- an argument given both by position and by keyword is Python's ``TypeError`` ("got
  multiple values for argument"), whether the model's kernels are ready (warm) or not (cold).
"""

import gc
import inspect

from conftest import TWO_JOINTS
import numpy as np
import pytest
import spatial_dynamics as sd
from spatial_dynamics.backends import compiled

Z = [0.0, 0.0]
#: The functions the door enters, with one state's joint vectors.
DOORS = {'rnea': 3, 'gravity_torque': 1, 'bias_torque': 2, 'mass_matrix': 1,
         'generalized_momentum': 2, 'regressor': 3}
NOT_MODELS = [None, 'two', 0, 1.5, object(), {}, [Z], np.zeros(3)]
BACKENDS = ['auto', 'numpy'] + (['compiled'] if compiled.ext is not None else [])


def call(name, model, backend='auto'):
    return getattr(sd, name)(model, *[Z] * DOORS[name], backend=backend)


def refused(name, model, backend):
    with pytest.raises(TypeError) as info:
        call(name, model, backend)
    return str(info.value)


@pytest.mark.parametrize('name', sorted(DOORS))
def test_anything_but_a_model_is_a_type_error_naming_the_model(name):
    for backend in BACKENDS:
        for bad in NOT_MODELS:
            message = refused(name, bad, backend)
            assert message.startswith('model must be a spatial_dynamics.Model, got '), message
            assert type(bad).__name__ in message


@pytest.mark.parametrize('name', sorted(DOORS))
def test_none_after_the_last_model_was_collected_is_a_type_error(name):
    """The report: a dead weak reference compared equal to None, which then got its torques."""
    for backend in BACKENDS:
        model = sd.Model.from_urdf(TWO_JOINTS)
        call(name, model, backend)
        call(name, model, backend)         # warm: the door remembers this model
        del model
        gc.collect()
        for bad in NOT_MODELS:
            assert refused(name, bad, backend).startswith('model must be a spatial_dynamics.Model')


@pytest.mark.skipif(compiled.ext is None, reason='the doors exist with the extension only')
def test_a_door_lets_go_of_a_collected_models_kernels():
    kernels_type = compiled.ext.Kernels
    model = sd.Model.from_urdf(TWO_JOINTS)
    for name in DOORS:
        call(name, model)           # cold: the model's kernels are made
        call(name, model)
        held = [k for k in gc.get_referents(getattr(sd, name)) if type(k) is kernels_type]
        assert held, name           # the door keeps the live model's kernels at hand
    del model
    gc.collect()
    for name in DOORS:
        held = [k for k in gc.get_referents(getattr(sd, name)) if type(k) is kernels_type]
        assert not held, name


def duplicates(name):
    """Each way to give one of ``name``'s arguments twice: (positional, keywords)."""
    parameters = [p for p in inspect.signature(getattr(sd, name)).parameters.values()
                  if p.kind is not p.KEYWORD_ONLY]     # base=: by keyword only, never twice
    values = {'model': None, 'q': Z, 'qd': Z, 'qdd': Z, 'gravity': sd.GRAVITY,
              'f_ext': {'b': np.ones(6)}, 'backend': 'auto'}
    for k, twice in enumerate(parameters):
        given = [values[p.name] for p in parameters[:k + 1]]
        for value in ({} if twice.name == 'f_ext' else values[twice.name], None):
            yield given, {twice.name: value}


@pytest.mark.parametrize('name', sorted(DOORS))
def test_an_argument_given_twice_is_a_type_error_warm_or_cold(name):
    """rnea(m, q, qd, qdd, g, w, f_ext={}) dropped the wrench w once the model was warm."""
    function = getattr(sd, name)
    for given, keywords in duplicates(name):
        outcomes = []
        for warm in (False, True):
            model = sd.Model.from_urdf(TWO_JOINTS)
            if warm:
                call(name, model)
                call(name, model)
            args = [model] + given[1:]
            with pytest.raises(TypeError) as info:
                function(*args, **keywords)
            outcomes.append(str(info.value))
        twice = next(iter(keywords))
        assert outcomes[0] == outcomes[1] == (
            f"{name}() got multiple values for argument '{twice}'"), (given, keywords)


def test_the_other_public_functions_name_the_model_and_f_ext_too():
    """Functions without a door: the same TypeError for a model that is none, and f_ext."""
    others = {'jacobian': lambda m: sd.jacobian(m, Z, 'a'),
              'rnea_spatial': lambda m: sd.rnea_spatial(m, Z, Z, Z),
              'friction_torque': lambda m: sd.friction_torque(m, Z, 0.1),
              'clamp_to_effort_limits': lambda m: sd.clamp_to_effort_limits(m, Z),
              'per_joint': lambda m: sd.per_joint(m, 'damping', 1.0)}
    for name, function in others.items():
        for bad in NOT_MODELS:
            with pytest.raises(TypeError, match='^model must be a spatial_dynamics.Model'):
                function(bad)
    model = sd.Model.from_urdf(TWO_JOINTS)
    for backend in BACKENDS:
        for bad in ([('b', np.ones(6))], 'b', np.ones(6)):
            with pytest.raises(TypeError, match='^f_ext must map link names'):
                sd.rnea(model, Z, Z, Z, f_ext=bad, backend=backend)
        with pytest.raises(TypeError, match=r"^f_ext\['b'\] must be an array of real"):
            sd.rnea(model, Z, Z, Z, f_ext={'b': None}, backend=backend)
