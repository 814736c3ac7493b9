"""Android GnssLogger raw measurement logs -> :class:`~navtrack.gnss.observations.Observations`.

:func:`read_gnsslogger` reads the ``Raw,`` rows of a GnssLogger text log (old and new column
sets: the ``# Raw,...`` header comment defines the columns) and builds, per epoch and signal,
the RINEX-like observables

* ``C..`` pseudorange (m) from ``TimeNanos``, ``FullBiasNanos``, ``BiasNanos``,
  ``TimeOffsetNanos`` and ``ReceivedSvTimeNanos`` with each constellation's time of week /
  day / 100 ms ambiguity resolved;
* ``L..`` carrier phase (cycles) from ``AccumulatedDeltaRangeMeters`` when the ADR state is
  valid (LLI bit 0 set on reset or cycle slip);
* ``D..`` Doppler (Hz, RINEX sign: positive when the satellite approaches) = -PRR / λ;
* ``S..`` carrier-to-noise density ``Cn0DbHz`` (dB-Hz).

Signal codes are RINEX 3 codes chosen by constellation and carrier frequency
(``CarrierFrequencyHz``; logs without it are taken to be on the primary band: GPS/QZSS/Galileo
L1/E1 ``1C``, GLONASS G1 ``1C``, BeiDou B1I ``2I``) with the attribute from ``CodeType`` when
logged (else the usual smartphone attribute: C for L1/E1/G1, Q for L5/E5a, I for B1I).

Rows that cannot give a valid pseudorange are not dropped silently: each is listed in
:attr:`Observations.skipped` with its line number and one of the reasons in
:data:`SKIP_REASONS`; :func:`skipped_counts` tallies them. Damage is refused (strict reading)
or skipped and counted (``lenient=True``) like the RINEX readers do: a ``Raw`` row with a field
that is not a number -- in any numeric column, used or not -- or with more fields than its
header (``"unreadable row"``), and a line that is no GnssLogger record at all (neither a
``#`` comment nor ``Type,...`` with a record-type word, ``"not a log record"``). Records of the
other types (``Fix``, ``Status``, ``UncalAccel``, ...) are not read.

References
----------
European GNSS Agency, "Using GNSS raw measurements on Android devices", white paper, 2017,
sections 2.4 and 5 (pseudorange generation, time ambiguities per constellation);
Android ``android.location.GnssMeasurement`` reference (state bits, ADR state bits, Svid
ranges); RINEX 3.05 section 5.2.10 (Doppler sign) and table 4-10 (codes).
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections import Counter
from os import fspath
from typing import NamedTuple

import numpy as np

from navtrack._typing import StrPath
from navtrack.errors import FileFormatError
from navtrack.geodesy import C_MPS
from navtrack.gnss.observations import Observations, ObsHeader, SkippedLine
from navtrack.gnss.rinex._io import read_bytes
from navtrack.timescale import BDT_MINUS_GPST_S, GLONASST_MINUS_UTC_S, leap_seconds

__all__ = ["SKIP_REASONS", "read_gnsslogger", "skipped_counts"]

_WEEK_NS = 604800 * 10**9
_DAY_NS = 86400 * 10**9
_100MS_NS = 100 * 10**6

# android.location.GnssMeasurement state bits
_TOW_DECODED = 8
_MSEC_AMBIGUOUS = 16
_GLO_TOD_DECODED = 128
_GAL_E1C_2ND_CODE_LOCK = 2048
_TOW_KNOWN = 16384
_GLO_TOD_KNOWN = 32768
# AccumulatedDeltaRangeState bits
_ADR_VALID = 1
_ADR_RESET = 2
_ADR_CYCLE_SLIP = 4

# Android ConstellationType -> RINEX system letter (2 SBAS and 0 unknown are not used)
_CONSTELLATION = {1: "G", 3: "R", 4: "J", 5: "C", 6: "E", 7: "I"}

SKIP_REASONS = (
    "constellation not supported",
    "no GNSS time (FullBiasNanos missing)",
    "GLONASS slot unknown (frequency channel only)",
    "millisecond ambiguity",
    "TOW/TOD not decoded",
    "satellite time uncertainty too large",
    "pseudorange out of range",
    "unknown carrier frequency",
    "duplicate signal in epoch",
    "unreadable row",
    "not a log record",
)
"""Reasons a ``Raw`` row gives no observation (the ``reason`` of its ``SkippedLine``)."""

_REQUIRED = (
    "TimeNanos",
    "FullBiasNanos",
    "Svid",
    "State",
    "ReceivedSvTimeNanos",
    "ReceivedSvTimeUncertaintyNanos",
    "Cn0DbHz",
    "ConstellationType",
)
# Carrier frequencies (Hz) of the bands phones track, by system: (centre, band digit,
# default attribute when CodeType is not logged).
_BANDS: dict[str, tuple[tuple[float, str, str], ...]] = {
    "G": ((1575.42e6, "1", "C"), (1176.45e6, "5", "Q"), (1227.60e6, "2", "L")),
    "J": ((1575.42e6, "1", "C"), (1176.45e6, "5", "Q"), (1227.60e6, "2", "L")),
    "E": ((1575.42e6, "1", "C"), (1176.45e6, "5", "Q"), (1207.14e6, "7", "Q")),
    "C": ((1561.098e6, "2", "I"), (1575.42e6, "1", "P"), (1176.45e6, "5", "P")),
    "I": ((1176.45e6, "5", "A"),),
}
_DEFAULT_FREQ = {"G": 1575.42e6, "J": 1575.42e6, "E": 1575.42e6, "C": 1561.098e6, "I": 1176.45e6}
_PR_MIN_M, _PR_MAX_M = 1.0e7, 6.0e7
# a record of any GnssLogger type: "Fix,...", "UncalAccel,...", "Raw,..."
_RECORD_TYPE = re.compile(r"[A-Za-z][A-Za-z0-9]*,")
_TEXT_COLUMNS = frozenset({"CodeType"})  # every other Raw column is a number


def read_gnsslogger(
    path: StrPath,
    *,
    max_sv_time_uncertainty_ns: float = 500.0,
    lenient: bool = False,
) -> Observations:
    """Read an Android GnssLogger raw log into observations.

    Parameters
    ----------
    path : str or path-like
        GnssLogger ``.txt`` log (plain or gzip).
    max_sv_time_uncertainty_ns : float
        Rows with ``ReceivedSvTimeUncertaintyNanos`` at or above this are skipped (500 ns,
        ~150 m, as in Google's gps-measurement-tools and the shared data README).
    lenient : bool
        When true, an unreadable ``Raw`` row is skipped with reason ``"unreadable row"`` and a
        line that is not a log record with ``"not a log record"``; when false (default) both
        raise.

    Returns
    -------
    Observations
        Epochs are the distinct ``TimeNanos`` of the rows, in time order; ``t_gps_s`` is the
        phone's GPS time of reception ``TimeNanos - (FullBiasNanos + BiasNanos)`` (s).
        ``clock_offset_s`` is NaN (the phone's clock bias is already removed by
        ``FullBiasNanos``/``BiasNanos``; what remains is estimated by the positioning).
        ``header.version`` is 0.0 and ``header.receiver`` holds the logger's version line.
        Every ``Raw`` row either gives values or is listed in ``skipped``.

    Notes
    -----
    Validity, per constellation (GSA white paper table 5): GPS, QZSS, BeiDou, NavIC and
    Galileo need ``TOW_DECODED`` or ``TOW_KNOWN`` (pseudorange from the time of week; BeiDou
    in BDT = GPST - 14 s); Galileo with only ``GAL_E1C_2ND_CODE_LOCK`` gives the time within
    100 ms and the pseudorange is resolved modulo 100 ms (valid since Galileo ranges are
    < 100 light-ms); GLONASS needs ``GLO_TOD_DECODED`` or ``GLO_TOD_KNOWN`` (time of day in
    UTC(SU) + 3 h; GPS - UTC from the ``LeapSecond`` column when logged, else from the IERS
    table). Rows with ``MSEC_AMBIGUOUS`` are skipped. GLONASS rows whose ``Svid`` is a
    frequency channel (93-106) rather than an orbital slot cannot be matched to an ephemeris
    and are skipped. Doppler for GLONASS needs ``CarrierFrequencyHz`` (NaN otherwise).

    Raises
    ------
    FileFormatError
        No ``# Raw,`` header line, a required column missing, or (strict reading) an
        unreadable ``Raw`` row or a line that is not a log record; the message names the file
        and line (and the column of a malformed field).
    """
    text = read_bytes(path).decode("utf-8", "replace")
    log = _scan_lines(path, text.splitlines(), lenient)
    n_lines = len(text.splitlines())
    rows = log.rows
    cut = rows and rows[-1][0] == n_lines and not text.endswith(("\n", "\r"))
    if cut and len(rows[-1][1]) < len(log.columns):
        # the last row, without its end of line, has fewer fields than the header: cut short
        # by the end of the file, its last field possibly cut too
        if not lenient:
            raise FileFormatError(path, n_lines, "Raw row cut short by the end of the file")
        log.garbage.append(SkippedLine(n_lines, "unreadable row"))
        rows.pop()
    obs = _build(path, log, max_sv_time_uncertainty_ns, lenient)
    if not log.garbage:
        return obs
    skipped = tuple(sorted((*obs.skipped, *log.garbage), key=lambda sk: sk.line))
    return obs.replace(skipped=skipped)


@dataclasses.dataclass(slots=True)
class _Log:
    """The lines of a log that matter: the ``Raw`` columns (index of each name in a row's
    fields after the record type), the version line, other comments, the ``Raw`` rows (line,
    fields) and the lines that are no log record."""

    columns: dict[str, int]
    version_line: str = ""
    comments: list[str] = dataclasses.field(default_factory=list)
    rows: list[tuple[int, list[str]]] = dataclasses.field(default_factory=list)
    garbage: list[SkippedLine] = dataclasses.field(default_factory=list)


def _scan_lines(path: StrPath, lines: list[str], lenient: bool) -> _Log:
    log: _Log | None = None
    version_line = ""
    comments: list[str] = []
    garbage: list[SkippedLine] = []
    for i, line in enumerate(lines):
        if line.startswith("#"):
            body = line[1:].strip()
            if body.startswith("Raw,"):
                names = [c.strip() for c in body.split(",")]
                columns = {n: k - 1 for k, n in enumerate(names) if k > 0}
                missing = [c for c in _REQUIRED if c not in columns]
                if missing:
                    raise FileFormatError(
                        path, i + 1, f"Raw header lacks column(s) {', '.join(missing)}"
                    )
                rows = log.rows if log is not None else []
                log = _Log(columns, rows=rows)
            elif body.startswith("Version"):
                version_line = body
            elif body:
                comments.append(body)
        elif line.startswith("Raw,"):
            if log is None:
                raise FileFormatError(path, i + 1, "Raw row before the '# Raw,...' header line")
            log.rows.append((i + 1, line.split(",")[1:]))
        elif line.strip() and not _RECORD_TYPE.match(line):
            if not lenient:
                raise FileFormatError(
                    path, i + 1, f"not a GnssLogger record or comment: {line[:40]!r}"
                )
            garbage.append(SkippedLine(i + 1, "not a log record"))
    if log is None:
        raise FileFormatError(path, None, "not a GnssLogger log: no '# Raw,...' header line")
    log.version_line, log.comments, log.garbage = version_line, comments, garbage
    return log


def skipped_counts(obs: Observations) -> dict[str, int]:
    """Number of skipped rows per reason (in :data:`SKIP_REASONS` order)."""
    counts = Counter(s.reason for s in obs.skipped)
    return {r: counts[r] for r in SKIP_REASONS if counts[r]}


def _int_field(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        value = float(text)  # some loggers write integers as 1.0E10
        if not math.isfinite(value):
            raise ValueError(f"{text.strip()!r} is not an integer") from None
        return int(value)


def _check_numbers(fields: list[str], numeric: list[tuple[int, str]]) -> None:
    """Every non-empty field of a numeric column is a number (used by navtrack or not)."""
    for k, name in numeric:
        if k < len(fields) and fields[k].strip():
            try:
                float(fields[k])
            except ValueError:
                raise ValueError(f"{name} {fields[k][:20]!r} is not a number") from None


def _float_field(text: str) -> float:
    return float(text) if text.strip() else math.nan


class _RawRow(NamedTuple):
    """The fields of a ``Raw`` row that navtrack uses (NaN / None where not logged)."""

    time_nanos: int
    const: int
    svid: int
    state: int
    rx_sv_ns: int
    unc_ns: float
    cn0: float
    full_bias: int | None
    bias_ns: float
    offset_ns: float
    prr: float
    freq: float
    adr: float
    adr_state: int
    leap: int | None
    code_type: str


def _parse_row(f: list[str], col: dict[str, int], numeric: list[tuple[int, str]]) -> _RawRow:
    """The fields of one row; ValueError or IndexError when it cannot be read."""
    n_cols = max(col.values()) + 1
    if len(f) < min(n_cols, max(col[c] for c in _REQUIRED) + 1):
        raise ValueError("too few fields")
    if len(f) > n_cols:
        raise ValueError(f"{len(f)} fields, the header has {n_cols}")
    _check_numbers(f, numeric)

    def opt(name: str) -> str:
        k = col.get(name)
        return f[k] if k is not None and k < len(f) else ""

    full_bias_txt = f[col["FullBiasNanos"]].strip()
    adr_state_txt = opt("AccumulatedDeltaRangeState").strip()
    leap_txt = opt("LeapSecond").strip()
    bias_ns = _float_field(opt("BiasNanos"))
    offset_ns = _float_field(opt("TimeOffsetNanos"))
    return _RawRow(
        time_nanos=_int_field(f[col["TimeNanos"]]),
        const=_int_field(f[col["ConstellationType"]]),
        svid=_int_field(f[col["Svid"]]),
        state=_int_field(f[col["State"]]),
        rx_sv_ns=_int_field(f[col["ReceivedSvTimeNanos"]]),
        unc_ns=_float_field(f[col["ReceivedSvTimeUncertaintyNanos"]]),
        cn0=_float_field(f[col["Cn0DbHz"]]),
        full_bias=_int_field(full_bias_txt) if full_bias_txt else None,
        bias_ns=0.0 if math.isnan(bias_ns) else bias_ns,
        offset_ns=0.0 if math.isnan(offset_ns) else offset_ns,
        prr=_float_field(opt("PseudorangeRateMetersPerSecond")),
        freq=_float_field(opt("CarrierFrequencyHz")),
        adr=_float_field(opt("AccumulatedDeltaRangeMeters")),
        adr_state=_int_field(adr_state_txt) if adr_state_txt else 0,
        leap=_int_field(leap_txt) if leap_txt else None,
        code_type=opt("CodeType").strip(),
    )


# (epoch key, sat, signal, pseudorange m, phase cycles, Doppler Hz, C/N0 dB-Hz, LLI)
_Measurement = tuple[int, str, str, float, float, float, float, int]


def _measurement(r: _RawRow, max_unc_ns: float) -> _Measurement | str:
    """The measurement of a row, or the reason it is skipped (:data:`SKIP_REASONS`)."""
    sys_letter = _CONSTELLATION.get(r.const)
    if sys_letter is None:
        return "constellation not supported"
    assert r.full_bias is not None  # checked by the caller (the epoch needs it)
    t_rx_int = r.time_nanos - r.full_bias
    if sys_letter == "R" and not 1 <= r.svid <= 24:
        return "GLONASS slot unknown (frequency channel only)"
    if r.state & _MSEC_AMBIGUOUS:
        return "millisecond ambiguity"
    period, t_rx_scale = _time_reference(sys_letter, r.state, t_rx_int, r.leap)
    if period == 0:
        return "TOW/TOD not decoded"
    if not r.unc_ns < max_unc_ns:  # NaN uncertainty fails too
        return "satellite time uncertainty too large"
    # travel time; the modulo also resolves a week/day rollover between transmission and
    # reception (Python's % of ints is never negative)
    tau_ns = ((t_rx_scale - r.rx_sv_ns) % period) + (r.offset_ns - r.bias_ns)
    pr_m = tau_ns * 1e-9 * C_MPS
    if not _PR_MIN_M < pr_m < _PR_MAX_M:
        return "pseudorange out of range"
    sig = _signal(sys_letter, r.freq, r.code_type)
    if sig is None:
        return "unknown carrier frequency"
    sat = f"{sys_letter}{r.svid - 192 if sys_letter == 'J' else r.svid:02d}"
    f_hz = r.freq if not math.isnan(r.freq) else _DEFAULT_FREQ.get(sys_letter, math.nan)
    wavelength = C_MPS / f_hz
    phase = r.adr / wavelength if r.adr_state & _ADR_VALID else math.nan
    lli = 1 if r.adr_state & (_ADR_RESET | _ADR_CYCLE_SLIP) else 0
    if math.isnan(phase):
        lli = -1
    return (r.time_nanos, sat, sig, pr_m, phase, -r.prr / wavelength, r.cn0, lli)


def _build(path: StrPath, log: _Log, max_unc_ns: float, lenient: bool) -> Observations:
    skipped: list[SkippedLine] = []
    good: list[_Measurement] = []
    epoch_time: dict[int, float] = {}
    seen: set[tuple[int, str, str]] = set()
    numeric = [(k, name) for name, k in log.columns.items() if name not in _TEXT_COLUMNS]
    for lineno, f in log.rows:
        try:
            r = _parse_row(f, log.columns, numeric)
        except (ValueError, IndexError) as exc:
            if not lenient:
                raise FileFormatError(path, lineno, f"unreadable Raw row ({exc})") from None
            skipped.append(SkippedLine(lineno, "unreadable row"))
            continue
        if r.const in _CONSTELLATION and not r.full_bias:
            skipped.append(SkippedLine(lineno, "no GNSS time (FullBiasNanos missing)"))
            continue
        if r.const in _CONSTELLATION and r.time_nanos not in epoch_time:
            # receiver GNSS time: integer ns since the GPS epoch plus a sub-ns float part
            t_rx_int = r.time_nanos - (r.full_bias or 0)
            t_s = (t_rx_int // 10**9) + ((t_rx_int % 10**9) - r.bias_ns) * 1e-9
            epoch_time[r.time_nanos] = t_s
        m = _measurement(r, max_unc_ns)
        if isinstance(m, tuple) and (m[0], m[1], m[2]) in seen:
            m = "duplicate signal in epoch"
        if isinstance(m, str):
            skipped.append(SkippedLine(lineno, m))
            continue
        seen.add((m[0], m[1], m[2]))
        good.append(m)
    skipped.sort(key=lambda s: s.line)
    return _observations(path, log, good, epoch_time, skipped)


def _observations(
    path: StrPath,
    log: _Log,
    good: list[_Measurement],
    epoch_time: dict[int, float],
    skipped: list[SkippedLine],
) -> Observations:
    keys = sorted(epoch_time)
    e_index = {k: n for n, k in enumerate(keys)}
    sats = tuple(sorted({g[1] for g in good}, key=lambda s: ("GRECJSI".index(s[0]), s)))
    s_index = {s: n for n, s in enumerate(sats)}
    signals = sorted({g[2] for g in good}, key=lambda c: (c[0], c[1]))
    codes = tuple(f"{t}{c}" for c in signals for t in "CLDS")
    c_index = {c: n for n, c in enumerate(codes)}
    values = np.full((len(keys), len(sats), len(codes)), np.nan)
    lli_arr = np.full(values.shape, -1, dtype=np.int8)
    for time_nanos, sat, sig, pr_m, phase, doppler, cn0, lli in good:
        e, s = e_index[time_nanos], s_index[sat]
        values[e, s, c_index["C" + sig]] = pr_m
        values[e, s, c_index["L" + sig]] = phase
        values[e, s, c_index["D" + sig]] = doppler
        values[e, s, c_index["S" + sig]] = cn0
        lli_arr[e, s, c_index["L" + sig]] = lli
    obs_types: dict[str, tuple[str, ...]] = {}
    for sys_letter in "GRECJSI":
        present = sorted({g[2] for g in good if g[1][0] == sys_letter})
        if present:
            obs_types[sys_letter] = tuple(f"{t}{c}" for c in present for t in "CLDS")
    version = log.version_line
    header = ObsHeader(
        version=0.0,
        file_type="O",
        system="M",
        receiver=f"Android GnssLogger ({version})" if version else "Android GnssLogger",
        time_system="GPS",
        obs_types=obs_types,
        comments=tuple(log.comments),
    )
    return Observations(
        path=fspath(path),
        header=header,
        t_gps_s=np.array([epoch_time[k] for k in keys], dtype=float),
        epoch_flag=np.zeros(len(keys), dtype=np.int8),
        clock_offset_s=np.full(len(keys), np.nan),
        sats=sats,
        codes=codes,
        values=values,
        lli=lli_arr,
        ssi=np.full(values.shape, -1, dtype=np.int8),
        skipped=tuple(skipped),
    )


def _time_reference(
    sys_letter: str, state: int, t_rx_int: int, leap: int | None
) -> tuple[int, int]:
    """Ambiguity period (ns; 0 when the satellite time is not usable) and the receiver time
    expressed in the satellite's time scale, reduced modulo that period (ns)."""
    if sys_letter == "R":
        if not state & (_GLO_TOD_DECODED | _GLO_TOD_KNOWN):
            return 0, 0
        if leap is None:
            leap = int(leap_seconds(t_rx_int * 1e-9))
        t_glo = t_rx_int - leap * 10**9 + int(GLONASST_MINUS_UTC_S) * 10**9
        return _DAY_NS, t_glo % _DAY_NS
    t = t_rx_int
    if sys_letter == "C":
        t += int(BDT_MINUS_GPST_S) * 10**9
    if state & (_TOW_DECODED | _TOW_KNOWN):
        return _WEEK_NS, t % _WEEK_NS
    if sys_letter == "E" and state & _GAL_E1C_2ND_CODE_LOCK:
        return _100MS_NS, t % _100MS_NS
    return 0, 0


def _signal(sys_letter: str, freq_hz: float, code_type: str) -> str | None:
    """RINEX band digit + attribute of a signal (``"1C"``), None for an unknown frequency."""
    if sys_letter == "R":
        # G1 FDMA: 1602 MHz + k * 562.5 kHz, k = -7..+6; G2: 1246 MHz + k * 437.5 kHz
        if math.isnan(freq_hz) or 1597.0e6 < freq_hz < 1606.5e6:
            return "1" + (code_type or "C")
        if 1242.0e6 < freq_hz < 1249.5e6:
            return "2" + (code_type or "C")
        return None
    bands = _BANDS[sys_letter]
    if math.isnan(freq_hz):
        band, attr = bands[0][1], bands[0][2]
        return band + (code_type or attr)
    for centre, band, attr in bands:
        if abs(freq_hz - centre) < 2.0e6:
            return band + (code_type or attr)
    return None
