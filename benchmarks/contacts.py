# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Time contact-consistent inverse dynamics per state from Python (Solo12 on four feet).

``python -m benchmarks.contacts`` (from the checkout): ``contact_jacobian`` and
``contact_inverse_dynamics`` with each method, on a standing Solo12 (example-robot-data),
and in the same run Pinocchio's ``rnea`` and its four feet's Jacobians
(``computeJointJacobians`` + ``getFrameJacobian``) of the same state. Every implementation
is timed in interleaved rounds (:func:`benchmarks.bench.interleaved`: one block of ~20 ms of
each per round, the order rotated, the median over the rounds), so that a machine that
slows down or speeds up meanwhile hits all of them alike; each of ours is printed as a
multiple of Pinocchio's: the ratios hold on a busy machine, where the microseconds do not.
The load average (``uptime``'s) is printed with them.
"""

import os
import sysconfig

import numpy as np
import spatial_dynamics as sd

from .bench import interleaved
from .floating import solo_standing

#: Interleaved rounds, and the length of one block of calls (s).
ROUNDS = 15
BLOCK_S = 0.02


def main() -> None:
    robots = os.path.join(sysconfig.get_paths()['purelib'], 'cmeel.prefix', 'share',
                          'example-robot-data', 'robots')
    model_path = os.path.join(robots, 'solo_description', 'robots', 'solo12.urdf')
    model = sd.Model.from_urdf(model_path, base='floating')
    q, qd, qdd, feet = solo_standing(model)
    entries = {'rnea': (lambda: sd.rnea(model, q, qd, qdd), [()]),
               'jacobian': (lambda: sd.contact_jacobian(model, q, feet), [()])}
    for method in ('torques', 'forces', 'qp'):
        entries[method] = (lambda m=method: sd.contact_inverse_dynamics(
            model, q, qd, qdd, feet, method=m), [()])
    try:
        import pinocchio as pin
    except ImportError:
        pin = None
    if pin is not None:
        pm = pin.buildModelFromUrdf(model_path, pin.JointModelFreeFlyer())
        pd = pm.createData()
        frames = [pm.getFrameId(c.link) for c in feet]
        vp, ap = (np.r_[x[3:6], x[:3], x[6:]] for x in (qd, qdd))    # Pinocchio: [v; ω] first

        def jacobians():
            pin.computeJointJacobians(pm, pd, q)
            pin.updateFramePlacements(pm, pd)
            return [pin.getFrameJacobian(pm, pd, f, pin.LOCAL_WORLD_ALIGNED) for f in frames]
        entries['pin_rnea'] = (lambda: pin.rnea(pm, pd, q, vp, ap), [()])
        entries['pin_jacobians'] = (jacobians, [()])
    us = {name: t * 1e6 for name, t in interleaved(entries, ROUNDS, BLOCK_S, 1).items()}
    print(f'rnea (M q̈ + h):       {us["rnea"]:8.1f} µs')
    print(f'contact_jacobian:       {us["jacobian"]:8.1f} µs')
    for method in ('torques', 'forces', 'qp'):
        print(f'contact_inverse_dynamics {method!r:9} {us[method]:8.1f} µs')
    if pin is None:
        print('(Pinocchio is not installed: no ratios)')
        return
    pin_rnea, pin_jac = us['pin_rnea'], us['pin_jacobians']
    print(f'Pinocchio rnea:         {pin_rnea:8.1f} µs; the feet\'s Jacobians {pin_jac:8.1f} µs')
    print('load average (1, 5, 15 min): ' + ', '.join(f'{x:.2f}' for x in os.getloadavg()))
    print(f'ratios, same run: contact_jacobian {us["jacobian"] / pin_jac:.1f}x Pinocchio\'s '
          f'Jacobians; contact_inverse_dynamics torques {us["torques"] / pin_rnea:.1f}x, '
          f'forces {us["forces"] / pin_rnea:.1f}x, qp {us["qp"] / pin_rnea:.0f}x '
          f'Pinocchio\'s rnea')


if __name__ == '__main__':
    main()
