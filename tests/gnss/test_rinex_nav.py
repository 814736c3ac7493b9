"""RINEX navigation reader: every shared file, georinex cross-check, traps, bad input.

Expected values are copied from the printed text of the files (line numbers given) or computed
from the standards (GPS/BDT week origins, IERS leap seconds); georinex 1.16.2 is the independent
reader for the field-by-field cross-check.
"""

from __future__ import annotations

import gzip
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from navtrack.data import sample_path
from navtrack.errors import FileFormatError
from navtrack.gnss.rinex.nav import NavData, read_nav
from navtrack.timescale import calendar_gps_seconds

TEST_DATA = Path(__file__).resolve().parents[1] / "data"

SHARED_NAV = (
    "rtklib_gsi0759/07590920.05n",
    "gpstk_arl1/arlm2000.15n",
    "cssrlib_sept/SEPT078M.21P",
    "gogps_yamatogawa/brdc0060.10n",
    "gogps_yamatogawa/yamatogawa_rover.nav",
    "google_gnsslogger/hour2350.16n",
)
LOCAL_NAV = (
    "BRDC00IGS_R_20230010000_01D_MN_cut.rnx",
    "ubloxrs_glo_convbin.19g",
    "spare_filled_nav3.rnx",
    "brdc0320_cut.16l",
    "ceda2100_cut.18e",
)
BUNDLED_NAV = ("07590920.05n", "SEPT078M.21P", "hour2350.16n")


def _record_starts(path: Path) -> int:
    """Number of records counted the plain way: lines after the header whose first columns
    hold a satellite (RINEX 3: letter in column 1; RINEX 2: PRN in columns 1-2)."""
    lines = path.read_text().splitlines()
    end = next(i for i, ln in enumerate(lines) if ln[60:].startswith("END OF HEADER"))
    v3 = float(lines[0][:9]) >= 3
    return sum(1 for ln in lines[end + 1 :] if (ln[:1].strip() if v3 else ln[:2].strip()))


@pytest.mark.parametrize("name", SHARED_NAV)
def test_shared_nav_file_reads(gnss_data: Path, name: str) -> None:
    path = gnss_data / name
    nav = read_nav(path)
    assert isinstance(nav, NavData)
    assert sum(len(df) for df in nav.ephemerides.values()) == _record_starts(path)
    assert nav.skipped == ()
    for df in nav.ephemerides.values():
        # rows sorted by (sat, toc)
        key = list(zip(df["sat"], df["toc_gps_s"], strict=True))
        assert key == sorted(key)
        assert not df[["toc_gps_s", "sqrta", "toe_gps_s", "af0"]].isna().any().any()
        # toe within half a week of toc after week resolution
        assert (np.abs(df["toe_gps_s"] - df["toc_gps_s"]) <= 302400).all()
    summary = nav.summary()
    assert summary["records_per_system"] == {s: len(df) for s, df in nav.ephemerides.items()}


@pytest.mark.parametrize("name", BUNDLED_NAV)
def test_bundled_nav_reads(name: str) -> None:
    nav = read_nav(sample_path(name))
    assert sum(len(df) for df in nav.ephemerides.values()) == _record_starts(sample_path(name))


# --- cross-check against georinex 1.16.2 -----------------------------------------------------

