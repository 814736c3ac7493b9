"""Satellite position, velocity and clock from broadcast ephemerides.

Everything is vectorised over ``(epochs, satellites)``: an ephemeris is *selected* per epoch and
satellite (:func:`select_ephemeris`), its parameters are gathered into flat arrays and evaluated
in one pass per system (:func:`kepler_orbit`, :func:`glonass_orbit`).

Satellite clock offsets ``clock_s`` are those of the broadcast clock polynomial
*including* the relativistic correction and *excluding* group delays: the single-frequency user
applies :func:`group_delay_s` (TGD/BGD) for the signal used.

References
----------
IS-GPS-200N, 20.3.3.3.3 (clock, relativity, TGD) and 20.3.3.4.3 table 20-IV (orbit, velocity);
IS-QZSS-PNT-005 (QZSS as GPS); Galileo OS SIS ICD 2.1, 5.1.1-5.1.5 (BGD, data sources);
BDS-SIS-ICD-B1I 3.0, 5.2.4 (constants, GEO transformation, TGD1);
GLONASS ICD 5.1 (2008), A.3.1.2 (PZ-90 equations of motion, 4th-order Runge-Kutta).
Precise orbits and clocks (SP3, RINEX clock) are evaluated by :mod:`navtrack.gnss.precise`.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import TYPE_CHECKING

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._record import Record
from navtrack._typing import BoolArray, FloatArray, IntArray
from navtrack.geodesy import C_MPS
from navtrack.timescale import SECONDS_PER_WEEK

if TYPE_CHECKING:
    import pandas as pd

    from navtrack.gnss.rinex.nav import NavData

# Gravitational constants (m^3/s^2) and earth rotation rates (rad/s) per system.
MU_M3S2 = {
    "G": 3.986005e14,
    "J": 3.986005e14,
    "E": 3.986004418e14,
    "C": 3.986004418e14,
    "I": 3.986005e14,
}
OMEGA_E_RAD_S = {
    "G": 7.2921151467e-5,
    "J": 7.2921151467e-5,
    "E": 7.2921151467e-5,
    "C": 7.292115e-5,
    "I": 7.2921151467e-5,
}
# GLONASS PZ-90 (ICD 5.1 table 3.2)
GLO_MU_M3S2 = 398600.4418e9
GLO_A_M = 6378136.0
GLO_J2 = 1082625.75e-9
GLO_OMEGA_RAD_S = 7.292115e-5
GLO_STEP_S = 60.0

MAX_AGE_S = {"G": 7200.0, "J": 7200.0, "E": 14400.0, "C": 21600.0, "I": 86400.0, "R": 1800.0}
"""Default validity windows ``|t - toe|`` (s): half the GPS/QZSS 4 h curve fit, the Galileo 4 h
validity, BeiDou 6 h (RTKLIB ``MAXDTOE*``), GLONASS 30 min around tb (ICD 5.1 4.4)."""

BDS_GEO_PRN = frozenset({1, 2, 3, 4, 5, 59, 60, 61, 62, 63})
"""BeiDou GEO satellites (BDS-2 C01-C05, BDS-3 C59-C63)."""

_GALILEO_INAV = 0b101  # data source bits 0 (E1-B) and 2 (E5b-I)
_GALILEO_FNAV = 0b010  # bit 1 (E5a-I)

KEPLER_FIELDS = (
    "toc_gps_s",
    "af0",
    "af1",
    "af2",
    "crs",
    "deltan",
    "m0",
    "cuc",
    "e",
    "cus",
    "sqrta",
    "toe_sow",
    "toe_gps_s",
    "cic",
    "omega0",
    "cis",
    "i0",
    "crc",
    "omega",
    "omegadot",
    "idot",
)
GLONASS_FIELDS = (
    "toc_gps_s",
    "taun",
    "gamman",
    "x_m",
    "y_m",
    "z_m",
    "vx_mps",
    "vy_mps",
    "vz_mps",
    "ax_mps2",
    "ay_mps2",
    "az_mps2",
)


class EphemerisTable(Record):
    """The broadcast records of one system as plain arrays (one entry per record).

    Attributes
    ----------
    system : str
        System letter.
    sat : ndarray of str, shape (n,)
        Satellite id of each record.
    columns : mapping of str to ndarray, shape (n,)
        The reader's columns (floats; integer fields as int64 with -1 for blank).
    """

    system: str
    sat: np.ndarray
    columns: Mapping[str, np.ndarray] = MappingProxyType({})

    @classmethod
    def from_frame(cls, system: str, df: pd.DataFrame) -> EphemerisTable:
        cols = {c: df[c].to_numpy() for c in df.columns if c != "sat"}
        return cls(system, df["sat"].to_numpy().astype(str), cols)

    def get(self, name: str, default: float = np.nan) -> np.ndarray:
        col = self.columns.get(name)
        if col is None:
            return np.full(len(self.sat), default)
        return col


class SatStates(Record):
    """Satellite states at signal transmission, per epoch and satellite.

    Attributes
    ----------
    pos_m : ndarray, shape (E, S, 3)
        ECEF position at transmission time, in the earth-fixed frame *of that time* (m).
    vel_mps : ndarray, shape (E, S, 3)
        ECEF velocity (m/s).
    clock_s : ndarray, shape (E, S)
        Satellite clock offset (s) including the relativistic correction, excluding group
        delays.
    var_m2 : ndarray, shape (E, S)
        Variance of the signal-in-space range error (m^2): URA/SISA as broadcast, or the SP3
        accuracy.
    svh : ndarray of int, shape (E, S)
        Health as broadcast (0 healthy); -1 where no ephemeris.
    eph_index : ndarray of int, shape (E, S)
        Row of the selected record in the system's table; -1 where none.
    valid : ndarray of bool, shape (E, S)
        A usable, healthy ephemeris was found and evaluated.
    """

    pos_m: FloatArray
    vel_mps: FloatArray
    clock_s: FloatArray
    var_m2: FloatArray
    svh: IntArray
    eph_index: IntArray
    valid: BoolArray

    def __post_init__(self) -> None:
        freeze_arrays(self)


# --------------------------------------------------------------------------- selection
def select_ephemeris(
    table: EphemerisTable,
    sats: tuple[str, ...] | list[str],
    t_gps_s: FloatArray,
    *,
    max_age_s: float | None = None,
    healthy_only: bool = True,
    galileo_nav: str = "inav",
) -> IntArray:
    """Index of the ephemeris to use for each epoch and satellite.

    The record with the nearest reference time (``toe``; ``tb`` for GLONASS) within the validity
    window ``|t - toe| <= max_age_s`` is chosen, *before or after* ``t``: receiver logs and
    daily files start with ephemerides broadcast after the first epochs (the shared SEPT and
    ARL1 files need this). Ties go to the later record in the table. Unhealthy records
    (``svh != 0``), records with an IODE/IODC mismatch (GPS/QZSS cut-over, IS-GPS-200
    20.3.4.4) and, for Galileo, records of the other data source are skipped.

    Parameters
    ----------
    table : EphemerisTable
        Records of one system.
    sats : sequence of str, length S
        Satellite ids (of that system; others get -1).
    t_gps_s : ndarray, shape (E,) or (E, S)
        Times (GPS s) at which the orbits are needed.
    max_age_s : float, optional
        Validity half-window; default :data:`MAX_AGE_S` of the system.
    healthy_only : bool
        Skip records whose health word is non-zero.
    galileo_nav : {"inav", "fnav", "any"}
        Galileo data source to use (I/NAV pairs with E1/E5b and BGD(E5b,E1), F/NAV with E5a).

    Returns
    -------
    ndarray of int, shape (E, S)
        Row in ``table``, -1 where no record qualifies.
    """
    sys = table.system
    if galileo_nav not in ("inav", "fnav", "any"):
        raise ValueError(f"galileo_nav: expected 'inav', 'fnav' or 'any', got {galileo_nav!r}")
    t = np.asarray(t_gps_s, dtype=float)
    if t.ndim == 1:
        t = np.broadcast_to(t[:, None], (t.shape[0], len(sats)))
    n_e = t.shape[0]
    out = np.full((n_e, len(sats)), -1, dtype=np.int64)
    if len(table.sat) == 0:
        return out
    age = MAX_AGE_S.get(sys, 7200.0) if max_age_s is None else max_age_s
    toe = table.get("toe_gps_s") if sys != "R" else table.get("toc_gps_s")
    ok = np.isfinite(toe)
    if healthy_only:
        ok &= table.get("svh", 0) == 0
    if sys in "GJ" and "iodc" in table.columns:
        iode, iodc = table.get("iode"), table.get("iodc")
        ok &= (iodc < 0) | (iode < 0) | ((iodc & 0xFF) == iode)
    if sys == "E" and galileo_nav != "any":
        src = table.get("data_source", 0).astype(np.int64)
        bits = _GALILEO_INAV if galileo_nav == "inav" else _GALILEO_FNAV
        ok &= (src & bits) != 0
    for j, sat in enumerate(sats):
        rows = np.flatnonzero((table.sat == sat) & ok)
        if rows.size == 0:
            continue
        dt = np.abs(t[:, j, None] - toe[rows][None, :])  # (E, K)
        dt = np.where(np.isfinite(dt), dt, np.inf)
        # nearest toe; among equals the last row (argmin on the reversed order)
        k = rows.size - 1 - np.argmin(dt[:, ::-1], axis=1)
        best = dt[np.arange(n_e), k]
        out[:, j] = np.where(best <= age, rows[k], -1)
    return out


# --------------------------------------------------------------------------- clocks
def broadcast_clock(table: EphemerisTable, idx: IntArray, t_gps_s: FloatArray) -> FloatArray:
    """Broadcast clock polynomial (no relativity, no group delay) at ``t``, NaN where ``idx<0``.

    ``dt_sv = af0 + af1 (t - toc) + af2 (t - toc)^2`` (IS-GPS-200 20.3.3.3.3.1); GLONASS
    ``-tau_n + gamma_n (t - t_b)`` (ICD 5.1 3.3.2.3; the RINEX field is already -tau_n).
    """
    idx = np.asarray(idx)
    ok = idx >= 0
    i = np.where(ok, idx, 0)
    t = np.asarray(t_gps_s, dtype=float)
    dt = t - table.get("toc_gps_s")[i]
    if table.system == "R":
        out = table.get("taun")[i] + table.get("gamman")[i] * dt
    else:
        out = table.get("af0")[i] + (table.get("af1")[i] + table.get("af2")[i] * dt) * dt
    return np.where(ok, out, np.nan)


def group_delay_s(table: EphemerisTable, idx: IntArray, band: str = "1") -> FloatArray:
    """Broadcast group delay to *subtract from* the satellite clock for a single-frequency user.

    GPS/QZSS L1 ``TGD``, L2 ``gamma TGD`` with ``gamma = (77/60)^2`` (IS-GPS-200 20.3.3.3.3.2);
    Galileo E1 ``BGD(E1,E5b)`` for I/NAV and ``BGD(E1,E5a)`` for F/NAV records, E5a
    ``(f1/f5a)^2 BGD(E1,E5a)``, E5b ``(f1/f5b)^2 BGD(E1,E5b)`` (OS SIS ICD 5.1.5); BeiDou B1I
    ``TGD1``, B2I ``TGD2`` (clocks refer to B3I, BDS-SIS-ICD 5.2.4.10); GLONASS and others 0.

    Parameters
    ----------
    table : EphemerisTable
    idx : ndarray of int
        Selected rows (-1: none, giving 0).
    band : str
        RINEX band digit of the signal used.

    Returns
    -------
    ndarray
        Group delay (s), same shape as ``idx``.
    """
    idx = np.asarray(idx)
    ok = idx >= 0
    i = np.where(ok, idx, 0)
    sys = table.system
    zero = np.zeros(idx.shape)
    if len(table.sat) == 0:
        return zero
    if sys in "GJ":
        tgd = np.nan_to_num(table.get("tgd", 0.0)[i])
        factor = {"1": 1.0, "2": (77.0 / 60.0) ** 2}.get(band, 0.0)
        out = factor * tgd
    elif sys == "E":
        e5a = np.nan_to_num(table.get("bgd_e5a", 0.0)[i])
        e5b = np.nan_to_num(table.get("bgd_e5b", 0.0)[i])
        fnav = (table.get("data_source", 0).astype(np.int64)[i] & _GALILEO_FNAV) != 0
        if band == "1":
            out = np.where(fnav, e5a, e5b)
        elif band == "5":
            out = (1575.42 / 1176.45) ** 2 * e5a
        elif band == "7":
            out = (1575.42 / 1207.14) ** 2 * e5b
        else:
            out = zero
    elif sys == "C":
        name = {"2": "tgd1", "1": "tgd1", "7": "tgd2"}.get(band)
        out = zero if name is None else np.nan_to_num(table.get(name, 0.0)[i])
    elif sys == "I":
        out = np.nan_to_num(table.get("tgd", 0.0)[i])
    else:
        out = zero
    return np.where(ok, out, 0.0)


# --------------------------------------------------------------------------- orbits
def _eccentric_anomaly(m: FloatArray, e: FloatArray) -> FloatArray:
    """Solve Kepler's equation ``E - e sin E = M`` by Newton's method (vectorised)."""
    ecc = m.copy()
    for _ in range(30):
        f = ecc - e * np.sin(ecc) - m
        step = f / (1.0 - e * np.cos(ecc))
        ecc -= step
        if np.all(np.abs(step[np.isfinite(step)]) < 1e-14):
            break
    return ecc


def kepler_orbit(
    p: Mapping[str, FloatArray],
    t_gps_s: FloatArray,
    system: str,
    *,
    geo: BoolArray | None = None,
    geo_velocity: bool = True,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Position, velocity and relativistic clock term from Keplerian broadcast elements.

    Parameters
    ----------
    p : mapping of str to ndarray, shape (N,)
        Elements per item (names of :data:`KEPLER_FIELDS`).
    t_gps_s : ndarray, shape (N,)
        GPS time of transmission.
    system : {"G", "J", "E", "C", "I"}
        System (constants ``mu``, ``Omega_e``).
    geo : ndarray of bool, shape (N,), optional
        BeiDou GEO items: orbit computed in the inertial-like frame of BDS-SIS-ICD 5.2.4.12
        and rotated by ``Rz(Omega_e tk) Rx(-5 deg)``.

    Returns
    -------
    pos : ndarray, shape (N, 3)
        ECEF position (m).
    vel : ndarray, shape (N, 3)
        ECEF velocity (m/s), IS-GPS-200 table 20-IV (GEO: finite difference over 1 s).
    dtr : ndarray, shape (N,)
        Relativistic clock correction ``F e sqrt(A) sin E`` (s), ``F = -2 sqrt(mu) / c^2``.

    References
    ----------
    IS-GPS-200N 20.3.3.4.3, table 20-IV; BDS-SIS-ICD-B1I 3.0, 5.2.4.12.
    """
    mu = MU_M3S2[system]
    we = OMEGA_E_RAD_S[system]
    t = np.asarray(t_gps_s, dtype=float)
    a = p["sqrta"] ** 2
    tk = t - p["toe_gps_s"]
    n0 = np.sqrt(mu / a**3)
    n = n0 + p["deltan"]
    m = p["m0"] + n * tk
    e = p["e"]
    ecc = _eccentric_anomaly(m, e)
    sin_e, cos_e = np.sin(ecc), np.cos(ecc)
    one_ecos = 1.0 - e * cos_e
    nu = np.arctan2(np.sqrt(1.0 - e**2) * sin_e, cos_e - e)
    phi = nu + p["omega"]
    s2, c2 = np.sin(2.0 * phi), np.cos(2.0 * phi)
    du = p["cus"] * s2 + p["cuc"] * c2
    dr = p["crs"] * s2 + p["crc"] * c2
    di = p["cis"] * s2 + p["cic"] * c2
    u = phi + du
    r = a * one_ecos + dr
    inc = p["i0"] + di + p["idot"] * tk
    xp, yp = r * np.cos(u), r * np.sin(u)
    # rates (table 20-IV, "SV velocity")
    e_dot = n / one_ecos
    nu_dot = e_dot * np.sqrt(1.0 - e**2) / one_ecos
    u_dot = nu_dot * (1.0 + 2.0 * (p["cus"] * c2 - p["cuc"] * s2))
    r_dot = a * e * sin_e * e_dot + 2.0 * (p["crs"] * c2 - p["crc"] * s2) * nu_dot
    i_dot = p["idot"] + 2.0 * (p["cis"] * c2 - p["cic"] * s2) * nu_dot
    xp_dot = r_dot * np.cos(u) - r * u_dot * np.sin(u)
    yp_dot = r_dot * np.sin(u) + r * u_dot * np.cos(u)
    is_geo = np.zeros(t.shape, dtype=bool) if geo is None else np.asarray(geo, dtype=bool)
    om_rate = np.where(is_geo, p["omegadot"], p["omegadot"] - we)
    om = p["omega0"] + om_rate * tk - we * p["toe_sow"]
    pos, vel = _plane_to_ecef((xp, yp, xp_dot, yp_dot), (om, om_rate), (inc, i_dot))
    if is_geo.any():
        pos[is_geo] = _bds_geo_rotate(pos[is_geo], tk[is_geo], we)
        if geo_velocity:
            sub = {k: v[is_geo] for k, v in p.items()}
            vel[is_geo] = _bds_geo_velocity(sub, t[is_geo], system)
    dtr = -2.0 * np.sqrt(mu) / C_MPS**2 * e * p["sqrta"] * sin_e
    return pos, vel, dtr


