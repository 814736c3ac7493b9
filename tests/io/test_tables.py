"""One table reader by file suffix (``navtrack.io.tables.read_table``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from navtrack.errors import FileFormatError
from navtrack.io.solution import read_solution, write_solution
from navtrack.io.tables import read_table


def _solution_frame(n: int = 5) -> pd.DataFrame:
    t = 1.3e9 + np.arange(n, dtype=float)
    xyz = np.array([-3947762.0, 3364399.0, 3699428.0]) + np.arange(n)[:, None] * 0.01
    return pd.DataFrame(
        {"t_gps_s": t, "x_m": xyz[:, 0], "y_m": xyz[:, 1], "z_m": xyz[:, 2], "status": "ok"}
    )


def test_plain_csv_with_comments(tmp_path: Path) -> None:
    path = tmp_path / "series.CSV"  # the suffix is compared lower-cased
    path.write_text("# yaw from the INS\nt_s,yaw_deg\n0,1.5\n1,2.5\n")
    df = read_table(path)
    assert list(df.columns) == ["t_s", "yaw_deg"]
    np.testing.assert_array_equal(df["yaw_deg"].to_numpy(), [1.5, 2.5])


def test_solution_tables_are_read_as_solutions(tmp_path: Path) -> None:
    path = write_solution(_solution_frame(), tmp_path / "sol.csv")
    df = read_table(path)
    pd.testing.assert_frame_equal(df, read_solution(path))
    assert "t_gps_s" in df.columns
    np.testing.assert_array_equal(df["t_gps_s"].to_numpy(), _solution_frame()["t_gps_s"])


def test_parquet(tmp_path: Path) -> None:
    pytest.importorskip("pyarrow")
    path = tmp_path / "series.parquet"
    pd.DataFrame({"t_s": [0.0, 1.0], "a_m": [3.0, 4.0]}).to_parquet(path)
    np.testing.assert_array_equal(read_table(path)["a_m"].to_numpy(), [3.0, 4.0])
    sol = write_solution(_solution_frame(), tmp_path / "sol.parquet")
    pd.testing.assert_frame_equal(read_table(sol), read_solution(sol))


def test_rtklib_pos(gnss_data: Path) -> None:
    path = gnss_data / "rtklib_spp" / "gsi0759_gps.pos"
    rows = [ln.split() for ln in path.read_text().splitlines() if ln and not ln.startswith("%")]
    table = read_table(path)
    assert len(table) == len(rows)
    xyz = [[float(v) for v in r[2:5]] for r in rows]
    np.testing.assert_array_equal(table[["x_m", "y_m", "z_m"]], xyz)
    np.testing.assert_array_equal(table["ns"], [int(r[6]) for r in rows])


def test_errors_name_the_file(tmp_path: Path) -> None:
    path = tmp_path / "track.gpx"
    path.write_text("<gpx/>")
    with pytest.raises(FileFormatError, match=r"track.gpx: unknown table suffix '.gpx' \(known: "):
        read_table(path)
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    with pytest.raises(FileFormatError, match=r"empty.csv: not a CSV table"):
        read_table(empty)
