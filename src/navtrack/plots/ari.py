"""Figures of ARI smoothing: filtered series with sigma_x band and gross errors; Monte Carlo.

matplotlib (extra ``plot``) is imported only when a figure is drawn, on its own Agg canvas (no
pyplot, no global backend change).
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from navtrack._typing import ArrayLike, StrPath
from navtrack.plots.canvas import new_figure, save_figure
from navtrack.timescale import to_datetime64

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from navtrack.smoothing.ari import AriResult

__all__ = [
    "estimates_figure",
    "plot_series",
    "recall_figure",
    "series_figure",
    "write_reproduction_figures",
]


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", text).strip("_")


def series_figure(
    t: ArrayLike, result: AriResult, title: str = "", unit: str = "", time_name: str = "t"
) -> Figure:
    """Observed and filtered series (band ±2 sigma_x), gross errors; residuals below.

    Top panel: observations ``y`` (dots), filtered ``x`` (line) and ``x ± 2 sigma_x``; flagged
    gross errors circled; the y axis names the quantity (``title``) and its ``unit``. Bottom
    panel: ``y - x`` with ``±3 sigma_n``. The time axis is ``t - t0`` (s) with ``t0`` the first
    epoch, written in the axis label: its value in ``time_name`` and, for GPS seconds
    (``time_name == "t_gps_s"``), its GPST calendar time.
    """
    t_arr = np.asarray(t, dtype=float)
    t0 = float(t_arr[0]) if t_arr.size else 0.0
    t_arr = t_arr - t0
    fig = new_figure((9.0, 5.5))
    ax1, ax2 = fig.subplots(2, 1, sharex=True, height_ratios=[2, 1])
    ax1.plot(t_arr, result.y, ".", ms=2, color="0.55", label="observed")
    ax1.plot(t_arr, result.x, "-", lw=1.0, color="C0", label="filtered")
    ax1.fill_between(
        t_arr,
        result.x - 2 * result.sigma_x,
        result.x + 2 * result.sigma_x,
        color="C0",
        alpha=0.25,
        lw=0,
        label="±2σx",
    )
    flagged = result.gross_error
    if flagged.any():
        ax1.plot(
            t_arr[flagged], result.y[flagged], "o", mfc="none", color="C3", label="gross error"
        )
    ax1.set_ylabel(f"{title} ({unit})" if title and unit else title or unit)
    ax1.ticklabel_format(axis="y", useOffset=False, style="plain")  # values, not an offset
    ax1.legend(loc="best", fontsize=8)
    ax1.set_title(
        f"{title}  ARI({result.p},{result.d})  σn={result.sigma_n:.3g}  σe={result.sigma_e:.3g}  "
        f"σx={result.sigma_x_rms:.3g} {unit}",
        fontsize=9,
    )
    resid = result.y - result.x
    ax2.plot(t_arr, resid, ".", ms=2, color="0.3")
    if flagged.any():
        ax2.plot(t_arr[flagged], resid[flagged], "o", mfc="none", color="C3")
    for s in (-3, 3):
        ax2.axhline(s * result.sigma_n, color="C1", lw=0.8, ls="--")
    ax2.set_ylabel(f"y − x [{unit}]" if unit else "y − x")
    t0_text = f"{time_name} = {t0:.10g} s"
    if time_name == "t_gps_s":
        t0_text += f", {str(to_datetime64(np.array([t0]))[0])[:19]} GPST"
    ax2.set_xlabel(f"t − t0 (s), t0 = first epoch ({t0_text})")
    return fig


def plot_series(
    path: StrPath,
    t: ArrayLike,
    result: AriResult,
    title: str = "",
    unit: str = "",
    time_name: str = "t",
) -> Path:
    """Write :func:`series_figure` as a PNG file."""
    return save_figure(series_figure(t, result, title, unit, time_name), Path(path))


def estimates_figure(ratios: Mapping[str, tuple[Sequence[float], Sequence[float]]]) -> Figure:
    """Box plots of estimate/truth of sigma_n and sigma_e per synthetic case."""
    names = list(ratios)
    fig = new_figure((8.0, 4.0))
    ax1, ax2 = fig.subplots(1, 2, sharey=False)
    for ax, k, label in ((ax1, 0, "σn estimate / truth"), (ax2, 1, "σe estimate / truth")):
        data = [np.asarray(ratios[n][k], dtype=float) for n in names]
        ax.boxplot(data, showfliers=False)
        ax.set_xticks(range(1, len(names) + 1), names, rotation=20, fontsize=8)
        ax.axhline(1.0, color="k", lw=0.8)
        for b in (0.9, 1.1):
            ax.axhline(b, color="C1", lw=0.8, ls="--")
        ax.set_title(label, fontsize=9)
    return fig


def recall_figure(detections: Mapping[str, tuple[Sequence[float], Sequence[bool]]]) -> Figure:
    """Recall of injected gross errors against their magnitude (in sigma_n), per case."""
    fig = new_figure((6.0, 4.0))
    ax = fig.subplots()
    edges = np.array([5, 6, 7, 8, 10, 12, 15.01])
    centres = 0.5 * (edges[:-1] + edges[1:])
    for name, (mags, hits) in detections.items():
        m = np.asarray(mags, dtype=float)
        h = np.asarray(hits, dtype=bool)
        rec = [
            h[(m >= lo) & (m < hi)].mean() if np.any((m >= lo) & (m < hi)) else np.nan
            for lo, hi in itertools.pairwise(edges)
        ]
        ax.plot(centres, rec, "o-", label=name)
    ax.axhline(0.95, color="k", lw=0.8, ls="--")
    ax.set_xlabel("gross error |Δ| / σn")
    ax.set_ylabel("recall")
    ax.set_ylim(0, 1.02)
    ax.legend(fontsize=8)
    return fig


def write_reproduction_figures(
    out_dir: Path,
    runs: Sequence[Mapping[str, Any]],
    cases: Sequence[Any],
    sources: Sequence[Any],
    fits: Mapping[tuple[str, str], AriResult],
) -> Iterator[Path]:
    """Figures of ``navtrack reproduce ari``: estimates, recall, one series per real source;
    yields each path once its file is on disk.

    Parameters
    ----------
    out_dir : Path
    runs : sequence of mapping
        Results of the successful synthetic runs (case name -> run record), in run order.
    cases : sequence of SyntheticCase
    sources : sequence of RealSeries
    fits : mapping
        ``(source, column) -> AriResult`` of the real series.
    """
    ratios: dict[str, tuple[list[float], list[float]]] = {}
    detections: dict[str, tuple[list[float], list[bool]]] = {}
    for case in cases:
        recs = [r[case.name] for r in runs if case.name in r]
        if not recs:
            continue
        ratios[case.name] = ([r["sigma_n_ratio"] for r in recs], [r["sigma_e_ratio"] for r in recs])
        detections[case.name] = (
            [m for r in recs for m in r["magnitude_sigma"]],
            [h for r in recs for h in r["robust_detected"]],
        )
    if ratios:
        yield save_figure(estimates_figure(ratios), out_dir / "synthetic_sigma_ratios.png")
        yield save_figure(recall_figure(detections), out_dir / "gross_error_recall.png")
    for src in sources:
        col = next(iter(src.columns))
        res = fits.get((src.source, col))
        if res is None or not res.estimated:
            continue
        name = _slug(f"real_{src.source}_{col}") + ".png"
        yield save_figure(
            series_figure(src.t_s, res, f"{src.source} {col}", src.unit), out_dir / name
        )


def regime_figure(results: Mapping[str, Any]) -> Figure | None:
    """σn in the paper's regimes beside the printed values: the carrier-phase strips (both VCE
    forms of the paper's estimator and the exact one) against Table 1's range, and the INS
    columns against Tables 4–5 (log scale); ``None`` when neither was run."""
    carrier = results.get("carrier") or []
    ins = (results.get("ins") or {}).get("rows") or []
    if not carrier and not ins:
        return None
    fig = new_figure((9.0, 4.0))
    axes = fig.subplots(1, 2)
    fits = (
        ("exact", "o", "exact"),
        ("paper_redundancy", "s", "paper, redundancy VCE"),
        ("paper_forstner", "x", "paper, Förstner VCE"),
    )
    panels = (
        (axes[0], carrier, "carrier-phase strips: σn (m)", (0.007, 0.038), "Table 1 range"),
        (axes[1], ins, "INS attitude: σn (deg)", (0.0023, 0.0060), "Tables 4–5 range"),
    )
    for ax, rows, title, printed, label in panels:
        names = [
            " ".join([r["source"], *([f"strip {r['strip']}"] if "strip" in r else []), r["column"]])
            for r in rows
        ]
        for key, marker, fit_label in fits:
            vals = [(r.get(key) or {}).get("sigma_n", np.nan) for r in rows]
            ax.plot(range(len(rows)), vals, marker, label=fit_label, ms=5, mfc="none")
        ax.axhspan(*printed, color="C3", alpha=0.15, label=f"paper, {label}")
        ax.set_yscale("log")
        ax.set_xticks(range(len(rows)), names, rotation=80, fontsize=6)
        ax.set_title(title, fontsize=9)
    axes[0].legend(fontsize=7)
    return fig
