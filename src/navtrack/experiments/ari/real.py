"""Real data of the ARI reproduction: the paper's Tables 1–5 quantities for real series.

The series (:func:`default_real_sources`): BROAD optical orientation as the rotation-vector
path of its increments (:func:`navtrack.experiments.ari.broad.broad_series`; decimated
285.7 Hz -> 28.6 Hz, near the paper's 10 Hz INS rate, which also keeps the run short), the
pyins receiver track (ENU), RTKLIB SPP solutions of the shared GNSS stations and the walking
rover next to navtrack's own SPP solutions of the same files with the same options
(:data:`SPP_RUNS`, :func:`spp_series`; ENU about their mean), and any further solution
tables (:func:`solution_series`: navtrack CSV/Parquet or RTKLIB ``.pos``).
:func:`real_data_rows` fits every column; :func:`spp_comparison` puts navtrack's and RTKLIB's
rows of a run side by side.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from navtrack import geodesy
from navtrack._typing import BoolArray, FloatArray
from navtrack.errors import FileFormatError
from navtrack.experiments.ari.broad import broad_series
from navtrack.experiments.ari.series import RealSeries
from navtrack.gnss.rinex.nav import read_nav
from navtrack.gnss.rinex.obs import read_obs
from navtrack.gnss.spp import SppConfig, solution_frame, solve_spp
from navtrack.io.rtklib import to_solution_frame
from navtrack.io.tables import read_table
from navtrack.smoothing.ari import AriConfig, AriResult, fit_ari, regularize_time
from navtrack.smoothing.attitude import AttitudeForm
from navtrack.smoothing.identifiability import identifiability_warnings, sigma_bounds

__all__ = [
    "SPP_RUNS",
    "STRIP_EPOCHS",
    "RealSeries",
    "SppRun",
    "default_real_sources",
    "pyins_series",
    "real_data_rows",
    "solution_series",
    "spp_comparison",
    "spp_series",
    "strip_rows",
    "table2_rows",
]

#: Epochs per strip of :func:`strip_rows`, by unit of the series.
STRIP_EPOCHS = {"m": 130, "deg": 400}


def pyins_series(path: Path) -> RealSeries:
    """pyins receiver track (``gnss.csv``) as ENU (m) about its first epoch."""
    df = pd.read_csv(path)
    llh = np.column_stack(
        [np.radians(df["lat"].to_numpy()), np.radians(df["lon"].to_numpy()), df["alt"].to_numpy()]
    )
    xyz = geodesy.geodetic_to_ecef(llh)
    enu = geodesy.ecef_to_enu(xyz, xyz[0])
    t = df["time"].to_numpy(dtype=float)
    t_grid, enu_grid, inserted = regularize_time(t, enu)
    cols = {name: enu_grid[:, k] for k, name in enumerate(("e_m", "n_m", "u_m"))}
    dt = float(np.median(np.diff(t)))
    return RealSeries("pyins gnss.csv", t_grid, cols, "m", dt, inserted, {"kinematic": True})


def solution_series(path: Path) -> RealSeries:
    """A positioning solution (RTKLIB ``.pos`` or navtrack CSV/Parquet) as ENU about its mean.

    The file is read by :func:`navtrack.io.tables.read_table` (format by suffix). Epochs missing
    from the file are inserted as missing (NaN) on the median time step.
    """
    return _table_series(path.name, read_table(path), path=path)


def _table_series(
    source: str, df: Any, meta: dict[str, Any] | None = None, path: Path | None = None
) -> RealSeries:
    """ENU (m) about the mean of the usable epochs of a solution table (``t_gps_s``, ``x_m``,
    ``y_m``, ``z_m``, optional ``status``); unusable epochs and gaps are missing (NaN).
    ``path``: the file the table was read from, named in the error when columns are missing."""
    missing = [c for c in ("t_gps_s", "x_m", "y_m", "z_m") if c not in df.columns]
    if missing:
        message = f"not a solution table: no column {', '.join(missing)}"
        if path is None:
            raise ValueError(f"{source}: {message}")
        raise FileFormatError(path, None, message)

    xyz = df[["x_m", "y_m", "z_m"]].to_numpy(dtype=float)
    t = df["t_gps_s"].to_numpy(dtype=float)
    ok = np.all(np.isfinite(xyz), axis=1)
    if "status" in df.columns:
        ok &= df["status"].astype(str).str.lower().isin(["ok", "0", "fix", "single"]).to_numpy()
    if not np.any(ok):
        raise ValueError(f"{source}: no usable epoch in the solution")
    ref = np.mean(xyz[ok], axis=0)
    enu = np.full_like(xyz, np.nan)
    enu[ok] = geodesy.ecef_to_enu(xyz[ok], ref)
    t_grid, enu_grid, inserted = regularize_time(t, enu)
    cols = {name: enu_grid[:, k] for k, name in enumerate(("e_m", "n_m", "u_m"))}
    info = dict(meta or {})
    sd = _single_epoch_sd(df)
    if sd is not None:
        # paper Table 2: the accuracy of the single epochs from their least-squares adjustment
        info["ls_sd_rms_m"] = {
            name: float(np.sqrt(np.nanmean(sd[ok, k] ** 2)))
            for k, name in enumerate(("e_m", "n_m", "u_m"))
        }
    return RealSeries(source, t_grid, cols, "m", float(np.median(np.diff(t))), inserted, info)


def _single_epoch_sd(df: Any) -> FloatArray | None:
    """Formal standard deviations ``(n, 3)`` (m) of each epoch's solution in east, north, up:
    a solution table's ``sd_e_m sd_n_m sd_u_m``, or an RTKLIB ``.pos`` frame's ECEF
    ``sdx..sdzx`` rotated to the local frame (:func:`navtrack.io.rtklib.to_solution_frame`);
    ``None`` when the table carries neither."""
    cols = ["sd_e_m", "sd_n_m", "sd_u_m"]
    if not set(cols) <= set(df.columns) and {"sdx_m", "lat_deg"} <= set(df.columns):
        df = to_solution_frame(df)
    if not set(cols) <= set(df.columns):
        return None
    return np.asarray(df[cols].to_numpy(dtype=float))


@dataclass(frozen=True, slots=True)
class SppRun:
    """One shared GNSS data set solved by navtrack's SPP like RTKLIB's reference run ``name``.

    Attributes
    ----------
    name : str
        Name of the RTKLIB run (``shared/data/gnss/rtklib_spp/<name>.pos``).
    obs : str
        Observation file, relative to ``shared/data/gnss``.
    nav : tuple of str
        Navigation files, relative to ``shared/data/gnss``.
    systems : str
        Systems used (RTKLIB ``pos1-navsys``: ``G`` = 1, ``GEJ`` = 25).
    kinematic : bool
        The receiver moves (the walking rover); static stations otherwise.
    """

    name: str
    obs: str
    nav: tuple[str, ...]
    systems: str
    kinematic: bool = False


#: The RTKLIB SPP runs of ``shared/data/gnss/rtklib_spp/README.md`` (single point, L1, mask
#: 15 deg, Klobuchar, Saastamoinen, broadcast ephemeris, GDOP > 30 rejected): navtrack solves the
#: same files with :class:`navtrack.gnss.spp.SppConfig` defaults, which reproduce those options.
SPP_RUNS: tuple[SppRun, ...] = (
    SppRun("gsi0759_gps", "rtklib_gsi0759/07590920.05o", ("rtklib_gsi0759/07590920.05n",), "G"),
    SppRun("arl1_gps", "gpstk_arl1/arlm200a.15o", ("gpstk_arl1/arlm2000.15n",), "G"),
    SppRun("sept078_gps", "cssrlib_sept/SEPT078M.21O", ("cssrlib_sept/SEPT078M.21P",), "G"),
    SppRun("sept078_gej", "cssrlib_sept/SEPT078M.21O", ("cssrlib_sept/SEPT078M.21P",), "GEJ"),
    SppRun(
        "yamatogawa_master_gps",
        "gogps_yamatogawa/yamatogawa_master.obs",
        ("gogps_yamatogawa/brdc0060.10n",),
        "G",
    ),
    SppRun(
        "yamatogawa_rover_gps",
        "gogps_yamatogawa/yamatogawa_rover.obs",
        ("gogps_yamatogawa/brdc0060.10n",),
        "G",
        kinematic=True,
    ),
)


def spp_series(gnss: Path, run: SppRun) -> RealSeries:
    """navtrack's own single point solution of ``run`` as ENU (m) about its mean position.

    Parameters
    ----------
    gnss : Path
        ``shared/data/gnss``.
    run : SppRun

    Returns
    -------
    RealSeries
        Source ``navtrack <name>``; epochs without a solution (any status but ``ok``) are
        missing (NaN). ``meta`` holds the SPP epoch count, status counts and solve time.
    """
    obs = read_obs(gnss / run.obs)
    navs = [read_nav(gnss / p) for p in run.nav]
    t0 = time.perf_counter()
    result = solve_spp(obs, navs, config=SppConfig(systems=run.systems))
    elapsed = time.perf_counter() - t0
    counts = {k: v for k, v in result.status_counts().items() if v}
    meta = {
        "solver": "navtrack",
        "run": run.name,
        "kinematic": run.kinematic,
        "epochs": int(result.t_gps_s.size),
        "solved": int(counts.get("ok", 0)),
        "spp_status": counts,
        "spp_seconds": elapsed,
    }
    cols = solution_frame(result)
    keep = ("t_gps_s", "x_m", "y_m", "z_m", "status", "sd_e_m", "sd_n_m", "sd_u_m")
    df = pd.DataFrame({k: cols[k] for k in keep})
    return _table_series(f"navtrack {run.name}", df, meta)


@dataclass(frozen=True, slots=True)
class _ColumnTask:
    """One real column to fit (the unit of work of :func:`real_data_rows`; picklable)."""

    source: str
    column: str
    unit: str
    dt_s: float
    values: FloatArray
    n_inserted: int
    meta: dict[str, Any]
    model_error: BoolArray | None
    causes: dict[str, BoolArray]
    kinematic: bool
    strip_epochs: int | None


def _column_task(src: RealSeries, col: str, strips: bool) -> _ColumnTask:
    values = src.columns[col]
    model_error = src.meta.get("model_error", {}).get(col)
    length = STRIP_EPOCHS.get(src.unit, 130)
    return _ColumnTask(
        src.source,
        col,
        src.unit,
        src.dt_s,
        np.asarray(values),
        src.n_inserted,
        {k: v for k, v in src.meta.items() if k not in _EPOCH_META},
        None if model_error is None else np.asarray(model_error, dtype=bool),
        dict(src.meta.get("flag_causes", {})),
        bool(src.meta.get("kinematic", False)),
        length if strips and values.size >= 2 * length else None,
    )


#: ``RealSeries.meta`` entries that hold per-epoch arrays (kept out of the rows).
_EPOCH_META = ("model_error", "flag_causes")


def _flag_explanation(task: _ColumnTask, res: AriResult) -> dict[str, Any]:
    """Flags of ``res`` at the epochs of each cause of ``task.causes``, how many have one, and
    each cause's share of the observed epochs (what chance alone would explain)."""
    if not task.causes:
        return {}
    flags = res.gross_error
    observed = np.isfinite(task.values)
    n_observed = max(int(np.count_nonzero(observed)), 1)
    any_cause = np.zeros(flags.size, dtype=bool)
    by_cause, share = {}, {}
    for cause, mask in task.causes.items():
        m = np.asarray(mask, dtype=bool)
        any_cause |= m
        by_cause[cause] = int(np.count_nonzero(flags & m))
        share[cause] = np.count_nonzero(m & observed) / n_observed
    share["any"] = np.count_nonzero(any_cause & observed) / n_observed
    return {
        "by_cause": by_cause,
        "n_explained": int(np.count_nonzero(flags & any_cause)),
        "epoch_share": share,
    }


