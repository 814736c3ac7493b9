"""Attitude as series for ARI smoothing (navtrack.smoothing.attitude).

Oracle: scipy's Rotation (composition, rotation vectors, Euler angles).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from navtrack.smoothing.attitude import (
    euler_artefacts,
    euler_path,
    increment_path,
    rotations_from_path,
)


def _random_walk(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    steps = Rotation.from_rotvec(0.3 * rng.standard_normal((n, 3)))
    rot = [Rotation.random(random_state=seed)]
    for k in range(1, n):
        rot.append(rot[-1] * steps[k])
    return np.array([r.as_quat() for r in rot])


def test_path_increments_are_the_body_frame_rotations() -> None:
    quat = _random_walk(50, 1)
    path = increment_path(quat)
    rot = Rotation.from_quat(quat)
    for k in (1, 17, 49):
        expected = (rot[k - 1].inv() * rot[k]).as_rotvec()
        np.testing.assert_allclose(path[k] - path[k - 1], expected, atol=1e-12)
    np.testing.assert_array_equal(path[0], 0.0)


def test_round_trip_with_gaps() -> None:
    quat = _random_walk(60, 2)
    quat[[0, 1, 20, 21, 22, 59]] = np.nan
    path = increment_path(quat)
    assert np.array_equal(np.isnan(path[:, 0]), np.isnan(quat[:, 0]))
    back = rotations_from_path(path, quat[2])
    ok = np.isfinite(quat[:, 0])
    angle = (Rotation.from_quat(back[ok]).inv() * Rotation.from_quat(quat[ok])).magnitude()
    assert np.max(angle) < 1e-9
    assert np.all(np.isnan(back[~ok]))


def test_euler_path_and_artefacts_at_gimbal_lock() -> None:
    # pitch about the body y axis through 90 deg: Euler yaw and roll jump, the turn does not
    angle = np.radians(np.linspace(80.0, 100.0, 41))
    quat = Rotation.from_rotvec(np.outer(angle, [0.0, 1.0, 0.0])).as_quat()
    ypr = euler_path(quat)
    assert np.nanmax(np.abs(ypr[:, 1])) <= np.pi / 2 + 1e-12
    artefact, step = euler_artefacts(quat)
    assert np.any(artefact)
    np.testing.assert_allclose(step[1:], np.radians(0.5), rtol=1e-9)
    # away from the lock nothing is marked
    far = Rotation.from_rotvec(np.outer(np.radians(np.linspace(0, 40, 41)), [0, 1, 0]))
    assert not np.any(euler_artefacts(far.as_quat())[0])


def test_bad_quaternions_are_refused() -> None:
    with pytest.raises(ValueError, match=r"quat_xyzw: expected shape \(n, 4\)"):
        increment_path(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="zero quaternion"):
        increment_path(np.zeros((3, 4)))
    with pytest.raises(ValueError, match=r"path: expected shape \(n, 3\)"):
        rotations_from_path(np.zeros((3, 4)), [0, 0, 0, 1])
