"""``navtrack smooth``: CSV and RTKLIB input, summary lines, --out table."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from navtrack.cli import main
from navtrack.smoothing.ari import simulate_ari


def test_smooth_csv_with_gap_and_gross_error(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    rng = np.random.default_rng(2)
    y, _ = simulate_ari(rng, 600, (-1.2, 0.5), 2, 0.003, 0.0013)
    y[300] += 10 * 0.003
    t = 0.1 * np.arange(600)
    keep = np.ones(600, dtype=bool)
    keep[100:105] = False  # a gap in the time stamps
    src = tmp_path / "att.csv"
    pd.DataFrame({"t_s": t[keep], "roll_deg": y[keep]}).to_csv(src, index=False)
    out = tmp_path / "out.csv"
    code = main(["smooth", str(src), "--columns", "roll_deg", "--order", "2,2", "--out", str(out)])
    assert code == 0
    text = capsys.readouterr().out
    assert "5 missing epochs inserted" in text
    assert "sigma_n = " in text
    assert " deg" in text
    assert "order (2,2)" in text
    table = pd.read_csv(out)
    assert len(table) == 600
    assert {"roll_deg_filtered", "roll_deg_sigma_x", "roll_deg_gross_error", "gross_error"} <= set(
        table.columns
    )
    assert bool(table["gross_error"].iloc[300])
    assert table["roll_deg"].iloc[100:105].isna().all()
    assert table["roll_deg_filtered"].notna().all()
    assert out.with_suffix(".json").exists()


def test_smooth_rtklib_pos(gnss_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    pos = gnss_data / "rtklib_spp" / "gsi0759_gps.pos"
    code = main(["smooth", str(pos), "--order", "0,1", "--robust", "huber"])
    assert code == 0
    text = capsys.readouterr().out
    for col in ("e_m", "n_m", "u_m"):  # east/north/up about the mean position by default
        assert f"{col}: status" in text
    assert text.count("sigma_n = ") == 3


def test_smooth_pos_output_uses_ok_rows_in_east_north_up(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    """The 0759 solution has 5 ``high_dop`` epochs: they are missing epochs of the smoother,
    not data; the position is smoothed as east/north/up about the mean of the ok epochs."""
    from importlib import resources

    data = Path(str(resources.files("navtrack.data")))
    sol = tmp_path / "sol.csv"
    assert (
        main(["pos", str(data / "07590920.05o"), str(data / "07590920.05n"), "--out", str(sol)])
        == 0
    )
    capsys.readouterr()
    out = tmp_path / "smooth.csv"
    assert main(["smooth", str(sol), "--order", "0,1", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    solution = pd.read_csv(sol)
    bad = (solution["status"] != "ok").to_numpy()
    assert bad.sum() == 5
    assert "status     5 rows not ok taken as missing (high_dop 5)" in text
    assert "n 120 (missing 5)" in text
    table = pd.read_csv(out)
    enu = table[["e_m", "n_m", "u_m"]].to_numpy()
    assert np.isnan(enu[bad]).all()
    assert np.isfinite(enu[~bad]).all()
    np.testing.assert_allclose(enu[~bad].mean(axis=0), 0.0, atol=1e-6)
    xyz = solution[["x_m", "y_m", "z_m"]].to_numpy()[~bad]
    dist = np.linalg.norm(xyz - xyz.mean(axis=0), axis=1)
    np.testing.assert_allclose(np.linalg.norm(enu[~bad], axis=1), dist, atol=1e-6)
    assert main(["smooth", str(sol), "--order", "0,1", "--frame", "ecef"]) == 0
    assert "x_m: status" in capsys.readouterr().out


@pytest.mark.parametrize("estimator", ["exact", "paper"])
def test_smooth_warns_outside_the_papers_conditions(
    estimator: str, tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    """Paper §2.2: sigma_e and sigma_n of the same order; a slow random walk under much noise
    leaves it (sigma_e/sigma_n = 0.05, estimated 0.06), a constant with noise puts sigma_e at
    its bound; a series within both conditions gets no such warning."""
    rng = np.random.default_rng(3)
    n = 400
    walk, _ = simulate_ari(rng, n, (), 1, 1.0, 0.05)
    flat = 1.0 + 0.02 * rng.standard_normal(n)
    good, _ = simulate_ari(rng, n, (), 1, 0.02, 0.02)
    src = tmp_path / "series.csv"
    pd.DataFrame({"t_s": np.arange(n), "walk": walk, "flat": flat, "good": good}).to_csv(
        src, index=False
    )
    out = tmp_path / "out.csv"
    argv = ["smooth", str(src), "--order", "0,1", "--estimator", estimator, "--out", str(out)]
    assert main(argv) == 0
    text = capsys.readouterr().out
    warned = {
        col: [ln for ln in text.splitlines() if ln.startswith(f"warning    {col}:")]
        for col in ("walk", "flat", "good")
    }
    assert any("not of the same order of magnitude" in ln for ln in warned["walk"])
    assert any("sits at its bound" in ln for ln in warned["flat"])
    assert not any("same order" in ln or "bound" in ln for ln in warned["good"])
    summary = json.loads(out.with_suffix(".json").read_text())["columns"]
    assert summary["flat"]["status"] == "boundary"
    assert [f"warning    flat: {w}" for w in summary["flat"]["warnings"]] == warned["flat"]


def test_smooth_bad_column(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    src = tmp_path / "a.csv"
    pd.DataFrame({"t": [0.0, 1.0, 2.0], "v": [1.0, 2.0, 3.0]}).to_csv(src, index=False)
    with pytest.raises(SystemExit, match="not in") as info:
        main(["smooth", str(src), "--columns", "w"])
    assert info.value.code == 2
    assert "navtrack smooth: error: columns w not in" in capsys.readouterr().err


def test_smooth_example_is_the_0759_solution(capsys: pytest.CaptureFixture) -> None:
    assert main(["smooth", "--example", "--order", "0,1"]) == 0
    text = capsys.readouterr().out
    assert "example    single point positions of 07590920.05o" in text
    assert "status     5 rows not ok taken as missing (high_dop 5)" in text
    assert text.count("n 120 (missing 5)") == 3


def test_smooth_vce_forstner_needs_the_paper_estimator(tmp_path: Path) -> None:
    rng = np.random.default_rng(5)
    y, _ = simulate_ari(rng, 300, (-0.5,), 1, 0.02, 0.01)
    src = tmp_path / "series.csv"
    pd.DataFrame({"t_s": np.arange(y.size), "v": y}).to_csv(src, index=False)
    with pytest.raises(SystemExit, match="estimator='paper'"):
        main(["smooth", str(src), "--order", "1,1", "--vce", "forstner"])
    out = tmp_path / "out.csv"
    argv = ["smooth", str(src), "--order", "1,1", "--estimator", "paper", "--vce", "forstner"]
    assert main([*argv, "--out", str(out)]) == 0
    summary = json.loads(out.with_suffix(".json").read_text())["columns"]["v"]
    assert summary["sigma_n"] == pytest.approx(0.02, rel=0.3)
