# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""``replay residual/identify --base-odometry/--base-imu``: a UR5 on a base that moves.

The bag is written from closed forms: the UR5's joints swing (two sines each), its base
sways along x and y, yaws and rolls (a mobile base on uneven ground, or a ship), and the
effort is ``rnea(..., base=BaseMotion(...))`` plus known damping, Coulomb friction and
armature. The base's odometry (100 Hz: twist and orientation of ``base_link``) and an IMU on
``base_link`` (500 Hz: gyro and specific force) are in the same bag, as a mobile
manipulator records them. With either, the residual is the drive torque (up to the
differentiation); without, it is metres per second squared of base acceleration times the arm.
"""

import csv
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(__file__))
from conftest import robot_urdf_path  # noqa: E402

import spatial_dynamics as sd  # noqa: E402
from spatial_dynamics.base import quaternion_of  # noqa: E402
from spatial_dynamics.recordings import bags, cdr  # noqa: E402
from spatial_dynamics.replay.__main__ import main  # noqa: E402

pytest.importorskip('rosbags')
DAMPING = np.array([2.0, 3.0, 1.5, 0.8, 0.5, 0.3])
FRICTION = np.array([3.0, 4.0, 2.0, 1.0, 0.6, 0.4])
ARMATURE = np.array([0.4, 0.5, 0.3, 0.1, 0.08, 0.05])
EPS = 0.01                 # the friction threshold (the node's default)
RATE, ODOMETRY_RATE, IMU_RATE = 1000.0, 100.0, 500.0
DURATION = 10.0
T0 = 1_700_000_000 * 10 ** 9
GRAVITY = np.array([0.0, 0.0, -9.81])


def joints(t):
    """``q, q̇, q̈`` (N, 6): each joint a sum of two sines of its own frequencies."""
    k = np.arange(6)
    amp, w = 0.6 / (1 + 0.2 * k), 2 * np.pi * (0.3 + 0.17 * k)
    t = t[:, None]
    q = amp * (np.sin(w * t) + 0.3 * np.sin(3.1 * w * t))
    qd = amp * w * (np.cos(w * t) + 0.93 * np.cos(3.1 * w * t))
    qdd = -amp * w * w * (np.sin(w * t) + 0.3 * 9.61 * np.sin(3.1 * w * t))
    return q, qd, qdd


def pose(t):
    """Return the base's position (N, 3) and orientation (N, 3, 3) in the world."""
    p = np.stack([0.3 * np.sin(2 * np.pi * 0.7 * t), 0.3 * np.sin(2 * np.pi * 0.5 * t),
                  0.02 * np.sin(2 * np.pi * 0.9 * t)], -1)
    yaw, roll = 0.8 * np.sin(2 * np.pi * 0.4 * t), 0.1 * np.sin(2 * np.pi * 0.6 * t)
    cy, sy, cr, sr = np.cos(yaw), np.sin(yaw), np.cos(roll), np.sin(roll)
    one, zero = np.ones_like(t), np.zeros_like(t)
    Rz = np.stack([np.stack([cy, -sy, zero], -1), np.stack([sy, cy, zero], -1),
                   np.stack([zero, zero, one], -1)], -2)
    Rx = np.stack([np.stack([one, zero, zero], -1), np.stack([zero, cr, -sr], -1),
                   np.stack([zero, sr, cr], -1)], -2)
    return p, Rz @ Rx


H = 1e-5        # s, the step of the central differences of the closed forms


def twist(t):
    """Return the base's twist ``[ω; v]`` (N, 6) in its own frame (odometry's child frame)."""
    p, R = pose(t)
    (pa, Ra), (pb, Rb) = pose(t + H), pose(t - H)
    Rdot, pdot = (Ra - Rb) / (2 * H), (pa - pb) / (2 * H)
    W = np.swapaxes(R, -1, -2) @ Rdot           # [ω×] in the base frame
    w = np.stack([W[:, 2, 1], W[:, 0, 2], W[:, 1, 0]], -1)
    return np.concatenate([w, np.einsum('nji,nj->ni', R, pdot)], -1)


def motion(t):
    """Return the base's BaseMotion (spatial acceleration: the twist's rate)."""
    a = (twist(t + 1e-4) - twist(t - 1e-4)) / 2e-4
    return sd.BaseMotion(twist(t), a, quaternion_of(pose(t)[1]))


