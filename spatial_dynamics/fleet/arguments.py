# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The fleet command's options: their declarations and their types, each refused by name.

``--out``/``--cache`` a folder that can be written, ``--urdf`` a regular file of a URDF's
size, ``--chunk`` and ``--baseline-days`` in range, ``--workers`` a count of processes,
``--scheduler`` a ``tcp://host:port`` whose host resolves (refused here, not after Dask's
30 s of connection attempts). Declared by :func:`add_arguments` on the command's own parser
or on ``replay fleet``'s.
"""

from __future__ import annotations

import argparse
import ipaddress
import os
import re
import socket
import threading
from typing import List, Optional

from ..files import regular_file
from ..text import shown
from ..urdf import MAX_FILE_BYTES
from . import drift as drift_of
from .chunks import CHUNK, MIN_CHUNK
from .engine import SERIAL_BYTES, WORKERS_PER_CORE

#: The longest --chunk, s (a year of bag time; 0 already means never cut).
MAX_CHUNK = 366 * 86400.0


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Declare the command's options on ``p`` (its own parser, or a ``replay`` subparser)."""
    p.add_argument('source', help='manifest (.csv, .yaml) or a folder ROBOT/.../BAG')
    p.add_argument('--urdf', type=urdf_file,
                   help='the URDF of every robot of a folder (default: each robot '
                   "folder's robot.urdf)")
    p.add_argument('--out', default='fleet_out', type=output_folder,
                   help='output directory, created (default %(default)s)')
    p.add_argument('--cache', type=output_folder,
                   help='results by content hash (default: OUT/cache)')
    where = p.add_mutually_exclusive_group()
    where.add_argument('--workers', type=workers_count, metavar='N',
                       help='local cluster of N worker processes (default: the cores, when '
                       f'the work is large enough; at most {WORKERS_PER_CORE} a core; none when '
                       'every bag is in the cache; see --serial)')
    where.add_argument('--serial', action='store_true',
                       help='no cluster: every bag in this process, one after the other '
                       '(the default when the bags to process are less than '
                       f'{SERIAL_BYTES >> 20} MB)')
    where.add_argument('--scheduler', metavar='ADDRESS', type=scheduler_address,
                       help='an existing Dask scheduler, tcp://host:port (tls:// is not '
                       'supported; not contacted when every bag is in the cache)')
    p.add_argument('--chunk', type=chunk_seconds, default=CHUNK, metavar='SECONDS',
                   help='cut a bag longer than this into tasks of this much bag time, their '
                   'sums added (default %(default)g; 0: one task per bag)')
    p.add_argument('--baseline-days', type=baseline_days, default=5.0,
                   help="each robot-joint's baseline: its first days, at least "
                   f'{drift_of.MIN_BASELINE} bags (default %(default)g)')
    p.add_argument('--no-plots', action='store_true', help='write no PNG files')


