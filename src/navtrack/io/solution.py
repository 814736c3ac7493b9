"""Positioning solution files: CSV and Parquet tables, NMEA GGA, KML and GPX tracks.

A *solution frame* is a pandas DataFrame with one row per epoch (see :func:`write_solution` for
its columns). :func:`write_solution` picks the file format from the suffix; :func:`read_solution`
reads navtrack's own CSV and Parquet tables back.

Heights: navtrack writes WGS-84 **ellipsoidal** heights everywhere. Where a format expects a
height above mean sea level (NMEA GGA altitude, GPX ``ele``), the ellipsoidal height is written
and the geoid separation is stated as 0 (GGA field 11, GPX ``geoidheight``), which keeps the
file self-consistent (h = altitude + separation) without pretending to a geoid model. KML tracks
are clamped to the ground, since KML altitudes are above the EGM96 geoid.

References
----------
NMEA 0183 v4.11, GGA sentence; GPX 1.1 schema (https://www.topografix.com/GPX/1/1/);
OGC 07-147r2 KML 2.2.
"""

from __future__ import annotations

from collections.abc import Sequence
from os import fspath
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from navtrack import geodesy, timescale
from navtrack._typing import BoolArray, FloatArray, IntArray, StrPath
from navtrack.errors import FileFormatError, MissingDependencyError

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "FORMATS",
    "SOLUTION_COLUMNS",
    "read_solution",
    "solution_table",
    "write_solution",
]

#: Columns of navtrack's CSV/Parquet solution tables, in file order (docs/vocabulary.md).
SOLUTION_COLUMNS = (
    "time_gps",
    "week",
    "tow_s",
    "x_m",
    "y_m",
    "z_m",
    "lat_deg",
    "lon_deg",
    "h_m",
    "clock_m",
    "sd_e_m",
    "sd_n_m",
    "sd_u_m",
    "n_sats",
    "pdop",
    "status",
    "excluded",
)

#: File suffixes :func:`write_solution` understands.
FORMATS = (".csv", ".parquet", ".nmea", ".kml", ".gpx")

# Decimals written to CSV: 0.1 mm for metres (lat/lon 1e-9 deg ~ 0.1 mm), 1 us for tow_s.
_CSV_DECIMALS = {
    "tow_s": 6,
    "x_m": 4,
    "y_m": 4,
    "z_m": 4,
    "lat_deg": 9,
    "lon_deg": 9,
    "h_m": 4,
    "clock_m": 4,
    "sd_e_m": 4,
    "sd_n_m": 4,
    "sd_u_m": 4,
    "pdop": 3,
}

# RTKLIB solution quality Q -> NMEA GGA fix quality (NMEA 0183: 1 GPS fix, 2 differential,
# 4 RTK fixed, 5 RTK float). PPP (Q=6) has no NMEA code; its ambiguities are float, so 5.
_RTKLIB_Q_TO_GGA = {1: 4, 2: 5, 3: 2, 4: 2, 5: 1, 6: 5}


# --------------------------------------------------------------------------------------------
# Normalising a solution frame
# --------------------------------------------------------------------------------------------


def _missing(df: pd.DataFrame, names: Sequence[str]) -> list[str]:
    return [n for n in names if n not in df.columns]


def _excluded_strings(values: Any) -> np.ndarray:
    """Space-separated satellite ids from strings, sequences of ids or missing values."""
    out = []
    for v in values:
        if isinstance(v, str):
            out.append(v)
        elif v is None or (isinstance(v, float) and np.isnan(v)):
            out.append("")
        else:
            out.append(" ".join(str(s) for s in v))
    return np.array(out, dtype=object)


