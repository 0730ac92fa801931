# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Read and write rosbag2 recordings (sqlite3 and MCAP) without ROS, through ``rosbags``.

``sensor_msgs/JointState`` is the bulk of a recording (1 kHz for an hour: 3.6 M messages), so
it has a fast path: consecutive messages of one CDR layout (same byte length, frame_id, joint
names and array lengths) are stacked into one ``(k, L)`` byte matrix and their stamps and
doubles read as numpy views at the offsets found in the first message of the run. The
layout of every run is checked on that first message against ``rosbags``' own
deserialiser, and every message that does not match the run's layout byte for byte (outside
the stamp, the doubles and the alignment padding) goes through the deserialiser instead.

CDR (little endian, ``00 01`` encapsulation) of a JointState, offsets after the 4-byte
encapsulation header, each field aligned to its size::

    int32 sec, uint32 nanosec, string frame_id (uint32 length incl. NUL, bytes),
    uint32 count, count x string name,
    3 x (uint32 count, [pad to 8 if count], count x float64)   position, velocity, effort
"""

from __future__ import annotations

from dataclasses import dataclass, field
import os
import shutil
from typing import Callable, Dict, Iterable, Iterator, List, Optional, Sequence, Tuple, Union
from urllib.parse import quote
import weakref

import numpy as np

from ..files import load_yaml, read_regular, regular_file

JOINT_STATE = 'sensor_msgs/msg/JointState'
JOINT_TRAJECTORY = 'trajectory_msgs/msg/JointTrajectory'
FIELDS = ('position', 'velocity', 'effort')
INSTALL_HINT = ("the 'rosbags' package is needed to read bags: pip install rosbags "
                "(or pip install 'spatial_dynamics[replay]')")


class MissingDependency(RuntimeError):
    """``rosbags`` (or another optional package) is not installed."""


class BagError(ValueError):
    """The bag cannot be read as asked: no such bag, topic or type; the message says which."""


def typestore():
    """Return ``rosbags``' ROS 2 Jazzy type store; :class:`MissingDependency` without it."""
    try:
        from rosbags.typesys import get_typestore, Stores
    except ImportError:
        raise MissingDependency(INSTALL_HINT) from None
    return get_typestore(Stores.ROS2_JAZZY)


@dataclass
class JointStates:
    """Joint states of one topic in the order of ``names``; ``nan`` where a message lacks one.

    ``stamp`` (N,) s: ``header.stamp``, or the bag's receive time when the stamp is zero;
    ``position``, ``velocity``, ``effort``: (N, n). Messages are in bag order (not sorted).
    ``skipped`` counts the messages dropped while reading, by reason.
    """

    names: Tuple[str, ...]
    stamp: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    effort: np.ndarray
    skipped: Dict[str, int] = field(default_factory=dict)
    fast: int = 0           # messages read by the numpy path
    generic: int = 0        # messages read by rosbags' deserialiser


# --------------------------------------------------------------------------------------------
# The CDR layout of one JointState message

@dataclass(frozen=True)
class Layout:
    """Where a JointState's fields are in its CDR bytes (offsets from the message start)."""

    size: int
    names: Tuple[str, ...]
    arrays: Tuple[Tuple[int, int], ...]   # (offset, count) of position, velocity, effort
    fixed: np.ndarray                     # offsets of the bytes every message of it shares


def layout(data: bytes) -> Optional[Layout]:
    """Return the :class:`Layout` of a little-endian CDR JointState, or None if it is not one."""
    if len(data) < 16 or data[:2] != b'\x00\x01':
        return None
    fixed = [0, 1]
    o = 12                                  # after encapsulation, sec, nanosec

    def u32() -> int:
        nonlocal o
        o += -(o - 4) % 4
        if o + 4 > len(data):
            raise IndexError
        fixed.extend(range(o, o + 4))
        o += 4
        return int.from_bytes(data[o - 4:o], 'little')

    def string() -> str:
        nonlocal o
        n = u32()
        if n < 1 or o + n > len(data):
            raise IndexError
        fixed.extend(range(o, o + n))
        o += n
        return data[o - n:o - 1].decode('utf-8')

    try:
        string()                                        # frame_id
        names = tuple(string() for _ in range(u32()))
        arrays = []
        for _ in FIELDS:
            count = u32()
            if count:
                o += -(o - 4) % 8
            arrays.append((o, count))
            o += 8 * count
    except (IndexError, UnicodeDecodeError):
        return None
    if o != len(data):
        return None
    return Layout(len(data), names, tuple(arrays), np.array(fixed, dtype=np.intp))


