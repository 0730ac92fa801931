# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The QoS overrides an endpoint takes, checked before rcl sees them (no ROS needed)."""

import pytest

from spatial_dynamics.ros.arguments import empty_param_rules
from spatial_dynamics.ros.parameters import ParameterError
from spatial_dynamics.ros.qos_overrides import check_overrides, DEPTH_MAX

TOPIC = '/desired_joint_states'
PREFIX = f'qos_overrides.{TOPIC}.subscription.'


@pytest.mark.parametrize('policy, value, words', [
    ('depth', -1, ('depth: need an integer from 0 to 2147483647', 'got -1')),
    ('depth', DEPTH_MAX + 1, ('got 2147483648',)),
    ('depth', 1e300, ('got 1e+300 (a double)',)),
    ('depth', 1e20, ('got 1e+20 (a double)',)),     # -p ...:=99999999999999999999
    ('depth', 1.5, ('got 1.5 (a double)',)),
    ('depth', 'abc', ("got 'abc'",)),
    ('depth', True, ('got true (a bool)',)),
    ('reliability', 1, ('reliability: need one of reliable, best_effort, best_available, '
                        'system_default, got 1',)),
    ('reliability', 'sometimes', ("got 'sometimes'",)),
    ('reliability', '', ("got ''",)),
    ('history', 5, ('history: need one of keep_last, keep_all, system_default, got 5',)),
    ('durability', 'forever', ("durability: the subscription of '/desired_joint_states' "
                               "takes overrides of history, depth, reliability only, "
                               "got 'forever'",)),
    ('deadline', -1, ('deadline: the subscription', 'got -1')),
])
def test_a_bad_override_is_refused_naming_it_the_value_and_allowed(policy, value, words):
    with pytest.raises(ParameterError) as caught:
        check_overrides({PREFIX + policy: value}, TOPIC, 'subscription')
    said = str(caught.value)
    assert said.startswith(PREFIX + policy + ': '), said
    for word in words:
        assert word in said, (word, said)


def test_good_overrides_pass_and_other_endpoints_are_not_looked_at():
    good = {PREFIX + 'depth': 0, PREFIX + 'reliability': 'RELIABLE',
            PREFIX + 'history': 'keep_all',
            f'qos_overrides.{TOPIC}.publisher.depth': -1,          # not an endpoint we make
            'qos_overrides./other.subscription.durability': 'forever',
            f'qos_overrides.{TOPIC}.subscription_id.depth': -1,     # another entity id
            f'qos_overrides.{TOPIC}/deeper.subscription.depth': -1,
            'gravity': [0.0, 0.0, -9.81]}
    assert check_overrides(good, TOPIC, 'subscription') == {
        'depth': 0, 'reliability': 'RELIABLE', 'history': 'keep_all'}
    for value in ('best_effort', 'best_available', 'system_default', 'Reliable'):
        check_overrides({PREFIX + 'reliability': value}, TOPIC, 'subscription')
    check_overrides({PREFIX + 'depth': DEPTH_MAX}, TOPIC, 'subscription')


def test_a_parameter_rule_without_a_value_is_found():
    argv = ['prog', '--ros-args', '-p', 'a:=1', '-p', f'{PREFIX}reliability:=',
            '--param', 'node:b:= ', '-r', 'x:=', '--', '-p', 'c:=']
    assert empty_param_rules(argv) == [(PREFIX + 'reliability', f'{PREFIX}reliability:='),
                                       ('b', 'node:b:= ')]
