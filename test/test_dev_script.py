# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""``scripts/dev`` says what it is doing before each step that takes minutes.

The first ``scripts/dev demo`` creates the venv, installs the requirements (~2 min) and builds
(~1 min); it used to print nothing for the whole of it. Here the script runs in a copy of the
checkout whose interpreter, pip and colcon are stand-ins that only record their call, so the
steps are the script's own and nothing is installed.
"""

import os
import shutil
import stat
import subprocess

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

#: The stand-in interpreter: answers the version check, records every other call.
PYTHON = '''#!/usr/bin/env bash
case "$*" in
    *sys.version_info*) echo 3.11 ;;
    "-m venv "*) mkdir -p "$3/bin" && cp "$0" "$3/bin/python" \\
        && printf 'export PATH="%s/bin:$PATH"\\n' "$3" > "$3/bin/activate" ;;
    *) echo "python $*" >> "$CALLS" ;;
esac
'''
COLCON = '''#!/usr/bin/env bash
echo "colcon $*" >> "$CALLS"
mkdir -p install && echo ': install' > install/setup.bash
'''


def executable(path, text):
    with open(path, 'w', encoding='utf-8') as f:
        f.write(text)
    os.chmod(path, os.stat(path).st_mode | stat.S_IXUSR)


@pytest.fixture
def checkout(tmp_path):
    """Make a checkout with scripts/dev and a requirement list; python3.11 and colcon stubbed."""
    root = tmp_path / 'checkout'
    (root / 'scripts').mkdir(parents=True)
    (root / '.ci').mkdir()
    shutil.copy(os.path.join(ROOT, 'scripts', 'dev'), root / 'scripts' / 'dev')
    (root / '.ci' / 'requirements.txt').write_text('# a comment\nnumpy==2.0\n\nlxml\n')
    stubs = tmp_path / 'stubs'
    stubs.mkdir()
    executable(stubs / 'python3.11', PYTHON)
    executable(stubs / 'colcon', COLCON)
    env = dict(os.environ, PATH=f'{stubs}:/usr/bin:/bin', PYTHON=str(stubs / 'python3.11'),
               CALLS=str(tmp_path / 'calls'))
    return root, env, tmp_path / 'calls'


def test_first_setup_says_each_long_step_before_it_runs(checkout):
    root, env, calls = checkout
    run = subprocess.run(['bash', 'scripts/dev', 'test', 'test/x.py'], cwd=root, env=env,
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    said = run.stderr.splitlines()
    done = open(calls, encoding='utf-8').read().splitlines()
    # each step is announced, in the order the steps ran
    assert said[0].startswith('scripts/dev: creating ')
    assert 'installing the 2 requirements of .ci/requirements.txt' in said[1]
    assert '~2 min' in said[1]
    assert any(line.startswith('scripts/dev: installed in ') for line in said)
    building = next(k for k, line in enumerate(said) if 'building the package' in line)
    assert said[building + 1].startswith('scripts/dev: built in ')
    assert [c.split()[:2] for c in done][:2] == [['python', '-m'], ['colcon', '--log-base']]
    # a second run installs nothing and says so by saying nothing of it
    again = subprocess.run(['bash', 'scripts/dev', 'test', 'test/x.py'], cwd=root, env=env,
                           capture_output=True, text=True, timeout=120)
    assert again.returncode == 0, again.stderr
    assert 'installing' not in again.stderr and 'building the package' in again.stderr
