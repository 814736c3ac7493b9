"""RINEX 3.04 observation and navigation writers.

:func:`write_obs` writes an :class:`~navtrack.gnss.observations.Observations` (from any
source: a u-blox log, an Android log, another RINEX file) as a RINEX 3.04 mixed observation
file; :func:`write_nav` writes the GPS, QZSS, Galileo, BeiDou and GLONASS records, ionosphere
and GPS-UTC parameters and leap seconds of a :class:`~navtrack.gnss.rinex.nav.NavData` as a RINEX
3.04 navigation file.
Both read back with :func:`~navtrack.gnss.rinex.obs.read_obs` /
:func:`~navtrack.gnss.rinex.nav.read_nav` to the written precision, and with RTKLIB and
georinex.

Values are written as RINEX prints them: observations F14.3 with the loss-of-lock indicator
(LLI) in the next column (the signal strength indicator is left blank unless the source gives
one), epochs to 0.1 µs, navigation fields D19.12 (``E`` exponent). Missing values (NaN) are
blank fields; an epoch with no value at all is not written.

References
----------
RINEX 3.04 (IGS/RTCM-SC104, 2018), tables A1-A3 (observation header and records), A4-A8
(navigation header; GPS, QZSS, Galileo, BeiDou and GLONASS records).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable
from datetime import UTC, datetime

import numpy as np

from navtrack import __version__
from navtrack._typing import StrPath
from navtrack.gnss.observations import Observations
from navtrack.gnss.rinex.nav import KM_FIELDS, RECORD_FIELDS, NavData
from navtrack.timescale import BDT_MINUS_GPST_S, gps_to_utc, to_datetime64

__all__ = ["write_nav", "write_obs"]

_SYSTEM_ORDER = "GRECJSI"


def _label(text: str, label: str) -> str:
    return f"{text:<60.60}{label}"


def _run_by() -> str:
    stamp = datetime.now(UTC).strftime("%Y%m%d %H%M%S UTC")
    return _label(f"{'navtrack ' + __version__:<20.20}{'':<20}{stamp:<20}", "PGM / RUN BY / DATE")


def _calendar(t_gps_s: float) -> tuple[int, int, int, int, int, float]:
    """GPST calendar fields of GPS seconds, seconds to 0.1 µs."""
    whole = math.floor(t_gps_s)
    frac = round(t_gps_s - whole, 7)
    d = to_datetime64(whole).astype("datetime64[s]").item()
    return d.year, d.month, d.day, d.hour, d.minute, d.second + frac


def write_obs(obs: Observations, path: StrPath, *, comments: Iterable[str] = ()) -> None:
    """Write observations as a RINEX 3.04 mixed observation file (module notes).

    Parameters
    ----------
    obs : Observations
        What to write; its ``header.obs_types`` give the codes per system (every code of
        ``obs.codes`` for a system without its own list).
    path : str or path-like
        The output file.
    comments : iterable of str
        ``COMMENT`` lines for the header (each cut to 60 characters).
    """
    present = [s for s in _SYSTEM_ORDER if any(sat[0] == s for sat in obs.sats)]
    types = {s: tuple(obs.header.obs_types.get(s, obs.codes)) for s in present}
    lines = _obs_header(obs, types, comments)
    epoch_rows = _data_lines(obs, types)
    for e, t in enumerate(obs.t_gps_s):
        rows = epoch_rows.get(e)
        if not rows:
            continue
        y, mo, d, hh, mi, ss = _calendar(float(t))
        clk = obs.clock_offset_s[e]
        clock = f"{'':6}{clk:15.12f}" if np.isfinite(clk) else ""
        flag = int(obs.epoch_flag[e])
        lines.append(
            f"> {y:4d} {mo:02d} {d:02d} {hh:02d} {mi:02d}{ss:11.7f}  {flag:1d}{len(rows):3d}{clock}"
        )
        lines.extend(rows)
    with open(path, "w", encoding="ascii", newline="\n") as f:
        f.write("\n".join(lines) + "\n")


def _obs_header(
    obs: Observations, types: dict[str, tuple[str, ...]], comments: Iterable[str]
) -> list[str]:
    """The header lines of :func:`write_obs`, ``END OF HEADER`` included."""
    h = obs.header
    lines = [
        _label(f"{3.04:9.2f}{'':11}{'OBSERVATION DATA':<20}{'M: Mixed':<20}",
               "RINEX VERSION / TYPE"),
        _run_by(),
        *(_label(c, "COMMENT") for c in comments),
        _label(h.marker or "", "MARKER NAME"),
        _label("", "OBSERVER / AGENCY"),
        _label(f"{'':<20}{h.receiver:<20.20}{'':<20}", "REC # / TYPE / VERS"),
        _label(f"{'':<20}{h.antenna:<20.20}", "ANT # / TYPE"),
    ]  # fmt: skip
    xyz = h.approx_xyz_m if h.approx_xyz_m is not None else np.zeros(3)
    lines.append(_label("".join(f"{v:14.4f}" for v in xyz), "APPROX POSITION XYZ"))
    hen = h.antenna_delta_hen_m if h.antenna_delta_hen_m is not None else np.zeros(3)
    lines.append(_label("".join(f"{v:14.4f}" for v in hen), "ANTENNA: DELTA H/E/N"))
    for s, codes in types.items():
        for k in range(0, len(codes), 13):
            head = f"{s}  {len(codes):3d}" if k == 0 else f"{'':6}"
            lines.append(
                _label(head + "".join(f" {c}" for c in codes[k : k + 13]), "SYS / # / OBS TYPES")
            )
    if len(obs.t_gps_s):
        y, mo, d, hh, mi, ss = _calendar(float(obs.t_gps_s[0]))
        lines.append(
            _label(f"{y:6d}{mo:6d}{d:6d}{hh:6d}{mi:6d}{ss:13.7f}     GPS", "TIME OF FIRST OBS")
        )
    for s in types:  # phase shift corrections: none applied
        lines.append(_label(s, "SYS / PHASE SHIFT"))
    fcn = sorted(h.glonass_fcn.items())
    if "R" in types:
        for k in range(0, max(len(fcn), 1), 8):
            part = "".join(f"{sat} {n:2d} " for sat, n in fcn[k : k + 8])
            head = f"{len(fcn):3d} " if k == 0 else "    "
            lines.append(_label(head + part, "GLONASS SLOT / FRQ #"))
        lines.append(
            _label(" C1C    0.000 C1P    0.000 C2C    0.000 C2P    0.000", "GLONASS COD/PHS/BIS")
        )
    lines.append(_label("", "END OF HEADER"))
    return lines


def _data_lines(obs: Observations, types: dict[str, tuple[str, ...]]) -> dict[int, list[str]]:
    """The data lines of each epoch: every present value formatted once (F14.3, LLI, SSI),
    then one line per (epoch, satellite) group of values, in the order of the satellite's
    system's code list."""
    idx = np.nonzero(~np.isnan(obs.values))
    digit = np.array([" ", *"123456789"])
    texts = [
        f + li + si
        for f, li, si in zip(
            map("%14.3f".__mod__, obs.values[idx].tolist()),
            digit[np.clip(obs.lli[idx], 0, 9)].tolist(),
            digit[np.clip(obs.ssi[idx], 0, 9)].tolist(),
            strict=True,
        )
    ]
    col = {c: k for k, c in enumerate(obs.codes)}
    sat_cols = [[col.get(c, -1) for c in types[sat[0]]] for sat in obs.sats]
    blank = " " * 16
    row = idx[0] * len(obs.sats) + idx[1]
    starts = [*np.flatnonzero(np.r_[True, row[1:] != row[:-1]]).tolist(), len(row)]
    epoch_rows: dict[int, list[str]] = {}
    for a, b in itertools.pairwise(starts):
        e, j = int(idx[0][a]), int(idx[1][a])
        have = dict(zip(idx[2][a:b].tolist(), texts[a:b], strict=True))
        if have.keys().isdisjoint(sat_cols[j]):
            continue
        line = obs.sats[j] + "".join(have.get(k, blank) for k in sat_cols[j])
        epoch_rows.setdefault(e, []).append(line.rstrip())
    return epoch_rows


