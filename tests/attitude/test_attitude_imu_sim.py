"""Simulated gyros and the Earth-rate frame chain (paper 6, eq. 3)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from navtrack.attitude import frames, imu_sim
from navtrack.attitude.quaternion import attitude_errors
from navtrack.io.broad import read_broad

BERLIN_LAT = np.radians(52.51)
BERLIN_LON = np.radians(13.33)


def _stationary(duration_s: float = 200.0) -> tuple[np.ndarray, np.ndarray]:
    t = imu_sim.sample_times(duration_s, 400.0)
    q = np.tile(Rotation.from_euler("ZYX", [30.0, 5.0, -3.0], degrees=True).as_quat(), (t.size, 1))
    return t, q


def test_ln200_constant_is_the_data_sheet() -> None:
    """Northrop Grumman LN-200 data sheet: 1 °/h bias (best grade), ARW within 0.04-0.1 °/√h,
    100 ppm scale factor, 400 Hz."""
    assert imu_sim.LN200.bias_deg_h == pytest.approx(1.0)
    assert 0.04 <= imu_sim.LN200.arw_deg_sqrt_h <= 0.1
    assert imu_sim.LN200.scale_factor == pytest.approx(1e-4)
    assert imu_sim.LN200.rate_hz == 400.0


def test_stationary_gyro_sees_the_earth_rate() -> None:
    """A gyro at rest on the ground measures 15.041 °/h (WGS-84 Ω = 7.2921151467e-5 rad/s)."""
    t, q = _stationary()
    perfect = imu_sim.GyroSpec("perfect", 0.0, 0.0, 0.0)
    rec = imu_sim.simulate_gyro(
        t, q, perfect, np.random.default_rng(1), frame_rate_rad_s=frames.earth_rate_enu(0.9)
    )
    deg_h = np.degrees(np.linalg.norm(rec.gyr_rad_s, axis=1)) * 3600.0
    np.testing.assert_allclose(deg_h, 15.0411, atol=1e-3)


def test_earth_rate_chain_keeps_a_stationary_attitude() -> None:
    """Eq. 3: propagating the Earth-rate-sensing gyro in the inertial frame and rotating back
    with the Earth gives the constant attitude; ignoring the chain drifts Ω·200 s = 0.836°."""
    t, q = _stationary()
    perfect = imu_sim.GyroSpec("perfect", 0.0, 0.0, 0.0)
    rate = frames.earth_rate_enu(BERLIN_LAT)
    rec = imu_sim.simulate_gyro(t, q, perfect, np.random.default_rng(1), frame_rate_rad_s=rate)
    q0_inertial = frames.to_inertial(t[:1], q[:1], t[0], BERLIN_LAT, BERLIN_LON)[0]
    inertial = imu_sim.integrate_rates(t, rec.gyr_rad_s, q0_inertial)
    back = frames.from_inertial(t, inertial, t[0], BERLIN_LAT, BERLIN_LON)
    err = attitude_errors(Rotation.from_quat(back), Rotation.from_quat(q))[0]
    assert err.max() < 1e-9
    naive = imu_sim.integrate_rates(t, rec.gyr_rad_s, q[0])
    drift = attitude_errors(Rotation.from_quat(naive[-1:]), Rotation.from_quat(q[-1:]))[0]
    assert np.degrees(drift[0]) == pytest.approx(np.degrees(7.2921151467e-5 * 200.0), rel=1e-6)


def test_mount_round_trip() -> None:
    rng = np.random.default_rng(3)
    t = np.array([0.0, 50.0, 3600.0])
    q = Rotation.random(3, rng=rng).as_quat()
    mount = Rotation.from_euler("xyz", [1.0, -2.0, 90.0], degrees=True)
    i = frames.to_inertial(t, q, 10.0, 0.3, -1.2, mount)
    back = frames.from_inertial(t, i, 10.0, 0.3, -1.2, mount)
    assert attitude_errors(Rotation.from_quat(back), Rotation.from_quat(q))[0].max() < 1e-12


def test_body_rates_integrate_back_to_the_truth() -> None:
    rng = np.random.default_rng(7)
    t = imu_sim.sample_times(5.0, 400.0)
    w = np.cumsum(rng.normal(0.0, 0.05, (t.size, 3)), axis=0)
    truth = imu_sim.integrate_rates(t, w, Rotation.random(rng=rng))
    rates = imu_sim.body_rates(t, truth)
    np.testing.assert_allclose(rates[:-1], w[:-1], atol=1e-9)
    again = imu_sim.integrate_rates(t, rates, truth[0])
    assert attitude_errors(Rotation.from_quat(again), Rotation.from_quat(truth))[0].max() < 1e-10


def test_error_terms_have_their_stated_size() -> None:
    """Over 300 seeded recordings the drawn bias and scale factor have the spec's 1σ, and the
    angle of the white noise over 5 s has the variance N²·5 s (ARW)."""
    t, q = _stationary(5.0)
    spec = replace(imu_sim.LN200, bias_rad_s=1e-5, scale_factor=1e-3, misalignment_rad=2e-4)
    ss = np.random.SeedSequence(11).spawn(300)
    recs = [imu_sim.simulate_gyro(t, q, spec, np.random.default_rng(s)) for s in ss]
    bias = np.array([r.bias_rad_s for r in recs])
    assert np.std(bias) == pytest.approx(1e-5, rel=0.1)
    scale = np.array([np.diag(r.sensor_matrix) - 1.0 for r in recs])
    assert np.std(scale) == pytest.approx(1e-3, rel=0.1)
    noise = np.array([r.gyr_rad_s - r.bias_rad_s for r in recs])  # truth rate is 0
    angle = noise[:, :-1].sum(axis=1) * np.diff(t)[0]
    assert np.std(angle) == pytest.approx(spec.arw_rad_sqrt_s * np.sqrt(5.0), rel=0.1)


def test_gauss_markov_in_run_bias_is_stationary() -> None:
    spec = replace(imu_sim.LN200, bias_instability_rad_s=3e-6, bias_tau_s=2.0)
    t, q = _stationary(200.0)
    rec = imu_sim.simulate_gyro(t, q, spec, np.random.default_rng(5))
    d = rec.in_run_bias_rad_s
    assert np.std(d) == pytest.approx(3e-6, rel=0.15)
    lag = int(2.0 * 400)  # one correlation time: autocorrelation 1/e
    rho = np.mean(d[:-lag] * d[lag:]) / np.mean(d * d)
    assert rho == pytest.approx(np.exp(-1.0), abs=0.1)


def test_bad_spec_and_input() -> None:
    with pytest.raises(ValueError, match="GyroSpec"):
        imu_sim.GyroSpec("bad", -1.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="truth_xyzw"):
        imu_sim.body_rates([0.0, 1.0], [[0.0, 0.0, 0.0, 2.0], [0.0, 0.0, 0.0, 1.0]])


def test_ln200_on_broad_motion_drifts_like_its_bias(shared_data: Path) -> None:
    """BROAD trial 02's recorded motion at 400 Hz with an LN-200: after 180 s the attitude
    error is within three sigma of bias·t (1 °/h · 180 s = 0.05° per axis) plus scale
    factor · turned angle (100 ppm of the trial's total rotation), far below the MEMS drift."""
    trial = read_broad(shared_data / "trajectory" / "broad" / "02_undisturbed_slow_rotation_B.mat")
    t = imu_sim.sample_times(180.0, 400.0)
    w = np.stack([np.interp(t, trial.t_s, trial.gyr_rad_s[:, i]) for i in range(3)], axis=1)
    truth = imu_sim.integrate_rates(t, w, Rotation.identity())
    rec = imu_sim.simulate_gyro(t, truth, imu_sim.LN200, np.random.default_rng(2))
    est = imu_sim.integrate_rates(t, rec.gyr_rad_s, truth[0])
    err = np.degrees(attitude_errors(Rotation.from_quat(est), Rotation.from_quat(truth))[0])
    turned = np.sum(np.linalg.norm(w[:-1], axis=1) * np.diff(t))
    spec = imu_sim.LN200
    bound = 3.0 * np.sqrt(3.0) * (spec.bias_rad_s * 180.0 + spec.scale_factor * turned)
    assert 1e-3 < err[-1] < np.degrees(bound)
