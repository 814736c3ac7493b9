"""Tables (Markdown), figures and console lines of the AGPS reproduction."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from navtrack.experiments.agps.summary import (
    PAPER_MEAN_ITERATIONS,
    PAPER_TABLE_I,
    PAPER_TABLE_II,
)

__all__ = ["summary_lines", "tables_markdown", "write_figures"]

_LABEL = {"gn": "Gauss–Newton", "lm": "Marquardt", "map": "MAP (cell prior)"}
_FIG_HEIGHTS = (("fig2", ("56", "76")), ("fig3", ("96", "156")))


def _f(value: Any, digits: int = 1) -> str:
    if value is None:
        return "–"
    if isinstance(value, float):
        return f"{value:.{digits}f}" if value == value else "–"
    return str(value)


def _error_table(
    study: dict[str, Any], solver: str, interval: str, paper: dict[str, dict[str, float]] | None
) -> list[str]:
    """Percentiles and mean per height; with ``paper``, each cell ``navtrack (paper)``."""
    keys = ("p90_m", "p80_m", "p70_m", "p60_m", "p50_m", "mean_m")
    lines = [
        "| H/m | 90 % | 80 % | 70 % | 60 % | 50 % | mean | n | not ok |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for height, cases in study.get(solver, {}).items():
        s = cases.get(interval)
        if s is None:
            continue
        printed = (paper or {}).get(height, {})
        cells = [_f(s[k], 0) + (f" ({printed[k]:.0f})" if k in printed else "") for k in keys]
        lines.append(
            f"| {height} | " + " | ".join(cells) + f" | {s['n']} | {s['n_total'] - s['n']} |"
        )
    return lines


def _iteration_table(study: dict[str, Any], interval: str, paper: bool) -> list[str]:
    lines = [
        "| H/m | Gauss–Newton | Marquardt | ratio | MAP |"
        + (" paper GN | paper LM |" if paper else ""),
        "|---|---|---|---|---|" + ("---|---|" if paper else ""),
    ]
    for height in study.get("gn", {}):
        gn = study["gn"][height].get(interval, {}).get("mean_iterations")
        lm = study["lm"][height].get(interval, {}).get("mean_iterations")
        mp = study["map"][height].get(interval, {}).get("mean_iterations")
        ratio = lm / gn if gn and lm else None
        row = f"| {height} | {_f(gn, 3)} | {_f(lm, 3)} | {_f(ratio, 3)} | {_f(mp, 3)} |"
        if paper:
            pg, pl = PAPER_MEAN_ITERATIONS.get(height, (None, None))
            row += f" {_f(pg, 3)} | {_f(pl, 3)} |"
        lines.append(row)
    return lines


def _interval_table(study: dict[str, Any], heights: list[str]) -> list[str]:
    intervals = list(next(iter(study.get("gn", {}).values()), {}))
    lines = [
        "| H/m | solver | " + " | ".join(f"{i} min" for i in intervals) + " |",
        "|---|---|" + "---|" * len(intervals),
    ]
    for height in heights:
        for solver in ("gn", "lm", "map"):
            cases = study.get(solver, {}).get(height)
            if cases is None:
                continue
            lines.append(
                f"| {height} | {_LABEL[solver]} | "
                + " | ".join(_f(cases[i]["mean_m"]) for i in intervals)
                + " |"
            )
    return lines


def _verdict(f: dict[str, Any]) -> list[str]:
    gain = ", ".join(f"{k} min {_f(v)} m" for k, v in f["gain_m"].items())
    return [
        f"- Marquardt mean error at {f['interval_min']} min, height {f['height']}: "
        f"{_f(f['lm_mean_m'])} m vs Gauss–Newton {_f(f['gn_mean_m'])} m "
        f"(MAP {_f(f['map_mean_m'])} m)"
        f" — well below (< 40 %): **{'holds' if f['lm_below_gn'] else 'does not hold'}**.",
        "- Marquardt lowest at the true height (below the lowest and highest assumed heights): "
        f"**{'holds' if f.get('lm_lowest_at_true_height') else 'does not hold'}**.",
        f"- Iteration ratio Marquardt / Gauss–Newton {_f(f['iteration_ratio'], 3)} "
        f"— below 1.5: **{'holds' if f['ratio_below_1_5'] else 'does not hold'}**.",
        f"- Gain (GN − LM mean error) by interval: {gain} — shrinking with the interval: "
        f"**{'holds' if f['gain_shrinks'] else 'does not hold'}**.",
    ]


def _sensitivity_table(results: dict[str, Any]) -> list[str]:
    """One row per reading: Gauss–Newton and Marquardt at the first interval."""
    params = results["parameters"]
    first = f"{params['intervals_min'][0]:g}"
    heights = [f"{h:g}" for h in params["heights_m"]]
    true_h = min(heights, key=lambda h: abs(float(h) - params["site_llh"][2]))
    low, high = heights[0], heights[-1]
    rows = {"default": {s: results["simulation"][s] for s in ("gn", "lm")}}
    rows.update(results.get("sensitivity", {}))
    lines = [
        f"| reading | GN mean {true_h} m | LM mean {true_h} m | LM / GN | LM mean {low} / "
        f"{true_h} / {high} m | solves GN / LM | solves − 1 GN / LM |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, study in rows.items():

        def get(
            solver: str, height: str, key: str = "mean_m", study: dict[str, Any] = study
        ) -> float | None:
            value = study[solver].get(height, {}).get(first, {}).get(key)
            return None if value is None else float(value)

        gn, lm = get("gn", true_h), get("lm", true_h)
        it_gn, it_lm = get("gn", true_h, "mean_iterations"), get("lm", true_h, "mean_iterations")
        ratio = lm / gn if gn and lm is not None else None
        moved = [None if v is None else v - 1.0 for v in (it_gn, it_lm)]
        lines.append(
            f"| {name} | {_f(gn, 0)} | {_f(lm, 0)} | {_f(ratio, 2)} | "
            f"{_f(get('lm', low), 0)} / {_f(lm, 0)} / {_f(get('lm', high), 0)} | "
            f"{_f(it_gn, 2)} / {_f(it_lm, 2)} | {_f(moved[0], 2)} / {_f(moved[1], 2)} |"
        )
    return lines


def tables_markdown(results: dict[str, Any]) -> str:
    """Tables I, II, III and the data of Figs. 2/3 beside the paper's, the sensitivity to the
    unstated readings, and the real-data study."""
    first = f"{results['parameters']['intervals_min'][0]:g}"
    lines = _introduction(results)
    lines += _simulation_tables(results, first)
    lines += _real_data_tables(results, first)
    if results.get("real_skipped"):
        lines += ["Skipped: " + "; ".join(results["real_skipped"]), ""]
    return "\n".join(lines)


def _introduction(results: dict[str, Any]) -> list[str]:
    """Title, runs, the calibration on the baseline and the findings."""
    params = results["parameters"]
    cal = results.get("calibration", {})
    lines = [
        "# Two-satellite AGPS positioning (paper 1, Li 2010) — reproduction",
        "",
        f"Runs (fixes per case): {results['runs']} (seed {results['seed']}). Errors are 3-D "
        "distances to the truth (m) of the fixes with status `ok`; `not ok` counts the others. "
        "Simulation at the paper's site "
        f"{params['site_llh']} with the broadcast ephemerides of "
        f"`{results.get('nav_file', '')}`; error model and readings in `docs/agps.md`.",
        "",
        "## Calibration on the baseline",
        "",
        f"Fitted on {cal.get('fitted_on', '–')}: white pseudorange noise "
        f"{_f(cal.get('sigma_noise_m'))} m, elevation mask {_f(cal.get('elmask_deg'), 0)}°, "
        f"satellite pairs with a 2-min DOP ≤ {_f(cal.get('max_dop'), 0)}, cell radius "
        f"{_f(cal.get('cell_radius_m'), 0)} m (`python -m navtrack.experiments.agps.calibration`). "
        f"Misfit of this run to Table I ({cal.get('objective', '')}): "
        f"{_f(cal.get('table_i_misfit'), 3)}. Gauss–Newton's rows are the calibration; "
        "Marquardt's rows, Table III's Marquardt column and Figs. 2–3 are predictions.",
        "",
        "## Findings",
        "",
        "Simulation:",
        "",
        *_verdict(results["findings_simulation"]),
        "",
    ]
    if results.get("findings_real_data"):
        lines += [
            "Real data (fine-time assistance):",
            "",
            *_verdict(results["findings_real_data"]),
            "",
        ]
    return lines


def _simulation_tables(results: dict[str, Any], first: str) -> list[str]:
    """Tables I, II (and MAP), III, Figs. 2/3 and the sensitivity, simulation."""
    sim = results["simulation"]
    lines: list[str] = []
    for title, solver, paper in (
        ("Table I — Gauss–Newton (calibrated), navtrack (paper)", "gn", PAPER_TABLE_I),
        ("Table II — Marquardt (predicted), navtrack (paper)", "lm", PAPER_TABLE_II),
        ("Table II b — MAP with the cell prior (beyond the paper)", "map", None),
    ):
        lines += [f"## {title}, simulation, {first} min", ""]
        lines += [*_error_table(sim, solver, first, paper), ""]
    lines += [f"## Table III — mean iterations (linear solves), simulation, {first} min", ""]
    lines += [*_iteration_table(sim, first, True), ""]
    lines += ["## Figs. 2 and 3 — mean error (m) vs interval, simulation", ""]
    lines += [*_interval_table(sim, ["56", "76", "96", "156"]), ""]
    if results.get("sensitivity"):
        lines += [
            f"## Sensitivity — each unstated reading, simulation, {first} min",
            "",
            "The same fix sets solved under each reading: `f5_*` the other scale of the height "
            "equation, `cell_R` the cell radius R m, `noise_k` the white noise times k. "
            "Iterations are linear solves (the paper's k when its steps stop); `solves − 1` "
            "leaves out the last solve, taken from an iterate that already met ε.",
            "",
            *_sensitivity_table(results),
            "",
        ]
    return lines


def _real_data_tables(results: dict[str, Any], first: str) -> list[str]:
    """The real-data tables (pooled and per data set); nothing without real data."""
    lines: list[str] = []
    real = results.get("real_data") or {}
    if real.get("gn"):
        lines += [
            "## Real data (fine-time assistance)",
            "",
            "Heights are offsets (m) from each data set's reference height; receiver clocks "
            "known to ±300 m from a full single point solution, as a network's fine time. "
            "Pooled tables: the data sets with fixes at every interval ("
            + ", ".join(results.get("real_data_pooled_sets", []))
            + "); every set is in the per-set table. Fixes per data set and interval: "
            + "; ".join(
                f"{name} " + ", ".join(f"{k} min {v}" for k, v in n.items())
                for name, n in results.get("real_n_fixes", {}).items()
            )
            + ".",
            "",
        ]
        for title, solver in (("Gauss–Newton", "gn"), ("Marquardt", "lm"), ("MAP", "map")):
            lines += [f"### {title}, real data, {first} min", ""]
            lines += [*_error_table(real, solver, first, None), ""]
        lines += [f"### Mean iterations, real data, {first} min", ""]
        lines += [*_iteration_table(real, first, False), ""]
        lines += ["### Mean error (m) vs interval, real data", ""]
        lines += [*_interval_table(real, ["+0", "+20", "+40", "+100"]), ""]
        lines += _per_set_table(results)
    return lines


def _per_set_table(results: dict[str, Any]) -> list[str]:
    """Per data set at the true height: mean error / ok fixes with fine time and with the
    station clock."""
    lines: list[str] = []
    per_set = results.get("real_data_sets", {})
    if per_set:
        lines += [
            "### Per data set, true height (+0), mean error (m) / ok fixes",
            "",
            "Fine time: clocks known to ±300 m. Station clock: the receiver's own clock, "
            "milliseconds off on some stations (an extension beyond an AGPS phone).",
            "",
            "| data set | interval | GN | LM | MAP | GN, station clock | LM, station clock "
            "| MAP, station clock |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for name, by_solver in per_set.items():
            for interval in by_solver.get("gn", {}):
                cells = [by_solver[s][interval] for s in ("gn", "lm", "map")]
                cells += [by_solver["station_clock"][s][interval] for s in ("gn", "lm", "map")]
                lines.append(
                    f"| {name} | {interval} min | "
                    + " | ".join(f"{_f(c['mean_m'], 0)} / {c['n']}" for c in cells)
                    + " |"
                )
        lines.append("")
    return lines


def summary_lines(results: dict[str, Any]) -> list[str]:
    """Console lines: the verdicts of both studies."""
    out = []
    for key, name in (
        ("findings_simulation", "simulation"),
        ("findings_real_data", "real data"),
    ):
        f = results.get(key)
        if not f:
            continue
        out.append(
            f"{name:<10} {f['interval_min']} min h {f['height']}: mean GN {_f(f['gn_mean_m'])} m, "
            f"LM {_f(f['lm_mean_m'])} m, MAP {_f(f['map_mean_m'])} m; iteration ratio "
            f"{_f(f['iteration_ratio'], 3)}; LM below 40 % of GN: "
            f"{'yes' if f['lm_below_gn'] else 'no'}, LM lowest at the true height: "
            f"{'yes' if f.get('lm_lowest_at_true_height') else 'no'}, ratio < 1.5: "
            f"{'yes' if f['ratio_below_1_5'] else 'no'}, gain shrinks: "
            f"{'yes' if f['gain_shrinks'] else 'no'}"
        )
    for why in results.get("real_skipped", []):
        out.append(f"skipped: {why}")
    return out


def write_figures(results: dict[str, Any], out_dir: Path) -> list[Path]:
    """Figs. 2 and 3 (mean error vs interval, heights 56/76 and 96/156 m) of the simulation,
    and the same for the real data at offsets +0/+100 m."""
    # matplotlib: imported only when figures are written
    from navtrack.plots.canvas import new_figure, save_figure

    paths = []
    sets = [("simulation", name, heights) for name, heights in _FIG_HEIGHTS]
    sets.append(("real_data", "fig_real", ("+0", "+100")))
    for study_key, name, heights in sets:
        study = results.get(study_key) or {}
        if not study.get("gn"):
            continue
        fig = new_figure((6.0, 6.0))
        axes = fig.subplots(len(heights), 1, sharex=True)
        for ax, height in zip(axes, heights, strict=True):
            for solver, style in (("gn", "o-"), ("lm", "s-"), ("map", "^--")):
                cases = study[solver].get(height, {})
                xs = [float(k) for k in cases]
                ys = [
                    c["mean_m"] if c["mean_m"] is not None else float("nan") for c in cases.values()
                ]
                ax.plot(xs, ys, style, label=_LABEL[solver])
            where = "offset" if study_key == "real_data" else "height"
            ax.set_title(f"{study_key.replace('_', ' ')}, {where}: {height} m")
            ax.set_ylabel("mean error / m")
            if study_key == "real_data":  # receivers and readings spread over decades
                ax.set_yscale("log")
            else:
                ax.set_ylim(bottom=0.0)
            ax.grid(alpha=0.3, which="both")
        axes[-1].set_xlabel("interval between the measurements / min")
        axes[0].legend()
        paths.append(save_figure(fig, out_dir / f"{name}.png"))
    return paths
