"""Solution writers and reader on a solution frame built from a real RTKLIB solution file (the
bundled 60-epoch cut of RTKLIB's SEPT solution, ``tests/data/sept078_gej_cut.pos``).

Oracles: the RTKLIB file's own text (times, coordinates), pymap3d (geodetic conversions), an
independent XOR checksum and pynmea2 (NMEA), xml.etree and gpxpy (GPX/KML), IERS Bulletin C
(GPST - UTC = 18 s since 2017-01-01).
"""

from __future__ import annotations

import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from functools import reduce
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from navtrack.io.rtklib import read_pos, to_solution_frame
from navtrack.io.solution import (
    SOLUTION_COLUMNS,
    nmea_checksums,
    read_solution,
    solution_table,
    write_solution,
)

GPX_NS = {"g": "http://www.topografix.com/GPX/1/1"}
KML_NS = {"k": "http://www.opengis.net/kml/2.2", "gx": "http://www.google.com/kml/ext/2.2"}
FAILED_ROWS = (3, 4, 10, 59)  # 59: the last epoch of the cut


@pytest.fixture(scope="module")
def sept_pos(sept_pos_cut: Path) -> pd.DataFrame:
    return read_pos(sept_pos_cut)


@pytest.fixture
def solution(sept_pos: pd.DataFrame) -> pd.DataFrame:
    """Solution frame of RTKLIB's SEPT GPS+Galileo+QZSS solution, with a few failed epochs."""
    df = to_solution_frame(sept_pos).drop(columns=["q"])
    status = df["status"].to_numpy(dtype=object)
    status[list(FAILED_ROWS)] = "too_few_sats"
    df["status"] = status
    for i in FAILED_ROWS:
        df.loc[i, ["x_m", "y_m", "z_m"]] = np.nan
    excluded = [""] * len(df)
    excluded[5] = "G05 E11"
    df["excluded"] = excluded
    df["pdop"] = np.linspace(1.2, 1.9, len(df))
    df["clock_m"] = np.linspace(-30.0, 30.0, len(df))
    return df


def test_csv_columns_and_text(solution: pd.DataFrame, tmp_path: Path) -> None:
    out = write_solution(solution, tmp_path / "sol.csv")
    lines = out.read_text().splitlines()
    assert lines[0].split(",")[: len(SOLUTION_COLUMNS)] == list(SOLUTION_COLUMNS)
    first = lines[1].split(",")
    # RTKLIB line: "2021/03/19 12:00:00.000  -3962107.8688   3381308.7654   3668677.9286 ..."
    # header: "obs start : 2021/03/19 12:00:00.0 GPST (week2149 475200.0s)".
    assert first[:6] == [
        "2021-03-19T12:00:00.000",
        "2149",
        "475200.0",
        "-3962107.8688",
        "3381308.7654",
        "3668677.9286",
    ]
    assert lines[1 + FAILED_ROWS[0]].split(",")[3:9] == [""] * 6
    assert lines[6].split(",")[16] == "G05 E11"
    assert len(lines) == 1 + len(solution)


def test_csv_round_trip(solution: pd.DataFrame, tmp_path: Path) -> None:
    pymap3d = pytest.importorskip("pymap3d")
    back = read_solution(write_solution(solution, tmp_path / "sol.csv"))
    assert list(back.columns[: len(SOLUTION_COLUMNS) + 1]) == ["t_gps_s", *SOLUTION_COLUMNS]
    np.testing.assert_allclose(back["t_gps_s"], solution["t_gps_s"], rtol=0, atol=1e-6)
    cols = ["x_m", "y_m", "z_m", "clock_m", "sd_e_m", "sd_n_m", "sd_u_m"]
    np.testing.assert_allclose(back[cols], solution[cols], rtol=0, atol=5e-5)
    np.testing.assert_allclose(back["pdop"], solution["pdop"], rtol=0, atol=5e-4)
    np.testing.assert_array_equal(back["n_sats"], solution["n_sats"])
    assert list(back["status"]) == list(solution["status"])
    assert list(back["excluded"]) == list(solution["excluded"])
    ok = solution["status"] == "ok"
    lat, lon, h = pymap3d.ecef2geodetic(*solution.loc[ok, ["x_m", "y_m", "z_m"]].to_numpy().T)
    np.testing.assert_allclose(back.loc[ok, "lat_deg"], lat, rtol=0, atol=1e-9)
    np.testing.assert_allclose(back.loc[ok, "lon_deg"], lon, rtol=0, atol=1e-9)
    np.testing.assert_allclose(back.loc[ok, "h_m"], h, rtol=0, atol=1e-4)


