"""Every command's ``--example`` runs on the bundled data and prints its summary (the README's
"Try it on the bundled data")."""

from __future__ import annotations

import re

import pytest

from navtrack.cli import main

EXAMPLES = [
    (["pos", "--example", "--no-progress"], r"ok +\d+"),
    (["rinex", "info", "--example"], r"n_epochs +\d+"),
    (["convert", "--example"], r"60 epochs, 28 satellites"),
    (["agps", "--example"], r"status      ok"),
    (["rtk", "--example", "--no-progress"], r"  fix +120"),
    (["ppp", "--example"], r"formal sd      E/N/U"),
    (["smooth", "--example", "--order", "0,1", "--no-progress"], r"summary    ok 3"),
    (["track", "--example", "--quiet"], r"MOTA +0\.\d+"),
    (["attitude", "reconstruct", "--example"], r"smoother +error vs optical: mean 0\.\d+ deg"),
]


@pytest.mark.parametrize(("argv", "expected"), EXAMPLES, ids=lambda a: " ".join(a)[:30])
def test_every_example_runs(
    argv: list[str], expected: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(argv) == 0
    assert re.search(expected, capsys.readouterr().out)


def test_every_command_has_an_example() -> None:
    from navtrack.cli import COMMANDS

    covered = {a[0] for a, _ in EXAMPLES}
    assert covered == set(COMMANDS) - {"reproduce"}  # reproduce runs the papers' own set-ups
