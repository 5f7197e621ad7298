"""First-order semi-discretisation (Insperger & Stépán 2002/2004) of milling stability."""

from dataclasses import replace

import numpy as np
import pytest
from scipy.linalg import expm

import toolpoint.stability.sdm as sdm_mod
from toolpoint.errors import InputError
from toolpoint.stability import (
    CuttingConditions,
    ModalModel,
    average_directional_matrix,
    sdm_limit_near,
    sdm_limit_near_many,
    sdm_lobes,
    sdm_spectral_radius,
    zoa_lobes,
)
from toolpoint.stability.sdm import expm_batch

# Benchmark of Insperger & Stépán (2004): 2 teeth, Kt = 6e8, Kn = 2e8 N/m²,
# f_n = 922 Hz, ζ = 0.011, m = 0.03993 kg, flexible in x only, down-milling.
MODE = ModalModel([922.0], [0.011], [0.03993])


def cut(ri, milling="down", teeth=2, kr=2e8 / 6e8):
    return CuttingConditions(teeth=teeth, tangential_coeff=6e8, radial_ratio=kr, radial_immersion=ri, milling=milling)

# Speeds inside lobes (away from the cusps where lobes meet, where the limit jumps).
SPEEDS = {1.0: [7424.0, 10051.0, 15909.0, 21000.0], 0.05: [7500.0, 10000.0, 15800.0, 18900.0]}


def test_expm_batch_matches_scipy():
    rng = np.random.default_rng(0)
    X = rng.standard_normal((50, 6, 6)) * np.geomspace(1e-3, 30, 50)[:, None, None]
    ref = np.stack([expm(x) for x in X])
    assert expm_batch(X) == pytest.approx(ref, rel=1e-11, abs=1e-11 * np.abs(ref).max())


def test_zero_depth_is_free_vibration():
    """At a = 0 the only non-zero multipliers are those of free vibration over T: ρ = e^{−ζω_nT}."""
    rpm = np.array([3000.0, 9000.0, 20000.0])
    rho = sdm_spectral_radius(MODE, None, cut(0.3), rpm=rpm, depth=0.0)
    T = 60.0 / (2 * rpm)
    assert rho == pytest.approx(np.exp(-0.011 * 2 * np.pi * 922.0 * T), rel=1e-10)


def test_the_critical_multiplier_says_the_frequency_that_grows():
    """``multiplier=True``: μ with |μ| = ρ, and at zero depth μ = e^{λT} of the least damped mode — its angle the
    damped natural frequency modulo the tooth-passing frequency (closed form, two modes in x: 922 Hz at ζ 1.1 % and
    1500 Hz at ζ 5 %, the first the critical one)."""
    two = ModalModel([922.0, 1500.0], [0.011, 0.05], [0.03993, 0.03])
    rpm = np.array([3000.0, 9000.0, 20000.0])
    mu = sdm_spectral_radius(two, None, cut(0.3), rpm=rpm, depth=0.0, multiplier=True)
    T = 60.0 / (2 * rpm)
    wd = 2 * np.pi * 922.0 * np.sqrt(1 - 0.011 ** 2)
    assert np.abs(mu) == pytest.approx(np.exp(-0.011 * 2 * np.pi * 922.0 * T), rel=1e-10)
    # the angle as the distance of ω_d T to the nearest multiple of 2π (μ and its conjugate are both multipliers)
    want = np.abs((wd * T + np.pi) % (2 * np.pi) - np.pi)
    assert np.abs(np.angle(mu)) == pytest.approx(want, abs=1e-8)
    a = np.array([1e-4, 5e-4, 2e-3])  # and under cutting |μ| is the spectral radius
    rho = sdm_spectral_radius(two, None, cut(0.3), rpm=rpm, depth=a)
    assert np.abs(sdm_spectral_radius(two, None, cut(0.3), rpm=rpm, depth=a, multiplier=True)) == \
        pytest.approx(rho, rel=1e-12)


