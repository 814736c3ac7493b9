"""``navtrack track FILE [--format ais|opensky|csv] [--columns NAME=COLUMN,...]``: multi-target
tracking of real detections (the layout detected from the header unless given).

Detections are converted to a local east/north frame, tracked with their ids hidden, and the
confirmed tracks are scored against the ids (CLEAR-MOT MOTA/MOTP, id switches, fragmentation,
purity, HOTA) on a regular grid of report times where each id's true position is interpolated
between its own reports.

The tracker model is ``--preset auto`` unless a preset is named: chosen and tuned from the
detections without their ids (:mod:`navtrack.tracking.trackers.autotune`); the model options
override single values of the preset. The model as used is printed and written with ``--out`` (a
``.json`` beside a ``.csv``; in a ``.parquet`` file, the frame's ``attrs["navtrack"]``
as JSON, read back by ``pandas.read_parquet(F).attrs``).
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from tqdm import tqdm

from navtrack.cli.outputs import check_outputs
from navtrack.data import sample_path
from navtrack.errors import FileFormatError
from navtrack.geodesy import enu_rotation
from navtrack.io.tracks import (
    TrackDetections,
    detect_format,
    local_enu_to_geodetic,
    read_tracks,
    stale_repeats,
    to_local_enu,
    velocity_local_enu,
)
from navtrack.timescale import gps_to_utc, to_datetime64
from navtrack.tracking.models import constant_velocity
from navtrack.tracking.scoring import ScoringRule, score_tracks, scoring_rule
from navtrack.tracking.trackers.autotune import AutoTune, auto_config
from navtrack.tracking.trackers.tracker import (
    DET_STATUS_NAMES,
    TRACK_END_NAMES,
    TrackerConfig,
    TrackerResult,
    run_tracker,
)

MAX_REPORT_FRAMES = 1_000_000  # scoring grid size refused before it is allocated
EXAMPLE = "SolentAIS_20160112_130211_20min.csv"
"""The bundled example (``navtrack/data/README.md``)."""


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "track",
        help="track real AIS / ADS-B / CSV detections and score against their ids",
        description="Run the GNN or JPDA multi-target tracker on real position reports (ids "
        "hidden from the tracker) and score the confirmed tracks against the ids.",
    )
    p.add_argument("file", type=Path, nargs="?", help="detections file (CSV)")
    p.add_argument(
        "--example",
        action="store_true",
        help=f"track the bundled {EXAMPLE}: 20 minutes of AIS reports of 79 ships in The Solent",
    )
    p.add_argument(
        "--format",
        dest="fmt",
        choices=("ais", "opensky", "csv"),
        help="ais = Solent AIS CSV; opensky = OpenSky states CSV; csv = generic "
        "(time ISO 8601 UTC, lat/lon deg or x_m/y_m, optional id, alt_m, speed_mps, "
        "course_deg); default: detected from the header",
    )
    p.add_argument(
        "--columns",
        metavar="NAME=COLUMN,...",
        help="the generic layout's columns in this file, e.g. "
        "'time=Time,lat=latitude,lon=longitude,alt_m=altitude (m)' (implies --format csv)",
    )
    _add_model_options(p)
    p.add_argument("--out", type=Path, help="write track states to this .csv or .parquet file")
    p.add_argument("--plot", type=Path, metavar="DIR", help="write a map of the tracks here")
    p.add_argument(
        "--report-s",
        type=float,
        help="scoring grid interval, s (default: the median over the ids of their median "
        "report interval, 1-60 s; navtrack.tracking.scoring)",
    )
    p.add_argument(
        "--match-m",
        type=float,
        help="match threshold of CLEAR-MOT, HOTA and IDF1, m (default: 500)",
    )
    p.add_argument(
        "--no-velocity",
        action="store_true",
        help="do not use reported speed/course for one-point track initiation",
    )
    p.add_argument(
        "--keep-stale",
        action="store_true",
        help="track reports that repeat an earlier position while their reported speed says "
        "the target moved on (skipped by default: they are not measurements at their time)",
    )
    p.add_argument(
        "--max-range-km",
        type=float,
        default=1000.0,
        help="skip rows farther than this from the median position",
    )
    p.add_argument(
        "--max-time-days",
        type=float,
        default=30.0,
        help="skip rows dated farther than this from the median time",
    )
    p.add_argument(
        "--quiet", action="store_true", help="no progress indicator on stderr while tracking"
    )
    p.set_defaults(func=run_track)


def _add_model_options(p: argparse.ArgumentParser) -> None:
    """``--associator`` and the tracker model group."""
    p.add_argument(
        "--associator",
        choices=("gnn", "jpda"),
        default="gnn",
        help="data association: global nearest neighbour or joint probabilistic",
    )
    m = p.add_argument_group(
        "tracker model",
        "--preset auto (the default) chooses and tunes the model from the detections without "
        "their ids (navtrack.tracking.trackers.autotune); ships / aircraft are the presets "
        "tuned on the "
        "Solent AIS / OpenSky files. The options below override the preset's values.",
    )
    m.add_argument("--preset", choices=("auto", "ships", "aircraft"), default="auto")
    m.add_argument(
        "--motion",
        choices=("cv", "imm"),
        help="cv = one nearly-constant-velocity model; imm = IMM of a quiet and a "
        "manoeuvring CV model",
    )
    m.add_argument(
        "--q",
        metavar="Q[,Q_HI]",
        help="process-noise PSD per axis, m^2/s^3 (imm: quiet,manoeuvring)",
    )
    m.add_argument("--sigma-m", type=float, help="measurement noise per axis, m")
    m.add_argument("--pd", type=float, help="detection probability per scan, in (0, 1)")
    m.add_argument("--clutter-density", type=float, help="competing-report density, 1/m^2")
    m.add_argument(
        "--confirm",
        metavar="M/W",
        help="confirm a track after M updates within W seconds of its birth (e.g. 3/900)",
    )
    m.add_argument("--max-coast-s", type=float, help="delete a track after this long unupdated")
    m.add_argument("--gate-prob", type=float, help="chi-square gate probability, in (0, 1)")


def _column_map(text: str | None) -> dict[str, str]:
    """``--columns time=Time,lat=latitude`` as a mapping (empty without the option)."""
    if not text:
        return {}
    out: dict[str, str] = {}
    for item in text.split(","):
        name, sep, column = item.partition("=")
        if not sep or not name.strip() or not column.strip():
            raise SystemExit(f"navtrack track: --columns: expected NAME=COLUMN, got {item!r}")
        out[name.strip()] = column.strip()
    return out


def run_track(args: argparse.Namespace) -> int:
    _check_options(args)
    det, t_read = _read(args)
    summary: dict[str, Any] = det.summary()
    if len(det) == 0:
        return _no_detections(summary, det)
    en, ref = to_local_enu(det)
    # truth: each id's own reports, its stale repeats left out (navtrack.tracking.scoring)
    fresh = ~stale_repeats(det.t_gps_s, en, det.speed_mps, det.id)
    rule = scoring_rule(det.t_gps_s[fresh], det.id[fresh])
    rule = ScoringRule(
        rule.report_s if args.report_s is None else args.report_s,
        rule.max_gap_s,
        rule.match_m if args.match_m is None else args.match_m,
    )
    vel = None if args.no_velocity else velocity_local_enu(det, *ref) if det.geodetic else None
    if vel is not None and not np.isfinite(vel).any():
        vel = None
    for key, value in input_warnings(det, en).items():
        summary[key] = value
        print(f"navtrack track: {key}: {value}", file=sys.stderr)
    use = ~_stale(args, det, en, summary)
    clock = time.perf_counter()
    cfg, tune = model_config(args, det.t_gps_s, en, vel)  # tuned on the reports as read
    t_tune = time.perf_counter() - clock
    grid = _report_grid(det.t_gps_s, rule.report_s)
    clock = time.perf_counter()
    with _progress(len(det), quiet=args.quiet) as progress:
        res = run_tracker(
            det.t_gps_s[use],
            en[use],
            cfg,
            report_times=grid,
            velocity=None if vel is None else vel[use],
            progress=progress,
        )
    t_track = time.perf_counter() - clock
    summary["reference (lat, lon deg)"] = f"{ref[0]:.6f} {ref[1]:.6f}"
    summary["associator"] = args.associator
    model = model_summary(args.preset, cfg, tune)
    summary.update(model)
    summary.update(_run_lines(args.associator, vel, res))
    if np.any(det.id != ""):
        args_truth = (det.t_gps_s[fresh], en[fresh], det.id[fresh])
        summary.update(_score_lines(grid, args_truth, res, rule))
    summary["time read / tune / track (s)"] = f"{t_read:.2f} {t_tune:.2f} {t_track:.2f}"
    _print(summary)
    if args.out:
        meta = {"associator": args.associator, **model}
        table = _write(args.out, res, ref, meta, det.t_gps_s[use], det.alt_m[use])
        print(f"tracks written to {args.out}, one row per track to {table}")
    if args.plot:
        from navtrack.plots.tracks import plot_tracks  # matplotlib: imported when asked for

        path = plot_tracks(
            args.plot, en[use], res, title=f"{args.file.name} ({args.associator})", ref_deg=ref
        )
        print(f"plot written to {path}")
    return 0


def _check_options(args: argparse.Namespace) -> None:
    """Refuse non-positive numeric options, resolve ``--example``, check the outputs' paths."""
    for name, value in (
        ("--report-s", args.report_s),
        ("--match-m", args.match_m),
        ("--max-range-km", args.max_range_km),
        ("--max-time-days", args.max_time_days),
    ):
        if value is not None and not value > 0:  # also refuses NaN
            raise SystemExit(f"navtrack track: {name} must be a positive number, got {value:g}")
    if args.example:
        if args.file is not None:
            raise SystemExit("navtrack track: give either FILE or --example, not both")
        args.file = sample_path(EXAMPLE)
    if args.file is None:
        raise SystemExit("navtrack track: give a detections FILE, or --example")
    check_outputs("navtrack track", args.out, (".csv", ".parquet"), args.plot)


