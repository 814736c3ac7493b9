"""Estimation of the ARI model: likelihood, variance components, AR part, robust reweighting.

Everything here works on one :class:`~navtrack.smoothing.model.AriProblem` and the parameter
vector ``vec = (phi_1..phi_p, log sigma_n^2, log sigma_e^2)``:

* :func:`evaluate` — solution, redundancies ``r_k = n_k - tr(N^-1 N_k)`` (Förstner 1979) and
  the gradient of ``-log L``, whose variance part is the VCE equation
  ``r_k - Omega_k / sigma_k^2`` (zero at ``sigma_k^2 = Omega_k / r_k``) and whose AR part is the
  expected-moment least-squares equation of the paper's alternating scheme;
* :func:`quasi_newton` — BFGS with Armijo backtracking on ``-log L`` (all parameters jointly),
  optionally structured on a curvature model such as :func:`spectral_information` (Whittle's
  expected information, used for series of 64000 epochs and more);
* :func:`vce_iteration` — the reproducing VCE ``sigma_k^2 <- Omega_k / r_k`` with ``phi`` fixed;
* :func:`robust_reweight` — new weights of both equation groups from their studentized
  deletion residuals (:mod:`navtrack.estimation.robust`).

An *estimator* is a function ``(problem, config, starts, *, robust) -> EstimatorOutcome``
(:data:`Estimator`); :func:`navtrack.smoothing.exact.estimate_exact_likelihood` is one. Another
form of the estimation (e.g. the paper's alternation of filtering and variance-component
estimation on the conditional model) plugs in beside it with the same signature and reuses the
kernels here.

References
----------
W. Förstner, "Ein Verfahren zur Schätzung von Varianz- und Kovarianzkomponenten",
Allgemeine Vermessungs-Nachrichten 86, 446–453, 1979.
K.-R. Koch, "Maximum likelihood estimate of variance components", Bull. Géod. 60, 329–338, 1986.
J. Nocedal, S. J. Wright, "Numerical Optimization", 2nd ed., Springer 2006, algorithm 6.1
(BFGS) and 3.1 (backtracking).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal, Protocol

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, BoolArray, FloatArray
from navtrack.estimation.robust import deletion_statistic, robust_weight
from navtrack.smoothing.banded import weighted_band_sums
from navtrack.smoothing.config import AriConfig
from navtrack.smoothing.model import (
    AriProblem,
    GaussMarkovSolution,
    ari_polynomial,
    dense_block,
    process_residuals,
    process_variance,
    solve_gauss_markov,
    with_inverse,
)

__all__ = [
    "MIN_WEIGHT",
    "AriParameterEstimate",
    "Estimator",
    "EstimatorOutcome",
    "Evaluation",
    "choose_estimate",
    "evaluate",
    "make_estimate",
    "min_observations",
    "numerical_hessian",
    "observed_information",
    "phi_gradient_terms",
    "quasi_newton",
    "robust_reweight",
    "spectral_information",
    "starting_values",
    "trial_solution",
    "vce_iteration",
]


@dataclass(frozen=True, slots=True, eq=False)
class Evaluation:
    """The model evaluated at one parameter vector.

    Attributes
    ----------
    fit : GaussMarkovSolution
        Solution with the band of ``N^-1`` (offsets ``0..m``).
    r_n, r_e : float
        Redundancies of the observation and process groups.
    grad : ndarray, shape (p + 2,)
        Gradient of ``-log L`` with respect to ``vec``.
    """

    fit: GaussMarkovSolution
    r_n: float
    r_e: float
    grad: FloatArray

    def __post_init__(self) -> None:
        freeze_arrays(self)


@dataclass(frozen=True, slots=True, eq=False)
class AriParameterEstimate:
    """A point of the estimation with its evaluation and how it was reached.

    Attributes
    ----------
    vec : ndarray, shape (p + 2,)
        ``(phi_1..phi_p, log sigma_n^2, log sigma_e^2)``.
    evaluation : Evaluation
    n_iter : int
        Model evaluations spent reaching it.
    converged : bool
        The stopping rule was met.
    boundary : bool
        A variance component at its floor or with less than one observation's redundancy.
    """

    vec: FloatArray
    evaluation: Evaluation
    n_iter: int
    converged: bool
    boundary: bool

    def __post_init__(self) -> None:
        freeze_arrays(self)

    @property
    def phi(self) -> FloatArray:
        """AR coefficients ``(p,)``."""
        return self.vec[:-2]

    @property
    def log_sn2(self) -> float:
        """``log sigma_n^2``."""
        return float(self.vec[-2])

    @property
    def log_se2(self) -> float:
        """``log sigma_e^2``."""
        return float(self.vec[-1])

    @property
    def fit(self) -> GaussMarkovSolution:
        """The solution at ``vec``."""
        return self.evaluation.fit


@dataclass(frozen=True, slots=True, eq=False)
class EstimatorOutcome:
    """What an estimator returns.

    Attributes
    ----------
    estimate : AriParameterEstimate or None
        The estimate; ``None`` when the normal matrix was singular (``message`` says where).
    problem : AriProblem
        The problem with the final robust weights.
    n_iter : int
        Model evaluations in total (all starts and reweightings).
    message : str
        Why there is no estimate.
    """

    estimate: AriParameterEstimate | None
    problem: AriProblem
    n_iter: int
    message: str = ""


class Estimator(Protocol):
    """Signature of an estimator of the ARI model (see the module notes)."""

    def __call__(
        self, problem: AriProblem, config: AriConfig, starts: list[FloatArray], *, robust: bool
    ) -> EstimatorOutcome: ...


def min_observations(p: int, d: int) -> int:
    """Observed epochs an ARI(p, d) fit needs: redundancy ``n_o - m`` above the ``p + 2``
    estimated parameters."""
    return p + d + p + 4


def make_estimate(
    vec: FloatArray, evaluation: Evaluation, n_eval: int, converged: bool, log_floor: float
) -> AriParameterEstimate:
    """:class:`AriParameterEstimate` at ``vec``, with the boundary test."""
    p = vec.size - 2
    # A component at its floor, or with less than one observation's worth of redundancy, is
    # not estimable from these data (the likelihood is flat towards zero variance).
    boundary = (
        min(vec[p], vec[p + 1]) <= log_floor + 1e-6 or min(evaluation.r_n, evaluation.r_e) < 1.0
    )
    return AriParameterEstimate(vec.copy(), evaluation, n_eval, converged, bool(boundary))


def phi_gradient_terms(
    c: FloatArray, x: FloatArray, v: FloatArray, p: int, d: int, big_s: FloatArray
) -> FloatArray:
    """``sum_s v_s E[e_s u_{s-j}]``, ``j = 1..p`` (``u = (1 - B)^d x``, ``E`` under ``N^-1``).

    This is half the derivative of ``sum v_s E[e_s^2]`` with respect to ``phi_j``: the AR part of
    the likelihood gradient (and of the EM / alternating least-squares step of the paper's
    iterative scheme). ``E[e_s u_{s-j}] = e_s u_{s-j} + sum_{i,k} c_i delta_k Z[s-i, s-j-k]``;
    the covariance part summed over ``s`` is ``sum_{i,k} c_i delta_k S[i, j+k]``
    (:func:`navtrack.smoothing.banded.weighted_band_sums`).
    """
    m = p + d
    n = x.size
    ns = n - m
    delta = ari_polynomial(np.zeros(0), d)
    e = process_residuals(c, x)  # e_s, s = m..n-1
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


def trial_solution(vec: FloatArray, problem: AriProblem) -> GaussMarkovSolution | None:
    """Solution and likelihood at ``vec`` without the selected inversion (a line-search
    trial: :func:`evaluate` completes it when it is accepted)."""
    p = problem.p
    prior = problem.prior(vec[:p])
    if problem.stationary and p and prior is None:
        return None
    c = ari_polynomial(vec[:p], problem.d)
    return solve_gauss_markov(
        problem.y0, problem.w, problem.v, c, math.exp(vec[p]), math.exp(vec[p + 1]), None, prior
    )


def evaluate(
    vec: FloatArray, problem: AriProblem, partial: GaussMarkovSolution | None = None
) -> Evaluation | None:
    """Fit at ``vec``; redundancies and the gradient of ``-log L``.

    ``d(-log L)/d log sigma_k^2 = (r_k - Omega_k / sigma_k^2) / 2`` and
    ``d(-log L)/d phi_j = sum_s v_s E[e_s u_{s-j}] / sigma_e^2`` (+ the stationary-start
    term ``(d log det Gamma + tr(d Gamma^-1 E[u u^T]) / sigma_e^2) / 2``).

    Parameters
    ----------
    vec : ndarray, shape (p + 2,)
    problem : AriProblem
    partial : GaussMarkovSolution, optional
        The result of :func:`trial_solution` at the same point (its factor is reused).

    Returns
    -------
    Evaluation or None
        ``None`` when ``phi`` is not stationary (stationary start) or ``N`` is singular.
    """
    p, d, m = problem.p, problem.d, problem.m
    w, v = problem.w, problem.v
    phi = vec[:p]
    sn2 = math.exp(vec[p])
    se2 = math.exp(vec[p + 1])
    c = ari_polynomial(phi, d)
    prior = problem.prior(phi)
    if problem.stationary and p and prior is None:
        return None
    if partial is not None:
        fit: GaussMarkovSolution | None = with_inverse(partial, m)
    else:
        fit = solve_gauss_markov(problem.y0, w, v, c, sn2, se2, m, prior)
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
        z_top = dense_block(zb, m)
        trace_e += float(np.sum(prior.g_mat * z_top))
        n_v += p
    r_e = n_v - trace_e / se2
    grad = np.empty(p + 2)
    # d(-2 log L)/d log sigma_k^2 = r_k - Omega_k / sigma_k^2  (zero <=> VCE equation)
    grad[p] = 0.5 * (r_n - fit.omega_n / sn2)
    grad[p + 1] = 0.5 * (r_e - fit.omega_e / se2)
    if p:
        grad[:p] = phi_gradient_terms(c, fit.x, v, p, d, big_s) / se2
    if prior is not None and z_top is not None:
        u0 = prior.d_mat @ fit.x[:m]
        moment = prior.d_mat @ z_top @ prior.d_mat.T + np.outer(u0, u0)
        for j in range(p):
            grad[j] += 0.5 * (prior.dlogdet[j] + float(np.sum(prior.dgamma_inv[j] * moment)) / se2)
    return Evaluation(fit, r_n, r_e, grad)


def numerical_hessian(vec: FloatArray, problem: AriProblem) -> FloatArray:
    """Hessian ``(p + 2, p + 2)`` of ``-log L`` by forward differences of the analytic gradient,
    made SPD (eigenvalues by absolute value, floored)."""
    base = evaluate(vec, problem)
    k = vec.size
    if base is None:
        return np.eye(k)
    hess = np.empty((k, k))
    for j in range(k):
        h = 1e-5 * max(1.0, abs(vec[j]))
        shifted = vec.copy()
        shifted[j] += h
        out = evaluate(shifted, problem)
        hess[:, j] = (out.grad - base.grad) / h if out is not None else 0.0
    hess = 0.5 * (hess + hess.T)
    vals, vecs = np.linalg.eigh(hess)
    floor = 1e-8 * max(float(np.max(np.abs(vals))), 1e-12)
    return np.asarray((vecs * np.maximum(np.abs(vals), floor)) @ vecs.T, dtype=np.float64)


#: Frequencies (on ``(0, pi)``) of the quadrature in :func:`spectral_information`: resolves
#: spectral peaks of AR roots up to about ``1 - 2e-4`` in modulus.
SPECTRAL_GRID = 1 << 14


def spectral_information(vec: FloatArray, d: int, n_eff: float) -> FloatArray:
    """Expected information ``(p + 2, p + 2)`` of ``-log L`` by Whittle's approximation.

    The ``d``-th differences of the observations are stationary with spectrum
    ``f(w) = sigma_e^2 / |phi(e^-iw)|^2 + sigma_n^2 |1 - e^-iw|^(2d)``; Whittle's likelihood
    ``-log L = 1/2 sum_k (log f(w_k) + I(w_k) / f(w_k))`` over the Fourier frequencies has the
    expected Hessian ``n / (4 pi) int (d log f)(d log f)^T dw``, evaluated here by the midpoint
    rule on :data:`SPECTRAL_GRID` frequencies, with respect to ``vec = (phi, log sigma_n^2,
    log sigma_e^2)``.

    Why it is used: on long series the exact likelihood of ARI(p, 2) has a long, curved,
    weakly identified ``sigma_e``/``phi`` ridge. There the finite-difference Hessian of the
    exact gradient was dominated by rounding (n = 1e6, ARI(5, 2): curvature 40 along the
    ridge where the likelihood itself curves by 6–10; this formula gives 4; measured before
    the solve for the correction in :func:`navtrack.smoothing.model.solve_gauss_markov`), and
    BFGS updates learn the bending ridge one direction at a time (30 iterations from the same
    start where scoring with this matrix, recomputed at every iterate, took 10). It costs no
    evaluation of the series; gaps and robust weights are not in it (``n_eff`` counts the
    observations), so it is only the curvature model of the search, the gradient stays exact.

    Parameters
    ----------
    vec : ndarray, shape (p + 2,)
    d : int
    n_eff : float
        Number of observations.

    References
    ----------
    P. Whittle, "Estimation and information in stationary time series", Ark. Mat. 2, 423–434,
    1953. P. J. Brockwell, R. A. Davis, "Time Series: Theory and Methods", 2nd ed., Springer
    1991, §10.8.
    """
    p = vec.size - 2
    freq = np.pi * (np.arange(SPECTRAL_GRID) + 0.5) / SPECTRAL_GRID
    powers = np.exp(-1j * np.outer(np.arange(1, p + 1), freq))  # e^{-i k w}, k = 1..p
    phi_z = 1.0 + vec[:p] @ powers
    ar = math.exp(vec[p + 1]) / np.abs(phi_z) ** 2
    noise = math.exp(vec[p]) * np.abs(1.0 - np.exp(-1j * freq)) ** (2 * d)
    total = ar + noise
    dlog = np.empty((p + 2, SPECTRAL_GRID))
    # d log|phi|^-2 / d phi_k = -2 Re(e^{-ikw} conj(phi(e^{-iw}))) / |phi|^2
    dlog[:p] = -2.0 * (ar / total) * np.real(powers * np.conj(phi_z)) / np.abs(phi_z) ** 2
    dlog[p] = noise / total
    dlog[p + 1] = ar / total
    return np.asarray(0.5 * n_eff * (dlog @ dlog.T) / SPECTRAL_GRID, dtype=np.float64)


def quasi_newton(
    vec: FloatArray,
    hess: FloatArray,
    problem: AriProblem,
    tol: float,
    max_iter: int,
    start: AriParameterEstimate | None = None,
    information: Callable[[FloatArray], FloatArray] | None = None,
) -> AriParameterEstimate | None:
    """Quasi-Newton (BFGS from ``hess``, optionally structured) with Armijo backtracking on
    ``-log L``.

    The AR coefficients and the two log-variances move together with the analytic gradient.
    Steps are capped (1 in ``phi``, 2 in ``log sigma^2``) and the log-variances kept in
    ``[problem.log_floor, problem.log_ceiling]``.

    Parameters
    ----------
    vec : ndarray, shape (p + 2,)
        Start.
    hess : ndarray, shape (p + 2, p + 2)
        Initial Hessian approximation (SPD).
    problem : AriProblem
    tol : float
        Stopping rule: the expected gain ``g^T H^-1 g / 2`` of the next step is below ``tol``
        (log-likelihood units), or no step along the search direction that could still gain
        ``tol`` raises the likelihood (then converged when the expected gain is below
        ``1e3 tol``).
    max_iter : int
        Step limit.
    start : AriParameterEstimate, optional
        An estimate already evaluated at ``vec`` on this problem (saves that evaluation).
    information : callable, optional
        ``vec -> (p + 2, p + 2)`` curvature model (e.g. :func:`spectral_information`, ``hess``
        its value at ``vec``), followed between iterates (:func:`_follow_information`).

    Returns
    -------
    AriParameterEstimate or None
        ``None`` when the model cannot be evaluated at ``vec``.
    """
    p = problem.p
    log_floor = problem.log_floor
    out: Evaluation | None
    if start is not None:
        out = start.evaluation
        n_eval = 0
    else:
        out = evaluate(vec, problem)
        n_eval = 1
    if out is None:
        return None
    b_mat = hess.copy()
    converged = False
    info_at = information(vec) if information is not None else None
    for _ in range(max_iter):
        f, g = -out.fit.loglike, out.grad
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
        accepted, spent = _backtrack(vec, step, f, gain, cap, problem, tol)
        n_eval += spent
        if accepted is None:
            converged = gain < 1e3 * tol
            break
        trial, new = accepted
        if information is not None and info_at is not None:
            b_mat, info_at = _follow_information(b_mat, information(trial), info_at)
        b_mat = _bfgs_update(b_mat, trial - vec, new.grad - g)
        vec, out = trial, new
    return make_estimate(vec, out, n_eval, converged, log_floor)


def _backtrack(
    vec: FloatArray,
    step: np.ndarray,
    f: float,
    gain: float,
    cap: float,
    problem: AriProblem,
    tol: float,
) -> tuple[tuple[FloatArray, Evaluation] | None, int]:
    """Armijo backtracking along ``step`` (the Newton step divided by ``cap``) from ``vec``
    (``-log L = f`` there, expected gain of the Newton step ``gain``, so about
    ``2 t gain / cap`` for small ``t``): the accepted ``(point, evaluation)`` or None, and the
    likelihood evaluations spent."""
    p = problem.p
    t = 1.0
    n_eval = 0
    while t > 1e-6:
        trial = vec + t * step
        trial[p:] = np.clip(trial[p:], problem.log_floor, problem.log_ceiling)
        # likelihood first; the selected inversion and gradient only for an accepted step
        part = trial_solution(trial, problem)
        n_eval += 1
        if part is not None and -part.loglike <= f - 1e-4 * t * 2.0 * gain / cap:
            new = evaluate(trial, problem, partial=part)
            if new is not None:
                return (trial, new), n_eval
        t *= 0.25
        # backtrack only while the shortened step can still gain the tolerance: shorter
        # trials probe rounding noise
        if 2.0 * t * gain / cap < tol:
            break
    return None, n_eval


def _follow_information(
    b_mat: FloatArray, info_new: FloatArray, info_at: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Structured quasi-Newton: add the curvature model's change from the old point
    (``info_at``) to the new (``info_new``), keeping what the secant updates learned beyond it,
    unless that leaves the matrix indefinite (then the model alone). Returns the matrix and
    the model at the new point."""
    b_mat = b_mat + (info_new - info_at)
    if np.any(np.linalg.eigvalsh(b_mat) <= 0):
        b_mat = info_new.copy()
    return b_mat, info_new


