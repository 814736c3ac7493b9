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

from navtrack.smoothing.ari import (
    AriConfig,
    AriEpochStatus,
    AriStatus,
    fit_ari,
    gauss_markov_filter,
    regularize_time,
    simulate_ari,
)
from navtrack.smoothing.estimation import observed_information, spectral_information


def _dense_normal(y, phi, d, sigma_n, sigma_e, *, stationary=False):
    """Normal matrix and right-hand side of eqs. (2)-(3) as a dense weighted least-squares
    problem, built independently of the library: the process coefficients by NumPy's
    polynomial product, and for the stationary start the AR covariance ``Gamma_p`` from the
    discrete Lyapunov equation of the companion form (not the library's Yule-Walker solve)."""
    poly = np.polynomial.polynomial
    c = poly.polymul(np.concatenate([[1.0], phi]), poly.polypow([1.0, -1.0], d))
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
    p = len(phi)
    if stationary and p:
        from scipy.linalg import solve_discrete_lyapunov

        # u_t = -sum phi_i u_{t-i} + e_t; state (u_t, ..., u_{t-p+1}), unit innovation
        comp = np.zeros((p, p))
        comp[0] = -np.asarray(phi)
        comp[1:, :-1] = np.eye(p - 1)
        q = np.zeros((p, p))
        q[0, 0] = 1.0
        gamma = solve_discrete_lyapunov(comp, q)
        # u_{d+k} = sum_j (-1)^j C(d, j) x_{d+k-j}, k = 0..p-1: the first p differences
        diff = np.zeros((p, n))
        for k in range(p):
            for j in range(d + 1):
                diff[k, d + k - j] = (-1) ** j * math.comb(d, j)
        normal = normal + diff.T @ np.linalg.inv(gamma) @ diff / sigma_e**2
    rhs = a_obs.T @ y[obs] / sigma_n**2
    return normal, rhs


def _dense_gauss_markov(y, phi, d, sigma_n, sigma_e):
    """Filtered series and covariance of the conditional model from the dense normal matrix."""
    normal, rhs = _dense_normal(y, phi, d, sigma_n, sigma_e)
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
    assert res.status == AriStatus.OK
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


def test_covariance_and_autocorrelation_match_dense_inverse() -> None:
    # sigma_x, r(h) and the band of N^-1 against numpy.linalg.inv of the dense normal matrix,
    # at every epoch and lag where the band is defined (stationary start: the model fit_ari
    # estimates; conditional: the plain Gauss-Markov model).
    rng = np.random.default_rng(8)
    y, _ = simulate_ari(rng, 300, (-0.5,), 2, 0.02, 0.01)
    y[[40, 41, 150]] = np.nan
    n = y.size
    res = fit_ari(y, AriConfig(order=(1, 2), robust="off"))
    assert res.status == AriStatus.OK
    normal, _ = _dense_normal(y, res.phi, 2, res.sigma_n, res.sigma_e, stationary=True)
    cov = np.linalg.inv(normal)
    sd = np.sqrt(np.diag(cov))
    np.testing.assert_allclose(res.sigma_x, sd, rtol=1e-8)
    for h in range(1, 5):
        r = np.mean(np.diag(cov, h) / (sd[: n - h] * sd[h:]))
        assert res.autocorr[h - 1] == pytest.approx(r, abs=1e-8)
    assert res.sigma_x_rms == pytest.approx(np.sqrt(np.mean(np.diag(cov)[np.isfinite(y)])))
    for initial in ("stationary", "conditional"):
        stationary = initial == "stationary"
        normal, _ = _dense_normal(y, res.phi, 2, res.sigma_n, res.sigma_e, stationary=stationary)
        cov = np.linalg.inv(normal)
        _, zb, _ = gauss_markov_filter(
            y, res.phi, 2, res.sigma_n, res.sigma_e, width=6, initial=initial
        )
        for lag in range(7):
            np.testing.assert_allclose(zb[lag, : n - lag], np.diag(cov, lag), rtol=1e-8)
            assert np.all(np.isnan(zb[lag, n - lag :]))


def test_missing_epochs_are_kept_and_interpolated() -> None:
    rng = np.random.default_rng(9)
    y, _x_true = simulate_ari(rng, 400, (-0.8,), 2, 0.01, 0.005)
    y[100:110] = np.nan
    res = fit_ari(y, AriConfig(order=(1, 2)))
    assert res.n_missing == 10
    assert np.all(res.epoch_status[100:110] == AriEpochStatus.MISSING)
    assert np.all(np.isfinite(res.x[100:110]))
    assert np.all(res.sigma_x[100:110] > res.sigma_x[50])  # less certain inside the gap
    assert not res.gross_error[100:110].any()