def _plane_to_ecef(
    plane: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
    node: tuple[FloatArray, FloatArray],
    inclination: tuple[FloatArray, FloatArray],
) -> tuple[FloatArray, FloatArray]:
    """ECEF position and velocity from the orbital-plane position and velocity
    ``(xp, yp, xp_dot, yp_dot)``, the corrected longitude of the ascending node and its rate
    ``(om, om_rate)`` and the inclination and its rate (IS-GPS-200 table 20-IV)."""
    xp, yp, xp_dot, yp_dot = plane
    om, om_rate = node
    inc, i_dot = inclination
    so, co = np.sin(om), np.cos(om)
    si, ci = np.sin(inc), np.cos(inc)
    x = xp * co - yp * ci * so
    y = xp * so + yp * ci * co
    z = yp * si
    vx = xp_dot * co - yp_dot * ci * so + yp * si * so * i_dot - y * om_rate
    vy = xp_dot * so + yp_dot * ci * co - yp * si * co * i_dot + x * om_rate
    vz = yp_dot * si + yp * ci * i_dot
    return np.stack([x, y, z], axis=-1), np.stack([vx, vy, vz], axis=-1)


def _bds_geo_velocity(p: Mapping[str, FloatArray], t_gps_s: FloatArray, system: str) -> FloatArray:
    """Velocity of BeiDou GEO items' rotated orbits, by a central difference over +-0.5 s."""
    geo = np.ones(t_gps_s.size, dtype=bool)
    p_plus = kepler_orbit(p, t_gps_s + 0.5, system, geo=geo, geo_velocity=False)[0]
    p_minus = kepler_orbit(p, t_gps_s - 0.5, system, geo=geo, geo_velocity=False)[0]
    return p_plus - p_minus


