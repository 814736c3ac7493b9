"""Small real sample files shipped with navtrack (see README.md in this folder)."""

from __future__ import annotations

from pathlib import Path

_HERE = Path(__file__).resolve().parent


def sample_path(name: str) -> Path:
    """Path of a bundled sample file, e.g. ``sample_path("SEPT078M_120.21O")``."""
    path = _HERE / name
    if not path.is_file():
        available = sorted(p.name for p in _HERE.iterdir() if p.suffix not in {".py", ".md"})
        raise FileNotFoundError(f"no bundled sample {name!r}; available: {', '.join(available)}")
    return path