def test_bad_input_statuses() -> None:
    short = fit_ari(np.arange(6.0), AriConfig(order=(2, 2)))
    assert short.status == AriStatus.TOO_SHORT
    assert np.all(short.epoch_status == AriEpochStatus.NOT_ESTIMATED)
    assert fit_ari(np.full(100, 3.0), AriConfig(order=(1, 1))).status == AriStatus.CONSTANT
    t = np.arange(100.0)
    t[50] = t[49]
    y = np.sin(np.arange(100) / 5.0)
    assert fit_ari(y, AriConfig(order=(1, 1)), t=t).status == AriStatus.NON_MONOTONIC_TIME
    t2 = np.arange(100.0)
    t2[60:] += 0.5
    assert fit_ari(y, AriConfig(order=(1, 1)), t=t2).status == AriStatus.IRREGULAR_TIME
    bad = fit_ari(np.full(3, np.nan), AriConfig(order=(1, 1)))
    assert bad.status == AriStatus.TOO_SHORT
    assert not bad.estimated
    assert np.all(bad.epoch_status == AriEpochStatus.MISSING)
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
    from navtrack.smoothing import fitting

    path = shared_data / "trajectory" / "broad" / "07_undisturbed_fast_rotation_B.mat"
    if not path.exists():
        pytest.skip(f"{path} absent")
    y = broad_series(path, decimate=10, form="euler").columns["yaw_deg"][:2000]
    cfg = AriConfig(robust="off", min_d=1)
    plain = fit_ari(y, cfg)
    original = fitting.fit_fixed_order

    def perturbed_warm(yy, p, d, c, *, robust, starts=None):  # type: ignore[no-untyped-def]
        if starts is not None and len(starts) > 1:  # [warm from ARI(p-1, d), default start]
            warm = starts[0].copy()
            warm[:p] *= 0.5
            warm[p] += 2.0
            warm[p + 1] -= 2.0
            starts = [warm, *starts[1:]]
        return original(yy, p, d, c, robust=robust, starts=starts)

    monkeypatch.setattr(fitting, "fit_fixed_order", perturbed_warm)
    other = fit_ari(y, cfg)
    assert (other.p, other.d) == (plain.p, plain.d)
    a = {(p, d): s for p, d, s in plain.candidates}
    b = {(p, d): s for p, d, s in other.candidates}
    assert a.keys() == b.keys()
    for key, score in a.items():
        # the two modes differ by ~200 BIC units; 2 units is the convergence noise
        assert b[key] == pytest.approx(score, abs=2.0), key


def test_long_series_blocks_and_scoring_reach_the_window_bfgs_optimum() -> None:
    # A series of screen_n * stage_growth epochs or more goes through a leading block and the
    # structured quasi-Newton search on the spectral information; a stage_growth too large for
    # any block sends the same series through the window-Hessian BFGS path. Oracle: both are
    # maximum-likelihood routes, so they reach the same optimum (robust off, gaps included).
    y, _ = simulate_ari(np.random.default_rng(12), 80_000, [-0.6], 2, 0.02, 0.01)
    y[30_000:30_050] = np.nan
    fits = [
        fit_ari(y, AriConfig(order=(1, 2), robust="off", stage_growth=growth))
        for growth in (16, 1000)
    ]
    assert all(f.status == AriStatus.OK for f in fits)
    assert fits[0].loglike == pytest.approx(fits[1].loglike, abs=0.01)
    assert fits[0].sigma_n == pytest.approx(fits[1].sigma_n, rel=1e-3)
    assert fits[0].sigma_e == pytest.approx(fits[1].sigma_e, rel=1e-2)
    np.testing.assert_allclose(fits[0].x, fits[1].x, atol=1e-2 * float(np.min(fits[1].sigma_x)))


def test_spectral_information_matches_the_observed_information_on_a_long_series() -> None:
    # Oracle: Whittle's expected information equals the observed information of the exact
    # likelihood up to O(n^-1/2) relative terms; n = 50000, ARI(1,1) near its truth.
    phi, sn, se = [-0.5], 0.02, 0.01
    y, _ = simulate_ari(np.random.default_rng(13), 50_000, phi, 1, sn, se)
    observed = observed_information(y, phi, 1, sn, se)
    vec = np.array([phi[0], 2 * math.log(sn), 2 * math.log(se)])
    expected = spectral_information(vec, 1, float(y.size))
    np.testing.assert_allclose(np.diag(expected), np.diag(observed), rtol=0.05)
    assert np.all(np.linalg.eigvalsh(expected) > 0)