def _bds_geo_rotate(pos: FloatArray, tk: FloatArray, we: float) -> FloatArray:
    """``Rz(we tk) Rx(-5 deg)`` of BDS-SIS-ICD 5.2.4.12 applied to GEO positions (N, 3)."""
    phi = np.deg2rad(-5.0)
    cx, sx = np.cos(phi), np.sin(phi)
    x = pos[:, 0]
    y = cx * pos[:, 1] + sx * pos[:, 2]
    z = -sx * pos[:, 1] + cx * pos[:, 2]
    ang = we * tk
    cz, sz = np.cos(ang), np.sin(ang)
    return np.stack([cz * x + sz * y, -sz * x + cz * y, z], axis=-1)


def _glonass_derivative(s: FloatArray, acc: FloatArray) -> FloatArray:
    """Right side of the PZ-90 equations of motion (ICD 5.1 A.3.1.2), state ``(N, 6)``."""
    x, y, z, vx, vy, vz = (s[:, k] for k in range(6))
    r2 = x * x + y * y + z * z
    r = np.sqrt(r2)
    mu_r3 = GLO_MU_M3S2 / (r2 * r)
    j2 = 1.5 * GLO_J2 * GLO_MU_M3S2 * GLO_A_M**2 / (r2 * r2 * r)
    z2r2 = 5.0 * z * z / r2
    w2 = GLO_OMEGA_RAD_S**2
    ax = -mu_r3 * x - j2 * x * (1.0 - z2r2) + w2 * x + 2.0 * GLO_OMEGA_RAD_S * vy + acc[:, 0]
    ay = -mu_r3 * y - j2 * y * (1.0 - z2r2) + w2 * y - 2.0 * GLO_OMEGA_RAD_S * vx + acc[:, 1]
    az = -mu_r3 * z - j2 * z * (3.0 - z2r2) + acc[:, 2]
    return np.stack([vx, vy, vz, ax, ay, az], axis=-1)


