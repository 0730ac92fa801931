# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Name mapping and validation of message arrays (no ROS needed)."""

import math
import subprocess
import sys
from types import SimpleNamespace

from hypothesis import given, strategies as st
import numpy as np
import pytest

from spatial_dynamics.ros import inputs
from spatial_dynamics.ros.inputs import InputError, joint_state_arrays, trajectory_arrays

JOINTS = ('j1', 'j2', 'j3', 'j4')
Q = {'j1': 0.1, 'j2': -0.2, 'j3': 0.3, 'j4': 1.5}
QD = {'j1': 1.0, 'j2': 2.0, 'j3': 3.0, 'j4': 4.0}
QDD = {'j1': -1.0, 'j2': -2.0, 'j3': -3.0, 'j4': -4.0}


def state(names, q=Q, qd=QD, qdd=QDD, extra=7.0):
    """Arrays of a JointState naming ``names`` (unknown names get ``extra``)."""
    names = tuple(names)
    return (list(names), [q.get(n, extra) for n in names], [qd.get(n, extra) for n in names],
            [qdd.get(n, extra) for n in names])


def expect(reason, *args, match=None):
    with pytest.raises(InputError, match=match) as info:
        joint_state_arrays(JOINTS, *args)
    assert info.value.reason == reason
    assert isinstance(info.value, ValueError)
    assert reason in inputs.REASONS
    return info.value


def test_model_order_from_model_order():
    q, qd, qdd = joint_state_arrays(JOINTS, *state(JOINTS))
    np.testing.assert_array_equal(q, [Q[n] for n in JOINTS])
    np.testing.assert_array_equal(qd, [QD[n] for n in JOINTS])
    np.testing.assert_array_equal(qdd, [QDD[n] for n in JOINTS])
    assert q.dtype == np.float64 and q.shape == (4,)


@given(st.permutations(JOINTS + ('gripper', 'camera_pan')),
       st.sampled_from([math.nan, math.inf, 1e300]))
def test_any_order_and_unknown_names_ignored(names, extra):
    """Shuffled names and joints the model doesn't have (even non-finite) give the same arrays."""
    q, qd, qdd = joint_state_arrays(JOINTS, *state(names, extra=extra))
    np.testing.assert_array_equal(q, [Q[n] for n in JOINTS])
    np.testing.assert_array_equal(qd, [QD[n] for n in JOINTS])
    np.testing.assert_array_equal(qdd, [QDD[n] for n in JOINTS])


def test_array_array_input_like_rclpy():
    """Accept array.array('d'), as rclpy hands over float64[] fields; the result is a copy."""
    import array
    names, q, qd, qdd = state(reversed(JOINTS))
    position = array.array('d', q)
    out, _, _ = joint_state_arrays(JOINTS, names, position, array.array('d', qd),
                                   array.array('d', qdd))
    np.testing.assert_array_equal(out, [Q[n] for n in JOINTS])
    out[0] = 99.0
    assert position[-1] == Q['j1']


def test_empty_optional_arrays_are_zeros():
    names, q, _, _ = state(JOINTS)
    q_, qd, qdd = joint_state_arrays(JOINTS, names, q, [], [])
    np.testing.assert_array_equal(qd, np.zeros(4))
    np.testing.assert_array_equal(qdd, np.zeros(4))


def test_effort_none_means_zero_acceleration_even_with_torques_in_effort():
    """acceleration_source 'none': effort holds measured torques, of any length; it's unused."""
    names, q, qd, _ = state(JOINTS)
    _, _, qdd = joint_state_arrays(JOINTS, names, q, qd, None)
    np.testing.assert_array_equal(qdd, np.zeros(4))


def test_empty_message():
    err = expect('empty', [], [], [], [])
    assert "'name'" in str(err)


@pytest.mark.parametrize('field, index', [('position', 1), ('velocity', 2), ('effort', 3)])
def test_length_mismatch_names_the_field(field, index):
    args = list(state(JOINTS))
    args[index] = args[index][:-1]
    err = expect('length_mismatch', *args)
    assert f"'{field}'" in str(err) and '3 values for 4 names' in str(err)


