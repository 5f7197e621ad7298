"""Time-domain milling simulation against independent references: the SDM limit, the closed-form average
force, the frequency-domain SLE (Schmitz & Mann 2006)."""

import numpy as np
import pytest

from toolpoint.errors import InputError
from toolpoint.simulation import Tool, simulate_milling, sle_frequency_domain, stability_boundary
from toolpoint.stability import CuttingConditions, ModalModel, StateSpaceModel, sdm_lobes

MODE = ModalModel([922.0], [0.011], [0.03993])  # Insperger & Stépán benchmark, x only
SLOT = CuttingConditions(teeth=2, tangential_coeff=6e8, radial_ratio=1 / 3, radial_immersion=1.0)
MX = [(900.0, 2e6, 0.03), (2100.0, 8e6, 0.02)]
MY = [(850.0, 1.8e6, 0.03), (2300.0, 9e6, 0.02)]


def _flat_speeds(model, cut, lo, hi, n, count):
    """``count`` speeds where the SDM limit changes by < 5 % over ±1 % of speed (off the steep flanks)."""
    rpm = np.linspace(lo, hi, n)
    grid = np.sort(np.r_[rpm, rpm * 0.99, rpm * 1.01])
    lim = sdm_lobes(model, None, cut, rpm=grid, rtol=1e-4).depth_m
    d = dict(zip(grid, lim))
    flat = [r for r in rpm if abs(d[r * 1.01] / d[r] - 1) < 0.05 and abs(d[r * 0.99] / d[r] - 1) < 0.05
            and np.isfinite(d[r])]
    pick = np.array(flat)[np.linspace(0, len(flat) - 1, min(count, len(flat))).astype(int)]
    return pick, np.array([d[r] for r in pick])


@pytest.mark.slow
def test_boundary_within_2_percent_of_sdm_one_mode():
    rpm, sdm = _flat_speeds(MODE, SLOT, 4000, 25000, 200, 24)
    assert rpm.size >= 20
    sim = stability_boundary(MODE, None, SLOT, rpm=rpm, depth_lo=0.85 * sdm, depth_hi=1.2 * sdm, rtol=5e-3,
                             revolutions=40)
    err = sim / sdm - 1
    assert np.all(np.abs(err) < 0.02), np.c_[rpm, sdm, sim, err]


@pytest.mark.slow
@pytest.mark.first
def test_boundary_within_2_percent_of_sdm_two_modes_with_cross_terms():
    # two modes per direction, turned by 30°: the structure has cross receptances (a full state-space model)
    mx, my = (ModalModel([f for f, _, _ in m], [z for _, _, z in m], [k / (2 * np.pi * f) ** 2 for f, k, _ in m])
              for m in (MX, MY))
    ss = StateSpaceModel.from_modes(mx, my).rotated(np.deg2rad(30))
    cut = CuttingConditions(teeth=3, tangential_coeff=8e8, radial_ratio=0.3, radial_immersion=0.5)
    rpm, sdm = _flat_speeds(ss, cut, 6000, 24000, 30, 6)
    sim = stability_boundary(ss, None, cut, rpm=rpm, depth_lo=0.85 * sdm, depth_hi=1.2 * sdm, rtol=5e-3,
                             revolutions=40)
    err = sim / sdm - 1
    assert np.all(np.abs(err) < 0.02), np.c_[rpm, sdm, sim, err]


def test_verdict_brackets_sdm_limit_fast():
    # a fast guard of the same property: 5 % below the SDM limit stable, 5 % above unstable
    rpm = np.array([7500.0, 10000.0, 16000.0])
    sdm = sdm_lobes(MODE, None, SLOT, rpm=rpm).depth_m
    res = simulate_milling(MODE, None, SLOT, rpm=np.r_[rpm, rpm], depth_m=np.r_[0.95 * sdm, 1.05 * sdm],
                           revolutions=32, record_revolutions=2)
    assert res.stable.tolist() == [True] * 3 + [False] * 3


