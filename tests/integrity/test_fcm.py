"""Fuzzy-clustering RAIM (paper 2): the paper's numeric example, scikit-fuzzy as the FCM
oracle, parity-matrix properties and bad input.

The matrices are transcribed from section 5 of Gu et al. (2019),
``shared/papers/2_raim_fuzzy_clustering.txt``, in :mod:`navtrack.experiments.raim_fcm.example`
(which states the five minus signs of T the text extraction lost).
"""

from __future__ import annotations

import numpy as np
import pytest

from navtrack.experiments.raim_fcm.example import (
    EPS_ONE,
    EPS_TWO,
    F_ONE,
    F_TWO,
    T_PAPER,
    T_PRINTED,
    paper_example,
)
from navtrack.integrity.fcm import (
    fcm_initial_centres,
    full_design_matrix,
    fuzzy_cmeans,
    gross_error_columns,
    hierarchical_classes,
    mahalanobis_whitening,
    parity_matrix,
)


def _print_tolerance(eps: np.ndarray) -> np.ndarray:
    """Bound of |F(T, e) - F_printed| from rounding T, e and F to 3 decimals."""
    col = 0.0005 * (np.abs(eps)[None, :] + np.abs(T_PAPER)) + 0.0005 + 1e-9
    return np.concatenate([col, col.sum(axis=1, keepdims=True) + 0.0005], axis=1)


def test_restored_t_is_a_parity_matrix_to_print_precision() -> None:
    np.testing.assert_allclose(T_PAPER @ T_PAPER.T, np.eye(5), atol=2.5e-3)
    # the signs as extracted are not: off-diagonal products up to 0.28
    assert np.max(np.abs(T_PRINTED @ T_PRINTED.T - np.eye(5))) > 0.25


@pytest.mark.parametrize(("eps", "printed"), [(EPS_ONE, F_ONE), (EPS_TWO, F_TWO)])
def test_full_design_matrix_equals_the_printed_one(eps: np.ndarray, printed: np.ndarray) -> None:
    f = full_design_matrix(T_PAPER, eps)
    assert f.shape == (5, 10)
    assert np.all(np.abs(f - printed) <= _print_tolerance(eps))


@pytest.mark.parametrize(
    ("eps", "faulty", "hard_faulty"),
    [(EPS_ONE, [4], [4]), (EPS_TWO, [4, 7], [7])],
)
def test_paper_example_classes(eps: np.ndarray, faulty: list[int], hard_faulty: list[int]) -> None:
    """FCM (c = 3, m = 2, centres at the max/min/middle column) puts satellite 4 (single
    fault), and 4 and 7 (two faults), into the gross-error class; hierarchical clustering finds
    4 alone but only 7 of the two (paper 5.2-5.3, Figs. 1-4)."""
    x = mahalanobis_whitening(full_design_matrix(T_PAPER, eps).T, cov=np.eye(5))
    res = fuzzy_cmeans(x, 3, 2.0)
    assert res.converged
    assert list(np.flatnonzero(gross_error_columns(res.classes)) + 1) == faulty
    hard = hierarchical_classes(x, 2, method="single")
    assert list(np.flatnonzero(gross_error_columns(hard)) + 1) == hard_faulty


def test_paper_example_fcm_partition_single_fault() -> None:
    """The three classes of Fig. 2: {1, 2, 9}, {4, t}, {3, 5, 6, 7, 8} (the text lists
    3, 5, 6, 7; 8 is in no other class)."""
    res = fuzzy_cmeans(full_design_matrix(T_PAPER, EPS_ONE).T, 3, 2.0)
    groups = {frozenset(np.flatnonzero(res.classes == k) + 1) for k in range(3)}
    assert groups == {frozenset({1, 2, 9}), frozenset({4, 10}), frozenset({3, 5, 6, 7, 8})}


