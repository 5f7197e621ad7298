import sys
from pathlib import Path

import pytest

from toolpoint.dynamics.assembly import load_assembly

# The suite mirrors the sub-packages (tests/<sub-package>/); the shared test helpers (virtual measurements,
# synthetic systems) stay in tests/, and a few tests reuse another folder's fixtures (test module names are unique):
# every folder is importable by module name, whichever test runs first.
_HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(_HERE)] + sorted(str(d) for d in _HERE.iterdir() if d.is_dir() and any(d.glob("test_*.py")))

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "numerical_case.toml"


@pytest.fixture(scope="session")
def example_path() -> Path:
    return EXAMPLE


@pytest.fixture(scope="session")
def example():
    return load_assembly(EXAMPLE)
