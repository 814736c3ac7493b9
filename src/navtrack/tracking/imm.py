"""Interacting multiple model (IMM) kernels, batched over leading axes.

Model-conditioned states ``x (..., r, n)``, covariances ``P (..., r, n, n)`` and model
probabilities ``mu (..., r)`` for ``r`` models sharing one state space.

References
----------
.. [1] H. A. P. Blom, Y. Bar-Shalom, "The interacting multiple model algorithm for systems with
   Markovian switching coefficients", IEEE T-AC 33(8), 1988.
.. [2] Y. Bar-Shalom, X. R. Li, T. Kirubarajan, *Estimation with Applications to Tracking and
   Navigation*, Wiley 2001, section 11.6.6 (IMM cycle, eq. 11.6.6-6..-19).
"""

from __future__ import annotations

import numpy as np

from navtrack._typing import ArrayLike, FloatArray

__all__ = ["imm_combine", "imm_mix", "imm_model_probabilities", "markov_matrix"]


def markov_matrix(r: int, switch_probability: float) -> FloatArray:
    """Mode transition matrix ``Pi[i, j] = P(model j at k | model i at k-1)``.

    Stay with probability ``1 - switch_probability``, switch evenly to the other models.
    """
    if r < 1 or not 0 <= switch_probability < 1:
        raise ValueError("need r >= 1 and 0 <= switch_probability < 1")
    if r == 1:
        return np.ones((1, 1))
    Pi = np.full((r, r), switch_probability / (r - 1))
    np.fill_diagonal(Pi, 1 - switch_probability)
    return Pi


def imm_mix(
    x: ArrayLike, P: ArrayLike, mu: ArrayLike, Pi: ArrayLike
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """IMM interaction (mixing) step, Bar-Shalom et al. eq. 11.6.6-6..-11.

    Returns
    -------
    x0 : (..., r, n), P0 : (..., r, n, n) mixed initial conditions
    c : (..., r) predicted model probabilities ``c_j = sum_i Pi[i, j] mu_i``
    """
    x = np.asarray(x, dtype=float)
    P = np.asarray(P, dtype=float)
    mu = np.asarray(mu, dtype=float)
    Pi = np.asarray(Pi, dtype=float)
    c = mu @ Pi  # (..., r)
    w = mu[..., :, None] * Pi / np.where(c > 0, c, 1.0)[..., None, :]  # w[i, j] = mu_{i|j}
    wt = np.swapaxes(w, -1, -2)  # (..., j, i)
    x0 = wt @ x
    d = x[..., None, :, :] - x0[..., :, None, :]  # (..., j, i, n)
    # sums over i as stacked products: P0_j = sum_i w_ij (P_i + d_ji d_jiᵀ)
    n = x.shape[-1]
    P0 = (wt @ P.reshape(*P.shape[:-2], n * n)).reshape(P.shape)
    P0 += np.swapaxes(d * wt[..., None], -1, -2) @ d
    return x0, P0, c


def imm_model_probabilities(c: ArrayLike, log_likelihood: ArrayLike) -> FloatArray:
    """Posterior model probabilities ``mu_j ∝ c_j Λ_j`` from log-likelihoods (eq. 11.6.6-15)."""
    c = np.asarray(c, dtype=float)
    ll = np.asarray(log_likelihood, dtype=float)
    a = np.log(np.where(c > 0, c, 1e-300)) + ll
    a = a - a.max(axis=-1, keepdims=True)
    p = np.exp(a)
    return np.asarray(p / p.sum(axis=-1, keepdims=True))


def imm_combine(x: ArrayLike, P: ArrayLike, mu: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Moment-matched combination of the model-conditioned estimates (eq. 11.6.6-17, -18)."""
    x = np.asarray(x, dtype=float)
    P = np.asarray(P, dtype=float)
    mu = np.asarray(mu, dtype=float)
    n = x.shape[-1]
    m = mu[..., None, :]  # (..., 1, r): the sums over the models as stacked products
    xc = (m @ x)[..., 0, :]
    d = x - xc[..., None, :]
    spread = P + d[..., :, None] * d[..., None, :]
    Pc = (m @ spread.reshape(*P.shape[:-2], n * n)).reshape(*P.shape[:-3], n, n)
    return xc, Pc
