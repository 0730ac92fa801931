# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Uncompressed rosbag2 sqlite3 files read with the standard library's sqlite3 (no ``rosbags``).

rosbags counts every topic's messages and their time range when it opens a bag (1.7 s for an
hour at 1 kHz); the rows of one topic are read here straight from the ``messages`` table, in
batches, through its time index when a range is asked for.
"""

from __future__ import annotations

from operator import itemgetter
import os
import sqlite3
from typing import Dict, Iterator, List, Optional, Sequence, Tuple
from urllib.parse import quote

import numpy as np

from ..text import shown
from .cdr import Batch
from .errors import BagError

BATCH = 1 << 16       # messages per batch: bounds the memory of the byte blocks

_first, _second = itemgetter(0), itemgetter(1)


def connect(path: str):
    """Open a rosbag2 sqlite3 file read-only with the standard library."""
    # quoted: in a file: URI, %, # and ? of a path would mean something else
    return sqlite3.connect(f'file:{quote(os.path.abspath(path))}?mode=ro', uri=True)


def not_a_bag(path: str, why: str) -> BagError:
    return BagError(f'{os.path.realpath(path)!r}: not a rosbag2 sqlite3 database ({why})')


def batches(paths: Sequence[str], topic: str, start: Optional[int] = None,
            stop: Optional[int] = None) -> Iterator[Batch]:
    """Yield batches of one topic's messages from rosbag2 sqlite3 files (standard library).

    With ``start``/``stop`` (ns, bag time), those in ``[start, stop)`` only: rosbag2 (and
    ``rosbags``) index ``messages.timestamp``, so SQLite reads the range's rows alone. Either
    way the rows come in bag order (by id).
    """
    ranged = start is not None or stop is not None
    bounds = ([-(1 << 63) if start is None else int(start),
               (1 << 63) - 1 if stop is None else int(stop)] if ranged else [])
    where = 'timestamp >= ? AND timestamp < ? AND ' if ranged else ''
    for path in paths:
        con = connect(path)
        try:
            ids = [i for i, in con.execute('SELECT id FROM topics WHERE name = ?', (topic,))]
            # by topic id, without a join: the rows come straight from the messages table
            cur = con.execute(f'SELECT timestamp, data FROM messages WHERE {where}topic_id IN '
                              f'({", ".join("?" * len(ids))}) ORDER BY id', bounds + ids)
            while True:
                rows = cur.fetchmany(BATCH)
                if not rows:
                    break
                # two maps: a sixth of the time of zip(*rows) over 65536 rows
                times, data = list(map(_first, rows)), list(map(_second, rows))
                if set(map(type, data)) != {bytes} or set(map(type, times)) != {int}:
                    raise not_a_bag(path, 'a message whose timestamp is not an integer '
                                          'or data not bytes')
                yield np.array(times, dtype=np.int64), data
        except sqlite3.Error as err:
            raise not_a_bag(path, str(err)) from None
        finally:
            con.close()


def bag_files(staged: str, topic: str) -> Tuple[Optional[List[str]], int]:
    """``(storage files, messages of topic)`` of a staged bag that is uncompressed sqlite3.

    ``(None, 0)`` for any other bag; the count is the metadata's (0 if it has none).
    """
    if not os.path.isdir(staged):
        return ([staged] if staged.endswith('.db3') else None), 0
    import yaml       # optional (the replay extra): imported where a bag needs it
    with open(os.path.join(staged, 'metadata.yaml'), encoding='utf-8') as f:
        info = yaml.safe_load(f)['rosbag2_bagfile_information']     # written by bags._staged
    files = info['relative_file_paths']
    if (info.get('storage_identifier') != 'sqlite3' or not files
            or str(info.get('compression_mode') or '').lower() not in ('', 'none')
            or not all(f.endswith('.db3') for f in files)):
        return None, 0
    count = 0
    for entry in info.get('topics_with_message_count') or []:
        try:
            if entry['topic_metadata']['name'] == topic:
                count += max(0, int(entry['message_count']))
        except (KeyError, TypeError, ValueError):
            pass
    return [os.path.join(staged, f) for f in files], count


def topics_of(paths: Sequence[str], count: int) -> Tuple[Dict[str, Tuple[str, int]], int]:
    """:func:`.bags.topics` of sqlite3 files (counts left 0), and ``count`` made a safe hint.

    The metadata's message count only sizes the arrays (they grow when it is short), but a
    bag's metadata may say anything: it is capped by the rows the files hold (the largest
    message id, found in the index) and their size (16 bytes a message at least).
    """
    found: Dict[str, Tuple[str, int]] = {}
    rows = 0
    for path in paths:
        con = connect(path)
        try:
            for name, typ in con.execute('SELECT name, type FROM topics'):
                found.setdefault(name, (typ, 0))
            last = con.execute('SELECT max(id) FROM messages').fetchone()[0]
            rows += last if isinstance(last, int) and last > 0 else 0
        except sqlite3.Error as err:
            raise not_a_bag(path, str(err)) from None
        finally:
            con.close()
    size = sum(os.path.getsize(p) for p in paths)
    return found, max(0, min(count, rows, size // 16))


def time_range(files: Sequence[str], path: str, topic: str) -> Tuple[int, int]:
    """Return the bag times (ns) of the first and last message of ``topic`` in ``files``.

    From the time index; :class:`BagError` naming the bag ``path`` when the topic has no
    message.
    """
    ends = []
    for f in files:
        con = connect(f)
        try:
            ends.append(con.execute(
                'SELECT min(timestamp), max(timestamp) FROM messages WHERE topic_id '
                'IN (SELECT id FROM topics WHERE name = ?)', (topic,)).fetchone())
        except sqlite3.Error as err:
            raise not_a_bag(f, str(err)) from None
        finally:
            con.close()
    ends = [e for e in ends if isinstance(e[0], int) and isinstance(e[1], int)]
    if not ends:
        raise BagError(f'{path!r}: topic {shown(topic)} has no message')
    return min(e[0] for e in ends), max(e[1] for e in ends)
