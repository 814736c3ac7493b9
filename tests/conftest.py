"""Shared fixtures: the real data sets in ``../shared/data`` and the bundled samples."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = Path(os.environ.get("NAVTRACK_SHARED_DATA", REPO.parent / "shared" / "data"))
TEST_DATA = REPO / "tests" / "data"


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """Root of the shared real data sets; tests needing it skip when it is absent."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"shared data not found at {SHARED_DATA} (set NAVTRACK_SHARED_DATA)")
    return SHARED_DATA


@pytest.fixture(scope="session")
def gnss_data(shared_data: Path) -> Path:
    return shared_data / "gnss"
