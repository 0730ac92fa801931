# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Read and write rosbag2 recordings (sqlite3 and MCAP) without ROS, through ``rosbags``.

Uncompressed sqlite3 and MCAP files are read without ``rosbags``' per-message machinery (the
standard library's sqlite3; MCAP chunks parsed with numpy) and their JointStates decoded in
bulk by :mod:`.cdr`; anything else goes through ``rosbags``' readers and deserialiser.
"""

from __future__ import annotations

from operator import itemgetter
import os
import shutil
from typing import Callable, Dict, Iterator, List, Optional, Sequence, Tuple
from urllib.parse import quote
import weakref

import numpy as np

from ..files import load_yaml, read_regular, regular_file
from .cdr import (Batch, decode_fixed, decode_joint_states, encode_joint_states, FIELDS,
                  INSTALL_HINT, JOINT_STATE, joint_states_from_raw, JointStates, layout,
                  MissingDependency, Stamped, typestore, verify_layout, view_bytes)

__all__ = ['BagError', 'check_bag', 'decode_joint_states', 'encode_joint_states', 'FIELDS',
           'JOINT_STATE', 'JOINT_TRAJECTORY', 'joint_states_from_raw', 'JointStates', 'layout',
           'MissingDependency', 'open_reader', 'read_joint_states', 'read_messages',
           'serialize', 'typestore', 'verify_layout', 'write_bag']

JOINT_TRAJECTORY = 'trajectory_msgs/msg/JointTrajectory'


class BagError(ValueError):
    """The bag cannot be read as asked: no such bag, topic or type; the message says which."""


# --------------------------------------------------------------------------------------------
# Bags

#: Largest metadata.yaml read, bytes (an hour of a busy robot's bag has a few kB).
MAX_METADATA_BYTES = 16 * 1024 * 1024
#: Largest storage file opened, bytes.
MAX_STORAGE_BYTES = 1 << 44


def _staged(path: str) -> Tuple[str, str]:
    """Stage a bag in a private directory: ``(path to hand to rosbags, directory to remove)``.

    SQLite opens a database by a ``file:`` URI, in which ``%``, ``#`` and ``?`` of a path mean
    something else (rosbags builds ``file:{path}?immutable=1`` unquoted: a bag in ``pct%41``
    would read the bag ``pctA``). So a bag is never opened by the name the user gave: a fresh
    directory (its name chosen by ``tempfile``) gets a symbolic link with a plain name to each
    storage file, each checked to be a regular file first (a FIFO would block SQLite), and,
    for a bag directory, its ``metadata.yaml`` read by the safe reader, safe-loaded within
    budgets, and written back naming the links. Nothing else of the bag is read.
    """
    import tempfile
    import yaml
    stage = tempfile.mkdtemp(prefix='spatial_dynamics_bag_')
    try:
        if not os.path.isdir(path):
            ext = os.path.splitext(path)[1]
            if ext not in ('.db3', '.mcap'):
                raise BagError(f'{path}: a bag is a rosbag2 directory or a .db3 / .mcap file')
            regular_file(path, f'bag file {path!r}', MAX_STORAGE_BYTES)
            os.symlink(os.path.abspath(path), os.path.join(stage, 'bag' + ext))
            return os.path.join(stage, 'bag' + ext), stage
        where = f'bag {path!r} metadata.yaml'
        meta = load_yaml(read_regular(os.path.join(path, 'metadata.yaml'), where,
                                      MAX_METADATA_BYTES), where)
        info = meta.get('rosbag2_bagfile_information') if isinstance(meta, dict) else None
        files = info.get('relative_file_paths') if isinstance(info, dict) else None
        if not isinstance(files, list) or not all(isinstance(f, str) for f in files):
            raise BagError(f'{where}: no rosbag2_bagfile_information.relative_file_paths list')
        renamed = {}
        for k, rel in enumerate(files):
            name = os.path.basename(rel)        # as rosbags does: files are in the directory
            real = os.path.join(path, name)
            regular_file(real, f'bag file {real!r}', MAX_STORAGE_BYTES)
            renamed[rel] = f'{k}{os.path.splitext(name)[1]}'
            os.symlink(os.path.abspath(real), os.path.join(stage, renamed[rel]))
        info['relative_file_paths'] = [renamed[f] for f in files]
        for entry in info.get('files') or []:
            if isinstance(entry, dict) and entry.get('path') in renamed:
                entry['path'] = renamed[entry['path']]
        with open(os.path.join(stage, 'metadata.yaml'), 'w', encoding='utf-8') as f:
            yaml.safe_dump(meta, f, sort_keys=False)
        return stage, stage
    except BaseException:
        shutil.rmtree(stage, ignore_errors=True)
        raise


def _stage(path: str) -> Tuple[str, str]:
    """:func:`_staged` with its refusals as :class:`BagError`."""
    if not os.path.exists(path):
        raise BagError(f'{path}: no such bag')
    try:
        return _staged(path)
    except ValueError as err:      # BagError, and the safe reader's refusals name the file
        raise BagError(str(err)) from None


def check_bag(path: str) -> None:
    """Refuse a bag that cannot be opened, before any work: :class:`BagError` naming it.

    The checks of :func:`_staged` (the path exists; a .db3 or .mcap file, or a directory
    whose metadata.yaml names regular storage files), without reading a message.
    """
    shutil.rmtree(_stage(path)[1], ignore_errors=True)


def open_reader(path: str):
    """Return an open ``rosbags`` reader of a bag directory (or a single .db3/.mcap file).

    The bag is opened through :func:`_staged` (plain names, regular files only, metadata
    safe-loaded); the staging directory goes with the reader.
    """
    try:
        from rosbags.rosbag2 import Reader
    except ImportError:
        raise MissingDependency(INSTALL_HINT) from None
    staged, stage = _stage(path)
    try:
        reader = Reader(staged)
        reader.open()
    except Exception as err:     # rosbags' ReaderError and the storage plugins' errors
        shutil.rmtree(stage, ignore_errors=True)
        text = str(err).replace(stage, path)
        raise BagError(f'{path}: cannot open as a rosbag2 bag: {text}') from None
    except BaseException:       # Ctrl-C: the staging folder goes too
        shutil.rmtree(stage, ignore_errors=True)
        raise
    weakref.finalize(reader, shutil.rmtree, stage, True)
    return reader


def topics(reader) -> Dict[str, Tuple[str, int]]:
    """Map each topic of an open reader to ``(message type, message count)``.

    A count is metadata.yaml's for a bag directory: one that is not a whole number ≥ 0
    counts 0 (it only sizes arrays).
    """
    out: Dict[str, Tuple[str, int]] = {}
    for c in reader.connections:
        typ, count = out.get(c.topic, (c.msgtype, 0))
        usable = isinstance(c.msgcount, int) and c.msgcount > 0
        out[c.topic] = (typ, count + (c.msgcount if usable else 0))
    return out


def check_topic(found: Dict[str, Tuple[str, int]], topic: str, msgtype: str) -> None:
    """:class:`BagError` naming the topics there are unless ``topic`` of ``msgtype`` is one."""
    if topic not in found:
        have = ', '.join(f'{t} ({m})' for t, (m, _) in sorted(found.items())) or 'none'
        raise BagError(f'topic {topic!r} is not in the bag; its topics: {have}')
    if found[topic][0] != msgtype:
        raise BagError(f'topic {topic!r} has type {found[topic][0]}, expected {msgtype}')


def connections_of(reader, topic: str, msgtype: str) -> list:
    """Return the reader's connections of ``topic``; :class:`BagError` naming what there is."""
    check_topic(topics(reader), topic, msgtype)
    return [c for c in reader.connections if c.topic == topic]


