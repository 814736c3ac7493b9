"""Batched Gauss–Newton and Marquardt kernels, with scipy.optimize.least_squares as the oracle."""

from __future__ import annotations

import numpy as np
import pytest

from navtrack.estimation.least_squares import LsqStatus, gauss_newton, marquardt


def _range_problem(rng: np.random.Generator, n_batch: int, n_meas: int, noise_m: float):
    """Pseudorange-like problems: unknowns (x, y, z, clock), measurements to random beacons."""
    truth = np.concatenate(
        [rng.normal(0.0, 1000.0, (n_batch, 3)), rng.normal(0.0, 100.0, (n_batch, 1))], axis=1
    )
    beacons = rng.normal(0.0, 2.0e7, (n_batch, n_meas, 3))
    rho = np.linalg.norm(beacons - truth[:, None, :3], axis=-1)
    y = rho + truth[:, 3:4] + rng.normal(0.0, noise_m, (n_batch, n_meas))
    sigma = rng.uniform(0.5, 3.0, (n_batch, n_meas))

    def fun(x, idx):  # type: ignore[no-untyped-def]
        d = beacons[idx] - x[:, None, :3]
        r = np.linalg.norm(d, axis=-1)
        v = y[idx] - (r + x[:, 3:4])
        J = np.concatenate([-d / r[..., None], np.ones((*r.shape, 1))], axis=-1)
        return v, J, 1.0 / sigma[idx] ** 2, np.ones(r.shape, dtype=bool)

    return fun, truth, beacons, y, sigma


def _scipy_solution(beacons, y, sigma, x0):  # type: ignore[no-untyped-def]
    from scipy.optimize import least_squares

    def res(x):  # type: ignore[no-untyped-def]
        return (np.linalg.norm(beacons - x[:3], axis=-1) + x[3] - y) / sigma

    def jac(x):  # type: ignore[no-untyped-def]
        d = x[:3] - beacons
        r = np.linalg.norm(d, axis=-1)
        return np.concatenate([d / r[:, None], np.ones((len(r), 1))], axis=1) / sigma[:, None]

    return least_squares(res, x0, jac=jac, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15).x


@pytest.mark.parametrize("solver", ["gauss_newton", "marquardt"])
def test_matches_scipy_least_squares(solver: str) -> None:
    pytest.importorskip("scipy.optimize")
    rng = np.random.default_rng(3)
    fun, truth, beacons, y, sigma = _range_problem(rng, 20, 8, 2.0)
    x0 = np.zeros((20, 4))
    if solver == "gauss_newton":
        res = gauss_newton(fun, x0, max_iter=20, xtol=1e-8)
    else:
        res = marquardt(fun, x0, eps=1e-6, max_iter=200)
    assert np.all(res.status == LsqStatus.CONVERGED)
    for b in range(20):
        # scipy starts at the truth (from the origin its xtol stops it early at this scale)
        ref = _scipy_solution(beacons[b], y[b], sigma[b], truth[b])
        # ours no worse in cost, and the same estimate to 1e-4 of the formal sigma
        cost_ref = np.sum(
            ((np.linalg.norm(beacons[b] - ref[:3], axis=-1) + ref[3] - y[b]) / sigma[b]) ** 2
        )
        assert res.cost[b] <= cost_ref * (1 + 1e-7)
        sd = np.sqrt(np.diag(res.cov[b]))
        assert np.all(np.abs(res.x[b] - ref) < 1e-4 * sd)
    # covariance: (J^T W J)^-1 at the solution, symmetric positive definite
    assert np.all(np.linalg.eigvalsh(res.cov) > 0)
    np.testing.assert_allclose(res.cov, np.swapaxes(res.cov, 1, 2), rtol=1e-12, atol=0)
    np.testing.assert_array_equal(res.dof, 4)


def test_gauss_newton_statuses() -> None:
    rng = np.random.default_rng(5)
    fun, _, _beacons, _y, _sigma = _range_problem(rng, 3, 6, 1.0)

    def few(x, idx):  # type: ignore[no-untyped-def]
        v, J, w, valid = fun(x, idx)
        valid = valid.copy()
        valid[idx == 1, 3:] = False  # 3 measurements for 4 unknowns
        return v, J, w, valid

    res = gauss_newton(few, np.zeros((3, 4)), max_iter=20)
    assert res.status.tolist() == [0, LsqStatus.TOO_FEW_MEASUREMENTS, 0]
    res1 = gauss_newton(fun, np.zeros((3, 4)), max_iter=1)
    assert np.all(res1.status == LsqStatus.NO_CONVERGENCE)
    assert np.all(res1.iterations == 1)


