# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The one reader of the files users name: regular files only, bounded, YAML safe-loaded.

Every file the library, ``spatial_dynamics_check`` and ``replay`` read goes through
:func:`read_regular` or, in blocks, :func:`read_blocks` (or is checked by
:func:`regular_file` before a library such as SQLite opens it), so a path never blocks on a
FIFO, never reads a device or a directory, and never reads more than its caller's limit.
YAML goes through :func:`load_yaml`: PyYAML's safe loader (no ``!!python`` tags), a size
limit, and a budget on the nodes the document stands for once its aliases are expanded, so
a few hundred bytes of nested aliases ("billion laughs") are refused before anything walks
them.
"""

from __future__ import annotations

import errno
import os
import stat
from typing import Any, Callable, Iterator, Optional, Sequence, Tuple, Union

from .text import shown

#: The longest name of one file or folder (bytes), as Linux and macOS file systems take it.
NAME_MAX = 255

# yaml (load_yaml and its checks) and tempfile (write_atomic, check_folder) are imported inside
# the functions that use them: the core imports this module to read a URDF, and they would add
# some 20 ms each to `import spatial_dynamics` (python -X importtime -c 'import spatial_dynamics').

#: What a path is when it is not a regular file, by the test of its mode.
_KINDS = ((stat.S_ISDIR, 'a directory'), (stat.S_ISFIFO, 'a named pipe'),
          (stat.S_ISCHR, 'a character device'), (stat.S_ISBLK, 'a block device'),
          (stat.S_ISSOCK, 'a socket'))

#: Nodes a YAML document may stand for with its aliases expanded (a trajectory of 10,000
#: points of 32 joints with positions, velocities and accelerations is ~1 M).
MAX_YAML_NODES = 10_000_000


def size_text(n: int) -> str:
    """Return a byte count as people read it (``64 MiB``)."""
    return f'{n >> 20} MiB' if n >= 1 << 20 and not n % (1 << 20) else f'{n} bytes'


def _kind(mode: int) -> str:
    return next((name for test, name in _KINDS if test(mode)), 'a special file')


def regular_file(path: Union[str, os.PathLike], what: str, limit: int) -> int:
    """Check that ``path`` is a regular file of at most ``limit`` bytes; return its size.

    For files a library opens itself (SQLite, an MCAP memory map). ``ValueError`` names the
    file as ``what`` and says what it is instead.
    """
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise ValueError(f'{what}: no such file') from None
    except OSError as err:
        raise ValueError(f'{what}: {err.strerror}') from None
    if not stat.S_ISREG(info.st_mode):
        raise ValueError(f'{what} is not a regular file ({_kind(info.st_mode)})')
    if info.st_size > limit:
        raise ValueError(f'{what} is too large ({info.st_size} bytes, limit '
                         f'{size_text(limit)})')
    return info.st_size


def read_regular(path: Union[str, os.PathLike], what: str, limit: int) -> bytes:
    """Return the bytes of ``path``: a regular file of at most ``limit`` bytes.

    Never blocks on a FIFO or reads a device: the file is opened non-blocking and checked to
    be regular (on the open descriptor) before anything is read; a file that grows while it
    is read stops at ``limit + 1`` bytes and is refused. ``ValueError`` names the file as
    ``what``, and the reason.
    """
    return b''.join(read_blocks(path, what, limit, limit + 1))


def read_blocks(path: Union[str, os.PathLike], what: str, limit: int,
                block: int = 1 << 20) -> Iterator[bytes]:
    """Yield the bytes of ``path`` in blocks of at most ``block``: :func:`read_regular` in parts.

    For files too large to hold at once (a bag's bytes to hash): the same checks, made on
    the open descriptor before the first block (a regular file, at most ``limit`` bytes),
    and a file that grows past ``limit`` while it is read is refused. ``ValueError`` names
    the file as ``what``.
    """
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, 'O_NONBLOCK', 0)
                     | getattr(os, 'O_CLOEXEC', 0))
    except FileNotFoundError:
        raise ValueError(f'{what}: no such file') from None
    except OSError as err:
        raise ValueError(f'cannot read {what}: {err.strerror}') from None
    try:
        try:
            info = os.fstat(fd)
        except OSError as err:
            raise ValueError(f'cannot read {what}: {err.strerror}') from None
        if not stat.S_ISREG(info.st_mode):
            raise ValueError(f'{what} is not a regular file ({_kind(info.st_mode)})')
        if info.st_size > limit:
            raise ValueError(f'{what} is too large ({info.st_size} bytes, limit '
                             f'{size_text(limit)})')
        size = 0
        while size <= limit:
            try:
                chunk = os.read(fd, min(block, limit + 1 - size))
            except OSError as err:
                raise ValueError(f'cannot read {what}: {err.strerror}') from None
            if not chunk:
                return
            size += len(chunk)
            if size > limit:
                raise ValueError(f'{what} is too large (more than {size_text(limit)})')
            yield chunk
    finally:
        os.close(fd)


def _expanded_nodes(root) -> int:
    """Count the nodes a composed YAML graph stands for with every alias expanded.

    A shared subtree counts each time it is used; each distinct node is visited once, so the
    count takes time linear in the file, whatever it expands to.
    """
    from yaml.nodes import MappingNode, SequenceNode
    size: dict = {}
    stack = [(root, False)]
    while stack:
        node, children_done = stack.pop()
        if id(node) in size:
            continue
        if isinstance(node, SequenceNode):
            children = node.value
        elif isinstance(node, MappingNode):
            children = [x for pair in node.value for x in pair]
        else:
            size[id(node)] = 1
            continue
        if children_done:
            size[id(node)] = 1 + sum(size[id(c)] for c in children)
        else:
            stack.append((node, True))
            stack.extend((c, False) for c in children if id(c) not in size)
    return size[id(root)]


def _duplicate_key(root) -> Optional[Tuple[str, int]]:
    """Return ``(key, line)`` of the first key a mapping of a composed graph has twice.

    Keys are compared as scalars with their resolved tag (``1`` and ``'1'`` differ); the
    merge key ``<<`` and keys that are collections are left to the constructor.
    """
    from yaml.nodes import MappingNode, ScalarNode, SequenceNode
    seen_nodes = set()
    stack = [root]
    while stack:
        node = stack.pop()
        if id(node) in seen_nodes:
            continue
        seen_nodes.add(id(node))
        if isinstance(node, SequenceNode):
            stack.extend(node.value)
        elif isinstance(node, MappingNode):
            keys = set()
            for key, value in node.value:
                if isinstance(key, ScalarNode) and key.value != '<<':
                    if (key.tag, key.value) in keys:
                        return key.value, key.start_mark.line + 1
                    keys.add((key.tag, key.value))
                stack.extend((key, value))
    return None


def load_yaml(data: Union[str, bytes], what: str, max_nodes: int = MAX_YAML_NODES) -> Any:
    """Return the first document of YAML ``data`` (``None`` if empty), safe-loaded in budget.

    PyYAML's safe loader: tags such as ``!!python/object`` are refused. Before any Python
    object is built, the composed document is measured with its aliases expanded; one that
    stands for more than ``max_nodes`` nodes is refused, and so is a mapping with a key twice
    (PyYAML keeps the last silently; YAML says keys are unique). Further documents are ignored (as
    ``ros2 topic echo --once`` ends its output with ``---``). ``ValueError`` names ``what``.
    """
    import yaml
    try:
        loader_class = yaml.CSafeLoader
    except AttributeError:   # PyYAML built without libyaml
        loader_class = yaml.SafeLoader
    if isinstance(data, bytes):
        try:
            data = data.decode('utf-8')
        except UnicodeDecodeError as err:
            raise ValueError(f'{what}: not UTF-8 text (byte {err.start})') from None
    loader = loader_class(data)
    try:
        if not loader.check_node():
            return None
        node = loader.get_node()
        if _expanded_nodes(node) > max_nodes:
            raise ValueError(f'{what}: the YAML stands for more than {max_nodes:,} values '
                             'once its aliases are expanded (an alias bomb?)')
        twice = _duplicate_key(node)
        if twice:
            raise ValueError(f'{what}: the key {shown(twice[0])} is given twice in one mapping '
                             f'(line {twice[1]}); YAML keys are unique')
        return loader.construct_document(node)
    except yaml.YAMLError as err:
        text = ' '.join(str(err).split())
        raise ValueError(f'{what}: not valid YAML for this: {text}') from None
    except RecursionError:
        raise ValueError(f'{what}: the YAML is nested too deeply') from None
    finally:
        loader.dispose()


def _same_file(a: Union[str, os.PathLike], b: Union[str, os.PathLike]) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:
        return os.path.abspath(a) == os.path.abspath(b)


def output_path(path: Union[str, os.PathLike]) -> str:
    """Return the file an output ``path`` names, as it is checked, its folder made and written.

    ``os.path.realpath``: a link is followed (an output that is a link is written through to
    its target, the link kept), and a ``..`` after a folder that does not exist yet takes it
    back (``a/new1/../new2/x`` is ``a/new2/x``: ``new1`` is never made). The check
    (:func:`check_output`), the folders a command creates and the write (:func:`write_atomic`)
    all go through this one function, so they agree on the file.
    """
    return os.path.realpath(path)


def check_output(path: Union[str, os.PathLike], what: str,
                 inputs: Sequence[Union[str, os.PathLike]] = (),
                 missing_folders: bool = False) -> None:
    """Refuse an output path before any work is done for it.

    ``path`` must not be one of ``inputs`` (the files the command reads: writing over them
    would lose what the output was made from), must not be a directory, a named pipe or any
    other special file (writing would fail late or block forever), and its folder must exist
    and be writable (:func:`check_folder`; ``missing_folders``: or be creatable, for a command
    that creates it). The file checked is the one written, :func:`output_path`. ``ValueError``
    names the file as ``what`` and says why.
    """
    for source in inputs:
        if source is not None and _same_file(path, source):
            raise ValueError(f'{what} {os.fspath(path)!r} is also an input of this command; '
                             'choose another file (the input would be overwritten)')
    target = output_path(path)
    try:
        info = os.stat(target)
    except FileNotFoundError:
        info = None
    except OSError as err:
        raise ValueError(f'{what} {os.fspath(path)!r}: {err.strerror}') from None
    if info is not None and not stat.S_ISREG(info.st_mode):
        raise ValueError(f'{what} {os.fspath(path)!r} is not a regular file '
                         f'({_kind(info.st_mode)})')
    check_folder(os.path.dirname(target), f'{what} {os.fspath(path)!r}', missing_folders)


def check_folder(folder: Union[str, os.PathLike], what: str, missing: bool = False) -> None:
    """Refuse a folder outputs cannot be written in, before any work.

    It must be a folder in which a file can be created: tried, with a temporary that is
    removed at once (``os.access`` tells root that ``/proc`` is writable; creating one there
    fails with ENOENT, said as what it means). ``missing``: a
    folder that does not exist yet passes if the first of its parents that exists is a
    folder a folder can be created in (the command creates it). ``ValueError`` names it as
    ``what`` and says why.
    """
    import tempfile
    given = os.fspath(folder)
    if not given:
        raise ValueError(f'{what}: an empty path')
    if os.path.lexists(given) and not os.path.exists(given):
        # a link to nothing (its target missing) or a loop: makedirs would fail on the link
        raise ValueError(f'{what}: {given!r} is a link that leads to no folder (its target '
                         'is missing, or it leads back to itself)')
    folder = output_path(folder)
    for part in folder.split(os.sep):
        if len(os.fsencode(part)) > NAME_MAX:
            raise ValueError(f'{what}: the name {shown(part)} is longer than a folder '
                             f'name can be ({NAME_MAX} bytes)')
    head = folder
    while not os.path.exists(head):
        if not missing:
            raise ValueError(f'{what}: the folder {folder!r} does not exist')
        head = os.path.dirname(head)
    if not os.path.isdir(head):
        raise ValueError(f'{what}: {head!r} is not a folder')
    try:
        fd, probe = tempfile.mkstemp(prefix='.probe.', dir=head)
    except OSError as err:
        # ENOENT in a folder that exists: a file system that holds no files of its own
        why = ('the file system makes no new file there' if err.errno == errno.ENOENT
               else err.strerror)
        raise ValueError(f'{what}: cannot create a file in the folder {head!r} ({why})'
                         ) from None
    os.close(fd)
    _remove_quietly(probe)


def within(path: Union[str, os.PathLike], folder: Union[str, os.PathLike]) -> bool:
    """Tell whether ``path`` is ``folder`` or inside it (links resolved)."""
    path, folder = os.path.realpath(path), os.path.realpath(folder)
    return path == folder or path.startswith(folder.rstrip(os.sep) + os.sep)


def check_outside_recordings(path: Union[str, os.PathLike], what: str,
                             recordings: Sequence[Tuple[str, str]]) -> None:
    """Refuse an output ``path`` in a recording directory, before any work.

    ``recordings``: ``(where it was given, path)`` of each bag read; a bag directory (a
    rosbag2 recording) is left as it was made, nothing is written into it. ``ValueError``
    names the output as ``what`` and the bag with where it was given.
    """
    for where, bag in recordings:
        if os.path.isdir(bag) and within(path, bag):
            raise ValueError(f'{what} {os.fspath(path)}: in the bag {bag!r} ({where}); choose '
                             'another place (a recording is left as it was made)')


def write_atomic(path: Union[str, os.PathLike], data: Union[str, bytes, Callable[[Any], None]],
                 what: str) -> None:
    """Write ``data`` to ``path`` all or nothing: a temporary beside it, then a rename.

    ``data`` is text (UTF-8), bytes, or a function that writes into the binary file object
    it is given. A write that fails midway (a full disk, a quota) leaves ``path`` as it was
    and removes the temporary; the rename replaces ``path`` in one step, so a reader sees
    the old file or the new one, never half of one. The new file gets the permissions a
    plain ``open(path, 'w')`` would have given it (kept from the file it replaces). A
    ``path`` that is a link is written through to its target (:func:`output_path`: the file
    :func:`check_output` checked), the link kept. ``ValueError`` names the file as ``what``
    and the reason.
    """
    import tempfile
    shown_path = os.fspath(path)
    target = output_path(path)
    folder = os.path.dirname(target)
    try:
        # the temporary's name within NAME_MAX whatever the file's (a 250-byte name fits, its
        # '.NAME.XXXXXXXX.tmp' would not): the name cut to 200 bytes in it
        stem = os.fsencode(os.path.basename(target))[:200].decode(errors='ignore')
        fd, tmp = tempfile.mkstemp(prefix='.' + stem + '.', suffix='.tmp', dir=folder)
    except OSError as err:
        raise ValueError(f'cannot write {what} {shown_path!r}: {err.strerror}') from None
    try:
        with os.fdopen(fd, 'wb') as f:
            if callable(data):
                data(f)
            else:
                f.write(data.encode('utf-8') if isinstance(data, str) else data)
            f.flush()
            os.fsync(f.fileno())
        try:
            mode = stat.S_IMODE(os.stat(target).st_mode)
        except OSError:
            umask = os.umask(0)
            os.umask(umask)
            mode = 0o666 & ~umask
        os.chmod(tmp, mode)
        os.replace(tmp, target)
    except OSError as err:
        _remove_quietly(tmp)
        raise ValueError(f'cannot write {what} {shown_path!r}: {err.strerror}') from None
    except BaseException:
        _remove_quietly(tmp)
        raise


def _remove_quietly(path: str) -> None:
    try:
        os.unlink(path)
    except OSError:
        pass
