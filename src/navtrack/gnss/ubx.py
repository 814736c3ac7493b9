"""u-blox UBX raw receiver logs -> :class:`Observations` and broadcast navigation data.

:func:`read_ubx` reads a binary UBX log as recorded from a u-blox receiver (M8T, M8P, F9P, X20P,
...; UBX protocol 17 and later) and returns a :class:`UbxLog`:

* ``RXM-RAWX`` (0x02 0x15) -> :class:`~navtrack.gnss.observations.Observations`: per epoch and
  signal the pseudorange ``C`` (m), carrier phase ``L`` (cycles), Doppler ``D`` (Hz, RINEX sign)
  and ``S`` the carrier-to-noise density (dB-Hz), under RINEX 3.04 signal codes (table
  :data:`SIGNALS`). Time tags are the receiver's (``week``, ``rcvTow``), not snapped to a grid.
  The loss-of-lock indicator is built from the tracking state as RINEX defines it: bit 0
  (cycle slip possible) when the lock time is 0, shorter than the time since the signal's
  previous observation, lower than at that observation, when the half-cycle subtraction
  state changed, at a receiver clock reset and at a signal's first observation; bit 1
  (half-cycle ambiguity) while the receiver has not resolved the half cycle (``trkStat`` bit 2
  clear).
* ``RXM-SFRBX`` (0x02 0x13) -> :class:`~navtrack.gnss.rinex.nav.NavData`: GPS and QZSS LNAV
  subframes 1-3 become one ephemeris record per issue (IODC = IODE of both subframes), GPS
  subframe 4 page 18 the Klobuchar parameters, the GPS-UTC polynomial and the leap seconds;
  Galileo I/NAV word types 1-5 of one IODnav (E1-B or E5b-I pages, CRC-24Q checked) one
  record per (IODnav, toe); BeiDou D1 subframes 1-3 of one frame (on B1I, B2I or B3I, MEO and
  IGSO satellites) one record per (AODE, toe); GLONASS strings 1-4 of one frame one record per
  (slot, tb). Galileo F/NAV, BeiDou D2 (GEO) and B-CNAV, GLONASS strings 5-15, SBAS and
  GPS/QZSS CNAV are not decoded, nor the Galileo and BeiDou ionosphere parameters, and GLONASS
  strings get no Hamming check (the receiver's only): those messages are counted in
  :attr:`UbxLog.undecoded` by system and reason, so a log whose navigation data cannot serve a
  system says so (give a RINEX navigation file for it).

The framing (synchronisation, length, message class and id, resynchronisation after garbage
and NMEA or RTCM sentences interleaved in the log) is pyubx2's; the two payloads are decoded
here with NumPy record types laid out as the u-blox interface description gives them, and each
message's 8-bit Fletcher checksum (interface description 3.2) is verified in closed form
with NumPy (the tests check it against pyubx2's ``calc_checksum``). A message with a bad
checksum or a length that contradicts its own count is refused (``FileFormatError`` naming the
byte offset) or, with ``lenient=True``, skipped and listed in :attr:`UbxLog.skipped`.

Phase validity follows RTKLIB 2.4.3's ``convbin``, so that converted files agree with it: the
phase is dropped when ``trkStat`` bit 1 (carrier phase valid) is clear, when the receiver
writes -0.5 cycles (its marker of an unusable value) and when the phase standard deviation
exceeds ``max_cp_std_cycles`` (default 0.020 cycles: ``cpStdev`` index 5 of 0.004 cycles, the
``CPSTD_VALID`` of RTKLIB's ``ublox.c``); the pseudorange when ``trkStat`` bit 0 is clear.
BeiDou GEO phases (C01-C05, C59-C63) are shifted by +0.5 cycles as RTKLIB does (ublox.c
1.28: u-blox reports them half a cycle off the other BeiDou satellites).

References
----------
u-blox, "u-blox F9 HPG 1.32 Interface Description" (UBX-22008968), sections 3.2 (frame,
checksum), 3.17.6 (UBX-RXM-RAWX), 3.17.9 (UBX-RXM-SFRBX), 1.5.4 (signal identifiers);
"u-blox 8 / M8 Receiver description" (UBX-13003221) 10.2 (navigation data words);
IS-GPS-200N 20.3.2 and 20.3.3 (LNAV subframes 1-4); IS-QZSS-PNT-005 (QZSS LNAV);
BDS-SIS-ICD-B1I 3.0 (2019) 5.2.4 (D1 subframes 1-3); BDS-SIS-ICD-B3I 1.0 (D1 on B3I);
Galileo OS SIS ICD 2.0 (2021) 4.3.4-4.3.5 (I/NAV pages, CRC, word types 1-5), table 89 (SISA);
GLONASS ICD 5.1 (2008) 4.4 (immediate data, strings 1-4);
RINEX 3.04 table A2 (LLI) and section 5.1 (codes).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from os import fspath
from types import MappingProxyType
from typing import Any, BinaryIO

import numpy as np

from navtrack._typing import IntArray, StrPath
from navtrack.errors import FileFormatError
from navtrack.gnss.observations import Observations, ObsHeader, SkippedLine
from navtrack.gnss.rinex.nav import NavData
from navtrack.gnss.ubx_nav import SYSTEM_LETTERS, decode_navigation
from navtrack.timescale import SECONDS_PER_WEEK, gps_seconds

__all__ = ["SIGNALS", "UbxLog", "checksum_ok", "is_ubx", "read_ubx"]

SIGNALS: Mapping[tuple[int, int], str] = MappingProxyType(
    {
        (0, 0): "G1C", (0, 3): "G2L", (0, 4): "G2S", (0, 6): "G5I", (0, 7): "G5Q",
        (1, 0): "S1C",
        (2, 0): "E1C", (2, 1): "E1B", (2, 3): "E5I", (2, 4): "E5Q", (2, 5): "E7I",
        (2, 6): "E7Q", (2, 8): "E6B", (2, 9): "E6C",
        (3, 0): "C2I", (3, 1): "C2I", (3, 2): "C7I", (3, 3): "C7I", (3, 4): "C6I",
        (3, 10): "C6I", (3, 5): "C1P",
        (3, 6): "C1D", (3, 7): "C5P", (3, 8): "C5D",
        (5, 0): "J1C", (5, 1): "J1Z", (5, 4): "J2S", (5, 5): "J2L", (5, 8): "J5I",
        (5, 9): "J5Q",
        (6, 0): "R1C", (6, 2): "R2C",
        (7, 0): "I5A",
    }
)  # fmt: skip
"""(gnssId, sigId) of RXM-RAWX -> system letter and RINEX 3.04 band + attribute (BeiDou B1I is
``2I`` as RINEX 3.02-3.04 write it; D1 and D2 navigation of B1I/B2I/B3I share one code).
QZSS L1C/B (sigId 12) has no RINEX 3.04 code and is counted as unknown."""

_RAWX_HEAD = np.dtype(
    [
        ("rcvTow", "<f8"), ("week", "<u2"), ("leapS", "i1"), ("numMeas", "u1"),
        ("recStat", "u1"), ("version", "u1"), ("reserved", "V2"),
    ]
)  # fmt: skip
_RAWX_MEAS = np.dtype(
    [
        ("prMes", "<f8"), ("cpMes", "<f8"), ("doMes", "<f4"), ("gnssId", "u1"), ("svId", "u1"),
        ("sigId", "u1"), ("freqId", "u1"), ("locktime", "<u2"), ("cno", "u1"),
        ("prStdev", "u1"), ("cpStdev", "u1"), ("doStdev", "u1"), ("trkStat", "u1"),
        ("reserved", "V1"),
    ]
)  # fmt: skip
_SFRBX_HEAD = np.dtype(
    [
        ("gnssId", "u1"), ("svId", "u1"), ("sigId", "u1"), ("freqId", "u1"), ("numWords", "u1"),
        ("chn", "u1"), ("version", "u1"), ("reserved", "V1"),
    ]
)  # fmt: skip
_RAWX = (0x02, 0x15)
_SFRBX = (0x02, 0x13)
_CP_STD_UNIT_CYC = 0.004  # cpStdev: 0.004 cycles per count (4 bits)


@dataclass(frozen=True, slots=True, eq=False)
class UbxLog:
    """What a UBX log holds.

    Attributes
    ----------
    obs : Observations
        The ``RXM-RAWX`` epochs (``header.version`` 0.0, receiver ``u-blox``).
    nav : NavData
        Ephemerides decoded from ``RXM-SFRBX`` (``version`` 0.0); tables only for systems
        with at least one complete ephemeris. The ``line`` column holds the 1-based message
        number of the ephemeris' first subframe in the log.
    messages : mapping of str to int
        UBX messages by class/id (``"RXM-RAWX"``, ``"RXM-SFRBX"``, ``"0x01 0x07"`` ...),
        checksum-valid ones only.
    undecoded : mapping of str to int
        ``RXM-SFRBX`` messages not turned into navigation data, by system letter and reason
        (``"E: Galileo I/NAV not decoded"``, ``"G: subframe 5 (almanac)"``, ...).
    skipped : tuple of SkippedLine
        Messages skipped in lenient reading; ``line`` is the 1-based message number, the reason
        names the byte offset.
    unknown_signals : mapping of str to int
        RAWX measurements whose (gnssId, sigId) has no RINEX code in :data:`SIGNALS`, or
        whose satellite is not identified (GLONASS slot 255), by ``"gnssId/sigId"``.
    undated_epochs : int
        RXM-RAWX messages with week 0 (a receiver that does not know GPS time yet, at
        start-up): no epoch can be tagged, so they are not in ``obs``.
    """

    obs: Observations
    nav: NavData
    messages: Mapping[str, int]
    undecoded: Mapping[str, int]
    skipped: tuple[SkippedLine, ...] = ()
    unknown_signals: Mapping[str, int] = field(default_factory=dict)
    undated_epochs: int = 0

    def __post_init__(self) -> None:
        for name in ("messages", "undecoded", "unknown_signals"):
            object.__setattr__(self, name, MappingProxyType(dict(getattr(self, name))))


def is_ubx(path: StrPath) -> bool:
    """True when the file's first 4 kB hold a UBX frame start (``0xB5 0x62``) followed by a
    known message class: a UBX log, possibly with NMEA sentences interleaved."""
    with open(path, "rb") as f:
        head = f.read(4096)
    k = head.find(b"\xb5\x62")
    while k >= 0 and k + 2 < len(head):
        if head[k + 2] in (0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x0A, 0x0D, 0x10, 0x13, 0x21):
            return True
        k = head.find(b"\xb5\x62", k + 1)
    return False


def read_ubx(path: StrPath, *, lenient: bool = False, max_cp_std_cycles: float = 0.020) -> UbxLog:
    """Read a u-blox UBX log (module notes).

    Parameters
    ----------
    path : str or path-like
        The log (binary UBX, NMEA or RTCM 3 messages interleaved are passed over).
    lenient : bool, default False
        False: a message with a bad checksum or an inconsistent length raises. True: it is
        skipped and listed in :attr:`UbxLog.skipped`.
    max_cp_std_cycles : float, default 0.020
        Carrier phases whose reported standard deviation exceeds this are dropped (RTKLIB
        ``convbin``'s threshold; ``inf`` keeps every phase the receiver marks valid).

    Raises
    ------
    FileFormatError
        No RXM-RAWX message in the file, or (strict reading) a damaged message.
    ImportError
        pyubx2 is not installed (``pip install navtrack[ublox]``).
    """
    try:
        from pyubx2 import UBX_PROTOCOL, UBXReader
    except ImportError as exc:  # pragma: no cover - the extra is installed in tests
        raise ImportError(
            "reading u-blox logs needs pyubx2: pip install 'navtrack[ublox]'"
        ) from exc
    scan = _Scan(path, lenient)
    with open(path, "rb") as stream:
        _frame(
            stream,
            scan,
            lambda: UBXReader(stream, protfilter=UBX_PROTOCOL, parsing=False, quitonerror=0),
        )
    epochs, subframes = scan.epochs, scan.subframes
    if not epochs and not subframes:
        raise FileFormatError(path, None, "no RXM-RAWX nor RXM-SFRBX message: not a raw log")
    obs, unknown = _observations(path, epochs, max_cp_std_cycles)
    # the 10-bit LNAV week is resolved against the receiver's week; a log without RAWX
    # epochs has none, and the current date stands in (as RTKLIB does)
    t_epochs = [e[0] for e in epochs] or [_now_gps_s()]
    nav, undecoded = decode_navigation(path, subframes, t_epochs, scan.leap)
    return UbxLog(
        obs=obs,
        nav=nav,
        messages=dict(scan.messages),
        undecoded=undecoded,
        skipped=tuple(scan.skipped),
        unknown_signals=unknown,
        undated_epochs=scan.undated,
    )


def _frame(stream: BinaryIO, scan: _Scan, reader: Callable[[], Any]) -> None:
    """Pass every UBX message of ``stream`` to ``scan``, framed by the pyubx2 readers that
    ``reader`` makes. After a damaged message (lenient reading) framing resumes at the byte
    after its sync characters, so that the messages a false length would swallow are found
    (as RTKLIB's decoder does); after a text line that is not NMEA (a sentence cut short and
    run into binary messages) it resumes at that line's end."""
    number = 0
    while True:
        try:
            for raw, _ in reader():
                if raw is None:
                    continue
                number += 1
                at = stream.tell() - len(raw)
                if not scan.add(raw, number, at):
                    stream.seek(at + 2)
                    break
            else:
                return
        except UnicodeDecodeError:
            number += 1
            where = f"text line ending at byte {stream.tell()}"
            scan.bad(number, where, "not NMEA (a truncated sentence?)")


class _Scan:
    """The RXM-RAWX epochs and RXM-SFRBX messages of a log, checked as they are framed."""

    def __init__(self, path: StrPath, lenient: bool) -> None:
        self.path, self.lenient = path, lenient
        self.messages: Counter[str] = Counter()
        self.skipped: list[SkippedLine] = []
        self.epochs: list[tuple[float, int, np.ndarray]] = []  # (t_gps_s, recStat, measurements)
        # (RAWX epochs before it, gnssId, svId, sigId, freqId, words, message number)
        self.subframes: list[tuple[int, int, int, int, int, np.ndarray, int]] = []
        self.leap: int | None = None
        self.undated = 0

    def add(self, raw: bytes, number: int, at: int) -> bool:
        """Take message ``number``, starting at byte ``at``; False when its checksum fails."""
        where = f"message at byte {at}"
        if len(raw) < 8:
            return True
        cls_id = (raw[2], raw[3])
        if not checksum_ok(raw):
            self.bad(number, where, "checksum error")
            return False
        self.messages[_identity(cls_id)] += 1
        why = ""
        if cls_id == _RAWX:
            why = self._rawx(raw[6:-2])
        elif cls_id == _SFRBX:
            why = self._sfrbx(raw[6:-2], number)
        if why:
            self.bad(number, where, why)
        return True

    def bad(self, number: int, where: str, reason: str) -> None:
        if not self.lenient:
            raise FileFormatError(self.path, None, f"{where}: {reason}")
        self.skipped.append(SkippedLine(line=number, reason=f"{where}: {reason}"))

    def _rawx(self, payload: bytes) -> str:
        if len(payload) < _RAWX_HEAD.itemsize:
            return "RXM-RAWX shorter than its header"
        head = np.frombuffer(payload, _RAWX_HEAD, count=1)[0]
        n = int(head["numMeas"])
        if len(payload) != 16 + 32 * n:
            return f"RXM-RAWX of {len(payload)} bytes for {n} measurements"
        if int(head["week"]) == 0:  # no GPS time yet (receiver start-up)
            self.undated += 1
            return ""
        meas = np.frombuffer(payload, _RAWX_MEAS, count=n, offset=16)
        t = int(head["week"]) * SECONDS_PER_WEEK + float(head["rcvTow"])
        self.epochs.append((t, int(head["recStat"]), meas))
        if int(head["recStat"]) & 1:
            self.leap = int(head["leapS"])
        return ""

    def _sfrbx(self, payload: bytes, number: int) -> str:
        if len(payload) < _SFRBX_HEAD.itemsize:
            return "RXM-SFRBX shorter than its header"
        h = np.frombuffer(payload, _SFRBX_HEAD, count=1)[0]
        n = int(h["numWords"])
        if len(payload) != 8 + 4 * n:
            return f"RXM-SFRBX of {len(payload)} bytes for {n} words"
        words = np.frombuffer(payload, "<u4", count=n, offset=8)
        ids = (int(h["gnssId"]), int(h["svId"]), int(h["sigId"]), int(h["freqId"]))
        self.subframes.append((len(self.epochs), *ids, words, number))
        return ""


def checksum_ok(raw: bytes) -> bool:
    """The 8-bit Fletcher checksum over class, id, length and payload: CK_A is the byte sum,
    CK_B the sum of the running CK_A values, i.e. each byte weighted by its distance from the
    end (both modulo 256)."""
    b = np.frombuffer(raw, np.uint8, count=len(raw) - 4, offset=2).astype(np.int64)
    ck_a = int(b.sum()) & 0xFF
    ck_b = int(b @ np.arange(len(b), 0, -1)) & 0xFF
    return ck_a == raw[-2] and ck_b == raw[-1]


def _now_gps_s() -> float:
    return float(gps_seconds(np.datetime64("now", "s")))


def _identity(cls_id: tuple[int, int]) -> str:
    return {_RAWX: "RXM-RAWX", _SFRBX: "RXM-SFRBX"}.get(
        cls_id, f"0x{cls_id[0]:02X} 0x{cls_id[1]:02X}"
    )


# ------------------------------------------------------------------------------ observations


def _observations(
    path: StrPath, epochs: list[tuple[float, int, np.ndarray]], max_cp_std_cycles: float
) -> tuple[Observations, dict[str, int]]:
    """Epoch records -> fixed arrays (one column per satellite, four codes per signal)."""
    allm = np.concatenate([e[2] for e in epochs]) if epochs else np.zeros(0, _RAWX_MEAS)
    ep = np.repeat(np.arange(len(epochs)), [len(e[2]) for e in epochs])
    gnss, sig = allm["gnssId"].astype(int), allm["sigId"].astype(int)
    # one integer per (gnssId, sigId) and per satellite, so that the lookups are array ones
    sig_key = gnss * 256 + sig
    known_keys = np.array([g * 256 + k for g, k in SIGNALS], dtype=int)
    known = np.isin(sig_key, known_keys)
    sv = allm["svId"].astype(int)
    # SBAS PRN 120-158 -> S20-S58; QZSS svId 1-10 (PRN 193-202) -> J01-J10
    prn = np.where(gnss == 1, sv - 100, sv)
    ok = (
        known
        & np.isin(gnss, list(SYSTEM_LETTERS))
        & (prn >= 1)
        & (prn <= 99)
        & ~((gnss == 6) & (sv == 255))
    )
    bad_keys, bad_counts = np.unique(sig_key[~ok], return_counts=True)
    unknown = {f"{k // 256}/{k % 256}": int(n) for k, n in zip(bad_keys, bad_counts, strict=True)}
    rows = np.flatnonzero(ok)
    m, e_i = allm[rows], ep[rows]
    gnss, prn, sig_key = gnss[rows], prn[rows], sig_key[rows]
    sat_key = gnss * 256 + prn
    sat_keys, s_i = np.unique(sat_key, return_inverse=True)
    names = [f"{SYSTEM_LETTERS[k // 256]}{k % 256:02d}" for k in sat_keys]
    order = np.argsort(names, kind="stable")  # satellites sorted as strings
    sats = tuple(names[k] for k in order)
    s_i = np.argsort(order)[s_i]
    obs_types, codes = _observation_types(sig_key)
    n_e, n_s, n_c = len(epochs), len(sats), len(codes)
    values = np.full((n_e, n_s, n_c), np.nan)
    lli = np.full((n_e, n_s, n_c), -1, dtype=np.int8)
    c_idx = {c: i for i, c in enumerate(codes)}
    uniq_sig, sig_i = np.unique(sig_key, return_inverse=True)
    col = {
        t: np.array([c_idx[t + SIGNALS[(k // 256, k % 256)][1:]] for k in uniq_sig], dtype=int)[
            sig_i
        ]
        for t in "CLDS"
    }
    _fill(values, lli, epochs, m, (e_i, s_i, col), (gnss == 3) & ((prn <= 5) | (prn >= 59)),
          max_cp_std_cycles)  # fmt: skip
    glo = np.flatnonzero(gnss == 6)
    fcn = {f"R{int(prn[k]):02d}": int(m["freqId"][k]) - 7 for k in glo}
    header = ObsHeader(
        version=0.0,
        file_type="O",
        system="M",
        receiver="u-blox",
        time_system="GPS",
        obs_types=obs_types,
        glonass_fcn=fcn,
    )
    obs = Observations(
        path=fspath(path),
        header=header,
        t_gps_s=np.array([e[0] for e in epochs], dtype=float),
        epoch_flag=np.zeros(n_e, dtype=np.int8),
        clock_offset_s=np.full(n_e, np.nan),
        sats=sats,
        codes=codes,
        values=values,
        lli=lli,
        ssi=np.full(values.shape, -1, dtype=np.int8),
    )
    return obs, unknown


def _fill(
    values: np.ndarray,
    lli: np.ndarray,
    epochs: list[tuple[float, int, np.ndarray]],
    m: np.ndarray,
    where: tuple[IntArray, IntArray, dict[str, IntArray]],
    geo: np.ndarray,
    max_cp_std_cycles: float,
) -> None:
    """Code, phase (valid ones, BeiDou GEO shifted half a cycle), Doppler, C/N0 and the phase
    LLI of the measurements ``m`` into ``values`` and ``lli`` at (epoch, satellite, code)."""
    e_i, s_i, col = where
    n_c = values.shape[2]
    trk = m["trkStat"].astype(int)
    pr = np.where(trk & 1, m["prMes"], np.nan)
    cp = m["cpMes"].copy()
    cp_ok = (trk & 2 > 0) & (cp != -0.5) & ((m["cpStdev"] & 15) * _CP_STD_UNIT_CYC
                                            <= max_cp_std_cycles + 1e-12)  # fmt: skip
    cp = np.where(cp_ok, cp + np.where(geo, 0.5, 0.0), np.nan)
    values[e_i, s_i, col["C"]] = pr
    values[e_i, s_i, col["L"]] = cp
    values[e_i, s_i, col["D"]] = m["doMes"].astype(float)
    values[e_i, s_i, col["S"]] = m["cno"].astype(float)
    # continuity is judged between valid phases: the first valid phase after invalid ones
    # (tracked, phase not yet usable) starts a new arc
    flags = _lli(
        np.array([e[0] for e in epochs], dtype=float),
        np.array([e[1] for e in epochs], dtype=int),
        e_i[cp_ok],
        (s_i * n_c + col["L"])[cp_ok],
        m["locktime"][cp_ok].astype(float) * 1e-3,
        trk[cp_ok],
    )
    lli[e_i[cp_ok], s_i[cp_ok], col["L"][cp_ok]] = flags


def _observation_types(sig_key: IntArray) -> tuple[dict[str, tuple[str, ...]], tuple[str, ...]]:
    """RINEX observation types per system (``C L D S`` of each band, bands in first-seen order)
    and all codes, from the ``gnssId * 256 + sigId`` of every measurement."""
    # observation types per system, signals in first-seen order
    obs_types: dict[str, tuple[str, ...]] = {}
    first_rows = np.unique(sig_key, return_index=True)[1]
    seen = [int(sig_key[r]) for r in np.sort(first_rows)]
    for letter in "GRECJSI":
        bands = [
            SIGNALS[(k // 256, k % 256)][1:] for k in seen if SYSTEM_LETTERS[k // 256] == letter
        ]
        bands = list(dict.fromkeys(bands))
        if bands:
            obs_types[letter] = tuple(f"{t}{b}" for b in bands for t in "CLDS")
    codes = tuple(dict.fromkeys(c for v in obs_types.values() for c in v))
    return obs_types, codes


def _lli(
    t_epoch: np.ndarray,
    rec_stat: np.ndarray,
    e_i: np.ndarray,
    key: np.ndarray,
    lock_s: np.ndarray,
    trk: np.ndarray,
) -> np.ndarray:
    """RINEX loss-of-lock indicator of each valid phase measurement (module notes).

    ``key`` identifies the signal (satellite and code column); measurements are in epoch
    order, so each signal's previous valid phase is its previous row in a stable sort."""
    order = np.lexsort((e_i, key))
    k, e = key[order], e_i[order]
    first = np.r_[True, k[1:] != k[:-1]]
    prev = np.r_[order[:1], order[:-1]]  # (a first observation has no previous: masked)
    gap = t_epoch[e] - t_epoch[e_i[prev]]
    half_sub = trk[order] & 8
    slip = (
        first
        | (lock_s[order] == 0.0)
        | (lock_s[order] < lock_s[prev])
        | (lock_s[order] + 1e-3 < gap)
        | (half_sub != (trk[prev] & 8))
        | (rec_stat[e] & 2 > 0)  # receiver clock reset
    )
    out = np.empty(len(key), dtype=np.int8)
    out[order] = slip.astype(np.int8) | np.where(trk[order] & 4, 0, 2).astype(np.int8)
    return out