_KEPLER_COMMON = {
    "SVclockBias": "af0", "SVclockDrift": "af1", "SVclockDriftRate": "af2", "Crs": "crs",
    "DeltaN": "deltan", "M0": "m0", "Cuc": "cuc", "Eccentricity": "e", "Cus": "cus",
    "sqrtA": "sqrta", "Toe": "toe_sow", "Cic": "cic", "Omega0": "omega0", "Cis": "cis",
    "Io": "i0", "Crc": "crc", "omega": "omega", "OmegaDot": "omegadot", "IDOT": "idot",
}  # fmt: skip
_GEORINEX_NAMES = {
    "G": {**_KEPLER_COMMON, "IODE": "iode", "CodesL2": "codes_l2", "GPSWeek": "week",
          "L2Pflag": "l2p_flag", "SVacc": "sva_m", "health": "svh", "TGD": "tgd",
          "IODC": "iodc", "TransTime": "tot_sow", "FitIntvl": "fit_h"},
    "E": {**_KEPLER_COMMON, "IODnav": "iode", "DataSrc": "data_source", "GALWeek": "week",
          "SISA": "sva_m", "health": "svh", "BGDe5a": "bgd_e5a", "BGDe5b": "bgd_e5b",
          "TransTime": "tot_sow"},
    "C": {**_KEPLER_COMMON, "AODE": "iode", "BDTWeek": "week", "SVacc": "sva_m",
          "SatH1": "svh", "TGD1": "tgd1", "TGD2": "tgd2", "TransTime": "tot_sow",
          "AODC": "aodc"},
    # georinex 1.16.2 names the NavIC week "BDTWeek" and its accuracy "URA"
    "I": {**_KEPLER_COMMON, "IODEC": "iode", "BDTWeek": "week", "URA": "sva_m",
          "health": "svh", "TGD": "tgd", "TransTime": "tot_sow"},
    "R": {"SVclockBias": "taun", "SVrelFreqBias": "gamman", "MessageFrameTime": "tk_s",
          "X": "x_m", "dX": "vx_mps", "dX2": "ax_mps2", "health": "svh", "Y": "y_m",
          "dY": "vy_mps", "dY2": "ay_mps2", "FreqNum": "freq_num", "Z": "z_m", "dZ": "vz_mps",
          "dZ2": "az_mps2", "AgeOpInfo": "age_d"},
    "S": {"SVclockBias": "af0", "SVrelFreqBias": "af1", "MessageFrameTime": "tot_sow",
          "X": "x_m", "dX": "vx_mps", "dX2": "ax_mps2", "health": "svh", "Y": "y_m",
          "dY": "vy_mps", "dY2": "ay_mps2", "URA": "ura_m", "Z": "z_m", "dZ": "vz_mps",
          "dZ2": "az_mps2", "IODN": "iodn"},
}  # fmt: skip
_GEORINEX_NAMES["J"] = _GEORINEX_NAMES["G"]
# georinex 1.16.2 converts the GLONASS/SBAS state vector from km to m, as navtrack does.


def _written_epoch_s(sys_letter: str, toc_gps_s: np.ndarray) -> np.ndarray:
    """Back from GPST to the time scale the file writes the epoch in (what georinex keeps)."""
    from navtrack.timescale import gps_to_utc

    if sys_letter == "C":
        return toc_gps_s - 14.0
    if sys_letter == "R":
        return gps_to_utc(toc_gps_s)
    return toc_gps_s


def _georinex_cross_check(path: Path) -> int:
    georinex = pytest.importorskip("georinex")
    import warnings

    from navtrack.timescale import gps_seconds

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = georinex.load(path)
    nav = read_nav(path)
    t_written = gps_seconds(ds.time.values)
    checked = 0
    for sv in ds.sv.values:
        sat = str(sv)[:3]
        sys_letter = sat[0]
        df = nav.ephemerides[sys_letter]
        ours = df[df["sat"] == sat]
        ours_t = _written_epoch_s(sys_letter, ours["toc_gps_s"].to_numpy())
        names = _GEORINEX_NAMES[sys_letter]
        sub = ds.sel(sv=sv)
        for ti, t in enumerate(t_written):
            theirs = {n: float(sub[n].values[ti]) for n in names if n in sub}
            if all(math.isnan(v) for v in theirs.values()):
                continue  # no record of this satellite at this time
            candidates = ours[np.abs(ours_t - t) < 1e-3]
            assert len(candidates), f"{path.name}: {sat} at {ds.time.values[ti]} not read"

            def same(
                row: object, theirs: dict[str, float] = theirs, names: dict[str, str] = names
            ) -> bool:
                for n, v in theirs.items():
                    mine = float(row[names[n]])  # type: ignore[index]
                    if names[n] in ("svh", "iode", "iodc", "week") and mine == -1:
                        mine = math.nan  # blank integer field
                    if math.isnan(v) and math.isnan(mine):
                        continue
                    if not np.isclose(mine, v, rtol=1e-12, atol=1e-300):
                        return False
                return True

            assert any(same(row) for _, row in candidates.iterrows()), (
                f"{path.name}: {sat} at {ds.time.values[ti]} differs from georinex: "
                f"{theirs} vs {candidates.iloc[0].to_dict()}"
            )
            checked += 1
    return checked


@pytest.mark.parametrize("name", SHARED_NAV)
def test_georinex_cross_check_shared(gnss_data: Path, name: str) -> None:
    checked = _georinex_cross_check(gnss_data / name)
    assert checked > 0


