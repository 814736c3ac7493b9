"""Calibration, smoother, chain and pose trajectory on a synthetic gyro with known errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from navtrack.attitude.calibration import CalibrationConfig, calibrate_gyro
from navtrack.attitude.quaternion import attitude_errors, delta_angles, propagate
from navtrack.attitude.reconstruct import reconstruct
from navtrack.attitude.trajectory import GnssPositions, pose_frame
from navtrack.errors import FileFormatError
from navtrack.io.positions import read_gnss_positions

RATE_HZ = 100.0
BIAS = np.array([0.004, -0.002, 0.003])
K = np.array([[2e-3, 1e-3, -5e-4], [-1e-3, -3e-3, 8e-4], [6e-4, -7e-4, 1.5e-3]])
TAU = 0.02


def _recording(seconds: float = 60.0, seed: int = 0, drift: float = 0.0) -> dict[str, np.ndarray]:
    """True rates (sums of sines on every axis, up to ~3 rad/s), truth attitudes, measured
    rates ``(I + K) ω + b`` and fixes every second stamped ``TAU`` early, 0.5 mrad noise; the
    bias varies by ``drift`` rad/s (a 40 s sine) about ``BIAS``."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, seconds, 1.0 / RATE_HZ)
    f = rng.uniform(0.05, 0.5, (3, 3))
    a = rng.uniform(0.5, 1.5, (3, 3))
    ph = rng.uniform(0, 2 * np.pi, (3, 3))
    w_true = np.stack(
        [
            sum(a[i, j] * np.sin(2 * np.pi * f[i, j] * t + ph[i, j]) for j in range(3))
            for i in range(3)
        ],
        axis=1,
    )
    truth = propagate(Rotation.random(rng=rng), delta_angles(t, w_true)).quat
    # first order inverse of the corrected-rate model ω_c = ω_m - b - K ω_m
    bias = BIAS + drift * np.sin(2 * np.pi * t / 40.0)[:, None] * np.array([1.0, -0.5, 0.7])
    w_meas = np.linalg.solve(np.eye(3) - K, (w_true + bias).T).T
    k = np.arange(50, t.size, round(RATE_HZ))
    noise = Rotation.from_rotvec(rng.normal(0.0, 5e-4, (k.size, 3)))
    fixes = (noise * Rotation.from_quat(truth[k])).as_quat()
    return {
        "t": t,
        "truth": truth,
        "gyr": w_meas,
        "fix_t": t[k] - TAU,
        "fix_q": fixes,
        "fix_s": np.full(k.size, 5e-4),
    }


@pytest.fixture(scope="module")
def recording() -> dict[str, np.ndarray]:
    return _recording()


def test_calibration_recovers_bias_scale_misalignment_and_timing(
    recording: dict[str, np.ndarray],
) -> None:
    r = recording
    cal = calibrate_gyro(r["t"], r["gyr"], r["fix_t"], r["fix_q"], r["fix_s"])
    assert cal.converged
    np.testing.assert_allclose(cal.bias_rad_s, BIAS, atol=2e-4)
    np.testing.assert_allclose(cal.K, K, atol=5e-4)
    assert cal.time_offset_s == pytest.approx(TAU, abs=1e-3)
    assert cal.rms_rad < 1e-3  # the fix noise (5e-4 per axis) plus rectangular-rule error
    assert np.all(np.isfinite(cal.sigma))
    # the stated sigmas are honest: the bias error is within 5 of them
    assert np.all(np.abs(cal.bias_rad_s - BIAS) < 5 * cal.sigma[3:6] + 1e-5)


