"""Reader and writer of RTKLIB solution files (``.pos``).

RTKLIB's post-processors (``rnx2rtkp``, RTKPOST) and RTKNAVI write one solution per line after a
header of ``%`` comment lines. The last header line names the columns; the layout depends on the
output options:

* time: ``YYYY/MM/DD HH:MM:SS.SSS`` or ``WEEK TOW`` (two fields either way), in GPST, UTC or JST
  as the first column label says;
* position: ECEF ``x-ecef(m) y-ecef(m) z-ecef(m)``, geodetic ``latitude(deg) longitude(deg)
  height(m)`` (or ``latitude(d'")`` with degrees, minutes and seconds as three fields), or a local
  ``e-baseline(m) n-baseline(m) u-baseline(m)`` relative to the header's ``ref pos``;
* then ``Q`` (quality: 1 fix, 2 float, 3 SBAS, 4 DGPS, 5 single, 6 PPP), ``ns`` (satellites used),
  standard deviations ``sdx sdy sdz`` and the signed square roots of the covariances
  ``sdxy sdyz sdzx`` (or ``sdn sde sdu sdne sdeu sdun``), ``age(s)`` (age of differential),
  ``ratio`` (ambiguity validation ratio) and optional velocity columns.

The reader follows the column header, so every combination of these options reads without
configuration. :func:`format_pos` writes RTKLIB's default ECEF layout. Both were written from the
solution format as the RTKLIB manual's file-format appendix describes it and from the files in
``shared/data/gnss``; no RTKLIB code was used.

References
----------
T. Takasu, *RTKLIB ver. 2.4.2 Manual*, 2013, appendix B (solution file format).
"""

from __future__ import annotations

import csv
import io
import re
from collections.abc import Mapping, Sequence
from os import fspath
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from navtrack import geodesy, timescale
from navtrack._record import Record
from navtrack._typing import BoolArray, FloatArray, StrPath
from navtrack.errors import FileFormatError

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["format_pos", "read_pos", "to_solution_frame"]

# Column labels of RTKLIB solution files -> navtrack names (docs/vocabulary.md).
_KNOWN = {
    "x-ecef(m)": "x_m",
    "y-ecef(m)": "y_m",
    "z-ecef(m)": "z_m",
    "latitude(deg)": "lat_deg",
    "longitude(deg)": "lon_deg",
    "latitude(d'\")": "lat_deg",
    "longitude(d'\")": "lon_deg",
    "height(m)": "h_m",
    "e-baseline(m)": "e_m",
    "n-baseline(m)": "n_m",
    "u-baseline(m)": "u_m",
    "q": "q",
    "ns": "ns",
    "age(s)": "age_s",
    "ratio": "ratio",
}
_UNITS = {"(m)": "_m", "(s)": "_s", "(m/s)": "_mps", "(m/s^2)": "_mps2", "(deg)": "_deg"}
_TIME_LABELS = ("GPST", "UTC", "JST")
_INT_COLUMNS = ("q", "ns")
_JST_MINUS_UTC_S = 9 * 3600.0


def _column_name(label: str) -> str:
    """navtrack name of one RTKLIB column label (``sdx(m)`` -> ``sdx_m``)."""
    low = label.lower()
    if low in _KNOWN:
        return _KNOWN[low]
    for unit, suffix in _UNITS.items():
        if low.endswith(unit):
            return re.sub(r"\W+", "_", low[: -len(unit)]).strip("_") + suffix
    return re.sub(r"\W+", "_", low).strip("_")


def _parse_column_header(path: StrPath, lineno: int, line: str) -> tuple[str, list[str]]:
    """Time scale and column labels of the header line ``%  GPST  x-ecef(m) ...``."""
    labels = line.lstrip("%").split()
    scale = labels[0]
    cols = labels[1:]
    if not cols:
        raise FileFormatError(path, lineno, "column header names no columns after the time")
    names = [_column_name(c) for c in cols]
    seen: set[str] = set()
    for name in names:
        if name in seen:
            raise FileFormatError(path, lineno, f"column {name!r} appears twice in the header")
        seen.add(name)
    return scale, cols


