"""Readers of real tracking data (Stone Soup demo files) and of the generic CSV layout."""

from __future__ import annotations

import csv
import datetime as dt
from pathlib import Path

import numpy as np
import pytest

from navtrack.errors import FileFormatError
from navtrack.io.tracks import (
    local_enu_to_geodetic,
    read_ais_csv,
    read_opensky_csv,
    read_track_csv,
    read_tracks,
    stale_repeats,
    to_local_enu,
)


@pytest.fixture(scope="module")
def tracking_data(shared_data: Path) -> Path:
    return shared_data / "tracking"


def _gps_s(t: dt.datetime, leap_s: float = 0.0) -> float:
    return (t - dt.datetime(1980, 1, 6)).total_seconds() + leap_s


def test_ais_reader_counts_and_bad_row(tracking_data: Path) -> None:
    path = tracking_data / "SolentAIS_20160112_130211.csv"
    # independent scan of the file with the csv module: rows and the one positive longitude
    with path.open() as fh:
        rows = list(csv.DictReader(fh))
    bad = [i + 2 for i, r in enumerate(rows) if float(r["Longitude_degrees"]) > 0]
    assert len(rows) == 18623
    assert len(bad) == 1
    det = read_ais_csv(path)
    assert len(det) == 18622
    assert det.bad_lines.tolist() == bad
    assert "median position" in det.bad_reasons[0]
    assert np.unique(det.id).size == 91
    assert np.all(np.diff(det.t_gps_s) >= 0)
    # first report 2016-01-12 13:02:11.218 UTC, GPST - UTC = 17 s in 2016
    assert det.t_gps_s[0] == pytest.approx(
        _gps_s(dt.datetime(2016, 1, 12, 13, 2, 11, 218000), 17.0), abs=1e-6
    )
    assert rows[0]["MMSI"] == det.id[0]
    assert det.speed_mps[0] == pytest.approx(5.9 * 1852 / 3600)
    en, _ref = to_local_enu(det)
    assert np.abs(en).max() < 60e3  # the Solent is smaller than 60 km around its median


def test_opensky_reader(tracking_data: Path) -> None:
    det = read_opensky_csv(tracking_data / "OpenSky_Plane_States.csv")
    assert len(det) == 6052
    assert len(det.bad_lines) == 0
    assert np.unique(det.id).size == 84
    assert np.unique(det.t_gps_s).size == 121
    # 1626098400 = 2021-07-12 14:00:00 UTC; GPST - UTC = 18 s
    assert det.t_gps_s[0] == pytest.approx(_gps_s(dt.datetime(2021, 7, 12, 14), 18.0))
    assert "callsign" in det.ignored_columns


def test_generic_csv_bad_rows_order_and_columns(tmp_path: Path) -> None:
    p = tmp_path / "d.csv"
    p.write_text(
        "time,lat,lon,id,colour\n"
        "2020-01-01T00:00:10Z,50.0,-1.0,a,red\n"
        "2020-01-01T00:00:00Z,50.001,-1.0,a,red\n"
        "2020-01-01T00:00:20Z,95.0,-1.0,a,red\n"
        "2020-01-01T00:00:30Z,north,-1.0,b,red\n"
        "not a time,50.0,-1.0,b,red\n"
        "2020-01-01T00:00:40Z,50.002,-1.001,b,red\n"
    )
    det = read_track_csv(p)
    assert len(det) == 3
    assert det.line.tolist() == [3, 2, 7]  # sorted by time, lines kept
    assert det.n_reordered == 1
    assert det.bad_lines.tolist() == [4, 5, 6]
    assert det.bad_reasons == (
        "latitude outside [-90, 90]",
        "latitude/longitude not a finite number",
        "time not readable",
    )
    assert det.ignored_columns == ("colour",)
    s = det.summary()
    assert s["bad rows skipped"] == 3


