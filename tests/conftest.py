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


#: the test files that take longest (CPU seconds, measured 2026-12-05: test_docs 100 s down to
#: test_simulate 24 s), started first: xdist hands out whole files (``--dist loadfile``), and a
#: long file handed out last keeps one worker busy after the other has finished. The order
#: changes the wall time only, never what runs; files not named follow in their own order.
LONGEST_FIRST = ("test_docs.py", "test_readme.py", "test_study_parallel.py", "test_shooting.py", "test_fast_paths.py",
                 "test_balance_random_tendons.py", "test_fit.py", "test_bodies.py", "test_atomic_writes.py",
                 "test_plan.py", "test_contact.py", "test_dynamics_bodies.py", "test_dynamics_contact.py",
                 "test_muscles.py", "test_bench.py", "test_global_balance.py", "test_dynamics.py", "test_jit.py",
                 "test_friction.py", "test_simulate.py")


def pytest_collection_modifyitems(items):
    """Files in :data:`LONGEST_FIRST` order, then the rest; a file's tests keep their order."""
    rank = {name: k for k, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))        # stable: keeps the rest's order