def _read(args: argparse.Namespace) -> tuple[TrackDetections, float]:
    """The detections of ``args.file`` in the layout given or detected, and the reading time."""
    columns = _column_map(args.columns)
    if args.fmt is None:
        args.fmt = "csv" if columns else detect_format(args.file)
        print(f"format     {args.fmt} (from the header; --format overrides)")
    elif columns and args.fmt != "csv":
        raise SystemExit(f"navtrack track: --columns applies to --format csv, not {args.fmt}")
    clock = time.perf_counter()
    try:
        det = read_tracks(args.file, args.fmt, args.max_range_km, args.max_time_days, columns)
    except ValueError as exc:
        if isinstance(exc, FileFormatError):
            raise
        raise SystemExit(f"navtrack track: --{exc}") from None
    return det, time.perf_counter() - clock


def _no_detections(summary: dict[str, Any], det: TrackDetections) -> int:
    _print(summary)
    skipped = len(det.bad_lines)
    print(
        "no usable detections"
        + (
            f": all {skipped} rows were skipped (reasons above; --max-range-km and "
            "--max-time-days set how far from the median position and time a row may lie)"
            if skipped
            else ""
        )
    )
    return 1


def _stale(args: argparse.Namespace, det: TrackDetections, en: Any, summary: dict[str, Any]) -> Any:
    """The stale repeats the tracker skips (none with ``--keep-stale``), with their lines."""
    stale = stale_repeats(det.t_gps_s, en, det.speed_mps)
    if args.keep_stale:
        if stale.any():
            key = "warning: stale repeats kept"
            summary[key] = f"{int(stale.sum())} reports repeat an earlier position (--keep-stale)"
            print(f"navtrack track: {key}: {summary[key]}", file=sys.stderr)
        stale[:] = False
    summary["stale repeats skipped"] = int(stale.sum())
    return stale