def test_paper_example_fcm_partition_two_faults() -> None:
    """Fig. 4: {4}, {7, t}, and the healthy rest."""
    res = fuzzy_cmeans(full_design_matrix(T_PAPER, EPS_TWO).T, 3, 2.0)
    groups = {frozenset(np.flatnonzero(res.classes == k) + 1) for k in range(3)}
    assert groups == {frozenset({4}), frozenset({7, 10}), frozenset({1, 2, 3, 5, 6, 8, 9})}


@pytest.mark.parametrize(("eps", "faulty"), [(EPS_ONE, [4]), (EPS_TWO, [4, 7])])
def test_sample_covariance_reading_does_not_reproduce_the_paper(
    eps: np.ndarray, faulty: list[int]
) -> None:
    """With the sample covariance of the 10 columns as the Mahalanobis metric the faulty
    columns dominate the covariance that should measure them: the named satellites are not
    the paper's (docs/integrity.md)."""
    x = mahalanobis_whitening(full_design_matrix(T_PAPER, eps).T)
    named = np.flatnonzero(gross_error_columns(fuzzy_cmeans(x, 3, 2.0).classes)) + 1
    assert list(named) != faulty


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("m", [1.5, 2.0, 3.0])
def test_fcm_matches_scikit_fuzzy(seed: int, m: float) -> None:
    """Same data, same start: the memberships of scikit-fuzzy's ``cmeans`` (oracle)."""
    skfuzzy = pytest.importorskip("skfuzzy")
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(12, 5))
    x[3] += 6.0
    ours = fuzzy_cmeans(x, 3, m, tol=1e-10, max_iter=300)
    _, u, _, _, _, p, _ = skfuzzy.cluster.cmeans(x.T, 3, m, 1e-10, 300, init=ours.u0.copy())
    assert p == ours.iterations
    np.testing.assert_allclose(ours.u, u, atol=1e-10)


def test_fcm_on_the_paper_example_matches_scikit_fuzzy() -> None:
    skfuzzy = pytest.importorskip("skfuzzy")
    x = full_design_matrix(T_PAPER, EPS_TWO).T
    ours = fuzzy_cmeans(x, 3, 2.0)
    _, u, _, _, _, _, _ = skfuzzy.cluster.cmeans(x.T, 3, 2.0, 1e-6, 100, init=ours.u0.copy())
    np.testing.assert_allclose(ours.u, u, atol=1e-9)


def test_initial_centres_are_max_min_middle() -> None:
    x = np.array([[0.0, 1.0], [3.0, 4.0], [0.1, 0.0], [1.0, 1.0], [2.0, 0.0]])
    # norms 1, 5, 0.1, 1.41, 2
    np.testing.assert_array_equal(fcm_initial_centres(x), [1, 2, 3])


@pytest.mark.parametrize("seed", range(3))
def test_parity_matrix_properties(seed: int) -> None:
    rng = np.random.default_rng(seed)
    b = np.concatenate([rng.normal(size=(2, 9, 3)), np.ones((2, 9, 1))], axis=-1)
    t = parity_matrix(b)
    assert t.shape == (2, 5, 9)
    np.testing.assert_allclose(t @ b, 0.0, atol=1e-12)
    np.testing.assert_allclose(
        t @ np.swapaxes(t, 1, 2), np.broadcast_to(np.eye(5), (2, 5, 5)), atol=1e-12
    )
    # the parity vector carries the whole residual: |T e|^2 = e^T (I - H) e
    e = rng.normal(size=9)
    h = b[0] @ np.linalg.solve(b[0].T @ b[0], b[0].T)
    assert abs(np.sum((t[0] @ e) ** 2) - e @ (np.eye(9) - h) @ e) < 1e-10


def test_bad_input() -> None:
    x = np.random.default_rng(0).normal(size=(6, 2))
    with pytest.raises(ValueError, match="m: "):
        fuzzy_cmeans(x, 3, 1.0)
    with pytest.raises(ValueError, match="c: "):
        fuzzy_cmeans(x, 1, 2.0)
    bad = x.copy()
    bad[2, 1] = np.nan
    with pytest.raises(ValueError, match="finite"):
        fuzzy_cmeans(bad, 3, 2.0)
    with pytest.raises(ValueError, match="finite"):
        full_design_matrix(T_PAPER, np.where(np.arange(9) == 3, np.inf, EPS_ONE))
    with pytest.raises(ValueError, match="n > u"):
        parity_matrix(np.ones((4, 4)))