class _Fields:
    """The whitespace-separated fields of the solution lines, split by pandas' C parser.

    Columns come out as float64 or str arrays; when a field does not parse, the offending line
    is found (only then) and reported with its number.
    """

    def __init__(
        self,
        path: StrPath,
        lines: list[str],
        linenos: list[int],
        n_tokens: int,
        header_no: int,
        str_cols: Sequence[int],
    ) -> None:
        import pandas as pd  # for the readers only: `navtrack pos` writes without pandas

        self.path, self.lines, self.linenos = path, lines, linenos
        self.n_tokens, self.header_no = n_tokens, header_no
        self.n = len(lines)
        if not lines:
            self.frame = pd.DataFrame({k: np.zeros(0, dtype=object) for k in range(n_tokens)})
            return
        try:
            self.frame = pd.read_csv(
                io.StringIO("\n".join(lines)),
                sep=r"\s+",
                header=None,
                names=list(range(n_tokens)),
                dtype=dict.fromkeys(str_cols, str),
                quoting=csv.QUOTE_NONE,
                skip_blank_lines=False,
                na_filter=False,
                engine="c",
            )
        except pd.errors.ParserError as exc:
            m = re.search(r"line (\d+), saw (\d+)", str(exc))
            if m is None:
                raise FileFormatError(path, None, f"unreadable solution lines: {exc}") from None
            raise self._count_error(int(m.group(1)) - 1) from None
        # Short lines are padded with empty fields; find the first.
        last = self.frame[n_tokens - 1]
        if last.dtype.kind not in "fi":
            short = np.flatnonzero(last.to_numpy(dtype=str) == "")
            if short.size:
                raise self._count_error(int(short[0]))

    def _count_error(self, row: int) -> FileFormatError:
        found = len(self.lines[row].split())
        return FileFormatError(
            self.path,
            self.linenos[row],
            f"expected {self.n_tokens} fields as the column header on line {self.header_no} "
            f"says, found {found}",
        )

    def strings(self, col: int) -> np.ndarray:
        """Field ``col`` of every line as a str array."""
        return np.asarray(self.frame[col].to_numpy(dtype=str), dtype=str)

    def floats(self, col: int, what: str) -> FloatArray:
        """Field ``col`` of every line as float64; FileFormatError naming the first bad line."""
        column = self.frame[col]
        if column.dtype.kind in "fi":
            return np.asarray(column.to_numpy(dtype=float), dtype=float)
        for row, token in enumerate(column.to_numpy(dtype=str).tolist()):
            try:
                float(token)
            except ValueError:
                raise FileFormatError(
                    self.path, self.linenos[row], f"{what}: cannot read {token!r}"
                ) from None
        return np.asarray(column.to_numpy(dtype=str).astype(float), dtype=float)


def read_pos(path: StrPath) -> pd.DataFrame:
    """Read an RTKLIB solution file.

    Parameters
    ----------
    path : str or path-like
        RTKLIB ``.pos`` file (any time format, any position format, with or without velocities).

    Returns
    -------
    pandas.DataFrame
        One row per solution line, columns:

        ``t_gps_s``
            GPS seconds (UTC and JST time tags are converted to GPST).
        ``x_m``, ``y_m``, ``z_m``
            ECEF position (m); converted from geodetic coordinates (ellipsoidal heights) or from
            the ENU baseline plus the header's ``ref pos`` when the file is written that way.
        ``lat_deg``, ``lon_deg``, ``h_m``
            WGS-84 geodetic position (degrees, ellipsoidal height in m).
        ``q`` (int), ``ns`` (int), then every further column of the file in file order, named
        as ``docs/vocabulary.md`` says: ``sdx_m`` ... ``sdzx_m`` (or ``sdn_m`` ... ``sdun_m``),
        ``age_s``, ``ratio``, velocities ``vx_mps`` ... . RTKLIB writes the cross terms as signed
        square roots of the covariances, ``sign(c) * sqrt(|c|)``; they are kept as written.

        ``DataFrame.attrs`` holds ``"header"`` (the ``%`` lines, without ``%``), ``"time_scale"``
        (``"GPST"``, ``"UTC"`` or ``"JST"``) and ``"ref_xyz_m"`` (the header's reference position
        in ECEF, or None).

    Raises
    ------
    FileFormatError
        No column header before the first solution line, a line with the wrong number of fields,
        or a field that is not a number or a time; the message names the file and line.
        Geodetic files written with geoid ("geodetic") heights are refused: converting them to
        ECEF needs the geoid model RTKLIB used.

    References
    ----------
    T. Takasu, *RTKLIB ver. 2.4.2 Manual*, 2013, appendix B (solution file format).
    """
    import pandas as pd  # for the readers only: `navtrack pos` writes without pandas

    p = Path(path)
    text = _solution_text(p)
    fields = _Fields(
        p, text.lines, text.linenos, text.n_tokens, text.header_lineno, text.str_cols()
    )
    t_gps_s = _parse_times(fields, text.scale)
    data = _column_values(fields, text.columns)
    header = text.header
    ref_xyz = _header_ref_xyz(header)
    xyz, llh = _positions(p, data, header, ref_xyz)
    front = {
        "t_gps_s": t_gps_s,
        "x_m": xyz[:, 0],
        "y_m": xyz[:, 1],
        "z_m": xyz[:, 2],
        "lat_deg": np.degrees(llh[:, 0]),
        "lon_deg": np.degrees(llh[:, 1]),
        "h_m": llh[:, 2],
    }
    rest = {key: val for key, val in data.items() if key not in front}
    df = pd.DataFrame({**front, **rest})
    df.attrs["header"] = header
    df.attrs["time_scale"] = text.scale
    df.attrs["ref_xyz_m"] = None if ref_xyz is None else tuple(float(v) for v in ref_xyz)
    return df


