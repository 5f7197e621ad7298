"""Joint identification on the paper's numerical case (noise-free and noisy)."""

import numpy as np
import pytest

from toolpoint.errors import InputError
from toolpoint.frf import FRF
from toolpoint.identification.identify import identify, model_for, relative_errors
from toolpoint.identification.objective import JointProblem
from toolpoint.identification.params import Bounds
from toolpoint.identification.optim import Termination

F = np.arange(1.0, 3001.0)


@pytest.fixture(scope="module")
def case(example):
    model = model_for(example, F)
    exact = example.holder_tool.as_array()
    return model, exact, FRF(F, model.tool_point(exact))


def test_objective_is_the_norm_of_the_complex_difference(case):
    model, exact, meas = case
    prob = JointProblem(model.coupler, meas.values)
    rng = np.random.default_rng(0)
    X = np.log10(exact) + rng.normal(0, 0.3, (50, 4))
    direct = np.linalg.norm(model.tool_point(10.0**X) - meas.values, axis=1)
    assert np.allclose(prob.evaluate(X), direct, rtol=1e-9)
    assert prob.nfev == 50
    assert prob.evaluate(np.log10(exact)) < 1e-10 * np.linalg.norm(meas.values)  # log10 round trip


def test_hybrid_recovers_the_exact_joint(case):
    model, exact, meas = case
    r = identify(model, meas, "hybrid", seed=3)
    errs = relative_errors(r.x, exact)
    assert max(errs.values()) < 1e-4  # all four within 0.01 %
    assert r.nfev < 20000
    assert r.warnings == []
    for k, v in r.params.items():
        lo, hi = r.ci95[k]
        assert lo <= v <= hi


def test_same_seed_same_result(case):
    model, _, meas = case
    term = Termination(max_iter=30)
    for method in ("ga", "pso", "sa", "de"):
        a = identify(model, meas, method, seed=7, termination=term)
        b = identify(model, meas, method, seed=7, termination=term)
        assert np.array_equal(a.x, b.x) and a.nfev == b.nfev, method


def test_pso_beats_the_paper(case):
    """Paper Table 1, PSO: kt 0.3 %, ct 9.33 %, kr 49.8 %, cr 200 %."""
    model, exact, meas = case
    r = identify(model, meas, "pso", seed=0)
    e = relative_errors(r.x, exact)
    assert e["kt"] < 0.003 and e["ct"] < 0.0933 and e["kr"] < 0.498 and e["cr"] < 2.0


def test_bad_cr_is_flagged_when_the_fit_cannot_see_it(case, example):
    """With noise the rotational damping is barely visible: say so instead of reporting it silently."""
    model, exact, meas = case
    rng = np.random.default_rng(11)
    peak = np.abs(meas.values).max()
    noisy = FRF(F, meas.values + 0.05 * peak * (rng.standard_normal(F.size) + 1j * rng.standard_normal(F.size)) / np.sqrt(2))
    r = identify(model, noisy, "hybrid", seed=0)
    assert any(w.startswith("cr ") for w in r.warnings)
    assert not any(w.startswith("kt ") for w in r.warnings)


@pytest.mark.slow
def test_confidence_intervals_cover_the_truth(case):
    """1 % complex Gaussian noise (relative to the peak): truth inside the 95 % intervals in ≥ 90 % of trials."""
    model, exact, meas = case
    peak = np.abs(meas.values).max()
    hits, trials = 0, 0
    for seed in range(20):
        rng = np.random.default_rng(1000 + seed)
        noise = 0.01 * peak * (rng.standard_normal(F.size) + 1j * rng.standard_normal(F.size)) / np.sqrt(2)
        r = identify(model, FRF(F, meas.values + noise), "hybrid", seed=seed)
        inside = [lo <= t <= hi for t, (lo, hi) in zip(exact, r.ci95.values())]
        hits += sum(inside)
        trials += len(inside)
    assert hits / trials >= 0.90


def test_bounds_validation():
    assert np.allclose(Bounds.from_dict().lo, [1e6, 1.0, 1e5, 1.0])
    b = Bounds.from_dict({"kt": [1e5, 1e10]})
    assert b.lo[0] == 1e5 and b.hi[0] == 1e10
    for bad in ({"kt": [1e9, 1e6]}, {"ct": [0, 10]}, {"kr": [1, 1]}, {"zz": [1, 2]}, {"cr": "x"}):
        with pytest.raises(InputError):
            Bounds.from_dict(bad, source="a.toml")
