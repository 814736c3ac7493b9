"""``navtrack rinex info`` on observation files."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from navtrack.cli import main
from navtrack.data import sample_path


def test_info_example(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    out = tmp_path / "s.json"
    assert main(["rinex", "info", "--example", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    # The bundled cut of SEPT078M.21O: 120 epochs 12:00:00-12:01:59 GPST, GPS+Galileo+QZSS
    # (src/navtrack/data/README.md).
    assert "n_epochs" in text
    assert "120" in text
    assert "2021-03-19T12:01:59.000" in text
    assert "events_by_flag    none" in text
    summary = json.loads(out.read_text())
    assert summary["n_epochs"] == 120
    assert summary["marker"] == "SEPT"
    assert set(summary["sats_per_system"]) == {"G", "E", "J"}
    assert summary["codes_per_system"]["E"][:3] == ["C1C", "L1C", "S1C"]
    assert summary["skipped_lines"] == 0
    assert summary["events_by_flag"] == {}


def test_info_file_with_events(capsys: pytest.CaptureFixture[str]) -> None:
    # 0759: three flag-4 splice records (shared/data/gnss/README.md section 1).
    assert main(["rinex", "info", str(sample_path("07590920.05o"))]) == 0
    text = capsys.readouterr().out
    assert "events_by_flag" in text
    assert "4: 3" in text
    assert "2005-04-02T00:59:30.005" in text
    assert "version           2.10" in text


def test_info_bad_file(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    rows = sample_path("07590920.05o").read_text().splitlines()
    rows[18] = rows[18].replace("24767684.822", "2476x684.822")
    bad = tmp_path / "bad.05o"
    bad.write_text("\n".join(rows) + "\n")
    assert main(["rinex", "info", str(bad)]) == 2  # bad input
    err = capsys.readouterr().err
    assert f"navtrack rinex info: error: {bad}:19: " in err
    assert "Traceback" not in err


def test_info_needs_one_input(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main(["rinex", "info"])
    assert info.value.code == 2
    assert "navtrack rinex info: error: give exactly one of" in capsys.readouterr().err
