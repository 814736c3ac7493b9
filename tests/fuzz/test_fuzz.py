"""Damaged copies of the bundled and test files fed to every reader and command (issue 9).

Each mutant (:mod:`fuzz_mutations`) runs in a worker process limited in memory and time
(:mod:`fuzz_targets`); it must be refused with a navtrack error naming the file (and the
line, where the reader knows one), or read with its damaged records skipped and counted,
or read as valid -- never another exception, a hang or a memory blow-up. CI runs 14
derandomized mutants per target (one per operator and three more) and a sample of the
commands as separate processes; ``--hypothesis-profile=deep`` (registered in
``tests/conftest.py``) runs 300 per target, and ``tests/fuzz/report.py`` prints the table of
outcomes.
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import warnings
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from fuzz_mutations import OPERATORS
from fuzz_targets import FAILURES, TARGETS, Runner, mutate, run_mutant
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from navtrack.data import sample_path

DEEP = settings.get_current_profile_name() == "deep"
CI_EXAMPLES = 14
_DEFAULTS = settings.get_profile("default")
SRC = Path(__file__).resolve().parents[2] / "src"


@pytest.fixture(scope="module")
def runner() -> Iterator[Runner]:
    with Runner() as r:
        yield r


@pytest.fixture(scope="module")
def workdir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("fuzz")


@pytest.mark.parametrize("target", list(TARGETS))
def test_reader_survives_mutants(target: str, runner: Runner, workdir: Path) -> None:
    if TARGETS[target].seed(workdir) is None:
        pytest.skip(f"seed of {target} needs the shared data")
    seen: list[tuple[str, str]] = []

    @settings(
        max_examples=_DEFAULTS.max_examples if DEEP else CI_EXAMPLES,
        derandomize=not DEEP,
        deadline=None,
        database=None if not DEEP else _DEFAULTS.database,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
    )
    @given(operator=st.sampled_from(sorted(OPERATORS)), seed=st.integers(0, 2**32 - 1))
    def check(operator: str, seed: int) -> None:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            outcome, message, line = run_mutant(runner, target, operator, seed, workdir)
        seen.append((operator, outcome))
        assert outcome not in FAILURES, f"{operator} seed {seed} (line {line}): {message}"

    check()
    assert len({op for op, _ in seen}) >= min(len(OPERATORS), 8)


def _limits() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (3 * 2**30, 3 * 2**30))


def _cli(argv: list[str]) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(SRC), "PYTHONWARNINGS": "ignore"}
    return subprocess.run(
        [sys.executable, "-m", "navtrack", *argv],
        capture_output=True,
        text=True,
        env=env,
        timeout=120,
        preexec_fn=_limits,
        check=False,
    )


# (command line with {} for the mutant, seed file, header lines, operator, seed)
_CLI_CASES = [
    (
        ["pos", "{}", str(sample_path("SEPT078M.21P")), "--no-progress"],
        "SEPT078M_120.21O",
        "flip_bytes",
        3,
    ),
    (
        ["pos", str(sample_path("SEPT078M_120.21O")), "{}", "--no-progress"],
        "SEPT078M.21P",
        "truncate",
        5,
    ),
    (["rinex", "info", "{}"], "07590920.05o", "garbage_line", 2),
    (["rinex", "info", "{}"], "COD0MGXFIN_20210780000_01D_05M_ORB_1045-1330.SP3", "bad_number", 1),
    (["rinex", "info", "{}"], "07590920.05n", "fake_gzip", 0),
    (
        ["pos", "{}", str(sample_path("hour2350.16n")), "--no-progress"],
        "pseudoranges_log_2016_08_22_14_45_50.txt",
        "delete_line",
        4,
    ),
]


@pytest.mark.parametrize(("argv", "seed_name", "operator", "seed"), _CLI_CASES)
def test_command_exits_cleanly_on_mutant(
    argv: list[str], seed_name: str, operator: str, seed: int, tmp_path: Path
) -> None:
    """A sample of mutants through the command line as a user runs it: exit 0, 1 or 2, one
    error line ``navtrack CMD: error: FILE...`` and no traceback."""
    src = sample_path(seed_name)
    data = src.read_bytes()
    header = next(
        (k + 1 for k, ln in enumerate(data.splitlines()) if b"END OF HEADER" in ln[:80]), 1
    )
    mutant, _ = mutate(data, header, operator, seed)
    path = tmp_path / f"mutant{src.suffix}"
    path.write_bytes(mutant)
    proc = _cli([str(path) if a == "{}" else a for a in argv])
    assert proc.returncode in (0, 1, 2), proc.stderr
    assert "Traceback" not in proc.stderr
    if proc.returncode == 2:
        errors = [ln for ln in proc.stderr.splitlines() if ": error: " in ln]
        assert len(errors) == 1, proc.stderr
        assert errors[0].startswith(f"navtrack {argv[0]}")
        assert f"error: {path}" in errors[0]


def test_mutations_are_seeded() -> None:
    data = sample_path("07590920.05n").read_bytes()
    for op in OPERATORS:
        assert mutate(data, 12, op, 7) == mutate(data, 12, op, 7)
    assert len({mutate(data, 12, "flip_bytes", s)[0] for s in range(5)}) == 5
    assert np.all([mutate(data, 12, "empty", 1)[0] == b""])


@pytest.mark.parametrize(
    ("target", "argv", "operator", "seed"),
    [
        ("tracks_csv", ["track", "{}", "--format", "csv", "--quiet"], "bad_number", 2),
        ("smooth_command", ["smooth", "{}", "--order", "0,1"], "garbage_line", 3),
    ],
)
def test_table_command_exits_cleanly_on_mutant(
    target: str, argv: list[str], operator: str, seed: int, tmp_path: Path
) -> None:
    """``track`` and ``smooth`` on a mutant of their seed, as processes (see above)."""
    src = TARGETS[target].seed(tmp_path)
    assert src is not None
    mutant, _ = mutate(src.read_bytes(), 1, operator, seed)
    path = tmp_path / f"mutant{src.suffix}"
    path.write_bytes(mutant)
    proc = _cli([str(path) if a == "{}" else a for a in argv])
    assert proc.returncode in (0, 1, 2), proc.stderr
    assert "Traceback" not in proc.stderr
    if proc.returncode == 2:
        assert proc.stderr.startswith(f"navtrack {argv[0]}: error: {path}")
