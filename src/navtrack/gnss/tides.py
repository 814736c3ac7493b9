"""Solid Earth tide displacement of a station (IERS Conventions 2010, chapter 7.1.1, step 1).

:func:`solid_tide_m` gives the ECEF displacement of a point on the crust caused by the degree-2
and degree-3 tides of the Moon and the Sun, with the in-phase nominal Love and Shida numbers
``h2``, ``l2`` (latitude dependent, eq. 7.2) and ``h3``, ``l3`` (eq. 7.5): up to about 0.4 m
vertically and 0.05 m horizontally, twice a day. Step 2 (frequency-dependent corrections, up to
about 13 mm radially) and the ocean and pole tides are not applied. The displacement includes
the permanent tide, as the ITRF's conventional tide-free positions require.

:func:`sun_moon_ecef_m` gives the geocentric Sun and Moon positions from the low-precision
series of Montenbruck and Gill (ecliptic of date, rotated by the obliquity and by Greenwich mean
sidereal time, precession in longitude only; UT1 taken as GPS time minus the leap seconds): about
0.02 deg for the Sun and 0.3 deg for the Moon, far below what the tide needs (a millimetre).

References
----------
Petit, G., Luzum, B. (eds.), IERS Conventions (2010), IERS Technical Note 36, section 7.1.1
(eq. 7.5, 7.6 and the nominal Love numbers), and its DEHANTTIDEINEL test cases.
Montenbruck, O., Gill, E., Satellite Orbits (2000), section 3.3.2 (eq. 3.43-3.47).
"""

from __future__ import annotations

import numpy as np

from navtrack._typing import FloatArray

__all__ = ["solid_tide_m", "sun_moon_ecef_m"]

_GM_MOON_EARTH = 0.0123000371  # GM_Moon / GM_Earth (IERS 2010 table 1.1)
_GM_SUN_EARTH = 332946.0482  # GM_Sun / GM_Earth
_RE_M = 6378136.6  # equatorial radius (IERS 2010 table 1.1)
_ARCSEC = np.pi / 648000.0
_J2000_S = 630763200.0  # 2000-01-01 12:00 as seconds of a calendar counted from 1980-01-06
_TT_GPS_S = 51.184  # TT - GPS time (s)
_OBLIQUITY_RAD = np.radians(23.43929111)
_AU_M = 149.6e9


def _rotate_ecliptic_to_ecef(lon: FloatArray, lat: FloatArray, r: FloatArray, gmst: FloatArray):  # type: ignore[no-untyped-def]
    """ECEF ``(N, 3)`` of ecliptic longitude/latitude (rad) and distance (m) of date."""
    x = r * np.cos(lat) * np.cos(lon)
    y = r * np.cos(lat) * np.sin(lon)
    z = r * np.sin(lat)
    ce, se = np.cos(_OBLIQUITY_RAD), np.sin(_OBLIQUITY_RAD)
    ye, ze = ce * y - se * z, se * y + ce * z  # equatorial of date
    cg, sg = np.cos(gmst), np.sin(gmst)
    return np.stack([cg * x + sg * ye, -sg * x + cg * ye, ze], axis=-1)


