"""``navtrack track FILE --format ais|opensky|csv``: multi-target tracking of real detections.

Detections are converted to a local east/north frame, tracked with their ids hidden, and the
confirmed tracks are scored against the ids (CLEAR-MOT MOTA/MOTP, id switches, fragmentation,
purity) on a regular grid of report times where each id's true position is interpolated
between its own reports.
"""

from __future__ import annotations

import argparse
import contextlib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

DEFAULTS = {
    # report interval (s), max truth gap for interpolation (s), match threshold (m)
    "ais": (60.0, 400.0, 500.0),
    "opensky": (10.0, 60.0, 2000.0),
    "csv": (60.0, 400.0, 500.0),
}
MAX_REPORT_FRAMES = 1_000_000  # scoring grid size refused before it is allocated


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "track",
        help="track real AIS / ADS-B / CSV detections and score against their ids",
        description="Run the GNN or JPDA multi-target tracker on real position reports (ids "
        "hidden from the tracker) and score the confirmed tracks against the ids.",
    )
    p.add_argument("file", type=Path, help="detections file (CSV)")
    p.add_argument(
        "--format",
        dest="fmt",
        choices=("ais", "opensky", "csv"),
        required=True,
        help="ais = Solent AIS CSV; opensky = OpenSky states CSV; csv = generic "
        "(time ISO 8601 UTC, lat/lon deg or x_m/y_m, optional id, alt_m, speed_mps, "
        "course_deg)",
    )
    p.add_argument(
        "--associator",
        choices=("gnn", "jpda"),
        default="gnn",
        help="data association: global nearest neighbour or joint probabilistic",
    )
    p.add_argument("--out", type=Path, help="write track states to this .csv or .parquet file")
    p.add_argument("--plot", type=Path, metavar="DIR", help="write a map of the tracks here")
    p.add_argument(
        "--report-s",
        type=float,
        help="scoring grid interval, s (default: " + _by_format(0) + ")",
    )
    p.add_argument(
        "--match-m",
        type=float,
        help="CLEAR-MOT match threshold, m (default: " + _by_format(2) + ")",
    )
    p.add_argument(
        "--no-velocity",
        action="store_true",
        help="do not use reported speed/course for one-point track initiation",
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


def _by_format(k: int) -> str:
    """One column of :data:`DEFAULTS` as help text: ``60 for ais, 10 for opensky, ...``."""
    return ", ".join(f"{v[k]:g} for {fmt}" for fmt, v in DEFAULTS.items())


def run_track(args: argparse.Namespace) -> int:
    import time

    import numpy as np

    from navtrack.io.tracks import read_tracks, to_local_enu, velocity_local_enu
    from navtrack.tracking.metrics import clear_mot, interpolate_truth
    from navtrack.tracking.tracker import DET_STATUS_NAMES, TrackerConfig, run_tracker

    for name, value in (
        ("--report-s", args.report_s),
        ("--match-m", args.match_m),
        ("--max-range-km", args.max_range_km),
        ("--max-time-days", args.max_time_days),
    ):
        if value is not None and not value > 0:  # also refuses NaN
            raise SystemExit(f"navtrack track: {name} must be a positive number, got {value:g}")
    clock = time.perf_counter()
    det = read_tracks(args.file, args.fmt, args.max_range_km, args.max_time_days)
    t_read = time.perf_counter() - clock
    summary: dict[str, Any] = det.summary()
    if len(det) == 0:
        _print(summary)
        print("no usable detections")
        return 1
    en, ref = to_local_enu(det)
    report_s, max_gap_s, match_m = DEFAULTS[args.fmt]
    report_s = report_s if args.report_s is None else args.report_s
    match_m = match_m if args.match_m is None else args.match_m
    if args.fmt == "opensky":
        cfg = TrackerConfig.for_aircraft(args.associator)
    elif args.fmt == "ais":
        cfg = TrackerConfig.for_ships(args.associator)
    else:
        cfg = TrackerConfig(associator=args.associator)
    t0 = det.t_gps_s[0]
    n_frames = int((det.t_gps_s[-1] - t0) // report_s) + 1
    if n_frames > MAX_REPORT_FRAMES:
        raise SystemExit(
            f"navtrack track: --report-s {report_s:g} over {det.t_gps_s[-1] - t0:.0f} s of "
            f"detections gives {n_frames} report times, more than {MAX_REPORT_FRAMES}; "
            "give a larger --report-s (or a smaller --max-time-days)"
        )
    grid = t0 + np.arange(0.0, det.t_gps_s[-1] - t0 + 1e-9, report_s)
    vel = None if args.no_velocity else velocity_local_enu(det, *ref) if det.geodetic else None
    if vel is not None and not np.isfinite(vel).any():
        vel = None
    clock = time.perf_counter()
    with _progress(len(det), quiet=args.quiet):
        res = run_tracker(det.t_gps_s, en, cfg, report_times=grid, velocity=vel)
    t_track = time.perf_counter() - clock
    status = np.bincount(res.det_status, minlength=len(DET_STATUS_NAMES))
    summary["reference (lat, lon deg)"] = f"{ref[0]:.6f} {ref[1]:.6f}"
    summary["associator"] = args.associator
    summary["reported velocity used for initiation"] = (
        "no" if vel is None else f"yes ({int(np.isfinite(vel).all(axis=1).sum())} rows)"
    )
    summary["scans"] = res.counts.scans
    summary["detections by fate"] = {
        n: int(c) for n, c in zip(DET_STATUS_NAMES, status, strict=True)
    }
    summary["tracks started / confirmed"] = (
        f"{res.counts.tracks_started} / {res.counts.tracks_confirmed}"
    )
    summary["tracks deleted (coast, covariance, unconfirmed)"] = (
        f"{res.counts.deleted_coast} {res.counts.deleted_covariance} "
        f"{res.counts.deleted_unconfirmed}"
    )
    if args.associator == "jpda":
        summary["jpda clusters (exact, k-best)"] = (
            f"{res.counts.jpda_exact_clusters} {res.counts.jpda_kbest_clusters}"
        )
    has_ids = bool(np.any(det.id != ""))
    if has_ids:
        tf, tid, tpos = interpolate_truth(grid, det.t_gps_s, det.id, en, max_gap_s)
        mot = clear_mot(tf, tid, tpos, res.report_frame, res.report_id, res.report_xy, match_m)
        summary["scoring"] = (
            f"{len(grid)} frames every {report_s:g} s, match within {match_m:g} m, "
            f"truth interpolated over gaps <= {max_gap_s:g} s"
        )
        summary["MOTA"] = round(mot.mota, 4)
        summary["MOTP (m)"] = round(mot.motp, 1)
        summary["truth objects / matches / misses / false"] = (
            f"{mot.n_truth} {mot.n_matches} {mot.n_misses} {mot.n_false}"
        )
        summary["id switches"] = mot.id_switches
        summary["fragmentations"] = mot.fragmentations
        summary["track purity"] = round(mot.purity, 4)
        summary["ids / confirmed tracks"] = (
            f"{np.unique(det.id).size} / {res.counts.tracks_confirmed}"
        )
    summary["time read / track (s)"] = f"{t_read:.2f} {t_track:.2f}"
    _print(summary)
    if args.out:
        _write(args.out, res, ref)
        print(f"tracks written to {args.out}")
    if args.plot:
        from navtrack.plots.tracks import plot_tracks

        path = plot_tracks(
            args.plot, en, res, title=f"{args.file.name} ({args.associator})", ref_deg=ref
        )
        print(f"plot written to {path}")
    return 0


PROGRESS_MIN_DETECTIONS = 5000  # files this long take seconds: show that the tracker runs


@contextlib.contextmanager
def _progress(n_detections: int, *, quiet: bool) -> Iterator[None]:
    """An elapsed-time indicator on stderr while the tracker runs over a long file.

    ``run_tracker`` reports no progress of its own, so the indicator shows the detections
    being tracked and the seconds elapsed (refreshed twice a second); it is off with
    ``--quiet``, for files under :data:`PROGRESS_MIN_DETECTIONS` rows and when stderr is not a
    terminal (tqdm's ``disable=None``).
    """
    if quiet or n_detections < PROGRESS_MIN_DETECTIONS:
        yield
        return
    import sys
    import threading

    from tqdm import tqdm

    done = threading.Event()
    with tqdm(
        desc=f"tracking {n_detections} detections",
        bar_format="{desc}: {elapsed} elapsed",
        file=sys.stderr,
        disable=None,
        leave=False,
    ) as bar:

        def tick() -> None:
            while not done.wait(0.5):
                bar.refresh()

        ticker = threading.Thread(target=tick, daemon=True)
        ticker.start()
        try:
            yield
        finally:
            done.set()
            ticker.join()


def _print(summary: dict[str, Any]) -> None:
    width = max(len(k) for k in summary)
    for k, v in summary.items():
        if isinstance(v, dict):
            v = "; ".join(f"{a}: {b}" for a, b in v.items()) or "-"
        elif isinstance(v, list):
            v = " ".join(v) or "-"
        print(f"{k:<{width}}  {v}")


def _write(path: Path, res: Any, ref: tuple[float, float]) -> None:
    import numpy as np
    import pandas as pd

    from navtrack.io.tracks import local_enu_to_geodetic
    from navtrack.timescale import gps_to_utc, to_datetime64

    x = res.track_x
    times = to_datetime64(gps_to_utc(res.track_time_s))  # UTC calendar times
    df = pd.DataFrame(
        {
            "time": pd.to_datetime(times).strftime("%Y-%m-%dT%H:%M:%S.%fZ"),
            "track_id": res.track_id,
            "confirmed": res.track_confirmed,
            "x_m": x[:, 0],
            "y_m": x[:, 2],
            "vx_mps": x[:, 1],
            "vy_mps": x[:, 3],
            "std_m": res.track_std_m,
        }
    )
    if np.isfinite(ref[0]):
        latlon = local_enu_to_geodetic(x[:, [0, 2]], ref[0], ref[1])
        df["lat_deg"] = latlon[:, 0]
        df["lon_deg"] = latlon[:, 1]
    if path.suffix == ".parquet":
        df.to_parquet(path, index=False)
    else:
        df.to_csv(path, index=False)
