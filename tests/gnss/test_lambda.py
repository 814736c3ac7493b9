"""LAMBDA: factorisation, decorrelation, search against a brute-force integer least-squares
oracle, ratio test, partial fixing, conditional update, and the 20-ambiguity speed bar."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from navtrack.gnss.ambiguity import (
    HAVE_NUMBA,
    AmbiguityConfig,
    FixStatus,
    bootstrap_success_rate,
    condition_on_fix,
    decorrelate,
    integer_search,
    ltdl,
    resolve_ambiguities,
)


def _random_cov(rng: np.random.Generator, n: int, scale: float = 1.0) -> np.ndarray:
    """A strongly correlated covariance like that of double-differenced ambiguities: a few
    well-determined geometric directions mapped through a random design."""
    A = rng.normal(size=(n, n)) + 3.0 * rng.normal(size=(n, 1))
    return scale * (A @ A.T / n + 1e-3 * np.eye(n))


def _brute_force(a: np.ndarray, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Integer least squares by enumerating every integer vector of the box that must hold the
    two best (the oracle).

    The rounded vector and its unit neighbours give an upper bound ``chi2`` of the second best
    squared norm; every vector within ``chi2`` satisfies ``|a_i - z_i| <= sqrt(chi2 Q_ii)``.
    """
    Qi = np.linalg.inv(Q)
    n = a.size
    base = np.rint(a).astype(int)
    start = np.vstack([base, base + np.eye(n, dtype=int), base - np.eye(n, dtype=int)])
    d0 = start - a
    chi2 = np.sort(np.einsum("ki,ij,kj->k", d0, Qi, d0))[1]
    half = np.sqrt(chi2 * np.diag(Q))
    axes = [np.arange(np.floor(a[i] - half[i]), np.ceil(a[i] + half[i]) + 1) for i in range(n)]
    z = np.array(list(itertools.product(*axes)))
    d = z - a
    sq = np.einsum("ki,ij,kj->k", d, Qi, d)
    order = np.argsort(sq)
    return z[order[:2]], sq[order[:2]]


def test_ltdl_reconstructs_q() -> None:
    rng = np.random.default_rng(1)
    Q = _random_cov(rng, 6)
    L, D = ltdl(Q)
    L_ = np.array(L)
    np.testing.assert_allclose(np.diag(L_), 1.0)
    assert np.allclose(np.triu(L_, 1), 0.0)
    np.testing.assert_allclose(L_.T @ np.diag(D) @ L_, Q, rtol=1e-10, atol=1e-12)


def test_ltdl_refuses_indefinite() -> None:
    with pytest.raises(ValueError, match="positive definite"):
        ltdl(np.array([[1.0, 2.0], [2.0, 1.0]]))


def test_decorrelation_is_unimodular_and_reduces() -> None:
    rng = np.random.default_rng(2)
    Q = _random_cov(rng, 8)
    Z, L, D = decorrelate(Q)
    assert abs(round(np.linalg.det(Z))) == 1
    Qz = Z.T @ Q @ Z
    L_ = np.array(L)
    np.testing.assert_allclose(L_.T @ np.diag(D) @ L_, Qz, rtol=1e-8, atol=1e-10)
    assert np.all(np.abs(np.tril(L_, -1)) <= 0.5 + 1e-9)
    # decorrelation number (Teunissen 1995): the product of variances comes down to det(Q)
    r_before = np.prod(np.diag(Q)) / np.linalg.det(Q)
    r_after = np.prod(np.diag(Qz)) / np.linalg.det(Qz)
    assert r_after < r_before


@pytest.mark.parametrize("seed", range(12))
def test_search_matches_brute_force(seed: int) -> None:
    rng = np.random.default_rng(100 + seed)
    n = int(rng.integers(2, 5))
    Q = _random_cov(rng, n, scale=0.05)
    a = rng.normal(scale=3.0, size=n)
    Z, L, D = decorrelate(Q)
    cands, sq = integer_search(Z.T @ a, L, D, 2)
    a_cands = np.rint(np.linalg.solve(Z.T.astype(float), cands.T.astype(float))).T
    ref, ref_sq = _brute_force(a, Q)
    np.testing.assert_array_equal(a_cands, ref)
    np.testing.assert_allclose(sq, ref_sq, rtol=1e-9)


@pytest.mark.parametrize("seed", range(6))
def test_search_without_decorrelation_matches_brute_force(seed: int) -> None:
    rng = np.random.default_rng(200 + seed)
    Q = _random_cov(rng, 3, scale=0.05)
    a = rng.normal(scale=3.0, size=3)
    L, D = ltdl(Q)
    cands, sq = integer_search(a, L, D, 2)
    ref, ref_sq = _brute_force(a, Q)
    np.testing.assert_array_equal(cands, ref)
    np.testing.assert_allclose(sq, ref_sq, rtol=1e-9)


