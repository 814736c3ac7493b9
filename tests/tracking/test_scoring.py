"""The scoring rule of real report files: reporting gaps, the covered area, layouts.

Hand cases follow the rule as documented in ``navtrack.tracking.scoring``; the metrics
themselves are checked against py-motmetrics and TrackEval in ``test_scores_oracles.py``.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from navtrack.io.tracks import read_tracks, stale_repeats, to_local_enu
from navtrack.timescale import gps_to_utc, to_datetime64
from navtrack.tracking.metrics import (
    clear_mot,
    ignored_hypotheses,
    interpolate_truth,
    outside_coverage,
    truth_gaps,
)
from navtrack.tracking.scoring import ScoringRule, score_tracks, scoring_rule

# one id reporting every 10 s at 10 m/s east, silent for 180 s (t 20 -> 200) and 790 s
# (t 210 -> 1000)
T_REPORTS = np.array([0.0, 10.0, 20.0, 200.0, 210.0, 1000.0, 1010.0])
POS = np.c_[10.0 * T_REPORTS, np.zeros(T_REPORTS.size)]
FRAMES = np.arange(0.0, 1011.0, 10.0)


def test_truth_gaps_are_the_interpolated_frames_of_the_longer_silences() -> None:
    ids = np.zeros(T_REPORTS.size, dtype=int)
    tf, _, _ = interpolate_truth(FRAMES, T_REPORTS, ids, POS, 60.0)
    gf, gid, gpos = truth_gaps(FRAMES, T_REPORTS, ids, POS, 60.0, 600.0)
    assert FRAMES[tf].tolist() == [0.0, 10.0, 20.0, 200.0, 210.0, 1000.0, 1010.0]
    # strictly inside the 180 s silence; the 790 s one is longer than 600 s
    assert FRAMES[gf].tolist() == list(np.arange(30.0, 191.0, 10.0))
    assert (gid == 0).all()
    np.testing.assert_allclose(gpos[:, 0], 10.0 * FRAMES[gf])  # straight line between reports
    assert truth_gaps(FRAMES, T_REPORTS, ids, POS, 60.0, 1000.0)[0].size == 17 + 78


def test_ignored_hypotheses_hand_cases() -> None:
    # frame 0: a true position at x = 0 and an ignored one at x = 1000 (500 m threshold)
    tf, tpos = np.array([0]), np.array([[0.0, 0.0]])
    gf, gpos = np.array([0]), np.array([[1000.0, 0.0]])
    hf = np.array([0, 0, 0])
    hpos = np.array([[10.0, 0.0], [1010.0, 0.0], [5000.0, 0.0]])
    flags = ignored_hypotheses(tf, tpos, gf, gpos, hf, hpos, 500.0)
    assert flags.tolist() == [False, True, False]
    outside = np.array([True, False, True])  # the one on the true position is scored anyway
    flags = ignored_hypotheses(tf, tpos, gf, gpos, hf, hpos, 500.0, outside)
    assert flags.tolist() == [False, True, True]
    # two hypotheses near the true position: one matches it, the other is false, not ignored
    hpos2 = np.array([[10.0, 0.0], [20.0, 0.0]])
    flags = ignored_hypotheses(tf, tpos, np.array([], int), np.zeros((0, 2)), [0, 0], hpos2, 500.0)
    assert flags.tolist() == [False, False]


def test_outside_coverage_is_the_convex_hull_of_the_reports() -> None:
    square = np.array([[0.0, 0.0], [100.0, 0.0], [100.0, 100.0], [0.0, 100.0], [50.0, 50.0]])
    pts = np.array([[50.0, 50.0], [99.0, 1.0], [101.0, 50.0], [-1.0, -1.0]])
    assert outside_coverage(pts, square).tolist() == [False, False, True, True]
    # reports on one line span no area: everything is outside
    assert outside_coverage(pts, [[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]).all()


def test_a_track_coasting_through_a_reporting_gap_is_neither_match_nor_false() -> None:
    ids = np.zeros(T_REPORTS.size, dtype=int)
    hf = np.arange(FRAMES.size)  # the track follows the target at every frame
    hxy = np.c_[10.0 * FRAMES, np.zeros(FRAMES.size)]
    hid = np.zeros(FRAMES.size, dtype=int)
    rule = ScoringRule(10.0, 60.0, 500.0, coverage=False)
    s = score_tracks(FRAMES, T_REPORTS, POS, ids, hf, hid, hxy, rule)
    # 7 frames on reports scored; 17 in the 180 s silence ignored; the 78 in the 790 s
    # silence are false (the target was gone for longer than IGNORE_GAP_S)
    assert (s.n_truth, s.n_matches, s.n_false, s.n_ignored) == (7, 7, 78, 17)
    assert s.n_tracks == 1
    old = score_tracks(
        FRAMES, T_REPORTS, POS, ids, hf, hid, hxy, dataclasses.replace(rule, ignore_gap_s=0.0)
    )
    assert (old.n_false, old.n_ignored) == (95, 0)
    # reports along one line cover no area: with the covered area on, no track is false
    on = score_tracks(FRAMES, T_REPORTS, POS, ids, hf, hid, hxy, ScoringRule(10.0, 60.0, 500.0))
    assert (on.n_matches, on.n_false, on.n_ignored) == (7, 0, 95)
    # the scores are those of the metrics on the hypotheses left in
    keep = np.ones(FRAMES.size, dtype=bool)
    keep[3:20] = False
    tf, tid, tpos = interpolate_truth(FRAMES, T_REPORTS, ids, POS, 60.0)
    ref = clear_mot(tf, tid, tpos, hf[keep], hid[keep], hxy[keep], 500.0)
    assert s.mota == pytest.approx(ref.mota) == pytest.approx(1.0 - 78 / 7)


def test_same_reports_score_alike_in_the_opensky_and_csv_layouts(
    shared_data: Path, tmp_path: Path
) -> None:
    det = read_tracks(shared_data / "tracking" / "OpenSky_Plane_States.csv", "opensky")
    utc = pd.to_datetime(to_datetime64(gps_to_utc(det.t_gps_s)))
    path = tmp_path / "opensky.csv"
    pd.DataFrame(
        {
            "time": utc.strftime("%Y-%m-%dT%H:%M:%S.%fZ"),
            "id": det.id,
            "lat": det.lat_deg,
            "lon": det.lon_deg,
            "alt_m": det.alt_m,
            "speed_mps": det.speed_mps,
            "course_deg": det.course_deg,
        }
    ).to_csv(path, index=False, float_format="%.10f")
    csv = read_tracks(path, "csv")
    assert csv.format == "csv"
    truths = []
    for d in (det, csv):
        en, _ = to_local_enu(d)
        fresh = ~stale_repeats(d.t_gps_s, en, d.speed_mps, d.id)
        rule = scoring_rule(d.t_gps_s[fresh], d.id[fresh])
        grid = d.t_gps_s[0] + np.arange(0.0, d.t_gps_s[-1] - d.t_gps_s[0] + 1e-9, rule.report_s)
        truths.append(
            (
                rule,
                interpolate_truth(grid, d.t_gps_s[fresh], d.id[fresh], en[fresh], rule.max_gap_s),
            )
        )
    (rule_a, (fa, ia, pa)), (rule_b, (fb, ib, pb)) = truths
    assert rule_a == rule_b == ScoringRule(10.0, 60.0, 500.0)
    np.testing.assert_array_equal(fa, fb)
    np.testing.assert_array_equal(ia, ib)
    np.testing.assert_allclose(pa, pb, atol=1e-3)
