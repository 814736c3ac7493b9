"""RINEX clock files: reader, interpolation, and their use for the satellite states."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from navtrack.errors import FileFormatError
from navtrack.gnss.precise import clock_interpolation_error, sp3_clock, sp3_states
from navtrack.gnss.rinex_clock import RinexClock, interpolate_clock, read_clock
from navtrack.gnss.sp3 import read_sp3
from navtrack.timescale import calendar_gps_seconds

C_MPS = 299792458.0

DATA = Path(__file__).parent / "data"
CLK = DATA / "WUM0MGXFIN_20230010000_30M_30S_CLK_cut.CLK"
SP3 = DATA / "WUM0MGXFIN_20230010000_30M_05M_ORB_cut.SP3"
T0 = calendar_gps_seconds(2023, 1, 1, 0, 0, 0.0)


def _record(sat: str, hh: int, mm: int, ss: int) -> float:
    """The clock value of one AS record, read from the file's text by the columns of the
    format (A2,1X,A4,1X,I4,4I3,F10.6,I3,2X,E19.12)."""
    stamp = f"2023{1:3d}{1:3d}{hh:3d}{mm:3d}{ss:10.6f}"
    for line in CLK.read_text().splitlines():
        if line.startswith(f"AS {sat}") and line[8:34] == stamp:
            return float(line[39:60])
    raise AssertionError(f"no record {sat} {stamp}")


def test_reads_the_satellite_records() -> None:
    clk = read_clock(CLK)
    assert clk.version == "3.00"
    assert clk.agency == "WHU"
    assert clk.time_system == "GPS"
    assert clk.interval_s == 30.0
    assert clk.sats == ("G05", "G13", "G15", "G18", "G23", "G29")
    np.testing.assert_allclose(clk.t_gps_s, T0 + 30.0 * np.arange(61))
    assert clk.record_counts["AS"] == 6 * 61
    k = clk.sats.index("G13")
    assert clk.clock_s[20, k] == _record("G13", 0, 10, 0)
    assert np.isnan(clk.sd_s).all()  # the file gives one value per record
    # the header lists 121 satellites: the cut holds six, read with a warning naming both
    assert any("announces 121 satellites" in w and "hold 6" in w for w in clk.warnings)


def test_sp3_and_clock_file_of_one_centre_agree_at_the_sp3_epochs() -> None:
    """WUM's SP3 clocks are its 30 s clocks at the 5-min epochs (both files, same solution)."""
    clk, sp3 = read_clock(CLK), read_sp3(SP3)
    # the trimmed SP3 keeps the whole day's header: read with a warning naming both counts
    assert sp3.warnings == ("header announces 288 epochs, the file holds 7; read as found",)
    k = np.searchsorted(clk.t_gps_s, sp3.t_gps_s)
    for sat in clk.sats:
        a = sp3.clock_s[:, sp3.sat_index(sat)]
        b = clk.clock_s[k, clk.sats.index(sat)]
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)  # SP3 writes 1e-12 s


def test_interpolation_is_linear_between_records() -> None:
    clk = read_clock(CLK)
    t = T0 + np.array([60.0, 75.0, 1800.0, 1815.0, -1.0])
    got = interpolate_clock(clk, "G05", t)
    a, b = _record("G05", 0, 1, 0), _record("G05", 0, 1, 30)
    assert got[0] == a
    assert got[1] == pytest.approx((a + b) / 2, abs=1e-18)
    assert got[2] == _record("G05", 0, 30, 0)
    assert np.isnan(got[3:]).all()  # past the last record, before the first
    assert np.isnan(interpolate_clock(clk, "E11", t)).all()


def test_interpolation_does_not_bridge_a_long_gap() -> None:
    clk = read_clock(CLK)
    t = T0 + np.array([45.0])
    assert np.isfinite(interpolate_clock(clk, "G05", t, max_span_s=30.0))
    # a record spacing of 30 s is longer than a 20 s span: no value
    assert np.isnan(interpolate_clock(clk, "G05", t, max_span_s=20.0)).all()


def test_satellite_states_take_the_attached_clock_file() -> None:
    clk, sp3 = read_clock(CLK), read_sp3(SP3)
    t = T0 + np.array([[100.0, 100.0], [917.0, 917.0]])
    sats = ["G05", "G23"]
    with_clk = sp3.with_clock(clk)
    for c, sat in enumerate(sats):
        np.testing.assert_array_equal(
            sp3_clock(with_clk, sat, t[:, c]), interpolate_clock(clk, sat, t[:, c])
        )
    a, b = sp3_states(sp3, sats, t), sp3_states(with_clk, sats, t)
    # same orbits; the clocks differ by the interpolation error of the 5-min SP3 clocks
    np.testing.assert_allclose(a.pos_m, b.pos_m, atol=1e-3)
    diff_m = np.abs(a.clock_s - b.clock_s) * 299792458.0
    assert np.all(diff_m < 0.5)
    assert np.any(diff_m > 1e-4)