def test_parquet_round_trip_is_exact(solution: pd.DataFrame, tmp_path: Path) -> None:
    pytest.importorskip("pyarrow")
    back = read_solution(write_solution(solution, tmp_path / "sol.parquet"))
    np.testing.assert_array_equal(back["t_gps_s"], solution["t_gps_s"])
    np.testing.assert_array_equal(back[["x_m", "y_m", "z_m"]], solution[["x_m", "y_m", "z_m"]])
    assert list(back["status"]) == list(solution["status"])
    assert list(back["excluded"]) == list(solution["excluded"])


def test_geodetic_input_and_excluded_lists(sept_pos: pd.DataFrame, tmp_path: Path) -> None:
    pymap3d = pytest.importorskip("pymap3d")
    n = 20
    df = pd.DataFrame(
        {
            "t_gps_s": sept_pos["t_gps_s"][:n],
            "lat_deg": sept_pos["lat_deg"][:n],
            "lon_deg": sept_pos["lon_deg"][:n],
            "h_m": sept_pos["h_m"][:n],
            "status": ["ok"] * n,
            "excluded": [("G01", "J02")] + [()] * (n - 1),
        }
    )
    table = solution_table(df)
    x, _, z = pymap3d.geodetic2ecef(df["lat_deg"], df["lon_deg"], df["h_m"])
    np.testing.assert_allclose(table["x_m"], x, atol=1e-6)
    np.testing.assert_allclose(table["z_m"], z, atol=1e-6)
    assert table["excluded"].iloc[0] == "G01 J02"
    assert table["excluded"].iloc[1] == ""
    back = read_solution(write_solution(df, tmp_path / "llh.csv"))
    assert back["n_sats"].isna().all()
    assert back["excluded"].iloc[0] == "G01 J02"


def test_missing_columns_are_named(solution: pd.DataFrame, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="t_gps_s, status"):
        write_solution(solution.drop(columns=["t_gps_s", "status"]), tmp_path / "a.csv")
    with pytest.raises(ValueError, match="y_m"):
        write_solution(solution.drop(columns=["y_m"]), tmp_path / "a.csv")


def test_unwritable_and_unknown_paths(solution: pd.DataFrame, tmp_path: Path) -> None:
    target = tmp_path / "missing_dir" / "sol.csv"
    with pytest.raises(OSError, match="missing_dir") as info:
        write_solution(solution, target)
    assert str(target) in str(info.value)
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(OSError, match="file"):
        write_solution(solution, blocker / "sol.nmea")
    folder = tmp_path / "dir.gpx"
    folder.mkdir()
    with pytest.raises(IsADirectoryError, match=r"dir\.gpx"):
        write_solution(solution, folder)
    with pytest.raises(ValueError, match=r"\.txt"):
        write_solution(solution, tmp_path / "sol.txt")


def test_read_solution_detects_inconsistent_time(solution: pd.DataFrame, tmp_path: Path) -> None:
    out = write_solution(solution, tmp_path / "sol.csv")
    lines = out.read_text().splitlines(keepends=True)
    lines[7] = lines[7].replace("12:00:06.000", "12:00:07.000")
    out.write_text("".join(lines))
    with pytest.raises(ValueError, match="line 8"):
        read_solution(out)


# ---- NMEA ------------------------------------------------------------------------------------


def _xor(body: str) -> int:
    return reduce(lambda a, c: a ^ ord(c), body, 0)


def test_nmea_checksums_lengths_and_fields(solution: pd.DataFrame, tmp_path: Path) -> None:
    out = write_solution(solution, tmp_path / "sol.nmea")
    raw = out.read_bytes()
    assert raw.endswith(b"\r\n")
    sentences = raw.decode("ascii").split("\r\n")[:-1]
    assert len(sentences) == len(solution)
    for s in sentences:
        assert s.startswith("$GPGGA,")
        body, star, cs = s[1:].rpartition("*")
        assert star == "*"
        assert int(cs, 16) == _xor(body)
        assert len(s) + 2 <= 82  # NMEA 0183 maximum sentence length including CR LF
    # First epoch 2021-03-19 12:00:00 GPST = 11:59:42 UTC (GPST - UTC = 18 s).
    f = sentences[0].split(",")
    assert f[1] == "115942.00"
    assert f[6] == "1"
    assert f[7] == "21"  # ns of the RTKLIB line
    assert f[8] == "1.20"  # PDOP in the HDOP field (no hdop column)
    assert f[11:13] == ["0.0", "M"]
    bad = sentences[FAILED_ROWS[0]].split(",")
    assert bad[2:7] == ["", "", "", "", "0"]


