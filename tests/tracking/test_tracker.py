"""Simulation and tracker tests: seeded simulators, tracker on known truth, bad input."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from navtrack.tracking.metrics import clear_mot
from navtrack.tracking.models import constant_velocity, linear_position
from navtrack.tracking.simulate import simulate_detections, simulate_truth
from navtrack.tracking.trackers.tracker import DetStatus, TrackerConfig, run_tracker


def test_simulators_are_seeded_and_statistically_right() -> None:
    mot = constant_velocity(2, 0.1)
    meas = linear_position(4, (0, 2), 5.0)
    x0 = np.array([[0.0, 10, 0, 0], [1000, 0, 1000, -5]])
    t1 = simulate_truth(mot, x0, 400, 1.0, np.random.default_rng(1))
    t2 = simulate_truth(mot, x0, 400, 1.0, np.random.default_rng(1))
    np.testing.assert_array_equal(t1, t2)
    assert t1.shape == (400, 2, 4)
    np.testing.assert_allclose(simulate_truth(mot, x0, 3, 2.0)[2, 0], [40, 10, 0, 0])
    det = simulate_detections(
        t1, meas, 0.8, 3.0, [-5000, -5000], [5000, 5000], np.random.default_rng(2)
    )
    n_clutter = ((det.origin == -1) & det.valid).sum(axis=1)
    n_target = ((det.origin >= 0) & det.valid).sum()
    # Poisson(3) mean over 400 scans: sd of the mean 0.087; Pd 0.8 over 800: sd 0.014
    assert abs(n_clutter.mean() - 3.0) < 0.4
    assert abs(n_target / 800 - 0.8) < 0.06
    k, j = np.nonzero((det.origin >= 0) & det.valid)
    err = det.z[k, j] - t1[k, det.origin[k, j]][:, [0, 2]]
    assert abs(err.std() - 5.0) < 0.5


def _scenario(seed: int, n_targets: int = 5, steps: int = 60):
    rng = np.random.default_rng(seed)
    mot = constant_velocity(2, 0.05, "continuous")
    meas = linear_position(4, (0, 2), 10.0)
    x0 = np.zeros((n_targets, 4))
    x0[:, 0] = np.arange(n_targets) * 2000.0
    x0[:, 1] = rng.uniform(-8, 8, n_targets)
    x0[:, 3] = rng.uniform(-8, 8, n_targets)
    truth = simulate_truth(mot, x0, steps, 10.0, rng)
    det = simulate_detections(truth, meas, 0.9, 0.5, [-3000, -3000], [12000, 3000], rng)
    t, z, origin = [], [], []
    for k in range(steps):
        v = det.valid[k]
        t += [10.0 * k] * int(v.sum())
        z.append(det.z[k][v])
        origin.append(det.origin[k][v])
    return truth, np.array(t), np.concatenate(z), np.concatenate(origin)


@pytest.mark.parametrize("associator", ["gnn", "jpda"])
def test_tracker_follows_separated_targets(associator: str) -> None:
    truth, t, z, origin = _scenario(4)
    cfg = TrackerConfig(
        sigma_m=10.0,
        associator=associator,
        pd=0.9,
        clutter_density=0.5 / 4.5e7,
        max_coast_s=60.0,
        confirm_window_s=60.0,
        init_max_dt_s=30.0,
    )
    frames = np.arange(0, 600.0, 10.0)
    res = run_tracker(t, z, cfg, report_times=frames)
    K, n = truth.shape[:2]
    tf = np.repeat(np.arange(K), n)
    tid = np.tile(np.arange(n), K)
    tp = truth[:, :, [0, 2]].reshape(-1, 2)
    m = clear_mot(tf, tid, tp, res.report_frame, res.report_id, res.report_xy, 100.0)
    assert m.id_switches == 0
    assert m.mota > 0.85  # misses only while tracks are being confirmed
    assert m.purity == 1.0
    assert res.counts.tracks_confirmed == n
    # detections that updated confirmed tracks came from one target per track
    sel = (res.det_status == DetStatus.CONFIRMED) & (origin >= 0)
    for tid_ in np.unique(res.det_track[sel]):
        assert np.unique(origin[sel & (res.det_track == tid_)]).size == 1


def test_tracker_rejects_bad_input() -> None:
    with pytest.raises(ValueError, match="non-decreasing: detection 2"):
        run_tracker([0.0, 1.0, 0.5], np.zeros((3, 2)))
    with pytest.raises(ValueError, match="finite: detection 1"):
        run_tracker([0.0, 1.0], np.array([[0.0, 0.0], [np.nan, 1.0]]))
    with pytest.raises(ValueError, match="associator"):
        TrackerConfig(associator="mht")  # type: ignore[arg-type]
    empty = run_tracker(np.zeros(0), np.zeros((0, 2)))
    assert empty.det_track.size == 0
    assert empty.counts.scans == 0


def test_imm_with_identical_models_equals_single_model() -> None:
    # Blom & Bar-Shalom 1988: with identical models the mixing is exact and the IMM reduces to
    # the single-model filter, whatever the switching probability
    _, t, z, _ = _scenario(5, n_targets=3, steps=30)
    base = TrackerConfig(
        sigma_m=10.0,
        pd=0.9,
        clutter_density=0.5 / 4.5e7,
        max_coast_s=60.0,
        confirm_window_s=60.0,
        init_max_dt_s=30.0,
    )
    for assoc in ("gnn", "jpda"):
        a = run_tracker(t, z, replace(base, associator=assoc))
        b = run_tracker(
            t, z, replace(base, associator=assoc, imm_q=(base.motion.q,) * 3, imm_sojourn_s=20.0)
        )
        np.testing.assert_array_equal(a.det_track, b.det_track)
        np.testing.assert_allclose(a.track_x, b.track_x, rtol=1e-9, atol=1e-6)


def test_imm_kernels() -> None:
    from navtrack.tracking.imm import imm_combine, imm_mix, markov_matrix

    rng = np.random.default_rng(1)
    x = rng.normal(size=(4, 2, 3))
    A = rng.normal(size=(4, 2, 3, 3))
    P = A @ np.swapaxes(A, -1, -2) + np.eye(3)
    mu = rng.dirichlet([1, 1], size=4)
    Pi = markov_matrix(2, 0.1)
    np.testing.assert_allclose(Pi.sum(axis=1), 1.0)
    x0, P0, c = imm_mix(x, P, mu, Pi)
    np.testing.assert_allclose(c.sum(axis=1), 1.0)
    # the mixture is preserved: combining the mixed estimates with c gives the combined estimate
    xc, Pc = imm_combine(x, P, mu)
    xc0, Pc0 = imm_combine(x0, P0, c)
    np.testing.assert_allclose(xc0, xc, atol=1e-12)
    np.testing.assert_allclose(Pc0, Pc, atol=1e-12)


def test_one_point_initiation_with_reported_velocity() -> None:
    truth, t, z, origin = _scenario(6, n_targets=4, steps=40)
    k = np.round(t / 10.0).astype(int)
    vel = np.where(origin[:, None] >= 0, truth[k, np.maximum(origin, 0)][:, [1, 3]], np.nan)
    cfg = TrackerConfig(
        sigma_m=10.0,
        pd=0.9,
        clutter_density=0.5 / 4.5e7,
        max_coast_s=60.0,
        confirm_window_s=60.0,
        init_max_dt_s=30.0,
        init_velocity_std_mps=0.5,
    )
    two = run_tracker(t, z, cfg)
    one = run_tracker(t, z, cfg, velocity=vel)
    assert one.counts.tracks_confirmed == 4
    # every target's first detection starts its own track (no seed waiting for a partner)
    first = (t == 0) & (origin >= 0)
    assert np.all(one.det_status[first] == DetStatus.STARTED)

    def first_velocity_error(res) -> float:
        errs = []
        for tid in np.unique(res.track_id[res.track_confirmed]):
            i = np.flatnonzero(res.track_id == tid)[0]
            tgt = origin[res.det_track == tid]
            kk = round(float(res.track_time_s[i]) / 10.0)
            errs.append(np.hypot(*(res.track_x[i, [1, 3]] - truth[kk, tgt[tgt >= 0][0], [1, 3]])))
        return float(np.mean(errs))

    # the reported velocity (sd 0.5 m/s here) beats a two-point difference (sd 1.4 m/s)
    assert first_velocity_error(one) < first_velocity_error(two)
    with pytest.raises(ValueError, match="velocity"):
        run_tracker(t, z, cfg, velocity=vel[:3])


def test_simulate_detections_rejects_bad_clutter_box() -> None:
    meas = linear_position(4, (0, 2), 5.0)
    truth = np.zeros((3, 1, 4))
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match="clutter_low"):
        simulate_detections(truth, meas, 0.9, 1.0, [-1.0, -1.0, -1.0], [1.0, 1.0, 1.0], rng)
    with pytest.raises(ValueError, match="clutter box"):
        simulate_detections(truth, meas, 0.9, 1.0, [1.0, -1.0], [-1.0, 1.0], rng)


@pytest.mark.parametrize("associator", ["gnn", "jpda"])
def test_a_track_past_its_coast_is_not_reported_while_no_scan_comes(associator: str) -> None:
    """One target reports every 2 s for 40 s and falls silent; the next report (another
    target, far away) comes 1000 s later. Coasting tracks are deleted at scans, and none comes
    in between: the first track is reported at the output times up to ``max_coast_s`` after
    its last update and not after, though it is still alive until that next scan deletes it."""
    t1 = np.arange(0.0, 40.1, 2.0)
    z1 = np.column_stack([100.0 * t1, np.zeros_like(t1)])  # 100 m/s east
    t2 = 1040.0 + np.arange(0.0, 20.1, 2.0)
    z2 = np.column_stack([np.zeros_like(t2), 50_000.0 + 100.0 * (t2 - t2[0])])
    t, z = np.r_[t1, t2], np.r_[z1, z2]
    cfg = replace(TrackerConfig.for_aircraft(associator), max_coast_s=30.0, init_max_dt_s=5.0)
    frames = np.arange(0.0, 1061.0, 10.0)
    res = run_tracker(t, z, cfg, report_times=frames)
    first = res.report_id == res.det_track[0]
    shown = frames[res.report_frame[first]]
    assert shown.max() == 70.0  # last update at 40 s, coast 30 s
    assert shown.min() <= 10.0  # confirmed within its first reports
    assert res.end_time_s[res.end_id == res.det_track[0]][0] >= 1040.0  # deleted at that scan
