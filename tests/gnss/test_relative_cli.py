"""``navtrack rtk`` on the shared data: summary, output columns, refusals."""

from __future__ import annotations

from pathlib import Path

import pytest

from navtrack.cli import main

BASE = ["-3749943.5172", "3683398.2394", "3600629.5295"]


def _yama(gnss_data: Path) -> list[str]:
    d = gnss_data / "gogps_yamatogawa"
    return [
        str(d / "yamatogawa_rover.obs"),
        str(d / "yamatogawa_master.obs"),
        str(d / "brdc0060.10n"),
    ]


def test_rtk_summary_and_csv(
    gnss_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    from navtrack.io.solution import read_solution

    d = gnss_data / "gogps_yamatogawa"
    out = tmp_path / "rtk.csv"
    ref = str(d / "yamatogawa_rover_ref_rtklib_rtk_combined.pos")
    args = ["--base-pos", *BASE, "--direction", "combined", "--ref-pos", ref, "--out", str(out)]
    code = main(["rtk", *_yama(gnss_data), *args])
    text = capsys.readouterr()
    assert code == 0
    assert "common 193" in text.out
    assert "fix rate" in text.out
    assert "slips          lli" in text.out
    assert "193 common epochs used" in text.err
    table = read_solution(out)
    assert {"quality", "ratio", "n_fixed", "status"} <= set(table.columns)
    q = table["quality"].to_numpy()
    assert set(q.tolist()) <= {1, 2, 5}
    assert (q == 1).sum() == (table["status"] == "fix").sum() >= 22


def test_rtk_nmea_quality_and_plots(gnss_data: Path, tmp_path: Path) -> None:
    out = tmp_path / "rtk.nmea"
    args = ["--base-pos", *BASE, "--out", str(out), "--plot", str(tmp_path / "fig")]
    assert main(["rtk", *_yama(gnss_data), *args]) == 0
    for name in ("rtk_error.png", "rtk_ratio.png", "rtk_sats.png"):
        assert (tmp_path / "fig" / name).stat().st_size > 1000
    fields = [line.split(",") for line in out.read_text().splitlines()]
    gga_quality = {f[6] for f in fields}
    assert gga_quality <= {"1", "4", "5"}
    assert "5" in gga_quality  # float epochs are GGA quality 5


def test_rtk_refuses_missing_file(tmp_path: Path) -> None:
    with pytest.raises(SystemExit, match="not found"):
        main(["rtk", str(tmp_path / "r.obs"), str(tmp_path / "b.obs"), str(tmp_path / "n")])


def test_rtk_example_fixes_the_geonet_baseline(capsys: pytest.CaptureFixture) -> None:
    """0759 against 3040 (3.3 km, L1+L2, static): the tags sit 0-9 ms apart, every epoch
    pairs with its base epoch and fixes within 2 cm of RTKLIB's static fixed solution."""
    import re

    from navtrack.cli import main

    assert main(["rtk", "--example", "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "epochs         rover 120, base 120, common 120" in out
    assert re.search(r"base age       median 0\.00\d s, max 0\.0\d\d s", out)
    assert "  fix          120" in out
    row = re.search(r"  fix +([0-9.]+) +([0-9.]+) +([0-9.]+)", out)
    assert row is not None
    median, worst = float(row.group(1)), float(row.group(3))
    assert median < 0.01
    assert worst < 0.02
