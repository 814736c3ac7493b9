"""ANTEX antenna phase-centre files: offsets and elevation-dependent variations.

:func:`read_antex` reads every antenna of an ANTEX 1.3/1.4 file: receiver antennas by their
``TYPE RADOME`` name, satellite antennas by satellite id and validity period. Per frequency
(``G01``, ``G02``, ``E05`` ...) an :class:`AntennaPattern` holds the phase-centre offset (m;
north/east/up for receivers, satellite body x/y/z for satellites) and the azimuth-independent
(``NOAZI``) variation as a function of zenith (receivers) or nadir (satellites) angle (m).
Azimuth-dependent rows are not read.

:func:`receiver_range_m` and :func:`satellite_offset_m` turn them into the range corrections a
PPP model adds: ``-e . PCO + PCV(zenith)`` for the receiver (``e`` the unit vector to the
satellite, east/north/up) and the satellite antenna offset in ECEF, in the nominal yaw attitude
(z to the geocentre, y along z x (Sun - satellite), x completing the right-handed frame).

References
----------
Rothacher, M., Schmid, R., "ANTEX: The Antenna Exchange Format, Version 1.4", IGS (2010),
sections 2 and 3 (sign of the variations: added to the PCO-corrected geometric range).
Montenbruck, O. et al., "GNSS satellite geometry and attitude models", Adv. Space Res. 56 (2015),
eq. 2 (nominal yaw-steering frame).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from os import fspath

import numpy as np

from navtrack._typing import FloatArray, StrPath
from navtrack.errors import FileFormatError
from navtrack.gnss.rinex._io import read_bytes
from navtrack.timescale import calendar_gps_seconds

__all__ = [
    "AntennaPattern",
    "Antex",
    "read_antex",
    "receiver_range_m",
    "satellite_axes",
    "satellite_offset_m",
]


@dataclass(frozen=True, slots=True, eq=False)
class AntennaPattern:
    """Phase centre of one antenna on one frequency.

    Attributes
    ----------
    offset_m : ndarray, shape (3,)
        Receivers: north, east, up from the antenna reference point; satellites: x, y, z in the
        body frame from the centre of mass (m).
    zenith_deg : ndarray, shape (K,)
        Zenith (receivers) or nadir (satellites) angles of the variation grid (deg).
    variation_m : ndarray, shape (K,)
        Azimuth-independent phase-centre variation on that grid (m).
    """

    offset_m: FloatArray
    zenith_deg: FloatArray
    variation_m: FloatArray

    def variation_at(self, zenith_deg: FloatArray) -> FloatArray:
        """The variation (m) at any angle, linear between grid values (the end values beyond)."""
        return np.interp(zenith_deg, self.zenith_deg, self.variation_m)


@dataclass(frozen=True, slots=True, eq=False)
class Antex:
    """The antennas of one ANTEX file.

    Attributes
    ----------
    path : str
    receivers : dict
        ``"TYPE RADOME"`` (type and radome as written, blanks collapsed) to the patterns of each
        frequency code.
    satellites : dict
        Satellite id to a list of ``(valid_from_gps_s, valid_until_gps_s, patterns)``.
    """

    path: str
    receivers: dict[str, dict[str, AntennaPattern]] = field(default_factory=dict)
    satellites: dict[str, list[tuple[float, float, dict[str, AntennaPattern]]]] = field(
        default_factory=dict
    )

    def receiver(self, name: str) -> tuple[dict[str, AntennaPattern], str]:
        """Patterns of a receiver antenna named as a RINEX header writes it (``ANT # / TYPE``:
        serial number, type, radome), and a note when only the type without radome (``NONE``)
        was found.

        Raises
        ------
        KeyError
            Neither the antenna with its radome nor with ``NONE`` is in the file.
        """
        words = name.split()
        # the type has no blanks and follows the serial number; the radome, when written, is
        # the last word
        for i in range(len(words)):
            ant_type, radome = " ".join(words[i:-1]), words[-1]
            exact = self.receivers.get(f"{ant_type} {radome}")
            if exact is not None:
                return exact, ""
        for i in range(len(words)):
            for ant_type, radome in ((" ".join(words[i:-1]), words[-1]), (" ".join(words[i:]), "")):
                bare = self.receivers.get(f"{ant_type} NONE")
                if ant_type and bare is not None:
                    note = f"radome {radome} of {ant_type} not in {self.path}: NONE used"
                    return bare, note if radome and radome != "NONE" else ""
        raise KeyError(f"antenna {name.strip()!r} not in {self.path}")

    def satellite(self, sat: str, t_gps_s: float) -> dict[str, AntennaPattern] | None:
        """Patterns of a satellite valid at ``t_gps_s``, or None."""
        for start, end, patterns in self.satellites.get(sat, []):
            if start <= t_gps_s < end:
                return patterns
        return None


def read_antex(path: StrPath) -> Antex:
    """Read the antennas of an ANTEX file.

    Raises
    ------
    FileFormatError
        Not an ANTEX file, or an unreadable field; the message names the file and line.
    """
    lines = read_bytes(path).decode("ascii", "replace").splitlines()
    if not lines or lines[0][60:80].strip() != "ANTEX VERSION / SYST":
        raise FileFormatError(path, 1, "not an ANTEX file (no 'ANTEX VERSION / SYST' line)")
    out = Antex(fspath(path))
    k = 0
    while k < len(lines):
        if lines[k][60:80].strip() == "START OF ANTENNA":
            k = _antenna(path, lines, k + 1, out)
        k += 1
    return out


def _antenna(path: StrPath, lines: list[str], k: int, out: Antex) -> int:
    """Read one antenna block starting at line index ``k``; index of its END OF ANTENNA."""
    name = sat = ""
    grid = np.zeros(0)
    start, end = -np.inf, np.inf
    patterns: dict[str, AntennaPattern] = {}
    freq = ""
    offset = np.zeros(3)
    while k < len(lines):
        line, label = lines[k], lines[k][60:80].strip()
        if label == "END OF ANTENNA":
            break
        if label == "TYPE / SERIAL NO":
            # satellites carry their id (G01) in columns 21-23, receivers a serial or blanks
            code = line[20:23]
            if code[:1] in "GRECJIS" and code[1:3].isdigit():
                sat = code
            name = f"{line[:16].strip()} {line[16:20].strip() or 'NONE'}"
        elif label == "ZEN1 / ZEN2 / DZEN":
            z1, z2, dz = (_num(path, k, line[c : c + 6]) for c in (2, 8, 14))
            grid = np.arange(z1, z2 + dz / 2, dz)
        elif label in ("VALID FROM", "VALID UNTIL"):
            parts = line[:43].split()
            try:
                y, mo, d, h, mi = (int(p) for p in parts[:5])
                t = calendar_gps_seconds(y, mo, d, h, mi, float(parts[5]))
            except (ValueError, IndexError):
                raise FileFormatError(path, k + 1, f"unreadable {label.lower()} date") from None
            start, end = (t, end) if label == "VALID FROM" else (start, t)
        elif label == "START OF FREQUENCY":
            freq = line[3:6].strip()
        elif label == "NORTH / EAST / UP":
            offset = np.array([_num(path, k, line[c : c + 10]) for c in (0, 10, 20)]) * 1e-3
        elif line[3:8] == "NOAZI" and freq:
            values = np.array([_num(path, k, v) for v in line[8:].split()]) * 1e-3
            if values.size != grid.size:
                raise FileFormatError(path, k + 1, f"{values.size} NOAZI values, grid {grid.size}")
            patterns[freq] = AntennaPattern(offset, grid, values)
        k += 1
    if sat and patterns:
        out.satellites.setdefault(sat, []).append((start, end, patterns))
    elif patterns:
        out.receivers[name] = patterns
    return k


def _num(path: StrPath, k: int, text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise FileFormatError(path, k + 1, f"unreadable number {text.strip()!r}") from None


def receiver_range_m(pattern: AntennaPattern, los_enu: FloatArray) -> FloatArray:
    """Range correction (m) of a receiver antenna for lines of sight ``(..., 3)`` (unit, east/
    north/up, receiver to satellite): ``-e . PCO + PCV(zenith)``."""
    north, east, up = pattern.offset_m
    e = np.asarray(los_enu, dtype=float)
    zenith = np.degrees(np.arccos(np.clip(e[..., 2], -1.0, 1.0)))
    return -(e[..., 0] * east + e[..., 1] * north + e[..., 2] * up) + pattern.variation_at(zenith)


def satellite_axes(sat_m: FloatArray, sun_m: FloatArray) -> tuple[FloatArray, ...]:
    """Unit body axes ``x, y, z`` (ECEF, each ``(..., 3)``) of satellites at ``sat_m`` in the
    nominal yaw attitude: z to the geocentre, y along z x (Sun - satellite), x = y x z."""
    r = np.asarray(sat_m, dtype=float)
    ez = -r / np.linalg.norm(r, axis=-1, keepdims=True)
    ey = np.cross(ez, np.asarray(sun_m, dtype=float) - r)
    ey /= np.linalg.norm(ey, axis=-1, keepdims=True)
    return np.cross(ey, ez), ey, ez


def satellite_offset_m(
    offset_body_m: FloatArray, sat_m: FloatArray, sun_m: FloatArray
) -> FloatArray:
    """ECEF vector (m) from the centre of mass to the antenna phase centre of satellites at
    ``sat_m (..., 3)`` with body offsets ``offset_body_m (3,)`` in the nominal yaw attitude."""
    ex, ey, ez = satellite_axes(sat_m, sun_m)
    x, y, z = np.asarray(offset_body_m, dtype=float)
    return x * ex + y * ey + z * ez
