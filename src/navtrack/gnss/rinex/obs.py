"""RINEX 2.10/2.11 and 3.0x (4.0x) observation files -> :class:`Observations`.

Design (for speed): Python walks over the *epoch records only*
(:mod:`~navtrack.gnss.rinex.obs_scan`); the data lines of all epochs are gathered into one
fixed-width byte matrix and every ``F14.3,I1,I1`` field (value, LLI, signal strength) is decoded at
once by vectorised digit arithmetic (:mod:`~navtrack.gnss.rinex.obs_fields`). A RINEX 3 read of
selected systems or codes builds no matrix: it finds every line's start in the file's text and
takes only the fields asked for, at their columns, for decoding; the satellite ids and the line
lengths are read for all lines. This module checks the structure of the data lines (satellite
ids, types declared, surplus fields, duplicates) and places the values in the epoch x satellite
x code arrays.

Its intermediate records are :class:`~navtrack._record.Record` classes and plain classes: a
dataclass compiles its methods when its module is imported, a cost every ``navtrack pos`` start
would pay.

References
----------
RINEX 2.11 (Gurtner & Estey, IGS/RTCM-SC104, 2007), sections 5, 7 and tables A1-A3;
RINEX 3.05 (IGS/RTCM-SC104, 2020), sections 5.1-5.3, 6.1 and tables A1-A3;
RINEX 4.00 (IGS/RTCM-SC104, 2021), observation tables (same data section as 3.05).
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from os import fspath

import numpy as np

from navtrack._record import Record
from navtrack._typing import BoolArray, FloatArray, IntArray, StrPath
from navtrack.errors import FileFormatError
from navtrack.gnss.observations import SYSTEMS, Event, Observations, ObsHeader, SkippedLine
from navtrack.gnss.rinex._io import ends_inside_field, read_bytes, sniff
from navtrack.gnss.rinex.obs_fields import (
    FIELD_WIDTH,
    decode_fields,
    decode_some,
    field_matrix,
    gather_columns,
)
from navtrack.gnss.rinex.obs_header import V2_EPOCH, ObsTypes, parse_header, sat_id, to_gps_rinex
from navtrack.gnss.rinex.obs_scan import (
    EpochScan,
    TextLines,
    scan_v2,
    scan_v3,
    scan_v3_regular,
)

__all__ = ["read_obs"]

_CUT_FIELD = "data line cut in the middle of a field by the end of the file"


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
    selective = kind.version >= 3 and (systems is not None or codes is not None)
    header, types, scan, text = _walk(path, data, kind.version, kind.system, lenient, selective)
    return _assemble(path, header, types, scan, kind.version >= 3, lenient, text, systems, codes)


def _walk(
    path: StrPath, data: bytes, version: float, system: str, lenient: bool, selective: bool
) -> tuple[ObsHeader, list[ObsTypes], EpochScan, TextLines | None]:
    """The header, observation types and epoch walk of the file's text ``data``, and its
    lines when the read is ``selective`` (RINEX 3 only: the lines made only where read)."""
    v3 = version >= 3
    text = TextLines(data) if v3 else None
    lines: Sequence[bytes] = text if selective and text is not None else data.split(b"\n")
    end = len(lines)
    while end > 0 and not lines[end - 1].strip():
        end -= 1
    header, types, body = parse_header(path, lines, end, version, system)
    scan = EpochScan(keep_data=not selective)
    cut = _last_line_cut(path, data, lines[end - 1] if end > body else b"", end, v3, lenient)
    if cut:
        scan.skipped.append(SkippedLine(line=end, reason=_CUT_FIELD))
        end -= 1
    if text is not None:
        where = (body, text.starting_with(b">", body, end).tolist(), end)
        if not scan_v3_regular(text, where, len(types) - 1, scan):
            scan_v3(path, lines, where, types, scan, lenient)
    else:  # the RINEX 2 walk reads past `end`: blank lines may close the last record
        scan_v2(path, lines[:end] if cut else lines, body, end, types, scan, lenient)
    return header, types, scan, text if selective else None


def _last_line_cut(
    path: StrPath, data: bytes, last: bytes, end: int, v3: bool, lenient: bool
) -> bool:
    """True when the last line is a data line cut inside a field by the end of the file
    (raises unless ``lenient``)."""
    # not an epoch record, nor a header record of an event (its label in columns 61-80)
    epoch_line = last.startswith(b">") if v3 else V2_EPOCH.match(last)
    data_line = not epoch_line and not last[60:].strip(b" 0123456789.-")
    # F14.3 then LLI and SSI (I1 each) after the satellite id (A1,I2)
    cut = bool(last) and data_line and ends_inside_field(data, 3 if v3 else 0, 16, (0, 14, 15))
    if cut and not lenient:
        raise FileFormatError(path, end, _CUT_FIELD)
    return cut


# ----------------------------------------------------------------------------- assembling


class _Lines(Record):
    """Where each data line belongs: its epoch, observation types (segment), file line, first
    field's position in its system's type list (``offset``; RINEX 2 records span lines of 5
    fields) and line within its satellite record (``part``)."""

    epoch: IntArray
    segment: IntArray
    line_no: IntArray
    offset: IntArray
    part: IntArray
    record: IntArray | None  # RINEX 2: satellite record of each line


def _line_layout(scan: EpochScan, v3: bool) -> _Lines:
    n_lines = sum(scan.n_lines)
    per_epoch = np.asarray(scan.n_lines, dtype=np.int64)
    epoch = np.repeat(np.arange(len(scan.t_cal_s)), per_epoch)
    segment = np.repeat(np.asarray(scan.segment, dtype=np.int64), per_epoch)
    first_of_epoch = np.cumsum(per_epoch) - per_epoch
    line_no = np.repeat(
        np.asarray(scan.line_no, dtype=np.int64) - first_of_epoch, per_epoch
    ) + np.arange(n_lines)
    if v3:
        zeros = np.zeros(n_lines, dtype=np.int64)
        return _Lines(epoch, segment, line_no, zeros, zeros.copy(), None)
    rec_lines = np.asarray(scan.rec_lines, dtype=np.int64)
    rec_first = np.cumsum(rec_lines) - rec_lines
    part = np.arange(n_lines) - np.repeat(rec_first, rec_lines)
    record = np.repeat(np.arange(len(rec_lines)), rec_lines)
    return _Lines(epoch, segment, line_no, 5 * part, part, record)


class _Problems:
    """Why data lines are unusable, by data-line index, and the file line to name when raising
    where it is not the line's own."""

    def __init__(self) -> None:
        self.why: dict[int, str] = {}
        self.report_at: dict[int, int] = {}

    def add(self, m: int, why: str, at: int | None = None) -> None:
        self.why.setdefault(m, why)
        if at is not None:
            self.report_at.setdefault(m, at)

    def line(self, m: int, layout: _Lines) -> int:
        return int(self.report_at.get(m, layout.line_no[m]))


