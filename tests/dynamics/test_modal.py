"""Common-pole modal fit (toolpoint.dynamics.modal) against independent non-proportionally damped systems.

Exact FRFs and poles come from M, C, K (tests/modal_systems.py): a direct solve per
frequency and the state-space eigenvalues, not from the fitted model.
"""

import numpy as np
import pytest

from modal_systems import FIVE, FOUR, add_noise
from toolpoint.dynamics.modal import fit_frfs, fit_modal
from toolpoint.errors import InputError
from toolpoint.frf import FRF

F = np.arange(1.0, 3001.0)
BAND = (100.0, 3000.0)


def check_modes(fit, system, rel_f, rel_z):
    fn, ze = system.poles()
    assert fit.n_modes == fn.size  # no spurious mode, none lost
    assert fit.fn_hz == pytest.approx(fn, rel=rel_f)
    assert fit.zeta == pytest.approx(ze, rel=rel_z)
    assert np.all((fit.fn_hz >= fit.band_hz[0]) & (fit.fn_hz <= fit.band_hz[1]))


@pytest.mark.parametrize("system", [FOUR, FIVE], ids=["4-mode", "5-mode"])
def test_noise_free_complex_modes_are_exact(system):
    fit = fit_modal(F, system.frf(F, "accelerance"), quantity="accelerance", band=BAND)
    check_modes(fit, system, 1e-7, 1e-5)
    fb = F[F >= BAND[0]]
    H = system.receptance(fb)
    assert np.abs(fit(fb) - H).max() < 1e-7 * np.abs(H).max()
    A, B, C = fit.state_space()  # the real state-space form reproduces the modes
    s = 2j * np.pi * 777.0
    h = (C @ np.linalg.solve(s * np.eye(A.shape[0]) - A, B))[:, 0]
    assert h == pytest.approx(system.receptance([777.0])[0], rel=1e-6)


@pytest.mark.parametrize("system", [FOUR, FIVE], ids=["4-mode", "5-mode"])
def test_accelerance_noise_fitted_in_accelerance(system):
    """0.5 % noise white in accelerance: frequencies to 0.05 %, damping to 5 %, receptance error ≪ noise."""
    Y = add_noise(system.frf(F, "accelerance"), 0.005, seed=7)
    fit = fit_modal(F, Y, quantity="accelerance", band=BAND)
    check_modes(fit, system, 5e-4, 0.05)
    fb = F[F >= BAND[0]]
    H = system.receptance(fb)
    err = np.linalg.norm(fit(fb) - H, axis=0) / np.linalg.norm(H, axis=0)
    assert np.all(err < 0.01)


def test_receptance_noise_fitted_in_receptance():
    Y = add_noise(FOUR.frf(F, "receptance"), 0.005, seed=7)
    fit = fit_modal(F, Y, band=BAND)
    check_modes(fit, FOUR, 5e-4, 0.05)


def test_close_pair_is_recovered():
    """1482 / 1622 Hz, noise-free: a real-mode fit put 1482 Hz at 1467.6 Hz; complex modes are exact."""
    fit = fit_modal(F, FIVE.frf(F, "receptance"), band=BAND)
    fn, ze = FIVE.poles()
    assert fn[1] == pytest.approx(1482.0, rel=1e-3) and fn[2] == pytest.approx(1622.0, rel=1e-3)
    check_modes(fit, FIVE, 5e-4, 0.05)


def test_same_data_same_fit():
    Y = add_noise(FOUR.frf(F, "accelerance"), 0.005, seed=1)
    a = fit_modal(F, Y, quantity="accelerance", band=BAND)
    b = fit_modal(F, Y, quantity="accelerance", band=BAND)
    assert np.array_equal(a.poles, b.poles) and np.array_equal(a.residues, b.residues)


@pytest.mark.parametrize("kw, match", [
    (dict(band=(4000.0, 5000.0)), "band"),
    (dict(band=(100.0, 105.0)), "at least"),
    (dict(n_modes=0), "positive"),
    (dict(quantity="velocity"), "quantity"),
])
def test_bad_input_is_one_line(kw, match):
    with pytest.raises(InputError, match=match) as e:
        fit_modal(F, FOUR.frf(F, "receptance"), **kw)
    assert "\n" not in str(e.value)


