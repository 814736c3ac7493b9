"""Banded SPD kernels of the ARI model against dense NumPy linear algebra."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from navtrack.smoothing import banded
from navtrack.smoothing.banded import (
    band_to_dense,
    cholesky_solve_banded,
    inverse_band,
    inverse_band_from_factor,
    weighted_band_sums,
)


def _random_band(rng: np.random.Generator, n: int, m: int) -> tuple[np.ndarray, np.ndarray]:
    a = np.zeros((n, n))
    for lag in range(m + 1):
        idx = np.arange(n - lag)
        a[idx, idx + lag] = rng.normal(size=n - lag)
    dense = a @ a.T + 0.1 * np.eye(n)  # SPD, half-bandwidth m
    ab = np.zeros((m + 1, n))
    for lag in range(m + 1):
        ab[m - lag, lag:] = np.diag(dense, lag)
    return ab, dense


@pytest.mark.parametrize(
    ("n", "m", "width"),
    [
        (1, 1, 1),
        (2, 1, 1),
        (7, 2, 4),
        (17, 3, 3),
        (64, 2, 2),
        (101, 4, 4),
        (257, 7, 7),
        (300, 1, 4),
    ],
)
def test_banded_solve_and_selected_inverse_match_dense(
    n: int, m: int, width: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    rng = np.random.default_rng(n * 10 + m)
    ab, dense = _random_band(rng, n, m)
    np.testing.assert_allclose(band_to_dense(ab), dense)
    rhs = rng.normal(size=n)
    x, logdet, factor = cholesky_solve_banded(ab, rhs)
    with monkeypatch.context() as patch:  # LAPACK path (numba not installed)
        patch.setattr(banded, "_cholesky", None)
        x_lapack, logdet_lapack, factor_lapack = cholesky_solve_banded(ab, rhs)
    # same factor to rounding (the compiled loops sum in LAPACK's order), same solution
    np.testing.assert_allclose(factor, factor_lapack, rtol=1e-13, atol=1e-14)
    np.testing.assert_allclose(x, x_lapack, rtol=1e-11, atol=1e-12)
    assert logdet == pytest.approx(logdet_lapack, rel=1e-13)
    uncompiled, failed = banded.cholesky_loop(ab)
    assert failed == -1
    np.testing.assert_allclose(uncompiled.T, factor_lapack, rtol=1e-13, atol=1e-14)
    np.testing.assert_allclose(
        banded.solve_refined_loop(ab, uncompiled, rhs, 1), x_lapack, rtol=1e-11, atol=1e-12
    )
    np.testing.assert_allclose(x, np.linalg.solve(dense, rhs), rtol=1e-9, atol=1e-10)
    assert logdet == pytest.approx(np.linalg.slogdet(dense)[1], rel=1e-10, abs=1e-9)
    # the factor is the upper Cholesky factor: N = U^T U
    u_dense = np.zeros((n, n))
    m_f = factor.shape[0] - 1
    for lag in range(m_f + 1):
        idx = np.arange(n - lag)
        u_dense[idx, idx + lag] = factor[m_f - lag, lag:]
    np.testing.assert_allclose(u_dense.T @ u_dense, dense, rtol=1e-10, atol=1e-10)
    with pytest.raises(np.linalg.LinAlgError):
        cholesky_solve_banded(-ab, rhs)  # not positive definite
    inv = np.linalg.inv(dense)
    # both selected inversions: odd-even block recursion, and Takahashi's recursion on the
    # Cholesky factor (compiled when numba is installed, plain Python otherwise)
    for zb in (
        inverse_band(ab, width),
        inverse_band_from_factor(factor, width, method="takahashi"),
        banded.takahashi_loop(factor, max(width, m))[: width + 1],  # uncompiled recursion
    ):
        for lag in range(min(width, n - 1) + 1):
            np.testing.assert_allclose(zb[lag, : n - lag], np.diag(inv, lag), rtol=1e-8, atol=1e-10)
            assert np.all(np.isnan(zb[lag, n - lag :]))


@pytest.mark.parametrize(("n", "m"), [(9, 2), (40, 3), (120, 7)])
def test_weighted_band_sums_match_dense(n: int, m: int, monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(n + m)
    ab, dense = _random_band(rng, n, m)
    inv = np.linalg.inv(dense)
    v = rng.uniform(0.0, 1.0, size=n - m)
    expected = np.array(
        [
            [sum(v[s - m] * inv[s - a, s - b] for s in range(m, n)) for b in range(m + 1)]
            for a in range(m + 1)
        ]
    )
    zb = inverse_band(ab, m)
    np.testing.assert_allclose(weighted_band_sums(zb, v, m), expected, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(banded.band_sums_loop(zb, v, m), expected, rtol=1e-9, atol=1e-12)
    monkeypatch.setattr(banded, "_band_sums", None)  # NumPy path (numba not installed)
    np.testing.assert_allclose(weighted_band_sums(zb, v, m), expected, rtol=1e-9, atol=1e-12)
    with pytest.raises(ValueError, match="offsets"):
        weighted_band_sums(zb[:m], v, m)


def test_convolution_band_matches_dense(monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(8)
    n, c = 30, np.array([1.0, -1.7, 0.9, -0.15])
    m = c.size - 1
    vs = rng.uniform(0.2, 2.0, size=n - m)
    a = np.zeros((n - m, n))
    for s in range(m, n):
        a[s - m, s - np.arange(m + 1)] = c
    dense = a.T @ (vs[:, None] * a)
    compiled = np.zeros((m + 1, n))
    banded.add_convolution_band(compiled, c, vs)
    np.testing.assert_allclose(band_to_dense(compiled), dense, rtol=1e-13, atol=1e-13)
    monkeypatch.setattr(banded, "_add_convolution_band", None)  # NumPy path
    plain = np.zeros((m + 1, n))
    banded.add_convolution_band(plain, c, vs)
    np.testing.assert_array_equal(plain, compiled)  # same sums in the same order
    with pytest.raises(ValueError, match="do not match"):
        banded.add_convolution_band(plain, c, vs[1:])


def test_centred_convolution_is_exact_far_from_zero(monkeypatch: pytest.MonkeyPatch) -> None:
    # Oracle: the convolution in exact rational arithmetic of the same floating-point values.
    rng = np.random.default_rng(5)
    c = np.convolve(np.convolve([1.0, -0.6, 0.2], [1.0, -1.0]), [1.0, -1.0])  # c(1) = 0
    far = rng.normal(size=60) + 1e9 + 1e3 * np.arange(60)  # far from 0, slowly drifting
    m = c.size - 1
    exact = np.array(
        [
            float(sum(Fraction(c[i]) * Fraction(far[s - i]) for i in range(m + 1)))
            for s in range(m, far.size)
        ]
    )
    compiled = banded.centred_convolution(c, far)
    np.testing.assert_allclose(compiled, exact, rtol=0, atol=1e-11)
    assert np.max(np.abs(np.convolve(far, c, mode="valid") - exact)) > 1e-8  # what it replaces
    monkeypatch.setattr(banded, "_centred_convolution", None)  # NumPy path
    np.testing.assert_array_equal(banded.centred_convolution(c, far), compiled)
    assert banded.centred_convolution(c, far[:3]).size == 0
