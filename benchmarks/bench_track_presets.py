"""Honest tuning table of the tracker presets and ``auto`` on the shared tracking files.

Run: ``NAVTRACK_SHARED_DATA=../shared/data PYTHONPATH=src python
benchmarks/bench_track_presets.py [--associator gnn|jpda] [--quick]``.

Every file is split in time at the middle of its span. Rows are what chose the model, columns
where it is scored (MOTA / HOTA / IDF1 / confirmed tracks : ids), by the CLI's one scoring rule
(:mod:`navtrack.tracking.scoring`; the tracker skips stale repeats as the CLI does, ``auto``
tunes on the reports as read):

- ``ships`` and ``aircraft``: the presets (chosen on the whole Solent / OpenSky file: in sample
  on their own file, out of sample on the other);
- ``auto on h1``: :func:`~navtrack.tracking.trackers.autotune.auto_config` run on the first half
  (its rule constants were chosen on the first halves, two of them on the Solent west half: see
  the module notes of ``autotune``), the config then tracks the second half;
- ``auto in sample``: ``auto_config`` on the scored part itself (what ``navtrack track`` does
  with no tuning flags; it never sees the ids).

Hold-out files built from the shared data: the OpenSky file in the generic csv layout
(``alt_m``, ``speed_mps``, ``course_deg``, read by the csv reader), its reports thinned to one in
two (20 s reports) and its west / east halves (split at the median longitude), and the Solent
file's west / east halves. Times are of
the tracking alone (the machine may be loaded: compare within a column).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from navtrack.io.tracks import read_tracks, stale_repeats, to_local_enu, velocity_local_enu
from navtrack.tracking.scoring import score_tracks, scoring_rule
from navtrack.tracking.trackers.autotune import auto_config
from navtrack.tracking.trackers.tracker import TrackerConfig, run_tracker

DATA = Path(os.environ.get("NAVTRACK_SHARED_DATA", "../shared/data")) / "tracking"


def _part(t, en, vel, ids, mask):
    return t[mask], en[mask], vel[mask], ids[mask]


def load_parts() -> dict[str, tuple]:
    """Named parts: (t, en, vel, ids) each."""
    parts: dict[str, tuple] = {}
    for name, fname, fmt in (
        ("solent", "SolentAIS_20160112_130211.csv", "ais"),
        ("opensky", "OpenSky_Plane_States.csv", "opensky"),
    ):
        det = read_tracks(DATA / fname, fmt)
        en, ref = to_local_enu(det)
        vel = velocity_local_enu(det, *ref)
        t, ids = det.t_gps_s, det.id
        mid = 0.5 * (t[0] + t[-1])
        for key, mask in (
            ("all", np.ones(t.size, bool)),
            ("h1", t < mid),
            ("h2", t >= mid),
        ):
            parts[f"{name} {key}"] = _part(t, en, vel, ids, mask)
        west = det.lon_deg < np.median(det.lon_deg)
        if name == "solent":
            parts["solent west"] = _part(t, en, vel, ids, west)
            parts["solent east"] = _part(t, en, vel, ids, ~west)
        if name == "opensky":
            epochs = np.unique(t)
            thin = np.isin(t, epochs[::2])
            parts["opensky 20 s"] = _part(t, en, vel, ids, thin)
            parts["opensky west"] = _part(t, en, vel, ids, west)
            parts["opensky east"] = _part(t, en, vel, ids, ~west)
            parts["opensky csv"] = _csv_layout(det)
    return parts


def _csv_layout(det) -> tuple:
    """The OpenSky detections written in the generic csv layout and read back."""
    import pandas as pd

    from navtrack.timescale import gps_to_utc, to_datetime64

    times = pd.to_datetime(to_datetime64(gps_to_utc(det.t_gps_s)))
    df = pd.DataFrame(
        {
            "time": times.strftime("%Y-%m-%dT%H:%M:%S.%fZ"),
            "id": det.id,
            "lat": det.lat_deg,
            "lon": det.lon_deg,
            "alt_m": det.alt_m,
            "speed_mps": det.speed_mps,
            "course_deg": det.course_deg,
        }
    )
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "adsb.csv"
        df.to_csv(path, index=False)
        csv = read_tracks(path, "csv")
    en, ref = to_local_enu(csv)
    return csv.t_gps_s, en, velocity_local_enu(csv, *ref), csv.id


def score(part: tuple, cfg: TrackerConfig) -> dict[str, float]:
    """Track a part as ``navtrack track`` does (stale repeats skipped) and score it by the
    CLI's rule."""
    t, en, vel, ids = part
    speed = np.hypot(vel[:, 0], vel[:, 1])
    use = ~stale_repeats(t, en, speed)
    fresh = ~stale_repeats(t, en, speed, ids)
    rule = scoring_rule(t[fresh], ids[fresh])
    grid = t[0] + np.arange(0.0, t[-1] - t[0] + 1e-9, rule.report_s)
    clock = time.perf_counter()
    res = run_tracker(t[use], en[use], cfg, report_times=grid, velocity=vel[use])
    elapsed = time.perf_counter() - clock
    sc = score_tracks(
        grid, t[fresh], en[fresh], ids[fresh], res.report_frame, res.report_id, res.report_xy, rule
    )
    return {
        "mota": sc.mota,
        "hota": sc.hota,
        "idf1": sc.idf1,
        "switches": sc.id_switches,
        "confirmed": res.counts.tracks_confirmed,
        "ids": sc.n_ids,
        "time_s": elapsed,
    }


