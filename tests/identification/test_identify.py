"""Joint identification on the paper's numerical case (noise-free and noisy)."""

import dataclasses
import warnings

import numpy as np
import pytest

from toolpoint.errors import IdentifiabilityWarning, InputError
from toolpoint.frf import FRF
from toolpoint.identification.identify import IdentificationResult, identify, make_algorithm, model_for, relative_errors
from toolpoint.identification.objective import JointProblem
from toolpoint.identification.params import Bounds

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
    r = identify(model, meas, "hybrid", seed=3)  # no IdentifiabilityWarning (they are errors here)
    errs = relative_errors(r.x, exact)
    assert max(errs.values()) < 1e-4  # all four within 0.01 %
    assert r.nfev < 20000
    assert r.warnings == ()
    assert r.success and r.status == 0 and r.nit == r.optimizer.global_stage.nit
    for k, v in r.params.items():
        lo, hi = r.ci95[k]
        assert lo <= v <= hi


def test_result_is_frozen_and_forwards_the_optimiser(case):
    model, exact, meas = case
    r = identify(model, meas, "hybrid", seed=0)
    assert isinstance(r, IdentificationResult)
    assert np.allclose(10.0**r.optimizer.x, r.x, rtol=1e-14) and np.array_equal(r.x_log, r.optimizer.x)
    assert [r.params[k] for k in ("kt", "ct", "kr", "cr")] == list(r.x)
    assert (r.fun, r.nfev, r.nit, r.success, r.message) == (
        r.optimizer.fun, r.optimizer.nfev, r.optimizer.nit, r.optimizer.success, r.optimizer.message)
    assert r.history is r.optimizer.history
    assert r.method == "hybrid" and r.seed == 0 and r.bounds == Bounds.from_dict().as_dict() and r.seconds > 0
    assert np.allclose(r.model_frf.values, model.tool_point(r.x), rtol=1e-12)
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.seed = 1


def test_unknown_method_is_an_input_error(case):
    model, _, meas = case
    with pytest.raises(InputError, match="^method: unknown method 'magic'"):
        identify(model, meas, "magic")
    assert make_algorithm("GA").name == "ga"  # method names in any case, as `--method SDM` in lobes


@pytest.mark.slow
def test_same_seed_same_result(case):
    model, _, meas = case
    for method in ("ga", "pso", "sa", "de"):
        with warnings.catch_warnings():  # 30 iterations: wide intervals, not what is tested here
            warnings.simplefilter("ignore", IdentifiabilityWarning)
            a = identify(model, meas, method, seed=7, options={"maxiter": 30})
            b = identify(model, meas, method, seed=7, options={"maxiter": 30})
        assert np.array_equal(a.x, b.x) and a.nfev == b.nfev, method
        assert a.nit == 30 and not a.success and a.status == 1, method  # a capped run is not a success


def test_pso_beats_the_paper(case):
    """Paper Table 1, PSO: kt 0.3 %, ct 9.33 %, kr 49.8 %, cr 200 %."""
    # With the paper's settings PSO stops on its 280-iteration cap, not converged, and where it stops varies
    # with the seed (seeds 0–4: cr error 1e-4 … 99×). Seed 0 measured kt 1.9e-5, ct 0.029, kr 6.7e-4, cr 0.65;
    # the limits leave ×5 (kt, kr) and ×3 (ct) for other platforms; cr only beats the paper. The result must
    # say it is capped, and the profile interval must flag the undetermined cr.
    model, exact, meas = case
    with pytest.warns(IdentifiabilityWarning, match="cr"):
        r = identify(model, meas, "pso", seed=0)
    e = relative_errors(r.x, exact)
    assert e["kt"] < 1e-4 and e["ct"] < 0.09 and e["kr"] < 3.5e-3 and e["cr"] < 2.0, e
    assert not r.success and r.status == 1


def test_bad_cr_is_flagged_when_the_fit_cannot_see_it(case, example):
    """With noise the rotational damping is barely visible: say so instead of reporting it silently."""
    model, exact, meas = case
    rng = np.random.default_rng(11)
    peak = np.abs(meas.values).max()
    noise = (rng.standard_normal(F.size) + 1j * rng.standard_normal(F.size)) / np.sqrt(2)
    noisy = FRF(F, meas.values + 0.05 * peak * noise)
    with pytest.warns(IdentifiabilityWarning) as rec:
        r = identify(model, noisy, "hybrid", seed=0)
    assert any(w.startswith("cr ") for w in r.warnings)
    assert not any(w.startswith("kt ") for w in r.warnings)
    assert [str(w.message) for w in rec] == list(r.warnings)  # each emitted once, as in the result


@pytest.mark.slow
def test_confidence_intervals_cover_the_truth(case):
    """1 % complex Gaussian noise (relative to the peak): truth inside the 95 % intervals in ≥ 90 % of trials."""
    model, exact, meas = case
    peak = np.abs(meas.values).max()
    hits, trials = 0, 0
    for seed in range(20):
        rng = np.random.default_rng(1000 + seed)
        noise = 0.01 * peak * (rng.standard_normal(F.size) + 1j * rng.standard_normal(F.size)) / np.sqrt(2)
        with warnings.catch_warnings(record=True) as rec:
            warnings.simplefilter("always")
            r = identify(model, FRF(F, meas.values + noise), "hybrid", seed=seed)
        assert [str(w.message) for w in rec] == list(r.warnings)  # nothing else, each once
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
