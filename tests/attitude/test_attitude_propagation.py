"""Propagation: series against closed form on real data, kernels, bad input."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from navtrack.attitude import quaternion as Q
from navtrack.io.broad import read_broad

BROAD = ("07_undisturbed_fast_rotation_B", "02_undisturbed_slow_rotation_B")


def _whole_trial(shared: Path, name: str) -> tuple[np.ndarray, np.ndarray, int]:
    trial = read_broad(shared / "trajectory" / "broad" / f"{name}.mat")
    d = Q.delta_angles(trial.t_s, trial.gyr_rad_s)
    start = int(np.flatnonzero(np.all(np.isfinite(trial.opt_quat_xyzw), axis=1))[0])
    return d, trial.opt_quat_xyzw[start], start


@pytest.mark.parametrize("name", BROAD)
def test_third_order_series_against_closed_form_whole_trial(shared_data: Path, name: str) -> None:
    """The truncation turns each step by θ⁵/480 (scalar part short by θ⁴/384, vector part by
    θ⁵/3840, to leading order: 2 (θ⁵/768 - θ⁵/3840)); the accumulated difference
    stays below the sum of those (trial 02: below 1e-8 rad, the issue's bar; trial 07, with
    steps up to 0.088 rad at 25 rad/s, does not meet 1e-8 and is held to the bound)."""
    d, q0, start = _whole_trial(shared_data, name)
    closed = Q.propagate(q0, d, start=start)
    series = Q.propagate(q0, d, start=start, method="series", order=3)
    diff = Q.attitude_errors(series.rotation, closed.rotation)[0]
    bound = np.sum(np.linalg.norm(d, axis=1) ** 5) / 480.0
    assert diff.max() <= 1.05 * bound
    if name.startswith("02"):
        assert diff.max() < 1e-8
    order2 = Q.propagate(q0, d, start=start, method="series", order=2)
    assert Q.attitude_errors(order2.rotation, closed.rotation)[0].max() > 100 * diff.max()
    assert np.max(np.abs(closed.norm - 1.0)) < 1e-12


def test_single_step_series_error_scales_as_fifth_power() -> None:
    for th in (0.02, 0.04, 0.08):
        d = np.array([th, 0.0, 0.0])
        a = Rotation.from_quat(Q.delta_quaternions(d, "series", 3))
        b = Rotation.from_quat(Q.delta_quaternions(d))
        assert (a * b.inv()).magnitude() == pytest.approx(th**5 / 480.0, rel=0.02)


@pytest.mark.parametrize(("method", "order"), [("closed", 3), ("series", 1), ("series", 3)])
def test_compiled_loop_numpy_path_and_backward_propagation(method: Q.Method, order: int) -> None:
    """The one-loop kernel (compiled by numba when installed, run here as plain Python too)
    and the NumPy path (vectorised steps, blocked product) give the same attitudes and norms,
    forward and backward from a middle sample."""
    rng = np.random.default_rng(7)
    d = rng.normal(0.0, 0.05, (600, 3))
    q0 = Rotation.random(rng=rng).as_quat()
    ref = Q.propagate_numpy(q0, d, 250, method, order)
    fwd, nf = Q.propagate_loop(q0, d[250:], method == "closed", order, False)
    back, nb = Q.propagate_loop(
        q0, np.ascontiguousarray(d[:250][::-1]), method == "closed", order, True
    )
    np.testing.assert_allclose(np.concatenate([back[:0:-1], fwd]), ref.quat, atol=1e-13)
    np.testing.assert_allclose(np.concatenate([nb[:0:-1], nf]), ref.norm, rtol=1e-13)
    prop = Q.propagate(q0, d, start=250, method=method, order=order)
    np.testing.assert_allclose(prop.quat, ref.quat, atol=1e-13)
    mid = Q.propagate(ref.quat[400], d, start=400, method=method, order=order)
    assert Q.attitude_errors(mid.rotation, ref.rotation)[0].max() < 1e-12
    assert mid.start == 400


def test_interpolation_is_continuous_at_samples() -> None:
    rng = np.random.default_rng(8)
    t = np.arange(50) * 0.01
    gyr = rng.normal(0.0, 2.0, (50, 3))
    prop = Q.propagate(Rotation.identity(), Q.delta_angles(t, gyr))
    at = Q.interpolate_attitude(t, prop.quat, gyr, t[1:] - 1e-12)
    assert Q.attitude_errors(Rotation.from_quat(at), prop.rotation[1:])[0].max() < 1e-9


def test_bad_input() -> None:
    t = np.array([0.0, 0.01, 0.02, 0.015, 0.03])
    gyr = np.zeros((5, 3))
    with pytest.raises(ValueError, match="out of order at sample 3"):
        Q.delta_angles(t, gyr)
    gyr[2, 1] = np.nan
    with pytest.raises(ValueError, match="gyr_rad_s: sample 2"):
        Q.delta_angles(np.arange(5.0), gyr)
    with pytest.raises(ValueError, match="expected"):
        Q.delta_angles(np.arange(5.0), np.zeros((4, 3)))
    d = np.zeros((4, 3))
    with pytest.raises(ValueError, match="not a unit quaternion"):
        Q.propagate([0.0, 0.0, 0.0, 2.0], d)
    with pytest.raises(ValueError, match="is NaN"):
        Q.propagate([np.nan] * 4, d)
    with pytest.raises(ValueError, match="start"):
        Q.propagate([0.0, 0.0, 0.0, 1.0], d, start=5)
    with pytest.raises(ValueError, match="order"):
        Q.delta_quaternions(d, "series", 0)
    # the optical reference has NaN gaps: allowed only when asked for, partial rows never
    q = np.array([[0.0, 0.0, 0.0, 1.0], [np.nan] * 4])
    Q.check_quaternions(q, "truth", allow_nan=True)
    with pytest.raises(ValueError, match="row 1 is NaN"):
        Q.check_quaternions(q, "truth")
    with pytest.raises(ValueError, match="row 0 is not a unit"):
        Q.check_quaternions([[np.nan, 0.0, 0.0, 1.0]], "truth", allow_nan=True)