@pytest.mark.parametrize("name", LOCAL_NAV)
def test_georinex_cross_check_local(name: str) -> None:
    checked = _georinex_cross_check(TEST_DATA / name)
    assert checked > 0


# --- traps -----------------------------------------------------------------------------------


def test_arl1_touching_header_fields_and_d_exponents(gnss_data: Path) -> None:
    # arlm2000.15n lines 3-5:
    #    .745058D-08 .711478D-08-.603921D-08-.384468D-08          ION ALPHA
    #    .901120D+05 .365063D+05-.664019D+04-.169091D+05          ION BETA
    #      -.931322574615D-09-.355271367880D-14   233472     1854 DELTA-UTC: A0,A1,T,W
    nav = read_nav(gnss_data / "gpstk_arl1/arlm2000.15n")
    np.testing.assert_array_equal(
        nav.iono["GPSA"], [0.745058e-8, 0.711478e-8, -0.603921e-8, -0.384468e-8]
    )
    np.testing.assert_array_equal(
        nav.iono["GPSB"], [0.901120e5, 0.365063e5, -0.664019e4, -0.169091e5]
    )
    assert nav.time_corrections["GPUT"][:4] == (
        -0.931322574615e-9,
        -0.355271367880e-14,
        233472,
        1854,
    )
    assert nav.leap_seconds == 17
    g02 = nav.ephemerides["G"].query("sat == 'G02'").iloc[0]
    # line 8: " 2 15  7 19  1 59 28.0  .579084269702D-03  .227373675443D-11  .000000000000D+00"
    assert g02["toc_gps_s"] == calendar_gps_seconds(2015, 7, 19, 1, 59, 28.0)
    assert g02["af0"] == 0.579084269702e-3
    assert g02["af1"] == 0.227373675443e-11
    assert g02["iode"] == 7  # line 9 .700000000000D+01
    assert g02["crs"] == -0.646250000000e2
    assert g02["sqrta"] == 0.515359719276e4  # line 10
    assert g02["week"] == 1854
    assert g02["fit_h"] == 4.0
    # GPS week 1854 starts 2015-07-19 (1854 * 7 days after 1980-01-06)
    assert g02["toe_gps_s"] == 1854 * 604800 + 7168.0


def test_future_only_ephemerides_are_kept(gnss_data: Path) -> None:
    # ARL1 observations span 00:00-00:59:30; the nav file starts at 01:59:28 and G10/G06 have
    # nothing before 14:00/19:59:44 (lines 792, 1128): the records are returned all the same.
    nav = read_nav(gnss_data / "gpstk_arl1/arlm2000.15n")
    g = nav.ephemerides["G"]
    assert g["toc_gps_s"].min() == calendar_gps_seconds(2015, 7, 19, 1, 59, 28.0)
    assert g.query("sat == 'G10'")["toc_gps_s"].min() == calendar_gps_seconds(2015, 7, 19, 14, 0, 0)
    assert g.query("sat == 'G06'")["toc_gps_s"].min() == calendar_gps_seconds(
        2015, 7, 19, 19, 59, 44
    )
    # SEPT: G02 and G12 have only toc 14:00 and 13:59:44 (lines 1339, 1347), 2 h after the data
    sept = read_nav(gnss_data / "cssrlib_sept/SEPT078M.21P").ephemerides["G"]
    assert list(sept.query("sat == 'G02'")["toc_gps_s"]) == [
        calendar_gps_seconds(2021, 3, 19, 14, 0, 0)
    ]
    assert list(sept.query("sat == 'G12'")["toc_gps_s"]) == [
        calendar_gps_seconds(2021, 3, 19, 13, 59, 44)
    ]


def test_sept_galileo_inav_and_fnav_both_kept(gnss_data: Path) -> None:
    nav = read_nav(gnss_data / "cssrlib_sept/SEPT078M.21P")
    e = nav.ephemerides["E"]
    # lines 371 and 379: two E01 records at 2021-03-19 10:50:00, data sources 516 (I/NAV,
    # bits 0, 2, 9) and 258 (F/NAV, bits 1, 8), af0 -.106872984907D-02 / -.106872949982D-02
    toc = calendar_gps_seconds(2021, 3, 19, 10, 50, 0)
    both = e[(e["sat"] == "E01") & (e["toc_gps_s"] == toc)]
    assert sorted(both["data_source"]) == [258, 516]
    inav = both[both["data_source"] == 516].iloc[0]
    fnav = both[both["data_source"] == 258].iloc[0]
    assert inav["af0"] == -0.106872984907e-2
    assert fnav["af0"] == -0.106872949982e-2
    assert inav["bgd_e5b"] == 0.232830643654e-9
    assert fnav["bgd_e5b"] == 0.0
    assert inav["line"] == 371
    assert fnav["line"] == 379
    # Galileo week in RINEX is aligned to GPS: 2149 for 2021-03-19
    assert set(e["week"]) == {2149}
    assert nav.iono["GAL"].tolist() == [0.4550e2, 0.5859e-1, 0.2228e-2]
    assert nav.iono["QZSB"].tolist() == [0.9011e5, -0.4915e5, -0.8520e6, -0.2163e7]
    assert nav.leap_seconds == 18


