# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A fleet's manifest: what it may say is checked, and each refusal names the row or column."""

import os
import shutil
import sys

import pytest

from spatial_dynamics.fleet import command
from spatial_dynamics.fleet.manifest import (LISTED_TWICE, ManifestError, NAME_RULE,
                                             read_manifest, robot_name)

sys.path.insert(0, os.path.dirname(__file__))
from conftest import robot_urdf_path  # noqa: E402


@pytest.fixture
def urdf(tmp_path):
    """Copy a robot's URDF into the manifest's folder; return its name there."""
    shutil.copy(robot_urdf_path('ur5'), tmp_path / 'ur5.urdf')
    return 'ur5.urdf'


def refused(tmp_path, name, text, encoding='utf-8'):
    path = tmp_path / name
    path.write_bytes(text.encode(encoding))
    with pytest.raises(ManifestError) as err:
        read_manifest(str(path))
    return str(err.value)


def bags_of(tmp_path, name, text, encoding='utf-8'):
    path = tmp_path / name
    path.write_bytes(text.encode(encoding))
    tasks, _ = read_manifest(str(path))
    return [(t.robot, os.path.basename(t.bag)) for t in tasks]


# -- CSV -------------------------------------------------------------------------------------

def test_a_csv_without_a_bag_column_is_refused_naming_it(tmp_path, urdf):
    err = refused(tmp_path, 'm.csv', f'robot,urdf\nr01,{urdf}\n')
    assert "no 'bag' column" in err


def test_a_csv_with_a_column_twice_is_refused_naming_it(tmp_path, urdf):
    err = refused(tmp_path, 'm.csv', f'robot,robot,urdf,bag\nr01,r02,{urdf},a.db3\n')
    assert "column 'robot' is in the header twice" in err


def test_a_csv_line_with_more_fields_than_its_header_is_refused_naming_its_line(
        tmp_path, urdf):
    err = refused(tmp_path, 'm.csv',
                  f'robot,urdf,bag\nr01,{urdf},a.db3\nr01,{urdf},b.db3,extra,fields\n')
    assert 'line 3: 5 fields where the header has 3' in err and 'None' not in err


def test_an_unknown_csv_column_is_refused_even_when_empty(tmp_path, urdf):
    err = refused(tmp_path, 'm.csv', f'robot,urdf,bag,topik\nr01,{urdf},a.db3,\n')
    assert "unknown column 'topik'" in err


def test_a_spreadsheets_csv_with_a_byte_order_mark_and_crlf_is_read(tmp_path, urdf):
    got = bags_of(tmp_path, 'm.csv', f'robot,urdf,bag\r\nr01,{urdf},a.db3\r\n',
                  encoding='utf-8-sig')
    assert got == [('r01', 'a.db3')]


# -- YAML ------------------------------------------------------------------------------------

@pytest.mark.parametrize('bags', ['[1]', '[null]', '[{a: b}]', '{a: b}'])
def test_a_yaml_bag_that_is_not_a_path_is_refused_naming_the_row(tmp_path, urdf, bags):
    err = refused(tmp_path, 'm.yaml', f'- {{robot: r01, urdf: {urdf}, bags: [a.db3]}}\n'
                  f'- {{robot: r02, urdf: {urdf}, bags: {bags}}}\n')
    assert 'robot 2: ' in err and 'bag' in err


@pytest.mark.parametrize('entry, key', [
    ('{robot: r01, urdf: U, bags: [a.db3], topic: /js}', "'topic' (an option goes under"),
    ('{robot: r01, urdf: U, bags: [a.db3], optionz: {topic: /js}}', "'optionz'"),
    ('{robot: r01, urdf: U, bag: a.db3, bags: [b.db3]}', 'bag and bags')])
def test_an_unknown_yaml_key_is_refused_as_an_unknown_csv_column_is(
        tmp_path, urdf, entry, key):
    err = refused(tmp_path, 'm.yaml', '- ' + entry.replace('U', urdf) + '\n')
    assert 'robot 1: ' in err and key in err


def test_an_unknown_top_level_yaml_key_is_refused(tmp_path, urdf):
    err = refused(tmp_path, 'm.yaml',
                  f'topic: /js\nrobots:\n- {{robot: r01, urdf: {urdf}, bags: [a.db3]}}\n')
    assert "unknown key 'topic'" in err


def test_a_yaml_key_given_twice_is_refused_naming_it(tmp_path, urdf):
    err = refused(tmp_path, 'm.yaml', f'- {{robot: r01, robot: r02, urdf: {urdf}, '
                  'bags: [a.db3]}\n')
    assert "key 'robot' is given twice" in err and 'line 1' in err


@pytest.mark.parametrize('name', ['[a]', 'yes', '1.0e+3', '12', '{a: b}'])
def test_a_yaml_robot_name_that_is_not_text_is_refused(tmp_path, urdf, name):
    err = refused(tmp_path, 'm.yaml', f'- {{robot: {name}, urdf: {urdf}, bags: [a.db3]}}\n')
    assert 'robot 1: robot name' in err and 'not text' in err


