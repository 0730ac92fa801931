# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""Which inertial parameters a robot's torques can tell: the base parameters.

The torques are linear in the standard parameters ``π`` of the moving bodies (``τ = Y π``,
:func:`spatial_dynamics.regressor`), but not every column of ``Y`` is independent: a body's
mass on a joint whose axis is along gravity never loads a joint, the mass of a link and the
first moment of its parent enter only as a sum, and so on. Stacking ``Y`` over many states
``W`` and taking a QR decomposition with column pivoting, ``W P = Q [R₁ R₂]`` (Gautier 1990,
the numerical route), gives the rank ``r`` and splits the columns into ``r`` independent ones
(``P[:r]``) and the rest, each a combination of those: ``W_dep = W_ind K`` with
``K = R₁⁻¹ R₂``. Then

    τ = W_ind β,   β = π_ind + K π_dep

so the ``r`` base parameters ``β`` are what a recording can determine, each named as its
combination ("I_zz of link1 + 0.0841 · m of link2 …"), and a column that is zero over every
state is a parameter no torque depends on at all.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import List, Optional, Sequence, Tuple

import numpy as np

from .algorithms.regressor import PARAMETERS, regressor
from .model import Model

#: A pivot of ``R`` below ``RTOL`` times the largest counts as zero (the rank's threshold).
RTOL = 1e-9
#: Coefficients of ``K`` below this are dropped from the names (not from ``K``).
SHOWN = 1e-9


@dataclass(frozen=True)
class BaseParameters:
    """The base parameters of a model: see the module docstring.

    Attributes:
        names: (10·NB,) the standard parameters, ``'<parameter> of <link>'``.
        independent: (r,) indices into ``π`` of the columns kept, in pivot order.
        dependent: (p − r,) indices of the others.
        K: (r, p − r): ``β = π[independent] + K @ π[dependent]``.
        unexcited: indices of the parameters whose column is zero in every state: no torque
            depends on them (they are among ``dependent``, with a zero column of ``K``).
    """

    names: Tuple[str, ...]
    independent: np.ndarray
    dependent: np.ndarray
    K: np.ndarray
    unexcited: np.ndarray

    @property
    def rank(self) -> int:
        """The number of base parameters."""
        return len(self.independent)

    def beta(self, pi: np.ndarray) -> np.ndarray:
        """Return the base parameters ``β`` (r,) of standard parameters ``π`` (10·NB,)."""
        pi = np.asarray(pi, dtype=float)
        return pi[self.independent] + self.K @ pi[self.dependent]

    def columns(self, Y: np.ndarray) -> np.ndarray:
        """Return the base regressor ``Y[..., independent]``: τ is it times ``beta(π)``."""
        return np.asarray(Y)[..., self.independent]

    def describe(self, k: int) -> str:
        """Name base parameter ``k`` as its combination of standard parameters."""
        text = self.names[self.independent[k]]
        for j, c in enumerate(self.K[k]):
            if abs(c) > SHOWN:
                sign = '+' if c > 0 else '-'
                text += f' {sign} {abs(c):.4g} · {self.names[self.dependent[j]]}'
        return text

    def unexcited_names(self) -> List[str]:
        """Name the parameters no torque depends on."""
        return [self.names[i] for i in self.unexcited]


def parameter_names(model: Model) -> Tuple[str, ...]:
    """Return ``'<parameter> of <link>'`` for every standard parameter, in ``π``'s order."""
    return tuple(f'{p} of {link}' for link in model.body_names[1:] for p in PARAMETERS)


def random_states(model: Model, count: int, seed: int = 0) -> Tuple[np.ndarray, ...]:
    """``count`` states ``(q, q̇, q̈)`` spread over the joint limits (±π when unlimited)."""
    rng = np.random.default_rng(seed)
    n = len(model.joint_names)
    lo = np.where(np.isfinite(model.lower), model.lower, -np.pi)
    hi = np.where(np.isfinite(model.upper), model.upper, np.pi)
    q = rng.uniform(lo, hi, size=(count, n))
    qd = rng.uniform(-2.0, 2.0, size=(count, n))
    qdd = rng.uniform(-5.0, 5.0, size=(count, n))
    return q, qd, qdd


def base_parameters(model: Model, states: Optional[Sequence[np.ndarray]] = None,
                    gravity: Sequence[float] = (0.0, 0.0, -9.81), rtol: float = RTOL,
                    count: int = 400, seed: int = 0) -> BaseParameters:
    """Find the base parameters from the stacked regressor of ``states`` ``(q, q̇, q̈)``.

    Without ``states``, ``count`` random ones over the joint limits: what a well exciting
    recording can determine. With a recording's states, what that recording can.
    """
    from scipy.linalg import qr
    q, qd, qdd = random_states(model, count, seed) if states is None else states
    W = regressor(model, q, qd, qdd, gravity).reshape(-1, 10 * model.NB)
    scale = np.linalg.norm(W, axis=0)
    unexcited = np.flatnonzero(scale <= rtol * scale.max())
    R, P = qr(W, mode='r', pivoting=True)
    d = np.abs(np.diag(R))
    r = int(np.sum(d > rtol * d[0]))
    K = np.linalg.solve(R[:r, :r], R[:r, r:])
    K[np.abs(K) < 1e-12] = 0.0
    return BaseParameters(parameter_names(model), P[:r].copy(), P[r:].copy(), K, unexcited)
