"""General identification (issue 14): receptances at named points, the spindle–holder joint and the
bearings from FE "measurements" (:mod:`toolpoint.dynamics.fe`, a different discretisation: no inverse crime)."""

import warnings

import numpy as np
import pytest

from toolpoint.dynamics.model import AssemblyModel
from toolpoint.dynamics.points import ReceptanceModel, fe_frf, parse_point
from toolpoint.dynamics.subassembly import Subassembly
from toolpoint.errors import IdentifiabilityWarning, InputError
from toolpoint.frf import FRF
from toolpoint.identification.problem import FRFProblem, Measured, identify_frfs, joint_names
from toolpoint.identification.uncertainty import intervals_and_correlation

F = np.arange(2.0, 3001.0, 2.0)
HT, TIP, NOSE = parse_point("holder_tip"), parse_point("tool_tip"), parse_point("spindle_nose")
FAR = np.array([5.0, 0.2, 5.0, 0.2])  # the example file's values are the truth: start the searches away from it


def far_start(example, names):
    """Start values a factor 5 off the truth (the file's values), per parameter name."""
    out = {}
    for n in names:
        e, k = n.split(".")
        el = example.spindle_holder if e == "spindle_holder" else example.spindle.bearings[int(e[9:-1])]
        slot = ("kt", "ct", "kr", "cr").index(k) if e == "spindle_holder" else ("k", "c", "kr", "cr").index(k)
        out[n] = (el.as_array() if e == "spindle_holder" else np.array([el.k, el.c, el.kr, el.cr]))[slot] * FAR[slot]
    return out


@pytest.fixture(scope="module")
def fe_holder_tip(example):
    return fe_frf(example, F, HT, with_tool=False, max_element_m=0.5e-3)


def test_point_receptances_match_the_existing_couplings(example):
    f = F[::10]
    m = ReceptanceModel(example, f, [TIP, HT], ["holder_tool", "spindle_holder"])
    v = np.stack([example.holder_tool.as_array(), example.spindle_holder.as_array()])[None]
    ref = AssemblyModel(example, f).tool_point(example.holder_tool.as_array())
    assert np.max(abs(m.frf(v, TIP, TIP)[0] / ref - 1)) < 1e-7
    sub = Subassembly.from_assembly(example, f).R[:, 0, 0]
    m2 = ReceptanceModel(example, f, [HT], ["spindle_holder"], with_tool=False)
    c = m2.coupler(HT, HT)
    assert np.max(abs(c(example.spindle_holder.as_array()) / sub - 1)) < 1e-7


@pytest.mark.parametrize("resp, force, tool", [("tool:x_mm=40", "holder_tip", True),
                                               ("spindle:x_mm=370", "spindle_nose", False)])
def test_cross_and_interior_points_match_the_fe_model(example, resp, force, tool):
    f = F[::25]
    i, j = parse_point(resp), parse_point(force)
    m = ReceptanceModel(example, f, [i, j], [], with_tool=tool)
    g = m.G0[:, m.dof(i), m.dof(j)]
    h = fe_frf(example, f, i, j, with_tool=tool, max_element_m=0.5e-3)
    assert np.max(abs(h - g)) / np.max(abs(g)) < 2e-4  # h² discretisation error of the FE model


def test_exact_jacobian_of_the_general_path(example):
    f = F[::20]
    names = ["spindle_holder.kt", "spindle_holder.cr", "bearings[1].k", "bearings[2].c"]
    m = ReceptanceModel(example, f, [NOSE], [], with_tool=False)
    meas = Measured(FRF(f, m.G0[:, m.dof(NOSE), m.dof(NOSE)] * 1.01), NOSE, NOSE)
    p = FRFProblem(example, names, [meas], with_tool=False)
    assert not p.fast
    x = np.log10([4e8, 60.0, 2.5e8, 2000.0])
    J = p.jacobian(x)
    for k in range(4):
        e = np.zeros(4)
        e[k] = 1e-5
        fd = (p.residuals(x + e) - p.residuals(x - e)) / 2e-5
        assert np.max(abs(fd - J[:, k])) < 1e-5 * np.max(abs(J[:, k])) + 1e-12, names[k]


