"""Observation data as navtrack holds it, whatever file it came from.

RINEX observation files and Android raw logs both become an :class:`Observations`: fixed
``(epochs, satellites, codes)`` arrays with NaN for missing values, so that downstream code
vectorises over epochs and satellites with a ``valid`` mask instead of ragged lists.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from navtrack._typing import FloatArray, Int8Array

SYSTEMS = "GRECJSI"
"""RINEX system letters: GPS, GLONASS, Galileo, BeiDou, QZSS, SBAS, NavIC/IRNSS."""


def _freeze(*arrays: np.ndarray) -> None:
    for arr in arrays:
        arr.flags.writeable = False


@dataclass(frozen=True, slots=True, eq=False)
class Event:
    """A special event record of a RINEX observation file (epoch flag 2-5) or a skipped line.

    Attributes
    ----------
    line : int
        1-based line number of the event's epoch record.
    t_gps_s : float
        Epoch of the event in GPS seconds (NaN when the record carries no time).
    flag : int
        RINEX epoch flag: 2 start moving, 3 new site, 4 header information follows (comments,
        e.g. ``RINEX FILE SPLICE``), 5 external event.
    records : tuple of str
        The special records that follow the event line, as written.
    """

    line: int
    t_gps_s: float
    flag: int
    records: tuple[str, ...]


@dataclass(frozen=True, slots=True, eq=False)
class SkippedLine:
    """A damaged data line skipped in lenient reading: where and why."""

    line: int
    reason: str


@dataclass(frozen=True, slots=True, eq=False)
class ObsHeader:
    """Header metadata of an observation file.

    Attributes
    ----------
    version : float
        Format version (2.10, 3.04, ...; 0.0 for non-RINEX sources).
    file_type : str
        ``"O"`` for observation data.
    system : str
        Satellite system letter of the file (``"M"`` for mixed).
    marker : str
        Marker name.
    marker_number : str
        Marker number (empty when absent).
    receiver : str
        Receiver number, type and version as written.
    antenna : str
        Antenna number and type as written.
    approx_xyz_m : ndarray, shape (3,), or None
        ``APPROX POSITION XYZ`` (ECEF, m).
    antenna_delta_hen_m : ndarray, shape (3,), or None
        Antenna height, east and north eccentricities (m).
    interval_s : float or None
        Nominal observation interval (s).
    time_system : str
        Time system of the epochs (``GPS``, ``GAL``, ``BDT``, ``GLO``, ...); times in the result
        are converted to GPS time.
    obs_types : mapping of str to tuple of str
        Observation codes per system letter, in file order (RINEX 2: the same list for every
        system in the file).
    leap_seconds : int or None
        ``LEAP SECONDS`` when present.
    comments : tuple of str
        ``COMMENT`` lines.
    """

    version: float
    file_type: str
    system: str
    marker: str = ""
    marker_number: str = ""
    receiver: str = ""
    antenna: str = ""
    approx_xyz_m: FloatArray | None = None
    antenna_delta_hen_m: FloatArray | None = None
    interval_s: float | None = None
    time_system: str = "GPS"
    obs_types: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    leap_seconds: int | None = None
    comments: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "obs_types", MappingProxyType(dict(self.obs_types)))
        for arr in (self.approx_xyz_m, self.antenna_delta_hen_m):
            if arr is not None:
                _freeze(arr)


@dataclass(frozen=True, slots=True, eq=False)
class Observations:
    """Observations of one receiver, as fixed ``(epochs, satellites, codes)`` arrays.

    Attributes
    ----------
    path : str
        Source file.
    header : ObsHeader
        Header metadata.
    t_gps_s : ndarray, shape (n_epochs,)
        Epoch time tags in GPS seconds (receiver time, as written; not snapped to a grid).
    epoch_flag : ndarray of int8, shape (n_epochs,)
        RINEX epoch flag of each observation epoch (0 OK, 1 power failure since the previous
        epoch, 6 cycle-slip records).
    clock_offset_s : ndarray, shape (n_epochs,)
        Receiver clock offset field (s), NaN when not written.
    sats : tuple of str, length n_sats
        Satellite ids (``G05``, ``E11``, ...), sorted.
    codes : tuple of str, length n_codes
        Observation codes as written in the file (union over systems, in first-seen order).
    values : ndarray, shape (n_epochs, n_sats, n_codes)
        Observation values in the file's units (pseudorange m, phase cycles, Doppler Hz,
        signal strength dB-Hz); NaN where missing.
    lli : ndarray of int8, shape (n_epochs, n_sats, n_codes)
        Loss-of-lock indicator, -1 where blank.
    ssi : ndarray of int8, shape (n_epochs, n_sats, n_codes)
        Signal strength indicator 1-9, -1 where blank.
    events : tuple of Event
        Special records (epoch flags 2-5), in file order.
    skipped : tuple of SkippedLine
        Damaged lines skipped in lenient reading (always empty in strict reading).
    """

    path: str
    header: ObsHeader
    t_gps_s: FloatArray
    epoch_flag: Int8Array
    clock_offset_s: FloatArray
    sats: tuple[str, ...]
    codes: tuple[str, ...]
    values: FloatArray
    lli: Int8Array
    ssi: Int8Array
    events: tuple[Event, ...] = ()
    skipped: tuple[SkippedLine, ...] = ()

    def __post_init__(self) -> None:
        n_e, n_s, n_c = len(self.t_gps_s), len(self.sats), len(self.codes)
        for name in ("values", "lli", "ssi"):
            shape = getattr(self, name).shape
            if shape != (n_e, n_s, n_c):
                raise ValueError(f"{name}: expected shape {(n_e, n_s, n_c)}, got {shape}")
        for name in ("epoch_flag", "clock_offset_s"):
            if getattr(self, name).shape != (n_e,):
                raise ValueError(f"{name}: expected shape ({n_e},)")
        _freeze(self.t_gps_s, self.epoch_flag, self.clock_offset_s, self.values, self.lli, self.ssi)

    @property
    def time(self) -> np.ndarray:
        """Epoch times as GPST calendar ``datetime64[ns]``."""
        from navtrack.timescale import to_datetime64

        return to_datetime64(self.t_gps_s)

    @property
    def systems(self) -> str:
        """System letters present, in :data:`SYSTEMS` order."""
        present = {s[0] for s in self.sats}
        return "".join(s for s in SYSTEMS if s in present)

    def code(self, code: str) -> FloatArray:
        """Values of one observation code, shape ``(n_epochs, n_sats)`` (NaN where missing)."""
        try:
            k = self.codes.index(code)
        except ValueError:
            raise KeyError(f"code {code!r} not in {self.codes}") from None
        return self.values[:, :, k]

    def sat_index(self, sat: str) -> int:
        """Column of a satellite id in the satellite axis."""
        try:
            return self.sats.index(sat)
        except ValueError:
            raise KeyError(f"satellite {sat!r} not observed") from None
