"""A tuned Stone Soup tracker beside ``navtrack track`` on the same real report files.

Run: ``NAVTRACK_SHARED_DATA=../shared/data PYTHONPATH=src python
benchmarks/bench_track_stonesoup.py [--files opensky,solent] [--reps 1]``; a file of another
kind is given as ``KIND:PATH`` (``--files adsb:monterey.csv``; kinds: the keys of
:data:`GRID`: ``aircraft`` for ADS-B at ~10 s, ``adsb`` at 1-5 s, ``ships`` for AIS, in any
layout ``navtrack track`` reads). ``benchmarks/eval_track_files.py`` builds issue 32's table
from the same functions.

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

Speed without changing a track: Stone Soup's tracker hands every track and every report of a
scan to its associator, whose hypothesiser predicts each track to each report's time, and
appends a prediction to every track left without a report; its deleter and initiator then
walk each track's whole history at every scan. On AIS with 1 s scans that cost 535 s per
setting on a half of the Solent file. Here (:class:`GatedAssociator`,
:class:`CandidateHypothesiser`, :class:`ScanTimeDeleter`) the associators see only the tracks
with a report inside their own gate and, per track, only those reports; a track without
one is left as it is (a CV prediction in two steps is the prediction in one), and
``UpdateTimeDeleter``'s rule is asked at the scan time. The transition model is the same
CV model with its matrices built in closed form (:func:`constant_velocity_2d`).
``run_stonesoup(..., gated=False)`` runs Stone Soup's components as its tracker does; on the
first 5 min of the Solent file both give the same tracks at every scan (positions within
1e-6 m, GNN and JPDA).

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
from navtrack.tracking.scoring import Scores, ScoringRule, score_tracks, scoring_rule
from navtrack.tracking.trackers.autotune import auto_config
from navtrack.tracking.trackers.tracker import TrackerConfig, run_tracker

DATA = Path(os.environ.get("NAVTRACK_SHARED_DATA", "../shared/data")) / "tracking"
FILES = {
    "opensky": (DATA / "OpenSky_Plane_States.csv", "opensky", "aircraft"),
    "solent": (DATA / "SolentAIS_20160112_130211.csv", "ais", "ships"),
}
# Stone Soup's parameters searched on the first half: q (m²/s³), deleter time (s); σ (m),
# initial velocity standard deviation (m/s), P_D and λ (JPDA) fixed per kind.
# per kind of file: ADS-B at ~10 s (aircraft), at 1-5 s (adsb), AIS (ships)
GRID = {
    "aircraft": {"q": (30.0, 300.0, 3000.0), "delete_s": (30.0, 60.0)},
    "ships": {"q": (1e-3, 1e-2, 1e-1), "delete_s": (600.0,)},
    "adsb": {"q": (3.0, 30.0, 300.0), "delete_s": (20.0, 60.0)},
}
FIXED = {
    "aircraft": {"sigma_m": 25.0, "v0_mps": 300.0, "pd": 0.9, "clutter": 1e-10},
    "ships": {"sigma_m": 25.0, "v0_mps": 10.0, "pd": 0.9, "clutter": 1e-7},
    "adsb": {"sigma_m": 25.0, "v0_mps": 300.0, "pd": 0.9, "clutter": 1e-10},
}
GATE_PROBABILITY = 0.9999
"""Stone Soup's gates (GNN's Mahalanobis distance, JPDA's validation region): chi-square."""
GATE_SLACK = 1.01
"""The pre-gate of :class:`GatedAssociator` is this much wider (in squared distance) than
the hypothesisers' own gate, so that rounding never drops a report they would keep."""
SCAN_S = {"aircraft": 5.0, "ships": 1.0, "adsb": 1.0}
EPOCH = dt.datetime(2000, 1, 1)


def load(path: Path, fmt: str | None, split: bool = True) -> dict[str, tuple]:
    """The file's first and second halves (``h1``, ``h2``; with ``split=False`` the whole
    file as ``all``), each as (t, en, vel, ids) with stale repeats left out, the scoring
    truth (fresh reports within each id), and (t, en, vel) as read (``auto`` tunes on them,
    as ``navtrack track`` does)."""
    det = read_tracks(path, fmt)
    en, ref = to_local_enu(det)
    vel = velocity_local_enu(det, *ref)
    t, ids = det.t_gps_s, det.id
    use = ~stale_repeats(t, en, det.speed_mps)
    fresh = ~stale_repeats(t, en, det.speed_mps, ids)
    mid = 0.5 * (t[0] + t[-1])
    parts = {"h1": t < mid, "h2": t >= mid} if split else {"all": np.ones(t.size, bool)}
    out = {}
    for half, part in parts.items():
        k, f = part & use, part & fresh
        out[half] = (
            (t[k], en[k], vel[k], ids[k]),
            (t[f], en[f], ids[f]),
            (t[part], en[part], vel[part]),
        )
    return out