def test_generic_csv_xy_and_missing_columns(tmp_path: Path) -> None:
    p = tmp_path / "xy.csv"
    p.write_text("time,x_m,y_m\n2020-01-01T00:00:00Z,1.5,2.5\n")
    det = read_track_csv(p)
    en, ref = to_local_enu(det)
    np.testing.assert_allclose(en, [[1.5, 2.5]])
    assert np.isnan(ref[0])
    q = tmp_path / "bad.csv"
    q.write_text("time,east,north\n2020-01-01T00:00:00Z,1,2\n")
    with pytest.raises(FileFormatError, match=r"bad.csv, line 1: need columns lat, lon or x_m"):
        read_track_csv(q)
    e = tmp_path / "empty.csv"
    e.write_text("")
    with pytest.raises(FileFormatError, match="empty"):
        read_track_csv(e)
    with pytest.raises(FileFormatError, match="missing column"):
        read_ais_csv(p)


def test_velocity_from_speed_and_course(tracking_data: Path) -> None:
    from navtrack.io.tracks import velocity_local_enu

    det = read_ais_csv(tracking_data / "SolentAIS_20160112_130211.csv")
    v = velocity_local_enu(det)
    # first report: SOG 5.9 kn, COG 157.8 deg; 2 km from the reference the frames agree to 1e-3
    s = 5.9 * 1852 / 3600
    np.testing.assert_allclose(
        v[0], [s * np.sin(np.radians(157.8)), s * np.cos(np.radians(157.8))], atol=2e-3
    )
    # AIS "not available" course (360) gives NaN
    assert np.all(np.isnan(v[det.course_deg >= 360]))
    speed = np.hypot(v[:, 0], v[:, 1])
    ok = np.isfinite(speed)
    # rotating into the reference tangent plane drops the tiny vertical part (< 1e-4 relative)
    np.testing.assert_allclose(speed[ok], det.speed_mps[ok], rtol=1e-4)


def test_local_enu_round_trip(tmp_path: Path) -> None:
    # Property: local_enu_to_geodetic inverts to_local_enu (points 0-60 km from the reference,
    # where the tangent plane and the ellipsoid differ by up to ~280 m in height, which the
    # inverse must not turn into a horizontal error).
    rng = np.random.default_rng(7)
    lat = 50.8 + rng.uniform(-0.5, 0.5, 50)
    lon = -1.3 + rng.uniform(-0.5, 0.5, 50)
    f = tmp_path / "pts.csv"
    f.write_text(
        "time,lat,lon\n"
        + "".join(
            f"2020-01-01T00:00:{k:02d}Z,{a!r},{b!r}\n"
            for k, (a, b) in enumerate(zip(lat, lon, strict=True))
        )
    )
    det = read_track_csv(f)
    en, ref = to_local_enu(det)
    latlon = local_enu_to_geodetic(en, *ref)
    np.testing.assert_allclose(latlon[:, 0], det.lat_deg, atol=1e-9)
    np.testing.assert_allclose(latlon[:, 1], det.lon_deg, atol=1e-9)
    with pytest.raises(ValueError, match="en_m"):
        local_enu_to_geodetic(np.zeros((3, 3)), *ref)


