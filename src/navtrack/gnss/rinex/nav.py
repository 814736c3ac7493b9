"""RINEX 2.x/3.x/4.x navigation (broadcast ephemeris) reader.

:func:`read_nav` turns a RINEX navigation file into a :class:`NavData`: header ionosphere
parameters, time-system corrections and leap seconds, and one :class:`pandas.DataFrame` of
broadcast records per satellite system, in SI units with times converted to GPS seconds.

Formats read: RINEX 2.xx GPS (``N``), GLONASS (``G``) and SBAS (``H``) navigation files and
RINEX 3.xx navigation files, single-system or mixed, with GPS, QZSS, Galileo (I/NAV and F/NAV),
BeiDou, GLONASS, SBAS and NavIC/IRNSS records. Fields are cut at their fixed columns (so fields
that touch, ``.745058D-08-.603921D-08``, are read correctly), Fortran ``D`` exponents are
accepted, RINEX 2 two-digit years map to 1980-2079, and blank or missing trailing fields are
NaN (integer fields: -1).

Every record of the file is returned, including ephemerides whose time of clock lies after
the observations they will serve ("future" ephemerides) and duplicate records from different
data sources (Galileo I/NAV and F/NAV): selecting among them is the ephemeris module's job.

References
----------
RINEX 2.11 (IGS/RTCM-SC104, 2012), tables A4, A11, A12, A16; RINEX 3.05 (IGS/RTCM-SC104, 2020),
section 6 and tables A5-A23. IS-GPS-200N 20.3.3.4; Galileo OS SIS ICD 2.0 5.1; BDS-SIS-ICD-B1I
3.0 5.2.4; GLONASS ICD 5.1 4.4.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from os import fspath
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import numpy as np

from navtrack._record import Record
from navtrack._typing import FloatArray, StrPath
from navtrack.errors import FileFormatError
from navtrack.gnss.observations import SkippedLine
from navtrack.gnss.rinex._io import ends_inside_field, read_bytes, sniff
from navtrack.timescale import (
    BDS_WEEK_OFFSET,
    BDT_MINUS_GPST_S,
    SECONDS_PER_WEEK,
    calendar_gps_seconds,
    to_datetime64,
    utc_to_gps,
)

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["KM_FIELDS", "RECORD_FIELDS", "NavData", "read_nav", "toe_gps_s"]

_NAN = math.nan

# Field names of each record type, in file order: the three clock fields of the first line,
# then four fields per "BROADCAST ORBIT" line. ``None`` marks spare fields.
_GPS_FIELDS: tuple[str | None, ...] = (
    "af0", "af1", "af2",
    "iode", "crs", "deltan", "m0",
    "cuc", "e", "cus", "sqrta",
    "toe_sow", "cic", "omega0", "cis",
    "i0", "crc", "omega", "omegadot",
    "idot", "codes_l2", "week", "l2p_flag",
    "sva_m", "svh", "tgd", "iodc",
    "tot_sow", "fit_h", None, None,
)  # fmt: skip
_GAL_FIELDS: tuple[str | None, ...] = (
    *_GPS_FIELDS[:19],
    "idot", "data_source", "week", None,
    "sva_m", "svh", "bgd_e5a", "bgd_e5b",
    "tot_sow", None, None, None,
)  # fmt: skip
_BDS_FIELDS: tuple[str | None, ...] = (
    *_GPS_FIELDS[:19],
    "idot", None, "week", None,
    "sva_m", "svh", "tgd1", "tgd2",
    "tot_sow", "aodc", None, None,
)  # fmt: skip
_IRN_FIELDS: tuple[str | None, ...] = (
    *_GPS_FIELDS[:19],
    "idot", None, "week", None,
    "sva_m", "svh", "tgd", None,
    "tot_sow", None, None, None,
)  # fmt: skip
_GLO_FIELDS: tuple[str | None, ...] = (
    "taun", "gamman", "tk_s",
    "x_m", "vx_mps", "ax_mps2", "svh",
    "y_m", "vy_mps", "ay_mps2", "freq_num",
    "z_m", "vz_mps", "az_mps2", "age_d",
    # RINEX 3.05 optional fifth line
    "status_flags", "delta_taun_s", "urai", "health_flags",
)  # fmt: skip
_SBAS_FIELDS: tuple[str | None, ...] = (
    "af0", "af1", "tot_sow",
    "x_m", "vx_mps", "ax_mps2", "svh",
    "y_m", "vy_mps", "ay_mps2", "ura_m",
    "z_m", "vz_mps", "az_mps2", "iodn",
)  # fmt: skip

RECORD_FIELDS: Mapping[str, tuple[str | None, ...]] = MappingProxyType(
    {
        "G": _GPS_FIELDS,
        "J": _GPS_FIELDS,
        "E": _GAL_FIELDS,
        "C": _BDS_FIELDS,
        "I": _IRN_FIELDS,
        "R": _GLO_FIELDS,
        "S": _SBAS_FIELDS,
    }
)
"""Field names of each system's records, in file order: the three clock fields of the first
line, then four fields per ``BROADCAST ORBIT`` line; ``None`` marks spare fields. GLONASS and
SBAS state vectors are in m, m/s, m/s^2 here, in km, km/s, km/s^2 in the file
(:data:`KM_FIELDS`)."""

# Number of lines of a complete record, and the most a record may have (GLONASS in 3.05).
_N_LINES = {"G": 8, "J": 8, "E": 8, "C": 8, "I": 8, "R": 4, "S": 4}
_MAX_LINES = {**_N_LINES, "R": 5}
_KEPLER = "GJECI"
KM_FIELDS = frozenset(
    {"x_m", "y_m", "z_m", "vx_mps", "vy_mps", "vz_mps", "ax_mps2", "ay_mps2", "az_mps2"}
)
"""GLONASS and SBAS fields written in km (km/s, km/s^2) in RINEX and held in m here."""
_INT_FIELDS = {
    "iode", "iodc", "week", "svh", "codes_l2", "l2p_flag", "data_source", "aodc", "freq_num",
    "age_d", "status_flags", "urai", "health_flags", "iodn",
}  # fmt: skip
_STATE_ORDER = {
    c: k + 1
    for k, c in enumerate(
        ("x_m", "y_m", "z_m", "vx_mps", "vy_mps", "vz_mps", "ax_mps2", "ay_mps2", "az_mps2")
    )
}
_STATE_ORDER.update({c: 20 for c in ("svh", "freq_num", "age_d", "ura_m", "iodn")})
_STATE_ORDER.update({c: 30 for c in ("status_flags", "delta_taun_s", "urai", "health_flags")})
_TIME_SYSTEM = {"G": "GPS", "J": "GPS", "E": "GPS", "I": "GPS", "S": "GPS", "C": "BDT", "R": "UTC"}
# RINEX 2 file types; ``E`` is the Galileo type of the unofficial RINEX 2.12 (teqc).
_RINEX2_SYSTEM = {"N": "G", "G": "R", "H": "S", "E": "E"}
_D_TO_E = str.maketrans("Dd", "Ee")


class NavData(Record):
    """Broadcast navigation data of one RINEX navigation file.

    Attributes
    ----------
    path : str
        Source file.
    version : float
        RINEX version (2.10, 3.04, ...).
    file_type : str
        RINEX file type letter (``N``; RINEX 2 ``G`` GLONASS, ``H`` SBAS).
    system : str
        System letter of the file header (``M`` mixed).
    iono : mapping of str to ndarray
        Ionosphere parameters from the header, read-only arrays: ``GPSA``/``GPSB`` (Klobuchar
        alpha0-3 in s, s/semicircle, ...; beta0-3 in s, ...; from RINEX 2 ``ION ALPHA``/``ION
        BETA`` or RINEX 3 ``IONOSPHERIC CORR``), ``GAL`` (NeQuick ai0-ai2), ``QZSA``/``QZSB``,
        ``BDSA``/``BDSB``, ``IRNA``/``IRNB`` as present. Units as broadcast (ICD scaling
        applied, i.e. the values as written).
    time_corrections : mapping of str to tuple
        Time-system corrections ``(a0_s, a1_s_per_s, t_ref_sow, week, source, utc_id)`` keyed by
        the RINEX 3 type (``GPUT``, ``GAUT``, ``GPGA``, ``BDUT``, ``GLUT``, ``QZGP`` ...). RINEX 2
        ``DELTA-UTC: A0,A1,T,W`` becomes ``GPUT``, ``D-UTC A0,A1,T,W,S,U`` (SBAS) ``SBUT`` and
        GLONASS ``CORR TO SYSTEM TIME`` ``GLUT`` with ``a0_s`` = -TauC and the reference date's
        (year, month, day) in place of (t_ref_sow, week, source). Missing fields are ``None``.
    leap_seconds : int or None
        GPS - UTC from ``LEAP SECONDS`` (current value), when present.
    tables : mapping of str to mapping of str to ndarray
        One table per system letter present (``G``, ``R``, ``E``, ``C``, ``J``, ``S``, ``I``)
        as read-only NumPy columns of equal length (so that positioning needs no pandas;
        :attr:`ephemerides` gives the same tables as DataFrames), one row per broadcast record,
        rows sorted by (``sat``, ``toc_gps_s``, file order). Every record is kept (duplicates,
        I/NAV and F/NAV, future ephemerides).
        Float columns are NaN and integer columns (int64) -1 where the file leaves a field
        blank. Columns:

        *All systems*: ``sat`` (str, ``G05``; SBAS as written in RINEX, PRN - 100),
        ``toc_gps_s`` (time of clock / reference epoch in GPS seconds, converted from the
        system's time scale: BDT + 14 s; GLONASS UTC(SU) + leap seconds), ``line`` (1-based
        line of the record's first line).

        *Kepler systems* ``G``, ``J``, ``E``, ``C``, ``I`` (IS-GPS-200 names and units):
        ``af0`` (s), ``af1`` (s/s), ``af2`` (s/s²), ``iode`` (GPS/QZSS IODE, Galileo IODnav,
        BeiDou AODE, NavIC IODEC), ``crs``, ``crc`` (m), ``deltan`` (rad/s), ``m0``, ``omega0``,
        ``i0``, ``omega`` (rad), ``cuc``, ``cus``, ``cic``, ``cis`` (rad), ``e``, ``sqrta``
        (m^0.5), ``toe_sow`` (s of week, as written), ``week`` (as written: GPS week for G, J,
        E — RINEX aligns the Galileo week to GPS — and I; BDT week for C), ``toe_gps_s`` (full
        GPS seconds of toe: week rollovers and toe/toc week mismatches resolved against toc;
        BDT converted to GPST), ``omegadot``, ``idot`` (rad/s), ``svh`` (health as written),
        ``sva_m`` (URA/SISA/accuracy in m as written), ``tot_sow`` (transmission time, s of
        week as written), and by system:
        G/J ``tgd`` (s), ``iodc``, ``codes_l2``, ``l2p_flag``, ``fit_h`` (fit interval in h as
        written; QZSS in RINEX 3 writes the fit-interval flag 0/1 here);
        E ``bgd_e5a``, ``bgd_e5b`` (s, E5a/E1 and E5b/E1), ``data_source`` (bits 0/2 I/NAV,
        bit 1 F/NAV, bits 8/9 clock for E5a/E5b);
        C ``tgd1``, ``tgd2`` (s, B1/B3 and B2/B3), ``aodc``; I ``tgd`` (s).

        *GLONASS* ``R``: ``taun`` (s; the clock bias as the file gives it, i.e. **-TauN**),
        ``gamman`` (+GammaN), ``tk_s`` (message frame time as written: RINEX 2 seconds of the
        UTC day, RINEX 3 seconds of the UTC week), ``x_m``, ``y_m``, ``z_m`` (PZ-90, m),
        ``vx_mps``..., ``ax_mps2``... (lunisolar accelerations; converted from km), ``svh``,
        ``freq_num`` (-7..+13), ``age_d`` (days), and from RINEX 3.05 optional line 5:
        ``status_flags``, ``delta_taun_s``, ``urai``, ``health_flags``.

        *SBAS* ``S``: ``af0`` (s), ``af1`` (s/s), ``tot_sow``, ``x_m`` ... ``az_mps2`` (m),
        ``svh``, ``ura_m``, ``iodn``.
    skipped : tuple of SkippedLine
        Records skipped in lenient reading (first line of each and why); empty otherwise.
    records_not_read : mapping of str to int
        RINEX 4: records of the types not read, counted by record and message type
        (``"EPH CNAV"``, ``"EPH CNV2"``, ``"STO CNVX"``, ``"EOP CNVX"``, ``"ION CNVX"``, ...);
        empty for RINEX 2/3.

    References
    ----------
    RINEX 2.11 tables A4, A11, A16; RINEX 3.05 tables A5-A23.
    """

    path: str
    version: float
    file_type: str
    system: str
    iono: Mapping[str, FloatArray]
    time_corrections: Mapping[str, tuple[Any, ...]]
    leap_seconds: int | None
    tables: Mapping[str, Mapping[str, np.ndarray]]
    skipped: tuple[SkippedLine, ...] = ()
    comments: tuple[str, ...] = ()
    records_not_read: Mapping[str, int] = MappingProxyType({})

    def __post_init__(self) -> None:
        for arr in self.iono.values():
            arr.flags.writeable = False
        object.__setattr__(self, "iono", MappingProxyType(dict(self.iono)))
        object.__setattr__(self, "time_corrections", MappingProxyType(dict(self.time_corrections)))
        object.__setattr__(self, "records_not_read", MappingProxyType(dict(self.records_not_read)))
        frozen = {}
        for letter, columns in self.tables.items():
            for arr in columns.values():
                arr.flags.writeable = False
            frozen[letter] = MappingProxyType(dict(columns))
        object.__setattr__(self, "tables", MappingProxyType(frozen))

    @property
    def ephemerides(self) -> Mapping[str, pd.DataFrame]:
        """:attr:`tables` as one pandas DataFrame per system letter (built on each access)."""
        import pandas as pd  # only here: reading and positioning need no pandas

        return MappingProxyType(
            {letter: pd.DataFrame(dict(columns)) for letter, columns in self.tables.items()}
        )

    @property
    def systems(self) -> str:
        """System letters with at least one record, in ``GRECJSI`` order."""
        return "".join(s for s in "GRECJSI" if s in self.tables)

    def summary(self) -> dict[str, Any]:
        """What the file holds, as plain Python values (for ``navtrack rinex info``)."""
        tocs = [c["toc_gps_s"] for c in self.tables.values() if len(c["toc_gps_s"])]
        span: list[str] = []
        if tocs:
            t = np.concatenate(tocs)
            span = [str(to_datetime64(t.min()))[:19], str(to_datetime64(t.max()))[:19]]
        return {
            "path": self.path,
            "version": self.version,
            "file_type": self.file_type,
            "system": self.system,
            "records_per_system": {s: len(self.tables[s]["sat"]) for s in self.systems},
            "sats_per_system": {s: len(np.unique(self.tables[s]["sat"])) for s in self.systems},
            "sat_ids": {s: np.unique(self.tables[s]["sat"]).tolist() for s in self.systems},
            "iono": {k: [float(v) for v in a] for k, a in self.iono.items()},
            "time_corrections": {k: list(v) for k, v in self.time_corrections.items()},
            "leap_seconds": self.leap_seconds,
            "toc_span_gps": span,
            "skipped_records": len(self.skipped),
            "records_not_read": dict(self.records_not_read),
        }


def read_nav(path: StrPath, *, systems: str | None = None, lenient: bool = False) -> NavData:
    """Read a RINEX 2.x/3.x/4.x navigation file.

    RINEX 4 files are read through their record headers (``> EPH G01 LNAV``): the ephemeris
    messages with a RINEX 3 layout (GPS/QZSS/NavIC LNAV, Galileo I/NAV and F/NAV, BeiDou D1/D2,
    GLONASS FDMA, SBAS) become the same tables as a RINEX 3 file's; the broadcast Klobuchar
    and NeQuick parameters of ``> ION`` records fill :attr:`NavData.iono`; every other record
    (CNAV, CNV1-3, STO, EOP, other ION) is counted in :attr:`NavData.records_not_read`.

    Parameters
    ----------
    path : str or path-like
        Navigation file, plain or compressed (gzip, bzip2, ``.Z``).
    systems : str, optional
        System letters to decode (e.g. ``"GE"``); the records of the other systems are passed
        over unread (a daily multi-GNSS file holds ten times more of them than of GPS). Default:
        every system.
    lenient : bool
        When true, a damaged record (unreadable number, unknown system letter, missing lines)
        is skipped and listed in :attr:`NavData.skipped`; when false (default) it raises.

    Returns
    -------
    NavData
        See :class:`NavData` for the table schema.

    Raises
    ------
    FileFormatError
        Empty file, not a RINEX navigation file, unsupported version, missing ``END OF
        HEADER``, an unreadable header field, or (strict reading) a damaged record; the message
        names the file and line.
    """
    data = read_bytes(path)
    kind = sniff(path, data)
    if kind.format != "rinex" or kind.file_type not in "NGHE" or not kind.file_type.strip():
        raise FileFormatError(path, 1, f"not a RINEX navigation file (type {kind.file_type!r})")
    lines = data.decode("ascii", "replace").splitlines()
    header = _parse_header(path, lines)
    not_read: dict[str, int] = {}
    origin: list[int] | None = None  # RINEX 4: the file line of each kept line
    if kind.version >= 4:
        lines, origin, not_read = _rinex4_records(path, lines, header)
    v2 = kind.version < 3
    # RINEX 2 type letters name the system (some RINEX 3.0x writers keep them)
    system = kind.system if not v2 and kind.file_type == "N" else _RINEX2_SYSTEM[kind.file_type]
    if v2 and system == "E" and "GPSA" in header.iono:  # RINEX 2.12 Galileo: ION ALPHA = ai0-2
        header.iono["GAL"] = header.iono.pop("GPSA")[:3]
    layout = _Layout(v2, system, systems, lenient)
    groups, skipped = _records(path, data, lines, header.end, layout, origin)
    return NavData(
        path=fspath(path),
        version=kind.version,
        file_type=kind.file_type,
        system=system,
        iono=header.iono,
        time_corrections=header.time_corrections,
        leap_seconds=header.leap_seconds,
        tables=_tables(groups),
        skipped=tuple(skipped),
        comments=tuple(header.comments),
        records_not_read=not_read,
    )


class _Layout(Record):
    """How the records of a file are read: RINEX 2 or later, the system of a single-system
    file, the systems asked for (None: all), lenient reading."""

    v2: bool
    system: str
    systems: str | None
    lenient: bool


def _records(
    path: StrPath,
    data: bytes,
    lines: list[str],
    body: int,
    layout: _Layout,
    origin: list[int] | None,
) -> tuple[dict[str, tuple[_Group, FloatArray]], list[SkippedLine]]:
    """The records of ``lines[body:]`` by system, and the lines skipped; with ``origin`` (RINEX
    4), line numbers are mapped back to the file's."""
    # 3X (RINEX 2) or 4X (RINEX 3) then D19.12 fields; the satellite/epoch line is on that grid
    cut = len(lines) > body and ends_inside_field(data, 3 if layout.v2 else 4, 19, (0,))
    reason = "record line cut in the middle of a field by the end of the file"
    if cut:
        if not layout.lenient:
            raise FileFormatError(path, len(lines), reason)
        lines.pop()
    try:
        groups, skipped = _parse_records(
            path, lines, body, layout.v2, layout.system, layout.lenient, layout.systems
        )
    except FileFormatError as exc:
        if origin is None or exc.line is None:
            raise
        raise FileFormatError(path, origin[exc.line - 1] + 1, exc.message) from None
    if cut:
        skipped.append(SkippedLine(len(lines) + 1, reason))
    if origin is not None:
        for g, _ in groups.values():
            g.lines = [origin[k - 1] + 1 for k in g.lines]
        skipped = [SkippedLine(origin[sk.line - 1] + 1, sk.reason) for sk in skipped]
    return groups, skipped


# RINEX 4 ephemeris messages read (the RINEX 3 record layouts: LNAV of GPS, QZSS and NavIC,
# Galileo I/NAV and F/NAV, BeiDou D1/D2, GLONASS FDMA, SBAS); CNAV, CNV1-3 and the STO and
# EOP records are counted in NavData.records_not_read.
_V4_EPHEMERIS = frozenset({"LNAV", "INAV", "FNAV", "D1", "D2", "FDMA", "SBAS"})
# RINEX 4 ionosphere records read into NavData.iono (RINEX 4.00 table A32/A33): key per system
# letter and message, and how many values they hold.
_V4_IONO = {
    ("G", "LNAV"): (("GPSA", "GPSB"), 8),
    ("J", "LNAV"): (("QZSA", "QZSB"), 8),
    ("C", "D1D2"): (("BDSA", "BDSB"), 8),
    ("E", "IFNV"): (("GAL",), 3),
}


def _rinex4_records(
    path: StrPath, lines: list[str], header: _Header
) -> tuple[list[str], list[int], dict[str, int]]:
    """The RINEX 3-layout lines of a RINEX 4 file's ephemeris records (``> EPH`` record
    headers removed), the file line of each kept line, and the records not read by type.
    ``> ION`` records of the broadcast Klobuchar and NeQuick parameters go into
    ``header.iono`` (the first of each, as RINEX 3's header holds one)."""
    kept = lines[: header.end]
    origin = list(range(header.end))
    not_read: dict[str, int] = {}
    i, n = header.end, len(lines)
    while i < n:
        line = lines[i]
        if not line.startswith(">"):  # outside a record: left for the record parser to judge
            kept.append(line)
            origin.append(i)
            i += 1
            continue
        words = line[1:].split()
        kind = " ".join(words[:1] + words[2:3]) if len(words) >= 3 else line[1:].strip()
        j = i + 1
        while j < n and not lines[j].startswith(">"):
            j += 1
        if len(words) >= 3 and words[0] == "EPH" and words[2] in _V4_EPHEMERIS:
            kept.extend(lines[i + 1 : j])
            origin.extend(range(i + 1, j))
        elif len(words) >= 3 and words[0] == "ION" and (words[1][:1], words[2]) in _V4_IONO:
            keys, count = _V4_IONO[(words[1][:1], words[2])]
            text = " ".join([lines[i + 1][23:], *lines[i + 2 : j]]) if j > i + 1 else ""
            vals = _tokens(path, i + 2, text, count, f"ION {words[1]} {words[2]}")
            for k, key in enumerate(keys):
                header.iono.setdefault(key, np.array(vals[4 * k : 4 * k + 4]))
        else:
            not_read[kind] = not_read.get(kind, 0) + 1
        i = j
    return kept, origin, not_read


class _Header:
    """What the header records hold (a plain class, as :class:`_Group`)."""

    __slots__ = ("comments", "end", "iono", "leap_seconds", "time_corrections")

    def __init__(self) -> None:
        self.end = 0  # index of the first line after END OF HEADER
        self.iono: dict[str, FloatArray] = {}
        self.time_corrections: dict[str, tuple[Any, ...]] = {}
        self.leap_seconds: int | None = None
        self.comments: list[str] = []


def _parse_header(path: StrPath, lines: list[str]) -> _Header:
    # Numbers in header records are read as tokens rather than at their nominal columns:
    # writers disagree on the columns (GPSTk puts DELTA-UTC one column right) and fields may
    # touch (``.745058D-08-.603921D-08``); the token pattern splits both correctly.
    h = _Header()
    for i, line in enumerate(lines):
        n = i + 1
        label = line[60:80].strip()
        if label == "END OF HEADER":
            h.end = n
            return h
        if label == "COMMENT":
            h.comments.append(line[:60].rstrip())
        elif label in ("ION ALPHA", "ION BETA"):  # RINEX 2: 2X,4D12.4
            key = "GPSA" if label == "ION ALPHA" else "GPSB"
            h.iono[key] = np.array(_tokens(path, n, line[:60], 4, label))
        elif label == "IONOSPHERIC CORR":  # RINEX 3: A4,1X,4D12.4,1X,A1,1X,I2
            key = line[:4].strip()
            vals = _tokens(path, n, line[4:54], 4, f"IONOSPHERIC CORR {key}")
            if key == "GAL":
                vals = vals[:3]
            h.iono.setdefault(key, np.array(vals))  # BDS may repeat per time mark: keep first
        elif label in ("DELTA-UTC: A0,A1,T,W", "D-UTC A0,A1,T,W,S,U"):
            # RINEX 2 GPS 3X,2D19.12,2I9; SBAS adds 1X,A5,1X,I2 (beyond column 60: ignored)
            key = "GPUT" if label.startswith("DELTA") else "SBUT"
            a0, a1, t, w = _tokens(path, n, line[:59], 4, label)
            h.time_corrections[key] = (a0, a1, _int(t), _int(w), None, None)
        elif label == "CORR TO SYSTEM TIME":  # RINEX 2 GLONASS: 3I6,3X,D19.12
            y, m, d, tauc = _tokens(path, n, line[:60], 4, label)
            h.time_corrections["GLUT"] = (tauc, None, _int(y), _int(m), _int(d), None)
        elif label == "TIME SYSTEM CORR":  # RINEX 3: A4,1X,D17.10,D16.9,1X,I6,1X,I4,1X,A5,1X,I2
            key = line[:4].strip()
            a0, a1, t, w = _tokens(path, n, line[4:50], 4, f"TIME SYSTEM CORR {key}")
            u = _tokens(path, n, line[57:60], 1, f"TIME SYSTEM CORR {key} UTC id")[0]
            h.time_corrections[key] = (
                a0,
                a1,
                _int(t),
                _int(w),
                line[51:56].strip() or None,
                _int(u),
            )
        elif label == "LEAP SECONDS":
            h.leap_seconds = _int(_tokens(path, n, line[:6], 1, label)[0])
    raise FileFormatError(path, len(lines), "no END OF HEADER record (header not terminated)")


_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[DdEe][+-]?\d+)?")


