"""JMPD particle filter of paper 4: exact one-step reference, hypotheses vs brute force, bad input.

Oracles: the one-target posterior by quadrature on the predicted Gaussian (exact Bayes for one
scan); the joint association sum by explicit enumeration of every target-to-measurement map in
plain Python (Bar-Shalom & Fortmann 9.4 likelihood).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from navtrack.estimation.kalman import kf_predict
from navtrack.tracking.models import FovealScan, FovealSensor, constant_velocity
from navtrack.tracking.trackers.particle import (
    MAX_HYPOTHESES,
    JmpdConfig,
    JmpdState,
    StepStatus,
    association_hypotheses,
    gnn_assignment,
    hypothesis_count,
    ip_gnn_log_likelihoods,
    jmpd_init,
    jmpd_step,
    joint_log_likelihood,
    kmeans_permute,
    measurement_distances,
    systematic_resample,
    target_log_likelihoods,
    weighted_estimates,
)


def _scan(z: list[float]) -> FovealScan:
    z_arr = np.array([z], dtype=float).reshape(1, len(z))
    return FovealScan(z_arr, np.ones_like(z_arr, dtype=bool), np.full(z_arr.shape, -1))


def _grid_posterior(m: np.ndarray, P: np.ndarray, z: float, c: float, d: float, R: float):
    """Exact posterior mean and variance of X and mean of Xdot after one scan (quadrature)."""
    sx = math.sqrt(P[0, 0])
    X = m[0] + sx * np.linspace(-9, 9, 20001)
    w = np.exp(-0.5 * ((X - m[0]) / sx) ** 2 - 0.5 * (z - np.arctan(c * (X - d))) ** 2 / R)
    w /= w.sum()
    ex = float(np.sum(w * X))
    vx = float(np.sum(w * (X - ex) ** 2))
    ev = m[1] + P[1, 0] / P[0, 0] * (ex - m[0])  # E[Xdot | X] is linear in X
    return ex, vx, ev


@pytest.mark.parametrize("proposal", ["kp", "ip_jpda", "ip_gnn", "ip_gnn_joint"])
def test_one_target_no_clutter_matches_exact_posterior(proposal):
    rng = np.random.default_rng(7)
    # without a gate the paper's GNN is exact for one target (a gate truncates the posterior)
    cfg = JmpdConfig(n_particles=40_000, proposal=proposal, gnn_gate=np.inf)
    sensor = FovealSensor(R=0.05)
    m0, P0 = np.array([0.0, 1.0]), np.diag([1.0, 0.1])
    state = jmpd_init(m0[None, None], P0, cfg, rng)
    c, d, z = 2.0, 0.8, 0.4
    step = jmpd_step(state, _scan([z]), [c], [d], sensor, cfg, rng)
    assert step.status[0] == StepStatus.OK
    mp, Pp = kf_predict(m0, P0, cfg.motion.F(1.0), cfg.motion.Q(1.0))
    ex, vx, ev = _grid_posterior(mp, Pp, z, c, d, sensor.R)
    x = step.state.x[0, 0]
    tol = 5 * math.sqrt(vx) / math.sqrt(step.n_eff[0])
    assert abs(x[0] - ex) < tol
    assert abs(x[1] - ev) < 5 * math.sqrt(Pp[1, 1]) / math.sqrt(step.n_eff[0])
    assert step.state.P[0, 0, 0, 0] == pytest.approx(vx, rel=0.05)


def test_ip_proposal_with_one_target_gives_equal_weights():
    # one target, no clutter: the partition weight is the whole likelihood, so the bias cancels
    rng = np.random.default_rng(1)
    cfg = JmpdConfig(n_particles=500, proposal="ip_jpda", resample_fraction=1e-9)
    state = jmpd_init(np.array([[[0.0, 1.0]]]), np.diag([1.0, 0.1]), cfg, rng)
    step = jmpd_step(state, _scan([0.3]), [1.0], [0.5], FovealSensor(0.05), cfg, rng)
    np.testing.assert_allclose(step.state.log_weights, -math.log(500), atol=1e-9)


def test_hypotheses_match_brute_force_enumeration():
    for T, M in [(1, 0), (1, 3), (2, 2), (3, 4), (3, 1), (4, 3)]:
        H = association_hypotheses(T, M)
        brute = {
            h
            for h in itertools.product(range(-1, M), repeat=T)
            if len([j for j in h if j >= 0]) == len({j for j in h if j >= 0})
        }
        assert {tuple(r) for r in H} == brute
        assert len(H) == len(brute) == hypothesis_count(T, M)


def _brute_loglik(L: np.ndarray, lam: float) -> float:
    """log of the sum over every feasible map target -> measurement/none, plain Python."""
    T, M = L.shape[0], L.shape[1] - 1
    total = 0.0
    for h in itertools.product(range(-1, M), repeat=T):
        det = [j for j in h if j >= 0]
        if len(det) != len(set(det)):
            continue
        p = lam ** (M - len(det))
        for t, j in enumerate(h):
            p *= math.exp(L[t, j if j >= 0 else M])
        total += p
    return math.log(total) if total > 0 else -math.inf


@pytest.mark.parametrize(("pd", "clutter_rate", "n_meas"), [(0.8, 1.5, 4), (1.0, 0.0, 3)])
def test_joint_likelihood_matches_brute_force(pd, clutter_rate, n_meas):
    rng = np.random.default_rng(3)
    sensor = FovealSensor(0.05, pd, clutter_rate)
    particles = rng.normal(0, 1, (1, 5, 3, 2))
    scan = _scan(list(rng.uniform(-1.2, 1.2, n_meas)))
    L = target_log_likelihoods(particles, scan, [1.5], [0.2], sensor)
    ll, _, n_h = joint_log_likelihood(L, scan.valid, sensor.clutter_density)
    assert n_h == hypothesis_count(3, n_meas)
    for i in range(5):
        assert ll[0, i] == pytest.approx(_brute_loglik(L[0, i], sensor.clutter_density), rel=1e-9)


def test_joint_likelihood_recovers_linear_underflow():
    # R tiny, measurements far from every particle: every product underflows in linear form
    sensor = FovealSensor(1e-7, 0.9, 0.5)
    particles = np.zeros((1, 2, 2, 2))
    particles[0, 1, :, 0] = [0.05, -0.05]
    scan = _scan([1.0, -1.0])
    L = target_log_likelihoods(particles, scan, [1.0], [0.0], sensor)
    ll, _, _ = joint_log_likelihood(L, scan.valid, sensor.clutter_density)
    for i in range(2):
        assert np.isfinite(ll[0, i])
        assert ll[0, i] == pytest.approx(_brute_loglik_log(L[0, i], sensor.clutter_density))


def _brute_loglik_log(L: np.ndarray, lam: float) -> float:
    T, M = L.shape[0], L.shape[1] - 1
    terms = []
    for h in itertools.product(range(-1, M), repeat=T):
        det = [j for j in h if j >= 0]
        if len(det) == len(set(det)):
            terms.append((M - len(det)) * math.log(lam) + sum(L[t, j] for t, j in enumerate(h)))
    top = max(terms)
    return top + math.log(sum(math.exp(t - top) for t in terms))


def test_underflowing_weights_are_recovered_and_counted():
    rng = np.random.default_rng(5)
    sensor = FovealSensor(1e-6)
    cfg = JmpdConfig(n_particles=200, proposal="kp")
    state = jmpd_init(np.array([[[0.0, 0.0]]]), np.diag([1e-4, 1e-6]), cfg, rng)
    step = jmpd_step(state, _scan([1.2]), [1.0], [0.0], sensor, cfg, rng)
    assert step.status[0] == StepStatus.UNDERFLOW_RECOVERED
    w = np.exp(step.state.log_weights[0])
    assert np.all(np.isfinite(step.state.log_weights))
    assert w.sum() == pytest.approx(1.0)


def test_infeasible_scan_keeps_prior_weights():
    # no clutter, Pd = 1, one target but two measurements: no feasible association
    rng = np.random.default_rng(2)
    cfg = JmpdConfig(n_particles=50, proposal="kp", resample_fraction=1e-9)
    state = jmpd_init(np.array([[[0.0, 1.0]]]), np.diag([1.0, 0.1]), cfg, rng)
    step = jmpd_step(state, _scan([0.1, -0.2]), [1.0], [0.0], FovealSensor(0.05), cfg, rng)
    assert step.status[0] == StepStatus.NO_FEASIBLE_HYPOTHESIS
    np.testing.assert_allclose(step.state.log_weights, state.log_weights)


def test_kmeans_permute_restores_swapped_partitions():
    rng = np.random.default_rng(0)
    x = np.empty((1, 100, 2, 2))
    x[0, :, 0] = rng.normal([0.0, 1.0], 0.1, (100, 2))
    x[0, :, 1] = rng.normal([10.0, -1.0], 0.1, (100, 2))
    swapped = x.copy()
    swapped[0, ::3] = x[0, ::3, ::-1]
    out = kmeans_permute(swapped, np.full((1, 100), -math.log(100)), iterations=5)
    np.testing.assert_array_equal(out, x)


def test_systematic_resample_counts_follow_weights():
    rng = np.random.default_rng(0)
    w = np.array([[0.5, 0.25, 0.125, 0.125], [0.0, 0.0, 1.0, 0.0]])
    with np.errstate(divide="ignore"):
        idx = systematic_resample(np.log(w), rng)
    for b in range(2):
        counts = np.bincount(idx[b], minlength=4)
        assert np.all(np.abs(counts - 4 * w[b]) < 1.0 + 1e-12)


def test_weighted_estimates_are_weighted_moments():
    rng = np.random.default_rng(0)
    p = rng.normal(size=(2, 30, 3, 2))
    lw = rng.normal(size=(2, 30))
    lw -= np.log(np.exp(lw).sum(axis=1, keepdims=True))
    x, P = weighted_estimates(p, lw)
    w = np.exp(lw[1])
    mean = np.average(p[1, :, 2], axis=0, weights=w)
    np.testing.assert_allclose(x[1, 2], mean)
    np.testing.assert_allclose(P[1, 2], np.cov(p[1, :, 2].T, aweights=w, bias=True))


def test_bad_input_is_refused_by_name():
    with pytest.raises(ValueError, match="R"):
        FovealSensor(R=0.0)
    with pytest.raises(ValueError, match="R"):
        FovealSensor(R=-0.05)
    with pytest.raises(ValueError, match="pd"):
        FovealSensor(R=0.05, pd=0.0)
    with pytest.raises(ValueError, match="pd"):
        FovealSensor(R=0.05, pd=1.2)
    with pytest.raises(ValueError, match="clutter_rate"):
        FovealSensor(R=0.05, clutter_rate=-1)
    with pytest.raises(ValueError, match="n_particles"):
        JmpdConfig(n_particles=0)
    with pytest.raises(ValueError, match="proposal"):
        JmpdConfig(proposal="bootstrap")  # type: ignore[arg-type]


def test_too_many_targets_is_refused_with_the_limit():
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match=f"limit MAX_HYPOTHESES = {MAX_HYPOTHESES}"):
        jmpd_init(np.zeros((1, 7, 2)), np.eye(2), JmpdConfig(n_particles=4), rng)
    with pytest.raises(ValueError, match=str(MAX_HYPOTHESES)):
        association_hypotheses(4, 30)


def test_scan_with_too_many_hypotheses_is_skipped_and_counted():
    rng = np.random.default_rng(0)
    cfg = JmpdConfig(n_particles=10)
    state = jmpd_init(np.zeros((1, 4, 2)), np.eye(2), cfg, rng)
    sensor = FovealSensor(0.05, 0.9, 0.5)
    step = jmpd_step(state, _scan(list(np.linspace(-1, 1, 30))), [1.0], [0.0], sensor, cfg, rng)
    assert step.status[0] == StepStatus.TOO_MANY_HYPOTHESES
    assert step.n_hypotheses == 0
    assert isinstance(step.state, JmpdState)


def test_scan_simulation_counts_detections_and_clutter():
    rng = np.random.default_rng(0)
    sensor = FovealSensor(0.05, 0.9, 0.5)
    scan = sensor.scan(np.zeros((4000, 3)), np.ones(4000), np.zeros(4000), rng)
    n_det = ((scan.origin >= 0) & scan.valid).sum(axis=1)
    n_clutter = ((scan.origin < 0) & scan.valid).sum(axis=1)
    assert n_det.mean() == pytest.approx(2.7, abs=0.05)
    assert n_clutter.mean() == pytest.approx(0.5, abs=0.05)
    assert np.all(np.abs(scan.z[(scan.origin < 0) & scan.valid]) < math.pi / 2)
    assert constant_velocity(1, 0.01).dim_x == sensor.dim_x


@pytest.mark.parametrize("proposal", ["kp", "ip_jpda", "ip_gnn", "ip_gnn_joint"])
def test_scan_without_measurements_is_all_missed(proposal):
    # Pd < 1: an empty scan is feasible (every target missed), weights stay equal
    rng = np.random.default_rng(0)
    cfg = JmpdConfig(n_particles=20, proposal=proposal, resample_fraction=1e-9)
    state = jmpd_init(np.zeros((1, 2, 2)), np.eye(2), cfg, rng)
    step = jmpd_step(state, _scan([]), [1.0], [0.0], FovealSensor(0.05, 0.9, 0.5), cfg, rng)
    assert step.status[0] == StepStatus.OK
    np.testing.assert_allclose(step.state.log_weights, -math.log(20))


def test_gnn_assignment_hand_worked():
    # gate 9. Particle 0: both partitions nearest to z0 (1 and 0.25); one-to-one the least total
    # is t0->z1, t1->z0 (4 + 0.25) against t0->z0, t1->z1 (1 + 16) or one left unassigned
    # (>= 0.25 + 9). Particle 1: z1 is outside both gates, so one partition takes z0 and the
    # other is unassigned: t0->z0 (1 + 9) beats t1->z0 (2 + 9). Row 1 has one measurement only:
    # t1 takes it (0.25 + 9 against 1 + 9).
    D2 = np.array(
        [
            [[[1.0, 4.0], [0.25, 16.0]], [[1.0, 20.0], [2.0, 30.0]]],
            [[[1.0, np.inf], [0.25, np.inf]], [[10.0, np.inf], [12.0, np.inf]]],
        ]
    )
    valid = np.array([[True, True], [True, False]])
    best = gnn_assignment(D2, valid, gate=9.0)
    np.testing.assert_array_equal(best, [[[1, 0], [0, -1]], [[-1, 0], [-1, -1]]])


def test_measurement_distances_are_normalised_residuals():
    sensor = FovealSensor(0.05)
    particles = np.array([[[[0.5, 1.0], [2.0, 1.0]]]])  # (1, 1, 2, 2)
    scan = FovealScan(np.array([[0.1, 0.7]]), np.array([[True, False]]), np.full((1, 2), -1))
    D2 = measurement_distances(particles, scan, [2.0], [1.0], sensor)
    h = np.arctan(2.0 * (np.array([0.5, 2.0]) - 1.0))
    np.testing.assert_allclose(D2[0, 0, :, 0], (0.1 - h) ** 2 / 0.05)
    assert np.all(np.isinf(D2[0, 0, :, 1]))


def test_paper_gnn_differs_from_the_most_likely_joint_hypothesis():
    # two partitions near one measurement, the other measurement far: the paper's GNN assigns
    # one-to-one within the gate; the joint hypothesis may call the far one clutter instead.
    rng = np.random.default_rng(3)
    sensor = FovealSensor(0.05, 0.9, 0.5)
    particles = rng.normal(0, 1, (1, 200, 2, 2))
    scan = FovealScan(np.array([[0.0, 0.6]]), np.array([[True, True]]), np.full((1, 2), -1))
    L = target_log_likelihoods(particles, scan, [1.0], [0.0], sensor)
    _, joint, _ = joint_log_likelihood(L, scan.valid, sensor.clutter_density)
    D2 = measurement_distances(particles, scan, [1.0], [0.0], sensor)
    gnn = gnn_assignment(D2, scan.valid, 9.0)
    assert np.any(gnn != joint)
    # where both assign both partitions, the GNN's pair has the least summed distance
    both = np.all(gnn[0] >= 0, axis=-1)
    assert np.any(both)
    g, D = gnn[0][both], D2[0][both]
    d_gnn = np.take_along_axis(D, g[..., None], -1)[..., 0].sum(-1)
    d_swap = np.take_along_axis(D, (1 - g)[..., None], -1)[..., 0].sum(-1)
    assert np.all(d_gnn <= d_swap)


def test_gnn_assignment_is_the_best_hypothesis_per_row():
    # two batch rows with different measurement counts: each row's best map, by brute force
    rng = np.random.default_rng(11)
    sensor = FovealSensor(0.05, 0.9, 1.0)
    particles = rng.normal(0, 1, (2, 4, 2, 2))
    z = np.array([[0.3, -0.5, 1.0], [0.2, 0.0, 0.0]])
    valid = np.array([[True, True, True], [True, False, False]])
    scan = FovealScan(z, valid, np.full(z.shape, -1))
    L = target_log_likelihoods(particles, scan, [1.0, 2.0], [0.0, 0.5], sensor)
    _, best, _ = joint_log_likelihood(L, valid, sensor.clutter_density)
    lam = sensor.clutter_density
    for b, m in ((0, 3), (1, 1)):
        for i in range(4):
            score = {
                h: (m - sum(j >= 0 for j in h)) * math.log(lam)
                + sum(L[b, i, t, j if j >= 0 else 3] for t, j in enumerate(h))
                for h in map(tuple, association_hypotheses(2, m))
            }
            assert tuple(best[b, i]) == max(score, key=score.get)
    part = ip_gnn_log_likelihoods(L, best)
    assert part[1, 0, 0] == L[1, 0, 0, best[1, 0, 0] if best[1, 0, 0] >= 0 else 3]
