"""Observation inputs of the positioning commands, whatever the receiver wrote.

``pos``, ``rtk`` and ``ppp`` take a RINEX observation file or a u-blox UBX raw log where they
take observations (``pos`` also an Android GnssLogger log); a UBX log brings its own broadcast
ephemerides (RXM-SFRBX), used beside any navigation files given.
"""

from __future__ import annotations

import sys
from collections.abc import Collection, Sequence
from pathlib import Path

from navtrack.gnss.observations import Observations, SkippedLine
from navtrack.gnss.rinex.nav import NavData
from navtrack.gnss.rinex.obs import read_obs

UBX_SYNC = b"\xb5\x62"
"""The two bytes that start every UBX frame (u-blox interface description, "UBX frame
structure"); RINEX text never holds them."""


def is_raw_log(path: Path) -> bool:
    """True for a u-blox UBX log (which may stand without a navigation file).

    A file without the UBX frame start in its first 4 kB is not one; only a file that has it
    is handed to the UBX reader's own test, so the UBX reader is loaded for UBX logs only.
    """
    if not path.is_file():
        return False
    with open(path, "rb") as f:
        head = f.read(4096)
    if UBX_SYNC not in head:
        return False
    from navtrack.gnss.ubx import is_ubx  # the UBX reader for UBX logs only (start-up)

    return is_ubx(path)


def read_observations(
    path: Path,
    *,
    lenient: bool = False,
    systems: str | None = None,
    codes: Collection[str] | None = None,
) -> tuple[Observations, NavData | None]:
    """The observations of a RINEX file or a UBX log, and the log's navigation data (None for
    RINEX and for a log without a complete ephemeris). With ``lenient`` damaged data lines or
    messages are skipped; their count and the first of them are printed as a warning."""
    if is_raw_log(path):
        from navtrack.gnss.ubx import read_ubx  # for UBX logs only (start-up)

        log = read_ubx(path, lenient=lenient)
        _warn_skipped(path, log.skipped, "messages")
        return log.obs, (log.nav if log.nav.tables else None)
    obs = read_obs(path, lenient=lenient, systems=systems, codes=codes)
    _warn_skipped(path, obs.skipped, "data lines")
    return obs, None


def _warn_skipped(path: Path, skipped: Sequence[SkippedLine], what: str) -> None:
    if skipped:
        first = skipped[0]
        where = f"line {first.line}, " if what == "data lines" else ""
        print(
            f"warning        {path}: {len(skipped)} damaged {what} skipped "
            f"(first: {where}{first.reason})",
            file=sys.stderr,
        )