def _fit_column(
    task: _ColumnTask, cfg: AriConfig, further: bool = True
) -> tuple[dict[str, Any], AriResult, dict[str, Any] | None]:
    """Row (exact estimator, order by BIC; with ``further`` also the paper's estimator and the
    robust process equations on a moving platform), whole-series fit and strip row of one
    column."""
    t0 = time.perf_counter()
    res = fit_ari(task.values, cfg)
    elapsed = time.perf_counter() - t0
    crb_n, crb_e = sigma_bounds(res)
    model_error = (
        np.zeros(task.values.size, dtype=bool) if task.model_error is None else task.model_error
    )
    row: dict[str, Any] = {
        "source": task.source,
        "column": task.column,
        "unit": task.unit,
        "dt_s": task.dt_s,
        "n": int(task.values.size),
        "n_missing": res.n_missing,
        "n_inserted": task.n_inserted,
        "order": [res.p, res.d],
        **_estimates(res, crb_n, crb_e),
        "warnings": identifiability_warnings(res, crb_n, crb_e),
        "n_flagged": res.n_flagged,
        "n_model_error": int(np.count_nonzero(res.gross_error & model_error)),
        "flags_explained": _flag_explanation(task, res),
        "seconds": elapsed,
        "meta": task.meta,
        "paper": None,
        "robust_process": None,
    }
    strip = None
    if res.estimated and further:
        row["paper"] = _paper_fit(task.values, res.p, res.d, cfg)
        if task.kinematic:
            row["robust_process"] = _robust_process_fit(task, res, cfg)
        if task.strip_epochs is not None:
            strip = _strip_row(
                task.source,
                task.column,
                task.values,
                res,
                task.strip_epochs,
                AriConfig(robust_process=cfg.robust_process),
            )
    return row, res, strip