class _Satellites(Record):
    """The satellites of the data lines: ``names`` of the distinct ids written (None where
    malformed), ``inverse`` (id of each RINEX 3 line, of each RINEX 2 record), ``sats`` (sorted
    valid names), column of each line in ``sats`` (-1: malformed) and its system's index."""

    names: list[str | None]
    inverse: IntArray
    sats: list[str]
    of_line: IntArray
    sys_of_line: IntArray


def _raw_ids(scan: EpochScan, v3: bool, full: np.ndarray | None, text: _Text | None) -> np.ndarray:
    """The satellite id written for each RINEX 3 line / each RINEX 2 record, as ``S3``."""
    if not v3:
        return np.array(scan.rec_sat, dtype="S3")
    if full is not None:
        return np.ascontiguousarray(full[:, :3]).view("S3").ravel()
    assert text is not None
    zero = np.zeros(len(text.start), dtype=np.int64)
    return gather_columns(text.buf, text.start, text.length, zero, 3).view("S3").ravel()


def _satellites(
    raw_ids: np.ndarray, scan: EpochScan, v3: bool, layout: _Lines, problems: _Problems
) -> _Satellites:
    # unique ids through a 3-byte integer code (much faster than sorting byte strings)
    id_bytes = raw_ids.view(np.uint8).reshape(-1, 3).astype(np.uint32)
    id_code = (id_bytes[:, 0] << 16) | (id_bytes[:, 1] << 8) | id_bytes[:, 2]
    uniq_code, inverse = np.unique(id_code, return_inverse=True)
    names: list[str | None] = []
    for k, c in enumerate(uniq_code.tolist()):
        raw = bytes(((c >> 16) & 255, (c >> 8) & 255, c & 255)).replace(b"\0", b" ")
        try:
            names.append(sat_id(raw, blank_is_gps=not v3))
        except ValueError as exc:
            names.append(None)
            members = np.flatnonzero(inverse == k)
            if v3:
                for m in members.tolist():
                    problems.add(m, str(exc))
                continue
            # RINEX 2: the id is written in the epoch record: name that line when raising
            assert layout.record is not None
            for m in np.flatnonzero(np.isin(layout.record, members)).tolist():
                at = scan.epoch_line[layout.epoch[m]]
                problems.add(m, f"{exc} in the satellite list of the epoch record", at)
    sats = sorted({n for n in names if n is not None})
    sat_col = {s: k for k, s in enumerate(sats)}
    uniq_col = np.array([sat_col.get(n, -1) if n else -1 for n in names] or [0], dtype=np.int64)
    uniq_sys = np.array([SYSTEMS.index(n[0]) if n else 0 for n in names] or [0], dtype=np.int64)
    if v3:
        return _Satellites(names, inverse, sats, uniq_col[inverse], uniq_sys[inverse])
    assert layout.record is not None
    n_lines = len(layout.epoch)
    of_line = uniq_col[inverse][layout.record] if n_lines else np.zeros(0, np.int64)
    # RINEX 2: one type list for all systems
    return _Satellites(names, inverse, sats, of_line, np.zeros(n_lines, dtype=np.int64))


