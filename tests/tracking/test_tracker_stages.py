"""The tracker's stages one by one: store growth, predict/update against the Kalman kernels,
M-of-N management, initiation, and single vs batched JPDA through one pipeline."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from navtrack.estimation.kalman import (
    gain_update,
    innovation_gain,
    kalman_gain,
    kf_predict,
    kf_update,
)
from navtrack.tracking.imm import imm_mix, imm_model_probabilities, markov_matrix
from navtrack.tracking.jpda import JpdaConfig, JpdaMethod, jpda_step, jpda_step_batch, pda_update
from navtrack.tracking.models import RangeBearing, constant_velocity, linear_position
from navtrack.tracking.trackers.management import (
    initiate,
    manage,
    repeat_reports,
    same_scan_repeats,
)
from navtrack.tracking.trackers.stages import (
    Seeds,
    TrackStore,
    associate,
    associate_gnn,
    associate_jpda,
    gate_scan,
    predict,
    update,
)
from navtrack.tracking.trackers.track_config import (
    DET_STATUS_NAMES,
    DetStatus,
    TrackerConfig,
    TrackerModel,
)
from navtrack.tracking.trackers.tracker import run_tracker


def _spd(rng: np.random.Generator, n: int) -> np.ndarray:
    A = rng.normal(size=(n, n))
    return A @ A.T + n * np.eye(n)


def _store(rng: np.random.Generator, T: int, r: int = 1) -> TrackStore:
    store = TrackStore(4, r, capacity=1)
    for k in range(T):
        x = np.array([1000.0 * k, 5.0, -500.0 * k, -2.0]) + rng.normal(0, 10, 4)
        store.add(x, _spd(rng, 4) * 100, t_s=0.0, hits=2)
    return store


def test_status_enums_keep_printed_names() -> None:
    assert DET_STATUS_NAMES == ("confirmed", "tentative", "started", "seed", "unused")
    assert [int(s) for s in DetStatus] == [0, 1, 2, 3, 4]
    assert [m.name for m in JpdaMethod] == ["PDA", "EXACT", "KBEST"]
    assert [int(m) for m in JpdaMethod] == [0, 1, 2]


def test_store_grows_by_doubling_and_keeps_earlier_tracks() -> None:
    rng = np.random.default_rng(0)
    store = TrackStore(4, 2, capacity=1)
    caps, xs = [], []
    for k in range(100):
        x = rng.normal(size=4)
        assert store.add(x, np.eye(4) * (k + 1), t_s=float(k), hits=1) == k
        caps.append(store.capacity)
        xs.append(x)
        # every earlier track unchanged by the growth
        np.testing.assert_array_equal(store.x[:, 0], np.array(xs))
        np.testing.assert_array_equal(store.x[:, 1], np.array(xs))
    assert sorted(set(caps)) == [1, 2, 4, 8, 16, 32, 64, 128]  # 7 reallocations for 100 births
    np.testing.assert_array_equal(store.id, np.arange(100))
    np.testing.assert_array_equal(store.born_s, np.arange(100.0))
    np.testing.assert_array_equal(store.mu, np.full((100, 2), 0.5))
    assert not store.confirmed.any()
    keep = np.arange(100) % 3 == 0
    store.keep(keep)
    assert store.size == keep.sum()
    assert store.capacity == 128
    np.testing.assert_array_equal(store.id, np.flatnonzero(keep))  # order kept
    np.testing.assert_array_equal(store.P[:, 0, 0, 0], np.flatnonzero(keep) + 1.0)
    assert store.add(np.zeros(4), np.eye(4), 100.0, hits=1) == 100  # ids are never reused
    assert store.id[-1] == 100
    assert store.size == keep.sum() + 1


def test_predict_stage_equals_kalman_and_imm_kernels() -> None:
    rng = np.random.default_rng(1)
    cfg = TrackerConfig(sigma_m=10.0)
    model = TrackerModel.from_config(cfg)
    store = _store(rng, 5)
    x0, P0 = store.x.copy(), store.P.copy()
    predict(store, 7.5, model)
    xk, Pk = kf_predict(x0[:, 0], P0[:, 0], cfg.motion.F(7.5), cfg.motion.Q(7.5))
    # the same products over (T, 1, n) instead of (T, n): equal to rounding
    np.testing.assert_allclose(store.x[:, 0], xk, rtol=1e-15, atol=1e-12)
    np.testing.assert_allclose(store.P[:, 0], Pk, rtol=1e-15, atol=1e-12)
    x1 = store.x.copy()
    predict(store, 0.0, model)  # no time step: nothing moves
    np.testing.assert_array_equal(store.x, x1)
    # IMM: mixing with the continuous-time switching probability, then each model's KF
    icfg = replace(cfg, imm_q=(1e-4, 1.0), imm_sojourn_s=50.0)
    imodel = TrackerModel.from_config(icfg)
    store = _store(rng, 4, r=2)
    store.mu[:] = rng.dirichlet([1, 1], size=4)
    store.x[:, 1] += 30.0
    x0, P0, mu0 = store.x.copy(), store.P.copy(), store.mu.copy()
    predict(store, 10.0, imodel)
    xm, Pm, c = imm_mix(x0, P0, mu0, markov_matrix(2, -np.expm1(-10.0 / 50.0)))
    Q = np.stack([m.Q(10.0) for m in imodel.motions])
    xk, Pk = kf_predict(xm, Pm, icfg.motion.F(10.0), Q)
    np.testing.assert_allclose(store.x, xk, rtol=1e-15, atol=1e-12)
    np.testing.assert_allclose(store.P, Pk, rtol=1e-15, atol=1e-12)
    np.testing.assert_array_equal(store.mu, c)
    assert not np.allclose(Q[0], Q[1])


def test_gnn_update_stage_equals_kf_update() -> None:
    rng = np.random.default_rng(2)
    cfg = TrackerConfig(sigma_m=20.0, clutter_density=1e-8)
    model = TrackerModel.from_config(cfg)
    store = _store(rng, 4)
    H, R = model.measurement.jacobian(store.x[0, 0]), model.measurement.R
    # detections near tracks 0, 2 and 3 (track 1 has none), in shuffled order
    z = store.x[[3, 0, 2], 0][:, [0, 2]] + rng.normal(0, 20.0, (3, 2))
    x0, P0 = store.x[:, 0].copy(), store.P[:, 0].copy()
    g = gate_scan(store, z, model)
    S, K = innovation_gain(P0, H, R)
    np.testing.assert_array_equal(g.S[:, 0], S)
    np.testing.assert_array_equal(g.K[:, 0], K)
    a = associate_gnn(g, cfg.pd, cfg.gate_probability, cfg.clutter_density)
    np.testing.assert_array_equal(a.detection_track, [3, 0, 2])
    np.testing.assert_array_equal(a.hit, [True, False, True, True])
    update(store, g, a)
    for t, j in ((0, 1), (2, 2), (3, 0)):
        u = kf_update(x0[t], P0[t], z[j], H, R)
        np.testing.assert_allclose(store.x[t, 0], u.x, rtol=1e-14, atol=1e-10)
        np.testing.assert_allclose(store.P[t, 0], u.P, rtol=1e-14, atol=1e-10)
    np.testing.assert_array_equal(store.x[1, 0], x0[1])  # missed track: prediction kept
    np.testing.assert_array_equal(store.P[1, 0], P0[1])


def test_gnn_density_at_gate_ties_a_miss_exactly_on_the_gate() -> None:
    # One track whose prediction is uncertain (S ~ (400 m)^2 per axis, as after 10 s of an
    # aircraft's flight) and reports at normalised distances d2 along one axis. With one λ
    # from σ = 25 m a report is kept only far inside the gate (the pair costs more than a
    # miss beyond d2 = γ - log(det S / σ^4)); with the track's own gate-edge density it is kept
    # up to the gate, d2 = γ, and the pair cost equals the miss cost there.
    sigma = 25.0
    for flag in (False, True):
        cfg = TrackerConfig(sigma_m=sigma, gnn_density_at_gate=flag)
        model = TrackerModel.from_config(cfg)
        lam_sigma = cfg.pd / (1 - cfg.pd * cfg.gate_probability)
        lam_sigma *= np.exp(-model.gamma / 2) / (2 * np.pi * sigma**2)
        cfg = replace(cfg, clutter_density=lam_sigma)
        model = TrackerModel.from_config(cfg)
        store = TrackStore(4, 1, capacity=1)
        store.add(
            np.zeros(4), np.diag([400.0**2 - sigma**2, 1.0, 400.0**2 - sigma**2, 1.0]), 0.0, 3
        )
        kept = []
        for d2 in (3.0, 10.0, model.gamma - 0.01, model.gamma + 0.01):
            z = np.array([[400.0 * np.sqrt(d2), 0.0]])
            g = gate_scan(store, z, model)
            kept.append(bool(associate(g, model).hit[0]))
        threshold = model.gamma - np.log(400.0**4 / sigma**4)  # 7.3: kept below it only
        assert threshold < 10.0
        assert kept == ([True, False, False, False] if not flag else [True, True, True, False])


def test_jpda_update_stage_equals_pda_update_with_imm_probabilities() -> None:
    rng = np.random.default_rng(3)
    cfg = TrackerConfig(sigma_m=50.0, associator="jpda", clutter_density=1e-8, imm_q=(0.01, 1.0))
    model = TrackerModel.from_config(cfg)
    store = _store(rng, 3, r=2)
    store.x[1] = store.x[0] + [80.0, 0, 40.0, 0]  # tracks 0 and 1 share detections
    store.mu[:] = [[0.3, 0.7], [0.5, 0.5], [0.9, 0.1]]
    store.P[:, 1] *= 9.0  # the models disagree, so the detections move the probabilities
    z = np.vstack([store.x[:3, 0][:, [0, 2]] + rng.normal(0, 50.0, (3, 2)), [[20.0, 10.0]]])
    x0, P0, mu0 = store.x.copy(), store.P.copy(), store.mu.copy()
    g = gate_scan(store, z, model)
    a = associate_jpda(g, model.jpda)
    assert a.marginals is not None
    assert (a.marginals.method == JpdaMethod.EXACT).sum() == 2
    beta = a.beta
    update(store, g, a)
    b_r = np.broadcast_to(beta[:, None, :], (3, 2, beta.shape[1]))
    xp, Pp = pda_update(x0, P0, g.innovation, g.S, g.K, b_r)
    np.testing.assert_array_equal(store.x, xp)
    np.testing.assert_array_equal(store.P, Pp)
    lam = beta[:, None, 0] + np.einsum(
        "tj,trj->tr", beta[:, 1:], np.exp(g.log_likelihood - g.log_likelihood_mix[:, None, :])
    )
    np.testing.assert_allclose(store.mu, imm_model_probabilities(mu0, np.log(lam)), rtol=1e-12)
    assert not np.allclose(store.mu, mu0)


def test_manage_confirms_m_of_n_and_deletes() -> None:
    cfg = TrackerConfig(confirm_hits=3, confirm_window_s=100.0, max_coast_s=50.0)
    store = TrackStore(4, 1)
    for _ in range(3):
        store.add(np.zeros(4), np.eye(4), t_s=0.0, hits=1)
    hit = np.array([True, True, False])
    m = manage(store, hit, 10.0, cfg)  # hits 2, 2, 1: nobody confirmed yet
    assert m.confirmed_now == 0
    assert store.size == 3
    np.testing.assert_array_equal(store.hits, [2, 2, 1])
    np.testing.assert_array_equal(store.last_s, [10.0, 10.0, 0.0])
    m = manage(store, np.array([True, False, False]), 20.0, cfg)  # 3 hits within 100 s
    np.testing.assert_array_equal(m.confirmed, [True, False, False])
    assert m.confirmed_now == 1
    # at 101 s: track 1 (2 hits) has missed its window, track 2 also coasted; track 0 coasts
    # 81 s > 50 s since its last hit: deleted as a confirmed coasting track
    m = manage(store, np.array([False, False, False]), 101.0, cfg)
    np.testing.assert_array_equal(m.kept, [False, False, False])
    assert (m.deleted_coast, m.deleted_covariance, m.deleted_unconfirmed) == (1, 0, 2)
    assert store.size == 0
    # a confirmed track with a hit stays; a diverged one is deleted for its covariance
    store.add(np.zeros(4), np.eye(4), 0.0, hits=3)
    store.add(np.zeros(4), np.eye(4) * 1e8, 0.0, hits=3)
    m = manage(store, np.array([True, True]), 1.0, cfg)
    assert m.confirmed_now == 2
    assert m.deleted_covariance == 1
    np.testing.assert_array_equal(store.id, [3])


def test_initiate_grows_store_and_keeps_earlier_tracks() -> None:
    cfg = TrackerConfig(sigma_m=10.0, init_max_speed_mps=20.0, init_max_dt_s=30.0)
    store = TrackStore(4, 1, capacity=1)
    seeds = Seeds()
    store.add(np.array([5.0, 1.0, 5.0, 1.0]), np.eye(4), 0.0, hits=2)
    nan2 = np.full((2, 2), np.nan)
    ini = initiate(store, seeds, 0.0, np.array([[0.0, 0.0], [5000.0, 0.0]]), nan2, [0, 1], cfg)
    np.testing.assert_array_equal(ini.status, [DetStatus.SEED, DetStatus.SEED])
    assert store.size == 1
    assert len(seeds) == 2
    # 10 s later: one detection 150 m from seed 0 (reachable at 20 m/s), one with a velocity
    z = np.array([[150.0, 0.0], [-3000.0, 0.0]])
    v = np.array([[np.nan, np.nan], [3.0, -4.0]])
    ini = initiate(store, seeds, 10.0, z, v, [2, 3], cfg)
    np.testing.assert_array_equal(ini.status, [DetStatus.STARTED, DetStatus.STARTED])
    np.testing.assert_array_equal(ini.track, [1, 2])
    np.testing.assert_array_equal(ini.seed_det, [0])
    np.testing.assert_array_equal(ini.seed_track, [1])
    assert store.size == 3
    assert store.capacity == 4
    assert len(seeds) == 1
    np.testing.assert_array_equal(store.x[0, 0], [5.0, 1.0, 5.0, 1.0])  # earlier track kept
    np.testing.assert_allclose(store.x[1, 0], [150.0, 15.0, 0.0, 0.0])  # two-point velocity
    np.testing.assert_allclose(np.diag(store.P[1, 0]), [100.0, 2.0, 100.0, 2.0])  # 2σ²/dt²
    assert store.P[1, 0, 0, 1] == pytest.approx(10.0)  # σ²/dt
    np.testing.assert_array_equal(store.x[2, 0], [-3000.0, 3.0, 0.0, -4.0])
    np.testing.assert_allclose(np.diag(store.P[2, 0]), [100.0, 1.0, 100.0, 1.0])
    assert store.P[2, 0, 0, 1] == 0.0
    np.testing.assert_array_equal(store.hits, [2, 2, 1])
    # the remaining seed (5 km away) ages out after init_max_dt_s
    ini = initiate(store, seeds, 40.0, np.array([[5000.0, 100.0]]), nan2[:1], [4], cfg)
    assert ini.status[0] == DetStatus.SEED
    assert seeds.det == [4]


def _jpda_problem(bearing: bool):
    rng = np.random.default_rng(7)
    T, M = 4, 7
    mot = constant_velocity(2, 1.0)
    if bearing:
        model = RangeBearing(np.diag([50.0**2, 0.01**2]), sensor_xy=np.array([5000.0, 0.0]))
    else:
        model = linear_position(4, (0, 2), 30.0)
    x = rng.normal(0, 1, (T, 4)) * [60.0, 5.0, 60.0, 5.0]
    P = np.broadcast_to(np.diag([400.0, 25.0, 400.0, 25.0]), (T, 4, 4)).copy()
    xp = x @ mot.F(1.0).T
    z = np.vstack(
        [
            model.h(xp) + rng.normal(0, 1, (T, 2)) @ np.linalg.cholesky(model.R).T,
            model.h(xp[: M - T] + rng.normal(0, 60.0, (M - T, 4))),
        ]
    )
    return x, P, z, mot.F(1.0), mot.Q(1.0), model


@pytest.mark.parametrize("bearing", [False, True])
def test_single_and_batched_jpda_are_one_pipeline(bearing: bool) -> None:
    # one problem through jpda_step and through jpda_step_batch (per-problem marginals):
    # the same code path gives identical bits, marginal bookkeeping included
    x, P, z, F, Q, model = _jpda_problem(bearing)
    cfg = JpdaConfig(pd=0.9, clutter_density=1e-6, gate_probability=0.999)
    one = jpda_step(x, P, z, F, Q, model, cfg)
    assert ((one.marginals.beta[:, 1:] > 0).sum(axis=0) >= 2).any()  # joint association
    ok = np.ones((1, len(z)), dtype=bool)
    b = jpda_step_batch(x[None], P[None], z[None], ok, F, Q, model, cfg, max_events=0)
    for name in ("x", "P", "x_pred", "P_pred"):
        np.testing.assert_array_equal(getattr(b, name)[0], getattr(one, name))
    np.testing.assert_array_equal(b.marginals.beta, one.marginals.beta)  # (R·T, M+1)
    for name in ("cluster", "method", "error_bound", "n_events"):
        np.testing.assert_array_equal(getattr(b.marginals, name), getattr(one.marginals, name))
    # the dense enumeration of the batch agrees to rounding
    d = jpda_step_batch(x[None], P[None], z[None], ok, F, Q, model, cfg)
    np.testing.assert_allclose(d.marginals.beta, one.marginals.beta, rtol=0, atol=1e-13)
    np.testing.assert_array_equal(d.marginals.method, JpdaMethod.EXACT)


def test_kalman_gain_kernels() -> None:
    rng = np.random.default_rng(4)
    P = np.stack([_spd(rng, 4) for _ in range(3)])
    H = rng.normal(size=(2, 4))
    R = _spd(rng, 2)
    S, K = innovation_gain(P, H, R)
    np.testing.assert_allclose(S, H @ P @ H.T + R, rtol=1e-13)
    np.testing.assert_allclose(K, P @ H.T @ np.linalg.inv(S), rtol=1e-11)
    np.testing.assert_array_equal(kalman_gain(P @ H.T, S), K)
    x, z = rng.normal(size=(3, 4)), rng.normal(size=(3, 2))
    u = kf_update(x, P, z, H, R)
    xg, Pg = gain_update(x, P, z - np.einsum("ij,tj->ti", H, x), K, S)
    np.testing.assert_array_equal(xg, u.x)
    np.testing.assert_array_equal(Pg, u.P)
    np.testing.assert_array_equal(Pg, np.swapaxes(Pg, -1, -2))


def test_closed_form_2x2_inverse_and_gate_match_lapack() -> None:
    from navtrack.estimation.kalman import stacked_inverse
    from navtrack.tracking.gating import gate

    rng = np.random.default_rng(5)
    S = np.stack([_spd(rng, 2) * 10.0**k for k in range(-3, 5)])  # 1e-3 .. 1e4 scales
    np.testing.assert_allclose(stacked_inverse(S), np.linalg.inv(S), rtol=1e-12)
    # the plane gate (closed form) against the same gate of a 3-D measurement whose third
    # axis is independent with zero innovation (Cholesky path): equal distances
    zp, z = rng.normal(size=(8, 2)), rng.normal(size=(5, 2))
    g = gate(zp, S, z, 9.21)
    S3 = np.zeros((8, 3, 3))
    S3[:, :2, :2] = S
    S3[:, 2, 2] = 1.0
    g3 = gate(np.column_stack([zp, np.zeros(8)]), S3, np.column_stack([z, np.zeros(5)]), 9.21)
    np.testing.assert_allclose(g.d2, g3.d2, rtol=1e-12)
    np.testing.assert_allclose(g.log_norm, g3.log_norm + 0.5 * np.log(2 * np.pi), rtol=1e-12)
    with pytest.raises(ValueError, match="not positive definite"):
        gate(zp[:1], -S[:1], z, 9.21)


def _aircraft_model() -> TrackerModel:
    cfg = TrackerConfig(
        motion=constant_velocity(2, 30.0, "continuous"), sigma_m=25.0, init_max_speed_mps=300.0
    )
    return TrackerModel.from_config(cfg)


def test_same_scan_repeats_are_moving_reports_agreeing_in_place_and_velocity() -> None:
    model = _aircraft_model()
    r_z = np.sqrt(2 * model.gamma) * model.config.sigma_m  # 152 m at σ 25 m, P_G 0.9999
    z = np.array(
        [
            [0.0, 0.0],  # 0: first report of an aircraft
            [30.0, 10.0],  # 1: the same aircraft again (same velocity): a repeat of 0
            [5000.0, 0.0],  # 2: another aircraft, same velocity, far
            [10.0, 0.0],  # 3: beside 0 but flying the other way: not a repeat
            [-0.98 * r_z, 0.0],  # 4: just inside the position gate of 0: a repeat
            [0.0, -1.02 * r_z],  # 5: just outside it (and the others): not a repeat
            [3000.0, 0.0],  # 6: a still target ...
            [3020.0, 0.0],  # 7: ... and another beside it: still targets are never repeats
        ]
    )
    v = np.array(
        [[50, 0], [50.5, 0.3], [50, 0], [-50, 0], [50, 0], [50, 0], [0, 0], [0.2, 0]], float
    )
    twice = same_scan_repeats(z, v, model)
    np.testing.assert_array_equal(twice, [False, True, False, False, True, False, False, False])
    no_velocity = np.full_like(v, np.nan)
    assert not same_scan_repeats(z, no_velocity, model).any()


def test_repeat_reports_lie_in_the_updated_gate_of_a_track_hit_this_scan() -> None:
    model = _aircraft_model()
    store = TrackStore(4, 1)
    P = np.diag([20.0**2, 4.0, 20.0**2, 4.0])
    store.add(np.array([0.0, 50.0, 0.0, 0.0]), P, t_s=0.0, hits=3)  # hit this scan
    store.add(np.array([10_000.0, 50.0, 0.0, 0.0]), P, t_s=0.0, hits=3)  # not hit
    z = np.array([[40.0, 0.0], [2000.0, 0.0], [10_000.0, 0.0]])
    hit = np.array([True, False])
    S = P[[0, 2]][:, [0, 2]] + model.measurement.R
    d2 = 40.0**2 / S[0, 0]
    assert d2 < model.gamma  # the first report sits inside the updated gate of track 0
    np.testing.assert_array_equal(repeat_reports(store, z, hit, model), [True, False, False])
    # a report at the scan time minus 2 s is compared with the track moved back along its
    # velocity (100 m): 140 m from the track's position is then 40 m from where it was
    dt = np.array([-2.0, 0.0, 0.0])
    z_early = np.array([[-60.0, 0.0], [2000.0, 0.0], [10_000.0, 0.0]])
    np.testing.assert_array_equal(
        repeat_reports(store, z_early, hit, model, dt), [True, False, False]
    )


def test_a_target_reported_twice_in_a_scan_keeps_one_track() -> None:
    """Three aircraft at 1 s reports with reported velocities; every fifth second each is
    reported twice (two trace points stamped with one second, 40 m apart). One confirmed
    track per aircraft, every second report of a second set aside as a repeat."""
    rng = np.random.default_rng(7)
    cfg = TrackerConfig(
        motion=constant_velocity(2, 30.0, "continuous"),
        sigma_m=25.0,
        init_max_speed_mps=300.0,
        init_max_dt_s=10.0,
        confirm_window_s=30.0,
        max_coast_s=20.0,
        init_from="unassociated",
        gnn_density_at_gate=True,
    )
    starts = np.array([[0.0, 0.0], [0.0, 3000.0], [5000.0, -2000.0]])
    vel = np.array([[60.0, 0.0], [50.0, 20.0], [-40.0, 40.0]])
    t, z, v, dup = [], [], [], []
    for k in range(120):
        for i in range(3):
            p = starts[i] + vel[i] * k
            for j in range(2 if k % 5 == 0 else 1):
                t.append(float(k))
                z.append(p + rng.normal(0, 10, 2) + (40.0 * j, 0.0))
                v.append(vel[i])
                dup.append(j == 1)
    res = run_tracker(np.array(t), np.array(z), cfg, velocity=np.array(v))
    assert res.counts.tracks_confirmed == 3
    assert res.counts.tracks_started == 3
    dup = np.array(dup)
    assert np.all(res.det_status[dup] == DetStatus.UNUSED)
