# Copyright 2026 spatial_dynamics contributors
# SPDX-License-Identifier: Apache-2.0
"""A virtual force/torque sensor: the wrench at a link that explains joint torques.

A wrench ``w = [n; f]`` on a link, in the link's frame, loads the joints with ``τ = Jᵀ w``
(``J`` from :func:`spatial_dynamics.jacobian` with ``frame='local'``; principle of virtual
work). Given ``τ_ext`` (the observer's estimate), ``w`` is found by damped least squares
(Nakamura & Hanafusa 1986), damping only the directions that need it (the numerical
filtering of Maciejewski & Klein 1988)::

    ŵ = Σ_i σ_i / (σ_i² + λ_i²) u_i (v_iᵀ τ),   J = U Σ Vᵀ,
    λ_i = 0 for σ_i ≥ ε,   λ_i = λ for σ_i < ε

(with every ``λ_i = λ`` this is the plain damped least squares ``(J Jᵀ + λ² 1)⁻¹ J τ =
argmin |Jᵀ w − τ|² + λ² |w|²``; damping only the weak directions leaves the well observed
components exact).
``λ = 0`` while the smallest singular value ``σ_min ≥ ε``, then grows smoothly as it falls:
``λ² = (1 − (σ_min/ε)²) λ_max²``, so the estimate stays bounded near a singularity instead of
amplifying noise by ``1/σ_min``.

What cannot be observed: a wrench along a direction ``u_i`` with ``σ_i = 0`` loads no joint
(``Jᵀ u_i = 0``): with fewer than six joints at least ``6 − n`` such directions exist, and a
singular configuration adds more. The estimate has no component along them (it is the
projection of the true wrench onto the observable directions when λ = 0); directions with
``σ_i < ε`` are damped, so their component is underestimated. Singular values mix units
(the angular rows of ``J`` are dimensionless, the linear rows in m), so ``ε`` and
``λ_max`` are in m-like units at the scale of the arm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Default ``ε``: below this smallest singular value of J (m, or 1) damping starts.
EPSILON = 0.02
#: Default ``λ_max``: the damping at an exact singularity.
LAMBDA_MAX = 0.05
#: A singular value below ``RANK_RTOL · σ_max`` counts as zero for :attr:`WrenchEstimate.rank`.
RANK_RTOL = 1e-9


@dataclass(frozen=True)
class WrenchEstimate:
    """A wrench estimated from joint torques, and what the joints could not tell.

    Leading batch dimensions ``...`` as the inputs.

    Attributes:
        wrench: (..., 6) ``[n; f]`` (N m, N) in the frame of the Jacobian's rows.
        sigma: (..., 6) singular values of J, descending (zeros beyond ``n``).
        U: (..., 6, 6) the wrench directions, column ``i`` with singular value ``sigma[i]``.
        rank: (...) numerical rank of J: observable directions (at most ``min(6, n)``).
        sigma_min: (...) the smallest of the 6 singular values (0 with fewer than 6 joints).
        damping: (...) the ``λ`` used (0 where well conditioned).
        weak: (..., 6) bool, direction ``U[..., :, i]`` unobservable or damped
            (``sigma < ε``): the estimate's component along it is missing or too small.
    """

    wrench: np.ndarray
    sigma: np.ndarray
    U: np.ndarray
    rank: np.ndarray
    sigma_min: np.ndarray
    damping: np.ndarray
    weak: np.ndarray

    def unobservable(self) -> np.ndarray:
        """Return the weak directions of one state, (6, k) unit wrenches (columns)."""
        if self.U.ndim != 2:
            raise ValueError('unobservable() is for one state; index the batch first')
        return self.U[:, self.weak]


def wrench_from_torques(J, tau, epsilon: float = EPSILON,
                        lambda_max: float = LAMBDA_MAX) -> WrenchEstimate:
    """Estimate the wrench ``w`` with ``Jᵀ w ≈ τ`` by adaptively damped least squares.

    Args:
        J: (..., 6, n) Jacobian of the link whose wrench is wanted (its rows ``[ω; v]``; with
            :func:`spatial_dynamics.jacobian` ``frame='local'`` the wrench is in the link
            frame, with ``'world'`` in base axes at the link origin).
        tau: (..., n) joint torques (N m, N) caused by the wrench, e.g. the observer's τ_ext
            (sign: the torque the joints feel, ``τ = Jᵀ w``).
        epsilon: ``ε`` > 0, where damping starts (see the module).
        lambda_max: ``λ_max`` ≥ 0, the damping at a singularity.

    Returns:
        :class:`WrenchEstimate`.
    """
    J = np.asarray(J, dtype=float)
    tau = np.asarray(tau, dtype=float)
    if J.ndim < 2 or J.shape[-2] != 6:
        raise ValueError(f'J must have shape (..., 6, n), got {J.shape}')
    if tau.shape[-1:] != J.shape[-1:]:
        raise ValueError(f'tau must have shape (..., {J.shape[-1]}), got {tau.shape}')
    if not (epsilon > 0.0 and lambda_max >= 0.0):
        raise ValueError(f'need epsilon > 0 and lambda_max >= 0, got {epsilon}, {lambda_max}')
    U, s, Vt = np.linalg.svd(J, full_matrices=True)        # U (...,6,6), s (...,k), k=min(6,n)
    k = s.shape[-1]
    sigma = np.concatenate([s, np.zeros(s.shape[:-1] + (6 - k,))], axis=-1)
    sigma_min = sigma[..., -1]
    lam2 = np.where(sigma_min < epsilon, (1.0 - (sigma_min / epsilon) ** 2) * lambda_max ** 2,
                    0.0)
    # ŵ = Σ_i σ_i / (σ_i² + λ_i²) u_i (v_iᵀ τ); a direction with σ_i = 0 contributes nothing
    vt_tau = np.einsum('...ij,...j->...i', Vt[..., :k, :], tau)
    denom = s ** 2 + np.where(s < epsilon, lam2[..., None], 0.0)
    gain = np.divide(s, denom, out=np.zeros_like(s), where=denom > 0.0)
    wrench = np.einsum('...ij,...j->...i', U[..., :, :k], gain * vt_tau)
    rank = np.sum(sigma > RANK_RTOL * np.maximum(sigma[..., :1], np.finfo(float).tiny),
                  axis=-1)
    return WrenchEstimate(wrench=wrench, sigma=sigma, U=U, rank=rank, sigma_min=sigma_min,
                          damping=np.sqrt(lam2), weak=sigma < epsilon)
