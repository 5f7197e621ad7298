import os
import sys
from pathlib import Path

# `make test` runs two pytest workers on two cores. With a threaded BLAS in each (and in the CLI processes the tests
# start), four spinning threads share two cores and small solves crawl: the slow tier took 519 s with BLAS threads
# left alone and 357 s with one thread per worker (2026-11-27, 2-core VM). One thread per worker, set before any
# test imports numpy's BLAS into a subprocess.
if os.environ.get("PYTEST_XDIST_WORKER"):
    for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(_var, "1")
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)

import pytest

from toolpoint.dynamics.assembly import load_assembly

# The suite mirrors the sub-packages (tests/<sub-package>/); the shared test helpers (virtual measurements,
# synthetic systems) stay in tests/, and a few tests reuse another folder's fixtures (test module names are unique):
# every folder is importable by module name, whichever test runs first.
_HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(_HERE)] + sorted(str(d) for d in _HERE.iterdir() if d.is_dir() and any(d.glob("test_*.py")))

pytest_plugins = ["shared_fixtures"]  # tests/base: the property and fault tests' session fixtures

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "numerical_case.toml"


def pytest_collection_modifyitems(config, items):
    """Tests marked ``first`` run first: with ``--maxschedchunk 1`` (``make test-slow``) the longest campaigns start
    on both workers at once instead of ending the run on one of them (the slow tier: 416 s, one worker left with
    the 124 s campaign at the end, against the 288 s of its CPU time shared out)."""
    items.sort(key=lambda item: item.get_closest_marker("first") is None)  # stable: the rest keep their order


@pytest.fixture(scope="session")
def example_path() -> Path:
    return EXAMPLE


@pytest.fixture(scope="session")
def example():
    return load_assembly(EXAMPLE)
