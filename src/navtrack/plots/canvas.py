"""Figure set-up shared by the plot modules: an Agg canvas per figure, PNG files, directories.

Figures are :class:`matplotlib.figure.Figure` objects on their own Agg canvas: no pyplot, no
global backend change, nothing left open, so plotting is safe in scripts, servers and notebooks
alike. matplotlib (extra ``plot``) is imported only when a figure is made.
"""

from __future__ import annotations

from os import fspath
from pathlib import Path
from typing import TYPE_CHECKING

from navtrack._typing import StrPath
from navtrack.errors import MissingDependencyError

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["figure_dir", "new_figure", "save_figure"]


def new_figure(figsize: tuple[float, float]) -> Figure:
    """A new figure (constrained layout) on its own Agg canvas.

    Parameters
    ----------
    figsize : (float, float)
        Width and height in inches.

    Raises
    ------
    MissingDependencyError
        matplotlib is not installed.
    """
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg  # optional (extra plot)
        from matplotlib.figure import Figure
    except ImportError:
        raise MissingDependencyError("matplotlib", "plot", "Plots") from None
    fig = Figure(figsize=figsize, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def save_figure(fig: Figure, path: Path, dpi: float = 110.0) -> Path:
    """Write ``fig`` to ``path`` (format from the suffix) and return the path.

    Raises
    ------
    OSError
        The file cannot be written (the message names it).
    """
    try:
        fig.savefig(path, dpi=dpi)
    except OSError as exc:
        raise OSError(exc.errno, f"cannot write plot: {exc.strerror}", fspath(path)) from exc
    return path


def figure_dir(out_dir: StrPath) -> Path:
    """The directory ``out_dir``, created with its parents if missing.

    Raises
    ------
    NotADirectoryError
        ``out_dir`` exists and is not a directory.
    OSError
        It cannot be created (the message names it).
    """
    d = Path(out_dir)
    if d.exists() and not d.is_dir():
        raise NotADirectoryError(20, "plot directory is not a directory", fspath(d))
    try:
        d.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OSError(
            exc.errno, f"cannot create plot directory: {exc.strerror}", fspath(d)
        ) from exc
    return d