def solution_table(df: pd.DataFrame) -> pd.DataFrame:
    """The full solution table of a solution frame: every column of :data:`SOLUTION_COLUMNS`
    in order, derived where absent, then the frame's other columns.

    Parameters
    ----------
    df : pandas.DataFrame
        One row per epoch. Required: ``t_gps_s`` (GPS seconds), the position as ``x_m``,
        ``y_m``, ``z_m`` (ECEF, m) or as ``lat_deg``, ``lon_deg``, ``h_m`` (WGS-84, ellipsoidal
        height), and ``status``. Optional (written empty when absent): ``clock_m``, ``sd_e_m``,
        ``sd_n_m``, ``sd_u_m``, ``n_sats``, ``pdop``, ``excluded`` (space-separated satellite ids
        or a sequence of ids per row). ``time_gps``, ``week``, ``tow_s`` are always derived from
        ``t_gps_s``; the missing one of ECEF/geodetic position is derived from the other.

    Returns
    -------
    pandas.DataFrame
        A new frame (the input is not modified); ``t_gps_s`` is not among its columns.

    Raises
    ------
    ValueError
        Missing required columns (named in the message) or non-finite ``t_gps_s``.
    """
    import pandas as pd

    has_xyz = not _missing(df, ("x_m", "y_m", "z_m"))
    has_llh = not _missing(df, ("lat_deg", "lon_deg", "h_m"))
    missing = _missing(df, ("t_gps_s", "status"))
    if not has_xyz and not has_llh:
        missing += _missing(df, ("x_m", "y_m", "z_m"))
        missing = [*missing, "(or lat_deg, lon_deg, h_m)"]
    if missing:
        raise ValueError(f"df: solution frame lacks the columns {', '.join(missing)}")
    t = df["t_gps_s"].to_numpy(dtype=float)
    if not np.all(np.isfinite(t)):
        bad = int(np.flatnonzero(~np.isfinite(t))[0])
        raise ValueError(f"df: t_gps_s is not finite in row {bad}")

    n = len(df)
    if has_xyz:
        xyz = df[["x_m", "y_m", "z_m"]].to_numpy(dtype=float)
    if has_llh:
        llh_deg = df[["lat_deg", "lon_deg", "h_m"]].to_numpy(dtype=float)
    if not has_llh:
        llh = geodesy.ecef_to_geodetic(xyz)
        llh_deg = np.stack([np.degrees(llh[:, 0]), np.degrees(llh[:, 1]), llh[:, 2]], axis=-1)
    if not has_xyz:
        xyz = geodesy.geodetic_to_ecef(
            np.stack([np.radians(llh_deg[:, 0]), np.radians(llh_deg[:, 1]), llh_deg[:, 2]], -1)
        )
    week, tow = timescale.week_tow(t)
    time_gps = np.datetime_as_string(timescale.to_datetime64(t).astype("datetime64[ms]"))

    def optional_float(name: str) -> FloatArray:
        if name in df.columns:
            return df[name].to_numpy(dtype=float)
        return np.full(n, np.nan)

    if "n_sats" in df.columns:
        n_sats = pd.array(df["n_sats"].to_numpy(), dtype="Int64")
    else:
        n_sats = pd.array([None] * n, dtype="Int64")
    excluded = (
        _excluded_strings(df["excluded"]) if "excluded" in df.columns else np.full(n, "", object)
    )
    table = pd.DataFrame(
        {
            "time_gps": time_gps,
            "week": week,
            "tow_s": tow,
            "x_m": xyz[:, 0],
            "y_m": xyz[:, 1],
            "z_m": xyz[:, 2],
            "lat_deg": llh_deg[:, 0],
            "lon_deg": llh_deg[:, 1],
            "h_m": llh_deg[:, 2],
            "clock_m": optional_float("clock_m"),
            "sd_e_m": optional_float("sd_e_m"),
            "sd_n_m": optional_float("sd_n_m"),
            "sd_u_m": optional_float("sd_u_m"),
            "n_sats": n_sats,
            "pdop": optional_float("pdop"),
            "status": df["status"].to_numpy(),
            "excluded": excluded,
        },
        index=pd.RangeIndex(n),
    )
    extras = [c for c in df.columns if c not in table.columns and c != "t_gps_s"]
    for c in extras:
        table[c] = df[c].to_numpy()
    return table


def _ok_mask(status: Any, ok_status: object) -> BoolArray:
    """Epochs whose status marks a valid fix (equal to ``ok_status`` or, for enumerations and
    strings, named like it regardless of case)."""
    values = np.asarray(status, dtype=object)
    target = str(ok_status).lower()
    return np.array(
        [v == ok_status or str(getattr(v, "name", v)).lower() == target for v in values],
        dtype=bool,
    )


