# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The QoS overrides an endpoint of the nodes takes, checked before rcl sees them (no rclpy).

An endpoint made by :func:`.common.subscribe` or :func:`.common.advertise` takes
``qos_overrides.<topic>.<kind>.<policy>`` for the default policies of rclpy's
``QoSOverridingOptions.with_default_policies()`` only:

========================  ===================================================================
policy                    values
========================  ===================================================================
``history``               ``keep_last``, ``keep_all``, ``system_default``
``depth``                 an integer from 0 to 2147483647 (0 with ``keep_last``: the
                          middleware's default depth)
``reliability``           ``reliable``, ``best_effort``, ``best_available``, ``system_default``
========================  ===================================================================

``<topic>`` is the resolved name (``/ns/desired_joint_states``), ``<kind>`` ``subscription``
or ``publisher``. rclpy would hand a negative depth to rcl (which refuses it with a screen of
``rcutils_set_error_state()`` dumps), refuse a double or a string with its own words and
ignore any other policy (``durability``, ``deadline``) without a word; :func:`check_overrides`
refuses each with one message naming the parameter, the value given and what is allowed.
An override naming a topic the node does not have is not looked at, as by every ROS node.
"""

from __future__ import annotations

from typing import Any, Dict, Mapping, Tuple

from spatial_dynamics.ros.parameters import ParameterError

#: The largest queue a QoS profile holds (a C int in rclpy's profile).
DEPTH_MAX = 2 ** 31 - 1

#: The values of each policy that takes a name (lower case; rclpy takes any case).
NAMED: Dict[str, Tuple[str, ...]] = {
    'history': ('keep_last', 'keep_all', 'system_default'),
    'reliability': ('reliable', 'best_effort', 'best_available', 'system_default'),
}

#: The policies an endpoint takes an override of, in rclpy's order of applying them.
OVERRIDABLE = ('history', 'depth', 'reliability')


def allowed(policy: str) -> str:
    """Return what ``policy`` takes, in words (for the docs and the refusals)."""
    if policy == 'depth':
        return f'an integer from 0 to {DEPTH_MAX} (messages queued)'
    return 'one of ' + ', '.join(NAMED[policy])


def _given(value: Any) -> str:
    """Return ``value`` as a parameter override gives it, with its type when not the text's."""
    if isinstance(value, bool):
        return f'{str(value).lower()} (a bool)'
    if isinstance(value, float):
        return f'{value!r} (a double)'
    if isinstance(value, (list, tuple)):
        return f'{list(value)!r} (an array)'
    return repr(value)


def endpoint_overrides(overrides: Mapping[str, Any], topic: str, kind: str) -> Dict[str, Any]:
    """Return the overrides of endpoint ``kind`` (subscription, publisher) of ``topic``.

    ``overrides``: parameter name to value, as the node was started with; ``topic``: the
    resolved name. The result maps each policy named to its value.
    """
    prefix = f'qos_overrides.{topic}.{kind}.'
    return {name[len(prefix):]: value for name, value in overrides.items()
            if name.startswith(prefix)}


def check_overrides(overrides: Mapping[str, Any], topic: str, kind: str) -> Dict[str, Any]:
    """Return the overrides of ``kind`` of ``topic`` by policy; refuse one it cannot take.

    Raises :class:`~.parameters.ParameterError` naming the parameter, the value given and
    what is allowed: a policy other than :data:`OVERRIDABLE`, a depth that is not an integer
    from 0 to :data:`DEPTH_MAX`, a history or reliability that is not one of :data:`NAMED`'s
    (any case). The values returned are as given (a name in its own case).
    """
    given = endpoint_overrides(overrides, topic, kind)
    for policy in sorted(given):
        value = given[policy]
        name = f'qos_overrides.{topic}.{kind}.{policy}'
        if policy not in OVERRIDABLE:
            raise ParameterError(
                f'{name}: the {kind} of {topic!r} takes overrides of '
                f'{", ".join(OVERRIDABLE)} only, got {_given(value)}')
        if policy == 'depth':
            good = (isinstance(value, int) and not isinstance(value, bool)
                    and 0 <= value <= DEPTH_MAX)
        else:
            good = isinstance(value, str) and value.lower() in NAMED[policy]
        if not good:
            raise ParameterError(f'{name}: need {allowed(policy)}, got {_given(value)}')
    return given
