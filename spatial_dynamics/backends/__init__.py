# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""How an algorithm runs: each public function checks its arguments and picks a backend.

``backend=`` takes one of :data:`BACKENDS`, and means the same in every function:

* ``'numpy'``: the one source of :mod:`spatial_dynamics.algorithms` on Python floats (one
  state) or numpy arrays (a batch, any float dtype, computed in that dtype) — :mod:`.python`;
* ``'compiled'``: the C extension built with the package from the same source, for float64
  and float32 — :mod:`.compiled`; :class:`CompiledBackendUnavailable` when the package was
  built without a C compiler. float32 states are computed in float64 and the results
  returned as float32 (the dtype passed comes back, more accurate than float32 arithmetic);
  other float dtypes (``np.longdouble``, asked for its precision; float16) run on numpy;
* ``'auto'``: compiled when the extension was built, else numpy.

The result's dtype is that of q, qd, qdd (``tau`` in :func:`forward_dynamics`) promoted by
numpy (float32 only when all are float32, float16 only when all are float16; integers, lists
and tuples count as float64); gravity and ``f_ext`` do not change it. NaN or ±inf in any
input is answered, not refused: NaN (or ±inf) where it reaches, alike on both backends and
without a warning; what is not real numbers (text, ``None``, objects) is a ``TypeError``
naming the argument, the same on every path.

