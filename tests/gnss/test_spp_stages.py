"""The SPP stages one by one: signal selection, satellite states, corrected measurements,
estimation with exclusion masks and epoch subsets, validation, result assembly, epoch blocks,
and the solution frame's time column.

The bundled sample is SEPT078M_120.21O + SEPT078M.21P (120 epochs, GPS + Galileo + QZSS).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest

from navtrack.geodesy import C_MPS
from navtrack.gnss import ephemeris as eph
from navtrack.gnss.observations import Observations
from navtrack.gnss.rinex.nav import NavData
from navtrack.gnss.spp import (
    SppConfig,
    SppStatus,
    code_pseudoranges,
    corrected_measurements,
    estimate_position,
    merge_estimates,
    satellite_states,
    solution_frame,
    solve_spp,
    spp_result,
    validate,
)
from navtrack.io.solution import solution_columns, write_solution

GEJ = SppConfig(systems="GEJ")
SEPT_REF = np.array([-3962108.673, 3381309.574, 3668678.638])


@lru_cache(maxsize=1)
def _sample() -> tuple[Observations, NavData]:
    from navtrack.data import sample_path
    from navtrack.gnss.rinex.nav import read_nav
    from navtrack.gnss.rinex.obs import read_obs

    return read_obs(sample_path("SEPT078M_120.21O")), read_nav(sample_path("SEPT078M.21P"))


def _measurements(obs: Observations, nav: NavData, cfg: SppConfig = GEJ):  # type: ignore[no-untyped-def]
    pr = code_pseudoranges(obs, cfg)
    sv = satellite_states(pr, [nav], config=cfg)
    return pr, sv, corrected_measurements(pr, sv, cfg)


def _with_fault(obs: Observations, sat: str, epochs: slice, bias_m: float) -> Observations:
    values = np.array(obs.values)
    values[epochs, obs.sats.index(sat), obs.codes.index("C1C")] += bias_m
    return obs.replace(values=values)


# --------------------------------------------------------------------------- the chain
def test_chain_reproduces_the_single_function_solver() -> None:
    """Positions, clocks, satellites used, iterations and chi-square of the bundled sample as
    the single-function ``solve_spp`` of commit 8d888b4 gave them (printed to 0.1 mm), with
    that commit's default of no QZSS group delay."""
    obs, nav = _sample()
    res = solve_spp(obs, [nav], config=GEJ.replace(tgd_systems="GECIR"))
    expected = {
        0: ([-3962108.1457, 3381308.8644, 3668678.0399], -138137.4401, -0.1605, 1.894),
        60: ([-3962108.1224, 3381308.7226, 3668677.7205], -136559.2812, -0.1285, 1.3727),
        119: ([-3962108.1292, 3381308.6725, 3668677.8408], -135002.1137, -0.0585, 1.9924),
    }
    assert res.clock_groups == ("G", "E")
    for e, (xyz, clock, isb, chi2) in expected.items():
        np.testing.assert_allclose(res.pos_m[e], xyz, atol=6e-5)
        assert res.clock_m[e] == pytest.approx(clock, abs=6e-5)
        assert res.isb_m[e, 0] == pytest.approx(isb, abs=6e-5)
        assert res.chi2[e] == pytest.approx(chi2, abs=6e-5)
        assert res.n_sats[e] == 21
        assert res.iterations[e] == 3
        assert res.dof[e] == 16


def test_stages_by_hand_equal_solve_spp() -> None:
    obs, nav = _sample()
    _, _, meas = _measurements(obs, nav)
    est = estimate_position(meas, GEJ)
    by_hand = spp_result(meas, est, validate(est, GEJ))
    res = solve_spp(obs, [nav], config=GEJ)
    for name in ("pos_m", "cov", "residuals_m", "sigma_m", "dop", "chi2", "status", "used"):
        np.testing.assert_array_equal(getattr(by_hand, name), getattr(res, name), err_msg=name)


