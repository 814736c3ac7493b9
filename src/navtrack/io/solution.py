"""Positioning solution files: CSV and Parquet tables, RTKLIB .pos, NMEA GGA/RMC, KML and GPX.

A *solution frame* is a pandas DataFrame, or any mapping of column names to 1-D arrays, with
one row per epoch (see :func:`solution_columns` for its columns). :func:`write_solution` picks
the file format from the suffix; :func:`read_solution` reads navtrack's own CSV and Parquet
tables back.

Formats of :func:`write_solution` (by file suffix):

``.csv``
    :data:`SOLUTION_COLUMNS` in that order, then the frame's extra columns. Times are
    GPST: ``time_gps`` ISO 8601 to the millisecond, ``tow_s`` to the microsecond;
    metres to 0.1 mm, degrees to 1e-9, DOP to 0.001; missing values are empty fields.
``.parquet``
    The same table at full precision (needs pandas and pyarrow, extra ``parquet``).
``.pos``
    RTKLIB's solution file as ``rnx2rtkp`` writes it by default (GPST, ECEF, Q, ns,
    ``sdx`` ... ``sdzx``, age, ratio; :func:`navtrack.io.rtklib.format_pos`); epochs
    without a valid fix are left out, as RTKLIB leaves them out.
``.nmea``
    One ``$..GGA`` sentence per epoch: UTC time (GPST minus leap seconds) to 0.01 s,
    latitude/longitude as ``ddmm.mmmmmm``/``dddmm.mmmmmm``, fix quality 1 for valid
    epochs (or mapped from RTKLIB's ``q`` or navtrack's ``quality`` column: 1->4, 2->5,
    3/4->2, 5->1, 6->5), 0 and empty position fields otherwise, satellites used, HDOP from a
    ``hdop`` column when there is one, **otherwise PDOP** in the HDOP field, altitude =
    ellipsoidal height with geoid separation 0. GGA carries no date (``nmea_rmc=True`` adds
    RMC, with speed and course from ``ve_mps``/``vn_mps`` when the frame has them).
``.kml``
    KML 2.2 document with the valid epochs as one time-stamped ``gx:Track`` (UTC
    ``when`` per epoch) clamped to the ground.
``.gpx``
    GPX 1.1 track; one ``trkseg`` per run of consecutive valid epochs, ``time`` in UTC,
    ``ele`` = ellipsoidal height with ``geoidheight`` 0, ``fix`` 3d, ``sat``, ``pdop``
    (and ``hdop``/``vdop`` when the frame has them).

KML and GPX cannot hold an epoch without a position; the document's description states
how many epochs were left out.

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

from collections.abc import Mapping, Sequence
from os import fspath
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeAlias

import numpy as np

from navtrack import geodesy, timescale
from navtrack._typing import BoolArray, FloatArray, IntArray, StrPath
from navtrack.errors import FileFormatError, MissingDependencyError
from navtrack.io.rtklib import format_pos

if TYPE_CHECKING:
    import pandas as pd  # for the readers only: `navtrack pos` writes without pandas

#: A solution frame: a pandas DataFrame or any mapping of column name to a 1-D array.
SolutionLike: TypeAlias = "pd.DataFrame | Mapping[str, Any]"

__all__ = [
    "FORMATS",
    "SOLUTION_COLUMNS",
    "nmea_checksums",
    "nmea_gga",
    "ok_mask",
    "read_solution",
    "solution_columns",
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
FORMATS = (".csv", ".parquet", ".pos", ".nmea", ".kml", ".gpx")

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
# One knot in m/s (1852 m per hour).
_KNOT_MPS = 1852.0 / 3600.0
_HEX = tuple(f"{i:02X}" for i in range(256))
# GGA fix quality -> RMC mode indicator (NMEA 0183 v2.3+).
_GGA_TO_MODE = {1: "A", 2: "D", 4: "R", 5: "F"}


# --------------------------------------------------------------------------------------------
# Normalising a solution frame
# --------------------------------------------------------------------------------------------


def _keys(df: SolutionLike) -> list[str]:
    return [str(k) for k in df]


def _missing(df: SolutionLike, names: Sequence[str]) -> list[str]:
    keys = set(_keys(df))
    return [n for n in names if n not in keys]


def _float(values: Any) -> FloatArray:
    """float64 copy-free view of a column (pandas nullable NA -> NaN)."""
    if hasattr(values, "to_numpy"):
        return np.asarray(values.to_numpy(dtype=float, na_value=np.nan), dtype=float)
    return np.asarray(values, dtype=float)


def _excluded_strings(values: Any) -> np.ndarray:
    """Space-separated satellite ids from strings, sequences of ids or missing values."""
    if isinstance(values, np.ndarray) and values.dtype.kind == "U":
        return values.astype(object)
    out = []
    for v in values:
        if isinstance(v, str):
            out.append(v)
        elif v is None or (isinstance(v, float) and np.isnan(v)):
            out.append("")
        else:
            out.append(" ".join(str(s) for s in v))
    return np.array(out, dtype=object)


def solution_columns(df: SolutionLike) -> dict[str, np.ndarray]:
    """The full solution table of a solution frame as a dict of NumPy columns: every column of
    :data:`SOLUTION_COLUMNS` in order, derived where absent, then the frame's other columns.

    Needs no pandas: ``df`` may be a DataFrame or any mapping of column name to array (the
    positioning command writes its output without importing pandas).

    Parameters
    ----------
    df : pandas.DataFrame or mapping of str to array-like
        One row per epoch. Required: ``t_gps_s`` (GPS seconds), the position as ``x_m``,
        ``y_m``, ``z_m`` (ECEF, m) or as ``lat_deg``, ``lon_deg``, ``h_m`` (WGS-84, ellipsoidal
        height), and ``status``. Optional (written empty when absent): ``clock_m``, ``sd_e_m``,
        ``sd_n_m``, ``sd_u_m``, ``n_sats``, ``pdop``, ``excluded`` (space-separated satellite ids
        or a sequence of ids per row). ``time_gps``, ``week``, ``tow_s`` are always derived from
        ``t_gps_s`` (``time_gps`` rounded to the nearest millisecond: t = ...40.0006 s gives
        ``...40.001``); the missing one of ECEF/geodetic position is derived from the other.
        :func:`navtrack.gnss.spp.solution_frame` gives this frame for an SPP result.

    Returns
    -------
    dict of str to ndarray
        New arrays, all of length n (the input is not modified); ``n_sats`` is float64 with NaN
        where unknown; ``t_gps_s`` is not among the keys.

    Raises
    ------
    ValueError
        Missing required columns (named in the message), columns of different lengths or
        non-finite ``t_gps_s``.
    """
    t = _checked_times(df)
    n = t.shape[0]
    xyz, llh_deg = _both_positions(df)
    week, tow, time_gps = _gps_times(t)
    keys = set(_keys(df))

    def optional_float(name: str) -> FloatArray:
        return _float(df[name]).copy() if name in keys else np.full(n, np.nan)

    excluded = _excluded_strings(df["excluded"]) if "excluded" in keys else np.full(n, "", object)
    cols: dict[str, np.ndarray] = {
        "time_gps": time_gps,
        "week": week,
        "tow_s": tow,
        "x_m": xyz[:, 0].copy(),
        "y_m": xyz[:, 1].copy(),
        "z_m": xyz[:, 2].copy(),
        "lat_deg": llh_deg[:, 0].copy(),
        "lon_deg": llh_deg[:, 1].copy(),
        "h_m": llh_deg[:, 2].copy(),
        "clock_m": optional_float("clock_m"),
        "sd_e_m": optional_float("sd_e_m"),
        "sd_n_m": optional_float("sd_n_m"),
        "sd_u_m": optional_float("sd_u_m"),
        "n_sats": optional_float("n_sats"),
        "pdop": optional_float("pdop"),
        "status": np.array(df["status"], copy=True),
        "excluded": excluded,
    }
    for k in _keys(df):
        if k not in cols and k != "t_gps_s":
            cols[k] = np.array(df[k], copy=True)
    return cols


def _checked_times(df: SolutionLike) -> FloatArray:
    """``t_gps_s`` of a frame that has every required column, all of its length (ValueError
    naming what is wrong)."""
    has_xyz = not _missing(df, ("x_m", "y_m", "z_m"))
    has_llh = not _missing(df, ("lat_deg", "lon_deg", "h_m"))
    missing = _missing(df, ("t_gps_s", "status"))
    if not has_xyz and not has_llh:
        missing += _missing(df, ("x_m", "y_m", "z_m"))
        missing = [*missing, "(or lat_deg, lon_deg, h_m)"]
    if missing:
        raise ValueError(f"df: solution frame lacks the columns {', '.join(missing)}")
    t = _float(df["t_gps_s"])
    n = t.shape[0]
    if t.ndim != 1:
        raise ValueError(f"df: t_gps_s must be one-dimensional, got shape {t.shape}")
    lengths = {k: len(df[k]) for k in _keys(df)}
    wrong = sorted(k for k, m in lengths.items() if m != n)
    if wrong:
        raise ValueError(f"df: columns {', '.join(wrong)} do not have the {n} rows of t_gps_s")
    if not np.all(np.isfinite(t)):
        bad = int(np.flatnonzero(~np.isfinite(t))[0])
        raise ValueError(f"df: t_gps_s is not finite in row {bad}")
    return t


def _both_positions(df: SolutionLike) -> tuple[FloatArray, FloatArray]:
    """(xyz_m, llh_deg): the ECEF and geodetic position, the one absent derived from the other."""
    has_xyz = not _missing(df, ("x_m", "y_m", "z_m"))
    has_llh = not _missing(df, ("lat_deg", "lon_deg", "h_m"))
    if has_xyz:
        xyz = np.stack([_float(df["x_m"]), _float(df["y_m"]), _float(df["z_m"])], axis=-1)
    if has_llh:
        llh_deg = np.stack(
            [_float(df["lat_deg"]), _float(df["lon_deg"]), _float(df["h_m"])], axis=-1
        )
    if not has_llh:
        llh = geodesy.ecef_to_geodetic(xyz)
        llh_deg = np.stack([np.degrees(llh[:, 0]), np.degrees(llh[:, 1]), llh[:, 2]], axis=-1)
    if not has_xyz:
        xyz = geodesy.geodetic_to_ecef(
            np.stack([np.radians(llh_deg[:, 0]), np.radians(llh_deg[:, 1]), llh_deg[:, 2]], -1)
        )
    return xyz, llh_deg


def _gps_times(t: FloatArray) -> tuple[IntArray, FloatArray, np.ndarray]:
    """(week, tow_s, time_gps): GPS week, time of week and the ISO time rounded (not truncated)
    to the millisecond."""
    week, tow = timescale.week_tow(t)
    t_ms = np.round((t - timescale.from_week_tow(week, 0.0)) * 1e3).astype("timedelta64[ms]")
    week_start = timescale.GPS_EPOCH.astype("datetime64[ms]") + (week * 7).astype("timedelta64[D]")
    return week, tow, np.datetime_as_string(week_start + t_ms)


def solution_table(df: SolutionLike) -> pd.DataFrame:
    """:func:`solution_columns` as a pandas DataFrame (``n_sats`` as nullable ``Int64``)."""
    return _frame(solution_columns(df))


def _frame(cols: dict[str, np.ndarray]) -> pd.DataFrame:
    import pandas as pd  # for the readers only: `navtrack pos` writes without pandas

    table = pd.DataFrame(cols)
    table["n_sats"] = pd.array(
        [None if np.isnan(v) else int(v) for v in cols["n_sats"].tolist()], dtype="Int64"
    )
    return table


def ok_mask(status: Any, ok_status: object = "ok") -> BoolArray:
    """Epochs whose ``status`` marks a valid fix: equal to ``ok_status`` or, for strings and
    enumerations, named like it regardless of case (a tuple: any of its statuses). Returns a
    bool array of the length of ``status``."""
    if isinstance(ok_status, tuple):  # any of several statuses (RTK: fix, float, dgnss, ...)
        masks = [ok_mask(status, s) for s in ok_status]
        return np.logical_or.reduce(masks) if masks else np.zeros(len(status), dtype=bool)
    target = str(ok_status).lower()
    arr = np.asarray(status)
    if arr.dtype.kind == "U":
        return np.asarray((arr == str(ok_status)) | (np.strings.lower(arr) == target))
    values = np.asarray(status, dtype=object)
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
    df: SolutionLike,
    path: StrPath,
    *,
    ok_status: object = "ok",
    talker: str = "GP",
    nmea_rmc: bool = False,
    header: Sequence[str] = (),
) -> Path:
    """Write a solution frame in the format its file suffix names.

    Parameters
    ----------
    df : pandas.DataFrame or mapping of str to array-like
        One row per epoch; columns as :func:`solution_columns` describes (``t_gps_s``,
        position, ``status`` required). Rows are written in the given order, failed epochs
        included. CSV, NMEA, KML and GPX are written without pandas.
    path : str or path-like
        Output file; the suffix chooses the format (one of :data:`FORMATS`, described in
        the module notes).
    ok_status : object, default "ok"
        ``status`` value marking a valid fix (compared as is and, case-insensitively, by name);
        a tuple of values: any of them.
    talker : str, default "GP"
        NMEA talker id (two letters; ``"GN"`` for multi-GNSS).
    nmea_rmc : bool, default False
        NMEA only: follow each GGA with an RMC sentence, which carries the UTC date.
    header : sequence of str
        ``.pos`` only: header lines (input files, options) written above the column header.

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
        ``.parquet`` without pandas or pyarrow.
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
    cols = solution_columns(df)
    _check_writable(p)
    if suffix == ".parquet":
        _write_parquet(cols, p)
        return p
    if suffix == ".csv":
        text = _csv(cols)
    else:
        llh = np.stack([cols["lat_deg"], cols["lon_deg"], cols["h_m"]], axis=-1)
        ok = ok_mask(cols["status"], ok_status) & np.isfinite(llh).all(axis=1)
        t = _float(df["t_gps_s"])
        if suffix == ".pos":
            text = format_pos(cols, t, ok, header)
        elif suffix == ".nmea":
            text = "".join(s + "\r\n" for s in nmea_gga(cols, t, ok, talker=talker, rmc=nmea_rmc))
        elif suffix == ".kml":
            text = _kml(cols, t, ok)
        else:
            text = _gpx(cols, t, ok)
    with _open_for_writing(p) as fh:
        fh.write(text)
    return p


