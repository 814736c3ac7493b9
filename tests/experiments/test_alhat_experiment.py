"""``navtrack reproduce alhat``: the paper's regime (LN-200, narrow camera, LIDAR) on BROAD
trial 02's motion, and the shortened BROAD trial 07 with its own MEMS gyro (the full run is the
CLI's)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from navtrack.cli import main
from navtrack.experiments import ReproduceOptions, get_experiment, reproduce
from navtrack.experiments import alhat as exp
from navtrack.experiments.runner import run_generator


def test_registered_experiment_is_alhat() -> None:
    assert get_experiment("alhat") is exp.EXPERIMENT
    assert exp.EXPERIMENT.default_params() == exp.AlhatParams()
    assert exp.AlhatParams().trials[0].startswith("07")


def test_ransac_scenes_reject_every_outlier() -> None:
    params = exp.AlhatParams()
    runs = [exp.ransac_scene(params, run_generator(3, i)) for i in range(20)]
    s = exp.summarize_scenes(params, runs)
    assert s["all_outliers_rejected"] == 20
    assert s["outliers_accepted"] == 0
    assert s["from_oracle_max_rad"] < 1e-6  # refit on the true inliers = the oracle
    assert s["error_mean_rad"] < 2 * params.ray_sigma_rad


def test_reproduction_on_broad_trial_07(shared_data: Path, tmp_path: Path) -> None:
    """60 s of trial 07 (movement from 26.5 s): the bars' ordering of the four estimates."""
    params = exp.AlhatParams(trials=(exp.AlhatParams().trials[0],), duration_s=60.0)
    out = tmp_path / "alhat"
    res = reproduce("alhat", ReproduceOptions(out, runs=3, params=params, progress=False))
    saved = json.loads((out / "results.json").read_text())
    for key in ("propagation", "paper_correction", "calibrated", "smoother"):
        assert set(saved[key]) >= {"mean_deg", "max_deg"}
    assert saved["paper_correction"]["mean_deg"] < saved["propagation"]["mean_deg"]
    assert saved["calibrated"]["mean_deg"] < saved["paper_correction"]["mean_deg"]
    assert saved["smoother"]["mean_deg"] < saved["calibrated"]["mean_deg"]
    trial = saved["trials"][params.trials[0]]
    assert trial["fixes"]["outliers_accepted"] == 0
    assert trial["fixes"]["outlier_rays"] > 0
    assert trial["series"]["order3_max_rad"] <= trial["series"]["order3_bound_rad"]
    # the calibrated timing offset agrees with the gyro/optical rate lag (independent)
    check = trial["timing_offset_check"]
    assert check["calibrated_s"] == pytest.approx(check["expected_s"], abs=1.5e-3)
    tables = (out / "tables.md").read_text()
    assert tables.count("07_undisturbed") >= 5
    assert "Fig. 16 statistic" in tables
    assert "Extensions (not the paper's method)" in tables
    assert "pose_trajectory" not in res  # no pairing of unrelated recordings
    assert saved["regime"]["status"] == {"ok": 3}
    assert set(saved["regime_extensions"]["extensions"]) >= {"calibrated", "smoother"}
    assert any(f.endswith(".png") for f in res.get("figures", []))


def test_regime_e_s_statistic_within_band(shared_data: Path) -> None:
    """The paper's regime on BROAD trial 02's motion, three seeded recordings. Band: the
    paper's value x [1/2, 2] (the issue's bar) for the longest sequence's e_s maximum and
    standard deviation before the correction (0.26, 0.06 deg) and for the maximum after it
    (0.18 deg); over the three runs the correction lowers the mean maximum and the mean
    standard deviation (it does so in 17 of 20 runs of the default reproduction, not in every
    run)."""
    params = exp.AlhatParams()
    broad = shared_data / "trajectory" / "broad"
    rows = []
    for i in range(3):
        res = exp.regime_run(params, broad, run_generator(21, i))
        assert res["status"] == "ok"
        longest = max(res["sequences"], key=lambda s: s["fixes"])
        rows.append([longest[k] for k in ("max_before_deg", "max_after_deg")])
        rows[-1] += [longest[k] for k in ("std_before_deg", "std_after_deg")]
        assert 0.13 <= longest["max_before_deg"] <= 0.52
        assert 0.09 <= longest["max_after_deg"] <= 0.36
        assert 0.03 <= longest["std_before_deg"] <= 0.12
        assert res["paper"]["weighted_eq7"]["max_deg"] < 0.33  # the paper's worst observed
        lid = res["lidar"]
        assert lid["status"]["ok"] > 0
        assert lid["lidar_minus_true_rms_deg"] < 0.05
    mean = np.mean(rows, axis=0)
    assert mean[1] < mean[0]
    assert mean[3] < mean[2]


def test_cli_lists_alhat(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["reproduce", "--list"]) == 0
    assert "alhat:" in capsys.readouterr().out