def test_zero_and_nan_frfs():
    Y = FOUR.frf(F, "receptance")
    Y[:, 1] = 0
    with pytest.raises(InputError, match="zero"):
        fit_modal(F, Y)
    Y = FOUR.frf(F, "receptance")
    Y[50, 0] = np.nan
    with pytest.raises(InputError, match="finite"):
        fit_modal(F, Y)


@pytest.mark.slow  # 10–45 s here; many minutes on the minimum versions (numpy 1.26), so not in that CI pass
@pytest.mark.parametrize("lo, hi", [(1500.0, 1700.0), (1000.0, 1300.0)], ids=["between modes", "around a mode"])
def test_low_coherence_band_does_not_pull_the_fit(lo, hi):
    """frf.meta["coherence"]: a band of γ² = 0.2 whose data carry the matching large errors.

    The noise follows the H1 statistics the weights assume, σ = |y| √((1 − γ²)/γ²), so outside
    the band (γ² = 0.9999) it is 1 % of |y| and inside it is twice |y|. Weighted by coherence,
    the fit finds the four exact modes; unweighted (1 / peak per FRF), the corrupted band
    pulls spurious modes into the fit and the receptance error grows by more than ten times.
    """
    Y0 = FOUR.frf(F, "accelerance")
    gam = np.where((F >= lo) & (F <= hi), 0.2, 0.9999)
    rng = np.random.default_rng(5)
    sig = np.abs(Y0) * np.sqrt((1 - gam) / gam)[:, None]
    Y = Y0 + sig * (rng.standard_normal(Y0.shape) + 1j * rng.standard_normal(Y0.shape)) / np.sqrt(2)
    fb = F[F >= BAND[0]]
    H = FOUR.receptance(fb)
    err = {}
    for use in (True, False):
        frfs = [FRF(F, Y[:, k], "accelerance", f"y{k}", meta={"coherence": gam} if use else {}) for k in range(3)]
        fit = fit_frfs(frfs, band=BAND)
        err[use] = np.linalg.norm(fit(fb) - H, axis=0) / np.linalg.norm(H, axis=0)
        if use:
            check_modes(fit, FOUR, 5e-4, 0.05)
        else:
            assert fit.n_modes > 4  # the corrupted band did pull (the comparison is not vacuous)
    assert err[True].max() < 0.002
    assert err[True].max() < 0.1 * err[False].max()


def test_bad_coherence_is_one_line():
    Y = FOUR.frf(F, "receptance")
    for g in (np.full(F.size, 1.5), np.full(7, 0.9)):
        with pytest.raises(InputError, match="coherence") as e:
            fit_modal(F, Y, coherence=g)
        assert "\n" not in str(e.value)


# A 3-DOF chain with a damping matrix not ∝ M or K (moved from the former polefit tests).
M3 = np.diag([1.0, 0.6, 0.4])  # kg
K3 = np.array([[3.0, -1.5, 0.0], [-1.5, 2.5, -1.0], [0.0, -1.0, 1.0]]) * 4e7  # N/m
C3 = np.array([[60.0, -20.0, 0.0], [-20.0, 20.0, 0.0], [0.0, 0.0, 8.0]])  # N s/m
F3 = np.arange(20.0, 3000.0, 2.0)


def chain_frfs(f):
    """H00, H01, H22 (m/N) by a direct solve of (K − ω²M + iωC) x = F at each frequency."""
    w = 2 * np.pi * np.asarray(f)[:, None, None]
    H = np.linalg.inv(K3[None] - w**2 * M3[None] + 1j * w * C3[None])
    return np.stack([H[:, 0, 0], H[:, 0, 1], H[:, 2, 2]], -1)


def test_chain_noise_free_interpolates_off_the_grid():
    from modal_systems import System

    fit = fit_modal(F3, chain_frfs(F3))
    fn, ze = System(M3, C3, K3, (0,)).poles()
    assert fit.fn_hz == pytest.approx(fn, rel=1e-7) and fit.zeta == pytest.approx(ze, rel=1e-5)
    assert np.all(fit.fit_error < 1e-8)
    f_new = np.linspace(25.0, 2990.0, 777)  # off the fitted grid
    assert np.abs(fit(f_new) - chain_frfs(f_new)).max() < 1e-7 * np.abs(chain_frfs(f_new)).max()


