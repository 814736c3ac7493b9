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

import math
from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass, field
from os import fspath
from types import MappingProxyType
from typing import Any

import numpy as np

from navtrack._typing import StrPath
from navtrack.errors import FileFormatError
from navtrack.gnss.observations import Observations, ObsHeader, SkippedLine
from navtrack.gnss.rinex.nav import NavData, toe_gps_s
from navtrack.timescale import (
    BDS_WEEK_OFFSET,
    BDT_MINUS_GPST_S,
    SECONDS_PER_WEEK,
    leap_seconds,
    utc_to_gps,
)

__all__ = ["SIGNALS", "UbxLog", "is_ubx", "read_ubx"]

# UBX gnssId -> RINEX system letter
_SYSTEM = {0: "G", 1: "S", 2: "E", 3: "C", 5: "J", 6: "R", 7: "I"}
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
_PI = 3.1415926535898  # the value of pi IS-GPS-200 20.3.3.4.3 fixes for the orbit
# URA index -> nominal URA (m) the user applies, IS-GPS-200N 20.3.3.3.1.3 (2^(1+N/2) rounded to
# 0.1 m up to N = 6, 2^(N-2) above); index 15 means no accuracy prediction (NaN)
_URA_M = (2.0, 2.8, 4.0, 5.7, 8.0, 11.3, 16.0, 32.0, 64.0, 128.0, 256.0, 512.0, 1024.0, 2048.0,
          4096.0)  # fmt: skip


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
    messages: Counter[str] = Counter()
    skipped: list[SkippedLine] = []
    epochs: list[tuple[float, int, np.ndarray]] = []  # (t_gps_s, recStat, measurements)
    # (RAWX epochs before it, gnssId, svId, sigId, freqId, words, message number)
    subframes: list[tuple[int, int, int, int, int, np.ndarray, int]] = []
    leap: int | None = None
    undated = 0
    offset = 0
    with open(path, "rb") as stream:
        reader = UBXReader(stream, protfilter=UBX_PROTOCOL, parsing=False, quitonerror=0)
        for number, (raw, _) in enumerate(reader, start=1):
            where = f"message at byte {offset}"
            offset += len(raw)
            if raw is None or len(raw) < 8:
                continue
            cls_id = (raw[2], raw[3])
            payload = raw[6:-2]

            def bad(reason: str, number: int = number, where: str = where) -> None:
                if not lenient:
                    raise FileFormatError(path, None, f"{where}: {reason}")
                skipped.append(SkippedLine(line=number, reason=f"{where}: {reason}"))

            if not _checksum_ok(raw):
                bad("checksum error")
                continue
            messages[_identity(cls_id)] += 1
            if cls_id == _RAWX:
                if len(payload) < _RAWX_HEAD.itemsize:
                    bad("RXM-RAWX shorter than its header")
                    continue
                head = np.frombuffer(payload, _RAWX_HEAD, count=1)[0]
                n = int(head["numMeas"])
                if len(payload) != 16 + 32 * n:
                    bad(f"RXM-RAWX of {len(payload)} bytes for {n} measurements")
                    continue
                if int(head["week"]) == 0:  # no GPS time yet (receiver start-up)
                    undated += 1
                    continue
                meas = np.frombuffer(payload, _RAWX_MEAS, count=n, offset=16)
                t = int(head["week"]) * SECONDS_PER_WEEK + float(head["rcvTow"])
                epochs.append((t, int(head["recStat"]), meas))
                if int(head["recStat"]) & 1:
                    leap = int(head["leapS"])
            elif cls_id == _SFRBX:
                if len(payload) < _SFRBX_HEAD.itemsize:
                    bad("RXM-SFRBX shorter than its header")
                    continue
                h = np.frombuffer(payload, _SFRBX_HEAD, count=1)[0]
                n = int(h["numWords"])
                if len(payload) != 8 + 4 * n:
                    bad(f"RXM-SFRBX of {len(payload)} bytes for {n} words")
                    continue
                words = np.frombuffer(payload, "<u4", count=n, offset=8)
                ids = (int(h["gnssId"]), int(h["svId"]), int(h["sigId"]), int(h["freqId"]))
                subframes.append((len(epochs), *ids, words, number))
    if not epochs and not subframes:
        raise FileFormatError(path, None, "no RXM-RAWX nor RXM-SFRBX message: not a raw log")
    obs, unknown = _observations(path, epochs, max_cp_std_cycles)
    # the 10-bit LNAV week is resolved against the receiver's week; a log without RAWX
    # epochs has none, and the current date stands in (as RTKLIB does)
    t_epochs = [e[0] for e in epochs] or [_now_gps_s()]
    nav, undecoded = _navigation(path, subframes, t_epochs, leap)
    return UbxLog(
        obs=obs,
        nav=nav,
        messages=dict(messages),
        undecoded=undecoded,
        skipped=tuple(skipped),
        unknown_signals=unknown,
        undated_epochs=undated,
    )


