"""Carrier phase wind-up of right-hand circularly polarised signals.

A receiver sees the carrier phase of a circularly polarised wave advance by one cycle for every
turn of the transmitting antenna relative to the receiving one about the line of sight. For a
static receiver the satellite turns as it yaws to keep its solar panels to the Sun and as the
line of sight sweeps across its body: typically a fraction of a cycle over a pass (one cycle is
10.7 cm of GPS ionosphere-free phase), up to whole cycles during the yaw turns near noon and
midnight of the orbit, where the nominal attitude used here turns faster than a real satellite
can. The code is not affected, so the term is removed from the phase alone.

Wu et al. (1993), eq. 15-17, with ``k`` the unit vector from the satellite to the receiver and
each antenna an effective dipole built from its axes ``x, y``::

    D_sat = x_s - k (k . x_s) - k x y_s
    D_rcv = x_r - k (k . x_r) + k x y_r
    dphi  = sign(k . (D_sat x D_rcv)) arccos(D_sat . D_rcv / |D_sat| |D_rcv|) / 2 pi  (cycles)

The satellite axes are those of the nominal yaw attitude
(:func:`navtrack.gnss.antex.satellite_axes`), the receiver antenna's ``x`` north and ``y`` west
(an antenna pointed north, as IGS stations are). ``dphi`` is known up to whole cycles; along an
arc the whole cycles follow continuity (:func:`phase_windup_cyc`). The constant part is absorbed
by the float ambiguity, only its change over the arc moves the position.

References
----------
Wu, J.T., Wu, S.C., Hajj, G.A., Bertiger, W.I., Lichten, S.M. (1993). Effects of antenna
orientation on GPS carrier phase. Manuscripta Geodaetica 18, 91-98.
Kouba, J. (2009). A guide to using International GNSS Service (IGS) products, section 5.1.2.
"""

from __future__ import annotations

import numpy as np

from navtrack._typing import FloatArray
from navtrack.geodesy import ecef_to_geodetic, enu_rotation
from navtrack.gnss.antex import satellite_axes

__all__ = ["phase_windup_cyc", "windup_angle_cyc"]


def windup_angle_cyc(
    k: FloatArray,
    sat_x: FloatArray,
    sat_y: FloatArray,
    rcv_x: FloatArray,
    rcv_y: FloatArray,
) -> FloatArray:
    """Wind-up angle (cycles, in [-0.5, 0.5]) between a transmitting and a receiving antenna.

    Parameters
    ----------
    k : ndarray, shape (..., 3)
        Unit vectors from the satellite to the receiver.
    sat_x, sat_y : ndarray, shape (..., 3)
        Unit x and y axes of the satellite antenna.
    rcv_x, rcv_y : ndarray, shape (..., 3)
        Unit x and y axes of the receiver antenna.
    """
    k = np.asarray(k, dtype=float)

    def dot(a: FloatArray, b: FloatArray) -> FloatArray:
        return np.einsum("...i,...i->...", a, b)

    d_sat = sat_x - k * dot(k, sat_x)[..., None] - np.cross(k, sat_y)
    d_rcv = rcv_x - k * dot(k, rcv_x)[..., None] + np.cross(k, rcv_y)
    norm = np.linalg.norm(d_sat, axis=-1) * np.linalg.norm(d_rcv, axis=-1)
    angle = np.arccos(np.clip(dot(d_sat, d_rcv) / norm, -1.0, 1.0)) / (2.0 * np.pi)
    return np.where(dot(k, np.cross(d_sat, d_rcv)) < 0.0, -angle, angle)


def phase_windup_cyc(sat_m: FloatArray, rcv_m: FloatArray, sun_m: FloatArray) -> FloatArray:
    """Carrier phase wind-up (cycles) of satellites seen from a static receiver, continuous
    along each satellite's epochs.

    Parameters
    ----------
    sat_m : ndarray, shape (E, S, 3)
        Satellite positions (ECEF, m); NaN where a satellite has none.
    rcv_m : ndarray, shape (3,)
        Receiver position (ECEF, m).
    sun_m : ndarray, shape (E, 3)
        Sun position (ECEF, m) at each epoch.

    Returns
    -------
    ndarray, shape (E, S)
        Wind-up in cycles (NaN where the satellite position is missing). Whole cycles are
        carried across epochs (a jump of more than half a cycle between two epochs with a
        position is taken as the nearest whole turn); the value at a satellite's first epoch
        lies in [-0.5, 0.5].
    """
    sat = np.asarray(sat_m, dtype=float)
    rcv = np.asarray(rcv_m, dtype=float)
    los = rcv - sat
    k = los / np.linalg.norm(los, axis=-1, keepdims=True)
    sat_x, sat_y, _ = satellite_axes(sat, np.asarray(sun_m, dtype=float)[:, None, :])
    llh = ecef_to_geodetic(rcv)
    east, north, _up = enu_rotation(llh[0], llh[1])
    raw = windup_angle_cyc(k, sat_x, sat_y, north, -east)
    out = np.full(raw.shape, np.nan)
    for s in range(raw.shape[1]):
        ok = np.isfinite(raw[:, s])
        out[ok, s] = np.unwrap(raw[ok, s], period=1.0)
    return out
