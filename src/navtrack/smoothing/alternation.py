"""The paper's estimator of the ARI model: alternate filtering, VCE and the AR fit (paper 5).

Lindenberger (§2.2, after Lindenberger 1987) solves the Gauss–Markov model (2)–(3) as it stands
— conditional on the first ``p + d`` epochs, no stationary start — and estimates its unknowns
by an *iterative computation scheme*: with the current ``(phi, sigma_n, sigma_e)``

1. filter: solve the normal equations for ``x`` and the band of ``N^-1``;
2. variance components: ``sigma_k^2 <- Omega_k / r_k`` (Förstner's reproducing VCE; the
   redundancies ``r_k`` exact, or in Förstner's (1984) frequency-domain form with
   ``AriConfig(vce="forstner")``, :mod:`navtrack.smoothing.vce`);
3. AR part: ``phi`` by least squares of eq. (3) on the filtered series,

and repeat until nothing moves; gross errors get robust weights (Danish method) and, where
wanted, the process equations (3) too (``AriConfig.robust_process``).
:func:`estimate_alternating` is that scheme behind the
:class:`~navtrack.smoothing.estimation.Estimator` protocol (``AriConfig(estimator="paper")``).

Notes
-----
Reading of step 3: a least-squares fit of (3) to the filtered values ``x_hat`` alone ignores
that ``x_hat`` is smoother than ``x`` and biases ``phi`` towards a smoother process; the
consistent form of "least squares of eq. (3)" is the EM step, which replaces the products
``x_i x_j`` of the normal equations by their expectations ``x_hat_i x_hat_j + (N^-1)_ij`` (band
only). Its equations are the ``phi`` part of the likelihood gradient
(:func:`navtrack.smoothing.estimation.evaluate`), linear in ``phi`` for fixed moments, so one
step solves a ``p x p`` system. The scheme's fixed point is the maximum of the conditional
likelihood; it converges linearly, slowly along the weakly identified ``sigma_e``/``phi``
ridge, which is why the default estimator (``"exact"``) drives the same equations by a
quasi-Newton search. :func:`alternate` accelerates the iteration by SQUAREM extrapolation of
its parameter sequence (same fixed point; plain iteration with ``accelerate=False``). A step
that lowers the likelihood ends the iteration.

References
----------
J. Lindenberger, "Consideration of observation errors when modelling digital terrain
profiles", ISPRS WG III/3 colloquium, Lyngby 1987 (cited by paper 5 for the scheme).
A. P. Dempster, N. M. Laird, D. B. Rubin, "Maximum likelihood from incomplete data via the EM
algorithm", J. R. Stat. Soc. B 39, 1–38, 1977.
R. Varadhan, C. Roland, "Simple and globally convergent methods for accelerating the
convergence of any EM algorithm", Scand. J. Stat. 35, 335–353, 2008 (SQUAREM).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from navtrack._typing import FloatArray
from navtrack.smoothing.banded import weighted_band_sums
from navtrack.smoothing.config import AriConfig
from navtrack.smoothing.estimation import (
    AriParameterEstimate,
    EstimatorOutcome,
    Evaluation,
    choose_estimate,
    evaluate,
    make_estimate,
    min_observations,
    robust_reweight,
)
from navtrack.smoothing.model import AriProblem, ari_polynomial
from navtrack.smoothing.vce import VceForm, spectral_redundancies

__all__ = ["alternate", "ar_step", "estimate_alternating"]


def ar_step(phi: FloatArray, problem: AriProblem, fit_x: FloatArray, zb: FloatArray) -> FloatArray:
    """The AR coefficients ``(p,)`` that solve the expected-moment least-squares equations of
    eq. (3) at the filtered series ``fit_x`` ``(n,)`` and the band ``zb`` of ``N^-1``.

    With ``u = (1 - B)^d x`` and ``e_s = sum_k phi_k u_{s-k}`` (``phi_0 = 1``) the equations
    ``sum_s v_s E[e_s u_{s-j}] = 0`` (``j = 1..p``) read ``M[1:, 1:] phi = -M[1:, 0]`` with the
    expected moments ``M[j, k] = sum_s v_s E[u_{s-j} u_{s-k}]`` ``(p + 1, p + 1)``: the
    weighted Gram matrix of the lagged filtered differences plus ``D S D^T``, where
    ``S = weighted_band_sums(zb, v, m)`` and ``D[k, k + a] = delta_a`` (coefficients of
    ``(1 - B)^d``). Returns ``phi`` unchanged when the system is singular.
    """
    p, d, m = problem.p, problem.d, problem.m
    v = problem.v
    ns = v.size
    big_s = weighted_band_sums(zb, v, m)
    delta = ari_polynomial(np.zeros(0), d)
    u = np.convolve(fit_x, delta, mode="valid")  # u_t, t = d..n-1, at u[t - d]
    # lags[s - m, k] = u_{s-k}, s = m..n-1, k = 0..p
    lags = np.column_stack([u[p - k : p - k + ns] for k in range(p + 1)])
    d_mat = np.zeros((p + 1, m + 1))
    for k in range(p + 1):
        d_mat[k, k : k + d + 1] = delta
    moments = (lags * v[:, None]).T @ lags + d_mat @ big_s @ d_mat.T
    try:
        return np.asarray(np.linalg.solve(moments[1:, 1:], -moments[1:, 0]), dtype=np.float64)
    except np.linalg.LinAlgError:
        return phi


def _redundancies(
    vec: FloatArray, out: Evaluation, problem: AriProblem, vce: VceForm
) -> tuple[float, float]:
    """Redundancies of the observation and process groups: the exact traces of ``out``
    (``"redundancy"``) or Förstner's frequency-domain ones (``"forstner"``)."""
    if vce == "redundancy":
        return out.r_n, out.r_e
    p = problem.p
    total = np.count_nonzero(problem.w > 0) + np.count_nonzero(problem.v > 0) - problem.n
    return spectral_redundancies(
        vec[:p], problem.d, math.exp(vec[p]), math.exp(vec[p + 1]), float(total)
    )


