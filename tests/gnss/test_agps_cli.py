"""``navtrack agps``: a real two-satellite fix of the bundled 0759 file, and its bad input."""

from __future__ import annotations

import re
from importlib import resources
from pathlib import Path

import pytest

from navtrack.cli import main

DATA = Path(str(resources.files("navtrack.data")))
OBS, NAV = str(DATA / "07590920.05o"), str(DATA / "07590920.05n")
# RTKLIB static relative solution of 0759 (src/navtrack/data/README.md)
REF = ["-3976219.188", "3382371.606", "3652511.143"]
BASE = [OBS, NAV, "--sats", "G07,G11", "--height", "68.4", "--approx", "35.17", "139.63"]
EPOCHS = ["--epochs", "2005-04-02T00:00:00", "2005-04-02T00:04:00"]


@pytest.mark.parametrize("solver", ["gn", "map"])
def test_agps_fix_of_a_real_station(capsys, solver) -> None:
    assert main(["agps", *BASE, *EPOCHS, "--solver", solver, "--ref", *REF]) == 0
    out = capsys.readouterr().out
    assert "status      ok" in out
    err = float(re.search(r"error       3-D ([0-9.]+) m", out).group(1))  # type: ignore[union-attr]
    assert err < 2000.0  # a 4-min, two-satellite fix from a cell 1.7 km away
    assert re.search(r"height      [+-]0\.\d m", out)  # on the assumed height


def test_agps_marquardt_reports_iterations_and_status(capsys) -> None:
    code = main(["agps", *BASE, *EPOCHS, "--solver", "lm"])
    out = capsys.readouterr().out
    assert re.search(r"status      (ok|no_convergence|diverged)   iterations \d+", out)
    assert code == (0 if "status      ok" in out else 1)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--epochs", "2005-04-02T00:00:00", "2005-04-02T00:00:00"], "same epoch twice"),
        (["--epochs", "2005-04-02T00:00:00", "2005-04-03T00:00:00"], "no epoch at 2005-04-03"),
        (["--epochs", "yesterday", "2005-04-02T00:04:00"], "neither a GPST calendar time"),
    ],
)
def test_agps_bad_epochs(args, message) -> None:
    with pytest.raises(SystemExit, match=message):
        main(["agps", *BASE, *args])


def test_agps_bad_satellites_and_height() -> None:
    bad_sats = [OBS, NAV, "--height", "68.4", "--approx", "35.17", "139.63", *EPOCHS]
    with pytest.raises(SystemExit, match="satellite G02 is never observed"):
        main(["agps", *bad_sats, "--sats", "G07,G02"])
    with pytest.raises(SystemExit, match="two different satellites"):
        main(["agps", *bad_sats, "--sats", "G07,G07"])
    with pytest.raises(SystemExit, match="GPS satellites"):
        main(["agps", *bad_sats, "--sats", "G07,E11"])
    high = [OBS, NAV, "--sats", "G07,G11", "--height", "68400", "--approx", "35.17", "139.63"]
    with pytest.raises(SystemExit, match="outside the earth's range"):
        main(["agps", *high, *EPOCHS])
