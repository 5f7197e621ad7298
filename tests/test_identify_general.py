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

F = np.arange(2.0, 3001.0, 2.0)
HT, TIP, NOSE = parse_point("holder_tip"), parse_point("tool_tip"), parse_point("spindle_nose")


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
    p = FRFProblem(example, joint_names("spindle_holder"), [Measured(FRF(F, fe_holder_tip), HT, HT)],
                   with_tool=False)
    assert p.fast
    with pytest.warns(IdentifiabilityWarning, match="kt and spindle_holder.kr trade off"):
        r = identify_frfs(p, "hybrid", seed=0)
    err = r.x / example.spindle_holder.as_array() - 1
    assert r.success
    assert abs(err[0]) < 1e-3 and abs(err[2]) < 1e-3  # kt, kr (measured 1.0e-5, 5.2e-5)
    assert abs(err[1]) < 1e-2 and abs(err[3]) < 1e-2  # ct, cr (measured 5.0e-4, 8.3e-4)


def test_spindle_holder_joint_noisy_kt_inside_its_interval(example, fe_holder_tip):
    """1 % complex noise (of the peak |h|): only kt is identified (ct, cr, kr are flagged, see the design
    notes); the truth is inside kt's interval for seeds 0, 1, 3, 4, 5, not for seed 2 (reported)."""
    sigma = 0.01 * np.abs(fe_holder_tip).max() / np.sqrt(2)
    rng = np.random.default_rng(0)
    noisy = fe_holder_tip + sigma * (rng.standard_normal(F.size) + 1j * rng.standard_normal(F.size))
    p = FRFProblem(example, joint_names("spindle_holder"), [Measured(FRF(F, noisy), HT, HT)], with_tool=False)
    with pytest.warns(IdentifiabilityWarning) as rec:
        r = identify_frfs(p, "hybrid", seed=0)
    assert [str(w.message) for w in rec] == list(r.warnings)
    flagged = {w.split()[0] for w in r.warnings if " trade off" not in w}
    assert "spindle_holder.kt" not in flagged
    for k, v in zip(r.names, example.spindle_holder.as_array()):
        if k not in flagged:
            lo, hi = r.ci95[k]
            assert lo <= v <= hi, (k, lo, v, hi)


def test_front_bearing_stiffness_from_a_spindle_nose_frf(example):
    h = fe_frf(example, F, NOSE, with_tool=False, max_element_m=0.5e-3)
    p = FRFProblem(example, ["bearings[1].k", "bearings[1].c"], [Measured(FRF(F, h), NOSE, NOSE)],
                   with_tool=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing to warn about
        r = identify_frfs(p, "hybrid", seed=0)
    assert r.params["bearings[1].k"] == pytest.approx(3e8, rel=1e-2)
    assert r.params["bearings[1].c"] == pytest.approx(2500.0, rel=1e-2)


def test_joint_and_bearings_together_are_reported_as_trading_off(example, fe_holder_tip):
    names = ["spindle_holder.kt", "bearings[1].k", "bearings[2].k"]
    p = FRFProblem(example, names, [Measured(FRF(F, fe_holder_tip), HT, HT)], with_tool=False)
    with pytest.warns(IdentifiabilityWarning) as rec:
        r = identify_frfs(p, "hybrid", seed=0)
    msgs = [str(w.message) for w in rec]
    assert any("bearings[1].k and bearings[2].k trade off" in m for m in msgs), msgs
    rho = r.correlation
    assert abs(rho[1, 2]) > 0.95


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