def test_chain_noise_removed_peaks_kept():
    rng = np.random.default_rng(3)
    Y = chain_frfs(F3)
    sigma = 2e-3 * np.abs(Y).max(0)
    noisy = Y + sigma * (rng.standard_normal(Y.shape) + 1j * rng.standard_normal(Y.shape)) / np.sqrt(2)
    fit = fit_modal(F3, noisy)
    err_fit = np.sqrt(np.mean(np.abs(fit(F3) - Y) ** 2, 0))
    err_raw = np.sqrt(np.mean(np.abs(noisy - Y) ** 2, 0))
    assert np.all(err_fit < 0.2 * err_raw)  # most of the noise is gone …
    assert np.abs(fit(F3)).max(0) == pytest.approx(np.abs(Y).max(0), rel=5e-3)  # … and the peaks are not rounded
    assert fit.n_modes == 3
    with pytest.raises(InputError, match="increasing"):
        fit_modal(F3[::-1], Y)


EXAMPLE = __import__("pathlib").Path(__file__).resolve().parents[2] / "examples" / "numerical_case.toml"


def test_assembly_frf_automatic_order_finds_the_fe_modes():
    """The README case: the RCSA tool-point receptance (computed, noise-free, 1–3000 Hz), automatic order.

    Reference: the complex eigenvalues of the FE model of the same assembly (toolpoint.dynamics.fe,
    8 mm elements) — a second method. It has four modes in the band (775.8, 1090.5, 1904.0,
    2214.0 Hz) and the next at 3379 Hz. A computed FRF is no finite sum of viscous modes, and the
    former criterion (residual floor at round-off) chased that with 7 extra poles at 2.9–3 kHz
    that the refinement never moved (ζ = 1 %, whole-Hz frequencies). Now: the four, none at a
    damping limit, the 3379 Hz mode as a residual pole.
    """
    from scipy.linalg import eig

    from toolpoint.dynamics.assembly import load_assembly
    from toolpoint.dynamics.fe import assembly_fe
    from toolpoint.dynamics.model import frf_from_toml
    from toolpoint.dynamics.modal import ZETA_LIMITS

    fit = fit_frfs(frf_from_toml(EXAMPLE), band=(1.0, 3000.0))
    K, C, M = assembly_fe(load_assembly(EXAMPLE, require_holder_tool=True), 8e-3).matrices()
    n = K.shape[0]
    lam = eig(np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]]),
              right=False)
    lam = lam[lam.imag > 0]
    fn = np.sort(np.abs(lam)) / (2 * np.pi)
    ze = (-lam.real / np.abs(lam))[np.argsort(np.abs(lam))]
    inband = fn <= 3000.0
    assert inband.sum() == 4 and fit.n_modes == 4
    assert fit.fn_hz == pytest.approx(fn[inband], rel=2e-4)
    assert fit.zeta == pytest.approx(ze[inband], rel=0.02)
    assert np.all((fit.zeta > 1.01 * ZETA_LIMITS[0]) & (fit.zeta < 0.99 * ZETA_LIMITS[1]))
    assert np.any(np.abs(np.abs(fit.residual_poles) / (2 * np.pi) / fn[4] - 1) < 2e-3)  # 3379 Hz: a residual term
    assert fit.fit_error.max() < 1e-5


def test_a_pole_the_data_do_not_determine_is_flagged():
    """_undetermined: a fifth pole (2900 Hz, ζ = 1 %) added to the exact four of noise-free data gets
    no modal constant, so its variance is unbounded; the exact four are all determined."""
    from toolpoint.dynamics.modal import _Problem, _undetermined

    f = F[F >= BAND[0]]
    Y = FOUR.frf(f, "receptance")
    prob = _Problem(2 * np.pi * f, Y, np.broadcast_to(1 / np.abs(Y).max(0), Y.shape).copy(), 0, True)
    fn, ze = FOUR.poles()
    lam = 2 * np.pi * fn * (-ze + 1j * np.sqrt(1 - ze**2))
    assert _undetermined(prob, lam, *BAND) is None
    extra = 2 * np.pi * 2900.0 * (-0.01 + 1j * np.sqrt(1 - 1e-4))
    assert _undetermined(prob, np.r_[lam, extra], *BAND) == 4