class _SolutionText(Record):
    """The lines of a ``.pos`` file: its header, the column header and the solution lines."""

    header: list[str]
    columns: list[str]
    scale: str
    header_lineno: int
    lines: list[str]
    linenos: list[int]
    n_tokens: int

    def str_cols(self) -> list[int]:
        """Fields kept as text: the two time fields and the degrees of d m s angles ("-0"
        keeps its sign)."""
        str_cols = [0, 1]
        k = 2
        for label in self.columns:
            if label.endswith("(d'\")"):
                str_cols.append(k)
                k += 3
            else:
                k += 1
        return str_cols


def _solution_text(p: Path) -> _SolutionText:
    """Split ``p`` into header lines and solution lines (FileFormatError: no column header, or
    a solution line before it)."""
    try:
        text = p.read_text(encoding="ascii", errors="replace")
    except OSError as exc:
        raise OSError(
            exc.errno, f"cannot read RTKLIB solution file: {exc.strerror}", fspath(p)
        ) from exc
    header: list[str] = []
    columns: list[str] | None = None
    scale = "GPST"
    header_lineno = 0
    lines: list[str] = []
    linenos: list[int] = []
    n_tokens = 0
    for lineno, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped:
            continue
        if stripped[0] == "%":
            body = stripped[1:].strip()
            header.append(body)
            first = body.split(maxsplit=1)[0] if body else ""
            if first in _TIME_LABELS and not lines:
                scale, columns = _parse_column_header(p, lineno, stripped)
                header_lineno = lineno
                # Two time fields; latitude/longitude in d m s take three fields each.
                n_tokens = 2 + len(columns) + 2 * sum(c.endswith("(d'\")") for c in columns)
            continue
        if columns is None:
            raise FileFormatError(
                p, lineno, "solution line before the column header ('%  GPST  ...')"
            )
        lines.append(stripped)
        linenos.append(lineno)
    if columns is None:
        raise FileFormatError(p, None, "no column header ('%  GPST  ...') found")
    return _SolutionText(header, columns, scale, header_lineno, lines, linenos, n_tokens)


def _column_values(fields: _Fields, columns: list[str]) -> dict[str, np.ndarray]:
    """The values of every column after the time, by vocabulary name (d m s angles in degrees,
    ``q`` and ``ns`` as integers)."""
    data: dict[str, np.ndarray] = {}
    k = 2
    for label in columns:
        name = _column_name(label)
        if label.endswith("(d'\")"):
            data[name] = _parse_dms(fields, k)
            k += 3
            continue
        values = fields.floats(k, f"column {label}")
        if name in _INT_COLUMNS:
            if not np.all(values == np.round(values)):
                bad = int(np.flatnonzero(values != np.round(values))[0])
                raise FileFormatError(
                    fields.path, fields.linenos[bad], f"column {label}: not an integer"
                )
            data[name] = values.astype(np.int64)
        else:
            data[name] = values
        k += 1
    return data