def test_selected_systems_only(gnss_data: Path) -> None:
    path = gnss_data / "cssrlib_sept/SEPT078M.21P"
    full = read_nav(path)
    ge = read_nav(path, systems="ge")
    assert set(full.ephemerides) > {"G", "E"}
    assert set(ge.ephemerides) == {"G", "E"}
    for s in "GE":
        pd.testing.assert_frame_equal(ge.ephemerides[s], full.ephemerides[s])
    assert ge.iono.keys() == full.iono.keys()  # the header is read whole
    # a RINEX 2 file holds one system: all of it or nothing
    gps2 = sample_path("07590920.05n")
    assert len(read_nav(gps2, systems="G").ephemerides["G"]) == _record_starts(gps2)
    assert read_nav(gps2, systems="E").ephemerides == {}


def test_old_galileo_records() -> None:
    # brdc0320.16l (2016, RINEX 3.03 Galileo, georinex test data): data source 513, unknown
    # transmission time written as 9.999e8, SISA 0 (no accuracy prediction)
    e = read_nav(TEST_DATA / "brdc0320_cut.16l").ephemerides["E"]
    assert list(e["data_source"]) == [513, 513]
    assert list(e["tot_sow"]) == [9.999e8, 9.999e8]
    assert list(e["week"]) == [1882, 1882]
    assert e["toe_gps_s"].iloc[0] == 1882 * 604800 + 84000.0
    # RINEX 2.12 Galileo file written by teqc: ION ALPHA holds ai0-ai2
    nav = read_nav(TEST_DATA / "ceda2100_cut.18e")
    assert nav.iono["GAL"].tolist() == [4.9250e1, 2.0703e-1, 4.0283e-3]
    assert list(nav.ephemerides["E"]["sat"]) == ["E05", "E18", "E27"]


def test_all_systems_rinex3() -> None:
    # IGS merged broadcast file of 2023-01-01 (RINEX 3.05); values as printed (cut line numbers)
    nav = read_nav(TEST_DATA / "BRDC00IGS_R_20230010000_01D_MN_cut.rnx")
    assert nav.systems == "GRECJSI"
    # BeiDou C01 (GEO), lines 97-104: 2023-01-01 00:00:00 BDT = 00:00:14 GPST; BDT week 887
    # = GPS 2243; toe 0 s of the BDT week
    c01 = nav.ephemerides["C"].iloc[0]
    assert c01["sat"] == "C01"
    assert c01["toc_gps_s"] == calendar_gps_seconds(2023, 1, 1, 0, 0, 14)
    assert c01["week"] == 887
    assert c01["toe_gps_s"] == (887 + 1356) * 604800 + 0.0 + 14
    assert (c01["tgd1"], c01["tgd2"]) == (-4.699999944790e-09, -1.0e-08)
    # GLONASS R01, lines 161-165: 2022-12-31 23:45:00 UTC -> GPST + 18 s (IERS); km -> m;
    # -TauN as written; the RINEX 3.05 fifth line: status blank, delta tau 0.999999999999e9
    # written without its leading zero, URAI 15
    r01 = nav.ephemerides["R"].iloc[0]
    assert r01["toc_gps_s"] == calendar_gps_seconds(2022, 12, 31, 23, 45, 18)
    assert r01["taun"] == 2.048257738352e-05
    assert r01["x_m"] == pytest.approx(1.403724853516e04 * 1000, rel=1e-15)
    assert r01["vy_mps"] == pytest.approx(7.833652496338e-01 * 1000, rel=1e-15)
    assert r01["az_mps2"] == pytest.approx(2.793967723846e-09 * 1000, rel=1e-15)
    assert r01["freq_num"] == 1
    assert (r01["status_flags"], r01["delta_taun_s"], r01["urai"]) == (-1, 0.999999999999e09, 15)
    assert list(nav.ephemerides["R"]["freq_num"]) == [1, -4]
    # SBAS S22/S23, lines 171-178: GPS time, IODN in the last field
    s = nav.ephemerides["S"]
    assert list(s["sat"]) == ["S22", "S23"]
    assert s["toc_gps_s"].iloc[0] == calendar_gps_seconds(2023, 1, 1, 0, 1, 4)
    assert list(s["iodn"]) == [254, 160]
    assert list(s["ura_m"]) == [32767.0, 32767.0]
    assert s["x_m"].iloc[0] == pytest.approx(-3.389392800000e04 * 1000, rel=1e-15)
    # NavIC I02, lines 137-144: blank spare fields between written ones
    i02 = nav.ephemerides["I"].iloc[0]
    assert i02["week"] == 2242
    assert i02["sva_m"] == 2.0
    assert i02["tgd"] == -1.862645149230e-09
    assert i02["toc_gps_s"] == calendar_gps_seconds(2022, 12, 31, 23, 50, 24)
    # GPS G01, lines 121-136: the second record's last line holds all four fields
    g = nav.ephemerides["G"]
    assert list(g["iodc"]) == [79, 81]
    assert list(g["fit_h"]) == [4.0, 4.0]
    assert g["tot_sow"].iloc[1] == 6.0
    assert nav.time_corrections["BDUT"][:4] == (-4.6566128731e-09, 9.769962617e-15, 604745, 886)
    assert set(nav.iono) == {"GPSA", "GPSB", "GAL", "BDSA", "BDSB", "IRNA", "IRNB"}
    assert nav.leap_seconds == 18