@pytest.mark.parametrize("n_modes", [None, 1, 2])
@pytest.mark.parametrize("case", ["noise", "one point", "stiffness"])
def test_frf_without_resonance_ends_with_a_truthful_fit(case, n_modes):
    """No resonance: white noise, zero but one point, a pure stiffness 1/k (3001 points). The stabilisation
    diagram has no stable pole; the fit used to start from every peak (≈ 970 on noise) and ran for minutes.
    Now: the automatic order finds no mode, and any fit reports how little it explains (relative RMS error
    ≥ 0.95 on noise and the spike); the stiffness is explained by the residual terms alone."""
    f = np.linspace(0.0, 3000.0, 3001)
    rng = np.random.default_rng(1)
    y = {"noise": 1e-7 * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)),
         "one point": np.where(np.arange(f.size) == 1500, 1e-7, 0.0).astype(complex),
         "stiffness": np.full(f.size, 1e-7, complex)}[case]
    fit = fit_frfs([FRF(f, y)], n_modes=n_modes)
    if n_modes is None:
        assert fit.n_modes == 0
    if case == "stiffness":
        assert fit.fit_error[0] < 1e-10
    else:
        assert fit.fit_error[0] >= 0.95


# --------------------------------------------------------------------------- issue 20 item 3: the lab-like tool point
# Truth: tests/lab_like.py's structure (modes 293/1071/1265/1981/2607/2723 Hz, positive modal masses: a driving
# point), fitted as `toolpoint modal FILE` does (trusted band, noise quantity from it, automatic order).
def lab_fit(seed, noise, **kw):
    import time

    from lab_like import NOISE_ACCELERANCE, lab_like_frf
    from toolpoint.trust import common_band

    frf = lab_like_frf(seed, noise=NOISE_ACCELERANCE * noise)
    b = common_band([frf])
    t = time.process_time()
    fit = fit_frfs([b.cut(frf)], noise=b.noise_quantity or None, **kw)
    return fit, time.process_time() - t


def named_hz(message):
    """The frequencies a driving-point note or warning names ("… at 142.2, 460.4 Hz …")."""
    import re

    return np.array([float(x) for x in re.search(r" at ([\d., ]+) Hz", str(message)).group(1).split(", ")])


def check_lab_like(fit):
    from lab_like import DOMINANT_HZ

    for f0 in DOMINANT_HZ:
        r = np.argmin(np.abs(fit.fn_hz - f0))
        assert abs(fit.fn_hz[r] - f0) < 0.02 * f0 and 0.015 <= fit.zeta[r] <= 0.07
    assert fit.fn_hz.min() >= 200.0  # nothing from the rise towards 0 Hz or the noise above the band's edge
    assert np.all(fit.real_modes()[0][:, 0] > 0)  # no negative modal mass


@pytest.mark.parametrize("seed, noise", [(0, 1.0), (1, 10.0), (2, 30.0), (1, 100.0)])
def test_lab_like_driving_point_fit_keeps_the_structures_modes(seed, noise):
    """Declared a driving point, the fit is the unconstrained one (its modes already have positive mass)."""
    free, _ = lab_fit(seed, noise)
    fit, _ = lab_fit(seed, noise, driving_point=0)
    check_lab_like(fit)
    assert fit.notes == () and np.array_equal(fit.poles, free.poles)


@pytest.mark.slow  # 8 fits, ≈ 3 s CPU
def test_lab_like_fit_takes_at_most_1_s_cpu():
    """Issue 20 item 3: ≤ 1 s CPU per fit of the 5000-line FRF with the defaults, noise ×1 … ×100 (measured
    0.2–0.6 s on one thread of the loaded 2-core machine; benchmarks/bench_modal.py)."""
    for noise in (1.0, 10.0, 30.0, 100.0):
        for seed in (0, 1):
            fit, cpu = lab_fit(seed, noise, driving_point=0)
            check_lab_like(fit)
            assert cpu <= 1.0, (seed, noise, cpu)


