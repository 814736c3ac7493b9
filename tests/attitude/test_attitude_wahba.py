"""SVD attitude and RANSAC, against scipy's Rotation.align_vectors as the oracle."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from navtrack.attitude.wahba import (
    FixStatus,
    RansacConfig,
    ransac_attitude,
    ransac_trials,
    solve_fixes,
    svd_attitude,
)


def _scene(
    rng: np.random.Generator, n: int, sigma: float, n_out: int = 0
) -> tuple[Rotation, np.ndarray, np.ndarray, np.ndarray]:
    truth = Rotation.random(rng=rng)
    w = rng.normal(size=(n, 3))
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    v = truth.inv().apply(w)
    v = Rotation.from_rotvec(rng.normal(0.0, sigma, (n, 3))).apply(v)
    out = np.zeros(n, bool)
    out[rng.choice(n, n_out, replace=False)] = True
    v[out] = rng.normal(size=(n_out, 3))
    v[out] /= np.linalg.norm(v[out], axis=1, keepdims=True)
    return truth, v, w, out


def test_svd_attitude_matches_align_vectors() -> None:
    rng = np.random.default_rng(10)
    for _ in range(20):
        _, v, w, _ = _scene(rng, 7, 0.01)
        a = rng.uniform(0.5, 2.0, 7)
        R, _ = svd_attitude(v, w, a)
        oracle, _ = Rotation.align_vectors(w, v, weights=a)
        assert (Rotation.from_matrix(R) * oracle.inv()).magnitude() < 1e-10
        assert np.linalg.det(R) == pytest.approx(1.0)


def test_svd_attitude_is_proper_for_coplanar_rays() -> None:
    """Targets on a line seen from off the line give coplanar rays: A Bᵀ alone can be a
    reflection; the det correction keeps a rotation, equal to the oracle's."""
    rng = np.random.default_rng(11)
    truth = Rotation.random(rng=rng)
    targets = np.column_stack([np.linspace(-5, 5, 6), np.full(6, 10.0), np.zeros(6)])
    w = targets / np.linalg.norm(targets, axis=1, keepdims=True)
    v = Rotation.from_rotvec(rng.normal(0, 1e-3, (6, 3))).apply(truth.inv().apply(w))
    R, s = svd_attitude(v, w)
    assert s[2] < 1e-2 * s[0]  # rank two: coplanar
    assert np.linalg.det(R) == pytest.approx(1.0)
    oracle, _ = Rotation.align_vectors(w, v)
    assert (Rotation.from_matrix(R) * oracle.inv()).magnitude() < 1e-9
    fix = ransac_attitude(v, w, rng)
    assert fix.status == FixStatus.OK
    assert (Rotation.from_quat(fix.quat) * truth.inv()).magnitude() < 5e-3


def test_ransac_rejects_every_outlier_with_20_percent() -> None:
    """Seeded scenes: 10 rays, 2 outliers, 1 mrad noise; every outlier is rejected, every
    inlier kept, and the attitude is the oracle's least squares on the true inliers (so within
    the noise: below 3 mrad)."""
    cfg = RansacConfig()
    for seed in range(100):
        rng = np.random.default_rng(seed)
        truth, v, w, out = _scene(rng, 10, 1e-3, 2)
        fix = ransac_attitude(v, w, rng, cfg)
        assert fix.status == FixStatus.OK
        np.testing.assert_array_equal(fix.inliers, ~out)
        oracle, _ = Rotation.align_vectors(w[~out], v[~out])
        est = Rotation.from_quat(fix.quat)
        assert (est * oracle.inv()).magnitude() < 1e-9
        assert (est * truth.inv()).magnitude() < 3e-3
        assert fix.residuals_rad[out].min() > cfg.threshold_rad
        assert fix.n_inliers == 8


def test_ransac_is_seeded() -> None:
    _, v, w, _ = _scene(np.random.default_rng(3), 12, 1e-3, 3)
    a = ransac_attitude(v, w, np.random.default_rng(5))
    b = ransac_attitude(v, w, np.random.default_rng(5))
    np.testing.assert_array_equal(a.quat, b.quat)


def test_statuses_and_bad_input() -> None:
    rng = np.random.default_rng(4)
    _, v, w, _ = _scene(rng, 2, 0.0)
    assert ransac_attitude(v, w, rng).status == FixStatus.TOO_FEW_RAYS
    assert str(FixStatus.TOO_FEW_RAYS) == "too_few_rays"
    # targets on a line through the camera: parallel rays, rotation about them undetermined
    w_par = np.tile([0.0, 0.6, 0.8], (5, 1))
    fix = ransac_attitude(w_par, w_par, rng)
    assert fix.status == FixStatus.DEGENERATE
    assert np.all(np.isnan(fix.quat))
    with pytest.raises(ValueError, match="w_ref: ray 1 is zero or not finite"):
        ransac_attitude(np.ones((4, 3)), [[1, 0, 0], [np.nan, 0, 0], [0, 1, 0], [0, 0, 1]], rng)
    with pytest.raises(ValueError, match="same shape"):
        ransac_attitude(np.ones((4, 3)), np.ones((5, 3)), rng)
    with pytest.raises(ValueError, match="threshold_rad"):
        RansacConfig(threshold_rad=0.0)
    assert ransac_trials(0.5) == 52  # ceil(log(0.001) / log(1 - 0.125))
    assert ransac_trials(0.0) == 1


def test_solve_fixes_counts_statuses() -> None:
    rng = np.random.default_rng(6)
    truth, v, w, _ = _scene(rng, 8, 1e-3)
    vb = np.stack([v, v, v])
    visible = np.ones((3, 8), bool)
    visible[1, 3:] = False  # three rays: below min_rays
    fixes = solve_fixes(vb, w, visible, rng, min_rays=6)
    assert fixes.status_counts() == {
        "ok": 2,
        "too_few_rays": 1,
        "degenerate": 0,
        "no_consensus": 0,
    }
    assert (Rotation.from_quat(fixes.quat[0]) * truth.inv()).magnitude() < 3e-3
    assert np.all(np.isnan(fixes.quat[1]))
