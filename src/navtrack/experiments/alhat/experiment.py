"""``navtrack reproduce alhat``: paper 6 (ALHAT trajectory reconstruction) on the contract.

1. Monte Carlo runs: each run simulates one recording in the paper's regime (BROAD motion, an
   LN-200-class gyro at 400 Hz, a narrow camera on a patch of surveyed targets, GNSS, a flash
   LIDAR; :func:`~navtrack.experiments.alhat.regime.regime_run`) and runs the paper's method
   on it (eqs. 3, 5-11), plus one seeded RANSAC-SVD scene with 20 % outliers
   (:func:`~navtrack.experiments.alhat.synthetic.ransac_scene`);
2. the ``extra`` step: the extensions (calibration, filter, smoother) on one regime recording,
   and every BROAD trial of the parameters with its own real MEMS gyro
   (:func:`~navtrack.experiments.alhat.real.trial_study`), each with its own generator;
3. tables, console lines and the attitude-error figures.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from navtrack.attitude.reconstruct import ESTIMATES
from navtrack.experiments.alhat.figures import write_error_figures, write_fig16
from navtrack.experiments.alhat.params import AlhatParams
from navtrack.experiments.alhat.real import TrialOutcome, trial_study
from navtrack.experiments.alhat.regime import regime_run, summarize_regime
from navtrack.experiments.alhat.synthetic import ransac_scene, summarize_scenes
from navtrack.experiments.alhat.tables import PAPER_VALUES, summary_lines, tables_markdown
from navtrack.experiments.contract import (
    Experiment,
    ExperimentContext,
    ExtraResult,
    Outcome,
    shared_data_dir,
)

__all__ = ["EXPERIMENT", "AlhatExperiment"]

_RunResult = dict[str, Any]


def _broad_dir() -> Path:
    return shared_data_dir() / "trajectory" / "broad"


class AlhatExperiment(Experiment[AlhatParams, _RunResult]):
    """The paper's regime (LN-200, narrow camera, LIDAR) per run; extensions and BROAD's real
    MEMS gyro in the extra step."""

    name = "alhat"
    description = (
        "Paper 6: attitude reconstruction from gyro and camera fixes (ALHAT) in the paper's "
        "regime (LN-200, narrow camera, LIDAR check), with extensions and BROAD's MEMS gyro"
    )
    params_type = AlhatParams
    default_runs = 20

    def run_one(self, params: AlhatParams, rng: np.random.Generator) -> _RunResult:
        scene_rng, regime_rng = rng.spawn(2)
        broad = _broad_dir()
        out: _RunResult = {"ransac": ransac_scene(params, scene_rng)}
        if (broad / f"{params.regime_trial}.mat").exists():
            out["regime"] = regime_run(params, broad, regime_rng)
        else:
            out["regime"] = {"status": "no_truth_motion"}
        return out

    def summarize(self, params: AlhatParams, runs: Sequence[_RunResult]) -> dict[str, Any]:
        return {
            "paper": "ALHAT flash-LIDAR field test 1, trajectory reconstruction (paper 6)",
            "paper_values": PAPER_VALUES,
            "ransac": summarize_scenes(params, [r["ransac"] for r in runs]),
            "regime": summarize_regime(params, [r["regime"] for r in runs]),
        }

    def extra(self, params: AlhatParams, context: ExperimentContext) -> ExtraResult:
        broad = context.shared_data() / "trajectory" / "broad"
        ext_rng, *trial_rngs = context.rng.spawn(len(params.trials) + 1)
        results: dict[str, Any] = {}
        if params.extensions and (broad / f"{params.regime_trial}.mat").exists():
            results["regime_extensions"] = regime_run(params, broad, ext_rng, extensions=True)
        trials: dict[str, Any] = {}
        skipped: list[str] = []
        outcomes: list[TrialOutcome] = []
        for name, child in zip(params.trials, trial_rngs, strict=True):
            mat = broad / f"{name}.mat"
            if not mat.exists():
                skipped.append(f"{mat} absent")
                continue
            res, outcome, _ = trial_study(mat, params, child)
            trials[name] = res
            outcomes.append(outcome)
        results["trials"] = trials
        results["trials_skipped"] = skipped
        if trials:
            name = next(iter(trials))
            results["primary_trial"] = name
            for key in ESTIMATES:
                results[key] = trials[name][key]
        return ExtraResult(results, outcomes)

    def tables(self, results: dict[str, Any]) -> str:
        return tables_markdown(results)

    def figures(self, outcome: Outcome[AlhatParams, _RunResult], out_dir: Path) -> list[Path]:
        paths = write_error_figures(out_dir, outcome.artifacts or [])
        fig16 = write_fig16(out_dir, outcome.runs[0]["regime"]) if outcome.runs else None
        return [fig16, *paths] if fig16 else paths

    def summary_lines(self, results: dict[str, Any]) -> list[str]:
        return summary_lines(results)


#: The registered instance (``navtrack.experiments.EXPERIMENTS["alhat"]``).
EXPERIMENT = AlhatExperiment()
