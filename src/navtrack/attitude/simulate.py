"""Simulated camera sightings of surveyed targets from a reference attitude (paper 6 set-up).

The paper's wide-angle camera saw plywood attitude targets at surveyed positions at most once a
second; every image with six or more targets gave a fix. Here the optical attitude of a real
recording plays the truth: at every ``interval_s`` an image is taken, the targets inside the
camera's field of view become body-frame rays with noise, a fraction of them is replaced by
misidentified rays (outliers), and the image is stamped with a camera clock that is off the IMU
clock by ``time_offset_s``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, BoolArray, FloatArray, IntArray

__all__ = ["CameraSimConfig", "Sightings", "simulate_sightings", "surveyed_targets"]


@dataclass(frozen=True, slots=True)
class CameraSimConfig:
    """Camera and target field of the simulated fixes.

    Attributes
    ----------
    interval_s : float
        Time between images (paper: "at a maximum rate of once a second").
    n_targets : int
        Surveyed targets, spread over all directions around the camera.
    fov_half_angle_deg : float
        Half-angle of the field of view about the camera boresight (body +z).
    min_rays : int
        Images with fewer visible targets give no fix (paper: six or more).
    sigma_rad : float
        Ray noise per axis, rad (1 mrad: about a pixel of a 60° camera 1024 pixels wide).
    outlier_fraction : float
        Fraction of each image's rays replaced by rays in a random direction inside the field of
        view (misidentified targets), rounded to the nearest integer count.
    time_offset_s : float
        Camera clock error: an image stamped ``t`` was taken at IMU time ``t + time_offset_s``.
    """

    interval_s: float = 1.0
    n_targets: int = 24
    fov_half_angle_deg: float = 90.0
    min_rays: int = 6
    sigma_rad: float = 1e-3
    outlier_fraction: float = 0.2
    time_offset_s: float = 0.0

    def __post_init__(self) -> None:
        if not self.interval_s > 0 or self.n_targets < 3 or self.min_rays < 3:
            raise ValueError(
                "interval_s > 0, n_targets >= 3 and min_rays >= 3 expected, got "
                f"{self.interval_s}, {self.n_targets}, {self.min_rays}"
            )
        if not 0 < self.fov_half_angle_deg <= 180 or self.sigma_rad < 0:
            raise ValueError("fov_half_angle_deg in (0, 180] and sigma_rad >= 0 expected")
        if not 0 <= self.outlier_fraction < 1:
            raise ValueError(f"outlier_fraction must be in [0, 1), got {self.outlier_fraction}")


@dataclass(frozen=True, slots=True, eq=False)
class Sightings:
    """Simulated images (fixed shapes, ``valid`` masks; arrays read-only).

    Attributes
    ----------
    t_stamp_s : (m,) camera time stamps, s
    sample : (m,) IMU sample at which each image was taken (truth index)
    v_body : (m, n_targets, 3) measured rays, camera (body) frame
    w_ref : (n_targets, 3) rays from the camera to the surveyed targets, reference frame
    visible : (m, n_targets) bool, target in the field of view (ray present)
    outlier : (m, n_targets) bool, ray replaced by a misidentified one
    n_no_truth : int
        Image times skipped because the truth attitude was missing (NaN).
    """

    t_stamp_s: FloatArray
    sample: IntArray
    v_body: FloatArray
    w_ref: FloatArray
    visible: BoolArray
    outlier: BoolArray
    n_no_truth: int

    def __post_init__(self) -> None:
        freeze_arrays(self)


def surveyed_targets(rng: np.random.Generator, n: int) -> FloatArray:
    """Unit rays ``(n, 3)`` to targets spread over all directions (a Fibonacci sphere with a
    random rotation), reference frame."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    phi = np.pi * (3.0 - np.sqrt(5.0)) * i
    r = np.sqrt(1.0 - z * z)
    pts = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
    return np.asarray(Rotation.random(rng=rng).apply(pts), dtype=np.float64)


def _random_in_cone(rng: np.random.Generator, k: int, half_angle_rad: float) -> FloatArray:
    cos_max = np.cos(half_angle_rad)
    z = rng.uniform(cos_max, 1.0, k)
    phi = rng.uniform(0.0, 2.0 * np.pi, k)
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def simulate_sightings(
    t_s: ArrayLike,
    truth_xyzw: ArrayLike,
    rng: np.random.Generator,
    config: CameraSimConfig | None = None,
) -> Sightings:
    """Images of the surveyed targets every ``config.interval_s`` along a truth attitude.

    Parameters
    ----------
    t_s : (n,) IMU sample times, s
    truth_xyzw : (n, 4) truth attitude, body -> reference, scalar-last; NaN rows allowed
    rng : numpy.random.Generator
        Target layout, ray noise, outliers.
    config : CameraSimConfig or None

    Returns
    -------
    Sightings
        One image per interval whose truth is present (images with fewer than ``min_rays``
        visible targets are kept; the fix step reports them).
    """
    cfg = CameraSimConfig() if config is None else config
    t = np.asarray(t_s, dtype=np.float64)
    q = np.asarray(truth_xyzw, dtype=np.float64)
    grid = np.arange(t[0] + 0.5 * cfg.interval_s, t[-1], cfg.interval_s)
    sample = np.clip(np.searchsorted(t, grid), 0, t.size - 1)
    present = np.all(np.isfinite(q[sample]), axis=1)
    sample = sample[present]
    m, nt = sample.size, cfg.n_targets
    w = surveyed_targets(rng, nt)
    to_body = np.asarray(Rotation.from_quat(q[sample]).inv().as_matrix(), dtype=np.float64)
    v = np.einsum("mij,nj->mni", to_body, w)
    noise = Rotation.from_rotvec(rng.normal(0.0, cfg.sigma_rad, (m * nt, 3)))
    v = np.asarray(noise.apply(v.reshape(-1, 3)), dtype=np.float64).reshape(m, nt, 3)
    half = np.radians(cfg.fov_half_angle_deg)
    visible = v[..., 2] > np.cos(half)
    outlier = np.zeros((m, nt), bool)
    for i in range(m):
        seen = np.flatnonzero(visible[i])
        k = round(cfg.outlier_fraction * seen.size)
        if k:
            bad = rng.choice(seen, k, replace=False)
            outlier[i, bad] = True
            v[i, bad] = _random_in_cone(rng, k, half)
    stamps = t[sample] - cfg.time_offset_s
    return Sightings(stamps, sample, v, w, visible, outlier, int(np.count_nonzero(~present)))
