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

from navtrack._numba import HAVE_NUMBA
from navtrack._typing import FloatArray
from navtrack.experiments.contract import Experiment, ExperimentContext, ExtraResult, Outcome
from navtrack.experiments.sdcmsjpda.scenario import SdCmsjpdaParams, clutter_density, paper3_run
from navtrack.experiments.sdcmsjpda.sensitivity import compact, run_readings, sensitivity_markdown
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
        "post_crossing_worst": _post_crossing_worst(params, runs),
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


def _post_crossing_worst(
    params: SdCmsjpdaParams, runs: Sequence[_RunResult]
) -> dict[str, dict[str, dict[str, float]]]:
    """Per ``P_D`` and algorithm, over the converged runs: the run and target of the largest
    RMS position error over :data:`POST_CROSSING_STEPS` (``run``, ``target``, ``rms_m``) and
    the RMS over those steps of all converged runs with and without that run
    (``rms_all_m``, ``rms_without_m``): whether one run carries the post-crossing RMS."""
    a, b = POST_CROSSING_STEPS
    out: dict[str, dict[str, dict[str, float]]] = {}
    for pd in params.pd_values:
        key = f"{pd:g}"
        out[key] = {}
        for alg in params.algorithms:
            idx = [i for i, r in enumerate(runs) if not r[key][alg]["diverged"]]
            if not idx or params.n_steps < a:
                continue
            err = np.array([runs[i][key][alg]["pos_err_per_target_m"][a - 1 : b] for i in idx])
            per = np.sqrt(np.mean(err**2, axis=1))  # (runs, targets)
            j, t = np.unravel_index(int(np.argmax(per)), per.shape)
            rest = np.delete(err, j, axis=0)
            out[key][alg] = {
                "run": idx[j],
                "target": int(t),
                "rms_m": float(per[j, t]),
                "rms_all_m": float(np.sqrt(np.mean(err**2))),
                "rms_without_m": float(np.sqrt(np.mean(rest**2))) if rest.size else float("nan"),
            }
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
        numba = "with numba" if results["numba"] else "without numba"
        lines += [
            "",
            f"Time per step in these runs ({numba}), sdcmsjpda / sequential: {sd / seq:.2f} "
            f"[paper {paper_ratio:.2f}].",
        ]
    if "timing" in results:
        from navtrack.experiments.sdcmsjpda.timing import ratio_markdown

        t = results["timing"]["this_process"]
        lines += [
            "",
            "## Time per step, SD-CMSJPDA / sequential MSJPDA, with numba and without",
            "",
            f"CPU ms per fusion step, medians over {t['pairs']} scan-set runs per tracker "
            "(the trackers alternate on each scan set); ratio: median of the paired ratios "
            "to sequential on the same scan set. The paper's absolute times are of a 2005 PC; "
            "only its ratio is compared.",
            "",
            *ratio_markdown(results["timing"]),
        ]
    lines += _post_crossing_lines(results)
    if "sensitivity" in results:
        lines += ["", *sensitivity_markdown(results["sensitivity_study"], results["sensitivity"])]
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


def _post_crossing_lines(results: dict[str, Any]) -> list[str]:
    """Sequential MSJPDA's RMS over :data:`POST_CROSSING_STEPS` per ``P_D``, with and without
    its worst converged run."""
    worst = results["post_crossing_worst"]
    if not any("sequential" in per for per in worst.values()):
        return []
    a, b = POST_CROSSING_STEPS
    lines = [
        "",
        f"## Sequential MSJPDA after the crossing (steps {a}-{b}, converged runs)",
        "",
        "| Pd | RMS position m | worst run (target): its RMS m | RMS without that run m |",
        "|---|---|---|---|",
    ]
    for p, per in worst.items():
        if "sequential" in per:
            w = per["sequential"]
            lines.append(
                f"| {p} | {w['rms_all_m']:.0f} | {w['run']} ({w['target']}): {w['rms_m']:.0f} "
                f"| {w['rms_without_m']:.0f} |"
            )
    return lines


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
    if "sequential" in outcome.params.algorithms:
        paths.append(_post_crossing_figure(outcome, d))
    return paths


def _post_crossing_figure(outcome: Outcome[SdCmsjpdaParams, _RunResult], d: Path) -> Path:
    """Sequential MSJPDA after the crossing. Left: the mean position error over
    :data:`POST_CROSSING_STEPS` of every converged run and target, sorted, one curve per
    ``P_D`` (whether a few runs carry the RMS). Right: the error per step of the worst of them
    per ``P_D``, beside the distance between the targets (a track on the other target has an
    error near that distance; a track lost to clutter does not)."""
    from navtrack.plots.canvas import new_figure, save_figure

    results = outcome.results
    fig = new_figure((11.0, 3.8))
    left, right = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    truth = _truth(outcome.params)
    sep = np.hypot(*(truth[:, 0, [0, 2]] - truth[:, 1, [0, 2]]).T)
    steps = np.arange(1, sep.size + 1)
    for p, per in results["by_pd"].items():
        err = np.sort(np.ravel(per["sequential"]["post_crossing_err_per_run_m"]))[::-1]
        left.semilogy(np.arange(1, err.size + 1), err, marker=".", label=f"P_D = {p}")
        w = results["post_crossing_worst"][p].get("sequential")
        if w is not None:
            e = np.asarray(outcome.runs[w["run"]][p]["sequential"]["pos_err_per_target_m"])
            right.plot(steps, e[:, w["target"]], label=f"P_D = {p}: run {w['run']}")
    right.plot(steps, sep, "k--", lw=1, label="distance between the targets")
    a, b = POST_CROSSING_STEPS
    right.axvspan(a, b, color="0.9")
    left.set_xlabel("run x target, by decreasing error")
    left.set_ylabel(f"mean position error, steps {a}-{b}, m")
    left.set_title("Sequential MSJPDA, converged runs")
    right.set_yscale("log")
    right.set_xlabel("step")
    right.set_ylabel("position error, m")
    right.set_title(f"Worst run per P_D over steps {a}-{b}")
    left.legend(fontsize=8)
    right.legend(fontsize=7)
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
        out = summarize_runs(params, runs) | {"numba": HAVE_NUMBA}
        n = min(params.sensitivity_runs, len(runs))
        if n:
            out["sensitivity_study"] = compact(summarize_runs(params, runs[:n]))
        return out

    def extra(self, params: SdCmsjpdaParams, context: ExperimentContext) -> ExtraResult:
        """The sensitivity readings (``sensitivity_runs``) and the timing with and without
        numba (``timing_repeat``)."""
        out: dict[str, Any] = {}
        if params.sensitivity_runs:
            out["sensitivity"] = run_readings(params, context)
        if params.timing_repeat:
            from navtrack.experiments.sdcmsjpda.timing import both_paths  # runs as a module too

            out["timing"] = both_paths(params, repeat=params.timing_repeat)
        return ExtraResult(out)

    def tables(self, results: dict[str, Any]) -> str:
        return tables_markdown(results)

    def figures(self, outcome: Outcome[SdCmsjpdaParams, _RunResult], out_dir: Path) -> list[Path]:
        return write_figures(outcome, out_dir)

    def summary_lines(self, results: dict[str, Any]) -> list[str]:
        return summary_lines(results)


#: The registered instance (``navtrack.experiments.EXPERIMENTS["sdcmsjpda"]``).
EXPERIMENT = SdCmsjpdaExperiment()
