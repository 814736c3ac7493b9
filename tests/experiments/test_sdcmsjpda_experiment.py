"""``navtrack reproduce sdcmsjpda`` on a reduced study (few runs, short tracks)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from navtrack.experiments import EXPERIMENTS, ReproduceOptions, get_experiment, reproduce
from navtrack.experiments.sdcmsjpda import PAPER_TABLE1, SdCmsjpdaParams, summarize_runs
from navtrack.tracking.multisensor import ALGORITHMS


def test_registered() -> None:
    assert EXPERIMENTS["sdcmsjpda"] == "navtrack.experiments.sdcmsjpda"
    assert get_experiment("sdcmsjpda").default_runs == 50


def test_reduced_reproduction_writes_results(tmp_path: Path) -> None:
    params = SdCmsjpdaParams(pd_values=(0.97, 0.58), n_steps=25)
    res = reproduce(
        "sdcmsjpda",
        ReproduceOptions(
            tmp_path, runs=2, params=params, progress=False, backend="loop", figures=False
        ),
    )
    on_disk = json.loads((tmp_path / "results.json").read_text())
    assert set(on_disk["by_pd"]) == {"0.97", "0.58"}
    for pd in ("0.97", "0.58"):
        for alg in ALGORITHMS:
            row = on_disk["by_pd"][pd][alg]
            assert row["runs"] == 2
            assert len(row["rms_pos_per_step_m"]) == 25
            assert len(row["rms_vel_per_step_mps"]) == 25
            assert row["ms_per_step"] > 0
            if row["diverged"] < 2:  # position error of a tracked target: sensor-level, not km
                assert 10.0 < row["rms_pos_m"] < 1500.0
    assert "Table 1" in (tmp_path / "tables.md").read_text()
    assert res["paper_table1"] == PAPER_TABLE1
    assert "2000 m" in res["divergence_rule"]


def test_divergence_counted_and_excluded_from_rms() -> None:
    params = SdCmsjpdaParams(pd_values=(0.76,), n_steps=12)
    good = {"pos_err2_m2": np.full(12, 100.0**2), "vel_err2_m2ps2": np.full(12, 4.0),
            "diverged": False, "failed": "", "ms_per_step": 1.0}  # fmt: skip
    bad = dict(good, pos_err2_m2=np.full(12, 5000.0**2), diverged=True)
    runs = [{"0.76": dict.fromkeys(ALGORITHMS, good)}, {"0.76": dict.fromkeys(ALGORITHMS, bad)}]
    s = summarize_runs(params, runs)["by_pd"]["0.76"]["sequential"]
    assert s["diverged"] == 1
    assert s["runs"] == 2
    assert s["rms_pos_m"] == pytest.approx(100.0)
    assert s["rms_vel_mps"] == pytest.approx(2.0)


def test_bad_parameters() -> None:
    with pytest.raises(ValueError, match="sigma_r_m"):
        SdCmsjpdaParams(sigma_r_m=(300.0, 200.0))
    with pytest.raises(ValueError, match="pd_values"):
        SdCmsjpdaParams(pd_values=(1.2,))
