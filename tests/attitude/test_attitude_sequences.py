"""Multi-sequence weighting (paper 6, eqs. 5-7) and the LIDAR yaw/pitch of eqs. 10-11."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from navtrack.attitude import imu_sim, lidar, sequences
from navtrack.attitude.quaternion import attitude_errors


def _const(rotvec_deg: list[float], n: int) -> np.ndarray:
    return np.tile(Rotation.from_rotvec(np.radians(rotvec_deg)).as_quat(), (n, 1))


def test_two_sequences_hand_worked() -> None:
    """p1 = 10° about z from t = 0 with σ0 = 0.1°, p2 = 20° about z from t = 100 s with
    σ0 = 0.2°, b = 0.01°/s. At t = 50: σ = 0.6°, 0.7°, weights 1/0.6, 1/0.7, so
    u = (10/0.6 + 20/0.7) / (1/0.6 + 1/0.7) = 14.6154°. At t = 0: σ = 0.1°, 1.2°,
    u = (100 + 20/1.2) / (10 + 1/1.2) = 10.7692°. With p2 about x instead, at t = 50
    u = (16.667 z + 28.571 x) / 3.0952 = (9.2308 x, 5.3846 z)°."""
    t = np.array([0.0, 50.0])
    q = np.stack([_const([0, 0, 10], 2), _const([0, 0, 20], 2)])
    tq = np.array([0.0, 100.0])
    s0 = np.radians([0.1, 0.2])
    b = np.radians(0.01)
    u = sequences.weighted_attitude(t, q, tq, s0, b)
    deg = np.degrees(Rotation.from_quat(u).as_rotvec())
    np.testing.assert_allclose(deg[:, 2], [10.769231, 14.615385], atol=1e-5)
    np.testing.assert_allclose(deg[:, :2], 0.0, atol=1e-12)
    q2 = np.stack([_const([0, 0, 10], 2), _const([20, 0, 0], 2)])
    u2 = np.degrees(Rotation.from_quat(sequences.weighted_attitude(t, q2, tq, s0, b)).as_rotvec())
    np.testing.assert_allclose(u2[1], [9.230769, 0.0, 5.384615], atol=1e-5)
    rel = sequences.weighted_attitude(t, q, tq, s0, b, average="relative")
    np.testing.assert_allclose(np.degrees(Rotation.from_quat(rel).as_rotvec())[:, 2], deg[:, 2])
    inv_var = sequences.weighted_attitude(t, q, tq, s0, b, weight_power=2.0)
    w1, w2 = 1 / 0.6**2, 1 / 0.7**2
    expected = (10 * w1 + 20 * w2) / (w1 + w2)
    assert np.degrees(Rotation.from_quat(inv_var[1]).magnitude()) == pytest.approx(expected)


def test_weighted_attitude_rejects_bad_accuracy() -> None:
    q = np.stack([_const([0, 0, 1], 3)])
    with pytest.raises(ValueError, match="sigma0_rad"):
        sequences.weighted_attitude([0.0, 1.0, 2.0], q, [0.0], [0.0], 1e-5)
    with pytest.raises(ValueError, match="quat"):
        sequences.weighted_attitude([0.0, 1.0], q, [0.0], [1e-3], 1e-5)


def test_split_sequences() -> None:
    labels = sequences.split_sequences([0.0, 1.0, 2.0, 10.0, 11.0, 30.0], 5.0)
    np.testing.assert_array_equal(labels, [0, 0, 0, 1, 1, 2])


def test_sequence_correction_zeroes_the_mean_vector_error() -> None:
    """Exact fixes, a gyro with a constant bias: each sequence's corrected start leaves vector
    errors of zero mean (paper: "the vector error has the same shape, but now has zero mean"),
    and the corrected propagations, weighted, beat the plain propagation."""
    rng = np.random.default_rng(4)
    t = imu_sim.sample_times(60.0, 100.0)
    w = 0.2 * np.sin(np.outer(t, [0.3, 0.5, 0.7]))
    truth = imu_sim.integrate_rates(t, w, Rotation.random(rng=rng))
    gyr = w + np.radians([0.02, -0.01, 0.015])  # deg/s bias
    k = np.r_[np.arange(100, 2000, 100), np.arange(4000, 5900, 100)]
    labels = sequences.split_sequences(t[k], 5.0)
    assert labels.max() == 1
    st = sequences.sequence_starts(t, gyr, t[k], truth[k], labels, method="closed")
    for j in range(2):
        idx = labels == j
        np.testing.assert_allclose(st.e_v_after_rad[idx].mean(axis=0), 0.0, atol=2e-5)
        assert st.e_s_after_rad[idx].max() < st.e_s_before_rad[idx].max()
    u = sequences.weighted_attitude(t, st.quat, st.t_q0_s, st.sigma0_rad, np.radians(0.02))
    truth_r = Rotation.from_quat(truth)
    e_u = attitude_errors(Rotation.from_quat(u), truth_r)[0]
    e_first = attitude_errors(Rotation.from_quat(st.quat[0]), truth_r)[0]
    assert e_u[4000:].mean() < e_first[4000:].mean()


def test_fix_between_samples_is_carried_to_the_sample() -> None:
    t = imu_sim.sample_times(2.0, 50.0)
    w = np.tile([0.5, -0.2, 0.1], (t.size, 1))
    truth = imu_sim.integrate_rates(t, w, Rotation.identity())
    t_fix = t[30] + 0.007
    q_fix = Rotation.from_quat(truth[30]) * Rotation.from_rotvec(w[30] * 0.007)
    d = np.diff(t)[:, None] * w[:-1]
    q = sequences.propagate_from_fix(t, w, d, t_fix, q_fix, "closed", 3)
    assert attitude_errors(Rotation.from_quat(q), Rotation.from_quat(truth))[0].max() < 1e-12


@pytest.mark.parametrize(("axis", "index", "sign"), [("x", 0, 1.0), ("y", 1, -1.0)])
def test_lidar_recovers_a_known_attitude_error(axis: str, index: int, sign: float) -> None:
    """A reconstructed LIDAR attitude off by 0.2° about its x (y) axis shifts the DEM fit along
    y (x) by d·tan(0.2°): eq. 10 (eq. 11) returns the angle, the other stays near zero."""
    rng = np.random.default_rng(1)
    dem = lidar.smooth_dem(rng, size_m=60.0)
    pos = np.array([-150.0, 0.0, 250.0])
    att = Rotation.align_vectors([-pos / np.linalg.norm(pos)], [[0.0, 0.0, 1.0]])[0]
    pts = lidar.lidar_points(dem, pos, att, rng, lidar.FlashLidarConfig(pixels=64))
    est = att * Rotation.from_euler(axis, 0.2, degrees=True)
    sh = lidar.correlation_shift(dem, pos, est, pts)
    angles = np.degrees([sh.yaw_eq10_rad, sh.pitch_eq11_rad])
    assert sh.converged
    assert angles[index] * sign == pytest.approx(0.2, abs=0.01)
    assert abs(angles[1 - index]) < 0.01
    assert sh.distance_m == pytest.approx(np.linalg.norm(pos), rel=0.02)


def test_yaw_pitch_equations() -> None:
    """Eqs. 10-11 literally: Δ = (1, 2, 10) m at d = 300 m."""
    yaw, pitch = lidar.yaw_pitch_from_shift([1.0, 2.0, 10.0], 300.0)
    assert yaw == pytest.approx(np.arctan(2.0 / 290.0))
    assert pitch == pytest.approx(np.arctan(1.0 / 290.0))


def test_lidar_must_look_down() -> None:
    rng = np.random.default_rng(0)
    dem = lidar.smooth_dem(rng, size_m=10.0)
    with pytest.raises(ValueError, match="look down"):
        lidar.lidar_points(dem, [0.0, 0.0, 100.0], Rotation.identity(), rng)


def test_printed_average_breaks_across_pi_and_relative_does_not() -> None:
    """Two equally weighted propagations 179.9° and 180.1° about z (the second is 179.9° about
    -z): their axis-angle vectors cancel, so the printed (absolute) average is the identity,
    180° from both; the relative reading returns the rotation of 180° between them."""
    t = np.array([0.0])
    q = np.stack([_const([0, 0, 179.9], 1), _const([0, 0, -179.9], 1)])
    args = (t, q, np.array([0.0, 0.0]), np.radians([0.1, 0.1]), 0.0)
    absolute = Rotation.from_quat(sequences.weighted_attitude(*args, average="absolute"))
    relative = Rotation.from_quat(sequences.weighted_attitude(*args, average="relative"))
    half_turn = Rotation.from_rotvec([0.0, 0.0, np.pi])
    assert np.degrees((absolute * half_turn.inv()).magnitude()[0]) > 179.0
    assert np.degrees((relative * half_turn.inv()).magnitude()[0]) < 1e-9
