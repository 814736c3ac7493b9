"""Reproduction of paper 5 (Lindenberger): ARI modelling of orientation parameters.

``navtrack reproduce ari --out DIR`` runs :data:`EXPERIMENT`, split along the study's seams:

* :mod:`~navtrack.experiments.ari.synthetic` — the Monte Carlo on series like the paper's
  applications with known truth, and the parameters :class:`AriExperimentParams`;
* :mod:`~navtrack.experiments.ari.real` — the real data catalogue (BROAD orientation, pyins
  track, RTKLIB and navtrack SPP series, solution tables) and its fits;
* :mod:`~navtrack.experiments.ari.broad` — BROAD orientation as series (rotation-vector path
  or Euler angles) and the causes that explain gross-error flags on it;
* :mod:`~navtrack.experiments.ari.sarimax` — the statsmodels SARIMAX cross-check;
* :mod:`~navtrack.experiments.ari.tables` — tables, console lines, the paper's published values;
* :mod:`~navtrack.experiments.ari.experiment` — the :class:`~navtrack.experiments.Experiment`.
"""

from __future__ import annotations

from navtrack.experiments.ari.broad import FLAG_CAUSES, broad_series, flag_causes
from navtrack.experiments.ari.experiment import EXPERIMENT, AriExperiment
from navtrack.experiments.ari.real import (
    SPP_RUNS,
    RealSeries,
    SppRun,
    default_real_sources,
    pyins_series,
    real_data_rows,
    solution_series,
    spp_comparison,
    spp_series,
)
from navtrack.experiments.ari.sarimax import (
    SARIMAX_SPP_SOURCES,
    sarimax_compare,
    sarimax_comparisons,
)
from navtrack.experiments.ari.synthetic import (
    IDENTIFIABLE_CRB,
    SYNTHETIC_CASES,
    AriExperimentParams,
    SyntheticCase,
    run_index,
    summarize_synthetic,
    synthetic_run,
)
from navtrack.experiments.ari.tables import PAPER_TABLES, summary_lines, tables_markdown

__all__ = [
    "EXPERIMENT",
    "FLAG_CAUSES",
    "IDENTIFIABLE_CRB",
    "PAPER_TABLES",
    "SARIMAX_SPP_SOURCES",
    "SPP_RUNS",
    "SYNTHETIC_CASES",
    "AriExperiment",
    "AriExperimentParams",
    "RealSeries",
    "SppRun",
    "SyntheticCase",
    "broad_series",
    "default_real_sources",
    "flag_causes",
    "pyins_series",
    "real_data_rows",
    "run_index",
    "sarimax_compare",
    "sarimax_comparisons",
    "solution_series",
    "spp_comparison",
    "spp_series",
    "summarize_synthetic",
    "summary_lines",
    "synthetic_run",
    "tables_markdown",
]