@pytest.mark.parametrize("ri", [1.0, 0.05])
def test_default_is_within_one_percent_of_the_converged_limit(ri):
    """Default settings against the converged first-order SDM (Richardson extrapolation of
    the plain SDM at m = 80 and 160 steps over the cut, error O(Δt²)): < 1 % at every speed."""
    rpm = np.array(SPEEDS[ri])
    a = sdm_lobes(MODE, None, cut(ri), rpm=rpm, rtol=1e-5)
    d80, d160 = (sdm_lobes(MODE, None, cut(ri), rpm=rpm, m=m, rtol=1e-6).depth_m for m in (80, 160))
    ref = d160 + (d160 - d80) / 3
    assert np.all(a.params["m"] >= 20)
    assert a.depth_m == pytest.approx(ref, rel=0.01)


def test_fixed_m_converges_like_second_order():
    """Fixed m over the cut in slotting: successive differences fall ≈ 4× per doubling (O(Δt²))."""
    rpm = np.array([15909.0])
    d = [sdm_lobes(MODE, None, cut(1.0), rpm=rpm, m=m, rtol=1e-6).depth_m[0] for m in (20, 40, 80)]
    r = (d[0] - d[1]) / (d[1] - d[2])
    assert 3.0 < r < 5.5
    assert abs(d[2] / d[1] - 1) < 0.01


def test_slotting_minimum_agrees_with_zero_order():
    """Slotting: ZOA minimum 0.298 mm; the SDM minimum (time-varying H) within 10 %."""
    rpm = np.linspace(14000, 18000, 41)  # around the bottom of lobe k = 1
    res = sdm_lobes(MODE, None, cut(1.0), rpm=rpm)
    f = np.linspace(0.0, 3000.0, 3001)
    zoa = zoa_lobes(MODE.frf(f), "rigid", cut(1.0), rpm=np.linspace(5000, 25000, 1000))
    assert zoa.min_depth_m == pytest.approx(0.298e-3, rel=2e-3)
    assert res.min_depth_m == pytest.approx(zoa.min_depth_m, rel=0.10)
    assert res.min_chatter_hz == pytest.approx(zoa.min_chatter_hz, rel=0.01)
    assert {lobe.k for lobe in res.lobes} == {1}


def test_constant_directional_matrix_reproduces_zero_order(monkeypatch):
    """With H(t) replaced by its average H₀ the cut is time-invariant, where the ZOA
    is exact: the SDM must converge to it (checks the whole discrete map)."""

    def averaged(edges, teeth, kt, kr, st, ex):
        return np.repeat(average_directional_matrix(teeth, kt, kr, st, ex)[None], len(edges) - 1, axis=0)

    monkeypatch.setattr(sdm_mod, "interval_directional_matrix", averaged)
    rpm = np.array([7424.0, 12000.0, 15909.0, 21000.0])
    f = np.linspace(1.0, 3000.0, 300000)
    zoa = zoa_lobes(MODE.frf(f), "rigid", cut(1.0), rpm=rpm)
    res = sdm_lobes(MODE, None, cut(1.0), rpm=rpm, m=160, rtol=1e-6)
    assert res.depth_m == pytest.approx(zoa.depth_m, rel=0.003)
    assert res.chatter_hz == pytest.approx(zoa.chatter_hz, rel=0.002)


def test_lobes_move_right_when_frequency_rises():
    """Stiffness fixed, f_n → s·f_n: the limit at speeds × s equals the old one (exact scaling)."""
    s = 1.1
    k = MODE.stiffness[0]
    faster = ModalModel([922.0 * s], [0.011], [k / (2 * np.pi * 922.0 * s) ** 2])
    rpm = np.array([9000.0, 15909.0, 19000.0])
    # rtol 1e-7: the brackets of the two searches may end on different sides of the limit.
    a = sdm_lobes(MODE, None, cut(0.05), rpm=rpm, depth_min=1e-4, depth_max=0.05, rtol=1e-7)
    b = sdm_lobes(faster, None, cut(0.05), rpm=rpm * s, depth_min=1e-4, depth_max=0.05, rtol=1e-7)
    assert b.depth_m == pytest.approx(a.depth_m, rel=1e-6)
    assert b.chatter_hz == pytest.approx(s * a.chatter_hz, rel=1e-6)


def test_lobes_move_down_when_damping_drops():
    rpm = np.linspace(14000, 18000, 9)
    a = sdm_lobes(MODE, None, cut(1.0), rpm=rpm)
    b = sdm_lobes(ModalModel([922.0], [0.0055], [0.03993]), None, cut(1.0), rpm=rpm)
    assert np.all(b.depth_m < a.depth_m)
    assert b.min_depth_m / a.min_depth_m == pytest.approx(0.5, abs=0.05)


