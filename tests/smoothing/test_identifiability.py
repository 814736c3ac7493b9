"""Identifiability of ARI fits: Cramér–Rao bounds and ``navtrack smooth`` warnings.

Oracle for the bound: the spread of the estimates over independent simulated series of the
same model (the Cramér–Rao bound is the asymptotic standard deviation of the ML estimate).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from navtrack.cli import main
from navtrack.smoothing.ari import AriConfig, fit_ari, simulate_ari
from navtrack.smoothing.identifiability import identifiability_warnings, sigma_bounds


def test_bound_matches_the_spread_over_series() -> None:
    rng = np.random.default_rng(8)
    est_n, est_e, bounds = [], [], []
    for _ in range(12):
        y, _ = simulate_ari(rng, 1000, (-0.5,), 1, 0.02, 0.02)
        res = fit_ari(y, AriConfig(order=(1, 1), robust="off"))
        est_n.append(res.sigma_n)
        est_e.append(res.sigma_e)
        bounds.append(sigma_bounds(res))
    crb_n, crb_e = np.median(np.array(bounds), axis=0)
    # 12 series: the sample sd is within ~ +-40 % of the true one (chi distribution, 11 dof)
    assert np.std(est_n, ddof=1) / np.mean(est_n) == pytest.approx(crb_n, rel=0.5)
    assert np.std(est_e, ddof=1) / np.mean(est_e) == pytest.approx(crb_e, rel=0.5)
    assert identifiability_warnings(res, crb_n, crb_e) == []


def test_smooth_warns_when_sigmas_are_not_of_the_same_order(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    rng = np.random.default_rng(3)
    y, _ = simulate_ari(rng, 400, (-0.5,), 1, 0.1, 0.002)  # sigma_e / sigma_n = 0.02
    src = tmp_path / "s.csv"
    pd.DataFrame({"t_s": np.arange(400.0), "v_m": y}).to_csv(src, index=False)
    assert main(["smooth", str(src), "--columns", "v_m", "--order", "1,1"]) == 0
    text = capsys.readouterr().out
    assert "Cramér–Rao relative sd sigma_n" in text
    assert "warning    v_m:" in text
    assert "same order of magnitude" in text or "bound" in text


def test_smooth_runs_the_paper_estimator(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    rng = np.random.default_rng(9)
    y, _ = simulate_ari(rng, 500, (-0.5,), 1, 0.02, 0.02)
    src = tmp_path / "s.csv"
    pd.DataFrame({"t_s": np.arange(500.0), "v_m": y}).to_csv(src, index=False)
    out = tmp_path / "o.csv"
    args = ["smooth", str(src), "--columns", "v_m", "--order", "1,1", "--out", str(out)]
    assert main([*args, "--estimator", "paper"]) == 0
    text = capsys.readouterr().out
    assert "v_m: status ok" in text
    assert "same order" not in text  # sigma_e = sigma_n here
    import json

    summary = json.loads(out.with_suffix(".json").read_text())["columns"]["v_m"]
    assert summary["sigma_n"] == pytest.approx(0.02, rel=0.15)
    assert summary["crb_rel_sd_sigma_n"] < 0.10
