"""Shared fixtures: the real data sets in ``../shared/data`` and the bundled samples.

Without the shared data the tests that need them skip; under ``CI=true`` a missing or
incomplete shared data folder stops the run before any test, so CI cannot pass by skipping.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

REPO = Path(__file__).resolve().parents[1]

# Deep runs outside CI (``pytest tests/fuzz --hypothesis-profile=deep``): 300 examples per
# test instead of the fuzz suite's 14 derandomized mutants per target.
settings.register_profile(
    "deep",
    max_examples=300,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
SHARED_DATA = Path(os.environ.get("NAVTRACK_SHARED_DATA", REPO.parent / "shared" / "data"))
TEST_DATA = REPO / "tests" / "data"
# The folders of the shared data the tests read.
SHARED_PARTS = ("gnss", "tracking", "trajectory")


def shared_data_problem(root: Path) -> str | None:
    """Why ``root`` cannot serve as the shared data, or None when it can.

    Parameters
    ----------
    root : Path
        Candidate root of the shared real data sets.

    Returns
    -------
    str or None
        A sentence naming the path and what is missing; None when every folder of
        ``SHARED_PARTS`` is there.
    """
    if not root.is_dir():
        return f"shared data not found at {root} (set NAVTRACK_SHARED_DATA)"
    missing = [p for p in SHARED_PARTS if not (root / p).is_dir()]
    if missing:
        return f"shared data at {root} lack {', '.join(missing)} (set NAVTRACK_SHARED_DATA)"
    return None


def _in_ci() -> bool:
    return os.environ.get("CI", "").lower() == "true"


def pytest_configure(config: pytest.Config) -> None:
    """Under ``CI=true``, refuse to start when the shared data are missing."""
    problem = shared_data_problem(SHARED_DATA)
    if _in_ci() and problem is not None:
        raise pytest.UsageError(f"CI=true but {problem}; the tests needing them would skip")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Outside CI, ``slow`` tests are skipped unless a ``-m`` expression selects the tests."""
    if _in_ci() or config.getoption("markexpr"):
        return
    skip = pytest.mark.skip(reason="slow: runs under CI=true or when selected with -m slow")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """Root of the shared real data sets; tests needing it skip when it is absent."""
    problem = shared_data_problem(SHARED_DATA)
    if problem is not None:
        pytest.skip(problem)
    return SHARED_DATA


@pytest.fixture(scope="session")
def gnss_data(shared_data: Path) -> Path:
    return shared_data / "gnss"


@pytest.fixture(scope="session")
def sept_pos_cut() -> Path:
    """The bundled cut of RTKLIB's SEPT GPS+Galileo+QZSS solution (first 60 epochs)."""
    return TEST_DATA / "sept078_gej_cut.pos"
