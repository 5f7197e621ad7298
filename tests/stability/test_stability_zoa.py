"""Zero-order approximation (Altintas & Budak 1995) of milling stability."""

import numpy as np
import pytest

from toolpoint.errors import InputError
from toolpoint.frf import FRF
from toolpoint.stability import (
    CuttingConditions,
    LobeResult,
    ModalModel,
    average_directional_matrix,
    directional_coefficients,
    immersion_angles,
    zoa_lobes,
)
from toolpoint.stability.milling import interval_directional_matrix

# Benchmark of Insperger & Stépán (2004) / Bayly et al.: one mode in x.
FN, ZETA, MASS = 922.0, 0.011, 0.03993
KT, KN = 6e8, 2e8
KR = KN / KT
TEETH = 2


def cut(ri, milling="down", teeth=TEETH, kr=KR):
    return CuttingConditions(teeth=teeth, tangential_coeff=KT, radial_ratio=kr, radial_immersion=ri, milling=milling)


def single_mode(freq_hz, fn=FN, zeta=ZETA, mass=MASS):
    return ModalModel([fn], [zeta], [mass]).frf(freq_hz)


def closed_form_min(h0, fn=FN, zeta=ZETA, mass=MASS):
    """a_lim,min = 2kζ(1+ζ)/h0 for one mode (k = m ω_n²) and its directional factor h0 > 0.

    a_lim = −1/(2 h0 Re Φ): with h0 > 0 it needs Re Φ < 0, lowest −1/(4kζ(1+ζ));
    with h0 < 0 (e.g. half-immersion down-milling) Re Φ > 0, highest 1/(4kζ(1−ζ)).
    """
    k = mass * (2 * np.pi * fn) ** 2
    return 2 * k * zeta * (1 + np.sign(h0) * zeta) / abs(h0)


# ---------------------------------------------------------------- geometry
def test_immersion_angles():
    assert immersion_angles(1.0, "down") == pytest.approx((0.0, np.pi))
    assert immersion_angles(1.0, "up") == pytest.approx((0.0, np.pi))
    assert immersion_angles(0.5, "down") == pytest.approx((np.pi / 2, np.pi))
    assert immersion_angles(0.5, "up") == pytest.approx((0.0, np.pi / 2))


def test_directional_coefficients_slotting():
    a = directional_coefficients(0.0, np.pi, KR)
    assert a == pytest.approx(np.array([[-np.pi * KR, -np.pi], [np.pi, -np.pi * KR]]))
    h0 = average_directional_matrix(2, KT, KR, 0.0, np.pi)
    assert h0[0, 0] == pytest.approx(2 * KN / 4)  # N·Kn/4


@pytest.mark.parametrize("teeth,ri,milling", [(2, 1.0, "down"), (3, 0.5, "up"), (4, 0.7, "down"), (2, 0.05, "down")])
def test_interval_average_matches_tooth_pass_average(teeth, ri, milling):
    """Averaging H over a whole tooth period in pieces gives H₀ = −N K_t [α]/(4π)."""
    st, ex = immersion_angles(ri, milling)
    edges = st + np.linspace(0, 2 * np.pi / teeth, 37)
    H = interval_directional_matrix(edges, teeth, KT, KR, st, ex)
    assert H.mean(axis=0) == pytest.approx(average_directional_matrix(teeth, KT, KR, st, ex), rel=1e-12, abs=1e-3)


# ---------------------------------------------------------------- closed form
@pytest.mark.parametrize("df", [1.0, 0.1])
def test_single_mode_slotting_minimum_closed_form(df):
    """0.298 mm for the benchmark; to 1e-3 even on a 1 Hz grid (parabolic refinement)."""
    f = np.arange(0.0, 3000.0 + df / 2, df)
    res = zoa_lobes(single_mode(f), "rigid", cut(1.0), rpm=np.linspace(5000, 25000, 1000))
    ref = closed_form_min(2 * KN / 4)
    assert ref == pytest.approx(0.298e-3, abs=0.0005e-3)
    assert res.min_depth_m == pytest.approx(ref, rel=1e-3)
    # The chatter frequency at the minimum is where Re Φ is lowest: f_n √(1 + 2ζ).
    assert res.min_chatter_hz == pytest.approx(FN * np.sqrt(1 + 2 * ZETA), rel=2e-4)
    assert np.min(res.depth_m) >= res.min_depth_m * (1 - 1e-9)