# --------------------------------------------------------------------------- stages 1-3
def test_code_pseudoranges_select_the_configured_signals() -> None:
    obs, _ = _sample()
    pr = code_pseudoranges(obs, SppConfig(systems="GE"))
    assert pr.systems == ("G", "E")
    assert all(s[0] in "GE" for s in pr.sats)
    k = obs.sats.index("G03")
    np.testing.assert_array_equal(
        pr.pr_m[:, pr.sats.index("G03")], obs.values[:, k, obs.codes.index("C1C")]
    )
    assert pr.pr2_m is None
    np.testing.assert_array_equal(pr.observed, np.isfinite(pr.pr_m))
    dual = code_pseudoranges(obs, SppConfig(systems="G", iono="ionofree"))
    assert dual.pr2_m is not None
    np.testing.assert_array_equal(
        dual.pr2_m[:, dual.sats.index("G03")], obs.values[:, k, obs.codes.index("C2W")]
    )
    np.testing.assert_array_equal(dual.observed, np.isfinite(dual.pr_m) & np.isfinite(dual.pr2_m))
    np.testing.assert_allclose(pr.approx_xyz_m, obs.header.approx_xyz_m)


def test_satellite_states_group_delays_follow_the_config() -> None:
    obs, nav = _sample()
    pr = code_pseudoranges(obs, GEJ)
    sv = satellite_states(pr, [nav], config=GEJ)
    tables = eph.ephemeris_tables(nav)
    j = pr.sats.index("G03")
    t_tx = pr.t_gps_s - pr.pr_m[:, j] / C_MPS
    ref = eph.broadcast_states(tables, ["G03"], pr.t_gps_s, t_tx[:, None])
    np.testing.assert_array_equal(sv.pos_m[:, j], ref.pos_m[:, 0])
    np.testing.assert_array_equal(
        sv.group_delay_s[:, j], eph.group_delay_s(tables["G"], ref.eph_index)[:, 0]
    )
    assert np.all(sv.group_delay_s[:, j] != 0.0)
    qzss = [k for k, s in enumerate(pr.sats) if s[0] == "J"]
    assert qzss
    ref_j = eph.broadcast_states(
        tables, [pr.sats[k] for k in qzss], pr.t_gps_s, t_tx[:, None].repeat(len(qzss), 1)
    )
    np.testing.assert_array_equal(  # QZSS TGD applied (IS-QZSS-PNT), from the record in use
        sv.group_delay_s[:, qzss], eph.group_delay_s(tables["J"], ref_j.eph_index)
    )
    assert np.any(sv.group_delay_s[:, qzss] != 0.0)
    no_j = satellite_states(pr, [nav], config=GEJ.replace(tgd_systems="GECIR"))
    assert np.all(no_j.group_delay_s[:, qzss] == 0.0)
    np.testing.assert_allclose(sv.iono_scale[sv.valid], 1.0)  # L1 / E1 only
    no_tgd = satellite_states(pr, [nav], config=GEJ.replace(tgd_systems=""))
    assert np.all(no_tgd.group_delay_s == 0.0)
    with pytest.raises(ValueError, match="no broadcast ephemerides"):
        satellite_states(pr, None, config=GEJ)


def test_corrected_measurements_apply_clock_and_group_delay() -> None:
    obs, nav = _sample()
    pr, sv, meas = _measurements(obs, nav)
    np.testing.assert_array_equal(meas.y_m, pr.pr_m + C_MPS * (sv.clock_s - sv.group_delay_s))
    np.testing.assert_array_equal(meas.var_sat_m2, sv.var_m2 + 0.3**2)
    assert meas.clock_groups == ("G", "E")
    assert meas.n_params == 5
    assert {meas.group[k] for k, s in enumerate(meas.sats) if s[0] in "GJ"} == {0}
    assert {meas.group[k] for k, s in enumerate(meas.sats) if s[0] == "E"} == {1}
    assert not np.any(meas.usable & ~meas.observed)
    with pytest.raises(ValueError, match="satellite states"):
        corrected_measurements(code_pseudoranges(obs, SppConfig(systems="G")), sv, GEJ)