def _csv_quote(values: Any) -> list[str]:
    """Strings as RFC 4180 fields (quoted only when they hold a comma, quote or line end)."""
    out = []
    for v in values:
        s = "" if v is None or (isinstance(v, float) and np.isnan(v)) else str(v)
        if any(c in s for c in ',"\r\n'):
            s = '"' + s.replace('"', '""') + '"'
        out.append(s)
    return out


def _csv_floats(values: FloatArray, decimals: int | None) -> list[str]:
    """Shortest round-trip text of the values rounded to ``decimals``; NaN as empty field."""
    a = values if decimals is None else np.round(values, decimals)
    out = [repr(v) for v in a.tolist()]
    for i in np.flatnonzero(np.isnan(a)).tolist():
        out[i] = ""
    return out


def _csv_column(name: str, values: np.ndarray) -> list[str]:
    if name == "n_sats":
        return [str(int(v)) if v == v else "" for v in values.tolist()]
    kind = values.dtype.kind
    if kind == "f":
        return _csv_floats(values, _CSV_DECIMALS.get(name))
    if kind in "iub":
        return [str(v) for v in values.tolist()]
    return _csv_quote(values.tolist())


def _csv(cols: dict[str, np.ndarray]) -> str:
    fields = [_csv_column(name, values) for name, values in cols.items()]
    header = ",".join(_csv_quote(list(cols)))
    return header + "\n" + "".join(",".join(row) + "\n" for row in zip(*fields, strict=True))


