# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Read rosbag2 recordings (sqlite3 and MCAP) without ROS: opening a bag, reading a topic.

A bag is opened through a private staging directory (:func:`_staged`). Uncompressed sqlite3
and MCAP files are read without ``rosbags``' per-message machinery (:mod:`.sqlite`,
:mod:`.mcap`) and their JointStates decoded in bulk by :mod:`.cdr`; anything else goes
through ``rosbags``' readers and deserialiser. ``rosbags`` and PyYAML (the ``replay`` extra)
are imported where a bag needs them: the commands start, and say what to install, without
them. Writing a bag (tests, benchmarks) is :mod:`.writing`'s, named here too.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from typing import Callable, Dict, Iterator, List, Optional, Sequence, Tuple
import weakref

import numpy as np

from ..files import load_yaml, read_regular, regular_file
from ..text import shown
from . import mcap, sqlite
from .cdr import (Batch, decode_fixed, decode_joint_states, encode_joint_states, FIELDS,
                  INSTALL_HINT, JOINT_STATE, joint_states_from_raw, JointStates, layout,
                  MissingDependency, Stamped, typestore, verify_layout)
from .errors import BagError
from .sqlite import BATCH
from .writing import serialize, Topic, write_bag

__all__ = ['BagError', 'check_bag', 'decode_joint_states', 'encode_joint_states', 'FIELDS',
           'JOINT_STATE', 'JOINT_TRAJECTORY', 'joint_states_from_raw', 'JointStates', 'layout',
           'MissingDependency', 'open_reader', 'read_joint_states', 'read_messages',
           'serialize', 'Topic', 'typestore', 'verify_layout', 'write_bag']

JOINT_TRAJECTORY = 'trajectory_msgs/msg/JointTrajectory'


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
    import yaml
    stage = tempfile.mkdtemp(prefix='spatial_dynamics_bag_')
    try:
        if not os.path.isdir(path):
            ext = os.path.splitext(path)[1]
            if ext not in ('.db3', '.mcap'):
                raise BagError(f'{path!r}: a bag is a rosbag2 directory or a .db3 / .mcap file')
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
        raise BagError(f'{path!r}: no such bag')
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
        text = shown(text, quote=False, limit=len(text))     # the path: escaped, whole
        raise BagError(f'{path!r}: cannot open as a rosbag2 bag: {text}') from None
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
        have = ', '.join(f'{shown(t)} ({shown(m, quote=False)})'
                         for t, (m, _) in sorted(found.items())) or 'none'
        raise BagError(f'topic {shown(topic)} is not in the bag; its topics: {have}')
    if found[topic][0] != msgtype:
        raise BagError(f'topic {shown(topic)} has type {shown(found[topic][0], quote=False)}, '
                       f'expected {msgtype}')


def connections_of(reader, topic: str, msgtype: str) -> list:
    """Return the reader's connections of ``topic``; :class:`BagError` naming what there is."""
    check_topic(topics(reader), topic, msgtype)
    return [c for c in reader.connections if c.topic == topic]


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
        yield from sqlite.batches(paths, topic, start, stop)
        return
    if storage == 'mcap':
        yield from (mcap.batches_between(paths, topic, start, stop) if ranged
                    else mcap.batches(paths, topic))
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
            files, total = sqlite.bag_files(staged, topic)
            if files is not None:
                found, total = sqlite.topics_of(files, total)
                check_topic(found, topic, JOINT_STATE)
                return decode_joint_states(sqlite.batches(files, topic), names, fast,
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
            check_complete(js, mcap.listed(paths, topic), path, topic)
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
        raise BagError(f'{path!r}: {read} of the {listed} messages of {shown(topic)} its MCAP '
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
            files, _ = sqlite.bag_files(staged, topic)
            if files is not None:
                found, _ = sqlite.topics_of(files, 0)
                check_topic(found, topic, JOINT_STATE)
                return decode_joint_states(sqlite.batches(files, topic, start, stop),
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
        files, _ = sqlite.bag_files(staged, topic)
        if files is not None:
            found, _ = sqlite.topics_of(files, 0)
            check_topic(found, topic, JOINT_STATE)
            return sqlite.time_range(files, path, topic)
    finally:
        shutil.rmtree(stage, ignore_errors=True)
    reader = open_reader(path)
    try:
        connections_of(reader, topic, JOINT_STATE)
        if not reader.message_count:
            raise BagError(f'{path!r}: topic {shown(topic)} has no message')
        return int(reader.start_time), int(reader.end_time)
    finally:
        reader.close()