def test_fix_recovers_true_integers_and_ratio() -> None:
    rng = np.random.default_rng(3)
    n = 10
    Q = _random_cov(rng, n, scale=1e-3)
    truth = rng.integers(-20, 20, size=n)
    a = truth + np.linalg.cholesky(Q) @ rng.normal(size=n)
    fix = resolve_ambiguities(a, Q)
    assert fix.status == FixStatus.FIXED
    assert fix.ratio >= 3.0
    np.testing.assert_array_equal(fix.a_fixed, truth)


def test_ratio_fails_on_a_half_cycle_float() -> None:
    Q = np.diag([0.04, 0.04])
    fix = resolve_ambiguities(np.array([0.5, 0.0]), Q, AmbiguityConfig(partial=False))
    assert fix.status == FixStatus.RATIO_FAILED
    assert fix.ratio == pytest.approx(1.0)
    assert not fix.accepted


def test_partial_fix_of_the_well_determined_subset() -> None:
    # three precise ambiguities and two hopeless ones, uncorrelated: only the precise ones fix
    Q = np.diag([4.0, 4.0, 1e-3, 1e-3, 1e-3])
    a = np.array([0.5, -0.4, 3.01, -7.02, 5.0])
    fix = resolve_ambiguities(a, Q, AmbiguityConfig(partial=True))
    assert fix.status == FixStatus.PARTIAL
    assert fix.n_fixed == 3
    np.testing.assert_array_equal(fix.Z @ np.array([0, 0, 3, -7, 5]), fix.z)
    assert fix.ratio >= 3.0


def test_bootstrap_success_rate_of_one_ambiguity() -> None:
    # sigma = 0.5 cycle: P(|e| < 1/2) = 2 Phi(1) - 1 = 0.6827
    assert bootstrap_success_rate([0.25]) == pytest.approx(0.682689, abs=1e-6)


def test_condition_on_fix_is_the_conditional_mean() -> None:
    rng = np.random.default_rng(4)
    A = rng.normal(size=(5, 5))
    P = A @ A.T + np.eye(5)
    x = rng.normal(size=5)
    A = np.eye(5)[3:]  # the ambiguities are the last two states
    fix = resolve_ambiguities(np.array([2.0, -1.0]), np.eye(2) * 1e-4)
    xf, Pf = condition_on_fix(x, P, A, fix)
    # Gaussian conditioning on x[3:] = (2, -1): the textbook formula
    G = P[:3, 3:] @ np.linalg.inv(P[3:, 3:])
    np.testing.assert_allclose(xf[:3], x[:3] - G @ (x[3:] - np.array([2.0, -1.0])))
    np.testing.assert_allclose(xf[3:], [2.0, -1.0], atol=1e-12)
    np.testing.assert_allclose(Pf[:3, :3], P[:3, :3] - G @ P[3:, :3], atol=1e-12)


@pytest.mark.skipif(not HAVE_NUMBA, reason="the speed bar holds for the compiled kernels")
def test_twenty_ambiguities_are_resolved() -> None:
    rng = np.random.default_rng(5)
    n = 20
    Q = _random_cov(rng, n, scale=1e-2)
    truth = rng.integers(-50, 50, size=n)
    a = truth + np.linalg.cholesky(Q) @ rng.normal(size=n)
    fix = resolve_ambiguities(a, Q)
    np.testing.assert_array_equal(fix.a_fixed, truth)


@pytest.mark.skipif(not HAVE_NUMBA, reason="needs numba for the compiled kernels")
def test_compiled_and_interpreted_kernels_agree(monkeypatch: pytest.MonkeyPatch) -> None:
    from navtrack.gnss import ambiguity

    rng = np.random.default_rng(6)
    n = 14
    Q = _random_cov(rng, n, scale=0.05)
    a = rng.normal(scale=5.0, size=n)
    compiled = resolve_ambiguities(a, Q, AmbiguityConfig(ratio_threshold=1.0))
    monkeypatch.setattr(ambiguity, "COMPILE_MIN_AMBIGUITIES", 10**6)
    interpreted = resolve_ambiguities(a, Q, AmbiguityConfig(ratio_threshold=1.0))
    np.testing.assert_array_equal(compiled.a_fixed, interpreted.a_fixed)
    assert compiled.ratio == pytest.approx(interpreted.ratio, rel=1e-9)
