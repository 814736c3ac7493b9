"""Associator conformance kit: GNN and Murty vs brute force, JPDA marginals vs enumeration."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from navtrack.estimation.kalman import kf_update
from navtrack.tracking.assignment import assign2d, murty
from navtrack.tracking.gating import chi2_threshold, gate, kdtree_pregate
from navtrack.tracking.jpda import (
    JpdaConfig,
    JpdaMethod,
    clusters,
    joint_events,
    jpda_marginals,
    jpda_marginals_batch,
    jpda_step,
    jpda_step_batch,
    pda_update,
)
from navtrack.tracking.models import RangeBearing, constant_velocity, linear_position


def _events(T: int, M: int, allowed: np.ndarray) -> list[tuple[int, ...]]:
    """All joint events: each track takes -1 (none) or an allowed measurement, no sharing."""
    opts = [[-1] + [j for j in range(M) if allowed[t, j]] for t in range(T)]
    out = []
    for ev in itertools.product(*opts):
        taken = [e for e in ev if e >= 0]
        if len(taken) == len(set(taken)):
            out.append(ev)
    return out


def _cost_problem(draw_seed: int, T: int, M: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(draw_seed)
    C = rng.uniform(0, 10, size=(T, M)).round(3)
    C[rng.random((T, M)) < 0.3] = np.inf
    miss = rng.uniform(2, 12, size=T).round(3)
    return C, miss


def _event_cost(C: np.ndarray, miss: np.ndarray, ev: tuple[int, ...]) -> float:
    return float(sum(miss[t] if j < 0 else C[t, j] for t, j in enumerate(ev)))


@given(seed=st.integers(0, 2**32 - 1), T=st.integers(0, 5), M=st.integers(0, 5))
@settings(max_examples=80, deadline=None)
def test_gnn_is_optimal_against_brute_force(seed: int, T: int, M: int) -> None:
    C, miss = _cost_problem(seed, T, M)
    a = assign2d(C, miss)
    costs = [_event_cost(C, miss, ev) for ev in _events(T, M, np.isfinite(C))]
    assert a.cost == pytest.approx(min(costs), abs=1e-9)
    assert a.cost == pytest.approx(_event_cost(C, miss, tuple(a.track_to_meas)), abs=1e-9)
    taken = a.track_to_meas[a.track_to_meas >= 0]
    assert len(taken) == len(set(taken.tolist()))


@given(
    seed=st.integers(0, 2**32 - 1), T=st.integers(1, 4), M=st.integers(0, 4), k=st.integers(1, 40)
)
@settings(max_examples=60, deadline=None)
def test_murty_equals_sorted_brute_force(seed: int, T: int, M: int, k: int) -> None:
    C, miss = _cost_problem(seed, T, M)
    evs = _events(T, M, np.isfinite(C))
    ref = sorted(_event_cost(C, miss, ev) for ev in evs)
    kb = murty(C, miss, k)
    assert len(kb.cost) == min(k, len(evs))
    np.testing.assert_allclose(kb.cost, ref[: len(kb.cost)], atol=1e-9)
    # each listed assignment is feasible, costs what it says, and is listed once
    seen = set()
    for row, c in zip(kb.track_to_meas, kb.cost, strict=True):
        ev = tuple(int(v) for v in row)
        assert ev in evs
        assert _event_cost(C, miss, ev) == pytest.approx(c, abs=1e-9)
        seen.add(ev)
    assert len(seen) == len(kb.cost)


def _brute_marginals(W: np.ndarray) -> np.ndarray:
    T, M1 = W.shape
    B = np.zeros_like(W)
    for ev in _events(T, M1 - 1, W[:, 1:] > 0):
        p = np.prod([W[t, j + 1] for t, j in enumerate(ev)])
        for t, j in enumerate(ev):
            B[t, j + 1] += p
    return B / B[0].sum()


def _random_weights(seed: int, T: int, M: int, density: float) -> np.ndarray:
    rng = np.random.default_rng(seed)
    W = np.zeros((T, M + 1))
    W[:, 0] = rng.uniform(0.01, 1.0, T)
    gated = rng.random((T, M)) < density
    W[:, 1:] = np.where(gated, np.exp(rng.normal(0, 3, (T, M))), 0.0)
    return W


@given(
    seed=st.integers(0, 2**32 - 1),
    T=st.integers(1, 6),
    M=st.integers(0, 7),
    density=st.floats(0.1, 1.0),
)
@settings(max_examples=120, deadline=None)
def test_jpda_marginals_equal_brute_force(seed: int, T: int, M: int, density: float) -> None:
    W = _random_weights(seed, T, M, density)
    ref = _brute_marginals(W)
    jm = jpda_marginals(W)
    np.testing.assert_allclose(jm.beta, ref, rtol=0, atol=1e-12)
    np.testing.assert_allclose(jm.beta.sum(axis=1), 1.0, atol=1e-12)
    assert np.all(jm.beta[:, 1:].sum(axis=0) <= 1.0 + 1e-12)
    assert np.all(jm.error_bound == 0)


@given(
    seed=st.integers(0, 2**32 - 1),
    T=st.integers(1, 4),
    M=st.integers(0, 4),
    density=st.floats(0.1, 1.0),
)
@settings(max_examples=40, deadline=None)
def test_jpda_kbest_with_all_events_is_exact(seed: int, T: int, M: int, density: float) -> None:
    # at most 209 events for 4 tracks x 4 measurements: k = 1000 holds them all
    W = _random_weights(seed, T, M, density)
    kb = jpda_marginals(W, JpdaConfig(max_exact_bits=1, k_best=1000))
    np.testing.assert_allclose(kb.beta, _brute_marginals(W), rtol=0, atol=1e-12)


@given(seed=st.integers(0, 2**32 - 1), k=st.integers(1, 30))
@settings(max_examples=40, deadline=None)
def test_kbest_error_bound_holds(seed: int, k: int) -> None:
    W = _random_weights(seed, 4, 5, 0.8)
    ref = _brute_marginals(W)
    jm = jpda_marginals(W, JpdaConfig(max_exact_bits=1, k_best=k))
    err = np.abs(jm.beta - ref).max(axis=1)
    shared = jm.method == JpdaMethod.KBEST
    assert np.all(err[shared] <= jm.error_bound[shared] + 1e-12)
    np.testing.assert_allclose(jm.beta.sum(axis=1), 1.0, atol=1e-12)


def test_clusters_split_independent_tracks() -> None:
    W = np.array(
        [
            [1, 1, 0, 0, 0],
            [1, 1, 1, 0, 0],
            [1, 0, 0, 0, 1],
            [1, 0, 0, 0, 0],
            [1, 0, 1, 0, 0],
        ],
        dtype=float,
    )
    n, lab = clusters(W)
    assert n == 3
    assert lab[0] == lab[1] == lab[4]
    assert len({lab[0], lab[2], lab[3]}) == 3


def test_exact_is_fast_structure_for_twelve_mutual_targets() -> None:
    # 12 tracks all gating 14 measurements (the benchmark case): the exact route is chosen
    rng = np.random.default_rng(2)
    W = np.ones((12, 15))
    W[:, 1:] = rng.uniform(0.1, 1.0, (12, 14))
    jm = jpda_marginals(W)
    assert np.all(jm.method == JpdaMethod.EXACT)
    np.testing.assert_allclose(jm.beta.sum(axis=1), 1.0, atol=1e-12)
    assert np.all(jm.beta[:, 1:].sum(axis=0) <= 1 + 1e-12)


def test_pda_update_equals_moment_matched_mixture() -> None:
    rng = np.random.default_rng(4)
    meas = linear_position(4, (0, 2), 2.0)
    x = rng.normal(size=(3, 4))
    A = rng.normal(size=(3, 4, 4))
    P = A @ np.swapaxes(A, -1, -2) + 4 * np.eye(4)
    Z = rng.normal(size=(5, 2))
    beta = rng.dirichlet(np.ones(6), size=3)
    S = meas.H @ P @ meas.H.T + meas.R
    y = Z[None] - (x @ meas.H.T)[:, None]
    K = P @ meas.H.T @ np.linalg.inv(S)
    xn, Pn = pda_update(x, P, y, S, K, beta)
    for t in range(3):
        means = [x[t]] + [kf_update(x[t], P[t], z, meas.H, meas.R).x for z in Z]
        covs = [P[t]] + [kf_update(x[t], P[t], z, meas.H, meas.R).P for z in Z]
        m = sum(b * mu for b, mu in zip(beta[t], means, strict=True))
        C = sum(
            b * (c + np.outer(mu - m, mu - m))
            for b, mu, c in zip(beta[t], means, covs, strict=True)
        )
        np.testing.assert_allclose(xn[t], m, rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(Pn[t], C, rtol=1e-9, atol=1e-9)


def test_gate_distances_and_kdtree_pregate() -> None:
    rng = np.random.default_rng(8)
    zp = rng.uniform(0, 1000, (40, 2))
    A = rng.normal(size=(40, 2, 2)) * 5
    S = A @ np.swapaxes(A, -1, -2) + 25 * np.eye(2)
    Z = rng.uniform(0, 1000, (300, 2))
    gamma = chi2_threshold(0.99, 2)
    assert gamma == pytest.approx(9.2103, abs=1e-4)  # chi-square table, 2 dof, 0.99
    g = gate(zp, S, Z, gamma)
    y = Z[None] - zp[:, None]
    d2 = np.einsum("tji,tik,tjk->tj", y, np.linalg.inv(S), y)
    np.testing.assert_allclose(g.d2, d2, rtol=1e-10)
    log_norm = -0.5 * (2 * np.log(2 * np.pi) + np.linalg.slogdet(S)[1])
    np.testing.assert_allclose(g.log_norm, log_norm, rtol=1e-12)
    # m = 3 takes the Cholesky path (m = 2 the closed form): same quantities
    A3 = rng.normal(size=(5, 3, 3))
    S3 = A3 @ np.swapaxes(A3, -1, -2) + np.eye(3)
    zp3, Z3 = rng.normal(size=(5, 3)), rng.normal(size=(7, 3))
    g3 = gate(zp3, S3, Z3, gamma)
    y3 = Z3[None] - zp3[:, None]
    np.testing.assert_allclose(
        g3.d2, np.einsum("tji,tik,tjk->tj", y3, np.linalg.inv(S3), y3), rtol=1e-10
    )
    np.testing.assert_allclose(
        g3.log_norm, -0.5 * (3 * np.log(2 * np.pi) + np.linalg.slogdet(S3)[1]), rtol=1e-12
    )
    cand = kdtree_pregate(zp, S, Z, gamma)
    assert np.all(cand[g.valid])  # no false rejections
    g2 = gate(zp, S, Z, gamma, candidates=cand)
    np.testing.assert_array_equal(g2.valid, g.valid)


def test_bad_inputs() -> None:
    with pytest.raises(ValueError, match="finite"):
        gate(np.zeros((1, 2)), np.eye(2)[None], np.array([[np.nan, 0.0]]), 9.0)
    with pytest.raises(ValueError, match="positive definite"):
        gate(np.zeros((1, 2)), -np.eye(2)[None], np.zeros((1, 2)), 9.0)
    with pytest.raises(ValueError, match="positive definite"):  # indefinite, positive diagonal
        gate(np.zeros((1, 2)), np.array([[[1.0, 2.0], [2.0, 1.0]]]), np.zeros((1, 2)), 9.0)
    with pytest.raises(ValueError, match="positive definite"):
        gate(np.zeros((1, 3)), -np.eye(3)[None], np.zeros((1, 3)), 9.0)
    with pytest.raises(ValueError, match="NaN"):
        assign2d(np.array([[np.nan]]), [1.0])
    with pytest.raises(ValueError, match="W must be finite"):
        jpda_marginals(np.array([[1.0, -1.0]]))
    with pytest.raises(ValueError, match="pd"):
        JpdaConfig(pd=0.0)


def test_batched_enumeration_equals_per_problem_marginals() -> None:
    from math import comb, perm

    for T, M in [(1, 0), (2, 3), (3, 4), (2, 6)]:
        E = joint_events(T, M)
        assert len(E) == sum(comb(T, k) * perm(M, k) for k in range(min(T, M) + 1))
        assert len({tuple(e) for e in E}) == len(E)
    rng = np.random.default_rng(12)
    Wb = np.stack([_random_weights(int(s), 3, 4, 0.7) for s in rng.integers(0, 2**31, 50)])
    beta = jpda_marginals_batch(Wb.reshape(5, 10, 3, 5)).reshape(50, 3, 5)
    for b in range(50):
        np.testing.assert_allclose(beta[b], _brute_marginals(Wb[b]), atol=1e-12)


@pytest.mark.parametrize("seed", range(5))
def test_tensor_elimination_path_equals_brute_force(seed: int) -> None:
    # clusters of 4-6 tracks (beyond the dense-enumeration shortcut for <= 3 tracks)
    W = _random_weights(seed, 4 + seed % 3, 7, 0.6 + 0.1 * (seed % 4))
    jm = jpda_marginals(W)
    assert np.bincount(jm.cluster).max() > 3
    assert (jm.method == JpdaMethod.EXACT).all()
    np.testing.assert_allclose(jm.beta, _brute_marginals(W), rtol=0, atol=1e-12)


def test_chi2_threshold_against_scipy_stats() -> None:
    # oracle: scipy.stats.chi2.ppf; spot values from printed chi-square tables (upper 1 %
    # points: 6.635 for 1 and 9.210 for 2 degrees of freedom)
    from scipy.stats import chi2

    for p in (0.5, 0.9, 0.99, 0.9997):
        for m in (1, 2, 3, 4, 6):
            assert chi2_threshold(p, m) == pytest.approx(chi2.ppf(p, m), rel=1e-12)
    assert round(chi2_threshold(0.99, 1), 2) == 6.63
    assert round(chi2_threshold(0.99, 2), 2) == 9.21
    assert chi2_threshold(1.0, 2) == float("inf")
    with pytest.raises(ValueError, match="gate_probability"):
        chi2_threshold(0.0, 2)
    with pytest.raises(ValueError, match="dim_z"):
        chi2_threshold(0.9, 0)


@pytest.mark.parametrize("max_events", [20_000, 0])  # dense enumeration / per-problem path
@pytest.mark.parametrize("bearing", [False, True])
def test_jpda_step_batch_equals_per_problem_step(max_events: int, bearing: bool) -> None:
    # Conformance: the batched step over R problems (padded measurements, valid mask) must
    # give what jpda_step gives for each problem alone with its valid measurements.
    rng = np.random.default_rng(5)
    R_, T, M = 6, 3, 5
    mot = constant_velocity(2, 1.0)
    F, Q = mot.F(1.0), mot.Q(1.0)
    if bearing:  # sensor far off so bearings of tracks and clutter straddle +-pi
        model = RangeBearing(np.diag([50.0**2, 0.01**2]), sensor_xy=np.array([5000.0, 0.0]))
    else:
        model = linear_position(4, (0, 2), 30.0)
    x = rng.normal(0, 1, (R_, T, 4)) * [100.0, 5.0, 100.0, 5.0]
    P = np.broadcast_to(np.diag([400.0, 25.0, 400.0, 25.0]), (R_, T, 4, 4)).copy()
    xp = np.einsum("ij,rtj->rti", F, x)
    z = np.empty((R_, M, 2))
    for r in range(R_):  # measurements near the predicted tracks, then extra clutter
        z[r, :T] = model.h(xp[r]) + rng.normal(0, 1, (T, 2)) @ np.linalg.cholesky(model.R).T
        z[r, T:] = model.h(xp[r, : M - T] + rng.normal(0, 60.0, (M - T, 4)))
    valid = rng.random((R_, M)) < 0.8
    valid[0] = False  # a problem with no measurement at all
    cfg = JpdaConfig(pd=0.9, clutter_density=1e-6, gate_probability=0.999)
    batch = jpda_step_batch(x, P, z, valid, F, Q, model, cfg, max_events=max_events)
    assert (batch.marginals.beta[:, 1:] > 0.5).sum() >= R_  # the gates do take measurements
    for r in range(R_):
        one = jpda_step(x[r], P[r], z[r][valid[r]], F, Q, model, cfg)
        np.testing.assert_allclose(batch.x[r], one.x, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(batch.P[r], one.P, rtol=1e-9, atol=1e-9)
        beta = batch.marginals.beta.reshape(R_, T, M + 1)[r]
        np.testing.assert_allclose(beta[:, 1:][:, ~valid[r]], 0.0, atol=0)
        np.testing.assert_allclose(beta[:, np.r_[True, valid[r]]], one.marginals.beta, atol=1e-12)
