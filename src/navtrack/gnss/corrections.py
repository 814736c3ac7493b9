"""Range corrections for pseudorange positioning: geometry with Sagnac, ionosphere, troposphere.

All functions are vectorised over leading axes (typically ``(epochs, satellites)``) and take SI
units and radians.

References
----------
IS-GPS-200N 20.3.3.5.2.5 (Klobuchar model) and 20.3.3.3.3.3 (dual-frequency combination);
J. Saastamoinen, "Atmospheric correction for the troposphere and stratosphere in radio ranging
of satellites", AGU Geophysical Monograph 15, 1972 (zenith delays);
RTCA DO-229D A.4.4.10 / J. Kouba, *A guide to using IGS products*, 2009, 4.2 (Sagnac term);
B. Hofmann-Wellenhof et al., *GNSS*, Springer 2008, 5.3 (standard atmosphere, ionosphere-free
combination); RTKLIB 2.4.3 manual E.5 (the standard-atmosphere parameters used by its SPP).
"""

from __future__ import annotations

import numpy as np

from navtrack._typing import ArrayLike, FloatArray
from navtrack.geodesy import C_MPS, OMEGA_E_RAD_S

FREQ_L1_HZ = 1575.42e6

FREQUENCY_HZ: dict[str, dict[str, float]] = {
    "G": {"1": 1575.42e6, "2": 1227.60e6, "5": 1176.45e6},
    "J": {"1": 1575.42e6, "2": 1227.60e6, "5": 1176.45e6, "6": 1278.75e6},
    "E": {"1": 1575.42e6, "5": 1176.45e6, "7": 1207.14e6, "8": 1191.795e6, "6": 1278.75e6},
    "C": {"1": 1575.42e6, "2": 1561.098e6, "5": 1176.45e6, "6": 1268.52e6, "7": 1207.14e6},
    "I": {"5": 1176.45e6, "9": 2492.028e6},
    "S": {"1": 1575.42e6, "5": 1176.45e6},
}
"""Carrier frequencies (Hz) per system and RINEX 3 band digit (RINEX 3.05 table 4-10)."""

KLOBUCHAR_DEFAULT = np.array(
    [0.1118e-07, -0.7451e-08, -0.5961e-07, 0.1192e-06, 0.1167e06, -0.2294e06, -0.1311e06, 0.1049e07]
)
"""Klobuchar alpha/beta used when a navigation file gives none (RTKLIB's default set, a typical
broadcast of 2004), so that results stay comparable with RTKLIB's SPP."""


def frequency_hz(system: str, band: str, freq_num: ArrayLike | None = None) -> FloatArray:
    """Carrier frequency of a system and band; GLONASS FDMA needs the frequency number ``k``.

    GLONASS G1 = 1602 + 0.5625 k MHz, G2 = 1246 + 0.4375 k MHz (ICD 5.1 3.3.1.4); G3 1202.025.
    """
    if system == "R":
        k = np.asarray(0 if freq_num is None else freq_num, dtype=float)
        match band:
            case "1":
                return np.asarray(1602.0e6 + 0.5625e6 * k)
            case "2":
                return np.asarray(1246.0e6 + 0.4375e6 * k)
            case "3":
                return np.asarray(1202.025e6 + 0.0 * k)
        raise ValueError(f"band: no GLONASS band {band!r}")
    try:
        return np.asarray(FREQUENCY_HZ[system][band])
    except KeyError:
        raise ValueError(f"band: no band {band!r} for system {system!r}") from None


