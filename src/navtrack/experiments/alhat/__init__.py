"""Reproduction of paper 6 (ALHAT field test 1): attitude and trajectory reconstruction.

``navtrack reproduce alhat --out DIR`` runs :data:`EXPERIMENT`:

* :mod:`~navtrack.experiments.alhat.params` — :class:`AlhatParams`;
* :mod:`~navtrack.experiments.alhat.synthetic` — seeded RANSAC-SVD scenes (Monte Carlo runs);
* :mod:`~navtrack.experiments.alhat.real` — BROAD trials with simulated camera fixes;
* :mod:`~navtrack.experiments.alhat.tables`, :mod:`~navtrack.experiments.alhat.figures`;
* :mod:`~navtrack.experiments.alhat.experiment` — the :class:`~navtrack.experiments.Experiment`.
"""

from __future__ import annotations

from navtrack.experiments.alhat.experiment import EXPERIMENT, AlhatExperiment
from navtrack.experiments.alhat.params import AlhatParams
from navtrack.experiments.alhat.real import (
    TrialOutcome,
    optical_rate_lag_s,
    series_accuracy,
    trial_study,
)
from navtrack.experiments.alhat.synthetic import ransac_scene, summarize_scenes

__all__ = [
    "EXPERIMENT",
    "AlhatExperiment",
    "AlhatParams",
    "TrialOutcome",
    "optical_rate_lag_s",
    "ransac_scene",
    "series_accuracy",
    "summarize_scenes",
    "trial_study",
]
