"""``navtrack pos``: example run, outputs, summary, exit codes and bad input."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from navtrack.cli import main
from navtrack.data import sample_path


def test_example_prints_summary_and_writes_csv(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "sept.csv"
    assert main(["pos", "--example", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "epochs         120" in text
    assert "solved         120" in text
    assert "error vs ref" in text
    assert "3D" in text
    rows = list(csv.DictReader(out.open()))
    assert len(rows) == 120
    assert rows[0]["time_gps"] == "2021-03-19T12:00:00.000"
    assert {r["status"] for r in rows} == {"ok"}
    xyz = np.array([[float(r[k]) for k in ("x_m", "y_m", "z_m")] for r in rows])
    ref = np.array([-3962108.673, 3381309.574, 3668678.638])
    assert np.median(np.linalg.norm(xyz - ref, axis=1)) < 3.0


@pytest.mark.parametrize("suffix", [".nmea", ".kml", ".gpx"])
def test_track_formats(tmp_path: Path, suffix: str) -> None:
    out = tmp_path / f"track{suffix}"
    assert main(["pos", "--example", "--out", str(out)]) == 0
    assert out.stat().st_size > 1000


def test_plots(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("matplotlib")
    assert main(["pos", "--example", "--plot", str(tmp_path / "fig")]) == 0
    pngs = sorted(p.name for p in (tmp_path / "fig").glob("*.png"))
    assert "enu_error.png" in pngs
    assert "skyplot.png" in pngs


def test_rinex2_with_ref_llh(capsys: pytest.CaptureFixture[str]) -> None:
    rc = main(
        [
            "pos",
            str(sample_path("07590920.05o")),
            str(sample_path("07590920.05n")),
            "--ref-llh",
            "35.160867766",
            "139.613844940",
            "68.4545",
        ]
    )
    assert rc == 0
    text = capsys.readouterr().out
    assert "solved         115" in text
    assert "high_dop           5" in text


def test_nav_not_matching_exits_nonzero(capsys: pytest.CaptureFixture[str]) -> None:
    rc = main(["pos", str(sample_path("SEPT078M_120.21O")), str(sample_path("07590920.05n"))])
    assert rc == 1
    captured = capsys.readouterr()
    assert "no_ephemeris       120" in captured.out
    assert "NAV file matches the observation day" in captured.err


def test_reference_in_wrong_units_is_refused() -> None:
    with pytest.raises(SystemExit, match="ECEF metres"):
        main(["pos", "--example", "--ref", "-3962.108", "3381.309", "3668.678"])  # km
    with pytest.raises(SystemExit, match="degrees"):
        main(["pos", "--example", "--ref-llh", "-3962108.6", "3381309.5", "3668678.6"])


def test_unwritable_output_still_solves(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rc = main(["pos", "--example", "--out", str(tmp_path / "missing" / "x.csv")])
    assert rc == 1
    captured = capsys.readouterr()
    assert "solved         120" in captured.out
    assert "does not exist" in captured.err
    assert "NOT written" in captured.err


def test_missing_inputs() -> None:
    with pytest.raises(SystemExit, match="no navigation file"):
        main(["pos", str(sample_path("SEPT078M_120.21O"))])
    with pytest.raises(SystemExit, match="not found"):
        main(["pos", "/nonexistent.21o", str(sample_path("SEPT078M.21P"))])
    with pytest.raises(SystemExit, match="systems"):
        main(["pos", "--example", "--systems", "GXQ"])


def test_android_log(capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("navtrack.gnss.android")
    rc = main(
        [
            "pos",
            str(sample_path("pseudoranges_log_2016_08_22_14_45_50.txt")),
            str(sample_path("hour2350.16n")),
            "--systems",
            "G",
            "--ref-llh",
            "37.422578",
            "-122.081678",
            "-28",
        ]
    )
    assert rc == 0
    text = capsys.readouterr().out
    assert "weighting cn0" in text
    line = next(ln for ln in text.splitlines() if ln.strip().startswith("3D"))
    assert float(line.split()[2]) <= 15.0  # 3D RMS


def test_long_files_are_solved_in_chunks(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Files longer than CHUNK_EPOCHS are solved block by block (with a progress bar); the
    written solution equals the one-block solution."""
    import navtrack.cli.pos as pos

    whole, chunked = tmp_path / "whole.csv", tmp_path / "chunked.csv"
    assert main(["pos", "--example", "--out", str(whole)]) == 0
    monkeypatch.setattr(pos, "CHUNK_EPOCHS", 25)
    assert main(["pos", "--example", "--out", str(chunked)]) == 0
    assert whole.read_text() == chunked.read_text()
