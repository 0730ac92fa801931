# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A time range of a bag: the fast readers against rosbags' own time filter."""

import numpy as np
import pytest

from spatial_dynamics.recordings import bags

NAMES = ('a', 'b')
T0 = 1_790_000_000 * 10 ** 9        # bag times, ns
N = 30000                          # 30 s at 1 kHz: several MCAP chunks


@pytest.fixture(scope='module', params=['sqlite3', 'mcap'])
def bag(request, tmp_path_factory):
    pytest.importorskip('rosbags')
    t_ns = T0 + np.arange(N, dtype=np.int64) * 1_000_000
    q = np.column_stack([np.sin(np.arange(N) / 300.0), np.arange(N) * 1e-4])
    block = bags.encode_joint_states(NAMES, t_ns + 12345, q, 2 * q, 3 * q)
    path = str(tmp_path_factory.mktemp('ranges') / f'bag_{request.param}')
    other = bags.encode_joint_states(('c',), t_ns[::10], q[::10, :1], None, None)
    bags.write_bag(path, request.param, [
        ('/joint_states', bags.JOINT_STATE, t_ns, [x.tobytes() for x in block]),
        ('/other', bags.JOINT_STATE, t_ns[::10], [x.tobytes() for x in other])])
    return path


RANGES = [(None, None), (None, T0 + 5_000_000_000), (T0 + 5_000_000_000, T0 + 17_500_000_001),
          (T0 + 17_500_000_001, None), (T0 - 10, T0 + 1), (T0 + 29_999_000_000, T0 + 10 ** 12),
          (T0 + 40 * 10 ** 9, None)]


@pytest.mark.parametrize('start, stop', RANGES)
def test_a_range_is_what_rosbags_reads_between_the_times(bag, start, stop):
    got = bags.read_joint_states_between(bag, '/joint_states', NAMES, start, stop)
    want = bags.read_joint_states_between(bag, '/joint_states', NAMES, start, stop,
                                          fast=False)
    assert want.generic == len(want.stamp) and got.fast == len(got.stamp)
    lo = 0 if start is None else max(0, -(-(start - T0) // 1_000_000))
    hi = N if stop is None else min(N, -(-(stop - T0) // 1_000_000))
    assert len(want.stamp) == max(0, hi - lo)
    for field in ('stamp', 'position', 'velocity', 'effort'):
        np.testing.assert_array_equal(getattr(got, field), getattr(want, field))
    if hi > lo:
        assert want.stamp[0] == pytest.approx((T0 + lo * 1_000_000 + 12345) * 1e-9, abs=1e-6)


def test_ranges_that_meet_read_every_message_once(bag):
    whole = bags.read_joint_states(bag, '/joint_states', NAMES)
    cuts = [None, T0 + 7_000_000_000, T0 + 7_000_500_000, T0 + 21_000_000_000, None]
    parts = [bags.read_joint_states_between(bag, '/joint_states', NAMES, a, b)
             for a, b in zip(cuts, cuts[1:])]
    np.testing.assert_array_equal(np.concatenate([p.stamp for p in parts]), whole.stamp)
    np.testing.assert_array_equal(np.concatenate([p.effort for p in parts]), whole.effort)


def test_time_range_is_the_first_and_last_message_of_the_topic(bag):
    first, last = bags.time_range(bag, '/joint_states')
    assert first == T0
    assert last in (T0 + (N - 1) * 1_000_000, T0 + (N - 1) * 1_000_000 + 1)


def test_a_missing_topic_is_named(bag):
    with pytest.raises(bags.BagError, match="'/nope' is not in the bag"):
        bags.read_joint_states_between(bag, '/nope', NAMES, T0, None)
    with pytest.raises(bags.BagError, match="'/nope' is not in the bag"):
        bags.time_range(bag, '/nope')