def _write_parquet(cols: dict[str, np.ndarray], path: Path) -> None:
    try:
        import pyarrow  # noqa: F401  # optional dependency (extra navtrack[parquet])
    except ImportError:
        raise MissingDependencyError("pyarrow", "parquet", "Parquet solution files") from None
    table = _frame(cols)
    if table["status"].dtype == object:
        table["status"] = table["status"].astype(str)
    table["excluded"] = table["excluded"].astype(str)
    try:
        table.to_parquet(path, index=False)
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
    # Bodies joined by NUL, the neutral element of XOR, so that one reduceat covers them all.
    raw = np.frombuffer(("\0".join(bodies) + "\0").encode("ascii"), dtype=np.uint8)
    lengths = np.fromiter((len(b) for b in bodies), dtype=np.int64, count=len(bodies))
    starts = np.concatenate([[0], np.cumsum(lengths[:-1] + 1)])
    sums = np.bitwise_xor.reduceat(raw, starts).astype(np.int64)
    # reduceat gives the byte at a start (a NUL separator here) for an empty body: 0 either way.
    return np.where(lengths > 0, sums, 0)


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
    cols: Mapping[str, np.ndarray],
    t_gps_s: FloatArray,
    ok: BoolArray,
    *,
    talker: str = "GP",
    rmc: bool = False,
) -> list[str]:
    """GGA sentences (with ``$`` and checksum, without line ends) of a solution table, each
    followed by an RMC sentence when ``rmc`` is true.

    RMC carries the UTC date; its status is A (valid) or V (void), speed over ground (knots)
    and course (degrees true) come from ``ve_mps``/``vn_mps`` where the table has them (empty
    otherwise), and the mode indicator (NMEA 2.3) follows the GGA quality: A autonomous,
    D differential, R RTK fixed, F RTK float, N not valid.

    Parameters
    ----------
    cols : mapping of str to ndarray
        As :func:`solution_columns` returns, n rows.
    t_gps_s : ndarray, shape (n,)
        GPS seconds of the rows.
    ok : ndarray of bool, shape (n,)
        Rows with a valid fix; the others get quality 0 and empty position fields.
    talker : str
        Two-letter talker id.
    rmc : bool
        Also write RMC sentences.

    Returns
    -------
    list of str, length n (2 n with RMC)
    """
    n = len(t_gps_s)
    utc_cs = np.round(timescale.gps_to_utc(t_gps_s) * 100.0).astype(np.int64)
    times = _utc_times_of_day(utc_cs)
    if "q" in cols or "quality" in cols:  # RTKLIB's Q, or navtrack's quality column (same codes)
        q = np.asarray(cols["quality"] if "quality" in cols else cols["q"])
        quality = np.array([_RTKLIB_Q_TO_GGA.get(int(v), 0) for v in q], dtype=np.int64)
    else:
        quality = np.ones(n, dtype=np.int64)
    quality = np.where(ok, quality, 0)
    n_sats = _float(cols["n_sats"])
    sats = [f"{v:02.0f}" if v == v else "" for v in n_sats.tolist()]
    dop_col = "hdop" if "hdop" in cols else "pdop"
    dops = [f"{v:.2f}" if v == v else "" for v in _float(cols[dop_col]).tolist()]
    where, alt = _gga_positions(cols, ok)
    sep = ["0.0" if v else "" for v in ok.tolist()]
    qual = quality.tolist()
    bodies = [
        f"{talker}GGA,{t},{w},{qq},{ns},{d},{a},M,{g},M,,"
        for t, w, qq, ns, d, a, g in zip(times, where, qual, sats, dops, alt, sep, strict=True)
    ]
    if rmc:
        days = timescale.GPS_EPOCH.astype("datetime64[D]") + (utc_cs // 8_640_000).astype(
            "timedelta64[D]"
        )
        iso = np.datetime_as_string(days).tolist()  # YYYY-MM-DD
        rmcs = [
            f"{talker}RMC,{t},{'A' if qq else 'V'},{w},{v},{d[8:10]}{d[5:7]}{d[2:4]},,,"
            f"{_GGA_TO_MODE.get(qq, 'N')}"
            for t, w, qq, v, d in zip(times, where, qual, _speed_course(cols, ok), iso, strict=True)
        ]
        bodies = [b for pair in zip(bodies, rmcs, strict=True) for b in pair]
    sums = nmea_checksums(bodies).tolist()
    return [f"${b}*{_HEX[c]}" for b, c in zip(bodies, sums, strict=True)]


