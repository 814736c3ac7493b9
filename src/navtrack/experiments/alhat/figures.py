"""Figure of ``navtrack reproduce alhat``: attitude error against time per estimate."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from navtrack.experiments.alhat.real import TrialOutcome
from navtrack.plots.canvas import new_figure, save_figure

__all__ = ["write_error_figures", "write_fig16"]


def write_error_figures(out_dir: Path, outcomes: Sequence[TrialOutcome]) -> list[Path]:
    """``attitude_error_<trial>.png``: error (deg, log scale) of every estimate against time."""
    paths = []
    for oc in outcomes:
        fig = new_figure((9, 4.5))
        ax = fig.add_subplot()
        for name, err in oc.errors_deg.items():
            ax.semilogy(oc.t_s, err, lw=0.6, label=name)
        for t in oc.fix_t_s:
            ax.axvline(t, color="0.85", lw=0.3, zorder=0)
        ax.set_xlabel("time since start of recording (s)")
        ax.set_ylabel("attitude error (deg)")
        ax.set_title(f"BROAD {oc.name}: error against optical truth (grey: camera fixes)")
        ax.legend(loc="upper left", fontsize=8)
        paths.append(save_figure(fig, out_dir / f"attitude_error_{oc.name}.png", dpi=120))
    return paths


def write_fig16(out_dir: Path, run: dict[str, Any]) -> Path | None:
    """``fig16_scalar_error.png``: ``e_s`` at the fixes of one regime run before and after each
    sequence's correction (the paper's Fig. 16 A and C), sequences marked by colour."""
    series = run.get("fix_series")
    if not series:
        return None
    t = np.asarray(series["t_since_first_fix_s"])
    seq = np.asarray(series["sequence"])
    fig = new_figure((10, 4))
    axes = fig.subplots(1, 2, sharey=True)
    for ax, key, title in (
        (axes[0], "e_s_before_deg", "before the correction (Fig. 16 A)"),
        (axes[1], "e_s_after_deg", "after the correction (Fig. 16 C)"),
    ):
        e = np.asarray(series[key])
        for j in np.unique(seq):
            sel = seq == j
            ax.plot(t[sel], e[sel], ".-", ms=3, lw=0.6, label=f"sequence {j}")
        ax.set_title(title)
        ax.set_xlabel("seconds since the first fix")
    axes[0].set_ylabel("scalar error e_s (deg)")
    axes[0].legend(fontsize=8)
    fig.suptitle("Paper's regime (LN-200, 30° camera, target patch), first run")
    return save_figure(fig, out_dir / "fig16_scalar_error.png", dpi=120)