def _runs(sizes: np.ndarray) -> List[Tuple[int, int]]:
    """Split message indices into runs ``[start, stop)`` of equal byte length."""
    edges = np.flatnonzero(np.diff(sizes)) + 1
    bounds = np.concatenate(([0], edges, [len(sizes)]))
    return [(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:])]


def decode_run(block: np.ndarray, lay: Layout, stamps_ns: np.ndarray
               ) -> Tuple[np.ndarray, List[np.ndarray]]:
    """Read stamps (s) and the three double arrays of a (k, L) byte block of one layout."""
    sec = block[:, 4:8].copy().view('<i4')[:, 0]
    nsec = block[:, 8:12].copy().view('<u4')[:, 0]
    stamp = sec.astype(np.float64) + nsec.astype(np.float64) * 1e-9
    zero = (sec == 0) & (nsec == 0)
    stamp[zero] = stamps_ns[zero] * 1e-9
    arrays = [block[:, off:off + 8 * count].copy().view('<f8') for off, count in lay.arrays]
    return stamp, arrays


def _decode_generic(msg, stamp_ns: int) -> Tuple[float, Tuple[str, ...], List[np.ndarray]]:
    """Stamp (s), names and arrays of a JointState deserialised by ``rosbags``."""
    sec, nsec = msg.header.stamp.sec, msg.header.stamp.nanosec
    stamp = sec + nsec * 1e-9 if (sec or nsec) else stamp_ns * 1e-9
    return stamp, tuple(msg.name), [np.asarray(getattr(msg, f), dtype=np.float64)
                                    for f in FIELDS]


Batch = Tuple[np.ndarray, Union[np.ndarray, Sequence[bytes]]]


def joint_states_from_raw(raw: Sequence[bytes], stamps_ns: np.ndarray, names: Sequence[str],
                          fast: bool = True) -> JointStates:
    """Decode serialised JointState messages into arrays by joint name (see the module doc).

    ``raw``: CDR bytes of each message; ``stamps_ns`` (N,) their bag times (int ns);
    ``names``: the joints wanted, the column order. ``fast=False`` sends every message
    through ``rosbags``' deserialiser (the reference of the fast path).
    """
    return decode_joint_states([(np.asarray(stamps_ns, dtype=np.int64), raw)], names, fast)


