"""Residual RAIM, protection levels, exclusion and solution separation: scipy and direct
least squares as oracles, injected faults on the bundled SEPT sample, bad input."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest

from navtrack.estimation.chi2 import ncx2_cdf, noncentrality_bias
from navtrack.gnss.spp import (
    SppConfig,
    SppStatus,
    code_pseudoranges,
    corrected_measurements,
    estimate_position,
    satellite_states,
    solve_spp,
)
from navtrack.integrity.raim import STATUS_NAMES, RaimConfig, RaimStatus, monitor, variance_factor
from navtrack.integrity.residuals import chi2_test, normalised_residuals, wraim_levels
from navtrack.integrity.separation import pair_hypotheses, solution_separation, subset_solutions
from navtrack.positioning import solution_frame, solve_positions


def _problem(seed: int, n_b: int = 3, n_s: int = 9, n_p: int = 4):  # type: ignore[no-untyped-def]
    """Random whitened least-squares problems at their solution (``g^T y = 0``)."""
    rng = np.random.default_rng(seed)
    los = rng.normal(size=(n_b, n_s, 3))
    los /= np.linalg.norm(los, axis=-1, keepdims=True)
    g = np.concatenate([-los, np.ones((n_b, n_s, n_p - 3))], axis=-1) * rng.uniform(
        0.5, 2.0, size=(n_b, n_s, 1)
    )
    e = rng.normal(size=(n_b, n_s))
    x = np.linalg.lstsq(g[0], e[0], rcond=None)[0]
    y = np.stack([e[b] - g[b] @ np.linalg.lstsq(g[b], e[b], rcond=None)[0] for b in range(n_b)])
    assert x.shape == (n_p,)
    used = np.ones((n_b, n_s), dtype=bool)
    return g, y, used


def test_chi2_thresholds_and_non_central_cdf_match_scipy() -> None:
    stats = pytest.importorskip("scipy.stats")
    _g, y, used = _problem(0)
    stat, thr, dof = chi2_test(y, used, np.full(3, 4), 1e-3)
    np.testing.assert_array_equal(dof, 5)
    np.testing.assert_allclose(thr, stats.chi2.ppf(1 - 1e-3, 5), rtol=1e-8)
    np.testing.assert_allclose(stat, np.sum(y**2, axis=1))
    for k, lam, x in [(1, 5.0, 3.0), (7, 40.0, 20.0), (20, 100.0, 60.0), (30, 80.0, 60.0)]:
        assert abs(ncx2_cdf(x, k, lam) - stats.ncx2.cdf(x, k, lam)) < 1e-12
    for k in (1, 4, 16):
        lam = noncentrality_bias(1e-3, 1e-4, k) ** 2
        assert abs(stats.ncx2.cdf(stats.chi2.ppf(1 - 1e-3, k), k, lam) - 1e-4) < 1e-9


@pytest.mark.parametrize("seed", range(3))
def test_subset_solutions_equal_direct_least_squares(seed: int) -> None:
    """Downdated normal equations = re-solving without the satellites (numpy lstsq)."""
    g, y, used = _problem(seed)
    members = pair_hypotheses(used, 2)
    sub = subset_solutions(g, y, used, members)
    assert members.shape == (3, 9 + 36, 2)
    x0 = np.zeros(4)  # y are the residuals at the solution
    for b in range(3):
        for h in (0, 5, 9, 20, 44):
            keep = np.ones(9, dtype=bool)
            keep[members[b, h][members[b, h] >= 0]] = False
            dx, *_ = np.linalg.lstsq(g[b, keep], y[b, keep], rcond=None)
            np.testing.assert_allclose(sub.dx[b, h], x0 + dx, atol=1e-10)
            np.testing.assert_allclose(
                sub.cov[b, h], np.linalg.inv(g[b, keep].T @ g[b, keep]), atol=1e-10
            )
            res = y[b, keep] - g[b, keep] @ dx
            assert abs(sub.chi2[b, h] - res @ res) < 1e-10
            assert sub.dof[b, h] == keep.sum() - 4


def test_normalised_residuals_are_baarda_w() -> None:
    g, y, used = _problem(1)
    w = normalised_residuals(g, y, used)
    h = g[0] @ np.linalg.solve(g[0].T @ g[0], g[0].T)
    np.testing.assert_allclose(w[0], y[0] / np.sqrt(1 - np.diag(h)), rtol=1e-10)


def test_wraim_protection_level_bounds_the_undetectable_bias() -> None:
    """A bias on the satellite of the largest slope that just reaches the non-centrality
    ``p_bias^2`` moves the position by exactly HPL (Walter & Enge 1995)."""
    g, _y, used = _problem(2, n_b=1, n_s=8)
    rot = np.eye(3)[None]
    hpl, vpl = wraim_levels(g, used, rot, 1e-3, 1e-3)
    q = np.linalg.inv(g[0].T @ g[0])
    a = q @ g[0].T
    r = 1 - np.einsum("sp,pq,sq->s", g[0], q, g[0])
    slope = np.hypot(a[0], a[1]) / np.sqrt(r)
    i = int(np.argmax(slope))
    # whitened bias giving lambda = p_bias^2
    bias = noncentrality_bias(1e-3, 1e-3, 4) / np.sqrt(r[i])
    fault = np.zeros(8)
    fault[i] = bias
    dx = a @ fault
    assert abs(np.hypot(dx[0], dx[1]) - hpl[0]) < 1e-9
    assert vpl[0] >= abs(dx[2]) - 1e-9


@lru_cache(maxsize=1)
def _sample_measurements():  # type: ignore[no-untyped-def]
    from navtrack.data import sample_path
    from navtrack.gnss.rinex.nav import read_nav
    from navtrack.gnss.rinex.obs import read_obs

    obs = read_obs(sample_path("SEPT078M_120.21O"))
    nav = read_nav(sample_path("SEPT078M.21P"))
    cfg = SppConfig(systems="GEJ")
    pr = code_pseudoranges(obs, cfg)
    meas = corrected_measurements(pr, satellite_states(pr, [nav], config=cfg), cfg)
    return meas, cfg, obs, nav


def _faulty(sats: list[str], bias_m: float, epochs: slice):  # type: ignore[no-untyped-def]
    meas, cfg, _, _ = _sample_measurements()
    fault = np.zeros(meas.y_m.shape, dtype=bool)
    for s in sats:
        fault[epochs, meas.sats.index(s)] = True
    return meas.replace(y_m=meas.y_m + bias_m * fault), fault, cfg


@pytest.mark.parametrize("method", ["loo", "fde", "ss", "fcm"])
def test_a_single_30m_fault_is_excluded(method: str) -> None:
    meas, fault, cfg = _faulty(["G03"], 30.0, slice(10, 30))
    clean, _, _, _ = _sample_measurements()
    s2 = variance_factor(estimate_position(clean, cfg))
    est, status, integ = monitor(
        meas, estimate_position(meas, cfg), cfg, RaimConfig(method=method, variance_factor=s2)
    )
    assert np.all(integ.status[10:30] == RaimStatus.EXCLUDED)
    np.testing.assert_array_equal(integ.excluded, fault)
    assert np.all(integ.status[:10] == RaimStatus.OK)
    assert np.all(status == SppStatus.OK)
    assert np.all(~est.used[10:30, meas.sats.index("G03")])
    assert np.all(np.isfinite(integ.hpl_m))
    assert np.all(np.isfinite(integ.vpl_m))


@pytest.mark.parametrize("method", ["fde", "ss"])
def test_two_simultaneous_faults_are_excluded(method: str) -> None:
    meas, fault, cfg = _faulty(["G03", "E13"], 25.0, slice(0, 20))
    clean, _, _, _ = _sample_measurements()
    s2 = variance_factor(estimate_position(clean, cfg))
    _, _, integ = monitor(
        meas, estimate_position(meas, cfg), cfg, RaimConfig(method=method, variance_factor=s2)
    )
    np.testing.assert_array_equal(integ.excluded[:20], fault[:20])
    assert np.all(integ.status[:20] == RaimStatus.EXCLUDED)


def test_chi2_method_alerts_without_excluding() -> None:
    meas, _, cfg = _faulty(["G03"], 60.0, slice(0, 5))
    _est, status, integ = monitor(meas, estimate_position(meas, cfg), cfg, RaimConfig("chi2"))
    assert np.all(integ.status[:5] == RaimStatus.ALERT)
    assert np.all(status[:5] == SppStatus.REJECTED_VALIDITY)
    assert not integ.excluded.any()


def test_too_few_satellites_is_unavailable_not_an_error() -> None:
    """5 satellites: detection only (a fault cannot be excluded); 4: nothing."""
    meas, _cfg, _, _ = _sample_measurements()
    keep = {"G03", "G04", "G06", "G09", "G17"}
    ex = np.array([[s not in keep for s in meas.sats]] * meas.y_m.shape[0])
    gps = SppConfig(systems="G")
    est5 = estimate_position(meas, gps, exclude=ex)
    for method in ("fde", "ss", "fcm", "loo"):
        _, _, integ = monitor(meas, est5, gps, RaimConfig(method, variance_factor=0.1))
        counts = integ.status_counts()
        assert sum(counts.values()) == meas.y_m.shape[0]
        if method == "ss":  # needs 6 for its single-fault subsets
            assert counts["unavailable"] == meas.y_m.shape[0]
    ex4 = ex.copy()
    ex4[:, meas.sats.index("G17")] = True
    _, _, integ = monitor(meas, estimate_position(meas, gps, exclude=ex4), gps, RaimConfig("fde"))
    assert np.all(integ.status == RaimStatus.UNAVAILABLE)
    assert np.all(np.isnan(integ.hpl_m))
    # a 5-satellite epoch with a fault: detected, cannot be excluded -> unavailable
    bad, _, _ = _faulty(["G03"], 200.0, slice(0, 3))
    _, _, integ = monitor(bad, estimate_position(bad, gps, exclude=ex), gps, RaimConfig("fde"))
    assert np.all(integ.detected[:3])
    assert np.all(integ.status[:3] == RaimStatus.UNAVAILABLE)


def test_solution_separation_detects_what_chi2_detects_on_a_large_fault() -> None:
    g, y, used = _problem(3, n_b=1, n_s=10)
    y = y.copy()
    g0 = g[0]
    h = g0 @ np.linalg.solve(g0.T @ g0, g0.T)
    y[0] += (np.eye(10) - h)[:, 2] * 30.0  # residuals of a 30-sigma fault on satellite 2
    sep = solution_separation(g, y, used, np.eye(3)[None], RaimConfig("ss"))
    assert sep.detected[0]
    assert np.isfinite(sep.hpl_m[0])
    assert sep.vpl_m[0] > 0


def test_solve_positions_with_raim_writes_integrity_columns() -> None:
    _, cfg, obs, nav = _sample_measurements()
    res = solve_positions(obs, [nav], config=cfg, raim=RaimConfig("fde"), chunk_epochs=50)
    assert res.integrity is not None
    assert res.integrity.status.shape == (120,)
    frame = solution_frame(res)
    for col in ("raim_status", "excluded", "hpl_m", "vpl_m", "test_stat", "threshold"):
        assert frame[col].shape == (120,)
    assert set(frame["raim_status"]) <= set(STATUS_NAMES)
    assert "raim_status" not in solution_frame(solve_spp(obs, [nav], config=cfg))


def test_bad_config() -> None:
    with pytest.raises(ValueError, match="method"):
        RaimConfig("xyz")
    with pytest.raises(ValueError, match="pfa"):
        RaimConfig(pfa=0.0)
    with pytest.raises(ValueError, match="fcm_m"):
        RaimConfig(fcm_m=1.0)
    with pytest.raises(ValueError, match="max_faults"):
        RaimConfig(max_faults=3)
    with pytest.raises(ValueError, match="variance_factor"):
        RaimConfig(variance_factor=float("nan"))
