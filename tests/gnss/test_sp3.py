"""SP3 reader: shared and bundled files, printed values, georinex cross-check, bad input.

Expected values are copied from the printed text of the files; unit conversions follow the SP3-d
specification (km, µs, dm/s, 10⁻⁴ µs/s). georinex 1.16.2 ``load_sp3`` is the independent reader.
"""

from __future__ import annotations

import gzip
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pytest

from navtrack.data import sample_path
from navtrack.errors import FileFormatError
from navtrack.gnss.sp3 import Sp3, read_sp3
from navtrack.timescale import calendar_gps_seconds

COD = "cssrlib_sept/COD0MGXFIN_20210780000_01D_05M_ORB.SP3"
NGA = "gpstk_arl1/test_input_sp3_nav_2015_200.sp3"
SHARED_SP3 = (COD, NGA)
BUNDLED = "COD0MGXFIN_20210780000_01D_05M_ORB_1045-1330.SP3"


def _epoch_lines(path: Path) -> int:
    return sum(1 for ln in path.read_text().splitlines() if ln.startswith("*"))


@pytest.mark.parametrize("name", SHARED_SP3)
def test_shared_sp3_reads(gnss_data: Path, name: str) -> None:
    path = gnss_data / name
    sp3 = read_sp3(path)
    assert isinstance(sp3, Sp3)
    n_e = _epoch_lines(path)
    assert sp3.t_gps_s.shape == (n_e,)
    assert sp3.header.n_epochs == n_e
    assert np.all(np.diff(sp3.t_gps_s) == sp3.header.interval_s)
    assert sp3.pos_m.shape == (n_e, len(sp3.sats), 3)
    # every P line of the file is one finite position (neither file has 0.000000 positions)
    p_lines = sum(1 for ln in path.read_text().splitlines() if ln.startswith("P"))
    assert np.isfinite(sp3.pos_m[..., 0]).sum() == p_lines
    # orbit radii of GNSS satellites: from ~23 200 km (perigee of the eccentric Galileo E14/E18)
    # to ~44 600 km (apogee of the QZSS quasi-zenith orbit, e = 0.075 at a = 42 164 km)
    r = np.linalg.norm(sp3.pos_m, axis=-1)
    assert np.nanmin(r) > 23.0e6
    assert np.nanmax(r) < 45.5e6
    assert sp3.summary()["n_epochs"] == n_e


def test_cod_printed_values(gnss_data: Path) -> None:
    sp3 = read_sp3(gnss_data / COD)
    h = sp3.header
    assert (h.version, h.pos_vel, h.agency, h.coordinate_system) == ("d", "P", "AIUB", "IGb14")
    assert (h.file_type, h.time_system, h.orbit_type, h.data_used) == ("M", "GPS", "FIT", "d+D")
    assert len(sp3.sats) == 117
    assert sp3.sats[:2] == ("G01", "G02")
    assert sp3.sats[-1] == "J03"
    assert sp3.t_gps_s[0] == calendar_gps_seconds(2021, 3, 19, 0, 0, 0)
    # line 'PG01  20538.194555  11867.640064  12051.184924    738.035739' (first epoch)
    g01 = sp3.sat_index("G01")
    np.testing.assert_allclose(
        sp3.pos_m[0, g01], [20538194.555, 11867640.064, 12051184.924], rtol=1e-15
    )
    assert sp3.clock_s[0, g01] == pytest.approx(738.035739e-6, rel=1e-15)
    # ++ accuracy exponents: 5 -> 2**5 mm; one satellite has 10 (1.024 m)
    assert sp3.header.accuracy_m[0] == 0.032
    assert sp3.header.base_pos_vel == 1.25
    assert sp3.header.base_clk_rate == 1.025
    # clocks written 999999.999999 are missing
    text = (gnss_data / COD).read_text()
    assert np.isnan(sp3.clock_s).sum() == text.count("999999.999999")
    assert sp3.vel_mps is None
    assert sp3.pos_sd_m is None


