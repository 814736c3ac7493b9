"""RINEX clock files (2.x and 3.x, ``.clk`` / ``_CLK.CLK``): satellite clock offsets.

:func:`read_clock` reads the ``AS`` (analysis, satellite) records of a RINEX clock file into a
:class:`RinexClock`: epoch times in GPS seconds, satellite ids, and the clock offset (s) with its
standard deviation as ``(epochs, satellites)`` arrays, NaN where a satellite has no record.
Receiver (``AR``), calibration (``CR``), discontinuity (``DR``) and monitor (``MS``) records are
counted, not kept. :func:`interpolate_clock` gives the offset at any time by linear
interpolation between the two bracketing epochs, the IGS practice for 30 s and 5 s clocks.

Lenient where real files are imperfect (each leniency is a warning in
:attr:`RinexClock.warnings`): a header satellite count (``# OF SOLN SATS``) that disagrees with
the records, satellites written without their ``PRN LIST`` line, a damaged ``AS`` record (skipped,
its line named in :attr:`RinexClock.skipped`), and a last line cut short by the end of the file.

References
----------
Ray, J., Gurtner, W., "RINEX extensions to handle clock information", version 3.00 (2010)
and 3.04 (2017, 9-character station names in the data records), IGS.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from os import fspath

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import FloatArray, StrPath
from navtrack.errors import FileFormatError
from navtrack.gnss.observations import SkippedLine
from navtrack.gnss.rinex._io import read_bytes
from navtrack.timescale import calendar_gps_seconds, to_gps

__all__ = ["RinexClock", "interpolate_clock", "read_clock"]

_RECORD_TYPES = (b"AR", b"AS", b"CR", b"DR", b"MS")
_GPS_EPOCH_UNIX_DAYS = 3657  # 1980-01-06 in days from 1970-01-01


@dataclass(frozen=True, slots=True, eq=False)
class RinexClock:
    """Satellite clocks of one RINEX clock file.

    Attributes
    ----------
    path : str
        Source file.
    version : str
        Format version as written (``3.00``, ``3.04``, ``2.00`` ...).
    agency : str
        Analysis centre (``ANALYSIS CENTER`` line, its 3-letter code).
    time_system : str
        Time system of the epochs as written (``GPS`` unless ``TIME SYSTEM ID`` says otherwise);
        :attr:`t_gps_s` is GPS time.
    interval_s : float
        Epoch interval (s): the header ``INTERVAL`` when present, else the median step.
    t_gps_s : ndarray, shape (K,)
        Epochs holding at least one satellite record, GPS seconds, increasing.
    sats : tuple of str, length S
        Satellite ids (``G01``, ``E11`` ...), sorted.
    clock_s : ndarray, shape (K, S)
        Satellite clock offset (s), NaN where the satellite has no record.
    sd_s : ndarray, shape (K, S)
        Its standard deviation (s) where the record gives one, else NaN.
    record_counts : dict of str to int
        Records of each type (``AS``, ``AR``, ``CR``, ``DR``, ``MS``).
    skipped : tuple of SkippedLine
        Damaged ``AS`` records left out (line and why).
    warnings : tuple of str
        What was read leniently.
    """

    path: str
    version: str
    agency: str
    time_system: str
    interval_s: float
    t_gps_s: FloatArray
    sats: tuple[str, ...]
    clock_s: FloatArray
    sd_s: FloatArray
    record_counts: dict[str, int]
    skipped: tuple[SkippedLine, ...] = ()
    warnings: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        shape = (len(self.t_gps_s), len(self.sats))
        for name in ("clock_s", "sd_s"):
            if getattr(self, name).shape != shape:
                raise ValueError(f"{name}: expected shape {shape}, got {getattr(self, name).shape}")
        freeze_arrays(self)


@dataclass(frozen=True, slots=True)
class _Header:
    version: str
    agency: str
    time_system: str
    interval_s: float
    n_sats: int
    prn_list: tuple[str, ...]
    end_line: int  # 0-based index of the first data line


def read_clock(path: StrPath) -> RinexClock:
    """Read the satellite clocks (``AS`` records) of a RINEX clock file.

    Parameters
    ----------
    path : str or path-like
        RINEX clock file, plain or compressed (gzip, bzip2, ``.Z``).

    Returns
    -------
    RinexClock

    Raises
    ------
    FileFormatError
        Not a RINEX clock file, no ``END OF HEADER``, an unreadable epoch or record type, or no
        ``AS`` record; the message names the file and line.
    """
    lines = read_bytes(path).splitlines()
    head = _header(path, lines)
    counts, records, skipped = _records(path, lines, head.end_line)
    sat_raw, t_cal, values, sds = records
    warnings: list[str] = []
    if skipped:
        warnings.append(
            f"{len(skipped)} damaged AS record(s) skipped (first at line "
            f"{skipped[0].line}: {skipped[0].reason})"
        )
    sats = tuple(sorted(set(sat_raw.tolist())))
    _check_satellites(head, sats, warnings)
    epochs, e_idx = np.unique(t_cal, return_inverse=True)
    s_idx = np.searchsorted(np.array(sats), sat_raw)
    clock = np.full((epochs.size, len(sats)), np.nan)
    sd = np.full_like(clock, np.nan)
    clock[e_idx, s_idx] = values
    sd[e_idx, s_idx] = sds
    try:
        t_gps_s = np.asarray(to_gps(epochs, head.time_system), dtype=float)
    except ValueError:
        raise FileFormatError(path, None, f"unknown time system {head.time_system!r}") from None
    interval = head.interval_s
    if not math.isfinite(interval) and epochs.size > 1:
        interval = float(np.median(np.diff(epochs)))
    return RinexClock(
        path=fspath(path),
        version=head.version,
        agency=head.agency,
        time_system=head.time_system,
        interval_s=interval,
        t_gps_s=t_gps_s,
        sats=sats,
        clock_s=clock,
        sd_s=sd,
        record_counts=counts,
        skipped=tuple(skipped),
        warnings=tuple(warnings),
    )


_Records = tuple[np.ndarray, FloatArray, FloatArray, FloatArray]  # sat, calendar s, clock, sd


def _records(
    path: StrPath, lines: list[bytes], start: int
) -> tuple[dict[str, int], _Records, list[SkippedLine]]:
    """Record counts per type, the AS records as arrays, and the damaged AS records skipped.

    The AS records are converted together (:func:`_convert`); a file with a damaged one is
    read line by line to name it (:func:`_satellite_record`).
    """
    counts = {t.decode(): 0 for t in _RECORD_TYPES}
    as_lines = []
    for k in range(start, len(lines)):
        kind = lines[k][:2]
        if kind == b"AS":
            as_lines.append(k)
        elif kind in _RECORD_TYPES:
            counts[kind.decode()] += 1
        elif kind.strip() and not kind[:1].isspace():
            text = lines[k][:20].decode("ascii", "replace")
            raise FileFormatError(path, k + 1, f"unknown record type {text!r}")
    counts["AS"] = len(as_lines)
    if not as_lines:
        raise FileFormatError(path, len(lines), "no satellite clock records (AS)")
    fast = _convert([lines[k] for k in as_lines])
    if fast is not None:
        return counts, fast, []
    rows: list[tuple[str, float, float, float]] = []
    skipped: list[SkippedLine] = []
    for k in as_lines:
        rec = _satellite_record(path, k + 1, lines[k], k == len(lines) - 1)
        if isinstance(rec, SkippedLine):
            skipped.append(rec)
        else:
            rows.append(rec)
    if not rows:
        raise FileFormatError(path, len(lines), "no readable satellite clock records (AS)")
    sat, t, clk, sd = zip(*rows, strict=True)
    return counts, (np.array(sat), np.array(t), np.array(clk), np.array(sd)), skipped


def _convert(as_lines: list[bytes]) -> _Records | None:
    """All AS records converted at once, or None if any is damaged."""
    tokens = [ln.split(None, 10) for ln in as_lines]
    if min(len(t) for t in tokens) < 10:
        return None
    try:
        fields = np.array([t[:10] for t in tokens], dtype="S24")
        date = fields[:, 2:7].astype(np.int64)
        sec = fields[:, 7].astype(float)
        n_values = fields[:, 8].astype(np.int64)
        clock = fields[:, 9].astype(float)
        raw_ids, sat_idx = np.unique(fields[:, 1], return_inverse=True)
        ids = np.array([_sat_id(r.decode("ascii")) for r in raw_ids])
        sd = np.array(
            [
                float(t[10].split()[0]) if len(t) > 10 and n > 1 else np.nan
                for t, n in zip(tokens, n_values, strict=True)
            ]
        )
    except (ValueError, IndexError, UnicodeDecodeError):
        return None
    month = (date[:, 0] - 1970).astype("datetime64[Y]").astype("datetime64[M]") + (date[:, 1] - 1)
    day = month.astype("datetime64[D]") + (date[:, 2] - 1)
    days = day.astype(np.int64) - _GPS_EPOCH_UNIX_DAYS
    t_cal = days * 86400.0 + date[:, 3] * 3600.0 + date[:, 4] * 60.0 + sec
    return ids[sat_idx.ravel()], t_cal, clock, sd


def _header(path: StrPath, lines: list[bytes]) -> _Header:
    """Fields of the header lines (label in columns 61-80)."""
    first = lines[0].decode("ascii", "replace")
    if first[60:80].strip() != "RINEX VERSION / TYPE" or first[20:21] != "C":
        raise FileFormatError(
            path, 1, "not a RINEX clock file (line 1 is not a type C 'RINEX VERSION / TYPE' line)"
        )
    version = first[:9].strip()
    agency, time_system = "", "GPS"
    interval, n_sats = math.nan, -1
    prn: list[str] = []
    for k, raw in enumerate(lines):
        line = raw.decode("ascii", "replace")
        label = line[60:80].strip()
        if label == "END OF HEADER":
            return _Header(version, agency, time_system, interval, n_sats, tuple(prn), k + 1)
        if label == "ANALYSIS CENTER":
            agency = line[:3].strip()
        elif label == "TIME SYSTEM ID":
            time_system = line[:60].strip() or "GPS"
        elif label == "INTERVAL":
            interval = _number(path, k + 1, line[:10], "interval")
        elif label == "# OF SOLN SATS":
            n_sats = int(_number(path, k + 1, line[:6], "number of satellites"))
        elif label == "PRN LIST":
            prn.extend(_sat_id(s) for s in line[:60].split())
    raise FileFormatError(path, len(lines), "no END OF HEADER line")


def _satellite_record(
    path: StrPath, lineno: int, line: bytes, last: bool
) -> tuple[str, float, float, float] | SkippedLine:
    """``(sat, calendar GPS s, clock s, sd s)`` of an AS record, or why it was skipped.

    Fields are read by tokens, not columns: the name is 4 characters wide in 3.00 and up to 9
    in 3.04, and neither holds blanks.
    """
    parts = line.split()
    try:
        sat = _sat_id(parts[1].decode("ascii"))
        y, mo, d, h, mi = (int(p) for p in parts[2:7])
        sec = float(parts[7])
        n_values = int(parts[8])
        clock = float(parts[9])
    except (ValueError, IndexError, UnicodeDecodeError):
        if last:
            return SkippedLine(lineno, "last line cut short by the end of the file")
        try:
            int(parts[2])
        except (ValueError, IndexError):
            return SkippedLine(lineno, "unreadable satellite record")
        text = line[:40].decode("ascii", "replace").rstrip()
        raise FileFormatError(path, lineno, f"unreadable AS record {text!r}") from None
    sd = float(parts[10]) if n_values >= 2 and len(parts) > 10 else math.nan
    return sat, calendar_gps_seconds(y, mo, d, h, mi, sec), clock, sd


def _check_satellites(head: _Header, sats: tuple[str, ...], warnings: list[str]) -> None:
    if head.n_sats >= 0 and head.n_sats != len(sats):
        warnings.append(
            f"header announces {head.n_sats} satellites (# OF SOLN SATS), the records hold "
            f"{len(sats)}; read as found"
        )
    unlisted = sorted(set(sats) - set(head.prn_list)) if head.prn_list else []
    if unlisted:
        warnings.append(f"satellites with records but not in the PRN LIST: {', '.join(unlisted)}")


def _sat_id(text: str) -> str:
    s = text.strip()
    if s[:1].isdigit():  # RINEX clock 2.00: no system letter means GPS
        return f"G{int(s):02d}"
    return f"{s[0]}{int(s[1:]):02d}"


def _number(path: StrPath, lineno: int, text: str, what: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise FileFormatError(path, lineno, f"unreadable {what} {text.strip()!r}") from None


def interpolate_clock(
    clock: RinexClock, sat: str, t_gps_s: FloatArray, *, max_span_s: float | None = None
) -> FloatArray:
    """Clock offset (s) of one satellite at ``t_gps_s`` by linear interpolation.

    Parameters
    ----------
    clock : RinexClock
    sat : str
        Satellite id; all NaN when the file has none for it.
    t_gps_s : ndarray
        Times (GPS s).
    max_span_s : float, optional
        Longest span between the two records interpolated across (default four nominal
        intervals: a few missing records are bridged, a gap of minutes is not).

    Returns
    -------
    ndarray
        Same shape as ``t_gps_s``; NaN outside the file, where a bracketing record is missing,
        or across a longer gap.
    """
    t = np.asarray(t_gps_s, dtype=float)
    out = np.full(t.shape, np.nan)
    if sat not in clock.sats:
        return out
    col = clock.clock_s[:, clock.sats.index(sat)]
    ok = np.isfinite(col)
    tn, cn = clock.t_gps_s[ok], col[ok]
    if tn.size == 0:
        return out
    span = 4.0 * clock.interval_s if max_span_s is None else max_span_s
    i1 = np.clip(np.searchsorted(tn, t, side="right"), 1, max(tn.size - 1, 1))
    i0 = i1 - 1
    if tn.size == 1:
        return np.where(np.abs(t - tn[0]) < 1e-6, cn[0], np.nan)
    t0, t1 = tn[i0], tn[i1]
    w = (t - t0) / (t1 - t0)
    inside = (w >= -1e-9) & (w <= 1.0 + 1e-9) & (t1 - t0 <= span + 1e-6)
    return np.where(inside, cn[i0] + w * (cn[i1] - cn[i0]), np.nan)
