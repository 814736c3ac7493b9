"""The header of a RINEX observation file, and the observation types in force for its epochs.

:func:`parse_header` reads the header records (RINEX 2.11 table A1, RINEX 3.05 table A2) into an
:class:`~navtrack.gnss.observations.ObsHeader` and the initial :class:`ObsTypes`; header records
inside the data (epoch flags 3 and 4) may redefine the types for the epochs that follow
(:func:`redefined_types`).
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Sequence

import numpy as np

from navtrack._record import Record
from navtrack._typing import FloatArray, StrPath
from navtrack.errors import FileFormatError
from navtrack.gnss.observations import SYSTEMS, ObsHeader
from navtrack.timescale import calendar_gps_seconds, to_gps

__all__ = [
    "V2_EPOCH",
    "V2_EVENT_NO_TIME",
    "ObsTypes",
    "parse_header",
    "redefined_types",
    "sat_id",
    "to_gps_rinex",
]

# Time system of the epochs when TIME OF FIRST OBS leaves it blank (RINEX 3.05 table A2).
_DEFAULT_TIME_SYSTEM = {
    "G": "GPS", "M": "GPS", "S": "GPS", "R": "GLO", "E": "GAL", "C": "BDT", "J": "QZS", "I": "IRN",
}  # fmt: skip
_KNOWN_TIME_SYSTEMS = {"GPS", "GLO", "GAL", "BDT", "QZS", "IRN", "UTC", "TAI"}

V2_EPOCH = re.compile(rb" [ \d]\d [ \d]\d [ \d]\d [ \d]\d [ \d]\d[ \d.]{11}  [0-6][ \d]{2}\d")
"""A RINEX 2 epoch record: (1X,I2.2,4(1X,I2),F11.7,2X,I1,I3,...)."""
V2_EVENT_NO_TIME = re.compile(rb" {26}  [2-5][ \d]{2}\d")
"""A RINEX 2 event record (flags 2-5) whose time is blank."""


class ObsTypes(Record, eq=True):
    """Observation types in force for a stretch of epochs (header records may change them).

    Attributes
    ----------
    obs_types : dict
        Codes of each system, in the order of the fields of its data lines.
    scale : dict
        ``SYS / SCALE FACTOR`` of (system, code) pairs; the values written are the observations
        times this factor.
    """

    obs_types: dict[str, tuple[str, ...]]
    scale: dict[tuple[str, str], float]


class _HeaderParse:
    """What the header records read so far hold.

    A plain class, not a dataclass: a dataclass compiles its methods when the module is
    imported, a cost every ``navtrack pos`` start would pay.
    """

    __slots__ = (
        "comments", "current", "declared", "first_obs", "glonass_fcn", "info", "last_obs",
        "scale", "scale_current", "time_system", "types", "v3",
    )  # fmt: skip

    def __init__(self, v3: bool) -> None:
        self.v3 = v3
        self.info: dict[str, object] = {}
        self.comments: list[str] = []
        self.types: dict[str, list[str]] = {}
        self.declared: dict[str, tuple[int, int]] = {}  # system: (count, line)
        self.scale: dict[tuple[str, str], float] = {}
        self.glonass_fcn: dict[str, int] = {}
        self.time_system = ""
        self.first_obs: tuple[float, int] | None = None
        self.last_obs: tuple[float, int] | None = None
        self.current = ""  # system of the last observation types record
        self.scale_current: tuple[str, float] | None = None

    def record(self, path: StrPath, label: str, text: str, i: int) -> None:
        """Take header record ``label`` of line ``i`` (0-based)."""
        if label == "COMMENT":
            self.comments.append(text[:60].rstrip())
        elif label == "MARKER NAME":
            self.info["marker"] = text[:60].strip()
        elif label == "MARKER NUMBER":
            self.info["marker_number"] = text[:20].strip()
        elif label == "REC # / TYPE / VERS":
            self.info["receiver"] = _join_fields(text, (0, 20, 40, 60))
        elif label == "ANT # / TYPE":
            self.info["antenna"] = _join_fields(text, (0, 20, 40))
        elif label == "APPROX POSITION XYZ":
            self.info["approx_xyz_m"] = _three_floats(text)
        elif label == "ANTENNA: DELTA H/E/N":
            self.info["antenna_delta_hen_m"] = _three_floats(text)
        elif label == "INTERVAL":
            self.info["interval_s"] = float(text[:10])
        elif label == "LEAP SECONDS":
            self.info["leap_seconds"] = int(text[:6])
        elif label == "TIME OF FIRST OBS":
            self.time_system = text[48:51].strip()
            self.first_obs = (_header_time(text), i)
        elif label == "TIME OF LAST OBS":
            self.last_obs = (_header_time(text), i)
        elif label == ("SYS / # / OBS TYPES" if self.v3 else "# / TYPES OF OBSERV"):
            if self.v3 and text[:1].strip() and text[:1] not in SYSTEMS:
                raise FileFormatError(path, i + 1, f"unknown satellite system {text[:1]!r}")
            self.current = _types_record(text, i, self.v3, self.types, self.declared, self.current)
        elif label == "SYS / SCALE FACTOR" and self.v3:
            if text[:1].strip():
                self.scale_current = (text[:1], float(int(text[2:6])))
            if self.scale_current is None:
                raise ValueError("continuation line without a preceding system")
            sys, factor = self.scale_current
            for code in text[10:58].split() or self.types.get(sys, []):
                self.scale[(sys, code)] = factor
        elif label == "GLONASS SLOT / FRQ #":
            for k in range(8):
                sat = text[4 + 7 * k : 7 + 7 * k].strip()
                if sat:
                    number = int(text[8 + 7 * k : 10 + 7 * k])
                    self.glonass_fcn[sat_id(sat.encode(), blank_is_gps=False)] = number


def parse_header(
    path: StrPath, lines: Sequence[bytes], end: int, version: float, file_system: str
) -> tuple[ObsHeader, list[ObsTypes], int]:
    """Parse the header; returns it, the initial observation types and the first data line.

    Raises
    ------
    FileFormatError
        A malformed record, no ``END OF HEADER``, no or miscounted observation types, an
        unknown time system.
    """
    v3 = version >= 3
    state = _HeaderParse(v3)
    body = -1
    for i in range(end):
        text = lines[i].decode("ascii", "replace").rstrip()
        label = text[60:].strip()
        if label == "END OF HEADER":
            body = i + 1
            break
        if i > 0 and (
            (v3 and text.startswith(">")) or (not v3 and V2_EPOCH.match(lines[i])) or not label
        ):
            raise FileFormatError(
                path, i + 1, "header not terminated: no 'END OF HEADER' before this line"
            )
        try:
            state.record(path, label, text, i)
        except FileFormatError:
            raise
        except (ValueError, IndexError, KeyError) as exc:
            raise FileFormatError(path, i + 1, f"malformed {label!r} record ({exc})") from None
    if body < 0:
        raise FileFormatError(
            path, end, "header not terminated: no 'END OF HEADER' up to the end of the file"
        )
    return _header(path, state, body, version, file_system), [_types(state)], body


def _types(state: _HeaderParse) -> ObsTypes:
    return ObsTypes({s: tuple(c) for s, c in state.types.items()}, state.scale)


def _header(
    path: StrPath, state: _HeaderParse, body: int, version: float, file_system: str
) -> ObsHeader:
    """The header of the records read, after the checks that need all of them."""
    if not state.types:
        label = "SYS / # / OBS TYPES" if state.v3 else "# / TYPES OF OBSERV"
        raise FileFormatError(path, body, f"no {label!r} record in the header")
    _check_counts(path, state.types, state.declared, 0, name_system=True)
    time_system = state.time_system or _DEFAULT_TIME_SYSTEM.get(file_system, "GPS")
    if time_system not in _KNOWN_TIME_SYSTEMS:
        line = state.first_obs[1] + 1 if state.first_obs else body
        raise FileFormatError(path, line, f"unknown time system {time_system!r}")

    def gps_s(t: tuple[float, int] | None) -> float | None:
        return None if t is None else float(to_gps_rinex(np.array([t[0]]), time_system)[0])

    return ObsHeader(
        version=version,
        file_type="O",
        system=file_system,
        time_system=time_system,
        obs_types=_types(state).obs_types,
        comments=tuple(state.comments),
        first_obs_gps_s=gps_s(state.first_obs),
        last_obs_gps_s=gps_s(state.last_obs),
        glonass_fcn=state.glonass_fcn,
        **state.info,  # type: ignore[arg-type]
    )


def _types_record(
    text: str,
    k: int,
    v3: bool,
    types: dict[str, list[str]],
    declared: dict[str, tuple[int, int]],
    current: str,
) -> str:
    """Add the codes of one ``SYS / # / OBS TYPES`` (RINEX 3) or ``# / TYPES OF OBSERV``
    (RINEX 2, the one list of every system, kept under ``G``) record of line ``k``; returns
    the system the record continues (``current``) or starts."""
    if v3:
        if text[:1].strip():
            current = text[:1]
            if current not in SYSTEMS:
                raise ValueError(f"unknown satellite system {current!r}")
            declared[current] = (int(text[3:6]), k)
            types[current] = []
        elif not current:
            raise ValueError("continuation line without a preceding system")
        types[current] += text[7:60].split()
    else:
        if text[:6].strip():
            current = "G"
            declared[current] = (int(text[:6]), k)
            types[current] = []
        elif not current:
            raise ValueError("continuation line without a preceding count")
        types[current] += text[6:60].split()
    return current


def _check_counts(
    path: StrPath,
    types: dict[str, list[str]],
    declared: dict[str, tuple[int, int]],
    first_line: int,
    *,
    name_system: bool = False,
) -> None:
    """Each system's listed codes against the count its record announces."""
    for sys, (count, k) in declared.items():
        if len(types[sys]) != count:
            which = f" for {sys!r}" if name_system else ""
            raise FileFormatError(
                path,
                first_line + k + 1,
                f"{count} observation types announced{which}, {len(types[sys])} listed",
            )


