"""``navtrack reproduce ari`` pieces, on reduced runs (the full reproduction is run by the CLI)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from navtrack.experiments import ReproduceOptions, get_experiment, reproduce
from navtrack.experiments import ari as exp
from navtrack.experiments.runner import run_generator

SMALL = exp.SyntheticCase("small", "small ARI(1,2)", (-0.8,), 2, 0.02, 0.005, 400, 1.0, "m")


def _small_params() -> exp.AriExperimentParams:
    return exp.AriExperimentParams(cases=(SMALL,), select_order=False)


def test_registered_experiment_is_ari() -> None:
    assert get_experiment("ari") is exp.EXPERIMENT
    assert exp.EXPERIMENT.default_params() == exp.AriExperimentParams()
    assert exp.EXPERIMENT.default_runs == 20
    with pytest.raises(ValueError, match="outlier_sigma"):
        exp.AriExperimentParams(outlier_sigma=(15.0, 5.0))
    with pytest.raises(ValueError, match="robust"):
        exp.AriExperimentParams(robust="l1")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="attitude_form"):
        exp.AriExperimentParams(attitude_form="quaternion")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="paper_runs"):
        exp.AriExperimentParams(paper_runs=-1)


def test_paper_estimator_and_order_only_in_the_first_runs() -> None:
    params = exp.AriExperimentParams(cases=(SMALL,), paper_runs=1, order_runs=2)
    runs = [exp.synthetic_run(params, run_generator(11, i)) for i in range(3)]
    assert [exp.run_index(run_generator(11, i)) for i in range(3)] == [0, 1, 2]
    assert ["paper_status" in r["small"] for r in runs] == [True, False, False]
    assert ["order" in r["small"] for r in runs] == [True, True, False]
    assert ["paper_order" in r["small"] for r in runs] == [True, True, False]
    # the other results do not depend on whether the paper's estimator ran
    alone = exp.synthetic_run(
        exp.AriExperimentParams(cases=(SMALL,), paper_runs=0), run_generator(11, 0)
    )
    assert alone["small"]["sigma_n_ratio"] == runs[0]["small"]["sigma_n_ratio"]
    assert alone["small"]["robust_detected"] == runs[0]["small"]["robust_detected"]
    s = exp.summarize_synthetic(params, runs)["small"]
    assert (s["runs"], s["paper_runs"], s["order_runs"]) == (3, 1, 2)
    assert sum(s["orders_selected_paper"].values()) == 2
    # how far the true order's BIC is from the chosen one's (0 when chosen), both estimators
    for est in ("exact", "paper"):
        gap = s["estimators"][est]["bic_true_minus_chosen"]
        assert gap["runs"] == 2
        assert gap["iqr"][0] >= 0.0
    assert [r["small"]["order"] for r in runs[:2]] == [[1, 2], [1, 2]]  # the true order
    assert [r["small"]["bic_true_minus_chosen"] for r in runs[:2]] == [0.0, 0.0]
    assert s["estimators"]["paper"]["sigma_n_ratio"]["runs"] == 1
    assert s["estimators"]["exact"]["sigma_n_ratio"]["runs"] == 3
    # both estimators on the contaminated series too, counted over their own runs
    rob_paper, rob_exact = s["estimators"]["paper"]["robust"], s["estimators"]["exact"]["robust"]
    assert (rob_paper["runs"], rob_exact["runs"]) == (1, 3)
    assert (rob_paper["injected"], rob_exact["injected"]) == (4, 12)
    assert rob_paper["recall"] >= 0.75
    assert rob_paper["false_flag_rate"] <= 0.01
    assert rob_paper["sigma_n_ratio"]["median"] == pytest.approx(1.0, abs=0.2)
    assert s["estimators"]["paper"]["bars"]["recall_ge_95pct"] == (rob_paper["recall"] >= 0.95)
    without = exp.AriExperimentParams(cases=(SMALL,), paper_runs=0, paper_order=False)
    run0 = exp.synthetic_run(without, run_generator(11, 0))
    rec0 = run0["small"]
    assert "order" in rec0
    assert "paper_order" not in rec0
    assert "paper_robust_status" not in rec0
    none = exp.summarize_synthetic(without, [run0])["small"]["estimators"]["paper"]
    assert none["robust"]["runs"] == 0
    assert none["bars"] == dict.fromkeys(none["bars"])  # no bar judged without runs


def test_synthetic_runs_recover_truth_and_gross_errors() -> None:
    params = _small_params()
    runs = [exp.EXPERIMENT.run_one(params, run_generator(11, i)) for i in range(4)]
    s = exp.summarize_synthetic(params, runs)["small"]
    assert s["truth"]["sigma_n"] == 0.02
    assert s["runs"] == 4
    assert s["injected"] == 16  # 1 % of 400 epochs, 4 runs
    # 400 epochs of a smooth ARI(1,2): sigma_n well determined (CRB ~ 5 %), errors >= 5 sigma_n
    # have a studentized deletion residual of >= ~4.5 here, so nearly all are found.
    assert s["median_sigma_n_ratio"] == pytest.approx(1.0, abs=0.15)
    assert s["recall"] >= 0.8
    assert s["false_flag_rate"] <= 0.01
    assert s["crb_rel_sd_sigma_n"] < 0.1


def test_solution_series_regularizes_rtklib_file(gnss_data: Path) -> None:
    path = gnss_data / "rtklib_spp" / "gsi0759_gps.pos"
    src = exp.solution_series(path)
    from navtrack.io.rtklib import read_pos

    df = read_pos(path)
    t = df["t_gps_s"].to_numpy()
    step = np.median(np.diff(t))
    expected = round((t[-1] - t[0]) / step) + 1
    assert src.t_s.size == expected
    assert src.n_inserted == expected - t.size
    assert set(src.columns) == {"e_m", "n_m", "u_m"}
    e = src.columns["e_m"]
    assert np.isnan(e).sum() == src.n_inserted
    assert abs(np.nanmean(e)) < 1e-6  # ENU about the mean position


def test_navtrack_spp_rows_next_to_rtklib(gnss_data: Path, tmp_path: Path) -> None:
    # reduced: only station 0759 (120 epochs); the shared tree holds just the GNSS folder
    (tmp_path / "gnss").symlink_to(gnss_data)
    run = next(r for r in exp.SPP_RUNS if r.name == "gsi0759_gps")
    sources, skipped = exp.default_real_sources(tmp_path, spp_runs=(run,))
    assert [s.source for s in sources] == ["RTKLIB gsi0759_gps", "navtrack gsi0759_gps"]
    assert any("broad" in s for s in skipped)  # absent data are skipped with a reason
    rows, _ = exp.real_data_rows(sources)
    ours = [r for r in rows if r["source"] == "navtrack gsi0759_gps"]
    theirs = {r["column"]: r for r in rows if r["source"] == "RTKLIB gsi0759_gps"}
    assert [r["column"] for r in ours] == ["e_m", "n_m", "u_m"]
    # RTKLIB 2.4.3 solves 115 of the 120 epochs (5 with GDOP > 30): shared/data/gnss/rtklib_spp
    # README; the rejected epochs are missing observations of the ARI model, not dropped.
    assert ours[0]["meta"]["solved"] == 115
    assert ours[0]["meta"]["spp_status"]["high_dop"] == 5
    for row in ours:
        assert row["status"] in ("ok", "boundary", "not_converged")
        assert np.isfinite(row["sigma_n"])
        assert row["sigma_n"] > 0
        assert np.isfinite(row["sigma_e"])
        assert row["sigma_e"] > 0
        assert row["n"] - row["n_missing"] == 115
        # navtrack's SPP equals RTKLIB's to millimetres here (tests/gnss/test_spp.py), so the
        # noise it shows must be RTKLIB's: sigma_n of the same column within 5 %
        assert row["sigma_n"] == pytest.approx(theirs[row["column"]]["sigma_n"], rel=0.05)
    comp = exp.spp_comparison(rows)
    assert {c["column"] for c in comp} == {"e_m", "n_m", "u_m"}
    assert all(c["navtrack"] is not None and c["rtklib"] is not None for c in comp)


def test_sarimax_comparison_same_or_better_likelihood() -> None:
    pytest.importorskip("statsmodels")
    rng = np.random.default_rng(5)
    from navtrack.smoothing.ari import simulate_ari

    y, _ = simulate_ari(rng, 300, (-0.5,), 2, 0.02, 0.01)
    comp = exp.sarimax_compare(y, 1, 2, "test")
    assert comp is not None
    assert comp["loglike_gain"] >= -1e-3
    assert comp["loglike_navtrack_at_navtrack"] == pytest.approx(
        comp["loglike_sarimax_at_navtrack"], abs=1e-4
    )


def _solution_csv(path: Path) -> None:
    """A 150-epoch static solution table with a 3-epoch gap and one failed epoch."""
    rng = np.random.default_rng(1)
    from navtrack.smoothing.ari import simulate_ari

    t = np.arange(150.0)
    enu = np.column_stack([simulate_ari(rng, 150, (-0.5,), 1, 0.05, 0.02)[0] for _ in range(3)])
    xyz = np.array([-3947762.0, 3364399.0, 3699428.0]) + enu  # near GSI 0759, axes as ENU
    status = np.full(150, "ok", dtype=object)
    status[100] = "high_dop"
    keep = np.ones(150, dtype=bool)
    keep[40:43] = False
    table = {"t_gps_s": t, "x_m": xyz[:, 0], "y_m": xyz[:, 1], "z_m": xyz[:, 2], "status": status}
    import pandas as pd

    pd.DataFrame({k: v[keep] for k, v in table.items()}).to_csv(path, index=False)


def test_reproduce_end_to_end_reduced(tmp_path: Path) -> None:
    pytest.importorskip("matplotlib")
    table = tmp_path / "rover.csv"
    _solution_csv(table)
    out = tmp_path / "out"
    tiny = exp.SyntheticCase("tiny", "tiny ARI(1,1)", (-0.5,), 1, 0.02, 0.01, 150, 1.0, "m")
    # the paper's-regime series have their own tests (test_ari_carrier.py, test_ari_truths.py)
    params = exp.AriExperimentParams(
        cases=(tiny,),
        select_order=False,
        real_data=False,
        carrier_phase=False,
        ins=False,
        printed_truths=False,
    )
    opts = ReproduceOptions(
        out_dir=out, runs=2, seed=3, params=params, progress=False, inputs=(table,)
    )
    results = reproduce("ari", opts)
    data = json.loads((out / "results.json").read_text())
    assert data["experiment"] == "ari"
    assert data["runs"] == 2
    assert data["run_counts"] == {"ok": 2, "error": 0, "resumed": 0}
    assert data["parameters"]["cases"][0]["name"] == "tiny"
    assert data["parameters"]["real_data"] is False
    assert set(data["synthetic"]) == {"tiny"}
    assert data["synthetic"]["tiny"]["runs"] == 2
    assert data["synthetic"]["tiny"]["injected"] == 4  # 1 % of 150 epochs rounds to 2 per run
    # the input table: its gap inserted as missing epochs, the failed epoch missing too
    assert [row["source"] for row in data["real"]] == ["rover.csv"] * 3
    assert [row["column"] for row in data["real"]] == ["e_m", "n_m", "u_m"]
    assert all(row["n"] == 150 and row["n_inserted"] == 3 for row in data["real"])
    assert all(row["n_missing"] == 4 for row in data["real"])
    assert data["real_skipped"] == []
    # the SARIMAX cross-check ran on the synthetic case (statsmodels is a test extra)
    assert [c["series"] for c in data["sarimax"]] == ["synthetic tiny"]
    tables = (out / "tables.md").read_text()
    assert "Runs: 2 (seed 3, backend " in tables
    assert "## Synthetic truths" in tables
    assert "# Consistency study on synthetic truths" in tables
    assert "No carrier-phase series: switched off." in tables
    assert "| tiny ARI(1,1) | 150 | 1 | (1,1) |" in tables
    # every row of the gross-error and bar tables has both estimators, with their run counts
    assert "| tiny ARI(1,1) | exact | 2 | 4 |" in tables
    assert "| | paper | 2 | 4 |" in tables
    assert "## Real data" in tables
    assert "| rover.csv | e_m | 150 | 4 |" in tables
    assert "## SARIMAX cross-check" in tables
    # both estimators side by side, with the CRB and the paper's estimator on the real rows
    assert "## Printed values, exact-likelihood and paper estimator" in tables
    assert set(data["synthetic"]["tiny"]["estimators"]) == {"exact", "paper"}
    assert all(row["paper"] is not None for row in data["real"])
    assert all(np.isfinite(row["crb_sigma_n"]) for row in data["real"])
    assert "sarimax_skipped" not in data
    # figures: the synthetic estimates and recall, one series figure of the input table
    names = sorted(Path(f).name for f in data["figures"])
    assert names == [
        "gross_error_recall.png",
        "real_rover.csv_e_m.png",
        "synthetic_sigma_ratios.png",
    ]
    assert all((out / name).stat().st_size > 0 for name in names)
    assert len(list((out / "runs").glob("run_*.pkl"))) == 2
    # rerun resumes both runs from the checkpoints and reproduces the same numbers
    again = reproduce("ari", opts)
    assert again["run_counts"]["resumed"] == 2
    assert again["synthetic"] == results["synthetic"]
    assert again["real"][0]["sigma_n"] == results["real"][0]["sigma_n"]


def test_solution_table_without_positions_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "angles.csv"
    path.write_text("t_s,yaw_deg\n0,1\n1,2\n")
    with pytest.raises(ValueError, match=r"angles.csv: not a solution table: no column t_gps_s"):
        exp.solution_series(path)
