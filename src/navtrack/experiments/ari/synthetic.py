"""Synthetic Monte Carlo of the ARI reproduction: series like paper 5's applications, known truth.

Series like the paper's three applications (:data:`SYNTHETIC_CASES`) — GPS coordinates ARI(5,2)
at 0.6 s with sigma_n = 0.02 m and ~130 epochs per strip (and a 2000-epoch flight for
comparison), Space Shuttle INS attitude ARI(6,1) at 2 s, aircraft INS attitude ARI(2,2) at 10 Hz
(sigma_n, sigma_e of Tables 4–5). Per run and case (:func:`synthetic_run`): ML estimate on the
clean series at the true order, the Cramér–Rao bound at the truth (identifiability), robust
estimate on the series with 1 % injected gross errors of 5–15 sigma_n (recall, false flags), and
the order chosen by BIC. :func:`summarize_synthetic` reduces the runs to medians and bars.

The AR parameters of the synthetic truths are not in the paper (it gives orders and sigmas only);
they were fitted so that the truth's theoretical ``sigma_x / sigma_n`` and ``r(h)`` are the
printed ones (:mod:`navtrack.experiments.ari.truths`; documented in :data:`SYNTHETIC_CASES`).
Every clean series is estimated by both estimators (``"exact"`` and the paper's ``"paper"``).

References
----------
Lindenberger, J., "Modelling orientation parameters of sensor platforms", ISPRS Comm. I
(paper 5): §3.1 Table 1 (GPS), §3.2 Tables 4–5 (INS).
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from navtrack._typing import BoolArray, FloatArray, IntArray
from navtrack.experiments.ari.truths import filtered_statistics
from navtrack.smoothing.ari import (
    AriConfig,
    AriResult,
    fit_ari,
    observed_information,
    simulate_ari,
)
from navtrack.smoothing.attitude import ATTITUDE_FORMS

__all__ = [
    "IDENTIFIABLE_CRB",
    "ROBUST_CHOICES",
    "SYNTHETIC_CASES",
    "AriExperimentParams",
    "SyntheticCase",
    "run_index",
    "summarize_synthetic",
    "synthetic_run",
]

#: Weight functions of the robust fit (``AriConfig.robust``).
ROBUST_CHOICES = ("danish", "huber", "igg3", "off")

IDENTIFIABLE_CRB = 0.10


@dataclass(frozen=True, slots=True)
class SyntheticCase:
    """A synthetic series like one of the paper's applications.

    Attributes
    ----------
    name, label : str
    phi : tuple of float
        AR coefficients of the ``d``-th differences (paper sign, stationary).
    d : int
    sigma_n, sigma_e : float
        Observation noise and prediction-error standard deviations (``unit``).
    n : int
        Epochs per series.
    dt_s : float
        Sampling interval (s).
    unit : str
    printed_ratio : float or None
        The paper's ``sigma_x / sigma_n`` the truth was fitted to.
    printed_r : tuple of float
        The paper's ``r(1..k)`` the truth was fitted to.
    printed_source : str
        Where they are printed.
    printed_sigma_n, printed_sigma_e : float or None
        The paper's printed sigmas of that series (``None``: not printed; the truth's value was
        then fitted).
    """

    name: str
    label: str
    phi: tuple[float, ...]
    d: int
    sigma_n: float
    sigma_e: float
    n: int
    dt_s: float
    unit: str
    printed_ratio: float | None = None
    printed_r: tuple[float, ...] = ()
    printed_source: str = ""
    printed_sigma_n: float | None = None
    printed_sigma_e: float | None = None


# AR parts fitted to the paper's printed statistics by
# :func:`navtrack.experiments.ari.truths.fit_published` (theoretical sigma_x/sigma_n and r(h) of
# the filtered series of n epochs against the printed values; 4 decimals kept). GPS X (Table 1
# rms of strips 3,4,5: sigma_n = 0.021 m; Table 3: sigma_x = 0.017 m, r = 0.46 -0.06 0.06; no
# sigma_e printed, fitted: 0.0618 m); residual RMS 2.6 hundredths.
_GPS_PHI = (-1.644, 1.4125, -1.4147, 1.6544, -0.95)
_GPS_R = (0.46, -0.06, 0.06)
# Shuttle yaw (Table 4: sigma_n 0.0060, sigma_e 0.0019, sigma_x 0.0027 deg,
# r = 0.71 0.46 0.18 0.13), 400 epochs; matched to 0.0002 hundredths.
_SHUTTLE_PHI = (-0.2312, -0.2031, 0.5404, -0.0188, -0.3356, 0.4191)
# Aircraft yaw (Table 5: sigma_n 0.0023, sigma_e 0.0005, sigma_x 0.0011 deg,
# r = 0.86 0.57 0.29 0.09), 3000 epochs; residual RMS 0.5 hundredths. Pitch (sigma_x/sigma_n =
# 0.37 with sigma_e/sigma_n = 0.37) is out of reach of any stationary ARI(2,2): the best fit
# gives 0.54 (roll: 0.57 for 0.57, but r(1) 0.74 for 0.80), so yaw is the case.
_AIRCRAFT_PHI = (-0.7318, 0.3832)

SYNTHETIC_CASES: tuple[SyntheticCase, ...] = (
    # Paper §3.1: GPS ARI(5,2), 0.6 s, ~130 epochs per strip (and a 2000-epoch flight).
    SyntheticCase(
        "gps_strip",
        "GPS strip ARI(5,2) 0.6 s",
        _GPS_PHI,
        2,
        0.021,
        0.0618,
        130,
        0.6,
        "m",
        0.017 / 0.021,
        _GPS_R,
        "Tables 1, 3 (X)",
        0.021,
    ),
    SyntheticCase(
        "gps_flight",
        "GPS flight ARI(5,2) 0.6 s",
        _GPS_PHI,
        2,
        0.021,
        0.0618,
        2000,
        0.6,
        "m",
        0.017 / 0.021,
        _GPS_R,
        "Tables 1, 3 (X)",
        0.021,
    ),
    # Paper §3.2, Table 4: Shuttle INS ARI(6,1), 2 s, strips of 120–800 points.
    SyntheticCase(
        "shuttle_ins",
        "Shuttle INS ARI(6,1) 2 s",
        _SHUTTLE_PHI,
        1,
        0.0060,
        0.0019,
        400,
        2.0,
        "deg",
        0.0027 / 0.0060,
        (0.71, 0.46, 0.18, 0.13),
        "Table 4 (yaw)",
        0.0060,
        0.0019,
    ),
    # Paper §3.2, Table 5: aircraft INS ARI(2,2), 10 Hz; 3000 epochs = 5 min of the
    # undisturbed central part of a flight.
    SyntheticCase(
        "aircraft_ins",
        "Aircraft INS ARI(2,2) 10 Hz",
        _AIRCRAFT_PHI,
        2,
        0.0023,
        0.0005,
        3000,
        0.1,
        "deg",
        0.0011 / 0.0023,
        (0.86, 0.57, 0.29, 0.09),
        "Table 5 (yaw)",
        0.0023,
        0.0005,
    ),
)


@dataclass(frozen=True, slots=True)
class AriExperimentParams:
    """Parameters of ``navtrack reproduce ari`` (the synthetic study's are passed to every run).

    The paper gives the applications' orders, sampling intervals and sigmas (:data:`SYNTHETIC_CASES`
    cites its sections and tables) and detects gross errors by robust weights (Danish method,
    eq. (2)), but injects none; the contamination (1 % of epochs, 5–15 sigma_n) is this
    reproduction's test design, and so are the order selection and the identifiability limit.

    Attributes
    ----------
    cases : tuple of SyntheticCase
        Synthetic series of each run (not settable from the command line).
    outlier_rate : float
        Fraction of epochs given a gross error (at least one per series), in [0, 1].
    outlier_sigma : (float, float)
        Range of gross-error magnitudes in units of sigma_n (uniform, random sign),
        ``0 < lo <= hi``.
    robust : {"danish", "huber", "igg3", "off"}
        Weight function of the robust fit (:class:`navtrack.smoothing.ari.AriConfig` ``robust``).
    select_order : bool
        Also select the order by BIC (the slowest part).
    identifiable_crb : float
        Relative Cramér–Rao standard deviation below which a sigma counts as identifiable (the
        10 % bars apply only then).
    real_data : bool
        Fit the shared real data sets (off: only the ``--input`` files); not part of the paper.
    paper_runs : int
        Runs ``0 .. paper_runs - 1`` also fit the paper's estimator (every case, on the clean
        and on the contaminated series); the others only the exact one. Its medians and spreads
        are over these runs (their count is printed with them). Default: all of the default
        runs (with SQUAREM its fits cost 0.04–1.2 s CPU per case, measured on one series each).
    order_runs : int
        Runs ``0 .. order_runs - 1`` also select the order by BIC (with ``select_order``): 14
        candidate fits per case, two thirds of a run's cost with the exact estimator alone.
    paper_order : bool
        In the ``order_runs``, select the order by BIC with the paper's estimator fitting every
        candidate too (every case). Measured CPU per selection, paper / exact estimator (one
        series each, SQUAREM iteration): GPS strip 1.3 / 2.3 s, flight 1.6 / 4.1 s, Shuttle
        1.8 / 1.5 s, aircraft 9.4 / 2.7 s.
    robust_process : bool
        Reweight the process equations (3) too wherever the reproduction weights robustly (the
        contaminated synthetic series, the real catalogue, the carrier-phase strips, the INS
        series): the paper's treatment of edges and discontinuities (§2.2), on by default as in
        the paper; ``False`` weights the observations only (``AriConfig``'s own default).
    carrier_phase : bool
        Fit the carrier-phase series of navtrack's relative positioning
        (:mod:`navtrack.experiments.ari.carrier`): paper Tables 1–3 in the paper's regime.
    carrier_strip_epochs : int
        Strip length of the carrier-phase series (the paper's "about 130 registrations").
    ins : bool
        Fit the navigation-grade INS attitude series (:mod:`navtrack.experiments.ari.ins`):
        paper Tables 4–5 in the paper's regime.
    printed_truths : bool
        Fit a truth to every column the paper prints
        (:func:`navtrack.experiments.ari.truths.printed_truths`, about 15 s CPU).
    attitude_form : {"rotvec", "euler"}
        Form of the BROAD attitude series (:func:`navtrack.experiments.ari.broad.broad_series`):
        the rotation-vector path (default, no gimbal-lock singularity) or the paper's Euler
        angles.
    """

    cases: tuple[SyntheticCase, ...] = SYNTHETIC_CASES
    outlier_rate: float = 0.01
    outlier_sigma: tuple[float, float] = (5.0, 15.0)
    robust: Literal["danish", "huber", "igg3", "off"] = "danish"
    select_order: bool = True
    identifiable_crb: float = IDENTIFIABLE_CRB
    real_data: bool = True
    paper_runs: int = 20
    order_runs: int = 10
    paper_order: bool = True
    attitude_form: Literal["rotvec", "euler"] = "rotvec"
    robust_process: bool = True
    carrier_phase: bool = True
    carrier_strip_epochs: int = 130
    ins: bool = True
    printed_truths: bool = True

    def __post_init__(self) -> None:
        if not self.cases or len({c.name for c in self.cases}) != len(self.cases):
            raise ValueError("cases: expected at least one case, names unique")
        if not 0.0 <= self.outlier_rate <= 1.0:
            raise ValueError(f"outlier_rate: expected 0 <= rate <= 1, got {self.outlier_rate}")
        lo, hi = self.outlier_sigma
        if not 0.0 < lo <= hi:
            raise ValueError(f"outlier_sigma: expected 0 < lo <= hi, got {self.outlier_sigma}")
        if self.robust not in ROBUST_CHOICES:
            raise ValueError(f"robust: expected one of {ROBUST_CHOICES}, got {self.robust!r}")
        if not self.identifiable_crb > 0.0:
            raise ValueError(f"identifiable_crb: expected > 0, got {self.identifiable_crb}")
        if self.paper_runs < 0 or self.order_runs < 0:
            raise ValueError(
                f"paper_runs, order_runs: expected >= 0, got {self.paper_runs}, {self.order_runs}"
            )
        if self.carrier_strip_epochs < 20:
            raise ValueError(
                f"carrier_strip_epochs: expected >= 20, got {self.carrier_strip_epochs}"
            )
        if self.attitude_form not in ATTITUDE_FORMS:
            raise ValueError(
                f"attitude_form: expected one of {ATTITUDE_FORMS}, got {self.attitude_form!r}"
            )


def run_index(rng: np.random.Generator) -> int:
    """Index of the Monte Carlo run whose generator is ``rng``.

    The runner's generator of run ``i`` is the ``i``-th child of ``SeedSequence(seed)``
    (:func:`navtrack.experiments.runner.run_generator`): ``i`` is the last entry of its spawn
    key. A generator made otherwise (no spawn key) counts as run 0.
    """
    seq = getattr(rng.bit_generator, "seed_seq", None)
    key = getattr(seq, "spawn_key", ())
    return int(key[-1]) if key else 0


def synthetic_run(params: AriExperimentParams, rng: np.random.Generator) -> dict[str, Any]:
    """One Monte Carlo run: every case simulated, estimated, contaminated, re-estimated.

    The paper's estimator runs only in the first ``params.paper_runs`` runs and the order
    selection in the first ``params.order_runs`` (:func:`run_index`); the random draws are the
    same either way, so a run's other results do not depend on them.

    Returns
    -------
    dict
        Case name -> per-run record (estimate/truth ratios, CRB, detections, order chosen).
    """
    index = run_index(rng)
    out: dict[str, dict[str, Any]] = {}
    for case in params.cases:
        y, _ = simulate_ari(rng, case.n, case.phi, case.d, case.sigma_n, case.sigma_e)
        k = max(1, round(params.outlier_rate * case.n))
        idx = rng.choice(case.n, size=k, replace=False)
        lo, hi = params.outlier_sigma
        mag = rng.uniform(lo, hi, size=k) * rng.choice([-1.0, 1.0], size=k)
        with_paper = index < params.paper_runs
        rec = _clean_record(case, y, with_paper)
        rec.update(_contaminated_record(params, case, y, idx, mag, with_paper))
        if params.select_order and index < params.order_runs:
            rec.update(_order_record(params, case, y))
        out[case.name] = rec
    return out


def _bic_gap(auto: AriResult, true_order: tuple[int, int]) -> float:
    """BIC of the true order minus that of the order ``auto`` chose (>= 0; NaN when the true
    order was not among the fitted candidates)."""
    scores = {(p, d): score for p, d, score in auto.candidates}
    true = scores.get(true_order)
    return math.nan if true is None else true - scores[(auto.p, auto.d)]


def _robust_record(
    prefix: str, res: AriResult, case: SyntheticCase, idx: IntArray, truth: BoolArray
) -> dict[str, Any]:
    """Robust fit ``res`` of a contaminated series as ``{prefix}_...`` entries: status, sigma
    ratios to the truth, which injected errors were flagged, false flags."""
    return {
        f"{prefix}_status": str(res.status),
        f"{prefix}_sigma_n_ratio": res.sigma_n / case.sigma_n,
        f"{prefix}_sigma_e_ratio": res.sigma_e / case.sigma_e,
        f"{prefix}_detected": [bool(v) for v in res.gross_error[idx]],
        f"{prefix}_false_flags": int(np.count_nonzero(res.gross_error & ~truth)),
    }


def _clean_record(case: SyntheticCase, y: FloatArray, with_paper: bool) -> dict[str, Any]:
    """Estimates of the clean series against the truth, the CRB and the true filtered
    statistics (and the paper's estimator's when ``with_paper``)."""
    p = len(case.phi)
    rec: dict[str, Any] = {}
    t0 = time.perf_counter()
    clean = fit_ari(y, AriConfig(order=(p, case.d), robust="off"))
    rec["exact_seconds"] = time.perf_counter() - t0
    rec["clean_status"] = str(clean.status)
    rec["sigma_n_ratio"] = clean.sigma_n / case.sigma_n
    rec["sigma_e_ratio"] = clean.sigma_e / case.sigma_e
    rec["sigma_x_over_sigma_n"] = clean.sigma_x_rms / clean.sigma_n
    rec["r"] = [float(v) for v in clean.autocorr]
    info = observed_information(y, case.phi, case.d, case.sigma_n, case.sigma_e)
    try:
        cov = np.linalg.inv(info)
        rec["crb_sigma_n"] = 0.5 * math.sqrt(max(cov[p, p], 0.0))
        rec["crb_sigma_e"] = 0.5 * math.sqrt(max(cov[p + 1, p + 1], 0.0))
    except np.linalg.LinAlgError:
        rec["crb_sigma_n"] = rec["crb_sigma_e"] = math.nan
    ratio, r_true = filtered_statistics(case.phi, case.d, case.sigma_n, case.sigma_e, case.n)
    rec["true_sigma_x_over_sigma_n"] = ratio
    rec["true_r"] = [float(v) for v in r_true]
    if with_paper:  # the paper's estimator on the same clean series
        t0 = time.perf_counter()
        paper = fit_ari(y, AriConfig(order=(p, case.d), robust="off", estimator="paper"))
        rec["paper_seconds"] = time.perf_counter() - t0
        rec["paper_status"] = str(paper.status)
        rec["paper_n_iter"] = paper.n_iter
        rec["paper_sigma_n_ratio"] = paper.sigma_n / case.sigma_n
        rec["paper_sigma_e_ratio"] = paper.sigma_e / case.sigma_e
        rec["paper_sigma_x_over_sigma_n"] = paper.sigma_x_rms / paper.sigma_n
        rec["paper_r"] = [float(v) for v in paper.autocorr]
    return rec


def _contaminated_record(
    params: AriExperimentParams,
    case: SyntheticCase,
    y: FloatArray,
    idx: Any,
    mag: FloatArray,
    with_paper: bool,
) -> dict[str, Any]:
    """The series with gross errors of ``mag`` sigma_n at ``idx``: robust fits (and the
    paper's estimator's when ``with_paper``) and the plain fit, against the injected errors."""
    p = len(case.phi)
    k = idx.size
    rec: dict[str, Any] = {}
    dirty = y.copy()
    dirty[idx] += mag * case.sigma_n
    truth = np.zeros(case.n, dtype=bool)
    truth[idx] = True
    t0 = time.perf_counter()
    robust = fit_ari(
        dirty,
        AriConfig(order=(p, case.d), robust=params.robust, robust_process=params.robust_process),
    )
    rec["robust_seconds"] = time.perf_counter() - t0
    rec.update(_robust_record("robust", robust, case, idx, truth))
    rec["n_injected"] = int(k)
    rec["magnitude_sigma"] = [float(v) for v in np.abs(mag)]
    rec["n_clean_epochs"] = int(np.count_nonzero(~truth))
    if with_paper:  # the paper's estimator on the same contaminated series
        t0 = time.perf_counter()
        paper = fit_ari(
            dirty,
            AriConfig(
                order=(p, case.d),
                robust=params.robust,
                robust_process=params.robust_process,
                estimator="paper",
            ),
        )
        rec["paper_robust_seconds"] = time.perf_counter() - t0
        rec.update(_robust_record("paper_robust", paper, case, idx, truth))
    # the same series without robust weighting, for comparison
    plain = fit_ari(dirty, AriConfig(order=(p, case.d), robust="off"))
    rec["plain_detected"] = int(np.count_nonzero(plain.gross_error[idx]))
    rec["plain_sigma_n_ratio"] = plain.sigma_n / case.sigma_n
    return rec


def _order_record(
    params: AriExperimentParams, case: SyntheticCase, y: FloatArray
) -> dict[str, Any]:
    """The order BIC selects on the clean series (both estimators with ``params.paper_order``)
    and its BIC gap to the true order."""
    p = len(case.phi)
    rec: dict[str, Any] = {}
    selections: tuple[tuple[str, Literal["exact", "paper"]], ...] = (
        ("", "exact"),
        ("paper_", "paper"),
    )
    for prefix, estimator in selections:
        if prefix and not params.paper_order:
            continue
        auto = fit_ari(y, AriConfig(robust="off", min_d=1, estimator=estimator))
        rec[f"{prefix}order"] = [auto.p, auto.d]
        rec[f"{prefix}bic_true_minus_chosen"] = _bic_gap(auto, (p, case.d))
    return rec


def summarize_synthetic(
    params: AriExperimentParams, runs: Sequence[dict[str, Any]]
) -> dict[str, Any]:
    """Medians, identifiability, detection rates and bars over the runs' results.

    Parameters
    ----------
    params : AriExperimentParams
    runs : sequence of dict
        :func:`synthetic_run` results of the successful runs, in run order.

    Returns
    -------
    dict
        Case name -> summary (truth, medians and IQRs, CRB, recall, false flags, bars).
    """
    summary: dict[str, Any] = {}
    for case in params.cases:
        recs = [r[case.name] for r in runs if case.name in r]
        if recs:
            summary[case.name] = _case_summary(case, recs, params.identifiable_crb)
    return summary


def _counts(recs: Sequence[dict[str, Any]], key: str) -> dict[str, int]:
    """How often each value of ``key`` occurs (records without it skipped); orders as
    ``"(p,d)"``."""
    counts: dict[str, int] = {}
    for r in recs:
        if key in r:
            value = r[key]
            name = f"({value[0]},{value[1]})" if isinstance(value, list | tuple) else value
            counts[name] = counts.get(name, 0) + 1
    return counts


def _estimator_summaries(recs: Sequence[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """Spread of every estimate of both estimators (exact likelihood, the paper's)."""
    return {
        "exact": {
            "status": _counts(recs, "clean_status"),
            "sigma_n_ratio": _spread(recs, "sigma_n_ratio"),
            "sigma_e_ratio": _spread(recs, "sigma_e_ratio"),
            "sigma_x_over_sigma_n": _spread(recs, "sigma_x_over_sigma_n"),
            "r": _spread(recs, "r"),
            "seconds": _spread(recs, "exact_seconds"),
            "bic_true_minus_chosen": _spread(recs, "bic_true_minus_chosen"),
            "robust": _contamination(recs, "robust"),
        },
        "paper": {
            "status": _counts(recs, "paper_status"),
            "sigma_n_ratio": _spread(recs, "paper_sigma_n_ratio"),
            "sigma_e_ratio": _spread(recs, "paper_sigma_e_ratio"),
            "sigma_x_over_sigma_n": _spread(recs, "paper_sigma_x_over_sigma_n"),
            "r": _spread(recs, "paper_r"),
            "seconds": _spread(recs, "paper_seconds"),
            "n_iter": _spread(recs, "paper_n_iter"),
            "bic_true_minus_chosen": _spread(recs, "paper_bic_true_minus_chosen"),
            "robust": _contamination(recs, "paper_robust"),
        },
    }


def _case_summary(
    case: SyntheticCase, recs: list[dict[str, Any]], crb_limit: float
) -> dict[str, Any]:
    """The summary of one case over its runs' records."""

    def arr(key: str) -> FloatArray:
        return np.array([r[key] for r in recs], dtype=float)

    crb_n = float(np.median(arr("crb_sigma_n")))
    crb_e = float(np.median(arr("crb_sigma_e")))
    med_n = float(np.median(arr("sigma_n_ratio")))
    med_e = float(np.median(arr("sigma_e_ratio")))
    estimators = _estimator_summaries(recs)
    for est in estimators.values():
        est["bars"] = _bars(est, crb_n, crb_e, crb_limit)
    exact_robust = estimators["exact"]["robust"]
    statuses = estimators["exact"]["status"]
    return {
        "label": case.label,
        "truth": {
            "order": [len(case.phi), case.d],
            "phi": list(case.phi),
            "sigma_n": case.sigma_n,
            "sigma_e": case.sigma_e,
            "n": case.n,
            "dt_s": case.dt_s,
            "unit": case.unit,
            "sigma_x_over_sigma_n": float(np.median(arr("true_sigma_x_over_sigma_n"))),
            "r": [float(v) for v in np.median([r["true_r"] for r in recs], axis=0)],
        },
        "printed": {
            "source": case.printed_source,
            "sigma_n": case.printed_sigma_n,
            "sigma_e": case.printed_sigma_e,
            "sigma_x_over_sigma_n": case.printed_ratio,
            "r": list(case.printed_r),
        },
        "estimators": estimators,
        "runs": len(recs),
        "paper_runs": sum("paper_status" in r for r in recs),
        "order_runs": sum("order" in r for r in recs),
        "clean_status": statuses,
        "median_sigma_n_ratio": med_n,
        "median_sigma_e_ratio": med_e,
        "iqr_sigma_n_ratio": [float(v) for v in np.percentile(arr("sigma_n_ratio"), [25, 75])],
        "iqr_sigma_e_ratio": [float(v) for v in np.percentile(arr("sigma_e_ratio"), [25, 75])],
        "median_sigma_n": med_n * case.sigma_n,
        "median_sigma_e": med_e * case.sigma_e,
        "median_sigma_x_over_sigma_n": float(np.median(arr("sigma_x_over_sigma_n"))),
        "median_r": [float(v) for v in np.median(np.array([r["r"] for r in recs]), axis=0)],
        "crb_rel_sd_sigma_n": crb_n,
        "crb_rel_sd_sigma_e": crb_e,
        "identifiable_sigma_n": crb_n < crb_limit,
        "identifiable_sigma_e": crb_e < crb_limit,
        "robust_median_sigma_n_ratio": float(np.median(arr("robust_sigma_n_ratio"))),
        "robust_median_sigma_e_ratio": float(np.median(arr("robust_sigma_e_ratio"))),
        "plain_median_sigma_n_ratio": float(np.median(arr("plain_sigma_n_ratio"))),
        "plain_recall": float(arr("plain_detected").sum() / max(exact_robust["injected"], 1)),
        "injected": exact_robust["injected"],
        "recall": exact_robust["recall"],
        "recall_by_magnitude": exact_robust["recall_by_magnitude"],
        "false_flags": exact_robust["false_flags"],
        "false_flag_rate": exact_robust["false_flag_rate"],
        "orders_selected": _counts(recs, "order"),
        "orders_selected_paper": _counts(recs, "paper_order"),
        "bars": estimators["exact"]["bars"],
    }


def _spread(recs: Sequence[dict[str, Any]], key: str) -> dict[str, Any] | None:
    """Median and IQR over the runs that have ``key`` (scalar or each element of a list);
    ``None`` when none has it."""
    vals = np.array([r[key] for r in recs if key in r], dtype=float)
    if not vals.size:
        return None
    q = np.nanpercentile(vals, [25, 50, 75], axis=0)
    return {"median": q[1].tolist(), "iqr": [q[0].tolist(), q[2].tolist()], "runs": len(vals)}


def _contamination(recs: Sequence[dict[str, Any]], prefix: str) -> dict[str, Any]:
    """Gross-error results of one estimator (``_robust_record`` entries ``{prefix}_...``) over
    the runs that have them: recall (overall and by magnitude), false flags, sigma ratios,
    statuses, seconds per fit."""
    have = [r for r in recs if f"{prefix}_detected" in r]
    if not have:
        return {"runs": 0, "injected": 0, "recall": math.nan, "false_flag_rate": math.nan}
    detected = np.concatenate([np.array(r[f"{prefix}_detected"], dtype=bool) for r in have])
    mags = np.concatenate([np.array(r["magnitude_sigma"], dtype=float) for r in have])
    false_flags = int(sum(r[f"{prefix}_false_flags"] for r in have))
    clean_epochs = int(sum(r["n_clean_epochs"] for r in have))
    by_magnitude = {}
    for lo, hi in ((5.0, 7.0), (7.0, 10.0), (10.0, 15.01)):
        sel = (mags >= lo) & (mags < hi)
        by_magnitude[f"{lo:g}-{min(hi, 15):g}"] = float(detected[sel].mean()) if sel.any() else None
    statuses: dict[str, int] = {}
    for r in have:
        statuses[r[f"{prefix}_status"]] = statuses.get(r[f"{prefix}_status"], 0) + 1
    return {
        "runs": len(have),
        "injected": int(detected.size),
        "recall": float(detected.mean()),
        "recall_by_magnitude": by_magnitude,
        "false_flags": false_flags,
        "false_flag_rate": false_flags / clean_epochs if clean_epochs else math.nan,
        "status": statuses,
        "sigma_n_ratio": _spread(have, f"{prefix}_sigma_n_ratio"),
        "sigma_e_ratio": _spread(have, f"{prefix}_sigma_e_ratio"),
        "seconds": _spread(have, f"{prefix}_seconds"),
    }


def _bars(est: dict[str, Any], crb_n: float, crb_e: float, limit: float) -> dict[str, Any]:
    """The bars of one estimator: median sigma ratios within 10 % of the truth on the clean
    series (only where the sigma is identifiable: CRB below ``limit``; ``None`` otherwise or
    without runs), recall >= 95 % and false flags <= 1 % on the contaminated ones."""

    def within(entry: dict[str, Any] | None, crb: float) -> bool | None:
        if entry is None or not crb < limit:
            return None
        return bool(abs(entry["median"] - 1.0) <= 0.10)

    rob = est["robust"]
    return {
        "sigma_n_within_10pct": within(est["sigma_n_ratio"], crb_n),
        "sigma_e_within_10pct": within(est["sigma_e_ratio"], crb_e),
        "recall_ge_95pct": bool(rob["recall"] >= 0.95) if rob["runs"] else None,
        "false_flags_le_1pct": bool(rob["false_flag_rate"] <= 0.01) if rob["runs"] else None,
    }
