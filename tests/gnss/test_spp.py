"""Single point positioning: accuracy bars against RTKLIB 2.4.3 on the shared real data, the
Android log bar, synthetic recoveries and bad-input statuses.

Reference numbers (RTKLIB's epochs and RMS, reference positions) are in
``tests/data/rtklib_spp_reference.json`` with their provenance in ``tests/data/README.md``.
"""

from __future__ import annotations

import json
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest

from navtrack.geodesy import ecef_to_enu, geodetic_to_ecef
from navtrack.gnss.spp import (
    STATUS_NAMES,
    SppConfig,
    SppStatus,
    concatenate_results,
    solution_frame,
    solve_spp,
    subset_epochs,
)
from navtrack.io.solution import solution_columns

REFERENCE = json.loads(
    (Path(__file__).resolve().parents[1] / "data" / "rtklib_spp_reference.json").read_text()
)
RUNS = REFERENCE["runs"]


@lru_cache(maxsize=8)
def _obs(path: str):  # type: ignore[no-untyped-def]
    from navtrack.gnss.rinex.obs import read_obs

    return read_obs(path)


@lru_cache(maxsize=8)
def _nav(path: str):  # type: ignore[no-untyped-def]
    from navtrack.gnss.rinex.nav import read_nav

    return read_nav(path)


def _run(gnss_data: Path, name: str, ephemeris=None, **cfg: object):  # type: ignore[no-untyped-def]
    run = RUNS[name]
    obs = _obs(str(gnss_data / run["obs"]))
    navs = [_nav(str(gnss_data / p)) for p in run["nav"]]
    sp3 = None
    if run.get("sp3"):
        from navtrack.gnss.sp3 import read_sp3

        sp3 = read_sp3(gnss_data / run["sp3"])
    config = SppConfig(systems=run["systems"], **cfg)  # type: ignore[arg-type]
    return solve_spp(obs, navs, sp3=sp3, config=config, ephemeris=ephemeris)


def _rtklib_gettgd_tables(nav):  # type: ignore[no-untyped-def]
    """The group delays RTKLIB 2.4.3's ``gettgd`` (``pntpos.c``) applies: those of each
    satellite's first record (SEPT078M.21P: F/NAV, BGD(E5b,E1) = 0, for several Galileo
    satellites)."""
    from navtrack.gnss.ephemeris import ephemeris_tables, first_record_group_delays

    return first_record_group_delays(ephemeris_tables(nav))


def _rtklib(gnss_data: Path, name: str):  # type: ignore[no-untyped-def]
    from navtrack.io.rtklib import read_pos

    return read_pos(gnss_data / "rtklib_spp" / f"{name}.pos")


