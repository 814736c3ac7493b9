"""Two-satellite AGPS fixes (paper 1): constructed cases with known answers, the Marquardt steps
against a plain re-implementation of the paper's steps 1–6, MAP vs Gauss–Newton, bad input."""

from __future__ import annotations

import dataclasses
import math
from importlib import resources

import numpy as np
import pytest

from navtrack.geodesy import C_MPS, OMEGA_E_RAD_S, WGS84_A_M, enu_rotation, geodetic_to_ecef
from navtrack.gnss.agps import (
    WGS84_B_M,
    AgpsConfig,
    AgpsProblem,
    AgpsStatus,
    ellipsoid_residual,
    fix_dop,
    solve_agps,
)
from navtrack.positioning.agps import assisted_pseudoranges, problem_from_measurements

SITE = (math.radians(39.959103), math.radians(116.352853), 56.23)  # paper IV-B


def _on_height_surface(lat: float, lon: float, h: float) -> np.ndarray:
    """A point with f5 = 0 exactly: the geodetic point scaled radially onto the surface."""
    p = geodetic_to_ecef(np.array([lat, lon, h]))
    return p / math.sqrt(1.0 + float(ellipsoid_residual(p, h)))


@pytest.fixture(scope="module")
def gps_sats() -> tuple[np.ndarray, np.ndarray]:
    """Positions of two GPS satellites visible at the paper's site, at t, t + 2/4/6/8 min, from
    the bundled broadcast ephemerides (hour2350.16n)."""
    from navtrack.geodesy import azimuth_elevation
    from navtrack.gnss.ephemeris import broadcast_states, ephemeris_tables
    from navtrack.gnss.rinex.nav import read_nav

    tables = ephemeris_tables(read_nav(resources.files("navtrack.data") / "hour2350.16n"))
    sats = sorted(set(tables["G"].sat.tolist()))
    t = 1155859200.0 + 36000.0 + 60.0 * np.array([0.0, 2.0, 4.0, 6.0, 8.0])
    st = broadcast_states(tables, sats, t, np.repeat((t - 0.075)[:, None], len(sats), 1))
    truth = geodetic_to_ecef(np.array(SITE))
    el = azimuth_elevation(np.where(st.valid[..., None], st.pos_m, 0.0), truth)[..., 1]
    seen = np.flatnonzero((st.valid & (el > math.radians(20.0))).all(axis=0))
    assert seen.size >= 2
    return t, st.pos_m[:, seen[:2]]


def _problem(
    t: np.ndarray,
    sat: np.ndarray,
    truth: np.ndarray,
    k: int,
    h: float,
    start: np.ndarray,
    noise: np.ndarray | None = None,
    clocks: tuple[float, float] = (120.0, -250.0),
) -> AgpsProblem:
    """Fixes from epochs 0 and k with exact pseudoranges (plus ``noise`` (B, 4))."""
    pos = np.concatenate([sat[0], sat[k]])  # (4, 3)
    d = pos - truth
    sagnac = OMEGA_E_RAD_S * (pos[:, 0] * truth[1] - pos[:, 1] * truth[0]) / C_MPS
    y = np.linalg.norm(d, axis=1) + sagnac + np.repeat(np.array(clocks), 2)
    b = 1 if noise is None else noise.shape[0]
    return AgpsProblem(
        t_gps_s=np.tile([t[0], t[k]], (b, 1)),
        sat_pos_m=np.tile(pos, (b, 1, 1)),
        y_m=y[None, :] + (0.0 if noise is None else noise),
        height_m=np.full(b, h),
        start_xyz_m=np.tile(start, (b, 1)),
        usable=np.ones((b, 4), dtype=bool),
    )


def _cell(truth: np.ndarray, east_m: float, north_m: float) -> np.ndarray:
    return truth + enu_rotation(SITE[0], SITE[1]).T @ np.array([east_m, north_m, 0.0])


@pytest.mark.parametrize("k", [1, 4])
def test_noise_free_geometry_gives_the_exact_solution(gps_sats, k) -> None:
    t, sat = gps_sats
    truth = _on_height_surface(SITE[0], SITE[1], SITE[2])
    problem = _problem(t, sat, truth, k, SITE[2], _cell(truth, 2500.0, -1500.0))
    tight = AgpsConfig(eps=1e-9, f5_units="m", max_iter=200)
    huge_prior = AgpsConfig(eps=1e-9, prior_sigma_m=1e9)
    for solver, cfg in (("gn", tight), ("lm", tight), ("map", huge_prior)):
        res = solve_agps(problem, solver, cfg)
        assert res.status[0] == AgpsStatus.OK, solver
        assert np.linalg.norm(res.pos_m[0] - truth) < 1e-3, solver
        np.testing.assert_allclose(res.clock_m[0], [120.0, -250.0], atol=1e-3)
        assert abs(res.height_residual_m[0]) < 0.5  # f5 = 0 is within h e^2 of height h


