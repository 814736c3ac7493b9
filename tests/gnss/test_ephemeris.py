"""Satellite orbits and clocks: broadcast vs precise (CODE MGEX SP3, an independent product),
GLONASS integration vs an inertial-frame scipy integration, BeiDou GEO, selection rules."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from navtrack.data import sample_path
from navtrack.geodesy import C_MPS, ecef_to_geodetic
from navtrack.gnss import ephemeris as eph
from navtrack.gnss.precise import sp3_states

TEST_DATA = Path(__file__).resolve().parents[1] / "data"


def _sept():  # type: ignore[no-untyped-def]
    from navtrack.gnss.rinex.nav import read_nav
    from navtrack.gnss.sp3 import read_sp3

    nav = read_nav(sample_path("SEPT078M.21P"))
    sp3 = read_sp3(sample_path("COD0MGXFIN_20210780000_01D_05M_ORB_1045-1330.SP3"))
    return nav, sp3


@pytest.mark.parametrize(
    ("system", "max_pos_m", "max_clk_ns"), [("G", 4.0, 8.0), ("E", 3.0, 8.0), ("J", 6.0, 15.0)]
)
def test_broadcast_agrees_with_precise_orbits(
    system: str, max_pos_m: float, max_clk_ns: float
) -> None:
    """Broadcast GPS/Galileo/QZSS orbits and clocks at 12:00-12:15 GPST on 2021-03-19 against
    CODE's final MGEX orbits at the SP3 epochs. The SP3 refers to the centre of mass and the
    broadcast to the antenna phase centre (offsets up to ~1-2.5 m) and the clocks differ by a
    common datum per epoch, removed here; broadcast signal-in-space errors are ~1 m (URA)."""
    nav, sp3 = _sept()
    tables = eph.ephemeris_tables(nav)
    t = sp3.t_gps_s[(sp3.t_gps_s >= 1300190400.0) & (sp3.t_gps_s <= 1300191300.0)]
    sats = [s for s in sp3.sats if s[0] == system and s in set(tables[system].sat)]
    assert len(sats) >= 3
    t_tx = np.broadcast_to(t[:, None], (t.size, len(sats)))
    st = eph.broadcast_states(tables, sats, t, t_tx + 0.0)
    # broadcast_states removes the clock from t_tx; evaluate SP3 at the same true GPS time
    t_true = t_tx - st.clock_s
    ref = sp3_states(sp3, sats, t_true + _sp3_clock(sp3, sats, t_true))
    ok = st.valid & ref.valid
    assert ok.mean() > 0.9
    d = np.linalg.norm(st.pos_m - ref.pos_m, axis=-1)[ok]
    assert np.median(d) < max_pos_m / 2
    assert d.max() < max_pos_m
    dclk = (st.clock_s - ref.clock_s) * 1e9
    dclk = dclk - np.nanmedian(np.where(ok, dclk, np.nan), axis=1, keepdims=True)
    assert np.nanmax(np.abs(dclk[ok])) < max_clk_ns


def _sp3_clock(sp3, sats, t):  # type: ignore[no-untyped-def]
    """SP3 clock at t (linear), to feed sp3_states a satellite-clock time tag."""
    out = np.zeros_like(t)
    for j, s in enumerate(sats):
        k = list(sp3.sats).index(s)
        out[:, j] = np.interp(t[:, j], sp3.t_gps_s, sp3.clock_s[:, k])
    return out


def test_kepler_velocity_is_the_derivative_of_position() -> None:
    nav, _ = _sept()
    tables = eph.ephemeris_tables(nav)
    for sys in "GEJ":
        tab = tables[sys]
        rows = np.arange(len(tab.sat))[:5]
        p = {k: tab.get(k)[rows] for k in eph.KEPLER_FIELDS}
        t = tab.get("toe_gps_s")[rows] + 1234.5
        pos, vel, dtr = eph.kepler_orbit(p, t, sys)
        # +-0.5 s: GPS seconds near 1.3e9 resolve 0.24 us, too coarse for shorter differences
        p1, _, _ = eph.kepler_orbit(p, t + 0.5, sys)
        p0, _, _ = eph.kepler_orbit(p, t - 0.5, sys)
        np.testing.assert_allclose(vel, (p1 - p0) / 1.0, atol=1e-4)
        r = np.linalg.norm(pos, axis=1)
        assert np.all((r > 2.5e7) & (r < 4.7e7))  # QZSS QZO apogee ~ 4.6e7 m
        assert np.all(np.abs(dtr) < 3e-7)  # tens of ns; QZSS (e = 0.075) up to ~0.2 us


def test_relativistic_term_formula() -> None:
    """F e sqrt(A) sin E with F = -4.442807633e-10 s/m^0.5 (IS-GPS-200 20.3.3.3.3.1)."""
    p = {k: np.zeros(1) for k in eph.KEPLER_FIELDS}
    p["sqrta"] = np.array([5153.7])
    p["e"] = np.array([0.01])
    p["m0"] = np.array([np.pi / 2])
    _, _, dtr = eph.kepler_orbit(p, np.zeros(1), "G")
    ecc = eph._eccentric_anomaly(np.array([np.pi / 2]), np.array([0.01]))
    assert dtr[0] == pytest.approx(-4.442807633e-10 * 0.01 * 5153.7 * np.sin(ecc[0]), rel=1e-9)


def _brdm():  # type: ignore[no-untyped-def]
    from navtrack.gnss.rinex.nav import read_nav

    return read_nav(TEST_DATA / "BRDC00IGS_R_20230010000_01D_MN_cut.rnx")


def test_beidou_geo_is_geostationary() -> None:
    """C01 and C02 (BDS-2 GEO) from their real broadcast elements with the GEO transformation
    of BDS-SIS-ICD 5.2.4.12: over +-2 h each stays at one longitude (drift < 0.1 deg), near
    the equator, at GEO height, moving < 100 m/s in ECEF. Without the transformation the same
    elements give a 5 deg inclined orbit."""
    tab = eph.ephemeris_tables(_brdm())["C"]
    for sat in ("C01", "C02"):
        row = int(np.flatnonzero(tab.sat == sat)[0])
        t = tab.get("toe_gps_s")[row] + np.linspace(-7200, 7200, 9)
        p = {k: np.repeat(tab.get(k)[row], t.size) for k in eph.KEPLER_FIELDS}
        pos, vel, _ = eph.kepler_orbit(p, t, "C", geo=np.ones(t.size, dtype=bool))
        llh = np.degrees(ecef_to_geodetic(pos)[:, :2])
        assert np.ptp(llh[:, 1]) < 0.1
        assert np.all(np.abs(llh[:, 0]) < 3.0)
        np.testing.assert_allclose(np.linalg.norm(pos, axis=1), 42164e3, rtol=2e-3)
        assert np.all(np.linalg.norm(vel, axis=1) < 100.0)
        wrong, _, _ = eph.kepler_orbit(p, t, "C")
        assert np.max(np.abs(np.degrees(ecef_to_geodetic(wrong)[:, 0]))) > 3.0


def _glonass_inertial(state0: np.ndarray, acc: np.ndarray, dt: float) -> np.ndarray:
    """Independent formulation: integrate in an inertial frame (central field + J2, lunisolar
    accelerations rotated along), rotate back to the earth-fixed frame at the end."""
    from scipy.integrate import solve_ivp

    w = eph.GLO_OMEGA_RAD_S
    x, v = state0[:3], state0[3:]
    v_in = v + np.cross([0.0, 0.0, w], x)

    def rot(a: float) -> np.ndarray:
        c, s = np.cos(a), np.sin(a)
        return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])

    def f(t: float, s: np.ndarray) -> np.ndarray:
        r = s[:3]
        rn = np.linalg.norm(r)
        mu, a, j2 = eph.GLO_MU_M3S2, eph.GLO_A_M, eph.GLO_J2
        z2 = (r[2] / rn) ** 2
        g = -mu * r / rn**3
        g += 1.5 * j2 * mu * a**2 / rn**5 * r * np.array([5 * z2 - 1, 5 * z2 - 1, 5 * z2 - 3])
        return np.concatenate([s[3:], g + rot(w * t) @ acc])

    sol = solve_ivp(f, (0.0, dt), np.concatenate([x, v_in]), method="DOP853", rtol=1e-12, atol=1e-6)
    r_in, v_in_end = sol.y[:3, -1], sol.y[3:, -1]
    back = rot(-w * dt)
    r_ef = back @ r_in
    v_ef = back @ v_in_end - np.cross([0.0, 0.0, w], r_ef)
    return np.concatenate([r_ef, v_ef])


@pytest.mark.parametrize("dt", [-900.0, 300.0, 900.0])
def test_glonass_rk4_matches_inertial_integration(dt: float) -> None:
    pytest.importorskip("scipy.integrate")
    tab = eph.ephemeris_tables(_brdm())["R"]
    for row in range(len(tab.sat)):
        p = {k: np.array([tab.get(k)[row]]) for k in eph.GLONASS_FIELDS}
        pos, vel = eph.glonass_orbit(p, p["toc_gps_s"] + dt)
        s0 = np.array([p[k][0] for k in ("x_m", "y_m", "z_m", "vx_mps", "vy_mps", "vz_mps")])
        acc = np.array([p[k][0] for k in ("ax_mps2", "ay_mps2", "az_mps2")])
        ref = _glonass_inertial(s0, acc, dt)
        # RK4 with 60 s steps: cm-level against the tight integration (ICD: 1 m accuracy)
        assert np.linalg.norm(pos[0] - ref[:3]) < 0.05
        assert np.linalg.norm(vel[0] - ref[3:]) < 1e-4


def test_select_future_ephemeris_and_window() -> None:
    """Only 'future' records within the window are valid: ARL1-like case built from the SEPT
    nav file (G02 has only toc 14:00 there: valid at 12:00:01, as 2 h window allows)."""
    nav, _ = _sept()
    tab = eph.ephemeris_tables(nav)["G"]
    toe = tab.get("toe_gps_s")
    t = np.array([1300190400.0, 1300190400.0 - 7200.0 * 2])
    idx = eph.select_ephemeris(tab, ["G02", "G05"], t)
    g02 = np.flatnonzero(tab.sat == "G02")
    if toe[g02].min() - t[0] <= 7200.0:
        assert idx[0, 0] in g02
    assert idx[1, 0] == -1  # 4 h before: outside the window
    assert np.all(idx[:, 1] == -1)  # G05 not in the file


def _toy_table(**cols: list[float]) -> eph.EphemerisTable:
    n = len(next(iter(cols.values())))
    sat = np.array(cols.pop("sat")) if "sat" in cols else np.array(["G01"] * n)  # type: ignore[arg-type]
    return eph.EphemerisTable("G", sat, {k: np.asarray(v) for k, v in cols.items()})


def test_select_nearest_healthy_consistent() -> None:
    tab = _toy_table(
        toe_gps_s=[0.0, 7200.0, 7200.0, 14400.0],
        svh=[0, 0, 0, 1],
        iode=[1, 2, 3, 4],
        iodc=[1, 2, 3 + 256, 4],
    )
    t = np.array([1000.0, 5000.0, 7000.0, 13000.0, 30000.0])
    idx = eph.select_ephemeris(tab, ["G01"], t)[:, 0]
    # 5000 -> record 1 (IODE 2; record 2 has IODC low byte == IODE too, ties go to the later)
    assert idx.tolist()[:2] == [0, 2]
    assert idx[3] == 2  # nearest (14400) is unhealthy -> 7200
    assert idx[4] == -1
    bad = _toy_table(toe_gps_s=[0.0], svh=[0], iode=[5], iodc=[6])
    assert eph.select_ephemeris(bad, ["G01"], np.array([0.0]))[0, 0] == -1


def test_galileo_data_source_selection() -> None:
    tab = eph.EphemerisTable(
        "E",
        np.array(["E01", "E01"]),
        {
            "toe_gps_s": np.array([0.0, 0.0]),
            "svh": np.array([0, 0]),
            "data_source": np.array([516, 258]),
            "bgd_e5a": np.array([1e-9, 2e-9]),
            "bgd_e5b": np.array([3e-9, 0.0]),
        },
    )
    t = np.array([10.0])
    i_inav = eph.select_ephemeris(tab, ["E01"], t, galileo_nav="inav")
    i_fnav = eph.select_ephemeris(tab, ["E01"], t, galileo_nav="fnav")
    assert (i_inav[0, 0], i_fnav[0, 0]) == (0, 1)
    assert eph.group_delay_s(tab, i_inav)[0, 0] == 3e-9  # I/NAV E1: BGD(E1,E5b)
    assert eph.group_delay_s(tab, i_fnav)[0, 0] == 2e-9  # F/NAV E1: BGD(E1,E5a)
    with pytest.raises(ValueError, match="galileo_nav"):
        eph.select_ephemeris(tab, ["E01"], t, galileo_nav="both")


def test_group_delay_gps_l2_scaling() -> None:
    tab = _toy_table(toe_gps_s=[0.0], tgd=[-5e-9])
    idx = np.array([[0, -1]])
    assert eph.group_delay_s(tab, idx, "1").tolist() == [[-5e-9, 0.0]]
    assert eph.group_delay_s(tab, idx, "2")[0, 0] == pytest.approx(-5e-9 * (77 / 60) ** 2)


def test_ura_variance_tables() -> None:
    """IS-GPS-200 20.3.3.3.1.1: URA index upper bounds; Galileo SISA grid (OS SIS ICD)."""
    v = eph.ura_variance("G", np.array([2.0, 2.4, 2.8, 3.4, 6.0, 1e4, np.nan]))
    np.testing.assert_allclose(np.sqrt(v), [2.4, 2.4, 3.4, 3.4, 6.85, 6144.0, 6144.0])
    s = eph.ura_variance("E", np.array([0.3, 0.75, 1.5, 3.12, 7.0]))
    np.testing.assert_allclose(np.sqrt(s), [0.3, 0.74, 1.48, 3.12, 6144.0], atol=1e-12)
    np.testing.assert_allclose(eph.ura_variance("G", np.array([2.0]), quantise=False), 4.0)


def test_sp3_interpolation_reproduces_dropped_nodes() -> None:
    """Interpolating a 10-min thinned copy of the 5-min CODE orbit at the dropped epochs gives
    the dropped positions to a few cm (degree-10 Lagrange in the rotated frame), and the nodes
    themselves exactly."""
    from types import SimpleNamespace

    _, sp3 = _sept()
    thin = SimpleNamespace(
        sats=sp3.sats,
        t_gps_s=sp3.t_gps_s[::2],
        pos_m=sp3.pos_m[::2],
        clock_s=sp3.clock_s[::2],
        clock=None,
    )
    sats = [s for s in sp3.sats if s[0] in "GEJ"][:20]
    cols = [list(sp3.sats).index(s) for s in sats]
    mid = slice(11, -11, 2)  # dropped epochs well inside the span
    t = sp3.t_gps_s[mid]
    tt = np.broadcast_to(t[:, None], (t.size, len(sats))).copy()
    clk = sp3.clock_s[mid][:, cols]
    st = sp3_states(thin, sats, tt + np.nan_to_num(clk))
    truth = sp3.pos_m[mid][:, cols]
    ok = st.valid & np.isfinite(truth).all(axis=-1)
    assert ok.mean() > 0.8
    err = np.linalg.norm(st.pos_m - truth, axis=-1)[ok]
    assert np.max(err) < 0.05
    # clocks: linear between 10-min nodes, ns-level for these clocks
    rel = -2.0 * np.einsum("esi,esi->es", st.pos_m, st.vel_mps) / C_MPS**2
    dclk = (st.clock_s - rel - clk)[ok]
    assert np.max(np.abs(dclk)) < 1e-9
    t_nodes = np.broadcast_to(sp3.t_gps_s[20:22, None], (2, len(sats)))
    at_nodes = sp3_states(sp3, sats, t_nodes + sp3.clock_s[20:22][:, cols])
    ok2 = at_nodes.valid
    np.testing.assert_allclose(at_nodes.pos_m[ok2], sp3.pos_m[20:22][:, cols][ok2], atol=1e-6)
