"""Time scales: GPS time inside, conversions at the edges.

navtrack keeps every time as **GPS seconds**: float64 seconds of GPS time (GPST) since the GPS
epoch 1980-01-06T00:00:00, without leap seconds. Week numbers are full (not modulo 1024).

Other time scales relate to GPST as (IS-GPS-200, Galileo OS SIS ICD, BDS-SIS-ICD, GLONASS ICD):

* GST (Galileo) = GPST (the week number starts at 1999-08-22 = GPS week 1024);
* BDT (BeiDou) = GPST - 14 s (BDT week 0 starts at 2006-01-01 00:00:00 BDT = GPS week 1356);
* UTC = GPST - leap seconds (table below);
* GLONASST = UTC(SU) + 3 h; RINEX writes GLONASS times (``GLO``) as UTC(SU), i.e. without the
  3 h, so ``GLO`` time tags convert like UTC.

References
----------
IERS Bulletin C (leap seconds); IS-GPS-200N 20.3.3.5.2.4; RINEX 3.05 section 6.1.
"""

from __future__ import annotations

import datetime as _dt

import numpy as np

from navtrack._typing import ArrayLike, BoolArray, FloatArray, IntArray

GPS_EPOCH = np.datetime64("1980-01-06T00:00:00", "ns")
SECONDS_PER_WEEK = 604800.0
BDT_MINUS_GPST_S = -14.0
BDS_WEEK_OFFSET = 1356
GLONASST_MINUS_UTC_S = 3 * 3600.0

# (UTC date from which it holds, GPST - UTC in s); IERS Bulletin C up to C72 (no new leap second
# announced after 2017-01-01).
_LEAP_TABLE = (
    ("1981-07-01", 1),
    ("1982-07-01", 2),
    ("1983-07-01", 3),
    ("1985-07-01", 4),
    ("1988-01-01", 5),
    ("1990-01-01", 6),
    ("1991-01-01", 7),
    ("1992-07-01", 8),
    ("1993-07-01", 9),
    ("1994-07-01", 10),
    ("1996-01-01", 11),
    ("1997-07-01", 12),
    ("1999-01-01", 13),
    ("2006-01-01", 14),
    ("2009-01-01", 15),
    ("2012-07-01", 16),
    ("2015-07-01", 17),
    ("2017-01-01", 18),
)
_LEAP_UTC_S = np.array(
    [(np.datetime64(d, "ns") - GPS_EPOCH) / np.timedelta64(1, "s") for d, _ in _LEAP_TABLE]
)
_LEAP_S = np.array([n for _, n in _LEAP_TABLE], dtype=float)