def test_driving_point_noise_pole_of_negative_mass_is_dropped():
    """A pole where the data have no mode (noise) that came out with a negative modal mass costs the criterion
    little: the driving-point rule drops it and the six true modes stay."""
    from lab_like import MODES, NOISE_ACCELERANCE, lab_like_frf
    from toolpoint.dynamics.modal import _FINAL_TOL, _negative_masses, _positive_masses, _Problem, _refine_clean

    frf = lab_like_frf(0, noise=NOISE_ACCELERANCE * 10)
    sel = frf.freq_hz >= 200.0
    w = 2 * np.pi * frf.freq_hz[sel]
    Yq = (frf.values[sel] * (1j * w) ** 2)[:, None]  # accelerance: the noise is white in it
    prob = _Problem(w, Yq, np.broadcast_to(1 / np.abs(Yq).max(0), Yq.shape).copy(), 2, True)
    true = np.array([2 * np.pi * fn * (-z + 1j * np.sqrt(1 - z * z)) for fn, z, _, _ in MODES])
    extra = 2 * np.pi * 1500.0 * (-0.01 + 1j)
    poles = _refine_clean(prob, np.r_[true, extra], 200.0, 5000.0, _FINAL_TOL)
    neg = _negative_masses(prob, poles, 200.0, 5000.0, 0)
    assert poles.size == 7 and neg.size == 1 and abs(abs(poles[neg[0]]) / (2 * np.pi) - 1500.0) < 20.0
    kept, notes = _positive_masses(prob, poles, 200.0, 5000.0, 0)
    assert np.sort(np.abs(kept) / (2 * np.pi)) == pytest.approx(sorted(m[0] for m in MODES), rel=2e-3)
    assert len(notes) == 1 and notes[0].startswith("note: driving point: modes of negative modal mass dropped")
    assert named_hz(notes[0]) == pytest.approx([abs(poles[neg[0]]) / (2 * np.pi)], abs=0.05)


def test_transfer_frf_declared_a_driving_point_keeps_its_modes_and_warns():
    """FRF 2 of the 5-mode system is a transfer FRF: four of its exact modal constants (state-space eigenvectors)
    are negative masses. Declared a driving point, the data demand every mode: all five kept, a warning names
    exactly those four."""
    from toolpoint.dynamics.modal import DrivingPointWarning

    lam, A = FIVE.modal_constants()
    a = -2 * (A[:, 2] * np.conj(lam)).real
    neg_hz = np.abs(lam[a < 0]) / (2 * np.pi)
    assert neg_hz.size == 4
    Y = add_noise(FIVE.frf(F, "accelerance"), 0.005, seed=7)
    with pytest.warns(DrivingPointWarning, match="negative modal mass kept") as rec:
        fit = fit_modal(F, Y, quantity="accelerance", band=BAND, driving_point=2)
    check_modes(fit, FIVE, 5e-4, 0.05)
    named = named_hz(rec[0].message)
    assert named == pytest.approx(neg_hz, rel=1e-3)
    assert fit_modal(F, Y, quantity="accelerance", band=BAND, driving_point=0).notes == ()  # the real one


def test_pyuff_meas_point_1_declared_a_driving_point_keeps_its_real_modes():
    """pyuff's meas_point_1.txt is described as a driving point, yet its measured accelerance swings the other way
    at 142, 460 and 959 Hz (Re y(f⁺) − Re y(f⁻) across the peak < 0: a negative modal mass). An automatic rule
    once dropped such modes; now every measured peak keeps its mode and a warning names those three."""
    from pathlib import Path

    from scipy.signal import find_peaks

    from toolpoint.dynamics.modal import DrivingPointWarning

    y = np.genfromtxt(Path(__file__).resolve().parents[1] / "data" / "pyuff" / "meas_point_1.txt", dtype=complex)
    f = np.arange(y.size, dtype=float)
    pk, _ = find_peaks(np.abs(y[1:]), prominence=0.05 * np.abs(y[1:]).max())
    pk += 1
    peaks = f[pk]
    negative = peaks[(y[pk + 1] - y[pk - 1]).real < 0]
    assert peaks.size == 6 and negative.tolist() == [142.0, 460.0, 959.0]
    free = fit_modal(f[1:], y[1:], quantity="accelerance")
    with pytest.warns(DrivingPointWarning, match="check that the FRF is a driving point") as rec:
        fit = fit_modal(f[1:], y[1:], quantity="accelerance", driving_point=0)
    assert np.array_equal(fit.poles, free.poles)
    assert np.all(np.min(abs(peaks[:, None] - fit.fn_hz[None]), 1) <= 1.0)  # no measured mode lost
    named = named_hz(rec[0].message)
    assert np.all(np.min(abs(named[:, None] - negative[None]), 1) <= 1.0)  # only the negative ones …
    assert np.all(np.min(abs(negative[:, None] - named[None]), 1) <= 1.0)  # … and all of them


def test_bad_driving_point_is_one_line():
    for d in (3, -1, 0.5):
        with pytest.raises(InputError, match="driving_point|index") as e:
            fit_modal(F, FOUR.frf(F, "receptance"), driving_point=d)
        assert "\n" not in str(e.value)