def real_data_rows(
    sources: Sequence[RealSeries],
    config: AriConfig | None = None,
    *,
    track: Callable[[Sequence[Any], str], Iterable[Any]] | None = None,
    workers: int = 1,
    strips: list[dict[str, Any]] | None = None,
    further: bool = True,
) -> tuple[list[dict[str, Any]], dict[tuple[str, str], AriResult]]:
    """Fit every column of every source; one table row per column (paper Tables 1–5).

    Each column is fitted by the exact-likelihood estimator (order by BIC), then by the
    paper's estimator at that order (``row["paper"]``); both with the Cramér–Rao bounds of
    ``sigma_n``, ``sigma_e`` at their estimate
    (:func:`navtrack.smoothing.identifiability.sigma_bounds`) and the identifiability
    warnings. On a moving platform (``meta["kinematic"]``: attitude, vehicle tracks, the
    walking rover — where the paper's edges and discontinuities are) both estimators are run
    again with the other treatment of the process equations (3) than ``config``'s
    (``row["robust_process"]``, :func:`_robust_process_fit`).
    Flags at epochs the source marks as outside the model (``meta["model_error"]``:
    Euler-angle artefacts of attitude near gimbal lock) are counted apart as
    ``n_model_error``; flags at epochs of each of ``meta["flag_causes"]`` are counted in
    ``row["flags_explained"]``. The paper's estimator gets the series without its leading and
    trailing missing epochs (its conditional model starts at an observation: a leading gap
    leaves the first ``p + d`` states pinned only by decayed modes, a numerically singular
    system).

    Parameters
    ----------
    sources : sequence of RealSeries
    config : AriConfig, optional
        Settings of the whole-series fits (default: order by BIC over ``d = 1, 2``, process
        equations not reweighted).
    track : callable, optional
        ``track(items, desc)`` wraps the loop over the columns, e.g. in a progress bar
        (:meth:`~navtrack.experiments.contract.ExperimentContext.track`).
    workers : int
        Columns are fitted in this many processes (1: in this one).
    strips : list, optional
        When given, the :func:`strip_rows` rows of the columns long enough are appended to it
        (computed in the same task as the column).
    further : bool
        Also the paper's estimator and the robust process equations (off: the exact estimator
        only, e.g. for a comparison of two forms of the same data).
    """
    cfg = AriConfig(min_d=1, select_n=10000) if config is None else config
    if workers < 1:
        raise ValueError(f"workers: expected >= 1, got {workers}")
    tasks = [_column_task(src, col, strips is not None) for src in sources for col in src.columns]
    # longest series first, so that the pool ends together
    order = sorted(range(len(tasks)), key=lambda k: -tasks[k].values.size)
    done: dict[int, tuple[dict[str, Any], AriResult, dict[str, Any] | None]] = {}
    if workers == 1 or len(tasks) < 2:
        for k in order if track is None else track(order, "real series"):
            done[k] = _fit_column(tasks[k], cfg, further)
    else:
        with ProcessPoolExecutor(max_workers=workers) as pool:
            futures = [(k, pool.submit(_fit_column, tasks[k], cfg, further)) for k in order]
            for k, fut in futures if track is None else track(futures, "real series"):
                done[k] = fut.result()
    rows = [done[k][0] for k in range(len(tasks))]
    fits = {(t.source, t.column): done[k][1] for k, t in enumerate(tasks)}
    if strips is not None:
        strips += [done[k][2] for k in range(len(tasks)) if done[k][2] is not None]  # type: ignore[misc]
    return rows, fits