def test_rinex2_glonass_two_digit_year() -> None:
    # RINEX 2.11 GLONASS file written by RTKLIB's convbin, values without a leading zero
    nav = read_nav(TEST_DATA / "ubloxrs_glo_convbin.19g")
    r = nav.ephemerides["R"]
    assert list(r["sat"]) == ["R02", "R03", "R12"]
    # line 6, "12 19 11 26 21 45 00.0": 2019-11-26 21:45 UTC; no LEAP SECONDS record, so the
    # IERS count of that date (18 s) gives GPST
    assert nav.leap_seconds is None
    assert r["toc_gps_s"].iloc[2] == calendar_gps_seconds(2019, 11, 26, 21, 45, 18)
    assert list(r["tk_s"]) == [77910.0] * 3
    assert r["taun"].iloc[2] == 0.827098265290e-04
    assert r["z_m"].iloc[2] == pytest.approx(0.168744916992e05 * 1000, rel=1e-15)
    assert r["vy_mps"].iloc[2] == pytest.approx(0.209329700470e01 * 1000, rel=1e-15)
    assert list(r["freq_num"]) == [-4, 5, -1]


def test_mixed_prn_formats_and_spare_fields() -> None:
    # "G 1" and "G01" are the same satellite; trailing spares filled or absent
    g = read_nav(TEST_DATA / "spare_filled_nav3.rnx").ephemerides["G"]
    assert list(g["sat"]) == ["G01", "G01", "G04", "G04"]
    assert list(g["iodc"]) == [72, 73, 959, 960]


def test_rinex2_sbas_file(tmp_path: Path) -> None:
    # RINEX 2.11 'H' layout (3X,4D19.12), values of record S22 of the DLR file
    text = (
        f"{'     2.11           H: GEO NAV MSG DATA':<60}RINEX VERSION / TYPE\n"
        f"{'':<60}END OF HEADER\n"
        "22 23  3 14  0  0 48.0 0.000000000000D+00 0.000000000000D+00 1.728670000000D+05\n"
        "   -3.389392800000D+04 0.000000000000D+00 0.000000000000D+00 1.000000000000D+00\n"
        "    2.508018800000D+04 0.000000000000D+00 0.000000000000D+00 3.276700000000D+04\n"
        "    0.000000000000D+00 0.000000000000D+00 0.000000000000D+00 3.000000000000D+00\n"
    )
    path = tmp_path / "sbas.23h"
    path.write_text(text)
    s = read_nav(path).ephemerides["S"]
    assert s["sat"].iloc[0] == "S22"
    assert s["toc_gps_s"].iloc[0] == calendar_gps_seconds(2023, 3, 14, 0, 0, 48)
    assert s["iodn"].iloc[0] == 3
    assert s["tot_sow"].iloc[0] == 172867.0


