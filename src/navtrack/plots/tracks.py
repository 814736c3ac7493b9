"""Map-like figure of detections and confirmed tracks (east/north, km)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from navtrack._typing import ArrayLike, StrPath


def plot_tracks(out_dir: StrPath, en: ArrayLike, result: Any, title: str = "") -> Path:
    """Write ``tracks.png`` in ``out_dir``: detections (grey dots), confirmed tracks (lines).

    Parameters
    ----------
    out_dir : directory (created if absent)
    en : (N, 2) detections, east/north m
    result : :class:`navtrack.tracking.tracker.TrackerResult`
    title : figure title
    """
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        from navtrack.errors import MissingDependencyError

        raise MissingDependencyError("matplotlib", "plot", "--plot") from None
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    en = np.asarray(en, dtype=float)
    fig, ax = plt.subplots(figsize=(9, 8))
    ax.plot(en[:, 0] / 1e3, en[:, 1] / 1e3, ".", color="0.75", ms=1.5, label="detections")
    conf = np.asarray(result.track_confirmed)
    ids = np.asarray(result.track_id)
    x = np.asarray(result.track_x)
    confirmed_ids = np.unique(ids[conf])
    cmap = plt.get_cmap("tab20")
    for k, tid in enumerate(confirmed_ids):
        sel = ids == tid
        ax.plot(x[sel, 0] / 1e3, x[sel, 2] / 1e3, "-", lw=0.9, color=cmap(k % 20))
    ax.set_xlabel("east (km)")
    ax.set_ylabel("north (km)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_title(f"{title}\n{len(confirmed_ids)} confirmed tracks")
    ax.legend(loc="best", fontsize=8)
    path = out / "tracks.png"
    fig.savefig(path, dpi=130, bbox_inches="tight")
    plt.close(fig)
    return path
