"""The paper's estimator of the ARI model: alternate filtering, VCE and the AR fit (paper 5).

Lindenberger (§2.2, after Lindenberger 1987) solves the Gauss–Markov model (2)–(3) as it stands
— conditional on the first ``p + d`` epochs, no stationary start — and estimates its unknowns
by an *iterative computation scheme*: with the current ``(phi, sigma_n, sigma_e)``

1. filter: solve the normal equations for ``x`` and the band of ``N^-1``;
2. variance components: ``sigma_k^2 <- Omega_k / r_k`` (Förstner's reproducing VCE);
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
quasi-Newton search. A step that lowers the likelihood ends the iteration.

References
----------
J. Lindenberger, "Consideration of observation errors when modelling digital terrain
profiles", ISPRS WG III/3 colloquium, Lyngby 1987 (cited by paper 5 for the scheme).
A. P. Dempster, N. M. Laird, D. B. Rubin, "Maximum likelihood from incomplete data via the EM
algorithm", J. R. Stat. Soc. B 39, 1–38, 1977.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from navtrack._typing import FloatArray
from navtrack.smoothing._banded import weighted_band_sums
from navtrack.smoothing.config import AriConfig
from navtrack.smoothing.estimation import (
    Estimate,
    EstimatorOutcome,
    choose_estimate,
    evaluate,
    make_estimate,
    min_observations,
    phi_gradient_terms,
    robust_reweight,
)
from navtrack.smoothing.model import AriProblem, ari_polynomial

__all__ = ["alternate", "ar_step", "estimate_alternating"]


def ar_step(phi: FloatArray, problem: AriProblem, fit_x: FloatArray, zb: FloatArray) -> FloatArray:
    """The AR coefficients ``(p,)`` that solve the expected-moment least-squares equations of
    eq. (3) at the filtered series ``fit_x`` ``(n,)`` and the band ``zb`` of ``N^-1``.

    The equations ``sum_s v_s E[e_s u_{s-j}] = 0`` (``j = 1..p``) are linear in ``phi``:
    ``g(phi) = A phi + g(0)`` with column ``j`` of ``A`` equal to ``g(unit_j) - g(0)``.
    Returns ``phi`` unchanged when the system is singular.
    """
    p, d, m = problem.p, problem.d, problem.m
    big_s = weighted_band_sums(zb, problem.v, m)

    def g(coef: FloatArray) -> FloatArray:
        return phi_gradient_terms(ari_polynomial(coef, d), fit_x, problem.v, p, d, big_s)

    g0 = g(np.zeros(p))
    a_mat = np.column_stack([g(np.eye(p)[j]) - g0 for j in range(p)])
    try:
        return np.asarray(np.linalg.solve(a_mat, -g0), dtype=np.float64)
    except np.linalg.LinAlgError:
        return phi


def alternate(vec: FloatArray, problem: AriProblem, tol: float, max_iter: int) -> Estimate | None:
    """Iterate filtering, VCE and the AR step from ``vec`` ``(p + 2,)`` on ``problem``.

    Stopping rule: the largest change of ``phi`` and of the relative standard deviations
    ``sigma_n``, ``sigma_e`` below ``tol``. Returns ``None`` when the model cannot be
    evaluated at ``vec``.
    """
    p = problem.p
    out = evaluate(vec, problem)
    if out is None:
        return None
    n_eval = 1
    converged = False
    for _ in range(max_iter):
        fit = out.fit
        if out.r_n <= 0 or out.r_e <= 0 or fit.zb is None:
            break
        new = vec.copy()
        new[p] = max(math.log(max(fit.omega_n, 1e-300) / out.r_n), problem.log_floor)
        new[p + 1] = max(math.log(max(fit.omega_e, 1e-300) / out.r_e), problem.log_floor)
        if p:
            new[:p] = ar_step(vec[:p], problem, fit.x, fit.zb)
        change = max(
            0.5 * float(np.max(np.abs(new[p:] - vec[p:]))),
            float(np.max(np.abs(new[:p] - vec[:p]))) if p else 0.0,
        )
        if change < tol:
            converged = True
            break
        trial = evaluate(new, problem)
        n_eval += 1
        if trial is None or trial.fit.loglike < fit.loglike - 1e-9 * abs(fit.loglike):
            converged = change < 1e3 * tol
            break
        vec, out = new, trial
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
        ``alternation_tol`` and ``max_iter`` (stopping rule of :func:`alternate`), ``screen_n``,
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
    found: list[Estimate] = []
    n_iter = 0
    for start in starts:
        out = alternate(start, window, config.alternation_tol, config.max_iter)
        if out is not None:
            found.append(out)
            n_iter += out.n_iter
    if not found:
        return EstimatorOutcome(None, problem, n_iter, "normal matrix singular at every start")
    best: Estimate | None = choose_estimate(found, config.boundary_margin)
    if window.n < n and best is not None:
        best = alternate(best.vec, problem, config.alternation_tol, config.max_iter)
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
        again = alternate(best.vec, problem, config.alternation_tol, config.max_iter)
        if again is None:
            break
        best = again
        n_iter += best.n_iter
    return EstimatorOutcome(best, problem, n_iter)