# --------------------------------------------------------------------------------------------
# Writing
# --------------------------------------------------------------------------------------------


def _check_writable(path: Path) -> None:
    parent = path.parent if fspath(path.parent) else Path(".")
    if not parent.is_dir():
        raise FileNotFoundError(
            2,
            f"cannot write solution file: directory {fspath(parent)!r} does not exist",
            fspath(path),
        )
    if path.is_dir():
        raise IsADirectoryError(21, "cannot write solution file: it is a directory", fspath(path))


def _open_for_writing(path: Path) -> Any:
    try:
        return path.open("w", encoding="utf-8", newline="")
    except OSError as exc:
        raise OSError(
            exc.errno, f"cannot write solution file: {exc.strerror}", fspath(path)
        ) from exc


def write_solution(
    df: pd.DataFrame,
    path: StrPath,
    *,
    ok_status: object = "ok",
    talker: str = "GP",
) -> Path:
    """Write a solution frame in the format its file suffix names.

    Parameters
    ----------
    df : pandas.DataFrame
        One row per epoch; columns as :func:`solution_table` describes (``t_gps_s``, position,
        ``status`` required). Rows are written in the given order, failed epochs included.
    path : str or path-like
        Output file; the suffix chooses the format:

        ``.csv``
            :data:`SOLUTION_COLUMNS` in that order, then the frame's extra columns. Times are
            GPST: ``time_gps`` ISO 8601 to the millisecond, ``tow_s`` to the microsecond;
            metres to 0.1 mm, degrees to 1e-9. Missing values are empty fields.
        ``.parquet``
            The same table at full precision (needs pyarrow, extra ``parquet``).
        ``.nmea``
            One ``$..GGA`` sentence per epoch: UTC time (GPST minus leap seconds) to 0.01 s,
            latitude/longitude as ``ddmm.mmmmmm``/``dddmm.mmmmmm``, fix quality 1 for valid
            epochs (or mapped from RTKLIB's ``q`` column: 1->4, 2->5, 3/4->2, 5->1, 6->5), 0 and
            empty position fields otherwise, satellites used, HDOP from a ``hdop`` column when
            there is one, **otherwise PDOP** in the HDOP field, altitude = ellipsoidal height
            with geoid separation 0. GGA carries no date.
        ``.kml``
            KML 2.2 document with the valid epochs as one ``LineString`` clamped to the ground.
        ``.gpx``
            GPX 1.1 track; one ``trkseg`` per run of consecutive valid epochs, ``time`` in UTC,
            ``ele`` = ellipsoidal height with ``geoidheight`` 0, ``fix`` 3d, ``sat``, ``pdop``
            (and ``hdop``/``vdop`` when the frame has them).

        KML and GPX cannot hold an epoch without a position; the document's description states
        how many epochs were left out.
    ok_status : object, default "ok"
        ``status`` value marking a valid fix (compared as is and, case-insensitively, by name).
    talker : str, default "GP"
        NMEA talker id (two letters; ``"GN"`` for multi-GNSS).

    Returns
    -------
    pathlib.Path
        The written file.

    Raises
    ------
    ValueError
        Unknown suffix, missing columns (named), bad ``talker``.
    OSError
        The file cannot be written; the message names the path.
    MissingDependencyError
        ``.parquet`` without pyarrow.
    """
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix not in FORMATS:
        raise ValueError(
            f"path: unknown solution format {p.suffix!r} of {fspath(p)!r}; "
            f"expected one of {', '.join(FORMATS)}"
        )
    if len(talker) != 2 or not talker.isalpha() or not talker.isupper():
        raise ValueError(f"talker: expected two upper-case letters, got {talker!r}")
    table = solution_table(df)
    _check_writable(p)
    if suffix == ".csv":
        _write_csv(table, p)
    elif suffix == ".parquet":
        _write_parquet(table, p)
    else:
        ok = _ok_mask(table["status"], ok_status) & np.isfinite(
            table[["lat_deg", "lon_deg", "h_m"]].to_numpy(float)
        ).all(axis=1)
        t = df["t_gps_s"].to_numpy(float)
        if suffix == ".nmea":
            text = "".join(s + "\r\n" for s in nmea_gga(table, t, ok, talker=talker))
        elif suffix == ".kml":
            text = _kml(table, ok)
        else:
            text = _gpx(table, t, ok)
        with _open_for_writing(p) as fh:
            fh.write(text)
    return p


