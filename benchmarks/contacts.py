# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Time contact-consistent inverse dynamics per state from Python (Solo12 on four feet).

``python -m benchmarks.contacts`` (from the checkout): ``time.thread_time``, the minimum of
7 repeats of 300 calls, for ``contact_jacobian`` and ``contact_inverse_dynamics`` with each
method, on a standing Solo12 (example-robot-data); and, in the same run, Pinocchio's ``rnea``
and its four feet's Jacobians (``computeJointJacobians`` + ``getFrameJacobian``) of the same
state, with each of ours as a multiple of them: the ratios hold on a busy machine, where the
microseconds do not. The load average (``uptime``'s) is printed with them.
"""

import os
import sysconfig
import time

import numpy as np
import spatial_dynamics as sd

from .floating import solo_standing


def per_call(f, n=300, repeats=7) -> float:
    """Return the least thread time of one call of ``f`` (µs) over ``repeats`` runs."""
    best = float('inf')
    for _ in range(repeats):
        t = time.thread_time()
        for _ in range(n):
            f()
        best = min(best, (time.thread_time() - t) / n)
    return best * 1e6


def main() -> None:
    robots = os.path.join(sysconfig.get_paths()['purelib'], 'cmeel.prefix', 'share',
                          'example-robot-data', 'robots')
    model_path = os.path.join(robots, 'solo_description', 'robots', 'solo12.urdf')
    model = sd.Model.from_urdf(model_path, base='floating')
    q, qd, qdd, feet = solo_standing(model)
    print(f'rnea (M q̈ + h):       {per_call(lambda: sd.rnea(model, q, qd, qdd)):8.1f} µs')
    t = per_call(lambda: sd.contact_jacobian(model, q, feet))
    print(f'contact_jacobian:       {t:8.1f} µs')
    ours = {'jacobian': t}
    for method in ('torques', 'forces', 'qp'):
        t = per_call(lambda: sd.contact_inverse_dynamics(model, q, qd, qdd, feet, method=method),
                     n=100 if method == 'qp' else 300)
        ours[method] = t
        print(f'contact_inverse_dynamics {method!r:9} {t:8.1f} µs')
    try:
        import pinocchio as pin
    except ImportError:
        print('(Pinocchio is not installed: no ratios)')
        return
    pm = pin.buildModelFromUrdf(model_path, pin.JointModelFreeFlyer())
    pd = pm.createData()
    frames = [pm.getFrameId(c.link) for c in feet]
    vp, ap = (np.r_[x[3:6], x[:3], x[6:]] for x in (qd, qdd))    # Pinocchio: [v; ω] first

    def jacobians():
        pin.computeJointJacobians(pm, pd, q)
        pin.updateFramePlacements(pm, pd)
        return [pin.getFrameJacobian(pm, pd, f, pin.LOCAL_WORLD_ALIGNED) for f in frames]

    pin_rnea = per_call(lambda: pin.rnea(pm, pd, q, vp, ap))
    pin_jac = per_call(jacobians)
    print(f'Pinocchio rnea:         {pin_rnea:8.1f} µs; the feet\'s Jacobians {pin_jac:8.1f} µs')
    print('load average (1, 5, 15 min): ' + ', '.join(f'{x:.2f}' for x in os.getloadavg()))
    print(f'ratios, same run: contact_jacobian {ours["jacobian"] / pin_jac:.1f}x Pinocchio\'s '
          f'Jacobians; contact_inverse_dynamics torques {ours["torques"] / pin_rnea:.1f}x, '
          f'forces {ours["forces"] / pin_rnea:.1f}x, qp {ours["qp"] / pin_rnea:.0f}x '
          f'Pinocchio\'s rnea')


if __name__ == '__main__':
    main()
