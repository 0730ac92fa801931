# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Which bags belong to which robot: a manifest (CSV or YAML) or a folder ``ROBOT/…/BAG``.

CSV: a header with ``robot,urdf,bag`` and optional option columns (``topic``, ``joints``
(space-separated), ``threshold``, ``window``, ``order``, ``measured_effort``, ``gravity``,
and for a mobile manipulator ``base_odometry`` or ``base_imu`` with ``odometry_link`` or
``imu_link``: the base's motion from that topic of each bag); ``bag`` may be a glob.
A CSV is UTF-8 (a byte-order mark is skipped), each column once, no line longer than its
header. YAML: a list of ``{robot, urdf, bags: [path or glob, ...], options: {...}}`` (or
``robots:`` that list), no other key, no key twice, names and paths as text. A robot of
several rows has the same URDF and options (but ``topic``) in each. Paths are relative to
the manifest's folder. A folder: each sub-folder is a robot, every bag below
it (a directory holding ``metadata.yaml``, or a ``.db3``/``.mcap`` file outside one) is one
of its bags, and the URDF is ``--urdf`` or the robot folder's ``robot.urdf``.
"""

from __future__ import annotations

import argparse
import csv
import filecmp
import glob
import io
import os
from typing import Dict, List, Optional, Sequence, Tuple
import unicodedata

import numpy as np

from ..bounds import MAX_GRAVITY
from ..effort import MEASURED_EFFORT
from ..files import load_yaml, read_regular
from ..recordings.ranges import gravity_component, velocity_threshold, window_s
from ..text import listed, shown
from .task import BASE_TOPICS, DEFAULTS, Task

#: Largest manifest read (a fleet of thousands of bags is a few MB).
MANIFEST_LIMIT = 64 << 20
BAG_SUFFIXES = ('.db3', '.mcap')
#: Longest robot name (it names files: ``trend_ROBOT.png``).
NAME_LIMIT = 64
#: The note of a bag listed twice (:func:`once`).
LISTED_TWICE = 'bags listed twice, each counted once'
#: The per-robot options checked as ``replay``'s options of the same name are.
CHECKED = {'window': window_s, 'threshold': velocity_threshold}


class ManifestError(ValueError):
    """The manifest or folder cannot be used; the message names the file and the row."""


#: What a robot's name may be; :func:`robot_name` checks exactly this.
NAME_RULE = (f'a name is 1 to {NAME_LIMIT} letters (of any script), digits, - and _, '
             'starting with a letter or digit')


def _name_char(c: str) -> bool:
    """Whether ``c`` is a letter (Unicode category L*) or a decimal digit (Nd)."""
    return unicodedata.category(c)[0] == 'L' or unicodedata.category(c) == 'Nd'


def robot_name(name, where: str) -> str:
    """Return ``name`` as a robot's name, or refuse it naming ``where``.

    A name becomes a file name (``trend_ROBOT.png``) and a line of drift.txt: it is text
    (YAML reads ``yes``, ``1e3``, ``[a]`` as other types), and :data:`NAME_RULE` holds: no
    space, path separator, dot, quote, glob or control character, no leading ``-``.
    """
    if not isinstance(name, str):
        raise ManifestError(f'{where}: robot name {shown(name)} is a {type(name).__name__}, not '
                            f'text (quote it in YAML); {NAME_RULE}')
    odd = [c for c in name if not (_name_char(c) or c in '-_')]
    why = ('is empty' if not name else
           f'is longer than {NAME_LIMIT} characters' if len(name) > NAME_LIMIT else
           f'has {odd[0]!r} ({unicodedata.name(odd[0], "a control character")})' if odd else
           f'starts with {name[0]!r}' if not _name_char(name[0]) else None)
    if why:
        raise ManifestError(f'{where}: robot name {shown(name)} {why}; '
                            f'{NAME_RULE}')
    return name


def _option(name: str, value, where: str):
    if name not in DEFAULTS:
        raise ManifestError(f'{where}: unknown option {shown(name)} (known: '
                            f'{", ".join(sorted(DEFAULTS))})')
    try:
        if name in CHECKED:
            return CHECKED[name](str(value))
        if name == 'order':
            x = int(value)
            if not 2 <= x <= 6:
                raise ValueError
            return x
        if name == 'joints':
            return tuple(value.split() if isinstance(value, str) else value)
        if name == 'gravity':
            try:        # each component as replay's --gravity takes it, then |g|
                g = tuple(gravity_component(str(v))
                          for v in (value.split() if isinstance(value, str) else value))
            except argparse.ArgumentTypeError:
                g = ()
            if len(g) != 3 or not float(np.linalg.norm(g)) <= MAX_GRAVITY:
                raise ManifestError(f'{where}: option gravity = {shown(value)}: three numbers, '
                                    f'm/s², |g| at most {MAX_GRAVITY:g} (100 g)')
            return g
        if name == 'measured_effort':
            if value not in MEASURED_EFFORT:
                raise ValueError
        return str(value)
    except ManifestError:
        raise
    except argparse.ArgumentTypeError as err:
        raise ManifestError(f'{where}: option {name}: {err}') from None
    except (TypeError, ValueError):
        raise ManifestError(f'{where}: option {name} = {shown(value)} is not valid') from None


def _bags(pattern: str, base: str) -> Tuple[str, List[str]]:
    """Return the pattern's path and the bags it names (none: a glob that matches nothing)."""
    path = os.path.join(base, os.path.expanduser(pattern))
    return path, sorted(glob.glob(path)) if glob.has_magic(path) else [path]


def _urdf(path: str, base: str, where: str) -> str:
    path = os.path.join(base, os.path.expanduser(str(path)))
    if not os.path.isfile(path):
        raise ManifestError(f'{where}: URDF {path!r} is not a file')
    return path


#: A YAML manifest's keys of a robot; ``bag`` is ``bags`` with one path.
YAML_KEYS = ('robot', 'urdf', 'bags', 'bag', 'options')
#: The options a robot's rows may give differently: where its joint states are in the bags.
PER_ROW = ('topic',)
#: A CSV manifest's columns every row needs; the others are options (:data:`.task.DEFAULTS`).
CSV_COLUMNS = ('robot', 'urdf', 'bag')


def _text(value, what: str, where: str) -> str:
    """Return ``value`` if it is text; refuse any other type (YAML's ``1``, ``null``, ``{}``)."""
    if not isinstance(value, str) or not value:
        raise ManifestError(f'{where}: {what} {shown(value)} is not a path (text)')
    return value


def _row(robot, urdf, patterns, options: Dict, base: str, where: str,
         robots: Dict[str, Tuple[str, Dict, str]]) -> Tuple[List[Task], List[Dict]]:
    """Return the tasks of one row and a failed result per glob matching none.

    ``robots``: the robots of the rows before (name -> URDF, options, row); a robot of two
    rows has the same URDF (the same file, or the same bytes) and the same options but
    :data:`PER_ROW` in both.
    """
    if robot is None or not urdf or not patterns:
        raise ManifestError(f'{where}: robot, urdf and bag are all needed')
    robot = robot_name(robot, where)
    opts = {k: _option(k, v, where) for k, v in options.items()
            if v is not None and v != ''}
    topics = [k for k in BASE_TOPICS if k in opts]
    if len(topics) > 1:
        raise ManifestError(f'{where}: base_odometry and base_imu: give one (each gives the '
                            'whole motion of the base)')
    for topic, link in BASE_TOPICS.items():
        if link in opts and topic not in opts:
            raise ManifestError(f'{where}: {link} needs {topic}')
    urdf = _urdf(_text(urdf, 'urdf', where), base, where)
    if robot in robots:
        _same_robot(robot, (urdf, opts, where), robots[robot])
    robots.setdefault(robot, (urdf, opts, where))
    tasks: List[Task] = []
    unmatched: List[Dict] = []
    for pattern in patterns:
        path, found = _bags(_text(pattern, 'bag', where), base)
        tasks += [Task(robot, urdf, bag, opts, where=where) for bag in found]
        if not found:
            unmatched.append({'robot': robot, 'bag': path, 'where': where, 'ok': False,
                              'reason': f'no bag matches {pattern!r}'})
    return tasks, unmatched


def _same_robot(robot: str, here: Tuple[str, Dict, str], before: Tuple[str, Dict, str]
                ) -> None:
    """Refuse a robot whose URDF or options differ from its earlier row's, naming both."""
    (urdf, opts, where), (urdf0, opts0, where0) = here, before
    if not (os.path.samefile(urdf, urdf0) or filecmp.cmp(urdf, urdf0, shallow=False)):
        raise ManifestError(f'{where}: robot {robot!r} has the URDF {urdf!r} here and '
                            f'{urdf0!r} in {where0}: a robot has one URDF (a different '
                            'robot needs another name)')
    mine, theirs = ({k: v for k, v in o.items() if k not in PER_ROW} for o in (opts, opts0))
    if mine != theirs:
        raise ManifestError(f'{where}: robot {robot!r} has the options {mine} here and '
                            f'{theirs} in {where0}: a robot has one set of options (only '
                            f'{", ".join(PER_ROW)} may differ between its rows)')


def _yaml_rows(text: bytes, path: str) -> List[Tuple[str, Dict]]:
    """Return ``(where, entry)`` of each robot of a YAML manifest, its keys checked."""
    try:
        doc = load_yaml(text, f'manifest {path!r}')
    except ValueError as err:       # not YAML, a key twice, an alias bomb: the file's fault
        raise ManifestError(str(err)) from None
    if isinstance(doc, dict) and 'robots' in doc:
        extra = sorted(map(str, set(doc) - {'robots'}))
        if extra:
            raise ManifestError(f'manifest {path!r}: unknown key {shown(extra[0])} (the top level '
                                'is a list of robots, or robots: that list)')
        doc = doc['robots']
    if not isinstance(doc, list):
        raise ManifestError(f'manifest {path!r}: a list of robots is needed')
    rows = []
    for k, entry in enumerate(doc):
        where = f'manifest {path!r}, robot {k + 1}'
        if not isinstance(entry, dict):
            raise ManifestError(f'{where}: a mapping (robot, urdf, bags) is needed')
        for key in entry:
            if key not in YAML_KEYS:
                hint = ' (an option goes under options:)' if key in DEFAULTS else ''
                raise ManifestError(f'{where}: unknown key {shown(key)}{hint}; the keys are '
                                    f'{", ".join(YAML_KEYS)}')
        if 'bag' in entry and 'bags' in entry:
            raise ManifestError(f'{where}: bag and bags: give one')
        rows.append((where, entry))
    return rows


def _csv_rows(text: bytes, path: str) -> List[Tuple[str, Dict]]:
    """Return ``(where, row)`` of each line of a CSV manifest, its header and fields checked.

    UTF-8 with or without a byte-order mark (a spreadsheet's export); the header has
    :data:`CSV_COLUMNS`, each column once, and option columns; a line has no more fields
    than the header.
    """
    try:
        reader = csv.reader(io.StringIO(text.decode('utf-8-sig')))
        header = next(reader, None)
        if header is None:
            raise ManifestError(f'manifest {path!r}: empty (a header robot,urdf,bag is needed)')
        header = [c.strip() for c in header]
        twice = sorted({c for c in header if header.count(c) > 1})
        if twice:
            raise ManifestError(f'manifest {path!r}: the column {shown(twice[0])} is in the '
                                'header twice')
        missing = [c for c in CSV_COLUMNS if c not in header]
        if missing:
            raise ManifestError(f'manifest {path!r}: no {", ".join(map(repr, missing))} column '
                                f'(the header has {listed(header)}; it needs '
                                f'{", ".join(CSV_COLUMNS)} and options)')
        for c in header:
            if c not in CSV_COLUMNS and c not in DEFAULTS:
                raise ManifestError(f'manifest {path!r}: unknown column {shown(c)} (the columns '
                                    f'are {", ".join(CSV_COLUMNS)} and the options '
                                    f'{", ".join(sorted(DEFAULTS))})')
        rows = []
        for fields in reader:
            where = f'manifest {path!r}, line {reader.line_num}'
            if not any(f.strip() for f in fields):
                continue
            if len(fields) > len(header):
                raise ManifestError(f'{where}: {len(fields)} fields where the header has '
                                    f'{len(header)} (a comma in a value needs quotes)')
            rows.append((where, dict(zip(header, fields))))
        return rows
    except (UnicodeDecodeError, csv.Error) as err:
        raise ManifestError(f'manifest {path!r}: not a CSV file ({err})') from None


def read_manifest(path: str) -> Tuple[List[Task], List[Dict]]:
    """Return the tasks of a CSV or YAML manifest and a failed result per glob matching none.

    A row that cannot be used (no robot, a bad name or option, no URDF, a robot's URDF or
    options other than in its earlier row, an unknown key or column) refuses the manifest
    (:class:`ManifestError` names the row); a glob that matches no bag is one failed bag
    (``{robot, bag: the glob's path, where: the row, ok: False, reason}``), the other rows
    are used.
    """
    text = read_regular(path, f'manifest {path!r}', MANIFEST_LIMIT)
    base = os.path.dirname(os.path.abspath(path))
    tasks: List[Task] = []
    unmatched: List[Dict] = []
    robots: Dict[str, Tuple[str, Dict, str]] = {}
    if path.endswith(('.yaml', '.yml')):
        for where, entry in _yaml_rows(text, path):
            patterns = entry.get('bags', entry.get('bag'))
            if isinstance(patterns, str):
                patterns = [patterns]
            elif patterns is not None and not isinstance(patterns, list):
                raise ManifestError(f'{where}: bags must be a list of paths')
            options = entry.get('options') or {}
            if not isinstance(options, dict):
                raise ManifestError(f'{where}: options must be a mapping')
            found, none = _row(entry.get('robot'), entry.get('urdf'), patterns, options, base,
                               where, robots)
            tasks += found
            unmatched += none
    else:
        for where, row in _csv_rows(text, path):
            options = {c: v for c, v in row.items() if c not in CSV_COLUMNS}
            found, none = _row(row.get('robot'), row.get('urdf'),
                               [row['bag']] if row.get('bag') else None, options, base, where,
                               robots)
            tasks += found
            unmatched += none
    if not tasks and not unmatched:
        raise ManifestError(f'manifest {path!r}: no bags')
    return tasks, unmatched


def storage_identity(bag: str) -> frozenset:
    """Return what makes a bag the same bag: its storage files' ``(st_dev, st_ino)``.

    A bag directory's files whose name has ``.db3`` or ``.mcap`` (compressed ones too), or
    the ``.db3``/``.mcap`` file itself, links followed: a directory and its own ``.db3``, a
    hard link, a symbolic link and two spellings of a path are one bag. A path that cannot
    be looked at is itself (its task then says what is wrong with it).
    """
    try:
        if os.path.isdir(bag):
            files = [os.path.join(bag, f) for f in sorted(os.listdir(bag))
                     if any(s in f for s in BAG_SUFFIXES)]
            files = [f for f in files if os.path.isfile(f)] or [bag]
        else:
            files = [bag]
        return frozenset((st.st_dev, st.st_ino) for st in map(os.stat, files))
    except (OSError, ValueError):
        return frozenset([('path', os.path.realpath(bag))])


def once(tasks: Sequence[Task]) -> Tuple[List[Task], List[Tuple[str, str]]]:
    """Return each bag's first task and a note ``(kind, which)`` for each bag left out.

    Bags are the same when they share a storage file (:func:`storage_identity`): the later
    one is left out, whatever its robot (it is counted under its first row's).
    """
    first: Dict[object, Task] = {}
    kept: List[Task] = []
    notes: List[Tuple[str, str]] = []
    for t in tasks:
        ids = storage_identity(t.bag)
        seen = next((first[i] for i in ids if i in first), None)
        if seen is not None:
            notes.append((LISTED_TWICE, f'{t.bag!r} ({t.where}) is {seen.bag!r} of {seen.robot} '
                          f'({seen.where})'))
            continue
        first.update((i, t) for i in ids)
        kept.append(t)
    return kept, notes


def _is_bag_dir(path: str) -> bool:
    return os.path.isfile(os.path.join(path, 'metadata.yaml'))


def scan_folder(folder: str, urdf: Optional[str]) -> List[Task]:
    """Return the tasks of a folder ``ROBOT/…/BAG`` (see the module's docstring)."""
    tasks: List[Task] = []
    for robot in sorted(os.listdir(folder)):
        top = os.path.join(folder, robot)
        if not os.path.isdir(top):
            continue
        where = f'{folder!r}: robot folder {shown(robot)}'
        own = os.path.join(top, 'robot.urdf')
        robot_urdf = urdf or (own if os.path.isfile(own) else None)
        found = []
        for dirpath, dirnames, filenames in os.walk(top):
            dirnames.sort()
            if _is_bag_dir(dirpath):
                found.append(dirpath)
                dirnames[:] = []
                continue
            found += [os.path.join(dirpath, f) for f in sorted(filenames)
                      if f.endswith(BAG_SUFFIXES)]
        if not found:
            continue
        robot_name(robot, where)
        if robot_urdf is None:
            raise ManifestError(f'robot {robot}: no --urdf and no {own!r}')
        tasks += [Task(robot, robot_urdf, bag, {}, where=where) for bag in found]
    if not tasks:
        raise ManifestError(f'{folder!r}: no bags found in ROBOT/…/BAG')
    return tasks
