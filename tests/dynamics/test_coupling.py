"""RCSA against a full-assembly FE model, the rigid-joint limit and the 0 Hz point."""

import numpy as np
import pytest

from toolpoint.dynamics.assembly import Component, Material, Segment
from toolpoint.dynamics.components import end_receptances
from toolpoint.dynamics.coupling import couple
from toolpoint.dynamics.fe import FEModel, tool_point_fe
from toolpoint.dynamics.model import AssemblyModel

F = np.arange(0.0, 3001.0)


@pytest.fixture(scope="module")
def rcsa(example):
    return AssemblyModel(example, F).tool_point_frf()


@pytest.fixture(scope="module")
def fe_fine(example):
    return tool_point_fe(example, F, max_element_m=0.1e-3)


@pytest.mark.slow
def test_rcsa_equals_full_assembly_fe(rcsa, fe_fine):
    """The paper's check (ANSYS BEAM188 + COMBIN14), here with our own FE: 1e-6 relative norm."""
    err = np.linalg.norm(rcsa.values - fe_fine) / np.linalg.norm(fe_fine)
    assert err < 1e-6
    assert np.all(np.isfinite(rcsa.values)) and rcsa.freq_hz[0] == 0


@pytest.mark.slow
def test_fe_converges_to_rcsa(example, rcsa):
    """FE error falls like h² towards the exact RCSA; Richardson-extrapolated it agrees to ~1e-8."""
    h1 = tool_point_fe(example, F, 1.0e-3)
    h2 = tool_point_fe(example, F, 0.5e-3)
    e1 = np.linalg.norm(rcsa.values - h1)
    e2 = np.linalg.norm(rcsa.values - h2)
    assert 3.5 < e1 / e2 < 4.5
    richardson = (4 * h2 - h1) / 3
    assert np.linalg.norm(rcsa.values - richardson) / np.linalg.norm(richardson) < 1e-7


@pytest.mark.slow
def test_static_point_is_the_assembly_compliance(rcsa, fe_fine):
    """0 Hz: the static compliance of the grounded assembly, continuous with 1 Hz."""
    assert rcsa.values[0].imag == 0
    assert rcsa.values[0] == pytest.approx(fe_fine[0], rel=1e-9)
    assert abs(rcsa.values[1] - rcsa.values[0]) < 1e-5 * abs(rcsa.values[0])


def test_with_structural_damping_against_fe(example):
    """Complex modulus E(1 + iη) in every part: RCSA still equals FE."""
    from dataclasses import replace

    def damp(c):
        segs = tuple(replace(s, material=replace(s.material, loss_factor=0.02)) for s in c.segments)
        return replace(c, segments=segs)

    a = replace(example, spindle=damp(example.spindle), holder=damp(example.holder), tool=damp(example.tool))
    f = np.arange(1.0, 3001.0, 10.0)
    h = AssemblyModel(a, f).tool_point_frf().values
    fe = tool_point_fe(a, f, 0.1e-3)
    assert np.linalg.norm(h - fe) / np.linalg.norm(fe) < 1e-6


def test_rigid_joint_gives_the_one_piece_beam():
    steel = Material("steel", 210e9, 7800.0, 0.3)
    s1 = (Segment(0.08, 0.04, 0.0, steel), Segment(0.03, 0.03, 0.0, steel))
    s2 = (Segment(0.05, 0.016, 0.0, steel),)
    f = np.linspace(5.0, 6000.0, 300)
    w = 2 * np.pi * f
    A = end_receptances(Component("a", s1), f)
    B = end_receptances(Component("b", s2), f)
    whole = end_receptances(Component("ab", s1 + s2), f)[:, 2:, 2:]
    # B joined to A's free end through an (almost) rigid joint → tip receptance of the one-piece beam
    for k in (1e14, np.inf):
        tip = couple(B, A[:, 2:, 2:], [k, 0.0, k, 0.0], w)
        err = np.abs(tip - whole).max() / np.abs(whole).max()
        assert err < (1e-6 if np.isfinite(k) else 1e-9)


def test_batched_coupler_equals_matrix_coupling(example):
    m = AssemblyModel(example, np.arange(1.0, 3001.0, 7.0))
    rng = np.random.default_rng(1)
    P = example.holder_tool.as_array() * rng.uniform(0.3, 3.0, (37, 4))
    h = m.tool_point(P)
    for p, hp in zip(P[:5], h[:5]):
        ref = couple(m.T, m.SH, p, m.omega)[:, 0, 0]
        # at 1 Hz the tool's rigid-body receptance (~1 m/N) cancels down to h ~ 1e-7 m/N,
        # so both routes carry ~ε·|T|/|h| ≈ 1e-9 there; elsewhere they agree to round-off
        assert np.all(np.abs(hp - ref) <= 1e-8 * np.abs(ref))
        assert np.linalg.norm(hp - ref) <= 1e-10 * np.linalg.norm(ref)
    # rigid limit of the rational expression
    assert np.allclose(m.coupler.rigid(), m.tool_point([1e16, 0, 1e16, 0]), rtol=1e-6)


def test_coupler_jacobian_matches_finite_differences(example):
    m = AssemblyModel(example, np.arange(10.0, 3001.0, 10.0))
    p = example.holder_tool.as_array()
    J = m.coupler.jacobian(p[None])[0]
    for i in range(4):
        dp = np.zeros(4)
        dp[i] = 1e-4 * p[i]  # central differences: truncation ~1e-8, round-off well below
        fd = (m.tool_point(p + dp) - m.tool_point(p - dp)) / (2 * dp[i])
        assert np.linalg.norm(J[i] - fd) < 1e-5 * np.linalg.norm(fd)


def test_free_assembly_drops_zero_hz_with_a_warning(example):
    from dataclasses import replace

    free = replace(example, spindle=replace(example.spindle, bearings=()))
    with pytest.warns(UserWarning, match="0 Hz dropped"):
        frf = AssemblyModel(free, np.arange(0.0, 50.0)).tool_point_frf()
    assert frf.freq_hz[0] == 1.0 and np.all(np.isfinite(frf.values))


def test_spindle_holder_point_against_fe(example):
    f = np.arange(0.0, 3001.0, 5.0)
    sh = AssemblyModel(example, f).spindle_holder_frf().values
    fe = FEModel([example.spindle, example.holder], [example.spindle_holder.as_array()], 0.1e-3)
    ref = fe.receptance(f, int(fe.last_dof[-1]))
    assert np.linalg.norm(sh - ref) / np.linalg.norm(ref) < 1e-6