def _tokens(path: StrPath, lineno: int, text: str, count: int, what: str) -> list[float]:
    """The first ``count`` numbers of a header field (NaN for missing trailing ones)."""
    found = _NUMBER.findall(text)
    if _NUMBER.sub("", text).strip():
        raise FileFormatError(path, lineno, f"unreadable {what} {text.strip()!r}")
    vals = [float(t.translate(_D_TO_E)) for t in found[:count]]
    return vals + [_NAN] * (count - len(vals))


def _int(v: float) -> int | None:
    return None if math.isnan(v) else round(v)


class _Group:
    """Records of one system: header data of each record and the text of its fields.

    A plain class, not a dataclass: a dataclass compiles its methods when the module is
    imported, a cost every ``navtrack pos`` start would pay.
    """

    __slots__ = ("lines", "n_lines", "sats", "starts", "t_cal")

    def __init__(self) -> None:
        self.sats: list[str] = []
        self.lines: list[int] = []  # 1-based line of the first line
        self.n_lines: list[int] = []
        self.t_cal: list[float] = []  # epoch as calendar seconds, as written
        self.starts: list[int] = []  # 0-based index of the first line


def _parse_records(
    path: StrPath,
    lines: list[str],
    start: int,
    v2: bool,
    file_system: str,
    lenient: bool,
    systems: str | None = None,
) -> tuple[dict[str, tuple[_Group, FloatArray]], list[SkippedLine]]:
    # Record boundaries: a record's first line has the satellite in columns 1-3 (RINEX 3: a
    # system letter in column 1; RINEX 2: the PRN in columns 1-2); continuation lines start
    # with 3 (RINEX 2) or 4 (RINEX 3) blanks.
    n = len(lines)
    while n > start and not lines[n - 1].strip():
        n -= 1
    starts = [i for i in range(start, n) if (lines[i][:3].strip() if v2 else lines[i][:1].strip())]
    skipped: list[SkippedLine] = []
    if start < n and (not starts or starts[0] != start):
        msg = "navigation data does not start with a satellite/epoch line"
        if not lenient:
            raise FileFormatError(path, start + 1, msg)
        skipped.append(SkippedLine(start + 1, msg))
    groups: dict[str, _Group] = {}
    records = list(zip(starts, [*starts[1:], n], strict=False))  # none without starts
    if systems is not None:
        wanted = set(systems.upper())
        records = [r for r in records if (file_system if v2 else lines[r[0]][0]) in wanted]
    for i0, i1 in records:
        try:
            sys_letter, sat, n_lines, t_cal = _record_head(path, lines, i0, i1, v2, file_system)
        except FileFormatError as exc:
            if not lenient:
                raise
            skipped.append(SkippedLine(i0 + 1, exc.message))
            continue
        g = groups.setdefault(sys_letter, _Group())
        g.sats.append(sat)
        g.lines.append(i0 + 1)
        g.n_lines.append(n_lines)
        g.t_cal.append(t_cal)
        g.starts.append(i0)
    out: dict[str, tuple[_Group, FloatArray]] = {}
    for sys_letter, g in groups.items():
        try:
            values = _fields_fast(lines, g, sys_letter, v2)
        except ValueError:  # find the damaged field, record by record
            g, values = _fields_slow(path, lines, g, sys_letter, v2, lenient, skipped)
        if g.sats:
            out[sys_letter] = (g, values)
    skipped.sort(key=lambda sk: sk.line)
    return out, skipped


