"""Small real sample files shipped with navtrack (see README.md in this folder)."""

from __future__ import annotations

from pathlib import Path

_HERE = Path(__file__).resolve().parent

REFERENCE_XYZ_M = {
    "07590920.05o": (-3976219.188, 3382371.606, 3652511.143),
    "30400920.05o": (-3978241.958, 3382840.234, 3649900.853),
    "SEPT078M_120.21O": (-3962108.673, 3381309.574, 3668678.638),
}
"""Reference positions (ECEF, m) of the bundled station files, with their sources in
README.md: 0759 from RTKLIB's static relative solution against 3040, 3040 the base coordinate
of RTKLIB's own test makefile, SEPT cssrlib's ``xyz_ref``."""


def sample_path(name: str) -> Path:
    """Path of a bundled sample file, e.g. ``sample_path("SEPT078M_120.21O")``."""
    path = _HERE / name
    if not path.is_file():
        available = sorted(p.name for p in _HERE.iterdir() if p.suffix not in {".py", ".md"})
        raise FileNotFoundError(f"no bundled sample {name!r}; available: {', '.join(available)}")
    return path