BATCH = 1 << 16       # messages per batch: bounds the memory of the byte blocks


def storage_files(reader) -> Tuple[str, List[str]]:
    """Return ``(storage, paths)`` of an open reader's files when they are uncompressed.

    ``storage`` is ``'sqlite3'`` or ``'mcap'`` (files the fast readers below understand), or
    ``''`` when the bag is compressed as a whole or of another kind.
    """
    storage = reader.storage
    parts = getattr(storage, 'storages', [storage])
    meta = getattr(storage, 'metadata', None)
    if meta is not None and getattr(meta, 'compression_mode', None):
        return '', []
    paths = [str(getattr(p, 'path', '')) for p in parts]
    if paths and all(p.endswith('.db3') for p in paths):
        return 'sqlite3', paths
    if paths and all(p.endswith('.mcap') for p in paths):
        return 'mcap', paths
    return '', []


_first, _second = itemgetter(0), itemgetter(1)


def _sqlite_connect(path: str):
    """Open a rosbag2 sqlite3 file read-only with the standard library."""
    import sqlite3
    # quoted: in a file: URI, %, # and ? of a path would mean something else
    return sqlite3.connect(f'file:{quote(os.path.abspath(path))}?mode=ro', uri=True)


def _not_sqlite_bag(path: str, why: str) -> BagError:
    return BagError(f'{os.path.realpath(path)}: not a rosbag2 sqlite3 database ({why})')


