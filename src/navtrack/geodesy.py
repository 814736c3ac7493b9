"""WGS-84 geodesy: ECEF <-> geodetic <-> local ENU, azimuth and elevation.

All functions are vectorised over leading axes; positions are ``(..., 3)`` arrays in metres,
angles in radians.

References
----------
NIMA TR8350.2, *Department of Defense World Geodetic System 1984*, 3rd ed. (constants);
B. Hofmann-Wellenhof, H. Lichtenegger, E. Wasle, *GNSS*, Springer 2008, sections 8.2 and 8.3
(geodetic conversion, local frames).
"""

from __future__ import annotations

import numpy as np

from navtrack._typing import ArrayLike, FloatArray

WGS84_A_M = 6378137.0
WGS84_F = 1.0 / 298.257223563
WGS84_E2 = WGS84_F * (2.0 - WGS84_F)
OMEGA_E_RAD_S = 7.2921151467e-5
C_MPS = 299792458.0


# Plausible distance from the earth's centre of a point near its surface (m): 6357 km (pole)
# - 150 km to 6378 km (equator) + 200 km; anything else is a position in the wrong units or
# frame (latitude/longitude in degrees, kilometres).
NEAR_SURFACE_NORM_M = (6.2e6, 6.6e6)


def check_near_surface(xyz_m: ArrayLike, name: str = "xyz_m") -> FloatArray:
    """One ECEF position as a float array of shape (3,), refusing implausible values.

    Parameters
    ----------
    xyz_m : array-like, shape (3,)
        ECEF position (m) of a point near the earth's surface (a receiver, a reference).
    name : str
        Parameter name used in the error message.

    Raises
    ------
    ValueError
        Not three finite numbers, or farther from the earth's centre than
        :data:`NEAR_SURFACE_NORM_M` allows.
    """
    xyz = np.asarray(xyz_m, dtype=float)
    if xyz.shape != (3,) or not np.all(np.isfinite(xyz)):
        raise ValueError(f"{name}: expected three finite ECEF coordinates (m), got {xyz!r}")
    norm = float(np.linalg.norm(xyz))
    lo, hi = NEAR_SURFACE_NORM_M
    if not lo <= norm <= hi:
        raise ValueError(
            f"{name}: distance from the earth's centre is {norm:.6g} m, not a point near the "
            f"earth's surface ({lo:.3g}-{hi:.3g} m); give ECEF metres"
        )
    return xyz


def _as_xyz(name: str, value: ArrayLike) -> FloatArray:
    arr = np.asarray(value, dtype=float)
    if arr.shape[-1:] != (3,):
        raise ValueError(f"{name}: expected shape (..., 3), got {arr.shape}")
    return arr


def geodetic_to_ecef(llh: ArrayLike) -> FloatArray:
    """ECEF position of geodetic coordinates.

    Parameters
    ----------
    llh : array-like, shape (..., 3)
        Latitude (rad), longitude (rad), ellipsoidal height (m).

    Returns
    -------
    ndarray, shape (..., 3)
        ECEF x, y, z in metres.
    """
    llh = _as_xyz("llh", llh)
    lat, lon, h = llh[..., 0], llh[..., 1], llh[..., 2]
    sin_lat = np.sin(lat)
    n = WGS84_A_M / np.sqrt(1.0 - WGS84_E2 * sin_lat**2)
    return np.stack(
        [
            (n + h) * np.cos(lat) * np.cos(lon),
            (n + h) * np.cos(lat) * np.sin(lon),
            (n * (1.0 - WGS84_E2) + h) * sin_lat,
        ],
        axis=-1,
    )