@pytest.mark.parametrize("ri,milling,sign", [(0.5, "down", -1), (0.3, "up", 1), (0.8, "down", 1)])
def test_single_mode_minimum_closed_form_partial_immersion(ri, milling, sign):
    st, ex = immersion_angles(ri, milling)
    h0 = average_directional_matrix(2, KT, KR, st, ex)[0, 0]
    assert np.sign(h0) == sign  # both signs of the x directional factor are covered
    f = np.linspace(0.0, 3000.0, 3001)
    res = zoa_lobes(single_mode(f), "rigid", cut(ri, milling),
                    rpm=np.linspace(5000, 25000, 500))
    assert res.min_depth_m == pytest.approx(closed_form_min(h0), rel=1e-3)


# ---------------------------------------------------------------- the eigenvalue solution itself
def _char_det(res, h0, phi_xx, phi_yy, teeth):
    """|det[I + a(1 − e^{−iωT}) H₀ Φ(iω)]| on every lobe point — eq. (2) must vanish there."""
    out = []
    for lobe in res.lobes:
        w = 2 * np.pi * lobe.chatter_hz
        T = 60.0 / (teeth * lobe.rpm)
        c = lobe.depth_m * (1 - np.exp(-1j * w * T))
        pxx, pyy = phi_xx(lobe.chatter_hz), phi_yy(lobe.chatter_hz)
        det = (1 + c * h0[0, 0] * pxx) * (1 + c * h0[1, 1] * pyy) - c**2 * h0[0, 1] * h0[1, 0] * pxx * pyy
        out.append(np.abs(det))
    return np.concatenate(out)


@pytest.mark.parametrize("ri,milling", [(1.0, "down"), (0.5, "up"), (0.25, "down")])
def test_lobe_points_solve_characteristic_equation(ri, milling):
    """Both directions flexible (different modes): each lobe point is a root of eq. (2),
    which checks the eigenvalues, the ε branch and the lobe-number-to-speed map."""
    f = np.linspace(1.0, 3000.0, 3000)
    mx, my = ModalModel([922.0, 1800.0], [0.011, 0.02], [0.04, 0.1]), ModalModel([1000.0], [0.015], [0.05])
    res = zoa_lobes(mx.frf(f), my.frf(f), cut(ri, milling, teeth=3, kr=0.3),
                    rpm=np.linspace(3000, 30000, 400))
    st, ex = immersion_angles(ri, milling)
    h0 = average_directional_matrix(3, KT, 0.3, st, ex)
    det = _char_det(res, h0, lambda q: mx.frf(q).values, lambda q: my.frf(q).values, 3)
    assert det.size > 1000
    assert det.max() < 1e-8
    assert {lobe.branch for lobe in res.lobes} == {0, 1}  # both eigenvalue branches give lobes
    assert {lobe.k for lobe in res.lobes} >= {0, 1, 2, 3}


def test_limit_is_minimum_over_lobes():
    """The limit at each speed is the lowest lobe there: never above the chord through
    neighbouring points of any lobe by more than the interpolation error, and it is
    attained by the lobe it reports (lobe number and chatter frequency agree)."""
    teeth = TEETH
    f = np.linspace(1.0, 3000.0, 3000)
    rpm = np.linspace(4000, 26000, 700)
    res = zoa_lobes(single_mode(f), None, cut(0.5), rpm=rpm)
    ref = np.full(rpm.size, np.inf)
    for lobe in res.lobes:
        r, d = lobe.rpm, lobe.depth_m
        assert np.all(np.diff(r) > 0)  # single-mode lobes do not fold back in speed
        j = np.searchsorted(r, rpm, side="right") - 1
        inside = (j >= 0) & (j < r.size - 1)
        j = j[inside]
        # Depth at the lower of the two neighbouring lobe points bounds the lobe between them
        # up to the FRF interpolation error (1/a is linear between FRF points).
        ref[inside] = np.minimum(ref[inside], np.maximum(d[j], d[j + 1]))
    fin = np.isfinite(ref)
    assert np.all(res.depth_m[fin] <= ref[fin] * (1 + 1e-3))
    assert np.all(res.depth_m > 0)
    ok = np.isfinite(res.depth_m)
    assert np.all(np.isfinite(res.chatter_hz[ok]))
    waves = res.chatter_hz[ok] * 60.0 / (teeth * rpm[ok])  # f_c T = k + ε/2π
    assert np.all((waves >= res.lobe_number[ok] - 1e-9) & (waves <= res.lobe_number[ok] + 1 + 1e-9))


