"""Figures of integrity monitoring: FCM memberships (paper 2, Figs. 2 and 4) and Stanford
diagrams (position error against protection level).

matplotlib (extra ``plot``) is imported only when a figure is drawn, on its own Agg canvas.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from navtrack._typing import ArrayLike
from navtrack.plots.canvas import figure_dir, new_figure, save_figure

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.collections import QuadMesh
    from matplotlib.figure import Figure

__all__ = [
    "membership_figure",
    "membership_figure_file",
    "stanford_axes",
    "stanford_figure",
    "stanford_figure_files",
]


def membership_figure(example: Mapping[str, Any]) -> Figure:
    """Memberships of the columns of the paper's full design matrices in the three FCM
    classes (one panel per case; column 10 is the parity vector ``t``).

    Parameters
    ----------
    example : mapping
        :func:`navtrack.experiments.raim_fcm.example.paper_example`.
    """
    fig = new_figure((9.0, 3.6))
    axes = fig.subplots(1, 2, sharey=True)
    for ax, case in zip(axes, ("single", "double"), strict=True):
        u = np.asarray(example[case]["memberships"])
        cols = np.arange(1, u.shape[1] + 1)
        for k in range(u.shape[0]):
            ax.bar(cols + (k - 1) * 0.27, u[k], width=0.27, label=f"class {k + 1}")
        ax.set_xticks(cols, [str(c) for c in cols[:-1]] + ["t"])
        named = example[case]["fcm_gross_errors"]
        ax.set_title(f"{case} fault {example[case]['injected']}: FCM names {named}")
        ax.set_xlabel("column of the full design matrix (satellite)")
    axes[0].set_ylabel("membership")
    axes[0].legend(fontsize=8)
    return fig


def membership_figure_file(example: Mapping[str, Any], out_dir: Path) -> Path:
    """:func:`membership_figure` written to ``out_dir/fcm_memberships.png``."""
    return save_figure(membership_figure(example), figure_dir(out_dir) / "fcm_memberships.png")


def stanford_axes(
    ax: Axes,
    error_m: ArrayLike,
    pl_m: ArrayLike,
    label: str = "",
    *,
    top_m: float | None = None,
    max_count: int | None = None,
) -> QuadMesh:
    """A Stanford diagram: 2-D histogram of (error, protection level), the diagonal, and the
    count of epochs with error above the protection level (misleading information).

    Parameters
    ----------
    ax : matplotlib Axes
    error_m, pl_m : array_like, shape (n,)
        Actual position error and protection level (m); epochs without a level are left out.
    label : str
    top_m : float, optional
        Upper limit of both axes (m); default: the largest value plus 5 %. Panels that are
        compared share it.
    max_count : int, optional
        Top of the logarithmic colour scale (epochs per cell); default: the fullest cell.
        Panels that are compared share it, and one colour bar.

    Returns
    -------
    matplotlib.collections.QuadMesh
        The histogram, for a colour bar.
    """
    from matplotlib.colors import LogNorm

    e = np.asarray(error_m, dtype=float)
    p = np.asarray(pl_m, dtype=float)
    ok = np.isfinite(e) & np.isfinite(p)
    e, p = e[ok], p[ok]
    top = _stanford_top(e, p) if top_m is None else float(top_m)
    bins = np.linspace(0.0, top, 60)
    h, xe, ye = np.histogram2d(e, p, bins=[bins, bins])
    vmax = max(float(h.max(initial=1.0)) if max_count is None else float(max_count), 1.0)
    mesh = ax.pcolormesh(
        xe, ye, np.where(h.T > 0, h.T, np.nan), cmap="viridis", norm=LogNorm(1.0, vmax)
    )
    ax.plot([0, top], [0, top], "k-", lw=0.8)
    ax.set_xlim(0.0, top)
    ax.set_ylim(0.0, top)
    ax.set_aspect("equal")
    mi = int(np.sum(e > p))
    ax.set_title(f"{label}\n{e.size} epochs, error > PL: {mi}", fontsize=9)
    ax.set_xlabel("position error (m)")
    ax.set_ylabel("protection level (m)")
    return mesh


def _stanford_top(*values: np.ndarray) -> float:
    """The largest finite value of ``values`` plus 5 % (at least 1 m)."""
    finite = [v[np.isfinite(v)] for v in values]
    return max([1.0, *(float(v.max()) for v in finite if v.size)]) * 1.05


def stanford_figure(name: str, methods: Mapping[str, tuple[Any, Any, Any, Any]]) -> Figure:
    """Stanford diagrams of one station: horizontal and vertical, one column per method, the
    methods of a row on the same axes and all panels on one colour scale with one colour bar.

    Parameters
    ----------
    name : str
        Station.
    methods : mapping
        ``{method: (err_h, hpl, err_v, vpl)}`` (m).
    """
    fig = new_figure((3.0 * len(methods) + 1.0, 5.6))
    axes = np.atleast_2d(fig.subplots(2, len(methods), squeeze=False))
    arrays = [[np.asarray(a, dtype=float) for a in m] for m in methods.values()]
    top_h = _stanford_top(*(a for eh, hpl, _, _ in arrays for a in (eh, hpl)))
    top_v = _stanford_top(*(a for _, _, ev, vpl in arrays for a in (ev, vpl)))
    count = max((a[0].size for a in arrays), default=1)
    mesh = None
    for j, (m, (eh, hpl, ev, vpl)) in enumerate(zip(methods, arrays, strict=True)):
        stanford_axes(axes[0, j], eh, hpl, f"{m} horizontal", top_m=top_h, max_count=count)
        mesh = stanford_axes(axes[1, j], ev, vpl, f"{m} vertical", top_m=top_v, max_count=count)
    fig.suptitle(name.replace("_", " "))
    if mesh is not None:
        fig.colorbar(mesh, ax=axes.ravel().tolist(), label="epochs per cell", shrink=0.8)
    return fig


def stanford_figure_files(
    artifacts: Mapping[str, Mapping[str, tuple[Any, Any, Any, Any]]], out_dir: Path
) -> list[Path]:
    """:func:`stanford_figure` of every station, written to ``out_dir/stanford_NAME.png``.

    Parameters
    ----------
    artifacts : mapping
        ``{station: {method: (err_h, hpl, err_v, vpl)}}`` of
        :func:`navtrack.experiments.raim_fcm.experiment.clean_protection`.
    out_dir : Path
    """
    return [
        save_figure(stanford_figure(name, methods), figure_dir(out_dir) / f"stanford_{name}.png")
        for name, methods in artifacts.items()
    ]
