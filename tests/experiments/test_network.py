"""A station network in one job: each station's dataset equals its own single point solution,
the job resumes, and the CLI takes several observation files."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from navtrack.cli import main
from navtrack.data import sample_path
from navtrack.errors import FileFormatError
from navtrack.experiments.network import solve_network
from navtrack.gnss.rinex.nav import read_nav
from navtrack.gnss.rinex.obs import read_obs
from navtrack.gnss.spp import SppConfig
from navtrack.positioning import solve_positions
from navtrack.positioning.stations import file_kind, station_jobs

pytest.importorskip("pyarrow")

STATIONS = {"07590920.05o": "07590920.05n", "SEPT078M_120.21O": "SEPT078M.21P"}


@pytest.fixture
def network(tmp_path: Path) -> list[Path]:
    """The two bundled stations, each in its own folder beside its navigation file."""
    obs = []
    for name, nav in STATIONS.items():
        folder = tmp_path / name.split(".")[0]
        folder.mkdir()
        for f in (name, nav):
            shutil.copy(sample_path(f), folder / f)
        obs.append(folder / name)
    return obs


def test_each_station_equals_its_own_solution_and_the_job_resumes(
    network: list[Path], tmp_path: Path
) -> None:
    config = SppConfig(systems="G")
    jobs = station_jobs(network)
    assert [j.name for j in jobs] == ["07590920", "SEPT078M_120"]
    assert [[p.name for p in j.navs] for j in jobs] == [[n] for n in STATIONS.values()]
    out = tmp_path / "out"
    result = solve_network(jobs, config, out, progress=False)
    assert result.runs.counts["ok"] == 2
    table = pd.read_parquet(out / "positions")
    assert sorted(table["station"].astype(str).unique()) == ["07590920", "SEPT078M_120"]
    for job in jobs:
        alone = solve_positions(read_obs(job.obs), read_nav(job.navs[0]), config=config)
        part = table[table["station"].astype(str) == job.name]
        np.testing.assert_array_equal(part["x_m"].to_numpy(), alone.pos_m[:, 0])
        assert (part["status"].to_numpy() == alone.to_frame()["status"].to_numpy()).all()
    summary = pd.read_csv(out / "stations.csv")
    assert summary["solved"].tolist() == [115, 120]
    again = solve_network(jobs, config, out, progress=False)
    assert again.runs.counts["resumed"] == 2
    pd.testing.assert_frame_equal(
        again.stations.drop(columns=["resumed", "seconds"]),
        result.stations.drop(columns=["resumed", "seconds"]),
    )


def test_a_station_without_navigation_data_is_named(tmp_path: Path) -> None:
    lonely = tmp_path / "07590920.05o"
    shutil.copy(sample_path("07590920.05o"), lonely)
    with pytest.raises(FileFormatError, match="no navigation file given and none beside it"):
        station_jobs([lonely])
    assert file_kind(sample_path("07590920.05n")) == "nav"
    assert file_kind(sample_path("COD0MGXFIN_20210780000_01D_05M_ORB_1045-1330.SP3")) == "sp3"


def test_pos_takes_several_observation_files(
    network: list[Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "net"
    assert main(["pos", *map(str, network), "--out", str(out), "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert "stations       ok 2, error 0, resumed 0" in text
    assert (out / "positions" / "station=07590920" / "part.parquet").is_file()
    with pytest.raises(SystemExit, match="need --out DIR"):
        main(["pos", *map(str, network), "--out", str(tmp_path / "x.csv")])
    with pytest.raises(SystemExit, match="need several observation files"):
        main(["pos", str(network[0]), str(network[0].with_name("07590920.05n")), "--workers", "2"])