def _record_head(
    path: StrPath, lines: list[str], i0: int, i1: int, v2: bool, file_system: str
) -> tuple[str, str, int, float]:
    """System, satellite id, number of lines and epoch (calendar seconds) of one record."""
    first = lines[i0]
    lineno = i0 + 1
    if v2:
        sys_letter = file_system
        prn_text, epoch_text, c0 = first[0:2], first[3:22], 22
    else:
        sys_letter = first[0]
        prn_text, epoch_text, c0 = first[1:3], first[4:23], 23
    if sys_letter not in RECORD_FIELDS:
        raise FileFormatError(path, lineno, f"unknown satellite system letter {sys_letter!r}")
    n_lines = i1 - i0
    # Blank lines after the last expected one (some writers pad) are ignored.
    while n_lines > _N_LINES[sys_letter] and not lines[i0 + n_lines - 1].strip():
        n_lines -= 1
    if n_lines < _N_LINES[sys_letter]:
        raise FileFormatError(
            path,
            lineno,
            f"truncated {sys_letter} record: {n_lines} of {_N_LINES[sys_letter]} lines",
        )
    if n_lines > _MAX_LINES[sys_letter]:
        raise FileFormatError(
            path,
            i0 + _MAX_LINES[sys_letter] + 1,
            f"{sys_letter} record has {n_lines} lines, expected {_N_LINES[sys_letter]} "
            "(unexpected continuation line)",
        )
    try:
        prn = int(prn_text)
        parts = epoch_text.split()
        if len(parts) != 6:
            raise ValueError
        year, month, day, hour, minute = (int(p) for p in parts[:5])
        sec = float(parts[5])
        if year < 100:  # RINEX 2: 80-99 -> 19xx, 00-79 -> 20xx
            year += 2000 if year < 80 else 1900
        t_cal = calendar_gps_seconds(year, month, day, hour, minute, sec)
    except ValueError:
        raise FileFormatError(
            path, lineno, f"unreadable satellite/epoch {first[:c0].strip()!r}"
        ) from None
    return sys_letter, f"{sys_letter}{prn:02d}", n_lines, t_cal