def _utc_times_of_day(utc_cs: IntArray) -> list[str]:
    """``hhmmss.ss`` of UTC times in centiseconds since the GPS epoch (1980-01-06 00:00 UTC is
    a midnight, so the time of day is the remainder modulo one day)."""
    tod = utc_cs % 8_640_000
    hh, mm, cs = tod // 360_000, (tod // 6_000) % 60, tod % 6_000
    return [
        f"{h:02d}{m:02d}{c // 100:02d}.{c % 100:02d}"
        for h, m, c in zip(hh.tolist(), mm.tolist(), cs.tolist(), strict=True)
    ]


def _gga_positions(cols: Mapping[str, np.ndarray], ok: BoolArray) -> tuple[list[str], list[str]]:
    """(latitude/longitude fields, altitude field) of every row: formatted for the valid rows
    (in one pass), empty for the others."""
    n = len(ok)
    lat = _float(cols["lat_deg"])
    lon = _float(cols["lon_deg"])
    h = _float(cols["h_m"])
    lat_f = _ddmm(lat[ok], 2, 6)
    lon_f = _ddmm(lon[ok], 3, 6)
    where_ok = [
        f"{a},{'N' if la >= 0.0 else 'S'},{b},{'E' if lo >= 0.0 else 'W'}"
        for a, la, b, lo in zip(lat_f, lat[ok].tolist(), lon_f, lon[ok].tolist(), strict=True)
    ]
    alt_ok = [f"{v:.3f}" for v in h[ok].tolist()]
    where = [",,,"] * n
    alt = [""] * n
    for i, j in enumerate(np.flatnonzero(ok).tolist()):
        where[j] = where_ok[i]
        alt[j] = alt_ok[i]
    return where, alt


