"""u-blox RXM-SFRBX navigation messages -> broadcast ephemerides (:func:`decode_navigation`,
used by :func:`navtrack.gnss.ubx.read_ubx`; the module notes there list what is decoded).

References
----------
IS-GPS-200N 20.3.2 and 20.3.3 (LNAV subframes 1-4); IS-QZSS-PNT-005 (QZSS LNAV);
BDS-SIS-ICD-B1I 3.0 (2019) 5.2.4 (D1 subframes 1-3); BDS-SIS-ICD-B3I 1.0 (D1 on B3I);
Galileo OS SIS ICD 2.0 (2021) 4.3.4-4.3.5 (I/NAV pages, CRC, word types 1-5), table 89 (SISA);
GLONASS ICD 5.1 (2008) 4.4 (immediate data, strings 1-4);
"u-blox 8 / M8 Receiver description" (UBX-13003221) 10.2 (navigation data words).
"""

from __future__ import annotations

import math
from collections import Counter
from os import fspath
from types import MappingProxyType
from typing import Any

import numpy as np

from navtrack._typing import StrPath
from navtrack.gnss.rinex.nav import NavData, toe_gps_s
from navtrack.timescale import (
    BDS_WEEK_OFFSET,
    BDT_MINUS_GPST_S,
    SECONDS_PER_WEEK,
    leap_seconds,
    utc_to_gps,
)

__all__ = ["SYSTEM_LETTERS", "decode_navigation"]

SYSTEM_LETTERS = MappingProxyType({0: "G", 1: "S", 2: "E", 3: "C", 5: "J", 6: "R", 7: "I"})
"""UBX ``gnssId`` -> RINEX system letter."""

_PI = 3.1415926535898  # the value of pi IS-GPS-200 20.3.3.4.3 fixes for the orbit
# URA index -> nominal URA (m) the user applies, IS-GPS-200N 20.3.3.3.1.3 (2^(1+N/2) rounded to
# 0.1 m up to N = 6, 2^(N-2) above); index 15 means no accuracy prediction (NaN)
_URA_M = (2.0, 2.8, 4.0, 5.7, 8.0, 11.3, 16.0, 32.0, 64.0, 128.0, 256.0, 512.0, 1024.0, 2048.0,
          4096.0)  # fmt: skip


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


