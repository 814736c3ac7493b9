"""navtrack's exception hierarchy.

Invalid *arguments* raise the built-in ``ValueError``/``TypeError``; malformed *files* raise
:class:`FileFormatError` naming the file and line. Algorithmic outcomes (too few satellites, no
convergence, ...) are never exceptions: they are ``status`` values in results.
"""

from __future__ import annotations

from os import fspath
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from navtrack._typing import StrPath


class NavtrackError(Exception):
    """Root of all navtrack errors."""


class FileFormatError(NavtrackError, ValueError):
    """A file could not be read because its content is malformed.

    Parameters
    ----------
    path : str or path-like
        The file being read.
    line : int or None
        1-based line number of the offending line, when known.
    message : str
        What is wrong, in the file format's own words.
    """

    def __init__(self, path: StrPath, line: int | None, message: str) -> None:
        self.path = fspath(path)
        self.line = line
        self.message = message
        where = self.path if line is None else f"{self.path}, line {line}"
        super().__init__(f"{where}: {message}")


class CheckpointMismatchError(NavtrackError, ValueError):
    """An output directory holds checkpoints of another experiment, seed or parameter set."""


class MissingDependencyError(NavtrackError, ImportError):
    """An optional dependency needed for the requested feature is not installed."""

    def __init__(self, package: str, extra: str, feature: str) -> None:
        super().__init__(
            f"{feature} needs the package {package!r}; install it with "
            f"`pip install 'navtrack[{extra}]'`"
        )
