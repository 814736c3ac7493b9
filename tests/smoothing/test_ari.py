"""ARI(p, d) Gauss–Markov filtering, variance components, robust weights (paper 5).

Oracles: dense NumPy linear algebra (normal equations built independently from eqs. (2)–(3)),
statsmodels SARIMAX (same model: ARI(p, d) observed with white noise), and known synthetic
truth (series simulated from given phi, sigma_n, sigma_e).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from navtrack.smoothing import _banded
from navtrack.smoothing._banded import (
    band_to_dense,
    cholesky_solve_banded,
    inverse_band,
    inverse_band_from_factor,
    solve_spd_banded,
    weighted_band_sums,
)
from navtrack.smoothing.ari import (
    AriConfig,
    ari_polynomial,
    fit_ari,
    gauss_markov_filter,
    regularize_time,
    robust_weight,
    simulate_ari,
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
def test_banded_solve_and_selected_inverse_match_dense(n: int, m: int, width: int) -> None:
    rng = np.random.default_rng(n * 10 + m)
    ab, dense = _random_band(rng, n, m)
    np.testing.assert_allclose(band_to_dense(ab), dense)
    rhs = rng.normal(size=n)
    x, logdet = solve_spd_banded(ab, rhs)
    np.testing.assert_allclose(x, np.linalg.solve(dense, rhs), rtol=1e-9, atol=1e-10)
    assert logdet == pytest.approx(np.linalg.slogdet(dense)[1], rel=1e-10, abs=1e-9)
    inv = np.linalg.inv(dense)
    _, _, factor = cholesky_solve_banded(ab, rhs)
    # both selected inversions: odd-even block recursion, and Takahashi's recursion on the
    # Cholesky factor (compiled when numba is installed, plain Python otherwise)
    for zb in (
        inverse_band(ab, width),
        inverse_band_from_factor(factor, width, method="takahashi"),
        _banded._takahashi_py(factor, max(width, m))[: width + 1],  # uncompiled recursion
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
    np.testing.assert_allclose(_banded._band_sums_py(zb, v, m), expected, rtol=1e-9, atol=1e-12)
    monkeypatch.setattr(_banded, "_band_sums", None)  # NumPy path (numba not installed)
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
    _banded.add_convolution_band(compiled, c, vs)
    np.testing.assert_allclose(band_to_dense(compiled), dense, rtol=1e-13, atol=1e-13)
    monkeypatch.setattr(_banded, "_add_convolution_band", None)  # NumPy path
    plain = np.zeros((m + 1, n))
    _banded.add_convolution_band(plain, c, vs)
    np.testing.assert_array_equal(plain, compiled)  # same sums in the same order
    with pytest.raises(ValueError, match="do not match"):
        _banded.add_convolution_band(plain, c, vs[1:])


def _dense_gauss_markov(y, phi, d, sigma_n, sigma_e):
    """Eqs. (2)-(3) as a dense weighted least-squares problem (independent construction)."""
    c = ari_polynomial(phi, d)
    m = c.size - 1
    n = y.size
    obs = np.flatnonzero(np.isfinite(y))
    a_obs = np.zeros((obs.size, n))
    a_obs[np.arange(obs.size), obs] = 1.0
    a_proc = np.zeros((n - m, n))
    for s in range(m, n):
        for i in range(m + 1):
            a_proc[s - m, s - i] = c[i]
    normal = a_obs.T @ a_obs / sigma_n**2 + a_proc.T @ a_proc / sigma_e**2
    rhs = a_obs.T @ y[obs] / sigma_n**2
    return np.linalg.solve(normal, rhs), np.linalg.inv(normal)


def test_gauss_markov_filter_matches_dense_least_squares() -> None:
    rng = np.random.default_rng(7)
    phi, d = (-0.8, 0.2), 2
    y, _ = simulate_ari(rng, 120, phi, d, 0.5, 0.2)
    y[[3, 40, 41, 42, 90]] = np.nan  # missing epochs
    x, zb, _ = gauss_markov_filter(y, phi, d, 0.5, 0.2, width=4)
    x_ref, cov_ref = _dense_gauss_markov(y, phi, d, 0.5, 0.2)
    np.testing.assert_allclose(x, x_ref, rtol=1e-9, atol=1e-9)
    for lag in range(5):
        np.testing.assert_allclose(zb[lag, : y.size - lag], np.diag(cov_ref, lag), rtol=1e-8)


@pytest.mark.parametrize(("phi", "d"), [((), 1), ((-0.5,), 1), ((-0.5,), 2), ((-1.2, 0.5), 2)])
def test_loglike_equals_statsmodels_sarimax(phi: tuple[float, ...], d: int) -> None:
    sm = pytest.importorskip("statsmodels.tsa.statespace.sarimax")
    rng = np.random.default_rng(3)
    y, _ = simulate_ari(rng, 250, phi, d, 0.5, 0.3)
    y[[10, 11, 100]] = np.nan
    model = sm.SARIMAX(y, order=(len(phi), d, 0), measurement_error=True, trend="n")
    # statsmodels AR sign: x_t = sum ar_i x_{t-i} + e_t, i.e. ar_i = -phi_i (paper sign)
    ll_sm = model.loglike(np.array([-f for f in phi] + [0.25, 0.09]))
    _, _, ll = gauss_markov_filter(y, phi, d, 0.5, 0.3, initial="stationary")
    assert ll == pytest.approx(ll_sm, abs=1e-5)


def test_estimator_recovers_known_truth_aircraft_like() -> None:
    # Paper Table 5 magnitudes: ARI(2,2), sigma_n = 0.003, sigma_e = 0.0013 (deg).
    rng = np.random.default_rng(11)
    phi = (-1.2, 0.5)
    y, x_true = simulate_ari(rng, 4000, phi, 2, 0.003, 0.0013)
    res = fit_ari(y, AriConfig(order=(2, 2), robust="off"))
    assert res.status == "ok"
    assert res.sigma_n == pytest.approx(0.003, rel=0.06)
    assert res.sigma_e == pytest.approx(0.0013, rel=0.10)
    np.testing.assert_allclose(res.phi, phi, atol=0.08)
    # filtered series closer to the truth than the observations, and sigma_x honest (±15 %)
    err = res.x - x_true
    assert np.sqrt(np.mean(err**2)) < 0.75 * 0.003
    assert np.sqrt(np.mean(err**2)) == pytest.approx(res.sigma_x_rms, rel=0.15)


def test_variance_components_satisfy_vce_equations() -> None:
    # At convergence sigma_n^2 = Omega_n / r_n (Förstner's redundancy-based VCE fixed point).
    rng = np.random.default_rng(5)
    y, _ = simulate_ari(rng, 600, (-0.7,), 1, 0.05, 0.03)
    res = fit_ari(y, AriConfig(order=(1, 1), robust="off"))
    omega_n = float(np.sum((y - res.x) ** 2))
    assert res.sigma_n**2 == pytest.approx(omega_n / res.redundancy_n, rel=1e-4)
    n_eq = y.size + (y.size - 2) - y.size  # observations + process equations - unknowns
    # with the stationary start the p = 1 prior equation adds one to the process group
    assert res.redundancy_n + res.redundancy_e == pytest.approx(n_eq + 1, abs=1e-6)


def test_sarimax_short_series_same_loglike_or_better() -> None:
    sm = pytest.importorskip("statsmodels.tsa.statespace.sarimax")
    import warnings

    rng = np.random.default_rng(2)
    phi = (-0.6,)
    y, _ = simulate_ari(rng, 150, phi, 1, 0.4, 0.3)
    ours = fit_ari(y, AriConfig(order=(1, 1), robust="off"))
    model = sm.SARIMAX(y, order=(1, 1, 0), measurement_error=True, trend="n")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = model.fit(disp=False)
        ll_ours = model.loglike(np.array([-ours.phi[0], ours.sigma_n**2, ours.sigma_e**2]))
    assert ll_ours >= res.llf - 1e-4
    assert ours.loglike == pytest.approx(ll_ours, abs=1e-5)


def test_gross_errors_flagged_with_few_false_flags() -> None:
    rng = np.random.default_rng(21)
    y, _ = simulate_ari(rng, 2000, (-1.2, 0.5), 2, 0.003, 0.0013)
    idx = rng.choice(np.arange(10, 1990), size=20, replace=False)
    y[idx] += rng.choice([-1.0, 1.0], size=20) * 8 * 0.003
    res = fit_ari(y, AriConfig(order=(2, 2)))
    assert np.all(res.gross_error[idx])
    false = np.count_nonzero(res.gross_error) - 20
    assert false <= 0.01 * 1980
    assert res.sigma_n == pytest.approx(0.003, rel=0.1)  # robust: errors do not inflate it
    plain = fit_ari(y, AriConfig(order=(2, 2), robust="off"))
    assert plain.sigma_n > res.sigma_n


def test_order_selection_picks_true_order_on_long_series() -> None:
    rng = np.random.default_rng(4)
    y, _ = simulate_ari(rng, 3000, (-1.2, 0.5), 2, 0.003, 0.0013)
    res = fit_ari(y, AriConfig(robust="off", max_p=4, min_d=1))
    assert (res.p, res.d) == (2, 2)
    assert len(res.candidates) == 10  # p = 0..4, d = 1..2: every candidate was fitted


def test_autocorrelation_of_filtered_data_from_inverse() -> None:
    rng = np.random.default_rng(8)
    y, _ = simulate_ari(rng, 300, (-0.5,), 2, 0.02, 0.01)
    res = fit_ari(y, AriConfig(order=(1, 2), robust="off"))
    _, cov = _dense_gauss_markov(y - np.mean(y), res.phi, 2, res.sigma_n, res.sigma_e)
    # the estimate uses the stationary start: rebuild with the same model via the library
    _, zb, _ = gauss_markov_filter(
        y, res.phi, 2, res.sigma_n, res.sigma_e, width=4, initial="stationary"
    )
    sd = np.sqrt(zb[0])
    for h in range(1, 5):
        r = np.mean(zb[h, : y.size - h] / (sd[: y.size - h] * sd[h:]))
        assert res.autocorr[h - 1] == pytest.approx(r, abs=1e-9)
    assert 0 < res.autocorr[0] < 1
    np.testing.assert_allclose(res.sigma_x, sd, rtol=1e-9)
    assert np.all(np.diag(cov) > 0)


def test_missing_epochs_are_kept_and_interpolated() -> None:
    rng = np.random.default_rng(9)
    y, _x_true = simulate_ari(rng, 400, (-0.8,), 2, 0.01, 0.005)
    y[100:110] = np.nan
    res = fit_ari(y, AriConfig(order=(1, 2)))
    assert res.n_missing == 10
    assert np.all(res.epoch_status[100:110] == 1)
    assert np.all(np.isfinite(res.x[100:110]))
    assert np.all(res.sigma_x[100:110] > res.sigma_x[50])  # less certain inside the gap
    assert not res.gross_error[100:110].any()


def test_bad_input_statuses() -> None:
    assert fit_ari(np.arange(6.0), AriConfig(order=(2, 2))).status == "too_short"
    assert fit_ari(np.full(100, 3.0), AriConfig(order=(1, 1))).status == "constant"
    t = np.arange(100.0)
    t[50] = t[49]
    y = np.sin(np.arange(100) / 5.0)
    assert fit_ari(y, AriConfig(order=(1, 1)), t=t).status == "non_monotonic_time"
    t2 = np.arange(100.0)
    t2[60:] += 0.5
    assert fit_ari(y, AriConfig(order=(1, 1)), t=t2).status == "irregular_time"
    bad = fit_ari(np.full(3, np.nan), AriConfig(order=(1, 1)))
    assert bad.status == "too_short"
    assert np.all(np.isnan(bad.x))
    with pytest.raises(ValueError, match="infinite"):
        fit_ari(np.array([1.0, np.inf, 2.0]))
    with pytest.raises(ValueError, match="one-dimensional"):
        fit_ari(np.zeros((10, 2)))
    with pytest.raises(ValueError, match="order"):
        AriConfig(order=(0, 0))


def test_regularize_time_inserts_missing_epochs() -> None:
    t = np.array([0.0, 1.0, 2.0, 5.0, 6.0])
    y = np.array([1.0, 2.0, 3.0, 6.0, 7.0])
    tg, yg, inserted = regularize_time(t, y)
    assert inserted == 2
    np.testing.assert_allclose(tg, np.arange(7.0))
    assert np.isnan(yg[3])
    assert np.isnan(yg[4])
    assert yg[5] == 6.0
    with pytest.raises(ValueError, match="off the"):
        regularize_time(np.array([0.0, 1.0, 2.5, 3.0]), np.zeros(4))
    with pytest.raises(ValueError, match="strictly increasing"):
        regularize_time(np.array([0.0, 1.0, 1.0]), np.zeros(3))


def test_robust_weight_functions() -> None:
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


def test_robust_process_equations_downweight_an_edge() -> None:
    # Paper §2.2: robust treatment of eq. (3) reduces the influence of edges/discontinuities.
    rng = np.random.default_rng(13)
    y, _ = simulate_ari(rng, 500, (-0.5,), 1, 0.01, 0.004)
    y[250:] += 0.2  # a step of 50 sigma_e in the process
    res = fit_ari(y, AriConfig(order=(1, 1), robust_process=True))
    # process equation s ends at epoch s + p + d; the step enters equations ending at 250, 251
    assert res.process_weight[250 - 2] < 0.1
    assert np.median(res.process_weight) == 1.0
    assert not res.gross_error[245:255].any()  # the step is not blamed on the observations
    plain = fit_ari(y, AriConfig(order=(1, 1), robust="off"))
    assert res.sigma_e < plain.sigma_e


@pytest.mark.parametrize("name", ["danish", "huber", "igg3"])
def test_robust_defaults_keep_sigma_n_on_clean_data(name: str) -> None:
    # Reweighting with simultaneous VCE must not shrink sigma_n on data without gross errors
    # (truth: simulated ARI(2,2), sigma_n = 0.003).
    rng = np.random.default_rng(31)
    y, _ = simulate_ari(rng, 2000, (-1.2, 0.5), 2, 0.003, 0.0013)
    res = fit_ari(y, AriConfig(order=(2, 2), robust=name))  # type: ignore[arg-type]
    assert res.sigma_n == pytest.approx(0.003, rel=0.06)
    assert res.n_flagged <= 0.01 * y.size


def test_order_selection_scores_every_candidate_after_a_leading_gap() -> None:
    # A series that starts with a gap (BROAD: optical tracking lost at the start). The
    # selection likelihood conditions on the first max(p+d) *observed* epochs; conditioning on
    # the unobserved head made its normal matrix singular up to rounding and dropped candidates.
    rng = np.random.default_rng(11)
    y, _ = simulate_ari(rng, 1200, (-0.6, 0.2), 1, 0.02, 0.01)
    y[:40] = np.nan
    res = fit_ari(y, AriConfig(robust="off", max_p=4, min_d=1))
    assert len(res.candidates) == 10  # p = 0..4, d = 1..2: every candidate was scored
    assert all(np.isfinite(score) for _, _, score in res.candidates)


def test_order_selection_does_not_depend_on_the_warm_start(
    shared_data: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # Real heavy-tailed series (BROAD 07 yaw, first 2000 epochs at 10 Hz): the non-robust
    # candidate likelihoods have two modes (sigma_n ~ 1.9 deg / sigma_e ~ 10 deg and
    # sigma_n ~ 5.2 deg / sigma_e ~ 1.9 deg at ARI(5,1)). Visiting each candidate from a
    # perturbed warm start (phi halved, sigma_n x e, sigma_e / e) must give the same scores and
    # order: the selection may not depend on the path that led to a candidate.
    from navtrack.experiments.ari import broad_series
    from navtrack.smoothing import ari

    path = shared_data / "trajectory" / "broad" / "07_undisturbed_fast_rotation_B.mat"
    if not path.exists():
        pytest.skip(f"{path} absent")
    y = broad_series(path, decimate=10).columns["yaw_deg"][:2000]
    cfg = AriConfig(robust="off", min_d=1)
    plain = fit_ari(y, cfg)
    original = ari._fit_fixed

    def perturbed_warm(yy, p, d, c, *, robust, starts=None):  # type: ignore[no-untyped-def]
        if starts is not None and len(starts) > 1:  # [warm from ARI(p-1, d), default start]
            warm = starts[0].copy()
            warm[:p] *= 0.5
            warm[p] += 2.0
            warm[p + 1] -= 2.0
            starts = [warm, *starts[1:]]
        return original(yy, p, d, c, robust=robust, starts=starts)

    monkeypatch.setattr(ari, "_fit_fixed", perturbed_warm)
    other = fit_ari(y, cfg)
    assert (other.p, other.d) == (plain.p, plain.d)
    a = {(p, d): s for p, d, s in plain.candidates}
    b = {(p, d): s for p, d, s in other.candidates}
    assert a.keys() == b.keys()
    for key, score in a.items():
        # the two modes differ by ~200 BIC units; 2 units is the convergence noise
        assert b[key] == pytest.approx(score, abs=2.0), key
