"""Reproduction of paper 1 (Li 2010): two-satellite AGPS positioning with two clock biases.

``navtrack reproduce agps --out DIR`` runs :data:`EXPERIMENT`, split along the study's seams:

* :mod:`~navtrack.experiments.agps.simulation` — the Monte Carlo at the paper's site with real
  broadcast ephemerides and the documented error model, and :class:`AgpsExperimentParams`;
* :mod:`~navtrack.experiments.agps.real` — the real-data study on the shared data sets;
* :mod:`~navtrack.experiments.agps.summary` — percentiles, means, iterations, the findings and
  the paper's published values;
* :mod:`~navtrack.experiments.agps.tables` — Tables I–III, Figs. 2/3, console lines;
* :mod:`~navtrack.experiments.agps.experiment` — the :class:`~navtrack.experiments.Experiment`.
"""

from __future__ import annotations

from navtrack.experiments.agps.experiment import EXPERIMENT, AgpsExperiment
from navtrack.experiments.agps.real import REAL_DATA_SETS, RealDataSet, real_data_study
from navtrack.experiments.agps.simulation import (
    PAPER_HEIGHTS_M,
    PAPER_INTERVALS_MIN,
    PAPER_SITE_LLH,
    AgpsExperimentParams,
    default_nav_path,
    simulate_fix_set,
)
from navtrack.experiments.agps.summary import (
    PAPER_MEAN_ITERATIONS,
    PAPER_TABLE_I_MEAN_M,
    PAPER_TABLE_II_MEAN_M,
    error_statistics,
    findings,
    summarize_cases,
)
from navtrack.experiments.agps.tables import summary_lines, tables_markdown, write_figures

__all__ = [
    "EXPERIMENT",
    "PAPER_HEIGHTS_M",
    "PAPER_INTERVALS_MIN",
    "PAPER_MEAN_ITERATIONS",
    "PAPER_SITE_LLH",
    "PAPER_TABLE_II_MEAN_M",
    "PAPER_TABLE_I_MEAN_M",
    "REAL_DATA_SETS",
    "AgpsExperiment",
    "AgpsExperimentParams",
    "RealDataSet",
    "default_nav_path",
    "error_statistics",
    "findings",
    "real_data_study",
    "simulate_fix_set",
    "summarize_cases",
    "summary_lines",
    "tables_markdown",
    "write_figures",
]