def _record_text(lines: list[str], i0: int, n_lines: int, max_lines: int, v2: bool) -> str:
    """The fields of one record as one fixed-width string, 19 characters per field."""
    c0, co = (22, 3) if v2 else (23, 4)
    parts = [lines[i0][c0 : c0 + 57].ljust(57)]
    parts.extend(lines[i0 + j][co : co + 76].ljust(76) for j in range(1, n_lines))
    parts.append(" " * (76 * (max_lines - n_lines)))
    return "".join(parts)


def _fields_fast(lines: list[str], g: _Group, sys_letter: str, v2: bool) -> FloatArray:
    """All fields of a system's records at once: (n_records, n_fields), NaN for blanks.

    Raises ValueError when any field is not a number (the caller then locates it).
    """
    max_lines = _MAX_LINES[sys_letter]
    n_fields = 3 + 4 * (max_lines - 1)
    text = "".join(
        _record_text(lines, i0, nl, max_lines, v2)
        for i0, nl in zip(g.starts, g.n_lines, strict=True)
    )
    buf = bytearray(text.translate(_D_TO_E).encode("ascii", "replace"))
    chars = np.frombuffer(buf, dtype=np.uint8).reshape(-1, 19)
    blank = (chars == 32).all(axis=1)
    chars[blank, :3] = np.frombuffer(b"nan", dtype=np.uint8)
    return chars.view("S19").reshape(len(g.sats), n_fields).astype(float)


