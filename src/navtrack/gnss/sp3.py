"""SP3 precise orbit and clock files (SP3-a, SP3-c, SP3-d).

:func:`read_sp3` turns an SP3 file into an :class:`Sp3`: epoch times in GPS seconds, satellite
ids, ECEF positions (m), clock offsets (s), and -- when the file has them -- velocities, clock
rates, standard deviations and the orbit/clock flags, as fixed ``(epochs, satellites, ...)``
arrays with NaN for missing values.

Units in the file are km, µs, dm/s and 10⁻⁴ µs/s; navtrack converts them to m, s, m/s and s/s.
Positions written as ``0.000000`` (all three components) and clocks written as
``999999.999999`` mean "bad or absent" and become NaN. Epochs are converted from the file's time
system (``%c`` line; SP3-a is always GPS) to GPS time.

References
----------
Hilla, S., "The Extended Standard Product 3 Orbit Format (SP3-d)", IGS, 2016 (and SP3-c, 2010;
Remondi, SP3-a, 1989).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from os import fspath
from typing import Any

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._typing import FloatArray, Int8Array, StrPath
from navtrack.errors import FileFormatError
from navtrack.geodesy import OMEGA_E_RAD_S
from navtrack.gnss.observations import SkippedLine
from navtrack.gnss.rinex._io import read_bytes
from navtrack.gnss.rinex_clock import RinexClock
from navtrack.timescale import calendar_gps_seconds, to_datetime64, to_gps

__all__ = ["Sp3", "Sp3Header", "read_sp3"]

_FILE_TYPES = {"G", "M", "R", "E", "C", "J", "I", "L", "S"}
_BAD_CLOCK = 999999.0  # 999999.999999 marks a bad/absent clock (any value >= this)
_FLAG_BITS = ((74, 1), (75, 2), (78, 4), (79, 8))  # column -> flag bit (E, P, M, P)
# Plausible distance of an orbit from the geocentre (m). GNSS orbits lie between GLONASS
# (semi-major axis 25,510 km) and GEO/IGSO (42,164 km; QZSS IGSO apogee about 45,300 km with
# e = 0.075), LEO satellites in SP3 files above about 6,500 km (120 km altitude over the 6,378 km
# equatorial radius): GLONASS ICD 5.1 3.1.1, BDS-OS-SIS-ICD 3.0 3.1, IS-QZSS-PNT-005 table 3.1-1.
PLAUSIBLE_RADIUS_M = (6.5e6, 5.0e7)
_GM_M3S2 = 3.986004418e14  # WGS 84 / IS-GPS-200 earth gravitational constant
_P_RECORD_CHARS = 60  # 'P', id, x, y, z (F14.6 km) and clock (F14.6 us): the fields always written


@dataclass(frozen=True, slots=True, eq=False)
class Sp3Header:
    """Header of an SP3 file.

    Attributes
    ----------
    version : str
        Format version letter (``a``, ``c``, ``d``).
    pos_vel : str
        ``P`` (positions only) or ``V`` (positions and velocities).
    n_epochs : int
        Number of epochs the header announces.
    data_used : str
        Data used descriptor (``d+D``, ``DD+AD`` ...).
    coordinate_system : str
        Reference frame (``IGb14``, ``WGS84`` ...).
    orbit_type : str
        ``FIT``, ``EXT``, ``BCT``, ``HLM``.
    agency : str
        Agency code.
    file_type : str
        ``G``, ``M``, ``R``, ``E``, ``C``, ``J``, ``I`` from ``%c`` (``G`` for SP3-a).
    time_system : str
        Time system of the epochs as written (``GPS``, ``UTC``, ``GAL``, ``BDT`` ...); the
        result's times are GPS time.
    interval_s : float
        Nominal epoch interval (s).
    accuracy_m : ndarray, shape (n_sats,)
        Satellite accuracy ``2**exponent`` mm converted to m, NaN where the exponent is 0
        (unknown).
    base_pos_vel : float
        ``%f`` floating-point base for position/velocity standard deviations (NaN if absent).
    base_clk_rate : float
        ``%f`` base for clock/clock-rate standard deviations (NaN if absent).
    comments : tuple of str
        ``/*`` comment lines.
    """

    version: str
    pos_vel: str
    n_epochs: int
    data_used: str
    coordinate_system: str
    orbit_type: str
    agency: str
    file_type: str
    time_system: str
    interval_s: float
    accuracy_m: FloatArray
    base_pos_vel: float = math.nan
    base_clk_rate: float = math.nan
    comments: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        freeze_arrays(self)


@dataclass(frozen=True, slots=True, eq=False)
class Sp3:
    """Precise orbits and clocks of one SP3 file.

    Attributes
    ----------
    path : str
        Source file.
    header : Sp3Header
        Header fields.
    t_gps_s : ndarray, shape (n_epochs,)
        Epoch times in GPS seconds.
    sats : tuple of str, length n_sats
        Satellite ids (``G01``, ``R07``, ``E11``, ...), in header order. SP3-a ids without a
        system letter are GPS.
    pos_m : ndarray, shape (n_epochs, n_sats, 3)
        Satellite ECEF position (m) in :attr:`Sp3Header.coordinate_system`; NaN where missing
        or written as 0.000000.
    clock_s : ndarray, shape (n_epochs, n_sats)
        Satellite clock offset (s); NaN where missing or written as 999999.999999.
    vel_mps : ndarray, shape (n_epochs, n_sats, 3), or None
        Velocity (m/s) from ``V`` records; None when the file has none.
    clock_rate : ndarray, shape (n_epochs, n_sats), or None
        Clock rate (s/s) from ``V`` records; None when the file has none.
    pos_sd_m : ndarray, shape (n_epochs, n_sats, 3), or None
        Position standard deviations ``base_pos_vel**exponent`` mm converted to m; None when no
        record has them, NaN where blank.
    clock_sd_s : ndarray, shape (n_epochs, n_sats), or None
        Clock standard deviation ``base_clk_rate**exponent`` ps converted to s.
    flags : ndarray of int8, shape (n_epochs, n_sats)
        Bit mask of the ``P`` record flags: 1 clock event, 2 clock predicted, 4 maneuver,
        8 orbit predicted.
    implausible : tuple of SkippedLine
        ``P`` records whose position lies outside :data:`PLAUSIBLE_RADIUS_M` from the geocentre
        or jumps from its neighbours farther than orbital motion allows (line and why); their
        position and clock are NaN, so that satellite is missing at that epoch only. A jump
        between two parts of one satellite's orbit excludes that satellite from the file (one
        entry, at the first record after the step).
    warnings : tuple of str
        What was read leniently: a header epoch count that disagrees with the records (both
        counts named).
    clock : RinexClock or None
        Satellite clocks of a RINEX clock file used instead of :attr:`clock_s` where the
        satellite positions are evaluated (:meth:`with_clock`); None: the SP3 clocks.

    References
    ----------
    SP3-d (IGS, 2016) section 2 (header) and 3 (records).
    """

    path: str
    header: Sp3Header
    t_gps_s: FloatArray
    sats: tuple[str, ...]
    pos_m: FloatArray
    clock_s: FloatArray
    vel_mps: FloatArray | None = None
    clock_rate: FloatArray | None = None
    pos_sd_m: FloatArray | None = None
    clock_sd_s: FloatArray | None = None
    flags: Int8Array | None = None
    implausible: tuple[SkippedLine, ...] = ()
    warnings: tuple[str, ...] = ()
    clock: RinexClock | None = None

    def __post_init__(self) -> None:
        n_e, n_s = len(self.t_gps_s), len(self.sats)
        shapes = {
            "pos_m": (n_e, n_s, 3),
            "clock_s": (n_e, n_s),
            "vel_mps": (n_e, n_s, 3),
            "clock_rate": (n_e, n_s),
            "pos_sd_m": (n_e, n_s, 3),
            "clock_sd_s": (n_e, n_s),
            "flags": (n_e, n_s),
        }
        for name, shape in shapes.items():
            arr = getattr(self, name)
            if arr is None:
                continue
            if arr.shape != shape:
                raise ValueError(f"{name}: expected shape {shape}, got {arr.shape}")
        freeze_arrays(self)

    @property
    def time(self) -> np.ndarray:
        """Epoch times as GPST calendar ``datetime64[ns]``."""
        return to_datetime64(self.t_gps_s)

    def with_clock(self, clock: RinexClock | None) -> Sp3:
        """The same orbits with the satellite clocks of a RINEX clock file (None: the SP3's)."""
        return dataclasses.replace(self, clock=clock)

    def sat_index(self, sat: str) -> int:
        """Column of a satellite id in the satellite axis."""
        try:
            return self.sats.index(sat)
        except ValueError:
            raise KeyError(f"satellite {sat!r} not in the SP3 file") from None

    def summary(self) -> dict[str, Any]:
        """What the file holds, as plain Python values (for ``navtrack rinex info``)."""
        per_system: dict[str, int] = {}
        for s in self.sats:
            per_system[s[0]] = per_system.get(s[0], 0) + 1
        span = [str(t)[:19] for t in self.time[[0, -1]]] if len(self.t_gps_s) else []
        return {
            "path": self.path,
            "version": f"SP3-{self.header.version}",
            "content": f"precise orbit{' + velocity' if self.vel_mps is not None else ''}",
            "agency": self.header.agency,
            "coordinate_system": self.header.coordinate_system,
            "orbit_type": self.header.orbit_type,
            "time_system": self.header.time_system,
            "n_epochs": len(self.t_gps_s),
            "interval_s": self.header.interval_s,
            "span_gps": span,
            "sats_per_system": per_system,
            "positions_missing": int(np.isnan(self.pos_m[..., 0]).sum()),
            "clocks_missing": int(np.isnan(self.clock_s).sum()),
            "implausible_records": len(self.implausible),
            "warnings": list(self.warnings),
        }


def read_sp3(path: StrPath) -> Sp3:
    """Read an SP3-a/c/d precise orbit (and clock) file.

    Parameters
    ----------
    path : str or path-like
        SP3 file, plain or compressed (gzip, bzip2, ``.Z``).

    Returns
    -------
    Sp3

    Raises
    ------
    FileFormatError
        Not an SP3 file, an unreadable header or data field, a satellite not listed in the
        header, a data record before the first epoch, or a file whose number of epochs
        differs from the header's (truncated file); the message names the file and line.
    """
    lines = read_bytes(path).decode("ascii", "replace").splitlines()
    header, sats, sat_ids, i = _read_header(path, lines)
    sat_col = {s: k for k, s in enumerate(sats)}
    # SP3-a ids are written "  1" (blank system letter = GPS) in records as in the header
    for raw, s in zip(sat_ids, sats, strict=True):
        sat_col.setdefault(raw, sat_col[s])
    data = _data_section(path, lines, i, header.n_epochs)
    p_rows = _rows(path, data.chars, data.kinds, "P", data.star, sat_col, i)
    v_rows = _rows(path, data.chars, data.kinds, "V", data.star, sat_col, i)
    n_e, n_s = len(data.epochs), len(sats)
    t_gps_s = _gps_times(path, np.array(data.epochs, dtype=float), header.time_system)
    base_pos, base_clk = header.base_pos_vel, header.base_clk_rate
    pos_m, clock_s, pos_sd, clk_sd, flags = _records(path, p_rows, n_e, n_s, base_pos, base_clk)
    pos_m *= 1e3
    clock_s *= 1e-6
    implausible = _implausible(pos_m, clock_s, p_rows)
    jumps = _jumps(t_gps_s, pos_m, clock_s, p_rows)
    if jumps:
        implausible = tuple(sorted((*implausible, *jumps), key=lambda sk: sk.line))
    vel_mps = clock_rate = None
    if len(v_rows[2]):
        vel, rate, _, _, _ = _records(path, v_rows, n_e, n_s, base_pos, base_clk)
        vel_mps = vel * 0.1  # dm/s
        clock_rate = rate * 1e-10  # 1e-4 us/s
    return Sp3(
        path=fspath(path),
        header=header,
        t_gps_s=t_gps_s,
        sats=sats,
        pos_m=pos_m,
        clock_s=clock_s,
        vel_mps=vel_mps,
        clock_rate=clock_rate,
        pos_sd_m=pos_sd,
        clock_sd_s=clk_sd,
        flags=flags,
        implausible=implausible,
        warnings=data.warnings,
    )


@dataclass
class _HeaderLines:
    """What the ``+``, ``++``, ``%c``, ``%f`` and ``/*`` header lines give."""

    sat_ids: list[str] = field(default_factory=list)
    acc_exp: list[int] = field(default_factory=list)
    n_sats: int = -1
    file_type: str = "G"
    time_system: str = "GPS"
    base_pos: float = math.nan
    base_clk: float = math.nan
    comments: list[str] = field(default_factory=list)


def _read_header(
    path: StrPath, lines: list[str]
) -> tuple[Sp3Header, tuple[str, ...], list[str], int]:
    """The header, the satellite ids (``G01``) and as written, and the index of the first data
    line."""
    first = lines[0]
    if not (first.startswith("#") and len(first) > 2 and first[1] in "abcd"):
        raise FileFormatError(path, 1, "not an SP3 file (line 1 does not start with #a/#c/#d)")
    pos_vel = first[2]
    if pos_vel not in "PV":
        raise FileFormatError(path, 1, f"position/velocity flag {pos_vel!r} is not P or V")
    try:
        n_epochs = int(first[32:39])
    except ValueError:
        raise FileFormatError(path, 1, f"unreadable number of epochs {first[32:39]!r}") from None
    interval_s = math.nan
    if len(lines) > 1 and lines[1].startswith("##"):
        interval_s = _float(path, 2, lines[1][24:38], "epoch interval")
    h, i = _header_lines(path, lines)
    if h.n_sats < 0:
        raise FileFormatError(path, 3, "no satellite list ('+' lines) in the header")
    sat_ids = h.sat_ids[: h.n_sats]
    sats = tuple(_sat_id(path, s) for s in sat_ids)
    if len(sats) < h.n_sats:
        raise FileFormatError(path, i, f"header lists {len(sats)} of {h.n_sats} satellites")
    exps = np.array((h.acc_exp + [0] * h.n_sats)[: h.n_sats], dtype=float)
    header = Sp3Header(
        version=first[1],
        pos_vel=pos_vel,
        n_epochs=n_epochs,
        data_used=first[40:45].strip(),
        coordinate_system=first[46:51].strip(),
        orbit_type=first[52:55].strip(),
        agency=first[56:60].strip(),
        file_type=h.file_type,
        time_system="GPS" if h.time_system.upper() in ("CCC", "CC", "") else h.time_system,
        interval_s=interval_s,
        accuracy_m=np.where(exps > 0, 2.0**exps * 1e-3, np.nan),
        base_pos_vel=h.base_pos,
        base_clk_rate=h.base_clk,
        comments=tuple(h.comments),
    )
    return header, sats, sat_ids, i


def _header_lines(path: StrPath, lines: list[str]) -> tuple[_HeaderLines, int]:
    """Read the header lines from line 3 to the first epoch line (its index is returned)."""
    h = _HeaderLines()
    n_c = n_f = 0
    i = 2
    while i < len(lines) and not lines[i].startswith("*"):
        line, lineno = lines[i], i + 1
        if line.startswith("++"):
            h.acc_exp.extend(_int(path, lineno, line[k : k + 3]) for k in range(9, 60, 3))
        elif line.startswith("+"):
            if h.n_sats < 0:
                h.n_sats = _int(path, lineno, line[3:6])
            h.sat_ids.extend(line[k : k + 3] for k in range(9, 60, 3))
        elif line.startswith("%c"):
            if n_c == 0:  # SP3-a writers fill the unused %c fields with "c"
                file_type = line[3:5].strip()
                h.file_type = file_type if file_type.upper() in _FILE_TYPES else "G"
                h.time_system = line[9:12].strip()
            n_c += 1
        elif line.startswith("%f"):
            if n_f == 0:
                base_pos = _float(path, lineno, line[3:13], "position base")
                base_clk = _float(path, lineno, line[14:26], "clock base")
                # 0 means "not used" (SP3-a writers and files without standard deviations)
                h.base_pos = base_pos if base_pos > 0 else math.nan
                h.base_clk = base_clk if base_clk > 0 else math.nan
            n_f += 1
        elif line.startswith("/*"):
            h.comments.append(line[3:].rstrip())
        elif line.strip() and not line.startswith(("%i", "EOF")):
            raise FileFormatError(path, lineno, f"unexpected header line {line[:20]!r}")
        i += 1
    return h, i


@dataclass(frozen=True, slots=True, eq=False)
class _DataSection:
    """The data lines as an ``(n_lines, 80)`` character matrix (records are fixed-width, so
    every field is a column slice of it), their record kinds, the epoch lines (``star``), the
    epochs (calendar s) and what was read leniently."""

    chars: np.ndarray
    kinds: np.ndarray
    star: np.ndarray
    epochs: list[float]
    warnings: tuple[str, ...]


def _data_section(path: StrPath, lines: list[str], i: int, n_epochs: int) -> _DataSection:
    """The data section from line index ``i``, checked: record kinds, the epochs, a last epoch
    cut short, and the header's epoch count (a mismatch is a warning naming both counts)."""
    data = lines[i:]
    chars = np.frombuffer(
        bytearray("".join(ln[:80].ljust(80) for ln in data).encode("ascii", "replace")),
        dtype=np.uint8,
    ).reshape(len(data), 80)
    kinds = chars[:, 0]
    eof = np.flatnonzero((chars[:, :3] == np.frombuffer(b"EOF", dtype=np.uint8)).all(axis=1))
    saw_eof = len(eof) > 0
    if saw_eof:
        chars, kinds = chars[: eof[0]], kinds[: eof[0]]
    star = np.flatnonzero(kinds == ord("*"))
    known = np.isin(kinds, np.frombuffer(b"*PVE", dtype=np.uint8))
    for k in np.flatnonzero(~known).tolist():
        if data[k].strip():
            raise FileFormatError(path, i + k + 1, f"unexpected record {data[k][:20]!r}")
    epochs = [_epoch(path, i + k + 1, data[k]) for k in star.tolist()]
    if not epochs:
        raise FileFormatError(path, len(lines), "no epoch records (lines starting with '*')")
    if not saw_eof and len(data) > int(star[-1]) + 1:
        _check_last_epoch(path, data, kinds, star, i)
    warnings = []
    if len(epochs) != n_epochs:
        # trimmed public files keep the original header: read what is there, and say so
        warnings.append(
            f"header announces {n_epochs} epochs, the file holds {len(epochs)}"
            + ("" if saw_eof else " and has no EOF line")
            + "; read as found"
        )
    return _DataSection(chars, kinds, star, epochs, tuple(warnings))


def _gps_times(path: StrPath, t_cal: FloatArray, time_system: str) -> FloatArray:
    """GPS seconds of epochs written in ``time_system``'s calendar."""
    if time_system.upper() == "TAI":
        return t_cal - 19.0  # GPST = TAI - 19 s
    try:
        return np.asarray(to_gps(t_cal, time_system), dtype=float)
    except ValueError:
        raise FileFormatError(path, 13, f"unknown time system {time_system!r}") from None


def _check_last_epoch(
    path: StrPath, data: list[str], kinds: np.ndarray, star: np.ndarray, offset: int
) -> None:
    """Refuse a last epoch cut short by the end of a file that has no EOF line.

    It is cut when it has fewer ``P`` records than the epoch before it, or when its last
    ``P`` record ends before the clock field.
    """
    last = int(star[-1])
    n_last = int((kinds[last:] == ord("P")).sum())
    n_before = int((kinds[int(star[-2]) : last] == ord("P")).sum()) if len(star) > 1 else n_last
    p_lines = np.flatnonzero(kinds[last:] == ord("P"))
    if n_last < n_before:
        raise FileFormatError(
            path,
            offset + last + 1,
            f"last epoch cut short by the end of the file: {n_last} of {n_before} P records "
            "and no EOF line",
        )
    if len(p_lines):
        k = last + int(p_lines[-1])
        if len(data[k].rstrip()) < _P_RECORD_CHARS:
            raise FileFormatError(
                path, offset + k + 1, "P record cut short by the end of the file (no EOF line)"
            )


def _implausible(pos_m: FloatArray, clock_s: FloatArray, p_rows: _Rows) -> tuple[SkippedLine, ...]:
    """Set positions off the orbit shell to NaN (with their clocks); their lines and why."""
    r = np.linalg.norm(pos_m, axis=-1)
    lo, hi = PLAUSIBLE_RADIUS_M
    with np.errstate(invalid="ignore"):
        bad = (r < lo) | (r > hi)
    if not bad.any():
        return ()
    ei, si, _, lineno = p_rows
    line_at = np.zeros(bad.shape, dtype=np.int64)
    line_at[ei, si] = lineno
    out = [
        SkippedLine(
            int(line_at[e, s]),
            f"position {r[e, s] / 1e3:.6g} km from the geocentre, outside the "
            f"{lo / 1e3:g}-{hi / 1e3:g} km orbit shell: satellite excluded at this epoch",
        )
        for e, s in zip(*np.nonzero(bad), strict=True)
    ]
    pos_m[bad] = np.nan
    clock_s[bad] = np.nan
    return tuple(sorted(out, key=lambda sk: sk.line))


def _jumps(
    t_gps_s: FloatArray, pos_m: FloatArray, clock_s: FloatArray, p_rows: _Rows
) -> tuple[SkippedLine, ...]:
    """Set records that jump farther than orbital motion allows to NaN; their lines and why.

    Between consecutive records ``a, b`` of one satellite (``dt`` apart, gaps skipped) the
    position may move at most ``(sqrt(2 GM / min(r_a, r_b)) + omega_E max(r_a, r_b)) dt``.

    Notes
    -----
    The bound is the escape speed at the lower of the two radii (no bound orbit is faster
    there) plus the speed the earth-fixed frame's rotation adds at the higher one: about twice
    the ECEF speed of a GNSS satellite (7.4 vs 3.9 km/s for GPS), so orbits are never flagged
    while a coordinate off by a few thousand km over a 5-minute interval is. A record that
    jumps from both neighbours (or from its only neighbour, when that one agrees with its own
    next neighbour) is the outlier and is set missing at its epoch. A jump that cannot be
    blamed on one record (a step: the orbit before and after disagree) excludes the satellite
    from the whole file.
    """
    ei, si, _, lineno = p_rows
    line_at = np.zeros(pos_m.shape[:2], dtype=np.int64)
    line_at[ei, si] = lineno
    out: list[SkippedLine] = []
    for s in range(pos_m.shape[1]):
        valid = np.flatnonzero(np.isfinite(pos_m[:, s, 0]))
        if valid.size < 2:
            continue
        bad = _jumping(t_gps_s[valid], pos_m[valid, s])
        if not bad.any():
            continue
        n = valid.size
        before = np.concatenate([[False], bad])  # record k jumps from record k - 1
        after = np.concatenate([bad, [False]])  # record k jumps to record k + 1
        outlier = before & after
        if n > 2:
            outlier[0] |= bad[0] and not bad[1]
            outlier[-1] |= bad[-1] and not bad[-2]
        keep = valid[~outlier]
        remaining = _jumping(t_gps_s[keep], pos_m[keep, s]) if keep.size > 1 else bad[:0]
        for k in valid[outlier]:
            out.append(
                SkippedLine(
                    int(line_at[k, s]),
                    "position jumps from the neighbouring records farther than orbital motion "
                    "allows: satellite excluded at this epoch",
                )
            )
        pos_m[valid[outlier], s] = np.nan
        clock_s[valid[outlier], s] = np.nan
        if remaining.any():
            k = int(keep[int(np.argmax(remaining)) + 1])
            out.append(
                SkippedLine(
                    int(line_at[k, s]),
                    "position jumps from the record before farther than orbital motion allows "
                    "(a step, not one bad record): satellite excluded from the whole file",
                )
            )
            pos_m[:, s] = np.nan
            clock_s[:, s] = np.nan
    return tuple(out)


def _jumping(t_s: FloatArray, pos_m: FloatArray) -> np.ndarray:
    """``(n - 1,)`` whether each step between consecutive positions ``(n, 3)`` exceeds the
    orbital-motion bound of :func:`_jumps`."""
    r = np.linalg.norm(pos_m, axis=-1)
    r_lo = np.minimum(r[1:], r[:-1])
    r_hi = np.maximum(r[1:], r[:-1])
    speed = np.sqrt(2.0 * _GM_M3S2 / r_lo) + OMEGA_E_RAD_S * r_hi
    step = np.linalg.norm(np.diff(pos_m, axis=0), axis=-1)
    return np.asarray(step > speed * np.diff(t_s))


_Rows = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]  # epoch, column, chars, line no.


def _rows(
    path: StrPath,
    chars: np.ndarray,
    kinds: np.ndarray,
    kind: str,
    star: np.ndarray,
    sat_col: dict[str, int],
    offset: int,
) -> _Rows:
    """Epoch index, satellite column, characters and line number of every P (or V) record."""
    idx = np.flatnonzero(kinds == ord(kind))
    epoch = np.searchsorted(star, idx) - 1
    lineno = offset + idx + 1
    if len(idx) and epoch[0] < 0:
        raise FileFormatError(path, int(lineno[0]), f"{kind} record before the first epoch")
    rec = chars[idx]
    ids, inverse = np.unique(rec[:, 1:4].copy().view("S3").ravel(), return_inverse=True)
    cols = np.empty(len(ids), dtype=np.int64)
    for u, raw in enumerate(ids):
        text = raw.decode("ascii", "replace").ljust(3)
        k = sat_col.get(text)
        if k is None:  # ids written differently from the header ("G 1")
            first = int(lineno[np.flatnonzero(inverse == u)[0]])
            k = _col(path, first, sat_col, text)
        cols[u] = k
    return epoch, cols[inverse.ravel()], rec, lineno


def _fixed_width(chars: np.ndarray, width: int) -> FloatArray:
    """Parse a (rows, n * width) character block of numeric fields: (rows, n) floats, NaN
    for blank fields; ValueError if any field is not a number."""
    n_rows = chars.shape[0]
    block = np.ascontiguousarray(chars).reshape(-1, width)
    blank = (block == 32).all(axis=1)
    block[blank, -1] = ord("0")
    out = block.view(f"S{width}").reshape(-1).astype(float)
    out[blank] = np.nan
    return out.reshape(n_rows, -1)


def _records(
    path: StrPath,
    rows: _Rows,
    n_e: int,
    n_s: int,
    base_pos: float,
    base_clk: float,
) -> tuple[FloatArray, FloatArray, FloatArray | None, FloatArray | None, Int8Array]:
    """Values of P (or V) records: xyz (file units), clock, standard deviations, flags."""
    ei, si, rec, lineno = rows
    xyz = np.full((n_e, n_s, 3), np.nan)
    clk = np.full((n_e, n_s), np.nan)
    flags = np.zeros((n_e, n_s), dtype=np.int8)
    try:
        vals = _fixed_width(rec[:, 4:60], 14)
    except ValueError:  # locate the damaged line
        for r, ln in zip(rec, lineno, strict=True):
            _fixed(path, int(ln), r.tobytes().decode("ascii", "replace"))
        raise
    bad_pos = np.all(vals[:, :3] == 0.0, axis=1)
    vals[bad_pos, :3] = np.nan
    vals[vals[:, 3] >= _BAD_CLOCK, 3] = np.nan
    xyz[ei, si] = vals[:, :3]
    clk[ei, si] = vals[:, 3]
    pos_sd = clk_sd = None
    extra = np.flatnonzero((rec[:, 60:80] != 32).any(axis=1))
    if len(extra):
        tail = rec[extra]
        # exponents: columns 62-63, 65-66, 68-69 (x, y, z) and 71-73 (clock), 1-based
        try:
            pos_exp = _fixed_width(tail[:, [61, 62, 64, 65, 67, 68]], 2)
            clk_exp = _fixed_width(tail[:, 70:73], 3)[:, 0]
        except ValueError:
            for k in extra.tolist():
                t = rec[k].tobytes().decode("ascii", "replace")
                for c0, c1 in ((61, 63), (64, 66), (67, 69), (70, 73)):
                    _opt_int(path, int(lineno[k]), t[c0:c1])
            raise
        e, s = ei[extra], si[extra]
        pos_sd = np.full((n_e, n_s, 3), np.nan)
        clk_sd = np.full((n_e, n_s), np.nan)
        pos_sd[e, s] = base_pos**pos_exp * 1e-3  # mm -> m (velocity: 1e-4 mm/s)
        clk_sd[e, s] = base_clk**clk_exp * 1e-12  # ps -> s (rate: 1e-4 ps/s)
        f = np.zeros(len(extra), dtype=np.int8)
        for c, bit in _FLAG_BITS:
            f |= np.where(tail[:, c] != 32, bit, 0).astype(np.int8)
        flags[e, s] = f
    return xyz, clk, pos_sd, clk_sd, flags


def _fixed(path: StrPath, lineno: int, line: str) -> list[float]:
    out = []
    for c in (4, 18, 32, 46):
        s = line[c : c + 14].strip()
        if not s:
            out.append(math.nan)
            continue
        out.append(_float(path, lineno, s, "coordinate/clock"))
    return out


def _float(path: StrPath, lineno: int, text: str, what: str) -> float:
    s = text.strip()
    if not s:
        return math.nan
    try:
        return float(s)
    except ValueError:
        raise FileFormatError(path, lineno, f"unreadable {what} {s!r}") from None


def _int(path: StrPath, lineno: int, text: str) -> int:
    s = text.strip()
    try:
        return int(s) if s else 0
    except ValueError:
        raise FileFormatError(path, lineno, f"unreadable integer {s!r}") from None


def _opt_int(path: StrPath, lineno: int, text: str) -> int | None:
    s = text.strip()
    return _int(path, lineno, s) if s else None


def _sat_id(path: StrPath, raw: str) -> str:
    s = raw.strip()
    if not s:
        raise FileFormatError(path, 3, "blank satellite id in the header list")
    try:
        if s[0].isdigit():  # SP3-a: no system letter means GPS
            return f"G{int(s):02d}"
        return f"{s[0]}{int(s[1:]):02d}"
    except ValueError:
        raise FileFormatError(path, 3, f"unreadable satellite id {raw!r}") from None


def _col(path: StrPath, lineno: int, sat_col: dict[str, int], raw: str) -> int:
    k = sat_col.get(raw)
    if k is None:
        try:
            k = sat_col.get(_sat_id(path, raw))
        except (ValueError, FileFormatError):
            k = None
        if k is None:
            raise FileFormatError(path, lineno, f"satellite {raw!r} not listed in the header")
        sat_col[raw] = k
    return k


def _epoch(path: StrPath, lineno: int, line: str) -> float:
    parts = line[2:].split()
    try:
        y, mo, d, h, mi = (int(p) for p in parts[:5])
        sec = float(parts[5])
        return calendar_gps_seconds(y, mo, d, h, mi, sec)
    except (ValueError, IndexError):
        raise FileFormatError(path, lineno, f"unreadable epoch {line.strip()!r}") from None
