"""``navtrack reproduce agps``: paper 1 (Li 2010) on the experiment contract.

1. Monte Carlo runs of :func:`~navtrack.experiments.agps.simulation.simulate_fix_set` (one fix
   set per run, solved for every interval, height and solver), summarized per solver, height and
   interval (:func:`~navtrack.experiments.agps.summary.summarize_cases`);
2. the ``extra`` step: the real-data study (:func:`~navtrack.experiments.agps.real.real_data_study`)
   on the shared stations and the Android log, with the step's own generator;
3. tables, console lines and Figs. 2/3 (:mod:`navtrack.experiments.agps.tables`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from navtrack.experiments.agps.calibration import table_i_misfit
from navtrack.experiments.agps.real import real_data_study
from navtrack.experiments.agps.simulation import (
    PAPER_SITE_LLH,
    SOLVER_NAMES,
    AgpsExperimentParams,
    default_nav_path,
    sensitivity_names,
    simulate_fix_set,
    solver_config,
)
from navtrack.experiments.agps.summary import (
    error_statistics,
    findings,
    height_key,
    interval_key,
    summarize_cases,
)
from navtrack.experiments.agps.tables import summary_lines, tables_markdown, write_figures
from navtrack.experiments.contract import Experiment, ExperimentContext, ExtraResult, Outcome

__all__ = ["EXPERIMENT", "AgpsExperiment"]

_RunResult = dict[str, Any]


class AgpsExperiment(Experiment[AgpsExperimentParams, _RunResult]):
    """Two-satellite AGPS fixes: Gauss–Newton vs Marquardt vs MAP, simulated and real."""

    name = "agps"
    description = "Paper 1: two-satellite AGPS positioning, Marquardt vs Gauss–Newton (Li 2010)"
    params_type = AgpsExperimentParams
    default_runs = 300

    def run_one(self, params: AgpsExperimentParams, rng: np.random.Generator) -> _RunResult:
        return simulate_fix_set(params, rng)

    def summarize(self, params: AgpsExperimentParams, runs: Sequence[_RunResult]) -> dict[str, Any]:
        heights = [height_key(h) for h in params.heights_m]
        intervals = [interval_key(i) for i in params.intervals_min]
        shape = (0, len(SOLVER_NAMES), len(intervals), len(heights))

        def stack(key: str) -> np.ndarray:
            return np.stack([r[key] for r in runs]) if runs else np.zeros(shape)

        sim = summarize_cases(
            stack("error_m"), stack("iterations"), stack("status"), SOLVER_NAMES, heights, intervals
        )
        true_h = height_key(min(params.heights_m, key=lambda h: abs(h - params.site_llh[2])))
        sensitivity = {}
        for v, name in enumerate(sensitivity_names(params)):

            def variant(key: str, v: int = v) -> np.ndarray:
                if not runs:
                    return np.zeros((0, 2, 1, len(heights)))
                return np.stack([r[key][v] for r in runs])[:, :, None, :]

            sensitivity[name] = summarize_cases(
                variant("sens_error_m"),
                variant("sens_iterations"),
                variant("sens_status"),
                ("gn", "lm"),
                heights,
                intervals[:1],
            )
        nav = params.nav if params.nav is not None else default_nav_path()
        return {
            "paper": "Li, Two satellites positioning algorithm based on AGPS system with two "
            "clock bias, ICCET 2010 (paper 1)",
            "nav_file": str(nav),
            "calibration": {
                "fitted_on": "Gauss–Newton Table I (66 cells) and Table III",
                "objective": "rms of log(simulated / printed) over Table I's cells",
                "table_i_misfit": table_i_misfit(
                    {h: sim["gn"][h][intervals[0]] for h in heights if h in sim["gn"]}
                ),
                "sigma_noise_m": params.sigma_noise_m,
                "elmask_deg": params.elmask_deg,
                "max_dop": params.max_dop,
                "cell_radius_m": params.cell_radius_m,
            },
            "simulation": sim,
            "findings_simulation": findings(sim, true_h, intervals),
            "sensitivity": sensitivity,
            "simulation_pairs": [list(r["sats"]) for r in runs],
        }

    def extra(self, params: AgpsExperimentParams, context: ExperimentContext) -> ExtraResult:
        """The real-data study on the shared data (skipped, with the reason, when absent)."""
        if not params.real_data:
            return ExtraResult({"real_data": {}, "real_skipped": ["real_data=false"]})
        gnss = context.shared_data() / "gnss"
        offsets = tuple(h - PAPER_SITE_LLH[2] for h in params.heights_m)
        offsets = tuple(round(o) for o in offsets)  # the paper's heights are 56 m +- whole metres
        arrays, skipped = real_data_study(
            gnss,
            context.rng,
            height_offsets_m=tuple(float(o) for o in offsets),
            intervals_min=params.intervals_min,
            fixes=params.real_fixes,
            cell_radius_m=params.cell_radius_m,
            clock_bias_m=params.clock_bias_m,
            config=dataclasses.replace(solver_config(params), max_dop=params.real_max_dop),
            elmask_deg=params.elmask_deg,
        )
        heights = [height_key(float(o), offset=True) for o in offsets]
        intervals = [interval_key(i) for i in params.intervals_min]
        # pooled over the sets with fixes at every interval, so that the intervals compare
        # the same receivers (the phone log and yamatogawa span 3.4 min)
        pooled = [n for n, by in arrays["n_fixes"].items() if all(v > 0 for v in by.values())]
        rows = np.isin(arrays["set"], pooled)
        real = summarize_cases(
            arrays["error_m"][rows], arrays["iterations"][rows], arrays["status"][rows],
            SOLVER_NAMES, heights, intervals,
        )  # fmt: skip
        per_set = {}
        zero = heights.index("+0") if "+0" in heights else 0
        for name in dict.fromkeys(arrays["set"].tolist()):
            rows = arrays["set"] == name
            sub = summarize_cases(
                arrays["error_m"][rows][..., zero : zero + 1],
                arrays["iterations"][rows][..., zero : zero + 1],
                arrays["status"][rows][..., zero : zero + 1],
                SOLVER_NAMES,
                [heights[zero]],
                intervals,
            )
            per_set[name] = {s: sub[s][heights[zero]] for s in SOLVER_NAMES}
            sc_err, sc_it, sc_st = (a[rows] for a in arrays["station_clock"])
            per_set[name]["station_clock"] = {
                s: {
                    i: error_statistics(sc_err[:, j, k], sc_it[:, j, k], sc_st[:, j, k])
                    for k, i in enumerate(intervals)
                }
                for j, s in enumerate(SOLVER_NAMES)
            }
        results = {
            "real_data": real,
            "real_data_pooled_sets": pooled,
            "findings_real_data": findings(real, heights[zero], intervals) if real else {},
            "real_data_sets": per_set,
            "real_n_fixes": arrays["n_fixes"],
            "real_skipped": skipped,
        }
        return ExtraResult(results)

    def tables(self, results: dict[str, Any]) -> str:
        return tables_markdown(results)

    def figures(
        self, outcome: Outcome[AgpsExperimentParams, _RunResult], out_dir: Path
    ) -> list[Path]:
        return write_figures(outcome.results, out_dir)

    def summary_lines(self, results: dict[str, Any]) -> list[str]:
        return summary_lines(results)


#: The registered instance (``navtrack.experiments.EXPERIMENTS["agps"]``).
EXPERIMENT = AgpsExperiment()
