"""Chi-square distribution functions of the residual tests (SPP validation, RAIM, gating).

* :func:`chi2_cdf`, :func:`chi2_quantile`: the central distribution, ``P(k/2, x/2)`` (the
  regularised lower incomplete gamma function) and its inverse (to 1e-10 relative);
* :func:`chi2_quantile_exact`: the inverse to machine precision (``scipy.special``), for the
  gates of the trackers;
* :func:`chi2_threshold`: the test threshold ``chi2_{1-pfa}(dof)`` of a false-alarm probability;
* :func:`ncx2_cdf`: the non-central distribution;
* :func:`noncentrality_bias`: ``sqrt(lambda)`` at which a test misses with a given probability
  (Walter & Enge's ``p_bias``).

The central functions are written out here (series and continued fraction of Numerical Recipes
6.2, bisection for the quantile) rather than taken from ``scipy.special``: importing
``scipy.special`` costs 160-220 ms, more than the whole start-up budget of ``navtrack pos``,
whose validation stage needs the quantile on every run. ``scipy.special`` (``gammainc``,
``gammaincinv``, ``chdtrc``, ``chndtr``) is their test oracle (``tests/estimation/test_chi2.py``).
"""

from __future__ import annotations

import math
from functools import lru_cache

__all__ = [
    "chi2_cdf",
    "chi2_quantile",
    "chi2_quantile_exact",
    "chi2_threshold",
    "ncx2_cdf",
    "noncentrality_bias",
]

_SERIES_MAX_TERMS = 10000
_RELATIVE_EPS = 1e-15
_LENTZ_TINY = 1e-300


def chi2_cdf(x: float, k: int) -> float:
    """CDF of the chi-square distribution with ``k`` degrees of freedom: the regularised lower
    incomplete gamma function ``P(k/2, x/2)`` (series below ``a + 1``, continued fraction of
    the upper tail above it; Numerical Recipes, 3rd ed., 6.2)."""
    if x <= 0.0:
        return 0.0
    a, y = 0.5 * k, 0.5 * x
    log_prefactor = -y + a * math.log(y) - math.lgamma(a)
    if y < a + 1.0:
        term = total = 1.0 / a
        n = a
        for _ in range(_SERIES_MAX_TERMS):
            n += 1.0
            term *= y / n
            total += term
            if abs(term) < abs(total) * _RELATIVE_EPS:
                break
        return total * math.exp(log_prefactor)
    # continued fraction of the upper tail (modified Lentz)
    b = y + 1.0 - a
    c = 1.0 / _LENTZ_TINY
    d = 1.0 / b
    h = d
    for i in range(1, _SERIES_MAX_TERMS):
        an = -i * (i - a)
        b += 2.0
        d = an * d + b
        d = _LENTZ_TINY if abs(d) < _LENTZ_TINY else d
        c = b + an / c
        c = _LENTZ_TINY if abs(c) < _LENTZ_TINY else c
        d = 1.0 / d
        delta = d * c
        h *= delta
        if abs(delta - 1.0) < _RELATIVE_EPS:
            break
    return 1.0 - math.exp(log_prefactor) * h


@lru_cache(maxsize=4096)
def chi2_quantile(p: float, k: int) -> float:
    """Quantile of the chi-square distribution with ``k`` degrees of freedom: bisection on
    :func:`chi2_cdf` to a relative width of 1e-10, from a bracket that holds the Wilson–Hilferty
    approximation.

    Raises
    ------
    ValueError
        ``p`` outside (0, 1) or ``k < 1``.
    """
    if not 0.0 < p < 1.0 or k < 1:
        raise ValueError(f"chi2_quantile: need 0 < p < 1 and k >= 1, got p={p}, k={k}")
    lo, hi = 0.0, max(10.0, k + 20.0 * math.sqrt(2.0 * k) + 50.0)
    while chi2_cdf(hi, k) < p:
        hi *= 2.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if chi2_cdf(mid, k) < p:
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-10 * hi:
            break
    return 0.5 * (lo + hi)


def chi2_quantile_exact(p: float, k: int) -> float:
    """Quantile of the chi-square distribution with ``k`` degrees of freedom to machine
    precision: ``2 P^-1(k/2, p)`` (``scipy.special.gammaincinv``, Cephes). :func:`chi2_quantile`
    agrees to 1e-10 relative without importing ``scipy.special``."""
    # scipy.special costs 160-220 ms to import: kept off the start-up of navtrack pos
    from scipy.special import gammaincinv

    return float(2.0 * gammaincinv(0.5 * k, p))


@lru_cache(maxsize=1024)
def chi2_threshold(pfa: float, dof: int) -> float:
    """Threshold of a chi-square test of false-alarm probability ``pfa``:
    ``chi2_{1-pfa}(dof)``."""
    return chi2_quantile(1.0 - pfa, dof)


def ncx2_cdf(x: float, k: int, lam: float) -> float:
    """CDF of the non-central chi-square distribution with ``k`` degrees of freedom and
    non-centrality ``lam``.

    The Poisson mixture ``sum_j e^(-lam/2) (lam/2)^j / j! P(chi2_(k+2j) <= x)`` (Johnson, Kotz
    & Balakrishnan, *Continuous Univariate Distributions* vol. 2, 2nd ed., 29.2), with the
    central CDFs by the recursion ``P_(k+2j+2) = P_(k+2j) - (x/2)^(k/2+j) e^(-x/2) /
    Gamma(k/2+j+1)``, summed until the Poisson weights are below 1e-17 past their mode (the
    remaining weights then fall faster than by half at each term).
    """
    half, a, y = 0.5 * lam, 0.5 * k, 0.5 * x
    p_j = chi2_cdf(x, k)
    log_y = math.log(y) if y > 0 else -math.inf
    log_half = math.log(half) if half > 0 else -math.inf
    total = 0.0
    j = 0
    while True:
        w = math.exp(-half + j * log_half - math.lgamma(j + 1.0)) if half > 0 else float(j == 0)
        total += w * p_j
        if j > half + 1.0 and w < 1e-17:
            return total
        p_j -= math.exp((a + j) * log_y - y - math.lgamma(a + j + 1.0)) if y > 0 else 0.0
        p_j = max(p_j, 0.0)
        j += 1


@lru_cache(maxsize=1024)
def noncentrality_bias(pfa: float, pmd: float, dof: int) -> float:
    """``sqrt(lambda)``: the root of the non-centrality at which a chi-square test of ``dof``
    degrees and false-alarm probability ``pfa`` misses with probability ``pmd`` (Walter &
    Enge's ``p_bias``, "Weighted RAIM for precision approach", ION GPS 1995), by bisection on
    :func:`ncx2_cdf` to a relative width of 1e-8."""
    thr = chi2_threshold(pfa, dof)
    lo, hi = 0.0, 1.0
    while ncx2_cdf(thr, dof, hi) > pmd:
        hi *= 2.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if ncx2_cdf(thr, dof, mid) > pmd:
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-8 * hi:
            break
    return math.sqrt(0.5 * (lo + hi))