def _speed_course(cols: Mapping[str, np.ndarray], ok: BoolArray) -> list[str]:
    """RMC speed over ground (knots) and course (degrees true, clockwise from north) fields of
    the valid rows with an east/north velocity; ``","`` (both empty) elsewhere."""
    n = len(ok)
    if "ve_mps" not in cols or "vn_mps" not in cols:
        return [","] * n
    ve, vn = _float(cols["ve_mps"]), _float(cols["vn_mps"])
    knots = np.hypot(ve, vn) / _KNOT_MPS
    course = np.degrees(np.arctan2(ve, vn)) % 360.0
    have = ok & np.isfinite(knots)
    return [
        f"{k:.3f},{c:.2f}" if h else ","
        for k, c, h in zip(knots.tolist(), course.tolist(), have.tolist(), strict=True)
    ]


# --------------------------------------------------------------------------------------------
# KML and GPX
# --------------------------------------------------------------------------------------------


def _utc_iso(t_gps_s: FloatArray) -> np.ndarray:
    """UTC ISO 8601 strings with milliseconds and ``Z``."""
    utc = timescale.to_datetime64(timescale.gps_to_utc(t_gps_s)).astype("datetime64[ms]")
    return np.char.add(np.datetime_as_string(utc), "Z")


def _kml(cols: Mapping[str, np.ndarray], t_gps_s: FloatArray, ok: BoolArray) -> str:
    lat = _float(cols["lat_deg"])[ok]
    lon = _float(cols["lon_deg"])[ok]
    whens = "".join(f"<when>{w}</when>\n" for w in _utc_iso(t_gps_s[ok]).tolist())
    coords = "".join(
        f"<gx:coord>{b:.9f} {a:.9f} 0</gx:coord>\n"
        for a, b in zip(lat.tolist(), lon.tolist(), strict=True)
    )
    n, n_ok = len(ok), int(ok.sum())
    first = cols["time_gps"][0] if n else ""
    last = cols["time_gps"][-1] if n else ""
    desc = (
        f"navtrack solution, {n} epochs ({first} to {last} GPST), {n_ok} with a valid "
        f"position drawn, {n - n_ok} without a valid position left out"
    )
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<kml xmlns="http://www.opengis.net/kml/2.2" xmlns:gx="http://www.google.com/kml/ext/2.2">\n'
        "<Document>\n"
        "<name>navtrack solution</name>\n"
        f"<description>{desc}</description>\n"
        '<Style id="track"><LineStyle><color>ff0000ff</color><width>2</width></LineStyle>'
        "</Style>\n"
        + (
            ""
            if n_ok == 0
            else "<Placemark>\n<name>track</name>\n<styleUrl>#track</styleUrl>\n"
            "<gx:Track>\n<altitudeMode>clampToGround</altitudeMode>\n"
            f"{whens}{coords}</gx:Track>\n</Placemark>\n"
        )
        + "</Document>\n</kml>\n"
    )


