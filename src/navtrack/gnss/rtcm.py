"""RTCM 3 MSM observations: the multiple signal messages of a base station stream or file.

:func:`read_rtcm` reads the MSM4, MSM5, MSM6 and MSM7 messages of GPS (1074-1077), GLONASS
(1084-1087), Galileo (1094-1097), QZSS (1114-1117) and BeiDou (1124-1127) into
:class:`~navtrack.gnss.observations.Observations`, and the station position of messages 1005
and 1006. The framing and the data fields come from pyrtcm (a dependency of pyubx2, extra
``ublox``); the observables are formed here (RTCM 10403.3, 3.5.16):

* pseudorange ``(N + r + fine_pr) c / 1000`` with the rough range ``N + r`` (DF397, DF398 in
  ms) and the fine pseudorange (DF400, DF405, ms);
* carrier phase ``(N + r + fine_phase) c / 1000 / lambda`` (DF401, DF406), in cycles;
* Doppler ``-(rate + fine_rate) / lambda`` (DF399, DF404; MSM5 and MSM7 only);
* C/N0 (DF403, DF408); loss of lock where the lock-time indicator (DF402, DF407) decreases or
  is zero, half-cycle ambiguity (DF420) as LLI bit 1.

Fields at their "invalid" values leave the observation empty. GLONASS carrier phase needs the
frequency channel, which MSM5 and MSM7 carry (DF419); without it the phase is left empty and
counted. Epoch times: GPS, Galileo and QZSS time of week in ms; BeiDou time + 14 s; GLONASS
day and time of day in Moscow time (UTC + 3 h) + leap seconds. Messages carry no week: it is
the one nearest ``t_approx_gps_s`` (the caller's, e.g. from a navigation file).
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass
from os import fspath
from typing import Any

import numpy as np

from navtrack._typing import FloatArray, StrPath
from navtrack.errors import FileFormatError
from navtrack.geodesy import C_MPS
from navtrack.gnss.corrections import frequency_hz
from navtrack.gnss.observations import Observations, ObsHeader
from navtrack.timescale import SECONDS_PER_WEEK, leap_seconds

__all__ = ["RtcmLog", "is_rtcm3", "read_rtcm"]

Cell = tuple[str, str, float, float, float, float, int, int, int | None]
"""Satellite, RINEX band + attribute, pseudorange (m), phase (m), range rate (m/s), C/N0, lock
indicator, half-cycle flag, GLONASS channel (None elsewhere or unknown)."""

MSM_SYSTEMS = {"107": "G", "108": "R", "109": "E", "111": "J", "112": "C"}
"""Message-number prefix of the MSM family -> system letter."""

_TOW_FIELD = {"G": "DF004", "E": "DF248", "J": "DF428", "C": "DF427"}
"""The MSM header field of each system's epoch time (ms of week)."""
_BDT_GPST_S = 14.0
_MOSCOW_UTC_S = 3 * 3600.0
_INVALID_ROUGH_MS = 255
# invalid markers as pyrtcm scales them: -2^14 * 2^-24 ms and -2^19 * 2^-29 ms (DF400, DF405),
# -2^21 * 2^-29 ms and -2^23 * 2^-31 ms (DF401, DF406), -2^14 * 0.0001 m/s (DF404)
_INVALID_FINE_PR_MS = -(2.0**-10)
_INVALID_FINE_PHASE_MS = -(2.0**-8)
_INVALID_FINE_RATE_MPS = -1.6384
_INVALID_RATE_MPS = -8192


@dataclass(frozen=True, slots=True, eq=False)
class RtcmLog:
    """What :func:`read_rtcm` found.

    Attributes
    ----------
    obs : Observations
        The MSM observations, one epoch per distinct time (all systems joined).
    station_xyz_m : ndarray, shape (3,), or None
        Antenna reference point of the last 1005/1006 message (ECEF, m).
    messages : dict
        Count of every message number read.
    skipped : dict
        Observations left empty, by reason (``glonass phase without channel``).
    """

    obs: Observations
    station_xyz_m: FloatArray | None
    messages: dict[str, int]
    skipped: dict[str, int]