def _code_table(
    segments: list[ObsTypes], code_index: dict[str, int], n_f: int
) -> tuple[IntArray, FloatArray, BoolArray]:
    """Code (index into ``code_index``) and scale factor of each field position, rows
    (segment, system); and whether the row's system has types declared."""
    n_sys = len(SYSTEMS)
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
    return table, scale, declared


class _Request(Record):
    """What the caller asked for: output codes (``kept`` maps the file's code index to the
    output's, -1 dropped, with a trailing -1 for "no code") and satellites (``out_col`` maps
    the column in ``sats`` to the output's likewise)."""

    systems: str | None
    codes: list[str]
    kept: IntArray
    sats: list[str]
    out_col: IntArray


def _request(
    codes: list[str], sats: list[str], systems: str | None, want: Collection[str] | None
) -> _Request:
    out_codes = [c for c in codes if want is None or c in want]
    kept = np.array([out_codes.index(c) if c in out_codes else -1 for c in codes] + [-1])
    out_sats = [s for s in sats if systems is None or s[0] in systems]
    out_col = np.array([out_sats.index(s) if s in out_sats else -1 for s in sats] + [-1])
    return _Request(systems, out_codes, kept, out_sats, out_col)


class _Text(Record):
    """The file's text as a uint8 buffer and, for each data line, its start and length (RINEX 3
    reads of selected systems or codes take their fields from it)."""

    data: bytes
    buf: np.ndarray
    start: IntArray
    length: IntArray


def _text(lines: TextLines, layout: _Lines) -> _Text:
    at = layout.line_no - 1
    buf = np.frombuffer(lines.data, dtype=np.uint8)
    return _Text(lines.data, buf, lines.start[at], lines.length[at])


def _too_long(text: _Text, n_types: IntArray, lead: int) -> BoolArray:
    """Data lines with text beyond their system's last field (trailing blanks aside)."""
    limit = lead + FIELD_WIDTH * n_types
    beyond = text.length > limit
    for m in np.flatnonzero(beyond).tolist():
        first = int(text.start[m])
        line = text.data[first : first + int(text.length[m])]
        beyond[m] = len(line.rstrip(b" ")) > limit[m]
    return beyond


def _duplicates(layout: _Lines, sats: _Satellites) -> IntArray:
    """Data lines of a satellite already seen in the same epoch (the second and later)."""
    n_lines = len(layout.epoch)
    key = layout.epoch * max(len(sats.sats), 1) + sats.of_line
    key = key * (int(layout.part.max(initial=0)) + 1) + layout.part
    valid = sats.of_line >= 0
    later = np.zeros(n_lines, dtype=bool)
    if np.bincount(key[valid]).max(initial=0) > 1:  # rare: the later ones in file order
        order = np.argsort(key, kind="stable")
        later[order[1:]] = (key[order][1:] == key[order][:-1]) & valid[order][1:]
    return np.flatnonzero(later)


class _Picked(Record):
    """The decoded fields that are not blank, of the satellites and codes asked for: data line,
    field position in its system's type list (``col``), file code index, value, LLI, SSI."""

    line: IntArray
    col: IntArray
    code: IntArray
    value: FloatArray
    lli: np.ndarray
    ssi: np.ndarray


