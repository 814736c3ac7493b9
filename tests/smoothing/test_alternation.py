"""The paper's estimator (``AriConfig(estimator="paper")``): alternating filtering, VCE, AR fit.

Oracles: the quasi-Newton maximum of the same (conditional) likelihood reached by the other
estimator (an independent search over the same function), Förstner's VCE fixed-point equation
``sigma_n^2 = Omega_n / r_n``, and known synthetic truth.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from navtrack.smoothing.alternation import alternate, ar_step
from navtrack.smoothing.ari import AriConfig, AriStatus, fit_ari, simulate_ari
from navtrack.smoothing.banded import weighted_band_sums
from navtrack.smoothing.estimation import evaluate, phi_gradient_terms, starting_values
from navtrack.smoothing.model import AriProblem, ari_polynomial


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


@pytest.mark.parametrize(
    ("phi", "d", "n", "seed"), [((-0.5, 0.2), 1, 600, 3), ((-0.73, 0.38), 2, 600, 5)]
)
def test_squarem_reaches_the_fixed_point_of_the_plain_iteration(
    phi: tuple[float, ...], d: int, n: int, seed: int
) -> None:
    # Oracle: the plain iteration of the scheme run to a tight tolerance; the accelerated
    # iteration must stop at the same fixed point, in fewer model evaluations.
    y, _ = simulate_ari(np.random.default_rng(seed), n, phi, d, 0.02, 0.01)
    p, m = len(phi), len(phi) + d
    yc = y - y.mean()
    scale = float(np.std(np.diff(yc, d)))
    problem = AriProblem(
        yc,
        np.ones(n),
        np.ones(n - m),
        p,
        d,
        False,
        2 * math.log(1e-6 * scale),
        2 * math.log(1e3 * scale),
    )
    start = starting_values(yc, p, d, 3)[1]
    plain = alternate(start, problem, 1e-8, 20000, accelerate=False)
    fast = alternate(start, problem, 1e-8, 20000)
    assert plain is not None
    assert fast is not None
    assert plain.converged
    assert fast.converged
    np.testing.assert_allclose(fast.vec, plain.vec, atol=1e-6)
    assert fast.fit.loglike == pytest.approx(plain.fit.loglike, abs=1e-6)
    assert fast.n_iter < plain.n_iter / 2


def test_ar_step_solves_the_expected_moment_equations() -> None:
    # Oracle: the phi part of the likelihood gradient (estimation.phi_gradient_terms, the same
    # expected moments summed term by term) vanishes at the step's coefficients.
    y, _ = simulate_ari(np.random.default_rng(9), 500, (-0.9, 0.3, 0.1), 1, 0.02, 0.01)
    p, d = 3, 1
    m = p + d
    yc = y - y.mean()
    v = np.random.default_rng(1).uniform(0.5, 1.0, y.size - m)
    problem = AriProblem(yc, np.ones(y.size), v, p, d, False)
    vec = np.array([-0.5, 0.1, 0.0, math.log(4e-4), math.log(1e-4)])
    out = evaluate(vec, problem)
    assert out is not None
    assert out.fit.zb is not None
    phi = ar_step(vec[:p], problem, out.fit.x, out.fit.zb)
    big_s = weighted_band_sums(out.fit.zb, v, m)
    c = ari_polynomial(phi, d)
    resid = phi_gradient_terms(c, out.fit.x, v, p, d, big_s)
    scale = phi_gradient_terms(ari_polynomial(np.zeros(p), d), out.fit.x, v, p, d, big_s)
    assert np.max(np.abs(resid)) < 1e-9 * np.max(np.abs(scale))
