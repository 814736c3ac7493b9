"""``navtrack reproduce alhat``: paper 6 (ALHAT trajectory reconstruction) on the contract.

1. Monte Carlo runs: seeded RANSAC-SVD scenes with 20 % outliers
   (:func:`~navtrack.experiments.alhat.synthetic.ransac_scene`);
2. the ``extra`` step: every BROAD trial of the parameters that is present
   (:func:`~navtrack.experiments.alhat.real.trial_study`), each with its own generator spawned
   from the step's; the first trial's estimates head ``results.json``; the pose trajectory of
   the first trial's smoother with the pyins GNSS positions (``pose_trajectory.parquet``);
3. tables, console lines and the attitude-error figures.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from navtrack.attitude.reconstruct import ESTIMATES
from navtrack.experiments.alhat.params import AlhatParams
from navtrack.experiments.alhat.real import TrialOutcome, trial_study
from navtrack.experiments.alhat.synthetic import ransac_scene, summarize_scenes
from navtrack.experiments.alhat.tables import PAPER_VALUES, summary_lines, tables_markdown
from navtrack.experiments.contract import Experiment, ExperimentContext, ExtraResult, Outcome

__all__ = ["EXPERIMENT", "AlhatExperiment"]

_RunResult = dict[str, Any]


def _pose_trajectory(recon: Any, shared: Path, out_dir: Path) -> tuple[str | None, str | None]:
    """Write the smoother's pose with the pyins GNSS positions; (path, reason skipped)."""
    from navtrack.attitude.trajectory import pose_frame, read_gnss_positions
    from navtrack.io.solution import write_solution

    gnss_path = shared / "trajectory" / "pyins_gnss" / "gnss.csv"
    if not gnss_path.exists():
        return None, f"{gnss_path} absent"
    gnss = read_gnss_positions(gnss_path)
    est = recon.estimates["smoother"]
    t_cam = recon.t_s - est.time_offset_s
    frame = pose_frame(t_cam, est.quat, gnss, gnss_offset_s=float(gnss.t_s[0] - t_cam[0]))
    try:
        path = write_solution(frame, out_dir / "pose_trajectory.parquet")
    except ImportError as exc:
        return None, str(exc)
    return str(path), None


class AlhatExperiment(Experiment[AlhatParams, _RunResult]):
    """Gyro propagation, RANSAC-SVD camera fixes, correction quaternion, calibration and
    smoother on BROAD."""

    name = "alhat"
    description = (
        "Paper 6: attitude reconstruction from gyro and camera fixes (ALHAT) on BROAD, with "
        "calibration and smoother"
    )
    params_type = AlhatParams
    default_runs = 200

    def run_one(self, params: AlhatParams, rng: np.random.Generator) -> _RunResult:
        return ransac_scene(params, rng)

    def summarize(self, params: AlhatParams, runs: Sequence[_RunResult]) -> dict[str, Any]:
        return {
            "paper": "ALHAT flash-LIDAR field test 1, trajectory reconstruction (paper 6)",
            "paper_values": PAPER_VALUES,
            "ransac": summarize_scenes(params, runs),
        }

    def extra(self, params: AlhatParams, context: ExperimentContext) -> ExtraResult:
        shared = context.shared_data()
        broad = shared / "trajectory" / "broad"
        trials: dict[str, Any] = {}
        skipped: list[str] = []
        outcomes: list[TrialOutcome] = []
        first = None
        for name, child in zip(params.trials, context.rng.spawn(len(params.trials)), strict=True):
            mat = broad / f"{name}.mat"
            if not mat.exists():
                skipped.append(f"{mat} absent")
                continue
            res, outcome, recon = trial_study(mat, params, child)
            trials[name] = res
            outcomes.append(outcome)
            if first is None:
                first = (name, res, recon)
        results: dict[str, Any] = {"trials": trials, "trials_skipped": skipped}
        if first is not None:
            name, res, recon = first
            results["primary_trial"] = name
            for key in ESTIMATES:
                results[key] = res[key]
            if params.pose_gnss:
                path, why = _pose_trajectory(recon, shared, context.out_dir)
                if path:
                    results["pose_trajectory"] = path
                else:
                    results["pose_trajectory_skipped"] = why
        return ExtraResult(results, outcomes)

    def tables(self, results: dict[str, Any]) -> str:
        return tables_markdown(results)

    def figures(self, outcome: Outcome[AlhatParams, _RunResult], out_dir: Path) -> list[Path]:
        from navtrack.experiments.alhat.figures import write_error_figures

        return write_error_figures(out_dir, outcome.artifacts or [])

    def summary_lines(self, results: dict[str, Any]) -> list[str]:
        return summary_lines(results)


#: The registered instance (``navtrack.experiments.EXPERIMENTS["alhat"]``).
EXPERIMENT = AlhatExperiment()
