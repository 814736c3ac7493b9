"""Conventions of navtrack.attitude pinned so they cannot flip silently.

* quaternions scalar-last [x, y, z, w] (scipy, Wertz/paper 6); BROAD stores scalar-first;
* attitude rotates body vectors into the reference frame;
* body-frame gyro rates, propagation by right-multiplication q[k+1] = q[k] ⊗ δq;
* errors in the reference frame, q_e = q_ref ⊗ q_est⁻¹ (the paper's p⁻¹ ⊗_W q);
* the paper's eq. 4 is the *matrix* series of exp(½Θ) with Wertz's Ω: the ``ahrs`` 0.4.0
  ``'series'`` method raises Θ element-wise (``Θ**2``), which agrees only to first order.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from navtrack.attitude.quaternion import (
    attitude_errors,
    correction_quaternion,
    delta_angles,
    delta_quaternions,
    from_scalar_first,
    propagate,
    qmul,
    series_matrix,
)
from navtrack.io.broad import read_broad

TRIAL07 = "07_undisturbed_fast_rotation_B.mat"


def test_scalar_first_to_scalar_last_matches_scipy() -> None:
    rng = np.random.default_rng(1)
    q_wxyz = Rotation.random(5, rng=rng).as_quat(scalar_first=True)
    q_xyzw = from_scalar_first(q_wxyz)
    np.testing.assert_array_equal(q_xyzw[:, 3], q_wxyz[:, 0])
    np.testing.assert_allclose(
        Rotation.from_quat(q_xyzw).as_matrix(),
        Rotation.from_quat(q_wxyz, scalar_first=True).as_matrix(),
    )
    # a rotation of 90 deg about z: scalar-last [0, 0, sin 45, cos 45]
    q = delta_quaternions(np.array([0.0, 0.0, math.pi / 2]))
    np.testing.assert_allclose(q, [0.0, 0.0, math.sqrt(0.5), math.sqrt(0.5)], atol=1e-15)


def test_attitude_rotates_body_into_reference_and_rates_are_body_frame() -> None:
    # start: body rotated 90 deg about reference x; then spin about *body* z at 1 rad/s
    q0 = Rotation.from_euler("x", 90, degrees=True)
    t = np.linspace(0.0, 1.0, 101)
    gyr = np.tile([0.0, 0.0, 1.0], (t.size, 1))
    prop = propagate(q0, delta_angles(t, gyr))
    expected = q0 * Rotation.from_rotvec([0.0, 0.0, 1.0])  # right-multiplied: body frame
    assert (prop.rotation[-1] * expected.inv()).magnitude() < 1e-12
    wrong = Rotation.from_rotvec([0.0, 0.0, 1.0]) * q0  # left-multiplied: reference frame
    assert (prop.rotation[-1] * wrong.inv()).magnitude() > 0.5
    # body z stays the axis: the body z axis in the reference frame is unchanged by the spin
    np.testing.assert_allclose(prop.rotation[-1].apply([0, 0, 1]), q0.apply([0, 0, 1]), atol=1e-12)


def test_propagation_matches_scipy_loop() -> None:
    rng = np.random.default_rng(2)
    t = np.cumsum(rng.uniform(0.002, 0.004, 400))
    gyr = rng.normal(0.0, 5.0, (400, 3))
    q0 = Rotation.random(rng=rng)
    prop = propagate(q0, delta_angles(t, gyr))
    r = q0
    for k in range(399):
        r = r * Rotation.from_rotvec(gyr[k] * (t[k + 1] - t[k]))
    assert (prop.rotation[-1] * r.inv()).magnitude() < 1e-12


@pytest.mark.parametrize("order", [1, 2, 3])
def test_series_is_the_papers_matrix_series(order: int) -> None:
    """q[k+1] = Σ_j (½Θ)^j / j! q[k] with Wertz's Θ acting on scalar-last components."""
    rng = np.random.default_rng(order)
    d = rng.normal(0.0, 0.3, 3)
    q = Rotation.random(rng=rng).as_quat()
    theta = series_matrix(d)
    M = sum(np.linalg.matrix_power(0.5 * theta, j) / math.factorial(j) for j in range(order + 1))
    np.testing.assert_allclose(M @ q, qmul(q, delta_quaternions(d, "series", order)), atol=1e-15)
    if order >= 2:  # ahrs 0.4.0 raises Θ element-wise: wrong beyond order 1
        E = sum((0.5 * theta) ** j / math.factorial(j) for j in range(order + 1))
        assert np.max(np.abs(E @ q - M @ q)) > 1e-3