# --------------------------------------------------------------------------- stage 4
def test_exclusion_equals_deleting_the_observations() -> None:
    """Excluding G03 at every epoch gives the estimate of the data without G03."""
    obs, nav = _sample()
    _, _, meas = _measurements(obs, nav)
    j = meas.sats.index("G03")
    exclude = np.zeros(meas.usable.shape, dtype=bool)
    exclude[:, j] = True
    excluded = estimate_position(meas, GEJ, exclude=exclude)
    values = np.array(obs.values)
    values[:, obs.sats.index("G03"), :] = np.nan
    _, _, meas_del = _measurements(obs.replace(values=values), nav)
    deleted = estimate_position(meas_del, GEJ)
    assert not excluded.used[:, j].any()
    np.testing.assert_array_equal(excluded.used, deleted.used)
    np.testing.assert_allclose(excluded.x, deleted.x, rtol=0, atol=1e-9)
    np.testing.assert_allclose(excluded.cov, deleted.cov, rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(excluded.dof, deleted.dof)
    full = estimate_position(meas, GEJ)
    assert np.all(excluded.dof == full.dof - 1)
    assert np.max(np.linalg.norm(excluded.x[:, :3] - full.x[:, :3], axis=1)) > 1e-3


def test_epoch_subset_equals_the_rows_of_the_full_estimate() -> None:
    obs, nav = _sample()
    _, _, meas = _measurements(obs, nav)
    full = estimate_position(meas, GEJ)
    idx = np.array([3, 50, 119])
    part = estimate_position(meas, GEJ, epochs=idx)
    np.testing.assert_array_equal(part.epochs, idx)
    np.testing.assert_allclose(part.x, full.x[idx], rtol=0, atol=1e-9)
    np.testing.assert_allclose(part.residuals_m, full.residuals_m[idx], rtol=0, atol=1e-9)
    np.testing.assert_array_equal(part.used, full.used[idx])


def test_residuals_change_by_minus_design_times_step() -> None:
    """v(x + dx) - v(x) = -B dx to first order (a 2 m step: curvature ~ 2^2 / 2e7 m)."""
    obs, nav = _sample()
    _, _, meas = _measurements(obs, nav)
    est = estimate_position(meas, GEJ)
    dx = np.array([1.5, -2.0, 0.7, 3.0, -1.0])
    moved = estimate_position(meas, GEJ.replace(max_iter=0), x0_m=est.x + dx)
    np.testing.assert_array_equal(moved.x, est.x + dx)  # evaluated, not iterated
    assert np.all(moved.status == SppStatus.NO_CONVERGENCE)
    both = est.used & moved.used
    change = (moved.residuals_m - est.residuals_m)[both]
    predicted = -np.einsum("esp,p->es", est.design, dx)[both]
    np.testing.assert_allclose(change, predicted, atol=2e-3)
    # design rows: unit line of sight, receiver clock 1, ISB indicator of Galileo
    used = est.used
    np.testing.assert_allclose(np.linalg.norm(est.design[..., :3], axis=-1)[used], 1.0)
    assert np.all(est.design[..., 3][used] == 1.0)
    is_gal = np.array([s[0] == "E" for s in meas.sats])
    np.testing.assert_array_equal(
        est.design[..., 4][used], np.broadcast_to(is_gal, used.shape)[used]
    )
    assert np.all(est.design[~used] == 0.0)
    # chi-square is v^T W v
    v = np.where(used, est.residuals_m, 0.0)
    np.testing.assert_allclose(est.chi2, np.sum(est.weights * v**2, axis=1), rtol=1e-12)


@pytest.mark.parametrize("weighting", ["equal", "elevation", "cn0"])
def test_weights_are_the_configured_model(weighting: str) -> None:
    obs, nav = _sample()
    cfg = GEJ.replace(weighting=weighting)
    _, _, meas = _measurements(obs, nav, cfg)
    est = estimate_position(meas, cfg)
    s0 = cfg.sigma0_m**2
    el = est.azel_rad[..., 1]
    if weighting == "equal":
        var = np.full(el.shape, s0)
    elif weighting == "elevation":
        var = s0 * (1.0 + 1.0 / np.sin(el) ** 2)
    else:
        var = s0 + 1.61e4 * 10.0 ** (-meas.cn0_dbhz / 10.0)
        assert np.isfinite(meas.cn0_dbhz[est.used]).all()
    np.testing.assert_allclose(est.weights[est.used], 1.0 / var[est.used], rtol=1e-12)
    assert np.all(est.weights[~est.used] == 0.0)
    assert np.all(el[est.used] >= np.radians(cfg.elmask_deg))


def test_estimation_input_checks() -> None:
    obs, nav = _sample()
    _, _, meas = _measurements(obs, nav)
    with pytest.raises(ValueError, match="exclude"):
        estimate_position(meas, GEJ, exclude=np.zeros((3, 3), dtype=bool))
    with pytest.raises(ValueError, match="epochs"):
        estimate_position(meas, GEJ, epochs=np.array([0, 500]))
    with pytest.raises(ValueError, match="epochs"):
        estimate_position(meas, GEJ, epochs=np.array([0.5]))
    with pytest.raises(ValueError, match="x0_m"):
        estimate_position(meas, GEJ, x0_m=np.zeros(4))


# --------------------------------------------------------------------------- stage 5
def test_validation_then_exclusion_on_the_failed_epochs() -> None:
    """The seam integrity monitoring uses: a 100 m fault on G03 fails the chi-square test;
    re-estimating only the failed epochs without G03 passes it and lands on the clean
    solution."""
    obs, nav = _sample()
    _, _, meas = _measurements(_with_fault(obs, "G03", slice(0, 5), 100.0), nav)
    est = estimate_position(meas, GEJ)
    status = validate(est, GEJ)
    failed = np.flatnonzero(status == SppStatus.REJECTED_VALIDITY)
    np.testing.assert_array_equal(failed, np.arange(5))
    assert np.all(status[5:] == SppStatus.OK)
    exclude = np.zeros((failed.size, len(meas.sats)), dtype=bool)
    exclude[:, meas.sats.index("G03")] = True
    again = estimate_position(meas, GEJ, epochs=failed, exclude=exclude, x0_m=est.x[failed])
    assert np.all(validate(again, GEJ) == SppStatus.OK)
    clean = solve_spp(obs, [nav], config=GEJ)
    assert np.max(np.linalg.norm(again.x[:, :3] - clean.pos_m[:5], axis=1)) < 1.0
    assert np.max(np.linalg.norm(est.x[failed, :3] - clean.pos_m[:5], axis=1)) > 5.0
    # the re-estimates replace the failed rows; the assembled result is all ok
    merged = merge_estimates(est, again)
    res = spp_result(meas, merged, validate(merged, GEJ))
    assert np.all(res.status == SppStatus.OK)
    np.testing.assert_array_equal(res.pos_m[:5], again.x[:, :3])
    np.testing.assert_array_equal(res.pos_m[5:], est.x[5:, :3])
    assert not res.used[:5, meas.sats.index("G03")].any()
    assert res.used[5:, meas.sats.index("G03")].all()
    with pytest.raises(ValueError, match="epochs"):
        merge_estimates(again, est)
    # the test can be switched off, and the GDOP limit is the other rule
    assert np.all(validate(est, GEJ.replace(chi2_alpha=0.0)) == SppStatus.OK)
    assert np.all(validate(est, GEJ.replace(chi2_alpha=0.0, max_gdop=1.0)) == SppStatus.HIGH_DOP)


def test_result_refuses_a_partial_estimate() -> None:
    obs, nav = _sample()
    _, _, meas = _measurements(obs, nav)
    part = estimate_position(meas, GEJ, epochs=np.arange(10))
    with pytest.raises(ValueError, match="all measurement epochs"):
        spp_result(meas, part, validate(part, GEJ))


# --------------------------------------------------------------------------- driver, frame
def test_blocks_of_epochs_equal_one_block_and_report_progress(tmp_path) -> None:  # type: ignore[no-untyped-def]
    obs, nav = _sample()
    whole = solve_spp(obs, [nav], config=GEJ)
    calls: list[tuple[int, int]] = []
    blocks = solve_spp(
        obs, [nav], config=GEJ, chunk_epochs=25, progress=lambda d, n: calls.append((d, n))
    )
    assert calls == [(25, 120), (50, 120), (75, 120), (100, 120), (120, 120)]
    np.testing.assert_allclose(blocks.pos_m, whole.pos_m, rtol=0, atol=1e-6)
    np.testing.assert_allclose(blocks.isb_m, whole.isb_m, rtol=0, atol=1e-6)
    np.testing.assert_array_equal(blocks.status, whole.status)
    assert blocks.clock_groups == whole.clock_groups
    a, b = tmp_path / "whole.csv", tmp_path / "blocks.csv"
    write_solution(solution_frame(whole), a)
    write_solution(solution_frame(blocks), b)
    assert a.read_text() == b.read_text()
    with pytest.raises(ValueError, match="chunk_epochs"):
        solve_spp(obs, [nav], config=GEJ, chunk_epochs=0)


def test_time_gps_is_rounded_to_the_millisecond(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """One rule for the time column: t = ...40.0006 s is written ...40.001 (rounded, not
    truncated), in the table and in the CSV file."""
    obs, nav = _sample()
    res = solve_spp(obs, [nav], config=GEJ)
    t0 = np.floor(res.t_gps_s[0] / 60.0) * 60.0 + 40.0006
    shifted = res.replace(t_gps_s=t0 + np.arange(res.t_gps_s.size))
    cols = solution_columns(solution_frame(shifted))
    assert cols["time_gps"][0] == "2021-03-19T12:00:40.001"
    assert cols["time_gps"][1] == "2021-03-19T12:00:41.001"
    out = tmp_path / "t.csv"
    write_solution(solution_frame(shifted), out)
    assert out.read_text().splitlines()[1].startswith("2021-03-19T12:00:40.001,2149,475240.0006,")


def test_solution_frame_columns() -> None:
    obs, nav = _sample()
    res = solve_spp(obs, [nav], config=GEJ)
    frame = solution_frame(res)
    assert list(frame) == [
        "t_gps_s",
        "x_m",
        "y_m",
        "z_m",
        "clock_m",
        "sd_e_m",
        "sd_n_m",
        "sd_u_m",
        "n_sats",
        "pdop",
        "status",
        "excluded",
        "gdop",
        "hdop",
        "vdop",
        "sdx_m",
        "sdy_m",
        "sdz_m",
        "sdxy_m",
        "sdyz_m",
        "sdzx_m",
        "isb_E_m",
    ]
    np.testing.assert_array_equal(frame["x_m"], res.pos_m[:, 0])
    # RTKLIB's signed square roots of the ECEF covariance: sdzx holds cov(z, x)
    np.testing.assert_allclose(frame["sdx_m"] ** 2, res.cov[:, 0, 0], rtol=1e-12)
    zx = res.cov[:, 2, 0]
    np.testing.assert_allclose(np.sign(frame["sdzx_m"]) * frame["sdzx_m"] ** 2, zx, rtol=1e-12)
    np.testing.assert_array_equal(frame["n_sats"], res.n_sats)
    np.testing.assert_array_equal(frame["sd_u_m"], np.sqrt(res.cov_enu_m2[:, 2, 2]))
    np.testing.assert_array_equal(frame["isb_E_m"], res.isb_m[:, 0])
    assert set(frame["status"]) == {"ok"}
