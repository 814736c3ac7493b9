"""``navtrack reproduce agps``: paper 1 (Li 2010) on the experiment contract.

1. Monte Carlo runs of :func:`~navtrack.experiments.agps.simulation.simulate_fix_set` (one fix
   set per run, solved for every interval, height and solver), summarized per solver, height and
   interval (:func:`~navtrack.experiments.agps.summary.summarize_cases`);
2. the ``extra`` step: the real-data study (:func:`~navtrack.experiments.agps.real.real_data_study`)
   on the shared stations and the Android log, with the step's own generator;
3. tables, console lines and Figs. 2/3 (:mod:`navtrack.experiments.agps.tables`).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from navtrack.experiments.agps.real import real_data_study
from navtrack.experiments.agps.simulation import (
    PAPER_SITE_LLH,
    SOLVER_NAMES,
    AgpsExperimentParams,
    default_nav_path,
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
        near_shape = (0, len(SOLVER_NAMES), len(intervals))

        def near(key: str) -> np.ndarray:
            arr = np.stack([r[key] for r in runs]) if runs else np.zeros(near_shape)
            return arr[..., None]

        near_cell = summarize_cases(
            near("near_error_m"),
            near("near_iterations"),
            near("near_status"),
            SOLVER_NAMES,
            [true_h],
            intervals,
        )
        nav = params.nav if params.nav is not None else default_nav_path()
        return {
            "paper": "Li, Two satellites positioning algorithm based on AGPS system with two "
            "clock bias, ICCET 2010 (paper 1)",
            "nav_file": str(nav),
            "simulation": sim,
            "findings_simulation": findings(sim, true_h, intervals),
            "simulation_near_cell": near_cell,
            "findings_near_cell": findings(near_cell, true_h, intervals),
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
            base_distance_m=params.base_distance_m,
            config=solver_config(params),
            elmask_deg=params.elmask_deg,
        )
        heights = [height_key(float(o), offset=True) for o in offsets]
        intervals = [interval_key(i) for i in params.intervals_min]
        real = summarize_cases(
            arrays["error_m"], arrays["iterations"], arrays["status"], SOLVER_NAMES, heights,
            intervals,
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
            cc_err, cc_it, cc_st = (a[rows] for a in arrays["lm_cell_clock"])
            per_set[name]["lm_cell_clock"] = {
                i: error_statistics(cc_err[:, k], cc_it[:, k], cc_st[:, k])
                for k, i in enumerate(intervals)
            }
        results = {
            "real_data": real,
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
