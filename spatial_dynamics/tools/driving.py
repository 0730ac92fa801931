# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Shared by the demo, the latency benchmark and the soak: start nodes, make a trajectory.

No rclpy import at module level: :func:`node_command` and :class:`Sinusoids` work without ROS.
"""

from __future__ import annotations

import argparse
import contextlib
import ctypes
import os
import signal
import subprocess
import sys
from typing import Dict, Iterator, List, Optional, Sequence, Tuple

import numpy as np

import spatial_dynamics as sd
from spatial_dynamics.files import check_folder, check_output, output_path, within

# Imported inside the functions that use them: ament_index_python (present only where ROS
# is sourced) and matplotlib (optional; seconds to import, for the plots only).

PACKAGE = 'spatial_dynamics'
#: The source tree (or the package's parent directory when installed): tools/ -> package -> root.
SOURCE_ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def package_prefix() -> Optional[str]:
    """Install prefix of the package on ``AMENT_PREFIX_PATH`` (a colcon install), or None."""
    try:
        from ament_index_python.packages import get_package_prefix, PackageNotFoundError
    except ImportError:
        return None
    try:
        return get_package_prefix(PACKAGE)
    except (PackageNotFoundError, OSError):  # OSError: AMENT_PREFIX_PATH not set
        return None


def node_command(executable: str, module: str) -> List[str]:
    """Command that starts ``executable`` as ``ros2 run`` would, else ``python -m module``.

    ``ros2 run spatial_dynamics <executable>`` runs ``<prefix>/lib/spatial_dynamics/<exe>`` of
    the prefix whose ament index lists the package; without a sourced install, the module of
    this source tree runs instead.
    """
    prefix = package_prefix()
    if prefix is not None:
        path = os.path.join(prefix, 'lib', PACKAGE, executable)
        if os.access(path, os.X_OK):
            return [path]
    return [sys.executable, '-m', module]


def share_file(*parts: str) -> str:
    """Return a file of the package's share directory (installed), else of this source tree."""
    prefix = package_prefix()
    if prefix is not None:
        path = os.path.join(prefix, 'share', PACKAGE, *parts)
        if os.path.exists(path):
            return path
    return os.path.join(SOURCE_ROOT, *parts)


def demo_urdf() -> str:
    """Path of the embedded demo robot, ``config/demo_arm.urdf``."""
    return share_file('config', 'demo_arm.urdf')


def start(command: Sequence[str], namespace: str, parameters: Dict[str, str],
          log_path: Optional[str] = None) -> subprocess.Popen:
    """Start a ROS node process in ``namespace`` with ``-p name:=value`` parameters.

    Its output goes to ``log_path`` (or is discarded). The child ignores nothing: Ctrl-C in a
    terminal reaches it too, and :func:`stop` ends it with SIGINT.
    """
    args = list(command) + ['--ros-args', '-r', f'__ns:={namespace}']
    for name, value in parameters.items():
        args += ['-p', f'{name}:={value}']
    out = open(log_path, 'w') if log_path else subprocess.DEVNULL
    try:
        return subprocess.Popen(args, stdout=out, stderr=subprocess.STDOUT,
                                preexec_fn=die_with_parent)
    finally:
        if log_path:
            out.close()


def die_with_parent() -> None:
    """In a child before exec: get SIGTERM when the parent dies (Linux), so none is orphaned."""
    try:
        PR_SET_PDEATHSIG = 1
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGTERM)
    except (OSError, AttributeError):
        pass


