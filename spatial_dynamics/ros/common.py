# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""What the package's nodes share: their QoS, endpoints and process around them.

The ``inverse_dynamics`` node, the simulator and the latency baseline's relay make their
subscriptions and publishers here (inputs best effort keep last 1, plans reliable keep last
10, outputs reliable, QoS overrides on, no per-endpoint event handlers) and run in
:func:`spin` (exit 0 on SIGINT and SIGTERM, 1 with one ``cannot start:`` line on a bad
start-up configuration).
"""

from __future__ import annotations

import os
import signal
import sys
import threading
import time
from typing import Any, Callable, Dict, Optional, Sequence
import warnings

import rclpy
from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks
from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.executors import (ExternalShutdownException, MultiThreadedExecutor,
                             SingleThreadedExecutor)
import rclpy.logging
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, QoSReliabilityPolicy
from rclpy.qos_overriding_options import QoSOverridingOptions

from spatial_dynamics.files import read_regular
from spatial_dynamics.ros.parameters import ConfigError, ParameterError
from spatial_dynamics.ros.qos_overrides import allowed, check_overrides, OVERRIDABLE
from spatial_dynamics.ros.realtime import AnsweringLoop, OthersExecutor
from spatial_dynamics.ros.arguments import empty_param_rules, params_files

#: The largest ``--params-file`` read (rcl parses it whole at ``rclpy.init``).
PARAMS_FILE_LIMIT = 64 << 20


def input_qos(depth: int = 1) -> QoSProfile:
    """Input QoS: best effort, keep last ``depth`` (connects to reliable and best-effort pubs).

    A new object per call: QoS overrides (``qos_overrides.<topic>.subscription.*``) are
    written into the profile passed to ``create_subscription``, so it must not be shared.
    """
    return QoSProfile(reliability=QoSReliabilityPolicy.BEST_EFFORT,
                      history=HistoryPolicy.KEEP_LAST, depth=depth)


def output_qos() -> QoSProfile:
    """Output QoS: reliable (what ros2_control's controllers subscribe with), keep last 10."""
    return QoSProfile(reliability=QoSReliabilityPolicy.RELIABLE,
                      history=HistoryPolicy.KEEP_LAST, depth=10)


def plan_qos() -> QoSProfile:
    """Plan (``desired_trajectory``) QoS: reliable, keep last 10.

    A plan is one large sample that must arrive whole: over best effort, Fast DDS drops a
    sample whose fragments do not all arrive (a 9,000-point plan, ~650 KB, never did). Keep
    last 10: plans queued for later starts sent in a burst. A new object per call, as
    :func:`input_qos`. Best-effort publishers do not match it (``ros2 topic pub`` and
    MoveIt publish reliable).
    """
    return QoSProfile(reliability=QoSReliabilityPolicy.RELIABLE,
                      history=HistoryPolicy.KEEP_LAST, depth=10)


DESCRIPTION_QOS = QoSProfile(reliability=QoSReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL,
                             history=HistoryPolicy.KEEP_LAST, depth=1)


def subscribe(node: Node, msg_type, topic: str, callback, depth: int = 1, group=None,
              qos: Optional[QoSProfile] = None, raw: bool = False):
    """Subscribe with :func:`input_qos` (or ``qos``), QoS overrides on, no QoS event handlers.

    ``raw``: the callback gets the serialized message (bytes), to be sized before converting.

    rclpy adds default event handlers (incompatible QoS / type warnings) per endpoint to the
    wait set, which costs every spin of the executor 5-12 µs per endpoint (measured with
    rclpy 7.1.6: an idle spin_once with 3 subscriptions + 3 publishers took 219 µs with them,
    148 µs without). The inputs' best effort + volatile accepts every publisher anyway, and
    the other end of an incompatible pair still reports it with its own default handlers.
    """
    return _endpoint(node, topic, 'subscription', lambda: node.create_subscription(
        msg_type, topic, callback, input_qos(depth) if qos is None else qos,
        callback_group=group, raw=raw,
        qos_overriding_options=QoSOverridingOptions.with_default_policies(),
        event_callbacks=SubscriptionEventCallbacks(use_default_callbacks=False)))


def advertise(node: Node, msg_type, topic: str):
    """Create a publisher with :func:`output_qos`, QoS overrides, no QoS event handlers."""
    return _endpoint(node, topic, 'publisher', lambda: node.create_publisher(
        msg_type, topic, output_qos(),
        qos_overriding_options=QoSOverridingOptions.with_default_policies(),
        event_callbacks=PublisherEventCallbacks(use_default_callbacks=False)))


#: The start of the warning rclpy's QoSProfile gives for keep last 0 (said by
#: :func:`_endpoint` in a line of its own instead).
ZERO_DEPTH_WARNING = "A zero depth with KEEP_LAST doesn't make sense"


def parameter_overrides(node: Node) -> Dict[str, Any]:
    """Return the parameter overrides ``node`` was started with, name to value.

    Those of the command line and the params files (rcl's, for this node and ``/**``) and
    the ``parameter_overrides`` of its constructor. rclpy has no public accessor: Node keeps
    them in ``_parameter_overrides`` (rclpy 7.1.6, Jazzy, and earlier). Without it, nothing
    is checked before the endpoints are made and :func:`_endpoint` still turns what rcl
    refuses into a :class:`ConfigError` (with rcl's own words and dumps).
    """
    given = getattr(node, '_parameter_overrides', None)
    if not isinstance(given, dict):
        return {}
    return {name: getattr(p, 'value', None) for name, p in given.items()}


def _endpoint(node: Node, topic: str, kind: str, create: Callable[[], Any]):
    """Make endpoint ``kind`` of ``topic`` by ``create()`` once its QoS overrides are checked.

    The overrides are checked before rcl sees them (:func:`~.qos_overrides.check_overrides`:
    a :class:`ParameterError` names the parameter, the value and what is allowed). A depth
    of 0 with keep last is said in one INFO line (rclpy's ``UserWarning`` for it is not
    shown). What rcl still refuses is a :class:`ConfigError` naming the endpoint, unless the
    context was shut down meanwhile (a signal while starting): then rcl's error is raised
    as it is, for :func:`spin` to end the process cleanly.
    """
    name = node.resolve_topic_name(topic)
    check_overrides(parameter_overrides(node), name, kind)
    try:
        with warnings.catch_warnings():
            warnings.filterwarnings('ignore', ZERO_DEPTH_WARNING, UserWarning)
            endpoint = create()
    except (_rclpy.RCLError, RuntimeError, TypeError) as err:
        if not node.context.ok():
            raise
        reason = str(err).strip().split('\n')[-1]
        raise ConfigError(f'the middleware refused the QoS of {kind} {name!r}: '
                          f'{reason}') from None
    qos = endpoint.qos_profile
    if qos.history == HistoryPolicy.KEEP_LAST and qos.depth == 0:
        node.get_logger().info(
            f'qos_overrides.{name}.{kind}.depth: 0 with keep_last is the middleware\'s '
            'default depth')
    return endpoint


def check_param_rules(argv: Sequence[str]) -> None:
    """Refuse a ``-p NAME:=`` without a value (rcl's words: ``Error: error not set``).

    Raises ValueError naming the parameter and, for a QoS override, what it takes.
    """
    for name, rule in empty_param_rules(argv):
        policy = name.rsplit('.', 1)[-1]
        if name.startswith('qos_overrides.') and policy in OVERRIDABLE:
            raise ValueError(f'{name}: need {allowed(policy)}, got nothing (-p {rule})')
        raise ValueError(f'{name}: no value after := (-p {rule}; an empty string is '
                         f"-p \"{rule}''\")")


def _context_shut_down(grace: float = 1.0) -> bool:
    """Whether the default context is shut down, or is within ``grace`` s (signal thread)."""
    deadline = time.monotonic() + grace
    while rclpy.ok():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.01)
    return True


