"""The short Python API of the README: ``navtrack.gnss`` names imported on first use, results
as pandas frames."""

from __future__ import annotations

import subprocess
import sys

import pandas as pd
import pytest

import navtrack.gnss as gnss
from navtrack.data import sample_path


def test_readme_lines_give_the_solution_table() -> None:
    from navtrack.gnss import read_nav, read_obs
    from navtrack.gnss.spp import solution_frame
    from navtrack.io.solution import solution_table
    from navtrack.positioning import solve_positions

    result = solve_positions(
        read_obs(sample_path("07590920.05o")), read_nav(sample_path("07590920.05n"))
    )
    table = result.to_frame()
    assert isinstance(table, pd.DataFrame)
    assert len(table) == 120
    assert table["status"].value_counts().to_dict() == {"ok": 115, "high_dop": 5}
    pd.testing.assert_frame_equal(table.iloc[:, 1:], solution_table(solution_frame(result)))
    assert (table["t_gps_s"] == result.t_gps_s).all()


def test_to_frame_reads_back_as_written(tmp_path) -> None:
    from navtrack.gnss import read_nav, read_obs
    from navtrack.gnss.spp import solution_frame
    from navtrack.io.solution import read_solution, write_solution
    from navtrack.positioning import solve_positions

    result = solve_positions(
        read_obs(sample_path("07590920.05o")), read_nav(sample_path("07590920.05n"))
    )
    path = write_solution(solution_frame(result), tmp_path / "sol.csv")
    back, table = read_solution(path), result.to_frame()
    assert list(back.columns) == list(table.columns)
    assert (back["status"] == table["status"]).all()
    assert abs(back["x_m"] - table["x_m"]).max() < 1e-3  # written to the mm


def test_names_are_imported_on_first_use_only() -> None:
    code = (
        "import sys, navtrack.gnss; "
        "print(int(any(m.startswith('navtrack.gnss.') for m in sys.modules)))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "0"
    for name in gnss.__all__:
        assert callable(getattr(gnss, name)), name
    with pytest.raises(AttributeError, match="no attribute 'solve_rtk'"):
        gnss.solve_rtk  # noqa: B018