def _field_problem(k: int, text: bytes) -> str:
    return f"malformed observation field {k + 1}: {text.decode('ascii', 'replace')!r}"


def _all_fields(
    mat: np.ndarray,
    lead: int,
    layout: _Lines,
    sats: _Satellites,
    req: _Request,
    tables: tuple[IntArray, IntArray, bool],
    problems: _Problems,
) -> tuple[_Picked, BoolArray]:
    """Fields of the byte matrix of all data lines: every one decoded, or only those asked
    for when ``selecting`` (blanks of all: they check the structure); and the lines with
    fields beyond their system's types."""
    table, row, selecting = tables
    n_lines = mat.shape[0]
    n_f = (mat.shape[1] - lead) // FIELD_WIDTH
    col = layout.offset[:, None] + np.arange(n_f)
    code = table[row[:, None], col]
    if lead == 0:
        code[:, 5:] = -1  # RINEX 2 lines hold 5 fields (80 columns)
    wanted = (req.kept[code] >= 0) & (req.out_col[sats.of_line] >= 0)[:, None]
    fields = mat[:, lead:].reshape(n_lines * n_f, FIELD_WIDTH)
    if selecting:
        decoded = decode_some(fields, np.flatnonzero(wanted.ravel()))
    else:
        decoded = decode_fields(fields)
    shape = (n_lines, n_f)
    value, lli, ssi, blank, bad = (a.reshape(shape) for a in decoded)
    value[value == 0.0] = np.nan  # "missing observations are written as 0.0 or blanks"
    for m in np.flatnonzero(bad.any(axis=1)).tolist():
        first = int(np.argmax(bad[m]))
        at = lead + FIELD_WIDTH * first
        problems.add(m, _field_problem(first, mat[m, at : at + FIELD_WIDTH].tobytes()))
    present = np.logical_not(blank)
    put = wanted & present
    line = np.broadcast_to(np.arange(n_lines)[:, None], shape)[put]
    picked = _Picked(line, col[put], code[put], value[put], lli[put], ssi[put])
    return picked, np.asarray((present & (code < 0)).any(axis=1))


def _some_fields(
    text: _Text,
    lead: int,
    sats: _Satellites,
    req: _Request,
    tables: tuple[IntArray, IntArray],
    problems: _Problems,
) -> _Picked:
    """The fields asked for, taken from the text of their lines and decoded (RINEX 3)."""
    table, row = tables
    lines = np.flatnonzero(req.out_col[sats.of_line] >= 0)
    i, k = np.nonzero((req.kept[table] >= 0)[row[lines]])
    m = lines[i]
    column = lead + FIELD_WIDTH * k
    fields = gather_columns(text.buf, text.start[m], text.length[m], column, FIELD_WIDTH)
    value, lli, ssi, blank, bad = decode_fields(fields)
    value[value == 0.0] = np.nan  # "missing observations are written as 0.0 or blanks"
    for j in np.flatnonzero(bad).tolist():  # in line order, then field order
        problems.add(int(m[j]), _field_problem(int(k[j]), fields[j].tobytes()))
    keep = ~blank
    m, k = m[keep], k[keep]
    return _Picked(m, k, table[row[m], k], value[keep], lli[keep], ssi[keep])


