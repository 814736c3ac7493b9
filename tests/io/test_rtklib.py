"""RTKLIB solution file reader on the shared RTKLIB outputs, on the bundled cut of one of them
(``tests/data/sept078_gej_cut.pos``, read without the shared data) and on re-written variants.

Oracles: the files' own header lines (``obs start ... (weekW T s)``), an independent plain-Python
parse of the data lines (datetime + float), pymap3d (geodetic/ENU conversions) for the llh, dms
and ENU variants, and IERS Bulletin C for the leap seconds (GPST - UTC = 17 s in July 2015).
"""

from __future__ import annotations

import datetime as dt
import re
from pathlib import Path

import numpy as np
import pytest

from navtrack.errors import FileFormatError
from navtrack.io.rtklib import read_pos, to_solution_frame

GPS_EPOCH = dt.datetime(1980, 1, 6)


def pos_files(gnss_data: Path) -> list[Path]:
    files = sorted((gnss_data / "rtklib_spp").glob("*.pos"))
    files.append(gnss_data / "gogps_yamatogawa" / "yamatogawa_rover_ref_rtklib_rtk_combined.pos")
    return files


def plain_parse(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """GPS seconds and numeric columns of every data line, parsed line by line."""
    times, values = [], []
    for line in path.read_text().splitlines():
        if not line.strip() or line.startswith("%"):
            continue
        tok = line.split()
        t = dt.datetime.strptime(tok[0] + " " + tok[1], "%Y/%m/%d %H:%M:%S.%f")
        times.append((t - GPS_EPOCH).total_seconds())
        values.append([float(v) for v in tok[2:]])
    return np.array(times), np.array(values)


def _matches_plain_parse_and_header(path: Path) -> int:
    """Check ``read_pos`` against the plain parse and the header's first epoch; return the rows."""
    df = read_pos(path)
    t, v = plain_parse(path)
    assert len(df) == len(t), path.name
    np.testing.assert_allclose(df["t_gps_s"], t, rtol=0, atol=1e-6, err_msg=path.name)
    np.testing.assert_array_equal(df[["x_m", "y_m", "z_m"]].to_numpy(), v[:, 0:3])
    np.testing.assert_array_equal(df["q"], v[:, 3].astype(int))
    np.testing.assert_array_equal(df["ns"], v[:, 4].astype(int))
    names = ["sdx_m", "sdy_m", "sdz_m", "sdxy_m", "sdyz_m", "sdzx_m", "age_s", "ratio"]
    np.testing.assert_array_equal(df[names].to_numpy(), v[:, 5:13])
    assert df["q"].dtype == np.int64
    assert df.attrs["time_scale"] == "GPST"
    # The header's first epoch in week/tow, an independent statement of the time.
    head = next(h for h in df.attrs["header"] if h.startswith("obs start"))
    m = re.search(r"week\s*(\d+)\s+([\d.]+)s", head)
    assert m is not None
    assert df["t_gps_s"].iloc[0] == pytest.approx(
        int(m.group(1)) * 604800 + float(m.group(2)), abs=1e-3
    )
    return len(df)


def test_every_shared_file_matches_plain_parse_and_header(gnss_data: Path) -> None:
    files = pos_files(gnss_data)
    assert len(files) == 16
    for path in files:
        assert _matches_plain_parse_and_header(path) > 100, path.name


def test_bundled_cut_matches_plain_parse_and_header(sept_pos_cut: Path) -> None:
    # As RTKLIB wrote them, header lines 1-5 and 12 end in LF, the other lines in CR LF.
    raw = sept_pos_cut.read_bytes().splitlines(keepends=True)
    assert [k for k, line in enumerate(raw, 1) if not line.endswith(b"\r\n")] == [1, 2, 3, 4, 5, 12]
    assert _matches_plain_parse_and_header(sept_pos_cut) == 60


def test_bundled_cut_is_the_head_of_the_shared_file(gnss_data: Path, sept_pos_cut: Path) -> None:
    full = (gnss_data / "rtklib_spp" / "sept078_gej.pos").read_bytes().splitlines(keepends=True)
    assert sept_pos_cut.read_bytes() == b"".join(full[:74])


def test_geodetic_columns_agree_with_pymap3d(sept_pos_cut: Path) -> None:
    pymap3d = pytest.importorskip("pymap3d")
    df = read_pos(sept_pos_cut)
    lat, lon, h = pymap3d.ecef2geodetic(df["x_m"], df["y_m"], df["z_m"])
    np.testing.assert_allclose(df["lat_deg"], lat, atol=1e-9)
    np.testing.assert_allclose(df["lon_deg"], lon, atol=1e-9)
    np.testing.assert_allclose(df["h_m"], h, atol=1e-4)


def test_reference_position_header(gnss_data: Path) -> None:
    path = gnss_data / "gogps_yamatogawa" / "yamatogawa_rover_ref_rtklib_rtk_combined.pos"
    df = read_pos(path)
    assert df.attrs["ref_xyz_m"] == (-3749943.5172, 3683398.2394, 3600629.5295)
    assert set(df["q"]) <= {1, 2}


# ---- re-written variants of a real file -----------------------------------------------------

ARL1_HEAD = "% program   : RTKLIB ver.2.4.3\n% obs start : 2015/07/19 00:00:00.0 GPST\n"


def _arl1(gnss_data: Path):
    return read_pos(gnss_data / "rtklib_spp" / "arl1_gps.pos"), plain_parse(
        gnss_data / "rtklib_spp" / "arl1_gps.pos"
    )


def test_week_tow_llh_variant(gnss_data: Path, tmp_path: Path) -> None:
    pymap3d = pytest.importorskip("pymap3d")
    ref, (t, v) = _arl1(gnss_data)
    lines = [
        ARL1_HEAD,
        "% (lat/lon/height=WGS84/ellipsoidal,Q=1:fix,2:float,3:sbas,4:dgps,5:single,6:ppp)\n",
        "%  GPST          latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   sde(m)   "
        "sdu(m)  sdne(m)  sdeu(m)  sdun(m) age(s)  ratio\n",
    ]
    for ti, vi in zip(t, v, strict=True):
        week, tow = divmod(ti, 604800.0)  # from the plain parse, not from navtrack
        lat, lon, h = pymap3d.ecef2geodetic(*vi[:3])
        lines.append(
            f"{int(week)} {tow:10.3f} {lat:14.9f} {lon:14.9f} {h:10.4f} {int(vi[3]):3d} "
            f"{int(vi[4]):3d} 1.0 2.0 3.0 0.5 -0.5 0.25 0.00 0.0\n"
        )
    f = tmp_path / "llh.pos"
    f.write_text("".join(lines))
    df = read_pos(f)
    np.testing.assert_allclose(df["t_gps_s"], t, atol=1e-6)
    # 1e-9 deg is 0.1 mm, the written resolution.
    np.testing.assert_allclose(df[["x_m", "y_m", "z_m"]], v[:, :3], atol=5e-4)
    assert list(df.columns[9:15]) == ["sdn_m", "sde_m", "sdu_m", "sdne_m", "sdeu_m", "sdun_m"]
    sol = to_solution_frame(df)
    np.testing.assert_array_equal(sol[["sd_e_m", "sd_n_m", "sd_u_m"]], [[2.0, 1.0, 3.0]] * len(t))
    np.testing.assert_allclose(ref["h_m"], df["h_m"], atol=1e-4)


def test_dms_utc_variant(gnss_data: Path, tmp_path: Path) -> None:
    pymap3d = pytest.importorskip("pymap3d")
    _, (t, v) = _arl1(gnss_data)
    lines = [
        ARL1_HEAD,
        "% (lat/lon/height=WGS84/ellipsoidal,Q=1:fix,2:float,3:sbas,4:dgps,5:single,6:ppp)\n",
        "%  UTC                   latitude(d'\")   longitude(d'\")  height(m)   Q  ns   sdn(m)   "
        "sde(m)   sdu(m)  sdne(m)  sdeu(m)  sdun(m) age(s)  ratio\n",
    ]
    for ti, vi in zip(t, v, strict=True):
        # GPST - UTC = 17 s from 2015-07-01 (IERS Bulletin C 49).
        utc = GPS_EPOCH + dt.timedelta(seconds=float(ti) - 17.0)
        lat, lon, h = pymap3d.ecef2geodetic(*vi[:3])

        def dms(a: float) -> str:
            s = "-" if a < 0 else ""
            a = abs(a)
            d = int(a)
            m = int((a - d) * 60)
            return f"{s}{d:d} {m:02d} {(a - d - m / 60) * 3600:9.6f}"

        lines.append(
            f"{utc:%Y/%m/%d %H:%M:%S}.000 {dms(lat)} {dms(lon)} {h:10.4f} 5 {int(vi[4])} "
            "1 1 1 0 0 0 0.00 0.0\n"
        )
    f = tmp_path / "dms.pos"
    f.write_text("".join(lines))
    df = read_pos(f)
    assert df.attrs["time_scale"] == "UTC"
    np.testing.assert_allclose(df["t_gps_s"], t, atol=1e-6)
    assert (df["lon_deg"] < -97).all()  # west: the sign of the degrees field is kept
    np.testing.assert_allclose(df[["x_m", "y_m", "z_m"]], v[:, :3], atol=5e-4)


def test_enu_baseline_variant(gnss_data: Path, tmp_path: Path) -> None:
    pymap3d = pytest.importorskip("pymap3d")
    path = gnss_data / "gogps_yamatogawa" / "yamatogawa_rover_ref_rtklib_rtk_combined.pos"
    t, v = plain_parse(path)
    ref = (-3749943.5172, 3683398.2394, 3600629.5295)
    lat0, lon0, h0 = pymap3d.ecef2geodetic(*ref)
    lines = [
        f"% ref pos   : {ref[0]:.4f} {ref[1]:.4f} {ref[2]:.4f}\n",
        "%  GPST                  e-baseline(m)  n-baseline(m)  u-baseline(m)   Q  ns   sde(m)   "
        "sdn(m)   sdu(m)  sden(m)  sdnu(m)  sdue(m) age(s)  ratio\n",
    ]
    text = path.read_text().splitlines()
    data = [ln for ln in text if ln.strip() and not ln.startswith("%")]
    enu = []
    for ln, vi in zip(data, v, strict=True):
        e, n, u = pymap3d.ecef2enu(*vi[:3], lat0, lon0, h0)
        enu.append((e, n, u))
        tok = ln.split()
        lines.append(f"{tok[0]} {tok[1]} {e:.4f} {n:.4f} {u:.4f} " + " ".join(tok[5:]) + "\n")
    f = tmp_path / "enu.pos"
    f.write_text("".join(lines))
    df = read_pos(f)
    np.testing.assert_allclose(df["t_gps_s"], t, atol=1e-6)
    # the baseline as written (4 decimals), and the ECEF position rebuilt from it
    np.testing.assert_allclose(df[["e_m", "n_m", "u_m"]], enu, atol=5.1e-5)
    np.testing.assert_allclose(df[["x_m", "y_m", "z_m"]], v[:, :3], atol=2e-4)


def test_to_solution_frame_rotates_covariance(sept_pos_cut: Path) -> None:
    pos = read_pos(sept_pos_cut)
    sol = to_solution_frame(pos)
    assert (sol["status"] == "ok").all()
    np.testing.assert_array_equal(sol["n_sats"], pos["ns"])
    # The trace of a covariance does not change under rotation.
    trace_xyz = (pos[["sdx_m", "sdy_m", "sdz_m"]].to_numpy() ** 2).sum(axis=1)
    trace_enu = (sol[["sd_e_m", "sd_n_m", "sd_u_m"]].to_numpy() ** 2).sum(axis=1)
    np.testing.assert_allclose(trace_enu, trace_xyz, rtol=1e-12)
    # Independent rotation: pymap3d's ENU axes applied to the rebuilt covariance.
    pymap3d = pytest.importorskip("pymap3d")
    r = pos.iloc[0]
    c = np.array(
        [
            [r.sdx_m**2, np.sign(r.sdxy_m) * r.sdxy_m**2, np.sign(r.sdzx_m) * r.sdzx_m**2],
            [np.sign(r.sdxy_m) * r.sdxy_m**2, r.sdy_m**2, np.sign(r.sdyz_m) * r.sdyz_m**2],
            [np.sign(r.sdzx_m) * r.sdzx_m**2, np.sign(r.sdyz_m) * r.sdyz_m**2, r.sdz_m**2],
        ]
    )
    axes = np.array(
        [pymap3d.ecef2enuv(*row, r.lat_deg, r.lon_deg) for row in np.eye(3)]
    ).T  # columns: images of the ECEF unit vectors
    sd = np.sqrt(np.diag(axes @ c @ axes.T))
    np.testing.assert_allclose(sol[["sd_e_m", "sd_n_m", "sd_u_m"]].iloc[0], sd, rtol=1e-10)


# ---- bad input ----------------------------------------------------------------------------


def _copy_with(path: Path, tmp_path: Path, lineno: int, new: str) -> Path:
    lines = path.read_text().splitlines(keepends=True)
    lines[lineno - 1] = new
    f = tmp_path / "bad.pos"
    f.write_text("".join(lines))
    return f


# Line 18 of the cut: "2021/03/19 12:00:03.000  -3962108.0650   3381308.8399   3668677.9471   5  21
# 2.5023   1.9529   1.9293  -1.7931   1.4931  -1.6529   0.00    0.0", damaged in one place each.
SIGMAS_18 = "   2.5023   1.9529   1.9293  -1.7931   1.4931  -1.6529   0.00    0.0\n"


@pytest.mark.parametrize(
    ("replacement", "message"),
    [
        (
            "2021/03/19 12:00:03.000  -3962108.0650   3381308.8399   3668677.9471   5  21\n",
            "expected 15 fields",
        ),
        (
            "2021/03/19 12:00:03.000  -3962108.0650   33813x8.8399   3668677.9471   5  21"
            + SIGMAS_18,
            "y-ecef",
        ),
        (
            "2021/03/19 12:00:03.000  -3962108.0650   3381308.8399   3668677.9471   5.5  21"
            + SIGMAS_18,
            "not an integer",
        ),
        (
            "2021/13/19 12:00:03.000  -3962108.0650   3381308.8399   3668677.9471   5  21"
            + SIGMAS_18,
            "time",
        ),
    ],
)
def test_bad_line_names_file_and_line(
    sept_pos_cut: Path, tmp_path: Path, replacement: str, message: str
) -> None:
    f = _copy_with(sept_pos_cut, tmp_path, 18, replacement)
    with pytest.raises(FileFormatError, match=message) as info:
        read_pos(f)
    assert info.value.line == 18
    assert info.value.path == str(f)
    assert f"{f}, line 18" in str(info.value)


def test_missing_column_header(tmp_path: Path) -> None:
    f = tmp_path / "nohead.pos"
    f.write_text("% program : x\n2015/07/19 00:00:00.000 1 2 3 5 6 0 0 0 0 0 0 0 0\n")
    with pytest.raises(FileFormatError, match="before the column header") as info:
        read_pos(f)
    assert info.value.line == 2


def test_geoid_heights_refused(tmp_path: Path) -> None:
    f = tmp_path / "geoid.pos"
    f.write_text(
        "% (lat/lon/height=WGS84/geodetic,Q=1:fix)\n"
        "%  GPST                  latitude(deg) longitude(deg)  height(m)   Q  ns\n"
        "2015/07/19 00:00:00.000 30.1 -97.2 200.0 5 6\n"
    )
    with pytest.raises(FileFormatError, match="geoid"):
        read_pos(f)


def test_extra_field_and_header_only(sept_pos_cut: Path, tmp_path: Path) -> None:
    lines = sept_pos_cut.read_text().splitlines(keepends=True)
    lines[40] = lines[40].rstrip("\n") + "   9.9\n"
    f = tmp_path / "extra.pos"
    f.write_text("".join(lines))
    with pytest.raises(FileFormatError, match="found 16") as info:
        read_pos(f)
    assert info.value.line == 41
    head_only = tmp_path / "head.pos"
    head_only.write_text("".join(lines[:14]))
    df = read_pos(head_only)
    assert len(df) == 0
    assert "sdzx_m" in df.columns


def test_dms_sign_near_zero_degrees(tmp_path: Path) -> None:
    f = tmp_path / "dms0.pos"
    f.write_text(
        "% (lat/lon/height=WGS84/ellipsoidal)\n"
        "%  GPST                  latitude(d'\")   longitude(d'\")  height(m)   Q  ns\n"
        "2015/07/19 00:00:00.000  -0 30 00.000   0 15 36.000   10.0   5   6\n"
    )
    df = read_pos(f)
    assert df["lat_deg"][0] == -0.5
    assert df["lon_deg"][0] == pytest.approx(0.26, abs=1e-12)  # 15' 36" = 0.26 deg
