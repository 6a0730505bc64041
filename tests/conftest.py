import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(Path(__file__).resolve().parent))

SCENARIOS = ROOT / "scenarios"


@pytest.fixture
def scenarios():
    return SCENARIOS


@pytest.fixture(autouse=True)
def _fresh_solvers_around_patches(request):
    """A test that patches (monkeypatch) may patch the physics a solver bakes in when built: it
    must neither reuse a solver built before nor leave one built with the patch."""
    from tca_casadi.solvers.collocation import clear_built_solvers
    patched = "monkeypatch" in request.fixturenames
    if patched:
        clear_built_solvers()
    yield
    if patched:
        clear_built_solvers()