def _d19(x: float) -> str:
    return f"{x:19.12E}" if np.isfinite(x) else " " * 19


def write_nav(nav: NavData, path: StrPath, *, comments: Iterable[str] = ()) -> None:
    """Write the GPS, QZSS, Galileo, BeiDou and GLONASS records of a :class:`NavData` as RINEX
    3.04 navigation.

    Raises
    ------
    ValueError
        When ``nav`` holds records of another system (this writer knows the LNAV layout
        only).
    """
    other = [s for s in nav.tables if s not in "GJECR"]
    if other:
        raise ValueError(f"nav: write_nav writes G, J, E, C and R records only, not {other}")
    lines = [
        _label(f"{3.04:9.2f}{'':11}{'N: GNSS NAV DATA':<20}{'M: Mixed':<20}",
               "RINEX VERSION / TYPE"),
        _run_by(),
        *(_label(c, "COMMENT") for c in comments),
    ]  # fmt: skip
    for name in ("GPSA", "GPSB", "QZSA", "QZSB"):
        if name in nav.iono:
            vals = "".join(f"{v:12.4E}" for v in nav.iono[name])
            lines.append(_label(f"{name} {vals}", "IONOSPHERIC CORR"))
    for name, (a0, a1, tref, week, _src, _utc) in nav.time_corrections.items():
        if tref is None or week is None:
            continue
        lines.append(
            _label(f"{name} {a0:17.10E}{a1:16.9E}{int(tref):7d}{int(week):5d}", "TIME SYSTEM CORR")
        )
    if nav.leap_seconds is not None:
        lines.append(_label(f"{nav.leap_seconds:6d}", "LEAP SECONDS"))
    lines.append(_label("", "END OF HEADER"))
    records = []
    for s in ("G", "J", "E", "C", "R"):
        table = nav.tables.get(s)
        if table is None:
            continue
        # BeiDou records are dated in BDT, GLONASS ones in UTC (RINEX 3.04 tables A14, A10)
        dated = table["toc_gps_s"] + BDT_MINUS_GPST_S if s == "C" else table["toc_gps_s"]
        if s == "R":
            dated = gps_to_utc(table["toc_gps_s"])
        # RINEX 3.04: 4 GLONASS lines
        fields = RECORD_FIELDS[s][:15] if s == "R" else RECORD_FIELDS[s]
        for r in range(len(table["sat"])):
            toc = float(table["toc_gps_s"][r])
            y, mo, d, hh, mi, ss = _calendar(float(dated[r]))
            values = [
                np.nan if f is None else float(table[f][r]) / (1e3 if f in KM_FIELDS else 1.0)
                for f in fields
            ]
            head = f"{table['sat'][r]} {y:4d} {mo:02d} {d:02d} {hh:02d} {mi:02d} {int(ss):02d}"
            text = [head + "".join(_d19(v) for v in values[:3])]
            body = values[3:]
            for k in range(0, len(body), 4):
                part = body[k : k + 4]
                if all(np.isnan(p) for p in part):
                    break
                text.append(("    " + "".join(_d19(p) for p in part)).rstrip())
            records.append((toc, table["sat"][r], "\n".join(text)))
    lines.extend(rec for _, _, rec in sorted(records, key=lambda x: (x[0], x[1])))
    with open(path, "w", encoding="ascii", newline="\n") as f:
        f.write("\n".join(lines) + "\n")