def decode_joint_states(batches: Iterable[Batch], names: Sequence[str], fast: bool = True,
                        progress: Optional[Callable[[int], None]] = None,
                        expected: int = 0) -> JointStates:
    """Decode batches ``(bag times ns, messages)`` of JointStates into arrays by joint name.

    ``messages`` is a list of CDR byte strings or a (k, L) uint8 block of k messages of L
    bytes each. A message that cannot be decoded, or whose position/velocity/effort length
    is neither 0 nor its number of names, is skipped and counted in ``skipped``; a joint a
    message does not carry is ``nan`` in its row. ``expected``: the number of messages if
    known (the arrays are then allocated once, not joined from the batches).
    """
    names = tuple(names)
    want = {name: k for k, name in enumerate(names)}
    skipped: Dict[str, int] = {}
    width = len(names)
    size = max(int(expected), 1)
    columns = [np.full(size, np.nan)] + [np.full((size, width), np.nan) for _ in FIELDS]
    used = 0            # rows of ``columns`` filled
    counts = {'fast': 0, 'generic': 0}
    store = None
    done = 0

    def skip(reason: str, count: int = 1) -> None:
        skipped[reason] = skipped.get(reason, 0) + count

    def place(out, keep, rows, msg_names: Tuple[str, ...], arrays: List[np.ndarray]) -> None:
        """Put the arrays of messages ``rows`` (all with ``msg_names``) into the columns."""
        src = [j for j, name in enumerate(msg_names) if name in want]
        dst = [want[msg_names[j]] for j in src]
        for k, a in enumerate(arrays):
            if a.shape[-1] == len(msg_names) and src:
                where = np.ix_(rows, dst) if np.ndim(rows) else (rows, dst)
                out[k][where] = a[..., src]
            elif a.shape[-1] not in (0, len(msg_names)):
                keep[rows] = False
                skip(f'{FIELDS[k]} has {a.shape[-1]} values for {len(msg_names)} names',
                     int(np.size(rows)))

    def generic(data: bytes, t_ns: int, i: int, stamp, out, keep) -> None:
        nonlocal store
        if store is None:
            store = typestore()
        try:
            msg = store.deserialize_cdr(data, JOINT_STATE)
        except Exception as err:   # rosbags raises several types for bad bytes
            keep[i] = False
            skip(f'cannot be deserialised ({type(err).__name__})')
            return
        stamp[i], msg_names, arrays = _decode_generic(msg, t_ns)
        place(out, keep, i, msg_names, arrays)
        counts['generic'] += 1

    def block_run(block: np.ndarray, times: np.ndarray, start: int, stamp, out, keep) -> None:
        """Decode rows of a block of one byte length: the fast path where the layout holds."""
        lay = layout(block[0].tobytes()) if fast else None
        if lay is not None and len(set(lay.names)) != len(lay.names):
            lay = None      # duplicate names: the generic path decides which value wins
        if lay is None:
            for r in range(len(block)):
                generic(block[r].tobytes(), int(times[r]), start + r, stamp, out, keep)
            return
        fixed = block[:, lay.fixed]
        same = np.all(fixed == fixed[0], axis=1)
        rows = np.flatnonzero(same)
        st, arrays = decode_run(block[rows] if len(rows) < len(block) else block, lay,
                                times[rows])
        stamp[start + rows] = st
        place(out, keep, start + rows, lay.names, arrays)
        counts['fast'] += len(rows)
        for r in np.flatnonzero(~same):
            generic(block[r].tobytes(), int(times[r]), start + int(r), stamp, out, keep)

    for times, messages in batches:
        N = len(times)
        if used + N > len(columns[0]):      # more than expected: grow by half at least
            grow = max(used + N, len(columns[0]) * 3 // 2)
            columns = [np.concatenate((c[:used], np.full((grow - used,) + c.shape[1:],
                                                         np.nan))) for c in columns]
        stamp = columns[0][used:used + N]
        out = [c[used:used + N] for c in columns[1:]]
        keep = np.ones(N, dtype=bool)
        if isinstance(messages, np.ndarray):
            block_run(messages, times, 0, stamp, out, keep)
        else:
            sizes = np.fromiter((len(b) for b in messages), dtype=np.int64, count=N)
            for start, stop in _runs(sizes):
                block = np.frombuffer(b''.join(messages[start:stop]), dtype=np.uint8)
                block_run(block.reshape(stop - start, -1), times[start:stop], start, stamp,
                          out, keep)
        kept = N
        if not keep.all():
            kept = int(keep.sum())
            for c in columns:
                c[used:used + kept] = c[used:used + N][keep]
                c[used + kept:used + N] = np.nan
        used += kept
        done += N
        if progress is not None:
            progress(done)
    return JointStates(names, *(c[:used] for c in columns), skipped=skipped, **counts)


def verify_layout(data: bytes) -> bool:
    """Check the fast path's reading of one message against ``rosbags``' deserialiser."""
    lay = layout(data)
    if lay is None:
        return False
    msg = typestore().deserialize_cdr(data, JOINT_STATE)
    block = np.frombuffer(data, dtype=np.uint8)[None, :]
    stamp, arrays = decode_run(block, lay, np.zeros(1))
    ref_stamp, names, ref = _decode_generic(msg, 0)
    return (names == lay.names and stamp[0] == ref_stamp
            and all(np.array_equal(a[0], r, equal_nan=True) for a, r in zip(arrays, ref)))


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


def open_reader(path: str):
    """Return an open ``rosbags`` reader of a bag directory (or a single .db3/.mcap file).

    The bag is opened through :func:`_staged` (plain names, regular files only, metadata
    safe-loaded); the staging directory goes with the reader.
    """
    try:
        from rosbags.rosbag2 import Reader
    except ImportError:
        raise MissingDependency(INSTALL_HINT) from None
    if not os.path.exists(path):
        raise BagError(f'{path}: no such bag')
    try:
        staged, stage = _staged(path)
    except ValueError as err:      # BagError, and the safe reader's refusals name the file
        raise BagError(str(err)) from None
    try:
        reader = Reader(staged)
        reader.open()
    except Exception as err:     # rosbags' ReaderError and the storage plugins' errors
        shutil.rmtree(stage, ignore_errors=True)
        text = str(err).replace(stage, path)
        raise BagError(f'{path}: cannot open as a rosbag2 bag: {text}') from None
    weakref.finalize(reader, shutil.rmtree, stage, True)
    return reader


def topics(reader) -> Dict[str, Tuple[str, int]]:
    """Map each topic of an open reader to ``(message type, message count)``."""
    out: Dict[str, Tuple[str, int]] = {}
    for c in reader.connections:
        typ, count = out.get(c.topic, (c.msgtype, 0))
        out[c.topic] = (typ, count + c.msgcount)
    return out


def connections_of(reader, topic: str, msgtype: str) -> list:
    """Return the reader's connections of ``topic``; :class:`BagError` naming what there is."""
    found = topics(reader)
    if topic not in found:
        have = ', '.join(f'{t} ({m})' for t, (m, _) in sorted(found.items())) or 'none'
        raise BagError(f'topic {topic!r} is not in the bag; its topics: {have}')
    if found[topic][0] != msgtype:
        raise BagError(f'topic {topic!r} has type {found[topic][0]}, expected {msgtype}')
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


def _sqlite_batches(paths: Sequence[str], topic: str) -> Iterator[Batch]:
    """Yield batches of one topic's messages from rosbag2 sqlite3 files (standard library)."""
    import sqlite3
    for path in paths:
        # quoted: in a file: URI, %, # and ? of a path would mean something else
        con = sqlite3.connect(f'file:{quote(os.path.abspath(path))}?mode=ro', uri=True)
        try:
            cur = con.execute('SELECT messages.timestamp, messages.data FROM messages JOIN '
                              'topics ON messages.topic_id = topics.id WHERE topics.name = ? '
                              'ORDER BY messages.id', (topic,))
            while True:
                rows = cur.fetchmany(BATCH)
                if not rows:
                    break
                times, data = zip(*rows)
                if set(map(type, data)) != {bytes} or set(map(type, times)) != {int}:
                    raise BagError(f'{os.path.realpath(path)}: not a rosbag2 sqlite3 database '
                                   '(a message whose timestamp is not an integer or data not '
                                   'bytes)')
                yield np.array(times, dtype=np.int64), data
        except sqlite3.Error as err:
            raise BagError(f'{os.path.realpath(path)}: not a rosbag2 sqlite3 database '
                           f'({err})') from None
        finally:
            con.close()


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
                lengths = block[:, 1:9].copy().view('<u8')[:, 0]
                same = (block[:, 0] == OP_MESSAGE) & (lengths == length)
                k = int(np.argmin(same)) if not same.all() else k
            if k > 1:
                block = block[:k]
                chan = block[:, 9:11].copy().view('<u2')[:, 0]
                ids = [c for c, t in channel_of.items() if t == topic]
                rows = np.isin(chan, ids)
                if rows.any():
                    if single:
                        yield np.array(single_t, dtype=np.int64), single
                        single_t, single = [], []
                    times = block[rows, 15:23].copy().view('<u8')[:, 0].astype(np.int64)
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


def _mcap_batches(paths: Sequence[str], topic: str) -> Iterator[Batch]:
    """Yield batches of one topic's messages from MCAP files (chunks parsed with numpy)."""
    import mmap
    for path in paths:
        with open(path, 'rb') as f, mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as mm:
            buf = memoryview(mm)
            try:
                if bytes(buf[:8]) != MCAP_MAGIC:
                    raise BagError(f'{path}: not an MCAP file')
                # Stop at the data end record (opcode 0x0F): the summary repeats channels.
                yield from _mcap_records(buf[8:_data_end(buf)], {}, topic)
            finally:
                buf.release()


def _data_end(buf: memoryview) -> int:
    """Offset of the MCAP data end record, found by walking the top-level records."""
    o = 8
    while o + 9 <= len(buf) and buf[o] != 0x0F:
        o += 9 + int.from_bytes(buf[o + 1:o + 9], 'little')
    return o


def raw_batches(reader, topic: str, msgtype: str, fast: bool = True) -> Iterator[Batch]:
    """Yield ``(bag times ns, messages)`` batches of a topic, in the order of the files.

    Uncompressed sqlite3 files are read with the standard library's sqlite3 and MCAP files
    with numpy (``fast``); anything else (compressed bags) through ``rosbags``.
    """
    conns = connections_of(reader, topic, msgtype)
    storage, paths = storage_files(reader) if fast else ('', [])
    if storage == 'sqlite3':
        yield from _sqlite_batches(paths, topic)
        return
    if storage == 'mcap':
        yield from _mcap_batches(paths, topic)
        return
    times: List[int] = []
    raw: List[bytes] = []
    for _, t, data in reader.messages(connections=conns):
        times.append(t)
        raw.append(data)
        if len(raw) == BATCH:
            yield np.array(times, dtype=np.int64), raw
            times, raw = [], []
    if raw:
        yield np.array(times, dtype=np.int64), raw


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
    ``progress(done, total)`` is called after each batch.
    """
    reader = open_reader(path)
    try:
        total = topics(reader).get(topic, ('', 0))[1]
        return decode_joint_states(raw_batches(reader, topic, JOINT_STATE, fast), names, fast,
                                   progress and (lambda k: progress(k, total)), total)
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
# Writing (tests and the benchmark)

def encode_joint_states(names: Sequence[str], stamp_ns: np.ndarray, position=None,
                        velocity=None, effort=None, frame_id: str = '') -> np.ndarray:
    """Serialise N JointStates of one layout into a (N, L) byte matrix (CDR, little endian).

    Arrays are (N, n) in the order of ``names``, or None for an empty field; ``stamp_ns``
    (N,) int ns goes into ``header.stamp``. The template is serialised by ``rosbags``.
    """
    store = typestore()
    JS = store.types[JOINT_STATE]
    Header, Time = store.types['std_msgs/msg/Header'], store.types['builtin_interfaces/msg/Time']
    arrays = [None if a is None else np.asarray(a, dtype=np.float64)
              for a in (position, velocity, effort)]
    n = len(names)
    template = JS(header=Header(stamp=Time(sec=0, nanosec=0), frame_id=frame_id),
                  name=list(names), **{f: np.zeros(0 if a is None else n)
                                       for f, a in zip(FIELDS, arrays)})
    data = bytes(store.serialize_cdr(template, JOINT_STATE))
    lay = layout(data)
    stamp_ns = np.asarray(stamp_ns, dtype=np.int64)
    block = np.tile(np.frombuffer(data, dtype=np.uint8), (len(stamp_ns), 1))
    block[:, 4:8] = (stamp_ns // 1_000_000_000).astype('<i4')[:, None].view(np.uint8)
    block[:, 8:12] = (stamp_ns % 1_000_000_000).astype('<u4')[:, None].view(np.uint8)
    for (off, count), a in zip(lay.arrays, arrays):
        if a is not None:
            block[:, off:off + 8 * count] = np.ascontiguousarray(a, dtype='<f8').view(np.uint8)
    return block


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