def test_nmea_against_pynmea2(solution: pd.DataFrame, tmp_path: Path) -> None:
    pynmea2 = pytest.importorskip("pynmea2")
    sol = solution.assign(hdop=np.full(len(solution), 0.87))
    out = write_solution(sol, tmp_path / "sol.nmea", talker="GN")
    table = solution_table(sol)
    for i, line in enumerate(out.read_text().splitlines()):
        msg = pynmea2.parse(line, check=True)
        assert msg.talker == "GN"
        assert msg.sentence_type == "GGA"
        if i in FAILED_ROWS:
            assert msg.gps_qual == 0
            assert msg.lat == ""
            continue
        assert msg.gps_qual == 1
        assert float(msg.horizontal_dil) == 0.87
        assert msg.latitude == pytest.approx(table["lat_deg"][i], abs=2e-8)
        assert msg.longitude == pytest.approx(table["lon_deg"][i], abs=2e-8)
        assert float(msg.altitude) == pytest.approx(table["h_m"][i], abs=5e-4)
        utc = (pd.Timestamp(table["time_gps"][i]) - pd.Timedelta(seconds=18)).time()
        assert msg.timestamp.replace(tzinfo=None) == utc


def test_nmea_minute_carry_and_hemispheres(tmp_path: Path) -> None:
    # 0.99999999999 minutes short of 36 deg N must print 3600.000000, never 3560.000000.
    t0 = 1300000000.0
    df = pd.DataFrame(
        {
            "t_gps_s": [t0, t0 + 1],
            "lat_deg": [36.0 - 1e-11, -33.5],
            "lon_deg": [-(120.0 - 1e-11), 151.25],
            "h_m": [10.0, -5.25],
            "status": ["ok", "OK"],
            "n_sats": [9, 12],
        }
    )
    lines = write_solution(df, tmp_path / "c.nmea").read_text().splitlines()
    f0, f1 = lines[0].split(","), lines[1].split(",")
    assert f0[2:6] == ["3600.000000", "N", "12000.000000", "W"]
    assert f1[2:6] == ["3330.000000", "S", "15115.000000", "E"]
    assert f1[9] == "-5.250"
    assert f1[6] == "1"  # "OK" matches ok_status case-insensitively


def test_nmea_quality_from_rtklib_q(gnss_data: Path, tmp_path: Path) -> None:
    pos = read_pos(gnss_data / "gogps_yamatogawa" / "yamatogawa_rover_ref_rtklib_rtk_combined.pos")
    out = write_solution(to_solution_frame(pos), tmp_path / "rtk.nmea")
    qual = [int(s.split(",")[6]) for s in out.read_text().splitlines()]
    # NMEA 0183 GGA: 4 = RTK fixed integer, 5 = RTK float.
    np.testing.assert_array_equal(qual, np.where(pos["q"] == 1, 4, 5))
    assert set(qual) == {4, 5}


def test_checksum_function_against_xor() -> None:
    bodies = ["GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,", "A", ""]
    np.testing.assert_array_equal(nmea_checksums(bodies), [_xor(b) for b in bodies])
    # The sentence widely quoted in NMEA references: $GPGGA,123519,...,M,,*47
    assert nmea_checksums(bodies[:1])[0] == 0x47


# ---- GPX and KML -----------------------------------------------------------------------------


def test_gpx_structure_and_times(solution: pd.DataFrame, tmp_path: Path) -> None:
    out = write_solution(solution, tmp_path / "sol.gpx")
    root = ET.parse(out).getroot()
    assert root.tag == "{http://www.topografix.com/GPX/1/1}gpx"
    assert root.get("version") == "1.1"
    segs = root.findall("g:trk/g:trkseg", GPX_NS)
    # Failed rows 3, 4 (adjacent), 10 and the last one split the track into 3 segments.
    assert len(segs) == 3
    pts = root.findall("g:trk/g:trkseg/g:trkpt", GPX_NS)
    assert len(pts) == len(solution) - len(FAILED_ROWS)
    table = solution_table(solution)
    ok = np.flatnonzero(solution["status"] == "ok")
    lat = np.array([float(p.get("lat")) for p in pts])
    np.testing.assert_allclose(lat, table["lat_deg"].to_numpy()[ok], atol=1e-9)
    assert pts[0].find("g:time", GPX_NS).text == "2021-03-19T11:59:42.000Z"
    assert pts[0].find("g:sat", GPX_NS).text == "21"
    assert "4 without a valid position" in root.find("g:metadata/g:desc", GPX_NS).text