def _robust_process_fit(task: _ColumnTask, whole: AriResult, cfg: AriConfig) -> dict[str, Any]:
    """Both estimators at the order of ``whole`` with the other treatment of the process
    equations (3) than ``cfg``'s (reweighted when ``cfg`` does not, and vice versa: the
    paper's treatment of edges and discontinuities beside the observations-only one); the
    paper's in ``"paper"``, on the series without its leading and trailing missing epochs (as
    :func:`_paper_fit`). ``"reweighted"`` says which treatment the record holds."""
    rp_cfg = dataclasses.replace(
        cfg, order=(whole.p, whole.d), robust_process=not cfg.robust_process
    )
    t0 = time.perf_counter()
    res = fit_ari(task.values, rp_cfg)
    out = _process_record(res) | {
        "reweighted": rp_cfg.robust_process,
        "flags_explained": _flag_explanation(task, res),
        "seconds": time.perf_counter() - t0,
    }
    seen = np.flatnonzero(np.isfinite(task.values))
    t0 = time.perf_counter()
    paper = fit_ari(
        task.values[seen[0] : seen[-1] + 1], dataclasses.replace(rp_cfg, estimator="paper")
    )
    out["paper"] = _process_record(paper) | {"seconds": time.perf_counter() - t0}
    return out


