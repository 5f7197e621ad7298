from pathlib import Path

import pytest

from toolpoint.dynamics.assembly import load_assembly

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "numerical_case.toml"


@pytest.fixture(scope="session")
def example_path() -> Path:
    return EXAMPLE


@pytest.fixture(scope="session")
def example():
    return load_assembly(EXAMPLE)