class GatedAssociator:
    """Stone Soup's associator over the tracks that can take a report of the scan.

    Before the wrapped associator runs, each track's last state is predicted (same CV model)
    to each report's time and the reports outside its Mahalanobis gate are found in one array
    operation; only tracks with a report inside (``GATE_SLACK`` wider than the hypothesiser's
    own gate) and those reports reach the associator. A track left out would have received
    only the missed-detection hypothesis, i.e. its prediction to the scan time; since a CV
    prediction to t1 then to t2 equals the prediction to t2, and the deleter is asked at the
    scan time (:class:`ScanTimeDeleter`), leaving it untouched changes no track. For the same
    reason a track whose GNN hypothesis is the missed detection is left out of the answer
    (JPDA's mixture of a missed track still moves it, and is kept).
    """

    def __init__(self, associator, q: float, noise_covar: np.ndarray, gate2: float) -> None:
        from stonesoup.types.multihypothesis import MultipleHypothesis

        self.mixture = MultipleHypothesis

        self.associator, self.q, self.R = associator, q, noise_covar
        self.hypothesiser = CandidateHypothesiser(associator.hypothesiser)
        associator.hypothesiser = self.hypothesiser
        self.gate2 = gate2 * GATE_SLACK

    def associate(self, tracks, detections, timestamp, **kwargs):
        tracks, dets = list(tracks), list(detections)
        if not tracks or not dets:
            return self.associator.associate(set(tracks), set(dets), timestamp, **kwargs)
        x = np.stack([np.asarray(tr.state_vector, dtype=float).ravel() for tr in tracks])
        P = np.stack([np.asarray(tr.covar, dtype=float) for tr in tracks])
        t0 = np.array([(tr.timestamp - EPOCH).total_seconds() for tr in tracks])
        z = np.stack([np.asarray(d.state_vector, dtype=float).ravel() for d in dets])
        tz = np.array([(d.timestamp - EPOCH).total_seconds() for d in dets])
        dt = tz[None, :] - t0[:, None]  # (T, D)
        G = np.zeros((*dt.shape, 2, 4))
        G[..., 0, 0] = G[..., 1, 2] = 1.0
        G[..., 0, 1] = G[..., 1, 3] = dt
        S = np.einsum("tdij,tjk,tdlk->tdil", G, P, G) + self.R
        S[..., 0, 0] += self.q * np.abs(dt) ** 3 / 3.0
        S[..., 1, 1] += self.q * np.abs(dt) ** 3 / 3.0
        e = z[None, :, :] - np.einsum("tdij,tj->tdi", G, x)
        d2 = np.einsum("tdi,tdi->td", e, np.linalg.solve(S, e[..., None])[..., 0])
        near = d2 <= self.gate2
        keep_t, keep_d = near.any(axis=1), near.any(axis=0)
        self.hypothesiser.candidates = {
            tr: {d for d, k in zip(dets, row, strict=True) if k}
            for tr, row in zip(tracks, near, strict=True)
            if row.any()
        }
        out = self.associator.associate(
            {tr for tr, k in zip(tracks, keep_t, strict=True) if k},
            {d for d, k in zip(dets, keep_d, strict=True) if k},
            timestamp,
            **kwargs,
        )
        # a single missed-detection hypothesis (GNN) is the prediction alone: left out too
        return {tr: h for tr, h in out.items() if isinstance(h, self.mixture) or h}


class CandidateHypothesiser:
    """Stone Soup's hypothesiser given, for each track, only the reports inside the track's
    pre-gate (:class:`GatedAssociator`): the others would get no hypothesis from it."""

    def __init__(self, hypothesiser) -> None:
        self.hypothesiser = hypothesiser
        self.candidates: dict = {}

    def hypothesise(self, track, detections, timestamp, **kwargs):
        own = self.candidates.get(track, set()) & set(detections)
        return self.hypothesiser.hypothesise(track, own, timestamp, **kwargs)


class ScanTimeDeleter:
    """Stone Soup's deleter asked at the time of the scan (as its tracker does when every
    track holds a state at the scan time), so that a track :class:`GatedAssociator` left
    untouched is deleted when its last update is older than the deleter's time."""

    def __init__(self, deleter, clock: list) -> None:
        self.deleter, self.clock = deleter, clock

    def delete_tracks(self, tracks, **kwargs):
        """``UpdateTimeDeleter``'s rule (no update with a measurement within its time before
        the scan time), read from the newest state back to that time: its own time slice of
        a track looks at every state the track ever had."""
        since = self.clock[0] - self.deleter.time_since_update
        return {tr for tr in tracks if not _updated_since(tr.states, since)}


