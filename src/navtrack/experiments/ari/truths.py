"""Synthetic truths built from paper 5's published statistics.

The paper prints, per application, the order, ``sigma_n``, ``sigma_e`` (INS only), ``sigma_x``
and the autocorrelations ``r(h)`` of the filtered series (Tables 1, 3–5), but no AR
coefficients. Those statistics are functions of the model: for a series of ``n`` epochs,
``sigma_x^2`` and ``r(h)`` are the mean diagonal and normalised off-diagonals of ``N^-1`` of
eqs. (2)–(3) (:func:`filtered_statistics`). :func:`fit_published` chooses the AR coefficients
(and ``sigma_e`` where the paper does not print it) whose theoretical ``sigma_x / sigma_n`` and
``r(1..k)`` are closest to the printed ones.

Notes
-----
Fitting: nonlinear least squares (``scipy.optimize.least_squares``, trust-region reflective)
over the partial autocorrelations ``pi_1..pi_p`` of the AR part, bounded to ``[-0.95, 0.95]``
(so every candidate is stationary; Durbin–Levinson maps them to ``phi``), and ``log sigma_e``
when it is free. Residuals: ``sigma_x / sigma_n`` and each ``r(h)`` minus the printed value,
each divided by 0.01 (the printed resolution), plus a ridge ``0.1 * pi_j`` so that
under-determined cases (GPS: six unknowns, four printed values) get the smoothest of the
equally good solutions. The result depends on ``n`` (the strip length) only weakly.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from navtrack._typing import ArrayLike, FloatArray
from navtrack.smoothing.ari import gauss_markov_filter

__all__ = ["filtered_statistics", "fit_published", "pacf_to_phi"]


def pacf_to_phi(pacf: ArrayLike) -> FloatArray:
    """AR coefficients ``(p,)`` in the paper's sign (``u_t + sum phi_i u_{t-i} = e_t``) of
    the partial autocorrelations ``pacf`` (Durbin–Levinson recursion; ``|pi| < 1`` gives a
    stationary AR)."""
    a = np.zeros(0)
    for k, pi in enumerate(np.asarray(pacf, dtype=float)):
        a = np.concatenate([a - pi * a[::-1], [pi]]) if k else np.array([pi])
    return -a


def filtered_statistics(
    phi: ArrayLike, d: int, sigma_n: float, sigma_e: float, n: int, lags: int = 4
) -> tuple[float, FloatArray]:
    """Theoretical ``sigma_x / sigma_n`` and ``r(1..lags)`` ``(lags,)`` of the filtered series
    of ``n`` epochs (stationary start, unit weights), as the paper computes them from ``N^-1``."""
    _, zb, _ = gauss_markov_filter(
        np.zeros(n), phi, d, sigma_n, sigma_e, width=lags, initial="stationary"
    )
    var = zb[0]
    r = np.array(
        [np.mean(zb[h, : n - h] / np.sqrt(var[: n - h] * var[h:])) for h in range(1, lags + 1)]
    )
    return math.sqrt(float(np.mean(var))) / sigma_n, r


def fit_published(
    p: int,
    d: int,
    sigma_n: float,
    sigma_e: float | None,
    n: int,
    ratio: float,
    r: Sequence[float],
) -> tuple[FloatArray, float, float]:
    """AR coefficients (and ``sigma_e`` if ``None``) matching the printed statistics.

    Parameters
    ----------
    p, d : int
        The paper's order.
    sigma_n : float
        Printed observation noise.
    sigma_e : float or None
        Printed prediction error; ``None``: fitted too (GPS, Table 1 has none).
    n : int
        Epochs per series (strip length).
    ratio : float
        Printed ``sigma_x / sigma_n``.
    r : sequence of float
        Printed ``r(1..k)``.

    Returns
    -------
    phi : ndarray, shape (p,)
    sigma_e : float
    cost : float
        RMS of the residuals in units of 0.01 (without the ridge).
    """
    from scipy.optimize import least_squares

    target_r = np.asarray(r, dtype=float)
    free_e = sigma_e is None

    def unpack(theta: FloatArray) -> tuple[FloatArray, float]:
        se = math.exp(theta[p]) if free_e else float(sigma_e)  # type: ignore[arg-type]
        return pacf_to_phi(theta[:p]), se

    def resid(theta: FloatArray, ridge: float = 0.1) -> FloatArray:
        phi, se = unpack(theta)
        rat, rr = filtered_statistics(phi, d, sigma_n, se, n, target_r.size)
        fit = np.concatenate([[rat - ratio], rr - target_r]) / 0.01
        return np.concatenate([fit, ridge * theta[:p]])

    theta0 = np.concatenate([np.zeros(p), [math.log(0.5 * sigma_n)] if free_e else []])
    lo = np.concatenate([np.full(p, -0.95), [math.log(1e-3 * sigma_n)] if free_e else []])
    hi = np.concatenate([np.full(p, 0.95), [math.log(1e2 * sigma_n)] if free_e else []])
    sol = least_squares(resid, theta0, bounds=(lo, hi), x_scale=1.0)
    phi, se = unpack(sol.x)
    cost = float(np.sqrt(np.mean(resid(sol.x, 0.0)[: 1 + target_r.size] ** 2)))
    return phi, se, cost