def _process_record(res: AriResult) -> dict[str, Any]:
    """Sigmas, flags and down-weighted process equations of a fit with ``robust_process``."""
    return {
        "status": str(res.status),
        "sigma_n": res.sigma_n,
        "sigma_e": res.sigma_e,
        "sigma_x": res.sigma_x_rms,
        "n_flagged": res.n_flagged,
        "n_process_downweighted": int(np.count_nonzero(res.process_weight < 0.5)),
        "n_process": int(res.process_weight.size),
    }


def _estimates(res: AriResult, crb_n: float, crb_e: float) -> dict[str, Any]:
    """Status, variance components, σx, r(h) and their Cramér–Rao bounds of one fit."""
    return {
        "status": str(res.status),
        "sigma_n": res.sigma_n,
        "sigma_e": res.sigma_e,
        "sigma_x": res.sigma_x_rms,
        "r": [float(v) for v in res.autocorr],
        "crb_sigma_n": crb_n,
        "crb_sigma_e": crb_e,
        "n_process_downweighted": int(np.count_nonzero(res.process_weight < 0.5)),
        "n_process": int(res.process_weight.size),
    }


def _paper_fit(values: FloatArray, p: int, d: int, cfg: AriConfig) -> dict[str, Any]:
    """The paper's estimator on one real column at the order ``(p, d)`` found by the exact one."""
    seen = np.flatnonzero(np.isfinite(values))
    t0 = time.perf_counter()
    res = fit_ari(
        values[seen[0] : seen[-1] + 1], dataclasses.replace(cfg, order=(p, d), estimator="paper")
    )
    elapsed = time.perf_counter() - t0
    crb_n, crb_e = sigma_bounds(res, conditional=True)
    return {
        **_estimates(res, crb_n, crb_e),
        "n_flagged": res.n_flagged,
        "n_iter": res.n_iter,
        "seconds": elapsed,
        "trimmed_epochs": int(values.size - (seen[-1] + 1 - seen[0])),
    }


