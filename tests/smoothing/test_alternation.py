"""The paper's estimator (``AriConfig(estimator="paper")``): alternating filtering, VCE, AR fit.

Oracles: the quasi-Newton maximum of the same (conditional) likelihood reached by the other
estimator (an independent search over the same function), Förstner's VCE fixed-point equation
``sigma_n^2 = Omega_n / r_n``, and known synthetic truth.
"""

from __future__ import annotations

import numpy as np
import pytest

from navtrack.smoothing.ari import AriConfig, AriStatus, fit_ari, simulate_ari


def test_alternation_reaches_the_conditional_likelihood_maximum() -> None:
    rng = np.random.default_rng(21)
    y, _ = simulate_ari(rng, 800, (-0.6,), 1, 0.02, 0.01)
    paper = fit_ari(y, AriConfig(order=(1, 1), robust="off", estimator="paper"))
    exact = fit_ari(y, AriConfig(order=(1, 1), robust="off", initial="conditional"))
    assert paper.status == AriStatus.OK
    assert paper.loglike == pytest.approx(exact.loglike, abs=0.05)
    assert paper.sigma_n == pytest.approx(exact.sigma_n, rel=0.01)
    assert paper.sigma_e == pytest.approx(exact.sigma_e, rel=0.02)
    np.testing.assert_allclose(paper.phi, exact.phi, atol=0.01)
    # the VCE fixed point of the alternation (to its stopping rule)
    omega_n = float(np.sum((y - paper.x) ** 2))
    assert paper.sigma_n**2 == pytest.approx(omega_n / paper.redundancy_n, rel=1e-3)


def test_alternation_recovers_known_truth_and_flags_gross_errors() -> None:
    rng = np.random.default_rng(4)
    y, _ = simulate_ari(rng, 1500, (-0.5,), 2, 0.003, 0.0013)
    idx = np.array([200, 700, 1200])
    y[idx] += np.array([10.0, -12.0, 9.0]) * 0.003
    res = fit_ari(y, AriConfig(order=(1, 2), estimator="paper"))
    assert res.estimated
    assert res.sigma_n == pytest.approx(0.003, rel=0.10)
    assert res.sigma_e == pytest.approx(0.0013, rel=0.15)
    assert np.all(res.gross_error[idx])
    assert res.n_flagged - idx.size <= 0.01 * y.size  # the reproduction's false-flag bar


def test_estimator_name_is_checked() -> None:
    with pytest.raises(ValueError, match="estimator"):
        AriConfig(estimator="sarimax")  # type: ignore[arg-type]