def ecef_to_geodetic(xyz: ArrayLike) -> FloatArray:
    """Geodetic latitude, longitude (rad) and height (m) of ECEF positions.

    Iterates the latitude equation a fixed six times, from the zero-height latitude
    ``tan(lat) = z / (p (1 - e^2))``; the iteration converges linearly at a rate of order
    ``e^2`` (about 0.007), so two to four steps already reach sub-millimetre for terrestrial and
    orbital heights.

    Parameters
    ----------
    xyz : array-like, shape (..., 3)
        ECEF position in metres.

    Returns
    -------
    ndarray, shape (..., 3)
        Latitude (rad), longitude (rad), ellipsoidal height (m).
    """
    xyz = _as_xyz("xyz", xyz)
    x, y, z = xyz[..., 0], xyz[..., 1], xyz[..., 2]
    p = np.hypot(x, y)
    lon = np.arctan2(y, x)
    # Latitude at zero height, then fixed-point iteration on the latitude.
    lat = np.arctan2(z, p * (1.0 - WGS84_E2))
    for _ in range(6):
        sin_lat = np.sin(lat)
        n = WGS84_A_M / np.sqrt(1.0 - WGS84_E2 * sin_lat**2)
        lat = np.arctan2(z + WGS84_E2 * n * sin_lat, p)
    sin_lat = np.sin(lat)
    cos_lat = np.cos(lat)
    n = WGS84_A_M / np.sqrt(1.0 - WGS84_E2 * sin_lat**2)
    # Height stable at all latitudes (Hofmann-Wellenhof et al., eq. 8.18 rearranged).
    h = p * cos_lat + z * sin_lat - n * (1.0 - WGS84_E2 * sin_lat**2)
    return np.stack([lat, lon, h], axis=-1)


def enu_rotation(lat_rad: ArrayLike, lon_rad: ArrayLike) -> FloatArray:
    """Rotation matrices ECEF -> local east/north/up.

    Parameters
    ----------
    lat_rad, lon_rad : array-like, broadcastable shapes ``(...)``
        Geodetic latitude and longitude (rad) of the local frame's origin.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ``R`` with ``enu = R @ (xyz - ref_xyz)``; its rows are the east, north and up unit
        vectors in ECEF (local-level frame of the module References).
    """
    lat = np.asarray(lat_rad, dtype=float)
    lon = np.asarray(lon_rad, dtype=float)
    sl, cl = np.sin(lat), np.cos(lat)
    so, co = np.sin(lon), np.cos(lon)
    zero = np.zeros_like(sl * so)
    return np.stack(
        [
            np.stack([-so + zero, co + zero, zero], axis=-1),
            np.stack([-sl * co, -sl * so, cl + zero], axis=-1),
            np.stack([cl * co, cl * so, sl + zero], axis=-1),
        ],
        axis=-2,
    )


def ecef_to_enu(xyz: ArrayLike, ref_xyz: ArrayLike) -> FloatArray:
    """East/north/up coordinates (m) of ECEF points relative to a reference ECEF point.

    Parameters
    ----------
    xyz : array-like, shape (..., 3)
        ECEF positions (m).
    ref_xyz : array-like, shape (..., 3)
        ECEF reference position(s) (m), broadcast against ``xyz``; the ENU axes are those of the
        ellipsoid normal at the reference.
    """
    xyz = _as_xyz("xyz", xyz)
    ref = _as_xyz("ref_xyz", ref_xyz)
    llh = ecef_to_geodetic(ref)
    rot = enu_rotation(llh[..., 0], llh[..., 1])
    return np.einsum("...ij,...j->...i", rot, xyz - ref)


def azimuth_elevation(sat_xyz: ArrayLike, rcv_xyz: ArrayLike) -> FloatArray:
    """Azimuth and elevation (rad) of satellites seen from a receiver.

    Parameters
    ----------
    sat_xyz : array-like, shape (..., 3)
        Satellite ECEF positions (m).
    rcv_xyz : array-like, shape (..., 3)
        Receiver ECEF positions (m), broadcast against ``sat_xyz``.

    Returns
    -------
    ndarray, shape (..., 2)
        Azimuth in [0, 2 pi) clockwise from north, elevation in [-pi/2, pi/2].
    """
    enu = ecef_to_enu(sat_xyz, rcv_xyz)
    az = np.mod(np.arctan2(enu[..., 0], enu[..., 1]), 2.0 * np.pi)
    el = np.arctan2(enu[..., 2], np.hypot(enu[..., 0], enu[..., 1]))
    return np.stack([az, el], axis=-1)
