# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Which bags belong to which robot: a manifest (CSV or YAML) or a folder ``ROBOT/…/BAG``.

CSV: a header with ``robot,urdf,bag`` and optional option columns (``topic``, ``joints``
(space-separated), ``threshold``, ``window``, ``order``, ``measured_effort``, ``gravity``,
and for a mobile manipulator ``base_odometry`` or ``base_imu`` with ``odometry_link`` or
``imu_link``: the base's motion from that topic of each bag); ``bag`` may be a glob.
YAML: a list of ``{robot, urdf, bags: [path or glob, ...], options: {...}}``. Paths are
relative to the manifest's folder. A folder: each sub-folder is a robot, every bag below
it (a directory holding ``metadata.yaml``, or a ``.db3``/``.mcap`` file outside one) is one
of its bags, and the URDF is ``--urdf`` or the robot folder's ``robot.urdf``.
"""

from __future__ import annotations

import argparse
import csv
import glob
import io
import os
from typing import Dict, List, Optional, Tuple
import unicodedata

import numpy as np

from ..bounds import MAX_GRAVITY
from ..files import load_yaml, read_regular
from ..replay.arguments import gravity_component, velocity_threshold, window_s
from .task import BASE_TOPICS, DEFAULTS, Task

#: Largest manifest read (a fleet of thousands of bags is a few MB).
MANIFEST_LIMIT = 64 << 20
BAG_SUFFIXES = ('.db3', '.mcap')
#: Longest robot name (it names files: ``trend_ROBOT.png``).
NAME_LIMIT = 64
#: The per-robot options checked as ``replay``'s options of the same name are.
CHECKED = {'window': window_s, 'threshold': velocity_threshold}


class ManifestError(ValueError):
    """The manifest or folder cannot be used; the message names the file and the row."""


def robot_name(name, where: str) -> str:
    """Return ``name`` as a robot's name, or refuse it naming ``where``.

    A name becomes a file name (``trend_ROBOT.png``) and a line of drift.txt: path
    separators, ``.`` and ``..``, control and format characters (a newline would forge a
    line) and names longer than :data:`NAME_LIMIT` characters are refused.
    """
    text = '' if name is None else str(name)
    bad = [c for c in text if unicodedata.category(c) in ('Cc', 'Cf', 'Zl', 'Zp')]
    why = ('is empty' if not text.strip() else
           f'is longer than {NAME_LIMIT} characters' if len(text) > NAME_LIMIT else
           'has a path separator' if any(c in text for c in ('/', '\\', os.sep)) else
           'is . or ..' if text in ('.', '..') else
           f'has the control character {bad[0]!r}' if bad else None)
    if why:
        raise ManifestError(f'{where}: robot name {text[:NAME_LIMIT + 8]!r} {why}; use '
                            'letters, digits, - and _')
    return text


def _option(name: str, value, where: str):
    if name not in DEFAULTS:
        raise ManifestError(f'{where}: unknown option {name!r} (known: '
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
                raise ManifestError(f'{where}: option gravity = {value!r}: three numbers, '
                                    f'm/s², |g| at most {MAX_GRAVITY:g} (100 g)')
            return g
        if name == 'measured_effort':
            from ..effort import MEASURED_EFFORT
            if value not in MEASURED_EFFORT:
                raise ValueError
        return str(value)
    except ManifestError:
        raise
    except argparse.ArgumentTypeError as err:
        raise ManifestError(f'{where}: option {name}: {err}') from None
    except (TypeError, ValueError):
        raise ManifestError(f'{where}: option {name} = {value!r} is not valid') from None


def _bags(pattern: str, base: str) -> Tuple[str, List[str]]:
    """Return the pattern's path and the bags it names (none: a glob that matches nothing)."""
    path = os.path.join(base, os.path.expanduser(pattern))
    return path, sorted(glob.glob(path)) if glob.has_magic(path) else [path]


def _urdf(path: str, base: str, where: str) -> str:
    path = os.path.join(base, os.path.expanduser(str(path)))
    if not os.path.isfile(path):
        raise ManifestError(f'{where}: URDF {path!r} is not a file')
    return path


def _row(robot, urdf, patterns, options: Dict, base: str, where: str
         ) -> Tuple[List[Task], List[Dict]]:
    if not robot or not urdf or not patterns:
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
    urdf = _urdf(urdf, base, where)
    tasks: List[Task] = []
    unmatched: List[Dict] = []
    for pattern in patterns:
        path, found = _bags(str(pattern), base)
        tasks += [Task(robot, urdf, bag, opts, where=where) for bag in found]
        if not found:
            unmatched.append({'robot': robot, 'bag': path, 'where': where, 'ok': False,
                              'reason': f'no bag matches {str(pattern)!r}'})
    return tasks, unmatched


def read_manifest(path: str) -> Tuple[List[Task], List[Dict]]:
    """Return the tasks of a CSV or YAML manifest and a failed result per glob matching none.

    A row that cannot be used (no robot, a bad name or option, no URDF) refuses the manifest
    (:class:`ManifestError` names the row); a glob that matches no bag is one failed bag
    (``{robot, bag: the glob's path, where: the row, ok: False, reason}``), the other rows
    are used.
    """
    text = read_regular(path, f'manifest {path}', MANIFEST_LIMIT)
    base = os.path.dirname(os.path.abspath(path))
    tasks: List[Task] = []
    unmatched: List[Dict] = []
    if path.endswith(('.yaml', '.yml')):
        doc = load_yaml(text, f'manifest {path}')
        if isinstance(doc, dict) and 'robots' in doc:
            doc = doc['robots']
        if not isinstance(doc, list):
            raise ManifestError(f'manifest {path}: a list of robots is needed')
        for k, entry in enumerate(doc):
            where = f'manifest {path}, robot {k + 1}'
            if not isinstance(entry, dict):
                raise ManifestError(f'{where}: a mapping (robot, urdf, bags) is needed')
            patterns = entry.get('bags', entry.get('bag'))
            if isinstance(patterns, str):
                patterns = [patterns]
            options = entry.get('options') or {}
            if not isinstance(options, dict):
                raise ManifestError(f'{where}: options must be a mapping')
            found, none = _row(entry.get('robot'), entry.get('urdf'), patterns, options, base,
                               where)
            tasks += found
            unmatched += none
    else:
        try:
            rows = list(csv.DictReader(io.StringIO(text.decode('utf-8'))))
        except (UnicodeDecodeError, csv.Error) as err:
            raise ManifestError(f'manifest {path}: not a CSV file ({err})') from None
        for k, row in enumerate(rows):
            where = f'manifest {path}, line {k + 2}'
            options = {c: v for c, v in row.items() if c not in ('robot', 'urdf', 'bag')}
            found, none = _row(row.get('robot'), row.get('urdf'), [row.get('bag')], options,
                               base, where)
            tasks += found
            unmatched += none
    if not tasks and not unmatched:
        raise ManifestError(f'manifest {path}: no bags')
    return tasks, unmatched


def _is_bag_dir(path: str) -> bool:
    return os.path.isfile(os.path.join(path, 'metadata.yaml'))


def scan_folder(folder: str, urdf: Optional[str]) -> List[Task]:
    """Return the tasks of a folder ``ROBOT/…/BAG`` (see the module's docstring)."""
    tasks: List[Task] = []
    for robot in sorted(os.listdir(folder)):
        top = os.path.join(folder, robot)
        if not os.path.isdir(top):
            continue
        where = f'{folder}: robot folder {robot!r}'
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
            raise ManifestError(f'robot {robot}: no --urdf and no {own}')
        tasks += [Task(robot, robot_urdf, bag, {}, where=where) for bag in found]
    if not tasks:
        raise ManifestError(f'{folder}: no bags found in ROBOT/…/BAG')
    return tasks