def _map_step(
    vec: FloatArray, out: Evaluation, problem: AriProblem, vce: VceForm = "redundancy"
) -> FloatArray | None:
    """One step of the scheme from the evaluation ``out`` at ``vec``: VCE (redundancies of
    the form ``vce``), then the AR step; ``None`` when a redundancy is not positive."""
    p = problem.p
    fit = out.fit
    r_n, r_e = _redundancies(vec, out, problem, vce)
    if r_n <= 0 or r_e <= 0 or fit.zb is None:
        return None
    new = vec.copy()
    new[p] = max(math.log(max(fit.omega_n, 1e-300) / r_n), problem.log_floor)
    new[p + 1] = max(math.log(max(fit.omega_e, 1e-300) / r_e), problem.log_floor)
    if p:
        new[:p] = ar_step(vec[:p], problem, fit.x, fit.zb)
    return new


def _change(new: FloatArray, vec: FloatArray, p: int) -> float:
    """Largest change of ``phi`` and of the relative sigmas (half the log-variances)."""
    return max(
        0.5 * float(np.max(np.abs(new[p:] - vec[p:]))),
        float(np.max(np.abs(new[:p] - vec[:p]))) if p else 0.0,
    )


def _worse(new: Evaluation | None, old: Evaluation) -> bool:
    """``new`` cannot be evaluated or its likelihood is below ``old``'s (beyond rounding)."""
    return new is None or new.fit.loglike < old.fit.loglike - 1e-9 * abs(old.fit.loglike)


def _squarem_jump(
    vec: FloatArray, x1: FloatArray, x2: FloatArray, out: Evaluation, problem: AriProblem
) -> tuple[FloatArray, Evaluation | None, int]:
    """The SQUAREM jump from ``vec`` with the two plain steps ``x1``, ``x2`` (see
    :func:`alternate`), ``alpha`` halved towards -1 until the likelihood at the jump is not
    below ``out``'s: (jump, its evaluation, evaluations spent)."""
    p = problem.p
    r = x1 - vec
    v = x2 - x1 - r
    norm_v = float(np.linalg.norm(v))
    alpha = min(-float(np.linalg.norm(r)) / norm_v, -1.0) if norm_v > 0 else -1.0
    n_eval = 0
    while True:
        jump = vec - 2.0 * alpha * r + alpha**2 * v
        # inside the box of the log-variances (and of exp() without a box)
        jump[p:] = np.clip(
            jump[p:], max(problem.log_floor, -700.0), min(problem.log_ceiling, 700.0)
        )
        out_jump = evaluate(jump, problem)
        n_eval += 1
        if not _worse(out_jump, out) or alpha == -1.0:
            return jump, out_jump, n_eval
        alpha = min(0.5 * (alpha - 1.0), -1.0) if alpha < -1.5 else -1.0