def _parse_times(fields: _Fields, scale: str) -> FloatArray:
    """GPS seconds of the two time fields (calendar or week/tow) of every line."""
    if fields.n == 0:
        return np.zeros(0)
    date, clock = fields.strings(0), fields.strings(1)
    if "/" in date[0]:
        iso = np.strings.add(np.strings.add(np.strings.replace(date, "/", "-"), "T"), clock)
        try:
            t = timescale.gps_seconds(iso.astype("datetime64[ns]"))
        except ValueError:
            for row, value in enumerate(iso.tolist()):
                try:
                    np.datetime64(value, "ns")
                except ValueError:
                    raise FileFormatError(
                        fields.path, fields.linenos[row], f"time: cannot read {value!r}"
                    ) from None
            raise FileFormatError(fields.path, None, "time: unreadable value") from None
        bad = np.flatnonzero(np.strings.find(date, "/") < 0)
        if bad.size:
            raise FileFormatError(
                fields.path, fields.linenos[bad[0]], "time: mixed calendar and week/tow"
            )
    else:
        week = fields.floats(0, "GPS week")
        tow = fields.floats(1, "time of week")
        bad = np.flatnonzero((week != np.round(week)) | (tow < 0) | (tow >= 604800.0))
        if bad.size:
            raise FileFormatError(
                fields.path,
                fields.linenos[bad[0]],
                "week/tow: week not integer or tow outside [0, 604800) s",
            )
        t = timescale.from_week_tow(week, tow)
    if scale == "UTC":
        t = timescale.utc_to_gps(t)
    elif scale == "JST":
        t = timescale.utc_to_gps(t - _JST_MINUS_UTC_S)
    return np.asarray(t, dtype=float)


def _parse_dms(fields: _Fields, k: int) -> FloatArray:
    """Signed degrees of ``deg min sec`` fields ``k, k+1, k+2`` (the sign sits on the degrees
    field, so that -0 30 00 is -0.5 deg)."""
    deg = fields.floats(k, "angle degrees")
    minutes = fields.floats(k + 1, "angle minutes")
    sec = fields.floats(k + 2, "angle seconds")
    negative = np.strings.startswith(fields.strings(k), "-")
    sign = np.where(negative, -1.0, 1.0)
    return np.asarray(sign * (np.abs(deg) + minutes / 60.0 + sec / 3600.0), dtype=float)


def _header_ref_xyz(header: list[str]) -> FloatArray | None:
    """ECEF reference position of the ``ref pos :`` header line, if any.

    RTKLIB writes it as ECEF metres for ECEF/ENU output and as latitude/longitude (deg)/height
    for geodetic output; the two are told apart by magnitude (an ECEF coordinate triple has a
    norm near the earth radius, a latitude/longitude/height triple cannot).
    """
    for line in header:
        if line.lower().startswith("ref pos"):
            _, _, value = line.partition(":")
            try:
                v = np.array([float(s) for s in value.split()[:3]])
            except ValueError:
                return None
            if v.size != 3:
                return None
            if np.linalg.norm(v) > 1e6:
                return v
            return geodesy.geodetic_to_ecef([np.radians(v[0]), np.radians(v[1]), v[2]])
    return None


def _positions(
    path: StrPath, data: dict[str, np.ndarray], header: list[str], ref_xyz: FloatArray | None
) -> tuple[FloatArray, FloatArray]:
    """ECEF and geodetic (rad, rad, m) positions from whichever columns the file has."""
    if {"x_m", "y_m", "z_m"} <= data.keys():
        xyz = np.stack([data["x_m"], data["y_m"], data["z_m"]], axis=-1)
        return xyz, geodesy.ecef_to_geodetic(xyz)
    if {"lat_deg", "lon_deg", "h_m"} <= data.keys():
        if any("geodetic" in line.lower() and "height" in line.lower() for line in header):
            raise FileFormatError(
                path,
                None,
                "heights are geodetic (above the geoid); ECEF needs ellipsoidal "
                "heights (RTKLIB option out-height=ellipsoidal)",
            )
        llh = np.stack(
            [np.radians(data["lat_deg"]), np.radians(data["lon_deg"]), data["h_m"]], axis=-1
        )
        return geodesy.geodetic_to_ecef(llh), llh
    if {"e_m", "n_m", "u_m"} <= data.keys():
        if ref_xyz is None:
            raise FileFormatError(path, None, "ENU baseline output without a 'ref pos' header")
        ref_llh = geodesy.ecef_to_geodetic(ref_xyz)
        rot = geodesy.enu_rotation(ref_llh[0], ref_llh[1])
        enu = np.stack([data["e_m"], data["n_m"], data["u_m"]], axis=-1)
        xyz = ref_xyz + enu @ rot
        return xyz, geodesy.ecef_to_geodetic(xyz)
    raise FileFormatError(path, None, "no position columns (x-ecef, latitude or e-baseline)")