def test_two_directions_and_grid_contour():
    """x and y flexible; the ρ = 1 crossing on a depth grid brackets the bisected limit."""
    my = ModalModel([1100.0, 2000.0], [0.02, 0.03], [0.05, 0.2])
    rpm = np.array([8000.0, 16000.0])
    c3 = cut(0.5, "up", teeth=3, kr=0.3)
    res = sdm_lobes(MODE, my, c3, rpm=rpm)
    depth = np.linspace(0.2, 1.8, 9)[:, None] * res.depth_m[None, :]
    rho = sdm_spectral_radius(MODE, my, c3, rpm=rpm[None, :], depth=depth)
    assert rho.shape == (9, 2)
    assert np.all(rho[depth < 0.999 * res.depth_m] < 1) and np.all(rho[depth > 1.001 * res.depth_m] >= 1)


def test_limits_only_are_the_same_limits_without_chatter_frequencies():
    """``chatter=False`` skips the eigenvectors, not the search: the same limits, no chatter frequency, no lobes."""
    rpm = np.linspace(7000.0, 16000.0, 12)
    full = sdm_lobes(MODE, None, cut(0.05), rpm=rpm)
    bare = sdm_lobes(MODE, None, cut(0.05), rpm=rpm, chatter=False)
    assert np.array_equal(bare.depth_m, full.depth_m) and np.all(np.isfinite(full.chatter_hz))
    assert np.all(np.isnan(bare.chatter_hz)) and bare.lobes == [] and bare.min_depth_m == full.min_depth_m


def test_stable_everywhere_gives_inf():
    res = sdm_lobes(MODE, None, cut(0.05), rpm=[9000.0, 9100.0], depth_min=1e-6, depth_max=1e-5)
    assert np.all(np.isinf(res.depth_m)) and np.all(np.isnan(res.chatter_hz))
    assert np.isnan(res.min_depth_m)


@pytest.mark.parametrize(
    "args,kw",
    [
        ((None, None), {}),
        ((ModalModel([922.0], [0.011], [-0.04]), None), {}),
        ((MODE, None), dict(m=1)),
        ((MODE, None), dict(rpm=[2000.0, 1000.0])),
        ((MODE, None), dict(cutting=dict(teeth=2))),
    ],
)
def test_bad_input(args, kw):
    base = dict(cutting=cut(0.5), rpm=[5000.0, 6000.0]) | kw
    with pytest.raises(InputError):
        sdm_lobes(*args, **base)


@pytest.mark.parametrize("ri", [1.0, 0.05])
def test_limit_near_a_guess_finds_the_searched_limit(ri):
    """The bracket-and-bisect search from a guess 0.6× or 1.7× the limit lands on :func:`sdm_lobes`' upward
    search (rtol 1e-5) within its final bracket (h/16 = 1.25 % in ln a, interpolated: < 0.5 % measured);
    a guess beyond the steps is reported unbracketed, at the last depth tried, on the right side."""
    rpm = np.array(SPEEDS[ri])
    ref = sdm_lobes(MODE, None, cut(ri), rpm=rpm, rtol=1e-5).depth_m
    for fac in (0.6, 1.7):
        lim, ok = sdm_limit_near(MODE, None, cut(ri), rpm=rpm, depth_m=ref * fac)
        assert ok.all()
        assert lim == pytest.approx(ref, rel=0.005)
    lim, ok = sdm_limit_near(MODE, None, cut(ri), rpm=rpm, depth_m=ref * 0.2, max_steps=2)
    assert not ok.any() and np.all(lim < ref) and lim == pytest.approx(ref * 0.2 * np.exp(0.4))
    with pytest.raises(InputError, match="guesses"):
        sdm_limit_near(MODE, None, cut(ri), rpm=rpm, depth_m=ref[:1])


