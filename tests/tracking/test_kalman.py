"""Filter conformance kit: KF == EKF == UKF on linear models, Joseph form, batching, FilterPy."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from navtrack.estimation.kalman import (
    ekf_predict,
    ekf_update,
    kalman_gain,
    kf_predict,
    kf_update,
    stacked_inverse,
    ukf_predict,
    ukf_update,
)
from navtrack.tracking.models import (
    CoordinatedTurn,
    FunctionMeasurement,
    LinearMeasurement,
    RangeBearing,
    constant_acceleration,
    constant_velocity,
    linear_position,
)


def _random_spd(rng: np.random.Generator, n: int, scale: float = 1.0) -> np.ndarray:
    A = rng.normal(size=(n, n))
    return scale * (A @ A.T + n * np.eye(n))


MODELS = [
    constant_velocity(1, 0.5),
    constant_velocity(2, 0.5, "continuous"),
    constant_velocity(3, 2.0),
    constant_acceleration(1, 0.1),
    constant_acceleration(2, 0.1, "continuous"),
    constant_acceleration(3, 0.3),
]


@pytest.mark.parametrize("motion", MODELS, ids=lambda m: f"{m.ndim}D-o{m.order}-{m.noise}")
@given(seed=st.integers(0, 2**32 - 1), dt=st.floats(0.1, 5.0))
@settings(max_examples=15, deadline=None)
def test_kf_ekf_ukf_agree_on_linear_models(motion, seed: int, dt: float) -> None:
    rng = np.random.default_rng(seed)
    n = motion.dim_x
    meas = linear_position(n, motion.position_index, sigma_m=rng.uniform(0.5, 5.0))
    x = rng.normal(size=(3, n)) * 10
    P = np.stack([_random_spd(rng, n) for _ in range(3)])
    z = rng.normal(size=(3, meas.dim_z)) * 10
    xk, Pk = kf_predict(x, P, motion.F(dt), motion.Q(dt))
    xe, Pe = ekf_predict(x, P, motion, dt)
    # alpha, beta, kappa do not matter for a linear model: the unscented transform is exact
    xu, Pu = ukf_predict(x, P, motion, dt, alpha=0.5, beta=2.0, kappa=3.0 - n)
    np.testing.assert_allclose(xe, xk, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(xu, xk, rtol=1e-9, atol=1e-7)
    np.testing.assert_allclose(Pe, Pk, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(Pu, Pk, rtol=1e-8, atol=1e-6)
    uk = kf_update(xk, Pk, z, meas.H, meas.R)
    ue = ekf_update(xk, Pk, z, meas)
    uu = ukf_update(xk, Pk, z, meas, alpha=1.0, beta=0.0, kappa=1.0)
    uj = kf_update(xk, Pk, z, meas.H, meas.R, joseph=True)
    for u in (ue, uu, uj):
        np.testing.assert_allclose(u.x, uk.x, rtol=1e-8, atol=1e-6)
        np.testing.assert_allclose(u.P, uk.P, rtol=1e-7, atol=1e-6)
        np.testing.assert_allclose(u.S, uk.S, rtol=1e-8, atol=1e-6)
        np.testing.assert_allclose(u.innovation, uk.innovation, rtol=1e-8, atol=1e-6)
    # posterior covariance symmetric positive definite
    np.linalg.cholesky(uk.P)
    np.testing.assert_array_equal(uk.P, np.swapaxes(uk.P, -1, -2))


def test_batched_equals_loop() -> None:
    rng = np.random.default_rng(3)
    mot = constant_velocity(2, 1.0)
    meas = linear_position(4, (0, 2), 3.0)
    x = rng.normal(size=(5, 7, 4))  # runs x tracks x state
    P = np.broadcast_to(_random_spd(rng, 4), (5, 7, 4, 4))
    z = rng.normal(size=(5, 7, 2))
    u = kf_update(*kf_predict(x, P, mot.F(1.0), mot.Q(1.0)), z, meas.H, meas.R)
    for r in range(5):
        for t in range(7):
            xp, Pp = kf_predict(x[r, t], P[r, t], mot.F(1.0), mot.Q(1.0))
            one = kf_update(xp, Pp, z[r, t], meas.H, meas.R)
            np.testing.assert_allclose(u.x[r, t], one.x, rtol=1e-13)
            np.testing.assert_allclose(u.P[r, t], one.P, rtol=1e-12)
    assert not u.x.flags.writeable


def test_discrete_white_noise_matches_bar_shalom() -> None:
    # Bar-Shalom, Li, Kirubarajan (2001) eq. 6.3.2-4: Q = q [[T^4/4, T^3/2], [T^3/2, T^2]]
    T, q = 2.0, 0.7
    np.testing.assert_allclose(
        constant_velocity(1, q).Q(T), q * np.array([[T**4 / 4, T**3 / 2], [T**3 / 2, T**2]])
    )
    # eq. 6.2.2-12 continuous: Q = q [[T^3/3, T^2/2], [T^2/2, T]]
    np.testing.assert_allclose(
        constant_velocity(1, q, "continuous").Q(T),
        q * np.array([[T**3 / 3, T**2 / 2], [T**2 / 2, T]]),
    )


@pytest.mark.parametrize("order", [1, 2])
def test_continuous_noise_is_consistent_under_splitting(order: int) -> None:
    m = (
        constant_velocity(2, 0.3, "continuous")
        if order == 1
        else constant_acceleration(2, 0.3, "continuous")
    )
    a, b = 0.7, 1.9
    F_b = m.F(b)
    np.testing.assert_allclose(F_b @ m.Q(a) @ F_b.T + m.Q(b), m.Q(a + b), rtol=1e-12)


def test_angle_innovation_is_wrapped() -> None:
    rb = RangeBearing(np.diag([10.0**2, 0.01**2]))
    # target just below the -x axis (bearing ~ -pi), measurement just above (bearing ~ +pi)
    x = np.array([-1000.0, 0.0, -1.0, 0.0])
    P = np.diag([100.0, 1.0, 100.0, 1.0])
    z = np.array([1000.0, np.pi - 0.001])
    for u in (ekf_update(x, P, z, rb), ukf_update(x, P, z, rb)):
        assert abs(u.innovation[1]) < 0.01
        assert abs(u.x[2] - x[2]) < 5.0


def test_range_bearing_jacobian_matches_finite_differences() -> None:
    rng = np.random.default_rng(5)
    for from_north in (False, True):
        rb = RangeBearing(
            np.diag([1.0, 1e-4]), sensor_xy=np.array([30.0, -20.0]), from_north=from_north
        )
        x = rng.normal(size=(6, 4)) * 1000
        J = rb.jacobian(x)
        h = 1e-4
        for k in range(4):
            e = np.zeros(4)
            e[k] = h
            d = (rb.h(x + e) - rb.h(x - e)) / (2 * h)
            np.testing.assert_allclose(J[..., k], d, rtol=1e-6, atol=1e-10)


def test_coordinated_turn_jacobian_and_limit() -> None:
    ct = CoordinatedTurn(q=1.0, q_omega=1e-4)
    rng = np.random.default_rng(9)
    x = rng.normal(size=(5, 5)) * np.array([100, 10, 100, 10, 0.05])
    x[0, 4] = 0.0  # straight line: must equal constant velocity
    np.testing.assert_allclose(
        ct.f(x[:1], 2.0)[0, :4], constant_velocity(2, 1.0).f(x[0, :4], 2.0), rtol=1e-12
    )
    J = ct.jacobian(x, 2.0)
    h = 1e-6
    for k in range(5):
        e = np.zeros(5)
        e[k] = h
        d = (ct.f(x + e, 2.0) - ct.f(x - e, 2.0)) / (2 * h)
        np.testing.assert_allclose(J[..., k], d, rtol=1e-5, atol=1e-6)
    # a full turn at omega = 2 pi / 10 brings the target back after 10 s
    x0 = np.array([0.0, 10.0, 0.0, 0.0, 2 * np.pi / 10])
    np.testing.assert_allclose(ct.f(x0, 10.0), x0, atol=1e-9)


def test_filterpy_equality() -> None:
    filterpy = pytest.importorskip("filterpy.kalman")
    rng = np.random.default_rng(11)
    mot = constant_velocity(2, 0.5)
    meas = linear_position(4, (0, 2), 2.0)
    x0 = rng.normal(size=4)
    P0 = _random_spd(rng, 4)
    kf = filterpy.KalmanFilter(dim_x=4, dim_z=2)
    kf.x = x0.copy()
    kf.P = P0.copy()
    kf.F = mot.F(1.0)
    kf.Q = mot.Q(1.0)
    kf.H = np.array(meas.H)
    kf.R = np.array(meas.R)
    x, P = x0, P0
    for _ in range(20):
        z = rng.normal(size=2) * 5
        kf.predict()
        kf.update(z)
        x, P = kf_predict(x, P, mot.F(1.0), mot.Q(1.0))
        u = kf_update(x, P, z, meas.H, meas.R, joseph=True)  # FilterPy uses the Joseph form
        x, P = u.x, u.P
        np.testing.assert_allclose(x, kf.x, rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(P, kf.P, rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(u.innovation, kf.y, rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(u.S, kf.S, rtol=1e-10, atol=1e-10)


def test_bad_covariance_rejected() -> None:
    with pytest.raises(ValueError, match="positive definite"):
        LinearMeasurement(np.eye(2), np.array([[1.0, 2.0], [2.0, 1.0]]))
    with pytest.raises(ValueError, match="symmetric"):
        LinearMeasurement(np.eye(2), np.array([[1.0, 0.5], [0.0, 1.0]]))
    with pytest.raises(ValueError, match="ndim"):
        constant_velocity(4, 1.0)


def test_function_measurement_hook_foveal_sensor() -> None:
    # paper 4 (Xi & Morrell 2005): z = arctan(c (X - d)) + v, R = 0.05, 1-D CV, P0 = diag(1, 0.1)
    c, d = 2.0, 0.3

    def h(x: np.ndarray) -> np.ndarray:
        return np.arctan(c * (x[..., :1] - d))

    def jac(x: np.ndarray) -> np.ndarray:
        J = np.zeros((*x.shape[:-1], 1, 2))
        J[..., 0, 0] = c / (1 + (c * (x[..., 0] - d)) ** 2)
        return J

    numeric = FunctionMeasurement(h, np.array([[0.05]]), dim_x=2)
    analytic = FunctionMeasurement(h, np.array([[0.05]]), dim_x=2, jac=jac)
    x = np.array([[0.1, 0.2], [1.5, -0.3]])
    np.testing.assert_allclose(numeric.jacobian(x), analytic.jacobian(x), rtol=1e-7)
    P = np.diag([1.0, 0.1])
    z = np.array([[0.2], [1.0]])
    ue = ekf_update(x, P, z, analytic)
    uu = ukf_update(x, P, z, analytic)
    # both shrink the position variance; the EKF moves toward the measurement's preimage
    assert np.all(ue.P[:, 0, 0] < 1.0)
    assert np.all(uu.P[:, 0, 0] < 1.0)
    target = np.tan(z[:, 0]) / c + d
    assert np.all(np.abs(ue.x[:, 0] - target) < np.abs(x[:, 0] - target))
    # with a small prior spread the model is locally linear: UKF -> EKF
    Ps = np.diag([1e-6, 1e-7])
    np.testing.assert_allclose(
        ukf_update(x, Ps, z, analytic).x, ekf_update(x, Ps, z, analytic).x, rtol=1e-5
    )


def test_stacked_inverse_and_closed_form_gain() -> None:
    """2 x 2 stacks in closed form (any non-singular matrix, symmetric ones exactly symmetric),
    others by LAPACK; the m = 2 gain equals the solve of the general path."""
    rng = np.random.default_rng(11)
    A = rng.normal(size=(50, 2, 2))  # general, some indefinite
    np.testing.assert_allclose(stacked_inverse(A), np.linalg.inv(A), rtol=1e-9, atol=1e-12)
    Ssym = A @ np.swapaxes(A, -1, -2) + 0.1 * np.eye(2)
    inv = stacked_inverse(Ssym)
    np.testing.assert_array_equal(inv, np.swapaxes(inv, -1, -2))
    B = rng.normal(size=(4, 3, 3, 3))
    np.testing.assert_allclose(stacked_inverse(B), np.linalg.inv(B), rtol=1e-12)
    with pytest.raises(np.linalg.LinAlgError):
        stacked_inverse(np.array([[[1.0, 2.0], [2.0, 4.0]]]))
    PHt = rng.normal(size=(50, 4, 2))
    K = kalman_gain(PHt, Ssym)
    ref = np.swapaxes(np.linalg.solve(Ssym, np.swapaxes(PHt, -1, -2)), -1, -2)
    np.testing.assert_allclose(K, ref, rtol=1e-9, atol=1e-12)