def _sqlite_batches(paths: Sequence[str], topic: str, start: Optional[int] = None,
                    stop: Optional[int] = None) -> Iterator[Batch]:
    """Yield batches of one topic's messages from rosbag2 sqlite3 files (standard library).

    With ``start``/``stop`` (ns, bag time), those in ``[start, stop)`` only: rosbag2 (and
    ``rosbags``) index ``messages.timestamp``, so SQLite reads the range's rows alone. Either
    way the rows come in bag order (by id).
    """
    import sqlite3
    ranged = start is not None or stop is not None
    bounds = ([-(1 << 63) if start is None else int(start),
               (1 << 63) - 1 if stop is None else int(stop)] if ranged else [])
    where = 'timestamp >= ? AND timestamp < ? AND ' if ranged else ''
    for path in paths:
        con = _sqlite_connect(path)
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
                    raise _not_sqlite_bag(path, 'a message whose timestamp is not an integer '
                                          'or data not bytes')
                yield np.array(times, dtype=np.int64), data
        except sqlite3.Error as err:
            raise _not_sqlite_bag(path, str(err)) from None
        finally:
            con.close()


def _sqlite_bag(staged: str, topic: str) -> Tuple[Optional[List[str]], int]:
    """``(storage files, messages of topic)`` of a staged bag that is uncompressed sqlite3.

    ``(None, 0)`` for any other bag; the count is the metadata's (0 if it has none).
    """
    if not os.path.isdir(staged):
        return ([staged] if staged.endswith('.db3') else None), 0
    import yaml
    with open(os.path.join(staged, 'metadata.yaml'), encoding='utf-8') as f:
        info = yaml.safe_load(f)['rosbag2_bagfile_information']     # written by _staged
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


