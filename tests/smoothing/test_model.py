"""The problem object every ARI estimator takes, and the status enums of the result."""

from __future__ import annotations

import dataclasses
import json
import math
import warnings

import numpy as np
import pytest

from navtrack.smoothing.ari import AriConfig, AriEpochStatus, AriStatus, fit_ari, simulate_ari
from navtrack.smoothing.estimation import MIN_WEIGHT, evaluate, observed_information
from navtrack.smoothing.model import AriProblem, gauss_markov_filter, stationary_prior


def _problem(n: int = 50, p: int = 2, d: int = 1, stationary: bool = True) -> AriProblem:
    rng = np.random.default_rng(0)
    return AriProblem(
        y0=rng.normal(size=n), w=np.ones(n), v=np.ones(n - p - d), p=p, d=d, stationary=stationary
    )


def test_problem_checks_shapes_and_is_read_only() -> None:
    pb = _problem()
    assert (pb.m, pb.n) == (3, 50)
    with pytest.raises(dataclasses.FrozenInstanceError):
        pb.p = 3  # type: ignore[misc]
    with pytest.raises(ValueError, match="read-only"):
        pb.w[0] = 0.5
    with pytest.raises(ValueError, match="do not match"):
        AriProblem(np.zeros(50), np.ones(50), np.ones(48), 2, 1, True)  # v needs n - 3
    with pytest.raises(ValueError, match="do not match"):
        AriProblem(np.zeros(50), np.ones(49), np.ones(47), 2, 1, True)


def test_problem_head_and_weights() -> None:
    pb = _problem()
    head = pb.head(20)
    assert (head.n, head.v.size) == (20, 17)
    np.testing.assert_array_equal(head.y0, pb.y0[:20])
    assert (head.p, head.d, head.stationary) == (pb.p, pb.d, pb.stationary)
    w = np.linspace(0.0, 1.0, 50)
    v = np.full(47, 0.5)
    other = pb.with_weights(w, v)
    np.testing.assert_array_equal(other.w, w)
    np.testing.assert_array_equal(other.v, v)
    np.testing.assert_array_equal(pb.w, 1.0)  # the original is unchanged
    # the weights enter the model: another likelihood at the same parameters
    vec = np.array([-0.5, 0.1, math.log(0.5), math.log(0.2)])
    base, weighted = evaluate(vec, pb), evaluate(vec, other)
    assert base is not None
    assert weighted is not None
    assert base.fit.loglike != weighted.fit.loglike


def test_problem_prior_only_for_a_stationary_start() -> None:
    phi = np.array([-0.5, 0.1])
    pb = _problem()
    prior = pb.prior(phi)
    assert prior is not None
    np.testing.assert_array_equal(prior.g_mat, stationary_prior(phi, 1).g_mat)  # type: ignore[union-attr]
    assert _problem(stationary=False).prior(phi) is None
    assert _problem(p=0, d=2).prior(np.zeros(0)) is None
    assert pb.prior(np.array([-2.5, 1.0])) is None  # explosive AR part: no stationary start
    assert evaluate(np.array([-2.5, 1.0, 0.0, 0.0]), pb) is None


def test_observed_information_is_symmetric_positive_definite() -> None:
    rng = np.random.default_rng(2)
    y, _ = simulate_ari(rng, 400, (-0.6,), 1, 0.05, 0.03)
    info = observed_information(y, (-0.6,), 1, 0.05, 0.03)
    assert info.shape == (3, 3)
    np.testing.assert_allclose(info, info.T)
    assert np.all(np.linalg.eigvalsh(info) > 0)


def test_statuses_are_int_enums_with_the_former_codes_and_names() -> None:
    assert [s.value for s in AriStatus] == list(range(8))
    assert [str(s) for s in AriStatus] == [
        "ok",
        "not_converged",
        "boundary",
        "too_short",
        "constant",
        "non_monotonic_time",
        "irregular_time",
        "singular",
    ]
    assert [(s.value, str(s)) for s in AriEpochStatus] == [
        (0, "ok"),
        (1, "missing"),
        (2, "gross_error"),
        (3, "not_estimated"),
    ]
    assert f"{AriStatus.BOUNDARY}" == "boundary"
    assert f"{AriStatus.OK:>4}" == "  ok"