def redefined_types(
    path: StrPath, records: Sequence[bytes], first_line: int, types: ObsTypes, v3: bool
) -> ObsTypes | None:
    """Observation types redefined by the header records of an epoch flag 3/4 record (None
    when they leave them as they are)."""
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
            current = _types_record(text, k, v3, new, declared, current)
        except ValueError as exc:
            raise FileFormatError(
                path, first_line + k + 1, f"malformed {label!r} ({exc})"
            ) from None
    _check_counts(path, new, declared, first_line)
    merged = dict(types.obs_types) if v3 else {}
    merged.update({s: tuple(c) for s, c in new.items()})
    return ObsTypes(merged, dict(types.scale))


def sat_id(raw: bytes, blank_is_gps: bool) -> str:
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


def to_gps_rinex(t_cal_s: FloatArray, time_system: str) -> FloatArray:
    """GPS seconds of calendar seconds in a RINEX time system.

    Time tags labelled GLO are UTC(SU), not Moscow time (RINEX 2.11 section 8.1, RINEX 3.05
    section 6.1); TAI = GPST + 19 s.
    """
    if time_system == "GLO":
        return to_gps(t_cal_s, "UTC")
    if time_system == "TAI":
        return t_cal_s - 19.0
    return to_gps(t_cal_s, time_system)


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