def test_missing_position_is_a_length_mismatch():
    names, _, qd, qdd = state(JOINTS)
    expect('length_mismatch', names, [], qd, qdd, match="'position' has 0 values")


def test_missing_joint_named():
    err = expect('missing_joint', *state(('j1', 'j2', 'j4', 'gripper')))
    assert "'j3'" in str(err) and "'j1'" not in str(err)


def test_many_missing_joints_listed_briefly():
    many = tuple(f'joint_{i}' for i in range(20))
    with pytest.raises(InputError) as info:
        joint_state_arrays(many, ['other'], [0.0], [], [])
    assert info.value.reason == 'missing_joint'
    assert "'joint_0'" in str(info.value) and str(info.value).endswith('...')


def test_duplicate_model_joint_rejected_duplicate_unknown_ignored():
    expect('duplicate_joint', *state(JOINTS + ('j2',)), match="'j2'")
    q, _, _ = joint_state_arrays(JOINTS, *state(JOINTS + ('x', 'x')))
    np.testing.assert_array_equal(q, [Q[n] for n in JOINTS])


@pytest.mark.parametrize('field, index', [('position', 1), ('velocity', 2), ('effort', 3)])
@pytest.mark.parametrize('bad', [math.nan, math.inf, -math.inf])
def test_non_finite_names_field_and_joint(field, index, bad):
    args = list(state(JOINTS))
    args[index][JOINTS.index('j3')] = bad
    err = expect('non_finite', *args)
    assert f"'{field}'" in str(err) and "'j3'" in str(err) and "'j1'" not in str(err)


def test_mapping_is_cached_per_name_tuple():
    """A publisher that repeats its name order gets the same (read-only) index, not a rebuild."""
    inputs.name_cache_clear()
    names = tuple(reversed(JOINTS))
    idx = inputs.name_index(JOINTS, names)
    assert not idx.flags.writeable
    # a new tuple with equal names (as each message brings) finds the same entry
    assert inputs.name_index(JOINTS, tuple(list(names))) is idx
    assert inputs.name_index(JOINTS, JOINTS) is not idx
    assert inputs.name_cache_info()[0] == 2
    for _ in range(3):
        joint_state_arrays(JOINTS, *state(reversed(JOINTS)))
        joint_state_arrays(JOINTS, *state(JOINTS))
    assert inputs.name_cache_info()[0] == 2


def test_name_cache_is_bounded_by_size_not_count():
    """Many distinct, long name lists (valid: extra names are ignored) keep bounded memory.

    The last 256 lists were all kept before, whatever their size (~3 GB with long lists; here
    ~20 MB); the cache now holds at most NAME_CACHE_BYTES of names, and mapping still works
    for every list.
    """
    import gc
    import tracemalloc
    inputs.name_cache_clear()
    gc.collect()
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        for k in range(300):
            names = [f'extra_{k}_{i}' for i in range(1000)] + list(JOINTS)
            q, _, _ = joint_state_arrays(JOINTS, names, [0.0] * 1000 + [Q[n] for n in JOINTS],
                                         [], [])
            np.testing.assert_array_equal(q, [Q[n] for n in JOINTS])
            del names
        gc.collect()
        held = tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()
    entries, size = inputs.name_cache_info()
    print(f'cache: {entries} entries, {size} bytes estimated; {held / 1e6:.1f} MB held')
    assert 1 < entries and size <= inputs.NAME_CACHE_BYTES
    # what stays allocated is the cache (within 2x of its own estimate) and nothing more
    assert held < 2 * inputs.NAME_CACHE_BYTES, held
    # the common case is still cached after the flood
    idx = inputs.name_index(JOINTS, JOINTS)
    assert inputs.name_index(JOINTS, tuple(JOINTS)) is idx


