"""Outputs that cannot be written fail before the command reads or solves anything (exit 2)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from navtrack.cli import EXIT_BAD_INPUT, main
from navtrack.cli.outputs import check_outputs
from navtrack.errors import MissingDependencyError


@pytest.mark.parametrize(
    "argv",
    [
        ["rtk", "--example", "--out", "{tmp}/no/such/folder/x.pos"],
        ["ppp", "--example", "--out", "{tmp}/x.txt"],
        ["track", "--example", "--out", "{tmp}/x.kml"],
        ["smooth", "--example", "--out", "{tmp}/x.json"],
        ["attitude", "reconstruct", "--example", "--out", "{tmp}"],
    ],
    ids=lambda a: a[0],
)
def test_a_bad_out_exits_2_before_any_work(
    argv: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys
) -> None:  # type: ignore[no-untyped-def]
    from navtrack.gnss import rinex

    def no_reading(*args, **kwargs):  # type: ignore[no-untyped-def]
        raise AssertionError("read before the output was checked")

    # the readers every one of these commands would call first
    monkeypatch.setattr(rinex.obs, "read_obs", no_reading)
    monkeypatch.setattr("navtrack.io.tables.read_table", no_reading)
    monkeypatch.setattr("navtrack.io.tracks.read_tracks", no_reading)
    monkeypatch.setattr("navtrack.io.broad.read_broad", no_reading)
    args = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    try:
        code = main(args)
    except SystemExit as exc:  # a refused option surfaces as the error line, exit 2
        code = EXIT_BAD_INPUT if exc.code != 0 else 0
    assert code == EXIT_BAD_INPUT
    capsys.readouterr()


def test_an_output_needing_an_extra_names_it(tmp_path: Path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    real = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util,
        "find_spec",
        lambda name: None if name in ("pyarrow", "matplotlib") else real(name),
    )
    with pytest.raises(MissingDependencyError, match=r"navtrack\[parquet\]"):
        check_outputs("navtrack x", tmp_path / "x.parquet", (".csv", ".parquet"))
    with pytest.raises(MissingDependencyError, match=r"navtrack\[plot\]"):
        check_outputs("navtrack x", plot=tmp_path / "figures")
    check_outputs("navtrack x", tmp_path / "x.csv", (".csv", ".parquet"))  # writable: passes