def to_solution_frame(pos: pd.DataFrame) -> pd.DataFrame:
    """A navtrack solution table (see :func:`navtrack.io.solution.write_solution`) of a
    :func:`read_pos` frame.

    ``status`` is ``"ok"`` where RTKLIB's ``Q`` is 1-6 and ``"no_solution"`` otherwise;
    ``n_sats`` = ``ns``; ``sd_e_m``, ``sd_n_m``, ``sd_u_m`` come from the full ECEF covariance
    (rebuilt from RTKLIB's signed square roots) rotated to the local frame at each position,
    or directly from ``sdn``/``sde``/``sdu`` for geodetic output. ``q`` is kept (the NMEA writer
    maps it to the GGA fix quality). RTKLIB does not write the receiver clock or DOPs:
    ``clock_m`` and ``pdop`` are NaN.

    Parameters
    ----------
    pos : pandas.DataFrame
        As returned by :func:`read_pos`.

    Returns
    -------
    pandas.DataFrame
    """
    import pandas as pd  # for the readers only: `navtrack pos` writes without pandas

    n = len(pos)
    out = pd.DataFrame(
        {
            "t_gps_s": pos["t_gps_s"].to_numpy(float),
            "x_m": pos["x_m"].to_numpy(float),
            "y_m": pos["y_m"].to_numpy(float),
            "z_m": pos["z_m"].to_numpy(float),
            "clock_m": np.full(n, np.nan),
        }
    )
    if {"sdx_m", "sdy_m", "sdz_m", "sdxy_m", "sdyz_m", "sdzx_m"} <= set(pos.columns):
        cov = _cov_from_signed_sqrt(
            pos[["sdx_m", "sdy_m", "sdz_m", "sdxy_m", "sdyz_m", "sdzx_m"]].to_numpy(float)
        )
        llh = np.radians(pos[["lat_deg", "lon_deg"]].to_numpy(float))
        rot = geodesy.enu_rotation(llh[:, 0], llh[:, 1])
        cov_enu = rot @ cov @ np.swapaxes(rot, -1, -2)
        sd = np.sqrt(np.clip(np.diagonal(cov_enu, axis1=-2, axis2=-1), 0.0, None))
    elif {"sde_m", "sdn_m", "sdu_m"} <= set(pos.columns):
        sd = pos[["sde_m", "sdn_m", "sdu_m"]].to_numpy(float)
    else:
        sd = np.full((n, 3), np.nan)
    out["sd_e_m"], out["sd_n_m"], out["sd_u_m"] = sd[:, 0], sd[:, 1], sd[:, 2]
    out["n_sats"] = pos["ns"].to_numpy(np.int64) if "ns" in pos else np.zeros(n, np.int64)
    out["pdop"] = np.full(n, np.nan)
    q = pos["q"].to_numpy(np.int64) if "q" in pos else np.full(n, 5, np.int64)
    out["status"] = np.where((q >= 1) & (q <= 6), "ok", "no_solution")
    out["excluded"] = ""
    out["q"] = q
    return out


def _cov_from_signed_sqrt(sd: FloatArray) -> FloatArray:
    """ECEF covariances ``(n, 3, 3)`` from RTKLIB's ``sdx sdy sdz sdxy sdyz sdzx`` (m)."""
    var = sd[:, :3] ** 2
    cross = np.sign(sd[:, 3:]) * sd[:, 3:] ** 2  # xy, yz, zx
    cov = np.empty((sd.shape[0], 3, 3))
    cov[:, 0, 0], cov[:, 1, 1], cov[:, 2, 2] = var[:, 0], var[:, 1], var[:, 2]
    cov[:, 0, 1] = cov[:, 1, 0] = cross[:, 0]
    cov[:, 1, 2] = cov[:, 2, 1] = cross[:, 1]
    cov[:, 2, 0] = cov[:, 0, 2] = cross[:, 2]
    return cov


