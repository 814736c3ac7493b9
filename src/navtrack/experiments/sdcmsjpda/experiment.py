"""``navtrack reproduce sdcmsjpda``: paper 3 (Zhang, Xiong & He) on the experiment contract.

1. Monte Carlo runs of :func:`~navtrack.experiments.sdcmsjpda.scenario.paper3_run` (every
   ``P_D`` and every fusion algorithm on one truth per run);
2. :func:`summarize_runs`: divergence counts (Table 1), RMS position / velocity error per step
   over the converged runs (Figs. 1-6), their means, ms per step;
3. tables, console lines and figures below.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from navtrack._typing import FloatArray
from navtrack.experiments.contract import Experiment, Outcome
from navtrack.experiments.sdcmsjpda.scenario import SdCmsjpdaParams, clutter_density, paper3_run
from navtrack.tracking.models import constant_velocity
from navtrack.tracking.simulate import simulate_truth

__all__ = ["EXPERIMENT", "PAPER_TABLE1", "SdCmsjpdaExperiment", "summarize_runs"]

_RunResult = dict[str, Any]

#: Paper 3, Table 1: divergences in 50 runs ("emanative times"), per P_D.
PAPER_TABLE1 = {
    "sequential": {"0.97": 2, "0.76": 11, "0.58": 17},
    "sdcmsjpda": {"0.97": 0, "0.76": 3, "0.58": 5},
}
#: Paper 3, section 4: mean time per step on a 2.0 GHz PC, ms.
PAPER_MS_PER_STEP = {"sequential": 25.1, "sdcmsjpda": 28.2}
#: Steps (1-based, inclusive) after the crossing at about step 31 whose error per run and
#: target the post-crossing figure shows.
POST_CROSSING_STEPS = (46, 80)

#: What each tracker of the tables implements (written to results.json).
ALGORITHM_EQUATIONS = {
    "sequential": "sequential MSJPDA (Pao & Frei 1995): single-sensor JPDA per sensor in turn",
    "parallel": "parallel MSJPDA (Pao & Frei 1995): joint S-tuple events, stacked EKF update",
    "sdcmsjpda": (
        "SD-CMSJPDA as printed: S-tuple events and marginals (eqs. 3-22, Poisson form of eq. "
        "21), tuple estimate X + sum_s w_s K_s nu_s (eq. 24), w_s = e_s / (b + sum e_i) (eq. "
        "25), eq. 26 nonparametric e_s = exp(-d_s^2 / 2), b = m (2 pi / gamma) (1 - Pd PG) / "
        "(pi Pd) with m = clutter_rate and gamma the PG gate threshold, beta_0 (eq. 28), "
        "covariance eqs. 31-32"
    ),
    "sd_gnn": "S-D assignment GNN: best joint event by (S+1)-D assignment, stacked EKF update",
    "sdcmsjpda_fused": (
        "SD-CMSJPDA, ML-fused reading: the tuple's equivalent measurement is the maximum-"
        "likelihood fusion of its detections (not eqs. 24-26); its association equals parallel"
    ),
    "sdcmsjpda_joint": "sdcmsjpda_fused with the joint tuple likelihood (diagnostic, not eq. 15)",
}


def summarize_runs(params: SdCmsjpdaParams, runs: Sequence[_RunResult]) -> dict[str, Any]:
    """Per ``P_D`` and algorithm: ``diverged``, ``failed``, ``runs``, ``rms_pos_m``,
    ``rms_vel_mps`` (mean over steps of the RMS over converged runs and both targets), the
    per-step arrays ``rms_pos_per_step_m`` / ``rms_vel_per_step_mps`` and ``ms_per_step``."""
    by_pd: dict[str, Any] = {}
    for pd in params.pd_values:
        key = f"{pd:g}"
        per: dict[str, Any] = {}
        for alg in params.algorithms:
            rows = [r[key][alg] for r in runs]
            div = np.array([row["diverged"] for row in rows], dtype=bool)
            ok = [row for row, d in zip(rows, div, strict=True) if not d]
            if ok:
                pos = np.sqrt(np.mean([row["pos_err2_m2"] for row in ok], axis=0))
                vel = np.sqrt(np.mean([row["vel_err2_m2ps2"] for row in ok], axis=0))
            else:
                pos = vel = np.full(params.n_steps, np.nan)
            ms = [row["ms_per_step"] for row in rows if np.isfinite(row["ms_per_step"])]
            a, b = POST_CROSSING_STEPS
            tail = [np.asarray(row["pos_err_per_target_m"])[a - 1 : b] for row in ok]
            per[alg] = {
                "diverged": int(div.sum()),
                "failed": sum(bool(row["failed"]) for row in rows),
                "runs": len(rows),
                "rms_pos_m": float(np.mean(pos)),
                "rms_vel_mps": float(np.mean(vel)),
                "rms_pos_per_step_m": pos,
                "rms_vel_per_step_mps": vel,
                "ms_per_step": float(np.mean(ms)) if ms else float("nan"),
                "post_crossing_err_per_run_m": [
                    np.mean(e, axis=0).tolist() for e in tail if e.size
                ],
            }
        by_pd[key] = per
    return {
        "paper": "Zhang, Xiong, He, S-D assignment CMSJPDA, ICMLC 2005 (paper 3)",
        "divergence_rule": (
            f"a run diverged for an algorithm when the mean position error of either target "
            f"over the last {params.divergence_window} scans exceeds {params.divergence_m:g} m "
            "(or the filter failed numerically)"
        ),
        "clutter_region": clutter_description(params),
        "clutter_density_per_m_rad": list(clutter_density(params, 2, _truth(params))),
        "ms_per_step_note": "CPU time of the fusion step (time.thread_time), mean over runs",
        "by_pd": by_pd,
        "algorithm_equations": {a: ALGORITHM_EQUATIONS[a] for a in params.algorithms},
        "diverged_by_threshold": _diverged_by_threshold(params, runs),
        "paper_table1": PAPER_TABLE1,
        "paper_ms_per_step": PAPER_MS_PER_STEP,
    }


#: Divergence thresholds of the sensitivity table, m (the rule's window unchanged).
SENSITIVITY_DIVERGENCE_M = (1000.0, 2000.0, 5000.0)


def _diverged_by_threshold(
    params: SdCmsjpdaParams, runs: Sequence[_RunResult]
) -> dict[str, dict[str, dict[str, int]]]:
    """Divergences per threshold of :data:`SENSITIVITY_DIVERGENCE_M`, ``P_D`` and algorithm,
    from the runs' per-target errors (the same runs under other divergence rules)."""
    out: dict[str, dict[str, dict[str, int]]] = {}
    w = params.divergence_window
    for dm in SENSITIVITY_DIVERGENCE_M:
        per_pd: dict[str, dict[str, int]] = {}
        for pd in params.pd_values:
            key = f"{pd:g}"
            per_pd[key] = {
                alg: sum(
                    bool(r[key][alg]["failed"])
                    or bool(np.any(np.mean(r[key][alg]["pos_err_per_target_m"][-w:], 0) > dm))
                    for r in runs
                )
                for alg in params.algorithms
            }
        out[f"{dm:g}"] = per_pd
    return out


