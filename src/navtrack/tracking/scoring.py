"""One scoring rule for tracks of real reports, whatever the file's layout.

The truth of a report file with ids is each id's own reports, its stale repeats left out
(:func:`navtrack.io.tracks.stale_repeats` within the id: a repeated position is not where the
target was at the repeat's time), interpolated linearly on a regular grid of frame times
between two reports at most ``max_gap_s`` apart
(:func:`~navtrack.tracking.metrics.interpolate_truth`).
Confirmed tracks predicted to the same frame times are scored against it by CLEAR-MOT,
HOTA and the identity scores IDF1 / IDP / IDR, all with one match threshold.

Between two reports of an id more than ``max_gap_s`` apart the target is in view of nobody's
truth: the file does not say where it was. A tracker that coasts a track through such a gap
is neither right nor wrong there, so at those frames the id is a don't-care object at the
straight line between the two reports (:func:`~navtrack.tracking.metrics.truth_gaps`), for
gaps up to ``ignore_gap_s``: a track matched to it (within the threshold, one-to-one with
the true positions of the frame, :func:`~navtrack.tracking.metrics.ignored_hypotheses`) is
left out of every score, as TrackEval leaves out tracker boxes on MOTChallenge's
distractors. A longer silence is a target gone (landed, moored out of range, out of
coverage), and a track there counts as false.

Likewise a file covers an area (a receiver's range, a region cut out of a larger feed, such
as a circle around an airport): outside the convex hull of all its reports nothing says
whether a target is there. A track position outside that hull which matches no true
position is left out of every score (:func:`~navtrack.tracking.metrics.outside_coverage`);
inside it, an unmatched track is false.

The grid, the gap and the threshold come from the data, not from the layout
(:func:`scoring_rule`): the frame interval is the median over the ids of their median
interval between reports, the largest gap twice the 95 % point of those intervals (at least
``MIN_GAP_S``), the threshold ``MATCH_M``. AIS ships reporting every 2 s to 3 min and ADS-B
aircraft every 1-10 s are thus scored by the same rule, and the same reports written in two
layouts score the same.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from navtrack._typing import ArrayLike, FloatArray
from navtrack.tracking.metrics import (
    clear_mot,
    hota,
    id_scores,
    ignored_hypotheses,
    interpolate_truth,
    outside_coverage,
    truth_gaps,
)

__all__ = [
    "IGNORE_GAP_S",
    "MATCH_M",
    "MIN_GAP_S",
    "Scores",
    "ScoringRule",
    "score_tracks",
    "scoring_rule",
]

MATCH_M = 500.0
"""Match threshold (m): a confirmed track within it of a true position may match it."""
MIN_GAP_S = 60.0
"""The truth is interpolated over gaps of at least this long (s)."""
MAX_FRAME_S = 60.0
"""The frame interval is at most this long (s), and at least 1 s."""
IGNORE_GAP_S = 600.0
"""Longest reporting gap of an id (s) inside which a track on its straight line is not scored
(docs/tracking.md, "The scoring rule": chosen on the readsb traces of KWVI and Monterey)."""


@dataclass(frozen=True, slots=True)
class ScoringRule:
    """Frame interval, largest interpolated truth gap (s), match threshold (m), longest gap
    (s) in which a track on the id's straight line is ignored, and whether tracks outside the
    area the reports cover are ignored (when they match no true position)."""

    report_s: float
    max_gap_s: float
    match_m: float
    ignore_gap_s: float = IGNORE_GAP_S
    coverage: bool = True


def scoring_rule(t_s: ArrayLike, ids: ArrayLike) -> ScoringRule:
    """The scoring rule of the module notes for reports ``t_s (N,)`` of ids ``ids (N,)``
    (stale repeats already left out)."""
    import pandas as pd

    df = pd.DataFrame({"t": np.asarray(t_s, dtype=float), "id": np.asarray(ids)})
    df = df.sort_values(["id", "t"], kind="stable")
    dt = df.groupby("id", sort=False)["t"].diff()
    per_id = dt[dt > 0].groupby(df["id"]).median().to_numpy()
    if per_id.size == 0:
        return ScoringRule(MAX_FRAME_S, MIN_GAP_S, MATCH_M)
    p50, p95 = np.quantile(per_id, [0.5, 0.95])
    return ScoringRule(
        float(np.clip(p50, 1.0, MAX_FRAME_S)), float(max(MIN_GAP_S, 2.0 * p95)), MATCH_M
    )


@dataclass(frozen=True, slots=True)
class Scores:
    """Scores of one run (:func:`score_tracks`).

    Attributes
    ----------
    mota, motp_m, id_switches, fragmentations, purity, n_truth, n_matches, n_misses, n_false :
        CLEAR-MOT (:func:`~navtrack.tracking.metrics.clear_mot`)
    hota, det_a, ass_a : HOTA (:func:`~navtrack.tracking.metrics.hota`)
    idf1, idp, idr : identity scores (:func:`~navtrack.tracking.metrics.id_scores`)
    n_ids : distinct true ids
    n_tracks : distinct track ids reported at the frames (confirmed tracks)
    n_ignored : track positions left out (on an id inside its reporting gap, or outside the
        area the reports cover)
    """

    mota: float
    motp_m: float
    id_switches: int
    fragmentations: int
    purity: float
    n_truth: int
    n_matches: int
    n_misses: int
    n_false: int
    hota: float
    det_a: float
    ass_a: float
    idf1: float
    idp: float
    idr: float
    n_ids: int
    n_tracks: int
    n_ignored: int


def score_tracks(
    frame_times: FloatArray,
    t_s: ArrayLike,
    pos: ArrayLike,
    ids: ArrayLike,
    report_frame: ArrayLike,
    report_id: ArrayLike,
    report_xy: ArrayLike,
    rule: ScoringRule,
) -> Scores:
    """Score confirmed tracks at ``frame_times`` (``TrackerResult.report_*``) against the
    truth interpolated from the reports ``t_s, pos (N, 2), ids`` (stale repeats left out)."""
    ids = np.asarray(ids)
    hf, hid = np.asarray(report_frame), np.asarray(report_id)
    hxy = np.asarray(report_xy, dtype=float)
    tf, tid, tpos = interpolate_truth(frame_times, t_s, ids, pos, rule.max_gap_s)
    gap = truth_gaps(frame_times, t_s, ids, pos, rule.max_gap_s, rule.ignore_gap_s)
    outside = outside_coverage(hxy, pos) if rule.coverage else None
    drop = ignored_hypotheses(tf, tpos, gap[0], gap[2], hf, hxy, rule.match_m, outside)
    args = (tf, tid, tpos, hf[~drop], hid[~drop], hxy[~drop], rule.match_m)
    mot = clear_mot(*args)
    hot = hota(*args)
    ids_ = id_scores(*args)
    return Scores(
        mota=mot.mota,
        motp_m=mot.motp,
        id_switches=mot.id_switches,
        fragmentations=mot.fragmentations,
        purity=mot.purity,
        n_truth=mot.n_truth,
        n_matches=mot.n_matches,
        n_misses=mot.n_misses,
        n_false=mot.n_false,
        hota=hot.hota,
        det_a=hot.det_a,
        ass_a=hot.ass_a,
        idf1=ids_.idf1,
        idp=ids_.idp,
        idr=ids_.idr,
        n_ids=int(np.unique(ids).size),
        n_tracks=int(np.unique(hid).size),
        n_ignored=int(drop.sum()),
    )
