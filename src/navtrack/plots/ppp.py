"""Figure of a static PPP solution: error against a reference beside the formal 95 % bound
(``navtrack ppp --ref ... --plot DIR``).

Drawn on its own Agg canvas (:mod:`navtrack.plots.canvas`); matplotlib (extra ``plot``) is
imported only when a figure is made.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from navtrack._typing import FloatArray, StrPath
from navtrack.geodesy import ecef_to_enu
from navtrack.gnss.ppp import PppResult
from navtrack.plots.canvas import figure_dir, new_figure, save_figure

__all__ = ["plot_ppp"]

_HORIZONTAL_95 = 2.447746830680816  # sqrt of the 95 % chi-square quantile, 2 degrees of freedom
_VERTICAL_95 = 1.959963984540054  # 95 % two-sided normal quantile


def plot_ppp(result: PppResult, ref_xyz_m: FloatArray, out_dir: StrPath) -> list[Path]:
    """Write ``ppp_error.png`` into ``out_dir``: horizontal and vertical error against the
    reference over time, each beside its formal 95 % bound (horizontal: the circle of radius
    2.45 sqrt((sd_e^2 + sd_n^2) / 2); vertical: 1.96 sd_u), on logarithmic axes.

    Returns
    -------
    list of Path
    """
    d = figure_dir(out_dir)
    ok = result.updated
    t = (result.t_gps_s - result.t_gps_s[0])[ok]
    enu = ecef_to_enu(result.pos_m[ok], np.asarray(ref_xyz_m, dtype=float))
    sd = result.sd_enu_m[ok]
    fig = new_figure((8.0, 5.0))
    ax_h, ax_u = fig.subplots(2, 1, sharex=True)
    ax_h.plot(t, np.hypot(enu[:, 0], enu[:, 1]), color="tab:blue", label="horizontal error")
    bound_h = _HORIZONTAL_95 * np.sqrt((sd[:, 0] ** 2 + sd[:, 1] ** 2) / 2.0)
    ax_h.plot(t, bound_h, color="k", ls="--", lw=0.8, label="formal 95 % bound")
    ax_u.plot(t, np.abs(enu[:, 2]), color="tab:orange", label="vertical error (absolute)")
    ax_u.plot(t, _VERTICAL_95 * sd[:, 2], color="k", ls="--", lw=0.8, label="formal 95 % bound")
    for ax, unit in ((ax_h, "horizontal (m)"), (ax_u, "up (m)")):
        ax.set_ylabel(unit)
        ax.set_yscale("log")
        ax.legend(loc="best", fontsize=8)
    ax_u.set_xlabel("time since first epoch (s)")
    ax_h.set_title(f"static PPP, {int(ok.sum())} epochs: error and formal 95 % bound", fontsize=9)
    return [save_figure(fig, d / "ppp_error.png")]