def _truth(params: SdCmsjpdaParams) -> FloatArray:
    motion = constant_velocity(2, params.accel_sigma_mps2**2)
    x0 = np.array([params.x1, params.x2], dtype=float)
    return simulate_truth(motion, x0, params.n_steps, params.dt_s)


def clutter_description(params: SdCmsjpdaParams) -> str:
    """One sentence: the clutter reading of ``params`` (for the tables and results)."""
    m, c = params.clutter_rate, params.clutter_halfwidth_sigma
    if params.clutter_model == "gate":
        return (
            f"{m:g} false measurements expected in each validation gate (eq. 26's m): density "
            f"m / (pi gamma |R_s|^1/2) of sensor s, uniform over the union of the boxes "
            f"+-{c:g} sigma_r x +-{c:g} sigma_theta around the targets' true measurements"
        )
    if params.clutter_model == "box":
        return (
            f"Poisson({m:g}) false measurements per sensor and scan, each uniform in the box "
            f"+-{c:g} sigma_r x +-{c:g} sigma_theta around a randomly chosen target's true "
            "measurement"
        )
    return (
        f"Poisson({m:g}) false measurements per sensor and scan, uniform over ranges 0 to the "
        f"largest true range + {c:g} sigma_r and all bearings"
    )


def tables_markdown(results: dict[str, Any]) -> str:
    """Table 1 (divergences, with the paper's), RMS errors and ms per step."""
    by_pd = results["by_pd"]
    pds = list(by_pd)
    lines = [
        "# Paper 3 reproduction: SD-CMSJPDA vs sequential / parallel MSJPDA, S-D GNN",
        "",
        f"Runs: {results['runs']}. Divergence rule: {results['divergence_rule']}.",
        f"Clutter: {results['clutter_region']}.",
        "",
        "## Table 1: divergences (paper's values in brackets)",
        "",
        "| algorithm | " + " | ".join(f"Pd = {p}" for p in pds) + " |",
        "|---|" + "---|" * len(pds),
    ]
    algs = list(by_pd[pds[0]])
    for alg in algs:
        cells = []
        for p in pds:
            c = f"{by_pd[p][alg]['diverged']}/{by_pd[p][alg]['runs']}"
            if alg in PAPER_TABLE1:
                c += f" [{PAPER_TABLE1[alg][p]}/50]"
            cells.append(c)
        lines.append(f"| {alg} | " + " | ".join(cells) + " |")
    lines += [
        "",
        "## Mean RMS error over steps (converged runs): position m / velocity m/s",
        "",
        "| algorithm | " + " | ".join(f"Pd = {p}" for p in pds) + " | ms per step |",
        "|---|" + "---|" * (len(pds) + 1),
    ]
    for alg in algs:
        cells = [
            f"{by_pd[p][alg]['rms_pos_m']:.1f} / {by_pd[p][alg]['rms_vel_mps']:.1f}" for p in pds
        ]
        ms = np.mean([by_pd[p][alg]["ms_per_step"] for p in pds])
        paper = PAPER_MS_PER_STEP.get(alg)
        cells.append(f"{ms:.2f}" + (f" [paper {paper}]" if paper else ""))
        lines.append(f"| {alg} | " + " | ".join(cells) + " |")
    if set(PAPER_MS_PER_STEP) <= set(algs):
        seq, sd = (np.mean([by_pd[p][a]["ms_per_step"] for p in pds]) for a in PAPER_MS_PER_STEP)
        paper_ratio = PAPER_MS_PER_STEP["sdcmsjpda"] / PAPER_MS_PER_STEP["sequential"]
        lines += [
            "",
            f"Time per step, sdcmsjpda / sequential: {sd / seq:.2f} [paper {paper_ratio:.2f}].",
        ]
    lines += [
        "",
        "## Sensitivity to the divergence threshold (same runs): divergences per Pd",
        "",
        "| algorithm | " + " | ".join(f"{d} m" for d in results["diverged_by_threshold"]) + " |",
        "|---|" + "---|" * len(results["diverged_by_threshold"]),
    ]
    for alg in algs:
        cells = [
            " / ".join(str(per[p][alg]) for p in pds)
            for per in results["diverged_by_threshold"].values()
        ]
        lines.append(f"| {alg} | " + " | ".join(cells) + " |")
    lines += ["", "## What each algorithm implements", ""]
    lines += [f"- `{a}`: {results['algorithm_equations'][a]}" for a in algs]
    return "\n".join(lines) + "\n"