def _match(t_a: np.ndarray, t_b: np.ndarray, tol_s: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """Indices of the same epochs in two time vectors (RTKLIB prints receiver time corrected by
    the estimated clock, up to ~5 ms from the tag for 0759)."""
    i = np.clip(np.searchsorted(t_a, t_b - tol_s), 0, t_a.size - 1)
    m = np.abs(t_a[i] - t_b) < tol_s
    return i[m], np.flatnonzero(m)


RTKLIB_OPTIONS = {"arl1_gps_sp3": {"sp3_needs_broadcast": True}}


@pytest.mark.parametrize("name", sorted(RUNS))
def test_accuracy_bars_against_rtklib(gnss_data: Path, name: str) -> None:
    """Issue 3 bars: >= RTKLIB's solved epochs, 3D RMS within 5 % of RTKLIB's (or better),
    median per-epoch 3D distance to RTKLIB's own solution <= 0.3 m."""
    run = RUNS[name]
    # Galileo in RTKLIB's solution carries its gettgd group-delay choice (see
    # test_sept_gej_differs_from_rtklib_by_its_group_delay_choice); compare like with like
    eph = (
        _rtklib_gettgd_tables(_nav(str(gnss_data / run["nav"][0])))
        if "E" in run["systems"]
        else None
    )
    res = _run(gnss_data, name, ephemeris=eph, **RTKLIB_OPTIONS.get(name, {}))
    rtk = _rtklib(gnss_data, name)
    ok = res.status == SppStatus.OK
    assert ok.sum() >= run["solved"]
    t_rtk = rtk["t_gps_s"].to_numpy()
    xyz_rtk = rtk[["x_m", "y_m", "z_m"]].to_numpy()
    if "ref_xyz_m" in run:
        ref = np.broadcast_to(np.asarray(run["ref_xyz_m"]), (int(ok.sum()), 3))
    else:  # kinematic rover: RTKLIB RTK trajectory as the reference
        from navtrack.io.rtklib import read_pos

        traj = read_pos(gnss_data / run["ref_pos"])
        i, j = _match(traj["t_gps_s"].to_numpy(), res.t_gps_s[ok])
        assert j.size == ok.sum()
        ref = traj[["x_m", "y_m", "z_m"]].to_numpy()[i]
    enu = ecef_to_enu(res.pos_m[ok], ref)
    rms = float(np.sqrt(np.mean(np.sum(enu**2, axis=1))))
    assert rms <= 1.05 * run["rms_3d_m"]
    i, j = _match(res.t_gps_s, t_rtk)
    assert j.size == len(t_rtk)
    dist = np.linalg.norm(res.pos_m[i] - xyz_rtk[j], axis=1)
    assert np.median(dist) <= 0.3
    # the same satellites as RTKLIB in the matched epochs
    assert np.mean(res.n_sats[i] == rtk["ns"].to_numpy()[j]) > 0.95


def test_sept_gej_differs_from_rtklib_by_its_group_delay_choice(gnss_data: Path) -> None:
    """navtrack applies the group delays of the ephemeris it uses, QZSS's included
    (IS-QZSS-PNT): 0.5-0.9 m from RTKLIB's GPS+Galileo+QZSS solution of SEPT. With RTKLIB's
    gettgd choice (first record of each satellite) the two agree to centimetres, so that
    choice is the whole difference; QZSS's TGD RTKLIB applies as navtrack does."""
    rtk = _rtklib(gnss_data, "sept078_gej")
    xyz = rtk[["x_m", "y_m", "z_m"]].to_numpy()
    icd = _run(gnss_data, "sept078_gej")
    assert np.median(np.linalg.norm(icd.pos_m - xyz, axis=1)) > 0.5
    nav = _nav(str(gnss_data / RUNS["sept078_gej"]["nav"][0]))
    like = _run(gnss_data, "sept078_gej", ephemeris=_rtklib_gettgd_tables(nav))
    dist = np.linalg.norm(like.pos_m - xyz, axis=1)
    assert np.median(dist) < 0.06
    assert dist.max() < 0.1


def test_gps_matches_rtklib_to_millimetres(gnss_data: Path) -> None:
    """Same models, same data: GPS-only solutions agree with RTKLIB's to the print precision
    (0.1 mm in x/y/z; a few mm allowed for its convergence threshold), and so do the formal
    standard deviations (RTKLIB's sdx/sdy/sdz are printed to 0.1 mm)."""
    res = _run(gnss_data, "sept078_gps")
    rtk = _rtklib(gnss_data, "sept078_gps")
    xyz = rtk[["x_m", "y_m", "z_m"]].to_numpy()
    assert np.max(np.linalg.norm(res.pos_m - xyz, axis=1)) < 0.005
    sd = np.sqrt(np.einsum("eii->ei", res.cov[:, :3, :3]))
    np.testing.assert_allclose(sd, rtk[["sdx_m", "sdy_m", "sdz_m"]].to_numpy(), atol=2e-4)


def test_high_dop_epochs_are_those_rtklib_drops(gnss_data: Path) -> None:
    res = _run(gnss_data, "gsi0759_gps")
    rtk = _rtklib(gnss_data, "gsi0759_gps")
    _, j = _match(rtk["t_gps_s"].to_numpy(), res.t_gps_s)
    missing = np.setdiff1d(np.arange(res.t_gps_s.size), j)
    assert missing.size == 5
    assert np.all(res.status[missing] == SppStatus.HIGH_DOP)
    assert np.all(res.dop[missing, 0] > 30.0)


def test_sp3_default_uses_satellites_without_broadcast(gnss_data: Path) -> None:
    """ARL1's nav file has no ephemeris for some satellites in the first hour; with SP3 clocks
    navtrack keeps them (RTKLIB drops them), solves every epoch and is more accurate."""
    res = _run(gnss_data, "arl1_gps_sp3")
    rtk = _rtklib(gnss_data, "arl1_gps_sp3")
    run = RUNS["arl1_gps_sp3"]
    ok = res.status == SppStatus.OK
    assert ok.sum() == 120
    enu = ecef_to_enu(res.pos_m[ok], np.asarray(run["ref_xyz_m"]))
    assert np.sqrt(np.mean(np.sum(enu**2, axis=1))) < run["rms_3d_m"]
    assert np.mean(res.n_sats) > rtk["ns"].mean()


def test_android_log_bar(gnss_data: Path) -> None:
    """Android GnssLogger log (GPS with broadcast nav): 3D RMS <= 15 m against the surveyed
    point (gps-measurement-tools' reference). A phone's pseudoranges are weighted by C/N0 (the
    RTKLIB receiver model is far too optimistic for them and its chi-square test would reject
    about half the epochs); the first 7 epochs have no decoded GPS time of week."""
    android = pytest.importorskip("navtrack.gnss.android")
    cfg = REFERENCE["android"]
    obs = android.read_gnsslogger(gnss_data / cfg["log"])
    navs = [_nav(str(gnss_data / p)) for p in cfg["nav"]]
    res = solve_spp(obs, navs, config=SppConfig(systems="G", elmask_deg=10.0, weighting="cn0"))
    ok = res.status == SppStatus.OK
    assert ok.sum() >= 0.9 * res.t_gps_s.size
    assert np.all(res.status[:7] == SppStatus.TOO_FEW_SATS)
    lat, lon, h = cfg["ref_llh_deg_m"]
    ref = geodetic_to_ecef([np.radians(lat), np.radians(lon), h])
    enu = ecef_to_enu(res.pos_m[ok], ref)
    assert np.sqrt(np.mean(np.sum(enu**2, axis=1))) <= cfg["bar_rms_3d_m"]


# --------------------------------------------------------------------------- bundled sample
def _sample():  # type: ignore[no-untyped-def]
    from navtrack.data import sample_path
    from navtrack.gnss.rinex.nav import read_nav
    from navtrack.gnss.rinex.obs import read_obs

    return read_obs(sample_path("SEPT078M_120.21O")), read_nav(sample_path("SEPT078M.21P"))


SEPT_REF = np.array([-3962108.673, 3381309.574, 3668678.638])


TRUTH_CLOCK_M, TRUTH_ISB_E_M = 1234.5, -7.25


def _synthetic_sample():  # type: ignore[no-untyped-def]
    """The bundled sample's C1C replaced by pseudoranges generated from the model itself at
    SEPT_REF with a known clock and Galileo ISB (no noise, no atmosphere)."""
    from navtrack.gnss import ephemeris as eph
    from navtrack.gnss.corrections import geometric_range

    obs, nav = _sample()
    cfg = SppConfig(systems="GEJ", iono="off", tropo="off", weighting="equal")
    sats = solve_spp(obs, [nav], config=cfg).sats
    tables = eph.ephemeris_tables(nav)
    pr = np.full((obs.t_gps_s.size, len(sats)), np.nan)
    rho0 = np.full_like(pr, 2.2e7)
    for _ in range(3):  # fixed point: transmit time depends on the pseudorange
        t_sv = obs.t_gps_s[:, None] - rho0 / 299792458.0
        st = eph.broadcast_states(tables, sats, obs.t_gps_s, t_sv)
        rho, _ = geometric_range(st.pos_m, SEPT_REF)
        gd = np.zeros_like(rho)
        for s in "GEJ":
            cols = [k for k, sat in enumerate(sats) if sat[0] == s]
            gd[:, cols] = eph.group_delay_s(tables[s], st.eph_index[:, cols])
        isb = np.array([TRUTH_ISB_E_M if s[0] == "E" else 0.0 for s in sats])
        pr = rho + TRUTH_CLOCK_M + isb - 299792458.0 * (st.clock_s - gd)
        rho0 = pr
    values = np.array(obs.values)
    codes = list(obs.codes)
    for k, sat in enumerate(obs.sats):
        if sat in sats:
            values[:, k, codes.index("C1C")] = pr[:, sats.index(sat)]
    return obs.replace(values=values), nav, cfg


def test_synthetic_pseudoranges_recover_position_and_clocks() -> None:
    """Pseudoranges generated from the model itself at a known position, clock and ISB (no
    noise) are inverted back to the millimetre: the solver and geometry loop are consistent."""
    synth, nav, cfg = _synthetic_sample()
    res = solve_spp(synth, [nav], config=cfg)
    assert np.all(res.status == SppStatus.OK)
    assert np.max(np.linalg.norm(res.pos_m - SEPT_REF, axis=1)) < 1e-3
    np.testing.assert_allclose(res.clock_m, TRUTH_CLOCK_M, atol=1e-3)
    np.testing.assert_allclose(res.isb_m[:, 0], TRUTH_ISB_E_M, atol=1e-3)
    assert np.max(np.abs(res.residuals_m[np.isfinite(res.residuals_m)])) < 1e-3


def test_epochs_without_the_first_clock_group_solve_on_the_next() -> None:
    """Without GPS and QZSS (the first clock group) in some epochs, those epochs are solved on
    Galileo alone, its clock as the receiver clock and its ISB not estimated, instead of being
    called singular (a multi-GNSS rover whose GPS ephemerides start late)."""
    synth, nav, cfg = _synthetic_sample()
    values = np.array(synth.values)
    gj = [k for k, sat in enumerate(synth.sats) if sat[0] in "GJ"]
    values[:20, gj, :] = np.nan
    res = solve_spp(synth.replace(values=values), [nav], config=cfg)
    assert np.all(res.status == SppStatus.OK)
    assert np.max(np.linalg.norm(res.pos_m - SEPT_REF, axis=1)) < 1e-3
    np.testing.assert_allclose(res.clock_m[:20], TRUTH_CLOCK_M + TRUTH_ISB_E_M, atol=1e-3)
    assert np.all(np.isnan(res.isb_m[:20, 0]))
    np.testing.assert_allclose(res.clock_m[20:], TRUTH_CLOCK_M, atol=1e-3)
    np.testing.assert_allclose(res.isb_m[20:, 0], TRUTH_ISB_E_M, atol=1e-3)
    assert np.all(res.dof[:20] == res.used[:20].sum(axis=1) - 4)


def test_sample_solution_columns_and_statuses() -> None:
    obs, nav = _sample()
    res = solve_spp(obs, [nav], config=SppConfig(systems="GEJ"))
    assert res.status_counts()["ok"] == 120
    assert set(res.status_counts()) == set(STATUS_NAMES)
    cols = solution_columns(solution_frame(res))
    for name in (
        "time_gps",
        "week",
        "tow_s",
        "x_m",
        "y_m",
        "z_m",
        "lat_deg",
        "lon_deg",
        "h_m",
        "clock_m",
        "sd_e_m",
        "sd_n_m",
        "sd_u_m",
        "n_sats",
        "pdop",
        "status",
        "excluded",
    ):
        assert len(cols[name]) == 120
    assert cols["time_gps"][0] == "2021-03-19T12:00:00.000"
    assert cols["week"][0] == 2149
    assert cols["tow_s"][0] == 475200.0
    np.testing.assert_allclose(cols["lat_deg"], 35.3393, atol=1e-3)
    assert np.all(cols["status"] == "ok")
    # covariances symmetric positive definite, ENU sd positive
    c = res.cov[:, :4, :4]
    np.testing.assert_allclose(c, np.swapaxes(c, 1, 2), atol=1e-9)
    assert np.all(np.linalg.eigvalsh(c) > 0)
    assert np.all(cols["sd_u_m"] > cols["sd_e_m"])
    # arrays are read-only
    with pytest.raises(ValueError, match="read-only"):
        res.pos_m[0, 0] = 0.0


def test_chunked_solution_equals_whole() -> None:
    obs, nav = _sample()
    cfg = SppConfig(systems="GEJ")
    whole = solve_spp(obs, [nav], config=cfg)
    parts = [
        solve_spp(subset_epochs(obs, slice(a, a + 50)), [nav], config=cfg)
        for a in range(0, 120, 50)
    ]
    joined = concatenate_results(parts)
    np.testing.assert_allclose(joined.pos_m, whole.pos_m, atol=1e-6)
    np.testing.assert_allclose(joined.isb_m, whole.isb_m, atol=1e-6)
    assert joined.clock_groups == whole.clock_groups


def test_ionofree_and_other_weightings_solve_the_sample() -> None:
    obs, nav = _sample()
    for cfg in (
        SppConfig(systems="GEJ", iono="ionofree"),
        SppConfig(systems="GEJ", weighting="cn0"),
        SppConfig(systems="GEJ", weighting="elevation"),
        SppConfig(systems="G", weighting="equal"),
    ):
        res = solve_spp(obs, [nav], config=cfg)
        ok = res.status == SppStatus.OK
        assert ok.sum() >= 110, cfg
        err = np.linalg.norm(res.pos_m[ok] - SEPT_REF, axis=1)
        assert np.median(err) < 6.0, cfg


# --------------------------------------------------------------------------- bad input
def test_nav_of_another_day_gives_no_ephemeris() -> None:
    from navtrack.data import sample_path
    from navtrack.gnss.rinex.nav import read_nav

    obs, _ = _sample()
    other = read_nav(sample_path("07590920.05n"))  # 2005 GPS nav for 2021 observations
    res = solve_spp(obs, [other], config=SppConfig(systems="G"))
    assert np.all(res.status == SppStatus.NO_EPHEMERIS)
    assert res.no_ephemeris.any(axis=1).all()
    assert np.all(np.isnan(res.pos_m))


def test_few_satellites_status_and_rest_solved() -> None:
    """Epochs left with 3 GPS satellites are too_few_sats; with an ISB, 4 satellites of two
    systems are too few as well; the other epochs still solve."""
    obs, nav = _sample()
    values = np.array(obs.values)
    keep = {"G03", "G04", "G09"}
    for k, sat in enumerate(obs.sats):
        if sat not in keep:
            values[:10, k, :] = np.nan
    res = solve_spp(obs.replace(values=values), [nav], config=SppConfig(systems="GEJ"))
    assert np.all(res.status[:10] == SppStatus.TOO_FEW_SATS)
    assert np.all(res.status[10:] == SppStatus.OK)
    values2 = np.array(obs.values)
    keep2 = {"G03", "G04", "G09", "E01"}
    for k, sat in enumerate(obs.sats):
        if sat not in keep2:
            values2[:5, k, :] = np.nan
    res2 = solve_spp(obs.replace(values=values2), [nav], config=SppConfig(systems="GEJ"))
    assert np.all(res2.status[:5] == SppStatus.TOO_FEW_SATS)
    assert np.all(res2.status[5:] == SppStatus.OK)


def test_satellite_without_ephemeris_is_flagged_not_used() -> None:
    obs, nav = _sample()
    from navtrack.gnss import ephemeris as eph

    tables = eph.ephemeris_tables(nav)
    g = tables["G"]
    keep = g.sat != "G14"
    tables["G"] = eph.EphemerisTable("G", g.sat[keep], {k: v[keep] for k, v in g.columns.items()})
    res = solve_spp(obs, [nav], config=SppConfig(systems="GEJ"), ephemeris=tables)
    j = res.sats.index("G14")
    assert res.no_ephemeris[:, j].all()
    assert not res.used[:, j].any()
    assert np.all(res.status == SppStatus.OK)


def test_config_validation() -> None:
    with pytest.raises(ValueError, match="weighting"):
        SppConfig(weighting="snr")
    with pytest.raises(ValueError, match="systems"):
        SppConfig(systems="GX")
    with pytest.raises(ValueError, match="elmask"):
        SppConfig(elmask_deg=95.0)


def test_chi2_validity_rejects_a_large_fault() -> None:
    """A 100 m error on one satellite makes the weighted residuals fail the chi-square test."""
    obs, nav = _sample()
    values = np.array(obs.values)
    k = obs.sats.index("G03")
    values[:5, k, obs.codes.index("C1C")] += 100.0
    res = solve_spp(obs.replace(values=values), [nav], config=SppConfig(systems="GEJ"))
    assert np.all(res.status[:5] == SppStatus.REJECTED_VALIDITY)
    assert np.all(res.status[5:] == SppStatus.OK)
    assert np.all(np.isfinite(res.pos_m[:5]))


def test_max_iter_gives_no_convergence() -> None:
    obs, nav = _sample()
    res = solve_spp(obs, [nav], config=SppConfig(systems="GEJ", max_iter=1), x0_m=np.zeros(3))
    assert np.all(res.status == SppStatus.NO_CONVERGENCE)
    assert np.all(np.isnan(res.pos_m))


def test_glonass_only_synthetic_recovery() -> None:
    """GLONASS path end to end (RK4 orbits, -tau_n clock, FDMA frequencies, own clock group):
    eight satellites made from the real R01/R02 records of the BRDM test file by rotating their
    state vectors about the earth's axis; pseudoranges synthesised at a known point are inverted
    back to the millimetre."""
    from navtrack.gnss import ephemeris as eph
    from navtrack.gnss.corrections import geometric_range
    from navtrack.gnss.observations import Observations, ObsHeader
    from navtrack.gnss.rinex.nav import read_nav

    nav = read_nav(
        Path(__file__).resolve().parents[1] / "data" / "BRDC00IGS_R_20230010000_01D_MN_cut.rnx"
    )
    src = eph.ephemeris_tables(nav)["R"]
    cols: dict[str, list[float]] = {k: [] for k in src.columns}
    sats = []
    for k in range(12):
        row = k % 2
        a = np.radians(30.0 * k)
        c, s = np.cos(a), np.sin(a)
        for name in src.columns:
            cols[name].append(float(src.columns[name][row]))
        for x, y in (("x_m", "y_m"), ("vx_mps", "vy_mps"), ("ax_mps2", "ay_mps2")):
            xv, yv = src.columns[x][row], src.columns[y][row]
            cols[x][-1], cols[y][-1] = c * xv - s * yv, s * xv + c * yv
        sats.append(f"R{k + 1:02d}")
    table = eph.EphemerisTable("R", np.array(sats), {k: np.asarray(v) for k, v in cols.items()})
    rcv = geodetic_to_ecef([np.radians(-50.0), np.radians(10.0), 200.0])  # under R01, R02
    t = table.get("toc_gps_s")[0] + np.arange(0.0, 300.0, 30.0)  # GDOP < 30 in this span
    clock = 3000.0
    pr = np.full((t.size, len(sats)), 2.2e7)
    for _ in range(3):
        st = eph.broadcast_states({"R": table}, sats, t, t[:, None] - pr / 299792458.0)
        rho, _ = geometric_range(st.pos_m, rcv)
        pr = rho + clock - 299792458.0 * st.clock_s
    values = pr[..., None]
    n_e, n_s = pr.shape
    obs = Observations(
        path="synthetic",
        header=ObsHeader(version=3.04, file_type="O", system="R", obs_types={"R": ("C1C",)}),
        t_gps_s=t,
        epoch_flag=np.zeros(n_e, np.int8),
        clock_offset_s=np.full(n_e, np.nan),
        sats=tuple(sats),
        codes=("C1C",),
        values=values,
        lli=np.full((n_e, n_s, 1), -1, np.int8),
        ssi=np.full((n_e, n_s, 1), -1, np.int8),
    )
    res = solve_spp(
        obs,
        None,
        config=SppConfig(systems="R", iono="off", tropo="off", weighting="equal", elmask_deg=5.0),
        ephemeris={"R": table},
    )
    ok = res.status == SppStatus.OK
    assert ok.all(), (res.status_counts(), res.status, res.n_sats, res.dop[:, 0])
    assert np.max(np.linalg.norm(res.pos_m - rcv, axis=1)) < 1e-3
    np.testing.assert_allclose(res.clock_m, clock, atol=1e-3)
    assert res.clock_groups == ("R",)


@pytest.mark.parametrize(
    ("name", "nav", "config"),
    [
        ("SEPT078M_120.21O", "SEPT078M.21P", SppConfig(systems="GEJ")),
        ("SEPT078M_120.21O", "SEPT078M.21P", SppConfig(systems="GE", iono="ionofree")),
        ("07590920.05o", "07590920.05n", SppConfig(systems="G")),
    ],
)
def test_reading_only_the_codes_spp_takes_gives_the_same_solution(name, nav, config) -> None:  # type: ignore[no-untyped-def]
    from navtrack.data import sample_path
    from navtrack.gnss.rinex.nav import read_nav
    from navtrack.gnss.rinex.obs import read_obs
    from navtrack.gnss.spp import observation_codes

    navs = read_nav(sample_path(nav))
    full = solve_spp(read_obs(sample_path(name)), navs, config=config)
    codes = observation_codes(config)
    part_obs = read_obs(sample_path(name), systems=config.systems, codes=codes)
    assert set(part_obs.codes) <= codes
    part = solve_spp(part_obs, navs, config=config)
    np.testing.assert_array_equal(part.status, full.status)
    np.testing.assert_array_equal(part.pos_m, full.pos_m)