def sun_moon_ecef_m(t_gps_s: FloatArray, leap_seconds: float = 18.0) -> tuple[FloatArray, ...]:
    """Geocentric ECEF positions (m) of the Sun and the Moon at GPS times ``t_gps_s``.

    Parameters
    ----------
    t_gps_s : array-like, shape (N,)
    leap_seconds : float
        GPS - UTC (s) at those times (18 since 2017), for sidereal time (UT1 ~ UTC).

    Returns
    -------
    sun, moon : ndarray, shape (N, 3)
    """
    t = np.atleast_1d(np.asarray(t_gps_s, dtype=float))
    T = (t + _TT_GPS_S - _J2000_S) / (86400.0 * 36525.0)  # Julian centuries of TT from J2000
    days_ut1 = (t - leap_seconds - _J2000_S) / 86400.0  # days of UT1 (~ UTC) from J2000
    gmst = np.radians((280.46061837 + 360.98564736629 * days_ut1) % 360.0)
    m = np.radians(357.5256 + 35999.049 * T)
    # the series are referred to the J2000 equinox: 1.3972 deg per century of general
    # precession in longitude bring them to the equinox of date, the frame GMST turns
    precession = np.radians(1.3972 * T)
    lon_sun = np.radians(282.9400) + m + (6892.0 * np.sin(m) + 72.0 * np.sin(2 * m)) * _ARCSEC
    lon_sun = lon_sun + precession
    r_sun = 149.619e9 - 2.499e9 * np.cos(m) - 0.021e9 * np.cos(2 * m)
    sun = _rotate_ecliptic_to_ecef(lon_sun, np.zeros_like(T), r_sun, gmst)
    L0, l, lp, F, D = (
        np.radians(a + b * T)
        for a, b in (
            (218.31617, 481267.88088),  # mean longitude of date
            (134.96292, 477198.86753),
            (357.52543, 35999.04944),
            (93.27283, 483202.01873),
            (297.85027, 445267.11135),
        )
    )
    dlon = (
        22640 * np.sin(l) + 769 * np.sin(2 * l) - 4586 * np.sin(l - 2 * D) + 2370 * np.sin(2 * D)
        - 668 * np.sin(lp) - 412 * np.sin(2 * F) - 212 * np.sin(2 * l - 2 * D)
        - 206 * np.sin(l + lp - 2 * D) + 192 * np.sin(l + 2 * D) - 165 * np.sin(lp - 2 * D)
        + 148 * np.sin(l - lp) - 125 * np.sin(D) - 110 * np.sin(l + lp) - 55 * np.sin(2 * F - 2 * D)
    )  # fmt: skip
    lon_moon = L0 + dlon * _ARCSEC
    u = F + (dlon + 412 * np.sin(2 * F) + 541 * np.sin(lp)) * _ARCSEC
    lat_moon = (
        18520 * np.sin(u) - 526 * np.sin(F - 2 * D) + 44 * np.sin(l + F - 2 * D)
        - 31 * np.sin(-l + F - 2 * D) - 25 * np.sin(-2 * l + F) - 23 * np.sin(lp + F - 2 * D)
        + 21 * np.sin(-l + F) + 11 * np.sin(-lp + F - 2 * D)
    ) * _ARCSEC  # fmt: skip
    r_moon = 1e3 * (
        385000 - 20905 * np.cos(l) - 3699 * np.cos(2 * D - l) - 2956 * np.cos(2 * D)
        - 570 * np.cos(2 * l) + 246 * np.cos(2 * l - 2 * D) - 205 * np.cos(lp - 2 * D)
        - 171 * np.cos(l + 2 * D) - 152 * np.cos(l + lp - 2 * D)
    )  # fmt: skip
    moon = _rotate_ecliptic_to_ecef(lon_moon, lat_moon, r_moon, gmst)
    return sun, moon


def solid_tide_m(station_m: FloatArray, sun_m: FloatArray, moon_m: FloatArray) -> FloatArray:
    """Solid Earth tide displacement (ECEF m) of a station, IERS 2010 step 1 (eq. 7.5).

    Parameters
    ----------
    station_m : array-like, shape (3,)
        Station ECEF position (m).
    sun_m, moon_m : array-like, shape (N, 3) or (3,)
        Geocentric ECEF positions of the Sun and the Moon (m).

    Returns
    -------
    ndarray, shape (N, 3) (or (3,) for single positions)
    """
    x = np.asarray(station_m, dtype=float)
    r = np.linalg.norm(x)
    rhat = x / r
    sin_lat2 = (x[2] / r) ** 2
    p2 = (3.0 * sin_lat2 - 1.0) / 2.0
    h2, l2 = 0.6078 - 0.0006 * p2, 0.0847 + 0.0002 * p2
    h3, l3 = 0.292, 0.015
    out = 0.0
    for body, ratio in ((moon_m, _GM_MOON_EARTH), (sun_m, _GM_SUN_EARTH)):
        b = np.asarray(body, dtype=float)
        rb = np.linalg.norm(b, axis=-1, keepdims=True)
        bhat = b / rb
        c = bhat @ rhat  # cosine of the body's angle from the station's zenith
        c1 = c[..., None]
        tangential = bhat - c1 * rhat
        k2 = ratio * _RE_M**4 / rb**3
        k3 = ratio * _RE_M**5 / rb**4
        deg2 = h2 * rhat * (1.5 * c1**2 - 0.5) + 3.0 * l2 * c1 * tangential
        deg3 = h3 * rhat * (2.5 * c1**3 - 1.5 * c1) + l3 * (7.5 * c1**2 - 1.5) * tangential
        out = out + k2 * deg2 + k3 * deg3
    return np.asarray(out)