def is_rtcm3(path: StrPath) -> bool:
    """True when the file starts with an RTCM 3 frame (preamble 0xD3, six zero bits), or with
    the response header of an NTRIP caster (``ICY 200 OK``, ``HTTP/1.1 200 OK`` or
    ``Ntrip-Version: ...`` lines up to a blank line, as a recorded stream keeps it) followed
    by one."""
    with open(path, "rb") as f:
        head = f.read(_NTRIP_HEADER_MAX)
    if head.startswith((b"ICY ", b"HTTP/", b"Ntrip-")):
        end = head.find(b"\r\n\r\n")
        head = head[end + 4 :] if end >= 0 else b""
    return len(head) >= 3 and head[0] == 0xD3 and head[1] & 0xFC == 0


_NTRIP_HEADER_MAX = 4096
"""Bytes searched for the end of an NTRIP caster's response header."""


def _epoch_gps_s(msg: Any, system: str, t_ref: float) -> float:
    """GPS seconds of an MSM epoch, the week (GLONASS: the day) nearest ``t_ref``."""
    if system == "R":
        dow = int(msg.DF416)
        tod = float(msg.DF034) / 1000.0
        sow = (dow % 7) * 86400.0 + tod - _MOSCOW_UTC_S
        sow += float(leap_seconds(t_ref))
        if dow == 7:  # day unknown: the day nearest t_ref
            day = 86400.0
            base = np.floor(t_ref / day) * day
            t = base + (tod - _MOSCOW_UTC_S + float(leap_seconds(t_ref))) % day
            return float(t + day * np.round((t_ref - t) / day))
    else:
        sow = float(getattr(msg, _TOW_FIELD[system])) / 1000.0
        if system == "C":
            sow += _BDT_GPST_S
    week0 = np.floor(t_ref / SECONDS_PER_WEEK) * SECONDS_PER_WEEK
    t = week0 + sow
    return float(t + SECONDS_PER_WEEK * np.round((t_ref - t) / SECONDS_PER_WEEK))


def _cells(msg: Any, system: str, kind: int) -> list[Cell]:
    """The :data:`Cell` of every cell of an MSM message; NaN where a field is invalid."""
    from pyrtcm import parse_msm  # pyubx2's dependency, loaded only to read RTCM

    _, sats, cells = parse_msm(msg)
    per_sat = {}
    for s in sats:
        rate = s.get("DF399", _INVALID_RATE_MPS)
        ext = s.get("DF419", s.get("ExtSatInfo"))
        fcn = int(ext) - 7 if system == "R" and ext is not None and int(ext) <= 13 else None
        per_sat[s["PRN"]] = (
            s["DF397"] + s["DF398"] if s["DF397"] != _INVALID_ROUGH_MS else np.nan,
            float(rate) if rate != _INVALID_RATE_MPS else np.nan,
            fcn,
        )
    f_pr, f_ph, f_cn, f_lock = ("DF405", "DF406", "DF408", "DF407") if kind >= 6 else (
        "DF400", "DF401", "DF403", "DF402"
    )  # fmt: skip
    out: list[Cell] = []
    for c in cells:
        rough_ms, rate, fcn = per_sat[c["CELLPRN"]]
        pr, ph = c[f_pr], c[f_ph]
        fine_rate = c.get("DF404", _INVALID_FINE_RATE_MPS)
        out.append(
            (
                f"{system}{int(c['CELLPRN']):02d}",
                str(c["CELLSIG"]),
                (rough_ms + pr) * C_MPS / 1e3 if pr > _INVALID_FINE_PR_MS else np.nan,
                (rough_ms + ph) * C_MPS / 1e3 if ph > _INVALID_FINE_PHASE_MS else np.nan,
                rate + fine_rate if fine_rate > _INVALID_FINE_RATE_MPS else np.nan,
                float(c[f_cn]),
                int(c[f_lock]),
                int(c.get("DF420", 0)),
                fcn,
            )
        )
    return out


