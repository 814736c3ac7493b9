"""Readers of real tracking data: AIS CSV (Solent), OpenSky state vectors, a generic CSV.

Every reader returns :class:`TrackDetections`: time-sorted detections with GPS-second times,
geodetic or local positions, the source line of each row and the id column (used only to score
a tracker, never by it). Rows that cannot be used are *reported and skipped*: their line numbers
and reasons are in ``bad_lines`` / ``bad_reasons``; a file whose required columns are missing
raises :class:`navtrack.errors.FileFormatError`.

Row checks: a last row without its end of line or with fewer fields than the header (a file
cut mid-line), unparsable or
non-finite time or position, times farther than ``max_time_days`` (default 30 days) from the
median time of the file (one row dated 1916 among 2016 rows would otherwise stretch the
tracker's report grid over a century), latitude outside [-90, 90], longitude outside
[-180, 180], and positions farther than ``max_range_km`` (default 1000 km) from the median
position of the file (the Solent AIS file has one report at longitude +54.8° among longitudes
near -1.2°: a valid number, an impossible position for a Solent vessel). Content that is not a
UTF-8 CSV (gzip, binary, JSON, bytes that are not UTF-8) raises :class:`FileFormatError`.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import ArrayLike, BoolArray, FloatArray, IntArray, StrPath
from navtrack.errors import FileFormatError
from navtrack.geodesy import (
    WGS84_A_M,
    WGS84_E2,
    ecef_to_enu,
    ecef_to_geodetic,
    enu_rotation,
    geodetic_to_ecef,
)
from navtrack.io.tables import last_row_cut, read_csv_text
from navtrack.timescale import gps_seconds, utc_to_gps

__all__ = [
    "GENERIC_COLUMNS",
    "TrackDetections",
    "detect_format",
    "local_enu_to_geodetic",
    "read_ais_csv",
    "read_opensky_csv",
    "read_track_csv",
    "read_tracks",
    "stale_repeats",
    "to_local_enu",
    "velocity_local_enu",
]

UNIX_TO_GPS_EPOCH_S = 315964800.0  # 1980-01-06T00:00:00 UTC in Unix seconds
KNOT_MPS = 1852.0 / 3600.0
STALE_MOVE_M = 25.0
"""A repeated position is stale when the reported speed says the target moved farther than this
since the position was first reported (:func:`stale_repeats`; the tracker's σ floor) ..."""
STALE_MIN_SPEED_MPS = 1.0
"""... at a reported speed above this (a moored ship's speed over ground wanders up to ~0.5 kn,
0.26 m/s, while its position repeats)."""


@dataclass(frozen=True, slots=True, eq=False)
class TrackDetections:
    """Detections read from a file, sorted by time (arrays read-only).

    Attributes
    ----------
    path, format : source file and format (``ais``, ``opensky``, ``csv``)
    t_gps_s : (N,) GPS seconds
    lat_deg, lon_deg : (N,) geodetic position, degrees (NaN when the file gives ``x_m``/``y_m``)
    x_m, y_m : (N,) local position, m (NaN when the file gives lat/lon)
    alt_m, speed_mps, course_deg : (N,) optional columns (NaN when absent)
    id : (N,) str, object identity for scoring (empty strings when absent)
    line : (N,) 1-based line number in the file of each row
    bad_lines : (B,) line numbers of skipped rows; bad_reasons : reason per skipped row
    n_reordered : rows that were out of time order in the file (now sorted, stable)
    ignored_columns : columns present in the file and not used
    """

    path: str
    format: str
    t_gps_s: FloatArray
    lat_deg: FloatArray
    lon_deg: FloatArray
    x_m: FloatArray
    y_m: FloatArray
    alt_m: FloatArray
    speed_mps: FloatArray
    course_deg: FloatArray
    id: np.ndarray
    line: IntArray
    bad_lines: IntArray
    bad_reasons: tuple[str, ...]
    n_reordered: int = 0
    ignored_columns: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        freeze_arrays(self)

    def __len__(self) -> int:
        return int(self.t_gps_s.size)

    @property
    def geodetic(self) -> bool:
        """True when positions are latitude/longitude."""
        return bool(np.isfinite(self.lat_deg).any())

    def summary(self) -> dict[str, Any]:
        reasons: dict[str, int] = {}
        for r in self.bad_reasons:
            reasons[r] = reasons.get(r, 0) + 1
        return {
            "file": self.path,
            "format": self.format,
            "detections": len(self),
            "ids": int(np.unique(self.id).size) if len(self) else 0,
            "bad rows skipped": len(self.bad_lines),
            "bad row reasons": reasons,
            "rows out of time order (sorted)": self.n_reordered,
            "ignored columns": list(self.ignored_columns),
        }


def _read_frame(path: StrPath) -> tuple[Any, bool]:
    """The file as a frame of strings, and whether its last row was cut short."""
    import pandas as pd

    text = read_csv_text(path)
    try:
        df = pd.read_csv(io.StringIO(text), dtype=str, keep_default_na=False, skipinitialspace=True)
    except pd.errors.EmptyDataError:
        raise FileFormatError(path, 1, "empty file (no header)") from None
    except pd.errors.ParserError as exc:
        raise FileFormatError(path, None, f"not a readable CSV: {exc}") from None
    return df, last_row_cut(text)


def _require(path: StrPath, df: Any, cols: list[str]) -> None:
    missing = [c for c in cols if c not in df.columns]
    if missing:
        raise FileFormatError(
            path, 1, f"missing column(s) {missing}; header has {list(df.columns)}"
        )


def _num(df: Any, col: str | None) -> FloatArray:
    import pandas as pd

    if col is None or col not in df.columns:
        return np.full(len(df), np.nan)
    return np.asarray(pd.to_numeric(df[col], errors="coerce"), dtype=float)


def _iso_utc_to_gps(values: Any) -> FloatArray:
    import pandas as pd

    dt = pd.DatetimeIndex(
        pd.to_datetime(np.asarray(values), errors="coerce", utc=True, format="mixed")
    )
    ok = np.asarray(~np.asarray(dt.isna()), dtype=bool)
    out = np.full(len(dt), np.nan)
    if ok.any():
        naive = dt[ok].tz_convert(None).to_numpy(dtype="datetime64[ns]")
        out[ok] = utc_to_gps(gps_seconds(naive))
    return out


@dataclass(frozen=True, slots=True, eq=False)
class _Rows:
    """The columns of a file as read, one value per row, before the row checks."""

    t: FloatArray
    lat: FloatArray
    lon: FloatArray
    x: FloatArray
    y: FloatArray
    alt: FloatArray
    speed: FloatArray
    course: FloatArray
    ids: np.ndarray


def _finish(
    path: StrPath,
    fmt: str,
    df: Any,
    rows: _Rows,
    used: list[str],
    cut_last: bool,
    limits: tuple[float | None, float | None],
) -> TrackDetections:
    """Rows checked (``limits``: ``max_range_km``, ``max_time_days``), the good ones sorted by
    time."""
    r = rows
    n = len(r.t)
    line = np.arange(2, n + 2, dtype=np.int64)  # header is line 1
    reason = _row_reasons(r, cut_last, *limits)
    ok = reason == ""
    idx = np.flatnonzero(ok)
    order = idx[np.argsort(r.t[idx], kind="stable")]
    return TrackDetections(
        path=str(path),
        format=fmt,
        t_gps_s=r.t[order],
        lat_deg=r.lat[order],
        lon_deg=r.lon[order],
        x_m=r.x[order],
        y_m=r.y[order],
        alt_m=r.alt[order],
        speed_mps=r.speed[order],
        course_deg=r.course[order],
        id=np.asarray(r.ids, dtype=str)[order],
        line=line[order],
        bad_lines=line[~ok],
        bad_reasons=tuple(str(v) for v in reason[~ok]),
        n_reordered=int(np.sum(np.diff(r.t[idx]) < 0)),
        ignored_columns=tuple(c for c in df.columns if c not in used),
    )


def _row_reasons(
    r: _Rows, cut_last: bool, max_range_km: float | None, max_time_days: float | None
) -> np.ndarray:
    """Why each row is skipped (module notes; the first reason found), ``""`` for a good row."""
    n = len(r.t)
    reason = np.full(n, "", dtype=object)
    lat, lon, x, y, t = r.lat, r.lon, r.x, r.y, r.t
    geo = not np.all(np.isnan(lat) & np.isnan(lon)) or np.all(np.isnan(x))

    def flag(mask: np.ndarray, why: str) -> None:
        new = mask & (reason == "")
        reason[new] = why

    if cut_last and n:
        reason[-1] = "last row cut by the end of the file (no end of line or fewer fields)"
    flag(~np.isfinite(t), "time not readable")
    if geo:
        flag(~np.isfinite(lat) | ~np.isfinite(lon), "latitude/longitude not a finite number")
        flag(np.abs(lat) > 90, "latitude outside [-90, 90]")
        flag(np.abs(lon) > 180, "longitude outside [-180, 180]")
    else:
        flag(~np.isfinite(x) | ~np.isfinite(y), "x_m/y_m not a finite number")
    ok = reason == ""
    if max_time_days is not None and ok.any():
        t_mid = np.median(t[ok])
        flag(
            ok & (np.abs(t - t_mid) > max_time_days * 86400.0),
            f"time more than {max_time_days:g} days from the median time",
        )
    ok = reason == ""
    if max_range_km is not None and ok.any():
        if geo:
            llh = np.stack([np.radians(lat), np.radians(lon), np.zeros(n)], axis=-1)
            llh[~ok] = 0.0
            xyz = geodetic_to_ecef(llh)
            centre = geodetic_to_ecef(
                [np.radians(np.median(lat[ok])), np.radians(np.median(lon[ok])), 0.0]
            )
            dist = np.linalg.norm(xyz - centre, axis=-1)
        else:
            dist = np.hypot(x - np.median(x[ok]), y - np.median(y[ok]))
        flag(
            ok & (dist > max_range_km * 1e3),
            f"position more than {max_range_km:g} km from the median position",
        )
    return reason


def read_ais_csv(
    path: StrPath, max_range_km: float | None = 1000.0, max_time_days: float | None = 30.0
) -> TrackDetections:
    """Solent AIS file: ``Time`` (UTC), ``MMSI``, ``Latitude_degrees``, ``Longitude_degrees``,
    ``COG_degrees``, ``SOG_knots``."""
    df, cut_last = _read_frame(path)
    cols = ["Time", "MMSI", "Latitude_degrees", "Longitude_degrees"]
    _require(path, df, cols)
    n = len(df)
    return _finish(
        path,
        "ais",
        df,
        _Rows(
            t=_iso_utc_to_gps(df["Time"]),
            lat=_num(df, "Latitude_degrees"),
            lon=_num(df, "Longitude_degrees"),
            x=np.full(n, np.nan),
            y=np.full(n, np.nan),
            alt=np.full(n, np.nan),
            speed=_num(df, "SOG_knots") * KNOT_MPS,
            course=_num(df, "COG_degrees"),
            ids=df["MMSI"].to_numpy(),
        ),
        [*cols, "COG_degrees", "SOG_knots"],
        cut_last,
        (max_range_km, max_time_days),
    )


def read_opensky_csv(
    path: StrPath, max_range_km: float | None = 1000.0, max_time_days: float | None = 30.0
) -> TrackDetections:
    """OpenSky state vectors: ``time`` (Unix s), ``icao24``, ``lat``, ``lon``, ``velocity``
    (m/s), ``heading`` (deg), ``geoaltitude`` (m, else ``baroaltitude``)."""

    df, cut_last = _read_frame(path)
    cols = ["time", "icao24", "lat", "lon"]
    _require(path, df, cols)
    n = len(df)
    alt_col = "geoaltitude" if "geoaltitude" in df.columns else "baroaltitude"
    t = utc_to_gps(_num(df, "time") - UNIX_TO_GPS_EPOCH_S)
    return _finish(
        path,
        "opensky",
        df,
        _Rows(
            t=t,
            lat=_num(df, "lat"),
            lon=_num(df, "lon"),
            x=np.full(n, np.nan),
            y=np.full(n, np.nan),
            alt=_num(df, alt_col),
            speed=_num(df, "velocity"),
            course=_num(df, "heading"),
            ids=df["icao24"].to_numpy(),
        ),
        [*cols, alt_col, "velocity", "heading"],
        cut_last,
        (max_range_km, max_time_days),
    )


GENERIC_COLUMNS = ("time", "lat", "lon", "x_m", "y_m", "id", "alt_m", "speed_mps", "course_deg")
"""The columns of the generic layout (:func:`read_track_csv`)."""

#: Header columns that name a layout (:func:`detect_format`), most specific first.
_SIGNATURES = (
    ("ais", ("Time", "MMSI", "Latitude_degrees", "Longitude_degrees")),
    ("opensky", ("time", "icao24", "lat", "lon")),
)


def detect_format(path: StrPath) -> str:
    """The layout of a tracking file from its header: ``ais`` (Solent AIS), ``opensky``
    (OpenSky state vectors) or ``csv`` (anything else, read by :func:`read_track_csv`).

    Raises
    ------
    FileFormatError
        An empty or unreadable file.
    """
    text = read_csv_text(path)
    header = next(csv.reader(io.StringIO(text.split("\n", 1)[0])), [])
    if not header:
        raise FileFormatError(path, 1, "empty file (no header)")
    names = {h.strip() for h in header}
    return next((fmt for fmt, need in _SIGNATURES if set(need) <= names), "csv")


def read_track_csv(
    path: StrPath,
    max_range_km: float | None = 1000.0,
    max_time_days: float | None = 30.0,
    columns: Mapping[str, str] | None = None,
) -> TrackDetections:
    """Generic layout: ``time`` (ISO 8601 UTC), ``lat`` and ``lon`` (deg) or ``x_m`` and ``y_m``,
    optional ``id``, ``alt_m``, ``speed_mps``, ``course_deg``; other columns are ignored (and
    listed in ``ignored_columns``).

    ``columns`` maps these names to the file's own (``{"lat": "latitude", "alt_m":
    "altitude (m)"}``); a name not mapped is looked up as itself.

    Raises
    ------
    ValueError
        ``columns`` maps a name that is not one of :data:`GENERIC_COLUMNS`.
    FileFormatError
        A mapped column the file does not have, or no time or position columns.
    """
    df, cut_last = _read_frame(path)
    if columns:
        unknown = sorted(set(columns) - set(GENERIC_COLUMNS))
        if unknown:
            raise ValueError(
                f"columns: {', '.join(unknown)} not among {', '.join(GENERIC_COLUMNS)}"
            )
        _require(path, df, list(columns.values()))
        mapped = set(columns.values())
        df = df.drop(columns=[c for c in columns if c in df.columns and c not in mapped])
        df = df.rename(columns={src: name for name, src in columns.items()})
    _require(path, df, ["time"])
    has_ll = "lat" in df.columns and "lon" in df.columns
    has_xy = "x_m" in df.columns and "y_m" in df.columns
    if not (has_ll or has_xy):
        raise FileFormatError(
            path, 1, f"need columns lat, lon or x_m, y_m; header has {list(df.columns)}"
        )
    n = len(df)
    nan = np.full(n, np.nan)
    used = ["time", "id", "alt_m", "speed_mps", "course_deg"]
    used += ["lat", "lon"] if has_ll else ["x_m", "y_m"]
    ids = df["id"].to_numpy() if "id" in df.columns else np.full(n, "", dtype=object)
    return _finish(
        path,
        "csv",
        df,
        _Rows(
            t=_iso_utc_to_gps(df["time"]),
            lat=_num(df, "lat") if has_ll else nan,
            lon=_num(df, "lon") if has_ll else nan,
            x=nan if has_ll else _num(df, "x_m"),
            y=nan if has_ll else _num(df, "y_m"),
            alt=_num(df, "alt_m"),
            speed=_num(df, "speed_mps"),
            course=_num(df, "course_deg"),
            ids=ids,
        ),
        used,
        cut_last,
        (max_range_km, max_time_days),
    )


def read_tracks(
    path: StrPath,
    fmt: str | None = None,
    max_range_km: float | None = 1000.0,
    max_time_days: float | None = 30.0,
    columns: Mapping[str, str] | None = None,
) -> TrackDetections:
    """Read a tracking file of format ``fmt`` in ``{"ais", "opensky", "csv"}``.

    Parameters
    ----------
    path : str or path-like
    fmt : str, optional
        None: detected from the header (:func:`detect_format`); ``csv`` when ``columns`` is
        given.
    max_range_km : float or None
        Rows farther than this (km) from the median position are skipped (None: no check).
    max_time_days : float or None
        Rows dated farther than this (days) from the median time are skipped (None: no check).
    columns : mapping, optional
        The generic layout's names mapped to the file's columns (:func:`read_track_csv`).

    Raises
    ------
    FileFormatError
        Content that is not a UTF-8 CSV, or required columns missing.
    """
    if fmt is None:
        fmt = "csv" if columns else detect_format(path)
    if fmt == "csv":
        return read_track_csv(path, max_range_km, max_time_days, columns)
    if columns:
        raise ValueError(f"columns: a column map applies to the csv layout, not to {fmt}")
    readers = {"ais": read_ais_csv, "opensky": read_opensky_csv}
    if fmt not in readers:
        raise ValueError(f"fmt must be one of ais, csv, opensky, got {fmt!r}")
    return readers[fmt](path, max_range_km, max_time_days)


def _reference_deg(
    det: TrackDetections, ref_lat_deg: float | None, ref_lon_deg: float | None
) -> tuple[float, float]:
    """The tangent-plane reference: the given latitude/longitude or the detections' medians."""
    lat0 = float(np.median(det.lat_deg)) if ref_lat_deg is None else ref_lat_deg
    lon0 = float(np.median(det.lon_deg)) if ref_lon_deg is None else ref_lon_deg
    return lat0, lon0


def to_local_enu(
    det: TrackDetections, ref_lat_deg: float | None = None, ref_lon_deg: float | None = None
) -> tuple[FloatArray, tuple[float, float]]:
    """East/north positions (m) in the tangent plane at a reference point (height 0).

    The reference defaults to the median latitude/longitude. Files with ``x_m``/``y_m`` are
    returned as they are (reference NaN).

    Returns
    -------
    en : (N, 2) east, north, m
    ref : (lat_deg, lon_deg)
    """

    if not det.geodetic:
        return np.stack([det.x_m, det.y_m], axis=-1), (float("nan"), float("nan"))
    lat0, lon0 = _reference_deg(det, ref_lat_deg, ref_lon_deg)
    n = len(det)
    xyz = geodetic_to_ecef(
        np.stack([np.radians(det.lat_deg), np.radians(det.lon_deg), np.zeros(n)], axis=-1)
    )
    ref = geodetic_to_ecef([np.radians(lat0), np.radians(lon0), 0.0])
    return np.asarray(ecef_to_enu(xyz, ref)[:, :2]), (lat0, lon0)


def velocity_local_enu(
    det: TrackDetections, ref_lat_deg: float | None = None, ref_lon_deg: float | None = None
) -> FloatArray:
    """Reported velocities (``speed_mps``, ``course_deg`` clockwise from true north) as east/north
    components (m/s) in the tangent plane of :func:`to_local_enu`.

    Each velocity is rotated from the local north/east at its own position into the reference
    frame (meridian convergence is a few degrees across the OpenSky area). AIS "not available"
    codes (course >= 360°, speed >= 102.2 kn) and missing values give NaN rows.

    Returns
    -------
    v_en : (N, 2)
    """

    s = np.asarray(det.speed_mps, dtype=float)
    c = np.asarray(det.course_deg, dtype=float)
    bad = ~np.isfinite(s) | ~np.isfinite(c) | (c >= 360) | (c < 0) | (s < 0)
    if det.format == "ais":
        bad |= s >= 102.2 * KNOT_MPS
    cr = np.radians(c)
    v_local = np.stack([s * np.sin(cr), s * np.cos(cr), np.zeros_like(s)], axis=-1)
    if det.geodetic:
        lat0, lon0 = _reference_deg(det, ref_lat_deg, ref_lon_deg)
        R_i = enu_rotation(np.radians(det.lat_deg), np.radians(det.lon_deg))  # (N, 3, 3)
        R_0 = enu_rotation(np.radians(lat0), np.radians(lon0))
        v_ecef = np.einsum("nji,nj->ni", R_i, v_local)
        v_local = v_ecef @ R_0.T
    out = np.asarray(v_local[:, :2], dtype=float)
    out[bad] = np.nan
    return out


def local_enu_to_geodetic(en_m: ArrayLike, ref_lat_deg: float, ref_lon_deg: float) -> FloatArray:
    """Latitude and longitude of east/north positions in the tangent plane of
    :func:`to_local_enu`: its exact inverse.

    :func:`to_local_enu` places a point of the ellipsoid (height 0) in the frame of the
    reference and drops its up coordinate, i.e. projects it along the reference's normal onto
    the tangent plane. The inverse goes back along that normal: the point of the ellipsoid on
    the line ``ref + e·east + n·north + u·up`` nearest the plane, ``u`` the smaller root of the
    line's quadratic with the ellipsoid ``(x² + y²)/a² + z²/b² = 1``. Setting ``u = 0`` instead
    misplaces a point by 12 m at 100 km from the reference and 330 m at 300 km.

    Parameters
    ----------
    en_m : array-like, shape (n, 2)
        East and north (m) in the plane tangent to the ellipsoid (height 0) at the reference.
    ref_lat_deg, ref_lon_deg : float
        The reference (deg), as returned by :func:`to_local_enu`.

    Returns
    -------
    ndarray, shape (n, 2)
        Geodetic latitude and longitude (deg, WGS-84) of the points of the ellipsoid that
        project onto ``en_m``.

    Raises
    ------
    ValueError
        ``en_m`` not of shape (n, 2), or a point beyond the ellipsoid's horizon seen along the
        reference's normal (more than about 6 000 km from the reference).
    """

    en = np.asarray(en_m, dtype=float)
    if en.ndim != 2 or en.shape[1] != 2:
        raise ValueError(f"en_m: expected shape (n, 2), got {en.shape}")
    lat0, lon0 = np.radians(ref_lat_deg), np.radians(ref_lon_deg)
    rot = enu_rotation(lat0, lon0)  # rows: east, north, up unit vectors in ECEF
    p0 = geodetic_to_ecef([lat0, lon0, 0.0]) + en @ rot[:2]
    up = rot[2]
    w = np.array([1.0, 1.0, 1.0 / (1.0 - WGS84_E2)]) / WGS84_A_M**2  # 1/a², 1/a², 1/b²
    qa = float(up @ (w * up))
    qb = (p0 * w) @ up
    qc = np.einsum("ij,ij->i", p0 * w, p0) - 1.0
    disc = qb**2 - qa * qc
    if np.any(disc < 0):
        bad = int(np.flatnonzero(disc < 0)[0])
        raise ValueError(
            f"en_m: row {bad} ({en[bad, 0]:.0f}, {en[bad, 1]:.0f} m) lies beyond the horizon "
            "of the tangent plane's reference"
        )
    u = -qc / (qb + np.sqrt(disc))  # the root nearest the plane, without cancellation
    xyz = p0 + u[:, None] * up
    return np.degrees(ecef_to_geodetic(xyz)[:, :2])


def stale_repeats(
    t_s: ArrayLike,
    position: ArrayLike,
    speed_mps: ArrayLike,
    ids: ArrayLike | None = None,
    min_move_m: float = STALE_MOVE_M,
) -> BoolArray:
    """Reports that repeat an earlier position of a target that has since moved on.

    ADS-B state vectors (OpenSky's one per aircraft per second, receivers' 1 s outputs) and
    some AIS feeds repeat the last decoded position at every output time until a new one is
    decoded: the report's time advances, its position does not. Such a report is not a
    measurement at its time; at 250 m/s, one second stale puts it 250 m behind the aircraft,
    outside the gate of a track fed 1 s reports, and it starts a duplicate track. A report is
    stale here when its position equals that of an earlier report exactly (bit for bit: two
    moving targets never share a position to 1e-15°) and its own reported speed
    times the time since that earlier report exceeds ``min_move_m``, at a speed above
    :data:`STALE_MIN_SPEED_MPS`. A moored ship repeating its position at a speed over ground
    of a few tenths of a knot is not stale; without a reported speed nothing is.

    Parameters
    ----------
    t_s : (N,) report times, s (any order)
    position : (N, 2) positions as read (latitude/longitude, or their tangent-plane east/north:
        the same repeats)
    speed_mps : (N,) reported speed over ground (NaN unknown)
    ids : (N,) or None
        Target ids: repeats are then sought within each id only (scoring truth); ``None`` for
        the tracker's input, whose ids are hidden.
    min_move_m : float

    Returns
    -------
    (N,) bool
    """
    import pandas as pd

    t = np.asarray(t_s, dtype=float)
    pos = np.asarray(position, dtype=float)
    keys: dict[str, Any] = {"p0": pos[:, 0], "p1": pos[:, 1]}
    if ids is not None:
        keys["id"] = np.asarray(ids)
    df = pd.DataFrame(keys)
    first = pd.Series(t).groupby([df[k] for k in keys], sort=False).transform("min").to_numpy()
    speed = np.asarray(speed_mps, dtype=float)
    moved = speed * (t - first)
    return np.asarray(np.isfinite(moved) & (moved > min_move_m) & (speed > STALE_MIN_SPEED_MPS))