def glonass_orbit(
    p: Mapping[str, FloatArray], t_gps_s: FloatArray, *, step_s: float = GLO_STEP_S
) -> tuple[FloatArray, FloatArray]:
    """GLONASS position and velocity by 4th-order Runge–Kutta from the broadcast state vector.

    The state at ``t_b`` (PZ-90, taken as earth-fixed WGS-84-compatible at the metre level) is
    integrated to ``t`` with the central field, the J2 term, the centrifugal and Coriolis terms
    of the rotating frame and the broadcast lunisolar accelerations held constant. All items use
    the same number of steps, ``ceil(max |t - t_b| / step_s)`` (each item its own step length).

    Parameters
    ----------
    p : mapping of str to ndarray, shape (N,)
        Records (:data:`GLONASS_FIELDS`).
    t_gps_s : ndarray, shape (N,)
        GPS time of transmission.
    step_s : float
        Maximum integration step (s).

    Returns
    -------
    pos : ndarray, shape (N, 3)
    vel : ndarray, shape (N, 3)

    References
    ----------
    GLONASS ICD 5.1 (2008), A.3.1.2.
    """
    t = np.asarray(t_gps_s, dtype=float)
    dt = t - p["toc_gps_s"]
    s = np.stack([p["x_m"], p["y_m"], p["z_m"], p["vx_mps"], p["vy_mps"], p["vz_mps"]], axis=-1)
    acc = np.stack([p["ax_mps2"], p["ay_mps2"], p["az_mps2"]], axis=-1)
    acc = np.nan_to_num(acc)
    fin = np.isfinite(dt)
    n_steps = int(np.ceil(np.max(np.abs(dt[fin])) / step_s)) if fin.any() else 0
    if n_steps:
        h = (np.where(fin, dt, 0.0) / n_steps)[:, None]
        for _ in range(n_steps):
            k1 = _glonass_derivative(s, acc)
            k2 = _glonass_derivative(s + 0.5 * h * k1, acc)
            k3 = _glonass_derivative(s + 0.5 * h * k2, acc)
            k4 = _glonass_derivative(s + h * k3, acc)
            s = s + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    s = np.where(fin[:, None], s, np.nan)
    return s[:, :3], s[:, 3:]


