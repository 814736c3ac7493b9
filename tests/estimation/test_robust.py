"""Robust weights and Baarda's w-test on their own (no ARI model).

Oracle: a linear least-squares adjustment with unequal variances, computed directly from the
hat matrix ``H = A (A^T P A)^-1 A^T P`` and by deleting observations one at a time.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from navtrack.estimation.robust import (
    ROBUST_DEFAULTS,
    danish_weight,
    deletion_statistic,
    flag_outliers,
    huber_weight,
    igg3_weight,
    redundancy_numbers,
    robust_weight,
    w_test,
)


def _linear_model(rng: np.random.Generator, n: int = 24, u: int = 4):
    """Design ``A (n, u)``, standard deviations ``(n,)``, observations with one blunder."""
    a = np.column_stack([np.ones(n), rng.normal(size=(n, u - 1))])
    sigma = rng.uniform(0.5, 2.0, size=n)
    x_true = rng.normal(size=u)
    obs = a @ x_true + sigma * rng.normal(size=n)
    blunder = 7
    obs[blunder] += 12.0 * sigma[blunder]
    return a, sigma, obs, blunder


def _adjust(a: np.ndarray, var: np.ndarray, obs: np.ndarray):
    """Weighted least squares: residuals ``l - A x`` and variances of the fitted values."""
    p = 1.0 / var
    q_xx = np.linalg.inv(a.T @ (p[:, None] * a))
    x = q_xx @ a.T @ (p * obs)
    return obs - a @ x, np.einsum("ij,jk,ik->i", a, q_xx, a)


def test_w_test_of_a_blunder_matches_the_hat_matrix() -> None:
    rng = np.random.default_rng(3)
    a, sigma, obs, blunder = _linear_model(rng)
    n, u = a.shape
    p = 1.0 / sigma**2
    hat = a @ np.linalg.inv(a.T @ (p[:, None] * a)) @ a.T * p[None, :]
    v_direct = (np.eye(n) - hat) @ obs
    q_vv = np.diag(sigma**2) - hat @ np.diag(sigma**2)  # Q_vv = (I - H) Q_ll
    w_direct = v_direct / np.sqrt(np.diag(q_vv))
    resid, var_fitted = _adjust(a, sigma**2, obs)
    r = redundancy_numbers(var_fitted, sigma**2)
    np.testing.assert_allclose(r, 1.0 - np.diag(hat), rtol=1e-12, atol=1e-12)
    assert float(np.sum(r)) == pytest.approx(n - u, abs=1e-10)
    assert np.all((r > 0) & (r < 1))
    w = w_test(resid, sigma, r)
    np.testing.assert_allclose(w, w_direct, rtol=1e-10)
    # the blunder has the largest statistic and is flagged at alpha_0 = 0.001 (least squares
    # smears it onto the others: w-testing them is the next step of data snooping)
    assert int(np.argmax(np.abs(w))) == blunder
    assert flag_outliers(w, 3.29)[blunder]
    assert abs(w[blunder]) > 2 * np.max(np.abs(np.delete(w, blunder)))


def test_deletion_statistic_is_the_w_test_at_full_weight() -> None:
    rng = np.random.default_rng(4)
    a, sigma, obs, _ = _linear_model(rng)
    resid, var_fitted = _adjust(a, sigma**2, obs)
    t = deletion_statistic(resid, var_fitted, np.ones(obs.size), sigma**2)
    w = w_test(resid, sigma, redundancy_numbers(var_fitted, sigma**2))
    np.testing.assert_allclose(t, w, rtol=1e-10)


def test_deletion_statistic_predicts_from_all_other_observations() -> None:
    # A down-weighted observation (robust factor 0.2 on the blunder, 0.7 on another): T is the
    # residual of its prediction from all other observations over its standard deviation,
    # computed here by deleting each observation in turn.
    rng = np.random.default_rng(5)
    a, sigma, obs, blunder = _linear_model(rng)
    n = obs.size
    factor = np.ones(n)
    factor[blunder] = 0.2
    factor[3] = 0.7
    var = sigma**2 / factor
    resid, var_fitted = _adjust(a, var, obs)
    t = deletion_statistic(resid, var_fitted, factor, sigma**2)
    p = 1.0 / var
    for i in range(n):
        keep = np.arange(n) != i
        q_xx = np.linalg.inv(a[keep].T @ (p[keep, None] * a[keep]))
        x_del = q_xx @ a[keep].T @ (p[keep] * obs[keep])
        pred = obs[i] - a[i] @ x_del
        expected = pred / math.sqrt(sigma[i] ** 2 + a[i] @ q_xx @ a[i])
        assert t[i] == pytest.approx(expected, rel=1e-9), i
    assert int(np.argmax(np.abs(t))) == blunder


def test_w_test_and_flags_of_unchecked_or_missing_values() -> None:
    w = w_test(np.array([1.0, 1.0]), 1.0, np.array([0.25, 0.0]))
    assert w[0] == pytest.approx(2.0)
    assert np.isinf(w[1])  # r = 0: the adjustment cannot check this observation
    np.testing.assert_array_equal(
        flag_outliers(np.array([np.nan, 3.29, -3.3, 4.0]), 3.29), [False, False, True, True]
    )


def test_weight_functions_values() -> None:
    t = np.array([0.0, 1.0, 2.5, 3.0, 5.0, np.nan])
    w = robust_weight(t, "huber", (1.5,))
    np.testing.assert_allclose(w[:5], [1, 1, 1.5 / 2.5, 0.5, 0.3])
    assert w[5] == 0.0
    w = robust_weight(t, "igg3", (1.5, 4.0))
    assert w[1] == 1.0
    assert w[4] == 0.0
    assert w[3] == pytest.approx(1.5 / 3.0 * ((4.0 - 3.0) / 2.5) ** 2)
    w = robust_weight(np.array([2.5 - 1e-9, 2.5 + 1e-9, 5.0]), "danish", (2.5,))
    assert w[0] == 1.0
    assert w[1] == pytest.approx(1.0, abs=1e-6)
    assert w[2] == pytest.approx(math.exp(1 - 4))
    np.testing.assert_array_equal(robust_weight(t, "off")[:5], 1.0)
    assert robust_weight(t, "off")[5] == 0.0
    with pytest.raises(ValueError, match="unknown"):
        robust_weight(t, "tukey")  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("name", "func"), [("danish", danish_weight), ("huber", huber_weight), ("igg3", igg3_weight)]
)
def test_weight_functions_properties(name: str, func) -> None:  # type: ignore[no-untyped-def]
    t = np.arange(-800, 801) / 100.0  # exactly symmetric grid, step 0.01
    w = func(t, *ROBUST_DEFAULTS[name])
    np.testing.assert_array_equal(robust_weight(t, name), w)  # type: ignore[arg-type]
    np.testing.assert_array_equal(w, w[::-1])  # symmetric in t
    assert np.all((w >= 0.0) & (w <= 1.0))
    half = w[800:]  # t >= 0
    assert np.all(np.diff(half) <= 0.0)  # non-increasing in |t|
    assert np.max(np.abs(np.diff(half))) < 0.05  # continuous (no jump at the cut-offs)
    assert np.all(w[np.abs(t) <= 2.5] == 1.0)  # full weight up to the first constant
    assert w[0] < 0.5  # far out: down-weighted
    assert func(np.array([np.nan]))[0] == 0.0
