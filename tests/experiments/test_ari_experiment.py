"""``navtrack reproduce ari`` pieces, on reduced runs (the full reproduction is run by the CLI)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from navtrack.experiments import ReproduceOptions, reproduce
from navtrack.experiments import ari as exp
from navtrack.experiments.runner import run_monte_carlo

SMALL = exp.SyntheticCase("small", "small ARI(1,2)", (-0.8,), 2, 0.02, 0.005, 400, 1.0, "m")


def _small_params() -> exp.AriExperimentParams:
    return exp.AriExperimentParams(cases=(SMALL,), select_order=False)


def test_synthetic_runs_recover_truth_and_gross_errors() -> None:
    params = _small_params()
    mc = run_monte_carlo(exp.synthetic_run, 4, 11, params, backend="loop", progress=False)
    assert mc.n_ok == 4
    s = exp.summarize_synthetic(mc, params)["small"]
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


def test_reproduce_end_to_end_reduced(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(exp, "default_params", _small_params)
    rng = np.random.default_rng(1)
    from navtrack.smoothing.ari import simulate_ari

    y, _ = simulate_ari(rng, 300, (-0.5,), 1, 0.05, 0.02)
    y[40:43] = np.nan
    meta = {"solver": "navtrack", "run": "fake", "solved": 297, "kinematic": False}
    fake = exp.RealSeries("fake", np.arange(300.0), {"a_m": y}, "m", 1.0, 0, meta)
    monkeypatch.setattr(exp, "default_real_sources", lambda shared: ([fake], []))
    monkeypatch.setattr(exp, "SYNTHETIC_CASES", (SMALL,))
    opts = ReproduceOptions(out_dir=tmp_path, runs=2, seed=3, progress=False)
    results = reproduce("ari", opts)
    data = json.loads((tmp_path / "results.json").read_text())
    assert data["runs"] == 2
    assert data["run_counts"]["ok"] == 2
    assert set(data["synthetic"]) == {"small"}
    assert data["real"][0]["source"] == "fake"
    assert data["real"][0]["n_missing"] == 3
    tables = (tmp_path / "tables.md").read_text()
    assert "## Synthetic series" in tables
    assert "## Real data" in tables
    assert "## GNSS SPP: navtrack's own solutions vs RTKLIB's" in tables
    assert "| fake | a_m | 297 / – |" in tables
    assert len(list((tmp_path / "runs").glob("run_*.pkl"))) == 2
    if "figures" in results:
        assert all(Path(f).exists() for f in results["figures"])
    # rerun resumes both runs from the checkpoints and reproduces the same numbers
    again = reproduce("ari", opts)
    assert again["run_counts"]["resumed"] == 2
    assert again["synthetic"] == results["synthetic"]


def test_unknown_experiment_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="unknown experiment"):
        reproduce("nope", ReproduceOptions(out_dir=tmp_path))