# The legend and column header rnx2rtkp writes above ECEF solutions (solution format xyz).
_XYZ_LEGEND = "(x/y/z-ecef=WGS84,Q=1:fix,2:float,3:sbas,4:dgps,5:single,6:ppp,ns=# of satellites)"
_XYZ_COLUMNS = (
    "  GPST                      x-ecef(m)      y-ecef(m)      z-ecef(m)   Q  ns   sdx(m)   sdy(m)"
    "   sdz(m)  sdxy(m)  sdyz(m)  sdzx(m) age(s)  ratio"
)
_SD_COLUMNS = ("sdx_m", "sdy_m", "sdz_m", "sdxy_m", "sdyz_m", "sdzx_m")
# RTKLIB's solution quality of a single point solution.
_Q_SINGLE = 5


def format_pos(
    cols: Mapping[str, np.ndarray], t_gps_s: FloatArray, ok: BoolArray, header: Sequence[str] = ()
) -> str:
    """The text of an RTKLIB solution file (ECEF, GPST, ``hms`` time, 3 decimals) of the valid
    rows of a solution table, as ``rnx2rtkp`` writes it with ``out-solformat=xyz``.

    Parameters
    ----------
    cols : mapping of str to ndarray
        As :func:`navtrack.io.solution.solution_columns` returns, n rows: ``x_m``, ``y_m``,
        ``z_m``, ``n_sats``, and when present ``q`` or ``quality`` (RTKLIB's Q; 5, single,
        otherwise), ``clock_m`` (receiver clock offset times c), ``sdx_m`` ... ``sdzx_m``
        (RTKLIB's signed square roots of the ECEF covariance; 0 otherwise), ``age_s`` and
        ``ratio``.
    t_gps_s : ndarray, shape (n,)
        Receiver time tags (GPS s). Like RTKLIB, the file gives the GPS time of the solution:
        the time tag minus the estimated receiver clock offset ``clock_m / c``, rounded to the
        millisecond.
    ok : ndarray of bool, shape (n,)
        Rows with a solution; the others are left out, as RTKLIB leaves them out.
    header : sequence of str
        Header lines above the legend (written after ``% ``), e.g. the input files and options.

    Returns
    -------
    str
        The file's text; :func:`read_pos` reads it back.

    References
    ----------
    T. Takasu, *RTKLIB ver. 2.4.2 Manual*, 2013, appendix B (solution file format).
    """
    idx = np.flatnonzero(ok)
    n = len(ok)

    def column(name: str, default: float) -> FloatArray:
        values = np.asarray(cols[name], dtype=float) if name in cols else np.full(n, default)
        return np.where(np.isfinite(values), values, default)[idx]

    q_name = "quality" if "quality" in cols else "q"
    q = column(q_name, _Q_SINGLE).astype(np.int64)
    ns = column("n_sats", 0.0).astype(np.int64)
    xyz = np.stack([column(c, np.nan) for c in ("x_m", "y_m", "z_m")], axis=-1)
    sd = np.stack([column(c, 0.0) for c in _SD_COLUMNS], axis=-1)
    age = column("age_s", 0.0)
    ratio = column("ratio", 0.0)
    t_sol = np.round(t_gps_s[idx] - column("clock_m", 0.0) / geodesy.C_MPS, 3)
    iso = np.datetime_as_string(timescale.to_datetime64(t_sol), unit="ms")
    times = np.strings.replace(np.strings.replace(iso, "-", "/"), "T", " ")
    lines = [f"% {h}".rstrip() for h in header]
    lines += ["%", f"% {_XYZ_LEGEND}", f"%{_XYZ_COLUMNS}"]
    for i in range(idx.size):
        s = sd[i]
        lines.append(
            f"{times[i]} {xyz[i, 0]:14.4f} {xyz[i, 1]:14.4f} {xyz[i, 2]:14.4f} {q[i]:3d}"
            f" {ns[i]:3d} {s[0]:8.4f} {s[1]:8.4f} {s[2]:8.4f} {s[3]:8.4f} {s[4]:8.4f}"
            f" {s[5]:8.4f} {age[i]:6.2f} {ratio[i]:6.1f}"
        )
    return "\n".join(lines) + "\n"