def test_closed_form_is_the_matrix_exponential() -> None:
    from scipy.linalg import expm

    rng = np.random.default_rng(5)
    d = rng.normal(0.0, 0.5, 3)
    q = Rotation.random(rng=rng).as_quat()
    np.testing.assert_allclose(expm(0.5 * series_matrix(d)) @ q, qmul(q, delta_quaternions(d)))


def test_error_quaternion_is_reference_frame() -> None:
    rng = np.random.default_rng(3)
    est = Rotation.random(4, rng=rng)
    e_true = rng.normal(0.0, 0.01, (4, 3))
    ref = Rotation.from_rotvec(e_true) * est  # q_ref = exp(e) ⊗ q_est
    e_s, e_v = attitude_errors(est, ref)
    np.testing.assert_allclose(e_v, e_true, atol=1e-15)
    np.testing.assert_allclose(e_s, np.linalg.norm(e_true, axis=1))


def test_correction_makes_the_vector_error_zero_mean() -> None:
    """Paper: after the correction "the vector error has the same shape, but now has zero mean"."""
    rng = np.random.default_rng(4)
    p = Rotation.random(30, rng=rng)
    e = rng.normal([0.002, -0.001, 0.003], 0.0005, (30, 3))
    q = Rotation.from_rotvec(e) * p
    e_s, e_v = attitude_errors(p, q)
    q_c = correction_quaternion(e_s, e_v)
    after = attitude_errors(q_c * p, q)[1]  # every propagated attitude turned by q_c
    assert np.linalg.norm(after.mean(axis=0)) < 1e-6 < np.linalg.norm(e_v.mean(axis=0))
    literal = correction_quaternion(e_s, e_v, "paper_literal")
    assert literal.magnitude() == pytest.approx(e_s.mean())  # turns by the mean scalar error
    assert literal.magnitude() > q_c.magnitude()


def test_broad_gyro_integrates_in_the_body_frame(shared_data: Path) -> None:
    """Data README: right-multiplied integration of imu_gyr from opt_quat at the first movement
    sample of trial 07 stays within 0.56 deg after 1 s (5.4 deg after 10 s, no bias removal)."""
    trial = read_broad(shared_data / "trajectory" / "broad" / TRIAL07)
    k0 = int(np.flatnonzero(trial.movement)[0])
    q = trial.opt_quat_xyzw
    for seconds, limit_deg in ((1, 0.6), (10, 5.5)):
        k1 = k0 + round(seconds * trial.rate_hz)
        d = delta_angles(trial.t_s[k0 : k1 + 1], trial.gyr_rad_s[k0 : k1 + 1])
        prop = propagate(q[k0], d)
        end = Rotation.from_quat(q[k1])
        assert np.degrees((prop.rotation[-1] * end.inv()).magnitude()) < limit_deg
    # the reference-frame (left-multiplied) reading is far off after 10 s
    r = Rotation.from_quat(q[k0])
    for k in range(d.shape[0]):
        r = Rotation.from_rotvec(d[k]) * r
    assert np.degrees((r * end.inv()).magnitude()) > 50.0
    # and BROAD's scalar-first file order is what from_scalar_first expects
    assert np.isclose(trial.opt_quat_xyzw[k0, 3], trial.opt_quat_wxyz[k0, 0])
