"""Reproduction of paper 6 (ALHAT field test 1): attitude and trajectory reconstruction.

``navtrack reproduce alhat --out DIR`` runs :data:`EXPERIMENT`:

* :mod:`~navtrack.experiments.alhat.params` — :class:`AlhatParams`;
* :mod:`~navtrack.experiments.alhat.synthetic` — seeded RANSAC-SVD scenes (Monte Carlo runs);
* :mod:`~navtrack.experiments.alhat.regime` — the paper's regime: one simulated recording per
  run (BROAD motion, LN-200-class gyro, narrow camera, GNSS, flash LIDAR);
* :mod:`~navtrack.experiments.alhat.real` — BROAD trials with their own MEMS gyro;
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
from navtrack.experiments.alhat.regime import regime_run, summarize_regime
from navtrack.experiments.alhat.synthetic import ransac_scene, summarize_scenes

__all__ = [
    "EXPERIMENT",
    "AlhatExperiment",
    "AlhatParams",
    "TrialOutcome",
    "optical_rate_lag_s",
    "ransac_scene",
    "regime_run",
    "series_accuracy",
    "summarize_regime",
    "summarize_scenes",
    "trial_study",
]
