"""ARI(p, d) modelling of orientation parameters (Lindenberger, paper 5).

Each series ``y_t`` (a position coordinate, an attitude angle, ...) is modelled as an ARI(p, d)
process ``x_t`` observed with white noise. The Gauss–Markov model of the paper is

* eq. (2), observations:    ``E(y_t) = x_t``,                      ``V(y_t) = sigma_n^2``
* eq. (3), process:         ``E(e_t) = 0 = x_t + sum_i a_i x_{t-i}``, ``V(e_t) = sigma_e^2``

with ``1 + sum_i a_i B^i = phi(B) (1 - B)^d`` (``B`` the backshift, ``phi(B) = 1 + phi_1 B + ...
+ phi_p B^p``; the paper's sign convention, eq. (1): ``x_t = -sum a_i x_{t-i} + e_t``). Both
groups together are a least-squares problem in the ``n`` unknowns ``x``; its normal matrix
``N = S^T W S / sigma_n^2 + C^T V C / sigma_e^2`` is banded (half-bandwidth ``m = p + d``), so
the filtered series, ``log det N`` and — by selected inversion — the band of ``N^-1`` cost O(n).

Everything the paper lists is estimated without a-priori stochastic information:

* ``sigma_n^2, sigma_e^2`` by redundancy-based variance component estimation (Förstner 1979;
  Koch 1986: ``sigma_k^2 = v_k^T P_k v_k / r_k`` with the redundancy
  ``r_k = n_k - tr(N^-1 N_k)``), iterated until the relative change of both sigmas is below
  ``tol``. The paper recommends Förstner's (1984) *frequency-domain* formulation, which replaces
  the redundancies by integrals of the stationary filter's transfer function. We use the exact
  time-domain redundancies instead, from the band of ``N^-1``: with gaps (missing epochs),
  robust weights and short strips (the paper's GPS strips have ~130 epochs) the series is not
  stationary and the frequency-domain values are only asymptotic, while selected inversion makes
  the exact ones O(n). The VCE fixed point is the stationary point of the likelihood below in
  the two variances (``d(-2 log L)/d log sigma_k^2 = r_k - Omega_k / sigma_k^2``).
* ``phi`` (the AR part; the ``d`` differences are fixed) jointly with the variances. The paper
  alternates (Lindenberger 1987) between filtering and a least-squares fit of eq. (3); its
  proper form is the EM step (moments ``E[x x^T] = x_hat x_hat^T + N^-1``, band only), whose
  equation is the ``phi`` part of the likelihood gradient. That alternation converged linearly
  and needed hundreds of iterations in our tests (even with SQUAREM acceleration), so the same
  gradient — VCE equations for the variances, expected-moment equations for ``phi``, plus the
  stationary-start term — drives a quasi-Newton (BFGS) search with Armijo backtracking,
  started from a finite-difference Hessian; a final VCE iteration certifies the variance
  components. Stopping rule: predicted log-likelihood gain of the next quasi-Newton step below
  ``gain_tol`` (1e-3), then VCE relative change below ``tol`` (1e-6); ``max_iter`` otherwise
  (status ``not_converged``).
* The likelihood in ``(phi, sigma_n, sigma_e)`` is multimodal on short series (``sigma_n -> 0``
  is a local optimum — the SARIMAX failure the issue describes); several starts spread over the
  noise fraction are run (on long series on a leading window, then refined on the whole
  series), and an interior optimum is kept over a boundary one unless the latter is
  significantly better (``boundary_margin``).
* robust reweighting (IRLS inside the VCE iteration) with a weight function of the studentized
  *deletion* residual ``T`` (Baarda's w-test statistic for unit weight; for a down-weighted
  observation it is the prediction residual from all other data, so the test does not
  oscillate as weights change). Danish method (default), Huber, IGG-III; observations with
  ``|T| > flag_threshold`` are flagged as gross errors; the process equations (3) can be
  reweighted too (``robust_process``) for edges and discontinuities.
* order ``(p, d)`` by BIC (or AIC) of the likelihood conditional on the first ``max(p + d)``
  epochs, so that candidates with different ``d`` are compared on the same data.
* ``sigma_x`` per epoch and the correlations ``r(h)`` of the filtered data from ``N^-1``.

Selected inversion: Takahashi's recursion on the banded Cholesky factor (compiled with numba
when installed, extra ``speed``; O(n m^2)), else an odd–even block recursion in NumPy
(:mod:`navtrack.smoothing._banded`). Both are tested against dense inverses.

Likelihood (``initial="stationary"``, the default; ``n_o`` observed epochs): the first ``d``
states are diffuse, the first ``p`` differences ``u = (1 - B)^d x`` follow the AR's stationary
distribution ``N(0, sigma_e^2 Gamma_p)``, then eq. (3)::

    -2 log L = (n_o - d) log 2 pi + sum log(sigma_n^2 / w_t) + sum log(sigma_e^2 / v_s)
               + p log sigma_e^2 + log det Gamma_p + log det N + Omega,
    Omega = sum w v^2 / sigma_n^2 + (sum v e^2 + u_0^T Gamma_p^-1 u_0) / sigma_e^2

(the change of variables ``x -> (x_1..x_d, u_0, e)`` has unit Jacobian because ``a_0 = 1``).
This is exactly the likelihood of statsmodels' ``SARIMAX(order=(p, d, 0),
measurement_error=True)`` (tested to 1e-5). ``initial="conditional"`` drops the stationary
start (the plain Gauss–Markov model (2)–(3), conditional on the first ``p`` differences).

References
----------
J. Lindenberger, "Modelling orientation parameters of sensor platforms", ISPRS Comm. I (paper 5
in ``shared/papers``), eqs. (1)–(3), section 2.
W. Förstner, "Ein Verfahren zur Schätzung von Varianz- und Kovarianzkomponenten",
Allgemeine Vermessungs-Nachrichten 86, 446–453, 1979.
W. Förstner, "Determination of the additive noise variance of observed autoregressive processes
using variance component estimation technique", Schriftenreihe 10, Inst. f. Photogrammetrie,
Univ. Stuttgart, 1984.
K.-R. Koch, "Maximum likelihood estimate of variance components", Bull. Géod. 60, 329–338, 1986.
T. Krarup, J. Juhl, K. Kubik, "Götterdämmerung over least squares adjustment", Int. Arch.
Photogramm. 23(B3), 369–378, 1980 (Danish method).
P. J. Huber, "Robust estimation of a location parameter", Ann. Math. Stat. 35, 73–101, 1964.
Y. Yang, "Robust estimation for dependent observations", Manuscripta Geodaetica 19, 10–17, 1994
(IGG-III).
R. Varadhan, C. Roland, "Simple and globally convergent methods for accelerating the
convergence of any EM algorithm", Scand. J. Stat. 35, 335–353, 2008.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, BoolArray, FloatArray, Int8Array
from navtrack.smoothing._banded import (
    add_convolution_band,
    cholesky_solve_banded,
    inverse_band_from_factor,
    single_threaded_blas,
    weighted_band_sums,
)

__all__ = [
    "EPOCH_STATUS",
    "SERIES_STATUS",
    "AriConfig",
    "AriResult",
    "ari_polynomial",
    "fit_ari",
    "fit_ari_order",
    "gauss_markov_filter",
    "observed_information",
    "regularize_time",
    "robust_weight",
    "simulate_ari",
]

RobustName = Literal["danish", "huber", "igg3", "off"]

#: Per-epoch status codes of :class:`AriResult` (``epoch_status``).
EPOCH_STATUS = {0: "ok", 1: "missing", 2: "gross_error", 3: "not_estimated"}
#: Series-level status values of :class:`AriResult` (``status``).
SERIES_STATUS = (
    "ok",
    "not_converged",
    "boundary",
    "too_short",
    "constant",
    "non_monotonic_time",
    "irregular_time",
    "singular",
)

#: Default tuning constants of the weight functions (of the studentized residual ``T``).
#: All three start down-weighting at ``|T| = 2.5`` (about 1.2 % of good observations). The
#: variance components are re-estimated from the reweighted data, so every good observation
#: that is down-weighted lowers sigma_n: the textbook constants 1.5 (Huber's and Yang's, chosen
#: for a known scale) gave sigma_n 8 % (Huber) and 46 % (IGG-III, with a spiral of false flags)
#: too small on clean ARI(2,2) series (3 seeds, n = 2000); with 2.5 the bias was <= 2 %.
ROBUST_DEFAULTS: dict[str, tuple[float, ...]] = {
    # Danish: w = 1 for |T| <= c, exp(1 - (T/c)^2) beyond (continuous at c).
    "danish": (2.5,),
    # Huber: w = 1 for |T| <= k, k/|T| beyond.
    "huber": (2.5,),
    # IGG-III (Yang 1994): w = 1, k0/|T| ((k1 - |T|)/(k1 - k0))^2, 0.
    "igg3": (2.5, 5.0),
    "off": (),
}


@dataclass(frozen=True, slots=True)
class AriConfig:
    """Settings of the ARI estimation.

    Parameters
    ----------
    order : (int, int) or None
        ``(p, d)``; ``None`` selects it by ``criterion`` over ``p = 0..max_p``,
        ``d = min_d..max_d`` (``p + d >= 1``).
    max_p, min_d, max_d : int
        Candidate orders for the selection. Defaults cover the paper's (5, 2), (6, 1), (2, 2).
    criterion : {"bic", "aic"}
        Information criterion of the order selection.
    robust : {"danish", "huber", "igg3", "off"}
        Weight function of the robust reweighting (applied to both equation groups unless
        ``robust_process`` is False).
    robust_c : tuple of float or None
        Tuning constants; ``None`` takes :data:`ROBUST_DEFAULTS`.
    robust_process : bool
        Reweight the process equations (3) too (the paper's treatment of edges and
        discontinuities). Off by default: an isolated gross error can be explained either by a
        down-weighted observation or by down-weighted process equations around it, and
        reweighting both groups let the estimate drift to ``sigma_n -> 0`` on short series in
        our tests (ARI(5,2), 130 epochs, 1 % gross errors), losing the detections.
    flag_threshold : float
        ``|T|`` above which an observation is flagged as a gross error. Default 3.29 is the
        two-sided 0.1 % normal quantile (Baarda's alpha_0 = 0.001).
    n_starts : int
        Starting points of the estimation (noise fractions spread over (0, 1)).
    tol : float
        Stopping rule of the VCE iteration: relative change of ``sigma_n`` and ``sigma_e``.
    gain_tol : float
        Stopping rule of the quasi-Newton search: predicted log-likelihood gain of the next
        step (default 1e-3: parameter changes far below their standard errors; the last digits
        of the likelihood along the weakly identified sigma_e/phi ridge cost many steps).
    max_iter : int
        Iteration limit of the VCE/AR fixed-point scheme (per start).
    max_robust_iter : int
        Limit of the reweighting loop.
    screen_n : int
        Starts are screened on the first ``screen_n`` epochs when the series is longer.
    boundary_margin : float
        An interior solution (both variances positive) is kept over a boundary one
        (``sigma_n`` or ``sigma_e`` at its lower bound) unless the boundary one has a larger
        log-likelihood by more than this (default 1.92 = half the 95 % point of chi-square(1)).
        The paper's model has observation noise by construction; a boundary optimum the data do
        not significantly prefer is the weak identifiability of short series (``sigma_n -> 0``
        is the failure statsmodels' SARIMAX shows), not evidence of noise-free data.
    initial : {"stationary", "conditional"}
        Start of the AR part. ``"stationary"``: the first ``p`` differences follow the AR's
        stationary distribution — the exact likelihood, the same as statsmodels' SARIMAX with
        ``measurement_error=True`` (``phi`` is then kept stationary). ``"conditional"``: the
        likelihood conditional on them (the plain Gauss–Markov model (2)–(3), any ``phi``).
    select_n : int
        The order is selected on the first ``select_n`` epochs when the series is longer (the
        chosen order is then fitted to the whole series).
    """

    order: tuple[int, int] | None = None
    max_p: int = 6
    min_d: int = 0
    max_d: int = 2
    criterion: Literal["bic", "aic"] = "bic"
    robust: RobustName = "danish"
    robust_c: tuple[float, ...] | None = None
    robust_process: bool = False
    flag_threshold: float = 3.29
    n_starts: int = 3
    tol: float = 1e-6
    gain_tol: float = 1e-3
    max_iter: int = 300
    max_robust_iter: int = 20
    screen_n: int = 4000
    select_n: int = 20000
    boundary_margin: float = 1.92
    initial: Literal["stationary", "conditional"] = "stationary"

    def __post_init__(self) -> None:
        if self.order is not None:
            p, d = self.order
            if p < 0 or d < 0 or p + d < 1:
                raise ValueError(
                    f"order must be (p, d) with p, d >= 0 and p + d >= 1, got {self.order}"
                )
        if self.max_p < 0 or self.min_d < 0 or self.max_d < self.min_d:
            raise ValueError("need max_p >= 0 and 0 <= min_d <= max_d")
        if self.robust not in ROBUST_DEFAULTS:
            raise ValueError(
                f"robust must be one of {sorted(ROBUST_DEFAULTS)}, got {self.robust!r}"
            )
        if self.criterion not in ("bic", "aic"):
            raise ValueError(f"criterion must be 'bic' or 'aic', got {self.criterion!r}")
        if self.n_starts < 1 or self.max_iter < 1 or self.tol <= 0:
            raise ValueError("need n_starts >= 1, max_iter >= 1, tol > 0")

    @property
    def tuning(self) -> tuple[float, ...]:
        """The weight function's constants actually used."""
        return ROBUST_DEFAULTS[self.robust] if self.robust_c is None else self.robust_c


@dataclass(frozen=True, slots=True, eq=False)
class AriResult:
    """Filtered series and stochastic model of one ARI fit.

    Attributes
    ----------
    x : ndarray, shape (n,)
        Filtered series (input units); NaN when ``status`` is a bad-input status.
    sigma_x : ndarray, shape (n,)
        Standard deviation of each filtered value, ``sqrt(diag N^-1)``.
    y : ndarray, shape (n,)
        The input series (NaN = missing).
    weight : ndarray, shape (n,)
        Final robust weight of each observation (0 where missing).
    process_weight : ndarray, shape (n - p - d,)
        Final robust weight of each process equation (3), equation ``s`` ending at epoch
        ``s + p + d``.
    test_statistic : ndarray, shape (n,)
        Studentized deletion residual ``T`` of each observation (NaN where missing).
    gross_error : ndarray of bool, shape (n,)
        ``|T| > flag_threshold``.
    epoch_status : ndarray of int8, shape (n,)
        :data:`EPOCH_STATUS` code per epoch.
    p, d : int
        ARI order.
    phi : ndarray, shape (p,)
        AR coefficients of the ``d``-th differences, paper sign (``u_t + sum phi_i u_{t-i} = e_t``).
    a : ndarray, shape (p + d,)
        Combined process parameters ``a_1..a_{p+d}`` of eq. (3).
    sigma_n, sigma_e : float
        Observation noise and ARI prediction-error standard deviations (input units).
    sigma_x_rms : float
        RMS of ``sigma_x`` over the observed epochs (the paper's one value per series).
    autocorr : ndarray, shape (4,)
        ``r(1..4)``: correlation of the filtered values ``h`` epochs apart, mean over epochs.
    loglike : float
        Log-likelihood (diffuse, see module notes) at the estimate, with the final weights.
    aic, bic : float
        Information criteria of the conditional likelihood used for the order selection
        (NaN when the order was given).
    redundancy_n, redundancy_e : float
        Redundancy of the observation and process groups at convergence.
    n_iter : int
        Fixed-point iterations of the last estimation (all starts and reweightings).
    status : str
        One of :data:`SERIES_STATUS`.
    message : str
        Human-readable detail of ``status``.
    """

    x: FloatArray
    sigma_x: FloatArray
    y: FloatArray
    weight: FloatArray
    process_weight: FloatArray
    test_statistic: FloatArray
    gross_error: BoolArray
    epoch_status: Int8Array
    p: int
    d: int
    phi: FloatArray
    a: FloatArray
    sigma_n: float
    sigma_e: float
    sigma_x_rms: float
    autocorr: FloatArray
    loglike: float
    aic: float
    bic: float
    redundancy_n: float
    redundancy_e: float
    n_iter: int
    status: str
    message: str = ""
    candidates: tuple[tuple[int, int, float], ...] = field(default=())

    def __post_init__(self) -> None:
        freeze_arrays(self)

    @property
    def n_flagged(self) -> int:
        """Number of observations flagged as gross errors."""
        return int(np.count_nonzero(self.gross_error))

    @property
    def n_missing(self) -> int:
        """Number of missing epochs (NaN input)."""
        return int(np.count_nonzero(self.epoch_status == 1))

    def summary(self) -> dict[str, object]:
        """Key figures as plain Python values (for JSON and the CLI)."""
        return {
            "status": self.status,
            "order": [self.p, self.d],
            "sigma_n": self.sigma_n,
            "sigma_e": self.sigma_e,
            "sigma_x": self.sigma_x_rms,
            "r": [float(v) for v in self.autocorr],
            "phi": [float(v) for v in self.phi],
            "n": int(self.x.size),
            "n_missing": self.n_missing,
            "n_flagged": self.n_flagged,
            "loglike": self.loglike,
            "message": self.message,
        }


# ---------------------------------------------------------------------------------------------
# model building blocks


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


def _normal_band(c: FloatArray, w: FloatArray, v: FloatArray, sn2: float, se2: float) -> FloatArray:
    """Upper banded normal matrix of eqs. (2)–(3), shape ``(m + 1, n)``."""
    m = c.size - 1
    n = w.size
    ab = np.zeros((m + 1, n))
    ab[m] = w / sn2
    # equation s (0-based, s = m..n-1) involves x_{s-i} with coefficient c_i
    add_convolution_band(ab, c, v / se2)
    return ab


def _process_residuals(c: FloatArray, x: FloatArray) -> FloatArray:
    """``e_s = sum_i c_i x_{s-i}`` for ``s = m..n-1``."""
    if x.size < c.size:
        return np.zeros(0)
    return np.convolve(x, c, mode="valid")


def _process_variance(c: FloatArray, zb: FloatArray) -> FloatArray:
    """``c^T Z c`` of each process equation from the band ``zb`` of ``Z = N^-1``."""
    m = c.size - 1
    n = zb.shape[1]
    q = np.zeros(n - m)
    for i in range(m + 1):
        q += c[i] ** 2 * zb[0, m - i : n - i]
        for i2 in range(i + 1, m + 1):
            # Z[s - i2, s - i] = zb[i2 - i, s - i2]
            q += 2.0 * c[i] * c[i2] * zb[i2 - i, m - i2 : n - i2]
    return q


@dataclass(frozen=True, slots=True)
class _Fit:
    """Internal state of one Gauss–Markov solution."""

    x: FloatArray
    zb: FloatArray | None
    loglike: float
    omega_n: float
    omega_e: float
    logdet: float
    # without zb: the Cholesky factor and the matrix, to add zb later (_with_inverse)
    factor: FloatArray | None = None
    ab: FloatArray | None = None


@dataclass(frozen=True, slots=True)
class _Prior:
    """Stationary start of the AR part: ``u_{d..m-1} ~ N(0, sigma_e^2 Gamma_p(phi))``.

    ``u = (1 - B)^d x``; ``D`` ``(p, m)`` maps ``x_0..x_{m-1}`` to ``u_d..u_{m-1}``;
    ``G = D^T Gamma^-1 D`` is the block added to the normal matrix (times ``1/sigma_e^2``).
    ``dlogdet[j]`` and ``dgamma_inv[j]`` are the exact derivatives with respect to ``phi_j``.
    """

    d_mat: FloatArray
    gamma_inv: FloatArray
    g_mat: FloatArray
    logdet_gamma: float
    dlogdet: FloatArray
    dgamma_inv: FloatArray


def _stationary_prior(phi: FloatArray, d: int) -> _Prior | None:
    """Yule–Walker ``gamma(k) + sum_i phi_i gamma(|k - i|) = [k == 0]`` (unit innovation),
    ``Gamma_p = toeplitz(gamma(0..p-1))`` and its derivatives; ``None`` unless stationary."""
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
    return _Prior(
        d_mat,
        gamma_inv,
        d_mat.T @ gamma_inv @ d_mat,
        2.0 * float(np.sum(np.log(np.diag(chol)))),
        dlogdet,
        dgamma_inv,
    )


def _solve(
    y0: FloatArray,
    w: FloatArray,
    v: FloatArray,
    c: FloatArray,
    sn2: float,
    se2: float,
    width: int | None,
    prior: _Prior | None = None,
) -> _Fit | None:
    """Solve the Gauss–Markov model; ``zb`` (band of ``N^-1``) when ``width`` is not None.

    With ``prior`` the first ``p`` differences get their stationary distribution (exact
    likelihood, as statsmodels' SARIMAX); without it the likelihood is conditional on them.
    """
    ab = _normal_band(c, w, v, sn2, se2)
    m = c.size - 1
    if prior is not None:
        g = prior.g_mat / se2
        for lag in range(m):
            ab[m - lag, lag:m] += np.diag(g, lag)
    try:
        x, logdet, factor = cholesky_solve_banded(ab, w * y0 / sn2)
    except np.linalg.LinAlgError:
        return None
    if not np.all(np.isfinite(x)):
        return None
    e = _process_residuals(c, x)
    resid = y0 - x
    omega_n = float(np.sum(w * resid**2))
    omega_e = float(np.sum(v * e**2))
    used_w = w > 0
    used_v = v > 0
    n_used = int(np.count_nonzero(used_w))
    diffuse = m
    extra = 0.0
    if prior is not None:
        p = prior.d_mat.shape[0]
        diffuse = m - p
        u0 = prior.d_mat @ x[:m]  # differences first: x itself can be large (no cancellation)
        omega_e += float(u0 @ prior.gamma_inv @ u0)
        extra = p * math.log(se2) + prior.logdet_gamma
    loglike = -0.5 * (
        (n_used - diffuse) * math.log(2 * math.pi)
        + float(np.sum(np.log(sn2 / w[used_w])))
        + float(np.sum(np.log(se2 / v[used_v])))
        + extra
        + logdet
        + omega_n / sn2
        + omega_e / se2
    )
    if width is None:
        return _Fit(x, None, loglike, omega_n, omega_e, logdet, factor, ab)
    zb = inverse_band_from_factor(factor, width, ab=ab)
    return _Fit(x, zb, loglike, omega_n, omega_e, logdet)


def _with_inverse(fit: _Fit, width: int) -> _Fit:
    """``fit`` (solved with ``width=None``) completed with the band of ``N^-1``."""
    if fit.zb is not None and fit.zb.shape[0] > width:
        return fit
    if fit.factor is None:
        raise ValueError("the fit keeps no factor")
    zb = inverse_band_from_factor(fit.factor, width, ab=fit.ab)
    return _Fit(fit.x, zb, fit.loglike, fit.omega_n, fit.omega_e, fit.logdet)


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
        See :class:`AriConfig`.

    Returns
    -------
    x : ndarray, shape (n,)
    zb : ndarray, shape (width + 1, n)
        ``zb[l, t] = cov(x_t, x_{t+l})``.
    loglike : float
        Log-likelihood (module notes).
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
        prior = _stationary_prior(phi_arr, d)
        if prior is None:
            raise ValueError("phi is not stationary; use initial='conditional'")
    y0 = np.where(observed, y_arr, 0.0)
    fit = _solve(y0, w, v, c, sigma_n**2, sigma_e**2, width, prior)
    if fit is None or fit.zb is None:
        raise np.linalg.LinAlgError("normal matrix of the Gauss-Markov model is singular")
    return fit.x, fit.zb, fit.loglike


# ---------------------------------------------------------------------------------------------
# estimation kernels


def _phi_gradient_terms(
    c: FloatArray,
    x: FloatArray,
    v: FloatArray,
    p: int,
    d: int,
    big_s: FloatArray,
) -> FloatArray:
    """``sum_s v_s E[e_s u_{s-j}]``, ``j = 1..p`` (``u = (1 - B)^d x``, ``E`` under ``N^-1``).

    This is half the derivative of ``sum v_s E[e_s^2]`` with respect to ``phi_j``: the AR part of
    the likelihood gradient (and of the EM / alternating least-squares step of the paper's
    iterative scheme). ``E[e_s u_{s-j}] = e_s u_{s-j} + sum_{i,k} c_i delta_k Z[s-i, s-j-k]``;
    the covariance part summed over ``s`` is ``sum_{i,k} c_i delta_k S[i, j+k]``
    (:func:`navtrack.smoothing._banded.weighted_band_sums`).
    """
    m = p + d
    n = x.size
    ns = n - m
    delta = ari_polynomial(np.zeros(0), d)
    e = _process_residuals(c, x)  # e_s, s = m..n-1
    ve = v * e
    u = np.convolve(x, delta, mode="valid")  # u_t, t = d..n-1
    out = np.empty(p)
    for j in range(1, p + 1):
        # u_{s-j} for s = m..n-1 is u[m - j - d : m - j - d + ns]
        start = m - j - d
        mean_part = float(np.dot(ve, u[start : start + ns]))
        cov_part = float(c @ big_s[:, j : j + d + 1] @ delta)
        out[j - 1] = mean_part + cov_part
    return out


@dataclass(frozen=True, slots=True)
class _Estimate:
    phi: FloatArray
    log_sn2: float
    log_se2: float
    fit: _Fit
    r_n: float
    r_e: float
    n_iter: int
    converged: bool
    boundary: bool
    grad: FloatArray | None = None  # gradient of -log L at the estimate, when evaluated


def _trial(
    vec: FloatArray,
    y0: FloatArray,
    w: FloatArray,
    v: FloatArray,
    p: int,
    d: int,
    stationary: bool,
) -> _Fit | None:
    """Solution and likelihood at ``(phi, log sn2, log se2)`` without the selected inversion
    (a line-search trial: :func:`_evaluate` completes it when it is accepted)."""
    c = ari_polynomial(vec[:p], d)
    prior = None
    if stationary and p:
        prior = _stationary_prior(vec[:p], d)
        if prior is None:
            return None
    return _solve(y0, w, v, c, math.exp(vec[p]), math.exp(vec[p + 1]), None, prior)


def _evaluate(
    vec: FloatArray,
    y0: FloatArray,
    w: FloatArray,
    v: FloatArray,
    p: int,
    d: int,
    stationary: bool,
    partial: _Fit | None = None,
) -> tuple[_Fit, float, float, FloatArray] | None:
    """Fit at ``(phi, log sn2, log se2)``; redundancies and the gradient of ``-log L``.

    ``d(-log L)/d log sigma_k^2 = (r_k - Omega_k / sigma_k^2) / 2`` and
    ``d(-log L)/d phi_j = sum_s v_s E[e_s u_{s-j}] / sigma_e^2`` (+ the stationary-start
    term ``(d log det Gamma + tr(d Gamma^-1 E[u u^T]) / sigma_e^2) / 2``). ``partial``: the
    result of :func:`_trial` at the same point (its factor is reused).
    """
    phi = vec[:p]
    sn2 = math.exp(vec[p])
    se2 = math.exp(vec[p + 1])
    c = ari_polynomial(phi, d)
    prior = None
    if stationary and p:
        prior = _stationary_prior(phi, d)
        if prior is None:
            return None
    m = p + d
    if partial is not None:
        fit: _Fit | None = _with_inverse(partial, m)
    else:
        fit = _solve(y0, w, v, c, sn2, se2, m, prior)
    if fit is None or fit.zb is None:
        return None
    zb = fit.zb
    n_w = float(np.count_nonzero(w > 0))
    n_v = float(np.count_nonzero(v > 0))
    # redundancies r_k = n_k - tr(N^-1 N_k) (Förstner 1979)
    r_n = n_w - float(np.sum(w * zb[0])) / sn2
    big_s = weighted_band_sums(zb, v, m)
    trace_e = float(c @ big_s @ c)  # sum_s v_s c^T Z_s c
    z_top = None
    if prior is not None:
        z_top = _dense_block(zb, m)
        trace_e += float(np.sum(prior.g_mat * z_top))
        n_v += p
    r_e = n_v - trace_e / se2
    grad = np.empty(p + 2)
    # d(-2 log L)/d log sigma_k^2 = r_k - Omega_k / sigma_k^2  (zero <=> VCE equation)
    grad[p] = 0.5 * (r_n - fit.omega_n / sn2)
    grad[p + 1] = 0.5 * (r_e - fit.omega_e / se2)
    if p:
        grad[:p] = _phi_gradient_terms(c, fit.x, v, p, d, big_s) / se2
    if prior is not None and z_top is not None:
        u0 = prior.d_mat @ fit.x[:m]
        moment = prior.d_mat @ z_top @ prior.d_mat.T + np.outer(u0, u0)
        for j in range(p):
            grad[j] += 0.5 * (prior.dlogdet[j] + float(np.sum(prior.dgamma_inv[j] * moment)) / se2)
    return fit, r_n, r_e, grad


def _dense_block(zb: FloatArray, m: int) -> FloatArray:
    """Top-left ``(m, m)`` block of ``Z`` from its band (needs ``zb.shape[0] >= m``)."""
    block = np.empty((m, m))
    for i in range(m):
        for j in range(i, m):
            block[i, j] = block[j, i] = zb[j - i, i]
    return block


def _make_estimate(
    vec: FloatArray,
    out: tuple[_Fit, float, float, FloatArray | None],
    p: int,
    n_eval: int,
    converged: bool,
    log_floor: float,
) -> _Estimate:
    fit, r_n, r_e, grad = out
    # A component at its floor, or with less than one observation's worth of redundancy, is
    # not estimable from these data (the likelihood is flat towards zero variance).
    boundary = min(vec[p], vec[p + 1]) <= log_floor + 1e-6 or min(r_n, r_e) < 1.0
    return _Estimate(
        vec[:p].copy(),
        float(vec[p]),
        float(vec[p + 1]),
        fit,
        r_n,
        r_e,
        n_eval,
        converged,
        boundary,
        grad,
    )


def _hessian(
    vec: FloatArray,
    y0: FloatArray,
    w: FloatArray,
    v: FloatArray,
    p: int,
    d: int,
    stationary: bool,
) -> FloatArray:
    """Hessian of ``-log L`` by forward differences of the analytic gradient, made SPD."""
    base = _evaluate(vec, y0, w, v, p, d, stationary)
    k = vec.size
    if base is None:
        return np.eye(k)
    hess = np.empty((k, k))
    for j in range(k):
        h = 1e-5 * max(1.0, abs(vec[j]))
        shifted = vec.copy()
        shifted[j] += h
        out = _evaluate(shifted, y0, w, v, p, d, stationary)
        hess[:, j] = (out[3] - base[3]) / h if out is not None else 0.0
    hess = 0.5 * (hess + hess.T)
    vals, vecs = np.linalg.eigh(hess)
    floor = 1e-8 * max(float(np.max(np.abs(vals))), 1e-12)
    return (vecs * np.maximum(np.abs(vals), floor)) @ vecs.T


def _refine(
    vec: FloatArray,
    hess: FloatArray,
    y0: FloatArray,
    w: FloatArray,
    v: FloatArray,
    p: int,
    d: int,
    stationary: bool,
    tol: float,
    max_iter: int,
    log_floor: float,
    log_ceiling: float,
    start: _Estimate | None = None,
) -> tuple[_Estimate, FloatArray] | None:
    """Quasi-Newton (BFGS from ``hess``) with Armijo backtracking.

    The AR coefficients and the two log-variances move together on ``-log L`` with the analytic
    gradient: its variance part is the VCE equation ``r_k - Omega_k / sigma_k^2``, its AR part
    the expected-moment least-squares equation of the paper's alternating scheme. Steps are
    capped (1 in ``phi``, 2 in ``log sigma^2``) and the log-variances kept in
    ``[log_floor, log_ceiling]``. Stopping rule: the expected gain ``g^T H^-1 g / 2`` of the
    next step is below ``tol`` (log-likelihood units), or ``max_iter`` steps. ``start``, an
    estimate already evaluated at ``vec`` with the same weights, saves that evaluation.
    """
    out: tuple[_Fit, float, float, FloatArray] | None
    if start is not None and start.grad is not None:
        out = (start.fit, start.r_n, start.r_e, start.grad)
        n_eval = 0
    else:
        out = _evaluate(vec, y0, w, v, p, d, stationary)
        n_eval = 1
    if out is None:
        return None
    b_mat = hess.copy()
    converged = False
    for _ in range(max_iter):
        f, g = -out[0].loglike, out[3]
        step = -np.linalg.solve(b_mat, g)
        gain = -0.5 * float(g @ step)
        if gain < tol:
            converged = True
            break
        cap = max(
            float(np.max(np.abs(step[:p]))) if p else 0.0,
            0.5 * float(np.max(np.abs(step[p:]))),
            1.0,
        )
        step = step / cap
        t = 1.0
        accepted = None
        while t > 1e-6:
            trial = vec + t * step
            trial[p:] = np.clip(trial[p:], log_floor, log_ceiling)
            # likelihood first; the selected inversion and gradient only for an accepted step
            part = _trial(trial, y0, w, v, p, d, stationary)
            n_eval += 1
            if part is not None and -part.loglike <= f - 1e-4 * t * 2.0 * gain / cap:
                new = _evaluate(trial, y0, w, v, p, d, stationary, partial=part)
                if new is not None:
                    accepted = (trial, new)
                    break
            t *= 0.25
        if accepted is None:
            converged = gain < 1e3 * tol
            break
        trial, new = accepted
        s_k = trial - vec
        y_k = new[3] - g
        sy = float(s_k @ y_k)
        if sy > 1e-12 * float(np.linalg.norm(s_k) * np.linalg.norm(y_k)):
            bs = b_mat @ s_k
            b_mat = b_mat - np.outer(bs, bs) / float(s_k @ bs) + np.outer(y_k, y_k) / sy
        vec, out = trial, new
    return _make_estimate(vec, out, p, n_eval, converged, log_floor), b_mat


def _vce_polish(
    est: _Estimate,
    y0: FloatArray,
    w: FloatArray,
    v: FloatArray,
    p: int,
    d: int,
    stationary: bool,
    tol: float,
    max_iter: int,
    log_floor: float,
) -> _Estimate:
    """Iterate the reproducing VCE ``sigma_k^2 <- Omega_k / r_k`` with ``phi`` fixed.

    Stopping rule: relative change of both standard deviations below ``tol``. A step that would
    lower the likelihood ends the iteration (the estimate is then already at the VCE fixed
    point to the likelihood's resolution).
    """
    vec = np.concatenate([est.phi, [est.log_sn2, est.log_se2]])
    out: tuple[_Fit, float, float, FloatArray | None] = (est.fit, est.r_n, est.r_e, est.grad)
    n_eval = 0
    converged = False
    for _ in range(max_iter):
        fit, r_n, r_e, _ = out
        if r_n <= 0 or r_e <= 0:
            break
        new = vec.copy()
        new[p] = max(math.log(max(fit.omega_n, 1e-300) / r_n), log_floor)
        new[p + 1] = max(math.log(max(fit.omega_e, 1e-300) / r_e), log_floor)
        change = 0.5 * float(np.max(np.abs(new[p:] - vec[p:])))
        if change < tol:
            converged = True
            break
        trial = _evaluate(new, y0, w, v, p, d, stationary)
        n_eval += 1
        if trial is None or trial[0].loglike < fit.loglike:
            converged = change < 1e3 * tol
            break
        vec, out = new, trial
    est_new = _make_estimate(vec, out, p, n_eval, converged and est.converged, log_floor)
    return est_new


def _starts(y: FloatArray, p: int, d: int, n_starts: int) -> list[FloatArray]:
    """Starting values: AR fit to the d-th differences, noise fractions spread over (0, 1)."""
    delta = ari_polynomial(np.zeros(0), d)
    u = np.convolve(y, delta, mode="valid")  # NaN propagates over gaps
    gamma0 = float(np.nanvar(u)) if np.isfinite(u).sum() > 1 else float(np.nanvar(y))
    if not np.isfinite(gamma0) or gamma0 <= 0:
        gamma0 = 1.0
    phi0 = np.zeros(p)
    resid_var = gamma0
    if p > 0:
        rows = np.column_stack([u[p - i : u.size - i] for i in range(1, p + 1)])
        target = u[p:]
        ok = np.isfinite(target) & np.all(np.isfinite(rows), axis=1)
        if np.count_nonzero(ok) > 2 * p:
            sol, *_ = np.linalg.lstsq(rows[ok], -target[ok], rcond=None)
            roots = np.roots(np.concatenate([[1.0], sol]))
            if np.all(np.abs(roots) < 0.98):
                phi0 = sol
            resid = target[ok] + rows[ok] @ phi0
            resid_var = max(float(np.var(resid)), 1e-12 * gamma0)
    noise_var_unit = math.comb(2 * d, d)
    fractions = np.linspace(0.1, 0.9, n_starts) if n_starts > 1 else np.array([0.5])
    starts = []
    for f in fractions:
        sn2 = f * gamma0 / noise_var_unit
        se2 = (1.0 - f) * resid_var
        starts.append(np.concatenate([phi0 * (1.0 - f), [math.log(sn2), math.log(se2)]]))
    return starts


# ---------------------------------------------------------------------------------------------
# robust weights


def robust_weight(t: ArrayLike, name: RobustName, c: tuple[float, ...] | None = None) -> FloatArray:
    """Weight of an equation from its studentized residual ``t``.

    Parameters
    ----------
    t : array_like
        Studentized (deletion) residuals; NaN gives weight 0.
    name : {"danish", "huber", "igg3", "off"}
        * ``danish``: ``1`` for ``|t| <= c``, ``exp(1 - (t/c)^2)`` beyond (default ``c = 2.5``).
          Krarup, Juhl & Kubik (1980) describe the Danish method as iterated reweighting with
          weights falling off exponentially beyond a few sigma; the exact function differs
          between later sources (squared vs. powered exponents, with or without the cut-off), so
          it is a parameter here. This continuous exponential form is the one often given for the
          method in the geodetic robust-estimation literature.
        * ``huber``: ``1`` for ``|t| <= k``, ``k / |t|`` beyond (Huber 1964; default
          ``k = 2.5``, see :data:`ROBUST_DEFAULTS`).
        * ``igg3``: ``1`` for ``|t| <= k0``; ``k0/|t| ((k1 - |t|)/(k1 - k0))^2`` for
          ``k0 < |t| <= k1``; ``0`` beyond (Yang 1994; default ``k0 = 2.5, k1 = 5.0``).
        * ``off``: all weights 1.
    c : tuple of float, optional
        Tuning constants (see above); default :data:`ROBUST_DEFAULTS`.

    Returns
    -------
    w : ndarray, same shape as ``t``, values in [0, 1]
    """
    if name not in ROBUST_DEFAULTS:
        raise ValueError(f"unknown robust weight function {name!r}")
    consts = ROBUST_DEFAULTS[name] if c is None else c
    a = np.abs(np.asarray(t, dtype=float))
    finite = np.isfinite(a)
    a = np.where(finite, a, 0.0)
    if name == "off":
        w = np.ones_like(a)
    elif name == "danish":
        (k,) = consts
        w = np.where(a <= k, 1.0, np.exp(1.0 - (a / k) ** 2))
    elif name == "huber":
        (k,) = consts
        w = np.where(a <= k, 1.0, k / np.maximum(a, k))
    else:
        k0, k1 = consts
        mid = k0 / np.maximum(a, k0) * ((k1 - a) / (k1 - k0)) ** 2
        w = np.where(a <= k0, 1.0, np.where(a <= k1, mid, 0.0))
    return np.where(finite, w, 0.0)


def _deletion_statistic(
    resid: FloatArray, var_post: FloatArray, weight: FloatArray, sigma2: float
) -> FloatArray:
    """Studentized deletion residual of equations with value ``resid = l - f(x_hat)``.

    With ``Q = var_post`` the posterior variance of the fitted value and weight ``w``, the
    prediction of that value from all other equations has variance ``P = 1/(1/Q - w/sigma2)``
    and residual ``u = resid P / Q``; ``T = u / sqrt(sigma2 + P)`` (for ``w = 1`` this is
    Baarda's normalized residual ``v / (sigma sqrt(r))``).
    """
    q = np.maximum(var_post, 1e-300)
    inv_p = 1.0 / q - weight / sigma2
    inv_p = np.maximum(inv_p, 1e-12 / sigma2)
    pred_var = 1.0 / inv_p
    u = resid * pred_var / q
    return u / np.sqrt(sigma2 + pred_var)


# ---------------------------------------------------------------------------------------------
# drivers


def _bad(y: FloatArray, status: str, message: str, p: int = 0, d: int = 0) -> AriResult:
    n = y.size
    nan = np.full(n, np.nan)
    m = p + d
    return AriResult(
        x=nan.copy(),
        sigma_x=nan.copy(),
        y=y.copy(),
        weight=np.zeros(n),
        process_weight=np.zeros(max(n - m, 0)),
        test_statistic=nan.copy(),
        gross_error=np.zeros(n, dtype=bool),
        epoch_status=np.where(np.isfinite(y), 3, 1).astype(np.int8),
        p=p,
        d=d,
        phi=np.full(p, np.nan),
        a=np.full(m, np.nan),
        sigma_n=math.nan,
        sigma_e=math.nan,
        sigma_x_rms=math.nan,
        autocorr=np.full(4, np.nan),
        loglike=math.nan,
        aic=math.nan,
        bic=math.nan,
        redundancy_n=math.nan,
        redundancy_e=math.nan,
        n_iter=0,
        status=status,
        message=message,
    )


def _check_input(y: ArrayLike, t: ArrayLike | None) -> tuple[FloatArray, str, str]:
    y_arr = np.asarray(y, dtype=float)
    if y_arr.ndim != 1:
        raise ValueError(f"y must be one-dimensional (n,), got shape {y_arr.shape}")
    if np.any(np.isinf(y_arr)):
        raise ValueError("y contains infinite values; mark missing epochs with NaN")
    if t is not None:
        t_arr = np.asarray(t, dtype=float)
        if t_arr.shape != y_arr.shape:
            raise ValueError(f"t must have the shape of y {y_arr.shape}, got {t_arr.shape}")
        if not np.all(np.isfinite(t_arr)):
            return y_arr, "non_monotonic_time", "time stamps contain NaN/inf"
        steps = np.diff(t_arr)
        if np.any(steps <= 0):
            k = int(np.argmax(steps <= 0))
            return y_arr, "non_monotonic_time", f"time not strictly increasing at index {k + 1}"
        if steps.size and np.max(steps) - np.min(steps) > 1e-6 * np.median(steps):
            return (
                y_arr,
                "irregular_time",
                "time steps are not uniform; use regularize_time() to put the series on a grid",
            )
    observed = np.isfinite(y_arr)
    if np.count_nonzero(observed) >= 2 and np.ptp(y_arr[observed]) == 0:
        return y_arr, "constant", "all observed values are equal"
    return y_arr, "ok", ""


def _min_observations(p: int, d: int) -> int:
    # redundancy n_o - m must exceed the p + 2 estimated parameters
    return p + d + p + 4


def fit_ari_order(
    y: ArrayLike,
    p: int,
    d: int,
    config: AriConfig | None = None,
    *,
    t: ArrayLike | None = None,
) -> AriResult:
    """Fit an ARI(p, d) model of fixed order (see :func:`fit_ari`)."""
    cfg = AriConfig(order=(p, d)) if config is None else config
    y_arr, status, message = _check_input(y, t)
    if status != "ok":
        return _bad(y_arr, status, message, p, d)
    with single_threaded_blas():
        return _fit_fixed(y_arr, p, d, cfg, robust=True)


def _robust_weights(
    est: _Estimate,
    y0: FloatArray,
    observed: BoolArray,
    w: FloatArray,
    v: FloatArray,
    d: int,
    cfg: AriConfig,
) -> tuple[FloatArray, FloatArray]:
    """New observation and process weights from the studentized deletion residuals."""
    zb = est.fit.zb
    if zb is None:
        return w, v
    sn2 = math.exp(est.log_sn2)
    se2 = math.exp(est.log_se2)
    t_obs = _deletion_statistic(y0 - est.fit.x, zb[0], w, sn2)
    w_new = np.where(observed, robust_weight(t_obs, cfg.robust, cfg.tuning), 0.0)
    if not cfg.robust_process:
        return w_new, v
    c = ari_polynomial(est.phi, d)
    e = _process_residuals(c, est.fit.x)
    q = _process_variance(c, zb)
    v_new = robust_weight(_deletion_statistic(-e, q, v, se2), cfg.robust, cfg.tuning)
    return w_new, v_new


def _choose(found: list[_Estimate], margin: float) -> _Estimate:
    """Largest likelihood, but an interior solution within ``margin`` beats a boundary one."""
    best = max(found, key=lambda e: e.fit.loglike)
    if best.boundary:
        interior = [e for e in found if not e.boundary]
        if interior:
            alt = max(interior, key=lambda e: e.fit.loglike)
            if alt.fit.loglike >= best.fit.loglike - margin:
                return alt
    return best


def _fit_fixed(
    y: FloatArray,
    p: int,
    d: int,
    cfg: AriConfig,
    *,
    robust: bool,
    starts: list[FloatArray] | None = None,
) -> AriResult:
    n = y.size
    m = p + d
    observed = np.isfinite(y)
    n_obs = int(np.count_nonzero(observed))
    if n <= m or n_obs < _min_observations(p, d):
        return _bad(
            y,
            "too_short",
            f"{n_obs} observed epochs; ARI({p},{d}) needs at least {_min_observations(p, d)}",
            p,
            d,
        )
    # Work on the series minus a polynomial of degree d - 1 (the mean when d <= 1): the process
    # equations annihilate it, so nothing changes but the scale of the numbers (ECEF offsets,
    # drifting integrated series); for d = 0 it gives the AR model its zero mean.
    tt = np.linspace(-1.0, 1.0, n)
    trend_coef = np.polynomial.polynomial.polyfit(tt[observed], y[observed], max(d - 1, 0))
    offset: FloatArray = np.asarray(
        np.polynomial.polynomial.polyval(tt, trend_coef), dtype=np.float64
    )
    yc = y - offset
    y0 = np.where(observed, yc, 0.0)
    scale = float(np.nanstd(np.convolve(yc, ari_polynomial(np.zeros(0), d), mode="valid")))
    if not np.isfinite(scale) or scale <= 0:
        scale = float(np.nanstd(yc)) or 1.0
    log_floor = math.log((1e-6 * scale) ** 2)
    w = observed.astype(float)
    v = np.ones(n - m)
    if starts is None:
        starts = _starts(yc, p, d, cfg.n_starts)
    log_ceiling = math.log((1e3 * scale) ** 2)
    st = cfg.initial == "stationary"
    # Several starts on a leading window (the whole series when short): the likelihood is
    # multimodal (sigma_n -> 0 and sigma_e -> 0 are local optima on short series).
    head = min(n, cfg.screen_n)
    hw = w[:head]
    hv = v[: head - m]
    found: list[_Estimate] = []
    n_iter = 0
    for start in starts:
        hess0 = _hessian(start, y0[:head], hw, hv, p, d, st)
        n_iter += p + 3
        out = _refine(
            start,
            hess0,
            y0[:head],
            hw,
            hv,
            p,
            d,
            st,
            cfg.gain_tol,
            cfg.max_iter,
            log_floor,
            log_ceiling,
        )
        if out is None:
            continue
        n_iter += out[0].n_iter
        found.append(out[0])
    if not found:
        return _bad(y, "singular", "normal matrix singular at every start", p, d)
    best = _choose(found, cfg.boundary_margin)
    vec = np.concatenate([best.phi, [best.log_sn2, best.log_se2]])
    hess = _hessian(vec, y0[:head], hw, hv, p, d, st)
    n_iter += p + 3
    # Quasi-Newton refinement on the whole series from the window's optimum, with the window's
    # Hessian scaled by the number of observations (also certifies convergence of short series).
    # Intermediate windows (8x per stage, fresh or carried-over Hessians) were tried: no less
    # work in total, because the last digits along the weakly identified sigma_e/phi ridge
    # dominate either way.
    hess = hess * (n_obs / max(int(np.count_nonzero(hw)), 1))
    use_robust = robust and cfg.robust != "off"
    # Long robust fits only need to get near the unweighted optimum before reweighting: loose
    # gain tolerance here, the tight joint refinement follows the reweighting.
    first_tol = cfg.gain_tol * 100 if (use_robust and head < n) else cfg.gain_tol
    refined = _refine(
        vec, hess, y0, w, v, p, d, st, first_tol, cfg.max_iter, log_floor, log_ceiling
    )
    if refined is None:
        return _bad(y, "singular", "normal matrix singular on the full series", p, d)
    best, hess = refined
    n_iter += best.n_iter
    budget = cfg.max_robust_iter if use_robust else 0
    for _ in range(3 if use_robust else 0):
        # IRLS inside the VCE: new weights, variance components re-estimated with phi fixed
        # (one solve + selected inversion per step) until the weights settle; then phi and
        # the variances jointly; repeated while that moves the weights.
        reweighted = False
        while budget > 0:
            budget -= 1
            w_new, v_new = _robust_weights(best, y0, observed, w, v, d, cfg)
            dw = np.concatenate([np.abs(w_new - w), np.abs(v_new - v)])
            # settled: no weight moved by 0.01, or on average by less than 1e-5 (on long
            # series some weight near the cut-off always moves a little)
            if (
                float(np.max(dw)) < 1e-2
                or float(np.mean(dw)) < 1e-5
                or np.count_nonzero(w_new > 0) < _min_observations(p, d)
            ):
                break
            w, v = w_new, v_new
            reweighted = True
            vec = np.concatenate([best.phi, [best.log_sn2, best.log_se2]])
            step_out = _evaluate(vec, y0, w, v, p, d, st)
            if step_out is None:
                break
            est = _make_estimate(vec, step_out, p, 1, best.converged, log_floor)
            best = _vce_polish(est, y0, w, v, p, d, st, 1e-3, 10, log_floor)
            n_iter += 1 + best.n_iter
        if not reweighted and best.converged:
            break
        # fresh curvature (window, current weights) rather than the BFGS matrix of the last
        # search, which crawls along the sigma_e/phi ridge once the weights have changed
        hw, hv = w[:head], v[: head - m]
        h_scale = np.count_nonzero(w) / max(int(np.count_nonzero(hw)), 1)
        vec = np.concatenate([best.phi, [best.log_sn2, best.log_se2]])
        hess = _hessian(vec, y0[:head], hw, hv, p, d, st) * h_scale
        n_iter += p + 3
        refined = _refine(
            vec,
            hess,
            y0,
            w,
            v,
            p,
            d,
            st,
            cfg.gain_tol,
            cfg.max_iter,
            log_floor,
            log_ceiling,
            start=best,  # already evaluated at vec with these weights
        )
        if refined is None:
            break
        best, hess = refined
        n_iter += best.n_iter
    best = _vce_polish(best, y0, w, v, p, d, st, cfg.tol, cfg.max_iter, log_floor)
    n_iter += best.n_iter
    return _finish(y, offset, observed, y0, w, v, p, d, best, n_iter, cfg)


def _finish(
    y: FloatArray,
    offset: FloatArray,
    observed: BoolArray,
    y0: FloatArray,
    w: FloatArray,
    v: FloatArray,
    p: int,
    d: int,
    est: _Estimate,
    n_iter: int,
    cfg: AriConfig,
) -> AriResult:
    sn2 = math.exp(est.log_sn2)
    se2 = math.exp(est.log_se2)
    c = ari_polynomial(est.phi, d)
    prior = _stationary_prior(est.phi, d) if cfg.initial == "stationary" and p else None
    fit = _solve(y0, w, v, c, sn2, se2, max(p + d, 4), prior)
    if fit is None or fit.zb is None:
        return _bad(y, "singular", "normal matrix singular at the estimate", p, d)
    zb = fit.zb
    n = y.size
    var_x = np.maximum(zb[0], 0.0)
    sigma_x = np.sqrt(var_x)
    t_obs = np.where(observed, _deletion_statistic(y0 - fit.x, zb[0], w, sn2), np.nan)
    gross = observed & (np.abs(np.nan_to_num(t_obs)) > cfg.flag_threshold)
    autocorr = np.full(4, np.nan)
    for h in range(1, min(4, n - 1) + 1):
        r = zb[h, : n - h] / np.sqrt(var_x[: n - h] * var_x[h:])
        autocorr[h - 1] = float(np.nanmean(r))
    status = "ok"
    message = ""
    if est.boundary:
        status = "boundary"
        message = "a variance component reached its lower bound (not identifiable from the data)"
    elif not est.converged:
        status = "not_converged"
        message = f"no convergence within max_iter={cfg.max_iter}"
    epoch_status = np.zeros(n, dtype=np.int8)
    epoch_status[~observed] = 1
    epoch_status[gross] = 2
    return AriResult(
        x=fit.x + offset,
        sigma_x=sigma_x,
        y=y.copy(),
        weight=w.copy(),
        process_weight=v.copy(),
        test_statistic=t_obs,
        gross_error=gross,
        epoch_status=epoch_status,
        p=p,
        d=d,
        phi=est.phi.copy(),
        a=c[1:].copy(),
        sigma_n=math.sqrt(sn2),
        sigma_e=math.sqrt(se2),
        sigma_x_rms=float(np.sqrt(np.mean(var_x[observed]))) if observed.any() else math.nan,
        autocorr=autocorr,
        loglike=fit.loglike,
        aic=math.nan,
        bic=math.nan,
        redundancy_n=est.r_n,
        redundancy_e=est.r_e,
        n_iter=n_iter,
        status=status,
        message=message,
    )


def _conditional_loglike(res: AriResult, big_m: int, initial: str) -> float:
    """Log-likelihood of the observations after the first ``M`` observed ones given those
    (prediction-error decomposition).

    The conditioning head ends at the ``M``-th observed epoch, not at epoch ``M``: a series
    that starts with a gap (BROAD: tracking lost at the start) would otherwise condition on an
    unobserved head, whose normal matrix is singular up to rounding, so that candidates were
    dropped or kept by rounding-level differences.
    """
    m = res.p + res.d
    if big_m <= m and (initial != "stationary" or res.p == 0):
        return res.loglike
    seen = np.flatnonzero(np.isfinite(res.y))
    k = int(seen[big_m - 1]) + 1 if seen.size >= big_m else big_m
    k = max(k, m + 1)
    head = res.y[:k] - float(np.nanmean(res.y))
    observed = np.isfinite(head)
    w = res.weight[:k]
    v = res.process_weight[: k - m]
    c = ari_polynomial(res.phi, res.d)
    prior = _stationary_prior(res.phi, res.d) if initial == "stationary" and res.p else None
    fit = _solve(
        np.where(observed, head, 0.0), w, v, c, res.sigma_n**2, res.sigma_e**2, None, prior
    )
    if fit is None:
        return math.nan
    return res.loglike - fit.loglike


def _better(new: AriResult, old: AriResult, cfg: AriConfig) -> bool:
    """``new`` has the larger likelihood, with :func:`_choose`'s preference for interior
    solutions (a boundary one must beat an interior one by ``boundary_margin``)."""
    margin = 0.0
    if (new.status == "boundary") != (old.status == "boundary"):
        margin = cfg.boundary_margin if new.status == "boundary" else -cfg.boundary_margin
    return new.loglike > old.loglike + margin


def fit_ari(
    y: ArrayLike,
    config: AriConfig | None = None,
    *,
    t: ArrayLike | None = None,
) -> AriResult:
    """Estimate the ARI model, filtered series and gross errors of one series.

    Parameters
    ----------
    y : array_like, shape (n,)
        Equally spaced series in any unit; NaN marks missing epochs (kept as missing
        observations: the filtered value is interpolated by the model and counted in
        ``n_missing``).
    config : AriConfig, optional
        Order (or its selection), robust weighting, stopping rule.
    t : array_like, shape (n,), optional
        Time stamps; checked to be strictly increasing and uniform (status
        ``non_monotonic_time`` / ``irregular_time`` otherwise; see :func:`regularize_time`).

    Returns
    -------
    AriResult
        Bad input gives a result with a non-``ok`` status (``too_short``, ``constant``,
        ``non_monotonic_time``, ``irregular_time``) and NaN estimates; wrong shapes or
        infinite values raise ``ValueError``.

    Examples
    --------
    >>> import numpy as np
    >>> from navtrack.smoothing.ari import AriConfig, fit_ari, simulate_ari
    >>> y, x = simulate_ari(np.random.default_rng(1), 2000, [-0.5], 2, 0.02, 0.01)
    >>> res = fit_ari(y, AriConfig(order=(1, 2)))
    >>> bool(abs(res.sigma_n / 0.02 - 1) < 0.2)
    True
    """
    cfg = AriConfig() if config is None else config
    y_arr, status, message = _check_input(y, t)
    if status != "ok":
        return _bad(y_arr, status, message)
    with single_threaded_blas():
        return _select_and_fit(y_arr, cfg)


def _select_and_fit(y_arr: FloatArray, cfg: AriConfig) -> AriResult:
    """Body of :func:`fit_ari` after input checks: order selection, then the robust fit."""
    if cfg.order is not None:
        return _fit_fixed(y_arr, cfg.order[0], cfg.order[1], cfg, robust=True)
    candidates = [
        (p, d) for d in range(cfg.min_d, cfg.max_d + 1) for p in range(cfg.max_p + 1) if p + d >= 1
    ]
    y_sel = y_arr[: cfg.select_n]
    n_obs = int(np.count_nonzero(np.isfinite(y_sel)))
    candidates = [(p, d) for p, d in candidates if n_obs >= _min_observations(p, d)]
    if not candidates:
        return _bad(y_arr, "too_short", f"{n_obs} observed epochs are too few for any ARI model")
    big_m = max(p + d for p, d in candidates)
    ok_status = ("ok", "not_converged", "boundary")
    yc = y_sel - float(np.nanmean(y_sel))
    found: dict[tuple[int, int], AriResult] = {}
    # Upward pass: ARI(p, d) warm from ARI(p-1, d) (phi_p = 0) plus the high-noise default start.
    for p, d in candidates:
        starts = None
        prev = found.get((p - 1, d))
        if prev is not None:
            warm = np.concatenate(
                [prev.phi, [0.0, 2 * math.log(prev.sigma_n), 2 * math.log(prev.sigma_e)]]
            )
            starts = [warm, *_starts(yc, p, d, cfg.n_starts)[-1:]]
        res = _fit_fixed(y_sel, p, d, cfg, robust=False, starts=starts)
        if res.status in ok_status:
            found[(p, d)] = res
    # Downward pass: ARI(p, d) again from ARI(p+1, d) without its last coefficient, the better
    # optimum kept. On heavy-tailed series the non-robust likelihood is multimodal (a
    # low-noise/rough-process mode and a high-noise/smooth-process one); reaching a candidate
    # from both neighbours makes its optimum, and so the selected order, independent of the
    # path that led to it in all the cases we tried (BROAD orientation; see docs/ari.md).
    for p, d in reversed(candidates):
        upper = found.get((p + 1, d))
        if upper is None:
            continue
        phi = upper.phi[:p].copy()
        # the truncated AR part need not be stationary: shrink it towards 0 until it is
        while phi.size and not np.all(np.abs(np.roots(np.concatenate([[1.0], phi]))) < 0.98):
            phi = np.zeros(p) if float(np.max(np.abs(phi))) < 1e-3 else 0.5 * phi
        start = np.concatenate([phi, [2 * math.log(upper.sigma_n), 2 * math.log(upper.sigma_e)]])
        res = _fit_fixed(y_sel, p, d, cfg, robust=False, starts=[start])
        current = found.get((p, d))
        if res.status in ok_status and (current is None or _better(res, current, cfg)):
            found[(p, d)] = res
    scores: list[tuple[int, int, float]] = []
    best_key: tuple[int, int] | None = None
    best_score = math.inf
    fits: dict[tuple[int, int], tuple[float, float]] = {}
    for p, d in candidates:
        if (p, d) not in found:
            continue
        ll = _conditional_loglike(found[(p, d)], big_m, cfg.initial)
        if not np.isfinite(ll):
            continue
        k = p + 2
        n_eff = n_obs - big_m
        aic = -2 * ll + 2 * k
        bic = -2 * ll + k * math.log(max(n_eff, 2))
        fits[(p, d)] = (aic, bic)
        score = bic if cfg.criterion == "bic" else aic
        scores.append((p, d, score))
        if score < best_score:
            best_score, best_key = score, (p, d)
    if best_key is None:
        return _bad(y_arr, "singular", "no candidate order could be fitted")
    final = _fit_fixed(y_arr, best_key[0], best_key[1], cfg, robust=True)
    aic, bic = fits[best_key]
    return _replace(final, aic=aic, bic=bic, candidates=tuple(scores))


def _replace(res: AriResult, **changes: object) -> AriResult:
    values: dict[str, Any] = {name: getattr(res, name) for name in res.__dataclass_fields__}
    values.update(changes)
    return AriResult(**values)


def observed_information(
    y: ArrayLike,
    phi: ArrayLike,
    d: int,
    sigma_n: float,
    sigma_e: float,
    *,
    initial: Literal["stationary", "conditional"] = "stationary",
) -> FloatArray:
    """Observed information (Hessian of ``-log L``) at given parameters, unit weights.

    Parameters
    ----------
    y : array_like, shape (n,)
        Series (NaN = missing).
    phi : array_like, shape (p,)
    d : int
    sigma_n, sigma_e : float

    Returns
    -------
    ndarray, shape (p + 2, p + 2)
        With respect to ``(phi_1..phi_p, log sigma_n^2, log sigma_e^2)``; its inverse is the
        Cramér–Rao covariance, so ``sqrt(inv[-2, -2]) / 2`` is the relative standard deviation
        of ``sigma_n`` attainable from these data (used to decide identifiability).
    """
    y_arr = np.asarray(y, dtype=float)
    phi_arr = np.asarray(phi, dtype=float).ravel()
    p = phi_arr.size
    m = p + d
    observed = np.isfinite(y_arr)
    y0 = np.where(observed, y_arr - float(np.mean(y_arr[observed])), 0.0)
    vec = np.concatenate([phi_arr, [2 * math.log(sigma_n), 2 * math.log(sigma_e)]])
    st = initial == "stationary"
    return _hessian(vec, y0, observed.astype(float), np.ones(y_arr.size - m), p, d, st)


def regularize_time(
    t: ArrayLike, y: ArrayLike, *, step: float | None = None, rtol: float = 0.1
) -> tuple[FloatArray, FloatArray, int]:
    """Put a series on a uniform time grid, inserting NaN (missing) epochs in gaps.

    Parameters
    ----------
    t : array_like, shape (n,)
        Strictly increasing time stamps (s).
    y : array_like, shape (n,) or (n, k)
        Values.
    step : float, optional
        Grid step (s); default the median step.
    rtol : float
        Largest allowed deviation of a time stamp from the grid, as a fraction of ``step``.

    Returns
    -------
    t_grid : ndarray, shape (N,)
    y_grid : ndarray, shape (N,) or (N, k)
        NaN at inserted epochs.
    n_inserted : int
        Number of missing epochs inserted.

    Raises
    ------
    ValueError
        When ``t`` is not strictly increasing or a time stamp is off the grid.
    """
    t_arr = np.asarray(t, dtype=float)
    y_arr = np.asarray(y, dtype=float)
    if t_arr.ndim != 1 or y_arr.shape[0] != t_arr.size:
        raise ValueError(f"t must be (n,) and y (n, ...), got {t_arr.shape} and {y_arr.shape}")
    steps = np.diff(t_arr)
    if np.any(~np.isfinite(t_arr)) or np.any(steps <= 0):
        k = int(np.argmax(~(steps > 0))) + 1 if steps.size else 0
        raise ValueError(f"t: time stamps must be finite and strictly increasing (index {k})")
    if t_arr.size < 2:
        return t_arr.copy(), y_arr.copy(), 0
    h = float(np.median(steps)) if step is None else float(step)
    k = (t_arr - t_arr[0]) / h
    idx = np.rint(k).astype(np.int64)
    off = np.abs(k - idx)
    if np.any(off > rtol):
        bad = int(np.argmax(off > rtol))
        raise ValueError(f"t: time stamp at index {bad} is {off[bad]:.2f} steps off the {h} s grid")
    if np.any(np.diff(idx) == 0):
        raise ValueError("t: two time stamps fall on the same grid epoch")
    size = int(idx[-1]) + 1
    t_grid = t_arr[0] + h * np.arange(size)
    y_grid = np.full((size, *y_arr.shape[1:]), np.nan)
    y_grid[idx] = y_arr
    return t_grid, y_grid, size - t_arr.size


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
    from scipy.signal import lfilter

    e = rng.normal(0.0, sigma_e, n + burn_in)
    u = lfilter([1.0], np.concatenate([[1.0], phi_arr]), e)[burn_in:]
    x = u
    for _ in range(d):
        x = np.cumsum(x)
    y = x + rng.normal(0.0, sigma_n, n)
    return y, x
