"""RTCM 3 MSM input: the MSM7 stream RTKLIB's str2str encodes from the X20P walk log, read
beside RTKLIB's convbin RINEX of the same stream, and as the base of an RTK zero baseline."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pyrtcm")

from navtrack.data import sample_path
from navtrack.gnss.relative import RtkConfig, RtkStatus, solve_relative
from navtrack.gnss.rinex.obs import read_obs
from navtrack.gnss.rtcm import is_rtcm3, read_rtcm
from navtrack.timescale import parse_gpst

DATA = Path(__file__).resolve().parents[1] / "data" / "rtk"
MSM7 = DATA / "gnss_imu_walk_cut_msm7.rtcm3"
T_APPROX = parse_gpst("2025-08-28T17:30:00")  # the walk's date (convbin -tr)
WALK_BASE = np.array([-1276964.2, -4717226.1, 4087226.7])


def test_msm7_observations_equal_convbin_to_the_printed_precision() -> None:
    """Same 60 epochs, satellites and values as ``convbin -r rtcm3`` (RINEX 3.04, printed to
    0.001 m, cycle, Hz): within 1e-3 everywhere; C/N0 equal; the loss-of-lock indicators
    agree on at least 98 % of the phases (convbin keeps the slip bit while the half-cycle flag
    is set and marks a new arc's first phase otherwise)."""
    assert is_rtcm3(MSM7)
    assert not is_rtcm3(sample_path("gnss_imu_walk_cut.ubx"))
    log = read_rtcm(MSM7, T_APPROX)
    ref = read_obs(DATA / "gnss_imu_walk_cut_msm7_convbin.obs")
    obs = log.obs
    assert log.messages["1077"] == log.messages["1097"] == 60
    assert log.station_xyz_m is None  # no 1005/1006 in this stream
    np.testing.assert_array_equal(obs.t_gps_s, ref.t_gps_s)
    assert obs.sats == ref.sats
    assert sorted(obs.codes) == sorted(ref.codes)
    agree = total = 0
    for code in ref.codes:
        ours = obs.values[:, :, obs.codes.index(code)]
        theirs = ref.values[:, :, ref.codes.index(code)]
        np.testing.assert_array_equal(np.isfinite(ours), np.isfinite(theirs), err_msg=code)
        ok = np.isfinite(ours)
        tol = 0.0 if code[0] == "S" else 1e-3
        np.testing.assert_allclose(ours[ok], theirs[ok], rtol=0, atol=tol, err_msg=code)
        if code[0] == "L":
            a = np.maximum(obs.lli[:, :, obs.codes.index(code)][ok], 0)
            b = np.maximum(ref.lli[:, :, ref.codes.index(code)][ok], 0)
            agree += int(np.sum(a == b))
            total += int(ok.sum())
    assert total > 1000
    assert agree >= 0.98 * total


def test_rtk_with_an_rtcm_base_zero_baseline() -> None:
    """The UBX log as rover against the RTCM 3 stream of the same log as base: a zero
    baseline through the two readers; every fix at the base position."""
    from navtrack.gnss.ubx import read_ubx

    rover = read_ubx(sample_path("gnss_imu_walk_cut.ubx"))
    base = read_rtcm(MSM7, float(np.median(rover.obs.t_gps_s)))
    res = solve_relative(rover.obs, base.obs, [rover.nav], WALK_BASE, RtkConfig(frequencies=2))
    fixed = res.status == RtkStatus.FIX
    assert res.n_common_epochs == 60
    assert fixed.sum() >= 55
    assert np.max(np.abs(res.pos_m[fixed] - WALK_BASE)) < 0.01


def test_a_file_without_msm_is_refused_with_its_name(tmp_path: Path) -> None:
    from navtrack.errors import FileFormatError

    empty = tmp_path / "none.rtcm3"
    empty.write_bytes(b"\xd3\x00\x00\x47\xea\x4b")  # one empty, CRC-valid frame
    with pytest.raises(FileFormatError, match=r"none\.rtcm3"):
        read_rtcm(empty, T_APPROX)


def test_a_recorded_ntrip_stream_keeps_the_casters_header(tmp_path: Path) -> None:
    """A stream recorded from an NTRIP caster starts with the caster's response header (the
    lines of the geofis/ppk recording of 2021-08-09 below): recognised and read as the same
    epochs as the bare stream."""
    header = (
        b"Ntrip-Version: Ntrip/1.0\r\nServer: NTRIP Caster 1.0\r\n"
        b"Date:  8/ 9/2021 15:10:55\r\nContent-Type: gnss/data\r\n\r\n"
    )
    for head in (header, b"ICY 200 OK\r\n\r\n"):
        recorded = tmp_path / "recorded.rtcm3"
        recorded.write_bytes(head + MSM7.read_bytes())
        assert is_rtcm3(recorded)
        log = read_rtcm(recorded, T_APPROX)
        np.testing.assert_array_equal(log.obs.t_gps_s, read_rtcm(MSM7, T_APPROX).obs.t_gps_s)
    text = tmp_path / "header_only.rtcm3"
    text.write_bytes(b"ICY 200 OK\r\n\r\nnot a frame")
    assert not is_rtcm3(text)
