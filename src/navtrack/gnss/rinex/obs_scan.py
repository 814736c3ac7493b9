"""The walk over the epoch records of a RINEX observation file.

Python visits the epoch records only (RINEX 3: the ``>`` lines; RINEX 2: the records with their
satellite lists); the data lines of each epoch are gathered, in file order, for the vectorised
field decoding of :mod:`navtrack.gnss.rinex.obs_fields`. Special records (epoch flags 2-5) become
events, and those that redefine the observation types start new :class:`ObsTypes`. A selective
RINEX 3 read whose epoch records are all regular (epoch flag 0, each followed by exactly the data
lines it announces) reads them at once with numpy (:func:`scan_v3_regular`); any other file is
walked record by record, which finds and names what is irregular.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import overload

import numpy as np

from navtrack._typing import FloatArray, IntArray, StrPath
from navtrack.errors import FileFormatError
from navtrack.gnss.observations import Event, SkippedLine
from navtrack.gnss.rinex.obs_fields import gather_columns, line_spans
from navtrack.gnss.rinex.obs_header import (
    V2_EPOCH,
    V2_EVENT_NO_TIME,
    ObsTypes,
    redefined_types,
)
from navtrack.timescale import calendar_gps_seconds

__all__ = ["EpochScan", "TextLines", "scan_v2", "scan_v3", "scan_v3_regular"]

_NAN = float("nan")
_DATA_FLAGS = (0, 1, 6)  # epoch flags whose records hold observations (6: cycle slips)
_INCOMPLETE = "incomplete record at the end of the file"


class TextLines(Sequence[bytes]):
    """The lines of a file's text, ``data.split(b"\\n")``, each made only when asked for: a
    RINEX 3 walk reads its epoch records, a read of selected codes its data lines' fields by
    column (``start``, ``length``: every line's offset in ``data`` and its length)."""

    __slots__ = ("data", "length", "start")

    def __init__(self, data: bytes) -> None:
        self.data = data
        self.start, self.length = line_spans(data)

    def __len__(self) -> int:
        return len(self.start)

    @overload
    def __getitem__(self, i: int) -> bytes: ...
    @overload
    def __getitem__(self, i: slice) -> list[bytes]: ...
    def __getitem__(self, i: int | slice) -> bytes | list[bytes]:
        if isinstance(i, slice):
            spans = zip(self.start[i].tolist(), self.length[i].tolist(), strict=True)
            return [self.data[a : a + n] for a, n in spans]
        first = int(self.start[i])
        return self.data[first : first + int(self.length[i])]

    def starting_with(self, char: bytes, first: int, stop: int) -> IntArray:
        """Indices of the lines ``first`` to ``stop - 1`` whose first character is ``char``."""
        start, length = self.start[first:stop], self.length[first:stop]
        head = np.frombuffer(self.data, dtype=np.uint8)[np.minimum(start, len(self.data) - 1)]
        return np.flatnonzero((head == ord(char)) & (length > 0)) + first


class EpochScan:
    """What the epoch walk found: epochs, where their data lines are, events, skipped lines.

    Per epoch: ``t_cal_s`` (calendar seconds since 1980-01-06 in the file's time system),
    ``flag``, ``clock_s``, ``segment`` (index of its :class:`ObsTypes`), ``n_lines`` (data
    lines), ``line_no`` (1-based line of its first data line) and ``epoch_line`` (of its
    record). ``data`` holds all data lines in file order (unless ``keep_data`` is False: a
    read that takes its fields from the text by column); RINEX 2 also gives the satellite of
    every satellite record (``rec_sat``) and its line count (``rec_lines``). A plain class, not
    a dataclass: a dataclass compiles its methods when the module is imported, a cost every
    ``navtrack pos`` start would pay.
    """

    __slots__ = (
        "clock_s", "data", "epoch_line", "event_t_cal_s", "events", "flag", "keep_data", "line_no",
        "n_lines", "rec_lines", "rec_sat", "segment", "skipped", "t_cal_s",
    )  # fmt: skip

    def __init__(self, keep_data: bool = True) -> None:
        self.keep_data = keep_data
        self.t_cal_s: list[float] = []
        self.flag: list[int] = []
        self.clock_s: list[float] = []
        self.segment: list[int] = []
        self.n_lines: list[int] = []
        self.data: list[bytes] = []
        self.line_no: list[int] = []
        self.epoch_line: list[int] = []
        self.rec_sat: list[bytes] = []
        self.rec_lines: list[int] = []
        self.events: list[Event] = []
        self.event_t_cal_s: list[float] = []
        self.skipped: list[SkippedLine] = []

    def add_epoch(
        self,
        record: tuple[float, int, float],
        segment: int,
        j: int,
        lines: Sequence[bytes],
        span: tuple[int, int],
    ) -> None:
        """An epoch of ``record`` (time, flag, clock) at line ``j`` whose data lines are
        ``lines[first:stop]`` (``span``, 0-based)."""
        first, stop = span
        t_cal, flag, clock_s = record
        self.t_cal_s.append(t_cal)
        self.flag.append(flag)
        self.clock_s.append(clock_s)
        self.segment.append(segment)
        self.n_lines.append(stop - first)
        self.line_no.append(first + 1)
        self.epoch_line.append(j + 1)
        if self.keep_data:
            self.data.extend(lines[first:stop])

    def skip(self, first: int, stop: int, reason: str) -> None:
        """Record lines ``first`` to ``stop - 1`` (0-based) as skipped."""
        self.skipped.extend(SkippedLine(line=j + 1, reason=reason) for j in range(first, stop))


def _midnight_s(key: bytes, days: dict[bytes, float]) -> float:
    """Calendar seconds of the midnight of the date ``key`` (see :func:`_epoch_time_s`)."""
    day_s = days.get(key)
    if day_s is None:
        year = int(key[:-6])
        if len(key) == 8:
            year += 1900 if year >= 80 else 2000
        day_s = days[key] = calendar_gps_seconds(year, int(key[-5:-3]), int(key[-2:]), 0, 0, 0.0)
    return day_s


def _epoch_time_s(rec: bytes, start: int, stop: int, days: dict[bytes, float]) -> float:
    """Calendar seconds since 1980-01-06 of the date and time of an epoch record.

    ``rec[start:stop]`` is the date, ``YYYY MM DD`` (RINEX 3) or ``YY MM DD`` (RINEX 2, years
    80-99 are 19xx); the time ``hh mm ss.sssssss`` (I2,1X,I2,F11.7) follows one blank later in
    both versions. ``days`` caches the seconds of each date's midnight: a file has few dates but
    one record per epoch, and ``datetime.date`` is the costly part.
    """
    return _midnight_s(rec[start:stop], days) + (
        int(rec[stop + 1 : stop + 3]) * 3600.0
        + int(rec[stop + 4 : stop + 6]) * 60.0
        + float(rec[stop + 6 : stop + 17])
    )


def _event(
    path: StrPath,
    lines: Sequence[bytes],
    i: int,
    flag: int,
    count: int,
    end: int,
    t_cal: float,
    scan: EpochScan,
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


def _v3_record(rec: bytes, days: dict[bytes, float]) -> tuple[float, int, int, float]:
    """Time, flag, satellite count and clock offset of a RINEX 3 epoch record
    (A1,1X,I4,4(1X,I2),F11.7,2X,I1,I3,6X,F15.12); ValueError or IndexError if malformed."""
    flag = rec[31] - 48
    count = int(rec[32:35])
    if not 0 <= flag <= 6 or count < 0:
        raise ValueError(f"epoch flag {rec[31:32]!r}")
    if rec[2:29].strip():
        t_cal = _epoch_time_s(rec, 2, 12, days)
    elif flag in _DATA_FLAGS:
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
    return t_cal, flag, count, float(clock) if clock.strip() else _NAN


def _v3_data_lines(
    path: StrPath, j: int, count: int, nxt: int, end: int, scan: EpochScan, lenient: bool
) -> int:
    """Data lines of the epoch record at line ``j`` that may be taken (the next record is at
    ``nxt``): ``count``, or in lenient mode fewer when they run short."""
    have = nxt - j - 1
    if have >= count:
        return count
    if not lenient:
        where = (
            " before the end of the file"
            if nxt == end
            else f" before the next epoch record (line {nxt + 1})"
        )
        raise FileFormatError(
            path,
            j + 1,
            f"epoch record announces {count} satellites but only {have} data lines follow{where}",
        )
    scan.skipped.append(
        SkippedLine(line=j + 1, reason=f"epoch cut short: {have} of {count} satellites")
    )
    return have


def scan_v3(
    path: StrPath,
    lines: Sequence[bytes],
    where: tuple[int, list[int], int],
    segments: list[ObsTypes],
    scan: EpochScan,
    lenient: bool,
) -> None:
    """Walk the RINEX 3 epoch records of ``lines[body:end]``; ``where`` is ``body``, the lines
    starting with ``>`` among them and ``end``."""
    body, records, end = where
    starts = [*records, end]
    seg = len(segments) - 1
    days: dict[bytes, float] = {}
    last: tuple[int, int, int] | None = None  # last data epoch: record line, count, end
    i = body
    pos = 0
    while pos < len(starts) - 1:
        j, nxt = starts[pos], starts[pos + 1]
        pos += 1
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
            scan.skip(i, j, "line outside any epoch record")
        try:
            t_cal, flag, count, clock_s = _v3_record(lines[j], days)
        except (ValueError, IndexError) as exc:
            if not lenient:
                raise FileFormatError(path, j + 1, f"malformed epoch record ({exc})") from None
            scan.skipped.append(SkippedLine(line=j + 1, reason=f"malformed epoch record ({exc})"))
            scan.skip(j + 1, nxt, "data line of a malformed epoch record")
            i = nxt
            continue
        if flag in _DATA_FLAGS:
            take = _v3_data_lines(path, j, count, nxt, end, scan, lenient)
            scan.add_epoch((t_cal, flag, clock_s), seg, j, lines, (j + 1, j + 1 + take))
            i = j + 1 + take
            last = (j, count, i)
            continue
        _event(path, lines, j, flag, count, end, t_cal, scan)
        i = j + 1 + count
        if flag in (3, 4):
            new = redefined_types(path, lines[j + 1 : i], j + 1, segments[seg], True)
            if new is not None:
                segments.append(new)
                seg = len(segments) - 1
        while starts[pos] < i:  # '>' lines inside the special records
            pos += 1
    if i < end:
        if not lenient:
            raise FileFormatError(path, i + 1, "line outside any epoch record")
        scan.skip(i, end, "line outside any epoch record")


def _right_aligned(chars: np.ndarray) -> tuple[np.ndarray, IntArray]:
    """Whether each row of ``chars`` is digits after blanks (as ``int()`` reads them, at least
    one digit), and its value."""
    digit = (chars >= 48) & (chars <= 57)
    blank = chars == 32
    ok = digit[:, -1] & (digit | blank).all(axis=1) & ~(digit[:, :-1] & blank[:, 1:]).any(axis=1)
    value = ((chars - 48) * digit).astype(np.int64) @ 10 ** np.arange(chars.shape[1] - 1, -1, -1)
    return ok, value


def _regular_times(m: np.ndarray) -> tuple[bool, FloatArray, IntArray]:
    """Whether the RINEX 3 epoch records whose first 35 characters are the rows of ``m`` all
    hold epoch flag 0, a time in digits (``hh mm sss.sssssss``) and a satellite count; their
    seconds of the day and counts."""
    ok_h, hour = _right_aligned(m[:, 13:15])
    ok_m, minute = _right_aligned(m[:, 16:18])
    ok_s, whole = _right_aligned(m[:, 18:21])
    ok_n, count = _right_aligned(m[:, 32:35])
    frac = m[:, 22:29].astype(np.int64) - 48
    ok = ok_h & ok_m & ok_s & ok_n & (m[:, 21] == 46) & (m[:, 31] == 48)
    ok &= ((frac >= 0) & (frac <= 9)).all(axis=1)
    # the integer number of 1e-7 s over 1e7: exact operands, correctly rounded, as float()
    seconds = (whole * 10_000_000 + frac @ 10 ** np.arange(6, -1, -1)) / 1e7
    return bool(ok.all()), hour * 3600.0 + minute * 60.0 + seconds, count


def scan_v3_regular(
    text: TextLines, where: tuple[int, list[int], int], segment: int, scan: EpochScan
) -> bool:
    """:func:`scan_v3` at once, for a file whose epoch records are all regular: epoch flag 0,
    time in digits, clock offset a number or blank, each followed by exactly the data lines it
    announces, no other line. Returns False, recording nothing, for any other file (its walk
    then finds what is irregular); only for reads that keep no data lines."""
    body, records, end = where
    if not records or records[0] != body or scan.keep_data:
        return False
    at = np.asarray(records, dtype=np.int64)
    start, length = text.start[at], text.length[at]
    buf = np.frombuffer(text.data, dtype=np.uint8)
    m = gather_columns(buf, start, length, np.zeros(len(at), dtype=np.int64), 35)
    ok, of_day_s, count = _regular_times(m)
    if not ok or (count != np.append(at[1:], end) - at - 1).any():
        return False
    days: dict[bytes, float] = {}
    midnight: list[float] = []
    clock_s: list[float] = []
    data = text.data
    try:
        for first, n in zip(start.tolist(), length.tolist(), strict=True):
            rec = data[first : first + n]
            midnight.append(_midnight_s(rec[2:12], days))
            clock = rec[41:56]
            if clock.strip() and len(rec.rstrip()) < 56:
                return False
            clock_s.append(float(clock) if clock.strip() else _NAN)
    except ValueError:
        return False
    n_e = len(at)
    scan.t_cal_s.extend((np.asarray(midnight) + of_day_s).tolist())
    scan.flag.extend([0] * n_e)
    scan.clock_s.extend(clock_s)
    scan.segment.extend([segment] * n_e)
    scan.n_lines.extend(count.tolist())
    scan.line_no.extend((at + 2).tolist())
    scan.epoch_line.extend((at + 1).tolist())
    return True


def _v2_record(rec: bytes, days: dict[bytes, float]) -> tuple[float, int, int]:
    """Time, flag and satellite count of a RINEX 2 epoch record
    (1X,I2.2,4(1X,I2),F11.7,2X,I1,I3,12(A1,I2),F12.9); ValueError if malformed."""
    if not (V2_EPOCH.match(rec) or V2_EVENT_NO_TIME.match(rec)):
        raise ValueError("not an epoch record")
    flag = rec[28] - 48
    count = int(rec[29:32])
    if rec[1:26].strip():
        t_cal = _epoch_time_s(rec, 1, 9, days)
    elif flag in _DATA_FLAGS:
        raise ValueError("no epoch time")
    else:
        t_cal = _NAN
    return t_cal, flag, count


def _v2_satellites(
    path: StrPath, lines: Sequence[bytes], i: int, end: int, count: int
) -> list[bytes]:
    """The satellite list of the epoch record at line ``i`` (12 per line, then continuation
    lines blank up to column 32)."""
    n_list = max(1, (count + 11) // 12)
    if i + n_list > end:
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
    return sats


def _v2_clock(path: StrPath, rec: bytes, i: int, scan: EpochScan, lenient: bool) -> float:
    """Receiver clock offset (F12.9, columns 69-80) of the RINEX 2 epoch record at line ``i``."""
    clock = rec[68:80]
    try:
        return float(clock) if clock.strip() else _NAN
    except ValueError:
        if not lenient:
            raise FileFormatError(
                path, i + 1, f"malformed receiver clock offset {clock!r}"
            ) from None
        scan.skipped.append(SkippedLine(line=i + 1, reason="malformed clock offset ignored"))
        return _NAN


class _V2Walk:
    """The state of a RINEX 2 walk: file, options, observation types in force (a plain class,
    as :class:`EpochScan`)."""

    __slots__ = (
        "end", "lenient", "limit", "lines", "path", "per_sat", "previous", "scan", "seg",
        "segments",
    )  # fmt: skip

    def __init__(
        self,
        path: StrPath,
        lines: Sequence[bytes],
        end: int,
        segments: list[ObsTypes],
        scan: EpochScan,
        lenient: bool,
    ) -> None:
        self.path = path
        self.lines = lines
        self.end = end
        self.limit = len(lines) - (lines[-1] == b"")  # the last record may end in blank lines
        self.segments = segments
        self.scan = scan
        self.lenient = lenient
        self.seg = 0
        self.per_sat = 1  # data lines per satellite
        self.previous = (-1, 0, 0, 0)  # last data epoch: record line, count, first/stop line
        self.use(len(segments) - 1)

    def use(self, seg: int) -> None:
        self.seg = seg
        self.per_sat = (len(self.segments[seg].obs_types["G"]) + 4) // 5

    def event(self, i: int, flag: int, count: int, t_cal: float) -> int:
        """A special record at line ``i``; returns the line after it."""
        _event(self.path, self.lines, i, flag, count, self.end, t_cal, self.scan)
        stop = i + 1 + count
        if flag in (3, 4):
            records = self.lines[i + 1 : stop]
            new = redefined_types(self.path, records, i + 1, self.segments[self.seg], False)
            if new is not None:
                self.segments.append(new)
                self.use(len(self.segments) - 1)
        return stop

    def epoch(self, i: int, t_cal: float, flag: int, count: int) -> int:
        """A data epoch whose record is at line ``i``; returns the line after it."""
        sats = _v2_satellites(self.path, self.lines, i, self.end, count)
        first = i + max(1, (count + 11) // 12)
        clock_s = _v2_clock(self.path, self.lines[i], i, self.scan, self.lenient)
        stop = first + count * self.per_sat
        take = count
        if stop > self.limit:
            if not self.lenient:
                raise FileFormatError(
                    self.path,
                    i + 1,
                    f"epoch record announces {count} satellites "
                    f"({count * self.per_sat} data lines) but the file ends after "
                    f"{self.limit - first}",
                )
            take = (self.limit - first) // self.per_sat
            reason = f"epoch cut short: {take} of {count} satellites"
            self.scan.skipped.append(SkippedLine(line=i + 1, reason=reason))
            self.scan.skip(first + take * self.per_sat, self.end, _INCOMPLETE)
            stop = self.limit
        if self.lenient:  # an epoch record among the data: lines missing, satellites misaligned
            intruder = next((j for j in range(first, stop) if V2_EPOCH.match(self.lines[j])), None)
            if intruder is not None:
                reason = (
                    f"epoch dropped: fewer than {count} satellite records before the next "
                    f"epoch record (line {intruder + 1})"
                )
                self.scan.skipped.append(SkippedLine(line=i + 1, reason=reason))
                self.scan.skip(i + 1, intruder, "data line of a dropped epoch")
                return intruder
        span = (first, first + take * self.per_sat)
        self.scan.add_epoch((t_cal, flag, clock_s), self.seg, i, self.lines, span)
        self.scan.rec_sat.extend(sats[:take])
        self.scan.rec_lines.extend([self.per_sat] * take)
        self.previous = (i, count, first, stop)
        return stop


def scan_v2(
    path: StrPath,
    lines: Sequence[bytes],
    body: int,
    end: int,
    segments: list[ObsTypes],
    scan: EpochScan,
    lenient: bool,
) -> None:
    """Walk the RINEX 2 epoch records of ``lines[body:end]`` (``end`` excludes trailing blank
    lines; the last record may still end in blank lines, all its observations missing)."""
    walk = _V2Walk(path, lines, end, segments, scan, lenient)
    days: dict[bytes, float] = {}
    i = body
    while i < end:
        try:
            t_cal, flag, count = _v2_record(lines[i], days)
        except ValueError as exc:
            if not lenient:
                _missing_v2_data_line(path, lines, walk.previous)
                raise FileFormatError(path, i + 1, f"malformed epoch record ({exc})") from None
            scan.skipped.append(SkippedLine(line=i + 1, reason=f"malformed epoch record ({exc})"))
            i += 1
            continue
        if flag in _DATA_FLAGS:
            i = walk.epoch(i, t_cal, flag, count)
        else:
            i = walk.event(i, flag, count, t_cal)


def _missing_v2_data_line(
    path: StrPath, lines: Sequence[bytes], previous: tuple[int, int, int, int]
) -> None:
    """Explain a malformed epoch record by a data line missing from the epoch before it."""
    rec, count, first, stop = previous
    for j in range(first, stop):
        if V2_EPOCH.match(lines[j]):
            raise FileFormatError(
                path,
                rec + 1,
                f"epoch record announces {count} satellites but fewer data lines "
                f"follow: line {j + 1}, read as its data, is an epoch record",
            )
