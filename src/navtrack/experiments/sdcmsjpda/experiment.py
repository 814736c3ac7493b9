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
from navtrack.experiments.contract import Experiment, ExperimentContext, ExtraResult, Outcome
from navtrack.experiments.sdcmsjpda.scenario import SdCmsjpdaParams, paper3_run
from navtrack.experiments.sdcmsjpda.sensitivity import compact, run_readings, sensitivity_markdown
from navtrack.experiments.sdcmsjpda.summary import (
    PAPER_MS_PER_STEP,
    PAPER_TABLE1,
    POST_CROSSING_STEPS,
    summarize_runs,
    truth_states,
)
from navtrack.experiments.sdcmsjpda.timing import both_paths, ratio_markdown
from navtrack.plots.canvas import figure_dir, new_figure, save_figure

__all__ = ["EXPERIMENT", "PAPER_TABLE1", "SdCmsjpdaExperiment", "summarize_runs"]

_RunResult = dict[str, Any]


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
    results = outcome.results
    fig = new_figure((11.0, 3.8))
    left, right = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    truth = truth_states(outcome.params)
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
