# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Free-flyer RNEA against Pinocchio's ``JointModelFreeFlyer``: one call, and a batch.

``python -m benchmarks.floating`` (from the checkout; needs Pinocchio and example-robot-data):
per robot (Solo12, Talos reduced, G1) the single-call time of ``sd.rnea`` and ``pin.rnea`` on
the same state (``time.thread_time``, the minimum of 25 repeats of 3000 calls: the CPU time
of this thread, steady on a busy machine), and a batch of 10,000 states through ``sd.rnea``
against ``pin.rneaInParallel`` on 2 threads (wall time, minimum of 9 runs), with their
ratios. Our ``q̇ = [ω; v, joints]`` is Pinocchio's ``[v; ω, joints]``. Then Solo12 standing
on its four feet (point contacts): ``sd.contact_inverse_dynamics`` (``'torques'``, the
contact-consistent split) per state, on the compiled path and on numpy (thread time as
above, 25 repeats of 300 calls).
"""

import os
import time
import timeit

import numpy as np

ROBOTS = {'solo12': ('solo_description', 'robots', 'solo12.urdf'),
          'talos': ('talos_data', 'robots', 'talos_reduced.urdf'),
          'g1': ('g1_description', 'urdf', 'g1_29dof_rev_1_0.urdf')}


def main() -> None:
    import pinocchio as pin
    import spatial_dynamics as sd
    from benchmarks.bench import _erd_dir
    base = _erd_dir()
    rng = np.random.default_rng(0)
    for name, parts in ROBOTS.items():
        path = os.path.join(base, *parts)
        model = sd.Model.from_urdf(path, base='floating')
        pm = pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer())
        pd = pm.createData()
        assert pm.nq == model.nq, 'a continuous joint: map it as the tests do'
        quat = rng.normal(size=4)
        q = np.r_[rng.uniform(-1, 1, 3), quat / np.linalg.norm(quat),
                  rng.uniform(-1, 1, model.nq - 7)]
        v, a = rng.uniform(-1, 1, model.nv), rng.uniform(-1, 1, model.nv)

        def swap(x):
            return np.concatenate([x[..., 3:6], x[..., :3], x[..., 6:]], axis=-1)

        vp, ap = swap(v), swap(a)

        def cpu(f):
            timer = timeit.Timer(f, timer=time.thread_time)
            return min(timer.repeat(number=3000, repeat=25)) / 3000 * 1e6

        ours = cpu(lambda: sd.rnea(model, q, v, a))
        theirs = cpu(lambda: pin.rnea(pm, pd, q, vp, ap))
        N = 10000
        Q = np.tile(q, (N, 1))
        Q[:, 7:] += rng.uniform(-0.5, 0.5, (N, model.nq - 7))
        V, A = rng.uniform(-1, 1, (N, model.nv)), rng.uniform(-1, 1, (N, model.nv))
        Qp, Vp, Ap = (np.asfortranarray(x.T) for x in (Q, swap(V), swap(A)))
        pool = pin.ModelPool(pm, 2)

        def wall(f):
            return min(timeit.repeat(f, number=1, repeat=9)) / N * 1e6

        batch = wall(lambda: sd.rnea(model, Q, V, A))
        batch_pin = wall(lambda: pin.rneaInParallel(2, pool, Qp, Vp, Ap))
        print(f'{name} (nq {model.nq}, nv {model.nv}): sd.rnea {ours:.3f} µs, pin.rnea '
              f'{theirs:.3f} µs ({ours / theirs:.2f}x); batch of {N}: {batch:.3f} against '
              f'rneaInParallel {batch_pin:.3f} µs a state ({batch / batch_pin:.2f}x)')
        if name == 'solo12':
            contacts(model, cpu)


def solo_standing(model) -> tuple:
    """Return Solo12 standing, knees bent, with small random rates: ``(q, qd, qdd, feet)``."""
    import spatial_dynamics as sd
    q = np.zeros(model.nq)
    q[2], q[6] = 0.25, 1.0
    q[7:] = [0.0, 0.8, -1.6] * 2 + [0.0, -0.8, 1.6] * 2
    rng = np.random.default_rng(0)
    qd, qdd = rng.normal(size=(2, model.nv)) * 0.1
    return q, qd, qdd, [sd.Contact(f) for f in ('FL_FOOT', 'FR_FOOT', 'HL_FOOT', 'HR_FOOT')]


def contacts(model, cpu) -> None:
    """Print the contact inverse dynamics row: Solo12 standing on four point feet."""
    import spatial_dynamics as sd
    q, qd, qdd, feet = solo_standing(model)

    def per_state(backend, calls=300):
        timer = timeit.Timer(lambda: sd.contact_inverse_dynamics(
            model, q, qd, qdd, feet, backend=backend), timer=time.thread_time)
        return min(timer.repeat(number=calls, repeat=25)) / calls * 1e6

    fast, slow = per_state('auto'), per_state('numpy', 30)
    print(f'solo12 contact_inverse_dynamics (four point feet, \'torques\'): {fast:.1f} µs '
          f'a state; numpy backend {slow:.1f} µs ({slow / fast:.1f}x)')


if __name__ == '__main__':
    main()
