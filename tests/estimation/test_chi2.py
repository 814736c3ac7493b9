"""The chi-square functions of navtrack.estimation.chi2 against scipy.special (Cephes)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.special import chdtrc, chndtr, gammainc, gammaincinv

from navtrack.estimation.chi2 import (
    chi2_cdf,
    chi2_quantile,
    chi2_quantile_exact,
    chi2_threshold,
    ncx2_cdf,
    noncentrality_bias,
)

DOFS = (1, 2, 3, 4, 5, 7, 10, 15, 20, 30, 50, 80)


@pytest.mark.parametrize("k", DOFS)
def test_cdf_equals_regularised_incomplete_gamma(k: int) -> None:
    # both branches: the series below k/2 + 1 and the continued fraction above
    x = np.concatenate([np.geomspace(1e-3, 4.0 * k + 60.0, 60), [k + 1.9, k + 2.1]])
    ours = np.array([chi2_cdf(float(v), k) for v in x])
    np.testing.assert_allclose(ours, gammainc(0.5 * k, 0.5 * x), rtol=1e-12, atol=1e-15)
    upper = chdtrc(k, x)
    np.testing.assert_allclose(1.0 - ours, upper, rtol=1e-9, atol=1e-14)


def test_cdf_is_zero_at_and_below_zero() -> None:
    assert chi2_cdf(0.0, 3) == 0.0
    assert chi2_cdf(-1.0, 3) == 0.0


@pytest.mark.parametrize(
    ("p", "k"), list(itertools.product((1e-6, 0.01, 0.5, 0.9, 0.999, 1 - 1e-7), DOFS))
)
def test_quantile_equals_gammaincinv(p: float, k: int) -> None:
    assert chi2_quantile(p, k) == pytest.approx(2.0 * gammaincinv(0.5 * k, p), rel=2e-10)


def test_threshold_is_the_upper_quantile() -> None:
    for k in DOFS:
        thr = chi2_threshold(1e-3, k)
        assert thr == chi2_quantile(1.0 - 1e-3, k)
        assert chdtrc(k, thr) == pytest.approx(1e-3, rel=1e-7)


@pytest.mark.parametrize(("p", "k"), [(0.0, 3), (1.0, 3), (0.5, 0), (-0.1, 2)])
def test_quantile_refuses_bad_arguments(p: float, k: int) -> None:
    with pytest.raises(ValueError, match="chi2_quantile"):
        chi2_quantile(p, k)


@pytest.mark.parametrize("k", [1, 2, 4, 9, 20])
def test_noncentral_cdf_equals_chndtr(k: int) -> None:
    for lam, x in itertools.product((0.0, 0.3, 4.0, 25.0, 120.0), (0.5, 3.0, 10.0, 40.0, 150.0)):
        assert ncx2_cdf(x, k, lam) == pytest.approx(chndtr(x, k, lam), rel=1e-9, abs=1e-14)


def test_noncentrality_bias_misses_with_pmd() -> None:
    # the definition: at lambda = p_bias^2 the test's non-central CDF at the threshold is pmd
    for pfa, pmd, k in itertools.product((1e-3, 1e-5), (1e-3, 1e-7), (1, 3, 8)):
        lam = noncentrality_bias(pfa, pmd, k) ** 2
        assert chndtr(chi2_threshold(pfa, k), k, lam) == pytest.approx(pmd, rel=1e-6)


def test_quantile_matches_rtklib_table() -> None:
    # RTKLIB 2.4.3 pntpos.c chisqr[] (alpha = 0.001) starts 10.8, 13.8, 16.3
    assert [round(chi2_quantile(0.999, k), 1) for k in (1, 2, 3)] == [10.8, 13.8, 16.3]


def test_exact_quantile_inverts_the_cdf_and_agrees_with_the_bisection() -> None:
    for k in DOFS:
        for p in (1e-4, 0.5, 0.99, 0.9997):
            q = chi2_quantile_exact(p, k)
            assert gammainc(0.5 * k, 0.5 * q) == pytest.approx(p, rel=1e-12)
            assert chi2_quantile(p, k) == pytest.approx(q, rel=2e-10)