def geometric_range(sat_xyz_m: ArrayLike, rcv_xyz_m: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Range from receiver to satellite with the Sagnac (earth rotation) correction.

    The satellite position is earth-fixed at *transmission*; the signal travels while the earth
    turns by ``Omega_e tau``. To first order the range in the frame of reception is
    ``|r_s - r_r| + Omega_e (x_s y_r - y_s x_r) / c``.

    Parameters
    ----------
    sat_xyz_m : array-like, shape (..., 3)
        Satellite ECEF position at transmission (m).
    rcv_xyz_m : array-like, shape (..., 3)
        Receiver ECEF position (m), broadcast against ``sat_xyz_m``.

    Returns
    -------
    range_m : ndarray, shape (...)
        Geometric range including the Sagnac term (m).
    los : ndarray, shape (..., 3)
        Unit vector from receiver to satellite (ECEF).
    """
    rs = np.asarray(sat_xyz_m, dtype=float)
    rr = np.asarray(rcv_xyz_m, dtype=float)
    d = rs - rr
    rho = np.sqrt(np.einsum("...i,...i->...", d, d))
    los = d / rho[..., None]
    sagnac = OMEGA_E_RAD_S * (rs[..., 0] * rr[..., 1] - rs[..., 1] * rr[..., 0]) / C_MPS
    return rho + sagnac, los


def transmit_time(t_rx_gps_s: ArrayLike, pr_m: ArrayLike) -> FloatArray:
    """Signal transmission time *by the satellite clock*: ``t_rx - P / c``.

    The pseudorange is the difference of the receiver's reception time tag and the satellite's
    transmission time tag times ``c``, so this is exact in the satellite time scale; the
    satellite clock offset is then removed with the broadcast clock
    (:func:`navtrack.gnss.ephemeris.broadcast_states`). No iteration on the geometry is needed.
    """
    t = np.asarray(t_rx_gps_s, dtype=float)
    pr = np.asarray(pr_m, dtype=float)
    if t.ndim == 1 and pr.ndim == 2:
        t = t[:, None]
    return t - pr / C_MPS


def klobuchar_delay_m(
    t_gps_s: ArrayLike,
    lat_rad: ArrayLike,
    lon_rad: ArrayLike,
    az_rad: ArrayLike,
    el_rad: ArrayLike,
    params: ArrayLike | None,
) -> FloatArray:
    """Ionospheric group delay on GPS L1 (m) of the Klobuchar broadcast model.

    Parameters
    ----------
    t_gps_s : array-like
        GPS time (the local time uses GPS seconds of day).
    lat_rad, lon_rad : array-like
        Receiver geodetic latitude and longitude (rad).
    az_rad, el_rad : array-like
        Satellite azimuth and elevation (rad).
    params : array-like, shape (8,), or None
        ``alpha0..3`` (s, s/sc, s/sc^2, s/sc^3) then ``beta0..3`` (s, ...); ``None`` or all zero
        uses :data:`KLOBUCHAR_DEFAULT`.

    Returns
    -------
    ndarray
        Delay (m) on L1 (scale by ``(f_L1 / f)^2`` for other frequencies); 0 for ``el <= 0``.

    References
    ----------
    IS-GPS-200N 20.3.3.5.2.5 and figure 20-4 (all angles in semicircles).
    """
    p = KLOBUCHAR_DEFAULT if params is None else np.asarray(params, dtype=float)
    if p.shape != (8,):
        raise ValueError(f"params: expected 8 Klobuchar coefficients, got shape {p.shape}")
    if not np.any(p):
        p = KLOBUCHAR_DEFAULT
    alpha, beta = p[:4], p[4:]
    el = np.asarray(el_rad, dtype=float)
    az = np.asarray(az_rad, dtype=float)
    e_sc = el / np.pi
    psi = 0.0137 / (e_sc + 0.11) - 0.022
    phi_i = np.clip(np.asarray(lat_rad) / np.pi + psi * np.cos(az), -0.416, 0.416)
    lam_i = np.asarray(lon_rad) / np.pi + psi * np.sin(az) / np.cos(phi_i * np.pi)
    phi_m = phi_i + 0.064 * np.cos((lam_i - 1.617) * np.pi)
    t = np.mod(4.32e4 * lam_i + np.asarray(t_gps_s, dtype=float), 86400.0)
    g = 0.53 - e_sc
    f = 1.0 + 16.0 * g * g * g  # products: ``**`` with exponents 3, 4 calls pow, ten times slower
    amp = alpha[0] + phi_m * (alpha[1] + phi_m * (alpha[2] + phi_m * alpha[3]))
    per = beta[0] + phi_m * (beta[1] + phi_m * (beta[2] + phi_m * beta[3]))
    amp = np.maximum(amp, 0.0)
    per = np.maximum(per, 72000.0)
    x = 2.0 * np.pi * (t - 50400.0) / per
    x2 = x * x
    night = 5e-9
    day = night + amp * (1.0 - x2 / 2.0 + x2 * x2 / 24.0)
    delay_s = f * np.where(np.abs(x) < 1.57, day, night)
    return np.where(el > 0.0, C_MPS * delay_s, 0.0)


def saastamoinen_delay_m(
    lat_rad: ArrayLike,
    h_m: ArrayLike,
    el_rad: ArrayLike,
    *,
    humidity: float = 0.7,
) -> FloatArray:
    """Slant tropospheric delay (m), Saastamoinen model with a standard atmosphere.

    Standard atmosphere at ellipsoidal height ``h`` (clamped at 0): pressure
    ``1013.25 (1 - 2.2557e-5 h)^5.2568`` hPa, temperature ``15 - 6.5e-3 h`` degC, water vapour
    pressure from the relative ``humidity`` by Magnus' formula
    ``6.108 RH exp((17.15 T - 4684) / (T - 38.45))`` (T in K). Zenith delays (Saastamoinen 1972)
    ``0.0022768 P / (1 - 0.00266 cos 2 phi - 0.00028 h_km)`` (hydrostatic) and
    ``0.002277 (1255 / T + 0.05) e`` (wet), both mapped with ``1 / cos z``. Heights outside
    [-100 m, 10 km] or ``el <= 0`` give 0 (the model's range; RTKLIB does the same).

    Parameters
    ----------
    lat_rad, h_m : array-like
        Receiver latitude (rad) and ellipsoidal height (m).
    el_rad : array-like
        Elevation (rad).
    humidity : float
        Relative humidity 0-1 (RTKLIB's SPP uses 0.7).
    """
    h = np.asarray(h_m, dtype=float)
    el = np.asarray(el_rad, dtype=float)
    lat = np.asarray(lat_rad, dtype=float)
    hgt = np.clip(h, 0.0, 1e4)  # outside [-100 m, 10 km] the result is 0 anyway
    pres = 1013.25 * (1.0 - 2.2557e-5 * hgt) ** 5.2568
    temp = 15.0 - 6.5e-3 * hgt + 273.16
    e = 6.108 * humidity * np.exp((17.15 * temp - 4684.0) / (temp - 38.45))
    cos_z = np.cos(np.pi / 2.0 - el)
    with np.errstate(divide="ignore", invalid="ignore"):
        zhd = 0.0022768 * pres / (1.0 - 0.00266 * np.cos(2.0 * lat) - 0.00028 * hgt / 1e3)
        zwd = 0.002277 * (1255.0 / temp + 0.05) * e
        out = (zhd + zwd) / cos_z
    ok = (h >= -100.0) & (h <= 1e4) & (el > 0.0)
    return np.where(ok, out, 0.0)


def ionofree(p1_m: ArrayLike, p2_m: ArrayLike, f1_hz: ArrayLike, f2_hz: ArrayLike) -> FloatArray:
    """Ionosphere-free combination ``(f1^2 P1 - f2^2 P2) / (f1^2 - f2^2)`` (first order)."""
    g1 = np.asarray(f1_hz, dtype=float) ** 2
    g2 = np.asarray(f2_hz, dtype=float) ** 2
    return (g1 * np.asarray(p1_m) - g2 * np.asarray(p2_m)) / (g1 - g2)