def _fields_slow(
    path: StrPath,
    lines: list[str],
    g: _Group,
    sys_letter: str,
    v2: bool,
    lenient: bool,
    skipped: list[SkippedLine],
) -> tuple[_Group, FloatArray]:
    """Field by field, to name the damaged one (strict) or skip its record (lenient)."""
    max_lines = _MAX_LINES[sys_letter]
    names = RECORD_FIELDS[sys_letter]
    keep = _Group()
    rows: list[list[float]] = []
    for k, (i0, nl) in enumerate(zip(g.starts, g.n_lines, strict=True)):
        text = _record_text(lines, i0, nl, max_lines, v2).translate(_D_TO_E)
        row: list[float] = []
        try:
            for m in range(len(text) // 19):
                s = text[19 * m : 19 * (m + 1)].strip()
                try:
                    row.append(float(s) if s else _NAN)
                except ValueError:
                    line = i0 + (0 if m < 3 else (m - 3) // 4 + 1) + 1
                    raise FileFormatError(
                        path,
                        line,
                        f"unreadable {names[m] or 'spare field'} {s!r} in {g.sats[k]} record",
                    ) from None
        except FileFormatError as exc:
            if not lenient:
                raise
            skipped.append(SkippedLine(g.lines[k], exc.message))
            continue
        rows.append(row)
        for attr in ("sats", "lines", "n_lines", "t_cal", "starts"):
            getattr(keep, attr).append(getattr(g, attr)[k])
    return keep, np.array(rows, dtype=float).reshape(len(rows), 3 + 4 * (max_lines - 1))


def toe_gps_s(
    sys_letter: str, week: FloatArray, toe_sow: FloatArray, toc_gps_s: FloatArray
) -> FloatArray:
    """Full GPS seconds of toe from the written week, resolved against toc.

    The written week may be rolled over (some writers give GPS weeks modulo 1024) or be the
    week of toc rather than of toe near a week boundary; toe lies within half a week of toc.
    """
    if sys_letter == "C":
        t = (week + BDS_WEEK_OFFSET) * SECONDS_PER_WEEK + toe_sow - BDT_MINUS_GPST_S
    else:
        t = week * SECONDS_PER_WEEK + toe_sow
        rollover = 1024 * SECONDS_PER_WEEK
        t = t + np.round((toc_gps_s - t) / rollover) * rollover
    return t + np.round((toc_gps_s - t) / SECONDS_PER_WEEK) * SECONDS_PER_WEEK


def _tables(groups: dict[str, tuple[_Group, FloatArray]]) -> dict[str, dict[str, np.ndarray]]:
    tables: dict[str, dict[str, np.ndarray]] = {}
    for sys_letter in "GRECJSI":
        if sys_letter not in groups:
            continue
        g, values = groups[sys_letter]
        all_names = RECORD_FIELDS[sys_letter]
        cols: dict[str, Any] = {
            name: values[:, k] for k, name in enumerate(all_names) if name is not None
        }
        names = [c for c in all_names if c is not None]
        if sys_letter == "R" and max(g.n_lines) < 5:
            names = names[:15]  # no record has the optional RINEX 3.05 fifth line
        if sys_letter in "RS":  # state vector components together, as in the docstring
            names = sorted(names, key=lambda c: _STATE_ORDER.get(c, 0))
            for name in KM_FIELDS:
                cols[name] = cols[name] * 1000.0
        t_cal = np.array(g.t_cal, dtype=float)
        ts = _TIME_SYSTEM[sys_letter]
        if ts == "BDT":
            toc = t_cal - BDT_MINUS_GPST_S
        elif ts == "UTC":
            toc = utc_to_gps(t_cal)
        else:
            toc = t_cal
        if sys_letter in _KEPLER:
            k = names.index("week") + 1
            names = [*names[:k], "toe_gps_s", *names[k:]]
            cols["toe_gps_s"] = toe_gps_s(sys_letter, cols["week"], cols["toe_sow"], toc)
        for name in _INT_FIELDS.intersection(names):
            v = cols[name]
            cols[name] = np.where(np.isnan(v), -1, np.round(v)).astype(np.int64)
        line = np.array(g.lines, dtype=np.int64)
        sats = np.array(g.sats)
        order = np.lexsort((line, toc, sats))  # by satellite, then toc, then file order
        data = {"sat": sats[order], "toc_gps_s": toc[order]}
        data.update((name, cols[name][order]) for name in names)
        data["line"] = line[order]
        tables[sys_letter] = data
    return tables