def test_nga_sp3a_with_velocities(gnss_data: Path) -> None:
    sp3 = read_sp3(gnss_data / NGA)
    assert (sp3.header.version, sp3.header.pos_vel, sp3.header.agency) == ("a", "V", "NGA")
    assert sp3.sats[:3] == ("G01", "G02", "G03")
    assert "G08" not in sp3.sats
    # 'P  1  18829.174521  13507.523267 -13215.249720     -2.670218'
    # 'V  1 -16658.679468  -1539.361524 -25226.490071      0.005752'
    np.testing.assert_allclose(sp3.pos_m[0, 0], [18829174.521, 13507523.267, -13215249.720])
    assert sp3.clock_s[0, 0] == pytest.approx(-2.670218e-6, rel=1e-15)
    assert sp3.vel_mps is not None
    assert sp3.clock_rate is not None
    np.testing.assert_allclose(sp3.vel_mps[0, 0], [-1665.8679468, -153.9361524, -2522.6490071])
    assert sp3.clock_rate[0, 0] == pytest.approx(0.005752e-10, rel=1e-12)
    # velocity agrees with the position difference over 5 min to ~0.1 % (orbit consistency)
    dp = (sp3.pos_m[1, 0] - sp3.pos_m[0, 0]) / 300.0
    v_mid = 0.5 * (sp3.vel_mps[0, 0] + sp3.vel_mps[1, 0])
    np.testing.assert_allclose(dp, v_mid, atol=2.0)


@pytest.mark.parametrize("name", SHARED_SP3)
def test_georinex_cross_check(gnss_data: Path, name: str) -> None:
    georinex = pytest.importorskip("georinex")
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = georinex.load_sp3(gnss_data / name, None)
    sp3 = read_sp3(gnss_data / name)
    theirs_sats = [f"G{int(s):02d}" if s[0].isdigit() else str(s) for s in ds.sv.values]
    assert tuple(theirs_sats) == sp3.sats
    from navtrack.timescale import gps_seconds

    np.testing.assert_array_equal(gps_seconds(ds.time.values), sp3.t_gps_s)
    pos = ds.position.values * 1e3
    np.testing.assert_allclose(sp3.pos_m, pos, rtol=1e-15, atol=0)
    clk = ds.clock.values
    expected = np.where(clk >= 999999.0, np.nan, clk * 1e-6)
    np.testing.assert_allclose(sp3.clock_s, expected, rtol=1e-15, atol=0)
    # NGA's file (SP3-a "V") carries velocities, CODE's ("P") does not.
    assert (sp3.vel_mps is not None) == (name == NGA)
    if sp3.vel_mps is not None:
        np.testing.assert_allclose(sp3.vel_mps, ds.velocity.values * 0.1, rtol=1e-15)


def test_bundled_cut_matches_full_file(gnss_data: Path) -> None:
    cut = read_sp3(sample_path(BUNDLED))
    full = read_sp3(gnss_data / COD)
    assert cut.header.n_epochs == 34
    assert cut.t_gps_s[0] == calendar_gps_seconds(2021, 3, 19, 10, 45, 0)
    assert cut.t_gps_s[-1] == calendar_gps_seconds(2021, 3, 19, 13, 30, 0)
    k = np.searchsorted(full.t_gps_s, cut.t_gps_s)
    np.testing.assert_array_equal(full.t_gps_s[k], cut.t_gps_s)
    np.testing.assert_array_equal(full.pos_m[k], cut.pos_m)
    np.testing.assert_array_equal(full.clock_s[k], cut.clock_s)
    # the SEPT observations (12:00-12:15) have >= 10 SP3 epochs on each side
    obs0, obs1 = (
        calendar_gps_seconds(2021, 3, 19, 12, 0, 0),
        calendar_gps_seconds(2021, 3, 19, 12, 15, 0),
    )
    assert (cut.t_gps_s < obs0).sum() >= 10
    assert (cut.t_gps_s > obs1).sum() >= 10


def _bundled_lines() -> list[str]:
    return sample_path(BUNDLED).read_text().splitlines(keepends=True)


def test_standard_deviations_and_flags(tmp_path: Path) -> None:
    lines = _bundled_lines()
    k = next(i for i, ln in enumerate(lines) if ln.startswith("PG05"))
    # SP3-d columns 62-63, 65-66, 68-69 x/y/z exponent, 71-73 clock exponent, 75 E, 76 P,
    # 79 M, 80 P (1-based)
    lines[k] = lines[k][:60].ljust(60) + "  5  6  7 120 EP  MP\n"
    path = tmp_path / "sd.sp3"
    path.write_text("".join(lines))
    sp3 = read_sp3(path)
    assert sp3.pos_sd_m is not None
    assert sp3.clock_sd_s is not None
    assert sp3.flags is not None
    s = sp3.sat_index("G05")
    np.testing.assert_allclose(sp3.pos_sd_m[0, s], [1.25**5 * 1e-3, 1.25**6 * 1e-3, 1.25**7 * 1e-3])
    assert sp3.clock_sd_s[0, s] == pytest.approx(1.025**120 * 1e-12)
    assert sp3.flags[0, s] == 1 | 2 | 4 | 8
    assert np.isnan(sp3.pos_sd_m[0, s + 1]).all()
    assert sp3.flags.sum() == 15