# URA index table (m), IS-GPS-200 20.3.3.3.1.1
_URA_M = np.array(
    [
        2.4,
        3.4,
        4.85,
        6.85,
        9.65,
        13.65,
        24.0,
        48.0,
        96.0,
        192.0,
        384.0,
        768.0,
        1536.0,
        3072.0,
        6144.0,
    ]
)


def ura_variance(system: str, sva_m: FloatArray, *, quantise: bool = True) -> FloatArray:
    """Variance (m^2) of the broadcast signal-in-space range error from URA/SISA in metres.

    With ``quantise`` the value written in RINEX is mapped as a receiver holding the broadcast
    *index* would: GPS/QZSS/BeiDou/NavIC URA to the upper bound of its index interval (IS-GPS-200
    20.3.3.3.1.1: 2.0 m -> index 0 -> 2.4 m), Galileo SISA to its index grid (OS SIS ICD
    5.1.12: 1 cm to 0.5 m, 2 cm to 1 m, 4 cm to 2 m, 16 cm to 6 m). Missing or out-of-range
    values give 6144 m (GPS "no accuracy prediction").
    """
    v = np.asarray(sva_m, dtype=float)
    bad = ~np.isfinite(v) | (v < 0)
    if not quantise:
        return np.where(bad, 6144.0**2, v**2)
    if system == "E":
        q = np.where(
            v <= 0.5,
            np.floor(v / 0.01 + 1e-9) * 0.01,
            np.where(
                v <= 1.0,
                0.5 + np.floor((v - 0.5) / 0.02 + 1e-9) * 0.02,
                np.where(
                    v <= 2.0,
                    1.0 + np.floor((v - 1.0) / 0.04 + 1e-9) * 0.04,
                    2.0 + np.floor((v - 2.0) / 0.16 + 1e-9) * 0.16,
                ),
            ),
        )
        bad |= v > 6.0
        return np.where(bad, 6144.0**2, q**2)
    k = np.searchsorted(_URA_M, np.where(bad, 0.0, v) - 1e-9, side="left")
    bad |= k >= _URA_M.size
    return np.where(bad, 6144.0**2, _URA_M[np.clip(k, 0, _URA_M.size - 1)] ** 2)


