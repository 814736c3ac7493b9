"""``navtrack pos``: example run, outputs, summary, exit codes and bad input."""

from __future__ import annotations

import csv
import re
from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest

from navtrack.cli import main
from navtrack.data import sample_path
from navtrack.geodesy import ecef_to_geodetic
from navtrack.gnss.android import read_gnsslogger
from navtrack.gnss.rinex.nav import read_nav
from navtrack.gnss.rinex.obs import read_obs
from navtrack.gnss.spp import SppConfig, SppResult, solve_spp
from navtrack.io.solution import SOLUTION_COLUMNS

EXAMPLE_REF = np.array([-3962108.673, 3381309.574, 3668678.638])


@lru_cache(maxsize=1)
def _library_result() -> SppResult:
    """What ``navtrack pos --example`` must write: the library's solution of the same input
    with the command's defaults (systems GREJC, 15 deg mask, RTKLIB weighting, Klobuchar)."""
    obs = read_obs(sample_path("SEPT078M_120.21O"))
    nav = read_nav(sample_path("SEPT078M.21P"))
    return solve_spp(obs, [nav], config=SppConfig())


def test_example_prints_summary_and_writes_csv(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The CSV holds the library's solution: columns in the documented order, positions in
    ECEF metres and degrees to the written precision, times, satellites, DOPs and statuses."""
    out = tmp_path / "sept.csv"
    assert main(["pos", "--example", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "epochs         120" in text
    assert "solved         120" in text
    assert "error vs ref" in text
    assert "reference      -3962108.673 3381309.574 3668678.638 (ECEF m; station SEPT, " in text
    res = _library_result()
    lines = out.read_text().splitlines()
    sd = ["sdx_m", "sdy_m", "sdz_m", "sdxy_m", "sdyz_m", "sdzx_m"]
    vel = ["ve_mps", "vn_mps", "vu_mps", "drift_mps"]
    assert lines[0].split(",") == [*SOLUTION_COLUMNS, "gdop", "hdop", "vdop", *sd, "isb_E_m", *vel]
    rows = list(csv.DictReader(lines))
    assert len(rows) == 120

    def col(name: str) -> np.ndarray:
        return np.array([float(r[name]) for r in rows])

    assert [r["time_gps"] for r in rows[:2]] == [
        "2021-03-19T12:00:00.000",
        "2021-03-19T12:00:01.000",
    ]
    np.testing.assert_array_equal(col("week"), 2149)
    np.testing.assert_allclose(col("tow_s"), res.t_gps_s - 2149 * 604800.0, atol=5e-7)
    for k, name in enumerate(("x_m", "y_m", "z_m")):
        np.testing.assert_allclose(col(name), res.pos_m[:, k], rtol=0, atol=5e-5)
    llh = ecef_to_geodetic(res.pos_m)
    np.testing.assert_allclose(col("lat_deg"), np.degrees(llh[:, 0]), rtol=0, atol=5e-10)
    np.testing.assert_allclose(col("lon_deg"), np.degrees(llh[:, 1]), rtol=0, atol=5e-10)
    np.testing.assert_allclose(col("h_m"), llh[:, 2], rtol=0, atol=5e-5)
    np.testing.assert_allclose(col("clock_m"), res.clock_m, rtol=0, atol=5e-5)
    sd = np.sqrt(np.einsum("eii->ei", res.cov_enu_m2))
    for k, name in enumerate(("sd_e_m", "sd_n_m", "sd_u_m")):
        np.testing.assert_allclose(col(name), sd[:, k], rtol=0, atol=5e-5)
    np.testing.assert_array_equal(col("n_sats"), res.n_sats)
    np.testing.assert_allclose(col("pdop"), res.dop[:, 1], rtol=0, atol=5e-4)
    np.testing.assert_allclose(col("hdop"), res.dop[:, 2], rtol=1e-12)
    np.testing.assert_allclose(col("isb_E_m"), res.isb_m[:, 0], rtol=1e-12)
    assert {r["status"] for r in rows} == {"ok"}
    assert {r["excluded"] for r in rows} == {""}
    assert np.median(np.linalg.norm(res.pos_m - EXAMPLE_REF, axis=1)) < 3.0


def _ddmm(value: str, hemisphere: str, deg_digits: int) -> float:
    deg = float(value[:deg_digits]) + float(value[deg_digits:]) / 60.0
    return -deg if hemisphere in "SW" else deg


def test_track_formats(tmp_path: Path) -> None:
    """NMEA GGA, KML and GPX carry the library's 120 positions (to the written precision)."""
    res = _library_result()
    llh = ecef_to_geodetic(res.pos_m)
    lat, lon = np.degrees(llh[:, 0]), np.degrees(llh[:, 1])
    paths = {s: tmp_path / f"track{s}" for s in (".nmea", ".kml", ".gpx")}
    for path in paths.values():
        assert main(["pos", "--example", "--out", str(path)]) == 0

    gga = [ln for ln in paths[".nmea"].read_text().splitlines() if ln[3:6] == "GGA"]
    assert len(gga) == 120
    fields = [ln.split("*")[0].split(",") for ln in gga]
    assert fields[0][1] == "115942.00"  # 12:00:00 GPST = 11:59:42 UTC (18 leap seconds)
    nmea_lat = np.array([_ddmm(f[2], f[3], 2) for f in fields])
    nmea_lon = np.array([_ddmm(f[4], f[5], 3) for f in fields])
    np.testing.assert_allclose(nmea_lat, lat, rtol=0, atol=1e-8)  # 1e-6 arc minutes
    np.testing.assert_allclose(nmea_lon, lon, rtol=0, atol=1e-8)
    assert [int(f[7]) for f in fields] == res.n_sats.tolist()
    np.testing.assert_allclose([float(f[9]) for f in fields], llh[:, 2], rtol=0, atol=5e-4)
    assert {f[6] for f in fields} == {"1"}

    coords = re.findall(r"<gx:coord>(.*?)</gx:coord>", paths[".kml"].read_text())
    assert len(coords) == 120
    kml = np.array([[float(v) for v in c.split()[:2]] for c in coords])
    np.testing.assert_allclose(kml, np.stack([lon, lat], axis=1), rtol=0, atol=5e-10)

    pts = re.findall(
        r'<trkpt lat="([-\d.]+)" lon="([-\d.]+)"><ele>([-\d.]+)</ele>', paths[".gpx"].read_text()
    )
    gpx = np.array(pts, dtype=float)
    np.testing.assert_allclose(gpx, np.stack([lat, lon, llh[:, 2]], axis=1), rtol=0, atol=5e-5)


def test_plots(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("matplotlib")
    assert main(["pos", "--example", "--plot", str(tmp_path / "fig")]) == 0
    pngs = sorted(p.name for p in (tmp_path / "fig").glob("*.png"))
    assert "enu_error.png" in pngs
    assert "skyplot.png" in pngs


def test_rinex2_with_ref_llh(capsys: pytest.CaptureFixture[str]) -> None:
    rc = main(
        [
            "pos",
            str(sample_path("07590920.05o")),
            str(sample_path("07590920.05n")),
            "--ref-llh",
            "35.160867766",
            "139.613844940",
            "68.4545",
        ]
    )
    assert rc == 0
    text = capsys.readouterr().out
    assert "solved         115" in text
    assert "high_dop           5" in text


def test_nav_not_matching_exits_nonzero(capsys: pytest.CaptureFixture[str]) -> None:
    rc = main(["pos", str(sample_path("SEPT078M_120.21O")), str(sample_path("07590920.05n"))])
    assert rc == 1
    captured = capsys.readouterr()
    assert "no_ephemeris       120" in captured.out
    assert "NAV file matches the observation day" in captured.err


def test_lenient_skips_a_damaged_data_line_and_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A pseudorange field turned to letters stops a strict run with the file and line named;
    with --lenient that line is skipped, counted in a warning, and the rest solved."""
    lines = sample_path("SEPT078M_120.21O").read_text().splitlines(keepends=True)
    first_epoch = next(i for i, line in enumerate(lines) if line.startswith(">"))
    row = first_epoch + 1  # the first satellite's data line (0-based)
    lines[row] = lines[row][:3] + "   X.XXX ABC " + lines[row][15:]
    damaged = tmp_path / "damaged.21O"
    damaged.write_text("".join(lines))
    nav = str(sample_path("SEPT078M.21P"))
    assert main(["pos", str(damaged), nav]) == 2
    assert f"{damaged}:{row + 1}: malformed observation field" in capsys.readouterr().err
    assert main(["pos", str(damaged), nav, "--lenient", "--out", str(tmp_path / "x.csv")]) == 0
    err = capsys.readouterr().err
    assert f"1 damaged data lines skipped (first: line {row + 1}," in err
    solved = read_obs(damaged, lenient=True)
    assert solved.t_gps_s.size == 120


def _refused(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    """The error line of a command refused as bad input (exit 2, no traceback)."""
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert err.startswith("navtrack pos: error: ")
    return err


def test_reference_in_wrong_units_is_refused(capsys: pytest.CaptureFixture[str]) -> None:
    km = ["pos", "--example", "--ref", "-3962.108", "3381.309", "3668.678"]
    assert "ECEF metres" in _refused(km, capsys)
    llh = ["pos", "--example", "--ref-llh", "-3962108.6", "3381309.5", "3668678.6"]
    assert "degrees" in _refused(llh, capsys)


def test_unwritable_output_refused_before_reading(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A bad --out (missing directory, unknown suffix) exits 2 before the observations are
    read: the reader is replaced by one that fails the test if it is called."""
    import navtrack.gnss.rinex.obs

    def no_reading(*_: object, **__: object) -> None:
        raise AssertionError("the observations were read")

    monkeypatch.setattr(navtrack.gnss.rinex.obs, "read_obs", no_reading)
    for out, why in ((tmp_path / "missing" / "x.csv", "does not exist"), ("x.pos2", ".pos2")):
        message = _refused(["pos", "--example", "--out", str(out)], capsys)
        assert why in message


def test_missing_inputs(capsys: pytest.CaptureFixture[str]) -> None:
    obs, nav = str(sample_path("SEPT078M_120.21O")), str(sample_path("SEPT078M.21P"))
    assert "no navigation file" in _refused(["pos", obs], capsys)
    assert "not found" in _refused(["pos", "/nonexistent.21o", nav], capsys)
    assert "systems" in _refused(["pos", "--example", "--systems", "GXQ"], capsys)


def test_android_log(capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("navtrack.gnss.android")
    rc = main(
        [
            "pos",
            str(sample_path("pseudoranges_log_2016_08_22_14_45_50.txt")),
            str(sample_path("hour2350.16n")),
            "--systems",
            "G",
            "--ref-llh",
            "37.422578",
            "-122.081678",
            "-28",
        ]
    )
    assert rc == 0
    text = capsys.readouterr().out
    assert "weighting cn0" in text
    # every Raw row without an observation is counted with its reason
    obs = read_gnsslogger(sample_path("pseudoranges_log_2016_08_22_14_45_50.txt"))
    assert f"rows skipped   {len(obs.skipped)} (" in text
    line = next(ln for ln in text.splitlines() if ln.strip().startswith("3D"))
    assert float(line.split()[2]) <= 15.0  # 3D RMS


def test_android_prints_the_systems_solved(capsys: pytest.CaptureFixture[str]) -> None:
    # issue 9: with all systems allowed, the GPS-only navigation file solves GPS alone, and
    # the summary names the systems whose satellites entered a solution
    log = sample_path("pseudoranges_log_2016_08_22_14_45_50.txt")
    assert {s[0] for s in read_gnsslogger(log).sats} > {"G"}
    assert main(["pos", str(log), str(sample_path("hour2350.16n"))]) == 0
    assert "\nsystems        G  (" in capsys.readouterr().out


def test_long_files_are_solved_in_blocks(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Files longer than a block are solved block by block with a progress bar; the written
    solution equals the one-block solution."""
    import navtrack.gnss.spp as spp

    whole, blocks = tmp_path / "whole.csv", tmp_path / "blocks.csv"
    assert main(["pos", "--example", "--out", str(whole)]) == 0
    monkeypatch.setattr(spp, "CHUNK_EPOCHS", 25)
    assert main(["pos", "--example", "--out", str(blocks)]) == 0
    assert whole.read_text() == blocks.read_text()


def test_summary_median_equals_nanmedian_without_importing_numpy_ma() -> None:
    import subprocess
    import sys

    import numpy as np

    from navtrack.cli.pos_summary import median_finite

    rng = np.random.default_rng(0)
    for n in (1, 2, 5, 6, 101):
        x = np.append(rng.normal(size=n), [np.nan] * 3)
        assert median_finite(x) == np.nanmedian(x)
    assert np.isnan(median_finite(np.full(3, np.nan)))
    # a run without a reference (error percentiles use np.quantile, which imports numpy.ma)
    code = (
        "import sys; from navtrack.cli import main; from navtrack.data import sample_path; "
        "main(['pos', str(sample_path('07590920.05o')), str(sample_path('07590920.05n')), "
        "'--no-progress']); print('numpy.ma' in sys.modules, file=sys.stderr)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stderr.strip().splitlines()[-1] == "False"


def test_a_model_or_system_the_inputs_leave_out_is_a_warning(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Issue 34: ``--sp3`` without a navigation file switched the ionosphere off silently;
    ``--systems E`` on a GPS-only file said only ``too_few_sats``."""
    from navtrack.data import sample_path

    sept, sp3 = (
        sample_path("SEPT078M_120.21O"),
        sample_path("COD0MGXFIN_20210780000_01D_05M_ORB_1045-1330.SP3"),
    )
    assert main(["pos", str(sept), "--sp3", str(sp3), "--systems", "G", "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "warning        ionosphere not modelled: no navigation file" in out
    obs, nav = sample_path("07590920.05o"), sample_path("07590920.05n")
    assert main(["pos", str(obs), str(nav), "--systems", "E", "--no-progress"]) == 1
    out = capsys.readouterr().out
    assert "warning        --systems E: not in 07590920.05o (it holds G)" in out
    assert main(["pos", str(obs), str(nav), "--no-progress"]) == 0
    assert "not modelled" not in capsys.readouterr().out
