# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""The node's parameter table, without ROS: each parameter written once, its defaults and bounds.

Pure Python + numpy + the library (no rclpy import), so all of it is tested without a ROS
graph (``test/test_node_config.py``, ``test/test_node_parameter_tables.py``). The node
(:mod:`spatial_dynamics.ros.node`) declares the parameters of :data:`PARAMETERS`;
config/inverse_dynamics.yaml and the table of doc/node.md are generated from it. What a
change of them makes (its checks across parameters and against the model, the
:class:`~.records.Config` swapped in) is :mod:`spatial_dynamics.ros.configure`'.
"""

from __future__ import annotations

import math

from spatial_dynamics.bounds import (
    BASE_ANGULAR_ACCELERATION, BASE_LINEAR_ACCELERATION, FRICTION_THRESHOLD_RANGE,
    MAX_BASE_ANGULAR_ACCELERATION, MAX_BASE_LINEAR_ACCELERATION, MAX_GRAVITY, MAX_IMU_RATE,
    MAX_IMU_SPECIFIC_FORCE, MAX_PLAN_BYTES, MIN_STAMP_INTERVAL)
from spatial_dynamics.effort import MAX_ANNOTATED_VALUES, MEASURED_EFFORT
from spatial_dynamics.wrench import EPSILON as WRENCH_EPSILON
from spatial_dynamics.ros.bases import (
    BASE_ACCELERATIONS, BASE_SOURCES, BASES, CONTACT_KINDS, CONTACT_METHODS)
from spatial_dynamics.ros.descriptions import MAX_DESCRIPTION_BYTES
from spatial_dynamics.ros.control import (
    CONTROL_MODES, FEEDBACK_REASONS, GAIN_UNITS, MAX_KD, MAX_KP, MAX_MEASURED_POSITION,
    MAX_MEASURED_VELOCITY, OUTPUTS)
from spatial_dynamics.ros.parameters import ConfigError, distinct, Param, Table
from spatial_dynamics.ros.observer import MAX_EXTERNAL_TORQUE_WARN, MAX_OBSERVER_GAIN

NODE_NAME = 'inverse_dynamics'
ACCELERATION_SOURCES = ('effort', 'none')
FRICTION_MODELS = ('none', 'urdf')
#: Values of the read-only ``backend`` parameter.
BACKEND_SETTINGS = ('auto', 'numpy', 'compiled')
DEFAULT_GRAVITY = (0.0, 0.0, -9.81)
DEFAULT_INPUT_TIMEOUT = 0.5         # s
DEFAULT_FRICTION_THRESHOLD = 0.01   # rad/s or m/s
DEFAULT_WRENCH_TIMEOUT = 0.5        # s
DEFAULT_MEASURED_TIMEOUT = 0.5      # s
DEFAULT_BASE_TIMEOUT = 0.5          # s
DEFAULT_BASE_MIN_INTERVAL = 1e-4    # s: twist sources up to 10 kHz
DEFAULT_BASE_FILTER = 0.01          # s: the differenced twist's low-pass, ~16 Hz
DEFAULT_THREAD_PRIORITY = 0         # normal scheduling: real-time is asked for (see the table)
DEFAULT_CONTACT_MU = 0.7            # Coulomb friction of a foot on a floor
MAX_CONTACT_MU = 10.0               # beyond it a cone is a wall: a mistake, not a floor
#: ``observer_gain`` K_O, 1/s: a 50 ms time constant (3.2 Hz bandwidth). A collision or a
#: wrong payload shows within ~0.15 s (3 time constants), while effort noise and the half
#: sample of timing between a drive's torque and its state pass at K_O times their size
#: (their rate of change over K_O): low enough to keep a 1 kHz state stream's noise out,
#: high enough that the estimate follows a contact as it happens.
DEFAULT_OBSERVER_GAIN = 20.0
#: ``external_torque_warn``, N m (N): RMS of the estimate per joint over a diagnostics
#: period above which diagnostics WARN. 5 N m is 1 kg at 0.5 m, a payload an arm's model
#: should know about; set it per joint for a robot with small wrist joints.
DEFAULT_EXTERNAL_TORQUE_WARN = 5.0

# Bounds beyond which a value cannot be physical: refused with the bound named, instead of
# being accepted and then making every answer non-finite.
MAX_ARMATURE = 1e6                  # kg m² (or kg), per joint
MAX_PAYLOAD_MASS = 1e6              # kg
MAX_PAYLOAD_COM = 1e3               # m, per component
MAX_PAYLOAD_INERTIA = 1e6           # kg m², per component
MAX_LOCKED_POSITION = 1e4           # rad or m
URDF_WARNINGS_LISTED = 5            # URDF warnings listed one by one in /diagnostics

# Rejection reasons the node adds to those of the input mapping.
NODE_REASONS = ('no_model', 'compute_error', 'non_finite_output') + FEEDBACK_REASONS
# Rejection reasons of external_wrenches messages.
WRENCH_REASONS = ('no_model', 'unknown_link', 'non_finite', 'out_of_bounds')


# --------------------------------------------------------------------------------------------
# Parameters

def _gravity_norm(name: str, g) -> None:
    norm = math.hypot(*g)
    if norm > MAX_GRAVITY:
        raise ConfigError(f'parameter {name}: |g| = {norm:g} m/s² in {list(g)}, more than '
                          f'{MAX_GRAVITY:g} m/s² (100 g) cannot be a mounting')


_gravity_norm.__doc__ = f'norm at most {MAX_GRAVITY:g} m/s² (100 g).'


def _distinct_cores(name: str, cores) -> None:
    """No core repeated."""
    if len(set(cores)) != len(cores):
        raise ConfigError(f'parameter {name}: cores repeated in {list(cores)}')


#: The top of config/inverse_dynamics.yaml, above the parameters the table writes.
PARAMETER_FILE_HEADER = (
    'Copyright 2026 spatial_dynamics contributors\n'
    'SPDX-License-Identifier: Apache-2.0\n'
    '\n'
    'Generated from the table in spatial_dynamics/ros/config.py '
    '(test/test_node_parameter_tables.py checks it).\n'
    'Parameters of the `inverse_dynamics` node (spatial_dynamics). Every parameter the node\n'
    'declares is listed here; all of them but those marked read-only can be changed while the\n'
    'node runs (`ros2 param set /inverse_dynamics <name> <value>`). Each change is validated\n'
    'first and rejected with a reason if it is unusable; a rejected change leaves everything\n'
    'as it was.\n'
    '\n'
    'Topics (relative names; remap them, e.g. effort_commands:=/effort_controller/commands):\n'
    '  in   desired_joint_states  sensor_msgs/JointState           best effort, keep last 1\n'
    '  in   desired_trajectory    trajectory_msgs/JointTrajectory  reliable, keep last 10 (a\n'
    '                             plan is one large sample: best effort loses big ones); at\n'
    '                             most 128 MB serialized, refused (too_large) unconverted\n'
    '  in   external_wrenches     geometry_msgs/WrenchStamped      best effort, keep last 10\n'
    '                             (depth 10: several links may publish in one burst)\n'
    '  in   joint_states          sensor_msgs/JointState, the MEASURED state (by name; position\n'
    '                             always, velocity in the feedback modes; effort = measured\n'
    '                             torque, used by the external-torque observer)\n'
    "                             best effort, keep last 1: connects to drivers' reliable and\n"
    '                             sensor-data best-effort publishers alike\n'
    '  in   robot_description     std_msgs/String (only if no description parameter is set)\n'
    '                             reliable, transient local, depth 1 (robot_state_publisher)\n'
    '  out  feedforward_efforts   sensor_msgs/JointState (stamp copied, effort = tau)  reliable\n'
    '  out  effort_commands       std_msgs/Float64MultiArray (tau in `joints` order)   reliable\n'
    '  out  feedforward_terms     sensor_msgs/JointState, name "<joint>/<term>", effort = value\n'
    '                             (gravity, velocity_product, inertial, armature, friction,\n'
    '                             external, feedback), summing to tau before clamping; computed\n'
    '                             and published only while someone subscribes   reliable\n'
    "  out  external_torque_estimate  sensor_msgs/JointState: the observer's external torque\n"
    '                             per model joint in effort (N m, N), header of the measured\n'
    '                             state it comes from; one per measured message carrying\n'
    '                             velocity and effort of every model joint    reliable\n'
    '  in   base/imu              sensor_msgs/Imu (base moving, base_input.source imu)\n'
    '  in   base/odometry         nav_msgs/Odometry: pose, child frame twist (base moving with\n'
    '                             base_input.source twist, or floating); best effort, last 1\n'
    '  in   base/pose, base/twist geometry_msgs/PoseStamped, TwistStamped: the same, apart\n'
    '  in   contact_states        std_msgs/UInt8MultiArray, a flag per contacts.links (floating)\n'
    '  out  contact_wrenches      geometry_msgs/WrenchStamped, one per contact, in its link\n'
    '  in   measured_contact_wrenches  geometry_msgs/WrenchStamped from foot sensors\n'
    '                             (floating, contacts.measured); best effort, keep last 10\n'
    '  out  external_wrench_estimate  geometry_msgs/WrenchStamped, the virtual F/T sensor\n'
    '                             of wrench_estimate.link          reliable\n'
    '  out  annotated_trajectory  trajectory_msgs/JointTrajectory, each plan with effort\n'
    '                             (trajectory_effort_tolerance > 0)  reliable\n'
    '  out  /diagnostics          diagnostic_msgs/DiagnosticArray, ~1 Hz\n'
    'QoS of the data topics can be overridden with the standard parameters, e.g.\n'
    '  qos_overrides./desired_joint_states.subscription.reliability: reliable'
)

#: Every parameter of the node, each written once (test/test_node_parameter_tables.py keeps
#: config/inverse_dynamics.yaml and the README's table equal to it).
PARAMETERS = Table(NODE_NAME, [
    Param('robot_description', 'string', '', (
        'URDF XML of the robot (XML text, never a path). Takes precedence over '
        'robot_description_file and the robot_description topic. A new value is parsed '
        'completely and swapped in only if it parses; otherwise it is rejected with the '
        "reason and the old model stays. Set to '' to fall back to robot_description_file "
        '(or, when that is empty too, to the topic).')),
    Param('robot_description_file', 'string', '', (
        'Path of a URDF (or .xacro, expanded when the xacro module is importable): a '
        f'regular UTF-8 file of at most {MAX_DESCRIPTION_BYTES >> 20} MiB. Used when '
        'robot_description is empty; set while robot_description is set, it is checked '
        'and kept for later, and the model stays that of robot_description.')),
    Param('strict_urdf', 'bool', False, (
        'Refuse a description with URDF warnings (physically inconsistent but computable: '
        'an inertia that is not positive semi-definite or breaks the triangle inequality, '
        'inertia on a massless link...) like any bad description. Off: it loads as written '
        'and each warning is logged and listed in /diagnostics. Cannot be switched on '
        'while the loaded description has warnings.')),
    Param('joints', 'string[]', None, (
        'Joints the model keeps, in the output order of effort_commands and '
        "feedforward_efforts: a subset of the URDF's movable, non-mimic joints. The "
        'others are locked (locked_joints/locked_positions, default 0) and lumped, and '
        'branches that cannot affect the kept joints are pruned (model reduction); inputs '
        'need only the kept joints. Unset or empty: all joints, in URDF order.')),
    Param('locked_joints', 'string[]', None, (
        'Joints locked at a non-zero position when joints is set (others lock at 0); '
        'values in locked_positions, same order.'), rules=(distinct,)),
    Param('locked_positions', 'double[]', None, (
        'Positions of locked_joints, same length; unset or empty = all 0.'), unit='rad or m',
        bounds=(-MAX_LOCKED_POSITION, MAX_LOCKED_POSITION)),
    Param('gravity', 'double[]', list(DEFAULT_GRAVITY), (
        'Gravity [gx, gy, gz] in the base frame (tilted or wall mounts); more than 100 g '
        'cannot be a mounting. Live.'), unit='m/s²', length=3, rules=(_gravity_norm,)),
    Param('acceleration_source', 'string', 'effort', (
        'Where desired_joint_states carries qdd: "effort" (the effort array holds desired '
        'accelerations, rad/s² or m/s²; empty = zeros) or "none" (qdd = 0: gravity and '
        'Coriolis compensation, safe with measured /joint_states).'),
        choices=ACCELERATION_SOURCES),
    Param('input_timeout', 'double', DEFAULT_INPUT_TIMEOUT, (
        'Seconds without a good input after which diagnostics report ERROR (stale). The '
        'node publishes only in answer to input, so stale input means no output, never '
        'zeros.'), bounds=(1e-3, 3600.0)),
    Param('output', 'string', 'full', (
        'What effort_commands and feedforward_efforts carry besides the feedback term: '
        '"full" (tau = ID + armature + friction - external: simulators, drives that add '
        'nothing), "without_gravity" (tau - g(q): drives that compensate gravity '
        'themselves, e.g. UR direct torque, Franka, KUKA FRI), "gravity_only" (g(q): hold '
        'an arm), "none" (no model term, only the feedback term: the PD-alone baseline; '
        'refused with control_mode feedforward, where it would publish zeros). Live.'),
        choices=OUTPUTS),
    Param('control_mode', 'string', 'feedforward', (
        '"feedforward": answer each desired message with the model part at the desired '
        'state (joint_states unused). "pd_feedforward": answer each measured joint_states '
        'message with model(q_d, qd_d, qdd_d) + kp (q_d - q) + kd (qd_d - qd), the desired '
        'state held from the last desired message. "computed_torque": answer each '
        'measured message with model(q, qd, qdd_d + kp e + kd ed), the model part at the '
        'measured state. Position errors of continuous joints wrap to (-pi, pi]. Live.'),
        choices=CONTROL_MODES),
    Param('kp', 'double[]', [0.0], (
        'Proportional gains, one value for all joints or one per model joint (order of '
        f'the joints parameter, or the URDF order when it is unset), 0 .. {MAX_KP:g}: '
        f'{GAIN_UNITS["kp"]}. Live.')),
    Param('kd', 'double[]', [0.0], (
        'Derivative gains, one value for all joints or one per model joint (order of '
        f'the joints parameter, or the URDF order when it is unset), 0 .. {MAX_KD:g}: '
        f'{GAIN_UNITS["kd"]}. Live.')),
    Param('measured_timeout', 'double', DEFAULT_MEASURED_TIMEOUT, (
        'Seconds (since receipt) after which the measured state on joint_states is stale: '
        'in the feedback modes diagnostics then report ERROR and nothing is published '
        '(answers come only in reply to a measured message), never zeros. Measured '
        f'values beyond ±{MAX_MEASURED_POSITION:g} rad (m) or ±{MAX_MEASURED_VELOCITY:g} '
        'rad/s (m/s) are refused.'), bounds=(1e-3, 3600.0)),
    Param('payload.link', 'string', '', (
        "Link carrying a rigid payload (tool, grasped object); '' = no payload. Live: "
        'applied from the next message. A new robot_description lacking this link is '
        'rejected.')),
    Param('payload.mass', 'double', 0.0, 'Payload mass.', unit='kg',
          bounds=(0.0, MAX_PAYLOAD_MASS)),
    Param('payload.com', 'double[]', [0.0, 0.0, 0.0], (
        "Payload centre of mass [x, y, z] in payload.link's frame."), unit='m', length=3,
        bounds=(-MAX_PAYLOAD_COM, MAX_PAYLOAD_COM)),
    Param('payload.inertia', 'double[]', [0.0] * 6, (
        'Payload inertia [ixx, ixy, ixz, iyy, iyz, izz] about its centre of mass, axes of '
        "payload.link's frame (positive semi-definite, triangle inequality)."),
        unit='kg m^2', length=6, bounds=(-MAX_PAYLOAD_INERTIA, MAX_PAYLOAD_INERTIA)),
    Param('armature', 'double[]', None, (
        'Rotor inertia reflected through the gear (kg m^2 or kg), one value >= 0 per '
        'model joint in the order of the joints parameter (URDF order when unset): '
        'tau += armature * qdd. Unset or empty: none.')),
    Param('friction_model', 'string', 'none', (
        '"none", or "urdf": tau += damping * qd + friction * tanh(qd / '
        "friction_velocity_threshold) from each joint's URDF <dynamics>."),
        choices=FRICTION_MODELS),
    Param('friction_velocity_threshold', 'double', DEFAULT_FRICTION_THRESHOLD, (
        'Velocity (rad/s or m/s) at which the smooth Coulomb sign reaches tanh(1) = 76 %.'),
        bounds=FRICTION_THRESHOLD_RANGE),
    Param('clamp_to_effort_limits', 'bool', False, (
        'Clamp tau to the URDF <limit effort> (joints without a positive limit are left '
        'alone); a throttled warning names the saturated joints. Off: an answer above a '
        'limit is published, counted in /diagnostics (above effort limit) and warned.')),
    Param('external_wrench_timeout', 'double', DEFAULT_WRENCH_TIMEOUT, (
        'Seconds after its receipt that an external_wrenches message stops applying.'),
        bounds=(1e-3, 3600.0)),
    Param('observer_gain', 'double', DEFAULT_OBSERVER_GAIN, (
        'Gain K_O (1/s) of the generalized-momentum observer of external joint torques: '
        'each measured joint_states message with effort for every model joint updates it '
        'and external_torque_estimate is published (time constant 1/K_O; the model '
        'includes payload, armature, friction_model and gravity). 0 = off. At most '
        f'{MAX_OBSERVER_GAIN:g} 1/s (1 ms: beyond it the estimate is the differentiated '
        'momentum). Live; a change restarts the observer.'), bounds=(0.0, MAX_OBSERVER_GAIN)),
    Param('external_torque_warn', 'double[]', [DEFAULT_EXTERNAL_TORQUE_WARN], (
        'Diagnostics WARN, naming the joints, when the RMS of external_torque_estimate over '
        'a diagnostics period exceeds this (N m, or N for prismatic joints): one value for '
        'all joints or one per model joint (order of the joints parameter), above 0 and at '
        f'most {MAX_EXTERNAL_TORQUE_WARN:g}. Live.')),
    Param('measured_effort', 'string', 'full', (
        'What the effort of a measured joint_states message is, for the observer: "full", '
        'the link-side torque including gravity (Franka tau_J, KUKA iiwa measured torque, '
        'MuJoCo and Gazebo joint torques, most ros2_control effort state interfaces), or '
        '"gravity_compensated", the torque beyond gravity (UR\'s joint torques: the node '
        'adds g(q) of its model before the observer). Live; a change restarts the '
        'observer.'), choices=MEASURED_EFFORT),
    Param('wrench_estimate.link', 'string', '', (
        'Link whose external wrench is estimated from the observer\'s external torques '
        '(a virtual force/torque sensor: damped least squares of J^T w = tau_ext, J the '
        "link's Jacobian in its own frame) and published on external_wrench_estimate "
        "(geometry_msgs/WrenchStamped, frame_id = the link, at the link's origin); '' = "
        'off. Needs observer_gain > 0. With fewer than six joints between the base and the '
        'link, or near a singularity, some directions cannot be observed: diagnostics WARN '
        'naming them. Live.')),
    Param('wrench_estimate.epsilon', 'double', WRENCH_EPSILON, (
        "Smallest singular value of the link's Jacobian (m, or 1 for rotations) below which "
        'the least squares are damped: directions weaker than this are underestimated '
        'instead of amplifying noise. Live.'), bounds=(1e-6, 10.0)),
    Param('trajectory_effort_tolerance', 'double', 0.0, (
        'When > 0, each desired_trajectory is also published on annotated_trajectory with '
        'effort filled at every point (the output part of the model torque, gravity '
        'included unless output says otherwise), resampled so that joint_trajectory_'
        'controller\'s linear interpolation of effort between points stays within this '
        'tolerance of the model torque (N m, or N); remap it to a JTC\'s ~/joint_trajectory. '
        '0 = off. Live.'), unit='N m or N', bounds=(0.0, 1e4)),
    Param('trajectory_max_bytes', 'int', MAX_PLAN_BYTES, (
        'Largest desired_trajectory taken, serialized: a larger one is refused (too_large) '
        'before it is converted, so its size never costs the answers. The default admits the '
        'most points a plan may have. Read-only.'), unit='bytes',
        bounds=(1024, 1 << 31), read_only=True),
    Param('trajectory_annotation_max_values', 'int', MAX_ANNOTATED_VALUES, (
        'Most values (points x joints x (fields + effort)) an annotated_trajectory may hold; '
        'a plan whose tolerance would need more is refused (too_many_points) and counted in '
        'diagnostics. Read-only.'), bounds=(1000, 10**8), read_only=True),
    Param('base', 'string', 'fixed', (
        '"fixed": the root link is fixed to the world (an arm on a table). "moving": the '
        'fixed-base model on a moving base (mobile manipulator, ship), its motion from '
        'base/imu or base/odometry (or base/pose + base/twist) (base_input.source); '
        'efforts = rnea(..., base=motion). '
        '"floating": the model with a free-flyer root (legged robots), its base state from '
        'base/odometry (or base/pose + base/twist); the joints\' efforts and the contact '
        'wrenches of contacts.links (published on contact_wrenches) split M qdd + h (contact '
        'inverse dynamics); the base never gets an effort. A missing or stale base input means no '
        'output, with the reason in /diagnostics. Read-only.'),
        choices=BASES, read_only=True),
    Param('base_input.source', 'string', 'imu', (
        'A moving base\'s motion: "imu" (base/imu, sensor_msgs/Imu on base_input.imu_link: its '
        'specific force and angular velocity, angular acceleration zero) or "twist" '
        '(base/odometry, or base/pose for the orientation of gravity and base/twist for the '
        'twist; its rate per base_input.acceleration). Live.'), choices=BASE_SOURCES),
    Param('base_input.imu_link', 'string', '', (
        'The link the IMU of base/imu is mounted on (its frame is the IMU frame, placed by '
        'the URDF; header.frame_id must be this link, empty, or base_input.imu_frame): the '
        'base link or a link fixed to it. Values beyond what an IMU reports (angular_velocity '
        f'±{MAX_IMU_RATE:g} rad/s, linear_acceleration ±{MAX_IMU_SPECIFIC_FORCE:g} m/s², per '
        'axis) are refused. Live.')),
    Param('base_input.imu_frame', 'string', '', (
        'The header.frame_id the IMU driver writes when it is not the name of '
        'base_input.imu_link in the URDF (e.g. "imu" or "imu_link_optical" for a link named '
        "otherwise): that frame is taken as base_input.imu_link's. '' = the link's own name. "
        'Live.')),
    Param('base_input.odometry_frame', 'string', '', (
        "The child_frame_id base/odometry's source writes (base/twist's header.frame_id) when "
        'it is not a link of the URDF (a typical /odom has child_frame_id base_footprint): '
        'exactly this frame is taken as base_input.odometry_link; any other frame that is not '
        "a link of the URDF is refused (wrong_frame). '' = the frame must be a link of the "
        'URDF (or empty, the root link). Live.')),
    Param('base_input.odometry_link', 'string', '', (
        'The link of the URDF that base_input.odometry_frame is (moving: the root link or a '
        "link fixed to it; floating: the root link); '' = the root link. A twist with an "
        "empty frame is this link's too. As replay's --odometry-link. Live.")),
    Param('base_input.acceleration', 'string', 'difference', (
        'The base\'s acceleration with base/twist (moving, source twist; and floating, '
        'the desired base acceleration): "difference", the difference of successive '
        'twists over their header stamps (two samples needed, a gap of base_input.timeout '
        'restarts it), low-pass filtered (base_input.acceleration_time_constant) and '
        'bounded (base_input.max_linear_acceleration, base_input.max_angular_acceleration), '
        'or "zero", a base moving at constant twist. Live.'),
        choices=BASE_ACCELERATIONS),
    Param('base_input.min_interval', 'double', DEFAULT_BASE_MIN_INTERVAL, (
        'Shortest stamp interval between two base twists that is differenced (the period of '
        'the fastest twist source expected; the default admits sources up to 10 kHz): a twist '
        'stamped closer to the last one is refused (interval_too_short) and the last good '
        f'acceleration is kept. At least {MIN_STAMP_INTERVAL:g} s. Live.'), unit='s',
        bounds=(MIN_STAMP_INTERVAL, 1.0)),
    Param('base_input.acceleration_time_constant', 'double', DEFAULT_BASE_FILTER, (
        'Time constant of the first-order low-pass filter of the differenced twist (over the '
        'stamps: a = a + (1 - exp(-dt / T)) (dv / dt - a)); a twist jump dv then moves the '
        'acceleration by at most dv / T however close the stamps. 0 = unfiltered. The first '
        'difference after a start or a gap is taken as it is. Live.'), unit='s',
        bounds=(0.0, 1.0)),
    Param('base_input.max_linear_acceleration', 'double', BASE_LINEAR_ACCELERATION, (
        "Largest norm of the rate of the base twist's linear part a real base reaches "
        '(default 5 g: above a mobile base, a ship, a jumping quadruped; set your base\'s): a '
        'differenced twist beyond it is refused (out_of_bounds) and the last good '
        'acceleration kept. Live.'), unit='m/s^2', bounds=(1e-3, MAX_BASE_LINEAR_ACCELERATION)),
    Param('base_input.max_angular_acceleration', 'double', BASE_ANGULAR_ACCELERATION, (
        "Largest norm of the rate of the base twist's angular part a real base reaches: a "
        'differenced twist beyond it is refused (out_of_bounds) and the last good acceleration '
        'kept. Live.'), unit='rad/s^2', bounds=(1e-3, MAX_BASE_ANGULAR_ACCELERATION)),
    Param('base_input.timeout', 'double', DEFAULT_BASE_TIMEOUT, (
        'Seconds (since receipt) after which a base input (base/imu, base/pose, '
        'base/twist, contact_states) is stale: answers are then refused (diagnostics say '
        'which input), never computed as if the base were fixed. Live.'),
        bounds=(1e-3, 3600.0)),
    Param('contacts.links', 'string[]', None, (
        'Floating base (required: nothing else carries the base): the links that may touch '
        'the ground (feet, soles), each a contact at its origin; all in contact while '
        'nothing comes on contact_states (std_msgs/UInt8MultiArray, one flag per link in this '
        'order); once something comes, only a valid one younger than base_input.timeout says '
        'which (none valid yet, or stale: no output). An answer whose contacts in contact '
        'cannot carry the base (base residual above 1e-6 m g), or with none in contact (in '
        'flight), is not published. Live.'),
        rules=(distinct,)),
    Param('contacts.kind', 'string', 'point', (
        '"point" (a force: feet) or "surface" (a wrench: soles). Live.'),
        choices=CONTACT_KINDS),
    Param('contacts.mu', 'double', DEFAULT_CONTACT_MU, (
        'Coulomb friction coefficient of every contact: a force outside its cone is reported '
        'in /diagnostics ("qp", and the QP that re-solves a pulling split, keep inside it). '
        'Live.'), bounds=(0.0, MAX_CONTACT_MU)),
    Param('contacts.method', 'string', 'torques', (
        'How M qdd + h is split: "torques", the least joint efforts consistent with the '
        'contacts; "forces", the least contact forces carrying the base; "qp", the least '
        'efforts with every force inside its friction cone (slower; infeasible = no '
        'output). A "torques" or "forces" split that makes a contact pull (n.f below '
        '-1e-6 m g) is re-solved by "qp" and its answer published; without the QP (clarabel, '
        'the qp extra) or when it is infeasible, no output. Live.'), choices=CONTACT_METHODS),
    Param('contacts.measured', 'bool', False, (
        'Take the contact wrenches from measured_contact_wrenches (geometry_msgs/'
        "WrenchStamped from foot force sensors: frame_id = a link of contacts.links, [n; f] "
        "in the link's frame at its origin; a point contact uses the force) instead of "
        'solving for them: efforts = (M qdd + h - J_c^T lambda) of the joints, the base '
        'rows\' residual in /diagnostics. Each contact in force needs a measurement younger '
        'than base_input.timeout. Live.')),
    Param('backend', 'string', 'auto', (
        'How tau is computed. "numpy": plain Python floats (~30-150 µs per call for 6-32 '
        'joints). "compiled" and "auto": the compiled kernels built with the package (~1-3 '
        'µs), from the first answer; numpy, with a warning, in a package built without them. '
        'Read-only.'), choices=BACKEND_SETTINGS, read_only=True),
    Param('thread_priority', 'int', DEFAULT_THREAD_PRIORITY, (
        'SCHED_FIFO priority of the thread that answers the inputs and of the middleware '
        "threads that receive them (controller_manager's parameter; it defaults to 50, "
        'this node to 0 = normal scheduling: on 2 cores with three busy loops and other jobs '
        '(load ~6), a node at 50 fed at 1 kHz gave no OK feedforward status in /diagnostics '
        'for 60 s, its other threads being under normal scheduling; ask for it, e.g. 50, '
        'where the node has a core to itself). A real-time thread runs before every normal '
        'one on its core: the answers keep their period on a busy machine, and a busy loop '
        'in the node would starve the core (the node only waits or answers). Needs the '
        'rtprio limit or CAP_SYS_NICE (a realtime group in /etc/security/limits.conf, ulimit -r, '
        'docker run --cap-add=sys_nice --ulimit rtprio=99); without it one WARN says so '
        'and the node answers under normal scheduling. /diagnostics (real-time) says what '
        'is in effect. With it granted, a queue of 10 on the answered input '
        '(qos_overrides./desired_joint_states.subscription.depth: 10) answered every input '
        'at 1 and 2 kHz where keep last 1 lost 0.3-2 % (doc/node.md). Read-only.'),
        bounds=(0, 99), read_only=True),
    Param('cpu_affinity', 'int[]', None, (
        'CPU cores the answering thread may run on (controller_manager\'s parameter); '
        'unset or empty = all. A core of its own (with isolcpus, or other processes kept '
        'off it) spares the answers the wait for other work on the core; pinning to a busy '
        'core costs latency. A core outside the process\'s allowed set is refused with a '
        'WARN and the thread runs on all of them. Read-only.'), bounds=(0, 1023),
        rules=(_distinct_cores,), read_only=True),
    Param('lock_memory', 'bool', False, (
        'Lock the process\'s memory in RAM (mlockall of current and future pages), so no '
        'answer waits for a page fault or swap-in. Costs resident memory: every page the '
        'process maps stays in RAM (the Python process, its libraries and the middleware: '
        '0.85 GB locked at start here, 1.4 GB after a 100,000-point plan; size memlock for '
        'it). Needs the memlock limit (unlimited; limits.conf, ulimit -l, docker --ulimit '
        'memlock=-1) or CAP_IPC_LOCK; without it one WARN and the node runs unlocked. '
        "controller_manager's default is false on a standard kernel, true on a real-time "
        'one. Read-only.'), read_only=True),
], header=PARAMETER_FILE_HEADER)
#: Every parameter, by name.
PARAMETER_NAMES = tuple(spec.name for spec in PARAMETERS)
#: Parameters that shape the model (a change re-parses the description).
MODEL_PARAMETERS = ('joints', 'locked_joints', 'locked_positions')
#: Changes that may parse a description (slow for a large one).
SLOW_PARAMETERS = frozenset({'robot_description', 'robot_description_file', *MODEL_PARAMETERS})
PAYLOAD_PARAMETERS = ('payload.link', 'payload.mass', 'payload.com', 'payload.inertia')
DESCRIPTION_PARAMETERS = ('robot_description', 'robot_description_file')