def test_period_doubling_of_a_four_tooth_cutter_is_chatter_like_the_sdm():
    # Cornelius et al. 2024's two modes, 4 teeth, 50 % down milling: at 13150 rpm the SDM's critical multiplier
    # is -1 (flip, f_c = (j + 1/2) f_t = 10 f_s, a spindle harmonic). The motion then repeats every revolution,
    # so a verdict against the previous revolution called it stable; against the tooth period it chatters.
    modes = [(1243.0, 2.92e6, 0.0619), (1747.0, 1.2e7, 0.0288)]
    mm = ModalModel([f for f, _, _ in modes], [z for _, _, z in modes], [k / (2 * np.pi * f) ** 2 for f, k, _ in modes])
    cut = CuttingConditions(teeth=4, tangential_coeff=2003e6, radial_ratio=0.404, radial_immersion=0.5)
    sdm = sdm_lobes(mm, mm, cut, rpm=[13150.0])
    f_t = 4 * 13150.0 / 60
    assert abs(sdm.chatter_hz[0] / f_t % 1 - 0.5) < 1e-3  # the case is a flip
    res = simulate_milling(mm, mm, cut, rpm=[13150.0] * 2, depth_m=sdm.depth_m[0] * np.array([0.9, 1.1]),
                           revolutions=40, record_revolutions=4)
    assert res.stable.tolist() == [True, False]
    assert abs(res.chatter_hz[1] / sdm.chatter_hz[0] - 1) < 0.01


def test_a_batch_too_large_for_the_tables_is_stepped_in_pieces_as_accurately(monkeypatch):
    # A batch whose angle tables exceed _TABLE_BYTES is stepped in pieces whose tables are built as it goes: here
    # pieces of a few steps that do not divide the revolution (a 10 kB budget: 31 of the slot's 256 steps a revolution).
    # Against the same independent references as the whole-revolution tables: the SDM's limit and the
    # frequency-domain SLE.
    import toolpoint.simulation.time_domain as td

    monkeypatch.setattr(td, "_TABLE_BYTES", 1e4)
    rpm = np.array([7500.0, 16000.0])
    sdm = sdm_lobes(MODE, None, SLOT, rpm=rpm).depth_m
    res = simulate_milling(MODE, None, SLOT, rpm=np.r_[rpm, rpm], depth_m=np.r_[0.95 * sdm, 1.05 * sdm],
                           revolutions=32, record_revolutions=2)
    assert res.stable.tolist() == [True] * 2 + [False] * 2
    cut = CuttingConditions(teeth=3, tangential_coeff=6e8, radial_ratio=0.3, radial_immersion=0.25, milling="up")
    tool = Tool(diameter_m=0.012, helix_deg=30, slices=4, edge_tangential=2e4, edge_normal=1e4)
    a = np.full(2, 0.2e-3)
    res = simulate_milling(MX, MY, cut, rpm=[6000.0, 17000.0], depth_m=a, tool=tool, revolutions=12,
                           record_revolutions=2)
    fd = sle_frequency_domain(MX, MY, cut, rpm=[6000.0, 17000.0], depth_m=a, tool=tool)
    assert res.stable.all()
    assert np.all((np.abs(res.sle_m - fd) <= 0.5e-6) | (np.abs(res.sle_m - fd) <= 0.02 * np.abs(fd))), (res.sle_m, fd)
    assert np.abs(fd).max() > 1e-6