def read_rtcm(path: StrPath, t_approx_gps_s: float) -> RtcmLog:
    """The MSM observations and station position of an RTCM 3 file.

    Parameters
    ----------
    path : path-like
    t_approx_gps_s : float
        A GPS time within half a week of the data (MSM epochs carry the time of week only).

    Raises
    ------
    FileFormatError
        The file holds no MSM message.
    """
    from pyrtcm import RTCMReader  # pyubx2's dependency, loaded only to read RTCM

    counts: Counter[str] = Counter()
    skipped: Counter[str] = Counter()
    rows: list[Cell] = []
    times: list[float] = []
    station = None
    with open(path, "rb") as stream:
        for _, msg in RTCMReader(stream, quitonerror=0):
            if msg is None:
                continue
            ident = str(msg.identity)
            counts[ident] += 1
            if ident in ("1005", "1006"):
                station = np.array([msg.DF025, msg.DF026, msg.DF027], dtype=float)
            system = MSM_SYSTEMS.get(ident[:3])
            kind = int(ident[3]) if len(ident) == 4 and ident[3].isdigit() else 0
            if system is None or kind < 4:
                continue
            t = _epoch_gps_s(msg, system, t_approx_gps_s)
            cells = _cells(msg, system, kind)
            rows.extend(cells)
            times.extend([t] * len(cells))
    if not rows:
        raise FileFormatError(path, None, "no RTCM 3 MSM message (MSM4 to MSM7) found")
    return RtcmLog(
        obs=_observations(path, np.round(np.array(times), 3), rows, skipped),
        station_xyz_m=station,
        messages=dict(sorted(counts.items())),
        skipped=dict(skipped),
    )


def _observations(
    path: StrPath, t: FloatArray, rows: list[Cell], skipped: Counter[str]
) -> Observations:
    """Cells -> fixed arrays (epochs, satellites, ``C L D S`` of each band)."""
    epochs, e_i = np.unique(t, return_inverse=True)
    sats = tuple(sorted({r[0] for r in rows}))
    s_idx = {s: i for i, s in enumerate(sats)}
    obs_types: dict[str, tuple[str, ...]] = {}
    for letter in "GRECJ":
        bands = list(dict.fromkeys(r[1] for r in rows if r[0][0] == letter))
        if bands:
            obs_types[letter] = tuple(f"{k}{b}" for b in bands for k in "CLDS")
    codes = tuple(dict.fromkeys(c for v in obs_types.values() for c in v))
    c_idx = {c: i for i, c in enumerate(codes)}
    values = np.full((epochs.size, len(sats), len(codes)), np.nan)
    lli = np.full(values.shape, -1, dtype=np.int8)
    prev_lock: dict[tuple[str, str], int] = {}
    fcn: dict[str, int] = {}
    for k in np.argsort(e_i, kind="stable"):
        sat, sig, pr, ph, rate, cn0, lock, half, ch = rows[k]
        if ch is not None:
            fcn[sat] = ch
        e, s = e_i[k], s_idx[sat]
        values[e, s, c_idx["C" + sig]] = pr
        values[e, s, c_idx["S" + sig]] = cn0
        if sat[0] == "R" and sat not in fcn:
            skipped["glonass phase without channel"] += int(np.isfinite(ph))
            continue
        lam = C_MPS / float(frequency_hz(sat[0], sig[0], fcn.get(sat)))
        values[e, s, c_idx["D" + sig]] = -rate / lam
        if np.isfinite(ph):
            values[e, s, c_idx["L" + sig]] = ph / lam
            before = prev_lock.get((sat, sig), 0)
            slip = (lock == 0 and before == 0) or lock < before
            lli[e, s, c_idx["L" + sig]] = int(slip) | (2 if half else 0)
            prev_lock[(sat, sig)] = lock
    header = ObsHeader(
        version=0.0,
        file_type="O",
        system="M",
        receiver="RTCM 3",
        time_system="GPS",
        obs_types=obs_types,
        glonass_fcn={f"{s}": c for s, c in fcn.items()},
    )
    return Observations(
        path=fspath(path),
        header=header,
        t_gps_s=epochs,
        epoch_flag=np.zeros(epochs.size, dtype=np.int8),
        clock_offset_s=np.full(epochs.size, np.nan),
        sats=sats,
        codes=codes,
        values=values,
        lli=lli,
        ssi=np.full(values.shape, -1, dtype=np.int8),
    )
