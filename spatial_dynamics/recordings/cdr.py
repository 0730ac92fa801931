# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""sensor_msgs/JointState in CDR: decoded with numpy in bulk, encoded for tests and benchmarks.

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
from typing import Callable, Dict, Iterable, List, Optional, Sequence, Tuple, Union

import numpy as np

JOINT_STATE = 'sensor_msgs/msg/JointState'
FIELDS = ('position', 'velocity', 'effort')
INSTALL_HINT = ("the 'rosbags' package is needed to read bags: pip install rosbags "
                "(or pip install 'spatial_dynamics[replay]')")


class MissingDependency(RuntimeError):
    """``rosbags`` (or another optional package) is not installed."""


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
    ``skipped`` counts the messages dropped while reading, by reason. ``received`` (N,) s
    since the epoch: each message's bag time, when the recorder received it (wall time,
    whatever clock the stamps are on), or None when not known.
    """

    names: Tuple[str, ...]
    stamp: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    effort: np.ndarray
    skipped: Dict[str, int] = field(default_factory=dict)
    fast: int = 0           # messages read by the numpy path
    generic: int = 0        # messages read by rosbags' deserialiser
    received: Optional[np.ndarray] = None


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


#: Messages decoded at once from a list of byte strings.
BLOCK = 4096


def _runs(sizes: np.ndarray) -> List[Tuple[int, int]]:
    """Split message indices into runs ``[start, stop)`` of equal byte length."""
    edges = np.flatnonzero(np.diff(sizes)) + 1
    bounds = np.concatenate(([0], edges, [len(sizes)]))
    return [(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:])]


def decode_run(block: np.ndarray, lay: Layout, stamps_ns: np.ndarray
               ) -> Tuple[np.ndarray, List[np.ndarray]]:
    """Read stamps (s) and the three double arrays of a (k, L) byte block of one layout."""
    sec = view_bytes(block, 4, 4, '<i4')[:, 0]
    nsec = view_bytes(block, 8, 4, '<u4')[:, 0]
    stamp = sec.astype(np.float64) + nsec.astype(np.float64) * 1e-9
    zero = (sec == 0) & (nsec == 0)
    stamp[zero] = stamps_ns[zero] * 1e-9
    arrays = [view_bytes(block, off, 8 * count, '<f8') for off, count in lay.arrays]
    return stamp, arrays


def view_bytes(block: np.ndarray, offset: int, size: int, dtype: str) -> np.ndarray:
    """Bytes ``offset`` .. ``offset + size`` of each row of ``block`` read as ``dtype``.

    A view where numpy can make one (rows of any stride; unaligned values are read as
    such), else a copy: no pass over the bytes only to copy them.
    """
    part = block[:, offset:offset + size]
    try:
        return part.view(dtype)
    except ValueError:
        return part.copy().view(dtype)


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
    # the stamps, the fields, the bag times
    columns = ([np.full(size, np.nan)] + [np.full((size, width), np.nan) for _ in FIELDS]
               + [np.full(size, np.nan)])
    used = 0            # rows of ``columns`` filled
    counts = {'fast': 0, 'generic': 0}
    store = None
    done = 0

    def skip(reason: str, count: int = 1) -> None:
        skipped[reason] = skipped.get(reason, 0) + count

    def place(out, keep, rows, msg_names: Tuple[str, ...], arrays: List[np.ndarray]) -> None:
        """Put the arrays of messages ``rows`` (all with ``msg_names``) into the columns.

        ``rows``: a row index, an index array, or a slice (a whole block: then plain slices
        where the names are in the columns' order, one pass instead of a gather/scatter).
        """
        src = [j for j, name in enumerate(msg_names) if name in want]
        dst = [want[msg_names[j]] for j in src]
        block = isinstance(rows, slice)
        count = rows.stop - rows.start if block else int(np.size(rows))
        if block and dst and dst == list(range(dst[0], dst[-1] + 1)):
            dst = slice(dst[0], dst[-1] + 1)
        for k, a in enumerate(arrays):
            if a.shape[-1] == len(msg_names) and src:
                if block:
                    out[k][rows, dst] = a if len(src) == a.shape[-1] else a[..., src]
                else:
                    where = np.ix_(rows, dst) if np.ndim(rows) else (rows, dst)
                    out[k][where] = a[..., src]
            elif a.shape[-1] not in (0, len(msg_names)):
                keep[rows] = False
                skip(f'{FIELDS[k]} has {a.shape[-1]} values for {len(msg_names)} names',
                     count)

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
        whole = len(rows) == len(block)
        st, arrays = decode_run(block if whole else block[rows], lay, times[rows])
        where = slice(start, start + len(block)) if whole else start + rows
        stamp[where] = st
        place(out, keep, where, lay.names, arrays)
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
        out = [c[used:used + N] for c in columns[1:-1]]
        columns[-1][used:used + N] = np.asarray(times, dtype=np.int64) * 1e-9
        keep = np.ones(N, dtype=bool)
        if isinstance(messages, np.ndarray):
            block_run(messages, times, 0, stamp, out, keep)
        else:
            sizes = np.fromiter(map(len, messages), dtype=np.int64, count=N)
            for run_start, run_stop in _runs(sizes):
                # in blocks that stay in the cache: 3 times faster than one of 65536 rows
                for start in range(run_start, run_stop, BLOCK):
                    stop = min(run_stop, start + BLOCK)
                    block = np.frombuffer(b''.join(messages[start:stop]), dtype=np.uint8)
                    block_run(block.reshape(stop - start, -1), times[start:stop], start,
                              stamp, out, keep)
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
    return JointStates(names, *(c[:used] for c in columns[:-1]), skipped=skipped,
                       received=columns[-1][:used], **counts)


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
# Encoding (tests and the benchmark)

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


# --------------------------------------------------------------------------------------------
# Messages of fixed size after their strings: nav_msgs/Odometry and sensor_msgs/Imu

ODOMETRY = 'nav_msgs/msg/Odometry'
IMU = 'sensor_msgs/msg/Imu'


def _odometry_doubles(msg) -> List[float]:
    """Return the 85 doubles of a deserialised Odometry, in CDR order."""
    p, t = msg.pose.pose, msg.twist.twist
    return [p.position.x, p.position.y, p.position.z, p.orientation.x, p.orientation.y,
            p.orientation.z, p.orientation.w, *msg.pose.covariance, t.linear.x, t.linear.y,
            t.linear.z, t.angular.x, t.angular.y, t.angular.z, *msg.twist.covariance]


def _imu_doubles(msg) -> List[float]:
    """Return the 37 doubles of a deserialised Imu, in CDR order."""
    o, w, f = msg.orientation, msg.angular_velocity, msg.linear_acceleration
    return [o.x, o.y, o.z, o.w, *msg.orientation_covariance, w.x, w.y, w.z,
            *msg.angular_velocity_covariance, f.x, f.y, f.z, *msg.linear_acceleration_covariance]


#: Per type: the strings after the stamp (header.frame_id, ...), the doubles that follow
#: them, the doubles of a deserialised message, and where each field is among the doubles.
FIXED_MESSAGES = {
    ODOMETRY: (('frame_id', 'child_frame_id'), 85, _odometry_doubles,
               {'position': slice(0, 3), 'orientation': slice(3, 7),
                'linear': slice(43, 46), 'angular': slice(46, 49)}),
    IMU: (('frame_id',), 37, _imu_doubles,
          {'orientation': slice(0, 4), 'angular_velocity': slice(13, 16),
           'linear_acceleration': slice(25, 28)}),
}


@dataclass
class Stamped:
    """Messages of one fixed-size type (:data:`FIXED_MESSAGES`) as arrays, sorted by stamp.

    ``stamp`` (N,) s: ``header.stamp``, or the bag's receive time when the stamp is zero;
    ``values`` (N, k): the message's doubles in CDR order (:meth:`field` picks one);
    ``frames``: the strings of the first message (``frame_id``, ``child_frame_id``).
    """

    msgtype: str
    stamp: np.ndarray
    values: np.ndarray
    frames: Tuple[str, ...]
    skipped: Dict[str, int] = field(default_factory=dict)
    fast: int = 0
    generic: int = 0

    def field(self, name: str) -> np.ndarray:
        """Return one of the fields, ``'orientation'``, ``'angular'``, ...: (N, 3) or (N, 4)."""
        return self.values[:, FIXED_MESSAGES[self.msgtype][3][name]]


def fixed_layout(data: bytes, msgtype: str) -> Optional[Tuple[int, Tuple[str, ...], np.ndarray]]:
    """Return ``(offset of the doubles, strings, offsets of the shared bytes)`` or None.

    For a little-endian CDR message of ``msgtype`` (:data:`FIXED_MESSAGES`): the stamp, the
    strings, then the doubles aligned to 8 that end the message. None if it is not one.
    """
    strings, count = FIXED_MESSAGES[msgtype][:2]
    if len(data) < 16 or data[:2] != b'\x00\x01':
        return None
    fixed = list(range(4))
    o = 12
    found = []
    try:
        for _ in strings:
            o += -(o - 4) % 4
            n = int.from_bytes(data[o:o + 4], 'little')
            if n < 1 or o + 4 + n > len(data):
                return None
            fixed.extend(range(o, o + 4 + n))
            found.append(data[o + 4:o + 3 + n].decode('utf-8'))
            o += 4 + n
    except UnicodeDecodeError:
        return None
    o += -(o - 4) % 8
    if o + 8 * count != len(data):
        return None
    return o, tuple(found), np.array(fixed, dtype=np.intp)


def decode_fixed(batches: Iterable[Batch], msgtype: str) -> Stamped:
    """Decode batches ``(bag times ns, messages)`` of Odometry or Imu into :class:`Stamped`.

    As :func:`decode_joint_states`: runs of messages of one byte length whose strings equal
    the first one's are read as numpy views; any other message goes through ``rosbags``'
    deserialiser, and one that cannot be deserialised is skipped and counted.
    """
    count, doubles_of = FIXED_MESSAGES[msgtype][1:3]
    stamps: List[np.ndarray] = []
    values: List[np.ndarray] = []
    frames: Optional[Tuple[str, ...]] = None
    skipped: Dict[str, int] = {}
    counts = {'fast': 0, 'generic': 0}
    store = None

    def generic(data: bytes, t_ns: int) -> None:
        nonlocal store, frames
        if store is None:
            store = typestore()
        try:
            msg = store.deserialize_cdr(data, msgtype)
        except Exception as err:   # rosbags raises several types for bad bytes
            reason = f'cannot be deserialised ({type(err).__name__})'
            skipped[reason] = skipped.get(reason, 0) + 1
            return
        sec, nsec = msg.header.stamp.sec, msg.header.stamp.nanosec
        stamps.append(np.array([sec + nsec * 1e-9 if (sec or nsec) else t_ns * 1e-9]))
        values.append(np.array([doubles_of(msg)], dtype=np.float64))
        if frames is None:
            frames = (msg.header.frame_id,) + ((msg.child_frame_id,)
                                               if msgtype == ODOMETRY else ())
        counts['generic'] += 1

    def block_run(block: np.ndarray, times: np.ndarray) -> None:
        nonlocal frames
        lay = fixed_layout(block[0].tobytes(), msgtype)
        if lay is None:
            for r in range(len(block)):
                generic(block[r].tobytes(), int(times[r]))
            return
        offset, strings, fixed = lay
        frames = strings if frames is None else frames
        shared = block[:, fixed]
        same = np.all(shared == shared[0], axis=1)
        rows = np.flatnonzero(same)
        part = block[rows]
        sec = view_bytes(part, 4, 4, '<i4')[:, 0]
        nsec = view_bytes(part, 8, 4, '<u4')[:, 0]
        stamp = sec.astype(np.float64) + nsec.astype(np.float64) * 1e-9
        zero = (sec == 0) & (nsec == 0)
        stamp[zero] = times[rows][zero] * 1e-9
        stamps.append(stamp)
        values.append(np.array(view_bytes(part, offset, 8 * count, '<f8'), dtype=np.float64))
        counts['fast'] += len(rows)
        for r in np.flatnonzero(~same):
            generic(block[r].tobytes(), int(times[r]))

    for times, messages in batches:
        if isinstance(messages, np.ndarray):
            block_run(messages, times)
            continue
        sizes = np.fromiter(map(len, messages), dtype=np.int64, count=len(times))
        for start, stop in _runs(sizes):
            block = np.frombuffer(b''.join(messages[start:stop]), dtype=np.uint8)
            block_run(block.reshape(stop - start, -1), times[start:stop])
    stamp = np.concatenate(stamps) if stamps else np.zeros(0)
    order = np.argsort(stamp, kind='stable')
    return Stamped(msgtype, stamp[order],
                   np.concatenate(values)[order] if values else np.zeros((0, count)),
                   frames or (), skipped, **counts)


def verify_fixed(data: bytes, msgtype: str) -> bool:
    """Check the fast path's reading of one Odometry or Imu against ``rosbags``'."""
    lay = fixed_layout(data, msgtype)
    if lay is None:
        return False
    fast = decode_fixed([(np.zeros(1, dtype=np.int64),
                          np.frombuffer(data, dtype=np.uint8)[None, :])], msgtype)
    msg = typestore().deserialize_cdr(data, msgtype)
    frames = (msg.header.frame_id,) + ((msg.child_frame_id,) if msgtype == ODOMETRY else ())
    stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
    return (fast.fast == 1 and fast.frames == frames and fast.stamp[0] == stamp
            and np.array_equal(fast.values[0], FIXED_MESSAGES[msgtype][2](msg)))
