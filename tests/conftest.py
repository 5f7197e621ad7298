import sys
from pathlib import Path

import pytest

# The suite mirrors the sub-packages (tests/<sub-package>/); the shared test helpers (virtual measurements,
# synthetic systems) stay in tests/ and are imported by name from every folder.
sys.path.insert(0, str(Path(__file__).resolve().parent))

from toolpoint.dynamics.assembly import load_assembly

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "numerical_case.toml"


@pytest.fixture(scope="session")
def example_path() -> Path:
    return EXAMPLE


@pytest.fixture(scope="session")
def example():
    return load_assembly(EXAMPLE)