def test_spindle_holder_joint_from_a_noise_free_fe_holder_tip_frf(example, fe_holder_tip):
    names = joint_names("spindle_holder")
    p = FRFProblem(example, names, [Measured(FRF(F, fe_holder_tip), HT, HT)], start=far_start(example, names),
                   with_tool=False)
    assert p.fast
    with pytest.warns(IdentifiabilityWarning, match="kt and spindle_holder.kr trade off"):
        r = identify_frfs(p, "hybrid", seed=0)
    err = r.x / example.spindle_holder.as_array() - 1
    assert r.success
    assert abs(err[0]) < 1e-3 and abs(err[2]) < 1e-3  # kt, kr (measured 1.0e-5, 5.2e-5)
    assert abs(err[1]) < 1e-2 and abs(err[3]) < 1e-2  # ct, cr (measured 5.0e-4, 8.3e-4)
    # the misfit is small enough for the fit to be linear across the intervals: the profile-likelihood
    # intervals are the linearised ones (both exclude the truth here: the FE discretisation bias is model
    # error, not noise, see the design notes)
    lin, se, _ = intervals_and_correlation(p, r.x_log)
    got = np.log10([r.ci95[k] for k in names])
    half = np.log10(lin[:, 1] / lin[:, 0]) / 2
    assert np.all(abs(got - np.log10(lin)) < 0.01 * half[:, None])


def noisy_holder_tip(fe_holder_tip, seed):
    """1 % complex noise: σ per real component = 1 % of the peak |h| / √2."""
    sigma = 0.01 * np.abs(fe_holder_tip).max() / np.sqrt(2)
    rng = np.random.default_rng(seed)
    return fe_holder_tip + sigma * (rng.standard_normal(F.size) + 1j * rng.standard_normal(F.size))


def test_spindle_holder_joint_noisy_truth_inside_every_profile_interval(example, fe_holder_tip):
    """1 % complex noise (seed 0): kt is identified; ct, cr and kr are not (flagged, and their intervals
    run into search bounds), but the truth is inside all four 95 % profile intervals. Over seeds 0–39
    155 of 160 intervals hold the truth (``benchmarks/bench_identify_general.py --coverage``)."""
    names = joint_names("spindle_holder")
    p = FRFProblem(example, names, [Measured(FRF(F, noisy_holder_tip(fe_holder_tip, 0)), HT, HT)],
                   start=far_start(example, names), with_tool=False)
    with pytest.warns(IdentifiabilityWarning) as rec:
        r = identify_frfs(p, "hybrid", seed=0)
    assert [str(w.message) for w in rec] == list(r.warnings)
    flagged = {w.split()[0] for w in r.warnings if "is not identifiable" in w}
    assert flagged == {"spindle_holder.ct", "spindle_holder.kr", "spindle_holder.cr"}
    assert any(w.startswith("spindle_holder.ct has a 95 % interval that runs into the lower search bound")
               for w in r.warnings)
    for k, v in zip(r.names, example.spindle_holder.as_array()):
        lo, hi = r.ci95[k]
        assert lo <= v <= hi, (k, lo, v, hi)
    # the linearised interval of kt, at the same optimum, misses the truth for seed 2 (the profile's too:
    # seeds 2 and 39 of 0–39 are the 5 % — see the design notes)


def test_profile_interval_ends_are_where_an_independent_profile_crosses_the_threshold(example, fe_holder_tip):
    """Two parameters that trade off (kt, kr; ct, cr fixed at the truth): at each reported end of kt's
    interval the profile, recomputed by a bounded scalar minimisation of the objective over kr (not least
    squares, not the Jacobian), rises by t² s² above the minimum."""
    from scipy.optimize import minimize_scalar

    from toolpoint.identification.params import ci_quantile
    from toolpoint.identification.uncertainty import profile_intervals

    f = F[::3]
    h = noisy_holder_tip(fe_holder_tip, 1)[::3]
    p = FRFProblem(example, ["spindle_holder.kt", "spindle_holder.kr"], [Measured(FRF(f, h), HT, HT)],
                   with_tool=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)  # kr is not identifiable
        r = identify_frfs(p, "hybrid", seed=0, intervals="linear")
    S0 = p.evaluate(r.x_log) ** 2
    dof = 2 * f.size - 2
    thr = S0 * (1 + ci_quantile(dof) ** 2 / dof)
    prof = profile_intervals(p, r.x_log, np.array(list(r.se_log10.values())))
    assert not prof.open_end[0].any() and prof.x_better is None

    def profile(x_kt):
        res = minimize_scalar(lambda x_kr: p.evaluate(np.array([x_kt, x_kr])) ** 2, bounds=(p.xl[1], p.xu[1]),
                              method="bounded", options={"xatol": 1e-9})
        return res.fun

    for end in np.log10(prof.ci[0]):
        assert profile(end) == pytest.approx(thr, rel=1e-6)
    lo, hi = np.log10(prof.ci[0])
    assert profile(lo + 1e-3) < thr and profile(hi - 1e-3) < thr
    assert profile(lo - 1e-3) > thr and profile(hi + 1e-3) > thr


