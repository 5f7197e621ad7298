"""Semi-discretisation of state-space tool-point models: complex modes, cross terms, the seeded search."""

import numpy as np
import pytest

import toolpoint.stability.sdm as sdm_mod
from toolpoint.errors import InputError
from toolpoint.frf import FRF
from toolpoint.stability import (
    CuttingConditions,
    ModalModel,
    StateSpaceModel,
    average_directional_matrix,
    from_modal_fit,
    sdm_lobes,
    zoa_lobes,
)

MODE = ModalModel([922.0], [0.011], [0.03993])
U = ModalModel([600.0, 1500.0], [0.02, 0.015], [0.5, 0.2])  # principal axis u
V = ModalModel([700.0], [0.025], [0.4])  # principal axis v


def cut(ri, milling="down", teeth=2, kr=1 / 3):
    return CuttingConditions(teeth=teeth, tangential_coeff=6e8, radial_ratio=kr, radial_immersion=ri, milling=milling)


def rotated_by_poles(theta):
    """The orthotropic tool U/V with principal axes turned by theta, built from poles and residue matrices
    R_r = ψψᵀ/(2iω_d m), ψ the mode's direction — independent of StateSpaceModel.rotated."""
    poles, res = [], []
    for mm, psi in ((U, (np.cos(theta), np.sin(theta))), (V, (-np.sin(theta), np.cos(theta)))):
        psi = np.array(psi)
        for wn, ze, m in zip(mm.omega_n, mm.zeta, mm.mass_kg):
            wd = wn * np.sqrt(1 - ze**2)
            poles.append(complex(-ze * wn, wd))
            res.append(np.outer(psi, psi) / (2j * wd * m))
    return StateSpaceModel.from_poles(poles, np.array(res))


def test_state_space_frf_matches_closed_forms():
    f = np.linspace(10.0, 2500.0, 400)
    ss = StateSpaceModel.from_modes(U, V)
    phi = ss.frf(f)
    assert phi[:, 0, 0] == pytest.approx(U.frf(f, residuals=False).values, rel=1e-10)
    assert phi[:, 1, 1] == pytest.approx(V.frf(f, residuals=False).values, rel=1e-10)
    assert np.all(phi[:, 0, 1] == 0) and np.all(phi[:, 1, 0] == 0)
    th = 0.61
    a, b = ss.rotated(th).frf(f), rotated_by_poles(th).frf(f)
    assert a == pytest.approx(b, rel=1e-9, abs=1e-9 * np.abs(a).max())
    c, s = np.cos(th), np.sin(th)
    # Φ_xy = Φ_yx = cs(Φ_u − Φ_v) for principal axes turned by θ.
    assert a[:, 0, 1] == pytest.approx(c * s * (phi[:, 0, 0] - phi[:, 1, 1]), rel=1e-9, abs=1e-9 * np.abs(a).max())


def test_complex_pole_form_gives_the_same_lobes_as_real_modes():
    rpm = np.array([9000.0, 15000.0])
    a = sdm_lobes(U, V, cut(0.3), rpm=rpm, rtol=1e-7)
    b = sdm_lobes(rotated_by_poles(0.0), cutting=cut(0.3), rpm=rpm, rtol=1e-7)
    assert b.depth_m == pytest.approx(a.depth_m, rel=1e-5)


