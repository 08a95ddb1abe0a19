"""Shared fixtures and test settings.

Data: the Tzionas sample and the MANO mean joints ship with handsim (``handsim.assets``, byte-identical to
``../shared/data``; ``tests/test_bundled_data.py`` pins them), so tests that need only those run
everywhere. The GraspDB14 files carry no license and are never bundled: tests that need them use
``graspdb_dir`` and skip with a reason when ``../shared/data`` is absent (a user's clone).

Hypothesis runs derandomized (seeded from each test, no example database) and without deadlines, so a
loaded machine cannot make a property test fail. (Hypothesis also draws constants from the local modules
loaded when a test runs, so one test may see other examples alone than in the whole suite: property tests
must hold for every valid input, which is what they claim anyway.)

Tests over about 5 s carry ``@pytest.mark.slow`` (registered in ``pyproject.toml``): ``python -m pytest
-q`` runs them, ``-m "not slow"`` leaves them out. No test asserts a wall-clock time; those figures are
printed by ``benchmarks/``.
"""

from __future__ import annotations

import secrets
from pathlib import Path

import pytest
from hypothesis import settings

from handsim.assets import MANO_DIR, TZIONAS_DIR

ROOT = Path(__file__).resolve().parents[1]
SHARED_DATA = ROOT.parent / "shared" / "data"
GRASPDB = SHARED_DATA / "graspdb14"
TZIONAS = TZIONAS_DIR
"""The Tzionas sample: the bundled copy (identical to ``../shared/data/tzionas_ijcv16``)."""
MANO = MANO_DIR
"""The MANO mean-joint table: the bundled copy (identical to ``../shared/data/mano``)."""

settings.register_profile("handsim", derandomize=True, deadline=None, database=None, print_blob=False)
settings.load_profile("handsim")

_REASON = "needs the real sample data in ../shared/data (present in the project's CI, not in a user's clone)"


def _require(path: Path) -> Path:
    if not path.exists():
        pytest.skip(f"{_REASON}: {path} is absent")
    return path


@pytest.fixture
def graspdb_dir() -> Path:
    """The GraspDB14 sample folder (skips the test when absent: GraspDB14 is never bundled)."""
    return _require(GRASPDB)


@pytest.fixture
def tzionas_dir() -> Path:
    """The Tzionas IJCV16 sample folder bundled with handsim (never skips)."""
    return TZIONAS


@pytest.fixture(scope="session")
def _ray_session_home(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The home of this session's Ray clusters, with the token of Ray's token authentication in it."""
    home = tmp_path_factory.mktemp("ray_home")
    token = home / ".ray" / "auth_token"
    token.parent.mkdir()
    token.write_text(secrets.token_hex(32))  # what `ray get-auth-token --generate` writes
    return home


@pytest.fixture
def ray_home(_ray_session_home: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A home of Ray's own for the test (its token in ``.ray/auth_token``), whatever ran before.

    Ray's token authentication (on by default for ``ray start`` and a local ``ray.init``) reads the token
    from ``~/.ray/auth_token`` (or ``RAY_AUTH_TOKEN_PATH``); ``ray start`` does not create one. Every Ray
    test of the session shares one home and one token (Ray caches the token it loaded once per process),
    and the user's home is never written. ``RAY_AUTH_MODE``, which a local ``ray.init`` sets in this
    process, is restored after the test.
    """
    monkeypatch.setenv("HOME", str(_ray_session_home))
    monkeypatch.setenv("RAY_AUTH_TOKEN_PATH", str(_ray_session_home / ".ray" / "auth_token"))
    monkeypatch.delenv("RAY_AUTH_TOKEN", raising=False)
    monkeypatch.delenv("RAY_AUTH_MODE", raising=False)
    return _ray_session_home
