"""``navtrack ppp``: the example's summary, clock files in and refused."""

from __future__ import annotations

from pathlib import Path

import pytest

from navtrack.cli import main
from navtrack.data import sample_path

DATA = Path(__file__).parent / "data"
CLK = DATA / "WUM0MGXFIN_20230010000_30M_30S_CLK_cut.CLK"


def test_ppp_example_presents_the_formal_sd_and_the_bound(capsys: pytest.CaptureFixture) -> None:
    assert main(["ppp", "--example"]) == 0
    out = capsys.readouterr().out
    assert "epochs         120, updated 120" in out
    assert "formal sd      E/N/U" in out
    # against the station's reference: the convergence table after 60 s, metres off in 2 min
    row = out.split("(m, error vs ref)\n")[1].split()
    assert float(row[0]) == 60.0
    assert 0.0 < float(row[3]) < 10.0
    share = float(out.split("inside 95 %")[1].split("%")[0])
    assert 0.0 <= share <= 100.0


def test_ppp_refuses_a_clock_file_of_another_day(capsys: pytest.CaptureFixture) -> None:
    """The 2023-01-01 clocks against the 2021-03-19 example: refused, both spans named."""
    args = ["ppp", str(sample_path("SEPT078M_120.21O")), str(sample_path("SEPT078M.21P"))]
    sp3 = sample_path("COD0MGXFIN_20210780000_01D_05M_ORB_1045-1330.SP3")
    with pytest.raises(SystemExit, match="covers 2023-01-01T00:00:00 to 2023-01-01T00:30:00"):
        main([*args, "--sp3", str(sp3), "--clk", str(CLK)])
    assert "2021-03-19" in capsys.readouterr().err


def test_ppp_names_the_line_of_a_damaged_clock_file(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    text = CLK.read_text().splitlines(keepends=True)
    end = next(i for i, ln in enumerate(text) if "END OF HEADER" in ln) + 1
    bad = tmp_path / "bad.clk"
    bad.write_text("".join(text[: end + 1]) + "AS G05  2023  1 xx\n" + "".join(text[end + 1 :]))
    args = ["ppp", str(sample_path("SEPT078M_120.21O"))]
    sp3 = sample_path("COD0MGXFIN_20210780000_01D_05M_ORB_1045-1330.SP3")
    assert main([*args, "--sp3", str(sp3), "--clk", str(bad)]) == 2
    err = capsys.readouterr().err
    assert f"bad.clk:{end + 2}: unreadable AS record 'AS G05  2023  1 xx'" in err


def test_ppp_plot_writes_the_error_figure(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    assert main(["ppp", "--example", "--plot", str(tmp_path / "fig")]) == 0
    png = tmp_path / "fig" / "ppp_error.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert f"figures        {png}" in capsys.readouterr().out
