"""Fitting the ARI model to a series: input checks, one order, order selection (paper 5).

:func:`fit_ari` is the entry point (re-exported by :mod:`navtrack.smoothing.ari`). One order:
the series minus its trend becomes an :class:`~navtrack.smoothing.model.AriProblem`, an
estimator (:mod:`navtrack.smoothing.estimation`) finds the parameters and weights, and
:func:`_finish` derives the filtered series, ``sigma_x``, the w-test statistics, flags and
``r(h)``. Order selection: every candidate ``(p, d)`` fitted without robust weights, from both
neighbours (upward and downward passes), scored by BIC/AIC of the likelihood conditional on the
first ``max(p + d)`` observed epochs, the best refitted with robust weights.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from navtrack._typing import ArrayLike, BoolArray, FloatArray
from navtrack.estimation.robust import deletion_statistic, flag_outliers
from navtrack.smoothing.alternation import estimate_alternating
from navtrack.smoothing.banded import single_threaded_blas
from navtrack.smoothing.config import AriConfig
from navtrack.smoothing.estimation import (
    AriParameterEstimate,
    Estimator,
    min_observations,
    starting_values,
)
from navtrack.smoothing.exact import estimate_exact_likelihood
from navtrack.smoothing.model import (
    AriProblem,
    ari_polynomial,
    solve_gauss_markov,
    stationary_prior,
)
from navtrack.smoothing.result import AriEpochStatus, AriResult, AriStatus, bad_result

__all__ = ["fit_ari", "fit_ari_order", "fit_fixed_order", "regularize_time"]


def _check_input(y: ArrayLike, t: ArrayLike | None) -> tuple[FloatArray, AriStatus, str]:
    """The series as float array, and a bad-input status with its message (or ``ok``)."""
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
            return y_arr, AriStatus.NON_MONOTONIC_TIME, "time stamps contain NaN/inf"
        steps = np.diff(t_arr)
        if np.any(steps <= 0):
            k = int(np.argmax(steps <= 0))
            return (
                y_arr,
                AriStatus.NON_MONOTONIC_TIME,
                f"time not strictly increasing at index {k + 1}",
            )
        if steps.size and np.max(steps) - np.min(steps) > 1e-6 * np.median(steps):
            return (
                y_arr,
                AriStatus.IRREGULAR_TIME,
                "time steps are not uniform; use regularize_time() to put the series on a grid",
            )
    observed = np.isfinite(y_arr)
    if np.count_nonzero(observed) >= 2 and np.ptp(y_arr[observed]) == 0:
        return y_arr, AriStatus.CONSTANT, "all observed values are equal"
    return y_arr, AriStatus.OK, ""


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
    if status != AriStatus.OK:
        return bad_result(y_arr, status, message, p, d)
    # the likelihood search probes parameters where the filter overflows; such trials come back
    # non-finite, and the checks on the likelihood reject them or end the fit in a status
    with single_threaded_blas(), np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        return fit_fixed_order(y_arr, p, d, cfg, robust=True)


def fit_fixed_order(
    y: FloatArray,
    p: int,
    d: int,
    cfg: AriConfig,
    *,
    robust: bool,
    starts: list[FloatArray] | None = None,
) -> AriResult:
    """ARI(p, d) of fixed order fitted to ``y`` (checked input, NaN = missing) with the
    settings of ``cfg``; ``robust`` reweights, ``starts`` replaces the default starting
    vectors (:func:`~navtrack.smoothing.estimation.starting_values`)."""
    n = y.size
    m = p + d
    observed = np.isfinite(y)
    n_obs = int(np.count_nonzero(observed))
    if n <= m or n_obs < min_observations(p, d):
        return bad_result(
            y,
            AriStatus.TOO_SHORT,
            f"{n_obs} observed epochs; ARI({p},{d}) needs at least {min_observations(p, d)}",
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
    scale = float(np.nanstd(np.convolve(yc, ari_polynomial(np.zeros(0), d), mode="valid")))
    if not np.isfinite(scale) or scale <= 0:
        scale = float(np.nanstd(yc)) or 1.0
    problem = AriProblem(
        y0=np.where(observed, yc, 0.0),
        w=observed.astype(float),
        v=np.ones(n - m),
        p=p,
        d=d,
        stationary=cfg.initial == "stationary",
        log_floor=math.log((1e-6 * scale) ** 2),
        log_ceiling=math.log((1e3 * scale) ** 2),
    )
    if starts is None:
        starts = starting_values(yc, p, d, cfg.n_starts)
    # the estimator stage: any ``navtrack.smoothing.estimation.Estimator`` fits here
    estimator: Estimator = (
        estimate_alternating if cfg.estimator == "paper" else estimate_exact_likelihood
    )
    try:
        outcome = estimator(problem, cfg, starts, robust=robust)
        if outcome.estimate is None:
            return bad_result(y, AriStatus.SINGULAR, outcome.message, p, d)
        return _finish(y, offset, observed, outcome.problem, outcome.estimate, outcome.n_iter, cfg)
    except np.linalg.LinAlgError as exc:
        # a system the gaps and weights leave singular is an outcome of this series, not an
        # error of the caller's
        return bad_result(y, AriStatus.SINGULAR, f"singular system: {exc}", p, d)


def _finish(
    y: FloatArray,
    offset: FloatArray,
    observed: BoolArray,
    problem: AriProblem,
    est: AriParameterEstimate,
    n_iter: int,
    cfg: AriConfig,
) -> AriResult:
    """The result at the estimate: filtered series, ``sigma_x``, w-tests, flags, ``r(h)``."""
    p, d = problem.p, problem.d
    w, v = problem.w, problem.v
    sn2 = math.exp(est.log_sn2)
    se2 = math.exp(est.log_se2)
    c = ari_polynomial(est.phi, d)
    fit = solve_gauss_markov(problem.y0, w, v, c, sn2, se2, max(p + d, 4), problem.prior(est.phi))
    if fit is None or fit.zb is None:
        return bad_result(y, AriStatus.SINGULAR, "normal matrix singular at the estimate", p, d)
    zb = fit.zb
    n = y.size
    var_x = np.maximum(zb[0], 0.0)
    sigma_x = np.sqrt(var_x)
    t_obs = np.where(observed, deletion_statistic(problem.y0 - fit.x, zb[0], w, sn2), np.nan)
    gross = observed & flag_outliers(t_obs, cfg.flag_threshold)
    autocorr = np.full(4, np.nan)
    for h in range(1, min(4, n - 1) + 1):
        r = zb[h, : n - h] / np.sqrt(var_x[: n - h] * var_x[h:])
        autocorr[h - 1] = float(np.nanmean(r))
    status = AriStatus.OK
    message = ""
    if est.boundary:
        status = AriStatus.BOUNDARY
        message = "a variance component reached its lower bound (not identifiable from the data)"
    elif not est.converged:
        status = AriStatus.NOT_CONVERGED
        message = f"no convergence within max_iter={cfg.max_iter}"
    epoch_status = np.zeros(n, dtype=np.int8)
    epoch_status[~observed] = AriEpochStatus.MISSING
    epoch_status[gross] = AriEpochStatus.GROSS_ERROR
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
        redundancy_n=est.evaluation.r_n,
        redundancy_e=est.evaluation.r_e,
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
    prior = stationary_prior(res.phi, res.d) if initial == "stationary" and res.p else None
    fit = solve_gauss_markov(
        np.where(observed, head, 0.0), w, v, c, res.sigma_n**2, res.sigma_e**2, None, prior
    )
    if fit is None:
        return math.nan
    return res.loglike - fit.loglike


def _better(new: AriResult, old: AriResult, cfg: AriConfig) -> bool:
    """``new`` has the larger likelihood, with the preference of
    :func:`~navtrack.smoothing.estimation.choose_estimate` for interior solutions (a boundary
    one must beat an interior one by ``boundary_margin``)."""
    margin = 0.0
    if (new.status == AriStatus.BOUNDARY) != (old.status == AriStatus.BOUNDARY):
        margin = cfg.boundary_margin if new.status == AriStatus.BOUNDARY else -cfg.boundary_margin
    return new.loglike > old.loglike + margin


def fit_ari(
    y: ArrayLike,
    config: AriConfig | None = None,
    *,
    t: ArrayLike | None = None,
    progress: Callable[[], None] | None = None,
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
    progress : callable, optional
        Called with no argument after each model fit (the order search fits every candidate
        twice, then the chosen order once more, robustly), e.g. a progress bar's ``update``.

    Returns
    -------
    AriResult
        Bad input gives a result with a non-``ok`` :class:`AriStatus` (``too_short``,
        ``constant``, ``non_monotonic_time``, ``irregular_time``) and NaN estimates; wrong shapes or
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
    if status != AriStatus.OK:
        return bad_result(y_arr, status, message)
    # the likelihood search probes parameters where the filter overflows; such trials come back
    # non-finite, and the checks on the likelihood reject them or end the fit in a status
    with single_threaded_blas(), np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        return _select_and_fit(y_arr, cfg, progress or (lambda: None))


def _select_and_fit(y_arr: FloatArray, cfg: AriConfig, tick: Callable[[], None]) -> AriResult:
    """Body of :func:`fit_ari` after input checks: order selection, then the robust fit."""
    if cfg.order is not None:
        res = fit_fixed_order(y_arr, cfg.order[0], cfg.order[1], cfg, robust=True)
        tick()
        return res
    candidates = [
        (p, d) for d in range(cfg.min_d, cfg.max_d + 1) for p in range(cfg.max_p + 1) if p + d >= 1
    ]
    y_sel = y_arr[: cfg.select_n]
    n_obs = int(np.count_nonzero(np.isfinite(y_sel)))
    candidates = [(p, d) for p, d in candidates if n_obs >= min_observations(p, d)]
    if not candidates:
        return bad_result(
            y_arr, AriStatus.TOO_SHORT, f"{n_obs} observed epochs are too few for any ARI model"
        )
    big_m = max(p + d for p, d in candidates)
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
            starts = [warm, *starting_values(yc, p, d, cfg.n_starts)[-1:]]
        res = fit_fixed_order(y_sel, p, d, cfg, robust=False, starts=starts)
        tick()
        if res.estimated:
            found[(p, d)] = res
    # Downward pass: ARI(p, d) again from ARI(p+1, d) without its last coefficient, the better
    # optimum kept. On heavy-tailed series the non-robust likelihood is multimodal (a
    # low-noise/rough-process mode and a high-noise/smooth-process one); reaching a candidate
    # from both neighbours makes its optimum, and so the selected order, independent of the
    # path that led to it (docs/ari.md, method notes, "Order selection").
    for p, d in reversed(candidates):
        upper = found.get((p + 1, d))
        if upper is None:
            continue
        phi = upper.phi[:p].copy()
        # the truncated AR part need not be stationary: shrink it towards 0 until it is
        while phi.size and not np.all(np.abs(np.roots(np.concatenate([[1.0], phi]))) < 0.98):
            phi = np.zeros(p) if float(np.max(np.abs(phi))) < 1e-3 else 0.5 * phi
        start = np.concatenate([phi, [2 * math.log(upper.sigma_n), 2 * math.log(upper.sigma_e)]])
        res = fit_fixed_order(y_sel, p, d, cfg, robust=False, starts=[start])
        tick()
        current = found.get((p, d))
        if res.estimated and (current is None or _better(res, current, cfg)):
            found[(p, d)] = res
    scores: list[tuple[int, int, float]] = []
    best_key: tuple[int, int] | None = None
    best_score = math.inf
    fits: dict[tuple[int, int], tuple[float, float]] = {}
    for p, d in candidates:
        if (p, d) not in found:
            continue
        initial = "conditional" if cfg.estimator == "paper" else cfg.initial
        ll = _conditional_loglike(found[(p, d)], big_m, initial)
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
        return bad_result(y_arr, AriStatus.SINGULAR, "no candidate order could be fitted")
    final = fit_fixed_order(y_arr, best_key[0], best_key[1], cfg, robust=True)
    tick()
    aic, bic = fits[best_key]
    return _replace(final, aic=aic, bic=bic, candidates=tuple(scores))


def _replace(res: AriResult, **changes: object) -> AriResult:
    values: dict[str, Any] = {name: getattr(res, name) for name in res.__dataclass_fields__}
    values.update(changes)
    return AriResult(**values)


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