def die_with_parent_ignoring_ctrl_c() -> None:
    """In a child before exec: :func:`die_with_parent`, and SIGINT ignored from the start.

    For the helpers a tool ends itself (busy loops, the latency benchmark's publisher): the
    terminal's Ctrl-C reaches them too, and ignored before exec it cannot interrupt their
    Python while it imports (a KeyboardInterrupt traceback from the import; Python keeps an
    ignored SIGINT ignored).
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    die_with_parent()


class Interrupt:
    """A tool's SIGINT (Ctrl-C) and SIGTERM handler: remembers the signal, then interrupts.

    Ctrl-C reaches the tool's nodes too (one process group): they exit on it, and without the
    signal remembered their exit read as a failure ("the node exited"), or the
    KeyboardInterrupt, raised inside rclpy's message conversion, as a RuntimeError. SIGTERM
    takes the same way: the children are stopped, and the tool says it was interrupted.
    """

    def __init__(self) -> None:
        self.signal: Optional[int] = None
        self._held = 0   # nested held() blocks running
        self._pending = False   # a signal came while held: raise when the blocks end

    def __call__(self, signum: int, frame) -> None:
        """Remember ``signum`` and raise KeyboardInterrupt where Python is (or once released)."""
        self.signal = signum
        if self._held:
            self._pending = True
            return
        raise KeyboardInterrupt

    @contextlib.contextmanager
    def held(self) -> Iterator[None]:
        """Hold a signal while the block runs; it interrupts once the block has ended.

        Around starting a child and recording it (a signal inside ``subprocess.Popen`` after
        the fork lost the child: never stopped nor waited for) and around ending them all (a
        second Ctrl-C skipped the rest).
        """
        self._held += 1
        try:
            yield
        finally:
            self._held -= 1
        if not self._held and self._pending:
            self._pending = False
            raise KeyboardInterrupt

    def install(self) -> 'Interrupt':
        """Handle SIGINT (even if it was ignored when the tool started) and SIGTERM."""
        signal.signal(signal.SIGINT, self)
        signal.signal(signal.SIGTERM, self)
        return self

    @property
    def name(self) -> str:
        """The signal's name: ``SIGINT`` (also for a KeyboardInterrupt of its own)."""
        return signal.Signals(self.signal or signal.SIGINT).name

    @property
    def status(self) -> int:
        """The exit status of a process ended by the signal: 128 + its number (130: SIGINT)."""
        return 128 + (self.signal or signal.SIGINT)


def stop(proc: subprocess.Popen, timeout: float = 10.0) -> Optional[int]:
    """SIGINT, then wait; SIGKILL after ``timeout`` s. Returns the exit status."""
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    return proc.returncode


def rss_bytes(pid: int) -> int:
    """Resident set size of process ``pid`` from ``/proc/<pid>/status`` (Linux)."""
    with open(f'/proc/{pid}/status') as f:
        for line in f:
            if line.startswith('VmRSS:'):
                return int(line.split()[1]) * 1024
    raise RuntimeError(f'no VmRSS for pid {pid}')


def cpu_seconds(pid: int) -> float:
    """User + system CPU time of process ``pid`` so far, from ``/proc/<pid>/stat`` (Linux)."""
    with open(f'/proc/{pid}/stat') as f:
        fields = f.read().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def thread_cpu_ns(pid: int) -> Optional[Dict[int, int]]:
    """CPU time each thread of process ``pid`` has run, ns, by thread id (Linux); None if unkept.

    The first field of ``/proc/<pid>/task/<tid>/schedstat``: the scheduler's own sum, in ns,
    brought up to date at each switch of the thread (:func:`cpu_seconds` counts clock ticks,
    10 ms each: a short measurement of a thread that mostly sleeps reads 0 or a whole tick).
    None where the kernel keeps no schedstat (built without ``CONFIG_SCHED_INFO``).
    """
    out: Dict[int, int] = {}
    for tid in os.listdir(f'/proc/{pid}/task'):
        try:
            with open(f'/proc/{pid}/task/{tid}/schedstat') as f:
                out[int(tid)] = int(f.read().split()[0])
        except FileNotFoundError:
            if os.path.exists(f'/proc/{pid}/task/{tid}'):
                return None
        except ProcessLookupError:   # the thread ended meanwhile
            continue
    return out


def cpu_ns_between(before: Optional[Dict[int, int]],
                   after: Optional[Dict[int, int]]) -> Optional[int]:
    """CPU ns the threads ran between two :func:`thread_cpu_ns` readings; None if either is.

    A thread started in between counts whole; one that ended in between is missing from
    ``after`` (its last part cannot be read): the threads of a node live as long as it.
    """
    if before is None or after is None:
        return None
    return sum(ns - before.get(tid, 0) for tid, ns in after.items())