class _NavDecoder:
    """Collects RXM-SFRBX messages per system into ephemeris records, ionosphere and UTC
    parameters; what it cannot use is counted by reason."""

    def __init__(self, t_epochs: list[float], leap: int | None) -> None:
        self.t_epochs, self.leap = t_epochs, leap
        self.undecoded: Counter[str] = Counter()
        self.seen: set[tuple[str, int, int, int]] = set()
        self.records: dict[str, list[dict[str, Any]]] = {s: [] for s in "GJCER"}
        self.lnav_pending: dict[tuple[str, int], dict[int, tuple[int, int, float]]] = {}
        self.bds_pending: dict[int, dict[int, tuple[int, int]]] = {}
        self.gal_pending: dict[int, dict[int, tuple[int, int]]] = {}
        self.glo_pending: dict[tuple[int, int], dict[int, tuple[int, int]]] = {}
        self.iono: dict[str, np.ndarray] = {}
        self.time_corrections: dict[str, tuple[Any, ...]] = {}

    def add(self, subframe: tuple[int, int, int, int, int, np.ndarray, int]) -> None:
        e_next, gnss, sv, sig, freq, words, number = subframe
        letter = SYSTEM_LETTERS.get(gnss, "?")
        # the receiver time at this message: the RAWX epoch just before it (or after)
        t_rx = self.t_epochs[min(max(e_next - 1, 0), len(self.t_epochs) - 1)]
        if letter in "GJ" and sig in (3, 4, 6, 7, 8, 9):
            why = "CNAV (L2C/L5) not decoded"
        elif letter == "C":
            why = _beidou_subframe(
                self.bds_pending, self.records["C"], self.seen, sv, sig, words, number
            )
        elif letter == "E":
            why = _galileo_page(
                self.gal_pending, self.records["E"], self.seen, sv, sig, words, number
            )
        elif letter == "R":
            why = _glonass_string(
                self.glo_pending, self.records["R"], self.seen, freq, words, number, t_rx
            )
        elif letter not in "GJ" or len(words) < 10:
            why = "navigation message not decoded"
        else:
            why = self._lnav(letter, sv, words, number, t_rx)
        if why:
            self.undecoded[f"{letter}: {why}"] += 1

    def _lnav(self, letter: str, sv: int, words: np.ndarray, number: int, t_rx: float) -> str:
        """A GPS or QZSS LNAV subframe; why it gives nothing (empty when used or pending)."""
        v = _bits(words)
        if _u(v, 1, 1, 8) != 0x8B:
            return "no LNAV preamble (CNAV or damaged)"
        sfid = _u(v, 2, 20, 3)
        if sfid in (1, 2, 3):
            have = self.lnav_pending.setdefault((letter, sv), {})
            have[sfid] = (v, number, t_rx)
            rec = _ephemeris(have) if len(have) == 3 else None
            if rec is not None:
                key = (letter, sv, rec["iode"], int(rec["toe_sow"]))
                if key not in self.seen:  # the same issue is broadcast every 30 s
                    self.seen.add(key)
                    rec["sat"] = f"{letter}{sv:02d}"
                    self.records[letter].append(rec)
            return ""
        if sfid == 4 and letter == "G" and _u(v, 3, 3, 6) == 56:
            self._page18(v, t_rx)
            return ""
        what = "almanac/health" if sfid in (4, 5) else f"subframe id {sfid}"
        return f"subframe {sfid} ({what})"

    def _page18(self, v: int, t_rx: float) -> None:
        """GPS subframe 4 page 18: Klobuchar, GPS-UTC polynomial, leap seconds."""
        self.iono["GPSA"] = np.array(
            [
                _s(v, 3, 9, 8) * 2.0**-30,
                _s(v, 3, 17, 8) * 2.0**-27,
                _s(v, 4, 1, 8) * 2.0**-24,
                _s(v, 4, 9, 8) * 2.0**-24,
            ]
        )
        self.iono["GPSB"] = np.array(
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
        self.time_corrections["GPUT"] = (a0, a1, tot, week_full, None, None)
        self.leap = _s(v, 9, 1, 8)

    def result(self, path: StrPath) -> tuple[NavData, dict[str, int]]:
        tables = {s: _table(s, recs) for s, recs in self.records.items() if recs}
        nav = NavData(
            path=fspath(path),
            version=0.0,
            file_type="N",
            system="M",
            iono=self.iono,
            time_corrections=self.time_corrections,
            leap_seconds=self.leap,
            tables=tables,
        )
        return nav, {k: c for k, c in self.undecoded.items() if c}


def decode_navigation(
    path: StrPath,
    subframes: list[tuple[int, int, int, int, int, np.ndarray, int]],
    t_epochs: list[float],
    leap: int | None,
) -> tuple[NavData, dict[str, int]]:
    """RXM-SFRBX messages -> broadcast navigation data and the undecoded counts by reason.

    Parameters
    ----------
    path : str or path-like
        The log (named in the navigation data).
    subframes : list of tuple
        ``(RAWX epochs before it, gnssId, svId, sigId, freqId, words, message number)`` of each
        RXM-SFRBX message, in log order.
    t_epochs : list of float
        GPS time of the RAWX epochs (s): the receiver time that resolves week numbers.
    leap : int or None
        Leap seconds reported by the receiver, if any.
    """
    decoder = _NavDecoder(t_epochs, leap)
    for subframe in subframes:
        decoder.add(subframe)
    return decoder.result(path)


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

    rec = _galileo_record(sv, have, seen)
    if rec is not None:
        records.append(rec)
    return ""


def _galileo_record(
    sv: int, have: dict[int, tuple[int, int]], seen: set[tuple[str, int, int, int]]
) -> dict[str, Any] | None:
    """The ephemeris of word types 1-5 of one issue (OS SIS ICD 2.0, 4.3.5); None while the
    words are of two issues or when the issue was already recorded."""

    def field(t: int, name: str) -> int:
        start, n, signed = _GAL_WORDS[t][name]
        x = (have[t][0] >> (128 - start - n)) & ((1 << n) - 1)
        return x - (1 << n) if signed and x >> (n - 1) else x

    iods = {field(t, "iod") for t in (1, 2, 3, 4)}
    if len(iods) != 1:
        return None  # words of two issues: wait for a consistent set
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
        return None
    seen.add(key)
    f = {name: field(t, name) for t, spec in _GAL_WORDS.items() for name in spec if name != "iod"}
    return {
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
