"""A tuned Stone Soup tracker beside ``navtrack track`` on the same real report files.

Run: ``NAVTRACK_SHARED_DATA=../shared/data PYTHONPATH=src python
benchmarks/bench_track_stonesoup.py [--files opensky,solent] [--reps 1]``; a file of another
kind is given as ``KIND:PATH`` (``--files adsb:monterey.csv``; kinds: the keys of
:data:`GRID`, ``adsb`` for ADS-B at fast report rates in any layout ``navtrack track`` reads).

Each file is split in time at the middle of its span. Stone Soup (``stonesoup``, the
``compare`` extra) runs the tracker of its own tutorials: a nearly-constant-velocity model per
axis (``ConstantVelocity(q)``), a Kalman predictor and updater on east/north positions
(σ per axis), GNN (``DistanceHypothesiser`` with the Mahalanobis distance gated at the
chi-square 99.99 % point, ``GNNWith2DAssignment``) or JPDA (``PDAHypothesiser``,
``JPDAwithEHM2``: the joint events by efficient hypothesis management, as plain ``JPDA``
enumerates them over all tracks at once and did not finish one run in 20 min;
``MultiTargetMixtureTracker``), a ``MultiMeasurementInitiator`` (3 points, its own GNN) and an
``UpdateTimeDeleter``. Its grid (:data:`GRID`, stated per file kind) is searched on the first
half of the file by HOTA; the best setting tracks the second half. navtrack runs with no
flags (``auto``, tuned on the second half itself without its ids, as ``navtrack track`` does).
Both skip the stale repeats (:func:`navtrack.io.tracks.stale_repeats`) and are scored by the
CLI's rule (:mod:`navtrack.tracking.scoring`: MOTA and id switches as py-motmetrics counts
them, HOTA as TrackEval, IDF1 as py-motmetrics; the test suite checks those equalities).

Stone Soup takes one scan per group of reports: the reports are grouped into windows of
:data:`SCAN_S` seconds (per file kind, shorter than a target's report interval so that a
window holds one report of a target), each report keeping its own time stamp (Stone Soup's
hypothesisers predict each track to each detection's time). Tracks are reported at the
scoring frame times by the CV prediction of their last state, as navtrack reports its own.

The printed times are the tracking alone (navtrack: ``auto``'s tuning separately), medians of
``--reps`` alternating runs of the two in one process.
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import sys
import time
from pathlib import Path

import numpy as np

from navtrack.io.tracks import read_tracks, stale_repeats, to_local_enu, velocity_local_enu
from navtrack.tracking.gating import chi2_threshold
from navtrack.tracking.scoring import Scores, score_tracks, scoring_rule
from navtrack.tracking.trackers.autotune import auto_config
from navtrack.tracking.trackers.tracker import TrackerConfig, run_tracker

DATA = Path(os.environ.get("NAVTRACK_SHARED_DATA", "../shared/data")) / "tracking"
FILES = {
    "opensky": (DATA / "OpenSky_Plane_States.csv", "opensky"),
    "solent": (DATA / "SolentAIS_20160112_130211.csv", "ais"),
}
# Stone Soup's parameters searched on the first half: q (m²/s³), deleter time (s); σ (m),
# initial velocity standard deviation (m/s), P_D and λ (JPDA) fixed per kind.
GRID = {
    "opensky": {"q": (30.0, 300.0, 3000.0), "delete_s": (30.0, 60.0)},
    "solent": {"q": (1e-3, 1e-2, 1e-1), "delete_s": (300.0, 600.0)},
    "adsb": {"q": (3.0, 30.0, 300.0), "delete_s": (20.0, 60.0)},
}
FIXED = {
    "opensky": {"sigma_m": 25.0, "v0_mps": 300.0, "pd": 0.9, "clutter": 1e-10},
    "solent": {"sigma_m": 25.0, "v0_mps": 10.0, "pd": 0.9, "clutter": 1e-7},
    "adsb": {"sigma_m": 25.0, "v0_mps": 300.0, "pd": 0.9, "clutter": 1e-10},
}
SCAN_S = {"opensky": 5.0, "solent": 1.0, "adsb": 1.0}
EPOCH = dt.datetime(2000, 1, 1)


def load(path: Path, fmt: str | None) -> dict[str, tuple]:
    """First and second halves: (t, en, vel, ids) with stale repeats left out, the scoring
    truth (fresh reports within each id), and (t, en, vel) as read (``auto`` tunes on them,
    as ``navtrack track`` does)."""
    det = read_tracks(path, fmt)
    en, ref = to_local_enu(det)
    vel = velocity_local_enu(det, *ref)
    t, ids = det.t_gps_s, det.id
    use = ~stale_repeats(t, en, det.speed_mps)
    fresh = ~stale_repeats(t, en, det.speed_mps, ids)
    mid = 0.5 * (t[0] + t[-1])
    out = {}
    for half, part in (("h1", t < mid), ("h2", t >= mid)):
        k, f = part & use, part & fresh
        out[half] = (
            (t[k], en[k], vel[k], ids[k]),
            (t[f], en[f], ids[f]),
            (t[part], en[part], vel[part]),
        )
    return out


def run_stonesoup(
    t: np.ndarray, en: np.ndarray, assoc: str, q: float, delete_s: float, fixed: dict, scan_s: float
) -> tuple[list[float], list[list[tuple[int, float, np.ndarray]]]]:
    """Stone Soup over the reports; per scan: its time and the live tracks as (id, time of
    last state, state)."""
    from stonesoup.dataassociator.neighbour import GNNWith2DAssignment
    from stonesoup.dataassociator.probability import JPDAwithEHM2
    from stonesoup.deleter.time import UpdateTimeDeleter
    from stonesoup.hypothesiser.distance import DistanceHypothesiser
    from stonesoup.hypothesiser.probability import PDAHypothesiser
    from stonesoup.initiator.simple import MultiMeasurementInitiator
    from stonesoup.measures import Mahalanobis
    from stonesoup.models.measurement.linear import LinearGaussian
    from stonesoup.models.transition.linear import (
        CombinedLinearGaussianTransitionModel,
        ConstantVelocity,
    )
    from stonesoup.predictor.kalman import KalmanPredictor
    from stonesoup.tracker.simple import MultiTargetMixtureTracker, MultiTargetTracker
    from stonesoup.types.detection import Detection
    from stonesoup.types.state import GaussianState
    from stonesoup.updater.kalman import KalmanUpdater

    s2 = fixed["sigma_m"] ** 2
    transition = CombinedLinearGaussianTransitionModel([ConstantVelocity(q), ConstantVelocity(q)])
    measurement = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.diag([s2, s2]))
    predictor = KalmanPredictor(transition)
    updater = KalmanUpdater(measurement)
    gate = float(np.sqrt(chi2_threshold(0.9999, 2)))
    gnn = GNNWith2DAssignment(DistanceHypothesiser(predictor, updater, Mahalanobis(), gate))
    deleter = UpdateTimeDeleter(dt.timedelta(seconds=delete_s))
    v2 = fixed["v0_mps"] ** 2
    initiator = MultiMeasurementInitiator(
        GaussianState(np.zeros((4, 1)), np.diag([s2, v2, s2, v2])),
        UpdateTimeDeleter(dt.timedelta(seconds=delete_s)),
        GNNWith2DAssignment(DistanceHypothesiser(predictor, updater, Mahalanobis(), gate)),
        updater,
        measurement,
        min_points=3,
    )
    bins = np.floor((t - t[0]) / scan_s).astype(np.int64)
    starts = np.flatnonzero(np.r_[True, bins[1:] != bins[:-1]])
    ends = np.r_[starts[1:], t.size]

    def scans():
        for a, b in zip(starts, ends, strict=True):
            dets = {
                Detection(
                    en[j].reshape(2, 1),
                    timestamp=EPOCH + dt.timedelta(seconds=float(t[j] - t[0])),
                    measurement_model=measurement,
                )
                for j in range(a, b)
            }
            yield EPOCH + dt.timedelta(seconds=float(t[b - 1] - t[0])), dets

    class Reader:
        def __iter__(self):
            return scans()

        @property
        def detections(self):  # (unused by the trackers; part of the reader interface)
            return set()

    if assoc == "gnn":
        tracker = MultiTargetTracker(initiator, deleter, Reader(), gnn, updater)
    else:
        hyp = PDAHypothesiser(
            predictor, updater, fixed["clutter"], prob_detect=fixed["pd"], prob_gate=0.9999
        )
        jpda = JPDAwithEHM2(hyp)
        tracker = MultiTargetMixtureTracker(initiator, deleter, Reader(), jpda, updater)
    times: list[float] = []
    live: list[list[tuple[int, float, np.ndarray]]] = []
    names: dict[int, int] = {}
    for when, tracks in tracker:
        times.append((when - EPOCH).total_seconds() + t[0])
        live.append(
            [
                (
                    names.setdefault(id(tr), len(names)),
                    (tr.state.timestamp - EPOCH).total_seconds() + t[0],
                    np.asarray(tr.state_vector, dtype=float).ravel(),
                )
                for tr in tracks
            ]
        )
    return times, live


def report(
    times: list[float], live: list[list[tuple[int, float, np.ndarray]]], grid: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Stone Soup's tracks at the frame times: the live tracks of the last scan at or before
    each frame time, their last state moved along its velocity to the frame time."""
    frames, ids, xy = [], [], []
    scan = np.searchsorted(np.asarray(times), grid, side="right") - 1
    for f, k in enumerate(scan):
        if k < 0:
            continue
        for tid, ts, x in live[k]:
            d = grid[f] - ts
            frames.append(f)
            ids.append(tid)
            xy.append([x[0] + d * x[1], x[2] + d * x[3]])
    return (
        np.asarray(frames, dtype=np.int64),
        np.asarray(ids, dtype=np.int64),
        np.asarray(xy, dtype=float).reshape(-1, 2),
    )