def default_real_sources(
    shared: Path, spp_runs: Sequence[SppRun] = SPP_RUNS, attitude_form: AttitudeForm = "rotvec"
) -> tuple[list[RealSeries], list[str]]:
    """The shared real data sets that are present; also a list of what was skipped and why.

    BROAD trials 02 and 07 in ``attitude_form``
    (:func:`navtrack.experiments.ari.broad.broad_series`), the pyins track, and for every run
    of ``spp_runs``: RTKLIB's stored solution and navtrack's own SPP solution of the same
    observation and navigation files (:func:`spp_series`), each as ENU about its mean.
    """
    sources: list[RealSeries] = []
    skipped: list[str] = []
    broad = shared / "trajectory" / "broad"
    for name in ("02_undisturbed_slow_rotation_B.mat", "07_undisturbed_fast_rotation_B.mat"):
        path = broad / name
        if path.exists():
            sources.append(broad_series(path, decimate=10, form=attitude_form))
        else:
            skipped.append(str(path))
    path = shared / "trajectory" / "pyins_gnss" / "gnss.csv"
    if path.exists():
        sources.append(pyins_series(path))
    else:
        skipped.append(str(path))
    gnss = shared / "gnss"
    for run in spp_runs:
        path = gnss / "rtklib_spp" / f"{run.name}.pos"
        if path.exists():
            src = solution_series(path)
            meta = {
                **src.meta,
                "solver": "RTKLIB 2.4.3 b34",
                "run": run.name,
                "kinematic": run.kinematic,
                "solved": int(np.count_nonzero(np.isfinite(src.columns["e_m"]))),
            }
            sources.append(
                RealSeries(
                    f"RTKLIB {run.name}",
                    src.t_s,
                    src.columns,
                    src.unit,
                    src.dt_s,
                    src.n_inserted,
                    meta,
                )
            )
        else:
            skipped.append(f"{path}: RTKLIB solution absent")
        missing = [str(gnss / p) for p in (run.obs, *run.nav) if not (gnss / p).exists()]
        if missing:
            skipped.append(f"navtrack SPP {run.name}: input absent ({', '.join(missing)})")
        else:
            try:
                sources.append(spp_series(gnss, run))
            except (ValueError, FileFormatError) as exc:  # unreadable file, nothing solved
                skipped.append(f"navtrack SPP {run.name}: {exc}")
    return sources, skipped


