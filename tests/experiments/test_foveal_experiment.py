"""``navtrack reproduce foveal`` on a reduced set-up: results.json structure, tables, statuses."""

from __future__ import annotations

import json

import numpy as np
import pytest

from navtrack.experiments import EXPERIMENTS, ReproduceOptions, get_experiment, reproduce
from navtrack.experiments.foveal import FovealParams, assigned_errors, foveal_run, wilson_interval

SMALL = FovealParams(n_particles=40, steps=8, last_steps=3, gain_check=False)


def test_registered():
    assert EXPERIMENTS["foveal"] == "navtrack.experiments.foveal"
    assert get_experiment("foveal").default_runs == 1000


def test_assigned_errors_pair_sorted_positions():
    est = np.array([[5.0, 0.1, 2.2]])
    truth = np.array([[0.0, 2.0, 5.5]])
    np.testing.assert_allclose(assigned_errors(est, truth), [[0.1, 0.2, -0.5]])


def test_wilson_interval_known_value():
    # Wilson score interval for 95/100 at z = 1.96 (Newcombe 1998, method 3): 0.8883-0.9785
    lo, hi = wilson_interval(95, 100)
    assert lo == pytest.approx(0.8883, abs=1e-4)
    assert hi == pytest.approx(0.9785, abs=1e-4)


def test_reproduce_writes_tables_3_to_5(tmp_path):
    res = reproduce(
        "foveal",
        ReproduceOptions(
            tmp_path, runs=2, params=SMALL, backend="loop", progress=False, figures=False
        ),
    )
    data = json.loads((tmp_path / "results.json").read_text())
    for key in ("table3", "table4"):
        assert set(data[key]) == {"so", "to", "wo"}
        for rule in data[key].values():
            assert set(rule) == {"ip_jpda", "kp"}
            for cell in rule.values():
                assert cell["runs"] == 2
                assert 0.0 <= cell["converged_fraction"] <= 1.0
                lo, hi = cell["ci95"]
                assert lo <= cell["converged_fraction"] <= hi
    assert set(data["table5"]) == {"ip_jpda", "ip_gnn"}
    assert set(data["table5"]["ip_gnn"]) == {"no_clutter", "clutter"}
    ase = data["table3"]["wo"]["ip_jpda"]["ase_m2"]
    assert ase == [] or np.asarray(ase).shape == (3, SMALL.steps)
    assert sum(data["step_status_counts"].values()) == 2 * 2 * (2 * 3 + 2) * SMALL.steps
    assert "gain_check" not in data
    assert "Table 5" in (tmp_path / "tables.md").read_text()
    assert res["initial_states"]["three"] == list(SMALL.x0_three)


def test_run_is_replayable():
    a = foveal_run(SMALL, np.random.default_rng(4))
    b = foveal_run(SMALL, np.random.default_rng(4))
    np.testing.assert_array_equal(
        a["table4"]["wo"]["kp"]["sq_err_m2"], b["table4"]["wo"]["kp"]["sq_err_m2"]
    )


def test_truth_q_sets_the_truth_noise_only():
    # truth_q = 0: constant-velocity truths (x0 + k Xdot), the filter's model keeps q
    p = FovealParams(n_particles=40, steps=8, last_steps=3, gain_check=False, truth_q=0.0)
    run = foveal_run(p, np.random.default_rng(5))
    x0 = np.asarray(p.x0_three).reshape(-1, 2)
    k = np.arange(1, p.steps + 1)[:, None]
    np.testing.assert_allclose(run["trajectory"]["truth_m"], x0[:, 0] + k * x0[:, 1])
    assert p.config("ip_jpda").motion.q == pytest.approx(0.01)
    # default: the truth has the filter's process noise
    noisy = foveal_run(SMALL, np.random.default_rng(5))["trajectory"]["truth_m"]
    assert np.abs(noisy - (x0[:, 0] + k * x0[:, 1])).max() > 0.05


def test_bad_parameters():
    with pytest.raises(ValueError, match="truth_q"):
        FovealParams(truth_q=-0.01)
    with pytest.raises(ValueError, match="x0_three"):
        FovealParams(x0_three=(0.0, 1.0, 2.0))
    with pytest.raises(ValueError, match="last_steps"):
        FovealParams(steps=5, last_steps=10)