def test_reproduction_example_reports_the_paper_classes() -> None:
    ex = paper_example()
    assert ex["t_orthonormality_error"] < 2.5e-3
    assert ex["single"]["fcm_gross_errors"] == [4]
    assert ex["double"]["fcm_gross_errors"] == [4, 7]
    assert ex["double"]["hierarchical_gross_errors"] == [7]
    assert ex["double"]["max_abs_difference"] < 3e-3


def test_batched_fcm_equals_each_problem_alone() -> None:
    """Padded problems of different sizes in one call give each problem's own result."""
    rng = np.random.default_rng(5)
    sizes = [(10, 5), (7, 3), (12, 6)]
    probs = [rng.normal(size=s) * [1.0] + np.eye(s[0], s[1]) * 5.0 for s in sizes]
    x = np.zeros((3, 12, 6))
    valid = np.zeros((3, 12), dtype=bool)
    for i, p in enumerate(probs):
        x[i, : p.shape[0], : p.shape[1]] = p
        valid[i, : p.shape[0]] = True
    batch = fuzzy_cmeans(x, 3, 2.0, valid=valid, tol=1e-9, max_iter=200)
    for i, p in enumerate(probs):
        one = fuzzy_cmeans(p, 3, 2.0, tol=1e-9, max_iter=200)
        n = p.shape[0]
        assert batch.iterations[i] == one.iterations
        np.testing.assert_allclose(batch.u[i, :, :n], one.u, atol=1e-12)
        np.testing.assert_array_equal(batch.classes[i, :n], one.classes)
        assert np.all(batch.classes[i, n:] == -1)


@pytest.mark.parametrize(("m", "faulty"), [(1.5, [4, 7]), (2.0, [4, 7]), (2.5, [7]), (3.0, [7])])
@pytest.mark.parametrize("stop", ["memberships", "centres"])
def test_two_fault_success_needs_fuzziness_at_most_two(
    m: float, faulty: list[int], stop: str
) -> None:
    """The paper's two-fault example: FCM names 4 and 7 for m <= 2 only; at 2.5 and 3 it names
    only 7, as hard (single-linkage) clustering does (docs/integrity.md), whichever the
    stopping rule."""
    x = mahalanobis_whitening(full_design_matrix(T_PAPER, EPS_TWO).T, cov=np.eye(5))
    res = fuzzy_cmeans(x, 3, m, stop=stop, max_iter=1000)
    assert list(np.flatnonzero(gross_error_columns(res.classes)) + 1) == faulty


def test_centre_stopping_rule_stops_on_the_centres() -> None:
    """With ``stop="centres"`` the last step moved the centres by less than ``tol`` (Frobenius
    norm), re-run one step longer to see it; the memberships rule stops elsewhere."""
    x = full_design_matrix(T_PAPER, EPS_ONE).T
    tol = 1e-4
    res = fuzzy_cmeans(x, 3, 2.0, stop="centres", tol=tol)
    before = fuzzy_cmeans(x, 3, 2.0, stop="centres", tol=0.0, max_iter=int(res.iterations) - 1)
    assert np.linalg.norm(res.centres - before.centres) < tol
    earlier = fuzzy_cmeans(x, 3, 2.0, stop="centres", tol=0.0, max_iter=int(res.iterations) - 2)
    assert np.linalg.norm(before.centres - earlier.centres) >= tol
    other = fuzzy_cmeans(x, 3, 2.0, stop="memberships", tol=tol)
    assert other.iterations != res.iterations
    with pytest.raises(ValueError, match="stop"):
        fuzzy_cmeans(x, 3, 2.0, stop="labels")