def test_a_quoted_yaml_name_and_a_shared_list_of_bags_are_read(tmp_path, urdf):
    got = bags_of(tmp_path, 'm.yaml', f"- {{robot: '12', urdf: {urdf}, bags: &b [a.db3]}}\n"
                  f'- {{robot: r02, urdf: {urdf}, bags: *b}}\n')
    assert got == [('12', 'a.db3'), ('r02', 'a.db3')]


# -- names: the rule is what the message says -------------------------------------------------

@pytest.mark.parametrize('name', ['r01 ', ' r01', '-rf', '.hidden', 'r*', 'r,01', 'r"01',
                                  'r.01', 'r01\u200b', 'r\u030101', '', 'r' * 65, '_r'])
def test_a_robot_name_outside_the_rule_is_refused_with_the_rule(name):
    with pytest.raises(ManifestError) as err:
        robot_name(name, 'row 1')
    assert str(err.value).startswith('row 1: robot name') and NAME_RULE in str(err.value)


@pytest.mark.parametrize('name', ['r01', 'R-2_b', '7', 'röbot_ü日本', 'r' * 64])
def test_a_robot_name_within_the_rule_is_kept_as_written(name):
    assert robot_name(name, 'row 1') == name


def test_the_rule_says_what_robot_name_checks():
    # letters of any script, digits, - and _, a letter or digit first, at most 64
    assert 'letters' in NAME_RULE and 'digits' in NAME_RULE and '- and _' in NAME_RULE
    assert 'starting with a letter or digit' in NAME_RULE and '64' in NAME_RULE


# -- one robot, one URDF ---------------------------------------------------------------------

def test_one_robot_name_with_two_different_urdfs_is_refused_naming_both_rows(tmp_path, urdf):
    shutil.copy(robot_urdf_path('panda'), tmp_path / 'panda.urdf')
    err = refused(tmp_path, 'm.csv',
                  f'robot,urdf,bag\nr01,{urdf},a.db3\nr02,{urdf},b.db3\nr01,panda.urdf,c.db3\n')
    assert 'line 4: ' in err and 'line 2' in err and 'one URDF' in err


def test_one_robot_name_with_two_sets_of_options_is_refused_naming_both_rows(tmp_path, urdf):
    err = refused(tmp_path, 'm.csv', f'robot,urdf,bag,threshold\nr01,{urdf},a.db3,0.01\n'
                  f'r01,{urdf},b.db3,0.1\n')
    assert 'line 3: ' in err and 'line 2' in err and 'threshold' in err


def test_one_robot_in_two_rows_with_the_same_urdf_has_the_bags_of_both(tmp_path, urdf):
    shutil.copy(tmp_path / urdf, tmp_path / 'copy.urdf')        # the same bytes
    got = bags_of(tmp_path, 'm.csv', f'robot,urdf,bag,topic\nr01,{urdf},a.db3,/a\n'
                  f'r01,copy.urdf,b.db3,/b\n')
    assert got == [('r01', 'a.db3'), ('r01', 'b.db3')]


# -- one bag, whatever its paths -------------------------------------------------------------

def test_a_bag_by_its_directory_its_db3_a_hard_link_and_a_symlink_is_one_bag(tmp_path, urdf):
    bag = tmp_path / 'day01'
    bag.mkdir()
    (bag / 'metadata.yaml').write_text('rosbag2_bagfile_information: {}\n')
    (bag / 'day01_0.db3').write_bytes(b'SQLite format 3\0')
    os.link(bag / 'day01_0.db3', tmp_path / 'hard.db3')
    os.symlink(bag / 'day01_0.db3', tmp_path / 'soft.db3')
    (tmp_path / 'other.db3').write_bytes(b'SQLite format 3\0')      # the same bytes: a bag
    path = tmp_path / 'm.csv'
    path.write_text(f'robot,urdf,bag\nr01,{urdf},day01\nr01,{urdf},day01/day01_0.db3\n'
                    f'r01,{urdf},hard.db3\nr01,{urdf},soft.db3\nr01,{urdf},other.db3\n')
    tasks, notes, _ = command.tasks_of(str(path), None)
    assert [os.path.basename(t.bag) for t in tasks] == ['day01', 'other.db3']
    lines = command.noted(notes)
    assert len(lines) == 1 and lines[0].startswith(f'note: {LISTED_TWICE} (3): ')
    assert all(f'line {k}' in lines[0] for k in (3, 4, 5))


def test_twenty_thousand_repeated_rows_are_one_note_line(tmp_path, urdf):
    (tmp_path / 'a.db3').write_bytes(b'SQLite format 3\0')
    path = tmp_path / 'm.csv'
    path.write_text('robot,urdf,bag\n' + f'r01,{urdf},a.db3\n' * 20000)
    tasks, notes, _ = command.tasks_of(str(path), None)
    assert len(tasks) == 1 and len(notes) == 19999
    lines = command.noted(notes)
    assert len(lines) == 1 and lines[0].endswith(
        f'; and {19999 - command.NOTE_EXAMPLES} more')
