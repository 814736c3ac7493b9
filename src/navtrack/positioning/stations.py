"""The stations of a network run: observation files sorted from navigation files, each with the
navigation data it is solved with (the files given, or those beside it)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from navtrack._record import Record
from navtrack.errors import FileFormatError
from navtrack.gnss.rinex._io import read_bytes, sniff

__all__ = ["StationJob", "file_kind", "station_jobs"]


class StationJob(Record, eq=True):
    """One station of a network job: a name (unique in the job), its observation file and the
    navigation files it is solved with."""

    name: str
    obs: Path
    navs: tuple[Path, ...]


def file_kind(path: Path) -> str:
    """``obs``, ``nav`` or ``sp3`` for a RINEX observation, RINEX navigation or SP3 file.

    Raises
    ------
    FileFormatError
        Neither (the reader's message).
    """
    with open(path, "rb") as f:
        head = f.read(81)
    data = head if b"RINEX VERSION / TYPE" in head or head.startswith(b"#") else read_bytes(path)
    kind = sniff(path, data)
    if kind.format == "sp3":
        return "sp3"
    return "obs" if kind.file_type == "O" else "nav"


def station_jobs(paths: Sequence[Path]) -> list[StationJob]:
    """The stations of a list of files (observation and, optionally, navigation files).

    Raises
    ------
    FileFormatError
        A file that is neither, or a station without navigation data (none given, none beside
        it).
    """
    kinds = {p: file_kind(p) for p in paths}
    given = tuple(p for p in paths if kinds[p] == "nav")
    jobs: list[StationJob] = []
    names: set[str] = set()
    for p in (p for p in paths if kinds[p] == "obs"):
        navs = given
        if not navs:
            beside = sorted(q for q in p.parent.iterdir() if q.is_file() and q != p)
            navs = tuple(q for q in beside if _is_nav(q))
        if not navs:
            raise FileFormatError(
                p, None, "no navigation file given and none beside it: give the NAV files"
            )
        name = p.name.split(".")[0]
        while name in names:  # the same file name in two folders
            name = f"{name}_{len(names)}"
        names.add(name)
        jobs.append(StationJob(name, p, navs))
    return jobs


def _is_nav(path: Path) -> bool:
    try:
        return file_kind(path) == "nav"
    except (FileFormatError, OSError):
        return False