def test_a_start_next_to_the_truth_needs_fewer_evaluations(example, fe_holder_tip):
    names = joint_names("spindle_holder")
    meas = [Measured(FRF(F, fe_holder_tip), HT, HT)]
    truth = example.spindle_holder.as_array()
    runs = {}
    for label, start, opts in [("global", far_start(example, names), None),
                               ("far", far_start(example, names), {"use_start": "local"}),
                               ("near", dict(zip(names, truth * 1.02)), {"use_start": "local"})]:
        p = FRFProblem(example, names, meas, start=start, with_tool=False)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", IdentifiabilityWarning)
            r = identify_frfs(p, "hybrid", seed=0, options=opts, intervals="linear")
        assert r.success
        assert np.max(abs(r.x / truth - 1)) < 1e-2, label
        runs[label] = r.nfev
    assert runs["near"] < runs["far"] < runs["global"] / 10, runs  # measured 37, 71, 1793
    # the population methods put one member at the start: the first generation is at least that good
    p = FRFProblem(example, names, meas, start=dict(zip(names, truth * 1.02)), with_tool=False)
    for method in ("ga", "pso", "sa", "de"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", IdentifiabilityWarning)  # 3 iterations do not identify the joint
            r = identify_frfs(p, method, seed=0, options={"maxiter": 3}, intervals="linear")
        assert r.history[0] <= p.evaluate(np.log10(truth * 1.02)) * (1 + 1e-12), method  # unit-cube round-off


def test_a_start_outside_the_bounds_is_refused(example, fe_holder_tip):
    names = joint_names("spindle_holder")
    meas = [Measured(FRF(F[::50], fe_holder_tip[::50]), HT, HT)]
    with pytest.raises(InputError) as e:
        FRFProblem(example, names, meas, start={"spindle_holder.kt": 1e12}, with_tool=False)
    assert e.value.field == "identify.start.spindle_holder.kt" and "outside its search bounds" in str(e.value)
    with pytest.raises(InputError, match="unknown parameter 'bearings.k'"):
        FRFProblem(example, names, meas, start={"bearings.k": 1e8}, with_tool=False)


@pytest.mark.parametrize("names", [
    ["spindle_holder.kt", "bearings[1].k", "bearings[2].k"],  # 4 spring DOFs
    ["spindle_holder.kt", "spindle_holder.cr", "bearings[0].c", "bearings[1].k", "bearings[1].kr"],  # 6
])
def test_the_polynomial_form_equals_the_woodbury_solves(example, names):
    """Populations on the general path are evaluated in the polynomial form (ReceptanceModel.minors); the
    Woodbury solves of the same receptances give the same objective. Two FRFs on the same grid, weighted."""
    f = F[::15]
    m = ReceptanceModel(example, f, [HT, NOSE], [], with_tool=False)
    meas = [Measured(FRF(f, m.G0[:, m.dof(HT), m.dof(HT)] * 1.05), HT, HT),
            Measured(FRF(f, m.G0[:, m.dof(NOSE), m.dof(HT)] * 0.95), NOSE, HT, weight=3.0)]
    p = FRFProblem(example, names, meas, start={"bearings[1].kr": 1e6} if "bearings[1].kr" in names else None,
                   with_tool=False)
    assert p._poly is not None
    X = p.xl + np.random.default_rng(0).random((60, p.n_var)) * (p.xu - p.xl)
    X[0] = p.x_start
    fp = p.evaluate(X)
    p._poly = None
    fw = p.evaluate(X)
    assert np.max(abs(fp / fw - 1)) < 1e-9
    r = p.residuals(X[0])
    assert fw[0] == pytest.approx(np.linalg.norm(r) * p.residual_scale, rel=1e-12)


def test_front_bearing_stiffness_from_a_spindle_nose_frf(example):
    h = fe_frf(example, F, NOSE, with_tool=False, max_element_m=0.5e-3)
    names = ["bearings[1].k", "bearings[1].c"]
    p = FRFProblem(example, names, [Measured(FRF(F, h), NOSE, NOSE)], start=far_start(example, names),
                   with_tool=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing to warn about
        r = identify_frfs(p, "hybrid", seed=0)
    assert r.params["bearings[1].k"] == pytest.approx(3e8, rel=1e-2)
    assert r.params["bearings[1].c"] == pytest.approx(2500.0, rel=1e-2)


@pytest.mark.slow
def test_joint_and_bearings_together_are_reported_as_trading_off(example, fe_holder_tip):
    """Exactly the pairs whose log10 estimates correlate with |ρ| > 0.95 are reported, ρ recomputed here
    from a central-difference Jacobian: the two front bearings trade off (ρ = −0.965), the joint's kt with
    neither (0.24, −0.41)."""
    names = ["spindle_holder.kt", "bearings[1].k", "bearings[2].k"]
    p = FRFProblem(example, names, [Measured(FRF(F, fe_holder_tip), HT, HT)], start=far_start(example, names),
                   with_tool=False)
    with pytest.warns(IdentifiabilityWarning) as rec:
        r = identify_frfs(p, "hybrid", seed=0)
    assert np.max(abs(r.x / [5e8, 3e8, 3e8] - 1)) < 1e-4
    J = np.stack([(p.residuals(r.x_log + e) - p.residuals(r.x_log - e)) / 2e-6 for e in np.eye(3) * 1e-6], 1)
    cov = np.linalg.inv(J.T @ J)
    rho = cov / np.sqrt(np.outer(np.diag(cov), np.diag(cov)))
    assert np.allclose(r.correlation, rho, atol=1e-4)
    reported = {tuple(m.split(" trade off")[0].split(" and ")) for m in map(str, (w.message for w in rec))
                if " trade off" in m}
    expected = {(names[i], names[j]) for i in range(3) for j in range(i + 1, 3) if abs(rho[i, j]) > 0.95}
    assert reported == expected == {("bearings[1].k", "bearings[2].k")}


@pytest.mark.parametrize("kw, field", [
    (dict(params=["spindle_holder.kx"]), "params"),
    (dict(params=["bearings[7].k"]), "params"),
    (dict(at="holder:x_mm=500"), "at"),
    (dict(at="tool_tip"), "at"),
    (dict(bounds={"kt": [1e9, 1e10]}), "joints.spindle_holder.kt"),
])
def test_bad_input_is_one_line(example, kw, field):
    from toolpoint.identification.problem import param_bounds, parse_params

    f = F[::50]
    pt = parse_point(kw.get("at", "holder_tip"))
    names = kw.get("params", joint_names("spindle_holder"))
    with pytest.raises(InputError) as e:
        b = param_bounds(parse_params(names, example), kw.get("bounds"))
        FRFProblem(example, names, [Measured(FRF(f, np.ones(f.size) * 1e-8), pt, pt)], b, with_tool=False)
    assert e.value.field == field and "\n" not in str(e.value)


def test_profiling_reports_a_better_point_only_when_it_matters():
    """x_better: set when the search stopped short of the minimum (by more than the profile's resolution),
    None when the start is the minimum up to round-off. A linear least-squares problem, minimum in closed form."""
    from toolpoint.identification.uncertainty import profile_intervals

    class P:
        xl, xu, nfev = np.array([-5.0, -5.0]), np.array([5.0, 5.0]), 0
        t = np.linspace(0, 1, 40)
        A = np.c_[t, np.ones_like(t)]
        y = 2.0 * t + 0.5 + 0.05 * np.sin(37 * t)

        def residuals(self, x):
            return self.A @ x - self.y

        def jacobian(self, x):
            return self.A

    p = P()
    x_min = np.linalg.lstsq(p.A, p.y, rcond=None)[0]
    assert profile_intervals(p, x_min * (1 + 1e-9)).x_better is None  # round-off away from the minimum
    far = profile_intervals(p, x_min + np.array([0.05, 0.0]))  # well off it: profiling meets the minimum
    assert far.x_better is not None and np.allclose(far.x_better, x_min, atol=1e-3)