def _assemble(
    path: StrPath,
    header: ObsHeader,
    segments: list[ObsTypes],
    scan: EpochScan,
    v3: bool,
    lenient: bool,
    lines: TextLines | None,
    want_systems: str | None = None,
    want_codes: Collection[str] | None = None,
) -> Observations:
    codes: list[str] = []
    for seg in segments:
        for types in seg.obs_types.values():
            codes.extend(c for c in types if c not in codes)
    lead = 3 if v3 else 0
    selecting = want_systems is not None or want_codes is not None
    layout = _line_layout(scan, v3)
    text = None if lines is None else _text(lines, layout)
    full = None if text is not None else field_matrix(scan.data, lead)
    problems = _Problems()
    sats = _satellites(_raw_ids(scan, v3, full, text), scan, v3, layout, problems)
    req = _request(codes, sats.sats, want_systems, want_codes)
    n_f = 0 if full is None else (full.shape[1] - lead) // FIELD_WIDTH
    table, scale, declared = _code_table(segments, {c: k for k, c in enumerate(codes)}, n_f)
    row = layout.segment * len(SYSTEMS) + sats.sys_of_line
    if full is None:
        assert text is not None
        picked = _some_fields(text, lead, sats, req, (table, row), problems)
        surplus = _too_long(text, (table >= 0).sum(axis=1)[row], lead)
    else:
        tables = (table, row, selecting)
        picked, surplus = _all_fields(full, lead, layout, sats, req, tables, problems)
    for m in np.flatnonzero(surplus & declared[row]).tolist():
        why = " (or data beyond column 80)" if not v3 else ""
        problems.add(m, "more observations than observation types" + why)
    for m in np.flatnonzero(~declared[row]).tolist():
        name = sats.names[int(sats.inverse[m])] if v3 else "?"
        problems.add(m, f"no observation types for the system of satellite {name}")
    for m in _duplicates(layout, sats).tolist():
        problems.add(m, f"satellite {sats.sats[sats.of_line[m]]} appears twice in one epoch")
    skipped = list(scan.skipped)
    usable = np.ones(len(layout.epoch), dtype=bool)
    if problems.why:
        if not lenient:
            m = min(problems.why, key=lambda j: problems.line(j, layout))
            raise FileFormatError(path, problems.line(m, layout), problems.why[m])
        for m, reason in problems.why.items():
            usable[m] = False
            skipped.append(SkippedLine(line=int(layout.line_no[m]), reason=reason))
    n_e = len(scan.t_cal_s)
    arrays = _scatter(picked, scale, (layout, row), sats, req, usable, n_e)
    return _observations(path, header, segments, scan, v3, req, sats.sats, arrays, skipped)


def _scatter(
    p: _Picked,
    scale: FloatArray,
    where: tuple[_Lines, IntArray],
    sats: _Satellites,
    req: _Request,
    usable: BoolArray,
    n_e: int,
) -> tuple[FloatArray, np.ndarray, np.ndarray]:
    """The epoch x satellite x code arrays of the values, LLI and SSI asked for."""
    layout, row = where
    n_s, n_c = len(req.sats), len(req.codes)
    values = np.full((n_e, n_s, n_c), np.nan)
    lli_out = np.full((n_e, n_s, n_c), -1, dtype=np.int8)
    ssi_out = np.full((n_e, n_s, n_c), -1, dtype=np.int8)
    keep = usable[p.line]
    line = p.line[keep]
    out_sat = req.out_col[sats.of_line[line]]
    target = (layout.epoch[line] * n_s + out_sat) * n_c + req.kept[p.code[keep]]
    value = p.value[keep]
    if (scale != 1.0).any():
        value = value / scale[row[line], p.col[keep]]
    values.reshape(-1)[target] = value
    lli_out.reshape(-1)[target] = p.lli[keep]
    ssi_out.reshape(-1)[target] = p.ssi[keep]
    return values, lli_out, ssi_out


def _observations(
    path: StrPath,
    header: ObsHeader,
    segments: list[ObsTypes],
    scan: EpochScan,
    v3: bool,
    req: _Request,
    sats: list[str],
    arrays: tuple[FloatArray, np.ndarray, np.ndarray],
    skipped: list[SkippedLine],
) -> Observations:
    t_gps = to_gps_rinex(np.asarray(scan.t_cal_s, dtype=float), header.time_system)
    t_events = to_gps_rinex(np.asarray(scan.event_t_cal_s, dtype=float), header.time_system)
    events = tuple(
        Event(line=e.line, t_gps_s=float(t), flag=e.flag, records=e.records)
        for e, t in zip(scan.events, t_events, strict=True)
    )
    if not v3:  # RINEX 2: one list of types for every system in the file
        present = {s[0] for s in sats} or {header.system if header.system in SYSTEMS else "G"}
        types = segments[0].obs_types["G"]
        header = header.replace(obs_types={s: types for s in SYSTEMS if s in present})
    values, lli, ssi = arrays
    return Observations(
        path=fspath(path),
        header=header,
        t_gps_s=t_gps,
        epoch_flag=np.asarray(scan.flag, dtype=np.int8),
        clock_offset_s=np.asarray(scan.clock_s, dtype=float),
        sats=tuple(req.sats),
        codes=tuple(req.codes),
        values=values,
        lli=lli,
        ssi=ssi,
        events=events,
        skipped=tuple(sorted(skipped, key=lambda s: s.line)),
    )
