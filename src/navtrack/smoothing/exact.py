"""The exact-likelihood estimator of the ARI model (the default of
:func:`navtrack.smoothing.ari.fit_ari`).

:func:`estimate_exact_likelihood` screens several starts on a leading window, refines the best
on the whole series (or on growing leading blocks for long series), reweights robustly (IRLS
inside the VCE) and ends with a VCE iteration. It is an
:class:`~navtrack.smoothing.estimation.Estimator` built on the kernels of
:mod:`navtrack.smoothing.estimation`; why it is staged this way is recorded in ``docs/ari.md``
(method notes, "Long series: a leading block and a structured search").
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from navtrack._typing import BoolArray, FloatArray
from navtrack.smoothing.config import AriConfig
from navtrack.smoothing.estimation import (
    AriParameterEstimate,
    EstimatorOutcome,
    choose_estimate,
    evaluate,
    make_estimate,
    min_observations,
    numerical_hessian,
    quasi_newton,
    robust_reweight,
    spectral_information,
    vce_iteration,
)
from navtrack.smoothing.model import AriProblem

__all__ = ["estimate_exact_likelihood"]

#: A search, ``(estimate, problem) -> (refined estimate or None, evaluations spent outside it)``.
Search = Callable[[AriParameterEstimate, AriProblem], tuple[AriParameterEstimate | None, int]]

#: What a stage returns: the estimate (None with a message when the normal matrix was
#: singular), the problem with its weights, the evaluations spent and the message.
_Stage = tuple[AriParameterEstimate | None, AriProblem, int, str]


def _reweighting_rounds(
    best: AriParameterEstimate,
    problem: AriProblem,
    observed: BoolArray,
    config: AriConfig,
    search: Search,
) -> tuple[AriParameterEstimate, AriProblem, int]:
    """IRLS inside the VCE (new weights, variance components re-estimated with ``phi`` fixed
    until the weights settle), then ``phi`` and the variances jointly by ``search``, repeated
    while that moves the weights. Returns the estimate, the problem with its weights and the
    evaluations spent."""
    p = problem.p
    n_iter = 0
    budget = config.max_robust_iter
    for _ in range(3):
        reweighted = False
        while budget > 0:
            budget -= 1
            w_new, v_new = robust_reweight(best, problem, observed, config)
            dw = np.concatenate([np.abs(w_new - problem.w), np.abs(v_new - problem.v)])
            # settled: no weight moved by 0.01, or on average by less than 1e-5 (on long
            # series some weight near the cut-off always moves a little)
            if (
                float(np.max(dw)) < 1e-2
                or float(np.mean(dw)) < 1e-5
                or np.count_nonzero(w_new > 0) < min_observations(p, problem.d)
            ):
                break
            problem = problem.with_weights(w_new, v_new)
            reweighted = True
            step_out = evaluate(best.vec, problem)
            if step_out is None:
                break
            est = make_estimate(best.vec, step_out, 1, best.converged, problem.log_floor)
            best = vce_iteration(est, problem, 1e-3, 10)
            n_iter += 1 + best.n_iter
        if not reweighted and best.converged:
            break
        refined, spent = search(best, problem)
        n_iter += spent
        if refined is None:
            break
        best = refined
        n_iter += best.n_iter
    return best, problem, n_iter


def _stage_sizes(head: int, n: int, growth: int) -> list[int]:
    """Leading blocks ``n / growth^k`` longer than ``head``, shortest first, ending with ``n``:
    each block is ``growth`` times the one before it."""
    sizes = [n]
    while sizes[0] // growth > head:
        sizes.insert(0, sizes[0] // growth)
    return sizes


def _screen_starts(
    window: AriProblem, config: AriConfig, starts: list[FloatArray]
) -> tuple[list[AriParameterEstimate], int]:
    """Every start refined on the leading window (BFGS from a finite-difference Hessian); the
    estimates reached and the evaluations spent."""
    p = window.p
    found: list[AriParameterEstimate] = []
    n_iter = 0
    for start in starts:
        hess0 = numerical_hessian(start, window)
        n_iter += p + 3
        out = quasi_newton(start, hess0, window, config.gain_tol, config.max_iter)
        if out is None:
            continue
        n_iter += out.n_iter
        found.append(out)
    return found, n_iter


def _scaled_window_hessian(vec: FloatArray, prob: AriProblem, head: int) -> FloatArray:
    """The finite-difference Hessian on the leading ``head`` epochs (current weights), scaled
    by the number of observations of the whole series."""
    window = prob.head(head)
    scale = np.count_nonzero(prob.w) / max(int(np.count_nonzero(window.w)), 1)
    return numerical_hessian(vec, window) * scale


def _refine_whole(
    best: AriParameterEstimate, problem: AriProblem, config: AriConfig, head: int, robust: bool
) -> _Stage:
    """Refinement on the whole series from the window's optimum with the window's Hessian
    scaled (also certifies the convergence of short series); robust: reweighting rounds whose
    search starts from a fresh window Hessian rather than the last BFGS matrix."""
    p = problem.p

    def finite_difference_search(
        est: AriParameterEstimate, prob: AriProblem
    ) -> tuple[AriParameterEstimate | None, int]:
        hess = _scaled_window_hessian(est.vec, prob, head)
        return quasi_newton(est.vec, hess, prob, config.gain_tol, config.max_iter, start=est), p + 3

    hess = _scaled_window_hessian(best.vec, problem, head)
    n_iter = p + 3
    # a long robust fit only needs to get near the unweighted optimum before reweighting
    first_tol = config.gain_tol * 100 if (robust and head < problem.n) else config.gain_tol
    refined = quasi_newton(best.vec, hess, problem, first_tol, config.max_iter)
    if refined is None:
        return None, problem, n_iter, "normal matrix singular on the full series"
    best = refined
    n_iter += best.n_iter
    if robust:
        best, problem, spent = _reweighting_rounds(
            best, problem, problem.w > 0, config, finite_difference_search
        )
        n_iter += spent
    return best, problem, n_iter, ""


def _refine_in_blocks(
    best: AriParameterEstimate, problem: AriProblem, config: AriConfig, head: int, robust: bool
) -> _Stage:
    """Refinement on growing leading blocks, each started from the previous block's estimate
    and weights (unit weights on the new epochs), searched by the structured quasi-Newton on
    :func:`~navtrack.smoothing.estimation.spectral_information`."""

    def spectral_search(
        est: AriParameterEstimate, prob: AriProblem
    ) -> tuple[AriParameterEstimate | None, int]:
        n_eff = float(np.count_nonzero(prob.w))

        def information(vec: FloatArray) -> FloatArray:
            return spectral_information(vec, problem.d, n_eff)

        return quasi_newton(
            est.vec,
            information(est.vec),
            prob,
            config.gain_tol,
            config.max_iter,
            start=est,
            information=information,
        ), 0

    full = problem
    n_iter = 0
    for size in _stage_sizes(head, full.n, config.stage_growth):
        stage = full.head(size)
        done = problem.n if problem.n < size else 0
        if robust and done:
            # the previous block's weights, unit weights after it, as the first weights
            m = problem.m
            stage = stage.with_weights(
                np.concatenate([problem.w, stage.w[done:]]),
                np.concatenate([problem.v, stage.v[done - m :]]),
            )
        at_start = evaluate(best.vec, stage)
        n_iter += 1
        if at_start is None:
            return None, problem, n_iter, f"normal matrix singular on the first {size} epochs"
        best = make_estimate(best.vec, at_start, 1, False, stage.log_floor)
        if robust:
            best, problem, spent = _reweighting_rounds(
                best, stage, full.w[:size] > 0, config, spectral_search
            )
        else:
            refined, spent = spectral_search(best, stage)
            if refined is None:
                return None, problem, n_iter, f"normal matrix singular on the first {size} epochs"
            best, problem = refined, stage
            spent += best.n_iter
        n_iter += spent
    return best, problem, n_iter, ""


def estimate_exact_likelihood(
    problem: AriProblem, config: AriConfig, starts: list[FloatArray], *, robust: bool
) -> EstimatorOutcome:
    """Maximum of the exact (or conditional) likelihood, with robust reweighting.

    Parameters
    ----------
    problem : AriProblem
        Unit weights; observations with ``w > 0`` are the observed epochs.
    config : AriConfig
        Stopping rules, window, stages, starts margin, weight function.
    starts : list of ndarray, shape (p + 2,)
        Starting vectors (:func:`~navtrack.smoothing.estimation.starting_values`).
    robust : bool
        Reweight (with ``config.robust``; ``"off"`` disables it too).

    Returns
    -------
    EstimatorOutcome

    Notes
    -----
    The likelihood is multimodal on short series (``sigma_n -> 0`` and ``sigma_e -> 0`` are
    local optima): every start is refined (BFGS from a finite-difference Hessian) on a
    leading window of ``config.screen_n`` epochs and the best kept
    (:func:`~navtrack.smoothing.estimation.choose_estimate`), then refined on the whole series
    by BFGS from the window's Hessian scaled by the number of observations. Robust: IRLS
    inside the VCE, then ``phi`` and the variances jointly (BFGS from a fresh window Hessian),
    repeated while that moves the weights; a final VCE iteration certifies the variance
    components.

    A series of ``screen_n * stage_growth`` epochs or more is instead fitted on growing
    leading blocks (``n / stage_growth^k`` epochs longer than the window, then the whole
    series), each started from the previous block's estimate and weights (unit weights on the
    new epochs, then reweighted over the block), and searched by the structured quasi-Newton
    on :func:`~navtrack.smoothing.estimation.spectral_information` (its change between
    iterates added to the BFGS matrix): the cost is the number of whole-series evaluations,
    and a block's optimum is close to the next block's. ``docs/ari.md`` (method notes, "Long
    series: a leading block and a structured search") records the measurements behind this choice.
    """
    head = min(problem.n, config.screen_n)
    found, n_iter = _screen_starts(problem.head(head), config, starts)
    if not found:
        return EstimatorOutcome(None, problem, n_iter, "normal matrix singular at every start")
    best = choose_estimate(found, config.boundary_margin)
    use_robust = robust and config.robust != "off"
    refine = _refine_whole if problem.n < head * config.stage_growth else _refine_in_blocks
    refined, problem, spent, message = refine(best, problem, config, head, use_robust)
    n_iter += spent
    if refined is None:
        return EstimatorOutcome(None, problem, n_iter, message)
    best = vce_iteration(refined, problem, config.tol, config.max_iter)
    n_iter += best.n_iter
    return EstimatorOutcome(best, problem, n_iter)