def _paper_marquardt(
    prob: AgpsProblem, i: int, scale: float, mu1: float = 0.1, beta: float = 10.0, eps: float = 0.1
) -> tuple[np.ndarray, int, int]:
    """The paper's steps 1–6 written out for one fix (the oracle): returns the solution, the
    linear solves and the rejected trials."""
    sat, y, h = prob.sat_pos_m[i], prob.y_m[i], prob.height_m[i]
    ah2, bh2 = (WGS84_A_M + h) ** 2, (WGS84_B_M + h) ** 2

    def f_and_a(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        r = x[:3]
        f = np.empty(5)
        a = np.zeros((5, 5))
        for m in range(4):
            d = sat[m] - r
            rho = math.sqrt(d @ d) + OMEGA_E_RAD_S * (sat[m, 0] * r[1] - sat[m, 1] * r[0]) / C_MPS
            f[m] = rho + x[3 + m // 2] - y[m]
            a[m, :3] = -d / math.sqrt(d @ d)
            a[m, 3 + m // 2] = 1.0
        f[4] = scale * ((r[0] ** 2 + r[1] ** 2) / ah2 + r[2] ** 2 / bh2 - 1.0)
        a[4, :3] = scale * 2.0 * np.array([r[0] / ah2, r[1] / ah2, r[2] / bh2])
        return f, a

    x = np.concatenate([prob.start_xyz_m[i], [0.0, 0.0]])  # step 1
    mu = mu1
    f, _ = f_and_a(x)
    big_f = f @ f
    solves = rejected = 0
    while True:
        mu /= beta  # step 2
        f, a = f_and_a(x)
        grad = a.T @ f
        while True:
            d = np.linalg.solve(a.T @ a + mu * np.eye(5), -grad)  # step 3
            solves += 1
            ft, _ = f_and_a(x + d)
            if ft @ ft < big_f:  # step 4 -> 6
                x = x + d
                big_f = ft @ ft
                if np.linalg.norm(grad) <= eps:
                    return x, solves, rejected
                break
            rejected += 1  # step 5
            if np.linalg.norm(grad) <= eps:
                return x, solves, rejected
            mu *= beta


@pytest.mark.parametrize(
    ("f5_units", "scale"), [("dimensionless", 1.0), ("m", (WGS84_A_M + 46.0) / 2.0)]
)
@pytest.mark.parametrize("cell_m", [4000.0, 1.0e6])
def test_marquardt_follows_the_papers_steps(gps_sats, f5_units, scale, cell_m) -> None:
    t, sat = gps_sats
    truth = _on_height_surface(SITE[0], SITE[1], SITE[2])
    rng = np.random.default_rng(12)
    noise = rng.normal(0.0, 5.0, (12, 4))
    cell = _cell(truth, cell_m, 0.75 * cell_m)
    prob = _problem(t, sat, truth, 1, 46.0, cell, noise, (2e4, -3e4))
    # the paper's steps alone: no plausibility checks
    res = solve_agps(prob, "lm", AgpsConfig(f5_units=f5_units, max_height_residual_m=np.inf,
                                            max_residual_m=np.inf))  # fmt: skip
    total_rejected = 0
    for i in range(prob.size):
        x, solves, rejected = _paper_marquardt(prob, i, scale)
        total_rejected += rejected
        assert res.status[i] == AgpsStatus.OK
        assert res.iterations[i] == solves
        np.testing.assert_allclose(res.pos_m[i], x[:3], atol=1e-4)
        np.testing.assert_allclose(res.clock_m[i], x[3:], atol=1e-4)
    # the far cell (1250 km) exercises step 5 (rejected trials, mu grown) as well as step 6
    assert (total_rejected > 0) == (cell_m > 1e5)


def test_map_with_huge_prior_variance_equals_gauss_newton(gps_sats) -> None:
    t, sat = gps_sats
    truth = _on_height_surface(SITE[0], SITE[1], SITE[2])
    noise = np.random.default_rng(3).normal(0.0, 5.0, (20, 4))
    prob = _problem(t, sat, truth, 2, 56.0, _cell(truth, -3000.0, 1000.0), noise)
    gn = solve_agps(prob, "gn", AgpsConfig(eps=1e-9))
    mp = solve_agps(prob, "map", AgpsConfig(eps=1e-9, prior_sigma_m=1e8))
    assert (gn.status == AgpsStatus.OK).all()
    assert (mp.status == AgpsStatus.OK).all()
    np.testing.assert_allclose(mp.pos_m, gn.pos_m, atol=1e-3)
    # a tight prior pulls the fix to the cell: the prior is honoured
    tight = solve_agps(prob, "map", AgpsConfig(eps=1e-9, prior_sigma_m=0.01))
    assert np.linalg.norm(tight.pos_m - prob.start_xyz_m, axis=1).max() < 1.0
    assert np.linalg.norm(gn.pos_m - prob.start_xyz_m, axis=1).min() > 100.0


def test_gauss_newton_is_newton_on_the_square_system(gps_sats) -> None:
    """Noisy fix: Gauss–Newton solves the five equations exactly (zero residuals)."""
    t, sat = gps_sats
    truth = _on_height_surface(SITE[0], SITE[1], SITE[2])
    noise = np.random.default_rng(5).normal(0.0, 5.0, (8, 4))
    prob = _problem(t, sat, truth, 1, 56.0, _cell(truth, 1000.0, 1000.0), noise)
    res = solve_agps(prob, "gn", AgpsConfig(eps=1e-9))
    assert (res.status == AgpsStatus.OK).all()
    assert np.all(res.cost < 1e-12)
    # the paper's point: 5 m noise is amplified to hundreds of metres at 2 min
    assert np.linalg.norm(res.pos_m - truth, axis=1).max() > 50.0


def test_bad_input_raises_naming_the_parameter(gps_sats) -> None:
    t, sat = gps_sats
    truth = _on_height_surface(SITE[0], SITE[1], SITE[2])
    good = _problem(t, sat, truth, 1, 56.0, _cell(truth, 0.0, 2000.0))
    fields = {name: getattr(good, name) for name in AgpsProblem.__slots__}
    with pytest.raises(ValueError, match="same epoch twice"):
        AgpsProblem(**(fields | {"t_gps_s": np.array([[t[0], t[0]]])}))
    with pytest.raises(ValueError, match=r"height_m.*outside the earth's range"):
        AgpsProblem(**(fields | {"height_m": np.array([56230.0])}))
    with pytest.raises(ValueError, match=r"height_m.*outside"):
        AgpsProblem(**(fields | {"height_m": np.array([np.nan])}))
    with pytest.raises(ValueError, match="start_xyz_m"):
        AgpsProblem(**(fields | {"start_xyz_m": np.full((1, 3), np.nan)}))
    with pytest.raises(ValueError, match="sat_pos_m: expected shape"):
        AgpsProblem(**(fields | {"sat_pos_m": np.zeros((1, 3, 3))}))
    with pytest.raises(ValueError, match="solver"):
        solve_agps(good, "newton")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="beta"):
        AgpsConfig(beta=1.0)
    with pytest.raises(ValueError, match="prior_sigma_m"):
        AgpsConfig(prior_sigma_m=0.0)


@pytest.mark.parametrize("solver", ["gn", "lm", "map"])
def test_singular_and_missing_fixes_are_statuses_never_nan_fixes(gps_sats, solver) -> None:
    t, sat = gps_sats
    truth = _on_height_surface(SITE[0], SITE[1], SITE[2])
    noise = np.random.default_rng(8).normal(0.0, 5.0, (5, 4))
    prob = _problem(t, sat, truth, 1, 56.0, _cell(truth, 1000.0, 2000.0), noise)
    start = prob.start_xyz_m.copy()
    start[1] = 0.0  # singular start: the earth's centre (height equation without gradient)
    sat_pos = prob.sat_pos_m.copy()
    sat_pos[2, 1] = sat_pos[2, 0]  # the same satellite twice
    sat_pos[2, 3] = sat_pos[2, 2]
    usable = prob.usable.copy()
    usable[3, 2] = False  # satellite 1 not observed at epoch 2
    y = prob.y_m.copy()
    y[4, 0] = np.nan  # no pseudorange
    bad = AgpsProblem(prob.t_gps_s, sat_pos, y, prob.height_m, start, usable)
    res = solve_agps(bad, solver)
    assert res.status[0] == AgpsStatus.OK
    assert res.status[1] == AgpsStatus.SINGULAR
    assert res.status[2] == AgpsStatus.SINGULAR
    assert res.status[3] == AgpsStatus.MISSING_MEASUREMENT
    assert res.status[4] == AgpsStatus.MISSING_MEASUREMENT
    assert np.isnan(res.pos_m[1:]).all()
    assert np.isfinite(res.pos_m[res.ok]).all()
    assert res.status_counts() == {
        "ok": 1,
        "missing_measurement": 2,
        "singular": 2,
        "no_convergence": 0,
        "diverged": 0,
        "weak_geometry": 0,
        "implausible": 0,
    }


def test_diverged_fix_is_not_reported(gps_sats) -> None:
    """A start 3000 km away (a wrong cell): whatever the solvers reach off the earth's surface
    is ``diverged`` with a NaN position, never an ``ok`` fix."""
    t, sat = gps_sats
    truth = _on_height_surface(SITE[0], SITE[1], SITE[2])
    far = _on_height_surface(SITE[0] + 0.5, SITE[1], 0.0) * 1.5
    prob = _problem(t, sat, truth, 1, 56.0, far)
    for solver in ("gn", "lm", "map"):
        res = solve_agps(prob, solver, AgpsConfig(max_iter=3))
        if res.status[0] == AgpsStatus.OK:
            assert 6.2e6 <= np.linalg.norm(res.pos_m[0]) <= 6.6e6
        else:
            assert res.status[0] in (AgpsStatus.DIVERGED, AgpsStatus.NO_CONVERGENCE)


def _bundled_0759():
    from navtrack.gnss.rinex.nav import read_nav
    from navtrack.gnss.rinex.obs import read_obs
    from navtrack.gnss.spp import SppConfig
    from navtrack.positioning.agps import gps_measurements

    data = resources.files("navtrack.data")
    cfg = SppConfig(systems="G")
    meas = gps_measurements(read_obs(data / "07590920.05o"), read_nav(data / "07590920.05n"), cfg)
    return meas, cfg


# RTKLIB static relative solution of 0759 (src/navtrack/data/README.md)
REF_0759 = np.array([-3976219.188, 3382371.606, 3652511.143])


def test_assisted_pseudoranges_leave_one_clock_per_epoch() -> None:
    """Corrected pseudoranges minus the geometric range at the reference: one receiver clock per
    epoch plus metre-level errors (the SPP corrections are applied)."""
    from navtrack.gnss.corrections import geometric_range

    meas, cfg = _bundled_0759()
    y = assisted_pseudoranges(meas, REF_0759 + np.array([2000.0, 0.0, 0.0]), cfg)
    rho, _ = geometric_range(np.where(np.isfinite(meas.sat_pos_m), meas.sat_pos_m, 0.0), REF_0759)
    r = y - rho
    spread = np.nanmax(r, axis=1) - np.nanmin(r, axis=1)
    assert np.isfinite(y).sum(axis=1).min() >= 4
    assert np.nanmedian(spread) < 15.0
    # without ionosphere and troposphere the spread grows (they are applied)
    raw = np.where(np.isfinite(y), meas.y_m, np.nan) - rho
    raw_spread = np.nanmax(raw, axis=1) - np.nanmin(raw, axis=1)
    assert np.nanmedian(raw_spread) > np.nanmedian(spread)


def test_problem_from_measurements_real_fixes_and_bad_indices() -> None:
    meas, cfg = _bundled_0759()
    cell = REF_0759 + enu_rotation(0.6137, 2.4367).T @ np.array([1500.0, 1500.0, 0.0])
    y = assisted_pseudoranges(meas, cell, cfg)
    both = np.flatnonzero(np.isfinite(y[0]) & np.isfinite(y[16]))
    eps = np.array([[0, 16]] * 3)
    sats = np.array([[both[0], both[1]], [both[1], both[2]], [both[0], both[2]]])
    prob = problem_from_measurements(meas, y, eps, sats, 68.4, cell)
    res = solve_agps(prob, "gn")
    assert (res.status == AgpsStatus.OK).all()
    assert np.linalg.norm(res.pos_m - REF_0759, axis=1).max() < 2000.0
    with pytest.raises(ValueError, match="sats: fix 0 uses satellite"):
        problem_from_measurements(meas, y, eps[:1], np.array([[both[0], both[0]]]), 68.4, cell)
    with pytest.raises(ValueError, match="same epoch twice"):
        problem_from_measurements(meas, y, np.array([[3, 3]]), sats[:1], 68.4, cell)
    with pytest.raises(ValueError, match="epochs: indices outside"):
        problem_from_measurements(meas, y, np.array([[0, 999]]), sats[:1], 68.4, cell)
    missing = np.flatnonzero(~np.isfinite(y[0]))
    if missing.size:
        p2 = problem_from_measurements(
            meas, y, eps[:1], np.array([[both[0], missing[0]]]), 68.4, cell
        )
        assert solve_agps(p2, "lm").status[0] == AgpsStatus.MISSING_MEASUREMENT


def test_marquardt_needs_the_clocks_the_cell_start_gives(gps_sats) -> None:
    """Receiver clocks of hundreds of km (real receivers: 0759, SEPT): with the dimensionless
    height equation the paper's zero start leaves Marquardt tens of km off — damping slows the
    clock steps and nothing holds the position — while clocks started from the cell, or the
    height equation in metres, bring it back to the cell's neighbourhood. The plausibility
    checks never report the lost fixes ``ok``."""
    t, sat = gps_sats
    truth = _on_height_surface(SITE[0], SITE[1], SITE[2])
    noise = np.random.default_rng(2).normal(0.0, 5.0, (10, 4))
    cell = _cell(truth, 1500.0, 1500.0)
    prob = _problem(t, sat, truth, 1, 56.0, cell, noise, (4.0e5, -1.3e5))
    printed = AgpsConfig(f5_units="dimensionless", max_height_residual_m=np.inf,
                         max_residual_m=np.inf)  # fmt: skip
    zero = solve_agps(prob, "lm", printed)
    from_cell = solve_agps(prob, "lm", dataclasses.replace(printed, clock_start="cell"))
    err_zero = np.linalg.norm(zero.pos_m - truth, axis=1)
    err_cell = np.linalg.norm(from_cell.pos_m - truth, axis=1)
    assert np.nanmedian(err_zero) > 10_000.0
    assert np.nanmedian(err_cell) < 3_000.0
    checked = solve_agps(prob, "lm", AgpsConfig(f5_units="dimensionless"))
    err_checked = np.linalg.norm(checked.pos_m - truth, axis=1)
    assert not (checked.ok & (err_checked > 3_000.0)).any()
    assert (checked.status == AgpsStatus.IMPLAUSIBLE).sum() >= 5
    assert all("from the assumed height" in r for r in checked.reason[checked.status == 6])
    metres = solve_agps(prob, "lm")
    assert np.nanmedian(np.linalg.norm(metres.pos_m - truth, axis=1)) < 3_000.0
    # Gauss–Newton's clock steps are exact (the clocks enter linearly): the start does not matter
    gn_zero = solve_agps(prob, "gn")
    gn_cell = solve_agps(prob, "gn", AgpsConfig(clock_start="cell"))
    np.testing.assert_allclose(gn_zero.pos_m, gn_cell.pos_m, atol=1e-2)
    with pytest.raises(ValueError, match="clock_start"):
        AgpsConfig(clock_start="mean")  # type: ignore[arg-type]


@pytest.mark.parametrize("k", [1, 4])
def test_dop_predicts_the_scatter_of_gauss_newton_fixes(gps_sats, k) -> None:
    """``fix_dop`` times the pseudorange noise is the rms 3-D error of Gauss–Newton fixes of
    that noise (2,000 noisy copies of one geometry), and the predicted-error screen turns a
    fix ``weak_geometry`` with its reason."""
    t, sat = gps_sats
    truth = _on_height_surface(SITE[0], SITE[1], SITE[2])
    sigma = 2.0
    noise = np.random.default_rng(21).normal(0.0, sigma, (2000, 4))
    prob = _problem(t, sat, truth, k, SITE[2], _cell(truth, 300.0, -200.0), noise)
    dop = fix_dop(prob)
    np.testing.assert_allclose(dop, dop[0], rtol=1e-9)  # one geometry, one start
    res = solve_agps(prob, "gn", AgpsConfig(max_height_residual_m=np.inf, max_residual_m=np.inf))
    rms = np.sqrt(np.mean(np.sum((res.pos_m - truth) ** 2, axis=1)))
    assert rms == pytest.approx(dop[0] * sigma, rel=0.05)  # 2,000 samples: ~2 % standard error
    screen = AgpsConfig.for_receiver(sigma, max_sigma_m=0.5 * dop[0] * sigma)
    screened = solve_agps(prob, "gn", screen)
    assert (screened.status == AgpsStatus.WEAK_GEOMETRY).all()
    assert screened.reason[0].startswith("predicted error")
    np.testing.assert_allclose(screened.sigma_m, dop * sigma)