def _bfgs_update(b_mat: FloatArray, s_k: FloatArray, y_k: FloatArray) -> FloatArray:
    """BFGS update of the Hessian approximation with the step ``s_k`` and gradient change
    ``y_k``; unchanged when the curvature condition ``s_k . y_k > 0`` fails."""
    sy = float(s_k @ y_k)
    if sy > 1e-12 * float(np.linalg.norm(s_k) * np.linalg.norm(y_k)):
        bs = b_mat @ s_k
        return b_mat - np.outer(bs, bs) / float(s_k @ bs) + np.outer(y_k, y_k) / sy
    return b_mat


def vce_iteration(
    est: AriParameterEstimate, problem: AriProblem, tol: float, max_iter: int
) -> AriParameterEstimate:
    """Iterate the reproducing VCE ``sigma_k^2 <- Omega_k / r_k`` with ``phi`` fixed.

    Stopping rule: relative change of both standard deviations below ``tol``. A step that would
    lower the likelihood ends the iteration (the estimate is then already at the VCE fixed
    point to the likelihood's resolution).
    """
    p = problem.p
    log_floor = problem.log_floor
    vec = est.vec
    out = est.evaluation
    n_eval = 0
    converged = False
    for _ in range(max_iter):
        fit, r_n, r_e = out.fit, out.r_n, out.r_e
        if r_n <= 0 or r_e <= 0:
            break
        new = vec.copy()
        new[p] = max(math.log(max(fit.omega_n, 1e-300) / r_n), log_floor)
        new[p + 1] = max(math.log(max(fit.omega_e, 1e-300) / r_e), log_floor)
        change = 0.5 * float(np.max(np.abs(new[p:] - vec[p:])))
        if change < tol:
            converged = True
            break
        trial = evaluate(new, problem)
        n_eval += 1
        if trial is None or trial.fit.loglike < fit.loglike:
            converged = change < 1e3 * tol
            break
        vec, out = new, trial
    return make_estimate(vec, out, n_eval, converged and est.converged, log_floor)