def test_calibration_with_fixed_parameters(recording: dict[str, np.ndarray]) -> None:
    r = recording
    cfg = CalibrationConfig(scale=False, misalignment=False, time_offset=False)
    cal = calibrate_gyro(r["t"], r["gyr"], r["fix_t"], r["fix_q"], r["fix_s"], cfg)
    assert cal.time_offset_s == 0.0
    assert np.all(cal.scale == 0.0)
    assert np.all(np.isnan(cal.sigma[6:]))
    with pytest.raises(ValueError, match="fix_sigma_rad"):
        calibrate_gyro(r["t"], r["gyr"], r["fix_t"], r["fix_q"], 0 * r["fix_s"])
    bad = r["fix_q"].copy()
    bad[3] = np.nan
    with pytest.raises(ValueError, match="fix_quat: quaternion row 3 is NaN"):
        calibrate_gyro(r["t"], r["gyr"], r["fix_t"], bad, r["fix_s"])


def test_chain_each_step_reduces_the_error() -> None:
    """With a bias that varies (which the constant-bias calibration cannot follow) the smoother
    improves on the calibrated propagation. Here the 20 ms timing error dominates the plain
    propagation's error and a constant correction cannot remove it: the paper's correction
    must not make it worse (its reduction is judged on BROAD, tests/experiments)."""
    r = _recording(drift=1e-3)
    rec = reconstruct(r["t"], r["gyr"], r["fix_t"], r["fix_q"], r["fix_s"])
    truth = Rotation.from_quat(r["truth"][200:-200])
    t_cam = r["t"][200:-200] - TAU  # truth at IMU time t is seen at camera time t - TAU
    err = {}
    for name in rec.estimates:
        est = Rotation.from_quat(rec.on_camera_clock(name, t_cam))
        err[name] = attitude_errors(est, truth)[0].mean()
    assert err["paper_correction"] < 1.01 * err["propagation"]
    assert err["calibrated"] < err["paper_correction"] / 10
    assert err["smoother"] <= err["calibrated"]
    assert err["smoother"] <= err["filter"]
    assert err["smoother"] < 1e-3
    nis = rec.smoother.nis
    assert 0.5 < np.nanmean(nis) < 10.0


def test_pose_frame_interpolates_gnss_linearly(tmp_path: Path) -> None:
    t = np.array([0.0, 0.5, 1.0, 2.5])
    q = Rotation.from_euler("z", np.array([[0.0], [10], [20], [30]]), degrees=True).as_quat()
    base = np.array([3.9e6, 3.0e5, 5.0e6])
    gnss = GnssPositions(
        np.array([10.0, 11.0, 12.0]), base + np.array([[0, 0, 0], [2, 0, 0], [4, 0, 0.0]]), "x"
    )
    frame = pose_frame(t, q, gnss, gnss_offset_s=10.0)
    np.testing.assert_allclose(frame["x_m"][:3] - base[0], [0.0, 1.0, 2.0])
    assert list(frame["status"]) == ["ok", "ok", "ok", "no_position"]
    np.testing.assert_allclose(frame["yaw_deg"], [0, 10, 20, 30])
    from navtrack.io.solution import write_solution
    from navtrack.io.tables import read_table

    for suffix in (".csv", ".parquet"):
        path = write_solution(frame, tmp_path / f"pose{suffix}")
        back = read_table(path)
        np.testing.assert_allclose(back["qw"].to_numpy(float), q[:, 3])
        np.testing.assert_allclose(back["yaw_deg"].to_numpy(float), [0, 10, 20, 30])
    with pytest.raises(ValueError, match="not a unit quaternion"):
        pose_frame(t, 2 * q)


def test_read_gnss_positions(shared_data: Path, tmp_path: Path) -> None:
    gnss = read_gnss_positions(shared_data / "trajectory" / "pyins_gnss" / "gnss.csv")
    assert gnss.t_s.size == 800
    assert np.linalg.norm(gnss.xyz_m[0]) == pytest.approx(6.364e6, rel=1e-3)
    bad = tmp_path / "g.csv"
    bad.write_text("time,lat,lon\n0,1,2\n")
    with pytest.raises(FileFormatError, match=r"g\.csv"):
        read_gnss_positions(bad)
    bad.write_text("time,lat,lon,alt\n1,58,56,100\n0,58,56,100\n")
    with pytest.raises(FileFormatError, match="increase strictly"):
        read_gnss_positions(bad)