def specific_force(t):
    """Return the accelerometer's reading at the base origin, base axes: ``Rᵀ (p̈ - g)``."""
    p, R = pose(t)
    pdd = (pose(t + 1e-4)[0] - 2 * p + pose(t - 1e-4)[0]) / 1e-8
    return np.einsum('nji,nj->ni', R, pdd - GRAVITY)


def drives(qd, qdd):
    """Return the drive terms the bag's effort holds beside the rigid body."""
    return DAMPING * qd + FRICTION * np.tanh(qd / EPS) + ARMATURE * qdd


def messages(msgtype, t_ns, frame, values):
    """Serialise Odometry (values: twist, quaternion) or Imu (gyro, specific force)."""
    store = cdr.typestore()
    T = store.types
    Header, Time = T['std_msgs/msg/Header'], T['builtin_interfaces/msg/Time']
    V3, Q = T['geometry_msgs/msg/Vector3'], T['geometry_msgs/msg/Quaternion']
    out = []
    for k, ns in enumerate(t_ns.tolist()):
        header = Header(stamp=Time(sec=ns // 10 ** 9, nanosec=ns % 10 ** 9), frame_id=frame[0])
        if msgtype == cdr.ODOMETRY:
            w, v, o = values[0][k, :3], values[0][k, 3:], values[1][k]
            msg = T[cdr.ODOMETRY](
                header=header, child_frame_id=frame[1],
                pose=T['geometry_msgs/msg/PoseWithCovariance'](
                    pose=T['geometry_msgs/msg/Pose'](
                        position=T['geometry_msgs/msg/Point'](x=0.0, y=0.0, z=0.0),
                        orientation=Q(x=o[0], y=o[1], z=o[2], w=o[3])),
                    covariance=np.zeros(36)),
                twist=T['geometry_msgs/msg/TwistWithCovariance'](
                    twist=T['geometry_msgs/msg/Twist'](linear=V3(x=v[0], y=v[1], z=v[2]),
                                                       angular=V3(x=w[0], y=w[1], z=w[2])),
                    covariance=np.zeros(36)))
        else:
            w, f = values[0][k], values[1][k]
            msg = T[cdr.IMU](header=header, orientation=Q(x=0.0, y=0.0, z=0.0, w=1.0),
                             orientation_covariance=np.zeros(9),
                             angular_velocity=V3(x=w[0], y=w[1], z=w[2]),
                             angular_velocity_covariance=np.zeros(9),
                             linear_acceleration=V3(x=f[0], y=f[1], z=f[2]),
                             linear_acceleration_covariance=np.zeros(9))
        out.append(bytes(store.serialize_cdr(msg, msgtype)))
    return out


def stamps(rate, start=0.0, stop=DURATION):
    """Bag times (int ns) and seconds from the start of ``start`` .. ``stop`` at ``rate``."""
    k = np.arange(int(round(start * rate)), int(round(stop * rate)) + 1)
    t_ns = T0 + k * int(round(1e9 / rate))
    return t_ns, (t_ns - T0) * 1e-9


def write_bag(path, storage='sqlite3', odometry=(0.0, DURATION), imu=(0.0, DURATION),
              hole=None):
    """Write the moving UR5's bag: /joint_states, /odom (``odometry`` s), /imu (``imu`` s).

    ``hole``: ``(start, stop)`` s without odometry messages.
    """
    model = sd.Model.from_urdf(robot_urdf_path('ur5'))
    t_ns, t = stamps(RATE)
    q, qd, qdd = joints(t)
    effort = sd.rnea(model, q, qd, qdd, GRAVITY, base=motion(t)) + drives(qd, qdd)
    block = bags.encode_joint_states(model.joint_names, t_ns, q, qd, effort)
    topics = [('/joint_states', bags.JOINT_STATE, t_ns, [r.tobytes() for r in block])]
    on, ton = stamps(ODOMETRY_RATE, *odometry)
    if hole is not None:
        keep = (ton < hole[0] - 1e-9) | (ton > hole[1] + 1e-9)
        on, ton = on[keep], ton[keep]
    topics.append(('/odom', cdr.ODOMETRY, on, messages(
        cdr.ODOMETRY, on, ('odom', 'base_link'), (twist(ton), quaternion_of(pose(ton)[1])))))
    im, tim = stamps(IMU_RATE, *imu)
    topics.append(('/imu', cdr.IMU, im, messages(
        cdr.IMU, im, ('base_link',), (twist(tim)[:, :3], specific_force(tim)))))
    bags.write_bag(str(path), storage, topics)
    return str(path)


@pytest.fixture(scope='module')
def bag(tmp_path_factory):
    """Write the moving UR5's bag once for the module, as sqlite3."""
    return write_bag(tmp_path_factory.mktemp('moving') / 'bag')


def residual_less_drives(out):
    """Read residual.csv and return it less the drive terms at its samples: (N, 6)."""
    data = np.loadtxt(os.path.join(out, 'residual.csv'), delimiter=',', skiprows=1)
    _, qd, qdd = joints(np.round(data[:, 0] * RATE) / RATE)
    return data[:, 1:] - drives(qd, qdd)


def summary(out):
    """Read summary.csv as {joint: {column: value}}."""
    with open(os.path.join(out, 'summary.csv')) as f:
        return {r['joint']: {k: (v if k == 'joint' else float(v)) for k, v in r.items()}
                for r in csv.DictReader(f)}


def test_the_bags_base_gives_the_residual_of_a_moving_base(bag, tmp_path, capsys):
    urdf = robot_urdf_path('ur5')
    rms = {}
    for option in ([], ['--base-imu', '/imu'], ['--base-odometry', '/odom']):
        out = str(tmp_path / (option[0][2:] if option else 'fixed'))
        assert main(['residual', bag, '--urdf', urdf, '--out', out, '--no-plots']
                    + option) == 0
        rms[option[0] if option else 'fixed'] = np.sqrt(np.mean(
            residual_less_drives(out) ** 2, axis=0))
    said = capsys.readouterr().out
    assert "base: moving, its motion from --base-imu '/imu'" in said
    # without the base: the base's acceleration (up to 6 m/s^2, 2 rad/s^2) times the arm
    assert rms['fixed'].max() > 5.0
    # with it: what the Savitzky-Golay derivative of the joints (and of the base's 100 Hz
    # twist, linearly interpolated) leaves
    assert rms['--base-imu'].max() < 0.01, rms['--base-imu']
    assert rms['--base-odometry'].max() < 0.02, rms['--base-odometry']


@pytest.mark.parametrize('option', ['--base-odometry', '--base-imu'])
def test_identify_on_a_moving_base_recovers_the_drives(bag, tmp_path, option):
    out = str(tmp_path / 'out')
    topic = '/odom' if option == '--base-odometry' else '/imu'
    assert main(['identify', bag, '--urdf', robot_urdf_path('ur5'), '--out', out,
                 '--no-plots', '--window', '0.1', option, topic]) == 0
    s = summary(out)
    for j, name in enumerate(sd.Model.from_urdf(robot_urdf_path('ur5')).joint_names):
        assert s[name]['damping'] == pytest.approx(DAMPING[j], rel=0.05), name
        assert s[name]['friction'] == pytest.approx(FRICTION[j], rel=0.05), name
        assert s[name]['armature'] == pytest.approx(ARMATURE[j], rel=0.05), name


def refusal(capsys, argv):
    """Run the command; return its stderr, which must be one line, exit status 1."""
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and 'Traceback' not in err
    return err


def test_a_base_topic_that_is_not_there_is_refused_naming_it(bag, tmp_path, capsys):
    urdf = robot_urdf_path('ur5')
    err = refusal(capsys, ['residual', bag, '--urdf', urdf, '--out', str(tmp_path / 'o'),
                           '--no-plots', '--base-imu', '/base/imu'])
    assert "--base-imu '/base/imu'" in err and "'/base/imu' is not in the bag" in err
    err = refusal(capsys, ['residual', bag, '--urdf', urdf, '--out', str(tmp_path / 'o'),
                           '--no-plots', '--base-odometry', '/imu'])
    assert "--base-odometry '/imu'" in err and 'expected nav_msgs/msg/Odometry' in err


@pytest.mark.parametrize('odometry, hole, said', [
    ((2.0, DURATION), None, 'covers 2.000 .. 10.000 s of the joint states\' 0 .. 10.000 s'),
    ((0.0, 6.0), None, 'covers 0.000 .. 6.000 s'),
    ((0.0, 0.03), None, '4 usable message(s) of 4 on the topic (at least 5'),
    ((0.0, DURATION), (4.0, 5.0), 'no message from 3.990 to 5.010 s of the joint states'),
])
def test_a_base_topic_that_does_not_cover_the_joints_is_refused(
        tmp_path, capsys, odometry, hole, said):
    bag = write_bag(tmp_path / 'short', odometry=odometry, imu=(0.0, 0.02), hole=hole)
    err = refusal(capsys, ['residual', bag, '--urdf', robot_urdf_path('ur5'), '--out',
                           str(tmp_path / 'o'), '--no-plots', '--base-odometry', '/odom'])
    assert "--base-odometry '/odom'" in err and said in err, err


@pytest.mark.parametrize('options, said', [
    (['--imu-link', 'base_link'], '--imu-link needs --base-imu'),
    (['--base-imu', '/imu', '--base-odometry', '/odom'],
     '--base-odometry and --base-imu: give one'),
])
def test_base_options_that_do_not_go_together_are_a_usage_error(bag, capsys, options, said):
    with pytest.raises(SystemExit) as exit_:
        main(['residual', bag, '--urdf', robot_urdf_path('ur5')] + options)
    assert exit_.value.code == 2
    assert said in capsys.readouterr().err


def test_a_frame_that_is_no_link_is_refused_naming_it(bag, tmp_path, capsys):
    err = refusal(capsys, ['residual', bag, '--urdf', robot_urdf_path('ur5'), '--out',
                           str(tmp_path / 'o'), '--no-plots', '--base-imu', '/imu',
                           '--imu-link', 'imu_frame'])
    assert "--imu-link 'imu_frame' is not a link of" in err


# --------------------------------------------------------------------------------------------
# The hand-written CDR decoding of Odometry and Imu against rosbags' deserialiser

@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
def test_odometry_and_imu_decoding_equals_rosbags_deserialiser(tmp_path, storage):
    rng = np.random.default_rng(3)
    n = 40
    t_ns = T0 + np.arange(n) * 10 ** 7
    # frame names of several lengths: every alignment of the doubles after the strings, and
    # messages of one length with other strings
    frames = [('odom' + 'x' * (k % 5), 'base_link') for k in range(n)]
    raw = {}
    for msgtype, count in ((cdr.ODOMETRY, 2), (cdr.IMU, 2)):
        raw[msgtype] = [messages(msgtype, t_ns[k:k + 1], frames[k],
                                 (rng.normal(size=(1, 6 if msgtype == cdr.ODOMETRY else 3)),
                                  rng.normal(size=(1, 4 if msgtype == cdr.ODOMETRY else 3))))[0]
                        for k in range(n)]
        for data in raw[msgtype]:
            assert cdr.verify_fixed(data, msgtype)
    path = str(tmp_path / 'bag')
    bags.write_bag(path, storage, [('/odom', cdr.ODOMETRY, t_ns, raw[cdr.ODOMETRY]),
                                   ('/imu', cdr.IMU, t_ns, raw[cdr.IMU])])
    store = cdr.typestore()
    for topic, msgtype in (('/odom', cdr.ODOMETRY), ('/imu', cdr.IMU)):
        found = bags.read_stamped(path, topic, msgtype)
        # a run of one byte length whose strings differ from its first message's goes
        # through rosbags: both paths are read here, and both must equal the deserialiser
        assert found.fast + found.generic == n and found.fast >= 8 and found.generic >= 8
        expected = np.array([cdr.FIXED_MESSAGES[msgtype][2](store.deserialize_cdr(d, msgtype))
                             for d in raw[msgtype]])
        assert np.array_equal(found.values, expected)
        assert np.array_equal(found.stamp, t_ns // 10 ** 9 + (t_ns % 10 ** 9) * 1e-9)
        assert found.frames == (frames[0] if msgtype == cdr.ODOMETRY else frames[0][:1])


def test_odometry_whose_quaternion_is_no_orientation_is_dropped_as_unusable():
    # a zero, half or doubled quaternion is a broken message, as a NaN is: not a tilt of
    # gravity; drift within 1e-2 of unit is kept (and normalised)
    from spatial_dynamics.recordings.base_topics import covering
    t = np.arange(100) / ODOMETRY_RATE
    quat = np.tile([0.0, 0.0, 0.0, 1.0], (len(t), 1))
    quat[10], quat[20], quat[30], quat[40] = 0.0, (0, 0, 0, 0.5), (0, 0, 0, 2), (0, 0, 0, 1.005)
    values = np.zeros((len(t), cdr.FIXED_MESSAGES[cdr.ODOMETRY][1]))
    layout = cdr.FIXED_MESSAGES[cdr.ODOMETRY][3]
    values[:, layout['orientation']] = quat
    found = cdr.Stamped(cdr.ODOMETRY, t, values, ('odom', 'base_link'))
    fields = [found.field(f) for f in ('orientation', 'angular', 'linear')]
    kept = covering(found, fields, t, 'base/odometry')
    assert len(kept) == len(t) - 3 and not {0.1, 0.2, 0.3} & set(np.round(kept, 6))
    assert 0.4 in np.round(kept, 6)
