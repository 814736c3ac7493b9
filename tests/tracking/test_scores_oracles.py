"""CLEAR-MOT and HOTA against independent implementations on the shared files' scoring frames.

Oracles: py-motmetrics (``motmetrics``, MOTAccumulator + metrics.compute) for MOTA, MOTP, id
switches, fragmentations, misses and false positives; TrackEval (``trackeval``, the HOTA
authors' code, ``metrics.HOTA().eval_sequence``) for HOTA, DetA, AssA and LocA with the same
point similarity. Hand-checked HOTA cases follow the definitions of Luiten et al. (2021).

The frames are those the CLI scores on: the ids' positions interpolated on the report grid of
the Solent AIS and OpenSky files. Hypotheses are the OpenSky tracker output, and for both files
the truth perturbed by a seeded generator (noise, dropped stretches, id swaps, false tracks),
so that every counted event occurs many times.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest

from navtrack.io.tracks import read_tracks, to_local_enu
from navtrack.tracking.metrics import clear_mot, hota, id_scores, interpolate_truth

# (file, format, report interval s, max truth gap s, match threshold m): the CLI's defaults
FILES = {
    "ais": ("SolentAIS_20160112_130211.csv", "ais", 60.0, 400.0, 500.0),
    "opensky": ("OpenSky_Plane_States.csv", "opensky", 10.0, 60.0, 2000.0),
}


def _frames(shared_data: Path, name: str):
    fname, fmt, report_s, gap_s, match_m = FILES[name]
    det = read_tracks(shared_data / "tracking" / fname, fmt)
    en, _ = to_local_enu(det)
    t0 = det.t_gps_s[0]
    grid = t0 + np.arange(0.0, det.t_gps_s[-1] - t0 + 1e-9, report_s)
    tf, tid, tpos = interpolate_truth(grid, det.t_gps_s, det.id, en, gap_s)
    return det, en, grid, (tf, tid, tpos), match_m


def _perturbed(tf, tid, tpos, match_m: float, seed: int):
    """Hypotheses from the truth: noise of match_m/3, stretches dropped, some ids swapped
    for the second half of their frames, false tracks."""
    rng = np.random.default_rng(seed)
    names = np.unique(tid)
    hid = np.searchsorted(names, tid).astype(np.int64)
    hpos = tpos + rng.normal(0.0, match_m / 3, tpos.shape)
    keep = rng.random(tf.size) > 0.1
    # a stretch of 3 frames dropped for a quarter of the ids (fragmentations)
    for u in rng.choice(names.size, names.size // 4, replace=False):
        k = np.flatnonzero(hid == u)
        if k.size > 6:
            keep[k[k.size // 2 : k.size // 2 + 3]] = False
    # a fifth of the ids take a new id for their later frames (id switches)
    for u in rng.choice(names.size, names.size // 5, replace=False):
        k = np.flatnonzero(hid == u)
        hid[k[k.size // 2 :]] = 10_000 + u
    n_false = tf.size // 20
    false_f = rng.choice(np.unique(tf), n_false)
    false_pos = tpos[rng.integers(0, tf.size, n_false)] + rng.normal(0, 5 * match_m, (n_false, 2))
    return (
        np.r_[tf[keep], false_f],
        np.r_[hid[keep], 20_000 + np.arange(n_false)],
        np.r_[hpos[keep], false_pos],
    )


def _motmetrics(tf, tid, tpos, hf, hid, hpos, threshold):
    mm = pytest.importorskip("motmetrics")
    from scipy.spatial.distance import cdist

    acc = mm.MOTAccumulator(auto_id=False)
    tid = np.unique(tid, return_inverse=True)[1]  # integer ids (the metric does not change)
    for f in np.union1d(tf, hf):
        ti, hi = np.flatnonzero(tf == f), np.flatnonzero(hf == f)
        d = cdist(tpos[ti], hpos[hi]) if ti.size and hi.size else np.zeros((ti.size, hi.size))
        d[d > threshold] = np.nan  # pairs beyond the threshold cannot match
        acc.update(list(tid[ti]), list(hid[hi]), d, frameid=int(f))
    names = [
        "idf1",
        "idp",
        "idr",
        "mota",
        "motp",
        "num_switches",
        "num_fragmentations",
        "num_misses",
        "num_false_positives",
    ]
    out = mm.metrics.create().compute(acc, metrics=names, name="x")
    return {n: float(out[n].iloc[0]) for n in names}


@lru_cache(maxsize=4)
def _hypotheses(shared_data: Path, name: str, source: str):
    det, en, grid, (tf, tid, tpos), match_m = _frames(shared_data, name)
    if source == "perturbed":
        hf, hid, hpos = _perturbed(tf, tid, tpos, match_m, seed=11)
    else:
        from navtrack.io.tracks import velocity_local_enu
        from navtrack.tracking.trackers.tracker import TrackerConfig, run_tracker

        res = run_tracker(
            det.t_gps_s,
            en,
            TrackerConfig.for_aircraft(),
            report_times=grid,
            velocity=velocity_local_enu(det),
        )
        hf, hid, hpos = res.report_frame, res.report_id, res.report_xy
    return (tf, tid, tpos), (hf, hid, hpos), match_m


CASES = [("ais", "perturbed"), ("opensky", "perturbed"), ("opensky", "tracker")]


@pytest.mark.parametrize(("name", "source"), CASES)
def test_clear_mot_equals_motmetrics(shared_data: Path, name: str, source: str) -> None:
    (tf, tid, tpos), (hf, hid, hpos), match_m = _hypotheses(shared_data, name, source)
    ours = clear_mot(tf, tid, tpos, hf, hid, hpos, match_m)
    ref = _motmetrics(tf, tid, tpos, hf, hid, hpos, match_m)
    assert ours.id_switches == ref["num_switches"] > 0
    assert ours.fragmentations == ref["num_fragmentations"]
    assert ours.n_misses == ref["num_misses"]
    assert ours.n_false == ref["num_false_positives"]
    assert ours.mota == pytest.approx(ref["mota"], abs=1e-12)
    assert ours.motp == pytest.approx(ref["motp"], rel=1e-12)
    if source == "perturbed":
        assert ours.fragmentations > 0


@pytest.mark.parametrize(("name", "source"), CASES)
def test_id_scores_equal_motmetrics(shared_data: Path, name: str, source: str) -> None:
    (tf, tid, tpos), (hf, hid, hpos), match_m = _hypotheses(shared_data, name, source)
    ours = id_scores(tf, tid, tpos, hf, hid, hpos, match_m)
    ref = _motmetrics(tf, tid, tpos, hf, hid, hpos, match_m)
    assert 0.3 < ours.idf1 < 0.99  # id swaps and false tracks leave room on both sides
    assert ours.idf1 == pytest.approx(ref["idf1"], abs=1e-12)
    assert ours.idp == pytest.approx(ref["idp"], abs=1e-12)
    assert ours.idr == pytest.approx(ref["idr"], abs=1e-12)


def _trackeval_hota(tf, tid, tpos, hf, hid, hpos, threshold):
    te = pytest.importorskip("trackeval")
    from scipy.spatial.distance import cdist

    frames = np.union1d(tf, hf)
    g_names, g = np.unique(tid, return_inverse=True)
    k_names, k = np.unique(hid, return_inverse=True)
    data: dict = {
        "num_timesteps": frames.size,
        "num_gt_ids": g_names.size,
        "num_tracker_ids": k_names.size,
        "num_gt_dets": tf.size,
        "num_tracker_dets": hf.size,
        "gt_ids": [],
        "tracker_ids": [],
        "similarity_scores": [],
    }
    for f in frames:
        ti, hi = np.flatnonzero(tf == f), np.flatnonzero(hf == f)
        D = cdist(tpos[ti], hpos[hi]) if ti.size and hi.size else np.zeros((ti.size, hi.size))
        data["gt_ids"].append(g[ti])
        data["tracker_ids"].append(k[hi])
        data["similarity_scores"].append(np.maximum(0.0, 1.0 - D / threshold))
    res = te.metrics.HOTA().eval_sequence(data)
    return {key: float(np.mean(res[key])) for key in ("HOTA", "DetA", "AssA", "LocA")}


@pytest.mark.parametrize(("name", "source"), CASES)
def test_hota_equals_trackeval(shared_data: Path, name: str, source: str) -> None:
    (tf, tid, tpos), (hf, hid, hpos), match_m = _hypotheses(shared_data, name, source)
    ours = hota(tf, tid, tpos, hf, hid, hpos, match_m)
    ref = _trackeval_hota(tf, tid, tpos, hf, hid, hpos, match_m)
    assert ours.hota == pytest.approx(ref["HOTA"], abs=1e-9)
    assert ours.det_a == pytest.approx(ref["DetA"], abs=1e-9)
    assert ours.ass_a == pytest.approx(ref["AssA"], abs=1e-9)
    assert ours.loc_a == pytest.approx(ref["LocA"], abs=1e-9)


def test_hota_hand_cases() -> None:
    """Cases worked from the paper's definitions (Luiten et al. 2021, eq. 4-10)."""
    f = np.arange(4)
    pos = np.zeros((4, 2))
    ids = np.zeros(4, dtype=int)
    # perfect: every pair at distance 0 -> similarity 1 -> TP at every alpha, AssA 1
    h = hota(f, ids, pos, f, ids, pos, 10.0)
    assert (h.hota, h.det_a, h.ass_a, h.loc_a) == (1.0, 1.0, 1.0, 1.0)
    # one object tracked by two hypotheses, two frames each: DetA 1; every TP has TPA 2,
    # FNA 2 (the object's other frames), FPA 0 -> A = 1/2; HOTA = sqrt(1/2)
    h = hota(f, ids, pos, f, np.array([0, 0, 1, 1]), pos, 10.0)
    assert h.det_a == 1.0
    assert h.ass_a == pytest.approx(0.5)
    assert h.hota == pytest.approx(np.sqrt(0.5))
    # the hypothesis 5 m off with threshold 10: similarity 1/2, a TP for alpha <= 0.5 only
    # (10 of the 19 alphas); DetA = AssA = HOTA = 10/19 averaged, LocA 1/2 on the TPs and 1
    # (nothing to localise) where there is no TP
    h = hota(f, ids, pos, f, ids, pos + np.array([5.0, 0.0]), 10.0)
    assert h.hota == pytest.approx(10 / 19)
    assert h.det_a == pytest.approx(10 / 19)
    assert h.loc_a == pytest.approx((10 * 0.5 + 9 * 1.0) / 19)
    # a missed frame and a false hypothesis at alpha 1: DetA = 3 / (3 + 1 + 1)
    hf = np.array([0, 1, 2, 3])
    hp = pos.copy()
    hp[3] = [100.0, 0.0]
    h = hota(f, ids, pos, hf, ids, hp, 10.0)
    assert h.det_a == pytest.approx(3 / 5)
    # AssA: TPA 3, FNA 1, FPA 1 -> 3/5 for each TP
    assert h.ass_a == pytest.approx(3 / 5)