def table2_rows(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Paper Table 2 on the GNSS series: ARI ``sigma_n`` (both estimators) beside the RMS of
    the single-epoch least-squares standard deviations of the same coordinate."""
    out = []
    for row in rows:
        ls = (row.get("meta") or {}).get("ls_sd_rms_m")
        if not ls or row["column"] not in ls:
            continue
        paper = row.get("paper") or {}
        out.append(
            {
                "source": row["source"],
                "column": row["column"],
                "sigma_n": row["sigma_n"],
                "paper_sigma_n": paper.get("sigma_n"),
                "ls_sd_rms": ls[row["column"]],
                "ratio": row["sigma_n"] / ls[row["column"]] if ls[row["column"]] > 0 else None,
                "paper_ratio": (
                    paper["sigma_n"] / ls[row["column"]]
                    if paper.get("sigma_n") is not None and ls[row["column"]] > 0
                    else None
                ),
            }
        )
    return out


def strip_rows(
    sources: Sequence[RealSeries],
    fits: dict[tuple[str, str], AriResult],
    config: AriConfig | None = None,
    max_strips: int = 6,
) -> list[dict[str, Any]]:
    """Paper Table 1: each series long enough cut into strips, one fit per strip, rms over
    strips.

    Strips are consecutive, of :data:`STRIP_EPOCHS` epochs (the paper's 130 GPS registrations;
    400 for attitude, within the Shuttle's 120–800), at most ``max_strips`` from the start; a
    strip more than 20 % missing is skipped. Each strip is fitted at the order found on the
    whole series (robust weights) by both estimators, the exact-likelihood one and the
    paper's (``paper_*``; NaN where it fails, which makes its rms NaN).
    """
    cfg = AriConfig() if config is None else config
    out = []
    for src in sources:
        length = STRIP_EPOCHS.get(src.unit, 130)
        for col, values in src.columns.items():
            whole = fits.get((src.source, col))
            if whole is None or not whole.estimated or values.size < 2 * length:
                continue
            row = _strip_row(src.source, col, values, whole, length, cfg, max_strips)
            if row is not None:
                out.append(row)
    return out


def _strip_row(
    source: str,
    column: str,
    values: FloatArray,
    whole: AriResult,
    length: int,
    cfg: AriConfig,
    max_strips: int = 6,
) -> dict[str, Any] | None:
    """One :func:`strip_rows` row: ``values`` cut into strips of ``length`` epochs, each fitted
    at the order of ``whole``; ``None`` when no strip could be fitted."""
    sigmas: list[float] = []
    paper: list[float] = []
    for k in range(min(max_strips, values.size // length)):
        part = values[k * length : (k + 1) * length]
        if np.count_nonzero(np.isnan(part)) > 0.2 * length:
            continue
        res = fit_ari(part, dataclasses.replace(cfg, order=(whole.p, whole.d)))
        if not res.estimated:
            continue
        sigmas.append(res.sigma_n)
        seen = np.flatnonzero(np.isfinite(part))  # the paper's estimator starts at an epoch
        res = fit_ari(
            part[seen[0] : seen[-1] + 1],
            dataclasses.replace(cfg, order=(whole.p, whole.d), estimator="paper"),
        )
        paper.append(res.sigma_n if res.estimated else math.nan)
    if not sigmas:
        return None
    return {
        "source": source,
        "column": column,
        "order": [whole.p, whole.d],
        "strip_epochs": length,
        "sigma_n_strips": sigmas,
        "rms_sigma_n": float(np.sqrt(np.mean(np.square(sigmas)))),
        "paper_sigma_n_strips": paper,
        "paper_rms_sigma_n": float(np.sqrt(np.mean(np.square(paper)))),
        "whole_sigma_n": whole.sigma_n,
    }


_COMPARED = ("n", "n_missing", "order", "sigma_n", "sigma_e", "sigma_x", "r", "n_flagged", "status")


def spp_comparison(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """navtrack's and RTKLIB's SPP rows of the same run and column side by side."""
    by_key: dict[tuple[str, str], dict[str, dict[str, Any]]] = {}
    for row in rows:
        meta = row.get("meta") or {}
        if "run" not in meta:
            continue
        solver = "navtrack" if meta.get("solver") == "navtrack" else "rtklib"
        by_key.setdefault((meta["run"], row["column"]), {})[solver] = row
    out = []
    for (run, col), pair in by_key.items():
        rec: dict[str, Any] = {"run": run, "column": col}
        for solver in ("navtrack", "rtklib"):
            found = pair.get(solver)
            if found is None:
                rec[solver] = None
                continue
            rec[solver] = {k: found[k] for k in _COMPARED} | {
                "solved": found["meta"].get("solved"),
                "kinematic": found["meta"].get("kinematic"),
            }
        out.append(rec)
    return out
