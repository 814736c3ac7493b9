"""Reproduction of paper 3 (Zhang, Xiong & He, ICMLC 2005): S-D assignment CMSJPDA.

``navtrack reproduce sdcmsjpda --out DIR`` runs :data:`EXPERIMENT`:

* :mod:`~navtrack.experiments.sdcmsjpda.scenario` — parameters, sensors, detections and clutter,
  one Monte Carlo run of the five fusion trackers of :mod:`navtrack.tracking.trackers.multisensor`;
* :mod:`~navtrack.experiments.sdcmsjpda.experiment` — summary (Table 1, Figs. 1-6), tables,
  figures and the :class:`~navtrack.experiments.Experiment`.
"""

from __future__ import annotations

from navtrack.experiments.sdcmsjpda.experiment import (
    EXPERIMENT,
    PAPER_TABLE1,
    SdCmsjpdaExperiment,
    summarize_runs,
)
from navtrack.experiments.sdcmsjpda.scenario import (
    SdCmsjpdaParams,
    clutter_density,
    paper3_run,
    sensors,
    simulate_scans,
)

__all__ = [
    "EXPERIMENT",
    "PAPER_TABLE1",
    "SdCmsjpdaExperiment",
    "SdCmsjpdaParams",
    "clutter_density",
    "paper3_run",
    "sensors",
    "simulate_scans",
    "summarize_runs",
]