def test_limit_near_for_many_models_finds_each_models_limit():
    """``sdm_limit_near_many`` evaluates the points of many models together (different frequencies, dampings,
    stiffnesses and K_t): each model's limits land on its own :func:`sdm_lobes` upward search (rtol 1e-5) within
    the final bracket (h/4 = 5 % in ln a with two halvings, interpolated in ρ: < 1 % measured), skipped guesses
    are NaN and unbracketed, and a model twice as stiff (mass doubled at the same frequency and damping ratio)
    has twice the limit, as the equation of motion scaled by k requires."""
    rng = np.random.default_rng(7)
    rpm = np.array([6000.0, 9000.0, 10000.0, 14000.0])
    models = [ModalModel([922.0 * (1 + 0.05 * j)], [0.011 * (1 + 0.2 * j)], [0.03993 * (1 + 0.3 * j)])
              for j in range(4)]
    cuts = [cut(0.05), cut(0.05), replace(cut(0.05), tangential_coeff=5e8), cut(0.05)]
    ref = np.array([sdm_lobes(mm, None, c, rpm=rpm, rtol=1e-5).depth_m for mm, c in zip(models, cuts)])
    guess = ref * np.exp(rng.normal(0, 0.15, ref.shape))
    guess[1, 2] = np.nan
    lim, ok = sdm_limit_near_many([(mm, None, c) for mm, c in zip(models, cuts)], rpm=rpm, depth_m=guess,
                                  bisections=2)
    v = np.isfinite(guess)
    assert ok[v].all() and not ok[1, 2] and np.isnan(lim[1, 2])
    assert lim[v] == pytest.approx(ref[v], rel=0.01)
    stiff = ModalModel([922.0], [0.011], [2 * 0.03993])
    two, _ = sdm_limit_near_many([(models[0], None, cut(0.05)), (stiff, None, cut(0.05))], rpm=rpm,
                                 depth_m=np.array([ref[0], 2 * ref[0]]), bisections=12)
    assert two[1] == pytest.approx(2 * two[0], rel=1e-3)
    with pytest.raises(InputError, match="one row"):
        sdm_limit_near_many([(models[0], None, cut(0.05))], rpm=rpm, depth_m=guess)
    with pytest.raises(InputError, match="one frequency per point") as exc:
        sdm_limit_near(MODE, None, cut(0.05), rpm=rpm, depth_m=ref[0], chatter_hz=[900.0, 950.0])
    assert exc.value.field == "chatter_hz"


def test_limit_near_for_many_models_says_how_fast_chatter_grows():
    """``extras``: ρ at asked depths is ``sdm_spectral_radius``'s for each model (the stacked evaluation against the
    one-model path), and the growth rate just past each limit is the central difference of ln ρ / T over ±0.5 % of
    it (T the tooth period) within 3 %, the same for a model twice as stiff (the same dynamics at twice the depth),
    and ζ ω_n within 5 % for one mode between its pockets (23.0 and 23.6 /s against 23.56 /s measured)."""
    rpm = np.array([6000.0, 10000.0])
    stiff = ModalModel([922.0], [0.011], [2 * 0.03993])
    tools = [(MODE, None, cut(0.05)), (stiff, None, cut(0.05))]
    ref = sdm_lobes(MODE, None, cut(0.05), rpm=rpm, rtol=1e-5).depth_m
    at = np.stack([np.stack([ref * 0.8, ref * 1.2], axis=1), np.stack([ref * 1.6, np.full(2, np.nan)], axis=1)])
    lim, ok, ex = sdm_limit_near_many(tools, rpm=rpm, depth_m=np.array([ref, 2 * ref]), bisections=4,
                                      rho_at=at, extras=True)
    assert ok.all()
    for i, (mm, _, c) in enumerate(tools):
        for k in range(2):
            for j in range(2):
                if np.isfinite(at[i, k, j]):
                    want = float(np.ravel(sdm_spectral_radius(mm, None, c, rpm=[rpm[k]], depth=[at[i, k, j]]))[0])
                    assert ex["rho_at"][i, k, j] == pytest.approx(want, rel=1e-9)
                else:
                    assert np.isnan(ex["rho_at"][i, k, j])
            lo, hi = (float(np.ravel(sdm_spectral_radius(mm, None, c, rpm=[rpm[k]], depth=[lim[i, k] * e]))[0])
                      for e in (np.exp(-0.005), np.exp(0.005)))
            fd = (np.log(hi) - np.log(lo)) / 0.01 / (60.0 / (2 * rpm[k]))
            assert ex["growth_per_s"][i, k] == pytest.approx(fd, rel=0.03)
    assert ex["growth_per_s"][1] == pytest.approx(ex["growth_per_s"][0], rel=0.03)
    with pytest.raises(InputError, match="rho_at"):
        sdm_limit_near_many(tools, rpm=rpm, depth_m=np.array([ref, 2 * ref]), rho_at=at[:, :1], extras=True)
    with pytest.raises(InputError, match="extras"):
        sdm_limit_near_many(tools, rpm=rpm, depth_m=np.array([ref, 2 * ref]), rho_at=at)
    # the closed form: one symmetric mode at half immersion, between its pockets, grows chatter at ζ ω_n just past
    # its limit (the zero-order characteristic equation's root moves off the axis at the mode's decay rate)
    mode = ModalModel([750.0], [0.005], [2e7 / (2 * np.pi * 750.0) ** 2])
    half = CuttingConditions(teeth=3, tangential_coeff=8e8, radial_ratio=0.3, radial_immersion=0.5)
    r2 = np.array([9000.0, 11000.0])
    a2 = sdm_lobes(mode, mode, half, rpm=r2, rtol=1e-5).depth_m
    _, _, ex2 = sdm_limit_near_many([(mode, mode, half)], rpm=r2, depth_m=a2[None], extras=True)
    assert ex2["growth_per_s"][0] == pytest.approx(0.005 * 2 * np.pi * 750.0, rel=0.05)