def _gpx(cols: Mapping[str, np.ndarray], t_gps_s: FloatArray, ok: BoolArray) -> str:
    n, n_ok = len(ok), int(ok.sum())
    idx = np.flatnonzero(ok)
    times = _utc_iso(t_gps_s[idx])
    lat = _float(cols["lat_deg"])[idx]
    lon = _float(cols["lon_deg"])[idx]
    h = _float(cols["h_m"])[idx]
    n_sats = _float(cols["n_sats"])[idx]

    def element(name: str, values: FloatArray, fmt: str) -> list[str]:
        return [f"<{name}>{v:{fmt}}</{name}>" if np.isfinite(v) else "" for v in values.tolist()]

    sats = element("sat", n_sats, ".0f")
    dops = [
        element(name, _float(cols[name])[idx], ".2f")
        for name in ("hdop", "vdop", "pdop")
        if name in cols
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
    import pandas as pd  # for the readers only: `navtrack pos` writes without pandas

    p = Path(path)
    suffix = p.suffix.lower()
    if suffix == ".csv":
        try:
            df = pd.read_csv(p, dtype={"excluded": str, "time_gps": str}, keep_default_na=True)
        except (pd.errors.ParserError, UnicodeDecodeError) as exc:
            raise FileFormatError(p, None, f"not a CSV solution table: {exc}") from None
    elif suffix == ".parquet":
        try:
            import pyarrow  # noqa: F401  # optional dependency (extra navtrack[parquet])
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
