"""``navtrack reproduce ari``: paper 5 (Lindenberger) on the experiment contract.

1. Monte Carlo runs of :func:`~navtrack.experiments.ari.synthetic.synthetic_run`, summarized by
   :func:`~navtrack.experiments.ari.synthetic.summarize_synthetic`;
2. the ``extra`` step: the real data catalogue (:mod:`navtrack.experiments.ari.real`) plus the
   user's ``--input`` solution tables, the series in the paper's own regimes (carrier-phase
   strips, :mod:`navtrack.experiments.ari.carrier`; navigation-grade INS attitude,
   :mod:`navtrack.experiments.ari.ins`), a truth for every printed column
   (:func:`navtrack.experiments.ari.truths.printed_truths`), then the SARIMAX cross-check
   (:mod:`navtrack.experiments.ari.sarimax`) with the step's own generator;
3. tables and console lines (:mod:`navtrack.experiments.ari.tables`), figures
   (:func:`navtrack.plots.ari.write_reproduction_figures`).
"""

from __future__ import annotations

import importlib.util
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from navtrack.experiments.ari.broad import broad_series
from navtrack.experiments.ari.carrier import carrier_rows, carrier_sources
from navtrack.experiments.ari.ins import INS_DESCRIPTION, ins_rows, ins_series
from navtrack.experiments.ari.real import (
    RealSeries,
    default_real_sources,
    real_data_rows,
    solution_series,
    spp_comparison,
    table2_rows,
)
from navtrack.experiments.ari.sarimax import sarimax_comparisons
from navtrack.experiments.ari.synthetic import (
    AriExperimentParams,
    summarize_synthetic,
    synthetic_run,
)
from navtrack.experiments.ari.tables import PAPER_TABLES, summary_lines, tables_markdown
from navtrack.experiments.ari.truths import printed_truths
from navtrack.experiments.contract import Experiment, ExperimentContext, ExtraResult, Outcome
from navtrack.plots import ari as ari_plots
from navtrack.plots.canvas import save_figure
from navtrack.smoothing.ari import AriConfig

__all__ = ["EXPERIMENT", "AriExperiment"]

_RunResult = dict[str, Any]


class AriExperiment(Experiment[AriExperimentParams, _RunResult]):
    """ARI(p,d) filtering, variance components and gross errors: synthetic truths, real series,
    statsmodels cross-check."""

    name = "ari"
    description = "Paper 5: ARI(p,d) filtering, variance components and gross errors (Lindenberger)"
    params_type = AriExperimentParams
    default_runs = 20

    def run_one(self, params: AriExperimentParams, rng: np.random.Generator) -> _RunResult:
        return synthetic_run(params, rng)

    def summarize(self, params: AriExperimentParams, runs: Sequence[_RunResult]) -> dict[str, Any]:
        return {
            "paper": "Lindenberger, Modelling orientation parameters of sensor platforms (paper 5)",
            "synthetic": summarize_synthetic(params, runs),
            "paper_tables": PAPER_TABLES,
        }

    def extra(self, params: AriExperimentParams, context: ExperimentContext) -> ExtraResult:
        """Fit the real series (shared data when ``params.real_data``, then ``context.inputs``)
        and cross-check against SARIMAX; artifacts: ``(sources, fits)`` for the figures."""
        sources: list[RealSeries] = []
        skipped: list[str] = []
        if params.real_data:
            sources, skipped = default_real_sources(
                context.shared_data(), attitude_form=params.attitude_form
            )
        sources += [solution_series(Path(path)) for path in context.inputs]
        strips: list[dict[str, Any]] = []
        config = AriConfig(min_d=1, select_n=10000, robust_process=params.robust_process)
        rows, fits = real_data_rows(
            sources, config, track=context.track, workers=context.workers, strips=strips
        )
        # the attitude series in the paper's Euler form too, exact estimator only: the flags
        # before (Euler) and after (rotation-vector path) the change of representation
        euler = [
            broad_series(Path(src.meta["path"]), decimate=src.meta["decimate"], form="euler")
            for src in sources
            if src.meta.get("form") == "rotvec"
        ]
        euler_rows, _ = real_data_rows(
            euler, config, track=context.track, workers=context.workers, further=False
        )
        results = {
            "real": rows,
            "attitude_euler": euler_rows,
            "real_skipped": skipped,
            "spp_comparison": spp_comparison(rows),
            "table2": table2_rows(rows),
            "strips": strips,
            "sarimax": sarimax_comparisons(context.rng, params.cases, sources, fits),
        }
        if params.carrier_phase:
            carrier, carrier_skipped = carrier_sources(context.shared_data() / "gnss")
            results["carrier"] = carrier_rows(
                carrier, params.carrier_strip_epochs, params.robust_process
            )
            results["carrier_skipped"] = carrier_skipped
        if params.ins:
            path = context.shared_data() / "trajectory" / "pyins_gnss" / "gnss.csv"
            if path.exists():
                # a child of the step's generator: the SARIMAX draws stay as they were
                series = ins_series(path, context.rng.spawn(1)[0])
                results["ins"] = {
                    "description": INS_DESCRIPTION,
                    "rows": ins_rows(series, params.robust_process),
                }
            else:
                results["ins_skipped"] = f"{path} absent"
        if params.printed_truths:
            results["printed_truths"] = printed_truths()
        if importlib.util.find_spec("statsmodels") is None:
            results["sarimax_skipped"] = (
                "statsmodels is not installed: the SARIMAX cross-check was skipped "
                "(pip install statsmodels, or the 'test' extra)"
            )
        return ExtraResult(results, (sources, fits))

    def tables(self, results: dict[str, Any]) -> str:
        return tables_markdown(results)

    def figures(
        self, outcome: Outcome[AriExperimentParams, _RunResult], out_dir: Path
    ) -> Iterator[Path]:
        sources, fits = outcome.artifacts
        yield from ari_plots.write_reproduction_figures(
            out_dir, outcome.runs, outcome.params.cases, sources, fits
        )
        regime = ari_plots.regime_figure(outcome.results)
        if regime is not None:
            yield save_figure(regime, out_dir / "paper_regimes_sigma_n.png")

    def summary_lines(self, results: dict[str, Any]) -> list[str]:
        return summary_lines(results)


#: The registered instance (``navtrack.experiments.EXPERIMENTS["ari"]``).
EXPERIMENT = AriExperiment()
