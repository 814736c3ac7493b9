"""Statistics of the AGPS reproduction: the paper's error percentiles, means and iterations,
and the verdict on its findings.

Keys (``results.json``): ``simulation`` and ``real_data`` hold, per solver (``gn``, ``lm``,
``map``), per assumed height (simulation: the height in m, e.g. ``"56"``; real data: the offset
from the reference height in m, e.g. ``"+0"``) and per interval (min, e.g. ``"2"``), the
statistics of :func:`error_statistics`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from navtrack._typing import ArrayLike

__all__ = [
    "PAPER_MEAN_ITERATIONS",
    "PAPER_TABLE_II_MEAN_M",
    "PAPER_TABLE_I_MEAN_M",
    "error_statistics",
    "findings",
    "height_key",
    "interval_key",
    "summarize_cases",
]

#: Mean errors (m) of the paper's Tables I (Gauss–Newton) and II (Marquardt), 2 min, per height.
PAPER_TABLE_I_MEAN_M = {
    "-44": 539.46, "16": 502.20, "36": 495.78, "46": 494.31, "51": 493.95, "56": 493.84,
    "61": 494.04, "66": 494.58, "76": 496.01, "96": 500.36, "156": 529.42,
}  # fmt: skip
PAPER_TABLE_II_MEAN_M = {
    "-44": 157.11, "16": 126.76, "36": 119.00, "46": 118.91, "51": 119.25, "56": 110.79,
    "61": 116.90, "66": 118.91, "76": 119.00, "96": 128.31, "156": 128.58,
}  # fmt: skip
#: Table III: mean iterations at 2 min (Gauss–Newton, Marquardt) per height.
PAPER_MEAN_ITERATIONS = {
    "56": (2.000, 2.783),
    "76": (2.000, 2.877),
    "96": (2.000, 2.690),
    "156": (2.000, 2.810),
}


def height_key(height_m: float, *, offset: bool = False) -> str:
    """Key of an assumed height: ``"56"`` (simulation) or ``"+0"`` (offset, real data)."""
    return f"{height_m:+g}" if offset else f"{height_m:g}"


def interval_key(interval_min: float) -> str:
    """Key of an interval in minutes: ``"2"``."""
    return f"{interval_min:g}"


def error_statistics(
    error_m: ArrayLike, iterations: ArrayLike, status: ArrayLike
) -> dict[str, Any]:
    """The paper's statistics of a set of fixes.

    Parameters
    ----------
    error_m : array-like, shape (n,)
        Distance of each fix to the truth (m), NaN where the fix is not ``ok``.
    iterations : array-like of int, shape (n,)
    status : array-like of int, shape (n,)
        :class:`~navtrack.gnss.agps.AgpsStatus`; -1 marks padding (not a fix, not counted).

    Returns
    -------
    dict
        ``p50_m`` … ``p90_m`` (error percentiles, the paper's "90 %" column is ``p90_m``),
        ``mean_m``, ``mean_iterations`` (over the ``ok`` fixes), ``n`` (``ok`` fixes),
        ``n_total`` and ``statuses`` (fixes per status name).
    """
    from navtrack.gnss.agps import STATUS_NAMES

    err = np.asarray(error_m, dtype=float).ravel()
    it = np.asarray(iterations, dtype=float).ravel()
    st = np.asarray(status, dtype=np.int64).ravel()
    fix = st >= 0  # status -1 pads cases with fewer fixes
    err, it, st = err[fix], it[fix], st[fix]
    ok = (st == 0) & np.isfinite(err)
    counts = np.bincount(st, minlength=len(STATUS_NAMES))
    out: dict[str, Any] = {}
    for p in (50, 60, 70, 80, 90):
        out[f"p{p}_m"] = float(np.percentile(err[ok], p)) if ok.any() else None
    out["mean_m"] = float(err[ok].mean()) if ok.any() else None
    out["mean_iterations"] = float(it[ok].mean()) if ok.any() else None
    out["n"] = int(ok.sum())
    out["n_total"] = int(err.size)
    out["statuses"] = {name: int(counts[i]) for i, name in enumerate(STATUS_NAMES)}
    return out


def summarize_cases(
    error_m: ArrayLike,
    iterations: ArrayLike,
    status: ArrayLike,
    solvers: Sequence[str],
    heights: Sequence[str],
    intervals: Sequence[str],
) -> dict[str, dict[str, dict[str, dict[str, Any]]]]:
    """Statistics per solver, height and interval of fixes stacked along the first axis.

    Parameters
    ----------
    error_m, iterations, status : array-like, shape (n, solvers, intervals, heights)
    solvers, heights, intervals : sequence of str
        Keys of the three trailing axes.

    Returns
    -------
    dict
        ``out[solver][height][interval]`` = :func:`error_statistics`.
    """
    err = np.asarray(error_m, dtype=float)
    it = np.asarray(iterations)
    st = np.asarray(status)
    return {
        s: {
            h: {
                i: error_statistics(err[:, j, ii, hh], it[:, j, ii, hh], st[:, j, ii, hh])
                for ii, i in enumerate(intervals)
            }
            for hh, h in enumerate(heights)
        }
        for j, s in enumerate(solvers)
    }


def findings(table: dict[str, Any], true_height: str, intervals: Sequence[str]) -> dict[str, Any]:
    """Whether the paper's three findings hold in one study.

    Parameters
    ----------
    table : dict
        ``out[solver][height][interval]`` of :func:`summarize_cases`.
    true_height : str
        Height key at the true height (``"56"`` or ``"+0"``).
    intervals : sequence of str
        Interval keys in increasing order; the first is the paper's 2 min.

    Returns
    -------
    dict
        ``lm_mean_m``/``gn_mean_m``/``map_mean_m`` at the first interval and true height;
        ``lm_below_gn`` (Marquardt's mean error below half of Gauss–Newton's: "well below");
        ``iteration_ratio`` (Marquardt / Gauss–Newton mean iterations) and ``ratio_below_1_5``;
        ``gain_m`` per interval (Gauss–Newton minus Marquardt mean error) and
        ``gain_shrinks`` (Marquardt gains at the first interval and gains less at the last).
    """

    def mean(solver: str, interval: str, key: str = "mean_m") -> float:
        value = table.get(solver, {}).get(true_height, {}).get(interval, {}).get(key)
        return float("nan") if value is None else float(value)

    first = intervals[0]
    gn, lm = mean("gn", first), mean("lm", first)
    it_gn, it_lm = mean("gn", first, "mean_iterations"), mean("lm", first, "mean_iterations")
    ratio = it_lm / it_gn if it_gn > 0 else float("nan")
    gain = {i: mean("gn", i) - mean("lm", i) for i in intervals}
    values = [gain[i] for i in intervals]
    return {
        "height": true_height,
        "interval_min": first,
        "gn_mean_m": gn,
        "lm_mean_m": lm,
        "map_mean_m": mean("map", first),
        "lm_below_gn": bool(lm < 0.5 * gn),
        "iteration_ratio": ratio,
        "ratio_below_1_5": bool(ratio < 1.5),
        "gain_m": gain,
        "gain_shrinks": bool(len(values) > 1 and values[0] > 0.0 and values[-1] < values[0]),
    }
