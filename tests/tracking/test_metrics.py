"""Metrics against hand-computed values from the definitions in the cited papers."""

from __future__ import annotations

import numpy as np
import pytest

from navtrack.tracking.metrics import (
    clear_mot,
    gospa,
    gospa_sequence,
    interpolate_truth,
    ospa,
    rmse,
)


def test_ospa_hand_values() -> None:
    # Schuhmacher et al. 2008 eq. (3): d = ((1/n)(min sum d_c^p + c^p (n - m)))^(1/p)
    assert ospa([[0.0, 0.0]], [[3.0, 4.0]], c=10, p=2) == pytest.approx(5.0)
    assert ospa([[0.0, 0.0], [10.0, 0.0]], [[0.0, 1.0]], c=4, p=1) == pytest.approx(2.5)
    assert ospa([[0.0]], [[100.0]], c=4, p=1) == pytest.approx(4.0)  # cut-off
    assert ospa([], [], c=4) == 0.0
    assert ospa([[1.0]], [], c=4) == 4.0


def test_gospa_hand_values() -> None:
    # Rahmathullah et al. 2017, alpha = 2: loc + c^p/2 (missed + false)
    r = gospa([[0.0], [10.0]], [[1.0]], c=4, p=1)
    assert r.distance == pytest.approx(3.0)
    assert (r.n_missed, r.n_false) == (1, 0)
    r = gospa([[0.0], [10.0]], [[1.0]], c=4, p=2)
    assert r.distance == pytest.approx(3.0)  # sqrt(1 + 16/2)
    assert r.localisation == pytest.approx(1.0)
    assert r.missed == pytest.approx(8.0)
    # a pair farther than c is cheaper as one missed + one false
    r = gospa([[0.0]], [[5.0]], c=4, p=1)
    assert (r.n_missed, r.n_false, r.localisation) == (1, 1, 0.0)


def test_gospa_switching_term() -> None:
    truth = [np.array([[0.0], [10.0]])] * 3
    tid = [np.array(["a", "b"])] * 3
    eid = [np.array([1, 2]), np.array([2, 1]), np.array([2, 1])]
    est_sw = [np.array([[0.0], [10.0]]), np.array([[10.0], [0.0]]), np.array([[10.0], [0.0]])]
    # estimates listed in another order together with their ids: no switch
    r = gospa_sequence(truth, tid, est_sw, eid, c=4, p=1, switching_cost=3.0)
    assert r.n_switches == 0
    assert r.distance == 0.0
    # same positions, ids kept: estimate 1 moves from "a" to "b" and 2 from "b" to "a"
    eid2 = [np.array([1, 2]), np.array([1, 2]), np.array([1, 2])]
    r = gospa_sequence(truth, tid, est_sw, eid2, c=4, p=1, switching_cost=3.0)
    assert r.n_switches == 2
    assert r.switching == pytest.approx(6.0)
    assert r.distance == pytest.approx(6.0)


def test_clear_mot_hand_example() -> None:
    # Bernardin & Stiefelhagen 2008: two objects, four frames (see comments)
    tf = [0, 0, 1, 1, 2, 2, 3, 3]
    tid = ["A", "B"] * 4
    tp = [[0, 0], [100, 0], [0, 10], [100, 10], [0, 20], [100, 20], [0, 30], [100, 30]]
    hf = [0, 0, 1, 1, 2, 3, 3, 3]
    hid = [1, 2, 1, 2, 1, 1, 3, 9]
    hp = [[1, 0], [101, 0], [0, 11], [100, 11], [0, 21], [0, 31], [100, 31], [500, 500]]
    m = clear_mot(tf, tid, tp, hf, hid, hp, threshold=5.0)
    assert (m.n_truth, m.n_matches, m.n_misses, m.n_false) == (8, 7, 1, 1)
    assert m.id_switches == 1  # B: track 2 -> track 3
    assert m.fragmentations == 1  # B lost in frame 2, found again in frame 3
    assert m.mota == pytest.approx(1 - 3 / 8)
    assert m.motp == pytest.approx(1.0)
    assert m.purity == pytest.approx(1.0)


def test_clear_mot_keeps_correspondence_and_purity() -> None:
    # track 7 follows A then jumps to B (A lost): one switch for B, purity 3/4
    tf = [0, 1, 2, 3, 3]
    tid = ["A", "A", "A", "B", "A"]
    tp = [[0, 0], [0, 0], [0, 0], [50, 0], [0, 0]]
    hf = [0, 1, 2, 3]
    hid = [7, 7, 7, 7]
    hp = [[0, 0], [0, 0], [0, 0], [50, 0]]
    m = clear_mot(tf, tid, tp, hf, hid, hp, threshold=5.0)
    assert m.n_matches == 4
    assert m.n_misses == 1
    assert m.id_switches == 0
    assert m.purity == pytest.approx(0.75)


def test_rmse_and_interpolation() -> None:
    est = np.zeros((4, 3, 2))
    tru = np.ones((4, 3, 2))
    np.testing.assert_allclose(rmse(est, tru), np.sqrt(2.0))
    f, i, p = interpolate_truth(
        [0, 5, 10, 100],
        [0, 10, 10.0, 20],
        ["a", "a", "b", "b"],
        [[0, 0], [10, 20], [0, 0], [10, 0]],
        max_gap_s=30,
    )
    got = {(int(a), str(b)): tuple(c) for a, b, c in zip(f, i, p, strict=True)}
    assert got == {(0, "a"): (0, 0), (1, "a"): (5, 10), (2, "a"): (10, 20), (2, "b"): (0, 0)}


def test_clear_mot_without_hypotheses() -> None:
    # issue 9, failure 3: a one-minute file gave no reported tracks and the scorer raised
    # "cannot reshape array of size 0"; every truth object is now a miss
    mot = clear_mot([0, 1], ["a", "a"], [[0.0, 0.0], [1.0, 0.0]], [], [], [], threshold=5.0)
    assert (mot.n_truth, mot.n_matches, mot.n_misses, mot.n_false) == (2, 0, 2, 0)
    assert mot.mota == 0.0
    assert np.isnan(mot.motp)
    assert mot.n_tracks == 0
    empty = clear_mot([], [], [], [0], [7], [[0.0, 0.0]], threshold=5.0)
    assert (empty.n_truth, empty.n_false) == (0, 1)
    assert np.isnan(empty.mota)
