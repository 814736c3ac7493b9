"""Figures 1-4 of the foveal reproduction and the gain-rule check (matplotlib, extra ``plot``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from navtrack.plots.canvas import figure_dir, new_figure, save_figure

__all__ = ["write_figures"]

_NAMES = {"ip_jpda": "IP-JPDA", "kp": "KP", "ip_gnn": "IP-GNN", "ip_gnn_joint": "IP-GNN joint"}
#: The paper's ASE axes (m²): Figs. 1-2 (three targets) 0-6, Fig. 3 (two targets) 0-3.
ASE_YLIM_M2 = {"table3": 6.0, "table4": 6.0, "table5": 3.0}


def _paper_axes(ax: Any, ymax: float, steps: int) -> None:
    ax.set_xlim(0, max(30, steps))
    ax.set_ylim(0, ymax)
    ax.set_xlabel("time index k")
    ax.set_ylabel("ASE of position, converged runs (m²)")


def _ase_panel(ax: Any, table: dict[str, Any], proposal: str, title: str, ymax: float) -> None:
    styles = {"so": ":", "to": "--", "wo": "-"}
    for rule, row in table.items():
        ase = np.asarray(row[proposal]["ase_m2"], dtype=float)
        if ase.size == 0:
            continue
        k = np.arange(1, ase.shape[1] + 1)
        for t in range(ase.shape[0]):
            ax.plot(k, ase[t], styles[rule], color=f"C{t}", label=f"t{t + 1} ({rule.upper()})")
        _paper_axes(ax, ymax, ase.shape[1])
    ax.set_title(title)
    ax.legend(fontsize=6, ncol=3)


def write_figures(results: dict[str, Any], runs: list[dict[str, Any]], out_dir: Path) -> list[Path]:
    """Write fig1..fig4 and the gain check as PNG into ``out_dir``; return their paths."""
    out = figure_dir(out_dir)
    paths = []
    for n, key, what in ((1, "table3", "no clutter"), (2, "table4", "clutter")):
        fig = new_figure((10, 4))
        for i, prop in enumerate(("ip_jpda", "kp")):
            ax = fig.add_subplot(1, 2, i + 1)
            _ase_panel(ax, results[key], prop, f"{_NAMES[prop]}, {what}", ASE_YLIM_M2[key])
        paths.append(save_figure(fig, out / f"fig{n}_ase_{key}.png"))
    fig = new_figure((10, 4))
    for i, cond in enumerate(("no_clutter", "clutter")):
        ax = fig.add_subplot(1, 2, i + 1)
        for prop, style in (("ip_gnn", "--"), ("ip_jpda", "-"), ("ip_gnn_joint", ":")):
            ase = np.asarray(results["table5"][prop][cond]["ase_m2"], dtype=float)
            for t in range(ase.shape[0] if ase.size else 0):
                k = np.arange(1, ase.shape[1] + 1)
                ax.plot(k, ase[t], style, color=f"C{t}", label=f"t{t + 1} ({_NAMES[prop]})")
                _paper_axes(ax, ASE_YLIM_M2["table5"], ase.shape[1])
        ax.set_title("Pd = 1, λV = 0" if cond == "no_clutter" else "Pd = 0.9, λV = 0.5")
        ax.legend(fontsize=7)
    paths.append(save_figure(fig, out / "fig3_ase_table5.png"))
    if runs:
        tr = runs[0]["trajectory"]
        truth, est = np.asarray(tr["truth_m"]), np.asarray(tr["estimate_m"])
        fig = new_figure((6, 4))
        ax = fig.add_subplot(1, 1, 1)
        k = np.arange(1, truth.shape[0] + 1)
        for t in range(truth.shape[1]):
            ax.plot(k, truth[:, t], "-", color=f"C{t}", label=f"t{t + 1} (true)")
            ax.plot(k, est[:, t], "o", ms=3, color=f"C{t}", label=f"t{t + 1} (estimated)")
        ax.set_xlabel("time index k")
        ax.set_ylabel("position (m)")
        ax.set_title("Run 0, IP-JPDA, WO, clutter")
        ax.legend(fontsize=7)
        paths.append(save_figure(fig, out / "fig4_trajectories.png"))
    if "gain_check" in results:
        g = results["gain_check"]
        P = np.array([r["P_m2"] for r in g["rule1"]])
        fig = new_figure((10, 4))
        ax = fig.add_subplot(1, 2, 1)
        ax.loglog(P, [r["c_optimal"] for r in g["rule1"]], "k-o", label="one-scan optimum")
        ax.loglog(P, [r["c_rule1"] for r in g["rule1"]], "C0--s", label="rule (1), log10(R)/8-0.4")
        ax.loglog(
            P, [r["c_rule1_other_reading"] for r in g["rule1"]], "C1:^", label="1/(8 log10 R)-0.4"
        )
        ax.set_xlabel("predicted position variance P (m²)")
        ax.set_ylabel("gain c (1/m)")
        ax.set_title(f"Rule (1) vs optimum, R = {g['R_rad2']}")
        ax.legend(fontsize=7)
        ax = fig.add_subplot(1, 2, 2)
        ax.semilogx(P, [r["var_ratio_rule1"] for r in g["rule1"]], "C0--s", label="rule (1)")
        ax.semilogx(P, [r["var_ratio_other_reading"] for r in g["rule1"]], "C1:^", label="other")
        ax.set_xlabel("predicted position variance P (m²)")
        ax.set_ylabel("E[posterior variance] / optimum")
        ax.legend(fontsize=7)
        paths.append(save_figure(fig, out / "gain_rule_check.png"))
    return paths