def test_result_status_and_summary() -> None:
    rng = np.random.default_rng(6)
    y, _ = simulate_ari(rng, 300, (-0.5,), 1, 0.02, 0.01)
    y[10] = np.nan
    y[200] += 0.5
    res = fit_ari(y, AriConfig(order=(1, 1)))
    assert isinstance(res.status, AriStatus)
    assert res.status == AriStatus.OK
    assert res.estimated
    assert res.epoch_status.dtype == np.int8
    assert res.epoch_status[10] == AriEpochStatus.MISSING
    assert res.epoch_status[200] == AriEpochStatus.GROSS_ERROR
    assert np.count_nonzero(res.epoch_status == AriEpochStatus.OK) == 298 - res.n_flagged + 1
    summary = res.summary()
    assert json.loads(json.dumps(summary))["status"] == "ok"  # the name, not the code
    bad = fit_ari(np.full(100, 3.0), AriConfig(order=(1, 1)))
    assert bad.status == AriStatus.CONSTANT
    assert not bad.estimated
    assert bad.summary()["status"] == "constant"


def test_likelihood_of_a_near_zero_weight_is_finite() -> None:
    # A weight in the subnormal range (a Danish weight of a 67-sigma outlier) once made
    # sigma_n^2 / w overflow and the log-likelihood -inf. Oracle: the weight enters the
    # likelihood only through -log(sigma_n^2 / w) / 2 once its epoch carries no information.
    y, _ = simulate_ari(np.random.default_rng(2), 300, [-0.5], 1, 0.02, 0.01)
    weights = []
    for tiny in (1e-320, 1e-310):
        w = np.ones(y.size)
        w[100] = tiny
        weights.append(w)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        ll = [gauss_markov_filter(y, [-0.5], 1, 0.02, 0.01, weight=w)[2] for w in weights]
    assert np.all(np.isfinite(ll))
    expected = 0.5 * (math.log(weights[0][100]) - math.log(weights[1][100]))
    assert ll[0] - ll[1] == pytest.approx(expected, abs=1e-6)


def test_robust_fit_with_huge_outliers_leaves_them_out() -> None:
    # Outliers of 55-80 sigma: Danish weights from exp(-480) to exp(-1000), through the
    # subnormal range. Weights below MIN_WEIGHT are 0 (the epoch leaves the fit, as it did
    # when its weight underflowed); no RuntimeWarning; every outlier flagged.
    rng = np.random.default_rng(5)
    y, _ = simulate_ari(rng, 3000, [-0.7318, 0.3832], 2, 0.0023, 0.0005)
    idx = np.arange(50, 3000, 60)
    y[idx] += np.linspace(55, 80, idx.size) * 0.0023
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        res = fit_ari(y, AriConfig(order=(2, 2)))
    assert res.status == AriStatus.OK
    assert np.all(res.weight[idx] == 0.0)
    assert np.all((res.weight == 0.0) | (res.weight >= MIN_WEIGHT))
    assert np.all(res.gross_error[idx])
    assert np.isfinite(res.loglike)
    assert res.sigma_n == pytest.approx(0.0023, rel=0.1)


def test_likelihood_does_not_depend_on_the_drift_of_an_integrated_series() -> None:
    # Oracle: the process equations of ARI(p, 2) annihilate a line, so adding one to the
    # observations leaves the likelihood unchanged. The data are multiples of 2^-20 and the
    # line integers, so both series are exact in floating point; solved for x itself (the
    # rounding of the solve proportional to |x|) the likelihood moved by 1.5e-5 with a line of
    # 1e7 and by ~1 on the 1e6-epoch benchmark series.
    phi = [-0.5]
    y, _ = simulate_ari(np.random.default_rng(4), 20000, phi, 2, 0.02, 0.01)
    y = np.round(y * 2**20) / 2**20
    y[5000:5010] = np.nan  # a gap: the correction is taken to an interpolated baseline
    drift = 1e9 + 1e4 * np.arange(y.size)
    assert np.array_equal((y + drift) - drift, y, equal_nan=True)  # exact
    lls = [
        gauss_markov_filter(series, phi, 2, 0.02, 0.01, initial="stationary")[2]
        for series in (y, y + drift)
    ]
    assert lls[1] == pytest.approx(lls[0], abs=1e-9)
