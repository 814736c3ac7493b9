"""Tracking time of the shared files with scan windows against one scan per time stamp.

Run: ``NAVTRACK_SHARED_DATA=../shared/data PYTHONPATH=src python
benchmarks/bench_track_windows.py [--reps N]``.

For each shared file and associator the ``auto`` model of the file (what ``navtrack track``
runs with no tuning flags) tracks the whole file with its scan window and with
``scan_window_s = 0`` (one scan per distinct time, the tracker before windows), alternating,
``--reps`` times each; medians, their ratio, the scans and MOTA of both are printed (stale
repeats skipped and scoring by the CLI's rule, :mod:`navtrack.tracking.scoring`). Both sides
run in the same process, so the ratio holds on a loaded machine.
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

from navtrack.io.tracks import read_tracks, stale_repeats, to_local_enu, velocity_local_enu
from navtrack.tracking.scoring import score_tracks, scoring_rule
from navtrack.tracking.trackers.autotune import auto_config
from navtrack.tracking.trackers.tracker import run_tracker

DATA = Path(os.environ.get("NAVTRACK_SHARED_DATA", "../shared/data")) / "tracking"
FILES = (("SolentAIS_20160112_130211.csv", "ais"), ("OpenSky_Plane_States.csv", "opensky"))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--reps", type=int, default=2)
    a = ap.parse_args(argv)
    print(
        "| file | associator | window (s) | scans | time (s) | scans, no window | time (s) "
        "| ratio | MOTA window / none |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for fname, fmt in FILES:
        det = read_tracks(DATA / fname, fmt)
        en, ref = to_local_enu(det)
        vel = velocity_local_enu(det, *ref)
        t, ids = det.t_gps_s, det.id
        use = ~stale_repeats(t, en, det.speed_mps)
        fresh = ~stale_repeats(t, en, det.speed_mps, ids)
        rule = scoring_rule(t[fresh], ids[fresh])
        grid = t[0] + np.arange(0.0, t[-1] - t[0] + 1e-9, rule.report_s)
        truth = (t[fresh], en[fresh], ids[fresh])
        for assoc in ("gnn", "jpda"):
            cfg = auto_config(t, en, vel, assoc).config
            variants = {"window": cfg, "none": dataclasses.replace(cfg, scan_window_s=0.0)}
            times: dict[str, list[float]] = {k: [] for k in variants}
            out = {}
            for _ in range(a.reps):
                for key, c in variants.items():
                    clock = time.perf_counter()
                    res = run_tracker(t[use], en[use], c, report_times=grid, velocity=vel[use])
                    times[key].append(time.perf_counter() - clock)
                    out[key] = res
            med = {k: statistics.median(v) for k, v in times.items()}
            mota = {
                k: score_tracks(grid, *truth, r.report_frame, r.report_id, r.report_xy, rule).mota
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
