"""Figure of ``navtrack reproduce alhat``: attitude error against time per estimate."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from navtrack.experiments.alhat.real import TrialOutcome

__all__ = ["write_error_figures"]


def write_error_figures(out_dir: Path, outcomes: Sequence[TrialOutcome]) -> list[Path]:
    """``attitude_error_<trial>.png``: error (deg, log scale) of every estimate against time."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    for oc in outcomes:
        fig, ax = plt.subplots(figsize=(9, 4.5))
        for name, err in oc.errors_deg.items():
            ax.semilogy(oc.t_s, err, lw=0.6, label=name)
        for t in oc.fix_t_s:
            ax.axvline(t, color="0.85", lw=0.3, zorder=0)
        ax.set_xlabel("time since start of recording (s)")
        ax.set_ylabel("attitude error (deg)")
        ax.set_title(f"BROAD {oc.name}: error against optical truth (grey: camera fixes)")
        ax.legend(loc="upper left", fontsize=8)
        fig.tight_layout()
        path = out_dir / f"attitude_error_{oc.name}.png"
        fig.savefig(path, dpi=120)
        plt.close(fig)
        paths.append(path)
    return paths