# ---------------------------------------------------------------- physics trends
def test_lobes_move_right_when_frequency_rises():
    """With the stiffness fixed, f_n → s·f_n maps the chart exactly onto speeds × s."""
    s = 1.1
    k = MASS * (2 * np.pi * FN) ** 2
    f = np.linspace(0.0, 3000.0, 3001)
    rpm = np.linspace(5000, 25000, 800)
    base = zoa_lobes(single_mode(f), "rigid", cut(0.5), rpm=rpm)
    mass_s = k / (2 * np.pi * FN * s) ** 2
    moved = zoa_lobes(single_mode(f * s, fn=FN * s, mass=mass_s), "rigid", cut(0.5), rpm=rpm * s)
    assert moved.depth_m == pytest.approx(base.depth_m, rel=1e-9)
    assert moved.min_rpm == pytest.approx(s * base.min_rpm, rel=1e-9)
    assert moved.pocket().rpm == pytest.approx(s * base.pocket().rpm, rel=1e-9)
    # Same grid: the chatter frequencies follow the mode up.
    up = zoa_lobes(single_mode(f, fn=FN * s, mass=mass_s), "rigid", cut(0.5), rpm=rpm)
    assert up.min_chatter_hz == pytest.approx(s * base.min_chatter_hz, rel=1e-3)


def test_lobes_move_down_when_damping_drops():
    f = np.linspace(0.0, 3000.0, 30001)
    rpm = np.linspace(5000, 25000, 800)
    base = zoa_lobes(single_mode(f), "rigid", cut(1.0), rpm=rpm)
    low = zoa_lobes(single_mode(f, zeta=ZETA / 2), "rigid", cut(1.0), rpm=rpm)
    ratio = (ZETA / 2) * (1 + ZETA / 2) / (ZETA * (1 + ZETA))
    assert low.min_depth_m / base.min_depth_m == pytest.approx(ratio, rel=1e-3)
    assert np.all(low.depth_m <= base.depth_m * (1 + 1e-12))


# ---------------------------------------------------------------- API details
def test_symmetric_default_and_regridded_y():
    f = np.linspace(0.0, 3000.0, 3001)
    x = single_mode(f)
    rpm = np.linspace(5000, 25000, 300)
    a = zoa_lobes(x, None, cut(0.5), rpm=rpm)
    b = zoa_lobes(x, x, cut(0.5), rpm=rpm)
    assert a.depth_m == pytest.approx(b.depth_m, rel=1e-12)
    # y on a finer, narrower grid: x is cut to the common band, y interpolated onto it.
    fy = np.linspace(200.0, 2500.0, 9201)
    c = zoa_lobes(x, single_mode(fy), cut(0.5), rpm=rpm)
    assert c.params["freq_band_hz"] == (200.0, 2500.0)
    assert c.min_depth_m == pytest.approx(a.min_depth_m, rel=2e-3)


