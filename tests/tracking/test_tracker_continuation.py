"""Track continuation: a new track that continues a track ended by coasting takes its id."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from navtrack.tracking.models import constant_velocity
from navtrack.tracking.trackers.management import EndedTracks, Management, continuation
from navtrack.tracking.trackers.track_config import TrackEnd, TrackerConfig, TrackerModel
from navtrack.tracking.trackers.tracker import run_tracker

CFG = TrackerConfig(
    motion=constant_velocity(2, 1.0, "continuous"),
    sigma_m=10.0,
    confirm_hits=3,
    confirm_window_s=60.0,
    max_coast_s=20.0,
    max_position_std_m=2000.0,
    continue_tracks=True,
)


def _ended(x: np.ndarray, P: np.ndarray, t_s: float) -> EndedTracks:
    """One confirmed track deleted for coasting at ``t_s`` with state ``x`` and covariance ``P``."""
    ended = EndedTracks(4)
    ended.add(
        Management(
            id=np.array([7]),
            x=x[None],
            P=P[None],
            std_m=np.array([np.sqrt(P[0, 0])]),
            confirmed=np.array([True]),
            confirmed_new=np.array([False]),
            kept=np.array([False]),
            end_reason=np.array([TrackEnd.COAST], dtype=np.int8),
            confirmed_now=0,
            deleted_coast=1,
            deleted_covariance=0,
            deleted_unconfirmed=0,
        ),
        t_s,
    )
    return ended


def test_continuation_links_the_predicted_track_only() -> None:
    model = TrackerModel.from_config(CFG)
    P = np.diag([100.0, 4.0, 100.0, 4.0])  # state [x, vx, y, vy]
    ended = _ended(np.array([0.0, 50.0, 0.0, 0.0]), P, 100.0)
    # at t = 150 s the ended track is predicted at x = 2500 m moving east at 50 m/s
    x_new = np.array(
        [
            [2510.0, 49.0, -5.0, 0.5],  # the same target
            [2500.0, 0.0, 3000.0, 40.0],  # another target, 3 km away, heading north
        ]
    )
    link = continuation(ended, x_new, np.stack([P, P]), 150.0, model)
    np.testing.assert_array_equal(link, [7, -1])
    assert ended.id.size == 0  # continued: forgotten
    # the same pair when the ended track's prediction is wider than a track may be: no link
    wide = continuation(
        ended,
        x_new[:1],
        P[None],
        150.0,
        TrackerModel.from_config(replace(CFG, max_position_std_m=50.0)),
    )
    np.testing.assert_array_equal(wide, [-1])


def test_continuation_mutual_best() -> None:
    """Two new tracks inside one ended track's gate: only the likelier one continues it."""
    model = TrackerModel.from_config(CFG)
    P = np.diag([100.0, 4.0, 100.0, 4.0])
    ended = _ended(np.array([0.0, 50.0, 0.0, 0.0]), P, 100.0)
    x_new = np.array([[2560.0, 52.0, 40.0, 1.0], [2505.0, 50.0, 5.0, 0.0]])
    link = continuation(ended, x_new, np.stack([P, P]), 150.0, model)
    np.testing.assert_array_equal(link, [-1, 7])


def _scene() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Target 0 moving east at 50 m/s, reported every 2 s except over 60-100 s (longer than
    the coast); target 1, 5 km away moving north, is reported from t = 71 s on (its scans
    delete target 0's coasting track)."""
    rng = np.random.default_rng(3)
    t0 = np.r_[np.arange(0.0, 61.0, 2.0), np.arange(100.0, 161.0, 2.0)]
    z0 = np.c_[50.0 * t0, np.zeros_like(t0)]
    t1 = np.arange(71.0, 161.0, 2.0)
    z1 = np.c_[np.full_like(t1, 4000.0), -5000.0 + 40.0 * (t1 - 71.0)]
    t = np.r_[t0, t1]
    z = np.r_[z0, z1] + rng.normal(0.0, CFG.sigma_m, (t.size, 2))
    truth = np.r_[np.zeros(t0.size, int), np.ones(t1.size, int)]
    order = np.argsort(t, kind="stable")
    return t[order], z[order], truth[order], np.zeros((t.size, 2))


def test_tracker_keeps_identity_over_a_gap() -> None:
    t, z, truth, _ = _scene()
    res = run_tracker(t, z, CFG)
    ids0 = set(res.det_track[(truth == 0) & (res.det_track >= 0)].tolist())
    ids1 = set(res.det_track[(truth == 1) & (res.det_track >= 0)].tolist())
    assert len(ids0) == 1
    assert len(ids1) == 1
    assert ids0 != ids1
    assert res.counts.tracks_continued == 1
    assert res.end_id.size == np.unique(res.end_id).size  # one end row per track
    # without the rule the target comes back as a second track
    off = run_tracker(t, z, replace(CFG, continue_tracks=False))
    assert len(set(off.det_track[(truth == 0) & (off.det_track >= 0)].tolist())) == 2
    assert off.counts.tracks_continued == 0