def _checksum_ok(raw: bytes) -> bool:
    """The 8-bit Fletcher checksum over class, id, length and payload: CK_A is the byte sum,
    CK_B the sum of the running CK_A values, i.e. each byte weighted by its distance from the
    end (both modulo 256)."""
    b = np.frombuffer(raw, np.uint8, count=len(raw) - 4, offset=2).astype(np.int64)
    ck_a = int(b.sum()) & 0xFF
    ck_b = int(b @ np.arange(len(b), 0, -1)) & 0xFF
    return ck_a == raw[-2] and ck_b == raw[-1]


def _now_gps_s() -> float:
    from navtrack.timescale import gps_seconds

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
        & np.isin(gnss, list(_SYSTEM))
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
    names = [f"{_SYSTEM[k // 256]}{k % 256:02d}" for k in sat_keys]
    order = np.argsort(names, kind="stable")  # satellites sorted as strings
    sats = tuple(names[k] for k in order)
    s_i = np.argsort(order)[s_i]
    # observation types per system, signals in first-seen order
    obs_types: dict[str, tuple[str, ...]] = {}
    first_rows = np.unique(sig_key, return_index=True)[1]
    seen = [int(sig_key[r]) for r in np.sort(first_rows)]
    for letter in "GRECJSI":
        bands = [SIGNALS[(k // 256, k % 256)][1:] for k in seen if _SYSTEM[k // 256] == letter]
        bands = list(dict.fromkeys(bands))
        if bands:
            obs_types[letter] = tuple(f"{t}{b}" for b in bands for t in "CLDS")
    codes = tuple(dict.fromkeys(c for v in obs_types.values() for c in v))
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
    trk = m["trkStat"].astype(int)
    pr = np.where(trk & 1, m["prMes"], np.nan)
    cp = m["cpMes"].copy()
    cp_ok = (trk & 2 > 0) & (cp != -0.5) & ((m["cpStdev"] & 15) * _CP_STD_UNIT_CYC
                                            <= max_cp_std_cycles + 1e-12)  # fmt: skip
    geo = (gnss == 3) & ((prn <= 5) | (prn >= 59))
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


# -------------------------------------------------------------------------------- navigation


def _bits(words: np.ndarray) -> int:
    """The 24 data bits of each of the 10 LNAV words (u-blox gives each 30-bit word with its
    parity in bits 5-0, polarity already corrected) as one 240-bit integer."""
    v = 0
    for w in words[:10]:
        v = (v << 24) | ((int(w) >> 6) & 0xFFFFFF)
    return v


def _u(v: int, word: int, bit: int, n: int) -> int:
    """Unsigned field of ``n`` bits starting at data bit ``bit`` (1-24) of word ``word``
    (1-10), IS-GPS-200 numbering."""
    start = 24 * (word - 1) + bit - 1
    return (v >> (240 - start - n)) & ((1 << n) - 1)


def _s(v: int, word: int, bit: int, n: int) -> int:
    x = _u(v, word, bit, n)
    return x - (1 << n) if x >> (n - 1) else x


def _split(v: int, w1: int, b1: int, n1: int, w2: int, n2: int, signed: bool) -> int:
    """A field whose ``n1`` most significant bits end a word and ``n2`` others fill the next."""
    x = (_u(v, w1, b1, n1) << n2) | _u(v, w2, 1, n2)
    n = n1 + n2
    return x - (1 << n) if signed and x >> (n - 1) else x


def _fit_hours(flag: int, iodc: int) -> float:
    """Curve-fit interval (h) from the fit flag and IODC, IS-GPS-200N table 20-XII."""
    if flag == 0:
        return 4.0
    for lo, hi, hours in ((240, 247, 8.0), (248, 255, 14.0), (496, 496, 14.0),
                          (497, 503, 26.0), (504, 510, 50.0), (511, 511, 74.0),
                          (752, 756, 74.0), (757, 763, 98.0), (764, 767, 122.0),
                          (1008, 1010, 122.0), (1011, 1020, 146.0)):  # fmt: skip
        if lo <= iodc <= hi:
            return hours
    return 6.0


def _navigation(
    path: StrPath,
    subframes: list[tuple[int, int, int, int, int, np.ndarray, int]],
    t_epochs: list[float],
    leap: int | None,
) -> tuple[NavData, dict[str, int]]:
    """LNAV subframes -> ephemeris tables, ionosphere and UTC parameters."""
    undecoded: Counter[str] = Counter()
    pending: dict[tuple[str, int], dict[int, tuple[int, int, float]]] = {}
    records: dict[str, list[dict[str, Any]]] = {"G": [], "J": []}
    seen: set[tuple[str, int, int, int]] = set()
    bds_pending: dict[int, dict[int, tuple[int, int]]] = {}
    bds_records: list[dict[str, Any]] = []
    gal_pending: dict[int, dict[int, tuple[int, int]]] = {}
    gal_records: list[dict[str, Any]] = []
    glo_pending: dict[tuple[int, int], dict[int, tuple[int, int]]] = {}
    glo_records: list[dict[str, Any]] = []
    iono: dict[str, np.ndarray] = {}
    time_corrections: dict[str, tuple[Any, ...]] = {}
    for e_next, gnss, sv, sig, freq, words, number in subframes:
        letter = _SYSTEM.get(gnss, "?")
        if letter in "GJ" and sig in (3, 4, 6, 7, 8, 9):
            undecoded[f"{letter}: CNAV (L2C/L5) not decoded"] += 1
            continue
        if letter == "C":
            why = _beidou_subframe(bds_pending, bds_records, seen, sv, sig, words, number)
            if why:
                undecoded[f"C: {why}"] += 1
            continue
        if letter == "E":
            why = _galileo_page(gal_pending, gal_records, seen, sv, sig, words, number)
            if why:
                undecoded[f"E: {why}"] += 1
            continue
        if letter == "R":
            t_rx = t_epochs[min(max(e_next - 1, 0), len(t_epochs) - 1)]
            why = _glonass_string(glo_pending, glo_records, seen, freq, words, number, t_rx)
            if why:
                undecoded[f"R: {why}"] += 1
            continue
        if letter not in "GJ" or len(words) < 10:
            undecoded[f"{letter}: navigation message not decoded"] += 1
            continue
        v = _bits(words)
        if _u(v, 1, 1, 8) != 0x8B:
            undecoded[f"{letter}: no LNAV preamble (CNAV or damaged)"] += 1
            continue
        sfid = _u(v, 2, 20, 3)
        # the receiver week at this subframe: from the RAWX epoch just before it (or after)
        t_rx = t_epochs[min(max(e_next - 1, 0), len(t_epochs) - 1)]
        if sfid in (1, 2, 3):
            pending.setdefault((letter, sv), {})[sfid] = (v, number, t_rx)
            have = pending[(letter, sv)]
            if len(have) == 3:
                rec = _ephemeris(have)
                if rec is not None:
                    key = (letter, sv, rec["iode"], int(rec["toe_sow"]))
                    if key not in seen:  # the same issue is broadcast every 30 s
                        seen.add(key)
                        rec["sat"] = f"{letter}{sv:02d}"
                        records[letter].append(rec)
        elif sfid == 4 and letter == "G" and _u(v, 3, 3, 6) == 56:
            iono["GPSA"] = np.array(
                [
                    _s(v, 3, 9, 8) * 2.0**-30,
                    _s(v, 3, 17, 8) * 2.0**-27,
                    _s(v, 4, 1, 8) * 2.0**-24,
                    _s(v, 4, 9, 8) * 2.0**-24,
                ]
            )
            iono["GPSB"] = np.array(
                [
                    _s(v, 4, 17, 8) * 2.0**11,
                    _s(v, 5, 1, 8) * 2.0**14,
                    _s(v, 5, 9, 8) * 2.0**16,
                    _s(v, 5, 17, 8) * 2.0**16,
                ]
            )
            a1 = _s(v, 6, 1, 24) * 2.0**-50
            a0 = _split(v, 7, 1, 24, 8, 8, True) * 2.0**-30
            tot = _u(v, 8, 9, 8) * 2**12
            week_t = _u(v, 8, 17, 8)
            week_rx = int(t_rx // SECONDS_PER_WEEK)
            week_full = week_rx + ((week_t - week_rx + 128) % 256) - 128  # 8-bit WNt
            time_corrections["GPUT"] = (a0, a1, tot, week_full, None, None)
            leap = _s(v, 9, 1, 8)
        else:
            what = "almanac/health" if sfid in (4, 5) else f"subframe id {sfid}"
            undecoded[f"{letter}: subframe {sfid} ({what})"] += 1
    records["C"] = bds_records
    records["E"] = gal_records
    records["R"] = glo_records
    tables = {s: _table(s, recs) for s, recs in records.items() if recs}
    nav = NavData(
        path=fspath(path),
        version=0.0,
        file_type="N",
        system="M",
        iono=iono,
        time_corrections=time_corrections,
        leap_seconds=leap,
        tables=tables,
    )
    return nav, {k: c for k, c in undecoded.items() if c}


def _ephemeris(have: dict[int, tuple[int, int, float]]) -> dict[str, Any] | None:
    """One ephemeris from subframes 1-3 of the same issue, IS-GPS-200N 20.3.3.3-20.3.3.4;
    None while their issues differ (a new upload arriving)."""
    v1, n1, t_rx = have[1]
    v2, _, _ = have[2]
    v3, _, _ = have[3]
    iodc = (_u(v1, 3, 23, 2) << 8) | _u(v1, 8, 1, 8)
    iode2, iode3 = _u(v2, 3, 1, 8), _u(v3, 10, 1, 8)
    if not (iode2 == iode3 == iodc & 0xFF):
        return None
    week_rx = int(t_rx // SECONDS_PER_WEEK)
    week10 = _u(v1, 3, 1, 10)
    week = week_rx + ((week10 - week_rx + 512) % 1024) - 512
    tot_sow = _u(v1, 2, 1, 17) * 6.0 - 6.0  # HOW TOW count: start of the next subframe
    ttr = week * SECONDS_PER_WEEK + tot_sow
    toc = week * SECONDS_PER_WEEK + _u(v1, 8, 9, 16) * 16.0
    # toc within half a week of the transmission (an upload near the end of a week)
    toc += round((ttr - toc) / SECONDS_PER_WEEK) * SECONDS_PER_WEEK
    toe_sow = _u(v2, 10, 1, 16) * 16.0
    fit_flag = _u(v2, 10, 17, 1)
    ura = _u(v1, 3, 13, 4)
    rec: dict[str, Any] = {
        "toc_gps_s": toc,
        "af0": _s(v1, 10, 1, 22) * 2.0**-31,
        "af1": _s(v1, 9, 9, 16) * 2.0**-43,
        "af2": _s(v1, 9, 1, 8) * 2.0**-55,
        "iode": iode2,
        "crs": _s(v2, 3, 9, 16) * 2.0**-5,
        "deltan": _s(v2, 4, 1, 16) * 2.0**-43 * _PI,
        "m0": _split(v2, 4, 17, 8, 5, 24, True) * 2.0**-31 * _PI,
        "cuc": _s(v2, 6, 1, 16) * 2.0**-29,
        "e": _split(v2, 6, 17, 8, 7, 24, False) * 2.0**-33,
        "cus": _s(v2, 8, 1, 16) * 2.0**-29,
        "sqrta": _split(v2, 8, 17, 8, 9, 24, False) * 2.0**-19,
        "toe_sow": toe_sow,
        "cic": _s(v3, 3, 1, 16) * 2.0**-29,
        "omega0": _split(v3, 3, 17, 8, 4, 24, True) * 2.0**-31 * _PI,
        "cis": _s(v3, 5, 1, 16) * 2.0**-29,
        "i0": _split(v3, 5, 17, 8, 6, 24, True) * 2.0**-31 * _PI,
        "crc": _s(v3, 7, 1, 16) * 2.0**-5,
        "omega": _split(v3, 7, 17, 8, 8, 24, True) * 2.0**-31 * _PI,
        "omegadot": _s(v3, 9, 1, 24) * 2.0**-43 * _PI,
        "idot": _s(v3, 10, 9, 14) * 2.0**-43 * _PI,
        "codes_l2": _u(v1, 3, 11, 2),
        "week": week,
        "l2p_flag": _u(v1, 4, 1, 1),
        "sva_m": _URA_M[ura] if ura < 15 else math.nan,  # 15: no accuracy prediction
        "svh": _u(v1, 3, 17, 6),
        "tgd": _s(v1, 7, 17, 8) * 2.0**-31,
        "iodc": iodc,
        "tot_sow": tot_sow % SECONDS_PER_WEEK,
        "fit_h": _fit_hours(fit_flag, iodc),
        "line": n1,
    }
    return rec


_ORBIT_COLUMNS = (
    "toc_gps_s", "af0", "af1", "af2", "iode", "crs", "deltan", "m0", "cuc", "e", "cus",
    "sqrta", "toe_sow", "cic", "omega0", "cis", "i0", "crc", "omega", "omegadot", "idot",
)  # fmt: skip
_TABLE_COLUMNS = {
    "G": (*_ORBIT_COLUMNS, "codes_l2", "week", "toe_gps_s", "l2p_flag", "sva_m", "svh", "tgd",
          "iodc", "tot_sow", "fit_h", "line"),
    "C": (*_ORBIT_COLUMNS, "week", "toe_gps_s", "sva_m", "svh", "tgd1", "tgd2", "tot_sow",
          "aodc", "line"),
}  # fmt: skip
_TABLE_COLUMNS["J"] = _TABLE_COLUMNS["G"]
_TABLE_COLUMNS["R"] = ("toc_gps_s", "taun", "gamman", "tk_s", "x_m", "y_m", "z_m", "vx_mps",
                       "vy_mps", "vz_mps", "ax_mps2", "ay_mps2", "az_mps2", "svh", "freq_num",
                       "age_d", "line")  # fmt: skip
_TABLE_COLUMNS["E"] = (*_ORBIT_COLUMNS, "data_source", "week", "toe_gps_s", "sva_m", "svh",
                       "bgd_e5a", "bgd_e5b", "tot_sow", "line")  # fmt: skip
_INT_COLUMNS = {
    "iode", "codes_l2", "week", "l2p_flag", "svh", "iodc", "aodc", "data_source", "line",
    "freq_num", "age_d",
}  # fmt: skip


def _table(letter: str, recs: list[dict[str, Any]]) -> dict[str, np.ndarray]:
    """Ephemeris records -> the column table :class:`NavData` holds, sorted as RINEX's."""
    sats = np.array([r["sat"] for r in recs])
    cols: dict[str, np.ndarray] = {}
    names = _TABLE_COLUMNS[letter]
    for name in names:
        if name == "toe_gps_s":
            continue
        dtype = np.int64 if name in _INT_COLUMNS else float
        cols[name] = np.array([r[name] for r in recs], dtype=dtype)
    if letter != "R":
        cols["toe_gps_s"] = toe_gps_s(
            letter, cols["week"].astype(float), cols["toe_sow"], cols["toc_gps_s"]
        )
    order = np.lexsort((cols["line"], cols["toc_gps_s"], sats))
    out = {"sat": sats[order]}
    out.update((name, cols[name][order]) for name in names)
    return out


# BeiDou D1 (BDS-SIS-ICD-B1I 3.0, 5.2.4): each 30-bit word carries 26 (word 1) or 22 (words
# 2-10) information bits before its parity; with the parity removed every field of subframes
# 1-3 is one run of bits. (start, length, signed) in that 224-bit information stream.
_BDS_SOW = (18, 20, False)
_BDS_D1: dict[int, dict[str, tuple[int, int, bool]]] = {
    1: {"svh": (38, 1, False), "aodc": (39, 5, False), "urai": (44, 4, False),
        "week": (48, 13, False), "toc": (61, 17, False), "tgd1": (78, 10, True),
        "tgd2": (88, 10, True), "af2": (162, 11, True), "af0": (173, 24, True),
        "af1": (197, 22, True), "iode": (219, 5, False)},
    2: {"deltan": (38, 16, True), "cuc": (54, 18, True), "m0": (72, 32, True),
        "e": (104, 32, False), "cus": (136, 18, True), "crc": (154, 18, True),
        "crs": (172, 18, True), "sqrta": (190, 32, False), "toe_msb": (222, 2, False)},
    3: {"toe_lsb": (38, 15, False), "i0": (53, 32, True), "cic": (85, 18, True),
        "omegadot": (103, 24, True), "cis": (127, 18, True), "idot": (145, 14, True),
        "omega0": (159, 32, True), "omega": (191, 32, True)},
}  # fmt: skip


def _bds_info(words: np.ndarray) -> int:
    """The information bits of a D1/D2 subframe (u-blox gives each 30-bit word with its BCH
    parity after the information bits, de-interleaved) as one 224-bit integer."""
    v = (int(words[0]) >> 4) & ((1 << 26) - 1)
    for w in words[1:10]:
        v = (v << 22) | ((int(w) >> 8) & ((1 << 22) - 1))
    return v


def _bds_field(v: int, start: int, n: int, signed: bool) -> int:
    x = (v >> (224 - start - n)) & ((1 << n) - 1)
    return x - (1 << n) if signed and x >> (n - 1) else x


def _beidou_subframe(
    pending: dict[int, dict[int, tuple[int, int]]],
    records: list[dict[str, Any]],
    seen: set[tuple[str, int, int, int]],
    sv: int,
    sig: int,
    words: np.ndarray,
    number: int,
) -> str:
    """Collect a BeiDou subframe; a D1 ephemeris when subframes 1-3 of one frame are in.
    Returns why the subframe gives nothing (empty when it was used or is pending)."""
    if sig not in (0, 1, 2, 3, 4, 10):  # B1I, B2I, B3I carry D1 (MEO/IGSO) or D2 (GEO)
        return "B-CNAV (B1C/B2a) not decoded"
    if sv <= 5 or sv >= 59:
        return "D2 (GEO) not decoded"
    if len(words) < 10:
        return "D1 subframe shorter than 10 words"
    v = _bds_info(words)
    if (v >> (224 - 11)) != 0b11100010010:
        return "no D1 preamble"
    frame_id = _bds_field(v, 15, 3, False)
    if frame_id not in (1, 2, 3):
        return f"D1 subframe {frame_id} (almanac)" if frame_id in (4, 5) else "D1 subframe id"
    have = pending.setdefault(sv, {})
    have[frame_id] = (v, number)
    if len(have) < 3:
        return ""
    sow = [_bds_field(have[k][0], *_BDS_SOW) for k in (1, 2, 3)]
    if not (sow[1] == sow[0] + 6 and sow[2] == sow[1] + 6):
        return ""  # subframes of different frames: wait for a consistent set
    f = {k: _bds_field(have[sf][0], *spec) for sf, t in _BDS_D1.items() for k, spec in t.items()}
    toe_sow = ((f["toe_msb"] << 15) | f["toe_lsb"]) * 8.0
    toc_sow = f["toc"] * 8.0
    if toe_sow != toc_sow:
        return "D1 toe != toc"
    week = f["week"]  # BDT week of the frame; toe within half a week of it
    week += round((sow[0] - toe_sow) / SECONDS_PER_WEEK)
    key = ("C", sv, f["iode"], int(toe_sow))
    if key in seen:
        return ""
    seen.add(key)
    toc = (week + BDS_WEEK_OFFSET) * SECONDS_PER_WEEK + toc_sow - BDT_MINUS_GPST_S
    records.append(
        {
            "sat": f"C{sv:02d}",
            "toc_gps_s": toc,
            "af0": f["af0"] * 2.0**-33,
            "af1": f["af1"] * 2.0**-50,
            "af2": f["af2"] * 2.0**-66,
            "iode": f["iode"],
            "crs": f["crs"] * 2.0**-6,
            "deltan": f["deltan"] * 2.0**-43 * _PI,
            "m0": f["m0"] * 2.0**-31 * _PI,
            "cuc": f["cuc"] * 2.0**-31,
            "e": f["e"] * 2.0**-33,
            "cus": f["cus"] * 2.0**-31,
            "sqrta": f["sqrta"] * 2.0**-19,
            "toe_sow": toe_sow,
            "cic": f["cic"] * 2.0**-31,
            "omega0": f["omega0"] * 2.0**-31 * _PI,
            "cis": f["cis"] * 2.0**-31,
            "i0": f["i0"] * 2.0**-31 * _PI,
            "crc": f["crc"] * 2.0**-6,
            "omega": f["omega"] * 2.0**-31 * _PI,
            "omegadot": f["omegadot"] * 2.0**-43 * _PI,
            "idot": f["idot"] * 2.0**-43 * _PI,
            "week": week,
            "sva_m": _URA_M[f["urai"]] if f["urai"] < 15 else math.nan,
            "svh": f["svh"],
            "tgd1": f["tgd1"] * 0.1e-9,
            "tgd2": f["tgd2"] * 0.1e-9,
            "tot_sow": float(sow[0]),
            "aodc": f["aodc"],
            "line": have[1][1],
        }
    )
    return ""


# Galileo I/NAV (OS SIS ICD 2.0, 4.3.5): a word is the 112 data bits of an even page and the
# first 16 of the odd page that follows; (start, length, signed) in the 128-bit word, after the
# 6-bit word type.
_GAL_WORDS: dict[int, dict[str, tuple[int, int, bool]]] = {
    1: {"iod": (6, 10, False), "toe": (16, 14, False), "m0": (30, 32, True),
        "e": (62, 32, False), "sqrta": (94, 32, False)},
    2: {"iod": (6, 10, False), "omega0": (16, 32, True), "i0": (48, 32, True),
        "omega": (80, 32, True), "idot": (112, 14, True)},
    3: {"iod": (6, 10, False), "omegadot": (16, 24, True), "deltan": (40, 16, True),
        "cuc": (56, 16, True), "cus": (72, 16, True), "crc": (88, 16, True),
        "crs": (104, 16, True), "sisa": (120, 8, False)},
    4: {"iod": (6, 10, False), "svid": (16, 6, False), "cic": (22, 16, True),
        "cis": (38, 16, True), "toc": (54, 14, False), "af0": (68, 31, True),
        "af1": (99, 21, True), "af2": (120, 6, True)},
    5: {"bgd_e5a": (47, 10, True), "bgd_e5b": (57, 10, True), "e5b_hs": (67, 2, False),
        "e1b_hs": (69, 2, False), "e5b_dvs": (71, 1, False), "e1b_dvs": (72, 1, False),
        "wn": (73, 12, False), "tow": (85, 20, False)},
}  # fmt: skip
_GAL_SOURCE_INAV = 1 | 1 << 9  # RINEX data source: I/NAV E1-B, clock for E5b/E1


def _crc24q(data: bytes) -> int:
    """CRC-24Q (generator 0x1864CFB) of a byte string (OS SIS ICD 2.0, 4.3.4)."""
    crc = 0
    for byte in data:
        crc ^= byte << 16
        for _ in range(8):
            crc <<= 1
            if crc & 0x1000000:
                crc ^= 0x1864CFB
    return crc & 0xFFFFFF


def _sisa_m(index: int) -> float:
    """Signal-in-space accuracy (m) of a SISA index, OS SIS ICD 2.0 table 89 (255: none)."""
    if index < 50:
        return index * 0.01
    if index < 75:
        return 0.5 + (index - 50) * 0.02
    if index < 100:
        return 1.0 + (index - 75) * 0.04
    if index < 126:
        return 2.0 + (index - 100) * 0.16
    return math.nan


def _galileo_page(
    pending: dict[int, dict[int, tuple[int, int]]],
    records: list[dict[str, Any]],
    seen: set[tuple[str, int, int, int]],
    sv: int,
    sig: int,
    words: np.ndarray,
    number: int,
) -> str:
    """Collect a Galileo I/NAV word; an ephemeris when word types 1-5 of one issue are in.
    Returns why the message gives nothing (empty when it was used or is pending)."""
    if sig not in (1, 5) or len(words) < 8:  # E1-B and E5b-I carry I/NAV
        return "F/NAV or E6 not decoded"
    v = 0
    for w in words[:8]:
        v = (v << 32) | int(w)

    def bit(start: int, n: int) -> int:
        """``n`` bits from bit ``start`` of the 256-bit page pair."""
        return (v >> (256 - start - n)) & ((1 << n) - 1)

    if bit(0, 1) != 0 or bit(128, 1) != 1:
        return "I/NAV page pair out of order"
    if bit(1, 1) or bit(129, 1):
        return "I/NAV alert page"
    # CRC over 4 zero bits, the even page's first 114 bits and the odd page's first 82
    crc_in = (bit(0, 114) << 82) | bit(128, 82)
    if _crc24q(crc_in.to_bytes(25, "big")) != bit(210, 24):
        return "I/NAV CRC error"
    word = (bit(2, 112) << 16) | bit(130, 16)
    wtype = word >> 122
    if wtype not in (1, 2, 3, 4, 5):
        return "I/NAV almanac, UTC, GST-GPS or spare word"
    have = pending.setdefault(sv, {})
    have[wtype] = (word, number)
    if wtype != 5 or len(have) < 5:
        return ""

    def field(t: int, name: str) -> int:
        start, n, signed = _GAL_WORDS[t][name]
        x = (have[t][0] >> (128 - start - n)) & ((1 << n) - 1)
        return x - (1 << n) if signed and x >> (n - 1) else x

    iods = {field(t, "iod") for t in (1, 2, 3, 4)}
    if len(iods) != 1:
        return ""  # words of two issues: wait for a consistent set
    iod = iods.pop()
    week = field(5, "wn") + 1024  # GST week -> the GPS week count RINEX uses
    tot_sow = float(field(5, "tow"))
    toe_sow = field(1, "toe") * 60.0
    toc_sow = field(4, "toc") * 60.0
    # toe and toc within half a week of the transmission time
    week_toe = week + round((tot_sow - toe_sow) / SECONDS_PER_WEEK)
    week_toc = week + round((tot_sow - toc_sow) / SECONDS_PER_WEEK)
    key = ("E", sv, iod, int(toe_sow))
    if key in seen:
        return ""
    seen.add(key)
    f = {name: field(t, name) for t, spec in _GAL_WORDS.items() for name in spec if name != "iod"}
    records.append(
        {
            "sat": f"E{sv:02d}",
            "toc_gps_s": week_toc * SECONDS_PER_WEEK + toc_sow,
            "af0": f["af0"] * 2.0**-34,
            "af1": f["af1"] * 2.0**-46,
            "af2": f["af2"] * 2.0**-59,
            "iode": iod,
            "crs": f["crs"] * 2.0**-5,
            "deltan": f["deltan"] * 2.0**-43 * _PI,
            "m0": f["m0"] * 2.0**-31 * _PI,
            "cuc": f["cuc"] * 2.0**-29,
            "e": f["e"] * 2.0**-33,
            "cus": f["cus"] * 2.0**-29,
            "sqrta": f["sqrta"] * 2.0**-19,
            "toe_sow": toe_sow,
            "cic": f["cic"] * 2.0**-29,
            "omega0": f["omega0"] * 2.0**-31 * _PI,
            "cis": f["cis"] * 2.0**-29,
            "i0": f["i0"] * 2.0**-31 * _PI,
            "crc": f["crc"] * 2.0**-5,
            "omega": f["omega"] * 2.0**-31 * _PI,
            "omegadot": f["omegadot"] * 2.0**-43 * _PI,
            "idot": f["idot"] * 2.0**-43 * _PI,
            "data_source": _GAL_SOURCE_INAV,
            "week": week_toe,
            "sva_m": _sisa_m(f["sisa"]),
            "svh": f["e5b_hs"] << 7 | f["e5b_dvs"] << 6 | f["e1b_hs"] << 1 | f["e1b_dvs"],
            "bgd_e5a": f["bgd_e5a"] * 2.0**-32,
            "bgd_e5b": f["bgd_e5b"] * 2.0**-32,
            "tot_sow": tot_sow,
            "line": have[1][1],
        }
    )
    return ""


# GLONASS navigation strings (ICD GLONASS 5.1, 4.4): (start, length) in the 85-bit string, bit 0
# the leading idle bit (ICD bit 85); sign-magnitude numbers ("*") have their sign in the MSB.
_GLO_STRINGS: dict[int, dict[str, tuple[int, int, bool]]] = {
    1: {"tk_h": (9, 5, False), "tk_m": (14, 6, False), "tk_s": (20, 1, False),
        "vx": (21, 24, True), "ax": (45, 5, True), "x": (50, 27, True)},
    2: {"bn_msb": (5, 1, False), "tb": (9, 7, False), "vy": (21, 24, True),
        "ay": (45, 5, True), "y": (50, 27, True)},
    3: {"gamman": (6, 11, True), "vz": (21, 24, True), "az": (45, 5, True), "z": (50, 27, True)},
    4: {"taun": (5, 22, True), "en": (32, 5, False), "slot": (70, 5, False)},
}  # fmt: skip


def _glonass_string(
    pending: dict[tuple[int, int], dict[int, tuple[int, int]]],
    records: list[dict[str, Any]],
    seen: set[tuple[str, int, int, int]],
    freq: int,
    words: np.ndarray,
    number: int,
    t_rx: float,
) -> str:
    """Collect a GLONASS string; an ephemeris when strings 1-4 of one frame are in. The frame
    is told by the frame id u-blox appends in the fourth word. Returns why the message gives
    nothing (empty when it was used or is pending)."""
    if len(words) < 4:
        return "string shorter than 4 words"
    v = 0
    for w in words[:4]:
        v = (v << 32) | int(w)
    m = (v >> (128 - 5)) & 0xF
    if m not in (1, 2, 3, 4):
        return "non-immediate string (almanac, time)" if 5 <= m <= 15 else "string number 0"
    frame_id = (v >> 16) & 0xFFFF
    have = pending.setdefault((freq, frame_id), {})
    have[m] = (v >> (128 - 85), number)
    if len(have) < 4:
        return ""
    del pending[(freq, frame_id)]

    def field(k: int, name: str) -> int:
        start, n, signed = _GLO_STRINGS[k][name]
        x = (have[k][0] >> (85 - start - n)) & ((1 << n) - 1)
        if signed and x >> (n - 1):
            return -(x & ((1 << (n - 1)) - 1))
        return x

    slot = field(4, "slot")
    tb = field(2, "tb")
    key = ("R", slot, tb, freq)
    if slot < 1 or key in seen:
        return "" if slot >= 1 else "slot 0 in string 4"
    seen.add(key)
    # tb and tk are Moscow times of day (UTC + 3 h): dated within 12 h of the reception
    leap = float(leap_seconds(t_rx))
    t_utc = t_rx - leap
    day = math.floor(t_utc / 86400.0) * 86400.0
    tod = t_utc - day
    toe = tb * 900.0 - 10800.0
    toe += 86400.0 * round((tod - toe) / 86400.0)
    tof = field(1, "tk_h") * 3600.0 + field(1, "tk_m") * 60.0 + field(1, "tk_s") * 30.0
    tof -= 10800.0
    tof += 86400.0 * round((tod - tof) / 86400.0)
    week_start = math.floor(t_utc / SECONDS_PER_WEEK) * SECONDS_PER_WEEK
    records.append(
        {
            "sat": f"R{slot:02d}",
            "toc_gps_s": float(utc_to_gps(day + toe)),
            "taun": -field(4, "taun") * 2.0**-30,  # RINEX writes -TauN
            "gamman": field(3, "gamman") * 2.0**-40,
            "tk_s": (day + tof) - week_start,  # message frame time, s of the UTC week
            "x_m": field(1, "x") * 2.0**-11 * 1e3,
            "y_m": field(2, "y") * 2.0**-11 * 1e3,
            "z_m": field(3, "z") * 2.0**-11 * 1e3,
            "vx_mps": field(1, "vx") * 2.0**-20 * 1e3,
            "vy_mps": field(2, "vy") * 2.0**-20 * 1e3,
            "vz_mps": field(3, "vz") * 2.0**-20 * 1e3,
            "ax_mps2": field(1, "ax") * 2.0**-30 * 1e3,
            "ay_mps2": field(2, "ay") * 2.0**-30 * 1e3,
            "az_mps2": field(3, "az") * 2.0**-30 * 1e3,
            "svh": field(2, "bn_msb"),
            "freq_num": freq - 7,
            "age_d": field(4, "en"),
            "line": have[1][1],
        }
    )
    return ""