def test_local_enu_inverse_matches_pymap3d_at_300_km(tmp_path: Path) -> None:
    # Oracle: pymap3d's geodetic2enu (an independent implementation of the same frame). Points
    # of the ellipsoid 300 km from references at three latitudes, eight azimuths: the tangent
    # plane lies up to 7 km above them there, and the inverse must bring each back to within
    # 1 mm along the reference's normal (setting up = 0 misplaces them by 330 m).
    pm = pytest.importorskip("pymap3d")
    for lat0, lon0 in ((50.8, -1.3), (10.0, 100.0), (-60.0, -170.0)):
        az = np.arange(0.0, 360.0, 45.0)
        lat, lon, _ = pm.aer2geodetic(az, 0.0, 300e3, lat0, lon0, 0.0)
        e, n, u = pm.geodetic2enu(lat, lon, 0.0, lat0, lon0, 0.0)
        assert np.all(u < -6000.0)  # the plane is far above the points: a real test
        latlon = local_enu_to_geodetic(np.stack([e, n], axis=1), lat0, lon0)
        back_e, back_n, _ = pm.geodetic2enu(latlon[:, 0], latlon[:, 1], 0.0, lat0, lon0, 0.0)
        np.testing.assert_allclose(back_e, e, atol=1e-3)
        np.testing.assert_allclose(back_n, n, atol=1e-3)
        np.testing.assert_allclose(latlon[:, 0], lat, atol=1e-8)  # 1e-8 deg: 1.1 mm
        dlon = (latlon[:, 1] - lon + 180.0) % 360.0 - 180.0  # (the -170 deg case crosses 180)
        np.testing.assert_allclose(dlon * np.cos(np.radians(lat)), 0.0, atol=1e-8)
        # the forward projection of the reader is the one pymap3d computes
        f = tmp_path / f"pts{lat0}.csv"
        f.write_text(
            "time,lat,lon\n"
            + "".join(
                f"2020-01-01T00:00:{k:02d}Z,{a!r},{b!r}\n"
                for k, (a, b) in enumerate(zip(lat.tolist(), lon.tolist(), strict=True))
            )
        )
        en, _ref = to_local_enu(read_track_csv(f), lat0, lon0)
        np.testing.assert_allclose(en, np.stack([e, n], axis=1), atol=1e-3)
    with pytest.raises(ValueError, match="horizon"):
        local_enu_to_geodetic(np.array([[1e7, 0.0]]), 50.0, 0.0)


def test_stale_repeats_are_moving_targets_repeating_a_position(shared_data: Path) -> None:
    # Hand case: a fast target repeats its position (stale), a moored ship repeats its own at
    # 0.2 m/s (not stale: a measurement), a target without speed (unknown: kept).
    t = np.array([0.0, 1.0, 2.0, 0.0, 180.0, 0.0, 5.0])
    pos = np.array([[0, 0], [0, 0], [250, 0], [900, 900], [900, 900], [5, 5], [5, 5]], float)
    speed = np.array([250.0, 250.0, 250.0, 0.2, 0.2, np.nan, np.nan])
    np.testing.assert_array_equal(
        stale_repeats(t, pos, speed), [False, True, False, False, False, False, False]
    )
    # OpenSky state vectors: the positions repeated while the aircraft flies on are found
    # alike with the ids hidden (the tracker's input) and within each id (the scoring truth)
    det = read_tracks(shared_data / "tracking" / "OpenSky_Plane_States.csv", "opensky")
    en, _ = to_local_enu(det)
    hidden = stale_repeats(det.t_gps_s, en, det.speed_mps)
    np.testing.assert_array_equal(hidden, stale_repeats(det.t_gps_s, en, det.speed_mps, det.id))
    assert 600 < hidden.sum() < 700  # 645 of 6052 state vectors


def _solent_cut(tracking_data: Path, n_rows: int = 2000) -> list[str]:
    """Header and the first ``n_rows`` rows of the Solent AIS file."""
    with (tracking_data / "SolentAIS_20160112_130211.csv").open() as fh:
        return [next(fh).rstrip("\n") for _ in range(n_rows + 1)]


def test_time_outlier_row_is_skipped_before_any_grid(tracking_data: Path, tmp_path: Path) -> None:
    # issue 9, failure 1: one AIS row dated 1916 among 2016 rows stretched the report grid over
    # a century; it is now a skipped row with a counted reason
    lines = _solent_cut(tracking_data)
    lines[1000] = "1916" + lines[1000][4:]
    p = tmp_path / "ais_1916.csv"
    p.write_text("\n".join(lines) + "\n")
    det = read_ais_csv(p)
    assert len(det) == 2000 - 1
    assert det.bad_lines.tolist() == [1001]
    assert det.summary()["bad row reasons"] == {"time more than 30 days from the median time": 1}
    assert det.t_gps_s[-1] - det.t_gps_s[0] < 3600
    assert len(read_ais_csv(p, max_time_days=None)) == 2000  # the check can be switched off
    g = tmp_path / "csv_1920.csv"
    g.write_text(
        "time,lat,lon\n"
        "2020-01-01T00:00:00Z,50.0,-1.0\n"
        "1920-01-01T00:00:10Z,50.0,-1.0\n"
        "2020-01-01T00:00:20Z,50.0,-1.0\n"
    )
    det = read_track_csv(g)
    assert det.bad_lines.tolist() == [3]
    assert det.line.tolist() == [2, 4]


