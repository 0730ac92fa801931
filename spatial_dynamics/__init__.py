# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""spatial_dynamics: inverse dynamics (RNEA) on Featherstone's spatial vector algebra.

The core (``spatial``, ``joints``, ``model``, ``urdf``, ``algorithms``, ``backends``) is
plain Python + numpy (lxml for the URDF) and never imports rclpy; ``ros`` is the ROS 2 shell
around it (the ``inverse_dynamics`` node), ``sim`` the simulated robot, ``replay`` the
recorded data against the model, ``tools`` the demos and measurements on top of all of them.

    >>> import spatial_dynamics as sd
    >>> model = sd.Model.from_urdf('robot.urdf')          # doctest: +SKIP
    >>> tau = sd.rnea(model, q, qd, qdd)                  # doctest: +SKIP
"""

from .model import Frame, Model, with_payload
from .base import (base_from_imu, base_from_odometry, BaseMotion, floating_twin,
                   spatial_acceleration)
from .algorithms.configuration import integrate
from .algorithms.jacobian import jacobian
from .algorithms.rnea import rnea_spatial
from .backends import (bias_torque, forward_dynamics, generalized_momentum, GRAVITY,
                       gravity_torque, mass_matrix, regressor, rnea, rnea_derivatives)
from .contacts import Contact, contact_inverse_dynamics, contact_jacobian, ContactResult
from .terms import (armature_torque, clamp_to_effort_limits, friction_derivative,
                    friction_torque, per_joint)
from .urdf import URDFWarning

__all__ = ['BaseMotion', 'Frame', 'GRAVITY', 'Model', 'armature_torque', 'base_from_imu',
           'base_from_odometry', 'bias_torque', 'floating_twin', 'spatial_acceleration',
           'clamp_to_effort_limits', 'Contact', 'contact_inverse_dynamics',
           'contact_jacobian', 'ContactResult', 'forward_dynamics', 'friction_derivative',
           'friction_torque', 'generalized_momentum',
           'gravity_torque', 'integrate', 'jacobian', 'mass_matrix',
           'per_joint', 'regressor', 'rnea', 'rnea_derivatives', 'rnea_spatial',
           'URDFWarning', 'with_payload']
__version__ = '0.1.0'
