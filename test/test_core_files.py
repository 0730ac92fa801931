# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The writers' guards: :func:`files.check_output` and :func:`files.write_atomic`.

An output is refused before any work when it is an input, a directory, a named pipe or a
device, or when its folder is missing; a write that fails midway (a writer that raises, a
full disk at ``fsync``) leaves the file that was there as it was and no temporary beside it.
"""

import errno
import os
import stat

import pytest

from spatial_dynamics import files


def listing(folder):
    """Return the names in ``folder``, sorted (temporaries start with a dot)."""
    return sorted(os.listdir(folder))


def test_a_write_replaces_the_file_whole_and_keeps_its_permissions(tmp_path):
    path = tmp_path / 'out.urdf'
    path.write_bytes(b'old')
    os.chmod(path, 0o640)
    files.write_atomic(path, '<robot/>\n', 'the URDF')
    assert path.read_bytes() == b'<robot/>\n'
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o640
    assert listing(tmp_path) == ['out.urdf']
    files.write_atomic(tmp_path / 'new.bin', b'\x00\x01', 'bytes')
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(os.stat(tmp_path / 'new.bin').st_mode) == 0o666 & ~umask
    files.write_atomic(tmp_path / 'by_writer.csv', lambda f: f.write(b'a,b\n1,2\n'), 'csv')
    assert (tmp_path / 'by_writer.csv').read_bytes() == b'a,b\n1,2\n'


def test_a_writer_that_raises_midway_leaves_the_old_file_and_no_temporary(tmp_path):
    path = tmp_path / 'residual.csv'
    path.write_bytes(b'the old file\n')

    def writer(f):
        f.write(b'half of the new')
        raise RuntimeError('the writer failed')
    with pytest.raises(RuntimeError, match='the writer failed'):
        files.write_atomic(path, writer, 'the residual')
    assert path.read_bytes() == b'the old file\n'
    assert listing(tmp_path) == ['residual.csv']

    def interrupted(f):
        f.write(b'half')
        raise KeyboardInterrupt
    with pytest.raises(KeyboardInterrupt):
        files.write_atomic(path, interrupted, 'the residual')
    assert path.read_bytes() == b'the old file\n'
    assert listing(tmp_path) == ['residual.csv']


@pytest.mark.parametrize('call', ['fsync', 'replace'])
def test_a_full_disk_leaves_the_old_file_and_no_temporary(tmp_path, monkeypatch, call):
    """ENOSPC at fsync (the data did not fit) or at the rename: one ValueError naming the file."""
    path = tmp_path / 'robot.urdf'
    path.write_bytes(b'<robot name="old"/>\n')

    def full(*args):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    monkeypatch.setattr(os, call, full)
    with pytest.raises(ValueError) as caught:
        files.write_atomic(path, b'<robot name="new"/>\n' * 1000, 'corrected URDF')
    monkeypatch.undo()
    assert str(path) in str(caught.value) and 'No space left' in str(caught.value)
    assert 'corrected URDF' in str(caught.value)
    assert path.read_bytes() == b'<robot name="old"/>\n'
    assert listing(tmp_path) == ['robot.urdf']


def test_a_missing_folder_is_refused_by_the_write_too(tmp_path):
    with pytest.raises(ValueError, match='cannot write plot'):
        files.write_atomic(tmp_path / 'no' / 'x.png', b'x', 'plot')


def test_an_output_that_is_an_input_is_refused(tmp_path):
    urdf = tmp_path / 'robot.urdf'
    urdf.write_text('<robot/>')
    (tmp_path / 'sub').mkdir()
    os.symlink(urdf, tmp_path / 'link.urdf')
    for same in (urdf, tmp_path / 'sub' / '..' / 'robot.urdf', tmp_path / 'link.urdf',
                 os.path.relpath(urdf)):
        with pytest.raises(ValueError, match='also an input') as caught:
            files.check_output(same, '--write-urdf', inputs=[str(urdf), None])
        assert os.fspath(same) in str(caught.value)
    files.check_output(tmp_path / 'other.urdf', '--write-urdf', inputs=[str(urdf)])
    # an input that does not exist yet is compared by its absolute path
    with pytest.raises(ValueError, match='also an input'):
        files.check_output(tmp_path / 'x.csv', 'out', inputs=[os.path.relpath(tmp_path / 'x.csv')])


@pytest.mark.parametrize('special, kind', [('fifo', 'named pipe'), ('dir', 'directory'),
                                           ('/dev/full', 'character device'),
                                           ('/dev/null', 'character device')])
def test_special_files_are_refused_without_opening_them(tmp_path, special, kind):
    """A FIFO would block the write forever, /dev/full fails it late, a directory cannot be one."""
    path = {'fifo': tmp_path / 'out.urdf', 'dir': tmp_path}.get(special, special)
    if special == 'fifo':
        os.mkfifo(path)
    with pytest.raises(ValueError, match=kind) as caught:
        files.check_output(path, '--write-urdf')
    assert os.fspath(path) in str(caught.value) and '--write-urdf' in str(caught.value)


def test_a_missing_or_unusable_folder_is_refused(tmp_path):
    with pytest.raises(ValueError, match='does not exist') as caught:
        files.check_output(tmp_path / 'missing' / 'out.urdf', '--write-urdf')
    assert os.fspath(tmp_path / 'missing') in str(caught.value)
    (tmp_path / 'a_file').write_text('x')
    with pytest.raises(ValueError, match='Not a directory|does not exist'):
        files.check_output(tmp_path / 'a_file' / 'out.urdf', '--write-urdf')
    files.check_output(tmp_path / 'fresh.urdf', '--write-urdf')     # a new file: fine
    assert listing(tmp_path) == ['a_file']                          # and nothing created


@pytest.mark.parametrize('path', ['/proc/version', '/proc/out.json'])
def test_a_folder_no_file_can_be_created_in_is_refused_even_where_access_says_writable(path):
    """As root, os.access calls /proc writable: `--json /proc/version` passed, then failed."""
    with pytest.raises(ValueError, match='cannot create a file in the folder') as caught:
        files.check_output(path, '--json')
    assert path in str(caught.value) and '--json' in str(caught.value)


def test_missing_folders_pass_for_a_command_that_creates_them(tmp_path):
    """Refused by default; with ``missing_folders``, checked where they would be created."""
    path = tmp_path / 'a' / 'b' / 'out.json'
    with pytest.raises(ValueError, match='does not exist'):
        files.check_output(path, '--json')
    files.check_output(path, '--json', missing_folders=True)
    assert listing(tmp_path) == []   # nothing created, no probe left
    (tmp_path / 'a').write_text('x')
    with pytest.raises(ValueError, match='Not a directory|is not a folder'):
        files.check_output(path, '--json', missing_folders=True)
    with pytest.raises(ValueError, match='is not a folder'):
        files.check_folder(tmp_path / 'a' / 'b', '--log-dir', missing=True)
    with pytest.raises(ValueError, match='cannot create a file in the folder'):
        files.check_folder('/proc/sd_logs', '--log-dir', missing=True)


def test_an_output_that_is_a_link_is_written_through_to_its_target(tmp_path):
    """`--json link.json` replaced the link by a regular file; the link's target kept the old."""
    (tmp_path / 'real').mkdir()
    target = tmp_path / 'real' / 'results.json'
    target.write_text('old\n')
    link = tmp_path / 'results.json'
    os.symlink(target, link)
    files.check_output(link, '--json')
    files.write_atomic(link, 'new\n', '--json')
    assert os.path.islink(link) and target.read_text() == 'new\n'
    assert listing(tmp_path / 'real') == ['results.json']   # no temporary left beside it


