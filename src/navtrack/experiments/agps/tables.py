"""Tables (Markdown), figures and console lines of the AGPS reproduction."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from navtrack.experiments.agps.summary import (
    PAPER_MEAN_ITERATIONS,
    PAPER_TABLE_I_MEAN_M,
    PAPER_TABLE_II_MEAN_M,
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
    study: dict[str, Any], solver: str, interval: str, paper: dict[str, float] | None
) -> list[str]:
    head = "| H/m | 90 % | 80 % | 70 % | 60 % | 50 % | mean | n | not ok |"
    rule = "|---|---|---|---|---|---|---|---|---|"
    if paper is not None:
        head += " paper mean |"
        rule += "---|"
    lines = [head, rule]
    for height, cases in study.get(solver, {}).items():
        s = cases.get(interval)
        if s is None:
            continue
        bad = s["n_total"] - s["n"]
        row = (
            f"| {height} | "
            + " | ".join(_f(s[f"p{p}_m"]) for p in (90, 80, 70, 60, 50))
            + f" | {_f(s['mean_m'])} | {s['n']} | {bad} |"
        )
        if paper is not None:
            row += f" {_f(paper.get(height))} |"
        lines.append(row)
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
        f" — well below (< half): **{'holds' if f['lm_below_gn'] else 'does not hold'}**.",
        f"- Iteration ratio Marquardt / Gauss–Newton {_f(f['iteration_ratio'], 3)} "
        f"— below 1.5: **{'holds' if f['ratio_below_1_5'] else 'does not hold'}**.",
        f"- Gain (GN − LM mean error) by interval: {gain} — shrinking with the interval: "
        f"**{'holds' if f['gain_shrinks'] else 'does not hold'}**.",
    ]


def tables_markdown(results: dict[str, Any]) -> str:
    """Tables I, II, III and the data of Figs. 2/3, for the simulation and the real data."""
    params = results["parameters"]
    sim = results["simulation"]
    first = f"{params['intervals_min'][0]:g}"
    lines = [
        "# Two-satellite AGPS positioning (paper 1, Li 2010) — reproduction",
        "",
        f"Runs (fixes per case): {results['runs']} (seed {results['seed']}). Errors are 3-D "
        "distances to the truth (m) of the fixes with status `ok`; `not ok` counts the others "
        "(no convergence, diverged, singular). Simulation at the paper's site "
        f"{params['site_llh']} with the broadcast ephemerides of "
        f"`{results.get('nav_file', '')}`; error model and base station in `docs/agps.md`.",
        "",
        "## Findings",
        "",
        "Simulation:",
        "",
        *_verdict(results["findings_simulation"]),
        "",
    ]
    if results.get("findings_real_data"):
        lines += ["Real data:", "", *_verdict(results["findings_real_data"]), ""]
    for title, solver, paper in (
        ("Table I — Gauss–Newton", "gn", PAPER_TABLE_I_MEAN_M),
        ("Table II — Marquardt", "lm", PAPER_TABLE_II_MEAN_M),
        ("Table II b — MAP with the cell prior (beyond the paper)", "map", None),
    ):
        lines += [f"## {title}, simulation, {first} min", ""]
        lines += [*_error_table(sim, solver, first, paper), ""]
    lines += [f"## Table III — mean iterations, simulation, {first} min", ""]
    lines += [*_iteration_table(sim, first, True), ""]
    lines += ["## Figs. 2 and 3 — mean error (m) vs interval, simulation", ""]
    lines += [*_interval_table(sim, ["56", "76", "96", "156"]), ""]
    near = results.get("simulation_near_cell") or {}
    if near.get("gn"):
        lo, hi = params["near_cell_distance_m"]
        lines += [
            f"## Sensitivity — the same fixes from a near cell ({lo:g}–{hi:g} m), true height",
            "",
            *_verdict(results["findings_near_cell"]),
            "",
            *_interval_table(near, list(near["gn"])),
            "",
            *_iteration_table(near, first, False),
            "",
        ]
    real = results.get("real_data") or {}
    if real.get("gn"):
        lines += [
            "## Real data",
            "",
            "Heights are offsets (m) from each data set's reference height. Fixes per data set "
            "and interval: "
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
        per_set = results.get("real_data_sets", {})
        if per_set:
            lines += [
                "### Per data set, true height (+0), mean error (m) / fixes",
                "",
                "Last column: Marquardt with the clocks started from the cell "
                "(`clock_start=cell`, beyond the paper's zero start).",
                "",
                "| data set | interval | Gauss–Newton | Marquardt | MAP | Marquardt, clocks "
                "from the cell |",
                "|---|---|---|---|---|---|",
            ]
            for name, by_solver in per_set.items():
                for interval in by_solver.get("gn", {}):
                    keys = ("gn", "lm", "map", "lm_cell_clock")
                    cells = [by_solver[s][interval] for s in keys if s in by_solver]
                    lines.append(
                        f"| {name} | {interval} min | "
                        + " | ".join(f"{_f(c['mean_m'])} / {c['n']}" for c in cells)
                        + " |"
                    )
            lines.append("")
    if results.get("real_skipped"):
        lines += ["Skipped: " + "; ".join(results["real_skipped"]), ""]
    return "\n".join(lines)


def summary_lines(results: dict[str, Any]) -> list[str]:
    """Console lines: the verdicts of both studies."""
    out = []
    for key, name in (
        ("findings_simulation", "simulation"),
        ("findings_near_cell", "near cell"),
        ("findings_real_data", "real data"),
    ):
        f = results.get(key)
        if not f:
            continue
        out.append(
            f"{name:<10} {f['interval_min']} min h {f['height']}: mean GN {_f(f['gn_mean_m'])} m, "
            f"LM {_f(f['lm_mean_m'])} m, MAP {_f(f['map_mean_m'])} m; iteration ratio "
            f"{_f(f['iteration_ratio'], 3)}; LM well below GN: "
            f"{'yes' if f['lm_below_gn'] else 'no'}, ratio < 1.5: "
            f"{'yes' if f['ratio_below_1_5'] else 'no'}, gain shrinks: "
            f"{'yes' if f['gain_shrinks'] else 'no'}"
        )
    for why in results.get("real_skipped", []):
        out.append(f"skipped: {why}")
    return out


def write_figures(results: dict[str, Any], out_dir: Path) -> list[Path]:
    """Figs. 2 and 3 (mean error vs interval, heights 56/76 and 96/156 m) of the simulation,
    and the same for the real data at offsets +0/+100 m."""
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
            ax.set_ylim(bottom=0.0)
            ax.grid(alpha=0.3)
        axes[-1].set_xlabel("interval between the measurements / min")
        axes[0].legend()
        paths.append(save_figure(fig, out_dir / f"{name}.png"))
    return paths
