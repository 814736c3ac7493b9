"""Reproduction of paper 4 (Xi & Morrell): foveal sensor control and the JMPD particle filter.

``navtrack reproduce foveal --out DIR`` runs :data:`EXPERIMENT`:

* :mod:`~navtrack.experiments.foveal.scenario` — the closed loop (truth, control, scan, filter);
* :mod:`~navtrack.experiments.foveal.study` — parameters, one run of every configuration, the
  summary (Tables 3-5, ASE arrays);
* :mod:`~navtrack.experiments.foveal.gains` — the gain rules against the one-scan optimum;
* :mod:`~navtrack.experiments.foveal.tables`, :mod:`~navtrack.experiments.foveal.figures`.
"""

from __future__ import annotations

from navtrack.experiments.foveal.experiment import EXPERIMENT, FovealExperiment
from navtrack.experiments.foveal.gains import gain_check
from navtrack.experiments.foveal.scenario import (
    FovealTrack,
    converged,
    simulate_truth,
    track_foveal,
)
from navtrack.experiments.foveal.study import (
    FovealParams,
    assigned_errors,
    foveal_run,
    summarize_foveal,
    wilson_interval,
)
from navtrack.experiments.foveal.tables import PAPER_TABLES, summary_lines, tables_markdown

__all__ = [
    "EXPERIMENT",
    "PAPER_TABLES",
    "FovealExperiment",
    "FovealParams",
    "FovealTrack",
    "assigned_errors",
    "converged",
    "foveal_run",
    "gain_check",
    "simulate_truth",
    "summarize_foveal",
    "summary_lines",
    "tables_markdown",
    "track_foveal",
    "wilson_interval",
]