def _updated_since(states: list, since: dt.datetime) -> bool:
    from stonesoup.types.update import Update

    for state in reversed(states):
        if state.timestamp < since:
            return False
        if isinstance(state, Update) and state.hypothesis:
            return True
    return False


def constant_velocity_2d(q: float):
    """Stone Soup's ``CombinedLinearGaussianTransitionModel([ConstantVelocity(q)] * 2)`` as
    one model with the same matrices (state x, vx, y, vy) built in closed form: the combined
    model assembles them by ``scipy.linalg.block_diag`` at every prediction."""
    from stonesoup.base import Property
    from stonesoup.models.base import TimeVariantModel
    from stonesoup.models.transition.linear import LinearGaussianTransitionModel
    from stonesoup.types.array import CovarianceMatrix

    class ConstantVelocity2D(LinearGaussianTransitionModel, TimeVariantModel):
        noise_diff_coeff: float = Property(doc="q, m²/s³, on both axes")

        @property
        def ndim_state(self) -> int:
            return 4

        def matrix(self, time_interval, **kwargs):
            F = np.eye(4)
            F[0, 1] = F[2, 3] = time_interval.total_seconds()
            return F

        def covar(self, time_interval, **kwargs):
            d = abs(time_interval.total_seconds())
            b = self.noise_diff_coeff * np.array([[d**3 / 3, d**2 / 2], [d**2 / 2, d]])
            Q = np.zeros((4, 4))
            Q[:2, :2] = Q[2:, 2:] = b
            return CovarianceMatrix(Q)

    return ConstantVelocity2D(q)


