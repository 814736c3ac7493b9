"""Reproduction of paper 2 (Gu et al. 2019): RAIM by fuzzy clustering analysis.

``navtrack reproduce raim-fcm --out DIR`` runs :data:`EXPERIMENT`:

* :mod:`~navtrack.experiments.raim_fcm.example` — the paper's numeric example (section 5);
* :mod:`~navtrack.experiments.raim_fcm.study` — fault injection on the shared real data,
  :class:`RaimFcmParams`;
* :mod:`~navtrack.experiments.raim_fcm.experiment` — the
  :class:`~navtrack.experiments.Experiment`, tables, console lines, clean-data protection
  levels.
"""

from __future__ import annotations

from navtrack.experiments.raim_fcm.example import paper_example
from navtrack.experiments.raim_fcm.experiment import (
    EXPERIMENT,
    RaimFcmExperiment,
    clean_protection,
    summary_lines,
    tables_markdown,
)
from navtrack.experiments.raim_fcm.study import (
    STATIONS,
    RaimFcmParams,
    injection_run,
    station_data,
    summarize_study,
)

__all__ = [
    "EXPERIMENT",
    "STATIONS",
    "RaimFcmExperiment",
    "RaimFcmParams",
    "clean_protection",
    "injection_run",
    "paper_example",
    "station_data",
    "summarize_study",
    "summary_lines",
    "tables_markdown",
]
