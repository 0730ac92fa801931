# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Every number option of every ``replay`` subcommand has a range, refused as a usage error.

``--window 1e308`` gave an OverflowError traceback (the window in samples, int(inf)), a
huge ``--threshold`` or ``--tolerance`` ran with meaningless results. Each value outside the
option's range (huge, NaN, inf, negative, zero where zero means nothing) is refused by the
parser: exit 2, the option named, before any file is read.
"""

import os
import sys

import pytest

sys.path.insert(0, os.path.dirname(__file__))
from conftest import robot_urdf_path  # noqa: E402

from spatial_dynamics.fleet.command import parser as fleet_parser  # noqa: E402
from spatial_dynamics.replay.__main__ import main, parser  # noqa: E402

UR5 = robot_urdf_path('ur5')
#: Each subcommand's positional arguments and required options but the model's.
HEADS = {'residual': ['b'], 'identify': ['b'], 'trajectory': ['p.yaml'],
         'annotate': ['p.yaml', '--out', 'o.yaml'],
         'excite': ['--duration', '10', '--out', 'o.yaml'], 'fleet': ['m.csv']}
#: The float options of each subcommand, and whether zero is a value they take.
FLOATS = {
    'residual': {'--window': False},
    'identify': {'--window': False, '--threshold': False},
    'trajectory': {'--rate': False, '--threshold': False},
    'annotate': {'--tolerance': False},
    'excite': {'--duration': False, '--period': False, '--margin': True,
               '--velocity-fraction': False, '--effort-fraction': False, '--rate': False},
    'fleet': {'--chunk': True, '--baseline-days': False},
}
BAD = ['1e308', '1e300', 'nan', 'inf', '-inf', '-1', '-1e-3', 'x']
CASES = [(command, option, value) for command, options in FLOATS.items()
         for option, zero in options.items() for value in BAD + ([] if zero else ['0'])]


def argv_of(command, option, value):
    """Return the argv of ``command`` with ``option=value`` (the URDF too where it is used).

    ``=``: argparse takes ``-inf`` or ``-1e-3`` after a space for an option, not a value.
    """
    model = [] if command == 'fleet' else ['--urdf', UR5]
    return [command] + HEADS[command] + model + [f'{option}={value}']


def refused(p, argv, capsys):
    """Parse ``argv`` with ``p`` expecting a usage error; return its last stderr line."""
    with pytest.raises(SystemExit) as exit:
        p.parse_args(argv)
    err = capsys.readouterr().err
    assert exit.value.code == 2, err
    assert 'Traceback' not in err
    return err.strip().splitlines()[-1]


@pytest.mark.parametrize('command, option, value', CASES)
def test_a_number_out_of_its_range_is_a_usage_error_naming_the_option(
        command, option, value, capsys):
    line = refused(parser(), argv_of(command, option, value), capsys)
    assert option in line and repr(value) in line, line


@pytest.mark.parametrize('command', ['residual', 'identify', 'trajectory', 'annotate',
                                     'excite'])
@pytest.mark.parametrize('values', [['0', '0', '1e308'], ['nan', '0', '-9.81'],
                                    ['0', 'inf', '-9.81'], ['0', '0', '-2000']])
def test_gravity_out_of_range_is_a_usage_error(command, values, capsys):
    argv = [command] + HEADS[command] + ['--urdf', UR5, '--gravity'] + values
    assert '--gravity' in refused(parser(), argv, capsys)


@pytest.mark.parametrize('value', ['1e308', 'nan', 'inf', '-1e6'])
def test_a_locked_value_out_of_range_is_a_usage_error(value, capsys):
    argv = ['residual', 'b', '--urdf', UR5, '--joints', 'elbow_joint', '--locked',
            f'wrist_1_joint={value}']
    assert '--locked' in refused(parser(), argv, capsys)


@pytest.mark.parametrize('option, value', [('--chunk', '1e300'), ('--baseline-days', 'nan')])
def test_the_fleet_command_alone_has_the_same_ranges(option, value, capsys):
    assert option in refused(fleet_parser(), ['m.csv', option, value], capsys)


@pytest.mark.parametrize('command, option, value', [
    ('residual', '--window', '10'), ('identify', '--threshold', '1e-9'),
    ('identify', '--threshold', '1000'), ('trajectory', '--rate', '1e6'),
    ('annotate', '--tolerance', '1e6'), ('excite', '--margin', '0'),
    ('fleet', '--chunk', '0'), ('excite', '--effort-fraction', '1')])
def test_the_ends_of_each_range_are_taken(command, option, value):
    args = parser().parse_args(argv_of(command, option, value))
    assert getattr(args, option[2:].replace('-', '_')) == float(value)


def test_a_huge_window_on_a_bag_is_refused_before_any_work(tmp_path, capsys):
    # the reported case: int(round(1e308 / period)) overflowed after the bag was read
    with pytest.raises(SystemExit) as exit:
        main(['residual', str(tmp_path / 'no_bag'), '--urdf', UR5, '--out',
              str(tmp_path / 'o'), '--window', '1e308'])
    err = capsys.readouterr().err
    assert exit.value.code == 2 and '--window' in err and 'Traceback' not in err
    assert not (tmp_path / 'o').exists()
