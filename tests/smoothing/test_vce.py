"""Förstner's frequency-domain variance-component estimation (``AriConfig(vce="forstner")``).

Oracles: the closed form of the spectral share of a random walk in white noise (the integral
``(1/pi) int_0^pi dw / (a - b cos w) = 1 / sqrt(a^2 - b^2)``), the exact time-domain redundancies
``n - tr(N^-1 N_k)`` of a long series (which the frequency-domain ones approximate), and
simulated series whose variance components are known.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from navtrack.smoothing.ari import AriConfig, AriStatus, fit_ari, simulate_ari
from navtrack.smoothing.model import gauss_markov_filter
from navtrack.smoothing.vce import spectral_redundancies, spectral_shares


@pytest.mark.parametrize("ratio", [0.01, 0.3, 1.0, 25.0])
def test_random_walk_share_has_its_closed_form(ratio: float) -> None:
    # ARI(0,1): q = ratio * 2 (1 - cos w), so r_e / R = 1 / sqrt(1 + 4 ratio)
    share_n, share_e = spectral_shares([], 1, ratio, 1.0, n_freq=4096)
    assert share_e == pytest.approx(1.0 / math.sqrt(1.0 + 4.0 * ratio), rel=1e-6)
    assert share_n + share_e == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize(("phi", "d"), [((-0.6,), 1), ((-0.7318, 0.3832), 2), ((0.4, -0.2), 1)])
def test_spectral_redundancies_approximate_the_exact_traces(phi: tuple[float, ...], d: int) -> None:
    n, sn, se = 6000, 0.02, 0.01
    _, zb, _ = gauss_markov_filter(np.zeros(n), phi, d, sn, se, width=0, initial="conditional")
    r_n_exact = n - float(np.sum(zb[0])) / sn**2
    m = len(phi) + d
    total = n + (n - m) - n
    r_n, r_e = spectral_redundancies(np.asarray(phi), d, sn**2, se**2, total)
    assert r_n + r_e == pytest.approx(total)
    # edge effects are O(m) epochs of a 6000-epoch series
    assert r_n == pytest.approx(r_n_exact, rel=5e-3)


@pytest.mark.parametrize(
    ("phi", "d", "sigma_n", "sigma_e"),
    [((-0.6,), 1, 0.02, 0.01), ((0.4, -0.2), 1, 0.01, 0.01)],
)
def test_forstner_vce_recovers_known_components(
    phi: tuple[float, ...], d: int, sigma_n: float, sigma_e: float
) -> None:
    rng = np.random.default_rng(35)
    ratios_n, ratios_e = [], []
    for _ in range(4):
        y, _ = simulate_ari(rng, 3000, phi, d, sigma_n, sigma_e)
        cfg = AriConfig(order=(len(phi), d), robust="off", estimator="paper", vce="forstner")
        res = fit_ari(y, cfg)
        assert res.status == AriStatus.OK
        ratios_n.append(res.sigma_n / sigma_n)
        ratios_e.append(res.sigma_e / sigma_e)
    # mean of four series; one series' relative sd is about 2 % (sigma_n) and 5-10 % (sigma_e)
    assert np.mean(ratios_n) == pytest.approx(1.0, abs=0.03)
    assert np.mean(ratios_e) == pytest.approx(1.0, abs=0.08)


def test_forstner_and_redundancy_forms_agree_on_a_long_series() -> None:
    rng = np.random.default_rng(7)
    y, _ = simulate_ari(rng, 4000, (-0.6,), 1, 0.02, 0.01)
    base = AriConfig(order=(1, 1), robust="off", estimator="paper")
    exact_traces = fit_ari(y, base)
    forstner = fit_ari(y, AriConfig(order=(1, 1), robust="off", estimator="paper", vce="forstner"))
    assert forstner.sigma_n == pytest.approx(exact_traces.sigma_n, rel=0.01)
    assert forstner.sigma_e == pytest.approx(exact_traces.sigma_e, rel=0.02)


def test_forstner_needs_the_paper_estimator() -> None:
    with pytest.raises(ValueError, match="estimator='paper'"):
        AriConfig(vce="forstner")
    with pytest.raises(ValueError, match="vce must be one of"):
        AriConfig(estimator="paper", vce="frequency")  # type: ignore[arg-type]
