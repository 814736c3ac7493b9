"""``navtrack reproduce foveal``: paper 4 (Xi & Morrell) on the experiment contract.

1. Monte Carlo runs of :func:`~navtrack.experiments.foveal.study.foveal_run` (every
   configuration of Tables 3-5 on one truth per run), summarised by
   :func:`~navtrack.experiments.foveal.study.summarize_foveal`;
2. the ``extra`` step: the gain-rule check (:func:`~navtrack.experiments.foveal.gains.gain_check`);
3. tables (:mod:`~navtrack.experiments.foveal.tables`) and Figs. 1-4
   (:mod:`~navtrack.experiments.foveal.figures`).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from navtrack.experiments.contract import Experiment, ExperimentContext, ExtraResult, Outcome
from navtrack.experiments.foveal.figures import write_figures
from navtrack.experiments.foveal.gains import gain_check
from navtrack.experiments.foveal.study import FovealParams, foveal_run, summarize_foveal
from navtrack.experiments.foveal.tables import PAPER_TABLES, summary_lines, tables_markdown

__all__ = ["EXPERIMENT", "FovealExperiment"]

_RunResult = dict[str, Any]


class FovealExperiment(Experiment[FovealParams, _RunResult]):
    """JMPD particle filter with IP-JPDA / IP-GNN / KP proposals under SO / TO / WO control."""

    name = "foveal"
    description = (
        "Paper 4: foveal sensor control (SO/TO/WO) and JMPD particle filter with "
        "IP-JPDA/IP-GNN/KP proposals (Xi & Morrell), Tables 3-5"
    )
    params_type = FovealParams
    default_runs = 1000

    def run_one(self, params: FovealParams, rng: np.random.Generator) -> _RunResult:
        return foveal_run(params, rng)

    def summarize(self, params: FovealParams, runs: Sequence[_RunResult]) -> dict[str, Any]:
        return {
            "paper": "Xi & Morrell, Tracking multiple closely spaced targets using an adaptive "
            "foveal sensor, ICASSP 2005 (paper 4)",
            **summarize_foveal(params, runs),
            "paper_tables": PAPER_TABLES,
        }

    def extra(self, params: FovealParams, context: ExperimentContext) -> ExtraResult:
        return ExtraResult({"gain_check": gain_check(params.R)} if params.gain_check else {})

    def tables(self, results: dict[str, Any]) -> str:
        return tables_markdown(results)

    def figures(self, outcome: Outcome[FovealParams, _RunResult], out_dir: Path) -> list[Path]:
        return write_figures(outcome.results, list(outcome.runs), out_dir)

    def summary_lines(self, results: dict[str, Any]) -> list[str]:
        return summary_lines(results)


#: The registered instance (``navtrack.experiments.EXPERIMENTS["foveal"]``).
EXPERIMENT = FovealExperiment()
