"""The ARI(p, d) Gauss–Markov model of paper 5: process polynomial, banded normal equations.

Eq. (2), observations ``E(y_t) = x_t``, ``V(y_t) = sigma_n^2 / w_t``; eq. (3), process
``E(e_s) = 0 = sum_i c_i x_{s-i}``, ``V(e_s) = sigma_e^2 / v_s`` with
``c = (1, a_1, ..., a_m)`` the coefficients of ``phi(B) (1 - B)^d`` (:func:`ari_polynomial`,
``m = p + d``). The normal matrix ``N = W / sigma_n^2 + C^T V C / sigma_e^2`` is banded with
half-bandwidth ``m`` (:func:`normal_band`); :func:`solve_gauss_markov` solves it, gives the
log-likelihood and, by selected inversion, the band of ``N^-1``. With the stationary start
(:class:`StationaryPrior`) the first ``p`` differences ``u = (1 - B)^d x`` follow the AR's
stationary distribution (exact likelihood); without it the model is conditional on them.

:class:`AriProblem` is one series ready for estimation (centred observations, weights, order,
start, search box of the log-variances); every estimator takes it (module
:mod:`navtrack.smoothing.estimation`).

References
----------
J. Lindenberger, "Modelling orientation parameters of sensor platforms", ISPRS Comm. I (paper 5
in ``shared/papers``), eqs. (1)–(3), section 2.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy.signal import lfilter

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, FloatArray
from navtrack.smoothing.banded import (
    add_convolution_band,
    centred_convolution,
    cholesky_solve_banded,
    inverse_band_from_factor,
)

__all__ = [
    "AriProblem",
    "GaussMarkovSolution",
    "StationaryPrior",
    "ari_polynomial",
    "dense_block",
    "gauss_markov_filter",
    "normal_band",
    "process_residuals",
    "process_transpose",
    "process_variance",
    "simulate_ari",
    "solve_gauss_markov",
    "stationary_prior",
    "with_inverse",
]


def ari_polynomial(phi: ArrayLike, d: int) -> FloatArray:
    """Coefficients ``(1, a_1, ..., a_{p+d})`` of ``phi(B) (1 - B)^d``.

    Parameters
    ----------
    phi : array_like, shape (p,)
        AR coefficients in the paper's sign (``1 + phi_1 B + ... + phi_p B^p``).
    d : int
        Number of differences.

    Returns
    -------
    c : ndarray, shape (p + d + 1,)
    """
    poly = np.concatenate([[1.0], np.asarray(phi, dtype=float).ravel()])
    for _ in range(int(d)):
        poly = np.convolve(poly, [1.0, -1.0])
    return poly


def normal_band(c: FloatArray, w: FloatArray, v: FloatArray, sn2: float, se2: float) -> FloatArray:
    """Upper banded normal matrix of eqs. (2)–(3).

    Parameters
    ----------
    c : ndarray, shape (m + 1,)
        Process coefficients (:func:`ari_polynomial`).
    w : ndarray, shape (n,)
        Observation weights (0 where missing).
    v : ndarray, shape (n - m,)
        Process-equation weights; equation ``s`` ends at epoch ``s + m``.
    sn2, se2 : float
        ``sigma_n^2``, ``sigma_e^2``.

    Returns
    -------
    ab : ndarray, shape (m + 1, n)
        LAPACK upper banded storage, ``ab[m + i - j, j] = N[i, j]``.
    """
    m = c.size - 1
    n = w.size
    ab = np.zeros((m + 1, n))
    ab[m] = w / sn2
    # equation s (0-based, s = m..n-1) involves x_{s-i} with coefficient c_i
    add_convolution_band(ab, c, v / se2)
    return ab


def process_residuals(c: FloatArray, x: FloatArray) -> FloatArray:
    """``e_s = sum_i c_i x_{s-i}`` for ``s = m..n-1``, shape ``(n - m,)`` (eq. (3)).

    Summed without cancellation (:func:`navtrack.smoothing.banded.centred_convolution`): an
    integrated series drifts far from zero (about 1e7 sigma_e after 1e6 epochs of ARI(5, 2))
    while ``e_s`` is of the order of ``sigma_e``; ``sum_i c_i x_{s-i}`` lost ``eps |c| |x|``.
    """
    return centred_convolution(c, x)


def process_transpose(c: FloatArray, r: FloatArray) -> FloatArray:
    """``C^T r`` ``(n,)`` for process-equation values ``r`` ``(n - m,)``: the adjoint of
    :func:`process_residuals` (``(C^T r)_t = sum_s r_s c_{s-t}``)."""
    return np.asarray(np.convolve(r, c[::-1], mode="full"), dtype=np.float64)


def _baseline(y0: FloatArray, w: FloatArray) -> FloatArray:
    """The observations, linearly interpolated over epochs without weight (0 when none has)."""
    used = w > 0
    if np.all(used):
        return y0
    if not np.any(used):
        return np.zeros_like(y0)
    t = np.arange(y0.size)
    return np.asarray(np.interp(t, t[used], y0[used]), dtype=np.float64)


def process_variance(c: FloatArray, zb: FloatArray) -> FloatArray:
    """``c^T Z c`` of each process equation ``(n - m,)`` from the band ``zb`` of ``Z = N^-1``."""
    m = c.size - 1
    n = zb.shape[1]
    q = np.zeros(n - m)
    for i in range(m + 1):
        q += c[i] ** 2 * zb[0, m - i : n - i]
        for i2 in range(i + 1, m + 1):
            # Z[s - i2, s - i] = zb[i2 - i, s - i2]
            q += 2.0 * c[i] * c[i2] * zb[i2 - i, m - i2 : n - i2]
    return q


def dense_block(zb: FloatArray, m: int) -> FloatArray:
    """Top-left ``(m, m)`` block of ``Z`` from its band (needs ``zb.shape[0] >= m``)."""
    block = np.empty((m, m))
    for i in range(m):
        for j in range(i, m):
            block[i, j] = block[j, i] = zb[j - i, i]
    return block


@dataclass(frozen=True, slots=True, eq=False)
class GaussMarkovSolution:
    """One solution of the Gauss–Markov model at given parameters and weights.

    Attributes
    ----------
    x : ndarray, shape (n,)
        Filtered series (centred units of the problem).
    zb : ndarray, shape (width + 1, n), or None
        Band of ``N^-1`` by diagonal offset, ``zb[l, t] = cov(x_t, x_{t+l})``; ``None`` when
        solved without the selected inversion (a line-search trial).
    loglike : float
        Log-likelihood (:mod:`navtrack.smoothing.ari` notes).
    omega_n, omega_e : float
        Weighted sums of squares of the observation and process residuals (the process one
        with the stationary-start term).
    logdet : float
        ``log det N``.
    factor, ab : ndarray, shape (m + 1, n), or None
        Without ``zb``: the banded Cholesky factor and the matrix, to add ``zb`` later
        (:func:`with_inverse`).
    """

    x: FloatArray
    zb: FloatArray | None
    loglike: float
    omega_n: float
    omega_e: float
    logdet: float
    factor: FloatArray | None = None
    ab: FloatArray | None = None

    def __post_init__(self) -> None:
        freeze_arrays(self)


@dataclass(frozen=True, slots=True, eq=False)
class StationaryPrior:
    """Stationary start of the AR part: ``u_{d..m-1} ~ N(0, sigma_e^2 Gamma_p(phi))``.

    Attributes
    ----------
    d_mat : ndarray, shape (p, m)
        Maps ``x_0..x_{m-1}`` to ``u_d..u_{m-1}`` (``u = (1 - B)^d x``).
    gamma_inv : ndarray, shape (p, p)
        ``Gamma_p^-1`` (unit innovation variance).
    g_mat : ndarray, shape (m, m)
        ``D^T Gamma^-1 D``, the block added to the normal matrix (times ``1/sigma_e^2``).
    logdet_gamma : float
        ``log det Gamma_p``.
    dlogdet : ndarray, shape (p,)
        ``d log det Gamma_p / d phi_j``.
    dgamma_inv : ndarray, shape (p, p, p)
        ``d Gamma_p^-1 / d phi_j`` (first axis ``j``).
    """

    d_mat: FloatArray
    gamma_inv: FloatArray
    g_mat: FloatArray
    logdet_gamma: float
    dlogdet: FloatArray
    dgamma_inv: FloatArray

    def __post_init__(self) -> None:
        freeze_arrays(self)


def stationary_prior(phi: FloatArray, d: int) -> StationaryPrior | None:
    """Yule–Walker ``gamma(k) + sum_i phi_i gamma(|k - i|) = [k == 0]`` (unit innovation),
    ``Gamma_p = toeplitz(gamma(0..p-1))`` and its derivatives; ``None`` unless stationary.

    Parameters
    ----------
    phi : ndarray, shape (p,), p >= 1
        AR coefficients (paper sign).
    d : int
        Number of differences.
    """
    p = phi.size
    m = p + d
    comp = np.zeros((p, p))
    comp[0] = -phi
    comp[1:, :-1] = np.eye(p - 1)
    if np.max(np.abs(np.linalg.eigvals(comp))) >= 1.0 - 1e-7:
        return None
    coef = np.concatenate([[1.0], phi])
    lag = np.abs(np.arange(p + 1)[:, None] - np.arange(p + 1)[None, :])
    mat = np.zeros((p + 1, p + 1))
    for i in range(p + 1):
        np.add.at(mat, (np.arange(p + 1), lag[:, i]), coef[i])
    rhs = np.zeros(p + 1)
    rhs[0] = 1.0
    try:
        gam = np.linalg.solve(mat, rhs)
    except np.linalg.LinAlgError:
        return None
    idx = np.abs(np.arange(p)[:, None] - np.arange(p)[None, :])
    gamma = gam[idx]
    try:
        chol = np.linalg.cholesky(gamma)
    except np.linalg.LinAlgError:
        return None
    gamma_inv = np.linalg.inv(gamma)
    gamma_inv = 0.5 * (gamma_inv + gamma_inv.T)
    # d gamma / d phi_j = -mat^-1 (d mat / d phi_j) gamma, d mat[k, |k-j|] / d phi_j = 1
    dlogdet = np.empty(p)
    dgamma_inv = np.empty((p, p, p))
    for j in range(1, p + 1):
        dgam = -np.linalg.solve(mat, gam[lag[:, j]])
        dgamma = dgam[idx]
        dgamma_inv[j - 1] = -gamma_inv @ dgamma @ gamma_inv
        dlogdet[j - 1] = float(np.sum(gamma_inv * dgamma))
    delta = ari_polynomial(np.zeros(0), d)
    d_mat = np.zeros((p, m))
    for k in range(p):
        for j in range(d + 1):
            d_mat[k, d + k - j] = delta[j]
    return StationaryPrior(
        d_mat=d_mat,
        gamma_inv=gamma_inv,
        g_mat=d_mat.T @ gamma_inv @ d_mat,
        logdet_gamma=2.0 * float(np.sum(np.log(np.diag(chol)))),
        dlogdet=dlogdet,
        dgamma_inv=dgamma_inv,
    )


def solve_gauss_markov(
    y0: FloatArray,
    w: FloatArray,
    v: FloatArray,
    c: FloatArray,
    sn2: float,
    se2: float,
    width: int | None,
    prior: StationaryPrior | None = None,
) -> GaussMarkovSolution | None:
    """Solve the Gauss–Markov model (2)–(3) at given parameters.

    Parameters
    ----------
    y0 : ndarray, shape (n,)
        Observations, 0 where missing.
    w, v : ndarray, shapes (n,) and (n - m,)
        Observation and process-equation weights.
    c : ndarray, shape (m + 1,)
        Process coefficients.
    sn2, se2 : float
        ``sigma_n^2``, ``sigma_e^2``.
    width : int or None
        Diagonal offsets of ``N^-1`` to compute; ``None`` skips the selected inversion and
        keeps the factor instead (:func:`with_inverse`).
    prior : StationaryPrior, optional
        The first ``p`` differences get their stationary distribution (exact likelihood, as
        statsmodels' SARIMAX); without it the likelihood is conditional on them.

    Returns
    -------
    GaussMarkovSolution or None
        ``None`` when ``N`` is not numerically positive definite or the solution not finite.
    """
    ab = normal_band(c, w, v, sn2, se2)
    m = c.size - 1
    if prior is not None:
        g = prior.g_mat / se2
        for lag in range(m):
            ab[m - lag, lag:m] += np.diag(g, lag)
    # Solved for the correction z = x - b to the observations b (interpolated over gaps):
    # x of an integrated series is large, and the solve's error (condition number times eps
    # |x|) would enter the likelihood through the residuals as one-sided noise (up to ~1 unit
    # at n = 1e6) that stalls line searches along the sigma_e/phi ridge; z is of the order of
    # sigma_n. N b - W y0 / sn2 has no cancellation in this form (W (b - y0) = 0).
    base = _baseline(y0, w)
    e_base = process_residuals(c, base)
    rhs = w * (y0 - base) / sn2 - process_transpose(c, v * e_base) / se2
    if prior is not None:
        u_base = prior.d_mat @ base[:m]
        rhs[:m] -= prior.d_mat.T @ (prior.gamma_inv @ u_base) / se2
    try:
        z, logdet, factor = cholesky_solve_banded(ab, rhs)
    except np.linalg.LinAlgError:
        return None
    if not np.all(np.isfinite(z)):
        return None
    x = base + z
    # z is small: a plain convolution loses nothing
    e = e_base + np.convolve(z, c, mode="valid") if z.size > m else e_base
    resid = (y0 - base) - z
    omega_n = float(np.sum(w * resid**2))
    omega_e = float(np.sum(v * e**2))
    diffuse = m
    extra = 0.0
    if prior is not None:
        p = prior.d_mat.shape[0]
        diffuse = m - p
        u0 = u_base + prior.d_mat @ z[:m]
        omega_e += float(u0 @ prior.gamma_inv @ u0)
        extra = p * math.log(se2) + prior.logdet_gamma
    loglike = _log_likelihood(w, v, (sn2, se2), diffuse, (extra, logdet), (omega_n, omega_e))
    if width is None:
        return GaussMarkovSolution(x, None, loglike, omega_n, omega_e, logdet, factor, ab)
    zb = inverse_band_from_factor(factor, width, ab=ab)
    return GaussMarkovSolution(x, zb, loglike, omega_n, omega_e, logdet)


def _log_likelihood(
    w: FloatArray,
    v: FloatArray,
    variances: tuple[float, float],
    diffuse: int,
    log_terms: tuple[float, float],
    omegas: tuple[float, float],
) -> float:
    """Gaussian log-likelihood of the equations in the fit (weights > 0) at the variances
    ``(sn2, se2)`` given the weighted squared residuals ``omegas = (omega_n, omega_e)``;
    ``diffuse`` leading differences do not count and ``log_terms = (prior, log |N|)`` are the
    prior's and the normal matrix's log-determinant terms."""
    sn2, se2 = variances
    extra, logdet = log_terms
    omega_n, omega_e = omegas
    used_w = w > 0
    used_v = v > 0
    n_used = int(np.count_nonzero(used_w))
    n_used_v = int(np.count_nonzero(used_v))
    return -0.5 * (
        (n_used - diffuse) * math.log(2 * math.pi)
        # sum of log(sigma^2 / weight) over the equations in the fit, without the ratio itself:
        # sigma^2 / w overflows for a weight near the underflow threshold (a Danish weight of
        # a 67-sigma outlier), log w does not
        + n_used * math.log(sn2)
        - float(np.sum(np.log(w[used_w])))
        + n_used_v * math.log(se2)
        - float(np.sum(np.log(v[used_v])))
        + extra
        + logdet
        + omega_n / sn2
        + omega_e / se2
    )


def with_inverse(fit: GaussMarkovSolution, width: int) -> GaussMarkovSolution:
    """``fit`` (solved with ``width=None``) completed with the band of ``N^-1``."""
    if fit.zb is not None and fit.zb.shape[0] > width:
        return fit
    if fit.factor is None:
        raise ValueError("the fit keeps no factor")
    zb = inverse_band_from_factor(fit.factor, width, ab=fit.ab)
    return GaussMarkovSolution(fit.x, zb, fit.loglike, fit.omega_n, fit.omega_e, fit.logdet)


@dataclass(frozen=True, slots=True, eq=False)
class AriProblem:
    """One series ready for estimation: what every estimator of the ARI model takes.

    Replaces the argument list ``(y0, w, v, p, d, stationary)`` (and the search box) that the
    estimation functions share. The parameter vector of an estimator is
    ``vec = (phi_1..phi_p, log sigma_n^2, log sigma_e^2)``, shape ``(p + 2,)``.

    Attributes
    ----------
    y0 : ndarray, shape (n,)
        Observations minus their trend (input units), 0 where missing.
    w : ndarray, shape (n,)
        Observation weights (0 where missing, robust weights otherwise).
    v : ndarray, shape (n - p - d,)
        Process-equation weights; equation ``s`` ends at epoch ``s + p + d``.
    p, d : int
        ARI order.
    stationary : bool
        Stationary start of the AR part (exact likelihood); False: conditional on it.
    log_floor, log_ceiling : float
        Box of the log-variances in the search (``-inf``/``inf``: none).
    """

    y0: FloatArray
    w: FloatArray
    v: FloatArray
    p: int
    d: int
    stationary: bool
    log_floor: float = -math.inf
    log_ceiling: float = math.inf

    def __post_init__(self) -> None:
        n = self.y0.size
        if self.w.shape != (n,) or self.v.shape != (max(n - self.m, 0),):
            raise ValueError(
                f"y0 {self.y0.shape}, w {self.w.shape} and v {self.v.shape} do not match "
                f"ARI({self.p},{self.d})"
            )
        freeze_arrays(self)

    @property
    def m(self) -> int:
        """Half-bandwidth ``p + d``."""
        return self.p + self.d

    @property
    def n(self) -> int:
        """Number of epochs."""
        return int(self.y0.size)

    def head(self, k: int) -> AriProblem:
        """The same problem on the first ``k`` epochs (``k > m``)."""
        return dataclasses.replace(self, y0=self.y0[:k], w=self.w[:k], v=self.v[: k - self.m])

    def with_weights(self, w: FloatArray, v: FloatArray) -> AriProblem:
        """The same problem with new observation / process weights."""
        return dataclasses.replace(self, w=w, v=v)

    def prior(self, phi: FloatArray) -> StationaryPrior | None:
        """Stationary start at ``phi`` when the problem has one and ``p > 0``, else ``None``."""
        return stationary_prior(phi, self.d) if self.stationary and self.p else None


def gauss_markov_filter(
    y: ArrayLike,
    phi: ArrayLike,
    d: int,
    sigma_n: float,
    sigma_e: float,
    *,
    weight: ArrayLike | None = None,
    process_weight: ArrayLike | None = None,
    width: int = 0,
    initial: Literal["stationary", "conditional"] = "conditional",
) -> tuple[FloatArray, FloatArray, float]:
    """Filtered series of eqs. (2)–(3) for a given model (no estimation).

    Parameters
    ----------
    y : array_like, shape (n,)
        Observed series; NaN marks missing epochs.
    phi : array_like, shape (p,)
        AR coefficients of the differences (paper sign).
    d : int
        Differences; ``p + d >= 1``.
    sigma_n, sigma_e : float
        Standard deviations of eqs. (2) and (3).
    weight, process_weight : array_like, optional
        Weights of the observations ``(n,)`` and process equations ``(n - p - d,)`` (default 1).
    width : int
        Diagonal offsets of ``N^-1`` to return.
    initial : {"conditional", "stationary"}
        See :class:`navtrack.smoothing.config.AriConfig`.

    Returns
    -------
    x : ndarray, shape (n,)
    zb : ndarray, shape (width + 1, n)
        ``zb[l, t] = cov(x_t, x_{t+l})``.
    loglike : float
        Log-likelihood (:mod:`navtrack.smoothing.ari` notes).
    """
    y_arr = np.asarray(y, dtype=float)
    phi_arr = np.asarray(phi, dtype=float).ravel()
    c = ari_polynomial(phi_arr, d)
    m = c.size - 1
    n = y_arr.size
    if m < 1 or n <= m:
        raise ValueError(f"need p + d >= 1 and len(y) > p + d, got {m} and {n}")
    observed = np.isfinite(y_arr)
    w = (
        observed.astype(float)
        if weight is None
        else np.where(observed, np.asarray(weight, dtype=float), 0.0)
    )
    v = np.ones(n - m) if process_weight is None else np.asarray(process_weight, dtype=float)
    prior = None
    if initial == "stationary" and phi_arr.size:
        prior = stationary_prior(phi_arr, d)
        if prior is None:
            raise ValueError("phi is not stationary; use initial='conditional'")
    y0 = np.where(observed, y_arr, 0.0)
    fit = solve_gauss_markov(y0, w, v, c, sigma_n**2, sigma_e**2, width, prior)
    if fit is None or fit.zb is None:
        raise np.linalg.LinAlgError("normal matrix of the Gauss-Markov model is singular")
    return fit.x, fit.zb, fit.loglike


def simulate_ari(
    rng: np.random.Generator,
    n: int,
    phi: ArrayLike,
    d: int,
    sigma_n: float,
    sigma_e: float,
    *,
    burn_in: int = 200,
) -> tuple[FloatArray, FloatArray]:
    """Simulate an observed ARI(p, d) series ``y = x + noise``.

    Parameters
    ----------
    rng : numpy.random.Generator
    n : int
        Number of epochs.
    phi : array_like, shape (p,)
        AR coefficients of the differences (paper sign); must be stationary.
    d : int
    sigma_n, sigma_e : float
        Observation noise and prediction-error standard deviations.
    burn_in : int
        Discarded leading samples of the stationary part.

    Returns
    -------
    y : ndarray, shape (n,)
        Observations.
    x : ndarray, shape (n,)
        True process.
    """
    phi_arr = np.asarray(phi, dtype=float).ravel()
    if phi_arr.size and np.any(np.abs(np.roots(np.concatenate([[1.0], phi_arr]))) >= 1):
        raise ValueError("phi must describe a stationary AR part (roots inside the unit circle)")
    e = rng.normal(0.0, sigma_e, n + burn_in)
    u = lfilter([1.0], np.concatenate([[1.0], phi_arr]), e)[burn_in:]
    x = u
    for _ in range(d):
        x = np.cumsum(x)
    y = x + rng.normal(0.0, sigma_n, n)
    return y, x