def score_stonesoup(half: tuple, assoc: str, setting: dict, fixed: dict, scan_s: float) -> tuple:
    (t, en, _vel, _ids), (tf, ef, idf), _read = half
    rule = scoring_rule(tf, idf)
    grid = t[0] + np.arange(0.0, t[-1] - t[0] + 1e-9, rule.report_s)
    clock = time.perf_counter()
    times, live = run_stonesoup(t, en, assoc, setting["q"], setting["delete_s"], fixed, scan_s)
    elapsed = time.perf_counter() - clock
    return score_tracks(grid, tf, ef, idf, *report(times, live, grid), rule), elapsed


def score_navtrack(half: tuple, assoc: str, cfg: TrackerConfig) -> tuple[Scores, float]:
    (t, en, vel, _ids), (tf, ef, idf), _read = half
    rule = scoring_rule(tf, idf)
    grid = t[0] + np.arange(0.0, t[-1] - t[0] + 1e-9, rule.report_s)
    clock = time.perf_counter()
    res = run_tracker(t, en, cfg, report_times=grid, velocity=vel)
    elapsed = time.perf_counter() - clock
    args = (res.report_frame, res.report_id, res.report_xy, rule)
    return score_tracks(grid, tf, ef, idf, *args), elapsed


def _row(name: str, s: Scores, confirmed: str) -> str:
    return (
        f"| {name} | {s.hota:.3f} | {s.mota:.3f} | {s.idf1:.3f} | {s.id_switches} | {confirmed} |"
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--files", default="opensky,solent")
    ap.add_argument("--associators", default="gnn,jpda")
    ap.add_argument("--reps", type=int, default=1)
    a = ap.parse_args(argv)
    try:
        import stonesoup  # noqa: F401
    except ImportError:
        print("Stone Soup is not installed (pip install -e '.[compare]'): nothing to compare")
        return 0
    for item in a.files.split(","):
        name, _, path = item.partition(":")
        halves = load(Path(path), None) if path else load(*FILES[name])
        fixed, scan_s = FIXED[name], SCAN_S[name]
        settings = [
            {"q": q, "delete_s": d} for q in GRID[name]["q"] for d in GRID[name]["delete_s"]
        ]
        for assoc in a.associators.split(","):
            print(f"\n{item}, {assoc}: Stone Soup's grid on h1 (HOTA / MOTA / IDF1 / switches)")
            best, best_h = settings[0], -np.inf
            for st in settings:
                sc, el = score_stonesoup(halves["h1"], assoc, st, fixed, scan_s)
                print(
                    f"  q={st['q']:g} delete={st['delete_s']:g} s: {sc.hota:.3f} / "
                    f"{sc.mota:.3f} / {sc.idf1:.3f} / {sc.id_switches} ({el:.1f} s)",
                    flush=True,
                )
                if sc.hota > best_h:
                    best, best_h = st, sc.hota
            h2 = halves["h2"]
            clock = time.perf_counter()
            t2, en2, vel2 = h2[2]
            cfg = auto_config(t2, en2, vel2, assoc).config
            tune_s = time.perf_counter() - clock
            t_ss, t_nt = [], []
            for _ in range(a.reps):
                ss, el = score_stonesoup(h2, assoc, best, fixed, scan_s)
                t_ss.append(el)
                nt, el = score_navtrack(h2, assoc, cfg)
                t_nt.append(el)
            n_ids = nt.n_ids
            print(
                f"\n{name} h2, {assoc} (Stone Soup: q={best['q']:g}, delete {best['delete_s']:g} s)"
            )
            print("| tracker | HOTA | MOTA | IDF1 | id switches | tracks / ids |")
            print("|---|---|---|---|---|---|")
            print(_row("Stone Soup, tuned on h1", ss, f"{ss.n_tracks} / {n_ids}"))
            print(_row("navtrack, no flags", nt, f"{nt.n_tracks} / {n_ids}"))
            med_ss, med_nt = float(np.median(t_ss)), float(np.median(t_nt))
            print(
                f"tracking time (s): Stone Soup {med_ss:.2f}, navtrack {med_nt:.2f} "
                f"(+ {tune_s:.2f} auto tuning); ratio Stone Soup / navtrack {med_ss / med_nt:.1f}, "
                f"with navtrack's tuning {med_ss / (med_nt + tune_s):.1f}",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