def test_zero_position_is_missing(tmp_path: Path) -> None:
    lines = _bundled_lines()
    k = next(i for i, ln in enumerate(lines) if ln.startswith("PE01"))
    lines[k] = "PE01      0.000000      0.000000      0.000000 999999.999999\n"
    path = tmp_path / "zero.sp3"
    path.write_text("".join(lines))
    sp3 = read_sp3(path)
    s = sp3.sat_index("E01")
    assert np.isnan(sp3.pos_m[0, s]).all()
    assert np.isnan(sp3.clock_s[0, s])
    assert np.isfinite(sp3.pos_m[1, s]).all()


def test_utc_time_system_converted(tmp_path: Path) -> None:
    lines = _bundled_lines()
    k = next(i for i, ln in enumerate(lines) if ln.startswith("%c"))
    lines[k] = lines[k][:9] + "UTC" + lines[k][12:]
    path = tmp_path / "utc.sp3"
    path.write_text("".join(lines))
    sp3 = read_sp3(path)
    assert sp3.header.time_system == "UTC"
    # 2021: GPST - UTC = 18 s (IERS Bulletin C)
    assert sp3.t_gps_s[0] == calendar_gps_seconds(2021, 3, 19, 10, 45, 18)


def test_gzip(tmp_path: Path) -> None:
    path = tmp_path / "cut.sp3.gz"
    path.write_bytes(gzip.compress(sample_path(BUNDLED).read_bytes()))
    np.testing.assert_array_equal(read_sp3(path).pos_m, read_sp3(sample_path(BUNDLED)).pos_m)


def test_truncated_file(tmp_path: Path) -> None:
    lines = _bundled_lines()
    path = tmp_path / "trunc.sp3"
    path.write_text("".join(lines[:-300]))  # cut inside an epoch
    with pytest.raises(FileFormatError, match=r"trunc\.sp3, line \d+: last epoch cut short"):
        read_sp3(path)


def test_a_trimmed_file_is_read_with_both_epoch_counts_named(tmp_path: Path) -> None:
    """Public files trimmed to fewer epochs keep their header's count (issue 30: a header of
    289 epochs over 73): read as found, with a warning."""
    lines = _bundled_lines()
    stars = [i for i, ln in enumerate(lines) if ln.startswith("*")]
    full = read_sp3(sample_path(BUNDLED))
    assert full.warnings == ()
    trimmed = tmp_path / "trimmed.sp3"
    trimmed.write_text("".join(lines[: stars[10]]) + "EOF\n")
    sp3 = read_sp3(trimmed)
    assert sp3.t_gps_s.size == 10
    assert sp3.warnings == ("header announces 34 epochs, the file holds 10; read as found",)
    np.testing.assert_array_equal(sp3.pos_m, full.pos_m[:10])
    no_eof = tmp_path / "no_eof.sp3"
    no_eof.write_text("".join(lines[: stars[10]]))  # whole epochs, no EOF line
    assert "and has no EOF line" in read_sp3(no_eof).warnings[0]


def test_garbage_in_data_line(tmp_path: Path) -> None:
    lines = _bundled_lines()
    k = next(i for i, ln in enumerate(lines) if ln.startswith("PG03"))
    lines[k] = "PG03  20538.1945xx  11867.640064  12051.184924    738.035739\n"
    path = tmp_path / "bad.sp3"
    path.write_text("".join(lines))
    with pytest.raises(FileFormatError, match=rf"bad\.sp3, line {k + 1}: unreadable"):
        read_sp3(path)


def test_unknown_satellite(tmp_path: Path) -> None:
    lines = _bundled_lines()
    k = next(i for i, ln in enumerate(lines) if ln.startswith("PG03"))
    lines[k] = "PX03" + lines[k][4:]
    path = tmp_path / "sat.sp3"
    path.write_text("".join(lines))
    with pytest.raises(FileFormatError, match=rf"line {k + 1}: satellite 'X03' not listed"):
        read_sp3(path)


def test_not_sp3(tmp_path: Path) -> None:
    with pytest.raises(FileFormatError, match="line 1: not an SP3 file"):
        read_sp3(sample_path("07590920.05n"))
    empty = tmp_path / "empty.sp3"
    empty.write_text("")
    with pytest.raises(FileFormatError, match="empty file"):
        read_sp3(empty)


