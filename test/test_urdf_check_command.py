# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The dynamics check of a robot description (``python -m spatial_dynamics.check``).

What it prints is compared with the model and with the URDF read independently here
(xml.etree): joint order, mimic multipliers, lumped links, total mass, warnings.
"""

import importlib.metadata
import os
import re
import subprocess
import sys
import warnings
import xml.etree.ElementTree as ET

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from conftest import robot_urdf_path  # noqa: E402
from node_harness import DEMO_URDF, PACKAGE, ROOT  # noqa: E402
import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics.check import main  # noqa: E402

#: bin/: the installed name of ``python -m spatial_dynamics.check``
COMMAND = 'spatial_dynamics_check'

BAD_INERTIA = """<robot name="bad">
  <link name="base"/>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="arm"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="10" velocity="2"/>
  </joint>
  <link name="arm">
    <inertial>
      <origin xyz="0.1 0 0"/><mass value="2"/>
      <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="3"/>
    </inertial>
  </link>
</robot>
"""


def run(capsys, *argv):
    """Run the check in this process; return (exit status, stdout, stderr)."""
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


def section(out, title):
    """Return the lines under the heading starting with ``title``, up to a blank line."""
    lines = out.splitlines()
    start = next(k for k, line in enumerate(lines) if line.startswith(title))
    end = next((k for k in range(start, len(lines)) if not lines[k].strip()), len(lines))
    return lines[start + 1:end]


def printed_joints(out):
    """Return the joint names of the joint table, in printed order (header and notes skipped)."""
    rows = [line.split() for line in section(out, 'joints in q order')]
    return [r[1] for r in rows[1:] if r[0].isdigit()]


def printed_bodies(out):
    """Map each body link to the links printed as lumped into (or pruned onto) it."""
    bodies, last, note = {}, None, None
    for line in section(out, 'bodies after lumping')[1:]:
        row = line.split()
        if row[0].isdigit():
            last, note = row[1], None
            bodies[last] = []
            continue
        text = line.strip()
        if text.startswith(('lumped:', 'pruned (fixed to the base):')):
            note, text = True, text.split(':', 1)[1]
        assert note, line
        bodies[last] += [n.strip() for n in text.split(',') if n.strip()]
    return bodies


def printed_mass(out):
    """Return the total mass printed (kg)."""
    return float(re.search(r'^total mass: (\S+) kg', out, re.M).group(1))


def urdf_facts(path):
    """Read from the XML alone: total mass, mimic joints and the body link of every fixed link."""
    root = ET.parse(path).getroot()
    mass = sum(float(m.get('value')) for m in root.findall('link/inertial/mass'))
    joints = root.findall('joint')
    mimic = {j.get('name'): (j.find('mimic').get('joint'),
                             float(j.find('mimic').get('multiplier', '1')),
                             float(j.find('mimic').get('offset', '0')))
             for j in joints if j.find('mimic') is not None}
    parent_joint = {j.find('child').get('link'): j for j in joints}
    onto = {}   # link -> the link of the body it is lumped into (the root: pruned)
    for link in (li.get('name') for li in root.findall('link')):
        body = link
        while body in parent_joint and parent_joint[body].get('type') == 'fixed':
            body = parent_joint[body].find('parent').get('link')
        if body != link:
            onto[link] = body
    return mass, mimic, onto


@pytest.fixture
def bad_inertia(tmp_path):
    """Write a URDF whose link 'arm' breaks the triangle inequality (1 + 1 < 3)."""
    path = tmp_path / 'bad_inertia.urdf'
    path.write_text(BAD_INERTIA)
    return path


@pytest.mark.parametrize('robot', ['demo_arm', 'panda', 'ur5'])
def test_joints_bodies_and_mass_agree_with_the_model_and_the_urdf(capsys, robot):
    path = DEMO_URDF if robot == 'demo_arm' else robot_urdf_path(robot)
    model = sd.Model.from_urdf(path)
    status, out, err = run(capsys, path)
    assert status == 0 and err == ''
    assert out.startswith(f'robot {model.name!r}: {model.nq} dof')
    assert printed_joints(out) == list(model.joint_names)
    mass, mimic, onto = urdf_facts(path)
    assert printed_mass(out) == pytest.approx(mass, rel=1e-5)
    bodies = printed_bodies(out)
    assert list(bodies) == list(model.body_names)
    assert {(link, body) for body, links in bodies.items() for link in links} == \
        set(onto.items())
    for name, (source, multiplier, offset) in mimic.items():
        assert (f'mimic: {name} = {multiplier:g} * {source} '
                f'{"-" if offset < 0 else "+"} {abs(offset):g}') in out
    if robot == 'panda':  # the hand and its tcp are lumped into link 7, the finger mimics
        assert set(bodies['panda_link7']) == {'panda_link8', 'panda_hand', 'panda_hand_tcp'}
        assert 'panda_finger_joint2' in mimic


def test_joint_types_axes_and_limits_are_printed(capsys):
    status, out, _ = run(capsys, DEMO_URDF)
    rows = {r[1]: r for r in (line.split() for line in section(out, 'joints in q order'))
            if r[0].isdigit()}
    root = ET.parse(DEMO_URDF).getroot()
    for joint in root.findall('joint'):
        name = joint.get('name')
        if name not in rows:
            continue
        row, limit = rows[name], joint.find('limit')
        assert row[2] == joint.get('type')
        axis = [float(x) for x in joint.find('axis').get('xyz').split()]
        norm = sum(x * x for x in axis) ** 0.5
        assert [float(x) for x in row[3:6]] == pytest.approx([x / norm for x in axis],
                                                             abs=1e-6)
        for k, attr in enumerate(('lower', 'upper', 'velocity', 'effort')):
            given = limit.get(attr) if joint.get('type') != 'continuous' or k >= 2 else None
            assert row[6 + k] == ('-' if given is None else f'{float(given):g}'), (name, attr)
    assert rows['joint7'][2] == 'continuous' and rows['joint7'][6:8] == ['-', '-']


def test_inconsistent_inertia_loads_with_the_warning_and_fails_strict(capsys, bad_inertia):
    model = pytest.warns(sd.URDFWarning, sd.Model.from_urdf, str(bad_inertia))
    assert len(model.warnings) == 1
    status, out, err = run(capsys, bad_inertia)
    assert status == 0 and err == ''
    warning = section(out, 'warnings (1)')
    assert warning[0].startswith("  - link 'arm'") and 'triangle' in ' '.join(warning)
    assert printed_mass(out) == pytest.approx(2.0)
    status, strict_out, err = run(capsys, bad_inertia, '--strict')
    assert status == 1 and strict_out == out    # every problem is still printed
    assert err.startswith('error: 1 warning')


def test_consistent_robot_says_no_warnings_and_passes_strict(capsys):
    status, out, _ = run(capsys, DEMO_URDF, '--strict', '--joints', 'joint1', 'joint2')
    model = sd.Model.from_urdf(DEMO_URDF, joints=['joint1', 'joint2'])
    assert model.warnings == ()
    assert status == 0 and out.rstrip().endswith('no warnings')


def test_warning_is_printed_once_by_the_command_not_by_python(bad_inertia):
    proc = subprocess.run([sys.executable, '-m', 'spatial_dynamics.check', str(bad_inertia)],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0 and proc.stderr == ''
    assert proc.stdout.count('triangle') == 1


@pytest.mark.parametrize('xml, named', [
    ('<robot name="r"><link name="a"/><joint name="j" type="revolute"><parent link="a"/>'
     '<child link="nowhere"/><axis xyz="0 0 1"/></joint></robot>', "'nowhere'"),
    ('<robot name="r"><link name="a"><inertial><mass value="-1"/></inertial></link></robot>',
     "link 'a'"),
    ('<robot name="r"><link name="a"/>', 'malformed'),
])
def test_refused_description_exits_1_with_the_element_named(capsys, tmp_path, xml, named):
    path = tmp_path / 'broken.urdf'
    path.write_text(xml)
    status, out, err = run(capsys, path)
    assert status == 1 and out == ''
    assert err.startswith('error: ') and named in err and 'Traceback' not in err


def test_missing_file_and_directory_exit_1(capsys, tmp_path):
    missing = tmp_path / 'nothing.urdf'
    status, out, err = run(capsys, missing)
    assert (status, out, err) == (1, '', f'error: {str(missing)!r}: no such file\n')
    status, out, err = run(capsys, tmp_path)
    assert (status, out) == (1, '') and 'not a regular file' in err


@pytest.mark.parametrize('argv', [[], ['--locked', 'joint1'], ['--locked', 'joint1=x'],
                                  ['--locked', 'joint1=1'], ['--no-such-option']])
def test_bad_usage_exits_2(capsys, argv):
    with pytest.raises(SystemExit) as exit_:
        main(([DEMO_URDF] if argv else []) + argv)
    assert exit_.value.code == 2
    assert 'usage:' in capsys.readouterr().err


def test_joints_keep_the_listed_order_and_lock_the_others(capsys):
    path = robot_urdf_path('panda')
    kept = ['panda_joint4', 'panda_joint2', 'panda_finger_joint1']
    status, out, _ = run(capsys, path, '--joints', *kept, '--locked', 'panda_joint1=0.5')
    assert status == 0
    assert printed_joints(out) == kept
    assert 'mimic: panda_finger_joint2 = 1 * panda_finger_joint1 + 0' in out
    locked = re.search(r'locked by model reduction: (.*?)\n\n', out, re.S).group(1)
    assert {item.strip() for item in locked.split(',')} == \
        {'panda_joint1=0.5'} | {f'panda_joint{k}=0' for k in (3, 5, 6, 7)}
    mass, _, _ = urdf_facts(path)
    assert printed_mass(out) == pytest.approx(mass, rel=1e-5)   # reduction keeps every mass
    bodies = printed_bodies(out)
    # panda_link2 hangs on joint 2; joint 3 is locked, so link3 (and nothing past joint 4) is
    # lumped into it, and link1 is fixed to the base by the locked joint 1.
    assert bodies['panda_link2'] == ['panda_link3']
    assert 'panda_link1' in bodies['panda_link0']
    status, _, err = run(capsys, path, '--joints', 'panda_finger_joint2')
    assert status == 1 and "'panda_finger_joint2'" in err


def test_no_command_of_ours_shares_a_name_with_another_package():
    """Each command in bin/ has a name no installed distribution's executable has.

    urdfdom (cmeel-urdfdom, a dependency of Pinocchio) installs ``check_urdf``: a command of
    that name in the same venv's bin/ was urdfdom's for whoever came first on PATH.
    """
    ours = set(os.listdir(os.path.join(ROOT, 'bin')))
    theirs = {}
    for dist in importlib.metadata.distributions():
        name = dist.metadata['Name']
        if name.lower().replace('-', '_') == PACKAGE:
            continue
        scripts = {e.name for e in dist.entry_points
                   if e.group in ('console_scripts', 'gui_scripts')}
        scripts |= {f.name for f in dist.files or () if 'bin' in f.parts[:-1]}
        for script in scripts & ours:
            theirs[script] = name
    assert not theirs, f'commands of ours that other packages install too: {theirs}'
    venv_bin = os.path.dirname(sys.executable)
    for name in ours:
        path = os.path.join(venv_bin, name)
        if os.path.exists(path):    # ours, from a pip install into this venv
            with open(path, encoding='utf-8', errors='replace') as f:
                assert 'spatial_dynamics' in f.read(), f'{path} is another package\'s'


def test_installed_executable_runs(install):
    executable = os.path.join(install.prefix, 'lib', PACKAGE, COMMAND)
    assert os.access(executable, os.X_OK)
    proc = subprocess.run([executable, DEMO_URDF], env=install.env(), capture_output=True,
                          text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert printed_joints(proc.stdout) == list(sd.Model.from_urdf(DEMO_URDF).joint_names)
    proc = subprocess.run([executable, DEMO_URDF + '.missing'], env=install.env(),
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 1 and proc.stderr.startswith('error: ')


def test_what_the_model_loads_check_urdf_reports(tmp_path, capsys):
    """Whitespace before the XML declaration or version 1.1 loads, so the check reports it.

    The joint types come from the model (the parser's record), not from a second parse of the
    file, which refused what the parser accepts and ended in a traceback.
    """
    path = tmp_path / 'ws.urdf'
    path.write_text('  <?xml version="1.1"?>\n<robot name="r"><link name="a"/><link name="b"/>'
                    '<joint name="j" type="continuous"><parent link="a"/><child link="b"/>'
                    '</joint></robot>\n')
    status, out, err = run(capsys, str(path))
    assert status == 0 and err == '', err
    assert re.search(r'^\s+0\s+j\s+continuous\s', out, re.M), out


@pytest.mark.parametrize('robot', ['panda', 'ur5', 'talos'])
def test_model_carries_the_joint_types_and_mimic_tags_as_written(robot):
    """model.joint_types and model.mimics equal an independent reading of the XML."""
    path = robot_urdf_path(robot)
    model = sd.Model.from_urdf(path)
    root = ET.parse(path).getroot()
    joints = root.findall('joint')
    assert model.joint_types == {j.get('name'): j.get('type') for j in joints}
    assert model.mimics == {
        j.get('name'): (j.find('mimic').get('joint'),
                        float(j.find('mimic').get('multiplier', 1.0)),
                        float(j.find('mimic').get('offset', 0.0)))
        for j in joints if j.find('mimic') is not None}


MASSLESS = """<robot name="massless"><link name="trunk"/><link name="leg"/>
  <joint name="hip" type="revolute"><parent link="trunk"/><child link="leg"/>
    <axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="10" velocity="2"/></joint>
</robot>"""
BOX = """<robot name="box"><link name="box"><inertial><mass value="2"/>
  <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.3"/></inertial></link>
</robot>"""


@pytest.mark.parametrize('xml, singular', ((MASSLESS, True), (BOX, False)))
def test_a_floating_tree_without_mass_is_said_to_have_a_singular_mass_matrix(
        capsys, tmp_path, xml, singular):
    path = tmp_path / 'robot.urdf'
    path.write_text(xml)
    model = sd.Model.from_urdf(str(path), base='floating')
    q = np.r_[np.zeros(6), 1.0, np.zeros(model.nq - 7)]
    M = sd.mass_matrix(model, q)
    assert (np.linalg.matrix_rank(M) < model.nv) == singular    # the physics said
    status, out, _ = run(capsys, path, '--base', 'floating', '--strict')
    if singular:
        assert status == 1 and 'warnings (1)' in out
        assert 'the tree has no mass' in out and 'mass matrix M is singular' in out
    else:
        assert status == 0 and out.rstrip().endswith('no warnings')


INERTIA = '<inertia ixx="{}" ixy="0" ixz="0" iyy="{}" iyz="0" izz="{}"/>'
# a root 'a' without <inertial> on the free-flyer and 'b' (1 kg, full inertia) on a z joint:
# the base's yaw and j turn the same inertia
YAW = f"""<robot name="yaw"><link name="a"/>
  <link name="b"><inertial><mass value="1"/>{INERTIA.format(0.1, 0.2, 0.3)}</inertial></link>
  <joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>"""
# a fixed arm whose last link 'c' has no inertia about its joint's axis (z): a point on it
FLAT = f"""<robot name="flat"><link name="a"/>
  <link name="b"><inertial><mass value="2"/>{INERTIA.format(0.1, 0.2, 0.3)}</inertial></link>
  <link name="c"><inertial><mass value="1"/>{INERTIA.format(0.01, 0.01, 0)}</inertial></link>
  <joint name="j1" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="j2" type="continuous"><parent link="b"/><child link="c"/>
    <origin xyz="0 0 0.5"/><axis xyz="0 0 1"/></joint>
</robot>"""


@pytest.mark.parametrize('xml, base, lost', ((YAW, 'floating', {'root_joint ωz', 'j'}),
                                             (FLAT, 'fixed', {'j2'})))
def test_a_mass_matrix_that_loses_a_motion_is_said_with_the_motion_named(
        capsys, tmp_path, xml, base, lost):
    """``check --base floating`` said "no warnings" for the yaw tree (smallest eigenvalue 4e-18).

    Oracle: Pinocchio's CRBA on the same URDF is singular there, and its null motion is the
    one named (the base's yaw against j; j2 alone).
    """
    pin = pytest.importorskip('pinocchio')
    path = tmp_path / 'robot.urdf'
    path.write_text(xml)
    pm = (pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer()) if base == 'floating'
          else pin.buildModelFromUrdf(str(path)))
    M = pin.crba(pm, pm.createData(), pin.neutral(pm))
    M = np.triu(M) + np.triu(M, 1).T
    lam, V = np.linalg.eigh(M)
    assert lam[0] < 1e-15 * lam[-1]                         # the physics said
    names = ([f'root_joint {c}' for c in ('vx', 'vy', 'vz', 'ωx', 'ωy', 'ωz')]
             if base == 'floating' else []) + list(pm.names[1 + (base == 'floating'):])
    assert {names[k] for k in np.flatnonzero(np.abs(V[:, 0]) > 0.1)} == lost
    status, out, _ = run(capsys, path, '--base', base, '--strict')
    assert status == 1 and 'warnings (1)' in out, out
    said = ' '.join(section(out, 'warnings')).replace('\n', ' ')
    said = re.sub(r'\s+', ' ', said)
    assert f'singular at the neutral configuration (rank {len(names) - 1} of {len(names)}' in said
    motion = re.search(r'the motion (.*) moves no inertia', said).group(1)
    assert {term.split(' ', 1)[1] for term in re.split(' [+-] ', motion)} == lost, said


@pytest.mark.parametrize('robot, base', (('ur5', 'fixed'), ('panda', 'fixed'),
                                         ('solo12', 'floating'), ('talos', 'floating')))
def test_a_robot_whose_joints_all_move_inertia_has_no_mass_matrix_warning(robot, base):
    from spatial_dynamics import check
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', sd.URDFWarning)
        model = sd.Model.from_urdf(robot_urdf_path(robot), base=base)
    assert check.singular_mass_matrix(model) == []


def test_a_floating_model_names_body_0_the_world(capsys):
    """``check --base floating`` called the world ``(fixed base)`` and put 0 kg on it."""
    status, out, _ = run(capsys, robot_urdf_path('solo12'), '--base', 'floating')
    assert status == 0
    assert 'fixed base' not in out, out
    rows = section(out, 'bodies after lumping')[1:]
    assert rows[0].split()[:2] == ['0', 'universe'] and ' (the world) ' in rows[0], rows[0]
    model = sd.Model.from_urdf(robot_urdf_path('solo12'), base='floating')
    mass = model.inertia[:, 3, 3]
    assert re.search(rf"\({mass[1]:g} kg on the root link 'base_link' \(on the free-flyer\), "
                     rf'{np.sum(mass[2:]):g} kg on the links beyond it\)', out), out


def test_a_description_the_node_refuses_for_its_size_is_refused(capsys, tmp_path):
    """The node's limit (32 MiB), not the library's: what the check accepts, the node loads."""
    from spatial_dynamics.ros.descriptions import MAX_DESCRIPTION_BYTES
    path = tmp_path / 'large.urdf'
    text = open(DEMO_URDF).read()
    path.write_text(text + ' ' * (MAX_DESCRIPTION_BYTES + 1 - len(text.encode())))
    status, _, err = run(capsys, path)
    assert status == 1 and 'too large' in err and str(path) in err, err


def test_a_repeated_locked_joint_is_refused_as_the_node_refuses_it(capsys):
    joints = sd.Model.from_urdf(DEMO_URDF).joint_names
    with pytest.raises(SystemExit) as exit:
        main([DEMO_URDF, '--joints', joints[0], '--locked', f'{joints[1]}=0.1',
              f'{joints[1]}=0.2'])
    assert exit.value.code == 2
    err = capsys.readouterr().err
    assert '--locked' in err and joints[1] in err, err


def test_a_closed_pipe_is_no_traceback():
    """``spatial_dynamics_check ROBOT | head -1``: the reader leaves early, no traceback."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([ROOT, os.environ.get('PYTHONPATH', '')]))
    proc = subprocess.Popen([sys.executable, '-m', 'spatial_dynamics.check', DEMO_URDF],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env, cwd=ROOT)
    proc.stdout.close()   # as head does after its lines
    err = proc.stderr.read().decode()
    proc.wait(timeout=120)
    assert 'Traceback' not in err and 'BrokenPipeError' not in err, err