def _write_csv(table: pd.DataFrame, path: Path) -> None:
    out = table.copy()
    for name, dec in _CSV_DECIMALS.items():
        out[name] = np.round(out[name].to_numpy(float), dec)
    with _open_for_writing(path) as fh:
        out.to_csv(fh, index=False, lineterminator="\n")


def _write_parquet(table: pd.DataFrame, path: Path) -> None:
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        raise MissingDependencyError("pyarrow", "parquet", "Parquet solution files") from None
    out = table.copy()
    out["status"] = out["status"].astype(str) if out["status"].dtype == object else out["status"]
    out["excluded"] = out["excluded"].astype(str)
    try:
        out.to_parquet(path, index=False)
    except OSError as exc:
        raise OSError(exc.errno, f"cannot write solution file: {exc}", fspath(path)) from exc


# --------------------------------------------------------------------------------------------
# NMEA
# --------------------------------------------------------------------------------------------


def nmea_checksums(bodies: Sequence[str]) -> IntArray:
    """NMEA checksums: XOR of the bytes between ``$`` and ``*`` (exclusive) of each body.

    Parameters
    ----------
    bodies : sequence of str, length n
        Sentence bodies without ``$`` and ``*`` (ASCII).

    Returns
    -------
    ndarray of int64, shape (n,)
    """
    if len(bodies) == 0:
        return np.zeros(0, dtype=np.int64)
    raw = np.array(bodies, dtype=str).astype(np.bytes_)
    codes = raw.view(np.uint8).reshape(len(bodies), raw.dtype.itemsize)
    # Padding bytes are 0, the neutral element of XOR.
    return np.bitwise_xor.reduce(codes, axis=1).astype(np.int64)


def _ddmm(value_deg: FloatArray, deg_width: int, decimals: int) -> list[str]:
    """Angles as NMEA ``d..dmm.mmmm`` with carries handled in integers (no ``60.0000``)."""
    scale = 10**decimals
    units = np.round(np.abs(value_deg) * 60.0 * scale).astype(np.int64)
    deg = units // (60 * scale)
    rem = units % (60 * scale)
    minutes, frac = rem // scale, rem % scale
    return [
        f"{d:0{deg_width}d}{m:02d}.{f:0{decimals}d}"
        for d, m, f in zip(deg.tolist(), minutes.tolist(), frac.tolist(), strict=True)
    ]


