"""Observation data as navtrack holds it, whatever file it came from.

RINEX observation files and Android raw logs both become an :class:`Observations`: fixed
``(epochs, satellites, codes)`` arrays with NaN for missing values, so that downstream code
vectorises over epochs and satellites with a ``valid`` mask instead of ragged lists.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import Any, NamedTuple

import numpy as np

from navtrack._frozen import freeze_arrays
from navtrack._record import Record
from navtrack._typing import FloatArray, Int8Array
from navtrack.timescale import GPS_EPOCH, to_datetime64

SYSTEMS = "GRECJSI"
"""RINEX system letters: GPS, GLONASS, Galileo, BeiDou, QZSS, SBAS, NavIC/IRNSS."""


class Event(NamedTuple):
    """A special event record of a RINEX observation file (epoch flag 2-5) or a skipped line.

    A named tuple, as :class:`SkippedLine`: every reader imports these, and a dataclass
    compiles its methods at import, a cost every ``navtrack pos`` start would pay.

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


class SkippedLine(NamedTuple):
    """A damaged data line skipped in lenient reading: where and why."""

    line: int
    reason: str


class ObsHeader(Record):
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
    first_obs_gps_s, last_obs_gps_s : float or None
        ``TIME OF FIRST OBS`` / ``TIME OF LAST OBS`` as written in the header, in GPS seconds
        (informative only: the epochs of the data are authoritative, and writers do get
        ``TIME OF LAST OBS`` wrong).
    glonass_fcn : mapping of str to int
        ``GLONASS SLOT / FRQ #``: frequency channel number of each GLONASS satellite id.
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
    obs_types: Mapping[str, tuple[str, ...]] = MappingProxyType({})
    leap_seconds: int | None = None
    comments: tuple[str, ...] = ()
    first_obs_gps_s: float | None = None
    last_obs_gps_s: float | None = None
    glonass_fcn: Mapping[str, int] = MappingProxyType({})

    def __post_init__(self) -> None:
        object.__setattr__(self, "obs_types", MappingProxyType(dict(self.obs_types)))
        object.__setattr__(self, "glonass_fcn", MappingProxyType(dict(self.glonass_fcn)))
        freeze_arrays(self)


class Observations(Record):
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
        epoch, 6 cycle-slip records: the values of a flag-6 epoch are slip counts, not
        observations, and must be masked out by users of the values).
    clock_offset_s : ndarray, shape (n_epochs,)
        Receiver clock offset field (s), NaN when not written.
    sats : tuple of str, length n_sats
        Satellite ids (``G05``, ``E11``, ...), sorted as strings.
    codes : tuple of str, length n_codes
        Observation codes as written in the file (union over systems, in first-seen order).
    values : ndarray, shape (n_epochs, n_sats, n_codes)
        Observation values in the file's units (pseudorange m, phase cycles, Doppler Hz,
        signal strength dB-Hz); NaN where missing (RINEX: blank or written as 0.0).
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
        freeze_arrays(self)

    @property
    def time(self) -> np.ndarray:
        """Epoch times as GPST calendar ``datetime64[ns]``."""
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

    def summary(self) -> dict[str, Any]:
        """What the observations hold, as a JSON-serialisable dict (``navtrack rinex info``).

        Keys: ``path``, ``version`` (text, ``"2.10"``), ``file_type``, ``marker``,
        ``receiver``, ``antenna``, ``approx_xyz_m``, ``interval_s``, ``time_system``,
        ``first_epoch``/``last_epoch`` (ISO 8601 GPST, ms), ``n_epochs``, ``epoch_flags``
        (epochs per flag), ``n_sats``, ``sats_per_system``, ``codes_per_system``,
        ``events_by_flag``, ``skipped_lines`` and ``warnings`` (header/data disagreements,
        e.g. a wrong ``TIME OF LAST OBS``).
        """
        h = self.header
        present = self.systems
        per_system = {s: sum(1 for sat in self.sats if sat[0] == s) for s in present}
        codes = {s: list(h.obs_types.get(s, self.codes)) for s in present}
        flags, counts = np.unique(self.epoch_flag, return_counts=True)
        events: dict[str, int] = {}
        for e in self.events:
            events[str(e.flag)] = events.get(str(e.flag), 0) + 1
        warnings = []
        n = len(self.t_gps_s)
        for label, written, actual in (
            ("TIME OF FIRST OBS", h.first_obs_gps_s, self.t_gps_s[0] if n else None),
            ("TIME OF LAST OBS", h.last_obs_gps_s, self.t_gps_s[-1] if n else None),
        ):
            if written is not None and actual is not None and abs(written - actual) > 5e-4:
                warnings.append(
                    f"header {label} {_iso(written)} differs from the data ({_iso(actual)})"
                )
        if n == 0:
            warnings.append("no observation epochs")
        if n > 1 and np.any(np.diff(self.t_gps_s) <= 0):
            warnings.append("epoch times are not strictly increasing")
        return {
            "path": self.path,
            "version": f"{h.version:.2f}",  # as RINEX writes it: 2.10, not 2.1
            "file_type": h.file_type,
            "marker": h.marker,
            "receiver": h.receiver,
            "antenna": h.antenna,
            "approx_xyz_m": None if h.approx_xyz_m is None else h.approx_xyz_m.tolist(),
            "interval_s": h.interval_s,
            "time_system": h.time_system,
            "first_epoch": _iso(self.t_gps_s[0]) if n else None,
            "last_epoch": _iso(self.t_gps_s[-1]) if n else None,
            "n_epochs": n,
            "epoch_flags": {str(int(f)): int(c) for f, c in zip(flags, counts, strict=True)},
            "n_sats": len(self.sats),
            "sats_per_system": per_system,
            "codes_per_system": codes,
            "events_by_flag": events,
            "skipped_lines": len(self.skipped),
            "warnings": warnings,
        }


def _iso(t_gps_s: float) -> str:
    """ISO 8601 GPST calendar string of GPS seconds, rounded to the millisecond."""
    ms = np.timedelta64(round(float(t_gps_s) * 1000.0), "ms")
    return str(np.datetime_as_string(GPS_EPOCH.astype("datetime64[ms]") + ms, unit="ms"))