def last_error(log_path: Optional[str], marker: str = '', limit: int = 300) -> str:
    """Return the line of a node's log that says why it ended: '' if none (or no log).

    Its last line containing ``marker`` if given; else its last ``[FATAL]`` or ``[ERROR]``
    line; else the exception of its last traceback; else its last line. At most ``limit``
    characters, from the log's last 16 KiB.
    """
    if not log_path:
        return ''
    try:
        with open(log_path, 'rb') as f:
            f.seek(max(os.fstat(f.fileno()).st_size - (1 << 14), 0))
            lines = [line.rstrip() for line in f.read().decode('utf-8', 'replace').splitlines()]
    except OSError:
        return ''
    lines = [line for line in lines if line.strip()]
    logged = [line for line in lines if marker and marker in line] or [
        line for line in lines if line.startswith(('[FATAL]', '[ERROR]'))]
    if logged:
        line = logged[-1]
    elif 'Traceback (most recent call last):' in lines:
        start = len(lines) - lines[::-1].index('Traceback (most recent call last):')
        line = next((x for x in lines[start:] if not x[0].isspace()), lines[-1])
    else:
        line = lines[-1] if lines else ''
    return line if len(line) <= limit else line[:limit - 3] + '...'


class Sinusoids:
    """A smooth, consistent joint trajectory: q, qd = dq/dt, qdd = d²q/dt² of sinusoids.

        q_i(t)   = c_i + a_i sin(w_i t + phi_i)
        qd_i(t)  = a_i w_i cos(w_i t + phi_i)
        qdd_i(t) = -a_i w_i² sin(w_i t + phi_i)

    Centre ``c_i`` and amplitude ``a_i`` keep q inside the URDF limits when the model has them
    (``model.lower``/``model.upper`` if present), else ±1 rad around 0; periods 4..8 s.
    """

    def __init__(self, joint_names: Sequence[str], lower: Optional[Sequence[float]] = None,
                 upper: Optional[Sequence[float]] = None) -> None:
        n = len(joint_names)
        self.joint_names = tuple(joint_names)
        lo = np.full(n, -1.0) if lower is None else np.asarray(lower, dtype=float)
        hi = np.full(n, 1.0) if upper is None else np.asarray(upper, dtype=float)
        bounded = np.isfinite(lo) & np.isfinite(hi) & (hi > lo)
        lo = np.where(bounded, lo, -1.0)
        hi = np.where(bounded, hi, 1.0)
        self.c = 0.5 * (lo + hi)
        self.a = 0.25 * (hi - lo)
        self.w = 2.0 * np.pi / np.linspace(4.0, 8.0, n)
        self.phi = np.linspace(0.0, np.pi, n)

    @classmethod
    def for_model(cls, model) -> 'Sinusoids':
        """Use the model's joint limits when it exposes them."""
        lower = getattr(model, 'lower', None)
        upper = getattr(model, 'upper', None)
        if lower is not None and upper is not None and len(lower) != len(model.joint_names):
            lower = upper = None
        return cls(model.joint_names, lower, upper)

    def __call__(self, t: float):
        """``(q, qd, qdd)`` at time ``t`` (s), each of shape (n,)."""
        angle = self.w * t + self.phi
        s = np.sin(angle)
        return self.c + self.a * s, self.a * self.w * np.cos(angle), -self.a * self.w ** 2 * s


def redraw(lines: Sequence[str], shown: int) -> int:
    """Write ``lines`` over the ``shown`` lines written last (a table refreshed in place).

    Returns how many lines are now shown; for a terminal only (ANSI cursor movement).
    """
    sys.stdout.write((f'\x1b[{shown}F' if shown else '')
                     + ''.join(f'\x1b[2K{line}\n' for line in lines))
    sys.stdout.flush()
    return len(lines)


def robot_model(urdf: Optional[str]):
    """Return the absolute path of ``urdf`` (the demo arm when None) and its ``Model``."""
    path = os.path.abspath(urdf or demo_urdf())
    return path, sd.Model.from_urdf(path)


def save_figure(plt, fig, path: str) -> None:
    """Lay ``fig`` out, write it to ``path`` (its directory created) and close it.

    The folder made is that of the file written (:func:`~spatial_dynamics.files.output_path`).
    """
    fig.tight_layout()
    target = output_path(path)
    os.makedirs(os.path.dirname(target), exist_ok=True)
    fig.savefig(target)
    plt.close(fig)


