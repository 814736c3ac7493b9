"""The command list: ``navtrack --help`` lists every command without importing any command
module, and a command imports only its own."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import navtrack.cli
from navtrack.cli import COMMANDS, DefaultsHelpFormatter

SRC = Path(navtrack.cli.__file__).resolve().parents[2]

# the command modules loaded after running ``main(argv)`` in a fresh interpreter
LOADED = (
    "import sys\nfrom navtrack.cli import main\ntry:\n    main(sys.argv[1:])\nexcept SystemExit:\n"
    "    pass\nprint(' '.join(m for m in sys.modules if m.startswith('navtrack.cli.')))"
)


def _cli_modules_after(*argv: str) -> set[str]:
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    proc = subprocess.run(
        [sys.executable, "-c", LOADED, *argv],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
        check=True,
    )
    return set(proc.stdout.split("\n")[-2].split())


def test_help_lists_every_command_without_importing_one(
    capsys: pytest.CaptureFixture[str],
) -> None:
    with pytest.raises(SystemExit):
        navtrack.cli.main(["--help"])
    out = capsys.readouterr().out
    for name, command in COMMANDS.items():
        assert f"    {name}" in out
        assert " ".join(command.summary.split()[:3]) in " ".join(out.split())
    assert _cli_modules_after("--help") == set()


def test_a_command_imports_only_its_module() -> None:
    assert _cli_modules_after("rinex", "--help") == {"navtrack.cli.rinex"}


def test_every_command_module_registers_its_command() -> None:
    for name, command in COMMANDS.items():
        parser = navtrack.cli.build_parser([name])
        assert parser.parse_args([name, *_minimal(name)]).command == name
        assert command.module in sys.modules


def _minimal(name: str) -> list[str]:
    """Words after the command that its parser accepts without reading any file."""
    return {"rinex": ["info", "--example"], "attitude": ["reconstruct", "--example"]}.get(
        name, ["--example"] if name != "reproduce" else ["ari", "--out", "x"]
    )


@pytest.mark.parametrize("columns", ["57", "133"])
def test_help_width_is_the_terminal_width(columns: str, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("COLUMNS", columns)
    # argparse's own formatter takes 2 columns off the width shutil reports
    expected = shutil.get_terminal_size().columns - 2
    assert DefaultsHelpFormatter("navtrack")._width == expected