Nothing is compiled at run time. One state of any form (ndarray of float64, float32 or
integers with any strides, list, tuple, Python floats and ints, gravity as a tuple, list or
array) goes to the extension's single-state entry as it is, converted once in C; a batch is
made one C-contiguous float64 array and split over threads; anything else (other dtypes,
wrong shapes) takes the general path, which validates and names the argument. The model's
table is prepared once per model (:mod:`.layout`).
"""

from __future__ import annotations

import functools
from typing import Mapping, Optional, Sequence

import numpy as np

from . import compiled, layout, python
from .layout import LAYOUTS
from ..algorithms.arguments import (as_joint_arrays, as_vector, check_configuration,
                                    batch_of, f_ext_in_bodies, with_wrenches)
from ..algorithms.forward import PIVOT_TOL
from ..base import base_batches, BaseMotion, check_base_motion, floating_twin, twin_state
from ..model import Model
from ..terms import check_threshold, friction_derivative, per_joint
from ..text import at_state, shown

BACKENDS = ('auto', 'numpy', 'compiled')
#: Default gravity (m/s², root-link coordinates).
GRAVITY = (0.0, 0.0, -9.81)

_F8 = np.dtype(np.float64)
_KERNEL_DTYPES = compiled.DTYPES
_ndarray = np.ndarray
_NO_GRAVITY = (None, None, None)
_REAL = (float, int, np.floating, np.integer, np.bool_)     # (bool is an int)
_layout_of = LAYOUTS.get                 # bound once: the fast path is ~1 µs
_ext = compiled.ext
_c_rnea = _ext.rnea if _ext else None
_c_gravity_torque = _ext.gravity_torque if _ext else None
_c_bias_torque = _ext.bias_torque if _ext else None
_c_mass_matrix = _ext.mass_matrix if _ext else None
_c_momentum = _ext.generalized_momentum if _ext else None
_c_regressor = _ext.regressor if _ext else None
_c_derivatives = getattr(_ext, 'rnea_derivatives', None)     # None: a build before it
_c_forward = _ext.forward_dynamics if _ext else None


class CompiledBackendUnavailable(ImportError):
    """``backend='compiled'`` was asked for, but the package was built without the kernels."""


def kernels(model: Model, backend: str = 'auto'):
    """Return the compiled kernels of ``model`` if ``backend`` selects them, else ``None``.

    Raises ``ValueError`` for an unknown backend and :class:`CompiledBackendUnavailable` for
    ``'compiled'`` in a package built without a C compiler.
    """
    lay = _layout_of(id(model)) or layout.of(model)
    return lay.kernels if backend == 'auto' else _select(backend, lay)


def _entered(model: Model, backend: str, entry, *args) -> tuple:
    """Return ``model``'s layout, the kernels ``backend`` selects, and ``entry``'s answer.

    ``entry`` is the extension's single-state function (or ``None``: not called); its answer
    is ``None`` when there are no kernels or it declines the arguments (see :func:`kernels`).
    """
    lay = _layout_of(id(model)) or layout.of(model)
    kern = lay.kernels if backend == 'auto' else _select(backend, lay)
    return lay, kern, (None if kern is None or entry is None else entry(kern, *args))


def _select(backend: str, lay: layout.Layout):
    """Return the kernels ``backend`` selects for ``lay`` (see :func:`kernels`)."""
    if backend == 'numpy':
        return None
    _check(backend)
    return lay.kernels


def _check(backend: str) -> None:
    """Refuse an unknown backend, and ``'compiled'`` in a package built without the kernels."""
    if backend not in BACKENDS:
        raise ValueError(f'backend must be one of {BACKENDS}, got {shown(backend)}')
    if compiled.ext is None and backend == 'compiled':
        raise CompiledBackendUnavailable(
            "backend='compiled' needs the compiled kernels, which this installation was built "
            f'without ({compiled.FAILURE}); install a C compiler and the Python headers '
            '(Debian/Ubuntu: build-essential python3-dev) and build the package again '
            "(colcon build, pip install), or use backend='auto' or 'numpy'")


def rnea(model: Model, q, qd, qdd, gravity: Sequence[float] = GRAVITY,
         f_ext: Optional[Mapping[str, np.ndarray]] = None, backend: str = 'auto', *,
         base: Optional[BaseMotion] = None) -> np.ndarray:
    """Joint torques/forces ``τ = M(q) q̈ + C(q, q̇) q̇ + g(q) - Σ Jᵀ f_ext`` (RBDA table 5.1).

    Args:
        model: the robot.
        q, qd, qdd: joint positions (rad, m), velocities and accelerations in the order of
            ``model.joint_names``; shape (n,) or (..., n), broadcast against each other;
            arrays, lists or tuples of any real type. A floating-base model's ``q`` has
            ``model.nq`` numbers (the base's position and quaternion x y z w first: its norm
            within 1e-2 of 1, then normalised, any other a ``ValueError``), ``qd`` and
            ``qdd`` ``model.nv`` (the base's twist ``[ω; v]`` and its rate first, base
            frame); see doc/floating_base.md.
        gravity: gravitational acceleration (m/s²) in root-link coordinates (fixed base) or
            world coordinates (floating base), 3 numbers.
        f_ext: link name → spatial force ``[n; f]`` (N m, N), angular first, acting on that
            link and expressed in that link's frame; shape (6,) or broadcastable to (..., 6).
        backend: ``'auto'`` (compiled when the package was built with its kernels),
            ``'numpy'`` or ``'compiled'`` (float64 and float32; other dtypes run on numpy).
        base: a fixed-base model's base motion (:class:`~spatial_dynamics.base.BaseMotion`:
            its spatial velocity, spatial acceleration and orientation, batched like ``q``);
            ``None``: the base is fixed. See :mod:`spatial_dynamics.base` for gravity.

    Returns:
        τ (N m or N), shape (..., nv): the broadcast batch shape; float64, or the inputs'
        floating dtype. A floating base's first six are the wrench ``[n; f]`` on the base,
        in its frame.
    """
    if base is not None:
        return _on_base(rnea, model, base, q, qd, qdd, gravity, f_ext=f_ext,
                        backend=backend)[..., 6:]
    # no wrenches: None or an empty dict (anything else, validated by f_ext_in_bodies)
    no_wrench = f_ext is None or (type(f_ext) is dict and not f_ext)
    lay, kern, tau = _entered(model, backend, _c_rnea if no_wrench else None, q, qd, qdd,
                              gravity)
    if tau is not None:
        return tau
    if no_wrench:
        if kern is not None:
            if (type(q) is type(qd) is type(qdd) is _ndarray and q.ndim > 1
                    and qd.shape == qdd.shape and q.shape[:-1] == qd.shape[:-1]
                    and q.shape[-1] == lay.n and qd.shape[-1] == lay.nv
                    and q.dtype is qd.dtype is qdd.dtype and q.dtype in _KERNEL_DTYPES):
                # a batch of states of one shape and dtype: no broadcasting to work out
                g = GRAVITY if gravity is GRAVITY else _gravity(gravity)
                if g[0] is not None:
                    if model.free_flyers:
                        check_configuration(model, q)
                    if q.size == lay.n:     # one state with batch dimensions of 1
                        return _c_rnea(kern, q.reshape(-1), qd.reshape(-1), qdd.reshape(-1),
                                       g).reshape(qd.shape)
                    return compiled.rnea(lay, q, qd, qdd, g, {})
        else:
            # numpy: one float64 state on Python floats (lists and tuples converted once)
            if not (type(q) is type(qd) is type(qdd) is _ndarray):
                q, qd, qdd = _vector(q, lay.n), _vector(qd, lay.nv), _vector(qdd, lay.nv)
            if (type(q) is type(qd) is type(qdd) is _ndarray
                    and (q.dtype is qd.dtype is qdd.dtype is _F8)
                    and q.ndim == qd.ndim == qdd.ndim == 1
                    and len(q) == lay.n and len(qd) == len(qdd) == lay.nv):
                gx, gy, gz = GRAVITY if gravity is GRAVITY else _gravity(gravity)
                if gx is not None:
                    if model.free_flyers:
                        check_configuration(model, q)
                    return np.array(python.rnea_rows(lay.rows, q.tolist(), qd.tolist(),
                                                     qdd.tolist(), (gx, gy, gz)))
    return _rnea(model, lay, q, qd, qdd, gravity, f_ext, kern)


def gravity_torque(model: Model, q, gravity: Sequence[float] = GRAVITY,
                   backend: str = 'auto', *, base: Optional[BaseMotion] = None) -> np.ndarray:
    """Generalized gravity ``g(q)``: the torque that holds the robot still at ``q``.

    ``rnea(model, q, 0, 0, gravity)``; the kernels then skip every velocity and acceleration
    product (see :func:`~spatial_dynamics.algorithms.rnea.rnea_kernel`). ``q`` of shape (n,)
    or (..., n); returns τ of the same shape. Arguments as for :func:`rnea`; on a moving
    ``base``, the torque that holds the joints still while the base moves.
    """
    if base is not None:
        return _on_base(rnea, model, base, q, None, None, gravity, backend=backend)[..., 6:]
    lay, kern, tau = _entered(model, backend, _c_gravity_torque, q, gravity)
    if tau is not None:
        return tau
    if kern is None and type(q) is _ndarray and q.dtype is _F8 and q.shape == (lay.n,):
        return rnea(model, q, lay.zeros, lay.zeros, gravity, backend=backend)
    (q,) = as_joint_arrays(model, _vector(q, lay.n))
    zero = np.zeros(q.shape[:-1] + (lay.nv,), dtype=q.dtype)
    return rnea(model, q, zero, zero, gravity, backend=backend)


def bias_torque(model: Model, q, qd, gravity: Sequence[float] = GRAVITY,
                backend: str = 'auto', *, base: Optional[BaseMotion] = None) -> np.ndarray:
    """Bias forces ``C(q, q̇) q̇ + g(q)`` (Pinocchio's ``nonLinearEffects``): RNEA at q̈ = 0.

    ``q``, ``qd`` of shape (n,) or (..., n), broadcast; returns τ of the broadcast shape.
    Arguments as for :func:`rnea`; on a moving ``base`` its motion is in the bias, and
    ``rnea(q, q̇, q̈, base=b) = mass_matrix(q) q̈ + bias_torque(q, q̇, base=b)`` (``M`` does
    not depend on the base's motion).
    """
    if base is not None:
        return _on_base(rnea, model, base, q, qd, None, gravity, backend=backend)[..., 6:]
    lay, kern, tau = _entered(model, backend, _c_bias_torque, q, qd, gravity)
    if tau is not None:
        return tau
    if (kern is None and type(q) is type(qd) is _ndarray and q.dtype is qd.dtype is _F8
            and q.shape == (lay.n,) and qd.shape == lay.zeros.shape):
        return rnea(model, q, qd, lay.zeros, gravity, backend=backend)
    q, qd = as_joint_arrays(model, _vector(q, lay.n), _vector(qd, lay.nv))
    zero = np.zeros(qd.shape, dtype=qd.dtype)
    return rnea(model, q, qd, zero, gravity, backend=backend)


def mass_matrix(model: Model, q, backend: str = 'auto', *,
                base: Optional[BaseMotion] = None) -> np.ndarray:
    """Joint-space inertia ``M(q)`` by the composite rigid body algorithm (RBDA table 6.2).

    ``M`` is symmetric positive definite (for a model whose every joint moves some mass);
    ``τ = M(q) q̈ + bias_torque(q, q̇)``. ``q`` of shape (n,) or (..., n), arrays, lists or
    tuples; returns an array of shape (..., n, n), float64 or ``q``'s floating dtype.
    ``base`` (a moving base's :class:`~spatial_dynamics.base.BaseMotion`) is taken as the
    other functions take it and changes nothing: the joints' block ``M_jj`` of the floating
    twin is the composite inertia of the bodies beyond each joint, which depends on ``q``
    only, never on the base's motion (only broadcast against its batch).
    """
    if base is not None:
        check_base_motion(base, model)
        H = mass_matrix(model, q, backend)
        shape = batch_of((f'q of shape {np.shape(q)}', H.shape[:-2]),
                         *base_batches(base)) + H.shape[-2:]
        return H if H.shape == shape else np.broadcast_to(H, shape).copy()
    lay, kern, H = _entered(model, backend, _c_mass_matrix, q)
    if H is not None:
        return H
    (q,) = as_joint_arrays(model, _vector(q, lay.n))
    if kern is not None and q.dtype in _KERNEL_DTYPES:
        return compiled.mass_matrix(lay, q)
    return python.mass_matrix(lay.rows, q)


def generalized_momentum(model: Model, q, qd, backend: str = 'auto', *,
                         base: Optional[BaseMotion] = None) -> tuple:
    """``(p, Cᵀ q̇)``: the generalized momentum ``p = M(q) q̇`` and ``Cᵀ(q, q̇) q̇``, in O(n).

    What a momentum observer of external torques integrates (``ṗ = τ + Cᵀ q̇ - g + τ_ext``);
    ``Cᵀ q̇ = ∂T/∂q`` for the kinetic energy ``T = ½ q̇ᵀ M q̇``, and ``Ṁ q̇ = C q̇ + Cᵀ q̇``
    (see :mod:`spatial_dynamics.algorithms.momentum`). ``q``, ``qd`` of shape (n,) or
    (..., n), broadcast; returns two arrays of the broadcast shape.

    On a moving ``base`` (its twist ``v_b``; its acceleration is not used) the joint rows of
    the floating twin's, with ``ν = [v_b; q̇]``::

        p = M_jb v_b + M_jj q̇,    Cᵀ q̇ → (Cᵀ(q, ν) ν)_j = ∂T(q, ν)/∂q

    and still ``ṗ = τ + (Cᵀ ν)_j − g_j + τ_ext``, ``g_j`` the gravity torque at the base's
    orientation (``gravity_torque(q, base=BaseMotion.at_rest(orientation))``): the joints
    are true coordinates, so their Lagrange equations hold as on a fixed base.
    """
    if base is not None:
        check_base_motion(base, model)
        twin = floating_twin(model)
        q, qd, _, _ = twin_state(model, base, q, qd)
        p, ctv = generalized_momentum(twin, q, qd, backend)
        return p[..., 6:], ctv[..., 6:]
    lay, kern, out = _entered(model, backend, _c_momentum, q, qd)
    if out is not None:
        return out
    q, qd = as_joint_arrays(model, q, qd)
    if kern is not None and q.dtype in _KERNEL_DTYPES:
        return compiled.momentum(lay, q, qd)
    return python.momentum(lay.rows, q, qd)


def regressor(model: Model, q, qd, qdd, gravity: Sequence[float] = GRAVITY,
              backend: str = 'auto', *, base: Optional[BaseMotion] = None) -> np.ndarray:
    """Return the joint-torque regressor ``Y`` (..., n, 10·NB): ``rnea(...) = Y @ π``.

    ``π`` stacks the ten inertial parameters ``m, m c, Ī`` (:data:`~spatial_dynamics.
    algorithms.regressor.PARAMETERS`) of each moving body ``model.body_names[1:]``
    (:func:`~spatial_dynamics.algorithms.regressor.parameters` gives the model's own); see
    :mod:`spatial_dynamics.algorithms.regressor`. Arguments as for :func:`rnea` (no
    ``f_ext``: external wrenches do not depend on the inertias); float64, or the inputs'
    floating dtype. On a moving ``base`` the columns are those of the same bodies.
    """
    if base is not None:
        Y = _on_base(regressor, model, base, q, qd, qdd, gravity, backend=backend)
        return Y[..., 6:, 10:]      # the twin's body 1 (the base) is none of model's bodies
    lay, kern, Y = _entered(model, backend, _c_regressor, q, qd, qdd, gravity)
    if Y is not None:
        return Y
    q, qd, qdd = as_joint_arrays(model, q, qd, qdd)
    g = tuple(as_vector('gravity', gravity, 3).tolist())
    if kern is not None and q.dtype in _KERNEL_DTYPES:
        if q.size == q.shape[-1] > 0:       # one state with batch dimensions of 1
            Y = _c_regressor(kern, *(x.reshape(-1) for x in (q, qd, qdd)), g)
            return Y.reshape(q.shape[:-1] + Y.shape)
        return compiled.regressor(lay, q, qd, qdd, g)
    return python.regressor(lay.rows, q, qd, qdd, g)


def forward_dynamics(model: Model, q, qd, tau, gravity: Sequence[float] = GRAVITY,
                     f_ext: Optional[Mapping[str, np.ndarray]] = None, backend: str = 'auto',
                     *, base: Optional[BaseMotion] = None, armature=None) -> np.ndarray:
    """Joint accelerations ``q̈ = (M + diag(armature))⁻¹ (τ - C(q, q̇) q̇ - g(q) + Σ Jᵀ f_ext)``.

    The exact inverse of :func:`rnea`: ``rnea(model, q, qd, forward_dynamics(model, q, qd,
    tau, ...), ...) == tau`` to rounding, with the same arguments (``q``, ``qd``, ``gravity``,
    ``f_ext``, ``backend``, ``base``; ``tau`` (..., nv) in place of ``qdd``), checked and
    refused as :func:`rnea` checks them. The articulated-body algorithm (RBDA table 7.1,
    :mod:`spatial_dynamics.algorithms.aba`), one C call a state on the compiled backend,
    batches on threads; where two bodies share a coordinate (a mimic joint), on a moving
    ``base`` and for a batch with armature: ``M`` from CRBA (RBDA table 6.2), the bias ``h``
    from RNEA at ``q̈ = 0``, then ``M q̈ = τ - h`` by the sparse ``LᵀL`` factorization of
    RBDA §6.5 (:mod:`spatial_dynamics.algorithms.forward`).

    A floating-base model's ``tau`` has the base's six rows first: the wrench ``[n; f]`` on
    the base (base frame), zero for a robot in free flight, as :func:`rnea` returns it; ``q̈``
    then has the base's spatial acceleration first. On a moving ``base`` the base's motion is
    given, and ``q̈`` are the joints' accelerations.

    Drive terms: ``armature`` (per joint: what :func:`~spatial_dynamics.per_joint` takes,
    kg m² or kg) multiplies ``q̈`` and is added to ``M``'s diagonal, so ``τ = rnea(q, q̇, q̈)
    + armature_torque(armature, q̈)``. Terms of ``q̇`` only (``friction_torque``) are known
    before ``q̈``: subtract them from ``tau``. ``ValueError`` when ``M`` (with the armature)
    is not positive definite, naming the joint: a joint that moves no mass and has no
    armature has no acceleration that ``τ`` decides. The message names the joints that
    repeat its motion and what the library takes to remove it (armature on one of them; for
    a floating base's massless root link, armature on the joint that repeats the base's
    motion or an ``<inertial>`` on the link: the free-flyer has no drive). Refused is a joint
    whose motion the rest of its subtree can make without it to within
    :data:`~spatial_dynamics.algorithms.forward.PIVOT_TOL` (1e-12) of its inertia: the
    pivot ``d_k`` of ``M``'s factorization from the leaves (ABA's ``D_i``) at most
    ``PIVOT_TOL M_kk``, every path alike (one state or a batch, either backend, armature, a
    moving base). Exactly singular, rounding leaves ``d_k / M_kk`` at 1e-13 or less, and
    ``q̈`` would be ~1e16 and wrong; the robots of example-robot-data have 2e-6 and more at
    random states (1e-9 within 1e-4 rad of a ball joint's gimbal lock through massless
    links, where ``M`` is singular). ``d_k / M_kk >= 1 / cond(M)``: an ``M`` whose
    condition number is below 1e12 is never refused.

    Returns:
        q̈ (rad/s², m/s²), shape (..., nv): the broadcast batch shape; float64, or the inputs'
        floating dtype (float32 and float16 states computed in float64 and rounded once: in
        their own precision a singular ``M`` would not be told from rounding).
    """
    if base is None and armature is None and (f_ext is None or (type(f_ext) is dict
                                                                and not f_ext)):
        lay, kern, qdd = _entered(model, backend, _c_forward, q, qd, tau, gravity)
        if qdd is not None:
            return qdd
    return _forward(model, q, qd, tau, gravity, f_ext, backend, base, armature)


def _forward(model: Model, q, qd, tau, gravity, f_ext, backend: str,
             base: Optional[BaseMotion], armature) -> np.ndarray:
    """Run :func:`forward_dynamics` beyond its single-state entry: checks, terms, batches."""
    low = _narrow_float(q, qd, tau)
    if low is not None:
        # float32 / float16 states: q̈ computed in float64 and rounded once. In their own
        # precision M's pivots keep ~eps M_kk of rounding (1e-8, 1e-3), far above
        # PIVOT_TOL: a singular M would answer q̈ of no digit instead of being refused
        wide = (x.astype(np.float64) for x in (q, qd, tau))
        return _forward(model, *wide, gravity, f_ext, backend, base, armature).astype(low)
    lay, kern, _ = _entered(model, backend, None)
    if base is None:
        q, qd, tau = as_joint_arrays(model, q, qd, tau, names=('q', 'qd', 'tau'))
        g = tuple(as_vector('gravity', gravity, 3).tolist())
        fb = f_ext_in_bodies(model, f_ext)
        arm = (None if armature is None
               else per_joint(model, 'armature', armature, nonnegative=True))
        if fb:  # batched wrenches broadcast against the batch of states
            q, qd, tau = with_wrenches(f_ext, [q, qd, tau], ('q', 'qd', 'tau'))
        single = q.size == q.shape[-1] > 0
        if kern is not None and q.dtype in _KERNEL_DTYPES:
            if single:
                fext = (compiled.f_body_table(lay, {b: np.reshape(f, -1) for b, f in fb.items()})
                        if fb else None)
                qdd = _c_forward(kern, *(x.reshape(-1) for x in (q, qd, tau)), g, fext, arm)
                if qdd is not None:
                    return qdd.reshape(tau.shape)
            elif arm is None:
                qdd = compiled.forward_dynamics(lay, q, qd, tau, g, fb)
                if not np.isnan(qdd).any():
                    return qdd
        elif single and q.dtype == np.float64 and tau.dtype == np.float64:
            # the articulated-body algorithm on floats, as the compiled kernels run it
            qdd, info = python.aba_rows(
                lay.rows, *(x.reshape(-1).tolist() for x in (q, qd, tau)), g,
                {b: np.reshape(f, -1)[-6:].tolist() for b, f in fb.items()},
                None if arm is None else arm.tolist())
            if info == -1:
                return np.array(qdd).reshape(tau.shape)
    # M, and the bias h: rnea at q̈ = 0 with every term rnea takes (and checks)
    zero = np.zeros(lay.nv, dtype=np.float16)      # the least float: q, q̇ decide the dtype
    h = rnea(model, q, qd, zero, gravity, f_ext, backend, base=base)
    H = mass_matrix(model, q, backend)
    (tau,) = as_joint_arrays(model, tau, names=('tau',))
    if armature is not None:
        H = H + np.diag(per_joint(model, 'armature', armature, nonnegative=True))
    b = tau - h
    qdd, failed = python.forward_solve(lay.rows, H.astype(b.dtype, copy=False), b)
    if failed is None:
        return qdd
    state, k = failed
    where = at_state(np.unravel_index(state, b.shape[:-1]))
    Hs = np.broadcast_to(H, b.shape[:-1] + H.shape[-2:]).reshape((-1,) + H.shape[-2:])[state]
    names = model.joint_names
    joint = names[0] if model.floating and k < 6 else names[k - 5 if model.floating else k]
    raise ValueError(f'forward_dynamics: M(q){" + armature" if armature is not None else ""} '
                     f'is not positive definite at velocity coordinate {k}, joint {shown(joint)}'
                     f'{where}: ' + _singular_reason(model, Hs.astype(float), k))


def _singular_reason(model: Model, H: np.ndarray, k: int) -> str:
    """Say why ``H`` (nv, nv) has no pivot ``k`` above ``PIVOT_TOL H_kk`` and what removes it.

    The factorization (:mod:`~spatial_dynamics.algorithms.forward`) runs from the last
    coordinate back: ``H[k+1:, k+1:]`` is positive definite, and the motion ``δ`` with
    ``δ_k = 1`` that moves no mass (to within the tolerance) has its later coordinates from
    it. Its joints are those
    that repeat coordinate ``k``'s motion; armature on any of them removes the singularity,
    on the free-flyer none (it has no drive: its root link needs an ``<inertial>``). In
    parentheses the pivot ``d_k = H_kk + H[k, k+1:] δ[k+1:]`` against the tolerance
    (``d_k / H_kk >= 1 / cond(H)``; ``H`` exactly singular leaves a few eps ``H_kk``).
    """
    later = np.linalg.solve(H[k + 1:, k + 1:], -H[k + 1:, k]) if k + 1 < len(H) else H[:0, 0]
    pivot = ('(M_kk = 0)' if not H[k, k] > 0.0 else
             f'(pivot d_k = {(H[k, k] + H[k, k + 1:] @ later) / H[k, k]:.1e} M_kk, at most '
             f'PIVOT_TOL = {PIVOT_TOL:.0e} M_kk; an exactly singular M leaves ~1e-16)')
    names, base, nv = model.joint_names, 6 if model.floating else 0, len(H)
    size = np.abs(later)
    small = 1e-6 * max(1.0, size.max(initial=0.0))
    # the joint of velocity coordinate c: one each, after the free-flyer's six
    repeating = [names[c - base + (1 if base else 0)]
                 for c in range(max(k + 1, base), nv) if size[c - k - 1] > small]
    joints = ', '.join(shown(j) for j in dict.fromkeys(repeating))
    if k < base:
        root = shown(model.body_names[1])
        if not repeating:
            return (f'the floating base moves no mass along it {pivot}: its root link {root} '
                    '(with the links fixed to it) needs an <inertial> (the free-flyer has no '
                    'drive to give armature)')
        return (f'the floating base\'s motion along it is repeated by the joint(s) {joints} '
                f'and its root link {root} has no mass of its own {pivot}, so no acceleration '
                f'of it follows from tau; give {joints} armature, or the root link an '
                '<inertial> (the free-flyer has no drive to give armature)')
    if not repeating:
        return (f'the joint moves no mass {pivot}, so no acceleration of it follows from tau; '
                'give it armature')
    return (f'the joint moves no mass that the joint(s) {joints} do not move too {pivot}, so '
            f'no acceleration of it follows from tau; give it or {joints} armature')


def rnea_derivatives(model: Model, q, qd, qdd, gravity: Sequence[float] = GRAVITY,
                     f_ext: Optional[Mapping[str, np.ndarray]] = None, backend: str = 'auto',
                     *, base: Optional[BaseMotion] = None, armature=None,
                     friction_threshold: Optional[float] = None,
                     out: Optional[Sequence[np.ndarray]] = None) -> tuple:
    """Return ``(∂τ/∂q, ∂τ/∂q̇, M)`` of :func:`rnea`, analytically (Carpentier & Mansard 2018).

    Each of shape (..., nv, nv), row ``r`` the derivative of ``τ[r]``, column ``c`` that with
    respect to coordinate ``c``: ``τ(q ⊕ δ, q̇ + ε, q̈ + η) ≈ τ + ∂τ/∂q δ + ∂τ/∂q̇ ε + M η``.
    ``∂τ/∂q̈ = M`` is :func:`mass_matrix`. On a floating base the configuration is moved on
    its tangent space: ``q ⊕ δ`` is ``integrate(model, q, δ, 1)`` (the free-flyer's twist
    ``[ω; v]`` in its own frame, then the joints), so ``∂τ/∂q`` is ``nv × nv``, as
    Pinocchio's ``computeRNEADerivatives`` (its base rows and columns linear first: see
    doc/floating_base.md). See :mod:`spatial_dynamics.algorithms.derivatives`.

    Arguments as for :func:`rnea` (and refused as it refuses them), with the drive terms of
    :mod:`spatial_dynamics.terms` that depend on the state: ``armature`` (a
    :func:`~spatial_dynamics.terms.per_joint` value, kg m² or kg) adds ``diag(armature)``
    to ``M``; ``friction_threshold`` (rad/s or m/s) adds the derivative of
    :func:`~spatial_dynamics.terms.friction_torque` (the URDF's ``<dynamics>``) to
    ``∂τ/∂q̇``. On a moving ``base`` the derivatives with respect to the joints of the joint
    rows (the base's motion is given, not a coordinate).

    ``out``: three arrays ``(dq, dv, M)`` to write the results into (a controller's loop that
    allocates nothing, as Pinocchio's ``data``), each numpy, writeable, of the result's shape
    (..., nv, nv) and dtype, sharing no memory with an input or with each other; that tuple's
    arrays are returned. C-contiguous float64 ones are written in place by the compiled
    kernels (one state and batches), any others get a copy. ``TypeError`` or ``ValueError``
    naming ``out[k]`` when they are not such arrays (a masked array, one overlapping itself
    too). A refused call leaves ``out`` as it was.
    """
    if (base is None and armature is None and friction_threshold is None
            and (f_ext is None or (type(f_ext) is dict and not f_ext))):
        # one state that the extension reads as it is: answered in C; into out when the
        # entry sees that it can (a tuple of arrays whose bounds meet no argument's)
        lay, kern, D = _entered(model, backend, _c_derivatives, q, qd, qdd, gravity,
                                *(() if out is None else (None, out)))
        if D is not None:
            return D
    if out is not None:
        out = _out_arrays(out, (('q', q), ('qd', qd), ('qdd', qdd), ('gravity', gravity),
                                ('f_ext', f_ext), ('armature', armature)))
    # the drive terms checked before anything is written into out: a refused call leaves it
    if armature is not None:
        armature = per_joint(model, 'armature', armature, nonnegative=True)
    if friction_threshold is not None:
        friction_threshold = check_threshold(friction_threshold, 'friction_threshold')
    if base is not None:
        check_base_motion(base, model)
        twin = floating_twin(model)
        tq, tqd, tqdd, tg = twin_state(model, base, q, qd, qdd, gravity)
        res = rnea_derivatives(twin, tq, tqd, tqdd, tg, f_ext, backend)
        res = tuple(x[..., 6:, 6:] for x in res)
        return _drive_terms(model, res, qd, armature, friction_threshold, out)
    lay = _layout_of(id(model)) or layout.of(model)
    kern = lay.kernels if backend == 'auto' else _select(backend, lay)
    q, qd, qdd, g, fb = _states(model, q, qd, qdd, gravity, f_ext)
    if out is not None:
        _check_out(out, qd.shape + (lay.nv,), q.dtype)
    if kern is not None and _c_derivatives is not None and q.dtype in _KERNEL_DTYPES:
        if q.size == q.shape[-1] > 0:
            # One state (maybe with batch dimensions of 1): the single-state entry.
            fext = (compiled.f_body_table(lay, {b: np.reshape(f, -1) for b, f in fb.items()})
                    if fb else None)
            vectors = [x.reshape(-1) for x in (q, qd, qdd)]
            direct = out is not None and q.ndim == 1 and q.dtype == _F8
            D = _c_derivatives(kern, *vectors, g, fext, out) if direct else None
            if D is None:   # no out, or out that the entry declines: new arrays to copy
                D = _c_derivatives(kern, *vectors, g, fext)
            res = tuple(x.reshape(qd.shape + (lay.nv,)) for x in D)
        else:
            res = compiled.derivatives(lay, q, qd, qdd, g, fb, out)
    else:
        res = python.derivatives(lay.rows, q, qd, qdd, g, fb)
    return _drive_terms(model, res, qd, armature, friction_threshold, out)


def _out_arrays(out, inputs: tuple) -> tuple:
    """Return ``out`` of :func:`rnea_derivatives` as a tuple of three writeable arrays.

    ``inputs``: (name, value) of the call's arguments; ``ValueError`` naming ``out[k]`` and
    the argument it shares memory with (or the other ``out[j]``). Bounds first
    (``may_share_memory``, cheap), then exactly: three views of one stacked array are fine.
    """
    if not isinstance(out, (tuple, list)) or len(out) != 3:
        got = (f'{type(out).__name__} of shape {out.shape}' if isinstance(out, _ndarray)
               else f'a {type(out).__name__} of {len(out)}' if isinstance(out, (tuple, list))
               else type(out).__name__)
        hint = (': tuple(a) gives the three of a stacked (3, nv, nv) array'
                if isinstance(out, _ndarray) and out.shape[:1] == (3,) else '')
        raise TypeError(f'out must be a tuple (or list) of three numpy arrays (dq, dv, M), '
                        f'got {got}{hint}')
    for k, x in enumerate(out):
        if not isinstance(x, _ndarray) or isinstance(x, np.ma.MaskedArray):
            raise TypeError(f'out[{k}] must be a numpy array (not masked), got '
                            f'{type(x).__name__}')
        if not x.flags.writeable:
            raise ValueError(f'out[{k}] must be writeable (it is read-only)')
        if _overlaps_itself(x):
            raise ValueError(f'out[{k}] overlaps itself (strides {x.strides} for shape '
                             f'{x.shape}): its states would be written over each other')
    given = [(name, a) for name, value in inputs for a in _arrays_in(value)]
    for k, x in enumerate(out):
        others = [(f'out[{j}]', out[j]) for j in range(k)] + given
        for name, a in others:
            if np.may_share_memory(x, a) and np.shares_memory(x, a):
                raise ValueError(f'out[{k}] shares memory with {name}: the results would '
                                 'overwrite it; pass separate arrays')
    return tuple(out)


def _overlaps_itself(x: np.ndarray) -> bool:
    """Tell whether two elements of ``x`` may lie at one address (a stride of 0, say).

    Sufficient test: each axis' stride (largest last) passes over all the smaller axes'
    extent. An interleaving that never meets but fails it is refused too (none is usual).
    """
    reach = x.itemsize
    for stride, dim in sorted((abs(s), d) for s, d in zip(x.strides, x.shape) if d > 1):
        if stride < reach:
            return True
        reach += stride * (dim - 1)
    return False


def _arrays_in(value) -> list:
    """Return the numpy arrays in an argument: itself, or those in a dict's values or a list.

    (A :class:`~spatial_dynamics.base.BaseMotion` holds copies of its own.)
    """
    if isinstance(value, _ndarray):
        return [value]
    if isinstance(value, dict):
        return [a for x in value.values() for a in _arrays_in(x)]
    if isinstance(value, (list, tuple)):
        return [a for x in value for a in _arrays_in(x)]
    return []


def _check_out(out: tuple, shape: tuple, dtype) -> None:
    """Refuse ``out`` arrays that are not of the results' ``shape`` and ``dtype``."""
    for k, x in enumerate(out):
        if x.shape != shape or x.dtype != dtype:
            want = np.dtype(dtype)
            raise ValueError(f'out[{k}] must be an array of the result\'s shape {shape} and '
                             f'dtype {want} ({want.str!r}), got shape {x.shape} and dtype '
                             f'{x.dtype} ({x.dtype.str!r})')


def _narrow_float(*arrays) -> Optional[np.dtype]:
    """Return float32 or float16 when the arrays are all of them (the result's dtype), else None.

    Only numpy arrays of a floating dtype count: anything else goes the usual way (and its
    checks), so that nothing is converted here that the checks would refuse.
    """
    if not all(type(x) is _ndarray and x.dtype.kind == 'f' for x in arrays):
        return None
    dtype = np.result_type(*arrays)
    return dtype if dtype in (np.float32, np.float16) else None


def _drive_terms(model: Model, res: tuple, qd, armature, friction_threshold,
                 out: Optional[tuple] = None) -> tuple:
    """Add the drive terms' derivatives to ``(∂τ/∂q, ∂τ/∂q̇, M)`` (:func:`rnea_derivatives`).

    ``out``: the caller's arrays: the sums are made in those of ``res`` that are they (written
    in place), the rest copied into them (after :func:`_check_out`).
    """
    dq, dv, M = res
    if armature is not None:     # checked (per_joint's array); in the states' dtype
        M = np.add(M, np.diag(armature).astype(M.dtype, copy=False),
                   out=M if out is not None and M is out[2] else None)
    if friction_threshold is not None:      # checked (check_threshold's float)
        dv = np.add(dv, friction_derivative(model, qd, friction_threshold).astype(
            dv.dtype, copy=False), out=dv if out is not None and dv is out[1] else None)
    if out is None:
        return dq, dv, M
    if not all(x is o for x, o in zip((dq, dv, M), out)):
        _check_out(out, M.shape, M.dtype)
        for o, x in zip(out, (dq, dv, M)):
            if x is not o:
                np.copyto(o, x)
    return out


def _on_base(algorithm, model: Model, base: BaseMotion, q, qd, qdd, gravity, **options):
    """Run ``algorithm`` for a fixed-base ``model`` on a moving ``base`` (all ``nv + 6`` rows).

    The floating twin's (:func:`~spatial_dynamics.base.floating_twin`) with the base's rows
    given by ``base``; the compiled kernels run it as any floating-base model.
    """
    check_base_motion(base, model)
    twin = floating_twin(model)
    q, qd, qdd, gravity = twin_state(model, base, q, qd, qdd, gravity)
    return algorithm(twin, q, qd, qdd, gravity, **options)


def _vector(x, n: int):
    """Return a list or tuple of ``n`` real numbers as a float64 array, anything else as it is.

    Real numbers as numpy reads them (booleans, integers, floats: what
    :func:`~spatial_dynamics.algorithms.arguments.as_real_array` takes); text (``'0.1'``),
    ``None`` or ``Decimal`` is left as it is, for :func:`as_joint_arrays` to refuse naming the
    argument as every other path does (float64 would read ``'0.1'`` as 0.1, ``None`` as NaN).
    """
    if (type(x) is list or type(x) is tuple) and len(x) == n:
        try:
            a = np.array(x)
        except (TypeError, ValueError):
            return x    # ragged: refused where it is validated
        if a.ndim == 1 and a.dtype.kind in 'biuf':
            return a.astype(_F8, copy=False)
    return x


def _gravity(gravity):
    """``gravity`` as three Python floats, or three Nones (the general path validates it).

    Only real numbers are converted (Python's or numpy's booleans, integers and floats, what
    :func:`~spatial_dynamics.algorithms.arguments.as_real_array` takes); text such as
    ``'9.81'`` goes to the general path, which refuses it naming ``gravity``.
    """
    if (type(gravity) is tuple or type(gravity) is list) and len(gravity) == 3:
        gx, gy, gz = gravity
        if type(gx) is float and type(gy) is float and type(gz) is float:
            return gravity
        if isinstance(gx, _REAL) and isinstance(gy, _REAL) and isinstance(gz, _REAL):
            return float(gx), float(gy), float(gz)
        return _NO_GRAVITY
    if type(gravity) is _ndarray and gravity.shape == (3,) and gravity.dtype.kind in 'fiu':
        return (gravity if gravity.dtype is _F8 else gravity.astype(_F8)).tolist()
    return _NO_GRAVITY


def _states(model: Model, q, qd, qdd, gravity, f_ext) -> tuple:
    """Return q, q̇, q̈ checked (broadcast against batched wrenches), gravity, body wrenches."""
    q, qd, qdd = as_joint_arrays(model, q, qd, qdd)
    g = tuple(as_vector('gravity', gravity, 3).tolist())
    fb = f_ext_in_bodies(model, f_ext)
    if fb:  # batched wrenches broadcast against the batch of states
        q, qd, qdd = with_wrenches(f_ext, [q, qd, qdd], ('q', 'qd', 'qdd'))
    return q, qd, qdd, g, fb


def _rnea(model: Model, lay: layout.Layout, q, qd, qdd, gravity, f_ext,
          kern) -> np.ndarray:
    """Run :func:`rnea` for all its fast path leaves: validation, wrenches, batches."""
    q, qd, qdd, g, fb = _states(model, q, qd, qdd, gravity, f_ext)
    if kern is not None and q.dtype in _KERNEL_DTYPES:
        if q.size == q.shape[-1] > 0:
            # One state (maybe with batch dimensions of 1): the single-state entry.
            fext = (compiled.f_body_table(lay, {b: np.reshape(f, -1) for b, f in fb.items()})
                    if fb else None)
            tau = _c_rnea(kern, *(x.reshape(-1) for x in (q, qd, qdd)), g, fext)
            return tau.reshape(qd.shape)
        return compiled.rnea(lay, q, qd, qdd, g, fb)
    return python.rnea(lay.rows, q, qd, qdd, g, fb)


def describe(backend: str = 'auto') -> str:
    """Name the backend that ``backend`` selects, for logs: e.g. ``'compiled (C extension, …)'``.

    Raises as :func:`kernels` does.
    """
    if backend == 'numpy':
        return 'numpy'
    _check(backend)
    return compiled.describe()


def warmup(model: Model, backend: str = 'auto') -> str:
    """Prepare ``model``'s table for the backend (once per model) and return :func:`describe`.

    Nothing is compiled: the kernels are compiled when the package is built.
    """
    kernels(model, backend)
    return describe(backend)


def _doors() -> None:
    """Enter the public functions in C when the extension is there (:class:`_compiled.Door`).

    One state with the default or a given gravity, no ``f_ext`` and backend ``'auto'`` or
    ``'compiled'`` is answered in C without the Python frame of the function (~0.2 µs); any
    other call goes to the function itself, unchanged. Each door carries the function's
    name, docstring and signature (``__wrapped__``). The extension names the functions it
    has an entry for (``ALGORITHMS``, in the order of the doors' kinds).
    """
    g = globals()
    for kind, name in enumerate(_ext.ALGORITHMS):
        function = g.get(name)
        if function is None:    # an entry no public function of this module has (bodies)
            continue
        g[name] = functools.update_wrapper(_ext.Door(function, kind, layout.KERNELS, GRAVITY),
                                           function)


if _ext is not None:
    _doors()


def prepare_compiled(timeout: Optional[float] = None) -> None:
    """Nothing to prepare: the kernels are compiled when the package is built.

    Kept for the node until it drops its preparation step; raises
    :class:`CompiledBackendUnavailable` when the package was built without the kernels.
    """
    _check('compiled')