def test_cli_rinex_info_on_sp3(capsys: pytest.CaptureFixture[str]) -> None:
    from navtrack.cli import main

    assert main(["rinex", "info", str(sample_path(BUNDLED))]) == 0
    out = capsys.readouterr().out
    assert "SP3-d" in out
    assert "epochs" in out


def _kepler_position(e: Mapping[str, float], t: float, mu: float) -> np.ndarray:
    """ECEF position from broadcast Keplerian elements (IS-GPS-200N table 20-IV)."""
    g = e.__getitem__  # a pandas row of the broadcast table
    omega_e = 7.2921151467e-5
    a = g("sqrta") ** 2
    tk = t - g("toe_gps_s")
    m = g("m0") + (np.sqrt(mu / a**3) + g("deltan")) * tk
    ecc = g("e")
    ea = m
    for _ in range(30):
        ea = m + ecc * np.sin(ea)
    nu = np.arctan2(np.sqrt(1 - ecc**2) * np.sin(ea), np.cos(ea) - ecc)
    phi = nu + g("omega")
    s2, c2 = np.sin(2 * phi), np.cos(2 * phi)
    u = phi + g("cus") * s2 + g("cuc") * c2
    r = a * (1 - ecc * np.cos(ea)) + g("crs") * s2 + g("crc") * c2
    inc = g("i0") + g("cis") * s2 + g("cic") * c2 + g("idot") * tk
    om = g("omega0") + (g("omegadot") - omega_e) * tk - omega_e * g("toe_sow")
    x, y = r * np.cos(u), r * np.sin(u)
    return np.array(
        [
            x * np.cos(om) - y * np.cos(inc) * np.sin(om),
            x * np.sin(om) + y * np.cos(inc) * np.cos(om),
            y * np.sin(inc),
        ]
    )


def test_sp3_agrees_with_broadcast_ephemeris(gnss_data: Path) -> None:
    # Two independent products read by two readers: CODE's precise orbits (SP3, centre of mass,
    # GPS time) and the SEPT receiver's broadcast ephemerides (RINEX nav, antenna phase
    # centre). Broadcast orbit errors are ~1 m (IS-GPS-200 URA 2 m) and the phase-centre
    # offsets ~1-2 m, so 12:00 GPST positions agree to a few metres and clocks to a few ns;
    # a unit, time-scale or field-order mistake in either reader would be kilometres off.
    from navtrack.gnss.rinex.nav import read_nav

    nav = read_nav(gnss_data / "cssrlib_sept/SEPT078M.21P")
    sp3 = read_sp3(sample_path(BUNDLED))
    t = calendar_gps_seconds(2021, 3, 19, 12, 0, 0)
    k = int(np.flatnonzero(sp3.t_gps_s == t)[0])
    mus = {"G": 3.986005e14, "J": 3.986005e14, "E": 3.986004418e14}  # IS-GPS-200, Galileo ICD
    n = 0
    for sys_letter, mu in mus.items():
        df = nav.ephemerides[sys_letter]
        for sat in sorted(set(df["sat"])):
            if sat not in sp3.sats or not np.isfinite(sp3.clock_s[k, sp3.sat_index(sat)]):
                continue
            rows = df[df["sat"] == sat]
            e = rows.iloc[int(np.argmin(np.abs(rows["toe_gps_s"] - t)))]
            d = _kepler_position(e, t, mu) - sp3.pos_m[k, sp3.sat_index(sat)]
            assert np.linalg.norm(d) < 5.0, sat
            dt = e["af0"] + e["af1"] * (t - e["toc_gps_s"]) - sp3.clock_s[k, sp3.sat_index(sat)]
            assert abs(dt) < 10e-9, sat
            n += 1
    assert n >= 25


@pytest.mark.parametrize("keep_chars", [30, 0])
def test_last_epoch_cut_short(tmp_path: Path, keep_chars: int) -> None:
    """A file cut inside its last epoch (no EOF line) is refused, naming the epoch or the line,
    whether the cut falls inside a P record (its y coordinate would read as -14044.3773 km)
    or between records (the last epoch's other satellites would read as missing)."""
    lines = _bundled_lines()
    last_epoch = max(k for k, ln in enumerate(lines) if ln.startswith("*"))
    k = last_epoch + 10
    path = tmp_path / "cut.sp3"
    path.write_text("".join(lines[:k]) + lines[k][:keep_chars])
    with pytest.raises(FileFormatError, match="cut short by the end of the file") as exc:
        read_sp3(path)
    assert exc.value.line == last_epoch + 1


