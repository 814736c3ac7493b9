"""Fit of what paper 4 leaves unstated on its baseline: Table 3's KP row.

The paper gives neither the convergence threshold nor how its truths were drawn (truth process
noise, spacing of the "closely spaced" targets). They are chosen on the KP row of Table 3 alone
— the tracker without the paper's two contributions (IP-JPDA, the multi-target control rules
judged against each other) — by least squares over a grid; every other cell is then a
prediction. ``benchmarks/foveal_calibration.py`` runs the grid through the Monte Carlo runner.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from navtrack.experiments.foveal.tables import PAPER_TABLES

__all__ = ["baseline_misfit", "fit_on_baseline"]

_RULES = ("so", "to", "wo")


def baseline_misfit(results: Mapping[str, Any], threshold_m: float) -> float:
    """Rms difference (percentage points) of Table 3's KP row from the paper's at a threshold.

    ``results``: the summary of ``navtrack reproduce foveal`` (``results.json``); the threshold
    must be one of its ``converged_fraction_by_threshold_m`` keys.
    """
    key = f"{threshold_m:g}"
    d = [
        100 * results["table3"][r]["kp"]["converged_fraction_by_threshold_m"][key]
        - PAPER_TABLES["table3"][r]["kp"]
        for r in _RULES
    ]
    return math.sqrt(sum(x * x for x in d) / len(d))


def fit_on_baseline(
    grid: Mapping[tuple[float, float], Mapping[str, Any]],
) -> list[dict[str, float]]:
    """Every (truth_q, spacing_m, threshold_m) of a grid with its baseline misfit, best first.

    Parameters
    ----------
    grid : mapping (truth_q m²/s³, spacing_m m) -> results summary
        One reproduction per scenario; the thresholds are those each summary holds.

    Returns
    -------
    list of dict
        ``truth_q``, ``spacing_m``, ``threshold_m``, ``rms_pp`` (percentage points), sorted by
        ``rms_pp``.
    """
    rows = []
    for (truth_q, spacing_m), res in grid.items():
        cell = res["table3"]["so"]["kp"]["converged_fraction_by_threshold_m"]
        for key in cell:
            t = float(key)
            rows.append(
                {
                    "truth_q": truth_q,
                    "spacing_m": spacing_m,
                    "threshold_m": t,
                    "rms_pp": baseline_misfit(res, t),
                }
            )
    return sorted(rows, key=lambda r: r["rms_pp"])