def test_opensky_absurd_time_is_skipped(tracking_data: Path, tmp_path: Path) -> None:
    # issue 9, failure 10: an OpenSky time of 1e40 gave "Maximum allowed size exceeded"
    with (tracking_data / "OpenSky_Plane_States.csv").open() as fh:
        lines = [next(fh) for _ in range(51)]
    lines[20] = "1e40" + lines[20][lines[20].index(",") :]
    p = tmp_path / "os.csv"
    p.write_text("".join(lines))
    det = read_opensky_csv(p)
    assert len(det) == 49
    assert det.bad_lines.tolist() == [21]
    assert "median time" in det.bad_reasons[0]


@pytest.mark.parametrize(
    ("content", "line", "what"),
    [
        (b"\x1f\x8b\x08\x00" + bytes(range(256)), None, "gzip-compressed"),
        (b"time,lat,lon\n2020-01-01T00:00:00Z,50\x00,-1\n", 2, "binary content"),
        (b'  [{"time": "2020-01-01T00:00:00Z", "lat": 50.0}]\n', 1, "JSON content"),
        (
            b"time,lat,lon,id\n2020-01-01T00:00:00Z,50,-1,a\n2020-01-01T00:00:01Z,50,-1,\xe9\n",
            3,
            "byte 0xe9 is not UTF-8",
        ),
    ],
)
def test_content_that_is_not_a_utf8_csv_is_refused(
    tmp_path: Path, content: bytes, line: int | None, what: str
) -> None:
    # issue 9, failures 2 and 4: a gzipped JSON file hung in pandas' header parsing, a byte
    # that is not UTF-8 raised UnicodeDecodeError; both now name the file (and line)
    p = tmp_path / "input.csv"
    p.write_bytes(content)
    with pytest.raises(FileFormatError, match=what) as info:
        read_track_csv(p)
    assert info.value.path == str(p)
    assert info.value.line == line


def test_utf8_bom_is_read(tmp_path: Path) -> None:
    p = tmp_path / "bom.csv"
    p.write_bytes(b"\xef\xbb\xbftime,lat,lon\n2020-01-01T00:00:00Z,50,-1\n")
    assert len(read_track_csv(p)) == 1
    p.write_bytes(b"\xef\xbb\xbftime,lat,lon\n2020-01-01T00:00:00Z,50,\xff\n")
    with pytest.raises(FileFormatError, match="0xff") as info:
        read_track_csv(p)
    assert info.value.line == 2


def test_last_row_cut_mid_line_is_not_data(tracking_data: Path, tmp_path: Path) -> None:
    # issue 9, failure 10: a file cut after the longitude's "-1" gave a detection at -1 deg
    lines = _solent_cut(tracking_data, 100)
    cut = lines[-1][: lines[-1].index(",-1.") + 3]
    p = tmp_path / "cut.csv"
    p.write_text("\n".join([*lines[:-1], cut]))
    det = read_ais_csv(p)
    assert len(det) == 99
    assert det.bad_lines.tolist() == [101]
    assert "cut by the end of the file" in det.bad_reasons[0]
    # a last row with all its fields but no line end may have a field cut short ("5.9" -> "5."):
    # reported, not data (issue 34)
    p.write_text("\n".join(lines))
    det = read_ais_csv(p)
    assert len(det) == 99
    assert det.bad_lines.tolist() == [101]
    p.write_text("\n".join(lines) + "\n")
    assert len(read_ais_csv(p)) == 100