def nmea_gga(
    table: pd.DataFrame, t_gps_s: FloatArray, ok: BoolArray, *, talker: str = "GP"
) -> list[str]:
    """GGA sentences (with ``$`` and checksum, without line ends) of a solution table.

    Parameters
    ----------
    table : pandas.DataFrame
        As :func:`solution_table` returns, n rows.
    t_gps_s : ndarray, shape (n,)
        GPS seconds of the rows.
    ok : ndarray of bool, shape (n,)
        Rows with a valid fix; the others get quality 0 and empty position fields.
    talker : str
        Two-letter talker id.

    Returns
    -------
    list of str, length n
    """
    n = len(table)
    utc_cs = np.round(timescale.gps_to_utc(t_gps_s) * 100.0).astype(np.int64)
    # 1980-01-06 00:00 UTC is a midnight, so the time of day is the remainder modulo one day.
    tod = utc_cs % 8_640_000
    hh, mm, cs = tod // 360_000, (tod // 6_000) % 60, tod % 6_000
    times = [
        f"{h:02d}{m:02d}{c // 100:02d}.{c % 100:02d}"
        for h, m, c in zip(hh.tolist(), mm.tolist(), cs.tolist(), strict=True)
    ]
    lat = table["lat_deg"].to_numpy(float)
    lon = table["lon_deg"].to_numpy(float)
    h = table["h_m"].to_numpy(float)
    lat_s = _ddmm(np.where(ok, lat, 0.0), 2, 6)
    lon_s = _ddmm(np.where(ok, lon, 0.0), 3, 6)
    ns = np.where(lat >= 0.0, "N", "S")
    ew = np.where(lon >= 0.0, "E", "W")
    if "q" in table.columns:
        q = table["q"].to_numpy()
        quality = np.array([_RTKLIB_Q_TO_GGA.get(int(v), 0) for v in q], dtype=np.int64)
    else:
        quality = np.ones(n, dtype=np.int64)
    quality = np.where(ok, quality, 0)
    n_sats = table["n_sats"].to_numpy(dtype=float, na_value=np.nan)
    sats = [f"{int(v):02d}" if np.isfinite(v) else "" for v in n_sats.tolist()]
    dop_col = "hdop" if "hdop" in table.columns else "pdop"
    dop = table[dop_col].to_numpy(float)
    dops = [f"{v:.2f}" if np.isfinite(v) else "" for v in dop.tolist()]
    bodies = []
    for i in range(n):
        if ok[i]:
            pos = (
                f"{lat_s[i]},{ns[i]},{lon_s[i]},{ew[i]},{quality[i]},{sats[i]},{dops[i]},"
                f"{h[i]:.3f},M,0.0,M"
            )
        else:
            pos = f",,,,0,{sats[i]},{dops[i]},,M,,M"
        bodies.append(f"{talker}GGA,{times[i]},{pos},,")
    sums = nmea_checksums(bodies)
    return [f"${b}*{c:02X}" for b, c in zip(bodies, sums.tolist(), strict=True)]


# --------------------------------------------------------------------------------------------
# KML and GPX
# --------------------------------------------------------------------------------------------


def _utc_iso(t_gps_s: FloatArray) -> np.ndarray:
    """UTC ISO 8601 strings with milliseconds and ``Z``."""
    utc = timescale.to_datetime64(timescale.gps_to_utc(t_gps_s)).astype("datetime64[ms]")
    return np.char.add(np.datetime_as_string(utc), "Z")


def _kml(table: pd.DataFrame, ok: BoolArray) -> str:
    lat = table["lat_deg"].to_numpy(float)[ok]
    lon = table["lon_deg"].to_numpy(float)[ok]
    coords = " ".join(f"{a:.9f},{b:.9f}" for a, b in zip(lon.tolist(), lat.tolist(), strict=True))
    n, n_ok = len(table), int(ok.sum())
    first = table["time_gps"].iloc[0] if n else ""
    last = table["time_gps"].iloc[-1] if n else ""
    desc = (
        f"navtrack solution, {n} epochs ({first} to {last} GPST), {n_ok} with a valid "
        f"position drawn, {n - n_ok} without a valid position left out"
    )
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<kml xmlns="http://www.opengis.net/kml/2.2">\n'
        "<Document>\n"
        "<name>navtrack solution</name>\n"
        f"<description>{desc}</description>\n"
        '<Style id="track"><LineStyle><color>ff0000ff</color><width>2</width></LineStyle>'
        "</Style>\n"
        "<Placemark>\n<name>track</name>\n<styleUrl>#track</styleUrl>\n"
        "<LineString>\n<tessellate>1</tessellate>\n<altitudeMode>clampToGround</altitudeMode>\n"
        f"<coordinates>{coords}</coordinates>\n"
        "</LineString>\n</Placemark>\n</Document>\n</kml>\n"
    )


