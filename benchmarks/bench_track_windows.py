"""Tracking time of the shared files with scan windows against one scan per time stamp.

Run: ``NAVTRACK_SHARED_DATA=../shared/data PYTHONPATH=src python
benchmarks/bench_track_windows.py [--reps N]``.

For each shared file and associator the ``auto`` model of the file (what ``navtrack track``
runs with no tuning flags) tracks the whole file with its scan window and with
``scan_window_s = 0`` (one scan per distinct time, the tracker before windows), alternating,
``--reps`` times each; medians, their ratio, the scans and MOTA of both are printed. Both
sides run in the same process, so the ratio holds on a loaded machine.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from navtrack.io.tracks import read_tracks, to_local_enu, velocity_local_enu
from navtrack.tracking.autotune import auto_config
from navtrack.tracking.metrics import clear_mot, interpolate_truth
from navtrack.tracking.tracker import run_tracker

DATA = Path(os.environ.get("NAVTRACK_SHARED_DATA", "../shared/data")) / "tracking"
FILES = (
    ("SolentAIS_20160112_130211.csv", "ais", (60.0, 400.0, 500.0)),
    ("OpenSky_Plane_States.csv", "opensky", (10.0, 60.0, 2000.0)),
)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--reps", type=int, default=2)
    a = ap.parse_args(argv)
    print(
        "| file | associator | window (s) | scans | time (s) | scans, no window | time (s) "
        "| ratio | MOTA window / none |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for fname, fmt, (report_s, gap_s, match_m) in FILES:
        det = read_tracks(DATA / fname, fmt)
        en, ref = to_local_enu(det)
        vel = velocity_local_enu(det, *ref)
        t = det.t_gps_s
        grid = t[0] + np.arange(0.0, t[-1] - t[0] + 1e-9, report_s)
        tf, tid, tp = interpolate_truth(grid, t, det.id, en, gap_s)
        for assoc in ("gnn", "jpda"):
            cfg = auto_config(t, en, vel, assoc).config
            variants = {"window": cfg, "none": dataclasses.replace(cfg, scan_window_s=0.0)}
            times: dict[str, list[float]] = {k: [] for k in variants}
            out = {}
            for _ in range(a.reps):
                for key, c in variants.items():
                    clock = time.perf_counter()
                    res = run_tracker(t, en, c, report_times=grid, velocity=vel)
                    times[key].append(time.perf_counter() - clock)
                    out[key] = res
            med = {k: statistics.median(v) for k, v in times.items()}
            mota = {
                k: clear_mot(tf, tid, tp, r.report_frame, r.report_id, r.report_xy, match_m).mota
                for k, r in out.items()
            }
            print(
                f"| {fname} | {assoc} | {cfg.scan_window_s:.2f} | {out['window'].counts.scans} "
                f"| {med['window']:.1f} | {out['none'].counts.scans} | {med['none']:.1f} "
                f"| {med['none'] / med['window']:.2f} | {mota['window']:.4f} / "
                f"{mota['none']:.4f} |",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