def test_cross_terms_reproduce_zero_order_with_averaged_directional_matrix(monkeypatch):
    """Slotting with 3 teeth (a tooth always cuts), H(t) replaced by its average H₀: the cut is
    time-invariant, the zero-order solution (independent code, cross receptances in its 2×2 eigenvalues)
    is exact: the SDM of
    the rotated orthotropic tool, cross terms included, must converge to it."""

    def averaged(edges, teeth, kt, kr, st, ex):
        return np.repeat(average_directional_matrix(teeth, kt, kr, st, ex)[None], len(edges) - 1, axis=0)

    monkeypatch.setattr(sdm_mod, "interval_directional_matrix", averaged)
    ss = rotated_by_poles(np.deg2rad(35.0))
    rpm = np.array([8000.0, 11000.0, 17000.0])
    f = np.linspace(1.0, 3000.0, 200000)
    phi = ss.frf(f)
    fr = {k: FRF(f, phi[:, i, j]) for k, (i, j) in dict(x=(0, 0), y=(1, 1), xy=(0, 1), yx=(1, 0)).items()}
    c = cut(1.0, teeth=3, kr=0.3)
    zoa = zoa_lobes(fr["x"], fr["y"], c, rpm=rpm, frf_xy=fr["xy"], frf_yx=fr["yx"])
    no_cross = zoa_lobes(fr["x"], fr["y"], c, rpm=rpm)
    res = sdm_lobes(ss, cutting=c, rpm=rpm, m=120, rtol=1e-6)
    assert res.depth_m == pytest.approx(zoa.depth_m, rel=0.005)
    # In slotting H₀ commutes with rotations: the principal-frame lobes are the same.
    principal = sdm_lobes(rotated_by_poles(0.0), cutting=c, rpm=rpm, m=120, rtol=1e-6)
    assert res.depth_m == pytest.approx(principal.depth_m, rel=1e-4)
    assert np.max(np.abs(no_cross.depth_m / zoa.depth_m - 1)) > 0.05  # the cross terms matter here


def test_rotation_by_pi_leaves_lobes_unchanged():
    """Turning the structure by 180° maps (x, y) → (−x, −y): Φ and the lobes are the same."""
    rpm = np.array([9000.0, 14000.0])
    a = sdm_lobes(rotated_by_poles(0.4), cutting=cut(0.5), rpm=rpm, rtol=1e-7)
    b = sdm_lobes(rotated_by_poles(0.4 + np.pi), cutting=cut(0.5), rpm=rpm, rtol=1e-7)
    assert b.depth_m == pytest.approx(a.depth_m, rel=1e-6)


@pytest.mark.parametrize("milling", ["down", "up"])
def test_seeded_search_finds_the_same_limit_as_the_full_search(milling):
    """Low immersion (flip lobes, SDM far from the zero-order limit): the search seeded at half
    the zero-order limit against the plain upward search from depth_min, same discretisation."""
    rpm = np.linspace(5000.0, 25000.0, 40)
    a = sdm_lobes(MODE, None, cut(0.05, milling), rpm=rpm, rtol=1e-4)
    b = sdm_lobes(MODE, None, cut(0.05, milling), rpm=rpm, rtol=1e-4, seed=False)
    # Never above the full search; below it only where the full search stepped over a thin unstable band.
    assert np.all(a.depth_m <= b.depth_m * (1 + 2e-4))
    assert np.mean(np.abs(a.depth_m / b.depth_m - 1) < 2e-4) >= 0.75
    assert a.params["evaluations"] < b.params["evaluations"]


def test_progress_callback_counts_every_speed():
    seen = []
    sdm_lobes(MODE, None, cut(0.05), rpm=np.linspace(9000.0, 10000.0, 7), progress=lambda k, n: seen.append((k, n)))
    assert seen[-1] == (7, 7)


def test_adapter_from_common_pole_fit():
    from toolpoint.dynamics.modal import fit_modal

    f = np.arange(50.0, 3000.0, 2.0)
    true = StateSpaceModel.from_modes(U, None)
    fit = fit_modal(f, true.frf(f)[:, :1, 0])
    ss = from_modal_fit(fit)
    fc = np.linspace(100.0, 2500.0, 50)
    assert ss.frf(fc)[:, 0, 0] == pytest.approx(true.frf(fc)[:, 0, 0], rel=1e-6)
    assert ss.frf(fc)[:, 1, 1] == pytest.approx(true.frf(fc)[:, 0, 0], rel=1e-6)  # symmetric tool


@pytest.mark.parametrize(
    "kw",
    [
        dict(A=[[0.0, 1.0], [-1.0, 0.0]], B=[[0, 0], [1, 0]], C=[[1, 0], [0, 0]]),  # undamped
        dict(A=[[-1.0]], B=[[1.0, 0.0]], C=[[1.0, 0.0]]),  # C wrong shape
        dict(A=[[-1.0]], B=[[0.0, 0.0]], C=[[1.0], [0.0]]),  # nothing excites it
        dict(A=[[np.nan]], B=[[1.0, 0.0]], C=[[1.0], [0.0]]),
    ],
)
def test_bad_state_space(kw):
    with pytest.raises(InputError):
        StateSpaceModel(**kw)