@pytest.mark.parametrize("milling,immersion", [("down", 0.25), ("up", 0.25), ("down", 1.0), ("up", 0.6)])
@pytest.mark.parametrize("helix", [False, True])
def test_sle_time_domain_matches_frequency_domain(milling, immersion, helix):
    cut = CuttingConditions(teeth=3, tangential_coeff=6e8, radial_ratio=0.3, radial_immersion=immersion,
                            milling=milling)
    tool = Tool(diameter_m=0.012, helix_deg=30, slices=4, edge_tangential=2e4, edge_normal=1e4) if helix else Tool()
    rpm = np.array([6000.0, 17000.0])
    a = np.full(2, 0.2e-3)
    res = simulate_milling(MX, MY, cut, rpm=rpm, depth_m=a, tool=tool, revolutions=12, record_revolutions=2)
    assert res.stable.all()
    fd = sle_frequency_domain(MX, MY, cut, rpm=rpm, depth_m=a, tool=tool)
    ok = (np.abs(res.sle_m - fd) <= 0.5e-6) | (np.abs(res.sle_m - fd) <= 0.02 * np.abs(fd))
    assert ok.all(), (res.sle_m, fd)
    assert np.abs(fd).max() > 1e-6  # the comparison is not between two zeros


def _average_force(cut, a, f, kte=0.0, kne=0.0):
    """Altintas' closed-form mean force per revolution (tooth integration), in this package's directions."""
    p0, p1 = cut.immersion_angles
    kt, kn, n = cut.tangential_coeff, cut.normal_coeff, cut.teeth

    def prim(p):  # ∫ of the x and y force of one tooth per unit depth over φ
        isc, iss = -np.cos(2 * p) / 4, p / 2 - np.sin(2 * p) / 4
        fx = f * (kt * isc + kn * iss) + kte * np.sin(p) - kne * np.cos(p)
        fy = f * (-kt * iss + kn * isc) + kte * np.cos(p) + kne * np.sin(p)
        return np.array([fx, fy])

    return n * a * (prim(p1) - prim(p0)) / (2 * np.pi)


@pytest.mark.parametrize("milling,immersion", [("down", 1.0), ("down", 0.3), ("up", 0.5)])
def test_mean_force_rigid_tool_matches_closed_form(milling, immersion):
    cut = CuttingConditions(teeth=4, tangential_coeff=7e8, radial_ratio=0.35, radial_immersion=immersion,
                            milling=milling)
    stiff = [(3000.0, 1e12, 0.05)]
    tool = Tool(edge_tangential=3e4, edge_normal=2e4)
    a, f = 2e-3, 0.08e-3
    res = simulate_milling(stiff, stiff, cut, rpm=8000.0, depth_m=a, feed_m=f, tool=tool, revolutions=8,
                           record_revolutions=2)
    ref = _average_force(cut, a, f, 3e4, 2e4)
    np.testing.assert_allclose(res.mean_force_n[0], ref, rtol=0.01, atol=1e-3 * np.abs(ref).max())


def test_runout_and_variable_pitch_keep_the_mean_force():
    # the material removed per revolution, hence the mean force, does not depend on runout or pitch
    cut = CuttingConditions(teeth=2, tangential_coeff=6e8, radial_ratio=1 / 3, radial_immersion=1.0)
    stiff = [(3000.0, 1e12, 0.05)]
    a, f = 1e-3, 0.1e-3
    ref = _average_force(cut, a, f)
    for tool in (Tool(runout_m=(10e-6, 0.0)), Tool(tooth_angles_deg=(0.0, 160.0))):
        res = simulate_milling(stiff, stiff, cut, rpm=6000.0, depth_m=a, feed_m=f, tool=tool, revolutions=8,
                               record_revolutions=2)
        np.testing.assert_allclose(res.mean_force_n[0], ref, rtol=0.01)
    # runout: tooth 0 (10 µm out) cuts f sinφ + 10 µm, tooth 1 f sinφ − 10 µm; the peak tangential forces differ by
    # Kt a (2 × 10 µm) ... seen in F_y at φ = π/2 (F_y = −F_t there)
    res = simulate_milling(stiff, stiff, cut, rpm=6000.0, depth_m=a, feed_m=f, tool=Tool(runout_m=(10e-6, 0.0)),
                           revolutions=8, record_revolutions=1, steps_per_tooth=64)
    M = res.steps_per_rev
    fy = res.force_n[0, :, 1]
    at = [int(round(M / 4)), int(round(M / 4 + M / 2))]  # tooth 0 at π/2, then tooth 1 at π/2 (mid-step)
    f0, f1 = -fy[at[0] - 1], -fy[at[1] - 1]
    assert f0 - f1 == pytest.approx(6e8 * a * 20e-6, rel=0.02)