def test_gpx_with_gpxpy(solution: pd.DataFrame, tmp_path: Path) -> None:
    gpxpy = pytest.importorskip("gpxpy")
    out = write_solution(solution, tmp_path / "sol.gpx")
    gpx = gpxpy.parse(out.read_text())
    pts = [p for seg in gpx.tracks[0].segments for p in seg.points]
    assert len(pts) == len(solution) - len(FAILED_ROWS)
    ts = pd.Timestamp(pts[1].time).tz_convert(None)
    assert ts == pd.Timestamp("2021-03-19T11:59:43")
    assert pts[1].position_dilution == pytest.approx(solution["pdop"][1], abs=5e-3)
    assert pts[1].satellites == 21


def test_kml_structure(solution: pd.DataFrame, tmp_path: Path) -> None:
    out = write_solution(solution, tmp_path / "sol.kml")
    root = ET.parse(out).getroot()
    track = root.find("k:Document/k:Placemark/gx:Track", KML_NS)
    coords = [c.text for c in track.findall("gx:coord", KML_NS)]
    whens = [w.text for w in track.findall("k:when", KML_NS)]
    assert len(coords) == len(whens) == len(solution) - len(FAILED_ROWS)
    # time stamps in UTC: 12:00:01 GPST in 2021 is 11:59:43 UTC (18 leap seconds)
    assert pd.Timestamp(whens[1]).tz_convert(None) == pd.Timestamp("2021-03-19T11:59:43")
    lon, lat = map(float, coords[0].split()[:2])
    table = solution_table(solution)
    assert lon == pytest.approx(table["lon_deg"][0], abs=1e-9)
    assert lat == pytest.approx(table["lat_deg"][0], abs=1e-9)


def test_mapping_input_gives_the_same_files(solution: pd.DataFrame, tmp_path: Path) -> None:
    mapping = {name: solution[name].to_numpy() for name in solution.columns}
    mapping["excluded"] = [s.split() for s in solution["excluded"]]  # lists of ids
    for suffix in (".csv", ".nmea", ".gpx", ".kml"):
        a = write_solution(solution, tmp_path / f"frame{suffix}").read_bytes()
        b = write_solution(mapping, tmp_path / f"dict{suffix}").read_bytes()
        assert a == b, suffix


def test_writers_do_not_import_pandas(tmp_path: Path) -> None:
    # The positioning command is timed as a whole process; pandas alone costs ~0.25 s to import.
    code = (
        "import sys, numpy as np\n"
        "from navtrack.io.solution import write_solution\n"
        "d = {'t_gps_s': np.array([1.3e9, 1.3e9 + 1]), 'x_m': np.array([-3962107.0, np.nan]),\n"
        "     'y_m': np.array([3381308.0, np.nan]), 'z_m': np.array([3668677.0, np.nan]),\n"
        "     'status': np.array(['ok', 'too_few_sats']), 'n_sats': np.array([9, 3])}\n"
        f"for s in ('csv', 'nmea', 'kml', 'gpx'): write_solution(d, r'{tmp_path}/x.' + s)\n"
        "assert 'pandas' not in sys.modules, 'pandas imported'\n"
    )
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2] / "src")}
    subprocess.run([sys.executable, "-c", code], check=True, env=env)
    assert (tmp_path / "x.csv").read_text().splitlines()[2].endswith(",,,,,,,,3,,too_few_sats,")


def test_empty_and_single_epoch_frames(tmp_path: Path) -> None:
    import datetime as dt

    empty = {
        "t_gps_s": np.zeros(0),
        "x_m": np.zeros(0),
        "y_m": np.zeros(0),
        "z_m": np.zeros(0),
        "status": np.zeros(0, dtype=str),
    }
    for suffix in (".csv", ".nmea", ".kml", ".gpx"):
        out = write_solution(empty, tmp_path / f"empty{suffix}")
        if suffix in (".kml", ".gpx"):
            ET.parse(out)
    assert (tmp_path / "empty.nmea").read_text() == ""
    assert len(read_solution(tmp_path / "empty.csv")) == 0
    # One epoch 0.4 ms before a full second: time_gps rounds to the nearest millisecond.
    t = 1300000000.9996
    one = {
        "t_gps_s": [t],
        "x_m": [-3962107.0],
        "y_m": [3381308.0],
        "z_m": [3668677.0],
        "status": ["ok"],
    }
    back = read_solution(write_solution(one, tmp_path / "one.csv"))
    expected = dt.datetime(1980, 1, 6) + dt.timedelta(seconds=1300000001)
    assert back["time_gps"][0] == expected.isoformat() + ".000"
    assert back["t_gps_s"][0] == pytest.approx(t, abs=1e-6)
    root = ET.parse(write_solution(one, tmp_path / "one.kml")).getroot()
    assert len(root.findall("k:Document/k:Placemark/gx:Track/gx:coord", KML_NS)) == 1
    root = ET.parse(write_solution(one, tmp_path / "one.gpx")).getroot()
    assert len(root.findall("g:trk/g:trkseg/g:trkpt", GPX_NS)) == 1


