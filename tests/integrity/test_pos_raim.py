"""``navtrack pos --raim``: integrity columns in the written solution and the summary lines,
on the bundled RINEX sample with an injected fault and on the shared Android log."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from navtrack.cli import main
from navtrack.io.solution import read_solution

COLUMNS = ("raim_status", "excluded", "hpl_m", "vpl_m", "test_stat", "threshold")


def _faulty_sample(tmp_path: Path) -> Path:
    """The bundled SEPT sample with +40 m on G28's C1C in epochs 20-39 (text edit of the
    RINEX records, F14.3 fields)."""
    from navtrack.data import sample_path

    lines = sample_path("SEPT078M_120.21O").read_text().splitlines(keepends=True)
    epoch = -1
    for i, line in enumerate(lines):
        if line.startswith(">"):
            epoch += 1
        elif 20 <= epoch < 40 and line.startswith("G28"):
            value = float(line[3:17]) + 40.0
            lines[i] = line[:3] + f"{value:14.3f}" + line[17:]
    path = tmp_path / "sept_fault.21O"
    path.write_text("".join(lines))
    return path


def test_fde_excludes_the_faulty_satellite(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from navtrack.data import sample_path

    out = tmp_path / "sol.csv"
    obs = _faulty_sample(tmp_path)
    rc = main(["pos", str(obs), str(sample_path("SEPT078M.21P")), "--systems", "GEJ",
               "--raim", "fde", "--out", str(out), "--no-progress"])  # fmt: skip
    assert rc == 0
    text = capsys.readouterr().out
    assert "integrity      fde: ok 100, excluded 20, alert 0, unavailable 0" in text
    assert "G28:20" in text
    df = read_solution(out)
    for col in COLUMNS:
        assert col in df.columns
    assert list(df["excluded"][20:40]) == ["G28"] * 20
    assert set(df["excluded"][:20]) == {""}
    assert np.all(df["hpl_m"] > 0)
    assert np.all(df["test_stat"][20:40] <= df["threshold"][20:40])


def test_default_writes_no_integrity_columns(tmp_path: Path) -> None:
    out = tmp_path / "sol.csv"
    assert main(["pos", "--example", "--out", str(out), "--no-progress"]) == 0
    assert "raim_status" not in read_solution(out).columns


def test_bad_probability_is_refused() -> None:
    with pytest.raises(SystemExit, match="pfa"):
        main(["pos", "--example", "--raim", "chi2", "--pfa", "2"])


def test_android_log_with_fcm(gnss_data: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log = gnss_data / "google_gnsslogger" / "pseudoranges_log_2016_08_22_14_45_50.txt"
    nav = gnss_data / "google_gnsslogger" / "hour2350.16n"
    rc = main(["pos", str(log), str(nav), "--raim", "fcm", "--no-progress"])
    assert rc == 0
    text = capsys.readouterr().out
    assert "integrity      fcm:" in text
    assert "unavailable 7" in text


def test_araim_summary_availability_and_misleading_information(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--raim araim`` on the bundled SEPT sample (GPS + Galileo, ionosphere-free): every
    epoch ``ok`` or ``excluded``, the LPV-200 availability line, no epoch with an error above
    its protection level, the EMT column; a bad ISM file is a clear error."""
    out = tmp_path / "sol.csv"
    rc = main(["pos", "--example", "--systems", "GE", "--iono", "ionofree", "--raim", "araim",
               "--out", str(out), "--no-progress"])  # fmt: skip
    assert rc == 0
    text = capsys.readouterr().out
    assert "integrity      araim: ok " in text
    assert "alert 0, unavailable 0" in text
    assert "availability 100.0 % (HPL <= 40 m, VPL <= 35 m)" in text
    assert "misleading   0 / 0 epochs" in text
    df = read_solution(out)
    assert np.all(df["emt_m"] > 0)
    assert np.all(df["vpl_m"] < 35.0)
    bad = tmp_path / "ism.toml"
    bad.write_text("[constellation.G]\nsigma_ura_m = 0.75\n")
    with pytest.raises(SystemExit, match=r"--ism: .*ism\.toml"):
        main(["pos", "--example", "--raim", "araim", "--ism", str(bad), "--no-progress"])