def spin(make_node: Callable[[], Node], args: Optional[Sequence[str]] = None,
         name: str = 'inverse_dynamics', threads: int = 2) -> int:
    """Make a node and spin it until SIGINT/SIGTERM; 0 on a clean exit, 1 on a bad start-up.

    The node's and the latency baseline's (``relay.py``) process around them, one routine.
    A node with an ``answering_group`` has it spun in a thread of its own by a loop that
    waits on that group only (:class:`~.realtime.AnsweringLoop`), and everything else by a
    MultiThreadedExecutor of ``threads`` - 1 threads that never waits on it (the node answers
    while a parameter change parses a description in rclpy's default group). Otherwise, with
    ``threads`` > 1 the executor is rclpy's MultiThreadedExecutor; 1 gives the
    SingleThreadedExecutor.

    SIGINT is handled as SIGTERM is: rclpy's handler shuts the context down and wakes the
    executor, which returns between two callbacks. Python's KeyboardInterrupt is not used: it
    would fire at any bytecode, inside rclpy's bookkeeping too (half-built tasks, a taken
    message lost in pybind11's conversion). Before ``rclpy.init`` has returned, nothing needs
    stopping: either signal ends the process at once with status 0 (as the launchers in
    ``bin/`` do while Python imports). While ``make_node`` runs, a signal shuts the context
    down: whatever that breaks (rcl refusing an endpoint on an invalid context) is the
    requested stop, one INFO line ``interrupted while starting`` and status 0, never a
    ``cannot start:`` line.

    Before ``rclpy.init``, each ``--params-file`` must be a readable regular file (rcl would
    block on a named pipe) and each ``-p`` rule must have a value; that, and what
    ``rclpy.init`` refuses (an unknown ROS argument, a params file it cannot parse), is one
    ``cannot start:`` line and status 1.
    """
    started = threading.Event()     # rclpy.init returned: rclpy's handlers stop the node

    def before_ros(signum: int, frame) -> None:
        if not started.is_set():     # nothing started yet that needs stopping
            os._exit(0)

    if threading.current_thread() is threading.main_thread():
        for signum in (signal.SIGINT, signal.SIGTERM):
            signal.signal(signum, before_ros)
    logger = rclpy.logging.get_logger(name)
    try:
        for path in params_files(sys.argv if args is None else args):
            read_regular(path, f'params file {path!r}', PARAMS_FILE_LIMIT)
        check_param_rules(sys.argv if args is None else args)
        rclpy.init(args=args)
    except (ValueError, _rclpy.UnknownROSArgsError, _rclpy.RCLError) as err:
        reason = str(err).strip().split('\n')[0]
        if isinstance(err, _rclpy.UnknownROSArgsError):
            reason = f'unknown ROS argument(s) {reason} (see --help)'
        logger.fatal(f'cannot start: {reason}')
        return 1
    started.set()
    node = None
    status = 0
    failed: list = []
    try:
        try:
            node = make_node()
        except Exception as err:
            if rclpy.ok():
                raise
            # a signal shut the context down while the node was being made: whatever that
            # broke (rcl refusing an endpoint on an invalid context) is the requested stop
            logger.debug(f'while starting: {type(err).__name__}: {err}')
        if not rclpy.ok():
            logger.info('interrupted while starting')
            return 0
        group = getattr(node, 'answering_group', None)
        if group is not None:
            _spin_answering(node, group, threads - 1, failed)
        else:
            executor = (MultiThreadedExecutor(num_threads=threads) if threads > 1
                        else SingleThreadedExecutor())
            executor.add_node(node)
            executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except (ConfigError, ParameterError, InvalidParameterTypeException,
            InvalidParameterValueException) as err:
        # e.g. -p gravity:=[0,0,-10] (integers) or -p input_timeout:=0.0 (out of range)
        logger.fatal(f'cannot start: {err}')
        status = 1
    except Exception:
        # SIGINT/SIGTERM shut the context down from rclpy's signal thread, wherever the
        # executor is: between two waits it raises RCLError ("failed to initialize wait set:
        # the given context is not valid"); in a take, the KeyboardInterrupt of SIGINT inside
        # pybind11's message conversion surfaces as RuntimeError ("Unable to convert call
        # argument"). Those are the requested shutdown; with the context still valid, an
        # exception is a real error and is raised.
        if not _context_shut_down():
            raise
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    if failed:   # the answering thread stopped on an error: the node must not run on mute
        raise failed[0]
    return status


def _spin_answering(node: Node, group, threads: int, failed: list) -> None:
    """Spin ``group`` of ``node`` in a thread of its own, the rest here, until shutdown.

    The answering thread first calls ``node.on_answering_thread()`` (its real-time knobs).
    An exception there (a bug: the callbacks catch what a message can cause) is put in
    ``failed`` and shuts the context down, so the process ends instead of running without
    answers; one raised by the requested shutdown is not.
    """
    answering = AnsweringLoop(node, group)
    others = OthersExecutor(group, max(threads, 1), node.context)
    others.add_node(node)

    def run() -> None:
        try:
            node.on_answering_thread()
            answering.spin()
        except Exception as err:  # raised again by spin, in the main thread
            if not _context_shut_down():
                failed.append(err)
                rclpy.try_shutdown()

    thread = threading.Thread(target=run, name='answering', daemon=True)
    thread.start()
    try:
        others.spin()
    finally:
        rclpy.try_shutdown()
        thread.join(5.0)