def test_gzip_input(tmp_path: Path) -> None:
    src = sample_path("07590920.05n")
    gz = tmp_path / "07590920.05n.gz"
    gz.write_bytes(gzip.compress(src.read_bytes()))
    a, b = read_nav(src).ephemerides["G"], read_nav(gz).ephemerides["G"]
    assert a.equals(b)


def test_result_is_read_only() -> None:
    nav = read_nav(sample_path("07590920.05n"))
    with pytest.raises(ValueError, match="read-only"):
        nav.iono["GPSA"][0] = 1.0
    with pytest.raises(TypeError):
        nav.ephemerides["X"] = None  # type: ignore[index]


# --- bad input -------------------------------------------------------------------------------


def _sample_lines() -> list[str]:
    return sample_path("07590920.05n").read_text().splitlines(keepends=True)


def test_truncated_record(tmp_path: Path) -> None:
    lines = _sample_lines()
    path = tmp_path / "trunc.05n"
    path.write_text("".join(lines[:-3]))
    last_start = max(i for i, ln in enumerate(lines) if ln[:2].strip()) + 1
    with pytest.raises(FileFormatError, match=r"trunc\.05n, line \d+: truncated G record") as exc:
        read_nav(path)
    assert exc.value.line == last_start
    nav = read_nav(path, lenient=True)
    assert len(nav.skipped) == 1
    assert nav.skipped[0].line == last_start
    assert len(nav.ephemerides["G"]) == _record_starts(sample_path("07590920.05n")) - 1


def test_missing_end_of_header(tmp_path: Path) -> None:
    lines = [ln for ln in _sample_lines()[:12] if "END OF HEADER" not in ln]
    path = tmp_path / "noend.05n"
    path.write_text("".join(lines))
    with pytest.raises(FileFormatError, match=r"noend\.05n, line 11: no END OF HEADER"):
        read_nav(path)


def test_garbage_file(tmp_path: Path) -> None:
    path = tmp_path / "garbage.05n"
    path.write_text("this is not a navigation file\nat all\n")
    with pytest.raises(FileFormatError, match=r"garbage\.05n, line 1: not a RINEX file"):
        read_nav(path)


def test_empty_file(tmp_path: Path) -> None:
    path = tmp_path / "empty.05n"
    path.write_text("")
    with pytest.raises(FileFormatError, match=r"empty\.05n, line 1: empty file"):
        read_nav(path)


def test_garbage_in_data_line(tmp_path: Path) -> None:
    lines = _sample_lines()
    k = 13  # line 14: second line of the first record (header is 12 lines)
    lines[k] = lines[k][:3] + "garbage!garbage!xxx" + lines[k][22:]
    path = tmp_path / "bad.05n"
    path.write_text("".join(lines))
    with pytest.raises(FileFormatError, match=r"bad\.05n, line 14: unreadable iode"):
        read_nav(path)
    nav = read_nav(path, lenient=True)
    assert [s.line for s in nav.skipped] == [13]


def test_unknown_system_letter(tmp_path: Path) -> None:
    lines = (TEST_DATA / "spare_filled_nav3.rnx").read_text().splitlines(keepends=True)
    k = next(i for i, ln in enumerate(lines) if ln.startswith("R21"))
    lines[k] = "X" + lines[k][1:]
    path = tmp_path / "unknown.rnx"
    path.write_text("".join(lines))
    with pytest.raises(FileFormatError, match=f"line {k + 1}: unknown satellite system letter 'X'"):
        read_nav(path)
    nav = read_nav(path, lenient=True)
    assert "R" not in nav.ephemerides
    assert len(nav.skipped) == 1


def test_observation_file_rejected() -> None:
    with pytest.raises(FileFormatError, match="line 1: not a RINEX navigation file"):
        read_nav(sample_path("07590920.05o"))


