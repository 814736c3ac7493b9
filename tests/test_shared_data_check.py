"""The shared data check of ``tests/conftest.py``: under ``CI=true`` a missing or incomplete
shared data folder stops pytest before any test runs; otherwise the tests needing it skip.

Each case runs pytest in a subprocess with its own environment, collecting one small test file.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


def _pytest(shared: Path, ci: str | None, *args: str) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k != "CI"}
    env["NAVTRACK_SHARED_DATA"] = str(shared)
    if ci is not None:
        env["CI"] = ci
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *args],
        cwd=REPO,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )


@pytest.mark.parametrize("make", ["absent", "empty", "partial"])
def test_ci_refuses_to_run_without_shared_data(tmp_path: Path, make: str) -> None:
    shared = tmp_path / "shared"
    if make != "absent":
        shared.mkdir()
    if make == "partial":
        (shared / "gnss").mkdir()
        (shared / "tracking").mkdir()
    run = _pytest(shared, "true", "tests/test_timescale.py")
    assert run.returncode == pytest.ExitCode.USAGE_ERROR, run.stdout + run.stderr
    assert f"CI=true but shared data {'not found at' if make == 'absent' else 'at'} {shared}" in (
        run.stderr
    )
    if make == "partial":
        assert "lack trajectory (set NAVTRACK_SHARED_DATA)" in run.stderr
    assert "passed" not in run.stdout  # nothing ran


def test_without_ci_the_shared_data_tests_skip(tmp_path: Path) -> None:
    run = _pytest(tmp_path / "none", None, "-rs", "tests/io/test_rtklib.py", "-k", "every_shared")
    assert run.returncode == pytest.ExitCode.OK, run.stdout + run.stderr
    assert "1 skipped" in run.stdout
    assert f"shared data not found at {tmp_path / 'none'}" in run.stdout


def test_ci_runs_when_the_shared_data_are_there(tmp_path: Path) -> None:
    for part in ("gnss", "tracking", "trajectory"):
        (tmp_path / part).mkdir()
    run = _pytest(tmp_path, "true", "tests/test_timescale.py", "-k", "not slow")
    assert run.returncode == pytest.ExitCode.OK, run.stdout + run.stderr
    assert "passed" in run.stdout
