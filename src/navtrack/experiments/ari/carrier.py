"""Carrier-phase series of the ARI reproduction: paper 5's Tables 1–3 in the paper's regime.

The paper's GPS series (§3.1) are positions from double-differenced carrier phase against a
stationary reference receiver, 0.6 s, cut into photo strips of about 130 registrations. The
like-for-like series here are navtrack's own relative positions
(:func:`navtrack.gnss.relative.solve_relative`, what ``navtrack rtk`` runs) of the pairs in
:data:`RTK_RUNS`, each solved once per reproduction and cut into strips
(:func:`strip_bounds`). Every strip and coordinate is fitted (:func:`strip_fits`):

* the exact-likelihood estimator with the order chosen by BIC (``p = 0..6``, ``d = 1..2``);
* the paper's estimator at that order with both forms of the variance components
  (``vce="redundancy"`` and Förstner's frequency-domain ``vce="forstner"``);

all with robust observation weights (Danish) and, by default, robust process equations (the
paper's treatment of edges and discontinuities, ``robust_process``). Table 2's least-squares
accuracy is the RMS over the strip of the solution's formal single-epoch standard deviation
(navtrack's RTK phase model: 3 mm + 3 mm / sin(el) per undifferenced phase, RTKLIB's default).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from navtrack import geodesy
from navtrack._typing import FloatArray
from navtrack.data import sample_path
from navtrack.gnss.relative import RtkConfig, RtkStatus, solve_relative
from navtrack.gnss.rinex.nav import read_nav
from navtrack.gnss.rinex.obs import read_obs
from navtrack.smoothing.ari import AriConfig, AriResult, fit_ari
from navtrack.smoothing.identifiability import sigma_bounds

__all__ = [
    "CARRIER_COLUMNS",
    "RTK_RUNS",
    "CarrierSeries",
    "RtkRun",
    "carrier_rows",
    "carrier_series",
    "carrier_sources",
    "strip_bounds",
    "strip_fits",
]

#: Coordinates of the carrier-phase series (local east, north, up about the mean, m).
CARRIER_COLUMNS = ("e_m", "n_m", "u_m")


@dataclass(frozen=True, slots=True)
class RtkRun:
    """One rover/base pair solved by navtrack's relative positioning.

    Attributes
    ----------
    name : str
    rover, base : str
        Observation files: relative to ``shared/data/gnss``, or ``package:NAME`` for a file
        bundled with navtrack (:func:`navtrack.data.sample_path`).
    nav : tuple of str
        Navigation files (same convention).
    base_xyz_m : tuple of float
        Base position (ECEF, m) and where it comes from (``base_source``).
    base_source : str
    frequencies : int
        1 (L1) or 2 (L1+L2).
    kinematic : bool
        The rover moves.
    description : str
    """

    name: str
    rover: str
    base: str
    nav: tuple[str, ...]
    base_xyz_m: tuple[float, float, float]
    base_source: str
    frequencies: int
    kinematic: bool
    description: str


#: The carrier-phase pairs available: the shared data hold one kinematic pair (the walking
#: u-blox rover against its static master, 1 s, GPS L1) and navtrack bundles one static
#: baseline (GEONET 0759 against 3040, 3.3 km, 30 s, GPS L1+L2). Both are solved in kinematic
#: mode (a new position every epoch, RTKLIB's ``dynamics off``): the series of epoch positions
#: is what the ARI model smooths; a static solution is one position.
RTK_RUNS: tuple[RtkRun, ...] = (
    RtkRun(
        "yamatogawa",
        "gogps_yamatogawa/yamatogawa_rover.obs",
        "gogps_yamatogawa/yamatogawa_master.obs",
        ("gogps_yamatogawa/brdc0060.10n",),
        (-3749943.5172, 3683398.2394, 3600629.5295),
        "master header APPROX POSITION (shared/data/gnss/README.md)",
        1,
        True,
        "walking u-blox rover vs static master, 1 s, GPS L1",
    ),
    RtkRun(
        "geonet_0759_3040",
        "package:07590920.05o",
        "package:30400920.05o",
        ("package:07590920.05n",),
        (-3978241.958, 3382840.234, 3649900.853),
        "RTKLIB's test coordinate of 3040 (navtrack/data/README.md)",
        2,
        False,
        "static GEONET baseline 0759-3040 (3.3 km), 30 s, GPS L1+L2, processed kinematically",
    ),
)


@dataclass(frozen=True, slots=True)
class CarrierSeries:
    """One RTK solution as local coordinates with formal standard deviations.

    Attributes
    ----------
    source : str
        ``<run> fixed`` (integer ambiguities where validated, float elsewhere) or
        ``<run> float``.
    dt_s : float
    columns : dict of str to ndarray (n,)
        ``e_m``, ``n_m``, ``u_m`` about the mean of the solved epochs (NaN where none).
    sd_m : dict of str to ndarray (n,)
        Formal standard deviation of each epoch's position per coordinate.
    meta : dict
        Run, description, status counts, solve time, base position source.
    """

    source: str
    dt_s: float
    columns: dict[str, FloatArray]
    sd_m: dict[str, FloatArray]
    meta: dict[str, Any]


def _path(shared_gnss: Path, name: str) -> Path:
    if name.startswith("package:"):
        return Path(sample_path(name.removeprefix("package:")))
    return shared_gnss / name


def carrier_series(shared_gnss: Path, run: RtkRun) -> list[CarrierSeries]:
    """Solve ``run`` once with and once without integer fixing (kinematic, forward and backward
    combined) and return both position series.

    Epochs without a relative solution (``no_base``, ``single``, ``no_solution``) are missing
    (NaN); the series keep the rover's epochs, trimmed of leading and trailing missing ones.
    """
    rover = read_obs(_path(shared_gnss, run.rover))
    base = read_obs(_path(shared_gnss, run.base))
    navs = [read_nav(_path(shared_gnss, p)) for p in run.nav]
    base_xyz = np.asarray(run.base_xyz_m, dtype=float)
    out = []
    relative = (int(RtkStatus.FIX), int(RtkStatus.FLOAT))
    for fix in (True, False):
        config = RtkConfig(frequencies=run.frequencies, direction="combined", fix=fix)
        t0 = time.perf_counter()
        res = solve_relative(rover, base, navs, base_xyz, config)
        elapsed = time.perf_counter() - t0
        ok = np.isin(res.status, relative) & np.all(np.isfinite(res.pos_m), axis=1)
        if not np.any(ok):
            raise ValueError(f"RTK run {run.name}: no epoch has a relative solution")
        seen = np.flatnonzero(ok)
        span = slice(int(seen[0]), int(seen[-1]) + 1)
        pos, keep = res.pos_m[span], ok[span]
        enu = np.full_like(pos, np.nan)
        enu[keep] = geodesy.ecef_to_enu(pos[keep], np.mean(pos[keep], axis=0))
        sd = np.where(keep[:, None], res.sd_enu_m[span], np.nan)
        counts = {k: v for k, v in res.status_counts().items() if v}
        dt = float(np.median(np.diff(res.t_gps_s)))
        out.append(
            CarrierSeries(
                f"{run.name} {'fixed' if fix else 'float'}",
                dt,
                {c: enu[:, k] for k, c in enumerate(CARRIER_COLUMNS)},
                {c: sd[:, k] for k, c in enumerate(CARRIER_COLUMNS)},
                {
                    "run": run.name,
                    "description": run.description,
                    "fix": fix,
                    "kinematic": run.kinematic,
                    "base_source": run.base_source,
                    "rtk_status": counts,
                    "epochs": int(keep.size),
                    "solved": int(np.count_nonzero(keep)),
                    "rtk_seconds": elapsed,
                },
            )
        )
    return out


def strip_bounds(n: int, strip_epochs: int) -> list[tuple[int, int]]:
    """Consecutive strips of about ``strip_epochs``: ``max(1, round(n / strip_epochs))`` equal
    parts of the ``n`` epochs (the paper's strips hold "about 130 registrations")."""
    if n < 1 or strip_epochs < 1:
        raise ValueError(f"need n >= 1 and strip_epochs >= 1, got {n}, {strip_epochs}")
    k = max(1, round(n / strip_epochs))
    edges = np.linspace(0, n, k + 1).round().astype(int)
    return [(int(a), int(b)) for a, b in itertools.pairwise(edges)]


def _record(res: AriResult, conditional: bool) -> dict[str, Any]:
    crb_n, crb_e = sigma_bounds(res, conditional=conditional) if res.estimated else (math.nan,) * 2
    return {
        "status": str(res.status),
        "order": [res.p, res.d],
        "sigma_n": res.sigma_n,
        "sigma_e": res.sigma_e,
        "sigma_x": res.sigma_x_rms,
        "r": [float(v) for v in res.autocorr[:3]],
        "crb_sigma_n": crb_n,
        "crb_sigma_e": crb_e,
        "n_flagged": res.n_flagged,
        "n_process_downweighted": int(np.count_nonzero(res.process_weight < 0.5)),
        "redundancy_n": res.redundancy_n,
        "redundancy_e": res.redundancy_e,
        "n_iter": res.n_iter,
    }


def strip_fits(values: FloatArray, robust_process: bool, *, paper: bool = True) -> dict[str, Any]:
    """One strip of one coordinate: exact estimator with the BIC order, then (``paper``) the
    paper's estimator at that order with both VCE forms.

    Returns
    -------
    dict
        ``exact``, ``paper_redundancy``, ``paper_forstner`` (records of :func:`_record`),
        ``bic_52_minus_best`` (BIC of ARI(5,2) above the chosen order's; NaN when (5,2) could
        not be fitted) and ``bic_top`` (the three best orders with their BIC).
    """
    cfg = AriConfig(min_d=1, robust_process=robust_process)
    t0 = time.perf_counter()
    exact = fit_ari(values, cfg)
    out: dict[str, Any] = {"exact": _record(exact, conditional=False)}
    scores = sorted(exact.candidates, key=lambda c: c[2])
    best = scores[0][2] if scores else math.nan
    by_order = {(p, d): s for p, d, s in scores}
    out["bic_52_minus_best"] = by_order.get((5, 2), math.nan) - best
    out["bic_top"] = [[p, d, s - best] for p, d, s in scores[:3]]
    if exact.estimated and paper:
        for vce in ("redundancy", "forstner"):
            paper_cfg = dataclasses.replace(
                cfg, order=(exact.p, exact.d), estimator="paper", vce=vce
            )
            out[f"paper_{vce}"] = _record(fit_ari(values, paper_cfg), conditional=True)
    out["seconds"] = time.perf_counter() - t0
    return out


def carrier_rows(
    series: Sequence[CarrierSeries], strip_epochs: int, robust_process: bool
) -> list[dict[str, Any]]:
    """Every strip of every coordinate of ``series`` fitted (:func:`strip_fits`), one row each,
    with the strip's epochs, missing epochs and the RMS formal sd (Table 2's least-squares
    accuracy)."""
    rows = []
    for src in series:
        n = next(iter(src.columns.values())).size
        for k, (a, b) in enumerate(strip_bounds(n, strip_epochs)):
            for col, values in src.columns.items():
                part = values[a:b]
                sd = src.sd_m[col][a:b]
                rows.append(
                    {
                        "source": src.source,
                        "strip": k + 1,
                        "epochs": [a, b],
                        "n": int(b - a),
                        "n_missing": int(np.count_nonzero(np.isnan(part))),
                        "dt_s": src.dt_s,
                        "column": col,
                        "ls_sd_rms": float(np.sqrt(np.nanmean(sd**2))),
                        "robust_process": robust_process,
                        "meta": src.meta,
                        **strip_fits(part, robust_process),
                    }
                )
    return rows


def carrier_sources(
    shared_gnss: Path, runs: Sequence[RtkRun] = RTK_RUNS
) -> tuple[list[CarrierSeries], list[str]]:
    """The series of every run of ``runs`` whose files are present (:func:`carrier_series`),
    and what was skipped and why (absent files, no relative solution)."""
    series: list[CarrierSeries] = []
    skipped: list[str] = []
    for run in runs:
        paths = [_path(shared_gnss, p) for p in (run.rover, run.base, *run.nav)]
        missing = [str(p) for p in paths if not p.exists()]
        if missing:
            skipped.append(f"RTK {run.name}: input absent ({', '.join(missing)})")
            continue
        try:
            series += carrier_series(shared_gnss, run)
        except ValueError as exc:
            skipped.append(f"RTK {run.name}: {exc}")
    return series, skipped
