"""Figures of relative (RTK) solutions: error series by status, ratio-test values, satellites and
slips (``navtrack rtk --plot DIR``).

Drawn on their own Agg canvas (:mod:`navtrack.plots.canvas`); matplotlib (extra ``plot``) is
imported only when a figure is made.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from navtrack._typing import FloatArray, StrPath
from navtrack.gnss.rtk_config import STATUS_NAMES
from navtrack.plots.canvas import figure_dir, new_figure, save_figure
from navtrack.timescale import to_datetime64

if TYPE_CHECKING:
    from navtrack.gnss.relative import RtkResult

__all__ = ["plot_rtk"]

_COLOURS = {
    "fix": "tab:green",
    "float": "tab:orange",
    "dgnss": "tab:blue",
    "single": "tab:red",
    "no_base": "tab:gray",
}


def _title(t_gps_s: FloatArray) -> str:
    """``RTK solution, 2010-01-06 09:00:00 - 09:59:59 GPST, 3600 epochs``."""
    if t_gps_s.size == 0:
        return "RTK solution, no epochs"
    first, last = (str(to_datetime64(v))[:19].replace("T", " ") for v in (t_gps_s[0], t_gps_s[-1]))
    end = last[11:] if last[:10] == first[:10] else last
    return f"RTK solution, {first} – {end} GPST, {t_gps_s.size} epochs"


def plot_rtk(
    result: RtkResult,
    out_dir: StrPath,
    *,
    error_m: FloatArray | None = None,
    ratio_threshold: float = 3.0,
) -> list[Path]:
    """Write ``rtk_error.png`` (3-D error against a reference by status; without one, the
    distance from the median fixed or float position), ``rtk_ratio.png`` (ratio-test values and
    the threshold) and ``rtk_sats.png`` (satellites in the double differences, ambiguities
    restarted by slips) into ``out_dir``.

    Parameters
    ----------
    result : RtkResult
    out_dir : str or path-like
        Created if missing.
    error_m : ndarray, shape (E,), optional
        Per-epoch error against a reference (m; NaN where not compared).
    ratio_threshold : float
        Drawn as a line on the ratio figure.

    Returns
    -------
    list of Path
    """
    d = figure_dir(out_dir)
    t = result.t_gps_s - result.t_gps_s[0]
    names = np.array(STATUS_NAMES, dtype=object)[result.status.astype(np.int64)]
    if error_m is None:
        good = np.isin(names, ("fix", "float")) & np.all(np.isfinite(result.pos_m), axis=1)
        centre = np.median(result.pos_m[good], axis=0) if good.any() else np.zeros(3)
        err = np.linalg.norm(result.pos_m - centre, axis=1)
        label = "distance from the median fix/float position (m)"
    else:
        err = np.asarray(error_m, dtype=float)
        label = "3-D error against the reference (m)"
    paths = []
    title = _title(result.t_gps_s)

    fig = new_figure((8.0, 3.6))
    ax = fig.add_subplot()
    for name, colour in _COLOURS.items():
        sel = names == name
        if sel.any():
            ax.plot(t[sel], err[sel], ".", ms=3, color=colour, label=f"{name} ({sel.sum()})")
    ax.set_yscale("log")
    ax.set_xlabel("time since first epoch (s)")
    ax.set_ylabel(label)
    ax.legend(loc="best", fontsize=8)
    ax.set_title(title, fontsize=9)
    paths.append(save_figure(fig, d / "rtk_error.png"))

    fig = new_figure((8.0, 3.0))
    ax = fig.add_subplot()
    ok = np.isfinite(result.ratio)
    ax.plot(t[ok], result.ratio[ok], ".", ms=3, color="tab:purple")
    ax.axhline(ratio_threshold, color="k", lw=0.8, ls="--", label=f"threshold {ratio_threshold:g}")
    ax.set_yscale("log")
    ax.set_xlabel("time since first epoch (s)")
    ax.set_ylabel("ratio test s2 / s1")
    ax.legend(loc="best", fontsize=8)
    ax.set_title(title, fontsize=9)
    paths.append(save_figure(fig, d / "rtk_ratio.png"))

    fig = new_figure((8.0, 3.0))
    ax = fig.add_subplot()
    ax.step(t, result.n_sats, where="post", color="tab:blue", label="satellites in the DDs")
    slips = result.slip_mask.sum(axis=1)
    sel = slips > 0
    ax.bar(t[sel], slips[sel], width=1.0, color="tab:red", label="ambiguities restarted by slips")
    ax.set_xlabel("time since first epoch (s)")
    ax.legend(loc="best", fontsize=8)
    ax.set_title(title, fontsize=9)
    paths.append(save_figure(fig, d / "rtk_sats.png"))
    return paths