def test_bad_accuracy_and_both_models():
    with pytest.raises(InputError, match="accuracy"):
        sdm_lobes(MODE, None, cut(0.5), rpm=[9000.0], accuracy=0.0)
    with pytest.raises(InputError, match="modes_y"):
        sdm_lobes(StateSpaceModel.from_modes(MODE, None), MODE, cut(0.5), rpm=[9000.0])


def test_adapter_from_common_pole_fits_with_cross_receptances():
    """Columns of the rotated orthotropic tool fitted per force (Φ_xx, Φ_yx | Φ_yy, Φ_xy): the realisation
    reproduces the whole 2×2 receptance of the exact model, cross terms included."""
    from toolpoint.dynamics.modal import fit_frfs

    exact = rotated_by_poles(np.deg2rad(35.0))
    f = np.arange(1.0, 3000.0, 1.0)
    phi = exact.frf(f)
    fx = fit_frfs([FRF(f, phi[:, 0, 0]), FRF(f, phi[:, 1, 0])])
    fy = fit_frfs([FRF(f, phi[:, 1, 1]), FRF(f, phi[:, 0, 1])])
    ss = from_modal_fit(fx, fy)
    fc = np.linspace(100.0, 2500.0, 60)
    ref = exact.frf(fc)
    assert ss.frf(fc) == pytest.approx(ref, rel=1e-6, abs=1e-6 * np.abs(ref).max())
    assert np.abs(ref[:, 0, 1]).max() > 0.1 * np.abs(ref).max()  # the cross terms are not negligible


def test_modal_model_validation():
    with pytest.raises(InputError):
        ModalModel([100.0, 200.0], [0.01], [1.0, 1.0])
    with pytest.raises(InputError):
        ModalModel([-100.0], [0.01], [1.0])
    with pytest.raises(InputError):
        ModalModel([100.0], [0.01], [0.0])


def test_lobes_sdm_path_recovers_a_close_pair_of_complex_modes():
    """Noise-free 5 modes, non-proportional damping (modal constants with a phase), a close pair
    1482 / 1622 Hz. A real-mode fit cannot represent it (the former ``stability.fit_modes`` put the 1482 Hz
    mode at 1495 Hz, ζ 2.66 % instead of 2.84 %); the SDM path of ``toolpoint lobes``
    (``dynamics.modal.fit_frfs`` → ``from_modal_fit``) must recover every pole within 0.1 % in f_n and 2 % in ζ."""
    from toolpoint.stability.measured import _fit_one

    fn = np.array([650.0, 1050.0, 1482.0, 1622.0, 2350.0])
    ze = np.array([0.025, 0.02, 0.0284, 0.021, 0.015])
    mass = np.array([0.5, 0.3, 0.12, 0.15, 0.25])
    wn = 2 * np.pi * fn
    wd = wn * np.sqrt(1 - ze**2)
    res = np.zeros((5, 2, 2), complex)
    res[:, 0, 0] = np.exp(1j * np.deg2rad([5.0, -10.0, 20.0, -25.0, 8.0])) / (2j * wd * mass)
    true = StateSpaceModel.from_poles(-ze * wn + 1j * wd, res)
    f = np.arange(0.0, 3000.5, 1.0)
    frf = FRF(f, true.frf(f)[:, 0, 0])

    model = from_modal_fit(_fit_one(frf, "FRF", "x.csv", None, None))
    lam = model.poles[model.poles.imag > 0]
    lam = np.unique(np.round(lam, 6))  # x and y realisations (symmetric tool) share the poles
    lam = lam[np.argsort(np.abs(lam))]
    assert lam.size == 5
    assert np.abs(lam) / (2 * np.pi) == pytest.approx(fn, rel=1e-3)
    assert -lam.real / np.abs(lam) == pytest.approx(ze, rel=0.02)
    fc = np.linspace(100.0, 2900.0, 200)
    assert model.frf(fc)[:, 0, 0] == pytest.approx(true.frf(fc)[:, 0, 0], rel=1e-6)