def broadcast_states(
    tables: Mapping[str, EphemerisTable],
    sats: tuple[str, ...] | list[str],
    t_rx_gps_s: FloatArray,
    t_tx_gps_s: FloatArray,
    *,
    max_age_s: Mapping[str, float] | None = None,
    healthy_only: bool = True,
    galileo_nav: str = "inav",
    quantise_ura: bool = True,
) -> SatStates:
    """Satellite states from broadcast ephemerides at given transmission times.

    Parameters
    ----------
    tables : mapping of str to EphemerisTable
        Broadcast records per system (:func:`ephemeris_tables`).
    sats : sequence of str, length S
        Satellite ids.
    t_rx_gps_s : ndarray, shape (E,)
        Reception epochs; the ephemeris is selected at these times.
    t_tx_gps_s : ndarray, shape (E, S)
        Transmission times *by the satellite clock* (``t_rx - P / c``); the satellite clock is
        removed here (two fixed-point steps of ``t = t_sv - dt_sv(t)``, IS-GPS-200
        20.3.3.3.3.1). NaN where no measurement.

    Returns
    -------
    SatStates
    """
    t_rx = np.asarray(t_rx_gps_s, dtype=float)
    t_sv = np.asarray(t_tx_gps_s, dtype=float)
    n_e, n_s = t_sv.shape
    pos = np.full((n_e, n_s, 3), np.nan)
    vel = np.full((n_e, n_s, 3), np.nan)
    clk = np.full((n_e, n_s), np.nan)
    var = np.full((n_e, n_s), np.nan)
    svh = np.full((n_e, n_s), -1, dtype=np.int64)
    index = np.full((n_e, n_s), -1, dtype=np.int64)
    for sys, table in tables.items():
        cols = np.flatnonzero([sat[0] == sys for sat in sats])
        if cols.size == 0 or sys not in "GJECIR":
            continue
        ages = max_age_s or {}
        idx = select_ephemeris(
            table,
            [sats[c] for c in cols],
            t_rx,
            max_age_s=ages.get(sys),
            healthy_only=healthy_only,
            galileo_nav=galileo_nav,
        )
        index[:, cols] = idx
        ts = t_sv[:, cols]
        use = (idx >= 0) & np.isfinite(ts)
        if not use.any():
            continue
        e_i, s_i = np.nonzero(use)
        rows = idx[e_i, s_i]
        ee, ss = e_i, cols[s_i]
        ids = [sats[c] for c in ss] if sys == "C" else []
        pos[ee, ss], vel[ee, ss], clk[ee, ss], var[ee, ss] = _record_states(
            table, sys, rows, ts[e_i, s_i], ids, quantise_ura
        )
        svh[ee, ss] = table.get("svh", 0)[rows]
    valid = (index >= 0) & np.isfinite(clk) & np.isfinite(pos).all(axis=-1)
    return SatStates(pos, vel, clk, var, svh, index, valid)