def _three_mode_floquet(rpm, rel_depth):
    """Floquet matrices of a three-mode symmetric tool (EM16-50-like: 748, 1890, 2176 Hz) slotting with three
    teeth at speeds ``rpm`` and depths ``rel_depth`` × each speed's limit: 46–214 states (the cut is the whole tooth
    period, so low speeds need many nodes)."""
    modes = ModalModel([748.0, 1890.0, 2176.0], [0.03, 0.025, 0.02], [0.35, 0.06, 0.08])
    c = CuttingConditions(teeth=3, tangential_coeff=8e8, radial_ratio=0.2, radial_immersion=1.0)
    sy = sdm_mod._System(sdm_mod.as_state_space(modes, modes), c)
    rpm = np.asarray(rpm, float)
    lim = sdm_lobes(modes, modes, c, rpm=rpm).depth_m
    m, s = sy.resolution(rpm, None, 1.0, sdm_mod.M_MAX, 1.1 * sy.f_max)
    return [sy.monodromy(np.full(len(rel_depth), r), a * np.asarray(rel_depth), int(mm), int(ss))
            for r, a, mm, ss in zip(rpm, lim, m, s)]


def test_the_krylov_multiplier_is_the_largest_eigenvalue(monkeypatch):
    """The critical multiplier from :data:`~toolpoint.stability.sdm.KRYLOV_DIM` Arnoldi steps is the eigenvalue of
    largest modulus of the whole Floquet matrix (all of NumPy's eigenvalues, an independent solver) within 1e-9,
    angle included, from free vibration (depth 0: Φ has rank n, an invariant subspace ends the Arnoldi steps early)
    to twice the limit — and without one full eigenvalue problem."""
    Phis = _three_mode_floquet([3000.0, 6000.0, 9000.0, 15000.0], [0.0, 0.5, 0.95, 1.0, 1.05, 2.0])
    assert sorted({P.shape[1] for P in Phis}) == [46, 82, 110, 214]
    want = [np.linalg.eigvals(P) for P in Phis]
    want = [ev[np.arange(ev.shape[0]), np.argmax(np.abs(ev), axis=1)] for ev in want]

    def refused(*a, **k):
        raise AssertionError("a full eigenvalue problem was solved")

    monkeypatch.setattr(np.linalg, "eigvals", refused)
    for P, w in zip(Phis, want):
        got = sdm_mod.critical_multipliers(P)
        assert np.abs(got) == pytest.approx(np.abs(w), rel=1e-9)
        assert got == pytest.approx(w, rel=1e-9, abs=1e-9)  # the same multiplier, not its conjugate's twin only
    assert np.abs(want[0][1:3]).max() < 1 < np.abs(want[0][4:]).min()  # the depths straddle the limit


def test_a_matrix_the_krylov_steps_cannot_resolve_gets_all_its_eigenvalues(monkeypatch):
    """A cyclic shift scaled by 1.01 has all its 80 eigenvalues on one circle: 24 Arnoldi steps cannot single out
    the largest (the residual stays large), so the whole eigenvalue problem answers, and the modulus is 1.01."""
    P = 1.01 * np.roll(np.eye(80), 1, axis=0)
    full, asked = np.linalg.eigvals, []
    monkeypatch.setattr(np.linalg, "eigvals", lambda a: (asked.append(a.shape), full(a))[1])
    mu = sdm_mod.critical_multipliers(np.stack([P, 0.5 * P]))
    assert np.abs(mu) == pytest.approx([1.01, 0.505], rel=1e-12)
    assert asked == [(2, 80, 80)]  # both matrices fell back, in one call


