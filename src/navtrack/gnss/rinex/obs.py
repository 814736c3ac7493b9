"""RINEX 2.10/2.11 and 3.0x (4.0x) observation files -> :class:`Observations`.

Design (for speed): Python walks over the *epoch records only*; the data lines of all epochs are
gathered into one fixed-width byte matrix and every ``F14.3,I1,I1`` field (value, LLI, signal
strength) is decoded at once by vectorised digit arithmetic. A value written in the standard
layout (decimal point in column 11 of the field, three decimals) is read as an integer number of
thousandths and divided by 1000: both are exact binary numbers and IEEE division is correctly
rounded, so the result equals Python's ``float(text)``. Fields in any other layout fall back to
``float()``; fields that are not numbers raise :class:`~navtrack.errors.FileFormatError` (or are
skipped and recorded with ``lenient=True``).

References
----------
RINEX 2.11 (Gurtner & Estey, IGS/RTCM-SC104, 2007), sections 5, 7 and tables A1-A3;
RINEX 3.05 (IGS/RTCM-SC104, 2020), sections 5.1-5.3, 6.1 and tables A1-A3;
RINEX 4.00 (IGS/RTCM-SC104, 2021), observation tables (same data section as 3.05).
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Collection
from dataclasses import dataclass, field, replace
from os import fspath

import numpy as np

from navtrack._typing import FloatArray, Int8Array, StrPath
from navtrack.errors import FileFormatError
from navtrack.gnss.observations import (
    SYSTEMS,
    Event,
    Observations,
    ObsHeader,
    SkippedLine,
)
from navtrack.gnss.rinex._io import ends_inside_field, read_bytes, sniff
from navtrack.timescale import calendar_gps_seconds, to_gps

__all__ = ["read_obs"]

_NAN = float("nan")
_FIELD = 16  # F14.3 value + LLI + SSI

# Time system of the epochs when TIME OF FIRST OBS leaves it blank (RINEX 3.05 table A2).
_DEFAULT_TIME_SYSTEM = {
    "G": "GPS", "M": "GPS", "S": "GPS", "R": "GLO", "E": "GAL", "C": "BDT", "J": "QZS", "I": "IRN",
}  # fmt: skip
_KNOWN_TIME_SYSTEMS = {"GPS", "GLO", "GAL", "BDT", "QZS", "IRN", "UTC", "TAI"}

# A RINEX 2 epoch record: (1X,I2.2,4(1X,I2),F11.7,2X,I1,I3,...). The time may be blank for
# event records (flags 2-5).
_V2_EPOCH = re.compile(rb" [ \d]\d [ \d]\d [ \d]\d [ \d]\d [ \d]\d[ \d.]{11}  [0-6][ \d]{2}\d")
_V2_EVENT_NO_TIME = re.compile(rb" {26}  [2-5][ \d]{2}\d")


@dataclass(slots=True)
class _Segment:
    """Observation types in force for a stretch of epochs (header records may change them)."""

    obs_types: dict[str, tuple[str, ...]]
    scale: dict[tuple[str, str], float] = field(default_factory=dict)


@dataclass(slots=True)
class _Scan:
    """What the epoch walk found: epochs, where their data lines are, events, skipped lines."""

    t_cal_s: list[float] = field(default_factory=list)
    flag: list[int] = field(default_factory=list)
    clock_s: list[float] = field(default_factory=list)
    segment: list[int] = field(default_factory=list)
    n_lines: list[int] = field(default_factory=list)  # data lines per epoch
    data: list[bytes] = field(default_factory=list)  # all data lines, in file order
    line_no: list[int] = field(default_factory=list)  # 1-based line of each epoch's first data line
    epoch_line: list[int] = field(default_factory=list)  # 1-based line of each epoch record
    rec_sat: list[bytes] = field(default_factory=list)  # RINEX 2: satellite id of every record
    rec_lines: list[int] = field(default_factory=list)  # RINEX 2: lines per record
    events: list[Event] = field(default_factory=list)
    event_t_cal_s: list[float] = field(default_factory=list)
    skipped: list[SkippedLine] = field(default_factory=list)


def read_obs(
    path: StrPath,
    *,
    lenient: bool = False,
    systems: str | None = None,
    codes: Collection[str] | None = None,
) -> Observations:
    """Read a RINEX observation file (2.10, 2.11, 3.00-3.05, 4.0x; plain, gzip, bzip2, ``.Z``,
    Hatanaka).

    Parameters
    ----------
    path : str or path-like
        The file.
    lenient : bool, default False
        False: any malformed line raises. True: damaged data lines (non-numeric fields, unknown
        satellite systems, satellites whose system has no observation types, surplus lines,
        epochs cut short by the end of the file) are skipped and listed in
        ``Observations.skipped``; a malformed header still raises.
    systems : str, optional
        Keep only these systems' satellites (``"GE"``); default all.
    codes : collection of str, optional
        Keep only these observation codes (``{"C1C", "L1C"}``); default all. The fields of the
        other systems and codes are not decoded (a read that asks for what it uses costs a
        fraction of a full one); the structure of the whole file (epoch records, satellite
        lines, line counts, identifiers) is still checked, but a malformed field of an unread
        code is not found.

    Returns
    -------
    Observations
        ``values[e, s, c]`` for epoch ``e`` (epoch flags 0, 1 and 6, in file order), satellite
        ``s`` (``sats``, sorted) and code ``c`` (``codes``: union of the header's observation
        types over the systems, first-seen order). Epoch times are converted to GPS seconds
        from the file's time system (``GLO`` time tags are UTC, RINEX 3.05 section 6.1).
        Special records (epoch flags 2-5) are kept in ``events``.

    Raises
    ------
    FileFormatError
        Naming file and 1-based line: empty file, not an observation file, unknown version,
        missing ``END OF HEADER`` or observation types, malformed epoch record, truncated epoch,
        non-numeric data field, unknown satellite system (strict mode).

    Notes
    -----
    A value written as 0.0 means "missing" (RINEX 2.11 table A2: missing observations are
    written as 0.0 or blanks) and becomes NaN; its LLI and SSI are kept as written.
    Epoch flag 6 records hold cycle-slip counts, not observations (RINEX 2.11 table A3); they are
    kept as epochs with ``epoch_flag == 6`` and must be masked by users of the values. Epoch flag
    3 and 4 records that redefine the observation types take effect for the following epochs.
    """
    data = read_bytes(path)
    kind = sniff(path, data)
    if kind.format != "rinex" or kind.file_type != "O":
        raise FileFormatError(
            path, 1, f"not a RINEX observation file (format {kind.format}, type {kind.file_type})"
        )
    if b"\r" in data:
        data = data.replace(b"\r\n", b"\n")
    lines = data.split(b"\n")
    end = len(lines)
    while end > 0 and not lines[end - 1].strip():
        end -= 1
    v3 = kind.version >= 3
    header, seg0, body = _parse_header(path, lines, end, kind.version, kind.system)
    scan = _Scan()
    last = lines[end - 1] if end > body else b""
    # not an epoch record, nor a header record of an event (its label in columns 61-80)
    epoch_line = last.startswith(b">") if v3 else _V2_EPOCH.match(last)
    data_line = not epoch_line and not last[60:].strip(b" 0123456789.-")
    # F14.3 then LLI and SSI (I1 each), 16 characters per field after the satellite id (A1,I2)
    if last and data_line and ends_inside_field(data, 3 if v3 else 0, 16, (0, 14, 15)):
        reason = "data line cut in the middle of a field by the end of the file"
        if not lenient:
            raise FileFormatError(path, end, reason)
        scan.skipped.append(SkippedLine(line=end, reason=reason))
        del lines[end - 1 :]
        end -= 1
    if v3:
        _scan_v3(path, lines, body, end, seg0, scan, lenient)
    else:
        _scan_v2(path, lines, body, end, seg0, scan, lenient)
    return _assemble(path, header, seg0, scan, v3, lenient, systems, codes)


# ----------------------------------------------------------------------------------- header


def _parse_header(
    path: StrPath, lines: list[bytes], end: int, version: float, file_system: str
) -> tuple[ObsHeader, list[_Segment], int]:
    """Parse the header; returns it, the initial observation types and the first data line."""
    v3 = version >= 3
    info: dict[str, object] = {}
    comments: list[str] = []
    obs_types: dict[str, list[str]] = {}
    declared: dict[str, tuple[int, int]] = {}  # system -> (count, line)
    scale: dict[tuple[str, str], float] = {}
    glonass_fcn: dict[str, int] = {}
    time_system = ""
    first_obs: tuple[float, int] | None = None
    last_obs: tuple[float, int] | None = None
    current = ""
    scale_current: tuple[str, float] | None = None
    body = -1
    for i in range(end):
        text = lines[i].decode("ascii", "replace").rstrip()
        label = text[60:].strip()
        if label == "END OF HEADER":
            body = i + 1
            break
        if i > 0 and (
            (v3 and text.startswith(">")) or (not v3 and _V2_EPOCH.match(lines[i])) or not label
        ):
            raise FileFormatError(
                path, i + 1, "header not terminated: no 'END OF HEADER' before this line"
            )
        try:
            if label == "COMMENT":
                comments.append(text[:60].rstrip())
            elif label == "MARKER NAME":
                info["marker"] = text[:60].strip()
            elif label == "MARKER NUMBER":
                info["marker_number"] = text[:20].strip()
            elif label == "REC # / TYPE / VERS":
                info["receiver"] = _join_fields(text, (0, 20, 40, 60))
            elif label == "ANT # / TYPE":
                info["antenna"] = _join_fields(text, (0, 20, 40))
            elif label == "APPROX POSITION XYZ":
                info["approx_xyz_m"] = _three_floats(text)
            elif label == "ANTENNA: DELTA H/E/N":
                info["antenna_delta_hen_m"] = _three_floats(text)
            elif label == "INTERVAL":
                info["interval_s"] = float(text[:10])
            elif label == "LEAP SECONDS":
                info["leap_seconds"] = int(text[:6])
            elif label == "TIME OF FIRST OBS":
                time_system = text[48:51].strip()
                first_obs = (_header_time(text), i)
            elif label == "TIME OF LAST OBS":
                last_obs = (_header_time(text), i)
            elif label == "# / TYPES OF OBSERV" and not v3:
                if text[:6].strip():
                    current = "G"
                    declared[current] = (int(text[:6]), i)
                    obs_types[current] = []
                elif not current:
                    raise ValueError("continuation line without a preceding count")
                obs_types[current] += text[6:60].split()
            elif label == "SYS / # / OBS TYPES" and v3:
                if text[:1].strip():
                    current = text[:1]
                    if current not in SYSTEMS:
                        raise FileFormatError(path, i + 1, f"unknown satellite system {current!r}")
                    declared[current] = (int(text[3:6]), i)
                    obs_types[current] = []
                elif not current:
                    raise ValueError("continuation line without a preceding system")
                obs_types[current] += text[7:60].split()
            elif label == "SYS / SCALE FACTOR" and v3:
                if text[:1].strip():
                    scale_current = (text[:1], float(int(text[2:6])))
                if scale_current is None:
                    raise ValueError("continuation line without a preceding system")
                codes = text[10:58].split()
                sys, factor = scale_current
                for code in codes or obs_types.get(sys, []):
                    scale[(sys, code)] = factor
            elif label == "GLONASS SLOT / FRQ #":
                for k in range(8):
                    sat = text[4 + 7 * k : 7 + 7 * k].strip()
                    if sat:
                        glonass_fcn[_sat_id(sat.encode(), blank_is_gps=False)] = int(
                            text[8 + 7 * k : 10 + 7 * k]
                        )
        except FileFormatError:
            raise
        except (ValueError, IndexError, KeyError) as exc:
            raise FileFormatError(path, i + 1, f"malformed {label!r} record ({exc})") from None
    if body < 0:
        raise FileFormatError(
            path, end, "header not terminated: no 'END OF HEADER' up to the end of the file"
        )
    if not obs_types:
        label = "SYS / # / OBS TYPES" if v3 else "# / TYPES OF OBSERV"
        raise FileFormatError(path, body, f"no {label!r} record in the header")
    for sys, (count, line) in declared.items():
        if len(obs_types[sys]) != count:
            raise FileFormatError(
                path,
                line + 1,
                f"{count} observation types announced for {sys!r}, {len(obs_types[sys])} listed",
            )
    time_system = time_system or _DEFAULT_TIME_SYSTEM.get(file_system, "GPS")
    if time_system not in _KNOWN_TIME_SYSTEMS:
        line = first_obs[1] + 1 if first_obs else body
        raise FileFormatError(path, line, f"unknown time system {time_system!r}")

    def conv(t: tuple[float, int] | None) -> float | None:
        return None if t is None else float(_to_gps_rinex(np.array([t[0]]), time_system)[0])

    types = {s: tuple(c) for s, c in obs_types.items()}
    header = ObsHeader(
        version=version,
        file_type="O",
        system=file_system,
        time_system=time_system,
        obs_types=types,
        comments=tuple(comments),
        first_obs_gps_s=conv(first_obs),
        last_obs_gps_s=conv(last_obs),
        glonass_fcn=glonass_fcn,
        **info,  # type: ignore[arg-type]
    )
    return header, [_Segment(types, scale)], body


def _join_fields(text: str, cuts: tuple[int, ...]) -> str:
    parts = (text[a:b].strip() for a, b in itertools.pairwise(cuts))
    return " ".join(p for p in parts if p)


def _three_floats(text: str) -> FloatArray | None:
    if not text[:42].strip():
        return None
    return np.array([float(text[k : k + 14]) for k in (0, 14, 28)])


def _header_time(text: str) -> float:
    """Calendar seconds since 1980-01-06 of a TIME OF FIRST/LAST OBS record (5I6,F13.7)."""
    y, mo, d, h, mi = (int(text[k : k + 6]) for k in range(0, 30, 6))
    return calendar_gps_seconds(y, mo, d, h, mi, float(text[30:43]))


def _epoch_time_s(rec: bytes, start: int, stop: int, days: dict[bytes, float]) -> float:
    """Calendar seconds since 1980-01-06 of the date and time of an epoch record.

    ``rec[start:stop]`` is the date, ``YYYY MM DD`` (RINEX 3) or ``YY MM DD`` (RINEX 2, years
    80-99 are 19xx); the time ``hh mm ss.sssssss`` (I2,1X,I2,F11.7) follows one blank later in
    both versions. ``days`` caches the seconds of each date's midnight: a file has few dates but
    one record per epoch, and ``datetime.date`` is the costly part.
    """
    key = rec[start:stop]
    day_s = days.get(key)
    if day_s is None:
        year = int(key[:-6])
        if stop - start == 8:
            year += 1900 if year >= 80 else 2000
        day_s = days[key] = calendar_gps_seconds(year, int(key[-5:-3]), int(key[-2:]), 0, 0, 0.0)
    return day_s + (
        int(rec[stop + 1 : stop + 3]) * 3600.0
        + int(rec[stop + 4 : stop + 6]) * 60.0
        + float(rec[stop + 6 : stop + 17])
    )


def _to_gps_rinex(t_cal_s: FloatArray, time_system: str) -> FloatArray:
    # RINEX time tags labelled GLO are UTC(SU), not Moscow time (RINEX 2.11 section 8.1,
    # RINEX 3.05 section 6.1); TAI = GPST + 19 s.
    if time_system == "GLO":
        return to_gps(t_cal_s, "UTC")
    if time_system == "TAI":
        return t_cal_s - 19.0
    return to_gps(t_cal_s, time_system)


def _sat_id(raw: bytes, blank_is_gps: bool) -> str:
    """``G05`` from ``G05`` or ``G 5`` (and `` 5`` in RINEX 2, where a blank system is GPS).

    Raises ValueError for an unknown system letter or a malformed number.
    """
    text = raw.decode("ascii", "replace").ljust(3)[:3]
    letter = text[0] if text[0] != " " or not blank_is_gps else "G"
    prn = "0" + text[2] if text[1] == " " else text[1:]
    if letter not in SYSTEMS:
        raise ValueError(f"unknown satellite system {letter!r} in satellite id {text!r}")
    if not prn.isdigit() or prn == "00":
        raise ValueError(f"malformed satellite id {text!r}")
    return letter + prn


def _new_segment(
    path: StrPath, records: list[bytes], first_line: int, seg: _Segment, v3: bool
) -> _Segment | None:
    """Observation types redefined by header records inside the data (epoch flag 3/4)."""
    label = "SYS / # / OBS TYPES" if v3 else "# / TYPES OF OBSERV"
    if not any(r[60:].strip() == label.encode() for r in records):
        return None
    new: dict[str, list[str]] = {}
    declared: dict[str, tuple[int, int]] = {}
    current = ""
    for k, raw in enumerate(records):
        text = raw.decode("ascii", "replace").rstrip()
        if text[60:].strip() != label:
            continue
        try:
            if v3:
                if text[:1].strip():
                    current = text[:1]
                    if current not in SYSTEMS:
                        raise ValueError(f"unknown satellite system {current!r}")
                    declared[current] = (int(text[3:6]), k)
                    new[current] = []
                elif not current:
                    raise ValueError("continuation line without a preceding system")
                new[current] += text[7:60].split()
            else:
                if text[:6].strip():
                    current = "G"
                    declared[current] = (int(text[:6]), k)
                    new[current] = []
                elif not current:
                    raise ValueError("continuation line without a preceding count")
                new[current] += text[6:60].split()
        except ValueError as exc:
            raise FileFormatError(
                path, first_line + k + 1, f"malformed {label!r} ({exc})"
            ) from None
    for sys, (count, k) in declared.items():
        if len(new[sys]) != count:
            raise FileFormatError(
                path,
                first_line + k + 1,
                f"{count} observation types announced, {len(new[sys])} listed",
            )
    types = dict(seg.obs_types) if v3 else {}
    types.update({s: tuple(c) for s, c in new.items()})
    return _Segment(types, dict(seg.scale))


# ------------------------------------------------------------------------------ epoch walk


def _event(
    path: StrPath,
    lines: list[bytes],
    i: int,
    flag: int,
    count: int,
    end: int,
    t_cal: float,
    scan: _Scan,
) -> None:
    if i + 1 + count > end:
        raise FileFormatError(
            path,
            i + 1,
            f"event record announces {count} special records but the file ends after {end - i - 1}",
        )
    records = tuple(r.decode("ascii", "replace").rstrip() for r in lines[i + 1 : i + 1 + count])
    scan.events.append(Event(line=i + 1, t_gps_s=_NAN, flag=flag, records=records))
    scan.event_t_cal_s.append(t_cal)


def _skip(scan: _Scan, first: int, stop: int, reason: str) -> None:
    scan.skipped.extend(SkippedLine(line=j + 1, reason=reason) for j in range(first, stop))


def _scan_v3(
    path: StrPath,
    lines: list[bytes],
    body: int,
    end: int,
    segments: list[_Segment],
    scan: _Scan,
    lenient: bool,
) -> None:
    """Walk the RINEX 3 epoch records: ``>`` lines, (A1,1X,I4,4(1X,I2),F11.7,2X,I1,I3,6X,F15.12)."""
    starts = [j for j in range(body, end) if lines[j][:1] == b">"]
    starts.append(end)
    seg = len(segments) - 1
    days: dict[bytes, float] = {}
    last: tuple[int, int, int] | None = None  # last data epoch: record line, count, end
    i = body
    pos = 0
    while pos < len(starts) - 1:
        j = starts[pos]
        if j > i:  # lines no epoch record accounts for
            if not lenient:
                if last is not None and last[2] == i:
                    raise FileFormatError(
                        path,
                        last[0] + 1,
                        f"epoch record announces {last[1]} satellites but {j - last[0] - 1} "
                        f"data lines follow (lines {i + 1}-{j} are surplus)",
                    )
                raise FileFormatError(path, i + 1, "line outside any epoch record")
            _skip(scan, i, j, "line outside any epoch record")
        rec = lines[j]
        nxt = starts[pos + 1]
        try:
            flag = rec[31] - 48
            count = int(rec[32:35])
            if not 0 <= flag <= 6 or count < 0:
                raise ValueError(f"epoch flag {rec[31:32]!r}")
            if rec[2:29].strip():
                t_cal = _epoch_time_s(rec, 2, 12, days)
            elif flag in (0, 1, 6):
                raise ValueError("no epoch time")
            else:
                t_cal = _NAN
            clock = rec[41:56]
            if clock.strip() and len(rec.rstrip()) < 56:
                # F15.12 ends in column 56: a shorter line was cut inside the clock value
                raise ValueError(
                    f"receiver clock offset {clock.strip().decode('ascii', 'replace')!r} cut "
                    "short (the field is columns 42-56)"
                )
            clock_s = float(clock) if clock.strip() else _NAN
        except (ValueError, IndexError) as exc:
            if not lenient:
                raise FileFormatError(path, j + 1, f"malformed epoch record ({exc})") from None
            scan.skipped.append(SkippedLine(line=j + 1, reason=f"malformed epoch record ({exc})"))
            _skip(scan, j + 1, nxt, "data line of a malformed epoch record")
            i = nxt
            pos += 1
            continue
        if flag in (0, 1, 6):
            have = nxt - j - 1
            take = count
            if have < count:
                if not lenient:
                    raise FileFormatError(
                        path,
                        j + 1,
                        f"epoch record announces {count} satellites but only "
                        f"{have} data lines follow"
                        + (
                            " before the end of the file"
                            if nxt == end
                            else f" before the next epoch record (line {nxt + 1})"
                        ),
                    )
                scan.skipped.append(
                    SkippedLine(line=j + 1, reason=f"epoch cut short: {have} of {count} satellites")
                )
                take = have
            scan.t_cal_s.append(t_cal)
            scan.flag.append(flag)
            scan.clock_s.append(clock_s)
            scan.segment.append(seg)
            scan.n_lines.append(take)
            scan.line_no.append(j + 2)
            scan.epoch_line.append(j + 1)
            scan.data.extend(lines[j + 1 : j + 1 + take])
            i = j + 1 + take
            last = (j, count, i)
            pos += 1
        else:
            _event(path, lines, j, flag, count, end, t_cal, scan)
            i = j + 1 + count
            if flag in (3, 4):
                new = _new_segment(path, lines[j + 1 : i], j + 1, segments[seg], True)
                if new is not None:
                    segments.append(new)
                    seg = len(segments) - 1
            pos += 1
            while starts[pos] < i:  # '>' lines inside the special records
                pos += 1
    if i < end:
        if not lenient:
            raise FileFormatError(path, i + 1, "line outside any epoch record")
        _skip(scan, i, end, "line outside any epoch record")


def _scan_v2(
    path: StrPath,
    lines: list[bytes],
    body: int,
    end: int,
    segments: list[_Segment],
    scan: _Scan,
    lenient: bool,
) -> None:
    """Walk RINEX 2 epoch records: (1X,I2.2,4(1X,I2),F11.7,2X,I1,I3,12(A1,I2),F12.9)."""
    # The last record may legitimately end in blank lines (all its observations on them
    # missing); ``end`` excludes trailing blank lines, ``limit`` is the true last line.
    limit = len(lines) - (lines[-1] == b"")
    seg = len(segments) - 1
    per_sat = (len(segments[seg].obs_types["G"]) + 4) // 5
    days: dict[bytes, float] = {}
    previous = (-1, 0, 0, 0)  # last data epoch: record line, satellites, first/stop data line
    i = body
    while i < end:
        rec = lines[i]
        try:
            if not (_V2_EPOCH.match(rec) or _V2_EVENT_NO_TIME.match(rec)):
                raise ValueError("not an epoch record")
            flag = rec[28] - 48
            count = int(rec[29:32])
            if rec[1:26].strip():
                t_cal = _epoch_time_s(rec, 1, 9, days)
            elif flag in (0, 1, 6):
                raise ValueError("no epoch time")
            else:
                t_cal = _NAN
        except ValueError as exc:
            if not lenient:
                _missing_v2_data_line(path, lines, previous)
                raise FileFormatError(path, i + 1, f"malformed epoch record ({exc})") from None
            scan.skipped.append(SkippedLine(line=i + 1, reason=f"malformed epoch record ({exc})"))
            i += 1
            continue
        if flag not in (0, 1, 6):
            _event(path, lines, i, flag, count, end, t_cal, scan)
            stop = i + 1 + count
            if flag in (3, 4):
                new = _new_segment(path, lines[i + 1 : stop], i + 1, segments[seg], False)
                if new is not None:
                    segments.append(new)
                    seg = len(segments) - 1
                    per_sat = (len(new.obs_types["G"]) + 4) // 5
            i = stop
            continue
        n_list = max(1, (count + 11) // 12)
        first = i + n_list
        if first > end:
            raise FileFormatError(path, i + 1, "satellite list cut short by the end of the file")
        sats: list[bytes] = []
        for k in range(n_list):
            row = lines[i + k]
            if k and row[:32].strip():
                raise FileFormatError(
                    path,
                    i + k + 1,
                    f"expected a satellite-list continuation line "
                    f"({count} satellites announced at line {i + 1})",
                )
            m = min(12, count - 12 * k)
            sats.extend(row[32 + 3 * c : 35 + 3 * c] for c in range(m))
        clock = rec[68:80]
        try:
            clock_s = float(clock) if clock.strip() else _NAN
        except ValueError:
            if not lenient:
                raise FileFormatError(
                    path, i + 1, f"malformed receiver clock offset {clock!r}"
                ) from None
            scan.skipped.append(SkippedLine(line=i + 1, reason="malformed clock offset ignored"))
            clock_s = _NAN
        stop = first + count * per_sat
        take = count
        if stop > limit:
            if not lenient:
                raise FileFormatError(
                    path,
                    i + 1,
                    f"epoch record announces {count} satellites "
                    f"({count * per_sat} data lines) but the file ends after {limit - first}",
                )
            take = (limit - first) // per_sat
            scan.skipped.append(
                SkippedLine(line=i + 1, reason=f"epoch cut short: {take} of {count} satellites")
            )
            _skip(scan, first + take * per_sat, end, "incomplete record at the end of the file")
            stop = limit
        if lenient:  # an epoch record among the data: lines are missing, satellites misaligned
            intruder = next((j for j in range(first, stop) if _V2_EPOCH.match(lines[j])), None)
            if intruder is not None:
                scan.skipped.append(
                    SkippedLine(
                        line=i + 1,
                        reason=f"epoch dropped: fewer than {count} satellite records before the "
                        f"next epoch record (line {intruder + 1})",
                    )
                )
                _skip(scan, i + 1, intruder, "data line of a dropped epoch")
                i = intruder
                continue
        scan.t_cal_s.append(t_cal)
        scan.flag.append(flag)
        scan.clock_s.append(clock_s)
        scan.segment.append(seg)
        scan.n_lines.append(take * per_sat)
        scan.line_no.append(first + 1)
        scan.epoch_line.append(i + 1)
        scan.data.extend(lines[first : first + take * per_sat])
        scan.rec_sat.extend(sats[:take])
        scan.rec_lines.extend([per_sat] * take)
        previous = (i, count, first, stop)
        i = stop


def _missing_v2_data_line(
    path: StrPath, lines: list[bytes], previous: tuple[int, int, int, int]
) -> None:
    """Explain a malformed epoch record by a data line missing from the epoch before it."""
    rec, count, first, stop = previous
    for j in range(first, stop):
        if _V2_EPOCH.match(lines[j]):
            raise FileFormatError(
                path,
                rec + 1,
                f"epoch record announces {count} satellites but fewer data lines "
                f"follow: line {j + 1}, read as its data, is an epoch record",
            )


# ------------------------------------------------------------------------------- decoding

# Decoding works on each 16-byte field viewed as two little-endian uint64 words: ``lo`` holds
# characters 0-7 of the F14.3 value, ``hi`` characters 8-13 and the LLI and SSI characters. Byte
# predicates (is blank, is digit, is minus) are computed as 0/1 bytes and tested as whole words.
_U8 = np.dtype("<u8")
_ONES = 0x0101010101010101
_BLANKS = 0x2020202020202020
_LOW2, _LOW6 = 0xFFFF, 0xFFFFFFFFFFFF
# Blank prefix of length s (0..10) of characters 0-9 as 0/1 bytes, split over lo and hi; and a
# single minus sign right after it.
_PREFIX_LO = np.array([_ONES >> (8 * (8 - min(s, 8))) if s else 0 for s in range(11)], _U8)
_PREFIX_HI = np.array([0, 0, 0, 0, 0, 0, 0, 0, 0, 0x01, 0x0101], _U8)
_MINUS_LO = np.array([1 << (8 * s) if s < 8 else 0 for s in range(11)], _U8)
_MINUS_HI = np.array([0] * 8 + [0x01, 0x0100, 0], _U8)
_SPACE = 32
_NUMBER = re.compile(rb"[+-]?(\d+\.?\d*|\.\d+)([eEdD][+-]?\d+)?")


def _decode(fields: np.ndarray) -> tuple[FloatArray, Int8Array, Int8Array, np.ndarray, np.ndarray]:
    """Decode ``F14.3,I1,I1`` fields.

    Parameters
    ----------
    fields : ndarray of uint8, shape (n, 16)
        Field bytes (ASCII), blank-padded.

    Returns
    -------
    value : ndarray, shape (n,)
        NaN where the value is blank.
    lli, ssi : ndarray of int8, shape (n,)
        -1 where blank.
    blank : ndarray of bool, shape (n,)
        All 16 characters blank.
    bad : ndarray of bool, shape (n,)
        Not a number (or LLI/SSI not a digit).

    Notes
    -----
    A value in the standard layout (blanks, an optional minus sign, digits, the decimal point
    in character 10, three digits) is read as an integer number of thousandths with the
    8-digits-at-once multiplication of Lemire (2022) plus the remaining digits, then divided by
    1000 (exact operands, correctly rounded division: equal to ``float(text)``). Other layouts go
    through ``float()``.

    References
    ----------
    D. Lemire, "Number parsing at a gigabyte per second", Software: Practice and Experience 51
    (2021); the 8-digit SWAR step as in his blog post "Quickly parsing eight digits" (2018).
    """
    f = np.ascontiguousarray(fields)
    n = len(f)
    words = f.view(_U8)
    lo, hi = words[:, 0], words[:, 1]
    value_blank = (lo == _BLANKS) & ((hi & _LOW6) == (_BLANKS & _LOW6))
    digit = (f - np.uint8(48)) < 10
    sp = (f == _SPACE).view(_U8)
    mi = (f == 45).view(_U8)
    dg = digit.view(_U8)
    sp_lo, sp_hi = sp[:, 0], sp[:, 1] & _LOW2
    mi_lo, mi_hi = mi[:, 0], mi[:, 1] & _LOW2
    allowed = sp | mi | dg
    std = (allowed[:, 0] == _ONES) & ((allowed[:, 1] & _LOW2) == 0x0101)
    std &= f[:, 10] == 46
    std &= ((dg[:, 1] >> 24) & 0xFFFFFF) == 0x010101
    blanks = ((sp_lo * _ONES) >> 56) + (sp_hi & 0xFF) + (sp_hi >> 8)
    std &= (sp_lo == _PREFIX_LO[blanks]) & (sp_hi == _PREFIX_HI[blanks])
    negative = (mi_lo | mi_hi) != 0
    std &= ~negative | ((mi_lo == _MINUS_LO[blanks]) & (mi_hi == _MINUS_HI[blanks]))
    dv = ((f - np.uint8(48)) * digit).view(_U8)  # digit values, 0 for anything else
    v: np.ndarray = dv[:, 0]
    v = (v * 2561) >> 8
    v = ((v & 0x00FF00FF00FF00FF) * 6553601) >> 16
    v = ((v & 0x0000FFFF0000FFFF) * 42949672960001) >> 32  # characters 0-7
    h = dv[:, 1]
    integer = v * 100 + (h & 0xFF) * 10 + ((h >> 8) & 0xFF)
    frac = ((h >> 24) & 0xFF) * 100 + ((h >> 32) & 0xFF) * 10 + ((h >> 40) & 0xFF)
    value = (integer * 1000 + frac).astype(np.float64) / 1000.0
    np.negative(value, out=value, where=negative)
    value[value_blank] = np.nan
    bad = np.zeros(n, dtype=bool)
    for k in np.flatnonzero(~std & ~value_blank).tolist():  # other layouts: float(), if a number
        text = f[k, :14].tobytes().strip()
        if _NUMBER.fullmatch(text):
            value[k] = float(text.replace(b"D", b"E").replace(b"d", b"e"))
        else:
            bad[k] = True
            value[k] = np.nan
    lli = _indicator(f[:, 14])
    ssi = _indicator(f[:, 15])
    bad |= (lli == -2) | (ssi == -2)
    lli[lli == -2] = -1
    ssi[ssi == -2] = -1
    blank = value_blank & (f[:, 14] == _SPACE) & (f[:, 15] == _SPACE)
    return value, lli, ssi, blank, bad


def _decode_some(
    fields: np.ndarray, which: np.ndarray
) -> tuple[FloatArray, Int8Array, Int8Array, np.ndarray, np.ndarray]:
    """:func:`_decode` of the fields ``which`` only, scattered back to all fields: the others
    are NaN with indicators -1, never ``bad``, and ``blank`` where all 16 characters are."""
    n = len(fields)
    words = np.ascontiguousarray(fields).view(_U8)
    blank = (words[:, 0] == _BLANKS) & (words[:, 1] == _BLANKS)
    value = np.full(n, np.nan)
    lli = np.full(n, -1, dtype=np.int8)
    ssi = np.full(n, -1, dtype=np.int8)
    bad = np.zeros(n, dtype=bool)
    value[which], lli[which], ssi[which], _, bad[which] = _decode(fields[which])
    return value, lli, ssi, blank, bad


def _indicator(c: np.ndarray) -> Int8Array:
    """Digit -> 0..9, blank -> -1, anything else -> -2 (bad)."""
    out = c.astype(np.int8) - np.int8(48)
    out[c == _SPACE] = -1
    out[(c != _SPACE) & ((c < 48) | (c > 57))] = -2
    return out


def _matrix(data: list[bytes], lead: int) -> np.ndarray:
    """Data lines as an (n, lead + 16 k) uint8 matrix, blank-padded to whole fields."""
    width = max(map(len, data), default=lead)
    width = lead + _FIELD * max(1, -(-(width - lead) // _FIELD))
    buf = b"".join([row.ljust(width) for row in data])
    return np.frombuffer(buf, dtype=np.uint8).reshape(len(data), width)


def _assemble(
    path: StrPath,
    header: ObsHeader,
    segments: list[_Segment],
    scan: _Scan,
    v3: bool,
    lenient: bool,
    want_systems: str | None = None,
    want_codes: Collection[str] | None = None,
) -> Observations:
    n_e = len(scan.t_cal_s)
    codes: list[str] = []
    for seg in segments:
        for types in seg.obs_types.values():
            codes.extend(c for c in types if c not in codes)
    # each field's code indexes ``codes``; ``kept`` maps it to the output's codes (-1: dropped)
    code_index = {c: k for k, c in enumerate(codes)}
    out_codes = [c for c in codes if want_codes is None or c in want_codes]
    kept = np.array([out_codes.index(c) if c in out_codes else -1 for c in codes] + [-1])
    n_c = len(out_codes)
    n_sys = len(SYSTEMS)

    lead = 3 if v3 else 0
    n_lines = len(scan.data)
    # RINEX 3 lines of other systems than those asked for are not decoded: their satellite and
    # length are checked (below), their fields not read
    select_lines = v3 and want_systems is not None
    full = None if select_lines else _matrix(scan.data, lead)
    lines_per_epoch = np.asarray(scan.n_lines, dtype=np.int64)
    epoch_of_line = np.repeat(np.arange(n_e), lines_per_epoch)
    seg_of_line = np.repeat(np.asarray(scan.segment, dtype=np.int64), lines_per_epoch)
    first_of_epoch = np.cumsum(lines_per_epoch) - lines_per_epoch
    line_no = np.repeat(
        np.asarray(scan.line_no, dtype=np.int64) - first_of_epoch, lines_per_epoch
    ) + np.arange(n_lines)
    problem: dict[int, str] = {}  # data-line index -> why it is unusable
    report_at: dict[int, int] = {}  # data-line index -> line to name when raising, if not its own

    # Satellite of each data line.
    if v3:
        if full is not None:
            raw_ids = np.ascontiguousarray(full[:, :3]).view("S3").ravel()
        else:
            heads = b"".join([row[:3] for row in scan.data])
            if len(heads) != 3 * n_lines:  # a line shorter than its satellite id
                heads = b"".join([row[:3].ljust(3) for row in scan.data])
            raw_ids = np.frombuffer(heads, dtype="S3")
        offset = np.zeros(n_lines, dtype=np.int64)
        part = np.zeros(n_lines, dtype=np.int64)
    else:
        raw_ids = np.array(scan.rec_sat, dtype="S3")
        rec_lines = np.asarray(scan.rec_lines, dtype=np.int64)
        rec_first = np.cumsum(rec_lines) - rec_lines
        part = np.arange(n_lines) - np.repeat(rec_first, rec_lines)
        offset = 5 * part
    # Unique ids through a 3-byte integer code (much faster than sorting byte strings).
    id_bytes = raw_ids.view(np.uint8).reshape(-1, 3).astype(np.uint32)
    id_code = (id_bytes[:, 0] << 16) | (id_bytes[:, 1] << 8) | id_bytes[:, 2]
    uniq_code, inverse = np.unique(id_code, return_inverse=True)
    uniq = [
        bytes(((c >> 16) & 255, (c >> 8) & 255, c & 255)).replace(b"\0", b" ")
        for c in uniq_code.tolist()
    ]
    names: list[str | None] = []
    for k, raw in enumerate(uniq):
        try:
            names.append(_sat_id(raw, blank_is_gps=not v3))
        except ValueError as exc:
            names.append(None)
            members = np.flatnonzero(inverse == k)
            where = (
                members
                if v3
                else np.flatnonzero(
                    np.isin(np.repeat(np.arange(len(rec_lines)), rec_lines), members)
                )
            )
            for m in where.tolist():
                if v3:
                    problem.setdefault(m, str(exc))
                else:  # the id is written in the epoch record: name that line when raising
                    problem.setdefault(m, f"{exc} in the satellite list of the epoch record")
                    report_at.setdefault(m, scan.epoch_line[epoch_of_line[m]])
    sats = sorted({n for n in names if n is not None})
    sat_col = {s: k for k, s in enumerate(sats)}
    out_sats = [s for s in sats if want_systems is None or s[0] in want_systems]
    out_col = np.array([out_sats.index(s) if s in out_sats else -1 for s in sats] + [-1])
    uniq_col = np.array([sat_col.get(n, -1) if n else -1 for n in names] or [0], dtype=np.int64)
    uniq_sys = np.array([SYSTEMS.index(n[0]) if n else 0 for n in names] or [0], dtype=np.int64)
    if v3:
        sat_of_line = uniq_col[inverse]
        sys_of_line = uniq_sys[inverse]
    else:
        rec_of_line = np.repeat(np.arange(len(rec_lines)), rec_lines)
        sat_of_line = uniq_col[inverse][rec_of_line] if n_lines else np.zeros(0, np.int64)
        sys_of_line = np.zeros(n_lines, dtype=np.int64)  # RINEX 2: one type list for all

    # Lines whose fields are decoded.
    if full is None:
        letter = raw_ids.view(np.uint8).reshape(-1, 3)[:, 0]
        other = np.isin(letter, np.frombuffer(SYSTEMS.encode(), np.uint8)) & ~np.isin(
            letter, np.frombuffer(str(want_systems).upper().encode(), np.uint8)
        )
        decode = np.flatnonzero(~other)
        mat = _matrix([scan.data[i] for i in decode.tolist()], lead)
    else:
        decode = np.arange(n_lines)
        mat = full
    n_dec = mat.shape[0]
    n_f = (mat.shape[1] - lead) // _FIELD

    # Code of each field: table rows are (segment, system), columns the field position.
    width = max((len(t) for seg in segments for t in seg.obs_types.values()), default=0)
    width += n_f + 5
    table = np.full((len(segments) * n_sys, width), -1, dtype=np.int64)
    scale = np.ones((len(segments) * n_sys, width))
    declared = np.zeros(len(segments) * n_sys, dtype=bool)
    for g, seg in enumerate(segments):
        for sys, types in seg.obs_types.items():
            r = g * n_sys + SYSTEMS.index(sys)
            declared[r] = True
            table[r, : len(types)] = [code_index[c] for c in types]
            scale[r, : len(types)] = [seg.scale.get((sys, c), 1.0) for c in types]
    row = seg_of_line * n_sys + sys_of_line
    col = offset[decode, None] + np.arange(n_f)
    code = table[row[decode, None], col]
    if not v3:
        code[:, 5:] = -1  # RINEX 2 lines hold 5 fields (80 columns)

    fields = mat[:, lead:].reshape(n_dec * n_f, _FIELD)
    if want_systems is None and want_codes is None:
        value, lli, ssi, blank, bad = _decode(fields)
    else:  # decode the wanted fields only; blanks of all (they check the structure)
        wanted = (kept[code] >= 0) & (out_col[sat_of_line[decode]] >= 0)[:, None]
        value, lli, ssi, blank, bad = _decode_some(fields, np.flatnonzero(wanted.ravel()))
    value = value.reshape(n_dec, n_f)
    value[value == 0.0] = np.nan  # "missing observations are written as 0.0 or blanks"
    lli, ssi = lli.reshape(n_dec, n_f), ssi.reshape(n_dec, n_f)
    blank, bad = blank.reshape(n_dec, n_f), bad.reshape(n_dec, n_f)

    for m in np.flatnonzero(bad.any(axis=1)).tolist():
        k = int(np.argmax(bad[m]))
        text = (
            mat[m, lead + _FIELD * k : lead + _FIELD * (k + 1)].tobytes().decode("ascii", "replace")
        )
        problem.setdefault(int(decode[m]), f"malformed observation field {k + 1}: {text!r}")
    surplus = (~blank & (code < 0)).any(axis=1)
    if n_dec < n_lines:  # a line not decoded: text beyond its system's last field
        n_types = (table >= 0).sum(axis=1)
        not_decoded = np.ones(n_lines, dtype=bool)
        not_decoded[decode] = False
        skipped_rows = np.flatnonzero(not_decoded)
        limit = lead + _FIELD * n_types[row[skipped_rows]]
        length = np.fromiter(map(len, map(scan.data.__getitem__, skipped_rows.tolist())), np.int64)
        beyond = length > limit
        for k in np.flatnonzero(beyond).tolist():  # trailing blanks do not count
            beyond[k] = len(scan.data[int(skipped_rows[k])].rstrip(b" ")) > limit[k]
        too_long = np.zeros(n_lines, dtype=bool)
        too_long[decode] = surplus
        too_long[skipped_rows] = beyond
        surplus = too_long
    for m in np.flatnonzero(surplus & declared[row]).tolist():
        problem.setdefault(
            m,
            "more observations than observation types"
            + ("" if v3 else " (or data beyond column 80)"),
        )
    for m in np.flatnonzero(~declared[row]).tolist():
        name = names[int(inverse[m])] if v3 else "?"
        problem.setdefault(m, f"no observation types for the system of satellite {name}")

    # The same satellite twice in one epoch.
    key = (epoch_of_line * max(len(sats), 1) + sat_of_line) * (int(part.max(initial=0)) + 1) + part
    valid_key = sat_of_line >= 0
    counts = np.bincount(key[valid_key])
    later = np.zeros(n_lines, dtype=bool)
    if counts.max(initial=0) > 1:  # rare: find the second and later occurrences in file order
        order = np.argsort(key, kind="stable")
        later[order[1:]] = (key[order][1:] == key[order][:-1]) & valid_key[order][1:]
    dup = np.flatnonzero(later)
    for m in dup.tolist():
        problem.setdefault(m, f"satellite {sats[sat_of_line[m]]} appears twice in one epoch")

    skipped = list(scan.skipped)
    usable = np.ones(n_lines, dtype=bool)
    if problem:
        if not lenient:
            m = min(problem, key=lambda j: report_at.get(j, line_no[j]))
            raise FileFormatError(path, int(report_at.get(m, line_no[m])), problem[m])
        for m, reason in problem.items():
            usable[m] = False
            skipped.append(SkippedLine(line=int(line_no[m]), reason=reason))

    n_s = len(out_sats)
    values = np.full((n_e, n_s, n_c), np.nan)
    lli_out = np.full((n_e, n_s, n_c), -1, dtype=np.int8)
    ssi_out = np.full((n_e, n_s, n_c), -1, dtype=np.int8)
    out_sat = out_col[sat_of_line[decode]]
    out_code = kept[code]
    put = (out_code >= 0) & (out_sat >= 0)[:, None] & ~blank & usable[decode, None]
    cell = (epoch_of_line[decode] * n_s + out_sat)[:, None] * n_c + out_code
    target = cell[put]
    if (scale != 1.0).any():
        value = value / scale[row[decode, None], col]
    values.reshape(-1)[target] = value[put]
    lli_out.reshape(-1)[target] = lli[put]
    ssi_out.reshape(-1)[target] = ssi[put]

    t_gps = _to_gps_rinex(np.asarray(scan.t_cal_s, dtype=float), header.time_system)
    t_events = _to_gps_rinex(np.asarray(scan.event_t_cal_s, dtype=float), header.time_system)
    events = tuple(
        Event(line=e.line, t_gps_s=float(t), flag=e.flag, records=e.records)
        for e, t in zip(scan.events, t_events, strict=True)
    )
    if not v3:  # RINEX 2: one list of types for every system in the file
        present = {s[0] for s in sats} or {header.system if header.system in SYSTEMS else "G"}
        types = segments[0].obs_types["G"]
        header = replace(header, obs_types={s: types for s in SYSTEMS if s in present})
    return Observations(
        path=fspath(path),
        header=header,
        t_gps_s=t_gps,
        epoch_flag=np.asarray(scan.flag, dtype=np.int8),
        clock_offset_s=np.asarray(scan.clock_s, dtype=float),
        sats=tuple(out_sats),
        codes=tuple(out_codes),
        values=values,
        lli=lli_out,
        ssi=ssi_out,
        events=events,
        skipped=tuple(sorted(skipped, key=lambda s: s.line)),
    )