def test_nmea_rmc_dates_against_pynmea2(solution: pd.DataFrame, tmp_path: Path) -> None:
    pynmea2 = pytest.importorskip("pynmea2")
    # Move the frame to just before a UTC midnight: 2021-03-19T23:59:58 UTC = ...:00:16 GPST.
    sol = solution.assign(t_gps_s=solution["t_gps_s"] - solution["t_gps_s"][0] + 1300233616.0)
    lines = write_solution(sol, tmp_path / "r.nmea", nmea_rmc=True).read_text().splitlines()
    assert len(lines) == 2 * len(sol)
    msgs = [pynmea2.parse(s, check=True) for s in lines]
    assert [m.sentence_type for m in msgs[:4]] == ["GGA", "RMC", "GGA", "RMC"]
    rmc = msgs[1::2]
    assert str(rmc[0].datestamp) == "2021-03-19"
    assert str(rmc[0].timestamp)[:8] == "23:59:58"
    assert str(rmc[2].datestamp) == "2021-03-20"  # two seconds later, the next UTC day
    assert str(rmc[2].timestamp)[:8] == "00:00:00"
    assert rmc[0].status == "A"
    assert rmc[FAILED_ROWS[0]].status == "V"
    assert rmc[0].latitude == pytest.approx(msgs[0].latitude, abs=1e-12)
    assert rmc[0].mode_indicator == "A"
    assert all(len(s) + 2 <= 82 for s in lines)


@settings(max_examples=60, deadline=None)
@given(
    lat=hnp.arrays(np.float64, 20, elements=st.floats(-89.999999, 89.999999)),
    lon=hnp.arrays(np.float64, 20, elements=st.floats(-179.999999, 179.999999)),
)
def test_nmea_angles_round_trip(lat: np.ndarray, lon: np.ndarray) -> None:
    # Property: ddmm.mmmmmm fields decode (independently, here) to the input within the
    # written resolution (0.5e-6 arc minute), with minutes always below 60.
    import tempfile

    n = lat.size
    df = {
        "t_gps_s": 1.3e9 + np.arange(n),
        "lat_deg": lat,
        "lon_deg": lon,
        "h_m": np.zeros(n),
        "status": np.array(["ok"] * n),
    }
    with tempfile.TemporaryDirectory() as tmp:
        lines = write_solution(df, Path(tmp) / "p.nmea").read_text().splitlines()
    for line, la, lo in zip(lines, lat, lon, strict=True):
        f = line.split(",")
        for field, hemi, width, want, neg in ((f[2], f[3], 2, la, "S"), (f[4], f[5], 3, lo, "W")):
            deg, minutes = int(field[:width]), float(field[width:])
            assert 0.0 <= minutes < 60.0
            assert len(field) == width + 9
            value = (deg + minutes / 60.0) * (-1 if hemi == neg else 1)
            assert abs(value - want) <= 0.5e-6 / 60.0 + 1e-12


def test_gpx_point_children_follow_schema_order(solution: pd.DataFrame, tmp_path: Path) -> None:
    # GPX 1.1 wptType is an xsd:sequence: ele, time, magvar, geoidheight, name, cmt, desc, src,
    # link, sym, type, fix, sat, hdop, vdop, pdop, ageofdgpsdata, dgpsid, extensions.
    order = [
        "ele",
        "time",
        "magvar",
        "geoidheight",
        "name",
        "cmt",
        "desc",
        "src",
        "link",
        "sym",
        "type",
        "fix",
        "sat",
        "hdop",
        "vdop",
        "pdop",
        "ageofdgpsdata",
        "dgpsid",
    ]
    sol = solution.assign(hdop=1.1, vdop=1.7)
    root = ET.parse(write_solution(sol, tmp_path / "o.gpx")).getroot()
    pt = root.find("g:trk/g:trkseg/g:trkpt", GPX_NS)
    tags = [child.tag.split("}")[1] for child in pt]
    assert tags == ["ele", "time", "geoidheight", "fix", "sat", "hdop", "vdop", "pdop"]
    assert [order.index(t) for t in tags] == sorted(order.index(t) for t in tags)