def _number(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        return float('nan')


def output_folder(text: str) -> str:
    """``--out``, ``--cache``: a folder, or a path where one can be created and written."""
    if not text:
        raise argparse.ArgumentTypeError('an empty value (a folder to write into)')
    path = os.path.abspath(text)
    there = path
    while not os.path.lexists(there):
        there = os.path.dirname(there)
    if not os.path.isdir(there):
        raise argparse.ArgumentTypeError(
            f'{text!r} is not a folder' if there == path else
            f'{text!r}: {there!r} is not a folder')
    if not os.access(there, os.W_OK | os.X_OK):
        raise argparse.ArgumentTypeError(f'{text!r}: cannot write in {there!r}')
    return text


def urdf_file(text: str) -> str:
    """``--urdf``: a regular file (never a FIFO or a device: hashing it would never end)."""
    if not text:
        raise argparse.ArgumentTypeError('an empty value (a URDF file is needed)')
    try:
        regular_file(text, repr(text), MAX_FILE_BYTES)
    except ValueError as err:
        raise argparse.ArgumentTypeError(str(err)) from None
    return text


def chunk_seconds(text: str) -> float:
    """``--chunk``: 0 (one task per bag) or seconds from MIN_CHUNK to MAX_CHUNK."""
    value = _number(text)
    if not (value == 0 or MIN_CHUNK <= value <= MAX_CHUNK):
        raise argparse.ArgumentTypeError(
            f'{shown(text)}: 0 (one task per bag) or a number of seconds >= {MIN_CHUNK:g} and <= '
            f'{MAX_CHUNK:.0f} (a year)')
    return value


def baseline_days(text: str) -> float:
    """``--baseline-days``: a number of days > 0, at most ten years."""
    value = _number(text)
    if not 0.0 < value <= 3660.0:
        raise argparse.ArgumentTypeError(f'{shown(text)}: a number of days > 0 and <= 3660')
    return value


def workers_count(text: str) -> int:
    """``--workers``: a whole number from 1 to 4096."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if not 1 <= value <= 4096:
        raise argparse.ArgumentTypeError(f'{shown(text)}: a whole number of processes, 1 to 4096')
    return value


#: How long the name of a scheduler may take to resolve, s.
RESOLVE_S = 10.0
#: A host name's label (RFC 1123): letters, digits and inner hyphens, at most 63.
_LABEL = re.compile(r'(?!-)[A-Za-z0-9-]{1,63}(?<!-)$')


def scheduler_address(text: str) -> str:
    """``--scheduler``: ``tcp://host:port``, the port 1 to 65535, the host one that resolves.

    The host is a name (RFC 1123 labels) or an IP literal (IPv6 in brackets); no user, path
    or space. A name that does not resolve within :data:`RESOLVE_S` is refused here, not
    after Dask's 30 s of connection attempts. ``tls://`` is refused: it needs certificates
    (a security context) this command does not take; ``ucx``, ``inproc`` and the rest are
    not for a cluster of plain processes.
    """
    example = 'e.g. tcp://10.0.0.5:8786'
    protocol, sep, rest = text.partition('://')
    if not text:
        raise argparse.ArgumentTypeError(
            f'an empty value; a scheduler address is tcp://host:port ({example})')
    if not sep:
        raise argparse.ArgumentTypeError(
            f'{shown(text)}: give the protocol, tcp://{shown(text, quote=False)} ({example})')
    if protocol == 'tls':
        raise argparse.ArgumentTypeError(
            f'{shown(text)}: tls:// needs certificates (a Dask security context), which this '
            'command does not take; give tcp://host:port (a scheduler reached through an SSH '
            'tunnel or a private network)')
    if protocol != 'tcp':
        raise argparse.ArgumentTypeError(
            f'{shown(text)}: the protocol {shown(protocol)} is not supported here; give '
            f'tcp://host:port ({example})')
    host, _, port = rest.rpartition(':')
    if not port.isdigit() or not 1 <= int(port) <= 65535:
        raise argparse.ArgumentTypeError(
            f'{shown(text)}: a scheduler address is tcp://host:port, the port 1 to 65535 '
            f'({example})')
    literal = host[1:-1] if host.startswith('[') and host.endswith(']') else host
    try:
        is_ip = (ipaddress.ip_address(literal).version == 6) == (literal != host)
    except ValueError:
        is_ip = False
    name = host[:-1] if host.endswith('.') else host
    if not is_ip and (literal != host or not name or len(name) > 253
                      or not all(_LABEL.match(label) for label in name.split('.'))
                      or name.replace('.', '').isdigit()):
        raise argparse.ArgumentTypeError(
            f'{shown(text)}: the host {shown(host)} is neither a host name (letters, digits, - '
            f'and .) nor an IP address (IPv6 in brackets); no user@, path or space ({example})')
    if not is_ip:
        why = _resolve(name, int(port))
        if why:
            raise argparse.ArgumentTypeError(f'{shown(text)}: the host {shown(host)} {why}')
    return f'tcp://{host}:{int(port)}'


def _resolve(name: str, port: int) -> Optional[str]:
    """Return why ``name`` does not resolve within :data:`RESOLVE_S` (None when it does).

    The lookup runs in a daemon thread: a resolver that never answers keeps neither the
    refusal nor the command's exit waiting.
    """
    answer: List[Optional[str]] = []

    def look_up() -> None:
        try:
            socket.getaddrinfo(name, port, type=socket.SOCK_STREAM)
            answer.append(None)
        except (OSError, UnicodeError) as err:
            answer.append(f'does not resolve ({getattr(err, "strerror", None) or err})')

    thread = threading.Thread(target=look_up, daemon=True)
    thread.start()
    thread.join(RESOLVE_S)
    return answer[0] if answer else f'did not resolve within {RESOLVE_S:g} s'