def run_stonesoup(
    t: np.ndarray,
    en: np.ndarray,
    assoc: str,
    q: float,
    delete_s: float,
    fixed: dict,
    scan_s: float,
    gated: bool = True,
) -> tuple[list[float], list[list[tuple[int, float, np.ndarray]]]]:
    """Stone Soup over the reports; per scan: its time and the live tracks as (id, time of
    last state, state). ``gated=False`` hands every track and report of a scan to Stone
    Soup's associators as its tracker does (same tracks, slower)."""
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
    transition = (
        constant_velocity_2d(q)
        if gated
        else CombinedLinearGaussianTransitionModel([ConstantVelocity(q), ConstantVelocity(q)])
    )
    measurement = LinearGaussian(ndim_state=4, mapping=(0, 2), noise_covar=np.diag([s2, s2]))
    predictor = KalmanPredictor(transition)
    updater = KalmanUpdater(measurement)
    gate2 = chi2_threshold(GATE_PROBABILITY, 2)
    clock = [EPOCH]

    def gated_gnn():
        hyp = DistanceHypothesiser(predictor, updater, Mahalanobis(), float(np.sqrt(gate2)))
        associator = GNNWith2DAssignment(hyp)
        return (
            GatedAssociator(associator, q, measurement.noise_covar, gate2) if gated else associator
        )

    def deleter():
        return ScanTimeDeleter(UpdateTimeDeleter(dt.timedelta(seconds=delete_s)), clock)

    v2 = fixed["v0_mps"] ** 2
    initiator = MultiMeasurementInitiator(
        GaussianState(np.zeros((4, 1)), np.diag([s2, v2, s2, v2])),
        deleter(),
        gated_gnn(),
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
            clock[0] = EPOCH + dt.timedelta(seconds=float(t[b - 1] - t[0]))
            yield clock[0], dets

    class Reader:
        def __iter__(self):
            return scans()

        @property
        def detections(self):  # (unused by the trackers; part of the reader interface)
            return set()

    if assoc == "gnn":
        tracker = MultiTargetTracker(initiator, deleter(), Reader(), gated_gnn(), updater)
    else:
        hyp = PDAHypothesiser(
            predictor,
            updater,
            fixed["clutter"],
            prob_detect=fixed["pd"],
            prob_gate=GATE_PROBABILITY,
        )
        jpda = JPDAwithEHM2(hyp)
        if gated:
            jpda = GatedAssociator(jpda, q, measurement.noise_covar, gate2)
        tracker = MultiTargetMixtureTracker(initiator, deleter(), Reader(), jpda, updater)
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


def _grid(half: tuple) -> tuple[np.ndarray, ScoringRule]:
    """The command's scoring frames and rule for a half: from the first report read, every
    ``report_s`` (:mod:`navtrack.tracking.scoring`)."""
    _use, (tf, _ef, idf), (t_read, _en, _vel) = half
    rule = scoring_rule(tf, idf)
    return t_read[0] + np.arange(0.0, t_read[-1] - t_read[0] + 1e-9, rule.report_s), rule


def score_stonesoup(half: tuple, assoc: str, setting: dict, fixed: dict, scan_s: float) -> tuple:
    (t, en, _vel, _ids), (tf, ef, idf), _read = half
    grid, rule = _grid(half)
    clock = time.perf_counter()
    times, live = run_stonesoup(t, en, assoc, setting["q"], setting["delete_s"], fixed, scan_s)
    elapsed = time.perf_counter() - clock
    return score_tracks(grid, tf, ef, idf, *report(times, live, grid), rule), elapsed


def score_navtrack(half: tuple, assoc: str, cfg: TrackerConfig) -> tuple[Scores, float]:
    (t, en, vel, _ids), (tf, ef, idf), _read = half
    grid, rule = _grid(half)
    clock = time.perf_counter()
    res = run_tracker(t, en, cfg, report_times=grid, velocity=vel)
    elapsed = time.perf_counter() - clock
    args = (res.report_frame, res.report_id, res.report_xy, rule)
    return score_tracks(grid, tf, ef, idf, *args), elapsed


def tune_on_first_half(h1: tuple, kind: str, assoc: str) -> tuple[dict, str]:
    """Stone Soup's best setting of ``GRID[kind]`` on the first half by HOTA, and its grid
    as text (HOTA per setting)."""
    best, best_h, lines = {}, -np.inf, []
    for q in GRID[kind]["q"]:
        for d in GRID[kind]["delete_s"]:
            st = {"q": q, "delete_s": d}
            sc, el = score_stonesoup(h1, assoc, st, FIXED[kind], SCAN_S[kind])
            print(
                f"  h1 q={q:g} delete={d:g} s: HOTA {sc.hota:.3f} / MOTA {sc.mota:.3f} / "
                f"IDF1 {sc.idf1:.3f} / {sc.id_switches} switches ({el:.1f} s)",
                flush=True,
            )
            lines.append(f"{q:g}/{d:g} s {sc.hota:.3f}")
            if sc.hota > best_h:
                best, best_h = st, sc.hota
    return best, "h1 HOTA by q/delete: " + ", ".join(lines)


def stonesoup_installed() -> bool:
    try:
        import stonesoup  # noqa: F401
    except ImportError:
        print("Stone Soup is not installed (pip install -e '.[compare]'): nothing to compare")
        return False
    return True


def _row(name: str, s: Scores, confirmed: str) -> str:
    return (
        f"| {name} | {s.hota:.3f} | {s.mota:.3f} | {s.idf1:.3f} | {s.id_switches} | {confirmed} |"
    )


def compare(halves: dict, kind: str, assoc: str, reps: int) -> None:
    """Stone Soup tuned on h1 beside navtrack (``auto`` on h2 without its ids) on h2."""
    best, _grid_text = tune_on_first_half(halves["h1"], kind, assoc)
    h2 = halves["h2"]
    clock = time.perf_counter()
    t2, en2, vel2 = h2[2]
    cfg = auto_config(t2, en2, vel2, assoc).config
    tune_s = time.perf_counter() - clock
    t_ss, t_nt = [], []
    for _ in range(reps):
        ss, el = score_stonesoup(h2, assoc, best, FIXED[kind], SCAN_S[kind])
        t_ss.append(el)
        nt, el = score_navtrack(h2, assoc, cfg)
        t_nt.append(el)
    print(f"\nh2, {assoc} (Stone Soup: q={best['q']:g}, delete {best['delete_s']:g} s)")
    print("| tracker | HOTA | MOTA | IDF1 | id switches | tracks / ids |")
    print("|---|---|---|---|---|---|")
    print(_row("Stone Soup, tuned on h1", ss, f"{ss.n_tracks} / {ss.n_ids}"))
    print(_row("navtrack, no flags", nt, f"{nt.n_tracks} / {nt.n_ids}"))
    med_ss, med_nt = float(np.median(t_ss)), float(np.median(t_nt))
    print(
        f"tracking time (s): Stone Soup {med_ss:.2f}, navtrack {med_nt:.2f} "
        f"(+ {tune_s:.2f} auto tuning); ratio Stone Soup / navtrack {med_ss / med_nt:.1f}, "
        f"with navtrack's tuning {med_ss / (med_nt + tune_s):.1f}",
        flush=True,
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--files", default="opensky,solent")
    ap.add_argument("--associators", default="gnn,jpda")
    ap.add_argument("--reps", type=int, default=1)
    a = ap.parse_args(argv)
    if not stonesoup_installed():
        return 0
    for item in a.files.split(","):
        kind, _, path = item.partition(":")
        if path:
            halves = load(Path(path), None)
        else:
            path_, fmt, kind = FILES[item]
            halves = load(path_, fmt)
        for assoc in a.associators.split(","):
            print(f"\n{item}, {assoc} ({kind}): Stone Soup's grid on h1", flush=True)
            compare(halves, kind, assoc, a.reps)
    return 0


if __name__ == "__main__":
    sys.exit(main())
