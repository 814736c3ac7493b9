"""The body of ``navtrack smooth`` (:mod:`navtrack.cli.smooth` holds its options)."""

from __future__ import annotations

import argparse
import contextlib
import math
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from tqdm import tqdm

from navtrack.cli.outputs import check_outputs
from navtrack.data import sample_path
from navtrack.errors import FileFormatError
from navtrack.experiments import write_json
from navtrack.geodesy import ecef_to_geodetic, enu_rotation
from navtrack.gnss.rinex.nav import read_nav
from navtrack.gnss.rinex.obs import read_obs
from navtrack.gnss.spp import SppConfig, solution_frame, solve_spp
from navtrack.io.solution import write_solution
from navtrack.io.tables import file_line, numeric_column, read_table
from navtrack.plots.ari import plot_series
from navtrack.plots.canvas import figure_dir
from navtrack.smoothing.ari import AriConfig, AriResult, fit_ari, regularize_time
from navtrack.smoothing.identifiability import identifiability_warnings, sigma_bounds

_TIME_CANDIDATES = ("t_gps_s", "t_s", "time_s", "time", "t")
_POSITION_COLUMNS = ("x_m", "y_m", "z_m")
_UNIT_SUFFIXES = {
    "_m": "m",
    "_deg": "deg",
    "_rad": "rad",
    "_s": "s",
    "_mps": "m/s",
    "_mps2": "m/s^2",
    "_hz": "Hz",
}


def _unit(column: str) -> str:
    for suffix, unit in sorted(_UNIT_SUFFIXES.items(), key=lambda kv: -len(kv[0])):
        if column.endswith(suffix):
            return unit
    return "(input units)"


def _mostly_numeric(column: Any) -> bool:
    """A column to smooth by default: most of its non-empty fields are numbers (so that a
    stray text line is reported, not the column dropped)."""
    present = column.dropna()
    return bool(present.size) and bool(pd.to_numeric(present, errors="coerce").notna().mean() > 0.5)


def _time_stamps(path: Path, df: Any, column: str) -> Any:
    """The time column (s), every stamp present and later than the one before it.

    Raises
    ------
    FileFormatError
        A missing, non-numeric or infinite stamp, or one that repeats or goes back in time,
        naming its file line (and the line it does not follow).
    """
    t = numeric_column(path, df, column)
    if np.isnan(t).any():
        k = int(np.argmax(np.isnan(t)))
        raise FileFormatError(path, file_line(df, k), f"time column {column!r}: no time stamp")
    back = np.flatnonzero(np.diff(t) <= 0)
    if back.size:
        k = int(back[0])
        what = "repeats" if t[k + 1] == t[k] else "goes back from"
        before = file_line(df, k)
        raise FileFormatError(
            path,
            file_line(df, k + 1),
            f"time {t[k + 1]:.10g} s {what} {t[k]:.10g} s"
            + (f" of line {before}" if before is not None else f" of row {k}")
            + " (times must increase)",
        )
    return t


def _example_solution(folder: Path) -> Path:
    """The single point solution of the bundled 0759 files, written as ``pos --out`` does."""
    obs, nav = sample_path("07590920.05o"), sample_path("07590920.05n")
    result = solve_spp(read_obs(obs), read_nav(nav), config=SppConfig(systems="G"))
    path = folder / "0759_spp.csv"
    write_solution(solution_frame(result), path)
    print(f"example    single point positions of {obs.name} with {nav.name} ({path.name})")
    return path


def _local_frame(path: Path, df: Any, ok: Any) -> tuple[Any, list[str]]:
    """``df`` with ``e_m, n_m, u_m``: the ECEF position about the mean of the ``ok`` rows, in
    its east/north/up frame; prints the origin."""
    xyz = np.column_stack([numeric_column(path, df, c) for c in _POSITION_COLUMNS])
    origin = np.nanmean(xyz[ok], axis=0)
    lat, lon, h = ecef_to_geodetic(origin)
    enu = (xyz - origin) @ enu_rotation(lat, lon).T
    print(
        f"frame      east/north/up about the mean position lat {math.degrees(lat):.8f} deg, "
        f"lon {math.degrees(lon):.8f} deg, h {h:.3f} m (--frame ecef for x/y/z)"
    )
    columns = ["e_m", "n_m", "u_m"]
    return df.assign(**dict(zip(columns, enu.T, strict=True))), columns


