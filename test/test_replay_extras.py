# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""An optional dependency that is not installed is said as the extra that brings it.

``pip install .`` installs numpy and lxml only; ``replay fleet`` then died with a traceback
(``ModuleNotFoundError: threadpoolctl``, then ``distributed``). A module missing here is a
``None`` entry of ``sys.modules`` (what ``import`` then refuses, as for a module not there).
"""

import ast
import os
import subprocess
import sys

import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from node_harness import ROOT  # noqa: E402
from spatial_dynamics.extras import EXTRAS, install_hint, MODULES  # noqa: E402
from spatial_dynamics.replay.__main__ import main as replay  # noqa: E402


@pytest.fixture(scope='module')
def small_fleet(tmp_path_factory):
    """One robot, one short day: a fleet ``replay fleet`` reads."""
    pytest.importorskip('mujoco')
    from spatial_dynamics.tools.fleet_demo import make_fleet
    out = str(tmp_path_factory.mktemp('fleet'))
    try:
        make_fleet(out, robots=1, days=1, seconds=0.5, wear=(0, 0, 5, 0.05))
    except RuntimeError as err:
        pytest.skip(str(err))
    return out


@pytest.mark.parametrize('module, options', [('threadpoolctl', ['--serial']),
                                             ('distributed', ['--scheduler',
                                                              'tcp://127.0.0.1:1'])])
def test_replay_fleet_without_a_dependency_names_the_fleet_extra(
        small_fleet, tmp_path, capsys, monkeypatch, module, options):
    monkeypatch.setitem(sys.modules, module, None)
    status = replay(['fleet', small_fleet, '--out', str(tmp_path / 'out'), '--no-plots',
                     *options])
    err = capsys.readouterr().err
    assert status == 1, err
    assert "pip install 'spatial_dynamics[fleet]'" in err and module in err, err
    assert 'Traceback' not in err


def test_the_replay_command_starts_without_its_extra():
    """``replay --help`` (and the parser of every subcommand) needs no optional module."""
    blocked = ', '.join(f'{m!r}: None' for m in MODULES)
    code = (f'import sys; sys.modules.update({{{blocked}}}); '
            'from spatial_dynamics.replay.__main__ import main; main(["--help"])')
    run = subprocess.run([sys.executable, '-c', code], cwd=ROOT, capture_output=True,
                         text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert 'fleet' in run.stdout


def test_the_hint_names_the_command_s_extra_when_it_brings_the_module():
    err = ModuleNotFoundError('no', name='scipy.linalg')
    assert "'spatial_dynamics[fleet]'" in install_hint(err, 'fleet')
    assert "'spatial_dynamics[identify]'" in install_hint(err, 'sim')   # sim does not bring it
    assert install_hint(ModuleNotFoundError('no', name='not_ours'), 'fleet') == ''


def test_every_optional_module_is_in_its_extra_and_setup_declares_them():
    for module, (distribution, extra) in MODULES.items():
        assert distribution in EXTRAS[extra], (module, extra)
    for extra in ('fleet', 'qp', 'sim', 'replay'):
        assert extra in EXTRAS
    with open(os.path.join(ROOT, 'setup.py'), encoding='utf-8') as f:
        setup = ast.parse(f.read())
    call = next(node for node in ast.walk(setup) if isinstance(node, ast.Call)
                and getattr(node.func, 'id', '') == 'setup')
    extras = next(k.value for k in call.keywords if k.arg == 'extras_require')
    assert 'extras.py' in ast.unparse(extras)      # read from the one table, not a copy
