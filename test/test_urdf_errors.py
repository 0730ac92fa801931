# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Bad URDFs raise ValueError naming the offending element; hostile XML is harmless.

Also: missing meshes do not matter, and a string and a file give the same model.
"""

import os
import re
import resource
import subprocess
import sys
import textwrap

from conftest import robot_urdf_path
import numpy as np
import pytest
import spatial_dynamics as sd

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LIMIT = '<limit effort="10" velocity="1" lower="-1" upper="1"/>'
GOOD_INERTIA = '<inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/>'


def inertial(mass='1.0', inertia=GOOD_INERTIA):
    return f'<inertial><mass value="{mass}"/>{inertia}</inertial>'


def link(name, body=inertial()):
    return f'<link name="{name}">{body}</link>'


def joint(name, parent, child, kind='revolute', axis='0 0 1', extra=''):
    axis_xml = f'<axis xyz="{axis}"/>' if axis is not None else ''
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/>'
            f'<child link="{child}"/>{axis_xml}{LIMIT}{extra}</joint>')


def robot(*elements):
    return '<?xml version="1.0"?>\n<robot name="bad">' + ''.join(elements) + '</robot>'


def arm(*extra, upper_body=inertial(), elbow_axis='0 1 0', elbow_kind='revolute'):
    """Return a valid 2-joint arm: base, shoulder, upper_arm, elbow, forearm; plus extras."""
    return robot(link('base'), link('upper_arm', upper_body), link('forearm'),
                 joint('shoulder', 'base', 'upper_arm'),
                 joint('elbow', 'upper_arm', 'forearm', kind=elbow_kind, axis=elbow_axis),
                 *extra)


def test_the_template_is_valid():
    model = sd.Model.from_urdf(arm())
    assert model.joint_names == ('shoulder', 'elbow')


CASES = {
    'malformed_xml': ('<robot name="bad"><link name="base"></robot>', None),
    'not_a_robot': ('<launch><node name="x"/></launch>', None),
    'empty_robot': ('<robot name="bad"/>', None),
    'unknown_parent_link': (arm(link('hand'), joint('wrist', 'ghost_link', 'hand')),
                            'wrist|ghost_link'),
    'unknown_child_link': (arm(joint('wrist', 'forearm', 'phantom_link')),
                           'wrist|phantom_link'),
    'cycle': (robot(link('cyc_a'), link('cyc_b'), link('cyc_c'),
                    joint('cyc_j1', 'cyc_a', 'cyc_b'), joint('cyc_j2', 'cyc_b', 'cyc_c'),
                    joint('cyc_j3', 'cyc_c', 'cyc_a')), 'cyc_'),
    'cycle_below_a_root': (robot(link('base'), link('loop_a'), link('loop_b'),
                                 joint('into_loop', 'base', 'loop_a'),
                                 joint('loop_j1', 'loop_a', 'loop_b'),
                                 joint('loop_j2', 'loop_b', 'loop_a')), 'loop_'),
    'two_parents': (arm(link('hand'), joint('wrist_a', 'forearm', 'hand'),
                        joint('wrist_b', 'upper_arm', 'hand')), 'hand|wrist_a|wrist_b'),
    'several_roots': (arm(link('stray_root'), link('stray_child'),
                          joint('stray_joint', 'stray_root', 'stray_child')), 'stray_root'),
    'negative_mass': (arm(upper_body=inertial('-1.0')), 'upper_arm'),
    'nan_mass': (arm(upper_body=inertial('nan')), 'upper_arm'),
    'inf_mass': (arm(upper_body=inertial('inf')), 'upper_arm'),
    'nan_inertia': (arm(upper_body=inertial(inertia='<inertia ixx="nan" ixy="0" ixz="0" '
                                            'iyy="1" iyz="0" izz="1"/>')), 'upper_arm'),
    'zero_axis': (arm(elbow_axis='0 0 0'), 'elbow'),
    'nan_axis': (arm(elbow_axis='nan 0 1'), 'elbow'),
    'nan_origin': (arm(link('hand'), '<joint name="wrist" type="fixed"><parent link="forearm"/>'
                       '<child link="hand"/><origin xyz="0 nan 0" rpy="0 0 0"/></joint>'),
                   'wrist'),
    'mimic_of_missing_joint': (arm(link('finger'), joint('finger_joint', 'forearm', 'finger',
                                                         extra='<mimic joint="ghost_joint"/>')),
                               'finger_joint|ghost_joint'),
    'floating_joint': (arm(elbow_kind='floating', elbow_axis=None), 'elbow'),
    'planar_joint': (arm(elbow_kind='planar'), 'elbow'),
}


# Physically inconsistent but computable: loaded as written with a URDFWarning by default,
# refused in strict mode; (URDF, the element and the problem the message must name).
INCONSISTENT = {
    'non_psd_inertia': (arm(upper_body=inertial(inertia='<inertia ixx="1" ixy="2" ixz="0" '
                                                'iyy="1" iyz="0" izz="1"/>')),
                        "link 'upper_arm'.*not positive semi-definite"),
    'negative_inertia': (arm(upper_body=inertial(inertia='<inertia ixx="-0.1" ixy="0" ixz="0" '
                                                 'iyy="0.1" iyz="0" izz="0.1"/>')),
                         "link 'upper_arm'.*not positive semi-definite"),
    'triangle_inequality': (arm(upper_body=inertial(inertia='<inertia ixx="1" ixy="0" ixz="0" '
                                                    'iyy="1" iyz="0" izz="3"/>')),
                            "link 'upper_arm'.*triangle inequality"),
}


@pytest.mark.parametrize('case', list(INCONSISTENT))
def test_inconsistent_urdf_raises_in_strict_mode(case):
    urdf, message = INCONSISTENT[case]
    with pytest.raises(ValueError, match=message):
        sd.Model.from_urdf(urdf, strict=True)


@pytest.mark.parametrize('case', list(INCONSISTENT))
def test_inconsistent_urdf_loads_with_a_warning_naming_it(case):
    urdf, message = INCONSISTENT[case]
    with pytest.warns(sd.URDFWarning, match=message):
        model = sd.Model.from_urdf(urdf)
    assert len(model.warnings) == 1 and re.search(message, model.warnings[0])


@pytest.mark.parametrize('case', list(CASES))
def test_bad_urdf_raises_value_error_naming_the_element(case):
    urdf, name = CASES[case]
    with pytest.raises(ValueError, match=name) as info:
        sd.Model.from_urdf(urdf)
    assert str(info.value).strip()


@pytest.mark.parametrize('case', ['negative_mass', 'zero_axis', 'floating_joint', 'cycle'])
def test_bad_urdf_file_raises_too(case, tmp_path):
    urdf, name = CASES[case]
    path = tmp_path / 'bad.urdf'
    path.write_text(urdf)
    with pytest.raises(ValueError, match=name):
        sd.Model.from_urdf(str(path))


def test_missing_file_raises_value_error(tmp_path):
    with pytest.raises((ValueError, FileNotFoundError, OSError), match='nope.urdf'):
        sd.Model.from_urdf(str(tmp_path / 'nope.urdf'))


# --------------------------------------------------------------------------------------------
# Hostile XML


def model_text(model):
    """Return every name and repr a loaded model exposes, to search for leaked content."""
    parts = [repr(model), model.name, *model.joint_names, *model.body_names,
             *model.body_joints, *model.frames]
    return '\n'.join(str(p) for p in parts)


SECRET = 'TOPSECRET-4242-do-not-leak'


@pytest.mark.parametrize('where', ['joint_name', 'link_name', 'robot_name'])
def test_external_entity_does_not_leak_a_local_file(tmp_path, where):
    secret = tmp_path / 'secret.txt'
    secret.write_text(SECRET)
    uri = secret.as_uri()
    names = {'joint_name': 'shoulder', 'link_name': 'upper_arm', 'robot_name': 'bad'}
    urdf = arm().replace(f'name="{names[where]}"', f'name="{names[where]}&xxe;"', 1)
    if where == 'link_name':
        urdf = urdf.replace('<child link="upper_arm"/>', '<child link="upper_arm&xxe;"/>')
    urdf = urdf.replace('<robot', f'<!DOCTYPE robot [<!ENTITY xxe SYSTEM "{uri}">]>\n<robot')
    for source in (urdf, str(tmp_path / 'xxe.urdf')):
        (tmp_path / 'xxe.urdf').write_text(urdf)
        try:
            model = sd.Model.from_urdf(source)
        except ValueError:
            continue
        assert 'TOPSECRET' not in model_text(model)


def test_external_parameter_entity_does_not_leak(tmp_path):
    """An external DTD defining an entity used in a name: must not be fetched."""
    dtd = tmp_path / 'evil.dtd'
    dtd.write_text(f'<!ENTITY leak "{SECRET}">')
    urdf = arm().replace('name="shoulder"', 'name="shoulder&leak;"')
    urdf = urdf.replace('<robot', f'<!DOCTYPE robot [<!ENTITY % ext SYSTEM "{dtd.as_uri()}"> '
                        '%ext;]>\n<robot')
    try:
        model = sd.Model.from_urdf(urdf)
    except ValueError:
        return
    assert 'TOPSECRET' not in model_text(model)


def test_external_dtd_is_not_fetched(tmp_path):
    dtd = tmp_path / 'evil.dtd'
    dtd.write_text(f'<!ENTITY leak "{SECRET}">')
    urdf = arm().replace('name="shoulder"', 'name="shoulder&leak;"')
    urdf = urdf.replace('<robot', f'<!DOCTYPE robot SYSTEM "{dtd.as_uri()}">\n<robot')
    try:
        model = sd.Model.from_urdf(urdf)
    except ValueError:
        return
    assert 'TOPSECRET' not in model_text(model)


BILLION_LAUGHS = textwrap.dedent('''\
    <?xml version="1.0"?>
    <!DOCTYPE robot [
     <!ENTITY lol "lol">
     <!ENTITY lol1 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">
     <!ENTITY lol2 "&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;&lol1;">
     <!ENTITY lol3 "&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;">
     <!ENTITY lol4 "&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;&lol3;">
     <!ENTITY lol5 "&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;&lol4;">
     <!ENTITY lol6 "&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;&lol5;">
     <!ENTITY lol7 "&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;&lol6;">
     <!ENTITY lol8 "&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;&lol7;">
     <!ENTITY lol9 "&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;&lol8;">
    ]>
    <robot name="&lol9;"><link name="base"/><link name="arm"/>
    <joint name="j&lol9;" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="0 0 1"/><limit effort="1" velocity="1" lower="-1" upper="1"/></joint></robot>
''')

# Many references to one big entity (quadratic blowup): no nesting, ~100 MB when expanded.
QUADRATIC = ('<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY big "' + 'x' * 20000 + '">]>\n'
             '<robot name="' + '&big;' * 5000 + '"><link name="base"/></robot>\n')

BOMB_SCRIPT = textwrap.dedent('''\
    import sys
    import spatial_dynamics as sd
    source = sys.stdin.read()
    if sys.argv[1] == 'file':
        with open(sys.argv[2], 'w') as f:
            f.write(source)
        source = sys.argv[2]
    try:
        model = sd.Model.from_urdf(source)
    except ValueError as e:
        print('VALUEERROR', str(e)[:200])
    else:
        print('LOADED', len(repr(model)), max(len(n) for n in model.joint_names))
''')


def _limit_memory():
    # 4 GiB of address space: an expanding bomb fails instead of swapping the machine to death.
    resource.setrlimit(resource.RLIMIT_AS, (4 << 30, 4 << 30))


@pytest.mark.parametrize('bomb', [BILLION_LAUGHS, QUADRATIC], ids=['billion_laughs', 'quadratic'])
@pytest.mark.parametrize('how', ['string', 'file'])
def test_entity_bomb_fails_quickly_with_value_error(bomb, how, tmp_path):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [ROOT] + [p for p in os.environ.get('PYTHONPATH', '').split(os.pathsep) if p]))
    proc = subprocess.run([sys.executable, '-c', BOMB_SCRIPT, how, str(tmp_path / 'bomb.urdf')],
                          input=bomb, capture_output=True, text=True, timeout=20, env=env,
                          preexec_fn=_limit_memory)
    assert proc.stdout.startswith('VALUEERROR'), (proc.stdout[:500], proc.stderr[-2000:])


# --------------------------------------------------------------------------------------------
# Meshes are never loaded; string and file give the same model


def with_meshes(urdf):
    geometry = ''.join(
        f'<{kind}><origin xyz="0 0 0" rpy="0 0 0"/><geometry><mesh filename="{uri}" '
        f'scale="1 1 1"/></geometry></{kind}>'
        for kind, uri in [('visual', 'package://nonexistent/meshes/x.stl'),
                          ('collision', 'package://nonexistent/meshes/x_collision.stl'),
                          ('visual', 'file:///nonexistent/dir/y.dae'),
                          ('collision', 'meshes/relative/z.obj')])
    return urdf.replace('</inertial></link>', '</inertial>' + geometry + '</link>')


def test_missing_meshes_load(tmp_path, rng):
    plain = arm(link('hand', inertial('0.3')), joint('wrist', 'forearm', 'hand', axis='1 0 0'))
    meshy = with_meshes(plain)
    assert meshy.count('<mesh') >= 8
    path = tmp_path / 'meshy.urdf'
    path.write_text(meshy)
    reference = sd.Model.from_urdf(plain)
    q, qd, qdd = rng.normal(size=(3, 4, 3))
    expected = sd.rnea(reference, q, qd, qdd)
    for source in (meshy, str(path)):
        model = sd.Model.from_urdf(source)
        assert model.joint_names == reference.joint_names
        np.testing.assert_array_equal(sd.rnea(model, q, qd, qdd), expected)


@pytest.mark.parametrize('name', ['panda', 'talos'])
def test_string_and_path_give_the_same_model(name, rng):
    path = robot_urdf_path(name)
    with open(path, encoding='utf-8') as f:
        text = f.read()
    from_path, from_text = sd.Model.from_urdf(path), sd.Model.from_urdf(text)
    assert from_path.joint_names == from_text.joint_names
    assert from_path.body_names == from_text.body_names
    n = len(from_path.joint_names)
    q, qd, qdd = rng.normal(size=(3, 5, n))
    f_ext = {from_path.body_names[-1]: rng.normal(size=6)}
    np.testing.assert_array_equal(sd.rnea(from_path, q, qd, qdd, f_ext=f_ext),
                                  sd.rnea(from_text, q, qd, qdd, f_ext=f_ext))
    for key in ('parent', 'jtype', 'axis', 'Xtree', 'inertia', 'qidx', 'qmul', 'qoff'):
        np.testing.assert_array_equal(getattr(from_path, key), getattr(from_text, key))
    bytes_model = sd.Model.from_urdf(text.encode('utf-8'))
    assert bytes_model.joint_names == from_path.joint_names
    import pathlib
    assert sd.Model.from_urdf(pathlib.Path(path)).joint_names == from_path.joint_names


# --------------------------------------------------------------------------------------------
# Files: only regular files of bounded size are read; bytes are XML, never a path

def test_a_fifo_is_refused_without_blocking(tmp_path):
    fifo = tmp_path / 'robot.urdf'
    os.mkfifo(fifo)       # no writer: an open() without O_NONBLOCK would hang here
    with pytest.raises(ValueError, match='not a regular file'):
        sd.Model.from_urdf(str(fifo))


@pytest.mark.parametrize('path', ['/dev/zero', '/'])
def test_devices_and_directories_are_refused(path):
    with pytest.raises(ValueError, match=f"{path!r}.*not a regular file"):
        sd.Model.from_urdf(path)


def test_a_file_over_the_size_limit_is_refused(tmp_path):
    from spatial_dynamics.urdf import read_urdf_file
    path = tmp_path / 'big.urdf'
    path.write_bytes(b' ' * 1001)
    with pytest.raises(ValueError, match='too large'):
        read_urdf_file(str(path), limit=1000)
    assert read_urdf_file(str(path), limit=1001) == b' ' * 1001


def test_bytes_are_xml_never_a_path(tmp_path):
    path = tmp_path / 'arm.urdf'
    path.write_text(arm())
    with pytest.raises(ValueError, match='malformed URDF XML'):
        sd.Model.from_urdf(str(path).encode())
    assert sd.Model.from_urdf(arm().encode()).joint_names == ('shoulder', 'elbow')


def test_a_file_that_is_not_utf8_is_a_value_error(tmp_path):
    path = tmp_path / 'latin.urdf'
    path.write_bytes(arm().replace('name="bad"', 'name="b\xe4d"').encode('latin-1'))
    with pytest.raises(ValueError, match='malformed URDF XML'):
        sd.Model.from_urdf(str(path))


def test_without_lxml_the_loader_says_what_to_install():
    """The package imports without lxml; loading a URDF says to install it, in one sentence."""
    code = ('import sys; sys.modules["lxml"] = None; sys.modules["lxml.etree"] = None\n'
            'import spatial_dynamics as sd\n'
            'try:\n'
            '    sd.Model.from_urdf("<robot name=\\"r\\"><link name=\\"a\\"/></robot>")\n'
            'except ModuleNotFoundError as err:\n'
            '    print(err)\n')
    import subprocess
    import sys
    run = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                         cwd=os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    assert run.returncode == 0, run.stderr
    assert 'needs lxml' in run.stdout and 'pip install lxml' in run.stdout, run.stdout