def test_singular_geometry() -> None:
    """All beacons on one line through the receiver: the normal matrix is singular."""
    d = np.array([1.0, 2.0, 3.0]) / np.sqrt(14.0)
    beacons = np.array([[k * 1e7 * d for k in (1.0, 1.5, 2.0, 2.5, 3.0)]])

    def fun(x, idx):  # type: ignore[no-untyped-def]
        diff = beacons[idx] - x[:, None, :3]
        r = np.linalg.norm(diff, axis=-1)
        J = np.concatenate([-diff / r[..., None], np.ones((*r.shape, 1))], axis=-1)
        return r * 0.0, J, np.ones(r.shape), np.ones(r.shape, dtype=bool)

    res = gauss_newton(fun, np.zeros((1, 4)))
    assert res.status[0] == LsqStatus.SINGULAR
    assert np.all(np.isnan(res.cov[0]))


def test_unobserved_parameter_is_held() -> None:
    """A parameter no valid measurement depends on keeps its start value and does not count in
    the redundancy (the ISB of an absent system)."""
    rng = np.random.default_rng(9)
    fun, truth, *_ = _range_problem(rng, 4, 7, 0.0)

    def fun5(x, idx):  # type: ignore[no-untyped-def]
        v, J, w, valid = fun(x[:, :4], idx)
        return v, np.concatenate([J, np.zeros((*J.shape[:2], 1))], axis=-1), w, valid

    x0 = np.zeros((4, 5))
    x0[:, 4] = 42.0
    res = gauss_newton(fun5, x0, max_iter=20, xtol=1e-6)
    assert np.all(res.status == LsqStatus.CONVERGED)
    np.testing.assert_allclose(res.x[:, :4], truth, atol=1e-5)
    np.testing.assert_array_equal(res.x[:, 4], 42.0)
    np.testing.assert_array_equal(res.dof, 3)
    np.testing.assert_array_equal(res.cov[:, 4, :], 0.0)


def _rosenbrock(x, idx):  # type: ignore[no-untyped-def]
    """Rosenbrock's function as least squares, f = (10 (x2 - x1^2), 1 - x1), minimum (1, 1)."""
    x1, x2 = x[:, 0], x[:, 1]
    h = np.stack([10.0 * (x2 - x1**2), 1.0 - x1], axis=1)
    J = np.zeros((len(x), 2, 2))
    J[:, 0, 0] = -20.0 * x1
    J[:, 0, 1] = 10.0
    J[:, 1, 0] = -1.0
    n = len(x)
    return -h, J, np.ones((n, 2)), np.ones((n, 2), dtype=bool)


def test_marquardt_on_rosenbrock_and_its_damping() -> None:
    """Rosenbrock's valley from the classic start (-1.2, 1): Marquardt with the paper's growth
    factor reaches the known minimum (1, 1), with at least as many (damped) steps as
    Gauss–Newton."""
    x0 = np.array([[-1.2, 1.0], [0.5, -0.5], [2.0, 2.0]])
    lm = marquardt(_rosenbrock, x0, eps=1e-10, max_iter=500)
    assert np.all(lm.status == LsqStatus.CONVERGED)
    np.testing.assert_allclose(lm.x, 1.0, atol=1e-8)
    gn = gauss_newton(_rosenbrock, x0, max_iter=50, xtol=1e-12)
    np.testing.assert_allclose(gn.x, 1.0, atol=1e-8)
    assert np.all(lm.iterations >= gn.iterations)

    np.testing.assert_allclose(lm.cost, 0.0, atol=1e-16)


def test_marquardt_parameter_validation() -> None:
    with pytest.raises(ValueError, match="beta"):
        marquardt(lambda x, i: (x, x, x, x), np.zeros((1, 2)), beta=1.0)  # type: ignore[arg-type,return-value]
    with pytest.raises(ValueError, match="x0"):
        gauss_newton(lambda x, i: (x, x, x, x), np.zeros(3))  # type: ignore[arg-type,return-value]
