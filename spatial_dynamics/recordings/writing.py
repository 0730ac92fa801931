# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Write rosbag2 bags (sqlite3 or MCAP) through ``rosbags``: for tests and the benchmarks.

``rosbags`` is imported when a bag is written (start-up time: reading needs it only for what
the fast readers leave).
"""

from __future__ import annotations

from typing import Callable, Optional, Sequence, Tuple

import numpy as np

from .cdr import INSTALL_HINT, MissingDependency, typestore


Topic = Tuple[str, str, np.ndarray, Sequence[bytes]]


def write_bag(path: str, storage: str, topics_messages: Sequence[Topic],
              progress: Optional[Callable[[int], None]] = None) -> None:
    """Write a rosbag2 bag: ``(topic, msgtype, times_ns, serialised messages)`` per topic.

    ``storage`` is ``'sqlite3'`` or ``'mcap'``; messages are written in the given order.
    """
    try:
        from rosbags.rosbag2 import StoragePlugin, Writer
    except ImportError:
        raise MissingDependency(INSTALL_HINT) from None
    store = typestore()
    plugin = {'sqlite3': StoragePlugin.SQLITE3, 'mcap': StoragePlugin.MCAP}[storage]
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        for topic, msgtype, times, messages in topics_messages:
            conn = writer.add_connection(topic, msgtype, typestore=store)
            write = writer.write
            for k, (t, data) in enumerate(zip(times.tolist(), messages)):
                write(conn, t, data)
                if progress is not None and not k % 65536:
                    progress(k)


def serialize(msg, msgtype: str) -> bytes:
    """Serialise one ``rosbags`` message object to CDR bytes."""
    return bytes(typestore().serialize_cdr(msg, msgtype))
