# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Time contact-consistent inverse dynamics per state from Python (Solo12 on four feet).

``python -m benchmarks.contacts`` (from the checkout): ``time.thread_time``, the minimum of
7 repeats of 300 calls, for ``contact_jacobian`` and ``contact_inverse_dynamics`` with each
method, on a standing Solo12 (example-robot-data).
"""

import os
import sysconfig
import time

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
    model = sd.Model.from_urdf(os.path.join(robots, 'solo_description', 'robots',
                                            'solo12.urdf'), base='floating')
    q, qd, qdd, feet = solo_standing(model)
    print(f'rnea (M q̈ + h):       {per_call(lambda: sd.rnea(model, q, qd, qdd)):8.1f} µs')
    t = per_call(lambda: sd.contact_jacobian(model, q, feet))
    print(f'contact_jacobian:       {t:8.1f} µs')
    for method in ('torques', 'forces', 'qp'):
        t = per_call(lambda: sd.contact_inverse_dynamics(model, q, qd, qdd, feet, method=method),
                     n=100 if method == 'qp' else 300)
        print(f'contact_inverse_dynamics {method!r:9} {t:8.1f} µs')


if __name__ == '__main__':
    main()