def write_figures(outcome: Outcome[SdCmsjpdaParams, _RunResult], out_dir: Path) -> list[Path]:
    """Figs. 1-6: RMS position and velocity error per step, one pair per ``P_D``."""
    from navtrack.plots.canvas import figure_dir, new_figure, save_figure

    d = figure_dir(out_dir)
    paths = []
    n = 1
    for p, per in outcome.results["by_pd"].items():
        for what, unit in (("pos", "m"), ("vel", "m/s")):
            fig = new_figure((6.4, 3.8))
            ax = fig.add_subplot()
            for alg in per:
                key = f"rms_{what}_per_step_{'m' if what == 'pos' else 'mps'}"
                y = np.asarray(per[alg][key], dtype=float)
                ax.plot(np.arange(1, y.size + 1), y, label=f"{alg} ({per[alg]['diverged']} div.)")
            ax.set_xlabel("step")
            ax.set_ylabel(f"RMS {'position' if what == 'pos' else 'velocity'} error, {unit}")
            ax.set_title(f"Fig. {n}: P_D = {p}")
            ax.legend(fontsize=8)
            paths.append(save_figure(fig, d / f"fig{n}_rms_{what}_pd{p}.png"))
            n += 1
    paths.append(_post_crossing_figure(outcome.results, d))
    return paths


