"""Flash-LIDAR verification of a reconstructed pose: DEM correlation shifts, yaw and pitch
(paper 6, eqs. 10-11).

The paper verifies the reconstructed attitude with the flash LIDAR: the LIDAR points, placed in
the target frame with the reconstructed pose (eqs. 8-9), are shifted until they fit the
surveyed truth DEM best; the shift ``(Δx, Δy, Δz)`` in the LIDAR frame (``z`` the boresight, the
array rows and columns ``x`` and ``y``) gives

``yaw = tan⁻¹(Δy / (d - Δz))`` (eq. 10), ``pitch = tan⁻¹(Δx / (d - Δz))`` (eq. 11)

with ``d`` the distance to the target. Here a terrain patch is a smooth random surface
(:func:`smooth_dem`), the LIDAR ranges are the intersections of the array's pixel rays with it
from the true pose (:func:`lidar_points`), and the shift is the least-squares fit of the points
placed with the reconstructed pose to the DEM (:func:`correlation_shift`).

A shift along ``y`` comes from a rotation about the LIDAR ``x`` axis and one along ``x`` from a
rotation about ``y``; the paper's text calls yaw "the rotation about the LIDAR y axis", the
opposite pairing to its equations. The equations are implemented as printed and the result
names say which shift each angle comes from.

References
----------
.. [1] ALHAT flash-LIDAR field test 1 (paper 6): "Constructing the LIDAR trajectory" (eqs. 8-9),
   "Instrument verification" (eqs. 10-11).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.ndimage import gaussian_filter, map_coordinates, spline_filter
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, FloatArray

__all__ = [
    "Dem",
    "FlashLidarConfig",
    "LidarShift",
    "correlation_shift",
    "lidar_points",
    "smooth_dem",
    "yaw_pitch_from_shift",
]


@dataclass(frozen=True, slots=True, eq=False)
class Dem:
    """A gridded terrain model (arrays read-only).

    Attributes
    ----------
    x0_m, y0_m : float
        Target-frame coordinates of the grid's first post (east, north).
    spacing_m : float
    z_m : (ny, nx) heights, m (row = y, column = x)
    coef : (ny, nx) cubic B-spline coefficients of ``z_m`` (computed, not passed)
    """

    x0_m: float
    y0_m: float
    spacing_m: float
    z_m: FloatArray
    coef: FloatArray = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "coef", spline_filter(self.z_m, order=3, mode="mirror"))
        freeze_arrays(self)

    def height(self, xy_m: ArrayLike) -> FloatArray:
        """Heights ``(...)`` at points ``(..., 2)`` (cubic spline; NaN outside the grid)."""
        xy = np.asarray(xy_m, dtype=np.float64)
        col = (xy[..., 0] - self.x0_m) / self.spacing_m
        row = (xy[..., 1] - self.y0_m) / self.spacing_m
        coords = np.stack([row.ravel(), col.ravel()])
        h = map_coordinates(self.coef, coords, order=3, mode="mirror", prefilter=False)
        outside = (
            (row < 0) | (row > self.z_m.shape[0] - 1) | (col < 0) | (col > self.z_m.shape[1] - 1)
        )
        h = np.asarray(h, dtype=np.float64).reshape(row.shape)
        return np.where(outside, np.nan, h)


def smooth_dem(
    rng: np.random.Generator,
    size_m: float = 80.0,
    spacing_m: float = 0.1,
    relief_m: float = 1.0,
    correlation_m: float = 1.5,
) -> Dem:
    """A smooth random terrain patch centred on the target-frame origin: white noise smoothed
    by a Gaussian of ``correlation_m`` and scaled to a standard deviation of ``relief_m``."""
    n = round(size_m / spacing_m) + 1
    z = gaussian_filter(rng.normal(size=(n, n)), correlation_m / spacing_m, mode="wrap")
    z *= relief_m / np.std(z)
    half = 0.5 * (n - 1) * spacing_m
    return Dem(-half, -half, spacing_m, z)


@dataclass(frozen=True, slots=True)
class FlashLidarConfig:
    """The flash LIDAR's array (FT1's LIDAR: a 128 x 128 array).

    Attributes
    ----------
    pixels : int
        Array side, pixels.
    fov_deg : float
        Full field of view of the array side.
    range_sigma_m : float
        Range noise per pixel.
    """

    pixels: int = 128
    fov_deg: float = 1.0
    range_sigma_m: float = 0.02

    def rays(self) -> FloatArray:
        """Unit pixel rays ``(pixels², 3)`` in the LIDAR frame (``z`` boresight)."""
        half = np.tan(np.radians(0.5 * self.fov_deg))
        g = np.linspace(-half, half, self.pixels)
        x, y = np.meshgrid(g, g)
        v = np.stack([x.ravel(), y.ravel(), np.ones(x.size)], axis=1)
        return v / np.linalg.norm(v, axis=1, keepdims=True)


def lidar_points(
    dem: Dem,
    position_m: ArrayLike,
    attitude: Rotation,
    rng: np.random.Generator,
    config: FlashLidarConfig | None = None,
    iterations: int = 30,
) -> FloatArray:
    """LIDAR returns ``(p, 3)`` in the LIDAR frame (range times pixel ray) from a pose.

    Each pixel ray from ``position_m`` (target frame) along ``attitude`` (LIDAR -> target
    frame) is intersected with the DEM by fixed-point iteration on the range; rays that leave
    the DEM give NaN rows.
    """
    cfg = FlashLidarConfig() if config is None else config
    r = np.asarray(position_m, dtype=np.float64)
    u = cfg.rays()
    u_t = np.asarray(attitude.apply(u), dtype=np.float64)
    if np.any(u_t[:, 2] >= 0):
        raise ValueError("attitude: the LIDAR must look down at the DEM (boresight z < 0)")
    rho = (0.0 - r[2]) / u_t[:, 2]
    for _ in range(iterations):
        p = r + rho[:, None] * u_t
        rho = (dem.height(p[:, :2]) - r[2]) / u_t[:, 2]
    rho = rho + rng.normal(0.0, cfg.range_sigma_m, rho.size)
    return rho[:, None] * u


@dataclass(frozen=True, slots=True, eq=False)
class LidarShift:
    """The DEM-correlation shift of one LIDAR frame and its angles (eqs. 10-11).

    Attributes
    ----------
    shift_m : (3,) ``(Δx, Δy, Δz)`` in the LIDAR frame that best fits the points to the DEM
    distance_m : float
        Mean range ``d`` to the target.
    yaw_eq10_rad : float
        ``tan⁻¹(Δy / (d - Δz))`` (from the shift along the LIDAR ``y`` axis).
    pitch_eq11_rad : float
        ``tan⁻¹(Δx / (d - Δz))`` (from the shift along ``x``).
    rms_m : float
        RMS height residual after the shift.
    converged : bool
    """

    shift_m: FloatArray
    distance_m: float
    yaw_eq10_rad: float
    pitch_eq11_rad: float
    rms_m: float
    converged: bool

    def __post_init__(self) -> None:
        freeze_arrays(self)


def yaw_pitch_from_shift(shift_m: ArrayLike, distance_m: float) -> tuple[float, float]:
    """Eqs. 10-11: ``(tan⁻¹(Δy/(d-Δz)), tan⁻¹(Δx/(d-Δz)))``, rad."""
    dx, dy, dz = np.asarray(shift_m, dtype=np.float64)
    return float(np.arctan2(dy, distance_m - dz)), float(np.arctan2(dx, distance_m - dz))


def correlation_shift(
    dem: Dem, position_m: ArrayLike, attitude_est: Rotation, points_lidar: ArrayLike
) -> LidarShift:
    """The shift of the LIDAR points (placed with a reconstructed pose) onto the DEM.

    Parameters
    ----------
    dem : Dem
    position_m : (3,) reconstructed LIDAR position, target frame (eq. 9)
    attitude_est : Rotation
        Reconstructed LIDAR attitude, LIDAR -> target frame (eq. 8).
    points_lidar : (p, 3) LIDAR returns in the LIDAR frame (:func:`lidar_points`); NaN rows
        are left out.

    Returns
    -------
    LidarShift
        The least-squares shift minimising the height differences between the shifted points
        and the DEM. A point shifted off the DEM adds no residual; callers check that the
        frame lies on the DEM (the reproduction counts frames that do not as ``off_dem``).
    """
    pts = np.asarray(points_lidar, dtype=np.float64)
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    r = np.asarray(position_m, dtype=np.float64)
    placed = r + np.asarray(attitude_est.apply(pts), dtype=np.float64)
    rot = np.asarray(attitude_est.as_matrix(), dtype=np.float64)

    def residual(s: FloatArray) -> FloatArray:
        p = placed + rot @ s
        h = dem.height(p[:, :2])
        return np.where(np.isfinite(h), p[:, 2] - h, 0.0)

    fit = least_squares(residual, np.zeros(3), method="lm", x_scale=0.1)
    d = float(np.mean(np.linalg.norm(pts, axis=1)))
    yaw, pitch = yaw_pitch_from_shift(fit.x, d)
    rms = float(np.sqrt(np.mean(fit.fun**2)))
    return LidarShift(fit.x, d, yaw, pitch, rms, bool(fit.success))
