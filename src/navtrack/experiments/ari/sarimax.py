"""SARIMAX cross-check of the ARI reproduction: statsmodels on the same series at the same order.

statsmodels' ``SARIMAX(order=(p, d, 0), measurement_error=True)`` is fitted and smoothed on the
same series as navtrack's :func:`navtrack.smoothing.ari.fit_ari`; both parameter sets are scored by
both likelihoods (they are the same exact likelihood, see
:class:`navtrack.smoothing.ari.AriConfig` ``initial="stationary"``), with times and convergence.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from navtrack._typing import FloatArray
from navtrack.experiments.ari.series import RealSeries
from navtrack.experiments.ari.synthetic import SyntheticCase
from navtrack.smoothing.ari import AriConfig, AriResult, fit_ari, gauss_markov_filter, simulate_ari

__all__ = ["SARIMAX_SPP_SOURCES", "sarimax_compare", "sarimax_comparisons"]

#: GNSS solutions also cross-checked against SARIMAX (RTKLIB's and navtrack's of the same file).
SARIMAX_SPP_SOURCES = ("RTKLIB sept078_gps", "navtrack sept078_gps")


def sarimax_compare(y: FloatArray, p: int, d: int, label: str) -> dict[str, Any] | None:
    """Fit+smooth with statsmodels SARIMAX and with navtrack at the same order; compare.

    Both parameter sets are scored by both implementations' (identical, exact) likelihoods.
    Returns None when statsmodels is not installed.
    """
    try:
        from statsmodels.tsa.statespace.sarimax import SARIMAX  # optional (extra compare)
    except ImportError:
        return None
    y_c = y - float(np.nanmean(y))
    t0 = time.perf_counter()
    ours = fit_ari(y, AriConfig(order=(p, d), robust="off"))
    t_ours = time.perf_counter() - t0
    model = SARIMAX(y_c, order=(p, d, 0), measurement_error=True, trend="n")
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = model.fit(disp=False)
        res.smoother_results  # noqa: B018 - the smoothed states are part of the timed work
    t_sm = time.perf_counter() - t0
    names = model.param_names
    sm_params = np.asarray(res.params, dtype=float)
    sm_sigma_n = math.sqrt(max(sm_params[names.index("var.measurement_error")], 0.0))
    sm_sigma_e = math.sqrt(max(sm_params[names.index("sigma2")], 0.0))
    sm_phi = -sm_params[:p]
    our_params = np.concatenate([-ours.phi, [ours.sigma_n**2, ours.sigma_e**2]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sm_ll_at_ours = float(model.loglike(our_params))
    try:
        _, _, our_ll_at_sm = gauss_markov_filter(
            y_c, sm_phi, d, max(sm_sigma_n, 1e-300), max(sm_sigma_e, 1e-300), initial="stationary"
        )
    except (ValueError, np.linalg.LinAlgError):
        our_ll_at_sm = math.nan
    return {
        "series": label,
        "order": [p, d],
        "n": int(y.size),
        "navtrack_seconds": t_ours,
        "sarimax_seconds": t_sm,
        "speedup": t_sm / t_ours if t_ours > 0 else math.nan,
        "navtrack_status": str(ours.status),
        "sarimax_converged": bool(res.mle_retvals.get("converged", False)),
        "navtrack_sigma_n": ours.sigma_n,
        "navtrack_sigma_e": ours.sigma_e,
        "sarimax_sigma_n": sm_sigma_n,
        "sarimax_sigma_e": sm_sigma_e,
        "loglike_navtrack_at_navtrack": ours.loglike,
        "loglike_navtrack_at_sarimax": our_ll_at_sm,
        "loglike_sarimax_at_sarimax": float(res.llf),
        "loglike_sarimax_at_navtrack": sm_ll_at_ours,
        "loglike_gain": sm_ll_at_ours - float(res.llf),
    }


def sarimax_comparisons(
    rng: np.random.Generator,
    cases: Sequence[SyntheticCase],
    sources: Sequence[RealSeries],
    fits: Mapping[tuple[str, str], AriResult],
) -> list[dict[str, Any]]:
    """The cross-check on one fresh series per synthetic case and on the chosen real series.

    Parameters
    ----------
    rng : numpy.random.Generator
        Draws the synthetic series (one per case, in order).
    cases : sequence of SyntheticCase
    sources : sequence of RealSeries
        Real series; those of pyins and of :data:`SARIMAX_SPP_SOURCES` are compared, at the
        order navtrack selected for them (``fits``), when that fit produced an estimate.
    fits : mapping
        ``(source, column) -> AriResult`` from
        :func:`~navtrack.experiments.ari.real.real_data_rows`.

    Returns
    -------
    list of dict
        One :func:`sarimax_compare` record per series; empty without statsmodels.
    """
    comparisons = []
    for case in cases:
        y, _ = simulate_ari(rng, case.n, case.phi, case.d, case.sigma_n, case.sigma_e)
        comp = sarimax_compare(y, len(case.phi), case.d, f"synthetic {case.name}")
        if comp is not None:
            comparisons.append(comp)
    for src in sources:
        if src.source.startswith("pyins") or src.source in SARIMAX_SPP_SOURCES:
            for col, values in src.columns.items():
                res = fits[(src.source, col)]
                if res.estimated:
                    comp = sarimax_compare(values, res.p, res.d, f"{src.source} {col}")
                    if comp is not None:
                        comparisons.append(comp)
    return comparisons