#: What matplotlib's Agg backend writes, by the file's suffix.
PLOT_FORMATS = ('eps', 'jpeg', 'jpg', 'pdf', 'pgf', 'png', 'ps', 'raw', 'rgba', 'svg', 'svgz',
                'tif', 'tiff', 'webp')


def path_text(text: str) -> str:
    """Return ``text``, an argparse type of a path: an empty one is refused (it names nothing).

    A line break or another control character is refused too: a path reaches the nodes as a
    ``-p name:=value`` rule, whose value is YAML (a line break read as a space: the node
    looked for another file).
    """
    if not text:
        raise argparse.ArgumentTypeError('an empty path names no file')
    if any(ord(c) < 32 or ord(c) == 127 for c in text):
        raise argparse.ArgumentTypeError(f'{text!r}: a path with a line break or another '
                                         'control character cannot be passed to a ROS node')
    return text


def outputs_error(files: Sequence[Tuple[str, Optional[str]]],
                  folders: Sequence[Tuple[str, Optional[str]]] = (),
                  inputs: Sequence[Tuple[str, Optional[str]]] = ()) -> Optional[str]:
    """Why an output of a tool cannot be written (None if all can), checked before its run.

    ``files`` and ``folders``: ``(option, path)``, None or '' for an option not given. A
    file must not be a folder, a named pipe or a device; a folder must be one a file can be
    created in. Folders that do not exist yet pass where they would be created: the tool
    creates them (``os.makedirs``) before its run. No output may be another (a file also
    another file or a folder of the run, one written over the other) or be inside a file
    (its folder would be made where the file goes): compared as written,
    :func:`~spatial_dynamics.files.output_path` (links followed). ``inputs``: ``(option,
    path)`` of the files the run reads (a robot description): no output may be one of them
    (the run would write over what it read).
    """
    try:
        for option, folder in folders:
            if folder is not None:      # '' given is refused (it names no folder)
                check_folder(folder, f'{option} {folder!r}', missing=True)
        for option, path in files:
            if path:
                check_output(path, option, missing_folders=True)
                for source_option, source in inputs:
                    if source and _same_path(path, source):
                        raise ValueError(f'{option} {path!r} is the file {source_option} '
                                         'reads; choose another (the run would write over it)')
    except ValueError as err:
        return str(err)
    given = [(option, path, k < len(files))
             for k, (option, path) in enumerate(list(files) + list(folders)) if path]
    pairs = [(option, path, other, where) for i, (option, path, is_file) in enumerate(given)
             for j, (other, where, _) in enumerate(given) if is_file and i != j]
    for option, path, other, where in pairs:   # the same path first: the plainer to say
        if output_path(where) == output_path(path):
            return (f'{option} {path!r} and {other} {where!r} name the same path: one would '
                    'be written over the other')
    for option, path, other, where in pairs:
        if within(where, path):
            return (f'{other} {where!r} is inside {option} {path!r}: the {option} file cannot '
                    'be a folder')
    return None


def _same_path(a: str, b: str) -> bool:
    """Tell whether ``a`` and ``b`` name one file (links followed; one inode if both exist)."""
    if output_path(a) == output_path(b):
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def plot_path_error(plot: str, *others: Optional[str]) -> Optional[str]:
    """Why ``--plot`` cannot be written after the run (None if it can), checked before it.

    Its suffix must name a format matplotlib writes (matplotlib raised ValueError after the
    run), and it must not be another output of the run (``others``: the plot overwrote it).
    """
    suffix = os.path.splitext(plot)[1].lstrip('.').lower()
    if suffix not in PLOT_FORMATS:
        return (f'--plot {plot!r}: .{suffix} is not a format matplotlib writes (one of '
                f'{", ".join(PLOT_FORMATS)})')
    for other in others:
        if other and output_path(other) == output_path(plot):
            return f'--plot {plot!r} is also another output of the run'
    return None


def pyplot():
    """Return matplotlib's pyplot on the file-only Agg backend, or None when not installed."""
    try:
        import matplotlib
        matplotlib.use('Agg')
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    return plt
