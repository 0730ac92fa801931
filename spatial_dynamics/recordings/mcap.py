# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Uncompressed MCAP files read with numpy (no ``rosbags``): one topic's messages in blocks.

Where a stretch of records is all messages of one length (the usual chunk), they are read as
one ``(k, record length)`` byte block; other stretches record by record. A chunk's time range
(in its header) lets a range of bag time step over the chunks outside it. ``rosbags`` is
imported only to decompress a compressed chunk (start-up time: the command starts without it).
"""

from __future__ import annotations

import mmap
from typing import Dict, Iterator, List, Optional, Sequence

import numpy as np

from .cdr import Batch, view_bytes
from .errors import BagError

MAGIC = b'\x89MCAP0\r\n'
OP_CHANNEL, OP_MESSAGE, OP_CHUNK = 0x04, 0x05, 0x06
MESSAGE_HEAD = 9 + 2 + 4 + 8 + 8      # opcode, length, channel, sequence, log and publish time


def record_batches(buf: memoryview, channel_of: Dict[int, str], topic: str) -> Iterator[Batch]:
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
            inner = buf[b + 8:b + 8 + size]
            if compression:
                from rosbags.rosbag2.storage_mcap import decompress     # compressed only
                raw_size = int.from_bytes(buf[o + 9 + 16:o + 9 + 24], 'little')
                inner = memoryview(decompress(bytes(inner), compression, raw_size, 0))
            if single:
                yield np.array(single_t, dtype=np.int64), single
                single_t, single = [], []
            yield from record_batches(inner, channel_of, topic)
        o += 9 + length
    if single:
        yield np.array(single_t, dtype=np.int64), single


def buffers(paths: Sequence[str]) -> Iterator[memoryview]:
    """Yield each MCAP file's bytes, mapped read-only, checked to be MCAP; released after."""
    for path in paths:
        with open(path, 'rb') as f, mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as mm:
            buf = memoryview(mm)
            try:
                if bytes(buf[:8]) != MAGIC:
                    raise BagError(f'{path!r}: not an MCAP file')
                yield buf
            finally:
                buf.release()


def batches(paths: Sequence[str], topic: str) -> Iterator[Batch]:
    """Yield batches of one topic's messages from MCAP files (chunks parsed with numpy)."""
    for buf in buffers(paths):
        # Stop at the data end record (opcode 0x0F): the summary repeats channels.
        yield from record_batches(buf[8:data_end(buf)], {}, topic)


def data_end(buf: memoryview) -> int:
    """Offset of the MCAP data end record, found by walking the top-level records."""
    o = 8
    while o + 9 <= len(buf) and buf[o] != 0x0F:
        o += 9 + int.from_bytes(buf[o + 1:o + 9], 'little')
    return o


def channels(buf: memoryview, end: int) -> Dict[int, str]:
    """Channel id -> topic from an MCAP file's summary section (empty if it has none)."""
    found: Dict[int, str] = {}
    o = end + 9 + int.from_bytes(buf[end + 1:end + 9], 'little')
    while o + 9 <= len(buf) and buf[o] != 0x02:          # up to the footer
        length = int.from_bytes(buf[o + 1:o + 9], 'little')
        if buf[o] == OP_CHANNEL:
            b = o + 9
            n = int.from_bytes(buf[b + 4:b + 8], 'little')
            found[int.from_bytes(buf[b:b + 2], 'little')] = bytes(
                buf[b + 8:b + 8 + n]).decode('utf-8', 'replace')
        o += 9 + length
    return found


OP_STATISTICS = 0x0B


def listed(paths: Sequence[str], topic: str) -> int:
    """Return how many messages of ``topic`` the MCAP files' statistics records list (0: none).

    Each file's summary section, found from its footer (so a damaged data section does not
    hide it): the Statistics record's ``channel_message_counts`` of the channels of
    ``topic``, named by the summary's Channel records.
    """
    total = 0
    for buf in buffers(paths):
        foot = len(buf) - len(MAGIC) - (9 + 20)        # the footer record, then magic
        if foot < 8 or buf[foot] != 0x02:
            continue
        o = int.from_bytes(buf[foot + 9:foot + 17], 'little')      # summary_start
        topic_of: Dict[int, str] = {}
        counts: Dict[int, int] = {}
        while 8 <= o and o + 9 <= foot:
            length = int.from_bytes(buf[o + 1:o + 9], 'little')
            end = min(o + 9 + length, foot)
            if buf[o] == OP_CHANNEL:
                n = int.from_bytes(buf[o + 13:o + 17], 'little')
                topic_of[int.from_bytes(buf[o + 9:o + 11], 'little')] = bytes(
                    buf[o + 17:o + 17 + n]).decode('utf-8', 'replace')
            elif buf[o] == OP_STATISTICS:
                b = o + 9 + 8 + 2 + 4 * 4 + 8 + 8            # to channel_message_counts
                size = int.from_bytes(buf[b:b + 4], 'little')
                for k in range(b + 4, min(b + 4 + size, end) - 9, 10):
                    counts[int.from_bytes(buf[k:k + 2], 'little')] = int.from_bytes(
                        buf[k + 2:k + 10], 'little')
            o += 9 + length
        total += sum(n for chan, n in counts.items() if topic_of.get(chan) == topic)
    return total


def batches_between(paths: Sequence[str], topic: str, start: Optional[int],
                    stop: Optional[int]) -> Iterator[Batch]:
    """:func:`batches` of the messages in ``[start, stop)``.

    A chunk whose message time range (in its header) misses ``[start, stop)`` is stepped
    over without being read or decompressed, when the summary names the channels (a
    skipped chunk may hold a channel record); the rest are read as the whole file is.
    """
    lo = -(1 << 63) if start is None else int(start)
    hi = (1 << 63) - 1 if stop is None else int(stop)
    for buf in buffers(paths):
        end = data_end(buf)
        channel_of = channels(buf, end)
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
            yield from between(record_batches(buf[o:o + 9 + length], channel_of, topic),
                               start, stop)
            o += 9 + length


def between(batches: Iterator[Batch], start: Optional[int], stop: Optional[int]
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