def alternate(
    vec: FloatArray,
    problem: AriProblem,
    tol: float,
    max_iter: int,
    *,
    accelerate: bool = True,
    vce: VceForm = "redundancy",
) -> AriParameterEstimate | None:
    """Iterate filtering, VCE and the AR step from ``vec`` ``(p + 2,)`` on ``problem``.

    Stopping rule: one step of the scheme changes ``phi`` and the relative standard deviations
    ``sigma_n``, ``sigma_e`` by less than ``tol``. ``max_iter`` bounds the model evaluations
    (filter solutions). Returns ``None`` when the model cannot be evaluated at ``vec``.

    Parameters
    ----------
    accelerate : bool
        Extrapolate the sequence of the scheme by SQUAREM (default) instead of iterating it
        plainly.
    vce : {"redundancy", "forstner"}
        Redundancies of the VCE step: exact traces, or Förstner's frequency-domain ones
        (:mod:`navtrack.smoothing.vce`). The frequency-domain scheme's fixed point is not the
        likelihood's maximum (its redundancies are those of an infinite series), so its plain
        steps are kept even when they lower the likelihood; the likelihood still guards the
        SQUAREM jumps (near the fixed point they fall back to plain steps).

    Notes
    -----
    The scheme is a fixed-point map ``F`` (EM-like: it converges linearly, at a rate near 1
    along the weakly identified ``sigma_e``/``phi`` ridge, so that the plain iteration stops
    on a small step far from the fixed point or runs out of iterations). SQUAREM (Varadhan &
    Roland 2008, scheme S3) takes two steps ``x1 = F(x0)``, ``x2 = F(x1)``, with
    ``r = x1 - x0``, ``v = x2 - 2 x1 + x0`` and ``alpha = -|r| / |v|`` (at most -1) jumps to
    ``x0 - 2 alpha r + alpha^2 v``; the jump is kept when the likelihood there is not below
    that at ``x0``, else ``alpha`` is halved towards -1, where the jump is the plain double
    step ``x2``. The fixed points are those of ``F`` (``r = 0``) and the stopping rule is
    tested on the plain step ``F(x0) - x0``, so the iteration stops at the same fixed point,
    reached in far fewer evaluations. A plain step that lowers the likelihood ends the
    iteration in both forms.

    References
    ----------
    R. Varadhan, C. Roland, "Simple and globally convergent methods for accelerating the
    convergence of any EM algorithm", Scand. J. Stat. 35, 335–353, 2008.
    """
    p = problem.p
    out = evaluate(vec, problem)
    if out is None:
        return None
    n_eval = 1
    converged = False
    monotone = vce == "redundancy"
    while n_eval < max_iter + 1:
        x1 = _map_step(vec, out, problem, vce)
        if x1 is None:
            break
        change = _change(x1, vec, p)
        if change < tol:
            converged = True
            break
        out1 = evaluate(x1, problem)
        n_eval += 1
        if out1 is None or (monotone and _worse(out1, out)):
            converged = out1 is not None and change < 1e3 * tol
            break
        assert out1 is not None
        x2 = _map_step(x1, out1, problem, vce) if accelerate else None
        if x2 is None:  # plain iteration (or no second step)
            vec, out = x1, out1
            continue
        jump, out_jump, spent = _squarem_jump(vec, x1, x2, out, problem)
        n_eval += spent
        if _worse(out_jump, out1):
            # even the plain double step lost likelihood: keep the single step
            vec, out = x1, out1
            continue
        assert out_jump is not None
        vec, out = jump, out_jump
    return make_estimate(vec, out, n_eval, converged, problem.log_floor)


def estimate_alternating(
    problem: AriProblem, config: AriConfig, starts: list[FloatArray], *, robust: bool
) -> EstimatorOutcome:
    """The paper's estimator: conditional Gauss–Markov model, alternating iteration.

    Parameters
    ----------
    problem : AriProblem
        Unit weights; its ``stationary`` flag is dropped (the paper's model is conditional).
    config : AriConfig
        ``alternation_tol`` and ``max_iter`` (stopping rule of :func:`alternate`), ``vce``
        (form of the variance-component step), ``screen_n``,
        ``boundary_margin``, robust weight function, ``robust_process``, ``max_robust_iter``.
    starts : list of ndarray, shape (p + 2,)
    robust : bool
        Reweight (with ``config.robust``; ``"off"`` disables it too).

    Returns
    -------
    EstimatorOutcome

    Notes
    -----
    Every start is iterated on the leading ``screen_n`` epochs, the best
    (:func:`~navtrack.smoothing.estimation.choose_estimate`) continued on the whole series.
    Robust: new weights from the deletion residuals, the iteration continued with them, until
    no weight moves by 0.01 (or ``max_robust_iter``).
    """
    problem = dataclasses.replace(problem, stationary=False)
    p, n = problem.p, problem.n
    observed = problem.w > 0
    window = problem.head(min(n, config.screen_n))
    found: list[AriParameterEstimate] = []
    n_iter = 0
    for start in starts:
        out = alternate(start, window, config.alternation_tol, config.max_iter, vce=config.vce)
        if out is not None:
            found.append(out)
            n_iter += out.n_iter
    if not found:
        return EstimatorOutcome(None, problem, n_iter, "normal matrix singular at every start")
    best: AriParameterEstimate | None = choose_estimate(found, config.boundary_margin)
    if window.n < n and best is not None:
        best = alternate(best.vec, problem, config.alternation_tol, config.max_iter, vce=config.vce)
        if best is None:
            return EstimatorOutcome(None, problem, n_iter, "normal matrix singular on the series")
        n_iter += best.n_iter
    assert best is not None
    use_robust = robust and config.robust != "off"
    for _ in range(config.max_robust_iter if use_robust else 0):
        w_new, v_new = robust_reweight(best, problem, observed, config)
        dw = np.concatenate([np.abs(w_new - problem.w), np.abs(v_new - problem.v)])
        if float(np.max(dw)) < 1e-2 or np.count_nonzero(w_new > 0) < min_observations(p, problem.d):
            break
        problem = problem.with_weights(w_new, v_new)
        again = alternate(
            best.vec, problem, config.alternation_tol, config.max_iter, vce=config.vce
        )
        if again is None:
            break
        best = again
        n_iter += best.n_iter
    return EstimatorOutcome(best, problem, n_iter)