def _report_grid(t_s: Any, report_s: float) -> Any:
    """The scoring frame times, refused when there would be more than ``MAX_REPORT_FRAMES``."""
    t0 = t_s[0]
    n_frames = int((t_s[-1] - t0) // report_s) + 1
    if n_frames > MAX_REPORT_FRAMES:
        raise SystemExit(
            f"navtrack track: --report-s {report_s:g} over {t_s[-1] - t0:.0f} s of "
            f"detections gives {n_frames} report times, more than {MAX_REPORT_FRAMES}; "
            "give a larger --report-s (or a smaller --max-time-days)"
        )
    return t0 + np.arange(0.0, t_s[-1] - t0 + 1e-9, report_s)


def _run_lines(associator: str, vel: Any, res: TrackerResult) -> dict[str, Any]:
    """Summary lines of the run: velocities used, scans, fates, births, deletions."""
    status = np.bincount(res.det_status, minlength=len(DET_STATUS_NAMES))
    out: dict[str, Any] = {
        "reported velocity used for initiation": (
            "no" if vel is None else f"yes ({int(np.isfinite(vel).all(axis=1).sum())} rows)"
        ),
        "scans": res.counts.scans,
        "detections by fate": {n: int(c) for n, c in zip(DET_STATUS_NAMES, status, strict=True)},
        "tracks started / confirmed": (
            f"{res.counts.tracks_started} / {res.counts.tracks_confirmed}"
        ),
        "tracks deleted (coast, covariance, unconfirmed)": (
            f"{res.counts.deleted_coast} {res.counts.deleted_covariance} "
            f"{res.counts.deleted_unconfirmed}"
        ),
        "tracks continuing an ended track": res.counts.tracks_continued,
    }
    if associator == "jpda":
        out["jpda clusters (exact, k-best)"] = (
            f"{res.counts.jpda_exact_clusters} {res.counts.jpda_kbest_clusters}"
        )
    return out


def _score_lines(
    grid: Any, truth: tuple[Any, Any, Any], res: TrackerResult, rule: ScoringRule
) -> dict[str, Any]:
    """Summary lines of the scores of the confirmed tracks against the ids' own reports."""
    scores = score_tracks(grid, *truth, res.report_frame, res.report_id, res.report_xy, rule)
    return {
        "scoring": (
            f"{len(grid)} frames every {rule.report_s:g} s, match within {rule.match_m:g} m, "
            f"truth interpolated over gaps <= {rule.max_gap_s:g} s"
        ),
        "MOTA": round(scores.mota, 4),
        "HOTA (DetA, AssA)": (
            f"{scores.hota:.4f} ({scores.det_a:.4f}, {scores.ass_a:.4f}; similarity 1 - d / match)"
        ),
        "IDF1 (IDP, IDR)": f"{scores.idf1:.4f} ({scores.idp:.4f}, {scores.idr:.4f})",
        "MOTP (m)": round(scores.motp_m, 1),
        "truth objects / matches / misses / false": (
            f"{scores.n_truth} {scores.n_matches} {scores.n_misses} {scores.n_false}"
        ),
        "id switches": scores.id_switches,
        "fragmentations": scores.fragmentations,
        "track purity": round(scores.purity, 4),
        "ids / confirmed tracks": (
            f"{scores.n_ids} / {res.counts.tracks_confirmed - res.counts.tracks_continued}"
        ),
    }


PROGRESS_MIN_DETECTIONS = 5000  # files this long take seconds: show that the tracker runs


@contextlib.contextmanager
def _progress(n_detections: int, *, quiet: bool) -> Iterator[Callable[[int], object] | None]:
    """A progress bar on stderr over the detections tracked, fed by ``run_tracker(progress=)``.

    Off (yields ``None``) with ``--quiet`` and for files under :data:`PROGRESS_MIN_DETECTIONS`
    rows; tqdm hides it when stderr is not a terminal (``disable=None``).
    """
    if quiet or n_detections < PROGRESS_MIN_DETECTIONS:
        yield None
        return
    with tqdm(
        total=n_detections, desc="tracking", unit=" det", file=sys.stderr, disable=None, leave=False
    ) as bar:
        yield bar.update


def _positive(name: str, value: float | None, upper: float | None = None) -> None:
    if value is not None and not (value > 0 and (upper is None or value < upper)):
        bound = f"in (0, {upper:g})" if upper is not None else "a positive number"
        raise SystemExit(f"navtrack track: {name} must be {bound}, got {value:g}")


def model_config(
    args: argparse.Namespace, t_s: Any, en: Any, vel: Any
) -> tuple[TrackerConfig, AutoTune | None]:
    """The tracker config of ``--preset`` with the model options applied over it, and the
    :class:`~navtrack.tracking.trackers.autotune.AutoTune` when the preset is ``auto``
    (else None)."""
    _positive("--sigma-m", args.sigma_m)
    _positive("--pd", args.pd, 1.0)
    _positive("--clutter-density", args.clutter_density)
    _positive("--max-coast-s", args.max_coast_s)
    _positive("--gate-prob", args.gate_prob, 1.0)
    q = _floats("--q", args.q)
    confirm = _confirm(args.confirm)
    tune = None
    if args.preset == "ships":
        cfg = TrackerConfig.for_ships(args.associator)
    elif args.preset == "aircraft":
        cfg = TrackerConfig.for_aircraft(args.associator)
    else:
        tune = auto_config(t_s, en, vel, args.associator)
        cfg = tune.config
    over: dict[str, Any] = {}
    motion = args.motion or ("imm" if cfg.imm_q is not None else "cv")
    qs = q or ((cfg.imm_q[-1],) if cfg.imm_q is not None else (cfg.motion.q,))
    if motion == "imm":
        if len(qs) == 1:
            qs = (qs[0] * 1e-3, qs[0])  # the ship preset's ratio of quiet to manoeuvring
        if len(qs) != 2:
            raise SystemExit(
                f"navtrack track: --motion imm takes --q QUIET,MANOEUVRING, got {args.q}"
            )
        over["imm_q"] = tuple(qs)
        over["motion"] = constant_velocity(2, qs[0], "continuous")
    else:
        if len(qs) != 1:
            raise SystemExit(f"navtrack track: --motion cv takes one --q value, got {args.q}")
        over["imm_q"] = None
        over["motion"] = constant_velocity(2, qs[0], "continuous")
    for key, value in (
        ("sigma_m", args.sigma_m),
        ("pd", args.pd),
        ("clutter_density", args.clutter_density),
        ("max_coast_s", args.max_coast_s),
        ("gate_probability", args.gate_prob),
    ):
        if value is not None:
            over[key] = value
    if confirm is not None:
        over["confirm_hits"], over["confirm_window_s"] = confirm
    try:
        return dataclasses.replace(cfg, **over), tune
    except ValueError as exc:
        raise SystemExit(f"navtrack track: {exc}") from None


def _floats(name: str, text: str | None) -> tuple[float, ...] | None:
    if text is None:
        return None
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise SystemExit(f"navtrack track: {name} takes numbers, got {text!r}") from None
    if not all(v >= 0 and v < float("inf") for v in values):
        raise SystemExit(f"navtrack track: {name} values must be finite and >= 0, got {text!r}")
    return values


def _confirm(text: str | None) -> tuple[int, float] | None:
    if text is None:
        return None
    m, _, w = text.partition("/")
    try:
        hits, window = int(m), float(w)
    except ValueError:
        raise SystemExit(
            f"navtrack track: --confirm takes M/W (M updates within W s), got {text!r}"
        ) from None
    if hits < 2 or not window > 0:
        raise SystemExit(f"navtrack track: --confirm needs M >= 2 and W > 0, got {text!r}")
    return hits, window


def model_summary(preset: str, cfg: Any, tune: Any) -> dict[str, Any]:
    """The model as used (summary lines; also the output's metadata)."""
    q = cfg.imm_q if cfg.imm_q is not None else (cfg.motion.q,)
    out: dict[str, Any] = {
        "preset": preset,
        "motion": "imm" if cfg.imm_q is not None else "cv",
        "q (m^2/s^3)": ",".join(f"{v:.3g}" for v in q),
        "sigma (m)": round(cfg.sigma_m, 2),
        "pd": cfg.pd,
        "clutter density (1/m^2)": float(f"{cfg.clutter_density:.3g}"),
        "confirm (M/W s)": f"{cfg.confirm_hits}/{cfg.confirm_window_s:.0f}",
        "max coast (s)": round(cfg.max_coast_s, 1),
        "gate probability": cfg.gate_probability,
        "scan window (s)": round(cfg.scan_window_s, 2),
        "track continuation": "on" if cfg.continue_tracks else "off",
    }
    if tune is not None:
        out["auto: report interval p50/p95 (s)"] = (
            f"{tune.report_interval_p50_s:.1f} {tune.report_interval_p95_s:.1f}"
        )
        out["auto: speed p50/p99 (m/s), still share"] = (
            f"{tune.speed_p50_mps:.1f} {tune.speed_p99_mps:.1f} {tune.stationary_share:.2f} "
            f"({tune.speed_source})"
        )
        nf = tune.noise
        out["auto: fitted sigma (m), q (m^2/s^3), residuals"] = (
            f"{nf.sigma_m:.1f} {nf.q:.3g} {nf.n_triplets} ({nf.n_dropped} dropped) on "
            f"{tune.sample_detections} detections"
            if np.isfinite(nf.sigma_m)
            else f"not fitted: {nf.n_triplets} three-point residuals in "
            f"{tune.sample_detections} detections (sigma at its floor)"
        )
        out["auto: q search (q m^2/s^3: births, log-likelihood per detection)"] = ", ".join(
            f"{tr.q:.3g}: {tr.births} {tr.mean_log_likelihood:.3f}" for tr in tune.q_trials
        )
    return out


def input_warnings(det: Any, en: Any) -> dict[str, str]:
    """Summary lines (``warning: ...``) for input the tracker can run on but that is likely
    wrong: all reports at one time, one id reported at one time at two positions, reported
    speeds that disagree with the positions (a knots column read as m/s)."""
    out: dict[str, str] = {}
    t = det.t_gps_s
    n_times = np.unique(t).size
    if n_times == 1 and t.size > 1:
        out["warning: one time"] = (
            f"all {t.size} reports have the same time; nothing can be tracked over time"
        )
    if not np.any(det.id != ""):
        return out
    order = np.lexsort((t, det.id))
    ids, ts, p = det.id[order], t[order], en[order]
    same_id = ids[1:] == ids[:-1]
    dt = np.diff(ts)
    dist = np.hypot(*np.diff(p, axis=0).T)
    dup = same_id & (dt == 0) & (dist > 1.0)
    if dup.any():
        out["warning: one id, one time, two positions"] = (
            f"{int(dup.sum())} report pairs of {np.unique(ids[1:][dup]).size} ids at one time "
            f"differ in position (up to {dist[dup].max():.0f} m, lines "
            f"{', '.join(str(v) for v in det.line[order][1:][dup][:5])}...)"
        )
    speed = det.speed_mps[order]
    ok = same_id & (dt >= 1.0) & np.isfinite(speed[1:]) & (dist > 0)
    if ok.sum() >= 20:
        derived = dist[ok] / dt[ok]
        ratio = float(np.median(speed[1:][ok] / np.maximum(derived, 1e-3)))
        moving = derived > 1.0
        if moving.sum() >= 20:
            ratio = float(np.median(speed[1:][ok][moving] / derived[moving]))
            off = int(np.sum(np.abs(speed[1:][ok][moving] / derived[moving] - 1) > 0.5))
            if not 0.67 < ratio < 1.5:
                hint = " (1.94: knots read as m/s)" if 1.7 < ratio < 2.2 else ""
                out["warning: implausible speeds"] = (
                    f"reported speed / speed between positions is {ratio:.2f} (median of "
                    f"{int(moving.sum())} moving reports; {off} differ by > 50 %){hint}"
                )
    return out


def _print(summary: dict[str, Any]) -> None:
    width = max(len(k) for k in summary)
    for k, v in summary.items():
        if isinstance(v, dict):
            v = "; ".join(f"{a}: {b}" for a, b in v.items()) or "-"
        elif isinstance(v, list):
            v = " ".join(v) or "-"
        print(f"{k:<{width}}  {v}")


def _write(
    path: Path,
    res: TrackerResult,
    ref: tuple[float, float],
    meta: dict[str, Any],
    report_t_s: Any,
    report_alt_m: Any,
) -> Path:
    """Track updates to ``path`` (``.csv`` with the model in a ``.json`` beside it, or
    ``.parquet`` with the model as JSON in the frame's ``attrs["navtrack"]``, which pandas
    keeps in the file) and one row per track to ``<stem>.tracks<suffix>`` beside it; returns
    the path of the per-track table.

    ``report_t_s``, ``report_alt_m``: the tracked reports' times and altitudes (the altitude of
    a row is that of the last report the track took; the tracker is 2-D)."""
    df = _update_rows(res, ref, report_t_s, report_alt_m)
    per = _track_table(df, res)
    meta = {"reference_lat_deg": ref[0], "reference_lon_deg": ref[1], **meta}
    table = path.with_name(f"{path.stem}.tracks{path.suffix}")
    if path.suffix == ".parquet":
        df.attrs["navtrack"] = json.dumps(meta)
        df.to_parquet(path, index=False)
        per.to_parquet(table, index=False)
    else:
        df.to_csv(path, index=False)
        per.to_csv(table, index=False)
        Path(f"{path}.json").write_text(json.dumps(meta, indent=1) + "\n")
    return table


def _utc(t_s: Any) -> Any:
    """GPS seconds as ISO 8601 UTC text."""
    return pd.to_datetime(to_datetime64(gps_to_utc(t_s))).strftime("%Y-%m-%dT%H:%M:%S.%fZ")


def _update_rows(
    res: TrackerResult, ref: tuple[float, float], report_t_s: Any, report_alt_m: Any
) -> pd.DataFrame:
    """One row per track update: state, position on the ellipsoid, speed, course, altitude."""
    x = res.track_x
    df = pd.DataFrame(
        {
            "time": _utc(res.track_time_s),
            "track_id": res.track_id,
            "confirmed": res.track_confirmed,
            "p_update": res.track_p_update,
            "x_m": x[:, 0],
            "y_m": x[:, 2],
            "vx_mps": x[:, 1],
            "vy_mps": x[:, 3],
            "std_m": res.track_std_m,
        }
    )
    v_en = x[:, [1, 3]]
    if np.isfinite(ref[0]):
        latlon = local_enu_to_geodetic(x[:, [0, 2]], ref[0], ref[1])
        df["lat_deg"] = latlon[:, 0]
        df["lon_deg"] = latlon[:, 1]
        # the velocity from the reference's east/north into the track's own
        r0 = enu_rotation(np.radians(ref[0]), np.radians(ref[1]))
        r_i = enu_rotation(np.radians(latlon[:, 0]), np.radians(latlon[:, 1]))
        v_ecef = v_en @ r0[:2]
        v_en = np.einsum("nij,nj->ni", r_i[:, :2], v_ecef)
    df["speed_mps"] = np.hypot(v_en[:, 0], v_en[:, 1])
    df["course_deg"] = np.mod(np.degrees(np.arctan2(v_en[:, 0], v_en[:, 1])), 360.0)
    took = res.det_track >= 0
    if np.isfinite(report_alt_m).any():
        rows = pd.DataFrame({"t": res.track_time_s, "track_id": res.track_id})
        rows["row"] = np.arange(len(rows))
        reps = pd.DataFrame(
            {"t": report_t_s[took], "track_id": res.det_track[took], "alt_m": report_alt_m[took]}
        )
        both = pd.merge_asof(
            rows.sort_values("t"), reps.sort_values("t"), on="t", by="track_id"
        ).sort_values("row")
        df["alt_m"] = both["alt_m"].to_numpy()
    return df


def _track_table(df: pd.DataFrame, res: TrackerResult) -> pd.DataFrame:
    """One row per track: first and last update, updates, reports taken, confirmed, mean
    position standard deviation, end time and reason."""
    took = res.det_track >= 0
    per = df.groupby("track_id").agg(
        first_update=("time", "first"),
        last_update=("time", "last"),
        updates=("time", "size"),
        confirmed=("confirmed", "max"),
        mean_std_m=("std_m", "mean"),
    )
    per["reports"] = pd.Series(res.det_track[took]).value_counts().reindex(per.index, fill_value=0)
    ends = pd.DataFrame(
        {
            "end_time": _utc(res.end_time_s),
            "end_reason": np.asarray(TRACK_END_NAMES)[res.end_reason],
        },
        index=pd.Index(res.end_id, name="track_id"),
    )
    per = per.join(ends, how="outer").reset_index()  # (tracks never updated: ends only)
    per = per.fillna({"updates": 0, "reports": 0, "confirmed": False})
    return per.astype({"updates": int, "reports": int, "confirmed": bool})
