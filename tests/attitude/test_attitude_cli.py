"""``navtrack attitude reconstruct``: tables in, pose trajectory out, bad input named."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.spatial.transform import Rotation

from navtrack.attitude.quaternion import delta_angles, propagate
from navtrack.cli import main


def _write_inputs(tmp: Path) -> tuple[Path, Path]:
    rng = np.random.default_rng(0)
    t = np.arange(0.0, 20.0, 0.01)
    w = np.column_stack([np.sin(0.7 * t), np.cos(0.3 * t), 0.5 * np.sin(0.2 * t + 1)])
    truth = propagate(Rotation.random(rng=rng), delta_angles(t, w)).quat
    imu = tmp / "imu.csv"
    pd.DataFrame(
        {"t_s": t, "gyr_x_rad_s": w[:, 0] + 0.002, "gyr_y_rad_s": w[:, 1], "gyr_z_rad_s": w[:, 2]}
    ).to_csv(imu, index=False)
    k = np.arange(30, t.size, 100)
    q = truth[k]
    fixes = tmp / "fixes.csv"
    pd.DataFrame({"t_s": t[k], "qx": q[:, 0], "qy": q[:, 1], "qz": q[:, 2], "qw": q[:, 3]}).to_csv(
        fixes, index=False
    )
    return imu, fixes


def test_reconstruct_from_tables(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    imu, fixes = _write_inputs(tmp_path)
    out = tmp_path / "pose.csv"
    summary = tmp_path / "s.json"
    args = ["attitude", "reconstruct", str(imu), "--fixes", str(fixes), "--out", str(out)]
    rc = main([*args, "--json", str(summary), "--estimate", "calibrated", "--t0-gps-s", "1e9"])
    assert rc == 0
    text = capsys.readouterr().out
    assert "20 camera fixes" in text
    pose = pd.read_csv(out)
    assert {"qx", "qy", "qz", "qw", "roll_deg", "pitch_deg", "yaw_deg", "x_m"} <= set(pose)
    assert len(pose) == 2000
    assert pose["time_gps"].iloc[0].startswith("2011-09-14")  # GPS second 1e9
    s = json.loads(summary.read_text())
    assert s["calibration"]["bias_rad_s"][0] == pytest.approx(0.002, abs=2e-4)


def test_summary_without_out_and_a_pose_table_without_gnss(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    imu, fixes = _write_inputs(tmp_path)
    args = ["attitude", "reconstruct", str(imu), "--fixes", str(fixes)]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "calibrated bias" in text
    assert "wrote" not in text
    out = tmp_path / "pose.csv"
    assert main([*args, "--out", str(out)]) == 0
    assert "(no GNSS positions)" in capsys.readouterr().out
    pose = pd.read_csv(out)
    # only the columns with values: no empty GNSS columns, no 1980 calendar time
    assert list(pose) == ["t_s", "qx", "qy", "qz", "qw", "roll_deg", "pitch_deg", "yaw_deg"]
    assert pose.notna().all().all()
    np.testing.assert_allclose(np.linalg.norm(pose[["qx", "qy", "qz", "qw"]], axis=1), 1.0)


def test_bad_input(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    imu, fixes = _write_inputs(tmp_path)
    out = str(tmp_path / "pose.csv")
    df = pd.read_csv(imu)
    df.loc[5, "t_s"] = df.loc[2, "t_s"]
    unordered = tmp_path / "unordered.csv"
    df.to_csv(unordered, index=False)
    with pytest.raises(SystemExit, match="out of order at sample 5"):
        main(["attitude", "reconstruct", str(unordered), "--fixes", str(fixes), "--out", out])
    f = pd.read_csv(fixes)
    f.loc[3, "qw"] = 2.0
    nonunit = tmp_path / "nonunit.csv"
    f.to_csv(nonunit, index=False)
    with pytest.raises(SystemExit, match="fix_quat: quaternion row 3 is not a unit"):
        main(["attitude", "reconstruct", str(imu), "--fixes", str(nonunit), "--out", out])
    f.drop(columns="qw").to_csv(nonunit, index=False)
    assert main(["attitude", "reconstruct", str(imu), "--fixes", str(nonunit), "--out", out]) == 2
    assert "lacks the columns qw" in capsys.readouterr().err
    with pytest.raises(SystemExit, match="exactly one of"):
        main(["attitude", "reconstruct", str(imu), "--out", out])
    with pytest.raises(SystemExit, match="needs a BROAD"):
        main(["attitude", "reconstruct", str(imu), "--simulate-fixes", "--out", out])
    with pytest.raises(SystemExit, match=r"unknown format '\.kml' \(use \.csv, \.parquet\)"):
        main(["attitude", "reconstruct", str(imu), "--fixes", str(fixes), "--out", "x.kml"])