def _gpx(table: pd.DataFrame, t_gps_s: FloatArray, ok: BoolArray) -> str:
    n, n_ok = len(table), int(ok.sum())
    idx = np.flatnonzero(ok)
    times = _utc_iso(t_gps_s[idx])
    lat = table["lat_deg"].to_numpy(float)[idx]
    lon = table["lon_deg"].to_numpy(float)[idx]
    h = table["h_m"].to_numpy(float)[idx]
    n_sats = table["n_sats"].to_numpy(dtype=float, na_value=np.nan)[idx]

    def element(name: str, values: FloatArray, fmt: str) -> list[str]:
        return [f"<{name}>{v:{fmt}}</{name}>" if np.isfinite(v) else "" for v in values.tolist()]

    sats = element("sat", n_sats, ".0f")
    dops = [
        element(name, table[name].to_numpy(float)[idx], ".2f")
        for name in ("hdop", "vdop", "pdop")
        if name in table.columns
    ]
    dop_str = ["".join(parts) for parts in zip(*dops, strict=True)] if dops else [""] * len(idx)
    # A new segment starts wherever the previous row was not a valid fix.
    new_seg = np.ones(len(idx), dtype=bool)
    new_seg[1:] = np.diff(idx) > 1
    pts = []
    for i in range(len(idx)):
        if new_seg[i] and i:
            pts.append("</trkseg><trkseg>")
        pts.append(
            f'<trkpt lat="{lat[i]:.9f}" lon="{lon[i]:.9f}"><ele>{h[i]:.4f}</ele>'
            f"<time>{times[i]}</time><geoidheight>0</geoidheight><fix>3d</fix>"
            f"{sats[i]}{dop_str[i]}</trkpt>"
        )
    desc = (
        f"navtrack solution, {n} epochs, {n_ok} with a valid position, {n - n_ok} without a "
        "valid position left out; ele is the WGS-84 ellipsoidal height (geoidheight 0)"
    )
    body = "\n".join(pts)
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<gpx version="1.1" creator="navtrack" xmlns="http://www.topografix.com/GPX/1/1">\n'
        f"<metadata><desc>{desc}</desc></metadata>\n"
        "<trk><name>navtrack solution</name>\n"
        + ("<trkseg>\n" + body + "\n</trkseg>\n" if len(idx) else "")
        + "</trk>\n</gpx>\n"
    )


# --------------------------------------------------------------------------------------------
# Reading navtrack's own tables
# --------------------------------------------------------------------------------------------


def read_solution(path: StrPath) -> pd.DataFrame:
    """Read a CSV or Parquet solution table written by :func:`write_solution`.

    Parameters
    ----------
    path : str or path-like
        ``.csv`` or ``.parquet`` file.

    Returns
    -------
    pandas.DataFrame
        ``t_gps_s`` (GPS seconds, from ``week`` and ``tow_s``) followed by the file's columns;
        ``excluded`` is a string column ("" where no satellite was excluded).

    Raises
    ------
    FileFormatError
        Columns of :data:`SOLUTION_COLUMNS` missing, or ``time_gps`` disagreeing with
        ``week``/``tow_s`` by more than 1 ms (the message names the data line).
    MissingDependencyError
        A Parquet file without pyarrow installed.
    """
    import pandas as pd

    p = Path(path)
    suffix = p.suffix.lower()
    if suffix == ".csv":
        try:
            df = pd.read_csv(p, dtype={"excluded": str, "time_gps": str}, keep_default_na=True)
        except (pd.errors.ParserError, UnicodeDecodeError) as exc:
            raise FileFormatError(p, None, f"not a CSV solution table: {exc}") from None
    elif suffix == ".parquet":
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            raise MissingDependencyError("pyarrow", "parquet", "Parquet solution files") from None
        df = pd.read_parquet(p)
    else:
        raise ValueError(f"path: expected a .csv or .parquet solution table, got {fspath(p)!r}")
    missing = _missing(df, SOLUTION_COLUMNS)
    if missing:
        raise FileFormatError(p, 1, f"solution table lacks the columns {', '.join(missing)}")
    df["excluded"] = df["excluded"].fillna("").astype(str)
    try:
        t = timescale.from_week_tow(df["week"].to_numpy(float), df["tow_s"].to_numpy(float))
        t_iso = timescale.gps_seconds(df["time_gps"].to_numpy(dtype=str))
    except ValueError as exc:
        raise FileFormatError(p, None, f"unreadable time: {exc}") from None
    bad = np.flatnonzero(~(np.abs(t - t_iso) <= 1e-3))
    if bad.size:
        k = int(bad[0])
        msg = f"time_gps {df['time_gps'].iloc[k]} disagrees with week/tow_s"
        if suffix == ".csv":
            raise FileFormatError(p, k + 2, msg)  # line 1 is the column header
        raise FileFormatError(p, None, f"row {k}: {msg}")
    df.insert(0, "t_gps_s", t)
    return df