def _post_crossing_figure(results: dict[str, Any], d: Path) -> Path:
    """Sequential MSJPDA's mean position error over :data:`POST_CROSSING_STEPS` of every
    converged run and target, sorted, one curve per ``P_D``: whether a few runs whose tracks
    coalesced or swapped (still under the divergence rule) carry the RMS."""
    from navtrack.plots.canvas import new_figure, save_figure

    fig = new_figure((6.4, 3.8))
    ax = fig.add_subplot()
    for p, per in results["by_pd"].items():
        err = np.sort(np.ravel(per["sequential"]["post_crossing_err_per_run_m"]))[::-1]
        ax.semilogy(np.arange(1, err.size + 1), err, marker=".", label=f"P_D = {p}")
    a, b = POST_CROSSING_STEPS
    ax.set_xlabel("run x target, by decreasing error")
    ax.set_ylabel(f"mean position error, steps {a}-{b}, m")
    ax.set_title("Sequential MSJPDA after the crossing (converged runs)")
    ax.legend(fontsize=8)
    return save_figure(fig, d / "sequential_post_crossing.png")


def summary_lines(results: dict[str, Any]) -> list[str]:
    """Console lines: divergences and mean RMS position per P_D and algorithm."""
    out = []
    for p, per in results["by_pd"].items():
        cells = ", ".join(
            f"{alg} {v['diverged']} div / {v['rms_pos_m']:.0f} m / {v['ms_per_step']:.2f} ms"
            for alg, v in per.items()
        )
        out.append(f"Pd {p}: {cells}")
    return out


class SdCmsjpdaExperiment(Experiment[SdCmsjpdaParams, _RunResult]):
    """Paper 3: three range-bearing sensors, two crossing targets, five fusion trackers."""

    name = "sdcmsjpda"
    description = "Paper 3: SD-CMSJPDA vs sequential/parallel MSJPDA and S-D GNN (Zhang et al.)"
    params_type = SdCmsjpdaParams
    default_runs = 50

    def run_one(self, params: SdCmsjpdaParams, rng: np.random.Generator) -> _RunResult:
        return paper3_run(params, rng)

    def summarize(self, params: SdCmsjpdaParams, runs: Sequence[_RunResult]) -> dict[str, Any]:
        return summarize_runs(params, runs)

    def tables(self, results: dict[str, Any]) -> str:
        return tables_markdown(results)

    def figures(self, outcome: Outcome[SdCmsjpdaParams, _RunResult], out_dir: Path) -> list[Path]:
        return write_figures(outcome, out_dir)

    def summary_lines(self, results: dict[str, Any]) -> list[str]:
        return summary_lines(results)


#: The registered instance (``navtrack.experiments.EXPERIMENTS["sdcmsjpda"]``).
EXPERIMENT = SdCmsjpdaExperiment()