def test_errors_name_file_and_line(tmp_path: Path) -> None:
    text = CLK.read_text().splitlines(keepends=True)
    bad = tmp_path / "bad.clk"
    bad.write_text("".join(text[:1]).replace("C  ", "O  ", 1) + "".join(text[1:]))
    with pytest.raises(FileFormatError, match="line 1: not a RINEX clock file"):
        read_clock(bad)
    end = next(i for i, ln in enumerate(text) if "END OF HEADER" in ln) + 1
    unknown = tmp_path / "unknown.clk"
    unknown.write_text("".join(text[: end + 2]) + "XX G05  2023 01 01\n" + "".join(text[end + 2 :]))
    with pytest.raises(FileFormatError, match=rf"unknown.clk, line {end + 3}: unknown record"):
        read_clock(unknown)
    no_end = tmp_path / "noend.clk"
    no_end.write_text("".join(text[: end - 1]))
    with pytest.raises(FileFormatError, match="no END OF HEADER"):
        read_clock(no_end)


def test_a_last_record_cut_short_is_skipped_with_a_warning(tmp_path: Path) -> None:
    text = CLK.read_text()
    cut = tmp_path / "cut.clk"
    cut.write_text(text.rstrip("\n")[:-25])  # the file ends inside the last clock value
    clk = read_clock(cut)
    assert len(clk.skipped) == 1
    assert "cut short" in clk.skipped[0].reason
    assert any("1 damaged AS record" in w for w in clk.warnings)
    assert clk.record_counts["AS"] == 6 * 61


def test_interpolation_error_of_a_random_walk_clock() -> None:
    """A clock whose phase is a random walk of diffusion q (m^2/s) sampled every h: the error
    of linear interpolation in the middle of a span (a Brownian bridge) has variance q h / 4,
    which the second differences of the samples recover."""
    rng = np.random.default_rng(7)
    q, h, n = 1e-5, 300.0, 20_000
    phase_m = np.cumsum(rng.normal(0.0, np.sqrt(q * h), size=(n, 2)), axis=0)
    phase_m[:, 1] *= 0.1  # a second, quieter clock: variance 100 times smaller
    t = T0 + h * np.arange(n)
    clk = RinexClock(
        path="synthetic",
        version="3.00",
        agency="TST",
        time_system="GPS",
        interval_s=h,
        t_gps_s=t,
        sats=("G01", "G02"),
        clock_s=phase_m / C_MPS,
        sd_s=np.full((n, 2), np.nan),
        record_counts={"AS": 2 * n},
    )
    got = clock_interpolation_error(read_sp3(SP3).with_clock(clk), ["G01", "G02", "G03"])
    assert got.interval_s == h
    # 20,000 squared residuals: the mean is within 3 % (its relative sd is about 1.2 %)
    np.testing.assert_allclose(got.var_m2[:2], [q * h / 4, q * h / 400], rtol=0.03)
    assert np.isnan(got.var_m2[2])  # no clock of that satellite


def test_interpolation_error_of_wum_5min_clocks_against_its_30s_clocks() -> None:
    """WUM's 5-minute SP3 clocks of 2023-01-01 00:00-00:30 interpolated linearly miss its 30 s
    clocks by a mean square of 0.61 times the variance measured on the 5-minute samples alone
    (the 30 s file is the truth here); the 30 s clocks' own measure is smaller for every
    satellite."""
    clk, sp3 = read_clock(CLK), read_sp3(SP3)
    five = clock_interpolation_error(sp3, clk.sats)
    assert five.interval_s == 300.0
    miss_m = np.stack(
        [
            (sp3_clock(sp3, s, clk.t_gps_s) - interpolate_clock(clk, s, clk.t_gps_s)) * C_MPS
            for s in clk.sats
        ],
        axis=1,
    )
    ratio = np.nanmean(miss_m**2) / np.mean(five.var_m2)
    assert 0.3 < ratio < 1.5
    thirty = clock_interpolation_error(sp3.with_clock(clk), clk.sats)
    assert thirty.interval_s == 30.0
    assert np.all(thirty.var_m2 < five.var_m2)