def _read_input(args: argparse.Namespace) -> pd.DataFrame:
    """The table to smooth: ``FILE`` or, with ``--example``, the bundled single point solution
    (``args.file`` is set to the file read)."""
    with contextlib.ExitStack() as stack:
        if args.example:
            if args.file is not None:
                raise SystemExit("navtrack smooth: give either FILE or --example, not both")
            args.file = _example_solution(Path(stack.enter_context(tempfile.TemporaryDirectory())))
        if args.file is None:
            raise SystemExit("navtrack smooth: give a FILE, or --example")
        df = read_table(args.file)
    if len(df) == 0:
        raise FileFormatError(args.file, None, "no data rows (a header only)")
    return df


def _ari_config(args: argparse.Namespace) -> AriConfig:
    """The model options of the command line (``--order`` 'auto' or ``P,D``)."""
    if args.order == "auto":
        order = None
    else:
        try:
            p_str, d_str = args.order.split(",")
            order = (int(p_str), int(d_str))
        except ValueError:
            raise SystemExit(
                f"navtrack smooth: --order must be 'auto' or P,D, got {args.order!r}"
            ) from None
    try:
        return AriConfig(
            order=order,
            robust=args.robust,
            robust_process=args.robust_process,
            flag_threshold=args.flag_threshold,
            estimator=args.estimator,
            vce=args.vce,
        )
    except ValueError as exc:
        raise SystemExit(f"navtrack smooth: {exc}") from None


def _time_column(args: argparse.Namespace, df: pd.DataFrame) -> str | None:
    """``--time``, else the first of :data:`_TIME_CANDIDATES` present (None: equally spaced)."""
    if args.time is None:
        return next((c for c in _TIME_CANDIDATES if c in df.columns), None)
    if args.time not in df.columns:
        raise SystemExit(f"navtrack smooth: no time column {args.time!r} in {args.file}")
    return str(args.time)


def _columns(
    args: argparse.Namespace, df: pd.DataFrame, ok: Any, time_col: str | None
) -> tuple[pd.DataFrame, list[str]]:
    """The columns to smooth (``--columns``, the position of a solution file in ``--frame``,
    else every mostly numeric column but the time), with ``df`` extended by the local frame."""
    if args.columns:
        columns = [c for item in args.columns for c in item.split(",") if c]
    elif all(c in df.columns for c in _POSITION_COLUMNS):
        columns = list(_POSITION_COLUMNS)
        if args.frame == "enu":
            df, columns = _local_frame(args.file, df, ok)
    else:
        columns = [
            c
            for c in df.columns
            if c != time_col and _mostly_numeric(df[c]) and not str(c).startswith("Unnamed")
        ]
    missing = [c for c in columns if c not in df.columns]
    if missing:
        raise SystemExit(
            f"navtrack smooth: columns {', '.join(missing)} not in {args.file} "
            f"(has {', '.join(map(str, df.columns))})"
        )
    if not columns:
        raise SystemExit(
            f"navtrack smooth: {args.file}: no numeric columns to smooth; give --columns"
        )
    return df, columns


def _epoch_grid(
    args: argparse.Namespace, df: pd.DataFrame, values: Any, time_col: str | None
) -> tuple[Any, Any]:
    """(t_grid, grid): the values on equally spaced epochs, missing ones inserted into time
    gaps (the epoch index when there is no time column); prints what was read."""
    n_read = values.shape[0]
    if time_col is not None:
        t = _time_stamps(args.file, df, time_col)
        try:
            t_grid, grid, inserted = regularize_time(t, values)
        except ValueError as exc:
            raise SystemExit(f"navtrack smooth: {args.file}: {exc}") from None
    else:
        t_grid, grid, inserted = np.arange(n_read, dtype=float), values, 0
    print(
        f"file       {args.file}: {n_read} epochs"
        + (f", {inserted} missing epochs inserted into time gaps" if inserted else "")
        + (f" (time column {time_col})" if time_col else " (no time column: equally spaced)")
    )
    return t_grid, grid