def test_name_cache_count_is_bounded_for_shuffled_orders():
    """A publisher that shuffles its name order fills at most NAME_CACHE_ENTRIES entries."""
    import itertools
    inputs.name_cache_clear()
    names = JOINTS + ('a', 'b')
    for order in itertools.islice(itertools.permutations(names), 600):
        q, _, _ = joint_state_arrays(JOINTS, *state(order))
        np.testing.assert_array_equal(q, [Q[n] for n in JOINTS])
    assert inputs.name_cache_info()[0] == inputs.NAME_CACHE_ENTRIES


def test_name_list_larger_than_an_entry_is_mapped_but_not_cached():
    inputs.name_cache_clear()
    many = tuple(f'n{i}' for i in range(inputs.NAME_CACHE_BYTES // 64)) + JOINTS
    idx = inputs.name_index(JOINTS, many)
    np.testing.assert_array_equal(idx, len(many) - 4 + np.arange(4))
    assert inputs.name_cache_info() == (0, 0)


def point(positions, velocities=(), accelerations=()):
    return SimpleNamespace(positions=list(positions), velocities=list(velocities),
                           accelerations=list(accelerations))


def test_trajectory_first_point_by_name():
    names, q, qd, qdd = state(('j4', 'j2', 'x', 'j1', 'j3'))
    later = point([0.0] * 5, [0.0] * 5, [0.0] * 5)
    q_, qd_, qdd_ = trajectory_arrays(JOINTS, names, [point(q, qd, qdd), later])
    np.testing.assert_array_equal(q_, [Q[n] for n in JOINTS])
    np.testing.assert_array_equal(qd_, [QD[n] for n in JOINTS])
    np.testing.assert_array_equal(qdd_, [QDD[n] for n in JOINTS])
    _, qd_, qdd_ = trajectory_arrays(JOINTS, names, [point(q)])
    np.testing.assert_array_equal(qd_, np.zeros(4))
    np.testing.assert_array_equal(qdd_, np.zeros(4))


def test_trajectory_errors():
    names, q, qd, qdd = state(JOINTS)
    with pytest.raises(InputError, match="'points'") as info:
        trajectory_arrays(JOINTS, names, [])
    assert info.value.reason == 'no_points'
    with pytest.raises(InputError, match="'points\\[0\\].accelerations'") as info:
        trajectory_arrays(JOINTS, names, [point(q, qd, qdd[:2])])
    assert info.value.reason == 'length_mismatch'
    qd[0] = math.nan
    with pytest.raises(InputError, match="'points\\[0\\].velocities'.*'j1'") as info:
        trajectory_arrays(JOINTS, names, [point(q, qd, qdd)])
    assert info.value.reason == 'non_finite'


def test_no_ros_import():
    code = ('import sys, spatial_dynamics.ros.inputs; '
            "assert 'rclpy' not in sys.modules, 'inputs imported rclpy'")
    subprocess.run([sys.executable, '-c', code], check=True)


def test_values_beyond_what_a_robot_reaches_are_refused_where_they_enter():
    """Desired and measured states alike: one bound per quantity (spatial_dynamics.bounds)."""
    names = ('a', 'b')
    for field, values, message in (
            ('position', ([1e300, 0.0], [0.0, 0.0], [0.0, 0.0]), "'position' of joint 'a'"),
            ('velocity', ([0.0, 0.0], [0.0, -2e4], [0.0, 0.0]), "'velocity' of joint 'b'"),
            ('effort', ([0.0, 0.0], [0.0, 0.0], [1e7, 0.0]), "'effort' of joint 'a'")):
        with pytest.raises(InputError, match=message) as err:
            joint_state_arrays(names, names, *values)
        assert err.value.reason == 'out_of_bounds', field
    point = SimpleNamespace(positions=[0.0, 1e5 + 1], velocities=[], accelerations=[])
    with pytest.raises(InputError) as err:
        trajectory_arrays(names, names, [point])
    assert err.value.reason == 'out_of_bounds' and 'points[0].positions' in str(err.value)
    # at the bound itself: accepted
    q, qd, qdd = joint_state_arrays(names, names, [1e5, -1e5], [1e4, 0.0], [1e6, 0.0])
    assert q.tolist() == [1e5, -1e5] and qdd.tolist() == [1e6, 0.0]
