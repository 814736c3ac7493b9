"""``navtrack reproduce agps`` on the experiment contract, reduced: a handful of fix sets, the
real-data study on few fixes; the statistics and the verdicts on constructed tables."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from navtrack.experiments import ReproduceOptions, get_experiment, reproduce
from navtrack.experiments.agps import (
    AgpsExperimentParams,
    error_statistics,
    findings,
    real_data_study,
    simulate_fix_set,
)
from navtrack.experiments.agps.simulation import (
    fix_set_problem,
    sensitivity_names,
    solver_config,
)
from navtrack.gnss.agps import AgpsStatus

STAT_KEYS = {"p50_m", "p60_m", "p70_m", "p80_m", "p90_m", "mean_m", "mean_iterations", "n"}


def test_error_statistics_match_numpy_and_skip_failed_and_padded_fixes() -> None:
    err = np.array([10.0, 20.0, 30.0, 40.0, np.nan, 1e9, np.nan])
    it = np.array([2, 3, 4, 5, 9, 9, 0])
    st = np.array([0, 0, 0, 0, AgpsStatus.DIVERGED, AgpsStatus.NO_CONVERGENCE, -1])
    s = error_statistics(err, it, st)
    assert s["n"] == 4
    assert s["n_total"] == 6
    assert s["mean_m"] == pytest.approx(25.0)
    assert s["p90_m"] == pytest.approx(np.percentile([10, 20, 30, 40], 90))
    assert s["p50_m"] == pytest.approx(25.0)
    assert s["mean_iterations"] == pytest.approx(3.5)
    assert s["statuses"]["diverged"] == 1
    assert s["statuses"]["no_convergence"] == 1


def _table(gn: list[float], lm: list[float], it: tuple[float, float]) -> dict:
    def cell(m: float, i: float) -> dict:
        return {"mean_m": m, "mean_iterations": i}

    return {
        "gn": {"56": {str(2 * k + 2): cell(m, it[0]) for k, m in enumerate(gn)}},
        "lm": {"56": {str(2 * k + 2): cell(m, it[1]) for k, m in enumerate(lm)}},
        "map": {"56": {str(2 * k + 2): cell(m, it[0]) for k, m in enumerate(lm)}},
    }


def test_findings_on_the_papers_numbers_and_on_their_opposite() -> None:
    # Tables I/II/III at 56 m: 493.84 vs 110.79 m, iterations 2.000 vs 2.783
    paper = findings(_table([493.84, 300, 200, 150], [110.79, 100, 95, 90], (2.0, 2.783)), "56",
                     ["2", "4", "6", "8"])  # fmt: skip
    assert paper["lm_below_gn"]
    assert paper["ratio_below_1_5"]
    assert paper["gain_shrinks"]
    assert paper["iteration_ratio"] == pytest.approx(1.3915)
    opposite = findings(_table([100, 90, 80, 70], [300, 300, 300, 300], (2.0, 4.0)), "56",
                        ["2", "4", "6", "8"])  # fmt: skip
    assert not opposite["lm_below_gn"]
    assert not opposite["ratio_below_1_5"]
    assert not opposite["gain_shrinks"]  # the (negative) gain grows in size


def test_fix_set_is_seeded_and_its_truth_is_consistent() -> None:
    params = AgpsExperimentParams(real_data=False, sigma_noise_m=0.0, sigma_iono_zenith_m=0.0,
                                  sigma_tropo_zenith_m=0.0, sigma_orbit_m=0.0)  # fmt: skip
    p1, truth, meta = fix_set_problem(params, np.random.default_rng(4))
    p2, _, _ = fix_set_problem(params, np.random.default_rng(4))
    np.testing.assert_array_equal(p1.y_m, p2.y_m)
    assert p1.size == len(params.heights_m) * len(params.intervals_min)
    distance = params.cell_radius_m * meta["cell_fraction"]
    assert 0.0 <= distance <= params.cell_radius_m
    assert np.linalg.norm(p1.start_xyz_m[0] - truth) == pytest.approx(distance)
    assert meta["dop"] <= params.max_dop
    # error-free pseudoranges: Gauss–Newton recovers the truth exactly once the height given is
    # the one whose f5 surface passes through the truth; that height departs from the geodetic
    # 56 m by less than h e² (0.38 m)
    from scipy.optimize import brentq

    from navtrack.gnss.agps import AgpsConfig, ellipsoid_residual, solve_agps

    h_f5 = brentq(lambda h: float(ellipsoid_residual(truth, h)), 0.0, 100.0, xtol=1e-9)
    assert abs(h_f5 - 56.0) < 56.0 * 6.69438e-3
    at_true = np.flatnonzero(p1.height_m == 56.0)
    on_surface = dataclasses.replace(p1, height_m=np.where(p1.height_m == 56.0, h_f5, p1.height_m))
    res = solve_agps(on_surface, "gn", AgpsConfig(eps=1e-9))
    err = np.linalg.norm(res.pos_m[at_true] - truth, axis=1)
    assert err.max() < 1e-3
    run = simulate_fix_set(params, np.random.default_rng(4))
    assert run["error_m"].shape == (3, 4, 11)
    assert run["sens_error_m"].shape == (len(sensitivity_names(params)), 2, 11)
    assert solver_config(params).prior_sigma_m == params.cell_radius_m / 2.0


def test_reproduce_agps_reduced(tmp_path: Path) -> None:
    exp = get_experiment("agps")
    params = AgpsExperimentParams(real_data=False)
    results = reproduce(
        exp,
        ReproduceOptions(out_dir=tmp_path, runs=4, params=params, progress=False, backend="loop"),
    )
    saved = json.loads((tmp_path / "results.json").read_text())
    for key in ("simulation", "real_data", "findings_simulation"):
        assert key in saved
    sim = saved["simulation"]
    assert set(sim) == {"gn", "lm", "map"}
    assert set(sim["lm"]) == {"-44", "16", "36", "46", "51", "56", "61", "66", "76", "96", "156"}
    case = sim["gn"]["56"]["2"]
    assert set(case) >= STAT_KEYS
    assert case["n"] + sum(v for k, v in case["statuses"].items() if k != "ok") == 4
    tables = (tmp_path / "tables.md").read_text()
    for title in ("Table I", "Table II", "Table III", "Figs. 2 and 3", "Findings"):
        assert title in tables
    if "figures" in results:
        assert {Path(f).name for f in results["figures"]} >= {"fig2.png", "fig3.png"}
        assert all(Path(f).stat().st_size > 0 for f in results["figures"])


def test_real_data_study_on_the_shared_data(gnss_data: Path) -> None:
    from navtrack.gnss.agps import AgpsConfig

    arrays, skipped = real_data_study(
        gnss_data,
        np.random.default_rng(0),
        height_offsets_m=(0.0,),
        intervals_min=(2.0, 8.0),
        fixes=5,
        cell_radius_m=500.0,
        clock_bias_m=300.0,
        config=AgpsConfig(max_dop=700.0),
    )
    assert skipped == []
    assert set(arrays["set"].tolist()) == {"0759", "ARL1", "SEPT", "yamatogawa_master", "android"}
    assert arrays["n_fixes"]["android"] == {"2": 5, "8": 0}  # a 3.4-min log
    assert arrays["n_fixes"]["0759"] == {"2": 5, "8": 5}
    err = arrays["error_m"]
    gn_ok = arrays["status"][:, 0, 0, 0] == AgpsStatus.OK
    assert gn_ok.sum() >= 20
    # real two-satellite Gauss–Newton fixes with fine time land within kilometres
    assert np.nanmedian(err[gn_ok, 0, 0, 0]) < 3000.0
    assert not math.isnan(float(np.nanmedian(err[gn_ok, 0, 0, 0])))
    # the station's own clocks (0759's is milliseconds off) leave Gauss–Newton unchanged
    station_err = arrays["station_clock"][0]
    both = gn_ok & np.isfinite(station_err[:, 0, 0])
    np.testing.assert_allclose(station_err[both, 0, 0], err[both, 0, 0, 0], atol=50.0)


def test_parameters_refuse_bad_values(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="nav: navigation file"):
        AgpsExperimentParams(nav=tmp_path / "missing.n")
    with pytest.raises(ValueError, match="cell_radius_m"):
        AgpsExperimentParams(cell_radius_m=-1.0)
    with pytest.raises(ValueError, match="intervals_min"):
        AgpsExperimentParams(intervals_min=(0.0, 2.0))


def test_a_folder_of_other_parameters_is_refused_with_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Issue 34: rerunning into a folder of an earlier run with other parameters printed
    "internal error ... this is a navtrack defect" (exit 3)."""
    from navtrack.cli import EXIT_BAD_INPUT, main

    base = ["reproduce", "agps", "--out", str(tmp_path), "--runs", "2", "--no-figures",
            "--no-progress", "--set", "real_data=false"]  # fmt: skip
    assert main(base) == 0
    assert main([*base, "--set", "sigma_noise_m=1"]) == EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert "give a new output folder" in err
    assert "defect" not in err
    assert main(base) == 0  # the same parameters resume