def _report_column(col: str, res: AriResult, cfg: AriConfig, unit: str) -> dict[str, Any]:
    """Print the fit of one column; its ``results.json`` entry."""
    entry: dict[str, Any] = {**res.summary(), "unit": unit}
    if not res.estimated:
        print(f"{col}: status {res.status} ({res.message})")
        return entry
    r = " ".join(f"{v:.2f}" for v in res.autocorr)
    print(
        f"{col}: status {res.status}, order ({res.p},{res.d}), "
        f"n {res.x.size} (missing {res.n_missing}), "
        f"sigma_n = {res.sigma_n:.4g} {unit}, sigma_e = {res.sigma_e:.4g} {unit}, "
        f"sigma_x = {res.sigma_x_rms:.4g} {unit}, r(1..4) = {r}, "
        f"flagged {res.n_flagged}"
    )
    crb_n, crb_e = sigma_bounds(res, conditional=cfg.estimator == "paper")
    print(f"{col}: Cramér–Rao relative sd sigma_n {crb_n:.1%}, sigma_e {crb_e:.1%}")
    warnings = identifiability_warnings(res, crb_n, crb_e)
    for why in warnings:
        print(f"warning    {col}: {why}")
    return entry | {"crb_rel_sd_sigma_n": crb_n, "crb_rel_sd_sigma_e": crb_e, "warnings": warnings}


def _write_table(out: Path, out_cols: dict[str, Any], summary: dict[str, Any]) -> None:
    """``--out`` (CSV or Parquet) and the JSON summary beside it."""
    table = pd.DataFrame(out_cols)
    if out.suffix.lower() == ".parquet":
        table.to_parquet(out, index=False)
    else:
        table.to_csv(out, index=False, float_format="%.10g")
    write_json(out.with_suffix(".json"), summary)
    print(f"wrote      {out} and {out.with_suffix('.json')}")


def run(args: argparse.Namespace) -> int:
    """``navtrack smooth`` with parsed options ``args``; the exit code."""
    check_outputs("navtrack smooth", args.out, (".csv", ".parquet"), args.plot)
    df = _read_input(args)
    cfg = _ari_config(args)
    time_col = _time_column(args, df)
    not_ok = (
        (df["status"].astype(str).str.strip() != "ok").to_numpy()
        if "status" in df.columns
        else np.zeros(len(df), dtype=bool)
    )
    if not_ok.all():
        raise SystemExit(f"navtrack smooth: {args.file}: no row has status ok")
    df, columns = _columns(args, df, ~not_ok, time_col)
    values = np.column_stack([numeric_column(args.file, df, c) for c in columns])
    values[not_ok] = np.nan
    t_grid, grid = _epoch_grid(args, df, values, time_col)
    if not_ok.any():
        counts = df["status"][not_ok].astype(str).str.strip().value_counts()
        print(
            f"status     {int(not_ok.sum())} rows not ok taken as missing ("
            + ", ".join(f"{name} {n}" for name, n in counts.items())
            + ")"
        )
    out_cols: dict[str, Any] = {} if time_col is None else {time_col: t_grid}
    any_gross = np.zeros(t_grid.size, dtype=bool)
    summary: dict[str, Any] = {"file": str(args.file), "epochs": int(t_grid.size), "columns": {}}
    for k, col in enumerate(columns):
        with tqdm(
            desc=f"{col}: " + ("order search" if cfg.order is None else f"ARI{cfg.order}"),
            unit=" fits",
            disable=args.no_progress,
            leave=False,
        ) as bar:
            res = fit_ari(grid[:, k], cfg, progress=bar.update)
        unit = _unit(col)
        summary["columns"][col] = _report_column(col, res, cfg, unit)
        out_cols[col] = grid[:, k]
        out_cols[f"{col}_filtered"] = res.x
        out_cols[f"{col}_sigma_x"] = res.sigma_x
        out_cols[f"{col}_gross_error"] = res.gross_error
        any_gross |= res.gross_error
        if args.plot is not None and res.estimated:
            path = plot_series(
                figure_dir(args.plot) / f"{args.file.stem}_{col}.png",
                t_grid,
                res,
                col,
                unit,
                time_name=time_col or "epoch index",
            )
            print(f"figure     {path}")
    out_cols["gross_error"] = any_gross
    statuses: dict[str, int] = {}
    for col_summary in summary["columns"].values():
        statuses[col_summary["status"]] = statuses.get(col_summary["status"], 0) + 1
    print(
        "summary    "
        + ", ".join(f"{k} {v}" for k, v in statuses.items())
        + f"; epochs with a gross error {int(any_gross.sum())} of {t_grid.size}"
    )
    if args.out is not None:
        _write_table(args.out, out_cols, summary)
    return 0