def starting_values(y: FloatArray, p: int, d: int, n_starts: int) -> list[FloatArray]:
    """Starting values ``vec`` ``(p + 2,)``: AR fit to the d-th differences of ``y`` (NaN =
    missing), noise fractions spread over (0, 1)."""
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


def choose_estimate(found: list[AriParameterEstimate], margin: float) -> AriParameterEstimate:
    """Largest likelihood, but an interior solution within ``margin`` beats a boundary one."""
    best = max(found, key=lambda e: e.fit.loglike)
    if best.boundary:
        interior = [e for e in found if not e.boundary]
        if interior:
            alt = max(interior, key=lambda e: e.fit.loglike)
            if alt.fit.loglike >= best.fit.loglike - margin:
                return alt
    return best


#: Robust weights below this leave the fit (weight 0, as a missing epoch). Such an equation adds
#: less than rounding to every sum it enters beside one of full weight, yet it would count as a
#: whole observation in the redundancy ``r_k`` while adding nothing to ``Omega_k``; and Danish
#: weights of 66–68-sigma outliers are subnormal numbers whose ``sigma^2 / w`` overflows. Below
#: it an epoch is treated as it already was when its weight underflowed to 0 (beyond ~68
#: sigma): for the Danish function with ``c = 2.5`` this is ``|T| > 15.2``.
MIN_WEIGHT = float(np.finfo(float).eps)