def test_record_cut_inside_clock_field(tmp_path: Path) -> None:
    """All P records of the last epoch present, the last one cut inside its clock field."""
    lines = _bundled_lines()
    eof = next(k for k, ln in enumerate(lines) if ln.startswith("EOF"))
    path = tmp_path / "cut.sp3"
    path.write_text("".join(lines[: eof - 1]) + lines[eof - 1][:56])  # clock -1.963693 -> -1.9
    with pytest.raises(FileFormatError, match=r"cut\.sp3, line \d+: P record cut short") as exc:
        read_sp3(path)
    assert exc.value.line == eof
    path.write_text("".join(lines[:eof]))  # complete, only the EOF line missing: accepted
    assert read_sp3(path).implausible == ()


def test_implausible_position_flagged_and_excluded(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """One coordinate set to 999999999999 km: the record is named with its line, that satellite
    is missing at that epoch only, and single point positioning solves every epoch."""
    from navtrack.cli import main

    lines = _bundled_lines()
    star = [k for k, ln in enumerate(lines) if ln.startswith("*")]
    k = next(j for j in range(star[15], star[16]) if lines[j][1:4] == "G01")
    lines[k] = lines[k][:4] + "999999999999".rjust(14) + lines[k][18:]
    path = tmp_path / "bad.sp3"
    path.write_text("".join(lines))
    sp3 = read_sp3(path)
    full = read_sp3(sample_path(BUNDLED))
    assert [s.line for s in sp3.implausible] == [k + 1]
    assert "outside the 6500-50000 km orbit shell" in sp3.implausible[0].reason
    g01 = sp3.sat_index("G01")
    assert np.isnan(sp3.pos_m[15, g01]).all()
    assert np.isnan(sp3.clock_s[15, g01])
    keep = np.ones(sp3.pos_m.shape[:2], dtype=bool)
    keep[15, g01] = False
    np.testing.assert_array_equal(sp3.pos_m[keep], full.pos_m[keep])
    assert full.implausible == ()
    assert sp3.summary()["implausible_records"] == 1
    data = sample_path("SEPT078M_120.21O"), sample_path("SEPT078M.21P")
    assert main(["pos", *map(str, data), "--sp3", str(path), "--no-progress"]) == 0
    assert f"{path}, line {k + 1}: position 1e+12 km" in capsys.readouterr().err


def _shift_x(line: str, km: float) -> str:
    x = float(line[4:18]) + km
    return line[:4] + f"{x:14.6f}" + line[18:]


def test_jump_between_records_is_flagged_and_excluded(tmp_path: Path) -> None:
    """Issue 9, failure 9: a coordinate moved 3,000 km (still on the orbit shell) at one epoch
    is a jump no orbit makes in 5 minutes: that record is missing, with its line; a step from
    one epoch on (the orbit before and after disagree) excludes the satellite from the file.
    The real orbits of all 117 satellites (GPS to BeiDou GEO) raise nothing."""
    lines = _bundled_lines()
    star = [k for k, ln in enumerate(lines) if ln.startswith("*")] + [len(lines)]

    def record(epoch: int, sat: str) -> int:
        return next(j for j in range(star[epoch], star[epoch + 1]) if lines[j][1:4] == sat)

    full = read_sp3(sample_path(BUNDLED))
    assert full.implausible == ()
    one = lines.copy()
    k = record(15, "G01")
    one[k] = _shift_x(one[k], 3000.0)
    path = tmp_path / "jump.sp3"
    path.write_text("".join(one))
    sp3 = read_sp3(path)
    assert [s.line for s in sp3.implausible] == [k + 1]
    assert "jumps from the neighbouring records" in sp3.implausible[0].reason
    g01 = sp3.sat_index("G01")
    assert np.isnan(sp3.pos_m[15, g01]).all()
    assert np.isfinite(sp3.pos_m[[14, 16], g01]).all()
    step = lines.copy()
    for epoch in range(20, 34):
        j = record(epoch, "E11")
        step[j] = _shift_x(step[j], 3000.0)
    path.write_text("".join(step))
    sp3 = read_sp3(path)
    assert [s.line for s in sp3.implausible] == [record(20, "E11") + 1]
    assert "excluded from the whole file" in sp3.implausible[0].reason
    assert np.isnan(sp3.pos_m[:, sp3.sat_index("E11")]).all()
    assert np.isfinite(sp3.pos_m[:, g01]).all()