def _sqlite_topics(paths: Sequence[str], count: int) -> Tuple[Dict[str, Tuple[str, int]], int]:
    """:func:`topics` of sqlite3 files (counts left 0), and ``count`` made a safe hint.

    The metadata's message count only sizes the arrays (they grow when it is short), but a
    bag's metadata may say anything: it is capped by the rows the files hold (the largest
    message id, found in the index) and their size (16 bytes a message at least).
    """
    import sqlite3
    found: Dict[str, Tuple[str, int]] = {}
    rows = 0
    for path in paths:
        con = _sqlite_connect(path)
        try:
            for name, typ in con.execute('SELECT name, type FROM topics'):
                found.setdefault(name, (typ, 0))
            last = con.execute('SELECT max(id) FROM messages').fetchone()[0]
            rows += last if isinstance(last, int) and last > 0 else 0
        except sqlite3.Error as err:
            raise _not_sqlite_bag(path, str(err)) from None
        finally:
            con.close()
    size = sum(os.path.getsize(p) for p in paths)
    return found, max(0, min(count, rows, size // 16))


MCAP_MAGIC = b'\x89MCAP0\r\n'
OP_CHANNEL, OP_MESSAGE, OP_CHUNK = 0x04, 0x05, 0x06
MESSAGE_HEAD = 9 + 2 + 4 + 8 + 8      # opcode, length, channel, sequence, log and publish time


def _mcap_records(buf: memoryview, channel_of: Dict[int, str], topic: str
                  ) -> Iterator[Batch]:
    """Yield the messages of ``topic`` among a run of MCAP records (a file or a chunk).

    Where a stretch of records is all messages of one length (the usual chunk), they are
    read as one (k, record length) block; other stretches record by record.
    """
    arr = np.frombuffer(buf, dtype=np.uint8)
    o, end = 0, len(buf)
    single_t: List[int] = []
    single: List[bytes] = []
    while o + 9 <= end:
        op = buf[o]
        length = int.from_bytes(buf[o + 1:o + 9], 'little')
        if op == OP_MESSAGE:
            size = 9 + length
            k = (end - o) // size
            if k > 1:
                block = arr[o:o + k * size].reshape(k, size)
                lengths = view_bytes(block, 1, 8, '<u8')[:, 0]
                same = (block[:, 0] == OP_MESSAGE) & (lengths == length)
                k = int(np.argmin(same)) if not same.all() else k
            if k > 1:
                block = block[:k]
                chan = view_bytes(block, 9, 2, '<u2')[:, 0]
                ids = [c for c, t in channel_of.items() if t == topic]
                rows = np.isin(chan, ids)
                if rows.any():
                    if single:
                        yield np.array(single_t, dtype=np.int64), single
                        single_t, single = [], []
                    times = view_bytes(block, 15, 8, '<u8')[rows, 0].astype(np.int64)
                    yield times, block[rows, MESSAGE_HEAD:]
                o += k * size
                continue
            chan = int.from_bytes(buf[o + 9:o + 11], 'little')
            if channel_of.get(chan) == topic:
                single_t.append(int.from_bytes(buf[o + 15:o + 23], 'little'))
                single.append(bytes(buf[o + MESSAGE_HEAD:o + size]))
        elif op == OP_CHANNEL:
            b = o + 9
            chan = int.from_bytes(buf[b:b + 2], 'little')
            n = int.from_bytes(buf[b + 4:b + 8], 'little')
            channel_of[chan] = bytes(buf[b + 8:b + 8 + n]).decode('utf-8', 'replace')
        elif op == OP_CHUNK:
            b = o + 9 + 24
            n = int.from_bytes(buf[b + 4:b + 8], 'little')
            compression = bytes(buf[b + 8:b + 8 + n]).decode()
            b += 8 + n
            size = int.from_bytes(buf[b:b + 8], 'little')
            records = buf[b + 8:b + 8 + size]
            if compression:
                from rosbags.rosbag2.storage_mcap import decompress
                raw_size = int.from_bytes(buf[o + 9 + 16:o + 9 + 24], 'little')
                records = memoryview(decompress(bytes(records), compression, raw_size, 0))
            if single:
                yield np.array(single_t, dtype=np.int64), single
                single_t, single = [], []
            yield from _mcap_records(records, channel_of, topic)
        o += 9 + length
    if single:
        yield np.array(single_t, dtype=np.int64), single


def _mcap_buffers(paths: Sequence[str]) -> Iterator[memoryview]:
    """Yield each MCAP file's bytes, mapped read-only, checked to be MCAP; released after."""
    import mmap
    for path in paths:
        with open(path, 'rb') as f, mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as mm:
            buf = memoryview(mm)
            try:
                if bytes(buf[:8]) != MCAP_MAGIC:
                    raise BagError(f'{path}: not an MCAP file')
                yield buf
            finally:
                buf.release()


def _mcap_batches(paths: Sequence[str], topic: str) -> Iterator[Batch]:
    """Yield batches of one topic's messages from MCAP files (chunks parsed with numpy)."""
    for buf in _mcap_buffers(paths):
        # Stop at the data end record (opcode 0x0F): the summary repeats channels.
        yield from _mcap_records(buf[8:_data_end(buf)], {}, topic)


def _data_end(buf: memoryview) -> int:
    """Offset of the MCAP data end record, found by walking the top-level records."""
    o = 8
    while o + 9 <= len(buf) and buf[o] != 0x0F:
        o += 9 + int.from_bytes(buf[o + 1:o + 9], 'little')
    return o


def raw_batches(reader, topic: str, msgtype: str, fast: bool = True,
                start: Optional[int] = None, stop: Optional[int] = None) -> Iterator[Batch]:
    """Yield ``(bag times ns, messages)`` batches of a topic, in the order of the files.

    Uncompressed sqlite3 files are read with the standard library's sqlite3 and MCAP files
    with numpy (``fast``); anything else (compressed bags) through ``rosbags``. With
    ``start``/``stop`` (ns, bag time): the messages in ``[start, stop)`` only (sqlite3
    through its time index, MCAP by its chunks' time ranges, else ``rosbags``' filter).
    """
    conns = connections_of(reader, topic, msgtype)
    storage, paths = storage_files(reader) if fast else ('', [])
    ranged = start is not None or stop is not None
    if storage == 'sqlite3':
        yield from _sqlite_batches(paths, topic, start, stop)
        return
    if storage == 'mcap':
        yield from (_mcap_batches_between(paths, topic, start, stop) if ranged
                    else _mcap_batches(paths, topic))
        return
    yield from _rosbags_batches(reader, conns, start, stop)


def read_raw(reader, topic: str, msgtype: str) -> Tuple[List[bytes], np.ndarray]:
    """Return the serialised messages of a topic and their bag times (int ns), in bag order."""
    conns = connections_of(reader, topic, msgtype)
    raw, times = [], []
    for _, t, data in reader.messages(connections=conns):
        raw.append(data)
        times.append(t)
    return raw, np.array(times, dtype=np.int64)


def read_joint_states(path: str, topic: str, names: Sequence[str], fast: bool = True,
                      progress: Optional[Callable[[int, int], None]] = None) -> JointStates:
    """Read a JointState topic of a bag into arrays in the order of ``names``.

    ``fast=False`` reads through ``rosbags`` alone (its readers and deserialiser).
    ``progress(done, total)`` is called after each batch. An MCAP file from which fewer
    messages of the topic could be read than its own summary's statistics list is refused
    (:func:`check_complete`). metadata.yaml's counts are only a hint (another file, which may
    be stale or say anything); sqlite3 reads every row of the topic or fails.
    """
    if fast:
        # An uncompressed sqlite3 bag is read without opening it in rosbags, which counts
        # every topic's messages and their time range first (1.7 s for an hour at 1 kHz).
        staged, stage = _stage(path)
        try:
            files, total = _sqlite_bag(staged, topic)
            if files is not None:
                found, total = _sqlite_topics(files, total)
                check_topic(found, topic, JOINT_STATE)
                return decode_joint_states(_sqlite_batches(files, topic), names, fast,
                                           progress and (lambda k: progress(k, total)), total)
        finally:
            shutil.rmtree(stage, ignore_errors=True)
    reader = open_reader(path)
    try:
        total = topics(reader).get(topic, ('', 0))[1]      # metadata.yaml's, for a bag dir
        storage, paths = storage_files(reader)
        if paths:       # only a size hint: capped by the files' size (16 bytes a message)
            total = min(total, sum(os.path.getsize(p) for p in paths) // 16)
        js = decode_joint_states(raw_batches(reader, topic, JOINT_STATE, fast), names, fast,
                                 progress and (lambda k: progress(k, total)), total)
        if fast and storage == 'mcap':
            check_complete(js, mcap_listed(paths, topic), path, topic)
        return js
    finally:
        reader.close()


def check_complete(js: JointStates, listed: int, path: str, topic: str) -> None:
    """Refuse ``js`` unless every message the storage lists for ``topic`` was read.

    ``listed``: the topic's message count in the MCAP files' statistics (0: not known). A
    damaged MCAP (a chunk overwritten) ends the reading early without an error: fewer
    messages read (decoded or skipped) than listed is a :class:`BagError` saying how many,
    not a partial fit.
    """
    read = len(js.stamp) + sum(js.skipped.values())
    if read < listed:
        raise BagError(f'{path}: {read} of the {listed} messages of {topic} its MCAP '
                       'statistics list could be read: the file is damaged (mcap recover may '
                       'repair it)')


def read_stamped(path: str, topic: str, msgtype: str, start: Optional[int] = None,
                 stop: Optional[int] = None) -> Stamped:
    """Read an Odometry or Imu topic of a bag into arrays (:func:`.cdr.decode_fixed`).

    ``start``/``stop``: the messages whose bag time (ns) is in ``[start, stop)`` only
    (``None``: the bag's beginning, end).
    """
    reader = open_reader(path)
    try:
        return decode_fixed(raw_batches(reader, topic, msgtype, start=start, stop=stop),
                            msgtype)
    finally:
        reader.close()


def read_messages(path: str, topic: str, msgtype: str) -> list:
    """Deserialise every message of a topic (for the few, large ones: trajectories)."""
    reader = open_reader(path)
    try:
        raw, _ = read_raw(reader, topic, msgtype)
    finally:
        reader.close()
    store = typestore()
    return [store.deserialize_cdr(data, msgtype) for data in raw]


# --------------------------------------------------------------------------------------------
# A time range of a bag (a chunk of a long recording)

def _between(batches: Iterator[Batch], start: Optional[int], stop: Optional[int]
             ) -> Iterator[Batch]:
    """Keep the messages of ``batches`` whose bag time (ns) is in ``[start, stop)``."""
    for times, messages in batches:
        rows = np.ones(len(times), dtype=bool)
        if start is not None:
            rows &= times >= start
        if stop is not None:
            rows &= times < stop
        if rows.all():
            yield times, messages
        elif rows.any():
            yield times[rows], (messages[rows] if isinstance(messages, np.ndarray)
                                else [m for m, r in zip(messages, rows.tolist()) if r])


def _mcap_channels(buf: memoryview, data_end: int) -> Dict[int, str]:
    """Channel id -> topic from an MCAP file's summary section (empty if it has none)."""
    channels: Dict[int, str] = {}
    o = data_end + 9 + int.from_bytes(buf[data_end + 1:data_end + 9], 'little')
    while o + 9 <= len(buf) and buf[o] != 0x02:          # up to the footer
        length = int.from_bytes(buf[o + 1:o + 9], 'little')
        if buf[o] == OP_CHANNEL:
            b = o + 9
            n = int.from_bytes(buf[b + 4:b + 8], 'little')
            channels[int.from_bytes(buf[b:b + 2], 'little')] = bytes(
                buf[b + 8:b + 8 + n]).decode('utf-8', 'replace')
        o += 9 + length
    return channels


OP_STATISTICS = 0x0B


def mcap_listed(paths: Sequence[str], topic: str) -> int:
    """Return how many messages of ``topic`` the MCAP files' statistics records list (0: none).

    Each file's summary section, found from its footer (so a damaged data section does not
    hide it): the Statistics record's ``channel_message_counts`` of the channels of
    ``topic``, named by the summary's Channel records.
    """
    listed = 0
    for buf in _mcap_buffers(paths):
        foot = len(buf) - len(MCAP_MAGIC) - (9 + 20)        # the footer record, then magic
        if foot < 8 or buf[foot] != 0x02:
            continue
        o = int.from_bytes(buf[foot + 9:foot + 17], 'little')      # summary_start
        channels: Dict[int, str] = {}
        counts: Dict[int, int] = {}
        while 8 <= o and o + 9 <= foot:
            length = int.from_bytes(buf[o + 1:o + 9], 'little')
            end = min(o + 9 + length, foot)
            if buf[o] == OP_CHANNEL:
                n = int.from_bytes(buf[o + 13:o + 17], 'little')
                channels[int.from_bytes(buf[o + 9:o + 11], 'little')] = bytes(
                    buf[o + 17:o + 17 + n]).decode('utf-8', 'replace')
            elif buf[o] == OP_STATISTICS:
                b = o + 9 + 8 + 2 + 4 * 4 + 8 + 8            # to channel_message_counts
                size = int.from_bytes(buf[b:b + 4], 'little')
                for k in range(b + 4, min(b + 4 + size, end) - 9, 10):
                    counts[int.from_bytes(buf[k:k + 2], 'little')] = int.from_bytes(
                        buf[k + 2:k + 10], 'little')
            o += 9 + length
        listed += sum(n for chan, n in counts.items() if channels.get(chan) == topic)
    return listed


def _mcap_batches_between(paths: Sequence[str], topic: str, start: Optional[int],
                          stop: Optional[int]) -> Iterator[Batch]:
    """:func:`_mcap_batches` of the messages in ``[start, stop)``.

    A chunk whose message time range (in its header) misses ``[start, stop)`` is stepped
    over without being read or decompressed, when the summary names the channels (a
    skipped chunk may hold a channel record); the rest are read as the whole file is.
    """
    lo = -(1 << 63) if start is None else int(start)
    hi = (1 << 63) - 1 if stop is None else int(stop)
    for buf in _mcap_buffers(paths):
        end = _data_end(buf)
        channel_of = _mcap_channels(buf, end)
        skip = topic in channel_of.values()
        o = 8
        while o + 9 <= end:
            length = int.from_bytes(buf[o + 1:o + 9], 'little')
            if skip and buf[o] == OP_CHUNK:
                first = int.from_bytes(buf[o + 9:o + 17], 'little')
                last = int.from_bytes(buf[o + 17:o + 25], 'little')
                if last < lo or first >= hi:
                    o += 9 + length
                    continue
            yield from _between(_mcap_records(buf[o:o + 9 + length], channel_of, topic),
                                start, stop)
            o += 9 + length


def read_joint_states_between(path: str, topic: str, names: Sequence[str],
                              start: Optional[int] = None, stop: Optional[int] = None,
                              fast: bool = True) -> JointStates:
    """:func:`read_joint_states` of the messages whose bag time (ns) is in ``[start, stop)``.

    ``None`` is the bag's beginning (end). The bag time is the time a message was recorded
    (the storage's timestamp), not its ``header.stamp``: it is what the storages index.
    Uncompressed sqlite3 is read through its time index, uncompressed MCAP by its chunks'
    time ranges (``fast``); anything else through ``rosbags``' own time filter.
    """
    if fast:
        staged, stage = _stage(path)
        try:
            files, _ = _sqlite_bag(staged, topic)
            if files is not None:
                found, _ = _sqlite_topics(files, 0)
                check_topic(found, topic, JOINT_STATE)
                return decode_joint_states(_sqlite_batches(files, topic, start, stop),
                                           names, fast)
        finally:
            shutil.rmtree(stage, ignore_errors=True)
    reader = open_reader(path)
    try:
        return decode_joint_states(raw_batches(reader, topic, JOINT_STATE, fast, start, stop),
                                   names, fast)
    finally:
        reader.close()


def _rosbags_batches(reader, conns, start: Optional[int] = None, stop: Optional[int] = None
                     ) -> Iterator[Batch]:
    """Batches of ``rosbags``' own reading of ``conns`` (in ``[start, stop)`` when given)."""
    times: List[int] = []
    raw: List[bytes] = []
    for _, t, data in reader.messages(connections=conns, start=start, stop=stop):
        times.append(t)
        raw.append(data)
        if len(raw) == BATCH:
            yield np.array(times, dtype=np.int64), raw
            times, raw = [], []
    if raw:
        yield np.array(times, dtype=np.int64), raw


def time_range(path: str, topic: str) -> Tuple[int, int]:
    """Return the bag times (ns) of the first and last message of ``topic``.

    An uncompressed sqlite3 bag answers from its time index; any other bag from ``rosbags``'
    reader (the whole bag's range: every topic's). :class:`BagError` when the topic has no
    message.
    """
    staged, stage = _stage(path)
    try:
        files, _ = _sqlite_bag(staged, topic)
        if files is not None:
            import sqlite3
            found, _ = _sqlite_topics(files, 0)
            check_topic(found, topic, JOINT_STATE)
            ends = []
            for f in files:
                con = _sqlite_connect(f)
                try:
                    ends.append(con.execute(
                        'SELECT min(timestamp), max(timestamp) FROM messages WHERE topic_id '
                        'IN (SELECT id FROM topics WHERE name = ?)', (topic,)).fetchone())
                except sqlite3.Error as err:
                    raise _not_sqlite_bag(f, str(err)) from None
                finally:
                    con.close()
            ends = [e for e in ends if isinstance(e[0], int) and isinstance(e[1], int)]
            if not ends:
                raise BagError(f'{path}: topic {topic!r} has no message')
            return min(e[0] for e in ends), max(e[1] for e in ends)
    finally:
        shutil.rmtree(stage, ignore_errors=True)
    reader = open_reader(path)
    try:
        connections_of(reader, topic, JOINT_STATE)
        if not reader.message_count:
            raise BagError(f'{path}: topic {topic!r} has no message')
        return int(reader.start_time), int(reader.end_time)
    finally:
        reader.close()


# --------------------------------------------------------------------------------------------
# Writing (tests and the benchmark)

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
