"""One error path for every command: ``navtrack CMD: error: FILE:LINE: what``, exit codes
2 (bad input), 1 (nothing solved), 3 (a defect, traceback only with ``--debug``), and output
piped into a reader that stops early."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

import navtrack.cli.rinex
from navtrack.cli import EXIT_BAD_INPUT, EXIT_INTERNAL, main
from navtrack.data import sample_path

SRC = Path(navtrack.cli.__file__).resolve().parents[2]


def test_malformed_file_names_file_and_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rows = sample_path("07590920.05n").read_text().splitlines()
    rows[13] = rows[13][:20] + "x" + rows[13][21:]  # line 14, inside a field
    bad = tmp_path / "bad.05n"
    bad.write_text("\n".join(rows) + "\n")
    assert main(["rinex", "info", str(bad)]) == EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert err.startswith(f"navtrack rinex info: error: {bad}:14: ")
    assert err.count("\n") == 1


def test_missing_file_is_bad_input(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    missing = tmp_path / "none.csv"
    assert main(["smooth", str(missing)]) == EXIT_BAD_INPUT
    assert f"navtrack smooth: error: {missing}: No such file" in capsys.readouterr().err


def test_unexpected_exception_is_short_unless_debug(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    def broken(_: object) -> int:
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setattr(navtrack.cli.rinex, "run_info", broken)
    assert main(["rinex", "info", "--example"]) == EXIT_INTERNAL
    err = capsys.readouterr().err
    assert err.startswith("navtrack rinex info: error: internal error ZeroDivisionError")
    assert "--debug" in err
    assert "Traceback" not in err
    assert main(["--debug", "rinex", "info", "--example"]) == EXIT_INTERNAL
    assert "Traceback (most recent call last)" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("command", "option", "default"),
    [
        ("track", "--associator", "gnn"),
        ("track", "--report-s", "the median over the ids of their median report interval"),
        ("track", "--match-m", "500"),
        ("track", "--max-time-days", "30"),
        ("pos", "--iono", "klobuchar"),
        ("pos", "--elmask", "15"),
        ("smooth", "--robust", "danish"),
        ("reproduce", "--seed", "0"),
    ],
)
def test_help_states_defaults(
    command: str, option: str, default: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as done:
        main([command, "--help"])
    assert done.value.code == 0
    text = " ".join(capsys.readouterr().out.split())
    start = text.index(option + " ", text.index("options:"))
    end = text.find(" --", start + len(option) + 1)
    entry = text[start : end if end > 0 else None]
    assert f"(default: {default}" in entry or f"(default {default}" in entry


@pytest.mark.parametrize("reader", ["head -1", "true"])
def test_pos_piped_into_head_writes_out_and_no_broken_pipe(tmp_path: Path, reader: str) -> None:
    # ``true`` exits before pos writes anything: every write meets a closed pipe
    out = tmp_path / "sol.csv"
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    cmd = f"{sys.executable} -m navtrack pos --example --out {out} | {reader}"
    proc = subprocess.run(
        ["bash", "-o", "pipefail", "-c", cmd], capture_output=True, text=True, env=env, timeout=120
    )
    assert "Broken pipe" not in proc.stderr, proc.stderr
    assert "Error" not in proc.stderr, proc.stderr
    assert proc.returncode == 0
    assert len(out.read_text().splitlines()) == 121