def test_a_complex_floquet_matrix_gets_its_largest_eigenvalue():
    """The Arnoldi steps are written for the SDM's real Φ; a complex one is solved whole, not projected wrongly."""
    rng = np.random.default_rng(3)
    Q = np.linalg.qr(rng.standard_normal((60, 60)) + 1j * rng.standard_normal((60, 60)))[0]
    P = (Q * np.r_[1.1j, 0.6 ** np.arange(1, 60)]) @ Q.conj().T
    mu = sdm_mod.critical_multipliers(P[None])
    assert mu[0] == pytest.approx(1.1j, abs=1e-12)


def test_old_loose_keywords_are_refused():
    with pytest.raises(TypeError, match="teeth"):
        sdm_lobes(MODE, None, teeth=2, kt=6e8, kr=1 / 3, radial_immersion=0.05, rpm=[9000.0], m=20)
    with pytest.raises(InputError, match="CuttingConditions"):
        sdm_spectral_radius(MODE, None, None, rpm=[9000.0], depth=0.0)


def _plain_sdm_limit(rpm, ri, m, lo=1e-4, hi=2e-2):
    """Independent reference: the first-order SDM of Insperger & Stépán (2004) for the one mode of MODE in x,
    written out directly (the cutting stiffness a·h_i inside the exponential of every step, scipy's expm),
    limit by bisection on ρ(Φ) = 1."""
    from toolpoint.stability.milling import interval_directional_matrix

    wn, ze, mass = MODE.omega_n[0], MODE.zeta[0], MODE.mass_kg[0]
    c = cut(ri)
    st, ex = c.immersion_angles
    tau = 60.0 / (2 * rpm)
    angle = min(ex - st, np.pi)
    t_cut = angle / (2 * np.pi * rpm / 60.0)
    dt = t_cut / m
    h = interval_directional_matrix(st + angle * np.arange(m + 1) / m, 2, 6e8, 1 / 3, st, ex)[:, 0, 0]
    A0 = np.array([[0.0, 1.0], [-wn**2, -2 * ze * wn]])

    def rho(a):
        D = 2 + m + 1
        Y = np.zeros((2, D))
        Y[:, :2] = np.eye(2)
        Phi = np.zeros((D, D))
        Phi[2, :2] = [1.0, 0.0]
        for i in range(m):
            Ai = A0 - np.array([[0.0, 0.0], [a * h[i] / mass, 0.0]])
            X = np.zeros((4, 4))
            X[:2, :2], X[:2, 2] = Ai * dt, np.array([0.0, a * h[i] / mass]) * dt
            X[2, 3] = 1.0
            E = expm(X)
            G1 = E[:2, 3]
            G0 = E[:2, 2] - G1
            Y = E[:2, :2] @ Y
            Y[:, 2 + i] += G0
            Y[:, 3 + i] += G1
            Phi[3 + i, :] = Y[0]
        Phi[:2] = expm(A0 * (tau - t_cut)) @ Y
        return np.abs(np.linalg.eigvals(Phi)).max()

    for _ in range(40):
        mid = np.sqrt(lo * hi)
        lo, hi = (mid, hi) if rho(mid) < 1 else (lo, mid)
    return hi


@pytest.mark.slow
@pytest.mark.parametrize("ri,rpm", [(1.0, 15909.0), (0.05, 10000.0)])
def test_converges_to_the_independent_first_order_sdm(ri, rpm):
    """The full discretisation (depth-independent exponentials) and the first-order SDM (written out above)
    share the limit they converge to: Richardson extrapolations from m = 40 and 80 within 0.01 %."""
    ref = [_plain_sdm_limit(rpm, ri, m, lo=0.1e-3, hi=10e-3) for m in (40, 80)]
    got = [sdm_lobes(MODE, None, cut(ri), rpm=[rpm], m=m, rtol=1e-7).depth_m[0] for m in (40, 80)]
    ext_ref, ext_got = ref[1] + (ref[1] - ref[0]) / 3, got[1] + (got[1] - got[0]) / 3
    assert ext_got == pytest.approx(ext_ref, rel=1e-4)


