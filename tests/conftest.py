"""Shared fixtures: paths to the real sample data in ../shared/data (skipped when absent)."""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED_DATA = ROOT.parent / "shared" / "data"
GRASPDB = SHARED_DATA / "graspdb14"
TZIONAS = SHARED_DATA / "tzionas_ijcv16"
MANO = SHARED_DATA / "mano"

_REASON = "needs the real sample data in ../shared/data (present in the project's CI, not in a user's clone)"


def _require(path: Path) -> Path:
    if not path.exists():
        pytest.skip(f"{_REASON}: {path} is absent")
    return path


@pytest.fixture
def graspdb_dir() -> Path:
    """The GraspDB14 sample folder (skips the test when absent)."""
    return _require(GRASPDB)


@pytest.fixture
def tzionas_dir() -> Path:
    """The Tzionas IJCV16 sample folder (skips the test when absent)."""
    return _require(TZIONAS)