def gps_seconds(t: ArrayLike) -> FloatArray:
    """GPS seconds of GPST calendar times.

    Parameters
    ----------
    t : datetime64 array-like or ISO 8601 strings
        Calendar times *in GPST* (no leap-second shift is applied).

    Returns
    -------
    ndarray of float64, shape of ``t``
    """
    ns = (np.asarray(t, dtype="datetime64[ns]") - GPS_EPOCH).astype(np.int64)
    # Whole and fractional seconds separately, so a time like 00:48:00.004 gives the float
    # nearest to its decimal value (as the RINEX readers' field arithmetic does).
    return np.asarray(ns // 1_000_000_000 + (ns % 1_000_000_000) / 1e9, dtype=float)


_GPS_EPOCH_ORDINAL = _dt.date(1980, 1, 6).toordinal()


def calendar_gps_seconds(
    year: int, month: int, day: int, hour: int, minute: int, second: float
) -> float:
    """GPS seconds of one GPST calendar time given by its fields (fast scalar path)."""
    days = _dt.date(year, month, day).toordinal() - _GPS_EPOCH_ORDINAL
    return days * 86400.0 + hour * 3600.0 + minute * 60.0 + second


def to_datetime64(t_gps_s: ArrayLike) -> np.ndarray:
    """GPST calendar times (``datetime64[ns]``) of GPS seconds, rounded to the nanosecond."""
    t = np.asarray(t_gps_s, dtype=float)
    return GPS_EPOCH + np.round(t * 1e9).astype("timedelta64[ns]")


def week_tow(t_gps_s: ArrayLike) -> tuple[IntArray, FloatArray]:
    """GPS week (full, not rolled over) and time of week in seconds."""
    t = np.asarray(t_gps_s, dtype=float)
    week = np.floor(t / SECONDS_PER_WEEK).astype(np.int64)
    return week, t - week * SECONDS_PER_WEEK


def from_week_tow(week: ArrayLike, tow_s: ArrayLike) -> FloatArray:
    """GPS seconds of a (week, time of week) pair."""
    return np.asarray(week, dtype=float) * SECONDS_PER_WEEK + np.asarray(tow_s, dtype=float)


def leap_seconds(t_gps_s: ArrayLike) -> FloatArray:
    """GPST - UTC in seconds at the given GPS times (0 before 1981-07-01)."""
    t = np.asarray(t_gps_s, dtype=float)
    # A leap second takes effect at a UTC instant; in GPST that instant is later by the new count.
    idx = np.searchsorted(_LEAP_UTC_S + _LEAP_S, t, side="right") - 1
    return np.where(idx >= 0, _LEAP_S[np.clip(idx, 0, None)], 0.0)


def utc_to_gps(t_utc_s: ArrayLike) -> FloatArray:
    """GPS seconds of UTC times given as seconds since 1980-01-06 UTC."""
    t = np.asarray(t_utc_s, dtype=float)
    idx = np.searchsorted(_LEAP_UTC_S, t, side="right") - 1
    return t + np.where(idx >= 0, _LEAP_S[np.clip(idx, 0, None)], 0.0)


def gps_to_utc(t_gps_s: ArrayLike) -> FloatArray:
    """UTC times (seconds since 1980-01-06 UTC) of GPS seconds."""
    t = np.asarray(t_gps_s, dtype=float)
    return t - leap_seconds(t)


def to_gps(t_s: ArrayLike, time_system: str) -> FloatArray:
    """Convert seconds since 1980-01-06 *in the given time scale's calendar* to GPS seconds.

    Parameters
    ----------
    t_s : array-like of float
        Times as calendar seconds of ``time_system`` (as :func:`gps_seconds` gives for its
        calendar fields).
    time_system : {"GPS", "GAL", "QZS", "IRN", "BDT", "GLO", "UTC"}
        RINEX 3 time-system identifier. ``GLO`` is UTC(SU) as RINEX 2.11 section 3 and RINEX
        3.05 section 6.1 define GLONASS time tags, so it converts like ``UTC``.
    """
    t = np.asarray(t_s, dtype=float)
    match time_system.upper():
        case "GPS" | "GAL" | "QZS" | "IRN" | "":
            return t
        case "BDT":
            return t - BDT_MINUS_GPST_S
        case "UTC" | "GLO":
            return utc_to_gps(t)
    raise ValueError(f"time_system: unknown time system {time_system!r}")


#: Tolerance (s) of the epoch selection of :func:`select_epochs`: receiver time tags a few ms
#: off the whole second are still on the grid (RTKLIB's ``-ts/-te/-ti`` keep them too; the
#: 0759 file has tags 1-5 ms late).
EPOCH_TOL_S = 0.025


def parse_gpst(text: str) -> float:
    """GPS seconds of a GPST calendar time written as RTKLIB writes it
    (``2005/04/02 00:10:00``) or in ISO 8601 (``2005-04-02T00:10:00``).

    Raises
    ------
    ValueError
        The text is neither form.
    """
    iso = text.strip().replace("/", "-").replace(" ", "T", 1)
    try:
        return float(gps_seconds(np.datetime64(iso, "ns")))
    except ValueError:
        raise ValueError(
            f"cannot read time {text!r}: expected 'YYYY/MM/DD HH:MM:SS' or ISO 8601"
        ) from None


def select_epochs(
    t_gps_s: ArrayLike,
    start_s: float | None = None,
    end_s: float | None = None,
    interval_s: float | None = None,
    tol_s: float = EPOCH_TOL_S,
) -> BoolArray:
    """Epochs within ``[start_s, end_s]`` whose time of week is a multiple of ``interval_s``
    (each within ``tol_s``): RTKLIB's ``-ts``, ``-te`` and ``-ti``.

    Parameters
    ----------
    t_gps_s : array-like, shape (n,)
        Epoch times, GPS s.
    start_s, end_s : float, optional
        First and last time kept (GPS s); None: open.
    interval_s : float, optional
        Interval (s) of the kept epochs on the GPS week's grid; None or 0: every epoch.

    Returns
    -------
    ndarray of bool, shape (n,)
    """
    t = np.asarray(t_gps_s, dtype=float)
    keep = np.ones(t.shape, dtype=bool)
    if start_s is not None:
        keep &= t >= start_s - tol_s
    if end_s is not None:
        keep &= t <= end_s + tol_s
    if interval_s:
        _, tow = week_tow(t)
        keep &= np.abs(np.remainder(tow + interval_s / 2, interval_s) - interval_s / 2) <= tol_s
    return keep
