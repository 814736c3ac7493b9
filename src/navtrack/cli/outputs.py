"""Checks of a command's outputs before it reads or solves anything: an output a command cannot
write, or needs an extra for, fails in its first second with exit 2, not after the work."""

from __future__ import annotations

import importlib.util
import os
from collections.abc import Sequence
from pathlib import Path

from navtrack.errors import MissingDependencyError

__all__ = ["check_outputs"]

# output suffix -> (module it needs, the extra that brings it)
_NEEDS = {".parquet": ("pyarrow", "parquet")}


def check_outputs(
    command: str,
    out: Path | None = None,
    formats: Sequence[str] = (),
    plot: Path | None = None,
) -> None:
    """Refuse ``--out`` and ``--plot`` that cannot be written.

    Parameters
    ----------
    command : str
        ``navtrack CMD`` for the messages.
    out : Path, optional
        The ``--out`` file: its suffix must be one of ``formats`` (when given), its folder must
        exist and be writable, and the package its format needs installed.
    formats : sequence of str
        Accepted suffixes, lower case with the dot.
    plot : Path, optional
        The ``--plot`` folder: matplotlib (extra ``plot``) must be installed and the folder
        creatable.

    Raises
    ------
    SystemExit
        ``navtrack CMD: --out ...: why`` (exit 2 through :func:`navtrack.cli.main`).
    MissingDependencyError
        The extra a format or the figures need is not installed.
    """
    if out is not None:
        suffix = out.suffix.lower()
        if formats and suffix not in formats:
            raise SystemExit(
                f"{command}: --out {out}: unknown format {out.suffix!r} (use {', '.join(formats)})"
            )
        parent = out.parent if str(out.parent) else Path(".")
        if not parent.is_dir():
            raise SystemExit(f"{command}: --out {out}: folder {str(parent)!r} does not exist")
        if out.is_dir():
            raise SystemExit(f"{command}: --out {out}: is a folder")
        if not os.access(parent, os.W_OK) or (out.exists() and not os.access(out, os.W_OK)):
            raise SystemExit(f"{command}: --out {out}: no permission to write it")
        if suffix in _NEEDS:
            module, extra = _NEEDS[suffix]
            if importlib.util.find_spec(module) is None:
                raise MissingDependencyError(module, extra, f"{suffix} output")
    if plot is not None:
        if importlib.util.find_spec("matplotlib") is None:
            raise MissingDependencyError("matplotlib", "plot", "--plot")
        if plot.exists() and not plot.is_dir():
            raise SystemExit(f"{command}: --plot {plot}: is a file, not a folder")