def test_the_default_range_widens_to_the_deep_pockets_of_a_lightly_damped_mode():
    # One mode of ζ 0.3 % at 25 % immersion, up milling (a campaign tool, EM28-80, in its prior's tail): the
    # pocket at 9600–9800 rpm is past 100 × the zero-order minimum and came back inf — campaigns' truth and the
    # SDM correction of update lost it. The widened default finds it; every limit is checked by the spectral
    # radius itself: stable 3 % below, unstable 3 % above.
    w = 2 * np.pi * 654.0
    mode = ModalModel([654.0], [0.003], [1.7e7 / w**2])
    c = CuttingConditions(teeth=4, tangential_coeff=7.96e8, radial_ratio=0.212, radial_immersion=0.25,
                          milling="up")
    rpm = np.linspace(9400, 10000, 7)
    narrow = sdm_lobes(mode, mode, c, rpm=rpm, widen=0)
    assert np.sum(~np.isfinite(narrow.depth_m)) >= 2
    res = sdm_lobes(mode, mode, c, rpm=rpm)
    a = res.depth_m
    assert np.all(np.isfinite(a)) and np.all(np.isfinite(res.chatter_hz))
    fin = np.isfinite(narrow.depth_m)  # the speeds found at once are not searched again
    np.testing.assert_allclose(a[fin], narrow.depth_m[fin], rtol=1e-12)
    assert res.params["depth_max"] > narrow.params["depth_max"]
    assert np.all(sdm_spectral_radius(mode, mode, c, rpm=rpm, depth=0.97 * a) < 1)
    assert np.all(sdm_spectral_radius(mode, mode, c, rpm=rpm, depth=1.03 * a) > 1)
    # a range given by the caller is kept
    assert sdm_lobes(mode, mode, c, rpm=rpm, depth_max=narrow.params["depth_max"]).params["depth_max"] == \
        narrow.params["depth_max"]
    with pytest.raises(InputError, match="widen"):
        sdm_lobes(mode, mode, c, rpm=rpm, widen=-1)
    for bad in ({"chatter": "False"}, {"seed": 0}):  # a flag, not a truthy string or number
        with pytest.raises(InputError, match=f"{next(iter(bad))}.*must be True or False"):
            sdm_lobes(mode, mode, c, rpm=rpm, **bad)


def test_a_speed_asked_alone_resolves_every_mode_that_can_chatter():
    # The example tool of toolpoint.shop (three modes: 2213 Hz ζ 0.99 %, 776 Hz ζ 0.55 %, 1908 Hz ζ 2.68 %; 3 teeth,
    # half immersion, climb). At 9000 rpm the zero-order lobe is the 776 Hz mode's, and the steps were sized for
    # that wave alone: asked alone, 9000 rpm read 0.56 mm with the 2213 Hz mode spuriously unstable, against
    # 1.07 mm asked beside 14000 and 20000 rpm (whose lobes are the 2213 Hz mode's). The check is the spectral
    # radius at accuracy 4, independent of the search: stable 1 % below the limit, unstable 1 % above, both ways
    # of asking.
    fn = np.array([2213.0, 776.0, 1908.0])
    k = np.array([9.02e6, 2.84e7, 1.96e7])
    tool = ModalModel(fn, [0.0099, 0.0055, 0.0268], k / (2 * np.pi * fn) ** 2)
    c = CuttingConditions(teeth=3, tangential_coeff=7e8, radial_ratio=0.3, radial_immersion=0.5, milling="down")
    alone = sdm_lobes(tool, tool, c, rpm=[9000.0])
    beside = sdm_lobes(tool, tool, c, rpm=[9000.0, 14000.0, 20000.0])
    assert alone.depth_m[0] == pytest.approx(beside.depth_m[0], rel=2e-3)
    assert alone.chatter_hz[0] == pytest.approx(776.0, rel=0.01)
    for a in (alone.depth_m[0], beside.depth_m[0]):
        assert sdm_spectral_radius(tool, tool, c, rpm=9000.0, depth=0.99 * a, accuracy=4.0) < 1
        assert sdm_spectral_radius(tool, tool, c, rpm=9000.0, depth=1.01 * a, accuracy=4.0) > 1