def test_cli_rinex_info_on_nav(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    import json

    from navtrack.cli import main

    out = tmp_path / "info.json"
    assert main(["rinex", "info", str(sample_path("SEPT078M.21P")), "--out", str(out)]) == 0
    # expected: record lines per system letter after END OF HEADER, counted plainly
    lines = sample_path("SEPT078M.21P").read_text().splitlines()
    end = next(i for i, ln in enumerate(lines) if "END OF HEADER" in ln)
    expected: dict[str, int] = {}
    for ln in lines[end + 1 :]:
        if ln[:1].strip():
            expected[ln[0]] = expected.get(ln[0], 0) + 1
    printed = capsys.readouterr().out
    assert "records_per_system" in printed
    assert f"G: {expected['G']}" in printed
    assert json.loads(out.read_text())["records_per_system"] == expected


def test_week_written_modulo_1024(tmp_path: Path) -> None:
    # 07590920.05n line 18 writes GPS week 1316 (2005-03-27); some writers give it modulo
    # 1024 (292): toe must come out the same, 1316 weeks + 525600 s (line 16)
    lines = _sample_lines()
    assert "1.316000000000D+03" in lines[17]
    lines[17] = lines[17].replace("1.316000000000D+03", "2.920000000000D+02")
    path = tmp_path / "rolled.05n"
    path.write_text("".join(lines))
    g = read_nav(path).ephemerides["G"]
    first = g[g["line"] == 13].iloc[0]
    assert first["week"] == 292
    assert first["toe_gps_s"] == 1316 * 604800 + 525600.0
    assert first["toe_gps_s"] == first["toc_gps_s"]


def test_rinex305_glonass_fifth_line(tmp_path: Path) -> None:
    # RINEX 3.05 table A10: optional BROADCAST ORBIT - 4 with status flags, L1/L2 group
    # delay difference, URAI and health flags
    lines = (TEST_DATA / "spare_filled_nav3.rnx").read_text().splitlines(keepends=True)
    k = next(i for i, ln in enumerate(lines) if ln.startswith("R21"))
    extra = "     1.790000000000E+02-1.862645149231E-09 2.000000000000E+00 0.000000000000E+00\n"
    lines.insert(k + 4, extra)
    path = tmp_path / "glo305.rnx"
    path.write_text("".join(lines))
    r = read_nav(path).ephemerides["R"].iloc[0]
    assert r["status_flags"] == 179
    assert r["delta_taun_s"] == -1.862645149231e-09
    assert r["urai"] == 2
    assert r["health_flags"] == 0
    assert r["z_m"] == pytest.approx(2.137510400391e04 * 1000, rel=1e-15)
    # a sixth line is one too many
    lines.insert(k + 5, extra)
    path.write_text("".join(lines))
    with pytest.raises(FileFormatError, match=f"line {k + 6}: R record has 6 lines"):
        read_nav(path)


def test_header_without_records(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A header and no records is an empty NavData; ``pos`` then says there are no ephemerides."""
    from navtrack.cli import main

    lines = _sample_lines()
    end = next(i for i, ln in enumerate(lines) if "END OF HEADER" in ln)
    path = tmp_path / "header_only.05n"
    path.write_text("".join(lines[: end + 1]))
    nav = read_nav(path)
    assert nav.tables == {}
    assert nav.systems == ""
    assert nav.leap_seconds == 13  # the header is still read
    assert main(["rinex", "info", str(path)]) == 0
    assert "records_per_system  none" in capsys.readouterr().out
    obs = sample_path("07590920.05o")
    assert main(["pos", str(obs), str(path), "--no-progress"]) == 1
    assert f"{path}: no ephemerides" in capsys.readouterr().err


@pytest.mark.parametrize("name", ["07590920.05n", "SEPT078M.21P"])
def test_file_cut_mid_line(tmp_path: Path, name: str) -> None:
    """A record line cut inside a field by the end of the file: an error naming the line
    (strict); in lenient reading that line and its record are skipped and counted."""
    raw = sample_path(name).read_bytes().rstrip()
    path = tmp_path / name
    path.write_bytes(
        raw[:-7]
    )  # the last field loses its exponent: '.000000000000D+00' -> '.0000000000'
    n_lines = raw.count(b"\n") + 1
    with pytest.raises(FileFormatError, match="cut in the middle of a field") as exc:
        read_nav(path)
    assert exc.value.line == n_lines
    nav = read_nav(path, lenient=True)
    assert [s.line for s in nav.skipped] == [n_lines - 7, n_lines]
    n_full = sum(len(t["sat"]) for t in read_nav(sample_path(name)).tables.values())
    assert sum(len(t["sat"]) for t in nav.tables.values()) == n_full - 1
    path.write_bytes(raw)  # no end-of-line after a complete last line
    assert read_nav(path).skipped == ()