def test_tool_leaves_the_cut_and_chatter_saturates():
    depth = 2.5 * sdm_lobes(MODE, None, SLOT, rpm=[10000.0]).depth_m[0]
    res = simulate_milling(MODE, None, SLOT, rpm=10000.0, depth_m=depth, start="rest", revolutions=60,
                           record_revolutions=4)
    assert not res.stable[0]
    fx = res.force_n[0, :, 0]
    assert np.mean(fx == 0) > 0.05  # slotting keeps a tooth in the immersion: zero force = the tool left the cut
    assert np.abs(res.displacement_m[0]).max() < 1e-3  # bounded: the nonlinearity limits the chatter
    # the chatter frequency is one of the SDM's family f_c + k f_tooth near the mode
    fc = sdm_lobes(MODE, None, SLOT, rpm=[10000.0]).chatter_hz[0]
    ft = 2 * 10000.0 / 60
    family = fc + ft * np.arange(-6, 7)
    assert np.min(np.abs(family - res.chatter_hz[0])) < 0.03 * fc


def test_bad_input_names_the_field():
    cases = [
        (lambda: CuttingConditions(teeth=0, tangential_coeff=6e8, radial_ratio=0.3, radial_immersion=1), "teeth"),
        (lambda: simulate_milling(MODE, None, SLOT, rpm=1e4, depth_m=-1e-3), "depth_m"),
        (lambda: simulate_milling(ModalModel([], [], []), None, SLOT, rpm=1e4, depth_m=1e-3), "modes"),
        (lambda: simulate_milling([], [], SLOT, rpm=1e4, depth_m=1e-3), "modes"),
        (lambda: simulate_milling(MODE, None, SLOT, rpm=1e4, depth_m=1e-3, steps_per_tooth=8, substeps=1),
         "substeps"),
        (lambda: simulate_milling(MODE, None, SLOT, rpm=1e4, depth_m=1e-3, tool=Tool(runout_m=(1e-6,))),
         "runout_m"),
    ]
    for make, fieldname in cases:
        with pytest.raises(InputError) as err:
            make()
        assert err.value.field == fieldname and "\n" not in str(err.value)


@pytest.mark.parametrize("rate_in", [52_345.6, 200_000.0, 731_111.1])
def test_audio_resampling_keeps_the_band_and_drops_what_would_fold(rate_in):
    # a recorder's anti-aliasing: a 5 kHz line keeps its amplitude and frequency (within 50 ppm, a sound card's
    # clock), a line at 30 kHz (which linear interpolation folds to 14.1 kHz) is gone, ≥ 60 dB down
    from toolpoint.simulation import to_audio_rate

    t = np.arange(int(2.0 * rate_in)) / rate_in
    f_hi = 30_000.0 if rate_in > 60_000 else 0.0
    x = np.sin(2 * np.pi * 5000.0 * t) + np.sin(2 * np.pi * f_hi * t)
    y = to_audio_rate(x, rate_in, 44100.0)
    assert abs(y.size - 2.0 * 44100) <= 1
    n = y.size - 2000
    spec = np.abs(np.fft.rfft(y[1000:1000 + n] * np.hanning(n), 16 * n)) * 4 / n  # skip the filter's edges
    f = np.fft.rfftfreq(16 * n, 1 / 44100.0)
    k = int(np.argmax(spec * (np.abs(f - 5000) < 50)))
    assert abs(f[k] / 5000.0 - 1) < 5e-5 and abs(spec[k] - 1) < 0.01
    if f_hi:
        assert spec[np.abs(f - (44100.0 - f_hi)) < 20].max() < 1e-3