def _cut_small(weight: FloatArray) -> FloatArray:
    return np.where(weight >= MIN_WEIGHT, weight, 0.0)


def robust_reweight(
    est: AriParameterEstimate, problem: AriProblem, observed: BoolArray, config: AriConfig
) -> tuple[FloatArray, FloatArray]:
    """New observation ``(n,)`` and process ``(n - m,)`` weights from the studentized deletion
    residuals at ``est`` (the process ones only with ``config.robust_process``); weights below
    :data:`MIN_WEIGHT` are set to 0 (the equation leaves the fit)."""
    zb = est.fit.zb
    if zb is None:
        return problem.w, problem.v
    sn2 = math.exp(est.log_sn2)
    se2 = math.exp(est.log_se2)
    t_obs = deletion_statistic(problem.y0 - est.fit.x, zb[0], problem.w, sn2)
    w_new = np.where(observed, _cut_small(robust_weight(t_obs, config.robust, config.tuning)), 0.0)
    if not config.robust_process:
        return w_new, problem.v
    c = ari_polynomial(est.phi, problem.d)
    e = process_residuals(c, est.fit.x)
    q = process_variance(c, zb)
    t_proc = deletion_statistic(-e, q, problem.v, se2)
    return w_new, _cut_small(robust_weight(t_proc, config.robust, config.tuning))


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
    problem = AriProblem(
        y0, observed.astype(float), np.ones(y_arr.size - m), p, d, initial == "stationary"
    )
    return numerical_hessian(vec, problem)