def test_result_is_si_and_plots(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    f = np.linspace(0.0, 3000.0, 3001)
    res = zoa_lobes(single_mode(f), "rigid", cut(1.0), rpm=np.linspace(5000, 25000, 200))
    assert isinstance(res, LobeResult) and res.method == "zoa"
    assert res.depth_mm == pytest.approx(1e3 * res.depth_m)
    assert 1e-4 < res.min_depth_m < 1e-3  # metres
    ax = res.plot()
    assert ax.get_xlabel() == "spindle speed [rpm]"
    assert ax.get_ylabel() == "axial depth of cut [mm]"
    plt.close("all")


def test_mobility_input_is_converted():
    f = np.linspace(1.0, 3000.0, 3000)
    rec = single_mode(f)
    mob = FRF(f, 1j * rec.omega * rec.values, "mobility")
    rpm = np.linspace(5000, 25000, 200)
    a = zoa_lobes(rec, "rigid", cut(1.0), rpm=rpm)
    b = zoa_lobes(mob, "rigid", cut(1.0), rpm=rpm)
    assert b.depth_m == pytest.approx(a.depth_m, rel=1e-9)


@pytest.mark.parametrize(
    "kw,field",
    [
        (dict(teeth=0), "teeth"),
        (dict(teeth=2.5), "teeth"),
        (dict(tangential_coeff=0.0), "tangential_coeff"),
        (dict(tangential_coeff=-1e8), "tangential_coeff"),
        (dict(tangential_coeff=float("nan")), "tangential_coeff"),
        (dict(radial_ratio=-0.1), "radial_ratio"),
        (dict(radial_immersion=0.0), "radial_immersion"),
        (dict(radial_immersion=1.2), "radial_immersion"),
        (dict(milling="climb"), "milling"),
    ],
)
def test_bad_cutting_conditions(kw, field):
    args = dict(teeth=2, tangential_coeff=KT, radial_ratio=KR, radial_immersion=0.5) | kw
    with pytest.raises(InputError) as err:
        CuttingConditions(**args)
    assert err.value.field == field and field in str(err.value)


@pytest.mark.parametrize(
    "rpm", [np.linspace(20000, 2000, 10), [0.0, 100.0], [1000.0, np.nan], np.linspace(1000, 2000, 100_001)]
)
def test_bad_speeds(rpm):
    f = np.linspace(0.0, 3000.0, 301)
    with pytest.raises(InputError) as err:
        zoa_lobes(single_mode(f), None, cut(0.5), rpm=rpm)
    assert err.value.field == "rpm"


def test_old_loose_keywords_are_refused():
    f = np.linspace(0.0, 3000.0, 301)
    with pytest.raises(TypeError, match="teeth"):
        zoa_lobes(single_mode(f), None, teeth=2, kt=KT, kr=KR, radial_immersion=0.5, rpm=[5000.0, 6000.0])


# --------------------------------------------------------------------------- issue 23 item 6: no chords at high speed
def _two_mode(f):
    w = 2 * np.pi * np.asarray(f, float)
    return sum(1 / (m * ((2 * np.pi * fn) ** 2 - w**2 + 2j * z * 2 * np.pi * fn * w))
               for fn, z, m in ((922.0, 0.011, 0.04), (2217.0, 0.008, 0.03)))


def test_limit_between_frf_points_follows_the_fine_frf():
    """A sharp resonance turns Φ by ~0.2 rad per 1 Hz step and one interval spans hundreds of rpm at low lobe
    numbers: with μ linear between 1 Hz points the limit was a chain of chords, 0.24 % off the limit of the same
    structure sampled at 0.05 Hz (where the chords are 400× shorter; 1.2 % on examples/numerical_case.toml). The FRF
    intervals are split by the FRF's own turn (Hermite Φ): within 0.1 % now (measured 0.063 %), the minimum
    unchanged, and the split does not depend on the speeds asked for."""
    from toolpoint.stability.zoa import interval_parts

    c = cut(0.5, teeth=2, kr=0.3)
    rpm = np.linspace(12000.0, 40000.0, 700)
    coarse, fine = np.arange(1.0, 3001.0), np.arange(1.0, 3000.001, 0.05)
    res = zoa_lobes(FRF(coarse, _two_mode(coarse)), None, c, rpm=rpm)
    ref = zoa_lobes(FRF(fine, _two_mode(fine)), None, c, rpm=rpm)
    assert np.all(interval_parts(fine, _two_mode(fine)) == 1)  # the reference is not refined itself
    assert np.max(np.abs(res.depth_m / ref.depth_m - 1)) < 1e-3
    assert res.min_depth_m == pytest.approx(ref.min_depth_m, rel=1e-3)
    parts = interval_parts(coarse, _two_mode(coarse))
    assert parts.max() > 1 and parts.max() <= 16
    sub = zoa_lobes(FRF(coarse, _two_mode(coarse)), None, c, rpm=rpm[::7])  # another speed grid: the same curve
    assert np.allclose(sub.depth_m, res.depth_m[::7], rtol=1e-12)


def test_directional_eigenvalues_per_sample_are_those_of_each_samples_matrix():
    """Each sample's own K_t, K_r: the eigenvalues of its average directional matrix (numpy.linalg.eigvals)."""
    from toolpoint.stability.milling import average_directional_matrix
    from toolpoint.stability.zoa_batch import directional_eigenvalues

    rng = np.random.default_rng(3)
    for cut in (CuttingConditions(3, 796e6, 0.212, 0.4, "up"), CuttingConditions(2, 6e8, 1 / 3, 1.0, "down")):
        ktf, kr = np.exp(0.1 * rng.standard_normal(40)), cut.radial_ratio * np.exp(0.15 * rng.standard_normal(40))
        lam = np.sort_complex(directional_eigenvalues(cut, ktf, kr))
        ref = np.sort_complex(np.array([np.linalg.eigvals(average_directional_matrix(
            cut.teeth, cut.tangential_coeff * k, r, *cut.immersion_angles)) for k, r in zip(ktf, kr)]))
        assert np.allclose(lam, ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())