def _record_states(
    table: EphemerisTable,
    sys: str,
    rows: IntArray,
    tsv: FloatArray,
    sat_ids: list[str],
    quantise_ura: bool,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Position, velocity, clock (relativistic term included) and URA variance of the records
    ``rows`` of one system at the transmission times ``tsv`` read by the satellite clock, which
    is removed by two fixed-point steps; ``sat_ids`` name BeiDou's items (GEO by PRN)."""
    t = tsv.copy()
    for _ in range(2):
        t = tsv - broadcast_clock(table, rows, t)
    dts = broadcast_clock(table, rows, t)
    if sys == "R":
        ps, vs = glonass_orbit({k: table.get(k)[rows] for k in GLONASS_FIELDS}, t)
        # no URA in RINEX 2/3.04 GLONASS records: a nominal 5 m
        return ps, vs, dts, np.full(rows.size, 5.0**2)
    geo = None
    if sys == "C":
        geo = np.isin(np.array([int(s[1:]) for s in sat_ids]), list(BDS_GEO_PRN))
    p = {k: table.get(k)[rows] for k in KEPLER_FIELDS}
    ps, vs, rel = kepler_orbit(p, t, sys, geo=geo)
    return ps, vs, dts + rel, ura_variance(sys, table.get("sva_m")[rows], quantise=quantise_ura)


def ephemeris_tables(nav: NavData | Mapping[str, pd.DataFrame]) -> dict[str, EphemerisTable]:
    """:class:`EphemerisTable` per system of a ``NavData`` (or a mapping of DataFrames)."""
    if isinstance(nav, Mapping):
        return {sys: EphemerisTable.from_frame(sys, df) for sys, df in nav.items()}
    return {
        sys: EphemerisTable(
            sys, cols["sat"].astype(str), {c: v for c, v in cols.items() if c != "sat"}
        )
        for sys, cols in nav.tables.items()
    }


def first_record_group_delays(tables: Mapping[str, EphemerisTable]) -> dict[str, EphemerisTable]:
    """Tables whose group delays (``tgd``, ``bgd_e5a``, ``bgd_e5b``, ``tgd1``, ``tgd2``) are,
    for every record of a satellite, those of its first record by transmission time (then
    ``toe``): RTKLIB 2.4.3's choice, whatever ephemeris it uses for the epoch. Where that first
    record is a Galileo F/NAV one its ``BGD(E5b,E1)`` is 0, so RTKLIB applies no group delay to
    the E1 pseudorange (docs/integrity.md). For matching an RTKLIB pipeline only
    (``navtrack pos --rtklib-compatible``); the ICD's choice is the default.
    """
    out = {}
    for sys, t in tables.items():
        cols = dict(t.columns)
        toc, tot = t.get("toc_gps_s"), t.get("tot_sow")
        # transmission time: the week of toc, wrapped to within half a week of it
        ttr = toc + (tot - toc % SECONDS_PER_WEEK + SECONDS_PER_WEEK / 2) % SECONDS_PER_WEEK
        ttr -= SECONDS_PER_WEEK / 2
        order = np.lexsort((t.get("toe_gps_s"), ttr))
        for name in ("tgd", "bgd_e5a", "bgd_e5b", "tgd1", "tgd2"):
            if name in cols:
                col = np.array(cols[name], dtype=float)
                for sat in np.unique(t.sat):
                    col[t.sat == sat] = col[order[t.sat[order] == sat][0]]
                cols[name] = col
        out[sys] = EphemerisTable(sys, t.sat, cols)
    return out


def merge_tables(tables: list[dict[str, EphemerisTable]]) -> dict[str, EphemerisTable]:
    """Concatenate the tables of several navigation files system by system."""
    out: dict[str, EphemerisTable] = {}
    systems = {s for t in tables for s in t}
    for sys in systems:
        parts = [t[sys] for t in tables if sys in t]
        if len(parts) == 1:
            out[sys] = parts[0]
            continue
        names = set().union(*(p.columns for p in parts))
        cols = {}
        for name in names:
            cols[name] = np.concatenate([p.get(name) for p in parts])
        out[sys] = EphemerisTable(sys, np.concatenate([p.sat for p in parts]), cols)
    return out