def test_a_path_through_a_missing_folder_and_dotdot_is_checked_and_written_alike(tmp_path):
    """`a/new1/../new2/x.json`: the check passed, new2 was made, the write failed (ENOENT)."""
    path = os.path.join(tmp_path, 'new1', '..', 'new2', 'x.json')
    files.check_output(path, '--json', missing_folders=True)
    os.makedirs(os.path.dirname(files.output_path(path)))
    files.write_atomic(path, '{}\n', '--json')
    assert (tmp_path / 'new2' / 'x.json').read_text() == '{}\n'


def test_a_folder_that_makes_no_file_says_so_not_no_such_file():
    """`--json /proc/x.json`: "the folder '/proc' is not writable (No such file or directory)"."""
    with pytest.raises(ValueError, match='cannot create a file in the folder') as caught:
        files.check_output('/proc/x.json', '--json')
    assert 'No such file' not in str(caught.value)


def test_a_file_whose_name_is_near_the_limit_is_written(tmp_path):
    """A 250-byte name passes the check, and its file is written.

    The temporary beside it ('.NAME.XXXXXXXX.tmp', 264 bytes) could not be made: the run's
    result was lost at its very end.
    """
    name = 'r' * 245 + '.json'
    files.check_output(tmp_path / name, '--json')
    files.write_atomic(tmp_path / name, '{}', '--json')
    assert (tmp_path / name).read_text() == '{}'
    assert os.listdir(tmp_path) == [name]       # no temporary left beside it