def _cell(r: dict[str, float]) -> str:
    return f"{r['mota']:.3f} / {r['hota']:.3f} / {r['idf1']:.3f} / {r['confirmed']}:{r['ids']}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--associator", choices=("gnn", "jpda"), default="gnn")
    ap.add_argument("--quick", action="store_true", help="OpenSky parts only")
    ap.add_argument("--only", help="comma-separated columns, e.g. 'solent west,solent east'")
    a = ap.parse_args(argv)
    parts = load_parts()
    cols = [
        c
        for c in (
            "solent all",
            "solent h2",
            "solent west",
            "solent east",
            "opensky all",
            "opensky h2",
            "opensky 20 s",
            "opensky west",
            "opensky east",
            "opensky csv",
        )
        if not (a.quick and c.startswith("solent")) and (a.only is None or c in a.only.split(","))
    ]
    presets = {
        "ships": TrackerConfig.for_ships(a.associator),
        "aircraft": TrackerConfig.for_aircraft(a.associator),
    }
    rows: dict[str, dict[str, dict[str, float]]] = {}
    for name, cfg in presets.items():
        rows[name] = {c: score(parts[c], cfg) for c in cols}
        print(name, {c: _cell(r) for c, r in rows[name].items()}, flush=True)
    rows["auto on h1"] = {}
    for c in cols:
        if c.endswith("h2"):
            h1 = parts[c.replace("h2", "h1")]
            cfg = auto_config(h1[0], h1[1], h1[2], a.associator).config
            rows["auto on h1"][c] = score(parts[c], cfg)
    print("auto on h1", {c: _cell(r) for c, r in rows["auto on h1"].items()}, flush=True)
    rows["auto in sample"] = {}
    for c in cols:
        p = parts[c]
        clock = time.perf_counter()
        cfg = auto_config(p[0], p[1], p[2], a.associator).config
        tune_s = time.perf_counter() - clock
        rows["auto in sample"][c] = score(p, cfg) | {"tune_s": tune_s}
    print("auto in sample", {c: _cell(r) for c, r in rows["auto in sample"].items()}, flush=True)
    print()
    print(f"MOTA / HOTA / IDF1 / confirmed tracks:ids ({a.associator}); rows: what chose the model")
    print("| chosen on \\ scored on | " + " | ".join(cols) + " |")
    print("|---" * (len(cols) + 1) + "|")
    for name, r in rows.items():
        print(f"| {name} | " + " | ".join(_cell(r[c]) if c in r else "-" for c in cols) + " |")
    print()
    print("tracking time (s) | " + " | ".join(cols))
    for name, r in rows.items():
        print(f"{name} | " + " | ".join(f"{r[c]['time_s']:.1f}" if c in r else "-" for c in cols))
    auto = rows["auto in sample"]
    print("auto tuning time (s) | " + " | ".join(f"{auto[c]['tune_s']:.1f}" for c in cols))
    return 0


if __name__ == "__main__":
    sys.exit(main())
